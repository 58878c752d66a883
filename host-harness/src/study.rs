//! The Monte Carlo runner: configuration, reproducible random streams, parallel runs,
//! checkpoints (resume), shards and the aggregation into the study outputs.
//!
//! A study is `runs` realizations of one scenario (grandstand or cantilever). Realization `r`
//! draws everything random (structure, excitation, transducer noise) from one stream derived
//! from `(seed, r)` alone, and every exposure of that run sees the same structure and excitation
//! (as in the paper). Results therefore do not depend on the thread count, the scheduling, the
//! sharding or on interruptions: each finished run is appended to `runs.jsonl` in the output
//! directory as soon as it is done, `--resume` skips the runs found there, and the summary is
//! always computed from the complete set of run records sorted by run index.

use crate::report::{FrfBandRow, RealizationRow, SummaryRow, System};
use crate::{bad_input, stats};
use anyhow::Context as _;
use rand::SeedableRng as _;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::{BufRead as _, Write as _};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Which simulated measurement a study runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Preset {
    /// SPEC 3.1: three-mode grandstand platform, decay test, 50 fps camera.
    Grandstand,
    /// SPEC 3.2: base-excited aluminium cantilever, 120 fps camera, accelerometers.
    Cantilever,
}

/// Optional image-formation effects (SPEC 3.1), all off by default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
pub struct ImagingOptions {
    /// Contrast gain applied to the image (1 = none).
    pub gain: Option<f64>,
    /// Quadratic radial distortion coefficient k1 (1/px^2 relative to the frame centre).
    pub distortion_k1: Option<f64>,
    /// Cubic radial distortion coefficient k2.
    pub distortion_k2: Option<f64>,
    /// Optical blur: Gaussian sigma in px.
    pub optical_blur_sigma_px: Option<f64>,
    /// Sensor read noise, std in grey levels.
    pub read_noise: Option<f64>,
    /// Shot noise: electrons per grey level (full well / full scale); none when absent.
    pub shot_noise_e_per_level: Option<f64>,
    /// Quantisation bit depth (8, 12 or 16); 8 when absent.
    pub bits: Option<u32>,
}

/// The complete, resolved description of a study. Written to `config.toml` in the output
/// directory; a study file (`--config FILE.toml`) has the same fields, all optional except
/// `preset`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyConfig {
    /// Scenario.
    pub preset: Preset,
    /// Number of realizations (runs).
    pub runs: u64,
    /// Camera exposure times, ms.
    pub exposures_ms: Vec<f64>,
    /// Master seed: run `r` uses the stream derived from `(seed, r)`.
    pub seed: u64,
    /// Method-uncertainty variant (SPEC 3.1, paper section 4.4): all modal parameter stds zero,
    /// only excitation and transducer noise vary.
    pub fixed_structure: bool,
    /// Highest frequency written to `frf_band.csv`, Hz.
    pub frf_max_hz: f64,
    /// Optional image-formation effects.
    #[serde(default)]
    pub imaging: ImagingOptions,
}

/// A study file: every field optional except the preset, whose defaults fill the rest.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct StudyFile {
    preset: Preset,
    runs: Option<u64>,
    exposures_ms: Option<Vec<f64>>,
    seed: Option<u64>,
    fixed_structure: Option<bool>,
    frf_max_hz: Option<f64>,
    #[serde(default)]
    imaging: ImagingOptions,
}

impl StudyConfig {
    /// Defaults of a preset. The grandstand run count is what finishes in about a minute on two
    /// cores; the paper used 1000.
    pub fn preset(preset: Preset) -> StudyConfig {
        match preset {
            Preset::Grandstand => StudyConfig {
                preset,
                runs: 100,
                exposures_ms: (0..8).map(|i| 40.0 + 20.0 * i as f64).collect(),
                seed: 1,
                fixed_structure: false,
                frf_max_hz: 5.0,
                imaging: ImagingOptions::default(),
            },
            Preset::Cantilever => StudyConfig {
                preset,
                runs: 100,
                exposures_ms: vec![2.0, 4.0, 6.0],
                seed: 1,
                fixed_structure: false,
                frf_max_hz: 60.0,
                imaging: ImagingOptions::default(),
            },
        }
    }

