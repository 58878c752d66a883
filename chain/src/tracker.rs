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
    /// Chosen for the user: with chosen points, per target the blob centroid where a threshold
    /// separates the target in its first-frame window, Lucas-Kanade otherwise; without points
    /// (one target, or the K blobs of the frame), the blob centroid. The default of `track`,
    /// `analyze` and Python.
    Auto,
}

impl TrackerKind {
    /// `blob`, `weighted` or `lk`.
    pub fn name(self) -> &'static str {
        match self {
            TrackerKind::Blob => "blob",
            TrackerKind::Weighted => "weighted",
            TrackerKind::Lk => "lk",
            TrackerKind::Auto => "auto",
        }
    }

    /// The tracker of targets that are not chosen points (the one target of the frame, the K
    /// blobs, a study's simulated disk): `auto` is the blob centroid there.
    pub fn without_points(self) -> TrackerKind {
        match self {
            TrackerKind::Auto => TrackerKind::Blob,
            t => t,
        }
    }

    /// The centroid's mode: binary for `blob` (and for `lk`, whose window the binary centroid
    /// places in the first frame), weighted for `weighted`.
    pub fn mode(self) -> firmware_core::centroid::Mode {
        match self {
            TrackerKind::Weighted => firmware_core::centroid::Mode::Weighted,
            TrackerKind::Blob | TrackerKind::Lk | TrackerKind::Auto => {
                firmware_core::centroid::Mode::Binary
            }
        }
    }
}
