//! The grandstand (method.md §3.1, the paper's simulation): the vertical receptance of a
//! platform tip, three modes drawn from the paper's table of PDFs, a decay-test excitation with
//! held process noise, the exact response, a load cell and a laser as transducers, and the
//! camera that looks at a painted disk on the platform. The only place the rig's constants live.

use super::DiskTarget;
use crate::{normal, uniform_ms};
use firmware_core::spectrum::{Detrend, WelchConfig, Window};
use num_complex::Complex64;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Acquisition rate (transducers and camera), Hz.
pub const FS_HZ: f64 = 50.0;
/// Record length, s.
pub const DURATION_S: f64 = N as f64 / FS_HZ;
/// Samples per record.
pub const N: usize = 5000;
/// Fine integration steps per acquisition sample (fine rate 1 kHz).
pub const FINE: usize = 20;
/// Welch segment: floor(N / 4.5) = 1111 samples (method.md §3.1).
pub const NPERSEG: usize = 1111;
/// Segment overlap (50 %).
pub const NOVERLAP: usize = 555;
/// Transform length (0.01 Hz bins at 50 Hz).
pub const NFFT: usize = 5000;
/// The estimator of the paper: periodic Hamming, 1111/555, nfft 5000, mean removed.
pub const WELCH: WelchConfig = WelchConfig {
    fs_hz: FS_HZ as f32,
    nperseg: NPERSEG,
    noverlap: NOVERLAP,
    nfft: NFFT,
    window: Window::Hamming,
    detrend: Detrend::Constant,
};
/// Mode bands, Hz: mode 1 in [1.5, 2.25], mode 2 in [2.25, 2.9].
pub const BANDS: [(f64, f64); 2] = [(1.5, 2.25), (2.25, 2.9)];
/// Camera scale, px/mm.
pub const PX_PER_MM: f64 = 20.0;
/// The painted disk: radius 12 px, level 200, edge smoothed by a Gaussian of 1.5 px.
pub const TARGET: DiskTarget = DiskTarget {
    radius_px: 12.0,
    level: 200.0,
    edge_sigma_px: 1.5,
    texture: crate::Texture::Plain,
};
/// Binary centroid threshold (grey levels).
pub const THRESHOLD: u16 = 100;
/// Start of the smoothed impulse, s.
pub const T0_S: f64 = 33.0;
/// Modal masses, kg (fixed).
pub const MASSES_KG: [f64; 3] = [11_885.0, 24_298.0, 24_298.0];
/// Process noise, N std per acquisition sample (held between samples).
pub const PROCESS_NOISE_N: f64 = 100.0;
/// Load cell signal-to-noise ratio (RMS of the clean signal / noise std).
pub const FORCE_SNR: f64 = 5.0;
/// Laser (displacement) and tip accelerometer signal-to-noise ratio.
pub const RESPONSE_SNR: f64 = 10.0;
/// Mean decay rate of the smoothed impulse, 1/s.
pub const ALPHA: f64 = 5.6;

/// The target's motion in the Welch segments of one nominal record (fixed structure, the
/// excitation of seed 0), as the H1 estimator weighs it
/// (`imaging::exposure::ExposureCorrection::for_segments` of the simulation): per segment of the study's
/// estimator, the energy of the Hamming-windowed, mean-removed force and the equivalent
/// sinusoidal amplitude (`sqrt(2)` windowed RMS) of the motion in px. The decay test makes it
/// two populations: a few px of response to the process noise, and the impulse's segments
/// with tens of px that carry most of the input energy.
pub fn nominal_motion_segments() -> Vec<crate::MotionSegment> {
    use rand::SeedableRng as _;
    let r = simulate(&mut ChaCha8Rng::seed_from_u64(0), true, 0);
    let step = NPERSEG - NOVERLAP;
    let w: Vec<f64> = (0..NPERSEG)
        .map(|n| Window::Hamming.value(n, NPERSEG) as f64)
        .collect();
    let w2: f64 = w.iter().map(|v| v * v).sum();
    let centred_energy = |x: &[f64]| {
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        x.iter()
            .zip(&w)
            .map(|(v, w)| (w * (v - mean)).powi(2))
            .sum::<f64>()
    };
    (0..=(N - NPERSEG) / step)
        .map(|s| {
            let seg = s * step..s * step + NPERSEG;
            let px: Vec<f64> = seg
                .clone()
                .map(|i| r.fine_disp_m[i * FINE] * 1000.0 * PX_PER_MM)
                .collect();
            crate::MotionSegment {
                weight: centred_energy(&r.force_n[seg]),
                amplitude_px: (2.0 * centred_energy(&px) / w2).sqrt(),
            }
        })
        .collect()
}

