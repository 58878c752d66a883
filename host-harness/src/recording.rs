//! Synthetic recordings: one simulated cantilever run written as a real rig would record it —
//! grey PNG frames plus an accelerometer CSV — so that `host-harness analyze` can be tried at
//! once, and its output checked against known modal parameters.
//!
//! # What is simulated (SPEC 3.2, nominal parameters, no run-to-run scatter)
//!
//! * Base-excited modal model `q_i'' + 2 h_i w_i q_i' + w_i^2 q_i = -G_i xb''`,
//!   `tip = xb + sum phi_i q_i` with the cantilever's `f_i`, `h_i`, `G_i phi_i`.
//! * Band-limited random base acceleration (flat complex Gaussian spectrum on 5-50 Hz), built
//!   **periodic over the record** on a fine time base of `fs * 15` Hz (30 720 Hz for 2048 Hz /
//!   120 fps, the common clock of SPEC 2.7). Because the record is periodic, the response is
//!   computed exactly in the frequency domain (steady state, no transient): tip acceleration
//!   `A_tip = A_b (1 + sum G_i phi_i w^2 / (w_i^2 - w^2 + 2 i h_i w_i w))`, tip displacement
//!   `A_tip / (-w^2)`. The excitation is scaled so that the tip moves `tip_pp_mm` peak to peak.
//! * Accelerometers: base and tip acceleration at `fs` with Gaussian noise of
//!   `accel_noise_g` RMS (0.00015 g).
//! * Camera: frame `k` at `t = k / fps`, exposure centred on it. The frame is the average of the
//!   instantaneous images over the exposure (the fine-step positions inside the exposure window,
//!   at least 8 instants), each a white disk of radius `radius_px` on black with a one-pixel
//!   linear anti-aliasing ramp (coverage `clamp(r + 0.5 - d, 0, 1)`), at level `level`, 8 bit.
//!   A positive tip displacement moves the disk **up** in the image (the `--axis y` convention
//!   of `analyze`).
//!
//! TODO(imaging): the EPSA renderer of [`crate::imaging`] and the time-domain model of
//! [`crate::model`] were not available when this was written; this module uses the exact
//! frequency-domain response and a direct time-averaged renderer described above.

use crate::bad_input;
use crate::study::Preset;
use anyhow::Context as _;
use num_complex::Complex64;
use rand::SeedableRng as _;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution as _, StandardNormal};
use std::path::{Path, PathBuf};

/// One mode of the base-excited model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaseExcitedMode {
    /// Natural frequency, Hz.
    pub f_hz: f64,
    /// Damping ratio.
    pub zeta: f64,
    /// Participation times tip mode shape, `G_i phi_i`.
    pub g_phi: f64,
}

/// Everything a synthetic recording depends on.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordingSpec {
    /// Seed of the excitation and noise streams (ChaCha8).
    pub seed: u64,
    /// Camera exposure, ms (centred on the frame time), `0 <= exposure < 1000 / fps`.
    pub exposure_ms: f64,
    /// Camera frame rate, Hz.
    pub fps: f64,
    /// Accelerometer sample rate, Hz.
    pub fs: f64,
    /// Fine time step per accelerometer sample (the fine rate is `fs * fine_per_sample`);
    /// `fs * fine_per_sample / fps` must be an integer.
    pub fine_per_sample: usize,
    /// Number of frames.
    pub frames: usize,
    /// Scale, mm per pixel.
    pub mm_per_px: f64,
    /// Target radius, px.
    pub radius_px: f64,
    /// Target grey level (8-bit); the background is 0.
    pub level: u8,
    /// Frame size, px (width, height).
    pub frame_size: (u32, u32),
    /// Modes of the structure.
    pub modes: Vec<BaseExcitedMode>,
    /// Excitation band, Hz.
    pub band_hz: (f64, f64),
    /// Tip motion peak to peak, mm.
    pub tip_pp_mm: f64,
    /// Accelerometer noise, g RMS.
    pub accel_noise_g: f64,
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
            level: 200,
            frame_size: (40, 112),
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
        }
    }

    /// Threshold of the binary centroid: half the target level.
    pub fn threshold(&self) -> u16 {
        u16::from(self.level / 2)
    }

    /// Accelerometer samples covered by the frames, `frames * fs / fps`.
    pub fn samples(&self) -> usize {
        (self.frames as f64 * self.fs / self.fps).round() as usize
    }

    /// Closed-form tip/base acceleration transmissibility at `f_hz`.
    pub fn transmissibility(&self, f_hz: f64) -> Complex64 {
        let w = 2.0 * std::f64::consts::PI * f_hz;
        let mut h = Complex64::new(1.0, 0.0);
        for m in &self.modes {
            let wn = 2.0 * std::f64::consts::PI * m.f_hz;
            h += m.g_phi * w * w / Complex64::new(wn * wn - w * w, 2.0 * m.zeta * wn * w);
        }
        h
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
        if !(self.exposure_ms >= 0.0 && self.exposure_ms < 1000.0 / self.fps) {
            return Err(bad_input(format!(
                "exposure {} ms must be >= 0 and shorter than the frame period {} ms",
                self.exposure_ms,
                1000.0 / self.fps
            )));
        }
        Ok((ppf, self.frames * ppf))
    }
}