    /// Reads a study file (TOML); missing fields come from the preset's defaults.
    pub fn from_toml_file(path: &Path) -> anyhow::Result<StudyConfig> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| bad_input(format!("cannot read {}: {e}", path.display())))?;
        Self::from_toml_str(&text).map_err(|e| bad_input(format!("{}: {e:#}", path.display())))
    }

    /// Parses a study file from text.
    pub fn from_toml_str(text: &str) -> anyhow::Result<StudyConfig> {
        let f: StudyFile = toml::from_str(text)?;
        let d = StudyConfig::preset(f.preset);
        Ok(StudyConfig {
            preset: f.preset,
            runs: f.runs.unwrap_or(d.runs),
            exposures_ms: f.exposures_ms.unwrap_or(d.exposures_ms),
            seed: f.seed.unwrap_or(d.seed),
            fixed_structure: f.fixed_structure.unwrap_or(d.fixed_structure),
            frf_max_hz: f.frf_max_hz.unwrap_or(d.frf_max_hz),
            imaging: f.imaging,
        })
    }

    /// Checks the values; the message names the field.
    pub fn validate(&self) -> anyhow::Result<()> {
        if self.runs == 0 {
            return Err(bad_input("runs: must be at least 1"));
        }
        if self.exposures_ms.is_empty() {
            return Err(bad_input("exposures_ms: at least one exposure is needed"));
        }
        for e in &self.exposures_ms {
            if !(e.is_finite() && *e >= 0.0) {
                return Err(bad_input(format!(
                    "exposures_ms: {e} is not a non-negative number of milliseconds"
                )));
            }
        }
        let mut sorted = self.exposures_ms.clone();
        sorted.sort_by(f64::total_cmp);
        sorted.dedup();
        if sorted.len() != self.exposures_ms.len() {
            return Err(bad_input("exposures_ms: exposures must be distinct"));
        }
        if !(self.frf_max_hz.is_finite() && self.frf_max_hz > 0.0) {
            return Err(bad_input("frf_max_hz: must be a positive number of Hz"));
        }
        Ok(())
    }

    /// The resolved configuration as TOML text (written to `config.toml`).
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_default()
    }
}

/// Peak picked in one mode band: frequency (Hz) and amplitude.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PeakRecord {
    /// Resonance frequency, Hz.
    pub f_hz: f64,
    /// Resonant amplitude (study units).
    pub a: f64,
}

/// What one system measured in one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SystemRecord {
    /// One entry per mode band; `None` when the band held no usable bin.
    pub peaks: Vec<Option<PeakRecord>>,
    /// |H1| at the scenario's output bins (see [`Scenario::frf_freqs`]).
    pub frf_abs: Vec<f32>,
}

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

/// A simulated measurement: how to run one realization.
pub trait Scenario: Sync {
    /// Short name printed in titles.
    fn name(&self) -> &'static str;
    /// Unit of the resonant amplitudes.
    fn amplitude_unit(&self) -> &'static str;
    /// Mode bands `(lo, hi)` in Hz, one per reported mode.
    fn bands(&self) -> Vec<(f64, f64)>;
    /// Frequencies of the bins in [`SystemRecord::frf_abs`], Hz.
    fn frf_freqs(&self) -> Vec<f64>;
    /// Whether the summary carries `chi_mu`/`chi_sigma` (cantilever).
    fn with_chi(&self) -> bool {
        false
    }
    /// Runs realization `run`; `rng` is its private stream.
    fn run(&self, run: u64, rng: &mut ChaCha8Rng) -> anyhow::Result<RunRecord>;
    /// Optional notes printed with the summary (e.g. exposure longer than the frame period).
    fn notes(&self) -> Vec<String> {
        Vec::new()
    }
}

/// The random stream of run `run`: ChaCha8 keyed by the master seed, one stream per run. It
/// depends on nothing else, so results are the same for any thread count or shard layout.
pub fn run_rng(seed: u64, run: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(run);
    rng
}

/// Selection of the runs a process computes: shard `index` (1-based) of `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 1-based shard number.
    pub index: u64,
    /// Number of shards.
    pub count: u64,
}

