//! The structures under test and what excites them, one module per rig (method.md §3): modal
//! parameters and their PDFs, excitation, the exact response, the transducers' noise and the
//! closed-form FRFs the tests compare with. Each rig's constants live in its module and nowhere
//! else.
//!
//! - [`grandstand`]: the paper's simulation (three-mode platform, decay test, 50 fps camera);
//! - [`cantilever`]: the paper's laboratory rig (base-excited two-mode beam, 120 fps camera);
//! - [`simulate`]: one run of either rig, periodic over the record, computed exactly in the
//!   frequency domain on a fine time base (what synthetic recordings and the cantilever study
//!   use; the grandstand study integrates its transient response in the time domain instead,
//!   [`grandstand::simulate`]).

pub mod cantilever;
pub mod field;
pub mod grandstand;
pub mod hammer;
pub mod target;

pub use target::{DiskTarget, Texture};

use num_complex::Complex64;
use rand::{Rng, SeedableRng as _};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution as _, StandardNormal};
use vibcam_readers::bad_input;

/// Standard gravity, m/s^2 (firmware-core's value).
pub const G0: f64 = firmware_core::convert::STANDARD_GRAVITY_F64;

/// A uniform variable given by its mean and standard deviation (spans `m +/- s sqrt 3`).
pub fn uniform_ms(rng: &mut ChaCha8Rng, mean: f64, std: f64) -> f64 {
    let u: f64 = rng.random();
    mean + std * 3f64.sqrt() * (2.0 * u - 1.0)
}

/// A normal variable.
pub fn normal(rng: &mut ChaCha8Rng, mean: f64, std: f64) -> f64 {
    let z: f64 = StandardNormal.sample(rng);
    mean + std * z
}

/// Either rig, as a synthetic run simulates it.
#[derive(Debug, Clone, PartialEq)]
pub enum Rig {
    /// Base-excited cantilever, two accelerometers.
    Cantilever(cantilever::Rig),
    /// Force-excited grandstand (decay test), load cell and tip accelerometer.
    Grandstand(grandstand::DecayTest),
}

impl Rig {
    /// Closed-form FRF from the input (base acceleration, or force) to the tip acceleration at
    /// `f_hz`: the cantilever's transmissibility, or the grandstand's accelerance in (m/s^2)/N.
    pub fn frf(&self, f_hz: f64) -> Complex64 {
        match self {
            Rig::Cantilever(rig) => rig.transmissibility(f_hz),
            Rig::Grandstand(test) => grandstand::accelerance(&test.modes, f_hz),
        }
    }

    /// The motion's FRF ([`Rig::frf`], what the camera sees) and what the tip transducer reads
    /// per unit input at `f_hz`: the same, except on a cantilever whose tip accelerometer reads
    /// gravity as it tilts ([`cantilever::Rig::accelerometer_transmissibility`]); computed once
    /// where they coincide.
    pub fn motion_and_transducer_frf(&self, f_hz: f64) -> (Complex64, Complex64) {
        let h = self.frf(f_hz);
        match self {
            Rig::Cantilever(rig) if rig.accel_tilt_gain != 0.0 => {
                (h, rig.accelerometer_transmissibility(f_hz))
            }
            _ => (h, h),
        }
    }

    /// Natural frequencies of the modes, Hz.
    pub fn natural_frequencies(&self) -> Vec<f64> {
        match self {
            Rig::Cantilever(rig) => rig.modes.iter().map(|m| m.f_hz).collect(),
            Rig::Grandstand(test) => test.modes.iter().map(|m| m.f_hz).collect(),
        }
    }

    /// Name of the input channel (`base_acc` or `force_n`).
    pub fn input_col(&self) -> &'static str {
        match self {
            Rig::Cantilever(_) => "base_acc",
            Rig::Grandstand(_) => "force_n",
        }
    }
}

/// The time bases of a run: frames at `fps`, transducer samples at `fs`, and a fine time base of
/// `fs * fine_per_sample` on which the camera integrates the motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Acquisition {
    /// Camera frame rate, Hz.
    pub fps: f64,
    /// Transducer sample rate, Hz.
    pub fs: f64,
    /// Fine steps per transducer sample; `fs * fine_per_sample / fps` must be an integer.
    pub fine_per_sample: usize,
    /// Number of frames.
    pub frames: usize,
}

impl Acquisition {
    /// Transducer samples covered by the frames, `frames * fs / fps`.
    pub fn samples(&self) -> usize {
        (self.frames as f64 * self.fs / self.fps).round() as usize
    }

