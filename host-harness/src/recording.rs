//! Synthetic recordings: one simulated run written as a real rig would record it — grey PNG
//! frames plus a transducer CSV — so that `host-harness analyze` can be tried at once, and its
//! output checked against known modal parameters.
//!
//! # What is simulated (nominal modal parameters, no run-to-run scatter)
//!
//! **Cantilever** (SPEC 3.2, the default): base-excited modal model
//! `q_i'' + 2 h_i w_i q_i' + w_i^2 q_i = -G_i xb''`, `tip = xb + sum phi_i q_i`, with
//! band-limited random base acceleration (flat complex Gaussian spectrum on 5-50 Hz) scaled so
//! that the tip moves `tip_pp_mm` peak to peak; accelerometers (base and tip) at 2048 Hz with
//! 0.00015 g RMS noise; camera 120 fps, 0.1266 mm/px, white disk of radius 10 px on black.
//! CSV columns `t_s,base_acc,tip_acc` (m/s^2).
//!
//! **Grandstand** (SPEC 3.1): receptance `G(s) = sum 1 / (m_i s^2 + 2 m_i h_i w_i s + m_i w_i^2)`
//! driven by the decay-test force `F0 e alpha (t - t0) exp(-alpha (t - t0))` (t0 = 33 s) plus
//! process noise (100 N std per acquisition sample, held); a load cell (SNR 5) and, since
//! `analyze` compares accelerations, a tip accelerometer (SNR 10) at 50 Hz; camera 50 fps,
//! 0.05 mm/px, disk of radius 12 px at level 200 with a Gaussian edge (sigma 1.5 px).
//! CSV columns `t_s,force_n,tip_acc` (N, m/s^2); the FRFs are accelerances, (m/s^2)/N.
//!
//! Both are built **periodic over the record** on a fine time base (`fs * fine_per_sample`:
//! 30 720 Hz for the cantilever, the common clock of SPEC 2.7; 1 kHz for the grandstand) and the
//! response is computed exactly in the frequency domain (periodic steady state, no transient).
//!
//! Camera: frame `k` at `t = k / fps`, exposure centred on it (it may exceed the frame period,
//! as in the grandstand study). The frame is the average of the instantaneous images over the
//! exposure (the tip path, linearly interpolated on the fine grid, at 8 to 64 instants), each a
//! disk at level `level` on black: anti-aliased by a one-pixel linear ramp
//! (`clamp(r + 0.5 - d, 0, 1)`) or, with `edge_sigma_px`, a Gaussian edge
//! (`erfc((d - r) / (sigma sqrt 2)) / 2`), 8 bit. A positive tip displacement moves the disk
//! **up** in the image (the `--axis y` convention of `analyze`).
//!
//! This module keeps its own small physics (exact periodic frequency-domain response, direct
//! time-averaged renderer) so that a recording has closed-form expected FRFs; the Monte Carlo
//! studies use the time-domain models and the blur renderer under `study/`. TODO: render the
//! recording's frames with the study's renderer too, so both paths share one image model.

use crate::bad_input;
use crate::study::Preset;
use anyhow::Context as _;
use num_complex::Complex64;
use rand::SeedableRng as _;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution as _, StandardNormal};
use std::path::{Path, PathBuf};

/// One mode of the base-excited (cantilever) model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaseExcitedMode {
    /// Natural frequency, Hz.
    pub f_hz: f64,
    /// Damping ratio.
    pub zeta: f64,
    /// Participation times tip mode shape, `G_i phi_i`.
    pub g_phi: f64,
}

/// One mode of the force-excited (grandstand) receptance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReceptanceMode {
    /// Natural frequency, Hz.
    pub f_hz: f64,
    /// Damping ratio.
    pub zeta: f64,
    /// Modal mass, kg.
    pub mass_kg: f64,
}