impl Shard {
    /// The whole study.
    pub const ALL: Shard = Shard { index: 1, count: 1 };

    /// Parses `K/N` with 1 <= K <= N.
    pub fn parse(s: &str) -> anyhow::Result<Shard> {
        let err = || bad_input(format!("--shard: `{s}` is not K/N with 1 <= K <= N"));
        let (k, n) = s.split_once('/').ok_or_else(err)?;
        let index: u64 = k.trim().parse().map_err(|_| err())?;
        let count: u64 = n.trim().parse().map_err(|_| err())?;
        if count == 0 || index == 0 || index > count {
            return Err(err());
        }
        Ok(Shard { index, count })
    }

    /// Whether run `r` belongs to this shard (runs are dealt round-robin).
    pub fn contains(&self, r: u64) -> bool {
        r % self.count == self.index - 1
    }
}

/// Revision of the simulation and measurement code whose results a study directory holds.
/// Bump it with every change that alters a study's numbers (models, renderer, firmware-core
/// numerics), so that a resumed or merged study never mixes runs of two code revisions: the
/// revision is written to [`files::REVISION`], checked on `--resume` and by `merge`, and part of
/// the default output directory's name.
///
/// History: 1 = everything before the file existed; 2 = `f32` twiddles and window in
/// firmware-core's `dft`/`spectrum` (results move in the 6th significant digit).
pub const MODEL_REVISION: u32 = 2;

/// The revision recorded in study directory `dir` (1 when the file is absent: directories
/// written before revisions were recorded).
pub fn recorded_revision(dir: &Path) -> anyhow::Result<u32> {
    let path = dir.join(files::REVISION);
    match std::fs::read_to_string(&path) {
        Ok(text) => text.trim().parse().map_err(|_| {
            bad_input(format!(
                "{}: expected a model revision number, found {:?}",
                path.display(),
                text.trim()
            ))
        }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(1),
        Err(e) => Err(e).with_context(|| format!("cannot read {}", path.display())),
    }
}

/// File names inside a study directory.
pub mod files {
    /// Model revision of the code that computed the runs ([`super::MODEL_REVISION`]).
    pub const REVISION: &str = "model_revision.txt";
    /// Resolved configuration.
    pub const CONFIG: &str = "config.toml";
    /// Checkpoint: one JSON run record per line.
    pub const RUNS: &str = "runs.jsonl";
    /// Shard description of this directory (`K/N`), absent for unsharded studies.
    pub const SHARD: &str = "shard.txt";
    /// Summary.
    pub const SUMMARY: &str = "summary.csv";
    /// Per-run picked modes.
    pub const REALIZATIONS: &str = "realizations.csv";
    /// FRF mean and 90 % band.
    pub const FRF_BAND: &str = "frf_band.csv";
    /// Lost frames per run and exposure.
    pub const LOST_FRAMES: &str = "lost_frames.csv";
}

/// Reads the run records of a checkpoint file. A last line cut short by an interruption is
/// ignored (that run is simply computed again); any other bad line is an error naming it.
pub fn read_checkpoint(path: &Path) -> anyhow::Result<Vec<RunRecord>> {
    let file = match std::fs::File::open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(e).with_context(|| format!("cannot read {}", path.display())),
    };
    let lines: Vec<String> = std::io::BufReader::new(file)
        .lines()
        .collect::<Result<_, _>>()
        .with_context(|| format!("cannot read {}", path.display()))?;
    let mut out = Vec::with_capacity(lines.len());
    for (i, line) in lines.iter().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        match serde_json::from_str::<RunRecord>(line) {
            Ok(r) => out.push(r),
            Err(_) if i + 1 == lines.len() => break,
            Err(e) => {
                return Err(bad_input(format!(
                    "{}: line {}: not a run record: {e}",
                    path.display(),
                    i + 1
                )))
            }
        }
    }
    Ok(out)
}

/// Options of one study execution (not part of the results).
#[derive(Debug, Clone)]
pub struct Execution {
    /// Output directory.
    pub out: PathBuf,
    /// Continue from `runs.jsonl` in `out`.
    pub resume: bool,
    /// Worker threads (0 = all cores).
    pub threads: usize,
    /// Runs computed by this process.
    pub shard: Shard,
    /// Show a progress bar (when stderr is a terminal).
    pub progress: bool,
}