/// One mode of the platform's vertical receptance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mode {
    /// Natural frequency, Hz.
    pub f_hz: f64,
    /// Damping ratio.
    pub zeta: f64,
    /// Modal mass, kg.
    pub mass_kg: f64,
}

impl Mode {
    /// Receptance term `1 / (m s^2 + 2 m h w s + m w^2)` at `s = i 2 pi f`, m/N.
    pub fn receptance(&self, f_hz: f64) -> Complex64 {
        let w = 2.0 * std::f64::consts::PI * self.f_hz;
        let s = Complex64::new(0.0, 2.0 * std::f64::consts::PI * f_hz);
        1.0 / (self.mass_kg * s * s + 2.0 * self.mass_kg * self.zeta * w * s + self.mass_kg * w * w)
    }

    /// The three modes at the means of their PDFs: 2.0, 2.5, 3.16 Hz; damping 0.06, 0.03, 0.15.
    pub fn nominal() -> [Mode; 3] {
        let (f, h) = ([2.0, 2.5, 3.16], [0.06, 0.03, 0.15]);
        [0, 1, 2].map(|i| Mode {
            f_hz: f[i],
            zeta: h[i],
            mass_kg: MASSES_KG[i],
        })
    }
}

/// The receptance of a set of modes, `sum 1 / (m s^2 + 2 m h w s + m w^2)` at `i 2 pi f`, m/N.
pub fn receptance(modes: &[Mode], f_hz: f64) -> Complex64 {
    modes.iter().map(|m| m.receptance(f_hz)).sum()
}

/// The accelerance `-w^2 G(i w)` of a set of modes, (m/s^2)/N.
pub fn accelerance(modes: &[Mode], f_hz: f64) -> Complex64 {
    let w = 2.0 * std::f64::consts::PI * f_hz;
    -w * w * receptance(modes, f_hz)
}

/// Draws the three modes of method.md §3.1 (Table of PDFs); `fixed` sets every std to zero.
pub fn sample_modes(rng: &mut ChaCha8Rng, fixed: bool) -> [Mode; 3] {
    let k = if fixed { 0.0 } else { 1.0 };
    let f1 = normal(rng, 2.0, 0.1 * k);
    let h1 = uniform_ms(rng, 0.06, 0.0014 * k);
    let f2 = normal(rng, 2.5, 0.05 * k);
    let h2 = uniform_ms(rng, 0.03, 0.0003 * k);
    let f3 = normal(rng, 3.16, 0.2 * k);
    let h3 = uniform_ms(rng, 0.15, 0.0029 * k);
    [
        Mode {
            f_hz: f1,
            zeta: h1,
            mass_kg: MASSES_KG[0],
        },
        Mode {
            f_hz: f2,
            zeta: h2,
            mass_kg: MASSES_KG[1],
        },
        Mode {
            f_hz: f3,
            zeta: h3,
            mass_kg: MASSES_KG[2],
        },
    ]
}

/// Exact zero-order-hold discretisation of `x'' + 2 h w x' + w^2 x = u` (u = F / m held over
/// each step): `[x, v](k+1) = Phi [x, v](k) + Gamma u(k)`.
#[derive(Debug, Clone, Copy)]
pub struct Zoh {
    phi: [[f64; 2]; 2],
    gamma: [f64; 2],
}

impl Zoh {
    /// Discretises `mode` at step `dt` (underdamped modes, `zeta < 1`).
    pub fn new(mode: &Mode, dt: f64) -> Zoh {
        let w = 2.0 * std::f64::consts::PI * mode.f_hz;
        let sigma = mode.zeta * w;
        let wd = w * (1.0 - mode.zeta * mode.zeta).max(1e-12).sqrt();
        let e = (-sigma * dt).exp();
        let (s, c) = (wd * dt).sin_cos();
        let phi = [
            [e * (c + sigma / wd * s), e * s / wd],
            [-e * w * w / wd * s, e * (c - sigma / wd * s)],
        ];
        let gamma = [
            (1.0 - phi[1][1] - 2.0 * sigma * phi[0][1]) / (w * w),
            phi[0][1],
        ];
        Zoh { phi, gamma }
    }

