//! Command-line interface: parses arguments and dispatches to one module per subcommand.

use clap::{Parser, Subcommand};
use std::process::ExitCode;
use vibcam_report::provenance::{Invocation, Setting};

pub mod analyze;
pub mod args;
pub mod calibrate;
pub mod centroid;
pub mod ema;
pub mod frf;
pub mod hammer;
pub mod merge;
pub mod modal;
pub mod pick;
pub mod plan;
pub mod render;
pub mod simulate;
pub mod study;
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

/// Writes `text` to standard output and flushes it: a standard output that cannot be written
/// (a full disk, a closed pipe) is an error naming it, never a panic. Every command prints
/// through this (or a writer whose errors it returns), never with `print!`.
pub fn stdout(text: &str) -> anyhow::Result<()> {
    use std::io::Write as _;
    let mut out = std::io::stdout().lock();
    // the settings the text names (`$nperseg`), spelled as this command line's flags
    let text = crate::setting::spell(text, crate::setting::Naming::Cli);
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(stdout_error)
}

/// The last line of a command that writes an output directory: where its outputs are (a
/// default `--out` such as `./analysis` is otherwise found only by looking). On standard error,
/// beside the progress: standard output stays the report.
pub fn outputs_in(dir: &std::path::Path) -> anyhow::Result<()> {
    let shown = match std::env::current_dir() {
        Ok(here) if dir.is_relative() => here.join(dir),
        _ => dir.to_path_buf(),
    };
    eprintln!("outputs in {}", shown.display());
    Ok(())
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

/// A failed write to standard output, named as such, the `io::Error` kept as its source (a
/// closed pipe is recognised by [`main`]).
fn stdout_error(e: std::io::Error) -> anyhow::Error {
    anyhow::Error::new(e).context("cannot write to standard output")
}

/// Whether `e` is a write into a closed pipe (`host-harness ... | head`): the reader has what it
/// wanted, so the command ends quietly with success, as ripgrep does.
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// The arguments with a negative number after a long flag joined to it (`--fps -60` ->
/// `--fps=-60`), so that the flag's own check refuses it by its range, rather than the parser
/// taking `-60` for short flags ("unexpected argument '-6'"). Nothing after `--` is touched.
pub fn negative_values_joined(
    args: impl IntoIterator<Item = std::ffi::OsString>,
) -> Vec<std::ffi::OsString> {
    let mut out: Vec<std::ffi::OsString> = Vec::new();
    let mut rest = false;
    for a in args {
        let text = a.to_str().unwrap_or("");
        let negative = text.starts_with('-') && text.parse::<f64>().is_ok();
        let flag = out
            .last()
            .and_then(|l| l.to_str())
            .filter(|l| l.starts_with("--") && l.len() > 2 && !l.contains('='));
        match flag {
            Some(f) if negative && !rest => {
                let joined = format!("{f}={text}");
                if let Some(last) = out.last_mut() {
                    *last = joined.into();
                }
            }
            _ => {
                rest |= text == "--";
                out.push(a);
            }
        }
    }
    out
}

/// How the command was asked for, for the reports' header: the command line as typed (each
/// argument quoted for a POSIX shell where needed) and every flag of the subcommand with its
/// value, the ones not given marked as defaults.
fn invocation(args: &[std::ffi::OsString], matches: &clap::ArgMatches) -> Invocation {
    use clap::parser::ValueSource;
    use clap::CommandFactory as _;
    let mut words: Vec<String> = args.iter().map(|a| quoted(&a.to_string_lossy())).collect();
    if let Some(first) = words.first_mut() {
        // the program as its name, not the path it was started by
        *first = "host-harness".into();
    }
    let mut settings = Vec::new();
    let command = Cli::command();
    let sub = matches
        .subcommand()
        .and_then(|(name, m)| Some((command.find_subcommand(name)?, m)));
    if let Some((cmd, m)) = sub {
        for arg in cmd.get_arguments() {
            let id = arg.get_id().as_str();
            if matches!(id, "help" | "version") {
                continue;
            }
            let name = arg.get_long().map_or(id.to_string(), |l| format!("--{l}"));
            let value = match m.try_get_raw(id) {
                Ok(Some(v)) => v
                    .map(|x| x.to_string_lossy().into_owned())
                    .collect::<Vec<_>>()
                    .join(" "),
                _ => "(none)".into(),
            };
            let default = m.value_source(id) != Some(ValueSource::CommandLine);
            settings.push(Setting {
                name,
                value,
                default,
            });
        }
    }
    Invocation {
        command: words.join(" "),
        settings,
    }
}

/// `word` as a POSIX shell reads it back: as it is when it holds only characters the shell
/// takes literally, else in single quotes (a `'` inside as `'\''`).
fn quoted(word: &str) -> String {
    let plain = !word.is_empty()
        && word
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-./=:,+@%".contains(c));
    match plain {
        true => word.to_string(),
        false => format!("'{}'", word.replace('\'', "'\\''")),
    }
}

/// Entry point used by `main.rs`: exit code 0 on success, 2 for bad input, 1 otherwise.
pub fn main() -> ExitCode {
    use clap::{CommandFactory as _, FromArgMatches as _};
    let args = negative_values_joined(std::env::args_os());
    let matches = Cli::command().get_matches_from(args.clone());
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    let stated = invocation(&args, &matches);
    let result = vibcam_report::provenance::with_invocation(stated, || run(cli))
        .and_then(|()| std::io::Write::flush(&mut std::io::stdout()).map_err(stdout_error));
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            // the settings the message names, spelled as this command line's flags
            let message = crate::setting::message(&e, crate::setting::Naming::Cli);
            eprintln!("error: {message}");
            if crate::setting::is_bad_input(&e) {
                ExitCode::from(2)
            } else {
                ExitCode::FAILURE
            }
        }
    }
}
