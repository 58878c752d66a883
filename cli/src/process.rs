//! What every command-line program of the workspace does around its command: the command line
//! read (a negative number joined to its flag), the invocation stated in the reports, standard
//! output written and flushed with its errors named, the error printed in the user's spelling of
//! the settings, and the exit code (0 success, 2 bad input, 1 otherwise).

use clap::parser::ValueSource;
use std::process::ExitCode;
use vibcam_common::setting::{self, Naming};
use vibcam_report::provenance::{Invocation, Setting};

/// Writes `text` to standard output and flushes it: a standard output that cannot be written
/// (a full disk, a closed pipe) is an error naming it, never a panic. Every command prints
/// through this (or a writer whose errors it returns), never with `print!`.
pub fn stdout(text: &str) -> anyhow::Result<()> {
    use std::io::Write as _;
    let mut out = std::io::stdout().lock();
    // the settings the text names (`$nperseg`), spelled as this command line's flags
    let text = setting::spell(text, Naming::Cli);
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
/// argument quoted for a POSIX shell where needed, the program by its `program` name, not the
/// path it was started by) and every flag of the command (of its subcommand, when it has
/// subcommands) with its value, the ones not given marked as defaults.
fn invocation(
    program: &str,
    args: &[std::ffi::OsString],
    command: &clap::Command,
    matches: &clap::ArgMatches,
) -> Invocation {
    let mut words: Vec<String> = args.iter().map(|a| quoted(&a.to_string_lossy())).collect();
    if let Some(first) = words.first_mut() {
        *first = program.into();
    }
    let chosen = match matches.subcommand() {
        Some((name, m)) => command.find_subcommand(name).map(|c| (c, m)),
        None => Some((command, matches)),
    };
    let mut settings = Vec::new();
    if let Some((cmd, m)) = chosen {
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

/// The whole program `program` (its name as the reports state it): parses the command line
/// into `C`, runs `run` with the invocation known to the reports, and turns its result into the
/// exit code: 0 on success (a closed standard output too), 2 for bad input, 1 otherwise.
pub fn main<C: clap::Parser>(program: &str, run: fn(C) -> anyhow::Result<()>) -> ExitCode {
    let args = negative_values_joined(std::env::args_os());
    let command = C::command();
    let matches = command.clone().get_matches_from(args.clone());
    let cli = C::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    let stated = invocation(program, &args, &command, &matches);
    let result = vibcam_report::provenance::with_invocation(stated, || run(cli))
        .and_then(|()| std::io::Write::flush(&mut std::io::stdout()).map_err(stdout_error));
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            // the settings the message names, spelled as this command line's flags
            let message = setting::message(&e, Naming::Cli);
            eprintln!("error: {message}");
            if setting::is_bad_input(&e) {
                ExitCode::from(2)
            } else {
                ExitCode::FAILURE
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_negative_value_is_joined_to_its_flag_but_not_after_the_separator() {
        let os = |v: &[&str]| v.iter().map(std::ffi::OsString::from).collect::<Vec<_>>();
        assert_eq!(
            negative_values_joined(os(&["p", "--fps", "-60", "-v", "--", "--x", "-1"])),
            os(&["p", "--fps=-60", "-v", "--", "--x", "-1"])
        );
        assert_eq!(
            negative_values_joined(os(&["p", "--a=1", "-2"])),
            os(&["p", "--a=1", "-2"])
        );
    }

    #[test]
    fn words_the_shell_reads_back() {
        assert_eq!(quoted("out/a-1.csv"), "out/a-1.csv");
        assert_eq!(quoted("a b"), "'a b'");
        assert_eq!(quoted("it's"), "'it'\\''s'");
        assert_eq!(quoted(""), "''");
    }
}
