//! Running a study: one reproducible random stream per run, the runs of this process's shard
//! computed in parallel (rayon) and appended to the checkpoint as each finishes, and the resume
//! of an interrupted study (method.md §3.1 "Reproducibility").

use super::checkpoint::{self, files, DirLock, MODEL_REVISION};
use super::{RunRecord, Scenario, StudyConfig};
use anyhow::Context as _;
use rand::SeedableRng as _;
use rand_chacha::ChaCha8Rng;
use std::io::Write as _;
use std::path::PathBuf;
use std::sync::Mutex;
use vibcam_common::setting::{spell, Naming};
use vibcam_readers::bad_input;

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
        let err = || bad_input(format!("$shard: `{s}` is not K/N with 1 <= K <= N"));
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

    /// Whether run `r` belongs to this shard when whole batches of `batch` runs are dealt
    /// round-robin (adaptive studies); [`Shard::contains`] without a batch.
    pub fn owns(&self, r: u64, batch: Option<u64>) -> bool {
        match batch {
            Some(m) => self.contains(r / m),
            None => self.contains(r),
        }
    }
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

/// What an execution produced.
#[derive(Debug, Clone, PartialEq)]
pub struct Executed {
    /// Every run record in the directory, sorted by run.
    pub records: Vec<RunRecord>,
    /// Runs computed by this process (the others were found in the checkpoint).
    pub computed: usize,
}

/// Most worker threads a study starts: more than this many per core only costs memory.
pub const MAX_THREADS_PER_CORE: usize = 4;

/// Worker threads for `pending` runs: `requested` (0 = all cores) capped at the pending runs
/// and at [`MAX_THREADS_PER_CORE`] per core, with a warning when the request is cut.
pub fn worker_threads(requested: usize, pending: usize) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let max = cores * MAX_THREADS_PER_CORE;
    let want = if requested == 0 { cores } else { requested };
    let n = want.min(max).min(pending.max(1));
    if requested > max {
        let warning = format!(
            "warning: $threads {requested} capped at {max} ({MAX_THREADS_PER_CORE} per core on \
             {cores} cores)"
        );
        // printed here, for the command line (the study's own loop has no caller to return it to)
        eprintln!("{}", spell(&warning, Naming::Cli));
    }
    n
}

/// Checks that the study in `out` is the one `cfg` describes (configuration, model revision,
/// shard), so that a resume never mixes two studies.
fn check_resumable(cfg: &StudyConfig, exec: &Execution) -> anyhow::Result<()> {
    let cfg_path = exec.out.join(files::CONFIG);
    let old_text = std::fs::read_to_string(&cfg_path)
        .with_context(|| format!("cannot read {}", cfg_path.display()))?;
    let old: StudyConfig =
        toml::from_str(&old_text).map_err(|e| bad_input(format!("{}: {e}", cfg_path.display())))?;
    if old.runs_key() != cfg.runs_key() {
        return Err(bad_input(format!(
            "$resume: the configuration differs from the one in {} (resume with the same \
             preset, exposures, seed and options; runs may be raised)",
            cfg_path.display()
        )));
    }
    if cfg.runs < old.runs {
        return Err(bad_input(format!(
            "$resume: $runs {} is below the {} the study in {} was started with; runs can \
             be raised on resume (each run has its own random stream), not lowered",
            cfg.runs,
            old.runs,
            exec.out.display()
        )));
    }
    let revision = checkpoint::recorded_revision(&exec.out)?;
    if revision != MODEL_REVISION {
        return Err(bad_input(format!(
            "$resume: {} holds runs of model revision {revision}, this build computes \
             revision {MODEL_REVISION}; mixing them would give a study of two code \
             versions. Start it again in a new $out (without $out, the default directory \
             already differs)",
            exec.out.display()
        )));
    }
    let shard_text = format!("{}/{}\n", exec.shard.index, exec.shard.count);
    let old_shard =
        std::fs::read_to_string(exec.out.join(files::SHARD)).unwrap_or_else(|_| "1/1\n".into());
    if old_shard != shard_text {
        return Err(bad_input(format!(
            "$resume: {} holds shard {}, not {}",
            exec.out.display(),
            old_shard.trim(),
            shard_text.trim()
        )));
    }
    Ok(())
}

