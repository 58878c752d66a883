//! The study directory on disk: the checkpoint (`runs.jsonl`, one run record per line), the model
//! revision of the code that computed it, and the names of the files a study writes.

use super::RunRecord;
use anyhow::Context as _;
use std::path::Path;
use vibcam_readers::bad_input;

/// Revision of the simulation and measurement code whose results a study directory holds.
/// Bump it with every change that alters a study's numbers (models, renderer, firmware-core
/// numerics), so that a resumed or merged study never mixes runs of two code revisions: the
/// revision is written to [`files::REVISION`], checked on `--resume` and by `merge`, and part of
/// the default output directory's name.
///
/// History: 1 = everything before the file existed; 2 = `f32` twiddles and window in
/// firmware-core's `dft`/`spectrum` (results move in the 6th significant digit); 3 = synthetic
/// recordings rendered by the studies' EPSA camera with the rig's target (level 255, threshold
/// 127, 0.5 px edge) instead of their own renderer (study outputs unchanged); 4 = the fast
/// binary-centroid path for identity effects (the same pixels as the rendered frame; the
/// centroid's f32 sums in another order: grandstand vision amplitudes move in the 6th-7th
/// significant digit, e.g. mode 1 at 40 ms 4.39004754 -> 4.39004554 mm/kN; cantilever unchanged);
/// 5 = the grandstand's rest padding a whole number of ramp blocks (every exposure window sums
/// whole precomputed blocks: other `f32` roundings of the averaged ramp) and the fast path's
/// row sums in `f32` (default study, mode 1 at 40 ms: 4.39004554 -> 4.39004738 mm/kN, sigma
/// 0.37510864 -> 0.37510850; cantilever unchanged); 6 = firmware-core's Lucas-Kanade window
/// smoothed in integers and its cross moments formed per lag in another order (the same step
/// to the `f32` rounding: studies with `tracker = "lk"` move in the 6th-7th significant digit,
/// e.g. grandstand, read noise 1, 4 runs, mode 1 at 40 ms 4.4749754667 -> 4.4749758244 mm/kN;
/// the other trackers unchanged); 7 = the Lucas-Kanade cross moments on hosts (x86-64,
/// AArch64) accumulated in eight lanes across the window, and the window's `[1 2 1]` smoothing
/// in two passes there (the smoothing exact as before; the moments' `f32` sums in another
/// order; the M4 keeps revision 6's): studies with `tracker = "lk"` move in the 7th
/// significant digit (the same study 4.4749758244 -> 4.4749749899 mm/kN); 8 = the Lucas-Kanade
/// window kept while the position stays within 0.95 px of it (was 3/4 px; fewer windows read
/// again, the same least-squares step on a window one pixel off): studies with
/// `tracker = "lk"` move in the 7th significant digit (the same study 4.4749749899 ->
/// 4.4749757051 mm/kN, mode 2 2.8392920494 -> 2.8392913342; at 180 ms unchanged); 9 = the
/// rig's paper configuration (`studies/paper-cantilever.toml`) takes the intensity-weighted
/// centroid instead of the binary one, after the paper's held-back figures confirmed its
/// prediction (docs/validation.md 2.5; no code of the studies changed, but a study of that
/// file now gives other figures: mode 2 `chi_mu` at 2 / 4 / 6 ms 100.41 / 98.88 / 97.05 %
/// (binary, 5000 runs) -> 99.18 / 97.10 / 93.79 % (1000 runs), mode 1 95.52 / 95.43 / 95.30 ->
/// 95.57 / 95.48 / 95.32 %).
pub const MODEL_REVISION: u32 = 9;

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
    /// JCGM 101 statement (both coverage intervals) of every reported quantity.
    pub const COVERAGE: &str = "coverage.csv";
    /// State of the adaptive procedure per quantity (adaptive studies only).
    pub const ADAPTIVE: &str = "adaptive.csv";
    /// Lock file of a running study (holds the pid).
    pub const LOCK: &str = ".lock";
}

/// The run records of a checkpoint, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct Checkpoint {
    /// The records, one per run, sorted by run.
    pub records: Vec<RunRecord>,
    /// Byte length of the complete lines (a torn last line is not counted).
    pub valid_len: u64,
    /// A last line cut short by an interruption was found (and is not in `records`).
    pub torn_tail: bool,
    /// Runs that appeared more than once with identical records (kept once).
    pub duplicates: Vec<u64>,
}

