//! The source's commit for the reports' header (`VIBCAM_COMMIT`, read by `provenance::COMMIT`):
//! `git rev-parse HEAD` when the build has a git checkout (nothing from a source package).
//! Rebuilt when HEAD or the branch it names moves, not on every edit: whether the work tree had
//! changes is not stated, since it would go stale between commits.

use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let Some(dir) = git(&["rev-parse", "--absolute-git-dir"]) else {
        return;
    };
    for f in ["HEAD", "packed-refs"] {
        println!("cargo:rerun-if-changed={dir}/{f}");
    }
    if let Some(r) = git(&["symbolic-ref", "-q", "HEAD"]) {
        println!("cargo:rerun-if-changed={dir}/{r}");
    }
    if let Some(head) = git(&["rev-parse", "HEAD"]) {
        println!("cargo:rustc-env=VIBCAM_COMMIT={head}");
    }
}
