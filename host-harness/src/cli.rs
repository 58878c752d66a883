//! Command-line interface: parses arguments and dispatches to one module per subcommand.

use clap::{Parser, Subcommand};
use std::process::ExitCode;
// The study's commands and what every program does around its command, shared with the
// `vibcam-study` binary.
pub use vibcam_cli::process::{negative_values_joined, outputs_in, stdout};
pub use vibcam_cli::{merge, study};

pub mod analyze;
pub mod args;
pub mod calibrate;
pub mod centroid;
pub mod ema;
pub mod frf;
pub mod hammer;
pub mod modal;
pub mod pick;
pub mod plan;
pub mod render;
pub mod simulate;
pub mod track;
pub mod upsample;

/// Vision-based vibration and modal measurement: Monte Carlo studies of motion blur and
/// analysis of camera + accelerometer recordings, running the firmware-core code.
#[derive(Debug, Parser)]
#[command(name = "host-harness", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run a Monte Carlo study (grandstand or cantilever) and write summary, realizations,
    /// FRF bands, coverage intervals and plots.
    ///
    /// Outputs (docs/cli.md): amplitudes in mm/kN (grandstand) or (m/s^2)/(m/s^2)
    /// (cantilever), frequencies in Hz, exposures in ms; systems transducer, vision and
    /// vision_compensated.
    Study(study::Args),
    /// Combine the outputs of `study --shard K/N` runs into one study output.
    Merge(merge::Args),
    /// Centroid of the thresholded target in image files and camera recordings; CSV on
    /// stdout.
    Centroid(centroid::Args),
    /// H1 frequency response and coherence of two CSV columns (streaming Welch).
    Frf(frf::Args),
    /// Fourier upsampling of a CSV column from one rate to another.
    Upsample(upsample::Args),
    /// Analyse a real recording: image sequence + accelerometer CSV -> FRFs and modes.
    Analyze(Box<analyze::Args>),
    /// Follow targets through frames (chosen points, or the blobs of the first frame):
    /// displacement.csv, a report and a plot; no accelerometer needed.
    Track(Box<track::Args>),
    /// Output-only modal analysis (FDD, EFDD, SSI-cov) of a displacement file: frequencies,
    /// damping and shapes without an accelerometer.
    Modal(Box<modal::Args>),
    /// Experimental modal analysis with a measured force (impact hammer or shaker): FRFs of
    /// the responses (a camera's displacements or a DAQ's channels) over the force, LSCF poles
    /// with a stabilisation diagram, LSFD shapes.
    Ema(Box<ema::Args>),
    /// Write pick.html: a page of the recording's frames where a click adds a window, a
    /// drag moves it, and "save" downloads the points.csv `track --points` reads.
    Pick(pick::Args),
    /// Write a synthetic field record: displacements of a structure under ambient excitation
    /// and its true modes.
    SimulateField(simulate::Args),
    /// Write a synthetic impact hammer test: the force at a DAQ's rate, five points'
    /// displacements at a camera's rate, the true modes (to try `ema` on).
    SimulateHammer(hammer::Args),
    /// Write PNG frames of the simulated target, sharp and blurred.
    Render(render::Args),
    /// Plan the exposure before a test: per mode the amplitude loss, the longest exposure
    /// within a tolerance, the residual after compensation, the lost-frame risk.
    Plan(plan::Args),
    /// Fit a study's unreported imaging knobs (target, threshold, noise, blur) to observed
    /// figures: coarse grid then local search, every evaluation the same small study.
    Calibrate(calibrate::Args),
}

/// Runs the command line; the error is returned to `main` for the exit code.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Study(a) => study::run(a),
        Command::Merge(a) => merge::run(a),
        Command::Centroid(a) => centroid::run(a),
        Command::Frf(a) => frf::run(a),
        Command::Upsample(a) => upsample::run(a),
        Command::Analyze(a) => analyze::run(*a),
        Command::Track(a) => track::run(*a),
        Command::Modal(a) => modal::run(*a),
        Command::Ema(a) => ema::run(*a),
        Command::Pick(a) => pick::run(a),
        Command::SimulateField(a) => simulate::run(a),
        Command::SimulateHammer(a) => hammer::run(a),
        Command::Render(a) => render::run(a),
        Command::Plan(a) => plan::run(a),
        Command::Calibrate(a) => calibrate::run(a),
    }
}

/// The end of a job that writes an output directory: its report on standard output, where its
/// outputs are when it succeeded, and its result (a failure's report is printed too).
pub fn finish(
    outcome: crate::analysis::request::Outcome,
    out: &std::path::Path,
) -> anyhow::Result<()> {
    stdout(&outcome.report)?;
    if outcome.result.is_ok() {
        outputs_in(out)?;
    }
    outcome.result
}

/// Entry point used by `main.rs`: exit code 0 on success, 2 for bad input, 1 otherwise.
pub fn main() -> ExitCode {
    vibcam_cli::process::main::<Cli>("host-harness", run)
}