/// The structure, its excitation and its transducers.
#[derive(Debug, Clone, PartialEq)]
pub enum Rig {
    /// SPEC 3.2: base-excited cantilever, two accelerometers.
    Cantilever {
        /// Modes.
        modes: Vec<BaseExcitedMode>,
        /// Band of the random base acceleration, Hz.
        band_hz: (f64, f64),
        /// Tip motion peak to peak, mm (the excitation is scaled to it).
        tip_pp_mm: f64,
        /// Accelerometer noise, g RMS.
        accel_noise_g: f64,
    },
    /// SPEC 3.1: force-excited grandstand (decay test), load cell and tip accelerometer.
    Grandstand {
        /// Modes.
        modes: Vec<ReceptanceMode>,
        /// Peak force of the decay pulse, N.
        f0_n: f64,
        /// Decay rate of the pulse, 1/s.
        alpha: f64,
        /// Start of the pulse, s.
        t0_s: f64,
        /// Process noise, N std per acquisition sample (held between samples).
        process_noise_n: f64,
        /// Load cell signal-to-noise ratio (RMS of the clean force / noise std).
        force_snr: f64,
        /// Tip accelerometer signal-to-noise ratio.
        accel_snr: f64,
    },
}

/// Everything a synthetic recording depends on.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordingSpec {
    /// Seed of the excitation and noise streams (ChaCha8).
    pub seed: u64,
    /// Camera exposure, ms (centred on the frame time), >= 0.
    pub exposure_ms: f64,
    /// Camera frame rate, Hz.
    pub fps: f64,
    /// Transducer sample rate, Hz.
    pub fs: f64,
    /// Fine steps per transducer sample (the fine rate is `fs * fine_per_sample`);
    /// `fs * fine_per_sample / fps` must be an integer.
    pub fine_per_sample: usize,
    /// Number of frames.
    pub frames: usize,
    /// Scale, mm per pixel.
    pub mm_per_px: f64,
    /// Target radius, px.
    pub radius_px: f64,
    /// Gaussian edge of the target, px (`None`: a one-pixel linear anti-aliasing ramp).
    pub edge_sigma_px: Option<f64>,
    /// Target grey level (8-bit); the background is 0.
    pub level: u8,
    /// Frame size, px (width, height).
    pub frame_size: (u32, u32),
    /// Structure, excitation and transducers.
    pub rig: Rig,
}

/// Standard gravity, m/s^2.
const G0: f64 = 9.80665;

impl RecordingSpec {
    /// The cantilever rig of SPEC 3.2 with nominal parameters: 120 fps, 10 s (1200 frames),
    /// 2048 Hz accelerometers, 0.1266 mm/px, disk of radius 10 px at level 200, modes 7.1 Hz
    /// (h 0.0115, G phi 1.566) and 32.4 Hz (h 0.011, G phi -0.867), 5-50 Hz excitation, tip
    /// 4.5 mm peak to peak, 0.00015 g accelerometer noise.
    pub fn cantilever(seed: u64, exposure_ms: f64) -> Self {
        RecordingSpec {
            seed,
            exposure_ms,
            fps: 120.0,
            fs: 2048.0,
            fine_per_sample: 15,
            frames: 1200,
            mm_per_px: 0.1266,
            radius_px: 10.0,
            edge_sigma_px: None,
            level: 200,
            frame_size: (40, 112),
            rig: Rig::Cantilever {
                modes: vec![
                    BaseExcitedMode {
                        f_hz: 7.1,
                        zeta: 0.0115,
                        g_phi: 1.566,
                    },
                    BaseExcitedMode {
                        f_hz: 32.4,
                        zeta: 0.011,
                        g_phi: -0.867,
                    },
                ],
                band_hz: (5.0, 50.0),
                tip_pp_mm: 4.5,
                accel_noise_g: 0.00015,
            },
        }
    }