/// Opens (or creates) the study directory under its lock and returns the runs already done.
/// A new study's revision, shard and configuration are written atomically (the configuration
/// last: its presence marks a study). On resume a torn last checkpoint line is cut off (the file
/// is only ever shortened to its complete lines, never rewritten), identical duplicate records
/// are reported.
fn open_study(cfg: &StudyConfig, exec: &Execution) -> anyhow::Result<(DirLock, Vec<RunRecord>)> {
    std::fs::create_dir_all(&exec.out)
        .with_context(|| format!("cannot create {}", exec.out.display()))?;
    let lock = checkpoint::lock_dir(&exec.out)?;
    let cfg_path = exec.out.join(files::CONFIG);
    let runs_path = exec.out.join(files::RUNS);
    if !(runs_path.exists() || cfg_path.exists()) {
        checkpoint::refuse_foreign_entries(&exec.out)?;
        vibcam_report::export::write_atomic(
            &exec.out.join(files::REVISION),
            format!("{MODEL_REVISION}\n").as_bytes(),
        )?;
        if exec.shard != Shard::ALL {
            let shard_text = format!("{}/{}\n", exec.shard.index, exec.shard.count);
            vibcam_report::export::write_atomic(
                &exec.out.join(files::SHARD),
                shard_text.as_bytes(),
            )?;
        }
        vibcam_report::export::write_atomic(&cfg_path, cfg.to_toml().as_bytes())?;
        return Ok((lock, Vec::new()));
    }
    if !exec.resume {
        return Err(bad_input(format!(
            "{} already holds a study; pass $resume to continue it, or choose another $out",
            exec.out.display()
        )));
    }
    check_resumable(cfg, exec)?;
    // only the reporting (the coverage probability) or the run count changed: record it
    let old_text = std::fs::read_to_string(&cfg_path).unwrap_or_default();
    if old_text != cfg.to_toml() {
        vibcam_report::export::write_atomic(&cfg_path, cfg.to_toml().as_bytes())?;
    }
    let ck = checkpoint::read_checkpoint(&runs_path)?;
    if ck.torn_tail {
        eprintln!(
            "{}: dropped a last line cut short by an interruption (that run is computed again)",
            runs_path.display()
        );
        let f = std::fs::OpenOptions::new()
            .write(true)
            .open(&runs_path)
            .with_context(|| format!("cannot open {}", runs_path.display()))?;
        f.set_len(ck.valid_len)?;
        f.sync_all()?;
        vibcam_common::failpoint::hit("checkpoint-cut");
    }
    if !ck.duplicates.is_empty() {
        eprintln!(
            "{}: runs {:?} were recorded more than once with identical results; each is counted \
             once",
            runs_path.display(),
            ck.duplicates
        );
    }
    Ok((lock, ck.records))
}

/// Computes `pending` runs on `threads` workers, appending each record to the checkpoint (and
/// syncing it) as soon as it is done; returns the new records.
fn run_pending(
    cfg: &StudyConfig,
    scenario: &dyn Scenario,
    exec: &Execution,
    pending: &[u64],
) -> anyhow::Result<Vec<RunRecord>> {
    let runs_path = exec.out.join(files::RUNS);
    let file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&runs_path)
        .with_context(|| format!("cannot open {}", runs_path.display()))?;
    let sink = Mutex::new(file);
    let new = Mutex::new(Vec::new());
    let bar = progress_bar(
        pending.len() as u64,
        exec.progress && !pending.is_empty(),
        "runs",
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(worker_threads(exec.threads, pending.len()))
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
                // two writes, so that a crash test can stop between them (a torn line)
                let (head, tail) = line.as_bytes().split_at(line.len() / 2);
                f.write_all(head)
                    .and_then(|_| {
                        vibcam_common::failpoint::hit("checkpoint-torn");
                        f.write_all(tail)
                    })
                    .and_then(|_| f.sync_data())
                    .with_context(|| format!("cannot append to {}", runs_path.display()))?;
                vibcam_common::failpoint::hit("checkpoint-appended");
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
    Ok(new.into_inner().unwrap_or_default())
}

