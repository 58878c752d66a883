//! The grandstand scenario (method.md §3.1, the paper's simulation): one run draws the platform
//! and the decay test from [`vibcam_model::grandstand`], measures force and displacement with the
//! transducers, films the platform with the camera ([`crate::imaging::Camera`]) at every exposure,
//! and pushes both systems through firmware-core's Welch H1 and peak picking
//! ([`vibcam_chain::frf::measure`]).

use super::{Filming, Reporting, RunRecord, Scenario, StudyConfig};
use crate::imaging::exposure::ExposureCorrection;
use crate::imaging::{Setup, TargetPath};
use firmware_core::spectrum::{scratch_capacity, WelchH1};
use rand_chacha::ChaCha8Rng;
use vibcam_chain::frf::measure;
use vibcam_model::grandstand::{
    simulate, BANDS, FINE, FS_HZ, N, NFFT, NPERSEG, PX_PER_MM, TARGET, THRESHOLD, WELCH,
};

type Welch = WelchH1<NPERSEG, NFFT, { scratch_capacity(NFFT) }>;

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// The grandstand study.
#[derive(Debug)]
pub struct Grandstand {
    /// The resolved `[imaging]` table: effects (identity by default: the fast 8-bit path),
    /// centroid, exposure alignment, view and lost-frame policy.
    imaging: Setup,
    exposures_ms: Vec<f64>,
    /// Path segments per precomputed ramp block: the largest step that divides the frame
    /// period and every half exposure (in fine steps), so windows cover whole blocks.
    block: usize,
    fixed: bool,
    /// The target and the binary threshold (the rig's, or the study file's `[imaging]`).
    target: crate::imaging::DiskTarget,
    threshold: u16,
}

impl Grandstand {
    /// Fine steps simulated before t = 0 (and after the record) for the exposure windows: half
    /// the longest exposure and one step, rounded up to a whole number of ramp blocks, so that
    /// every exposure window (centred on a frame; half-exposures a multiple of the block)
    /// starts and ends on block boundaries and the renderer sums precomputed blocks only. The
    /// padding is the structure at rest: the samples from t = 0 on do not depend on it.
    pub fn padding(&self) -> usize {
        let dt_ms = 1000.0 / (FS_HZ * FINE as f64);
        let max_exp = self.exposures_ms.iter().cloned().fold(0.0, f64::max);
        // an exposure starting at the trigger reaches a whole exposure past the last frame
        let reach = match self.imaging.alignment {
            crate::imaging::ExposureAlignment::Centred => max_exp / 2.0,
            crate::imaging::ExposureAlignment::Trigger => max_exp,
        };
        ((reach / dt_ms).ceil() as usize + 1).div_ceil(self.block) * self.block
    }

    /// Path segments per precomputed ramp block of the renderer.
    pub fn block(&self) -> usize {
        self.block
    }

    /// Builds the scenario from a resolved configuration.
    pub fn new(cfg: &StudyConfig) -> anyhow::Result<Self> {
        let imaging = Setup::from_options(&cfg.imaging)?;
        if !imaging.sees_the_tip() {
            return Err(vibcam_readers::bad_input(
                "imaging.tip_rotation_lever, imaging.target_position_xi: only the cantilever \
                 has a beam to place the target along",
            ));
        }
        let (target, threshold) = cfg.imaging.target_and_threshold(TARGET, THRESHOLD)?;
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
            imaging,
            block: block.max(1),
            exposures_ms: cfg.exposures_ms.clone(),
            fixed: cfg.fixed_structure,
            target,
            threshold,
        })
    }

    fn welch() -> anyhow::Result<Box<Welch>> {
        super::boxed_welch(WELCH)
    }

    /// |FRF| kept up to 5 Hz (0.01 Hz bins).
    const REPORTING: Reporting =
        Reporting::new("grandstand", "mm/kN", &BANDS, (FS_HZ, NFFT), 5.0, false);

    fn keep_bins() -> usize {
        Self::REPORTING.keep_bins()
    }
}