    /// The grandstand of SPEC 3.1 with the mean modal parameters (f 2.0, 2.5, 3.16 Hz; h 0.06,
    /// 0.03, 0.15; m 11 885, 24 298, 24 298 kg): 100 s at 50 Hz, one frame per sample, decay
    /// pulse at 33 s with `F0` drawn from U(950, 1050) N, 100 N process noise, 20 px/mm, disk
    /// of radius 12 px at level 200 with a 1.5 px Gaussian edge.
    pub fn grandstand(seed: u64, exposure_ms: f64) -> Self {
        use rand::Rng as _;
        let f0_n =
            ChaCha8Rng::seed_from_u64(seed ^ 0x6772_616e_6473_7461).random_range(950.0..1050.0);
        RecordingSpec {
            seed,
            exposure_ms,
            fps: 50.0,
            fs: 50.0,
            fine_per_sample: 20,
            frames: 5000,
            mm_per_px: 0.05,
            radius_px: 12.0,
            edge_sigma_px: Some(1.5),
            level: 200,
            frame_size: (48, 240),
            rig: Rig::Grandstand {
                modes: vec![
                    ReceptanceMode {
                        f_hz: 2.0,
                        zeta: 0.06,
                        mass_kg: 11_885.0,
                    },
                    ReceptanceMode {
                        f_hz: 2.5,
                        zeta: 0.03,
                        mass_kg: 24_298.0,
                    },
                    ReceptanceMode {
                        f_hz: 3.16,
                        zeta: 0.15,
                        mass_kg: 24_298.0,
                    },
                ],
                f0_n,
                alpha: 5.6,
                t0_s: 33.0,
                process_noise_n: 100.0,
                force_snr: 5.0,
                accel_snr: 10.0,
            },
        }
    }

    /// Threshold of the binary centroid: half the target level.
    pub fn threshold(&self) -> u16 {
        u16::from(self.level / 2)
    }

    /// Transducer samples covered by the frames, `frames * fs / fps`.
    pub fn samples(&self) -> usize {
        (self.frames as f64 * self.fs / self.fps).round() as usize
    }

    /// Name of the input column of the CSV.
    pub fn input_col(&self) -> &'static str {
        match self.rig {
            Rig::Cantilever { .. } => "base_acc",
            Rig::Grandstand { .. } => "force_n",
        }
    }

    /// Closed-form FRF from the input (base acceleration, or force) to the tip acceleration
    /// at `f_hz`: the cantilever's transmissibility, or the grandstand's accelerance
    /// `-w^2 G(i w)` in (m/s^2)/N.
    pub fn frf(&self, f_hz: f64) -> Complex64 {
        let w = 2.0 * std::f64::consts::PI * f_hz;
        match &self.rig {
            Rig::Cantilever { modes, .. } => {
                let mut h = Complex64::new(1.0, 0.0);
                for m in modes {
                    let wn = 2.0 * std::f64::consts::PI * m.f_hz;
                    h += m.g_phi * w * w / Complex64::new(wn * wn - w * w, 2.0 * m.zeta * wn * w);
                }
                h
            }
            Rig::Grandstand { modes, .. } => {
                let mut g = Complex64::new(0.0, 0.0);
                for m in modes {
                    let wn = 2.0 * std::f64::consts::PI * m.f_hz;
                    g += 1.0
                        / Complex64::new(
                            m.mass_kg * (wn * wn - w * w),
                            2.0 * m.mass_kg * m.zeta * wn * w,
                        );
                }
                -w * w * g
            }
        }
    }

    /// Natural frequencies of the modes, Hz.
    pub fn natural_frequencies(&self) -> Vec<f64> {
        match &self.rig {
            Rig::Cantilever { modes, .. } => modes.iter().map(|m| m.f_hz).collect(),
            Rig::Grandstand { modes, .. } => modes.iter().map(|m| m.f_hz).collect(),
        }
    }

    fn validate(&self) -> anyhow::Result<(usize, usize)> {
        let fine_hz = self.fs * self.fine_per_sample as f64;
        let per_frame = fine_hz / self.fps;
        let ppf = per_frame.round() as usize;
        if (per_frame - ppf as f64).abs() > 1e-9 || ppf == 0 {
            return Err(bad_input(format!(
                "fine rate {fine_hz} Hz is not a multiple of the frame rate {} fps",
                self.fps
            )));
        }
        let samples_f = self.frames as f64 * self.fs / self.fps;
        if (samples_f - samples_f.round()).abs() > 1e-9 {
            return Err(bad_input(format!(
                "{} frames at {} fps are not a whole number of samples at {} Hz",
                self.frames, self.fps, self.fs
            )));
        }
        let record_ms = 1000.0 * self.frames as f64 / self.fps;
        if !(self.exposure_ms >= 0.0 && self.exposure_ms < record_ms) {
            return Err(bad_input(format!(
                "exposure {} ms must be >= 0 and shorter than the record ({record_ms} ms)",
                self.exposure_ms,
            )));
        }
        Ok((ppf, self.frames * ppf))
    }
}

