//! The cantilever scenario (SPEC 3.2, the paper's laboratory validation replayed in
//! simulation): a base-excited two-mode aluminium cantilever, two accelerometers at 2048 Hz and
//! a 120 fps camera with 2, 4, 6 ms exposures. The vision path is the embedded chain, all in
//! firmware-core: centroid -> mm -> Fourier upsampling 1200 -> 20480 fused with -omega^2 ->
//! H1 against the base acceleration -> peaks.
//!
//! Structure and excitation come from [`crate::recording`] (exact periodic frequency-domain
//! response on a 30 720 Hz fine time base, the common clock of SPEC 2.7), with the run-to-run
//! scatter of SPEC 3.2 drawn from the run's stream: f ~ Normal(f, 0.3 % of f),
//! h ~ Uniform(h +/- 5 %). Frames are rendered by the separable EPSA renderer
//! ([`super::render`]): a white disk (level 255) of radius 10 px, its edge smoothed by a
//! Gaussian of 0.5 px so the image is band-limited and the phase shift exact; binary
//! centroid with the threshold at half the level (127). The `[imaging]` options of a study
//! file (gain, distortion, optical blur, shot and read noise, bit depth) apply as in the
//! grandstand ([`super::effects::Camera`]).

use super::effects::{Camera, Effects};
use super::render::{BlurRenderer, DiskTarget};
use super::{measure_system, measure_vision, RunRecord, Scenario, StudyConfig};
use crate::recording::{self, RecordingSpec, Rig};
use firmware_core::spectrum::{scratch_capacity, Detrend, WelchConfig, WelchH1, Window};
use firmware_core::upsample::{self, Upsampler};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// Frames per test (10 s at 120 fps).
pub const FRAMES: usize = 1200;
/// Accelerometer samples per test (10 s at 2048 Hz).
pub const SAMPLES: usize = 20480;
/// Camera frame rate, fps.
pub const FPS: f64 = 120.0;
/// Accelerometer rate, Hz.
pub const FS_HZ: f64 = 2048.0;
/// Camera scale, mm/px.
pub const MM_PER_PX: f64 = 0.1266;
/// Target level and binary threshold (half the level).
pub const LEVEL: f64 = 255.0;
/// Binary centroid threshold.
pub const THRESHOLD: u16 = 127;

type Welch = WelchH1<SAMPLES, SAMPLES, { scratch_capacity(SAMPLES) }>;
type Up = Upsampler<SAMPLES, { upsample::scratch_capacity(FRAMES, SAMPLES) }>;

/// The cantilever study.
#[derive(Debug)]
pub struct Cantilever {
    /// Optional image-formation effects (identity by default: the fast 8-bit path).
    effects: Effects,
    exposures_ms: Vec<f64>,
    fixed: bool,
}

impl Cantilever {
    /// Mode bands of SPEC 3.2, Hz.
    pub const BANDS: [(f64, f64); 2] = [(5.0, 15.0), (25.0, 45.0)];
    /// |FRF| kept up to this frequency, Hz.
    pub const FRF_MAX_HZ: f64 = 60.0;

    /// Builds the scenario from a resolved configuration.
    pub fn new(cfg: &StudyConfig) -> anyhow::Result<Self> {
        let effects = Effects::from_options(&cfg.imaging)?;
        let period_ms = 1000.0 / FPS;
        if let Some(e) = cfg.exposures_ms.iter().find(|e| **e >= period_ms) {
            return Err(crate::bad_input(format!(
                "exposures_ms: {e} ms is not shorter than the {period_ms:.3} ms frame period"
            )));
        }
        Ok(Cantilever {
            effects,
            exposures_ms: cfg.exposures_ms.clone(),
            fixed: cfg.fixed_structure,
        })
    }

    fn welch() -> anyhow::Result<Box<Welch>> {
        let cfg = WelchConfig {
            fs_hz: FS_HZ as f32,
            nperseg: SAMPLES,
            noverlap: 0,
            nfft: SAMPLES,
            window: Window::Hann,
            detrend: Detrend::Constant,
        };
        Ok(Box::new(
            Welch::try_new(cfg).map_err(|e| anyhow::anyhow!("Welch settings: {e}"))?,
        ))
    }

    fn keep_bins() -> usize {
        (Self::FRF_MAX_HZ * SAMPLES as f64 / FS_HZ) as usize + 1
    }

    /// The run's rig: nominal SPEC 3.2 parameters with the run-to-run scatter.
    fn spec(&self, rng: &mut ChaCha8Rng) -> RecordingSpec {
        let mut spec = RecordingSpec::cantilever(rng.random(), 0.0);
        if let Rig::Cantilever { modes, .. } = &mut spec.rig {
            for m in modes.iter_mut() {
                let z: f64 = StandardNormal.sample(rng);
                let u: f64 = rng.random();
                if !self.fixed {
                    m.f_hz *= 1.0 + 0.003 * z;
                    m.zeta *= 1.0 + 0.05 * (2.0 * u - 1.0);
                }
            }
        }
        spec
    }
}