    /// Response (displacement) to the force samples `force_n` held over each step, starting at
    /// rest; `mass_kg` scales the force to `u`. Adds into `out`.
    pub fn add_response(&self, force_n: &[f64], mass_kg: f64, out: &mut [f64]) {
        let (mut x, mut v) = (0.0, 0.0);
        for (f, o) in force_n.iter().zip(out.iter_mut()) {
            *o += x;
            let u = f / mass_kg;
            let nx = self.phi[0][0] * x + self.phi[0][1] * v + self.gamma[0] * u;
            let nv = self.phi[1][0] * x + self.phi[1][1] * v + self.gamma[1] * u;
            x = nx;
            v = nv;
        }
    }
}

/// Everything random about one realization, in the order it is drawn.
#[derive(Debug, Clone)]
pub struct Realization {
    /// The three modes.
    pub modes: [Mode; 3],
    /// Decay rate of the smoothed impulse, 1/s.
    pub alpha: f64,
    /// Peak of the smoothed impulse, N.
    pub f0_n: f64,
    /// True force at the acquisition instants, N.
    pub force_n: Vec<f64>,
    /// True displacement at the fine instants `(i - pad) / (FS FINE)`, m (`pad` fine steps of
    /// rest before t = 0 so exposures centred on early frames are defined).
    pub fine_disp_m: Vec<f64>,
    /// Fine steps before t = 0.
    pub pad: usize,
    /// Measured force (load cell), kN.
    pub force_meas_kn: Vec<f32>,
    /// Measured displacement (laser), mm.
    pub disp_meas_mm: Vec<f32>,
}

/// Simulates one realization: structure, excitation, response and transducer noise.
/// `pad` fine steps are kept before t = 0 and after the end (for the exposure windows).
pub fn simulate(rng: &mut ChaCha8Rng, fixed: bool, pad: usize) -> Realization {
    let modes = sample_modes(rng, fixed);
    let alpha = uniform_ms(rng, ALPHA, 0.0115);
    let f0_n = 950.0 + 100.0 * rng.random::<f64>();
    let noise = Normal::new(0.0, PROCESS_NOISE_N).expect("valid normal");
    let dt = 1.0 / (FS_HZ * FINE as f64);
    let n_fine = N * FINE + 2 * pad;
    let mut fine_force = vec![0.0; n_fine];
    let mut force_n = vec![0.0; N];
    for i in 0..N {
        let np: f64 = noise.sample(rng);
        force_n[i] = impulse(i as f64 / FS_HZ, alpha, f0_n) + np;
        for j in 0..FINE {
            // smooth part at the middle of the fine step, process noise held over the sample
            let t = (i * FINE + j) as f64 * dt + 0.5 * dt;
            fine_force[pad + i * FINE + j] = impulse(t, alpha, f0_n) + np;
        }
    }
    // after the record the excitation goes on as its smooth part (no noise draws)
    for (k, f) in fine_force.iter_mut().enumerate().skip(pad + N * FINE) {
        let t = (k - pad) as f64 * dt + 0.5 * dt;
        *f = impulse(t, alpha, f0_n);
    }
    let mut fine_disp_m = vec![0.0; n_fine];
    for m in &modes {
        Zoh::new(m, dt).add_response(&fine_force, m.mass_kg, &mut fine_disp_m);
    }
    let disp: Vec<f64> = (0..N).map(|i| fine_disp_m[pad + i * FINE]).collect();
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    let (sf, sx) = (rms(&force_n) / FORCE_SNR, rms(&disp) / RESPONSE_SNR);
    let force_meas_kn = force_n
        .iter()
        .map(|f| ((f + sf * normal(rng, 0.0, 1.0)) / 1000.0) as f32)
        .collect();
    let disp_meas_mm = disp
        .iter()
        .map(|x| ((x + sx * normal(rng, 0.0, 1.0)) * 1000.0) as f32)
        .collect();
    Realization {
        modes,
        alpha,
        f0_n,
        force_n,
        fine_disp_m,
        pad,
        force_meas_kn,
        disp_meas_mm,
    }
}