/// A simulated run in memory.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntheticRun {
    /// Input channel at `fs` (base acceleration m/s^2, or force N), with noise.
    pub input: Vec<f64>,
    /// Tip acceleration at `fs`, m/s^2, with noise.
    pub tip_acc: Vec<f64>,
    /// Tip displacement on the fine time base, mm (`frames * fine_per_frame` values, periodic).
    pub tip_mm: Vec<f64>,
    /// Fine samples per frame period.
    pub fine_per_frame: usize,
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

/// Simulates the run (see the module documentation).
pub fn simulate(spec: &RecordingSpec) -> anyhow::Result<SyntheticRun> {
    let (fine_per_frame, n) = spec.validate()?;
    let fine_hz = spec.fs * spec.fine_per_sample as f64;
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let mut planner = rustfft::FftPlanner::<f64>::new();
    let df = fine_hz / n as f64;
    // input spectrum on the fine grid
    let mut input = vec![Complex64::new(0.0, 0.0); n];
    match &spec.rig {
        Rig::Cantilever { band_hz, .. } => {
            // complex Gaussian on the band, Hermitian
            for k in 1..n / 2 {
                let f = k as f64 * df;
                if f < band_hz.0 || f > band_hz.1 {
                    continue;
                }
                let re: f64 = StandardNormal.sample(&mut rng);
                let im: f64 = StandardNormal.sample(&mut rng);
                input[k] = Complex64::new(re, im);
                input[n - k] = input[k].conj();
            }
        }
        Rig::Grandstand {
            f0_n,
            alpha,
            t0_s,
            process_noise_n,
            ..
        } => {
            let mut held = 0.0;
            for (j, v) in input.iter_mut().enumerate() {
                if j % spec.fine_per_sample == 0 {
                    let z: f64 = StandardNormal.sample(&mut rng);
                    held = process_noise_n * z;
                }
                let t = j as f64 / fine_hz - t0_s;
                let pulse = if t >= 0.0 {
                    f0_n * std::f64::consts::E * alpha * t * (-alpha * t).exp()
                } else {
                    0.0
                };
                *v = Complex64::new(pulse + held, 0.0);
            }
            planner.plan_fft_forward(n).process(&mut input);
        }
    }
    let mut tip_acc = vec![Complex64::new(0.0, 0.0); n];
    let mut tip_mm = vec![Complex64::new(0.0, 0.0); n];
    for k in 1..n {
        let signed = if k <= n / 2 {
            k as f64
        } else {
            k as f64 - n as f64
        };
        let f = signed * df;
        let h = if signed >= 0.0 {
            spec.frf(f)
        } else {
            spec.frf(-f).conj()
        };
        let w = 2.0 * std::f64::consts::PI * f;
        tip_acc[k] = input[k] * h;
        tip_mm[k] = -tip_acc[k] / (w * w) * 1000.0;
    }
    let ifft = planner.plan_fft_inverse(n);
    for buf in [&mut input, &mut tip_acc, &mut tip_mm] {
        ifft.process(buf);
    }
    // the inverse is unnormalised: one common factor, removed by the scaling below
    let norm = 1.0 / n as f64;
    let scale = match &spec.rig {
        Rig::Cantilever { tip_pp_mm, .. } => {
            let (lo, hi) = tip_mm
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(v.re), b.max(v.re))
                });
            tip_pp_mm / (hi - lo)
        }
        Rig::Grandstand { .. } => norm,
    };
    let step = spec.fine_per_sample;
    let clean_in: Vec<f64> = input.iter().step_by(step).map(|v| v.re * scale).collect();
    let clean_tip: Vec<f64> = tip_acc.iter().step_by(step).map(|v| v.re * scale).collect();
    let (in_noise, tip_noise) = match &spec.rig {
        Rig::Cantilever { accel_noise_g, .. } => (accel_noise_g * G0, accel_noise_g * G0),
        Rig::Grandstand {
            force_snr,
            accel_snr,
            ..
        } => (rms(&clean_in) / force_snr, rms(&clean_tip) / accel_snr),
    };
    let mut noisy = |clean: Vec<f64>, std: f64| -> Vec<f64> {
        clean
            .into_iter()
            .map(|v| {
                let z: f64 = StandardNormal.sample(&mut rng);
                v + std * z
            })
            .collect()
    };
    Ok(SyntheticRun {
        input: noisy(clean_in, in_noise),
        tip_acc: noisy(clean_tip, tip_noise),
        tip_mm: tip_mm.iter().map(|v| v.re * scale).collect(),
        fine_per_frame,
    })
}

