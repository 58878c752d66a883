//! # vibcam-cli
//!
//! The command line's common ground, below `host-harness`'s own command line: what every
//! program does around its command ([`process`]: standard output, the invocation the reports
//! state, the error in the user's spelling, the exit code), the flags checked against the
//! settings table ([`flags`]), and the Monte Carlo study's two commands ([`study`], [`merge`]).
//!
//! Its binary, `vibcam-study`, is `host-harness study` on its own: the same arguments and the
//! same code, compiled without the analysis crates (tracking, identification) the study does not
//! use, so that the README's main job builds in less time from a fresh clone
//! (`docs/performance.md`, "What the main job compiles").
//!
//! | module | what |
//! |---|---|
//! | [`flags`] | help, default and range of a flag from its row of the settings table; rates, coverage, choices |
//! | [`process`] | standard output, `--flag -1`, the invocation, the error message and the exit code |
//! | [`study`] | `study`: the configuration from preset, file and flags; the output directory; the run |
//! | [`merge`] | `merge`: the directories of a sharded study combined |

pub mod flags;
pub mod merge;
pub mod process;
pub mod study;
