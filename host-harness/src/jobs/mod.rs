//! What the user asks for, checked once: one spec type per job (`track`, `analyze`, `modal`),
//! built by a constructor from the settings as given ([`TrackInput`], [`AnalyzeInput`],
//! [`ModalInput`]) and refusing what is out of range or does not go together with a
//! [`SpecError`]. The command line (clap) and the Python package (keyword arguments) only
//! translate into these inputs; every rule spanning several settings, or a setting and the data
//! (the Nyquist frequency, the frame period), lives here once.
//!
//! A [`SpecError`] names settings by a key (`$gate_px`); [`SpecError::message`] spells them as
//! the caller's users write them: `--gate-px` on the command line, `gate_px` in Python.

mod analyze;
mod ema;
mod modal;
mod track;
pub mod tracking;
pub mod view;

pub use analyze::{AccelSettings, AnalyzeInput, AnalyzeSpec, TimeOffset, DEFAULT_ACCEL_BANDS};
pub use ema::{EmaInput, EmaSpec, RovingRecord};
pub use modal::{ModalComputed, ModalInput, ModalSpec};
pub use track::{TrackInput, TrackSpec};
pub use tracking::{PointsInput, Threshold, Tracker, Tracking, TrackingInput};
pub use view::{ViewInput, WorldInput};

pub use crate::frames::Rates;
pub use crate::setting::{
    bands_below_nyquist, bands_ordered, positive, Naming, SpecError, SpecResult,
};

use crate::frames::FrameRange;

/// Where the frames come from, as given: the path (as `--frames` takes it), `--retime`, and
/// the frames kept.
#[derive(Debug, Clone, PartialEq)]
pub struct FramesInput {
    /// `--frames` as the user wrote it.
    pub frames: String,
    /// A video's container rate retimed to the frame rate.
    pub retime: bool,
    /// Frames A..B only.
    pub frame_range: Option<FrameRange>,
}

/// `$geometry` read when given (its path and its nodes and lines); an error names the file and
/// the row.
pub fn read_geometry(
    path: Option<&std::path::Path>,
) -> SpecResult<Option<(std::path::PathBuf, vibcam_readers::geometry::Geometry)>> {
    path.map(|p| {
        let g = vibcam_readers::geometry::read(p).map_err(SpecError::Input)?;
        Ok((p.to_path_buf(), g))
    })
    .transpose()
}