impl Scenario for Grandstand {
    fn reporting(&self) -> Reporting {
        Self::REPORTING
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

    fn exposure_correction(&self) -> anyhow::Result<ExposureCorrection> {
        Ok(ExposureCorrection::for_segments(
            &self.imaging,
            self.target,
            self.threshold,
            &vibcam_model::grandstand::nominal_motion_segments(),
        )?)
    }

    fn run(&self, run: u64, rng: &mut ChaCha8Rng) -> anyhow::Result<RunRecord> {
        let r = simulate(rng, self.fixed, self.padding());
        let bands = self.bands();
        let mut welch = Self::welch()?;
        let transducer = measure(
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
        let path = TargetPath {
            path_px,
            pad: r.pad,
            fine_per_frame: FINE,
            fine_hz: FS_HZ * FINE as f64,
        };
        let camera = Filming {
            imaging: &self.imaging,
            target: &self.target,
            threshold: self.threshold,
            block: self.block,
        };
        let vision = camera.vision_records(
            &path,
            &self.exposures_ms,
            (N, bands.len()),
            |dy| -dy / PX_PER_MM,
            |y| {
                measure(
                    &mut welch,
                    &r.force_meas_kn,
                    y,
                    &bands,
                    Self::keep_bins(),
                    1.0,
                )
            },
            rng,
        )?;
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
    use vibcam_model::grandstand::simulate;

    /// Run `run` of `s` with the tests' seed (the same runs for every configuration).
    fn run_at(s: &Grandstand, run: u64) -> RunRecord {
        s.run(run, &mut crate::study::run_rng(7, run)).unwrap()
    }

    #[test]
    fn fast_imaging_path_gives_the_rendered_frames_records() {
        // The fast path selects the renderer's pixels, so a run's records (every centroid, the
        // vision H1 peaks and |H1|, lost frames) are the same as with every frame rendered:
        // two runs at the shortest and longest exposures, compared exactly.
        let mut cfg = StudyConfig::preset(crate::study::Preset::Grandstand);
        cfg.exposures_ms = vec![40.0, 180.0];
        let fast = Grandstand::new(&cfg).unwrap();
        cfg.imaging.fast_path = Some(false);
        let reference = Grandstand::new(&cfg).unwrap();
        for run in 0..2 {
            assert_eq!(run_at(&fast, run), run_at(&reference, run), "run {run}");
        }
    }

    #[test]
    fn discrete_exposures_take_the_fast_path_to_the_rendered_records_and_lose_more() {
        // the paper's averaging of 5 images: the fast path gives the rendered frames' records,
        // and mode 1 at 180 ms keeps less than with the continuous exposure of the same runs
        let mut cfg = StudyConfig::preset(crate::study::Preset::Grandstand);
        cfg.exposures_ms = vec![40.0, 180.0];
        cfg.fixed_structure = true;
        let continuous = Grandstand::new(&cfg).unwrap();
        cfg.imaging.epsa_images = Some(5);
        let fast = Grandstand::new(&cfg).unwrap();
        cfg.imaging.fast_path = Some(false);
        let reference = Grandstand::new(&cfg).unwrap();
        let amp = |r: &RunRecord, e: usize| r.vision[e].system.peaks[0].unwrap().a;
        for run in 0..2 {
            let got = run_at(&fast, run);
            assert_eq!(got, run_at(&reference, run), "run {run}");
            let c = run_at(&continuous, run);
            let (rd, rc) = (amp(&got, 1) / amp(&got, 0), amp(&c, 1) / amp(&c, 0));
            // Dirichlet (N = 5) 0.719 against the sinc's 0.809 for a linear centroid
            assert!(rd < rc - 0.05, "run {run}: discrete {rd}, continuous {rc}");
        }
    }

    #[test]
    fn exposure_at_the_trigger_delays_the_vision_record() {
        // Starting at the trigger with the timestamps left there, the centroid is late by half
        // the exposure: H1 turns by pi f Te, so the |Im H1| peak moves off resonance (to a higher
        // frequency for a receptance seen late) and |H1| there drops, by about cos(pi f Te / 2)
        // for a single mode. Fixed structure, the same runs (common random numbers), 180 ms.
        let mut cfg = StudyConfig::preset(crate::study::Preset::Grandstand);
        cfg.exposures_ms = vec![180.0];
        cfg.fixed_structure = true;
        let centred = Grandstand::new(&cfg).unwrap();
        cfg.imaging.exposure_alignment = Some(crate::imaging::ExposureAlignment::Trigger);
        let trigger = Grandstand::new(&cfg).unwrap();
        assert!(trigger.padding() > centred.padding());
        let (mut df, mut ratio) = (0.0, 0.0);
        let runs = 4;
        for run in 0..runs {
            let pick = |s: &Grandstand| {
                let r = s.run(run, &mut crate::study::run_rng(3, run)).unwrap();
                r.vision[0].system.peaks[0].unwrap()
            };
            let (c, t) = (pick(&centred), pick(&trigger));
            df += (t.f_hz - c.f_hz) / runs as f64;
            ratio += t.a / c.a / runs as f64;
        }
        let predicted = (std::f64::consts::PI * 2.0 * 0.18 / 2.0).cos(); // 0.844 at 2 Hz
        assert!(df > 0.02, "mode 1 moved by {df} Hz");
        assert!(
            (ratio - predicted).abs() < 0.08,
            "ratio {ratio}, single-mode {predicted}"
        );
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
            let got = measure(&mut welch, &force, &disp, &BANDS, 0, 1.0).unwrap();
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
                    let w = firmware_core::spectrum::Window::Hamming.value(n, NPERSEG) as f64;
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
        for (b, band) in BANDS.iter().enumerate() {
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
            let f = vibcam_common::stats::mean(&fs[b]).unwrap();
            let a = vibcam_common::stats::mean(&amps[b]).unwrap();
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
