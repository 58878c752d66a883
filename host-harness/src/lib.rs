//! # host-harness
//!
//! The `std` side of the toolkit: Monte Carlo studies that simulate the whole vision-based
//! vibration measurement (structure, excitation, transducers, camera image formation with
//! motion blur) and push the simulated frames and signals **through `firmware-core` itself**,
//! plus command-line tools that run the same firmware code on real recordings.
//!
//! Physics is kept apart from plumbing:
//!
//! | module | what |
//! |---|---|
//! | [`study`] | Monte Carlo runner: seeds, parallelism, checkpoints, shards; its scenarios ([`study::grandstand`]: structure, excitation, transducers; [`study::cantilever`]) and the EPSA camera ([`study::render`]) |
//! | [`fastpath`] | the binary centroid of EPSA frames without rendering them (identity effects) |
//! | [`stats`] | means, standard deviations, percentiles, histograms |
//! | [`report`] | CSV rows and the printed table (pure writers) |
//! | [`plots`] | PNG and SVG figures of study results |
//! | [`csvio`] | reading numeric CSV columns with errors naming row and column |
//! | [`recording`] | synthetic recordings (frames + accelerometer CSV) for `analyze` |
//! | [`analysis`] | the rig chain on real recordings (centroid, upsampling, H1, modes) |
//! | [`cli`] | argument parsing and the subcommands |

pub mod analysis;
pub mod cli;
pub mod csvio;
pub mod fastpath;
pub mod plots;
pub mod recording;
pub mod report;
pub mod stats;
pub mod study;

/// An error caused by the user's input (a file, a field, a flag value). The binary exits with
/// code 2 when the error chain contains one; other failures exit with 1.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct BadInput(pub String);

/// Shorthand to build an [`anyhow::Error`] carrying [`BadInput`].
pub fn bad_input(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(BadInput(msg.into()))
}
