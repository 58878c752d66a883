//! Output directories that are complete or absent: a command writes every output file into a
//! hidden staging directory beside the target (`.NAME.partial-PID`, the same file system),
//! syncs them, and only then moves the whole directory into place. A failure or a kill before
//! that leaves the target as it was; a directory of a previous run is replaced as a whole, so no
//! stale file of it survives beside the new ones.
//!
//! What may be replaced is decided by a **manifest**: every committed output directory holds
//! [`MANIFEST`], naming the command that wrote it and every file and folder it wrote. An
//! existing non-empty target is refused without `--force`; with it, it is replaced only when its
//! manifest names this command and every entry in it is listed there (nothing was added by
//! hand), and when none of the run's inputs lies inside it. A run that fails
//! ([`Staged::commit_unless_replacing`]) never replaces anything.
//!
//! A staging directory is locked (`flock`) by the process writing it and holds [`STAGE_MARKER`],
//! written before anything else. The next run into the same target looks only at the staging
//! directories holding that marker and the set-aside ones holding a manifest of ours, whose lock
//! is free (their writer is gone, whoever it was): a folder that merely has such a name is never
//! touched. A writer killed between its two renames leaves the target absent, the earlier output
//! set aside and the new one complete in its stage: the next run puts the newest complete output
//! back in place (the staged one when it holds its manifest, otherwise the set-aside one) before
//! it removes the rest.

use anyhow::Context as _;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use vibcam_readers::bad_input;

/// The manifest file of an output directory (hidden, TOML).
pub const MANIFEST: &str = ".vibcam-manifest.toml";

/// The file a staging directory holds from its creation on: what marks it as this program's.
pub const STAGE_MARKER: &str = ".vibcam-stage";

/// What a manifest records: the command and every entry it wrote, relative paths with `/`,
/// folders with a trailing `/`.
#[derive(Debug, Serialize, Deserialize, PartialEq)]
struct Manifest {
    /// The command that wrote the directory, e.g. `analyze`.
    command: String,
    /// Every file and folder written (not the manifest itself).
    entries: Vec<String>,
}

/// A staged output directory; see the module documentation.
#[derive(Debug)]
pub struct Staged {
    target: PathBuf,
    stage: PathBuf,
    command: &'static str,
    /// The run's inputs, as given.
    inputs: Vec<PathBuf>,
    replace: bool,
    committed: bool,
    /// The lock on the staging directory, held while the value lives.
    _lock: std::fs::File,
}