/// Runs (or resumes) the runs of `shard` and returns all records in `out`, sorted by run.
pub fn execute(
    cfg: &StudyConfig,
    scenario: &dyn Scenario,
    exec: &Execution,
) -> anyhow::Result<Vec<RunRecord>> {
    cfg.validate()?;
    std::fs::create_dir_all(&exec.out)
        .with_context(|| format!("cannot create {}", exec.out.display()))?;
    let cfg_path = exec.out.join(files::CONFIG);
    let runs_path = exec.out.join(files::RUNS);
    let shard_path = exec.out.join(files::SHARD);
    let shard_text = format!("{}/{}\n", exec.shard.index, exec.shard.count);
    let mut done = Vec::new();
    if runs_path.exists() || cfg_path.exists() {
        if !exec.resume {
            return Err(bad_input(format!(
                "{} already holds a study; pass --resume to continue it, or choose another --out",
                exec.out.display()
            )));
        }
        let old_text = std::fs::read_to_string(&cfg_path)
            .with_context(|| format!("cannot read {}", cfg_path.display()))?;
        let old: StudyConfig = toml::from_str(&old_text)
            .map_err(|e| bad_input(format!("{}: {e}", cfg_path.display())))?;
        if &old != cfg {
            return Err(bad_input(format!(
                "--resume: the configuration differs from the one in {} (resume with the same \
                 preset, runs, exposures, seed and options)",
                cfg_path.display()
            )));
        }
        let revision = recorded_revision(&exec.out)?;
        if revision != MODEL_REVISION {
            return Err(bad_input(format!(
                "--resume: {} holds runs of model revision {revision}, this build computes \
                 revision {MODEL_REVISION}; mixing them would give a study of two code \
                 versions. Start it again in a new --out (without --out, the default directory \
                 already differs)",
                exec.out.display()
            )));
        }
        let old_shard = std::fs::read_to_string(&shard_path).unwrap_or_else(|_| "1/1\n".into());
        if old_shard != shard_text {
            return Err(bad_input(format!(
                "--resume: {} holds shard {}, not {}",
                exec.out.display(),
                old_shard.trim(),
                shard_text.trim()
            )));
        }
        done = read_checkpoint(&runs_path)?;
        // rewrite the checkpoint without a possibly truncated tail
        let mut text = String::new();
        for r in &done {
            text.push_str(&serde_json::to_string(r)?);
            text.push('\n');
        }
        std::fs::write(&runs_path, text)
            .with_context(|| format!("cannot write {}", runs_path.display()))?;
    } else {
        std::fs::write(&cfg_path, cfg.to_toml())
            .with_context(|| format!("cannot write {}", cfg_path.display()))?;
        let rev_path = exec.out.join(files::REVISION);
        std::fs::write(&rev_path, format!("{MODEL_REVISION}\n"))
            .with_context(|| format!("cannot write {}", rev_path.display()))?;
        if exec.shard != Shard::ALL {
            std::fs::write(&shard_path, &shard_text)?;
        }
    }
    let have: std::collections::BTreeSet<u64> = done.iter().map(|r| r.run).collect();
    let pending: Vec<u64> = (0..cfg.runs)
        .filter(|r| exec.shard.contains(*r) && !have.contains(r))
        .collect();

    let file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&runs_path)
        .with_context(|| format!("cannot open {}", runs_path.display()))?;
    let sink = Mutex::new(file);
    let new = Mutex::new(Vec::new());
    let bar = progress_bar(pending.len() as u64, exec.progress && !pending.is_empty());
    if !have.is_empty() {
        eprintln!(
            "resuming {}: {} runs already done, {} to go",
            exec.out.display(),
            have.len(),
            pending.len()
        );
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(exec.threads)
        .stack_size(64 << 20)
        .build()
        .context("cannot start the worker threads")?;
    let result: anyhow::Result<()> = pool.install(|| {
        use rayon::prelude::*;
        pending.par_iter().try_for_each(|&r| -> anyhow::Result<()> {
            let mut rng = run_rng(cfg.seed, r);
            let rec = scenario
                .run(r, &mut rng)
                .with_context(|| format!("run {r}"))?;
            let line = serde_json::to_string(&rec)? + "\n";
            {
                let mut f = sink
                    .lock()
                    .map_err(|_| anyhow::anyhow!("checkpoint lock"))?;
                f.write_all(line.as_bytes())
                    .and_then(|_| f.flush())
                    .with_context(|| format!("cannot append to {}", runs_path.display()))?;
            }
            new.lock()
                .map_err(|_| anyhow::anyhow!("result lock"))?
                .push(rec);
            bar.inc(1);
            Ok(())
        })
    });
    bar.finish_and_clear();
    result?;
    done.extend(new.into_inner().unwrap_or_default());
    done.sort_by_key(|r| r.run);
    Ok(done)
}

