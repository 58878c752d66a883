//! The study directory on disk: the checkpoint (`runs.jsonl`, one run record per line), the model
//! revision of the code that computed it, and the names of the files a study writes.

use super::RunRecord;
use crate::bad_input;
use anyhow::Context as _;
use std::io::BufRead as _;
use std::path::Path;

/// Revision of the simulation and measurement code whose results a study directory holds.
/// Bump it with every change that alters a study's numbers (models, renderer, firmware-core
/// numerics), so that a resumed or merged study never mixes runs of two code revisions: the
/// revision is written to [`files::REVISION`], checked on `--resume` and by `merge`, and part of
/// the default output directory's name.
///
/// History: 1 = everything before the file existed; 2 = `f32` twiddles and window in
/// firmware-core's `dft`/`spectrum` (results move in the 6th significant digit); 3 = synthetic
/// recordings rendered by the studies' EPSA camera with the rig's target (level 255, threshold
/// 127, 0.5 px edge) instead of their own renderer (study outputs unchanged).
pub const MODEL_REVISION: u32 = 3;

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
        assert_eq!(read_checkpoint(&p).unwrap(), vec![rec.clone()]);
        std::fs::write(&p, format!("{}\n{line}\n", &line[..10])).unwrap();
        let e = read_checkpoint(&p).unwrap_err();
        assert!(format!("{e}").contains("line 1"));
    }
}
