//! The grandstand scenario (SPEC 3.1, the paper's simulation): a three-mode platform excited by
//! a smoothed impulse, a load cell and a laser as transducers, and a 50 fps camera looking at a
//! painted disk. Every run pushes its frames through firmware-core's centroiding, Welch H1 and
//! peak picking.

use super::{measure_system, measure_vision, RunRecord, Scenario, StudyConfig};
use crate::study::effects::{Camera, Effects};
use crate::study::render::{BlurRenderer, DiskTarget};
use firmware_core::spectrum::{scratch_capacity, Detrend, WelchConfig, WelchH1, Window};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal, StandardNormal};

/// Acquisition rate (transducers and camera), Hz.
pub const FS_HZ: f64 = 50.0;
/// Record length, s.
pub const DURATION_S: f64 = N as f64 / FS_HZ;
/// Samples per record.
pub const N: usize = 5000;
/// Fine integration steps per acquisition sample (fine rate 1 kHz).
pub const FINE: usize = 20;
/// Welch settings of SPEC 3.1: floor(N / 4.5) = 1111 samples, 50 % overlap, 0.01 Hz bins.
pub const NPERSEG: usize = 1111;
/// Segment overlap.
pub const NOVERLAP: usize = 555;
/// Transform length (0.01 Hz bins at 50 Hz).
pub const NFFT: usize = 5000;
/// Camera scale, px/mm.
pub const PX_PER_MM: f64 = 20.0;
/// Binary centroid threshold (grey levels).
pub const THRESHOLD: u16 = 100;
/// Start of the smoothed impulse, s.
pub const T0_S: f64 = 33.0;

type Welch = WelchH1<NPERSEG, NFFT, { scratch_capacity(NFFT) }>;

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
    pub fn receptance(&self, f_hz: f64) -> num_complex::Complex64 {
        let w = 2.0 * std::f64::consts::PI * self.f_hz;
        let s = num_complex::Complex64::new(0.0, 2.0 * std::f64::consts::PI * f_hz);
        1.0 / (self.mass_kg * s * s + 2.0 * self.mass_kg * self.zeta * w * s + self.mass_kg * w * w)
    }
}

/// Uniform distribution given by its mean and standard deviation (spans `m +/- s sqrt 3`).
fn uniform_ms(rng: &mut ChaCha8Rng, mean: f64, std: f64) -> f64 {
    let u: f64 = rng.random();
    mean + std * 3f64.sqrt() * (2.0 * u - 1.0)
}

fn normal(rng: &mut ChaCha8Rng, mean: f64, std: f64) -> f64 {
    let z: f64 = StandardNormal.sample(rng);
    mean + std * z
}