fn progress_bar(len: u64, show: bool) -> indicatif::ProgressBar {
    use std::io::IsTerminal as _;
    if !show || !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} runs (eta {eta})",
    ) {
        bar.set_style(style);
    }
    bar
}

/// The study outputs computed from a complete, sorted set of run records.
#[derive(Debug, Clone, PartialEq)]
pub struct Outputs {
    /// `summary.csv` rows.
    pub summary: Vec<SummaryRow>,
    /// `realizations.csv` rows.
    pub realizations: Vec<RealizationRow>,
    /// `frf_band.csv` rows.
    pub frf_band: Vec<FrfBandRow>,
    /// `(run, exposure_ms, lost_frames, frames, failed)`.
    pub lost: Vec<(u64, f64, u64, u64, bool)>,
}

/// Aggregates run records (sorted by run) into the study outputs. Deterministic.
pub fn aggregate(
    cfg: &StudyConfig,
    scenario: &dyn Scenario,
    records: &[RunRecord],
) -> anyhow::Result<Outputs> {
    let bands = scenario.bands();
    let freqs = scenario.frf_freqs();
    let mut summary = Vec::new();
    let mut realizations = Vec::new();
    let mut frf_band = Vec::new();
    let mut lost = Vec::new();
    for rec in records {
        if rec.vision.len() != cfg.exposures_ms.len() {
            return Err(bad_input(format!(
                "run {}: {} vision records for {} exposures",
                rec.run,
                rec.vision.len(),
                cfg.exposures_ms.len()
            )));
        }
    }
    // mean natural frequency of each mode over the runs, for the E2PR
    let nat: Vec<f64> = (0..bands.len())
        .map(|m| {
            let v: Vec<f64> = records
                .iter()
                .filter_map(|r| r.natural_f_hz.get(m).copied())
                .collect();
            stats::mean(&v).unwrap_or(f64::NAN)
        })
        .collect();
    let peaks_of = |sys: &SystemRecord, m: usize| sys.peaks.get(m).copied().flatten();
    for (ei, &exp) in cfg.exposures_ms.iter().enumerate() {
        let vis_ok: Vec<&RunRecord> = records.iter().filter(|r| !r.vision[ei].failed).collect();
        for r in records {
            let v = &r.vision[ei];
            lost.push((r.run, exp, v.lost_frames, v.frames, v.failed));
        }
        for (m, nat_m) in nat.iter().enumerate() {
            let tr: Vec<PeakRecord> = records
                .iter()
                .filter_map(|r| peaks_of(&r.transducer, m))
                .collect();
            let vi: Vec<PeakRecord> = vis_ok
                .iter()
                .filter_map(|r| peaks_of(&r.vision[ei].system, m))
                .collect();
            let row = |system, p: &[PeakRecord]| {
                let f: Vec<f64> = p.iter().map(|p| p.f_hz).collect();
                let a: Vec<f64> = p.iter().map(|p| p.a).collect();
                SummaryRow {
                    system,
                    exposure_ms: exp,
                    mode: m + 1,
                    runs: p.len(),
                    mu_f_hz: stats::mean(&f).unwrap_or(f64::NAN),
                    sigma_f_hz: stats::std_dev(&f).unwrap_or(f64::NAN),
                    mu_a: stats::mean(&a).unwrap_or(f64::NAN),
                    sigma_a: stats::std_dev(&a).unwrap_or(f64::NAN),
                    e2pr: exp / 1000.0 * nat_m,
                    chi_mu: None,
                    chi_sigma: None,
                }
            };
            let t = row(System::Transducer, &tr);
            let mut v = row(System::Vision, &vi);
            if scenario.with_chi() {
                v.chi_mu = Some(v.mu_a / t.mu_a);
                v.chi_sigma = Some(v.sigma_a / t.sigma_a);
            }
            summary.push(t);
            summary.push(v);
        }
        // realizations: transducer and vision picks of every run at this exposure
        for r in records {
            for (system, sys, ok) in [
                (System::Transducer, &r.transducer, true),
                (System::Vision, &r.vision[ei].system, !r.vision[ei].failed),
            ] {
                if !ok {
                    continue;
                }
                for m in 0..bands.len() {
                    if let Some(p) = peaks_of(sys, m) {
                        realizations.push(RealizationRow {
                            run: r.run,
                            exposure_ms: exp,
                            system,
                            mode: m + 1,
                            f_hz: p.f_hz,
                            a: p.a,
                        });
                    }
                }
            }
        }
        // FRF band per system
        for (system, curves) in [
            (
                System::Transducer,
                records
                    .iter()
                    .map(|r| &r.transducer.frf_abs)
                    .collect::<Vec<_>>(),
            ),
            (
                System::Vision,
                vis_ok
                    .iter()
                    .map(|r| &r.vision[ei].system.frf_abs)
                    .collect(),
            ),
        ] {
            if curves.is_empty() {
                continue;
            }
            let mut col = Vec::with_capacity(curves.len());
            for (k, &f) in freqs.iter().enumerate() {
                if f > cfg.frf_max_hz {
                    break;
                }
                col.clear();
                col.extend(curves.iter().filter_map(|c| c.get(k).map(|v| *v as f64)));
                col.sort_by(f64::total_cmp);
                frf_band.push(FrfBandRow {
                    system,
                    exposure_ms: exp,
                    freq_hz: f,
                    mean_abs: stats::mean(&col).unwrap_or(f64::NAN),
                    p05_abs: stats::percentile_sorted(&col, 5.0).unwrap_or(f64::NAN),
                    p95_abs: stats::percentile_sorted(&col, 95.0).unwrap_or(f64::NAN),
                });
            }
        }
    }
    Ok(Outputs {
        summary,
        realizations,
        frf_band,
        lost,
    })
}

