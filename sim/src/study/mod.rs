//! The Monte Carlo studies (method.md §3.1, §3.2): a study is `runs` realizations of one
//! scenario (grandstand or cantilever). Realization `r` draws everything random (structure,
//! excitation, transducer noise) from one stream derived from `(seed, r)` alone, and every
//! exposure of that run sees the same structure and excitation (as in the paper). Results
//! therefore do not depend on the thread count, the scheduling, the sharding or on
//! interruptions.
//!
//! - [`config`]: the resolved description of a study;
//! - [`grandstand`], [`cantilever`]: the scenarios, one run each: the rig's model, the camera and
//!   the firmware chain put together;
//! - [`runner`]: random streams, shards, the parallel runner and resume;
//! - [`checkpoint`]: `runs.jsonl`, the model revision, the file names;
//! - [`adaptive`]: the adaptive Monte Carlo procedure (JCGM 101 7.9): where a study stops;
//! - [`mod@aggregate`]: run records -> summary, realizations, FRF band and lost frames;
//! - [`merge`]: the shards of one study -> its outputs.

pub mod adaptive;
pub mod aggregate;
pub mod cantilever;
pub mod checkpoint;
pub mod config;
pub mod grandstand;
pub mod merge;
pub mod runner;

pub use aggregate::{aggregate, write_outputs, LostFrames, Outputs};
pub use cantilever::Cantilever;
pub use checkpoint::{files, read_checkpoint, recorded_revision, MODEL_REVISION};
pub use config::{ImagingOptions, Preset, StudyConfig};
pub use grandstand::Grandstand;
pub use runner::{execute, run_rng, Executed, Execution, Shard};

use anyhow::Context as _;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use vibcam_chain::displacement::{fill_lost_frames_with, too_many_lost};
pub use vibcam_chain::frf::{PeakRecord, SystemRecord};

/// The vision system at one exposure in one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VisionRecord {
    /// Exposure time, ms.
    pub exposure_ms: f64,
    /// Frames in which no pixel passed the threshold (filled by interpolation).
    pub lost_frames: u64,
    /// Frames in the record.
    pub frames: u64,
    /// More than 5 % of the frames were lost: the run is reported as failed at this exposure
    /// and left out of the statistics.
    pub failed: bool,
    /// The measurement (empty peaks when failed).
    pub system: SystemRecord,
}

/// Everything one realization produced. One JSON line of `runs.jsonl`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// Run index.
    pub run: u64,
    /// Natural frequencies of the modes drawn for this run, Hz (for the E2PR).
    pub natural_f_hz: Vec<f64>,
    /// Transducer path (independent of the exposure).
    pub transducer: SystemRecord,
    /// Vision path, one per exposure in configuration order.
    pub vision: Vec<VisionRecord>,
}

/// What a scenario reports, fixed by its rig: names, units, mode bands and the FRF bins kept.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reporting {
    /// Short name printed in titles.
    pub name: &'static str,
    /// Unit of the resonant amplitudes.
    pub amplitude_unit: &'static str,
    /// Mode bands `(lo, hi)` in Hz, one per reported mode.
    pub bands: &'static [(f64, f64)],
    /// Sample rate of the FRF, Hz.
    pub fs_hz: f64,
    /// Transform length of the FRF.
    pub nfft: usize,
    /// |FRF| kept up to this frequency, Hz.
    pub frf_max_hz: f64,
    /// Whether the summary carries `chi_mu`/`chi_sigma` (cantilever).
    pub with_chi: bool,
}

impl Reporting {
    /// What a rig reports: its `name`, amplitude `unit`, mode `bands`, the FRF's sample rate
    /// and transform length, the highest frequency kept and whether `chi_*` are reported.
    pub const fn new(
        name: &'static str,
        unit: &'static str,
        bands: &'static [(f64, f64)],
        (fs_hz, nfft): (f64, usize),
        frf_max_hz: f64,
        with_chi: bool,
    ) -> Reporting {
        Reporting {
            name,
            amplitude_unit: unit,
            bands,
            fs_hz,
            nfft,
            frf_max_hz,
            with_chi,
        }
    }

    /// Bins of |FRF| kept in a run record.
    pub fn keep_bins(&self) -> usize {
        (self.frf_max_hz * self.nfft as f64 / self.fs_hz) as usize + 1
    }
}