/// The smoothed impulse `F0 e alpha (t - t0) exp(-alpha (t - t0))` for `t >= t0`, else 0.
pub fn impulse(t: f64, alpha: f64, f0: f64) -> f64 {
    if t < T0_S {
        0.0
    } else {
        let u = alpha * (t - T0_S);
        f0 * std::f64::consts::E * u * (-u).exp()
    }
}

/// The decay test as a synthetic recording simulates it (method.md §3.1 and "Synthetic
/// recordings"): fixed modes and pulse, periodic over the record.
#[derive(Debug, Clone, PartialEq)]
pub struct DecayTest {
    /// Modes.
    pub modes: Vec<Mode>,
    /// Peak force of the decay pulse, N.
    pub f0_n: f64,
    /// Decay rate of the pulse, 1/s.
    pub alpha: f64,
    /// Start of the pulse, s.
    pub t0_s: f64,
    /// Process noise, N std per acquisition sample (held between samples).
    pub process_noise_n: f64,
    /// Load cell signal-to-noise ratio (RMS of the clean force / noise std).
    pub force_snr: f64,
    /// Tip accelerometer signal-to-noise ratio.
    pub accel_snr: f64,
}

impl DecayTest {
    /// The mean modes, `F0` drawn from U(950, 1050) N by a stream of `seed`, the mean decay rate.
    pub fn nominal(seed: u64) -> Self {
        use rand::SeedableRng as _;
        let f0_n =
            ChaCha8Rng::seed_from_u64(seed ^ 0x6772_616e_6473_7461).random_range(950.0..1050.0);
        DecayTest {
            modes: Mode::nominal().to_vec(),
            f0_n,
            alpha: ALPHA,
            t0_s: T0_S,
            process_noise_n: PROCESS_NOISE_N,
            force_snr: FORCE_SNR,
            accel_snr: RESPONSE_SNR,
        }
    }

    /// The force at time `t` (s) without process noise.
    pub fn pulse(&self, t: f64) -> f64 {
        let t = t - self.t0_s;
        if t >= 0.0 {
            self.f0_n * std::f64::consts::E * self.alpha * t * (-self.alpha * t).exp()
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zoh_matches_the_closed_form_step_response() {
        let m = Mode {
            f_hz: 2.0,
            zeta: 0.06,
            mass_kg: 11_885.0,
        };
        let dt = 1e-3;
        let f = vec![1000.0; 3000];
        let mut x = vec![0.0; 3000];
        Zoh::new(&m, dt).add_response(&f, m.mass_kg, &mut x);
        let w = 2.0 * std::f64::consts::PI * m.f_hz;
        let wd = w * (1.0 - m.zeta * m.zeta).sqrt();
        let xs = 1000.0 / (m.mass_kg * w * w);
        for (k, v) in x.iter().enumerate() {
            let t = k as f64 * dt;
            let want = xs
                * (1.0
                    - (-m.zeta * w * t).exp()
                        * ((wd * t).cos() + m.zeta * w / wd * (wd * t).sin()));
            assert!(
                (v - want).abs() < 1e-9 * xs.max(1.0),
                "t = {t}: {v} vs {want}"
            );
        }
    }

    #[test]
    fn accelerance_is_minus_w2_times_the_receptance() {
        // a single mode's receptance at its natural frequency is 1 / (i 2 m h w^2), exactly
        let modes = Mode::nominal();
        let m = modes[0];
        let w = 2.0 * std::f64::consts::PI * m.f_hz;
        let at_wn = m.receptance(m.f_hz);
        let want = Complex64::new(0.0, -1.0 / (2.0 * m.mass_kg * m.zeta * w * w));
        assert!(
            (at_wn - want).norm() < 1e-12 * want.norm(),
            "{at_wn} vs {want}"
        );
        for f in [0.5, 2.0, 2.5, 3.16, 7.0] {
            let w = 2.0 * std::f64::consts::PI * f;
            let a = accelerance(&modes, f);
            assert!((a + w * w * receptance(&modes, f)).norm() < 1e-12 * a.norm());
        }
        assert!(accelerance(&modes, 1e-6).norm() < 1e-12);
    }
}