/// Complementary error function (Abramowitz & Stegun 7.1.26, |error| < 1.5e-7).
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.327_591_1 * z);
    let poly = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    let r = poly * (-z * z).exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// Renders frame `k` of a run: the time average over the exposure of the target.
pub fn render_frame(spec: &RecordingSpec, run: &SyntheticRun, k: usize) -> Vec<u8> {
    let (w, h) = (spec.frame_size.0 as usize, spec.frame_size.1 as usize);
    let n = run.tip_mm.len();
    let fine_dt = 1.0 / (spec.fps * run.fine_per_frame as f64);
    let exposure = spec.exposure_ms / 1000.0;
    // instants spread over the centred window (periodic record): one per fine step, 8 to 64
    let half = exposure / 2.0;
    let count = ((exposure / fine_dt).floor() as usize + 1).clamp(8, 64);
    let centre = (k * run.fine_per_frame) as f64;
    let positions: Vec<f64> = (0..count)
        .map(|i| {
            let t = if exposure == 0.0 {
                0.0
            } else {
                -half + exposure * i as f64 / (count - 1) as f64
            };
            // linear interpolation on the periodic fine path
            let s = centre + t / fine_dt;
            let i0 = s.floor();
            let frac = s - i0;
            let a = run.tip_mm[(i0 as i64).rem_euclid(n as i64) as usize];
            let b = run.tip_mm[(i0 as i64 + 1).rem_euclid(n as i64) as usize];
            a + frac * (b - a)
        })
        .collect();
    let (cx, cy0) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    let r = spec.radius_px;
    let reach = r + 2.0 + 5.0 * spec.edge_sigma_px.unwrap_or(0.0);
    let coverage = |d: f64| match spec.edge_sigma_px {
        Some(sigma) => 0.5 * erfc((d - r) / (sigma * std::f64::consts::SQRT_2)),
        None => (r + 0.5 - d).clamp(0.0, 1.0),
    };
    let mut acc = vec![0.0f64; w * h];
    for d_mm in &positions {
        let cy = cy0 - d_mm / spec.mm_per_px;
        let j0 = (cy - reach).floor().max(0.0) as usize;
        let j1 = ((cy + reach).ceil().max(0.0) as usize).min(h - 1);
        for j in j0..=j1 {
            let dy = j as f64 - cy;
            for i in 0..w {
                let dx = i as f64 - cx;
                acc[j * w + i] += coverage((dx * dx + dy * dy).sqrt());
            }
        }
    }
    let level = f64::from(spec.level) / positions.len() as f64;
    acc.iter()
        .map(|v| (v * level).round().clamp(0.0, 255.0) as u8)
        .collect()
}