/// A simulated run in memory.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntheticRun {
    /// Base acceleration at `fs`, m/s^2 (with noise).
    pub base_acc: Vec<f64>,
    /// Tip acceleration at `fs`, m/s^2 (with noise).
    pub tip_acc: Vec<f64>,
    /// Tip displacement on the fine time base, mm (`frames * fine_per_frame` values, periodic).
    pub tip_mm: Vec<f64>,
    /// Fine samples per frame period.
    pub fine_per_frame: usize,
}

/// Simulates the run (see the module documentation).
pub fn simulate(spec: &RecordingSpec) -> anyhow::Result<SyntheticRun> {
    let (fine_per_frame, n) = spec.validate()?;
    let fine_hz = spec.fs * spec.fine_per_sample as f64;
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    // base acceleration spectrum: complex Gaussian on the band, Hermitian
    let df = fine_hz / n as f64;
    let mut ab = vec![Complex64::new(0.0, 0.0); n];
    let mut at = vec![Complex64::new(0.0, 0.0); n];
    let mut xt = vec![Complex64::new(0.0, 0.0); n];
    for k in 1..n / 2 {
        let f = k as f64 * df;
        if f < spec.band_hz.0 || f > spec.band_hz.1 {
            continue;
        }
        let re: f64 = StandardNormal.sample(&mut rng);
        let im: f64 = StandardNormal.sample(&mut rng);
        let a = Complex64::new(re, im);
        let t = a * spec.transmissibility(f);
        let w = 2.0 * std::f64::consts::PI * f;
        let x = -t / (w * w) * 1000.0; // mm
        for (buf, v) in [(&mut ab, a), (&mut at, t), (&mut xt, x)] {
            buf[k] = v;
            buf[n - k] = v.conj();
        }
    }
    let ifft = rustfft::FftPlanner::<f64>::new().plan_fft_inverse(n);
    for buf in [&mut ab, &mut at, &mut xt] {
        ifft.process(buf);
    }
    let tip: Vec<f64> = xt.iter().map(|v| v.re).collect();
    let (lo, hi) = tip
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let scale = spec.tip_pp_mm / (hi - lo);
    let noise = spec.accel_noise_g * G0;
    let mut sample = |v: &Complex64| {
        let z: f64 = StandardNormal.sample(&mut rng);
        v.re * scale + noise * z
    };
    let step = spec.fine_per_sample;
    let base_acc = ab.iter().step_by(step).map(&mut sample).collect();
    let tip_acc = at.iter().step_by(step).map(&mut sample).collect();
    Ok(SyntheticRun {
        base_acc,
        tip_acc,
        tip_mm: tip.iter().map(|v| v * scale).collect(),
        fine_per_frame,
    })
}

