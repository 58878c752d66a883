//! The trackers: what measures a target in each frame, as every command, Python and a study
//! file name it.

use serde::{Deserialize, Serialize};

/// What measures a target in each frame: the thresholded centroid (binary or weighted) or
/// Lucas-Kanade. The one tracker enum: `track --tracker`, `analyze --tracker`, Python's
/// `tracker` and a study's `[imaging] tracker` all name one of these.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TrackerKind {
    /// The binary centroid above the threshold (the paper's method; the default).
    #[default]
    Blob,
    /// The intensity-weighted centroid above the threshold.
    Weighted,
    /// Lucas-Kanade: the displacement of the first frame's window around the target.
    Lk,
}

impl TrackerKind {
    /// `blob`, `weighted` or `lk`.
    pub fn name(self) -> &'static str {
        match self {
            TrackerKind::Blob => "blob",
            TrackerKind::Weighted => "weighted",
            TrackerKind::Lk => "lk",
        }
    }

    /// The centroid's mode: binary for `blob` (and for `lk`, whose window the binary centroid
    /// places in the first frame), weighted for `weighted`.
    pub fn mode(self) -> firmware_core::centroid::Mode {
        match self {
            TrackerKind::Weighted => firmware_core::centroid::Mode::Weighted,
            TrackerKind::Blob | TrackerKind::Lk => firmware_core::centroid::Mode::Binary,
        }
    }
}