/// A simulated measurement: how to run one realization.
pub trait Scenario: Sync {
    /// What the scenario reports.
    fn reporting(&self) -> Reporting;
    /// Short name printed in titles.
    fn name(&self) -> &'static str {
        self.reporting().name
    }
    /// Unit of the resonant amplitudes.
    fn amplitude_unit(&self) -> &'static str {
        self.reporting().amplitude_unit
    }
    /// Mode bands `(lo, hi)` in Hz, one per reported mode.
    fn bands(&self) -> Vec<(f64, f64)> {
        self.reporting().bands.to_vec()
    }
    /// Frequencies of the bins in [`SystemRecord::frf_abs`], Hz.
    fn frf_freqs(&self) -> Vec<f64> {
        let r = self.reporting();
        (0..r.keep_bins())
            .map(|k| k as f64 * r.fs_hz / r.nfft as f64)
            .collect()
    }
    /// Whether the summary carries `chi_mu`/`chi_sigma` (cantilever).
    fn with_chi(&self) -> bool {
        self.reporting().with_chi
    }
    /// Runs realization `run`; `rng` is its private stream.
    fn run(&self, run: u64, rng: &mut ChaCha8Rng) -> anyhow::Result<RunRecord>;
    /// Optional notes printed with the summary (e.g. exposure longer than the frame period).
    fn notes(&self) -> Vec<String> {
        Vec::new()
    }
    /// What the `vision_compensated` rows divide the vision amplitudes by (method.md §2.8).
    fn exposure_correction(&self) -> anyhow::Result<crate::imaging::exposure::ExposureCorrection>;
}

/// A Welch H1 estimator of firmware-core on the heap (its buffers are large), or the error
/// naming the settings.
pub fn boxed_welch<const NPERSEG: usize, const NFFT: usize, const SCRATCH: usize>(
    config: firmware_core::spectrum::WelchConfig,
) -> anyhow::Result<Box<firmware_core::spectrum::WelchH1<NPERSEG, NFFT, SCRATCH>>> {
    Ok(Box::new(
        firmware_core::spectrum::WelchH1::try_new(config)
            .map_err(|e| anyhow::anyhow!("Welch settings: {e}"))?,
    ))
}

/// The vision system at one exposure, as every scenario runs it: measures frame `k` of
/// `0..disp.len()` with `centroid(k)` (the target's position, `None` when lost), turns its row
/// `cy` (px) into the displacement
/// with `to_disp`, fills the lost frames (`policy`, [`fill_lost_frames_with`]) and, unless too many of them were lost
/// ([`vibcam_chain::displacement::MAX_LOST_FRACTION`]), measures the filled record (as `f32`) with
/// `measure`. `disp` and `valid` are the caller's buffers, reused across exposures; `bands` is
/// the number of mode bands (the empty peaks of a failed run).
#[allow(clippy::too_many_arguments)]
pub fn measure_vision<E: std::fmt::Display>(
    exposure_ms: f64,
    policy: vibcam_common::lost_frames::LostFramePolicy,
    disp: &mut [f64],
    valid: &mut [bool],
    bands: usize,
    mut centroid: impl FnMut(usize) -> Result<Option<(f32, f32)>, E>,
    to_disp: impl Fn(f32) -> f64,
    measure: impl FnOnce(&[f32]) -> anyhow::Result<SystemRecord>,
) -> anyhow::Result<VisionRecord> {
    let frames = disp.len();
    for k in 0..frames {
        let c = centroid(k).map_err(|e| anyhow::anyhow!("frame {k}: {e}"))?;
        match c {
            Some((_, cy)) => {
                disp[k] = to_disp(cy);
                valid[k] = true;
            }
            None => valid[k] = false,
        }
    }
    let lost = fill_lost_frames_with(disp, valid, policy) as u64;
    let failed = too_many_lost(lost as usize, frames);
    let system = if failed {
        SystemRecord {
            peaks: vec![None; bands],
            frf_abs: Vec::new(),
        }
    } else {
        let d32: Vec<f32> = disp.iter().map(|v| *v as f32).collect();
        measure(&d32)?
    };
    Ok(VisionRecord {
        exposure_ms,
        lost_frames: lost,
        frames: frames as u64,
        failed,
        system,
    })
}

/// The camera of a scenario: effects, target and threshold, and the renderer's ramp block.
#[derive(Debug, Clone, Copy)]
pub struct Filming<'a> {
    /// The resolved `[imaging]` table.
    pub imaging: &'a crate::imaging::Setup,
    /// The target.
    pub target: &'a crate::imaging::DiskTarget,
    /// Centroid threshold on the 8-bit scale.
    pub threshold: u16,
    /// Path segments per precomputed ramp block of the renderer.
    pub block: usize,
}