/// `lost_frames.csv` bytes: `run,exposure_ms,lost_frames,frames,failed`.
pub fn lost_frames_csv(lost: &[(u64, f64, u64, u64, bool)]) -> Vec<u8> {
    let mut s = String::from("run,exposure_ms,lost_frames,frames,failed\n");
    for (r, e, l, n, f) in lost {
        s.push_str(&format!("{r},{e},{l},{n},{f}\n"));
    }
    s.into_bytes()
}

/// Writes the CSV outputs (and returns their paths). Plots are written separately.
pub fn write_outputs(
    dir: &Path,
    scenario: &dyn Scenario,
    out: &Outputs,
) -> anyhow::Result<Vec<PathBuf>> {
    let items: [(&str, Vec<u8>); 4] = [
        (
            files::SUMMARY,
            crate::report::summary_csv(&out.summary, scenario.with_chi()),
        ),
        (
            files::REALIZATIONS,
            crate::report::realizations_csv(&out.realizations),
        ),
        (files::FRF_BAND, crate::report::frf_band_csv(&out.frf_band)),
        (files::LOST_FRAMES, lost_frames_csv(&out.lost)),
    ];
    let mut paths = Vec::new();
    for (name, bytes) in items {
        let p = dir.join(name);
        std::fs::write(&p, bytes).with_context(|| format!("cannot write {}", p.display()))?;
        paths.push(p);
    }
    Ok(paths)
}

