//! # host-harness
//!
//! The `std` side of the toolkit: Monte Carlo studies that simulate the whole vision-based
//! vibration measurement and push the simulated frames and signals **through `firmware-core`
//! itself**, the analysis of real recordings with the same firmware code, and the `host-harness`
//! command line. The method is described in `docs/method.md`, the command line in `docs/cli.md`,
//! and the way data flows through these modules in `ARCHITECTURE.md`.
//!
//! Modules, in the order data flows:
//!
//! | module | what |
//! |---|---|
//! | [`model`] | the rigs: modal parameters and their PDFs, excitation, exact response, transducer noise, closed-form FRFs (one module per rig) |
//! | [`imaging`] | the camera: targets, the EPSA renderer (and its fast binary-centroid path), image-formation effects, the `Camera` that ends in firmware-core's centroid, the exposure transfer of the centroid (compensation tables) |
//! | [`chain`] | the host side of firmware-core: frames -> displacement (lost frames), two channels -> H1 -> peaks, upsampling to acceleration |
//! | [`study`] | Monte Carlo studies: configuration, scenarios, runner (seeds, threads, shards), checkpoint, aggregation, merge |
//! | [`recording`] | synthetic recordings (frames + transducer CSV) written from a model through the camera |
//! | [`analysis`] | real recordings: frame loading, alignment, the chain, modes, reports |
//! | [`jobs`] | one checked job per command (`track`, `analyze`, `modal`, `ema`): what the CLI and Python translate into |
//! | [`setting`] | errors naming the user's settings (`--gate-px` or `gate_px`), the rules several jobs share |
//! | [`stats`] | means, standard deviations, percentiles, histograms |
//! | [`uncertainty`] | JCGM 101: coverage intervals, standard uncertainty of the mean, the adaptive Monte Carlo procedure |
//! | [`plan`] | the exposure planner: per mode, the longest exposure meeting a tolerance, the compensated residual, the lost-frame risk |
//! | [`export`] | every output file's columns: typed rows -> bytes (one module per family), `write_atomic` |
//! | [`plots`] | PNG and SVG figures |
//! | [`geometry`] | homographies: fitted to point pairs (translation, similarity, normalised DLT), a plane seen obliquely |
//! | [`csvio`] | numeric CSV columns with errors naming row and column |
//! | [`outdir`] | output directories that are complete or absent (staged, synced, moved into place) |
//! | [`failpoint`] | `VIBCAM_FAILPOINT`: abort at a named point, for crash tests |
//! | [`calibrate`] | fitting unreported imaging knobs to observed figures (common random numbers) |
//! | [`cli`] | argument parsing and one module per subcommand |
//! | [`testing`] | seeded noise for tests, examples and benchmarks |

pub mod analysis;
#[cfg(feature = "cli")]
pub mod cli;
pub mod jobs;

// The readers' crate: its modules and its error are this crate's too, under the same paths.
pub use vibcam_readers::{bad_input, csvio, daq, frames, BadInput};
// What every layer shares: the same paths as before the cut.
pub use vibcam_chain as chain;
pub use vibcam_common::{failpoint, geometry, lost_frames, setting, stats, testing, uncertainty};
pub use vibcam_model as model;
pub use vibcam_report::{export, outdir, plots, provenance};
pub use vibcam_sim::{calibrate, imaging, plan, recording, study};