/// Reads the run records of a checkpoint file (a missing file is an empty checkpoint). A last
/// line without its newline that does not parse was cut short by an interruption: it is left out
/// (that run is computed again) and reported in [`Checkpoint::torn_tail`]. A run recorded twice
/// with identical records is kept once and reported; twice with different records is an error
/// naming the run, as is any other bad line (named by its number).
pub fn read_checkpoint(path: &Path) -> anyhow::Result<Checkpoint> {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
        Err(e) => return Err(e).with_context(|| format!("cannot read {}", path.display())),
    };
    let mut by_run: std::collections::BTreeMap<u64, RunRecord> = Default::default();
    let (mut valid_len, mut torn_tail, mut duplicates) = (0u64, false, Vec::new());
    let mut start = 0usize;
    let mut line_no = 0usize;
    while start < bytes.len() {
        line_no += 1;
        let end = bytes[start..]
            .iter()
            .position(|b| *b == b'\n')
            .map(|p| start + p);
        let line = &bytes[start..end.unwrap_or(bytes.len())];
        let parsed = std::str::from_utf8(line)
            .map_err(|e| e.to_string())
            .and_then(|t| {
                if t.trim().is_empty() {
                    Ok(None)
                } else {
                    serde_json::from_str::<RunRecord>(t)
                        .map(Some)
                        .map_err(|e| e.to_string())
                }
            });
        match (parsed, end) {
            (Ok(rec), Some(e)) => {
                if let Some(rec) = rec {
                    if let Some(old) = by_run.get(&rec.run) {
                        if *old != rec {
                            return Err(bad_input(format!(
                                "{}: line {line_no}: run {} is recorded twice with different \
                                 results (two processes with different code or settings wrote \
                                 this checkpoint); it cannot be resumed or merged",
                                path.display(),
                                rec.run
                            )));
                        }
                        duplicates.push(rec.run);
                    } else {
                        by_run.insert(rec.run, rec);
                    }
                }
                valid_len = e as u64 + 1;
                start = e + 1;
            }
            // no newline: the last write was cut short
            (_, None) => {
                torn_tail = true;
                break;
            }
            (Err(e), Some(_)) => {
                return Err(bad_input(format!(
                    "{}: line {line_no}: not a run record: {e}",
                    path.display()
                )))
            }
        }
    }
    Ok(Checkpoint {
        records: by_run.into_values().collect(),
        valid_len,
        torn_tail,
        duplicates,
    })
}

/// Refuses to start a study in `dir` when it holds anything a study's own start does not write
/// (the lock, the revision, the shard, the configuration and their temporary files): a new
/// study never writes its outputs over files of someone else's in an existing folder.
pub fn refuse_foreign_entries(dir: &Path) -> anyhow::Result<()> {
    let own = [
        files::LOCK,
        files::REVISION,
        files::SHARD,
        files::CONFIG,
        files::RUNS,
    ];
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let temporary = own.iter().any(|o| name.starts_with(&format!(".{o}.tmp-")));
        if !own.contains(&name.as_str()) && !temporary {
            return Err(bad_input(format!(
                "{}: holds {name}, which is not a study's; a new study goes into a new or \
                 empty $out (nothing in a folder of yours is overwritten)",
                dir.display()
            )));
        }
    }
    Ok(())
}

/// An exclusive lock on a study directory, held while the value lives (`flock` on
/// `DIR/.lock`, which also records the holder's pid).
#[derive(Debug)]
pub struct DirLock {
    _file: std::fs::File,
}

/// Takes the exclusive lock of study directory `dir`; a second process gets an error naming the
/// holder's pid.
pub fn lock_dir(dir: &Path) -> anyhow::Result<DirLock> {
    use std::io::{Read as _, Seek as _, Write as _};
    let path = dir.join(files::LOCK);
    let mut file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .with_context(|| format!("cannot open {}", path.display()))?;
    match file.try_lock() {
        Ok(()) => {}
        Err(std::fs::TryLockError::WouldBlock) => {
            let mut holder = String::new();
            file.read_to_string(&mut holder).ok();
            return Err(bad_input(format!(
                "{} is in use by another host-harness process (pid {}); wait for it to finish, \
                 or use another $out",
                dir.display(),
                holder.trim()
            )));
        }
        Err(std::fs::TryLockError::Error(e)) => {
            return Err(e).with_context(|| format!("cannot lock {}", path.display()))
        }
    }
    file.set_len(0)?;
    file.rewind()?;
    write!(file, "{}", std::process::id())?;
    file.sync_all().ok();
    Ok(DirLock { _file: file })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::{PeakRecord, SystemRecord};

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
        let c = read_checkpoint(&p).unwrap();
        assert_eq!(c.records, vec![rec.clone()]);
        assert!(c.torn_tail);
        assert_eq!(c.valid_len, line.len() as u64 + 1);
        // an identical duplicate is kept once and reported; a different one is refused
        std::fs::write(&p, format!("{line}\n{line}\n")).unwrap();
        let c = read_checkpoint(&p).unwrap();
        assert_eq!((c.records.len(), c.duplicates.clone()), (1, vec![3]));
        let mut other = rec.clone();
        other.natural_f_hz = vec![2.5];
        let o = serde_json::to_string(&other).unwrap();
        std::fs::write(&p, format!("{line}\n{o}\n")).unwrap();
        let e = read_checkpoint(&p).unwrap_err();
        assert!(format!("{e}").contains("run 3 is recorded twice"), "{e}");
        std::fs::write(&p, format!("{}\n{line}\n", &line[..10])).unwrap();
        let e = read_checkpoint(&p).unwrap_err();
        assert!(format!("{e}").contains("line 1"));
    }
}
