//! The cantilever scenario (method.md §3.2, the paper's laboratory validation replayed in
//! simulation): one run draws the rig's scatter ([`vibcam_model::cantilever`]), simulates a 10 s
//! test exactly in the frequency domain ([`vibcam_model::simulate`], periodic on the 30 720 Hz
//! common clock), and measures it with both systems. The vision path is the embedded chain, all
//! in firmware-core: centroid -> mm -> Fourier upsampling 1200 -> 20480 fused with `-omega^2` ->
//! H1 against the base acceleration -> peaks. The `[imaging]` options of a study file apply as
//! in the grandstand ([`crate::imaging::Camera`]).

use super::{Filming, Reporting, RunRecord, Scenario, StudyConfig};
use crate::imaging::exposure::ExposureCorrection;
use crate::imaging::{Setup, TargetPath};
use firmware_core::spectrum::{scratch_capacity, WelchH1};
use firmware_core::upsample::{self, Upsampler};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use vibcam_chain::frf::measure;
use vibcam_model::cantilever::{
    Rig, BANDS, FINE_PER_SAMPLE, FPS, FRAMES, FS_HZ, MM_PER_PX, SAMPLES, TARGET, THRESHOLD, WELCH,
};
use vibcam_model::{self as model, Acquisition};

type Welch = WelchH1<SAMPLES, SAMPLES, { scratch_capacity(SAMPLES) }>;
type Up = Upsampler<SAMPLES, { upsample::scratch_capacity(FRAMES, SAMPLES) }>;

/// The acquisition of one test: 1200 frames at 120 fps, 20480 samples at 2048 Hz.
pub const ACQUISITION: Acquisition = Acquisition {
    fps: FPS,
    fs: FS_HZ,
    fine_per_sample: FINE_PER_SAMPLE,
    frames: FRAMES,
};

/// The cantilever study.
#[derive(Debug)]
pub struct Cantilever {
    /// The resolved `[imaging]` table: effects (identity by default: the fast 8-bit path),
    /// centroid, exposure alignment, view and lost-frame policy.
    imaging: Setup,
    /// The target and the binary threshold (the rig's, or the study file's `[imaging]`).
    target: crate::imaging::DiskTarget,
    threshold: u16,
    exposures_ms: Vec<f64>,
    fixed: bool,
    /// The tip accelerometer's tilt gain (m/s^2 per radian) and the beam length (m), `[rig]`.
    accel_tilt: (f64, f64),
}

impl Cantilever {
    /// |FRF| kept up to this frequency, Hz.
    pub const FRF_MAX_HZ: f64 = 60.0;

    /// Builds the scenario from a resolved configuration.
    pub fn new(cfg: &StudyConfig) -> anyhow::Result<Self> {
        let imaging = Setup::from_options(&cfg.imaging)?;
        let (target, threshold) = cfg.imaging.target_and_threshold(TARGET, THRESHOLD)?;
        let period_ms = 1000.0 / FPS;
        if let Some(e) = cfg.exposures_ms.iter().find(|e| **e >= period_ms) {
            return Err(vibcam_readers::bad_input(format!(
                "exposures_ms: {e} ms is not shorter than the {period_ms:.3} ms frame period"
            )));
        }
        Ok(Cantilever {
            imaging,
            target,
            threshold,
            exposures_ms: cfg.exposures_ms.clone(),
            fixed: cfg.fixed_structure,
            accel_tilt: cfg.rig.accel_tilt()?,
        })
    }

    fn welch() -> anyhow::Result<Box<Welch>> {
        super::boxed_welch(WELCH)
    }

    const REPORTING: Reporting = Reporting::new(
        "cantilever",
        "(m/s^2)/(m/s^2)",
        &BANDS,
        (FS_HZ, SAMPLES),
        Self::FRF_MAX_HZ,
        true,
    );

    fn keep_bins() -> usize {
        Self::REPORTING.keep_bins()
    }
}

impl Scenario for Cantilever {
    fn reporting(&self) -> Reporting {
        Self::REPORTING
    }

    fn exposure_correction(&self) -> anyhow::Result<ExposureCorrection> {
        Ok(ExposureCorrection::for_segments(
            &self.imaging,
            self.target,
            self.threshold,
            &vibcam_model::cantilever::nominal_motion_segments(&ACQUISITION)?,
        )?)
    }