impl Staged {
    /// Starts staging the outputs of `command` into `target`; `force` allows replacing an
    /// earlier output directory of the same command (see the module documentation). `inputs`
    /// are the files and folders the run reads: a target that holds one is never replaced.
    pub fn new(
        target: &Path,
        force: bool,
        command: &'static str,
        inputs: &[&Path],
    ) -> anyhow::Result<Staged> {
        let name = target
            .file_name()
            .and_then(|n| n.to_str())
            .filter(|n| *n != "." && *n != "..")
            .ok_or_else(|| {
                vibcam_readers::bad_input(format!(
                    "{}: an output directory needs a name (not . or ..)",
                    target.display()
                ))
            })?;
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        recover_and_remove_stale_stages(&parent, name, target);
        let replace = check_target(target, force, command, inputs)?;
        std::fs::create_dir_all(&parent)
            .with_context(|| format!("cannot create {}", parent.display()))?;
        let stage = parent.join(format!(".{name}.partial-{}", std::process::id()));
        if stage.exists() {
            std::fs::remove_dir_all(&stage)
                .with_context(|| format!("cannot remove {}", stage.display()))?;
        }
        std::fs::create_dir(&stage)
            .with_context(|| format!("cannot create {}", stage.display()))?;
        let lock = std::fs::File::open(&stage)
            .with_context(|| format!("cannot open {}", stage.display()))?;
        // a fresh directory of this process: nobody else can hold its lock
        lock.try_lock()
            .with_context(|| format!("cannot lock {}", stage.display()))?;
        std::fs::write(stage.join(STAGE_MARKER), "a staging directory of vibcam\n")
            .with_context(|| format!("cannot write in {}", stage.display()))?;
        Ok(Staged {
            target: target.to_path_buf(),
            stage,
            command,
            inputs: inputs.iter().map(|p| p.to_path_buf()).collect(),
            replace,
            committed: false,
            _lock: lock,
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

    /// The run's inputs as given to [`Staged::new`] (for the report's provenance).
    pub fn inputs(&self) -> &[PathBuf] {
        &self.inputs
    }

    /// Whether committing would replace an earlier output directory.
    pub fn replaces(&self) -> bool {
        self.replace && self.target.exists()
    }

    /// Writes `bytes` to the staged file `name`; returns the path it will have in the target.
    pub fn write(&self, name: &str, bytes: impl AsRef<[u8]>) -> anyhow::Result<PathBuf> {
        let p = self.stage.join(name);
        std::fs::write(&p, bytes)
            .with_context(|| format!("cannot write {}", self.target.join(name).display()))?;
        Ok(self.target.join(name))
    }

    /// The outputs of a run that failed: committed into an absent or empty target (so its
    /// report can be read), but never in place of an earlier output directory, which is left as
    /// it was. Returns whether they were committed.
    pub fn commit_unless_replacing(self) -> anyhow::Result<bool> {
        if self.replaces() {
            return Ok(false);
        }
        self.commit().map(|()| true)
    }

    /// Writes the manifest, syncs every staged file and moves the directory into place
    /// (replacing a previous output directory as a whole when allowed), then syncs the parent
    /// directory.
    pub fn commit(mut self) -> anyhow::Result<()> {
        let mut entries = Vec::new();
        list_entries(&self.stage, "", &mut entries)?;
        let manifest = Manifest {
            command: self.command.to_string(),
            entries,
        };
        let text = toml::to_string(&manifest).context("cannot write the manifest")?;
        self.write(MANIFEST, text)?;
        sync_tree(&self.stage)?;
        // the stage holds its manifest: from here on it is a complete output (what a recovery
        // puts back in place if this writer dies before its renames are done)
        vibcam_common::failpoint::hit("outdir-synced");
        let parent = self.stage.parent().unwrap_or(Path::new(".")).to_path_buf();
        if self.replaces() {
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
            vibcam_common::failpoint::hit("outdir-old-moved");
            std::fs::rename(&self.stage, &self.target)
                .with_context(|| format!("cannot move the outputs to {}", self.target.display()))?;
            self.committed = true;
            // the new outputs are in place: a set-aside directory that cannot be removed (files
            // of another user) is left for the next run to clean, with a warning, not an error
            if let Err(e) = std::fs::remove_dir_all(&old) {
                eprintln!(
                    "warning: the earlier output was replaced, but its old copy {} could not be \
                     removed ({e}); remove it by hand",
                    old.display()
                );
            }
        } else {
            if self.target.exists() {
                // an empty directory (checked in `new`): make room for the rename
                std::fs::remove_dir(&self.target)
                    .with_context(|| format!("cannot replace {}", self.target.display()))?;
            }
            std::fs::rename(&self.stage, &self.target)
                .with_context(|| format!("cannot move the outputs to {}", self.target.display()))?;
            self.committed = true;
        }
        // the marker served the stage; a kill before this line leaves it, ignored, in place
        std::fs::remove_file(self.target.join(STAGE_MARKER)).ok();
        sync_dir(&parent)
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.committed {
            // best effort: a directory that cannot be removed is cleaned by the next run
            std::fs::remove_dir_all(&self.stage).ok();
        }
    }
}

/// Every entry below `dir` (relative to it, prefixed by `prefix`), folders with a trailing `/`,
/// sorted; the manifest itself is not listed.
fn list_entries(dir: &Path, prefix: &str, out: &mut Vec<String>) -> anyhow::Result<()> {
    let mut names: Vec<(String, bool)> = Vec::new();
    for e in std::fs::read_dir(dir).with_context(|| format!("cannot read {}", dir.display()))? {
        let e = e.with_context(|| format!("cannot read {}", dir.display()))?;
        let name = e.file_name().to_string_lossy().into_owned();
        let is_dir = e.file_type().is_ok_and(|t| t.is_dir());
        names.push((name, is_dir));
    }
    names.sort();
    for (name, is_dir) in names {
        if prefix.is_empty() && (name == MANIFEST || name == STAGE_MARKER) {
            continue;
        }
        if is_dir {
            let rel = format!("{prefix}{name}/");
            out.push(rel.clone());
            list_entries(&dir.join(&name), &rel, out)?;
        } else {
            out.push(format!("{prefix}{name}"));
        }
    }
    Ok(())
}

/// Whether `target` may be written: absent or empty (returns false), or with `force` an
/// earlier output directory of `command` holding nothing else and no input (returns true).
fn check_target(
    target: &Path,
    force: bool,
    command: &str,
    inputs: &[&Path],
) -> anyhow::Result<bool> {
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
            "{}: not empty; choose another $out, or $force to replace an earlier output \
             directory of this command as a whole",
            target.display()
        )));
    }
    if let Some(input) = input_inside(target, inputs) {
        return Err(bad_input(format!(
            "{}: holds {}, an input of this run: not replaced even with $force; choose \
             another $out",
            target.display(),
            input.display()
        )));
    }
    let refuse = |why: String| {
        bad_input(format!(
            "{}: {why}, so it is not only an earlier output of `{command}`: not replaced even \
             with $force; choose another $out",
            target.display()
        ))
    };
    let manifest_path = target.join(MANIFEST);
    let text = match std::fs::read_to_string(&manifest_path) {
        Ok(t) => t,
        Err(_) => return Err(refuse(format!("has no {MANIFEST}"))),
    };
    let manifest: Manifest = toml::from_str(&text)
        .map_err(|_| refuse(format!("its {MANIFEST} is not one this program wrote")))?;
    if manifest.command != command {
        return Err(refuse(format!("was written by `{}`", manifest.command)));
    }
    let mut found = Vec::new();
    list_entries(target, "", &mut found)?;
    let listed: std::collections::HashSet<&str> =
        manifest.entries.iter().map(String::as_str).collect();
    if let Some(extra) = found.iter().find(|e| !listed.contains(e.as_str())) {
        return Err(refuse(format!(
            "holds {extra}, which that command did not write"
        )));
    }
    Ok(true)
}

