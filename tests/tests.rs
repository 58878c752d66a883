//! Workspace-level end-to-end tests: one test binary with a module per area, driving the
//! `host-harness` binary and both crates together.

#[allow(dead_code)]
mod util;

mod analyze;
mod centroid;
mod signal;
mod study;

#[test]
fn help_lists_every_subcommand() {
    let out = util::harness(&["--help"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for cmd in [
        "study", "merge", "centroid", "frf", "upsample", "analyze", "render",
    ] {
        assert!(text.contains(cmd), "--help does not mention `{cmd}`");
    }
}