impl Scenario for Cantilever {
    fn name(&self) -> &'static str {
        "cantilever"
    }
    fn amplitude_unit(&self) -> &'static str {
        "(m/s^2)/(m/s^2)"
    }
    fn bands(&self) -> Vec<(f64, f64)> {
        Self::BANDS.to_vec()
    }
    fn frf_freqs(&self) -> Vec<f64> {
        (0..Self::keep_bins())
            .map(|k| k as f64 * FS_HZ / SAMPLES as f64)
            .collect()
    }
    fn with_chi(&self) -> bool {
        true
    }

    fn run(&self, run: u64, rng: &mut ChaCha8Rng) -> anyhow::Result<RunRecord> {
        let spec = self.spec(rng);
        let natural_f_hz = match &spec.rig {
            Rig::Cantilever { modes, .. } => modes.iter().map(|m| m.f_hz).collect(),
            Rig::Grandstand { .. } => Vec::new(),
        };
        let sim = recording::simulate(&spec)?;
        let bands = self.bands();
        let base: Vec<f32> = sim.input.iter().map(|v| *v as f32).collect();
        let tip: Vec<f32> = sim.tip_acc.iter().map(|v| *v as f32).collect();
        let mut welch = Self::welch()?;
        let transducer = measure_system(&mut welch, &base, &tip, &bands, Self::keep_bins(), 1.0)?;

        // camera: the record is periodic, so pad the fine path with its own wrap-around
        let ppf = sim.fine_per_frame;
        let fine_hz = FPS * ppf as f64;
        let max_half = self.exposures_ms.iter().cloned().fold(0.0, f64::max) / 2000.0 * fine_hz;
        let pad = max_half.ceil() as usize + 2;
        let n = sim.tip_mm.len();
        let to_px = |mm: f64| -mm / MM_PER_PX; // image y grows down, tip displacement up
        let path: Vec<f64> = (0..n + 2 * pad)
            .map(|i| to_px(sim.tip_mm[(i + n - pad) % n]))
            .collect();
        let target = DiskTarget {
            radius_px: 10.0,
            level: LEVEL,
            edge_sigma_px: 0.5,
        };
        let mut renderer = BlurRenderer::for_path(&target, &path, 16);
        let (w, h) = (renderer.width(), renderer.height());
        let rest_y = renderer.rest_y();
        let mut camera = Camera::new(&self.effects, THRESHOLD, w, h, rng);
        let mut disp = vec![0.0f64; FRAMES];
        let mut valid = vec![false; FRAMES];
        let mut up =
            Box::new(Up::try_new(FRAMES, SAMPLES).map_err(|e| anyhow::anyhow!("upsampler: {e}"))?);
        let mut acc = vec![0.0f32; SAMPLES];
        let mut vision = Vec::with_capacity(self.exposures_ms.len());
        for (ei, &exp) in self.exposures_ms.iter().enumerate() {
            let half = exp / 2000.0 * fine_hz;
            camera.start_exposure(ei);
            vision.push(measure_vision(
                exp,
                &mut disp,
                &mut valid,
                bands.len(),
                |k| {
                    let centre = (pad + k * ppf) as f64;
                    camera.frame(&mut renderer, centre - half, centre + half)
                },
                |cy| -(cy as f64 - rest_y) * MM_PER_PX,
                |d32| {
                    // mm -> m/s^2 in the same pass as the upsampling
                    up.process_acceleration(d32, &mut acc, FPS as f32, 1e-3)
                        .map_err(|e| anyhow::anyhow!("upsampling: {e}"))?;
                    measure_system(&mut welch, &base, &acc, &bands, Self::keep_bins(), 1.0)
                },
            )?);
        }
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

    #[test]
    fn accelerometer_peaks_near_the_model_and_mode_1_blur_follows_sinc() {
        let mut cfg = StudyConfig::preset(Preset::Cantilever);
        cfg.runs = 12;
        let sc = Cantilever::new(&cfg).unwrap();
        let records: Vec<RunRecord> = std::thread::Builder::new()
            .stack_size(64 << 20)
            .spawn(move || {
                let sc = Cantilever::new(&cfg).unwrap();
                (0..cfg.runs)
                    .map(|r| sc.run(r, &mut run_rng(cfg.seed, r)).unwrap())
                    .collect()
            })
            .unwrap()
            .join()
            .unwrap();
        let cfg = StudyConfig::preset(Preset::Cantilever);
        let out = aggregate(&cfg, &sc, &records).unwrap();
        let row = |sys: crate::report::System, e: f64, m: usize| {
            out.summary
                .iter()
                .find(|r| r.system == sys && r.exposure_ms == e && r.mode == m)
                .unwrap()
                .clone()
        };
        use crate::report::System::{Transducer, Vision};
        // model peaks |1 + sum G phi w^2 / (w_i^2 - w^2 + 2 i h_i w_i w)|: about 68 and 39.4;
        // a single Hann segment per test scatters by tens of percent (SPEC 3.2)
        let t1 = row(Transducer, 2.0, 1);
        let t2 = row(Transducer, 2.0, 2);
        assert!((t1.mu_f_hz - 7.1).abs() < 0.15, "{t1:?}");
        assert!((t2.mu_f_hz - 32.4).abs() < 0.2, "{t2:?}");
        assert!((t1.mu_a / 68.0 - 1.0).abs() < 0.3, "{t1:?}");
        assert!((t2.mu_a / 39.4 - 1.0).abs() < 0.2, "{t2:?}");
        // mode 1: the vision/accelerometer ratio follows sinc(pi f Te) within 1 %
        for e in [2.0, 4.0, 6.0] {
            let v = row(Vision, e, 1);
            let x = std::f64::consts::PI * 7.1 * e / 1000.0;
            let sinc = x.sin() / x;
            let chi = v.chi_mu.unwrap();
            assert!(
                (chi / sinc - 1.0).abs() < 0.01,
                "{e} ms: chi_mu {chi} vs sinc {sinc}"
            );
        }
    }
}