/// The canonical path of an input; a pattern (`rec/frame_*.png`) by its folder's.
fn canonical_input(p: &Path) -> Option<PathBuf> {
    let p = if p.exists() {
        p.to_path_buf()
    } else {
        p.parent().map(Path::to_path_buf).unwrap_or_default()
    };
    std::fs::canonicalize(p).ok()
}

/// The first of `inputs` that lies inside `dir` (or is `dir`), by their canonical paths.
pub fn input_inside<'a>(dir: &Path, inputs: &[&'a Path]) -> Option<&'a Path> {
    let dir = std::fs::canonicalize(dir).ok()?;
    inputs
        .iter()
        .copied()
        .find(|p| canonical_input(p).is_some_and(|c| c.starts_with(&dir)))
}

/// Refuses an output file that is one of the run's inputs (the same file, by any name) or lies
/// inside an input folder (a folder of frames, or a pattern's folder).
pub fn refuse_output_file_among_inputs(out: &Path, inputs: &[&Path]) -> anyhow::Result<()> {
    refuse_overwriting_input(out, inputs)?;
    let folder = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let folders: Vec<&Path> = inputs
        .iter()
        .copied()
        .filter(|p| p.is_dir() || !p.exists())
        .collect();
    if let Some(input) = input_folder_holding(folder, &folders) {
        return Err(bad_input(format!(
            "$out {}: lies inside {}, an input of this run; the command never writes among \
             its inputs, choose another $out",
            out.display(),
            input.display()
        )));
    }
    Ok(())
}