/// Files of a written recording.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordingFiles {
    /// The frames directory (`frame_00000.png` ...).
    pub frames_dir: PathBuf,
    /// `accel.csv` (`t_s,base_acc,tip_acc` or `t_s,force_n,tip_acc`).
    pub accel_csv: PathBuf,
    /// `recording.toml` (the parameters).
    pub toml: PathBuf,
    /// `README.txt` (the analyze command).
    pub readme: PathBuf,
    /// The exact `host-harness analyze` arguments for this recording (without the program).
    pub analyze_args: Vec<String>,
}

/// `recording.toml`: the parameters of the recording (also the modal parameters to expect).
pub fn recording_toml(spec: &RecordingSpec) -> String {
    use std::fmt::Write as _;
    let preset = match spec.rig {
        Rig::Cantilever { .. } => "cantilever",
        Rig::Grandstand { .. } => "grandstand",
    };
    let mut s = format!(
        "# synthetic recording written by host-harness render --recording\n\
         preset = \"{preset}\"\nseed = {}\nexposure_ms = {}\nfps = {}\nfs = {}\nframes = {}\n\
         samples = {}\nmm_per_px = {}\nradius_px = {}\nlevel = {}\nthreshold = {}\n\
         frame_size = [{}, {}]\n",
        spec.seed,
        spec.exposure_ms,
        spec.fps,
        spec.fs,
        spec.frames,
        spec.samples(),
        spec.mm_per_px,
        spec.radius_px,
        spec.level,
        spec.threshold(),
        spec.frame_size.0,
        spec.frame_size.1,
    );
    if let Some(e) = spec.edge_sigma_px {
        let _ = writeln!(s, "edge_sigma_px = {e}");
    }
    match &spec.rig {
        Rig::Cantilever {
            modes,
            band_hz,
            tip_pp_mm,
            accel_noise_g,
        } => {
            let _ = write!(
                s,
                "band_hz = [{}, {}]\ntip_pp_mm = {tip_pp_mm}\naccel_noise_g = {accel_noise_g}\n",
                band_hz.0, band_hz.1
            );
            for m in modes {
                let _ = write!(
                    s,
                    "\n[[modes]]\nf_hz = {}\nzeta = {}\ng_phi = {}\n",
                    m.f_hz, m.zeta, m.g_phi
                );
            }
        }
        Rig::Grandstand {
            modes,
            f0_n,
            alpha,
            t0_s,
            process_noise_n,
            force_snr,
            accel_snr,
        } => {
            let _ = write!(
                s,
                "f0_n = {f0_n}\nalpha = {alpha}\nt0_s = {t0_s}\nprocess_noise_n = \
                 {process_noise_n}\nforce_snr = {force_snr}\naccel_snr = {accel_snr}\n"
            );
            for m in modes {
                let _ = write!(
                    s,
                    "\n[[modes]]\nf_hz = {}\nzeta = {}\nmass_kg = {}\n",
                    m.f_hz, m.zeta, m.mass_kg
                );
            }
        }
    }
    s
}

