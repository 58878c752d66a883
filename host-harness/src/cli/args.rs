//! Argument types shared by several subcommands, so that a flag spelled the same way parses,
//! and is described in `--help`, the same way everywhere.
//!
//! `--window` is not shared: `frf` and `analyze` describe its `rect` value differently in their
//! help, and that text is part of the command-line interface.

/// Segment detrending (`--detrend` of `frf` and `analyze`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum DetrendArg {
    /// Subtract each segment's mean.
    Constant,
    /// No detrending.
    None,
}