/// The first of `inputs` (folders, or patterns checked by their folder) that holds `dir`.
fn input_folder_holding<'a>(dir: &Path, inputs: &[&'a Path]) -> Option<&'a Path> {
    let dir = std::fs::canonicalize(dir).ok()?;
    inputs
        .iter()
        .copied()
        .find(|p| canonical_input(p).is_some_and(|c| dir.starts_with(c)))
}

/// Refuses an output file that is one of the run's inputs (the same file, by any name).
pub fn refuse_overwriting_input(out: &Path, inputs: &[&Path]) -> anyhow::Result<()> {
    use std::os::unix::fs::MetadataExt as _;
    let Ok(o) = std::fs::metadata(out) else {
        return Ok(());
    };
    for input in inputs {
        if let Ok(i) = std::fs::metadata(input) {
            if (i.dev(), i.ino()) == (o.dev(), o.ino()) {
                return Err(bad_input(format!(
                    "$out {}: is the input {}; the command never writes over one of its \
                     inputs, choose another $out",
                    out.display(),
                    input.display()
                )));
            }
        }
    }
    Ok(())
}

/// What a directory left beside the target is, when this program made it.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Leftover {
    /// A staging directory (holds [`STAGE_MARKER`]); `complete` when it holds its manifest too.
    Stage { complete: bool },
    /// An earlier output set aside by a commit (holds a manifest this program wrote).
    SetAside,
}

fn is_our_manifest(dir: &Path) -> bool {
    std::fs::read_to_string(dir.join(MANIFEST))
        .ok()
        .and_then(|t| toml::from_str::<Manifest>(&t).ok())
        .is_some()
}

/// The leftovers of `name` whose writer is gone (their lock is free: a live writer holds it),
/// with what they are and their modification time; folders of that name without our marker are
/// not listed.
fn stale_leftovers(parent: &Path, name: &str) -> Vec<(PathBuf, Leftover, std::time::SystemTime)> {
    let Ok(entries) = std::fs::read_dir(parent) else {
        return Vec::new();
    };
    let (partial, old) = (format!(".{name}.partial-"), format!(".{name}.old-"));
    let mut out = Vec::new();
    for e in entries.flatten() {
        let file = e.file_name();
        let Some(f) = file.to_str() else { continue };
        let path = e.path();
        let kind = if f.starts_with(partial.as_str()) && path.join(STAGE_MARKER).is_file() {
            Leftover::Stage {
                complete: is_our_manifest(&path),
            }
        } else if f.starts_with(old.as_str()) && is_our_manifest(&path) {
            Leftover::SetAside
        } else {
            continue;
        };
        let Ok(dir) = std::fs::File::open(&path) else {
            continue;
        };
        if dir.try_lock().is_err() {
            continue;
        }
        // the lock is released when `dir` closes; a writer that starts now makes a stage of
        // its own pid, never one of these
        let modified = std::fs::metadata(&path)
            .and_then(|m| m.modified())
            .unwrap_or(std::time::UNIX_EPOCH);
        out.push((path, kind, modified));
    }
    out
}

