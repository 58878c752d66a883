//! `vibcam-study`: the Monte Carlo study of `host-harness study`, as a program of its own.

use std::process::ExitCode;

/// A Monte Carlo study of the motion blur (grandstand or cantilever): the same arguments and
/// outputs as `host-harness study` (docs/cli.md).
#[derive(Debug, clap::Parser)]
#[command(name = "vibcam-study", version)]
struct Cli {
    #[command(flatten)]
    args: vibcam_cli::study::Args,
}

fn main() -> ExitCode {
    vibcam_cli::process::main::<Cli>("vibcam-study", |cli| vibcam_cli::study::run(cli.args))
}
