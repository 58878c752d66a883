//! Helpers shared by the end-to-end tests.

use std::process::{Command, Output};

/// Runs the `host-harness` binary built for this test run with `args`.
pub fn harness(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_host-harness"))
        .args(args)
        .output()
        .expect("host-harness runs")
}