    /// Rate of the fine time base, Hz.
    pub fn fine_hz(&self) -> f64 {
        self.fs * self.fine_per_sample as f64
    }

    /// Checks the rates; returns (fine steps per frame, fine steps in the record).
    pub fn validate(&self) -> anyhow::Result<(usize, usize)> {
        let fine_hz = self.fine_hz();
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

/// Simulates one run of `rig` with the streams of `seed`: the input spectrum on the fine grid
/// (the cantilever's flat complex Gaussian spectrum on its band; the grandstand's pulse plus held
/// process noise), the response through the closed-form FRF (periodic steady state, no
/// transient), the cantilever scaled to its tip peak-to-peak, and the transducer noise (the
/// cantilever's accelerometer noise in g; the grandstand's SNRs).
pub fn simulate(rig: &Rig, acq: &Acquisition, seed: u64) -> anyhow::Result<SyntheticRun> {
    Ok(simulate_at(rig, acq, seed, &[])?.0)
}

/// [`simulate`], and the displacement (mm, on the fine time base, as `tip_mm`) at each position
/// `xi = x / L` of `positions` along the cantilever (the same run: the same input and scale;
/// the grandstand has no positions and refuses any).
pub fn simulate_at(
    rig: &Rig,
    acq: &Acquisition,
    seed: u64,
    positions: &[f64],
) -> anyhow::Result<(SyntheticRun, Vec<Vec<f64>>)> {
    let views: Vec<cantilever::View> = positions
        .iter()
        .map(|&xi| cantilever::View { xi, lever: 0.0 })
        .collect();
    simulate_seen(rig, acq, seed, &views)
}

/// The factor that takes the unnormalised inverse transforms of [`simulate_seen`] to
/// physical units: the cantilever's tip motion scaled to its peak to peak (`tip_pp_mm`), the
/// grandstand's `1 / n`.
fn output_scale(rig: &Rig, tip_mm: &[Complex64], n: usize) -> f64 {
    match rig {
        Rig::Cantilever(cantilever::Rig { tip_pp_mm, .. }) => {
            let (lo, hi) = tip_mm
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(v.re), b.max(v.re))
                });
            tip_pp_mm / (hi - lo)
        }
        Rig::Grandstand(_) => 1.0 / n as f64,
    }
}

/// [`simulate`], and what each of `views` sees of the cantilever (mm on the fine time base, as
/// `tip_mm`; [`cantilever::View`]: a position along the beam and a projected rotation).
pub fn simulate_seen(
    rig: &Rig,
    acq: &Acquisition,
    seed: u64,
    views: &[cantilever::View],
) -> anyhow::Result<(SyntheticRun, Vec<Vec<f64>>)> {
    let positions = views;
    let beam = match rig {
        Rig::Cantilever(beam) => Some(beam),
        Rig::Grandstand(_) if positions.is_empty() => None,
        Rig::Grandstand(_) => anyhow::bail!("targets along the structure need the cantilever"),
    };
    let (fine_per_frame, n) = acq.validate()?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut planner = vibcam_fft::Planner::new();
    let mut input = input_spectrum(rig, acq, n, &mut rng, &mut planner);
    let df = acq.fine_hz() / n as f64;
    let mut tip_acc = vec![Complex64::new(0.0, 0.0); n];
    let mut tip_mm = vec![Complex64::new(0.0, 0.0); n];
    let mut at_mm = vec![vec![Complex64::new(0.0, 0.0); n]; positions.len()];
    // each view's per-mode factors, once: they do not depend on the frequency
    let view_factors: Vec<Vec<f64>> = beam.map_or(Vec::new(), |b| {
        positions
            .iter()
            .map(|v| (0..b.modes.len()).map(|i| v.factor(i)).collect())
            .collect()
    });
    for k in 1..n {
        let signed = if k <= n / 2 {
            k as f64
        } else {
            k as f64 - n as f64
        };
        let f = signed * df;
        let side = |h: Complex64| if signed >= 0.0 { h } else { h.conj() };
        // the accelerometer reads its own tilt too (a cantilever standing in gravity); the
        // camera sees the motion
        let (motion, reading) = rig.motion_and_transducer_frf(f.abs());
        let h = side(motion);
        let w = 2.0 * std::f64::consts::PI * f;
        tip_acc[k] = input[k] * side(reading);
        tip_mm[k] = -input[k] * h / (w * w) * 1000.0;
        if let Some(b) = beam {
            for (buf, factors) in at_mm.iter_mut().zip(&view_factors) {
                let h = side(b.transmissibility_scaled(f.abs(), factors));
                buf[k] = -input[k] * h / (w * w) * 1000.0;
            }
        }
    }
    let ifft = planner.inverse(n);
    for buf in [&mut input, &mut tip_acc, &mut tip_mm]
        .into_iter()
        .chain(at_mm.iter_mut())
    {
        ifft.process(buf);
    }
    // the inverse is unnormalised: one common factor, removed by the scaling below
    let scale = output_scale(rig, &tip_mm, n);
    let step = acq.fine_per_sample;
    let clean_in: Vec<f64> = input.iter().step_by(step).map(|v| v.re * scale).collect();
    let clean_tip: Vec<f64> = tip_acc.iter().step_by(step).map(|v| v.re * scale).collect();
    let (input, tip_acc) = add_transducer_noise(rig, clean_in, clean_tip, &mut rng);
    let at_mm = at_mm
        .iter()
        .map(|b| b.iter().map(|v| v.re * scale).collect())
        .collect();
    let run = SyntheticRun {
        input,
        tip_acc,
        tip_mm: tip_mm.iter().map(|v| v.re * scale).collect(),
        fine_per_frame,
    };
    Ok((run, at_mm))
}