/// Lost-frame counts per exposure: (exposure_ms, total lost, total frames, failed runs).
pub fn lost_by_exposure(out: &Outputs) -> Vec<(f64, u64, u64, u64)> {
    let mut m: BTreeMap<u64, (f64, u64, u64, u64)> = BTreeMap::new();
    for &(_, e, l, n, f) in &out.lost {
        let k = e.to_bits();
        let s = m.entry(k).or_insert((e, 0, 0, 0));
        s.1 += l;
        s.2 += n;
        s.3 += f as u64;
    }
    let mut v: Vec<_> = m.into_values().collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lost_frames_are_interpolated_linearly() {
        let mut v = [9.0, 1.0, 9.0, 9.0, 4.0, 9.0];
        let ok = [false, true, false, false, true, false];
        assert_eq!(fill_lost_frames(&mut v, &ok), 4);
        assert_eq!(v, [1.0, 1.0, 2.0, 3.0, 4.0, 4.0]);
        let mut v = [5.0, 6.0];
        assert_eq!(fill_lost_frames(&mut v, &[false, false]), 2);
        assert_eq!(v, [5.0, 6.0]);
    }

    #[test]
    fn shards_partition_the_runs() {
        let shards: Vec<Shard> = (1..=3)
            .map(|k| Shard::parse(&format!("{k}/3")).unwrap())
            .collect();
        for r in 0..100 {
            assert_eq!(shards.iter().filter(|s| s.contains(r)).count(), 1);
        }
        for bad in ["0/2", "3/2", "1/0", "x", "1-2"] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn run_streams_depend_only_on_seed_and_run() {
        use rand::Rng as _;
        let a: u64 = run_rng(7, 3).random();
        let b: u64 = run_rng(7, 3).random();
        let c: u64 = run_rng(7, 4).random();
        let d: u64 = run_rng(8, 3).random();
        assert_eq!(a, b);
        assert_ne!(a, c);
        assert_ne!(a, d);
    }

    #[test]
    fn study_file_fills_defaults_and_rejects_unknown_fields() {
        let c = StudyConfig::from_toml_str("preset = \"grandstand\"\nruns = 7\n").unwrap();
        assert_eq!(c.runs, 7);
        assert_eq!(
            c.exposures_ms,
            StudyConfig::preset(Preset::Grandstand).exposures_ms
        );
        assert!(StudyConfig::from_toml_str("preset = \"grandstand\"\nrunz = 7\n").is_err());
        // the resolved config round-trips through its TOML
        let back: StudyConfig = toml::from_str(&c.to_toml()).unwrap();
        assert_eq!(back, c);
    }

    #[test]
    fn validation_names_the_field() {
        let mut c = StudyConfig::preset(Preset::Grandstand);
        c.runs = 0;
        assert!(format!("{}", c.validate().unwrap_err()).starts_with("runs"));
        let mut c = StudyConfig::preset(Preset::Grandstand);
        c.exposures_ms = vec![40.0, 40.0];
        assert!(format!("{}", c.validate().unwrap_err()).starts_with("exposures_ms"));
    }

    #[test]
    fn truncated_checkpoint_tail_is_ignored() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("runs.jsonl");
        let rec = RunRecord {
            run: 3,
            natural_f_hz: vec![2.0],
            transducer: SystemRecord {
                peaks: vec![Some(PeakRecord { f_hz: 2.0, a: 1.5 })],
                frf_abs: vec![0.1, 0.2],
            },
            vision: vec![],
        };
        let line = serde_json::to_string(&rec).unwrap();
        std::fs::write(&p, format!("{line}\n{}", &line[..10])).unwrap();
        assert_eq!(read_checkpoint(&p).unwrap(), vec![rec.clone()]);
        std::fs::write(&p, format!("{}\n{line}\n", &line[..10])).unwrap();
        let e = read_checkpoint(&p).unwrap_err();
        assert!(format!("{e}").contains("line 1"));
    }
}