/// Renders frame `k` of a run: the time average over the exposure of the anti-aliased disk.
pub fn render_frame(spec: &RecordingSpec, run: &SyntheticRun, k: usize) -> Vec<u8> {
    let (w, h) = (spec.frame_size.0 as usize, spec.frame_size.1 as usize);
    let n = run.tip_mm.len();
    let fine_dt = 1.0 / (spec.fps * run.fine_per_frame as f64);
    let exposure = spec.exposure_ms / 1000.0;
    // positions at the fine steps inside the centred window (periodic record), >= 8 instants
    let half = exposure / 2.0;
    let count = ((exposure / fine_dt).floor() as usize + 1).max(8);
    let centre = (k * run.fine_per_frame) as f64;
    let positions: Vec<f64> = (0..count)
        .map(|i| {
            let t = if count == 1 || exposure == 0.0 {
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
    let mut acc = vec![0.0f64; w * h];
    for d_mm in &positions {
        let cy = cy0 - d_mm / spec.mm_per_px;
        let j0 = ((cy - r - 2.0).floor().max(0.0)) as usize;
        let j1 = ((cy + r + 2.0).ceil() as usize).min(h - 1);
        for j in j0..=j1 {
            let dy = j as f64 - cy;
            for i in 0..w {
                let dx = i as f64 - cx;
                let d = (dx * dx + dy * dy).sqrt();
                acc[j * w + i] += (r + 0.5 - d).clamp(0.0, 1.0);
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
    /// `accel.csv` (`t_s,base_acc,tip_acc`).
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
    let mut s = format!(
        "# synthetic cantilever recording written by host-harness render --recording\n\
         preset = \"cantilever\"\nseed = {}\nexposure_ms = {}\nfps = {}\nfs = {}\nframes = {}\n\
         samples = {}\nmm_per_px = {}\nradius_px = {}\nlevel = {}\nthreshold = {}\n\
         frame_size = [{}, {}]\nband_hz = [{}, {}]\ntip_pp_mm = {}\naccel_noise_g = {}\n",
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
        spec.band_hz.0,
        spec.band_hz.1,
        spec.tip_pp_mm,
        spec.accel_noise_g
    );
    for m in &spec.modes {
        let _ = write!(
            s,
            "\n[[modes]]\nf_hz = {}\nzeta = {}\ng_phi = {}\n",
            m.f_hz, m.zeta, m.g_phi
        );
    }
    s
}

/// The analyze arguments for a recording written in `dir`.
pub fn analyze_args(spec: &RecordingSpec, dir: &Path) -> Vec<String> {
    let d = dir.display();
    vec![
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
        "base_acc".into(),
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
        "--out".into(),
        format!("{d}/analysis"),
    ]
}

/// Simulates one run of `preset` and writes it to `dir`: `frames/frame_00000.png` ...,
/// `accel.csv` (`t_s,base_acc,tip_acc`, m/s^2), `recording.toml` and `README.txt` with the
/// exact analyze command. Only the cantilever preset has accelerometers; the grandstand preset
/// is refused.
pub fn write_synthetic_recording(
    preset: Preset,
    seed: u64,
    exposure_ms: f64,
    dir: &Path,
) -> anyhow::Result<RecordingFiles> {
    let spec = match preset {
        Preset::Cantilever => RecordingSpec::cantilever(seed, exposure_ms),
        Preset::Grandstand => {
            return Err(bad_input(
                "synthetic recordings are written for the cantilever preset only (the \
                 grandstand rig has a load cell and a laser, not accelerometers)",
            ))
        }
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
    let mut csv = String::from("t_s,base_acc,tip_acc\n");
    for (j, (b, t)) in run.base_acc.iter().zip(&run.tip_acc).enumerate() {
        let _ = writeln!(csv, "{},{b},{t}", j as f64 / spec.fs);
    }
    let accel_csv = dir.join("accel.csv");
    std::fs::write(&accel_csv, csv)
        .with_context(|| format!("cannot write {}", accel_csv.display()))?;
    let toml = dir.join("recording.toml");
    std::fs::write(&toml, recording_toml(spec))
        .with_context(|| format!("cannot write {}", toml.display()))?;
    let args = analyze_args(spec, dir);
    let mut readme = format!(
        "Synthetic cantilever recording ({} frames at {} fps, exposure {} ms, {} accelerometer \
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
    for m in &spec.modes {
        let _ = write!(
            readme,
            " {} Hz (|T| = {:.1})",
            m.f_hz,
            spec.transmissibility(m.f_hz).norm()
        );
    }
    readme.push_str(" for both systems; see recording.toml for all parameters.\n");
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
    fn transmissibility_peaks_near_the_spec_values() {
        let s = RecordingSpec::cantilever(1, 2.0);
        // SPEC 3.2: about 68 for mode 1 and 39 for mode 2
        let a1 = s.transmissibility(7.1).norm();
        let a2 = s.transmissibility(32.4).norm();
        assert!((a1 - 68.0).abs() < 2.0, "{a1}");
        assert!((a2 - 39.0).abs() < 2.0, "{a2}");
    }

    #[test]
    fn rendered_disk_is_centred_on_the_displacement() {
        let mut s = RecordingSpec::cantilever(3, 0.0);
        s.frames = 15;
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
            let want = (h as f64 - 1.0) / 2.0 - run.tip_mm[k * run.fine_per_frame] / s.mm_per_px;
            assert!(
                (sy / m - want).abs() < 0.05,
                "frame {k}: {} vs {want}",
                sy / m
            );
        }
        let pp = run.tip_mm.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
            - run.tip_mm.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        assert!((pp - s.tip_pp_mm).abs() < 1e-9);
    }
}
