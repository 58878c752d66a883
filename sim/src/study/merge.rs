//! Merging the directories of `study --shard K/N` runs into the outputs of the whole study: the
//! shards must belong to one study (same configuration, same model revision) and together hold
//! every run exactly once.

use super::checkpoint::{files, read_checkpoint, recorded_revision};
use super::{RunRecord, StudyConfig};
use anyhow::Context as _;
use std::path::{Path, PathBuf};
use vibcam_readers::bad_input;

/// The shards of one study, read and checked.
#[derive(Debug, Clone, PartialEq)]
pub struct Merged {
    /// The study's configuration.
    pub config: StudyConfig,
    /// Model revision of the code that computed the runs.
    pub revision: u32,
    /// Every run, sorted by run index.
    pub records: Vec<RunRecord>,
}

/// Reads the shard directories `dirs` and checks that they are one study, complete, with no
/// run twice; errors name the directory or the run.
pub fn read_shards(dirs: &[PathBuf]) -> anyhow::Result<Merged> {
    let first = dirs
        .first()
        .ok_or_else(|| bad_input("no directories to merge"))?;
    let mut merged: Option<Merged> = None;
    let mut layout: Option<(String, &PathBuf)> = None;
    for dir in dirs {
        // shards of two layouts (K/N with different N) overlap: say so, not "run r twice"
        let shard = std::fs::read_to_string(dir.join(files::SHARD))
            .map(|t| t.trim().to_string())
            .unwrap_or_else(|_| "1/1".into());
        let count = shard.split_once('/').map(|(_, n)| n.to_string());
        match &layout {
            Some((n, d)) if Some(n) != count.as_ref() => {
                return Err(bad_input(format!(
                    "{} is shard {shard}, but {} is a shard of {n}: merge the shards of one \
                     layout ($shard K/N with the same N)",
                    dir.display(),
                    d.display()
                )));
            }
            Some(_) => {}
            None => layout = count.map(|n| (n, dir)),
        }
        // runs of two code revisions must not be mixed (see MODEL_REVISION)
        let rev = recorded_revision(dir)?;
        let p = dir.join(files::CONFIG);
        let text = std::fs::read_to_string(&p)
            .map_err(|e| bad_input(format!("cannot read {}: {e}", p.display())))?;
        let c: StudyConfig =
            toml::from_str(&text).map_err(|e| bad_input(format!("{}: {e}", p.display())))?;
        let records = read_checkpoint(&dir.join(files::RUNS))?.records;
        let Some(m) = &mut merged else {
            merged = Some(Merged {
                config: c,
                revision: rev,
                records,
            });
            continue;
        };
        if m.revision != rev {
            return Err(bad_input(format!(
                "{}: runs of model revision {rev}, but {} holds revision {}; only shards \
                 computed by the same code can be merged",
                dir.display(),
                first.display(),
                m.revision
            )));
        }
        if m.config.runs_key() != c.runs_key() || m.config.runs != c.runs {
            return Err(bad_input(format!(
                "{}: configuration differs from {}; only shards of one study can be merged",
                p.display(),
                first.join(files::CONFIG).display()
            )));
        }
        m.records.extend(records);
    }
    let mut m = merged.ok_or_else(|| bad_input("no directories to merge"))?;
    m.records.sort_by_key(|r| r.run);
    if let Some(w) = m.records.windows(2).find(|w| w[0].run == w[1].run) {
        return Err(bad_input(format!(
            "run {} appears in more than one directory",
            w[0].run
        )));
    }
    let missing: Vec<u64> = (0..m.config.runs)
        .filter(|r| m.records.binary_search_by_key(r, |x| x.run).is_err())
        .collect();
    if let Some(first_missing) = missing.first() {
        return Err(bad_input(format!(
            "{} of {} runs are missing (first: run {first_missing}); finish the shards (study \
             $resume) before merging",
            missing.len(),
            m.config.runs,
        )));
    }
    Ok(m)
}

/// Writes the merged study's configuration, revision and checkpoint into `out` (which must not
/// hold a study yet).
pub fn write_merged(out: &Path, m: &Merged) -> anyhow::Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    if out.join(files::RUNS).exists() {
        return Err(bad_input(format!(
            "{} already holds a study; choose another $out",
            out.display()
        )));
    }
    super::checkpoint::refuse_foreign_entries(out)?;
    // each file whole or absent; runs.jsonl last, so that a directory holding it is complete
    let write = vibcam_report::export::write_atomic;
    write(&out.join(files::CONFIG), m.config.to_toml().as_bytes())?;
    write(
        &out.join(files::REVISION),
        format!("{}\n", m.revision).as_bytes(),
    )?;
    let mut lines = String::new();
    for r in &m.records {
        lines.push_str(&serde_json::to_string(r)?);
        lines.push('\n');
    }
    write(&out.join(files::RUNS), lines.as_bytes())?;
    Ok(())
}
