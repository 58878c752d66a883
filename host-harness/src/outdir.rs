//! Output directories that are complete or absent (issue 11): a command writes every output
//! file into a hidden staging directory beside the target (`.NAME.partial-PID`, the same file
//! system), syncs them, and only then moves the whole directory into place. A failure or a
//! kill before that leaves the target as it was (the staging directory is removed on error;
//! after a kill, the next run removes stale ones); a directory of a previous run is replaced
//! as a whole, so no stale file of it survives beside the new ones.
//!
//! An existing non-empty target is refused without `--force`; with it, only a directory that
//! looks like an earlier output of the same command ([`Owner`]: it holds `report.txt` of
//! `analyze`, `recording.toml` of a recording, only rendered frames) is replaced, never one that
//! holds something else.

use crate::bad_input;
use anyhow::Context as _;
use std::path::{Path, PathBuf};

/// What an earlier output directory of a command looks like (so `--force` may replace it).
#[derive(Debug, Clone, Copy)]
pub enum Owner {
    /// It holds this file.
    Holds(&'static str),
    /// Every entry is a file whose name starts with the first and ends with the second text.
    OnlyFiles(&'static str, &'static str),
}

impl Owner {
    fn owns(self, dir: &Path) -> bool {
        match self {
            Owner::Holds(f) => dir.join(f).is_file(),
            Owner::OnlyFiles(pre, suf) => std::fs::read_dir(dir).is_ok_and(|d| {
                d.flatten().all(|e| {
                    let n = e.file_name();
                    let n = n.to_string_lossy();
                    e.path().is_file() && n.starts_with(pre) && n.ends_with(suf)
                })
            }),
        }
    }

    fn describe(self) -> String {
        match self {
            Owner::Holds(f) => format!("holds no {f}"),
            Owner::OnlyFiles(p, s) => format!("holds other files than {p}*{s}"),
        }
    }
}

/// A staged output directory; see the module documentation.
#[derive(Debug)]
pub struct Staged {
    target: PathBuf,
    stage: PathBuf,
    replace: bool,
    committed: bool,
}

impl Staged {
    /// Starts staging the outputs of a command into `target`; `force` allows replacing an
    /// earlier output directory of the command (`owner` says what one looks like).
    pub fn new(target: &Path, force: bool, owner: Owner) -> anyhow::Result<Staged> {
        let name = target
            .file_name()
            .and_then(|n| n.to_str())
            .filter(|n| *n != "." && *n != "..")
            .with_context(|| {
                format!(
                    "{}: an output directory needs a name (not . or ..)",
                    target.display()
                )
            })?;
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let replace = check_target(target, force, owner)?;
        std::fs::create_dir_all(&parent)
            .with_context(|| format!("cannot create {}", parent.display()))?;
        remove_stale_stages(&parent, name);
        let stage = parent.join(format!(".{name}.partial-{}", std::process::id()));
        if stage.exists() {
            std::fs::remove_dir_all(&stage)
                .with_context(|| format!("cannot remove {}", stage.display()))?;
        }
        std::fs::create_dir(&stage)
            .with_context(|| format!("cannot create {}", stage.display()))?;
        Ok(Staged {
            target: target.to_path_buf(),
            stage,
            replace,
            committed: false,
        })
    }

    /// The directory the outputs are written into until [`commit`](Self::commit).
    pub fn dir(&self) -> &Path {
        &self.stage
    }

    /// The target directory (where the outputs will be; for messages and reports).
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Writes `bytes` to the staged file `name`; returns the path it will have in the target.
    pub fn write(&self, name: &str, bytes: impl AsRef<[u8]>) -> anyhow::Result<PathBuf> {
        let p = self.stage.join(name);
        std::fs::write(&p, bytes)
            .with_context(|| format!("cannot write {}", self.target.join(name).display()))?;
        Ok(self.target.join(name))
    }

    /// Syncs every staged file and moves the directory into place (replacing a previous output
    /// directory as a whole when allowed), then syncs the parent directory.
    pub fn commit(mut self) -> anyhow::Result<()> {
        sync_tree(&self.stage)?;
        crate::failpoint::hit("outdir-synced");
        let parent = self.stage.parent().unwrap_or(Path::new(".")).to_path_buf();
        if self.replace && self.target.exists() {
            let old = parent.join(format!(
                ".{}.old-{}",
                self.target
                    .file_name()
                    .unwrap_or_default()
                    .to_string_lossy(),
                std::process::id()
            ));
            std::fs::rename(&self.target, &old)
                .with_context(|| format!("cannot move {} aside", self.target.display()))?;
            crate::failpoint::hit("outdir-old-moved");
            std::fs::rename(&self.stage, &self.target)
                .with_context(|| format!("cannot move the outputs to {}", self.target.display()))?;
            std::fs::remove_dir_all(&old)
                .with_context(|| format!("cannot remove {}", old.display()))?;
        } else {
            if self.target.exists() {
                // an empty directory (checked in `new`): make room for the rename
                std::fs::remove_dir(&self.target)
                    .with_context(|| format!("cannot replace {}", self.target.display()))?;
            }
            std::fs::rename(&self.stage, &self.target)
                .with_context(|| format!("cannot move the outputs to {}", self.target.display()))?;
        }
        self.committed = true;
        sync_dir(&parent)
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.stage);
        }
    }
}