    fn run(&self, run: u64, rng: &mut ChaCha8Rng) -> anyhow::Result<RunRecord> {
        // the test's seed first, then the rig's scatter: the order of the draws is the contract
        // that keeps results reproducible
        let seed: u64 = rng.random();
        let mut rig = Rig::nominal();
        rig.scatter(rng, self.fixed);
        (rig.accel_tilt_gain, rig.beam_length_m) = self.accel_tilt;
        let natural_f_hz = rig.modes.iter().map(|m| m.f_hz).collect();
        // what the camera sees: the tip's deflection, or the target's position along the beam,
        // plus the projected rotation when a lever is set (the same run: the transducer records
        // are the same either way)
        let (lever, xi) = (self.imaging.view.lever, self.imaging.view.xi);
        let (sim, seen) = if lever == 0.0 && xi == 1.0 {
            (
                model::simulate(&model::Rig::Cantilever(rig), &ACQUISITION, seed)?,
                None,
            )
        } else {
            let view = model::cantilever::View { xi, lever };
            let (sim, mut seen) =
                model::simulate_seen(&model::Rig::Cantilever(rig), &ACQUISITION, seed, &[view])?;
            (sim, seen.pop())
        };
        let bands = self.bands();
        let base: Vec<f32> = sim.input.iter().map(|v| *v as f32).collect();
        let tip: Vec<f32> = sim.tip_acc.iter().map(|v| *v as f32).collect();
        let mut welch = Self::welch()?;
        let transducer = measure(&mut welch, &base, &tip, &bands, Self::keep_bins(), 1.0)?;

        // camera: the record is periodic, so the path is padded with its own wrap-around; image
        // y grows down, the tip displacement up
        let fine_hz = FPS * sim.fine_per_frame as f64;
        let max_exp = self.exposures_ms.iter().cloned().fold(0.0, f64::max);
        // an exposure starting at the trigger reaches a whole exposure past a frame
        let reach_ms = match self.imaging.alignment {
            crate::imaging::ExposureAlignment::Centred => max_exp,
            crate::imaging::ExposureAlignment::Trigger => 2.0 * max_exp,
        };
        let pad = (reach_ms / 2000.0 * fine_hz).ceil() as usize + 2;
        let period_px: Vec<f64> = seen
            .as_deref()
            .unwrap_or(&sim.tip_mm)
            .iter()
            .map(|mm| -mm / MM_PER_PX)
            .collect();
        let path = TargetPath::periodic(&period_px, pad, sim.fine_per_frame, fine_hz);
        let mut up =
            Box::new(Up::try_new(FRAMES, SAMPLES).map_err(|e| anyhow::anyhow!("upsampler: {e}"))?);
        let mut acc = vec![0.0f32; SAMPLES];
        let camera = Filming {
            imaging: &self.imaging,
            target: &self.target,
            threshold: self.threshold,
            block: 16,
        };
        let vision = camera.vision_records(
            &path,
            &self.exposures_ms,
            (FRAMES, bands.len()),
            |dy| -dy * MM_PER_PX,
            |d32| {
                // mm -> m/s^2 in the same pass as the upsampling
                up.process_acceleration(d32, &mut acc, FPS as f32, 1e-3)
                    .map_err(|e| anyhow::anyhow!("upsampling: {e}"))?;
                measure(&mut welch, &base, &acc, &bands, Self::keep_bins(), 1.0)
            },
            rng,
        )?;
        Ok(RunRecord {
            run,
            natural_f_hz,
            transducer,
            vision,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::{aggregate, run_rng, Preset};
    use num_complex::Complex64;

    #[test]
    fn transducer_h1_is_the_closed_form_of_one_hann_segment_of_a_periodic_record() {
        // The simulated record is periodic, so its DFT is exact: Y[k] = T(f_k) X[k]. The periodic
        // Hann window convolves the spectrum with (-1/4, 1/2, -1/4), so the single-segment H1 at
        // bin k is (sum_j w_j T_{k+j} X_{k+j}) / (sum_j w_j X_{k+j}): a closed form per run,
        // without noise. Firmware-core's f32 estimator must give it at both picked peaks.
        let mut rig = Rig::nominal();
        rig.accel_noise_g = 0.0;
        let rig = model::Rig::Cantilever(rig);
        for seed in [1, 2, 3] {
            let sim = model::simulate(&rig, &ACQUISITION, seed).unwrap();
            let base: Vec<f32> = sim.input.iter().map(|v| *v as f32).collect();
            let tip: Vec<f32> = sim.tip_acc.iter().map(|v| *v as f32).collect();
            let got = std::thread::Builder::new()
                .stack_size(64 << 20)
                .spawn(move || {
                    let mut welch = Cantilever::welch().unwrap();
                    measure(&mut welch, &base, &tip, &BANDS, 0, 1.0).unwrap()
                })
                .unwrap()
                .join()
                .unwrap();
            let mut x: Vec<Complex64> = sim.input.iter().map(|v| Complex64::new(*v, 0.0)).collect();
            vibcam_fft::Planner::new().forward(SAMPLES).process(&mut x);
            let df = FS_HZ / SAMPLES as f64;
            let h1 = |k: usize| {
                let (mut num, mut den) = (Complex64::new(0.0, 0.0), Complex64::new(0.0, 0.0));
                for (j, w) in [(-1i64, -0.25), (0, 0.5), (1, -0.25)] {
                    let kk = (k as i64 + j) as usize;
                    num += w * rig.frf(kk as f64 * df) * x[kk];
                    den += w * x[kk];
                }
                num / den
            };
            for (b, p) in got.peaks.iter().enumerate() {
                let p = p.unwrap();
                let k = (p.f_hz / df).round() as usize;
                let want = h1(k).norm();
                // f32 transform of 20480 points: a few 1e-5 of the peak
                assert!(
                    (p.a / want - 1.0).abs() < 2e-4,
                    "seed {seed}, mode {}: {} vs closed form {want}",
                    b + 1,
                    p.a
                );
            }
        }
    }

    #[test]
    fn mode_1_vision_over_accelerometer_follows_sinc() {
        let mut cfg = StudyConfig::preset(Preset::Cantilever);
        cfg.runs = 12;
        let sc = Cantilever::new(&cfg).unwrap();
        let c2 = cfg.clone();
        let records: Vec<RunRecord> = std::thread::Builder::new()
            .stack_size(64 << 20)
            .spawn(move || {
                let sc = Cantilever::new(&c2).unwrap();
                (0..c2.runs)
                    .map(|r| sc.run(r, &mut run_rng(c2.seed, r)).unwrap())
                    .collect()
            })
            .unwrap()
            .join()
            .unwrap();
        let out = aggregate(&cfg, &sc, &records).unwrap();
        // the weighted-centroid transfer of a centred box exposure is sinc(pi f Te) (method.md
        // §2.6); the binary centroid of this 10 px disk follows it to 1 % at 7 Hz
        for e in [2.0, 4.0, 6.0] {
            let v = out
                .summary
                .iter()
                .find(|r| {
                    r.system == vibcam_report::export::study::System::Vision
                        && r.exposure_ms == e
                        && r.mode == 1
                })
                .unwrap();
            let x = std::f64::consts::PI * 7.1 * e / 1000.0;
            let sinc = x.sin() / x;
            let chi = v.chi_mu.unwrap();
            assert!(
                (chi / sinc - 1.0).abs() < 0.01,
                "{e} ms: chi_mu {chi} vs sinc {sinc}"
            );
        }
    }
    /// The cantilever preset with `runs` runs at 2 ms and the weighted centroid (no
    /// quantisation noise to blur a comparison of the same runs).
    fn weighted_at_2ms(runs: u64) -> StudyConfig {
        let mut cfg = StudyConfig::preset(Preset::Cantilever);
        cfg.runs = runs;
        cfg.exposures_ms = vec![2.0];
        cfg.imaging.centroid = Some(crate::imaging::CentroidKind::Weighted);
        cfg
    }

    /// chi_mu of every mode at 2 ms, `runs` runs of `cfg`.
    fn chi_mu_at_2ms(cfg: StudyConfig) -> Vec<f64> {
        std::thread::Builder::new()
            .stack_size(64 << 20)
            .spawn(move || {
                let sc = Cantilever::new(&cfg).unwrap();
                let records: Vec<RunRecord> = (0..cfg.runs)
                    .map(|r| sc.run(r, &mut run_rng(cfg.seed, r)).unwrap())
                    .collect();
                let out = aggregate(&cfg, &sc, &records).unwrap();
                (1..=2)
                    .map(|mode| {
                        out.summary
                            .iter()
                            .find(|r| {
                                r.system == vibcam_report::export::study::System::Vision
                                    && r.exposure_ms == 2.0
                                    && r.mode == mode
                            })
                            .and_then(|r| r.chi_mu)
                            .unwrap()
                    })
                    .collect()
            })
            .unwrap()
            .join()
            .unwrap()
    }

    #[test]
    fn lucas_kanade_on_a_plain_or_speckled_target_measures_what_the_weighted_centroid_does() {
        // the same runs at 2 ms (blur 0.9 % of mode 2's period): the trackers see the same
        // motion, so their chi_mu agree to the quantisation noise; the speckled target is not
        // symmetric and takes the general renderer, and the binary centroid still places LK's
        // window on it
        let weighted = chi_mu_at_2ms(weighted_at_2ms(4));
        for texture in [vibcam_model::Texture::Plain, vibcam_model::Texture::Speckle] {
            let mut cfg = weighted_at_2ms(4);
            cfg.imaging.centroid = None;
            cfg.imaging.tracker = Some(crate::imaging::TrackerKind::Lk);
            cfg.imaging.target_texture = Some(texture);
            let lk = chi_mu_at_2ms(cfg);
            for (mode, (a, b)) in weighted.iter().zip(&lk).enumerate() {
                assert!(
                    (a / b - 1.0).abs() < 0.003,
                    "{texture:?}, mode {}: weighted {a}, lk {b}",
                    mode + 1
                );
            }
        }
    }

    #[test]
    fn tracker_and_its_older_name_centroid_must_agree() {
        let mut cfg = weighted_at_2ms(1);
        cfg.imaging.tracker = Some(crate::imaging::TrackerKind::Weighted);
        assert!(Cantilever::new(&cfg).is_ok());
        cfg.imaging.tracker = Some(crate::imaging::TrackerKind::Lk);
        let e = Cantilever::new(&cfg).unwrap_err().to_string();
        assert!(
            e.contains("imaging.tracker") && e.contains("imaging.centroid"),
            "{e}"
        );
    }

    #[test]
    fn an_upright_beams_tilting_accelerometer_lowers_mode_1_six_times_more_than_mode_2() {
        // the same runs with the beam horizontal and upright (weighted centroid: no
        // quantisation noise): the camera sees the same motion, the tip accelerometer over-reads
        // mode i by 1 + g phi_i'/(phi_i L w_i^2) (model::cantilever::Tilt), so chi_mu falls by
        // that factor: 4.7 % for mode 1 of a 0.145 m beam, 0.8 % for mode 2 (1/w^2)
        let mut cfg = weighted_at_2ms(8);
        let plain = chi_mu_at_2ms(cfg.clone());
        let length_m = 0.145;
        cfg.rig.beam_orientation = Some(model::cantilever::Tilt::Upright);
        cfg.rig.beam_length_m = Some(length_m);
        let upright = chi_mu_at_2ms(cfg);
        for (mode, m) in Rig::nominal().modes.iter().enumerate() {
            let w = 2.0 * std::f64::consts::PI * m.f_hz;
            let over = 1.0
                + model::cantilever::STANDARD_GRAVITY * model::cantilever::tip_slope_ratio(mode)
                    / (length_m * w * w);
            let got = upright[mode] / plain[mode];
            assert!(
                (got * over - 1.0).abs() < 0.003,
                "mode {}: chi_mu {} -> {}, ratio {got}, want 1/{over}",
                mode + 1,
                plain[mode],
                upright[mode]
            );
        }
    }

    #[test]
    fn a_target_position_or_projected_tip_rotation_scales_each_mode_by_its_view_factor() {
        // the same runs with and without the lever (the weighted centroid: no quantisation
        // noise to blur the comparison); the camera then sees each mode scaled by
        // 1 + lever * phi_i'(L) / phi_i(L): 1 - 0.0324 * 1.3765 = 0.9554 for mode 1 (the
        // paper's 95.5 %) but 1 - 0.0324 * 4.7808 = 0.8451 for mode 2
        let mut cfg = weighted_at_2ms(8);
        let plain = chi_mu_at_2ms(cfg.clone());
        let lever = -0.0324;
        cfg.imaging.tip_rotation_lever = Some(lever);
        let turned = chi_mu_at_2ms(cfg.clone());
        let mut at = cfg.clone();
        at.imaging.tip_rotation_lever = None;
        at.imaging.target_position_xi = Some(0.9);
        let placed = chi_mu_at_2ms(at);
        for mode in 0..2 {
            let want = model::cantilever::View {
                xi: 0.9,
                lever: 0.0,
            }
            .factor(mode);
            let got = placed[mode] / plain[mode];
            assert!(
                (got / want - 1.0).abs() < 0.005,
                "target at 0.9 L, mode {}: ratio {got}, shape ratio {want}",
                mode + 1
            );
        }
        for mode in 0..2 {
            let want = model::cantilever::View { xi: 1.0, lever }.factor(mode);
            let got = turned[mode] / plain[mode];
            assert!(
                (got / want - 1.0).abs() < 0.005,
                "mode {}: chi_mu {} -> {}, ratio {got}, factor {want}",
                mode + 1,
                plain[mode],
                turned[mode]
            );
        }
    }
}