/// Puts the newest complete output of a writer that died between its renames back in place
/// when `target` is absent (a complete stage before a set-aside earlier output), then removes
/// the other leftovers of dead writers. What cannot be moved or removed is left as it is.
fn recover_and_remove_stale_stages(parent: &Path, name: &str, target: &Path) {
    let mut left = stale_leftovers(parent, name);
    if !target.exists() {
        let rank = |k: &Leftover| match k {
            Leftover::Stage { complete: true } => 2,
            Leftover::SetAside => 1,
            Leftover::Stage { complete: false } => 0,
        };
        let best = left
            .iter()
            .enumerate()
            .filter(|(_, (_, k, _))| rank(k) > 0)
            .max_by_key(|(_, (_, k, t))| (rank(k), *t))
            .map(|(i, _)| i);
        if let Some(i) = best {
            let (path, kind, _) = left.remove(i);
            if std::fs::rename(&path, target).is_ok() {
                std::fs::remove_file(target.join(STAGE_MARKER)).ok();
                let what = match kind {
                    Leftover::SetAside => "the earlier output it had set aside",
                    _ => "its complete new output",
                };
                eprintln!(
                    "note: a run into {} was stopped before it finished replacing its output: \
                     {what} was put back in place",
                    target.display()
                );
            }
        }
    }
    for (path, _, _) in left {
        std::fs::remove_dir_all(path).ok();
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

    const CMD: &str = "analyze";

    #[test]
    fn outputs_appear_only_on_commit_and_replace_an_earlier_directory_whole() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("out");
        let s = Staged::new(&out, false, CMD, &[]).unwrap();
        s.write("report.txt", "one").unwrap();
        s.write("stale.csv", "x").unwrap();
        assert!(!out.exists());
        s.commit().unwrap();
        assert_eq!(
            std::fs::read_to_string(out.join("report.txt")).unwrap(),
            "one"
        );
        // refused without --force
        let e = Staged::new(&out, false, CMD, &[]).unwrap_err().to_string();
        assert!(e.contains("not empty") && e.contains("$force"), "{e}");
        // a failed second run (dropped before commit) leaves the first as it was
        {
            let s = Staged::new(&out, true, CMD, &[]).unwrap();
            s.write("report.txt", "two").unwrap();
        }
        assert_eq!(
            std::fs::read_to_string(out.join("report.txt")).unwrap(),
            "one"
        );
        // so does a failed run that got as far as its report
        let s = Staged::new(&out, true, CMD, &[]).unwrap();
        s.write("report.txt", "failed").unwrap();
        assert!(!s.commit_unless_replacing().unwrap());
        assert_eq!(
            std::fs::read_to_string(out.join("report.txt")).unwrap(),
            "one"
        );
        // a forced second run replaces it whole: no stale file survives
        let s = Staged::new(&out, true, CMD, &[]).unwrap();
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
    }

    #[test]
    fn force_replaces_only_what_the_manifest_of_the_same_command_lists() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("out");
        let s = Staged::new(&out, false, CMD, &[]).unwrap();
        s.write("report.txt", "one").unwrap();
        std::fs::create_dir(s.dir().join("frames")).unwrap();
        s.write("frames/f1.png", "p").unwrap();
        s.commit().unwrap();
        // a file added by hand, in the folder or in a sub-folder: refused, named
        for extra in ["notes.txt", "frames/mine.png"] {
            std::fs::write(out.join(extra), "mine").unwrap();
            let e = Staged::new(&out, true, CMD, &[]).unwrap_err().to_string();
            assert!(e.contains(extra) && e.contains("not replaced"), "{e}");
            std::fs::remove_file(out.join(extra)).unwrap();
        }
        // another command's output
        let e = Staged::new(&out, true, "render", &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("written by `analyze`"), "{e}");
        // a directory holding an input of the run
        let input = out.join("frames/f1.png");
        let e = Staged::new(&out, true, CMD, &[&input])
            .unwrap_err()
            .to_string();
        assert!(e.contains("an input of this run"), "{e}");
        // one marker file is not a manifest: a folder with a report.txt is someone's
        let lab = tmp.path().join("lab");
        std::fs::create_dir(&lab).unwrap();
        std::fs::write(lab.join("report.txt"), "notes").unwrap();
        let e = Staged::new(&lab, true, CMD, &[]).unwrap_err().to_string();
        assert!(e.contains(MANIFEST), "{e}");
        assert!(lab.join("report.txt").exists());
        // the untouched output is still replaceable
        Staged::new(&out, true, CMD, &[]).unwrap().commit().unwrap();
        assert!(!out.join("report.txt").exists());
    }

    #[test]
    fn leftovers_of_a_killed_writer_are_removed_but_a_live_ones_are_not() {
        let tmp = tempfile::tempdir().unwrap();
        // an earlier output, so that the set-aside one below is not recovered
        Staged::new(&tmp.path().join("out"), false, CMD, &[])
            .unwrap()
            .commit()
            .unwrap();
        // a pid that is alive (init's) but no lock: a killed writer whose pid was reused
        let dead = tmp.path().join(".out.partial-1");
        let old = tmp.path().join(".out.old-1");
        let live = tmp.path().join(".out.partial-999999999");
        for d in [&dead, &old, &live] {
            std::fs::create_dir(d).unwrap();
            std::fs::write(d.join(STAGE_MARKER), "").unwrap();
        }
        std::fs::write(old.join(MANIFEST), "command = \"analyze\"\nentries = []\n").unwrap();
        let holder = std::fs::File::open(&live).unwrap();
        holder.lock().unwrap();
        let s = Staged::new(&tmp.path().join("out"), true, CMD, &[]).unwrap();
        assert!(!old.exists() && !dead.exists());
        assert!(live.exists(), "a live writer's stage was removed");
        s.commit().unwrap();
        assert!(live.exists());
        assert!(!tmp.path().join("out").join(STAGE_MARKER).exists());
    }

    #[test]
    fn folders_that_only_bear_a_stage_name_are_never_removed() {
        let tmp = tempfile::tempdir().unwrap();
        for name in [".res.old-2023", ".res.partial-7"] {
            let d = tmp.path().join(name);
            std::fs::create_dir(&d).unwrap();
            std::fs::write(d.join("n.txt"), "notes").unwrap();
        }
        Staged::new(&tmp.path().join("res"), false, CMD, &[])
            .unwrap()
            .commit()
            .unwrap();
        for name in [".res.old-2023", ".res.partial-7"] {
            assert_eq!(
                std::fs::read_to_string(tmp.path().join(name).join("n.txt")).unwrap(),
                "notes"
            );
        }
    }

    #[test]
    fn a_kill_between_the_renames_keeps_the_newest_complete_output() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("e");
        let s = Staged::new(&out, false, CMD, &[]).unwrap();
        s.write("report.txt", "old").unwrap();
        s.commit().unwrap();
        // what a writer killed between its renames leaves: the old output set aside, the new
        // one complete (manifest written) in its stage, the target absent
        let old = tmp.path().join(".e.old-1");
        std::fs::rename(&out, &old).unwrap();
        let stage = tmp.path().join(".e.partial-1");
        std::fs::create_dir(&stage).unwrap();
        std::fs::write(stage.join(STAGE_MARKER), "").unwrap();
        std::fs::write(stage.join("report.txt"), "new").unwrap();
        std::fs::write(
            stage.join(MANIFEST),
            "command = \"analyze\"\nentries = [\"report.txt\"]\n",
        )
        .unwrap();
        // the next run (refused without --force) finds the new output in place, nothing lost
        let e = Staged::new(&out, false, CMD, &[]).unwrap_err().to_string();
        assert!(e.contains("not empty"), "{e}");
        assert_eq!(
            std::fs::read_to_string(out.join("report.txt")).unwrap(),
            "new"
        );
        assert!(!out.join(STAGE_MARKER).exists());
        // only the set-aside one: it comes back
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("e");
        let s = Staged::new(&out, false, CMD, &[]).unwrap();
        s.write("report.txt", "old").unwrap();
        s.commit().unwrap();
        std::fs::rename(&out, tmp.path().join(".e.old-1")).unwrap();
        let s = Staged::new(&out, true, CMD, &[]).unwrap();
        assert!(s.replaces());
        drop(s);
        assert_eq!(
            std::fs::read_to_string(out.join("report.txt")).unwrap(),
            "old"
        );
    }

    #[test]
    fn an_output_file_that_is_an_input_is_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let a = tmp.path().join("a.csv");
        std::fs::write(&a, "x\n1\n").unwrap();
        let same = tmp.path().join(".").join("a.csv");
        let e = refuse_overwriting_input(&same, &[&a])
            .unwrap_err()
            .to_string();
        assert!(e.contains("is the input"), "{e}");
        refuse_overwriting_input(&tmp.path().join("b.csv"), &[&a]).unwrap();
    }
}