/// Draws the three modes of SPEC 3.1 (Table of PDFs); `fixed` sets every std to zero.
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
            mass_kg: 11_885.0,
        },
        Mode {
            f_hz: f2,
            zeta: h2,
            mass_kg: 24_298.0,
        },
        Mode {
            f_hz: f3,
            zeta: h3,
            mass_kg: 24_298.0,
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
    let alpha = uniform_ms(rng, 5.6, 0.0115);
    let f0_n = 950.0 + 100.0 * rng.random::<f64>();
    let noise = Normal::new(0.0, 100.0).expect("valid normal");
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
    let (sf, sx) = (rms(&force_n) / 5.0, rms(&disp) / 10.0);
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

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
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

/// The grandstand study.
#[derive(Debug)]
pub struct Grandstand {
    /// Optional image-formation effects (identity by default: the fast 8-bit path).
    effects: Effects,
    exposures_ms: Vec<f64>,
    /// Path segments per precomputed ramp block: the largest step that divides the frame
    /// period and every half exposure (in fine steps), so windows cover whole blocks.
    block: usize,
    fixed: bool,
    target: DiskTarget,
}

impl Grandstand {
    /// Mode bands of SPEC 3.1, Hz.
    pub const BANDS: [(f64, f64); 2] = [(1.5, 2.25), (2.25, 2.9)];

    /// Builds the scenario from a resolved configuration.
    pub fn new(cfg: &StudyConfig) -> anyhow::Result<Self> {
        let effects = Effects::from_options(&cfg.imaging)?;
        let dt_ms = 1000.0 / (FS_HZ * FINE as f64);
        let mut block = FINE;
        for e in &cfg.exposures_ms {
            let half = e / 2.0 / dt_ms;
            block = if (half - half.round()).abs() < 1e-9 {
                gcd(block, half.round() as usize)
            } else {
                1
            };
        }
        Ok(Grandstand {
            effects,
            block: block.max(1),
            exposures_ms: cfg.exposures_ms.clone(),
            fixed: cfg.fixed_structure,
            target: DiskTarget {
                radius_px: 12.0,
                level: 200.0,
                edge_sigma_px: 1.5,
            },
        })
    }

    fn welch() -> anyhow::Result<Box<Welch>> {
        let cfg = WelchConfig {
            fs_hz: FS_HZ as f32,
            nperseg: NPERSEG,
            noverlap: NOVERLAP,
            nfft: NFFT,
            window: Window::Hamming,
            detrend: Detrend::Constant,
        };
        Ok(Box::new(
            Welch::try_new(cfg).map_err(|e| anyhow::anyhow!("Welch settings: {e}"))?,
        ))
    }

    fn keep_bins() -> usize {
        // |FRF| kept up to 5 Hz (0.01 Hz bins)
        (5.0 * NFFT as f64 / FS_HZ) as usize + 1
    }
}

impl Scenario for Grandstand {
    fn name(&self) -> &'static str {
        "grandstand"
    }
    fn amplitude_unit(&self) -> &'static str {
        "mm/kN"
    }
    fn bands(&self) -> Vec<(f64, f64)> {
        Self::BANDS.to_vec()
    }
    fn frf_freqs(&self) -> Vec<f64> {
        (0..Self::keep_bins())
            .map(|k| k as f64 * FS_HZ / NFFT as f64)
            .collect()
    }
    fn notes(&self) -> Vec<String> {
        let period_ms = 1000.0 / FS_HZ;
        let long: Vec<String> = self
            .exposures_ms
            .iter()
            .filter(|e| **e > period_ms)
            .map(|e| e.to_string())
            .collect();
        if long.is_empty() {
            Vec::new()
        } else {
            vec![format!(
                "exposures {} ms are longer than the {period_ms} ms frame period: allowed in the simulation (overlapping exposures), impossible on a real camera",
                long.join(", ")
            )]
        }
    }

    fn run(&self, run: u64, rng: &mut ChaCha8Rng) -> anyhow::Result<RunRecord> {
        let dt_ms = 1000.0 / (FS_HZ * FINE as f64);
        let max_exp = self.exposures_ms.iter().cloned().fold(0.0, f64::max);
        let pad = (max_exp / 2.0 / dt_ms).ceil() as usize + 1;
        let r = simulate(rng, self.fixed, pad);
        let bands = self.bands();
        let mut welch = Self::welch()?;
        let transducer = measure_system(
            &mut welch,
            &r.force_meas_kn,
            &r.disp_meas_mm,
            &bands,
            Self::keep_bins(),
            1.0,
        )?;
        // camera: image y grows down, the platform's positive displacement is up
        let path_px: Vec<f64> = r
            .fine_disp_m
            .iter()
            .map(|x| -x * 1000.0 * PX_PER_MM)
            .collect();
        let mut renderer = BlurRenderer::for_path(&self.target, &path_px, self.block);
        let (w, h) = (renderer.width(), renderer.height());
        let rest_y = renderer.rest_y();
        let mut camera = Camera::new(&self.effects, THRESHOLD, w, h, rng);
        let mut vis = vec![0.0f64; N];
        let mut valid = vec![false; N];
        let mut vision = Vec::with_capacity(self.exposures_ms.len());
        for (ei, &exp) in self.exposures_ms.iter().enumerate() {
            let half = exp / 2.0 / dt_ms; // fine steps either side of the frame instant
            camera.start_exposure(ei);
            vision.push(measure_vision(
                exp,
                &mut vis,
                &mut valid,
                bands.len(),
                |i| {
                    let centre = (r.pad + i * FINE) as f64;
                    camera.frame(&mut renderer, centre - half, centre + half)
                },
                |cy| -(cy as f64 - rest_y) / PX_PER_MM,
                |y| {
                    measure_system(
                        &mut welch,
                        &r.force_meas_kn,
                        y,
                        &bands,
                        Self::keep_bins(),
                        1.0,
                    )
                },
            )?);
        }
        Ok(RunRecord {
            run,
            natural_f_hz: r.modes[..2].iter().map(|m| m.f_hz).collect(),
            transducer,
            vision,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

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
    fn transducer_path_without_noise_recovers_the_closed_form_peak() {
        // Noise-free transducers, fixed structure: over 24 runs (different excitations) the
        // mean picked peak must be within one 0.01 Hz bin of the receptance's |Im| maximum and
        // the mean amplitude within 2 % of |G| there. (A single run scatters by a few percent:
        // 7 segments of a finite random record leak.)
        let runs = 24;
        let (mut fs, mut amps) = (vec![vec![]; 2], vec![vec![]; 2]);
        let mut modes = None;
        for seed in 0..runs {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let r = simulate(&mut rng, true, 0);
            let force: Vec<f32> = r.force_n.iter().map(|f| (*f / 1000.0) as f32).collect();
            let disp: Vec<f32> = (0..N)
                .map(|i| (r.fine_disp_m[i * FINE] * 1000.0) as f32)
                .collect();
            let mut welch = Grandstand::welch().unwrap();
            let got =
                measure_system(&mut welch, &force, &disp, &Grandstand::BANDS, 0, 1.0).unwrap();
            for b in 0..2 {
                let p = got.peaks[b].unwrap();
                fs[b].push(p.f_hz);
                amps[b].push(p.a);
            }
            modes = Some(r.modes);
        }
        let modes = modes.unwrap();
        // What Welch H1 estimates for a broadband stationary input: the FRF smoothed by the
        // window's spectral kernel |W(nu)|^2 (W by a direct sum over the 1111 Hamming samples).
        let step = 0.002;
        let kernel: Vec<(f64, f64)> = (-500..=500)
            .map(|j| {
                let nu = j as f64 * step;
                let (mut re, mut im) = (0.0, 0.0);
                for n in 0..NPERSEG {
                    let w = Window::Hamming.value(n, NPERSEG) as f64;
                    let ph = -std::f64::consts::TAU * nu * n as f64 / FS_HZ;
                    re += w * ph.cos();
                    im += w * ph.sin();
                }
                (nu, re * re + im * im)
            })
            .collect();
        let ksum: f64 = kernel.iter().map(|k| k.1).sum();
        let smoothed = |f: f64| -> num_complex::Complex64 {
            kernel
                .iter()
                .map(|(nu, k)| {
                    modes
                        .iter()
                        .map(|m| m.receptance(f - nu))
                        .sum::<num_complex::Complex64>()
                        * *k
                })
                .sum::<num_complex::Complex64>()
                / ksum
        };
        for (b, band) in Grandstand::BANDS.iter().enumerate() {
            // closed form on the same 0.01 Hz grid, in mm/kN
            let (mut best_f, mut best_im, mut best_abs) = (0.0, 0.0, 0.0);
            let mut k = (band.0 * 100.0).round() as i64;
            while (k as f64) / 100.0 <= band.1 + 1e-9 {
                let f = k as f64 / 100.0;
                let g = smoothed(f) * 1e6;
                if g.im.abs() > best_im {
                    best_im = g.im.abs();
                    best_f = f;
                    best_abs = g.norm();
                }
                k += 1;
            }
            let f = crate::stats::mean(&fs[b]).unwrap();
            let a = crate::stats::mean(&amps[b]).unwrap();
            let raw: f64 = modes
                .iter()
                .map(|m| m.receptance(best_f))
                .sum::<num_complex::Complex64>()
                .norm()
                * 1e6;
            eprintln!(
                "mode {}: mean {a:.4} mm/kN at {f:.3} Hz; window-smoothed closed form {best_abs:.4} at {best_f} Hz; unsmoothed |G| {raw:.4}",
                b + 1
            );
            assert!(
                (f - best_f).abs() <= 0.0100001,
                "mode {}: {f} Hz vs {best_f} Hz",
                b + 1
            );
            assert!(
                (a / best_abs - 1.0).abs() < 0.02,
                "mode {}: {a} vs {best_abs} mm/kN",
                b + 1
            );
        }
    }
}