/// Runs (or resumes) the runs of `exec.shard`, holding the directory's lock throughout, and
/// returns all records in `exec.out`, sorted by run.
pub fn execute(
    cfg: &StudyConfig,
    scenario: &dyn Scenario,
    exec: &Execution,
) -> anyhow::Result<Executed> {
    cfg.validate()?;
    let (_lock, mut done) = open_study(cfg, exec)?;
    let batch = cfg.adaptive.as_ref().map(|a| a.batch);
    if !done.is_empty() {
        let have: std::collections::BTreeSet<u64> = done.iter().map(|r| r.run).collect();
        let to_go = (0..cfg.runs)
            .filter(|r| exec.shard.owns(*r, batch) && !have.contains(r))
            .count();
        eprintln!(
            "resuming {}: {} runs already done, {to_go} to go{}",
            exec.out.display(),
            done.len(),
            if batch.is_some() { " at most" } else { "" }
        );
    }
    let mut computed = 0;
    match (&cfg.adaptive, exec.shard == Shard::ALL) {
        // one process: batch after batch until the criterion holds (or the cap)
        (Some(a), true) => {
            let correction = scenario.exposure_correction()?;
            let modes = scenario.bands().len();
            let mut h = 2u64;
            loop {
                let upto = (h * a.batch).min(cfg.runs);
                computed += run_up_to(cfg, scenario, exec, &mut done, upto, batch)?;
                // `done` is sorted by run: the runs below `upto` are its start
                let prefix = &done[..done.partition_point(|r| r.run < upto)];
                let o = super::adaptive::outcome(cfg, a, modes, &correction, prefix)?;
                eprintln!(
                    "adaptive: {} batches ({} runs): {}",
                    h,
                    upto,
                    if o.stable {
                        "stable".to_string()
                    } else {
                        format!("not stable, about {} more batches", o.more_batches)
                    }
                );
                if o.stable || upto >= cfg.runs {
                    break;
                }
                h += 1;
            }
        }
        _ => computed += run_up_to(cfg, scenario, exec, &mut done, cfg.runs, batch)?,
    }
    Ok(Executed {
        records: done,
        computed,
    })
}

/// Runs this shard's runs below `upto` that `done` does not hold yet, appends them to `done`
/// (kept sorted by run) and returns how many were computed.
fn run_up_to(
    cfg: &StudyConfig,
    scenario: &dyn Scenario,
    exec: &Execution,
    done: &mut Vec<RunRecord>,
    upto: u64,
    batch: Option<u64>,
) -> anyhow::Result<usize> {
    let have: std::collections::BTreeSet<u64> = done.iter().map(|r| r.run).collect();
    let pending: Vec<u64> = (0..upto)
        .filter(|r| exec.shard.owns(*r, batch) && !have.contains(r))
        .collect();
    let new = run_pending(cfg, scenario, exec, &pending)?;
    let computed = new.len();
    done.extend(new);
    done.sort_by_key(|r| r.run);
    Ok(computed)
}

/// A progress bar of `len` `what` on standard error when `show` and it is a terminal (hidden
/// otherwise).
pub fn progress_bar(len: u64, show: bool, what: &str) -> indicatif::ProgressBar {
    use std::io::IsTerminal as _;
    if !show || !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    if let Ok(style) = indicatif::ProgressStyle::with_template(&format!(
        "{{spinner}} [{{elapsed_precise}}] {{bar:40}} {{pos}}/{{len}} {what} (eta {{eta}})"
    )) {
        bar.set_style(style);
    }
    bar
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
