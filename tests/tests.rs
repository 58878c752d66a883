//! Workspace-level end-to-end tests: one test binary with a module per area, driving the
//! `host-harness` binary and both crates together.

#[allow(dead_code)]
mod util;

mod adversarial;
mod analyze;
mod centroid;
mod plan;
mod robustness;
mod signal;
mod study;
mod targets;

#[test]
fn help_lists_every_subcommand() {
    let out = util::harness(&["--help"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    // the first word of each line of the "Commands:" section, so that a word in a description
    // cannot stand in for a missing subcommand
    let listed: Vec<&str> = text
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    for cmd in [
        "study", "merge", "centroid", "frf", "upsample", "analyze", "render", "plan",
    ] {
        assert!(
            listed.contains(&cmd),
            "--help lists {listed:?}, not `{cmd}`"
        );
    }
}