/// The input's spectrum on the fine grid of `n` steps: the cantilever's complex Gaussian on its
/// band (Hermitian); the grandstand's pulse plus process noise held over each transducer sample,
/// transformed.
fn input_spectrum(
    rig: &Rig,
    acq: &Acquisition,
    n: usize,
    rng: &mut ChaCha8Rng,
    planner: &mut vibcam_fft::Planner,
) -> Vec<Complex64> {
    let fine_hz = acq.fine_hz();
    let df = fine_hz / n as f64;
    let mut input = vec![Complex64::new(0.0, 0.0); n];
    match rig {
        Rig::Cantilever(cantilever::Rig { band_hz, .. }) => {
            for k in 1..n / 2 {
                let f = k as f64 * df;
                if f < band_hz.0 || f > band_hz.1 {
                    continue;
                }
                let re: f64 = StandardNormal.sample(rng);
                let im: f64 = StandardNormal.sample(rng);
                input[k] = Complex64::new(re, im);
                input[n - k] = input[k].conj();
            }
        }
        Rig::Grandstand(test) => {
            let mut held = 0.0;
            for (j, v) in input.iter_mut().enumerate() {
                if j % acq.fine_per_sample == 0 {
                    let z: f64 = StandardNormal.sample(rng);
                    held = test.process_noise_n * z;
                }
                *v = Complex64::new(test.pulse(j as f64 / fine_hz) + held, 0.0);
            }
            planner.forward(n).process(&mut input);
        }
    }
    input
}

/// The transducers' noise added to the clean input and tip records: the cantilever's
/// accelerometer noise in g, the grandstand's signal-to-noise ratios.
fn add_transducer_noise(
    rig: &Rig,
    clean_in: Vec<f64>,
    clean_tip: Vec<f64>,
    rng: &mut ChaCha8Rng,
) -> (Vec<f64>, Vec<f64>) {
    let (in_noise, tip_noise) = match rig {
        Rig::Cantilever(cantilever::Rig { accel_noise_g, .. }) => {
            (accel_noise_g * G0, accel_noise_g * G0)
        }
        Rig::Grandstand(test) => (
            rms(&clean_in) / test.force_snr,
            rms(&clean_tip) / test.accel_snr,
        ),
    };
    let mut noisy = |clean: Vec<f64>, std: f64| -> Vec<f64> {
        clean
            .into_iter()
            .map(|v| {
                let z: f64 = StandardNormal.sample(&mut *rng);
                v + std * z
            })
            .collect()
    };
    let input = noisy(clean_in, in_noise);
    (input, noisy(clean_tip, tip_noise))
}

/// One Welch segment of a motion as the H1 estimator sees it: the weight of the segment in the
/// estimate (the energy of the windowed input) and the amplitude of the target's motion in it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionSegment {
    /// Energy of the windowed input in the segment (any unit; only ratios matter).
    pub weight: f64,
    /// Equivalent sinusoidal amplitude of the target's motion in the segment, px.
    pub amplitude_px: f64,
}