impl Filming<'_> {
    /// Films `path` at every exposure of `exposures_ms` and measures each with
    /// [`measure_vision`]: one renderer and one camera for the run (the camera draws its noise
    /// seed from `rng`), frames `0..frames`, `to_disp` turning the centroid's offset from the
    /// rest position (px, image `y`) into the displacement, `measure` the filled record.
    pub fn vision_records(
        &self,
        path: &crate::imaging::TargetPath,
        exposures_ms: &[f64],
        (frames, bands): (usize, usize),
        to_disp: impl Fn(f64) -> f64,
        mut measure: impl FnMut(&[f32]) -> anyhow::Result<SystemRecord>,
        rng: &mut ChaCha8Rng,
    ) -> anyhow::Result<Vec<VisionRecord>> {
        let mut renderer =
            crate::imaging::BlurRenderer::for_path(self.target, &path.path_px, self.block);
        let im = self.imaging;
        // LK's template window reaches as far as the record's longest blur: each exposure's,
        // and a frame tall enough for the longest
        let mut blur = vec![0.0f64; exposures_ms.len()];
        if im.measurement.tracker == crate::imaging::TrackerKind::Lk {
            for (b, &exp) in blur.iter_mut().zip(exposures_ms) {
                *b = (0..frames)
                    .map(|k| {
                        let (a, b) = path.aligned_window(k, exp, im.alignment);
                        let (lo, hi) = renderer.path_range(a, b);
                        hi - lo
                    })
                    .fold(0.0, f64::max);
            }
            let (lo, hi) = renderer.path_range(0.0, path.path_px.len() as f64);
            let extra = (blur.iter().fold(0.0, |m: f64, b| m.max(*b)) / 2.0).ceil() + 8.0;
            renderer = crate::imaging::BlurRenderer::new(self.target, lo - extra, hi + extra);
            renderer.set_path(&path.path_px, self.block);
        }
        renderer.set_epsa_images(im.epsa_images);
        let (w, h) = (renderer.width(), renderer.height());
        let rest_y = renderer.rest_y();
        let mut camera = crate::imaging::Camera::new(
            &im.effects,
            &im.measurement,
            (self.target, self.threshold),
            w,
            h,
            rng,
        )?;
        camera.use_fast_path(self.target, self.threshold, &renderer);
        let mut disp = vec![0.0f64; frames];
        let mut valid = vec![false; frames];
        let mut vision = Vec::with_capacity(exposures_ms.len());
        for (ei, &exp) in exposures_ms.iter().enumerate() {
            camera.start_exposure(ei, blur[ei])?;
            vision.push(measure_vision(
                exp,
                self.imaging.lost_frame_policy,
                &mut disp,
                &mut valid,
                bands,
                |k| {
                    let (a, b) = path.aligned_window(k, exp, self.imaging.alignment);
                    camera.frame(&mut renderer, a, b)
                },
                |cy| to_disp(cy as f64 - rest_y),
                &mut measure,
            )?);
        }
        Ok(vision)
    }
}

/// The scenario a configuration describes.
pub fn scenario_for(cfg: &StudyConfig) -> anyhow::Result<Box<dyn Scenario>> {
    Ok(match cfg.preset {
        Preset::Grandstand => Box::new(Grandstand::new(cfg)?),
        Preset::Cantilever => Box::new(Cantilever::new(cfg)?),
    })
}

/// Aggregates, writes CSV files and plots, and returns the table and notes to print. Shared
/// by `study` and `merge` (plots only when `plots`).
pub fn finish(
    cfg: &StudyConfig,
    scenario: &dyn Scenario,
    records: &[RunRecord],
    out: &std::path::Path,
    plots: bool,
) -> anyhow::Result<String> {
    let correction = scenario.exposure_correction()?;
    let mut records = records;
    let mut adaptive_report = None;
    // a shard's directory holds some batches only (never two from the start, which are batches
    // 0 and 1 of two shards): its outputs are its own runs'
    let from_start = |batch: u64| {
        records.len() as u64 >= 2 * batch
            && records.iter().enumerate().all(|(i, r)| r.run == i as u64)
    };
    if let Some(a) = cfg.adaptive.as_ref().filter(|a| from_start(a.batch)) {
        let o = adaptive::outcome(cfg, a, scenario.bands().len(), &correction, records)?;
        vibcam_report::export::write_atomic(
            &out.join(files::ADAPTIVE),
            &adaptive::adaptive_csv(&o),
        )?;
        records = &records[..o.runs];
        adaptive_report = Some(adaptive::report(&o, a));
    }
    let outputs = aggregate::aggregate_with(cfg, scenario, records, &correction)?;
    let mut written = write_outputs(out, scenario, &outputs)?;
    if plots {
        let p = vibcam_report::plots::StudyPlots {
            title: scenario.name(),
            amplitude_unit: scenario.amplitude_unit(),
            summary: &outputs.summary,
            realizations: &outputs.realizations,
            frf_band: &outputs.frf_band,
        };
        for f in vibcam_report::plots::study_figures(&p)? {
            written.extend(
                f.write_into(out)
                    .with_context(|| format!("cannot write the figures in {}", out.display()))?,
            );
        }
    }
    use std::fmt::Write as _;
    let mut text = format!(
        "{}\n",
        vibcam_report::export::study::table(
            &outputs.summary,
            scenario.amplitude_unit(),
            cfg.coverage
        )
    );
    let _ = writeln!(text, "vision_compensated: {}", outputs.correction);
    for l in aggregate::lost_by_exposure(&outputs) {
        let _ = writeln!(
            text,
            "exposure {} ms: {} of {} frames lost (filled by interpolation), {} failed runs (> 5 % lost, left out)",
            l.exposure_ms, l.lost, l.frames, l.failed_runs
        );
    }
    for n in scenario.notes() {
        let _ = writeln!(text, "note: {n}");
    }
    for line in aggregate::chi_statements(&outputs) {
        let _ = writeln!(text, "{line}");
    }
    if let Some(r) = adaptive_report {
        text.push_str(&r);
        written.push(out.join(files::ADAPTIVE));
    }
    let _ = writeln!(
        text,
        "wrote {} files in {}",
        written.len() + 2,
        out.display()
    );
    Ok(text)
}