/// The analyze arguments for a recording written in `dir`.
pub fn analyze_args(spec: &RecordingSpec, dir: &Path) -> Vec<String> {
    let d = dir.display();
    let mut v: Vec<String> = vec![
        "analyze".into(),
        "--frames".into(),
        format!("{d}/frames"),
        "--fps".into(),
        spec.fps.to_string(),
        "--accel".into(),
        format!("{d}/accel.csv"),
        "--fs".into(),
        spec.fs.to_string(),
        "--input-col".into(),
        spec.input_col().into(),
        "--output-col".into(),
        "tip_acc".into(),
        "--time-col".into(),
        "t_s".into(),
        "--threshold".into(),
        spec.threshold().to_string(),
        "--mm-per-px".into(),
        spec.mm_per_px.to_string(),
        "--exposure-ms".into(),
        spec.exposure_ms.to_string(),
    ];
    if let Rig::Grandstand { .. } = spec.rig {
        // SPEC 3.1's estimator and bands
        for a in [
            "--window",
            "hamming",
            "--nperseg",
            "1111",
            "--noverlap",
            "555",
            "--nfft",
            "5000",
            "--bands",
            "1.5-2.25,2.25-2.9",
        ] {
            v.push(a.into());
        }
    }
    v.push("--out".into());
    v.push(format!("{d}/analysis"));
    v
}

/// Simulates one run of `preset` with its nominal modal parameters (seeded excitation and
/// noise) and writes it to `dir`: `frames/frame_00000.png` ..., `accel.csv`
/// (`t_s,base_acc,tip_acc` in m/s^2 for the cantilever, `t_s,force_n,tip_acc` for the
/// grandstand), `recording.toml` and `README.txt` with the exact analyze command.
pub fn write_synthetic_recording(
    preset: Preset,
    seed: u64,
    exposure_ms: f64,
    dir: &Path,
) -> anyhow::Result<RecordingFiles> {
    let spec = match preset {
        Preset::Cantilever => RecordingSpec::cantilever(seed, exposure_ms),
        Preset::Grandstand => RecordingSpec::grandstand(seed, exposure_ms),
    };
    write_recording(&spec, dir)
}