/// Whether `target` may be written: absent or empty (returns false), or with `force` an
/// earlier output directory of the command (returns true).
fn check_target(target: &Path, force: bool, owner: Owner) -> anyhow::Result<bool> {
    if !target.exists() {
        return Ok(false);
    }
    if !target.is_dir() {
        return Err(bad_input(format!(
            "{}: exists and is not a directory",
            target.display()
        )));
    }
    let mut entries =
        std::fs::read_dir(target).with_context(|| format!("cannot read {}", target.display()))?;
    if entries.next().is_none() {
        return Ok(false);
    }
    if !force {
        return Err(bad_input(format!(
            "{}: not empty; choose another --out, or --force to replace an earlier output \
             directory of this command as a whole",
            target.display()
        )));
    }
    if !owner.owns(target) {
        return Err(bad_input(format!(
            "{}: not empty and {}, so it is not an earlier output of this command: not \
             replaced even with --force",
            target.display(),
            owner.describe()
        )));
    }
    Ok(true)
}

/// Removes staging and set-aside directories of `name` left by killed processes.
fn remove_stale_stages(parent: &Path, name: &str) {
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    let prefixes = [format!(".{name}.partial-"), format!(".{name}.old-")];
    for e in entries.flatten() {
        let file = e.file_name();
        let Some(f) = file.to_str() else { continue };
        let Some(pid) = prefixes.iter().find_map(|p| f.strip_prefix(p.as_str())) else {
            continue;
        };
        let alive = pid
            .parse::<u32>()
            .is_ok_and(|p| Path::new(&format!("/proc/{p}")).exists());
        if !alive {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

/// fsyncs every file below `dir` and the directories themselves.
fn sync_tree(dir: &Path) -> anyhow::Result<()> {
    for e in std::fs::read_dir(dir).with_context(|| format!("cannot read {}", dir.display()))? {
        let p = e?.path();
        if p.is_dir() {
            sync_tree(&p)?;
        } else {
            std::fs::File::open(&p)
                .and_then(|f| f.sync_all())
                .with_context(|| format!("cannot sync {}", p.display()))?;
        }
    }
    sync_dir(dir)
}

fn sync_dir(dir: &Path) -> anyhow::Result<()> {
    std::fs::File::open(dir)
        .and_then(|f| f.sync_all())
        .with_context(|| format!("cannot sync {}", dir.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    const REPORT: Owner = Owner::Holds("report.txt");

    #[test]
    fn outputs_appear_only_on_commit_and_replace_an_earlier_directory_whole() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("out");
        let s = Staged::new(&out, false, REPORT).unwrap();
        s.write("report.txt", "one").unwrap();
        s.write("stale.csv", "x").unwrap();
        assert!(!out.exists());
        s.commit().unwrap();
        assert_eq!(
            std::fs::read_to_string(out.join("report.txt")).unwrap(),
            "one"
        );
        // refused without --force
        let e = Staged::new(&out, false, REPORT).unwrap_err().to_string();
        assert!(e.contains("not empty") && e.contains("--force"), "{e}");
        // a failed second run (dropped before commit) leaves the first as it was
        {
            let s = Staged::new(&out, true, REPORT).unwrap();
            s.write("report.txt", "two").unwrap();
        }
        assert_eq!(
            std::fs::read_to_string(out.join("report.txt")).unwrap(),
            "one"
        );
        // a forced second run replaces it whole: no stale file survives
        let s = Staged::new(&out, true, REPORT).unwrap();
        s.write("report.txt", "two").unwrap();
        s.commit().unwrap();
        assert_eq!(
            std::fs::read_to_string(out.join("report.txt")).unwrap(),
            "two"
        );
        assert!(!out.join("stale.csv").exists());
        // nothing is left beside it
        let names: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().flatten().collect();
        assert_eq!(names.len(), 1, "{names:?}");
        // a directory of something else is never replaced
        let other = tmp.path().join("other");
        std::fs::create_dir(&other).unwrap();
        std::fs::write(other.join("thesis.tex"), "").unwrap();
        let e = Staged::new(&other, true, REPORT).unwrap_err().to_string();
        assert!(e.contains("holds no report.txt"), "{e}");
        let frames = Owner::OnlyFiles("frame_", ".png");
        std::fs::write(other.join("frame_1.png"), "").unwrap();
        assert!(!frames.owns(&other));
        std::fs::remove_file(other.join("thesis.tex")).unwrap();
        assert!(frames.owns(&other));
    }
}