/// Fills the values of lost frames (`valid[i] == false`) by linear interpolation between the
/// neighbouring valid frames; lost frames before the first or after the last valid one take its
/// value. Returns the number of lost frames; with no valid frame at all, nothing is changed and
/// the count equals the length.
pub fn fill_lost_frames(values: &mut [f64], valid: &[bool]) -> usize {
    let n = values.len().min(valid.len());
    let lost = valid[..n].iter().filter(|v| !**v).count();
    let Some(first) = valid[..n].iter().position(|v| *v) else {
        return lost;
    };
    let mut prev = first;
    for i in 0..first {
        values[i] = values[first];
    }
    for i in first + 1..n {
        if valid[i] {
            let gap = i - prev;
            for j in prev + 1..i {
                let w = (j - prev) as f64 / gap as f64;
                values[j] = values[prev] * (1.0 - w) + values[i] * w;
            }
            prev = i;
        }
    }
    for i in prev + 1..n {
        values[i] = values[prev];
    }
    lost
}

/// Fraction of lost frames above which a vision run is reported as failed (SPEC 3.1).
pub const MAX_LOST_FRACTION: f64 = 0.05;

/// The vision system at one exposure, as every scenario runs it: centroids frame `k` of
/// `0..disp.len()` with `centroid(k)`, turns the centroid row `cy` (px) into the displacement
/// with `to_disp`, fills the lost frames ([`fill_lost_frames`]) and, unless more than
/// [`MAX_LOST_FRACTION`] of them were lost, measures the filled record (as `f32`) with
/// `measure`. `disp` and `valid` are the caller's buffers, reused across exposures; `bands` is
/// the number of mode bands (the empty peaks of a failed run).
pub fn measure_vision<E: std::fmt::Display>(
    exposure_ms: f64,
    disp: &mut [f64],
    valid: &mut [bool],
    bands: usize,
    mut centroid: impl FnMut(usize) -> Result<firmware_core::centroid::Centroid, E>,
    to_disp: impl Fn(f32) -> f64,
    measure: impl FnOnce(&[f32]) -> anyhow::Result<SystemRecord>,
) -> anyhow::Result<VisionRecord> {
    let frames = disp.len();
    for k in 0..frames {
        let c = centroid(k).map_err(|e| anyhow::anyhow!("frame {k}: {e}"))?;
        match c.position() {
            Some((_, cy)) => {
                disp[k] = to_disp(cy);
                valid[k] = true;
            }
            None => valid[k] = false,
        }
    }
    let lost = fill_lost_frames(disp, valid) as u64;
    let failed = lost as f64 > MAX_LOST_FRACTION * frames as f64;
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

/// Streams `x` (input) and `y` (output) through a firmware-core Welch estimator, picks the
/// peaks of `bands` with firmware-core's peak picking and keeps |H1| of the first `keep_bins`
/// bins. `scale` multiplies H1 (unit conversion).
pub fn measure_system<const SEG: usize, const NFFT: usize, const SCR: usize>(
    welch: &mut firmware_core::spectrum::WelchH1<SEG, NFFT, SCR>,
    x: &[f32],
    y: &[f32],
    bands: &[(f64, f64)],
    keep_bins: usize,
    scale: f64,
) -> anyhow::Result<SystemRecord> {
    welch.reset();
    welch
        .push(x, y)
        .map_err(|e| anyhow::anyhow!("Welch estimator: {e}"))?;
    let peaks = bands
        .iter()
        .map(|&(lo, hi)| {
            firmware_core::peaks::pick_with(
                welch.bins(),
                welch.df_hz(),
                (lo as f32, hi as f32),
                false,
                |k| welch.h1(k),
            )
            .map(|p| PeakRecord {
                f_hz: p.f_hz as f64,
                a: p.amplitude as f64 * scale,
            })
        })
        .collect();
    let frf_abs = (0..keep_bins.min(welch.bins()))
        .map(|k| {
            welch
                .h1(k)
                .map_or(f32::NAN, |h| (h.norm() as f64 * scale) as f32)
        })
        .collect();
    Ok(SystemRecord { peaks, frf_abs })
}

pub mod cantilever;
pub mod effects;
pub mod grandstand;
pub mod render;

pub use cantilever::Cantilever;
pub use grandstand::Grandstand;

/// The scenario a configuration describes.
pub fn scenario_for(cfg: &StudyConfig) -> anyhow::Result<Box<dyn Scenario>> {
    Ok(match cfg.preset {
        Preset::Grandstand => Box::new(Grandstand::new(cfg)?),
        Preset::Cantilever => Box::new(Cantilever::new(cfg)?),
    })
}