/// Writes the recording of `spec` to `dir` (see [`write_synthetic_recording`]).
pub fn write_recording(spec: &RecordingSpec, dir: &Path) -> anyhow::Result<RecordingFiles> {
    use std::fmt::Write as _;
    let run = simulate(spec)?;
    let frames_dir = dir.join("frames");
    std::fs::create_dir_all(&frames_dir)
        .with_context(|| format!("cannot create {}", frames_dir.display()))?;
    let (w, h) = spec.frame_size;
    for k in 0..spec.frames {
        let px = render_frame(spec, &run, k);
        let p = frames_dir.join(format!("frame_{k:05}.png"));
        image::GrayImage::from_raw(w, h, px)
            .context("frame buffer size")?
            .save(&p)
            .with_context(|| format!("cannot write {}", p.display()))?;
    }
    let mut csv = format!("t_s,{},tip_acc\n", spec.input_col());
    for (j, (b, t)) in run.input.iter().zip(&run.tip_acc).enumerate() {
        let _ = writeln!(csv, "{},{b},{t}", j as f64 / spec.fs);
    }
    let accel_csv = dir.join("accel.csv");
    std::fs::write(&accel_csv, csv)
        .with_context(|| format!("cannot write {}", accel_csv.display()))?;
    let toml = dir.join("recording.toml");
    std::fs::write(&toml, recording_toml(spec))
        .with_context(|| format!("cannot write {}", toml.display()))?;
    let args = analyze_args(spec, dir);
    let (what, unit) = match spec.rig {
        Rig::Cantilever { .. } => ("cantilever", "|tip/base|"),
        Rig::Grandstand { .. } => ("grandstand", "|accelerance| (m/s^2)/N"),
    };
    let mut readme = format!(
        "Synthetic {what} recording ({} frames at {} fps, exposure {} ms, {} transducer \
         samples at {} Hz, seed {}).\n\nAnalyse it with:\n\n  host-harness {}\n\n\
         Expected: modes near",
        spec.frames,
        spec.fps,
        spec.exposure_ms,
        spec.samples(),
        spec.fs,
        spec.seed,
        args.join(" ")
    );
    for f in spec.natural_frequencies() {
        let a = spec.frf(f).norm();
        let a = if a < 0.01 {
            format!("{a:.4e}")
        } else {
            format!("{a:.2}")
        };
        let _ = write!(readme, " {f} Hz ({unit} = {a})");
    }
    readme.push_str(
        " for both systems (one record is one noisy estimate); see recording.toml for all \
         parameters.\n",
    );
    let readme_path = dir.join("README.txt");
    std::fs::write(&readme_path, readme)
        .with_context(|| format!("cannot write {}", readme_path.display()))?;
    Ok(RecordingFiles {
        frames_dir,
        accel_csv,
        toml,
        readme: readme_path,
        analyze_args: args,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cantilever_transmissibility_peaks_near_the_spec_values() {
        let s = RecordingSpec::cantilever(1, 2.0);
        // SPEC 3.2: about 68 for mode 1 and 39 for mode 2
        let a1 = s.frf(7.1).norm();
        let a2 = s.frf(32.4).norm();
        assert!((a1 - 68.0).abs() < 2.0, "{a1}");
        assert!((a2 - 39.0).abs() < 2.0, "{a2}");
        // far below the modes the tip follows the base
        assert!((s.frf(0.01) - Complex64::new(1.0, 0.0)).norm() < 1e-3);
    }

    #[test]
    fn grandstand_accelerance_is_minus_w2_times_the_receptance() {
        let s = RecordingSpec::grandstand(1, 40.0);
        // a single mode well separated: at resonance |G| = 1 / (2 m h w^2)
        let f = 2.0;
        let w = 2.0 * std::f64::consts::PI * f;
        let g1 = 1.0 / (2.0 * 11_885.0 * 0.06 * w * w);
        let a = s.frf(f).norm() / (w * w);
        // the other two modes add a little at 2 Hz
        assert!((a / g1 - 1.0).abs() < 0.35, "{a} vs {g1}");
        // static limit: G(0) = sum 1 / (m w_i^2), accelerance -> 0
        assert!(s.frf(1e-6).norm() < 1e-12);
    }

    #[test]
    fn rendered_disk_is_centred_on_the_displacement() {
        for mut s in [
            RecordingSpec::cantilever(3, 0.0),
            RecordingSpec::grandstand(3, 0.0),
        ] {
            s.frames = 15;
            s.fs = s.fps * 16.0;
            s.fine_per_sample = 1;
            let run = simulate(&s).unwrap();
            let (w, h) = (s.frame_size.0 as usize, s.frame_size.1 as usize);
            for k in 0..15 {
                let px = render_frame(&s, &run, k);
                // weighted centroid of the sharp anti-aliased disk ~ its centre
                let (mut m, mut sy) = (0.0, 0.0);
                for j in 0..h {
                    for i in 0..w {
                        let v = f64::from(px[j * w + i]);
                        m += v;
                        sy += v * j as f64;
                    }
                }
                let want =
                    (h as f64 - 1.0) / 2.0 - run.tip_mm[k * run.fine_per_frame] / s.mm_per_px;
                assert!(
                    (sy / m - want).abs() < 0.05,
                    "frame {k}: {} vs {want}",
                    sy / m
                );
            }
        }
    }

    #[test]
    fn cantilever_tip_moves_the_requested_peak_to_peak() {
        let mut s = RecordingSpec::cantilever(3, 0.0);
        s.frames = 120;
        let run = simulate(&s).unwrap();
        let pp = run.tip_mm.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
            - run.tip_mm.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        assert!((pp - 4.5).abs() < 1e-9, "{pp}");
    }

    #[test]
    fn erfc_matches_known_values() {
        for (x, want) in [
            (0.0, 1.0),
            (0.5, 0.479_500_122),
            (1.0, 0.157_299_207),
            (-1.0, 1.842_700_793),
            (2.0, 0.004_677_735),
        ] {
            assert!(
                (erfc(x) - want).abs() < 2e-7,
                "erfc({x}) = {} vs {want}",
                erfc(x)
            );
        }
    }
}
