//! Modal identification: from spectra or records to poles, modes, shapes and their
//! intervals, knowing nothing of frames, files or outputs.
//!
//! - [`modal`]: the pole of one band fitted to an FRF (damping, shapes, MAC), the Welch window's
//!   kernel it can fit through;
//! - [`oma`]: output-only analysis: cross-spectra, FDD and EFDD, SSI, stabilisation and
//!   clustering, which peaks and clusters are modes, the jackknife's intervals;
//! - [`ema`]: experimental modal analysis with a measured force: hits and windows, H1/H2 and
//!   coherence, LSCF poles, LSFD residues, modes from the clusters.

pub mod ema;
pub mod modal;
pub mod oma;