/// The amplitude of the sinusoid with the RMS of a motion `path_px` (px): `sqrt(2) RMS` about
/// its mean. The one number a binary correction table is measured at.
pub fn equivalent_amplitude_px(path_px: &[f64]) -> f64 {
    let n = path_px.len().max(1) as f64;
    let mean = path_px.iter().sum::<f64>() / n;
    let ms = path_px.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n;
    (2.0 * ms).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn short(fps: f64, frames: usize) -> Acquisition {
        Acquisition {
            fps,
            fs: fps * 16.0,
            fine_per_sample: 1,
            frames,
        }
    }

    #[test]
    fn cantilever_tip_moves_the_requested_peak_to_peak() {
        let rig = Rig::Cantilever(cantilever::Rig::nominal());
        let run = simulate(&rig, &short(120.0, 120), 3).unwrap();
        let pp = run.tip_mm.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
            - run.tip_mm.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        assert!((pp - cantilever::TIP_PP_MM).abs() < 1e-9, "{pp}");
    }

    #[test]
    fn noise_free_response_is_the_closed_form_frf_at_every_bin() {
        // a periodic record's DFT is exactly input x FRF at each bin: check the tip against the
        // input through the closed form, with the transducer noise switched off
        let mut rig = cantilever::Rig::nominal();
        rig.accel_noise_g = 0.0;
        let rig = Rig::Cantilever(rig);
        let acq = short(120.0, 240);
        let run = simulate(&rig, &acq, 5).unwrap();
        let n = run.input.len();
        let mut planner = vibcam_fft::Planner::new();
        let fft = planner.forward(n);
        let spec = |v: &[f64]| {
            let mut b: Vec<Complex64> = v.iter().map(|x| Complex64::new(*x, 0.0)).collect();
            fft.process(&mut b);
            b
        };
        let (x, y) = (spec(&run.input), spec(&run.tip_acc));
        let peak = x.iter().map(|v| v.norm()).fold(0.0, f64::max);
        for k in 1..n / 2 {
            if x[k].norm() < 1e-6 * peak {
                continue; // outside the excitation band
            }
            let f = k as f64 * acq.fs / n as f64;
            let want = rig.frf(f);
            assert!(((y[k] / x[k]) - want).norm() < 1e-9 * want.norm(), "{f} Hz");
        }
    }

    #[test]
    fn a_tilting_tip_accelerometer_reads_gravity_times_the_tip_slope() {
        // time domain, against the frequency-domain implementation: the tip slope comes from a
        // view with a lever of one beam length ((seen - tip) = phi' q per beam length), and an
        // accelerometer turning with an upright beam reads a - g theta (hanging: a + g theta)
        let acq = short(120.0, 240);
        let mut beam = cantilever::Rig::nominal();
        beam.accel_noise_g = 0.0;
        let view = cantilever::View {
            xi: 1.0,
            lever: 1.0,
        };
        let (plain, seen) =
            simulate_seen(&Rig::Cantilever(beam.clone()), &acq, 7, &[view]).unwrap();
        let length_m = 0.15;
        for (tilt, sign) in [
            (cantilever::Tilt::Upright, -1.0),
            (cantilever::Tilt::Hanging, 1.0),
        ] {
            let mut tilted = beam.clone();
            (tilted.accel_tilt_gain, tilted.beam_length_m) = (tilt.gain(), length_m);
            let run = simulate(&Rig::Cantilever(tilted), &acq, 7).unwrap();
            // the camera's record does not change
            assert_eq!(run.tip_mm, plain.tip_mm);
            assert_eq!(run.input, plain.input);
            let peak = plain.tip_acc.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let mut largest = 0.0f64;
            for (n, (&a, &read)) in plain.tip_acc.iter().zip(&run.tip_acc).enumerate() {
                let k = n * acq.fine_per_sample;
                let theta = (seen[0][k] - plain.tip_mm[k]) / 1000.0 / length_m;
                let want = a + sign * cantilever::STANDARD_GRAVITY * theta;
                assert!(
                    (read - want).abs() < 1e-9 * peak,
                    "{tilt:?}, sample {n}: {read} vs {want}"
                );
                largest = largest.max((read - a).abs());
            }
            // and the tilt reading is there to see (a few percent of the motion's acceleration)
            assert!(largest > 0.01 * peak, "{tilt:?}: {largest} of {peak}");
        }
    }

    #[test]
    fn acquisition_rejects_rates_that_do_not_divide() {
        let mut a = short(120.0, 15);
        a.fs = 1000.0;
        assert!(a.validate().is_err());
        a.fs = 2048.0;
        a.fine_per_sample = 15;
        assert_eq!(a.validate().unwrap(), (256, 3840));
        a.frames = 7;
        assert!(a.validate().is_err());
    }
}
