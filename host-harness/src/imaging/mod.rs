//! The camera: what a target moving in front of it looks like in a frame, and the frame's
//! centroid as the firmware computes it (method.md §3.1 "Image formation").
//!
//! - [`render`]: the reference image of a [`DiskTarget`] and the EPSA renderer
//!   ([`BlurRenderer`]), the only renderer: studies, `render` and synthetic recordings all use it;
//! - [`effects`]: optional image-formation effects (gain, lens distortion, optical blur, sensor
//!   noise, bit depth) and the [`Camera`] that chains renderer -> effects -> quantisation ->
//!   firmware-core centroid;
//! - [`TargetPath`]: the motion of a target in pixels on a fine time base, and which part of it a
//!   frame of a given exposure integrates.

pub mod compensation;
pub mod effects;
pub mod fastpath;
pub mod render;

pub use effects::{Camera, Effects};
pub use render::{BlurRenderer, DiskTarget};

use serde::{Deserialize, Serialize};

/// The centroid the camera's firmware computes (`[imaging] centroid` of a study file).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum CentroidKind {
    /// Weight 1 for every pixel above the threshold (the paper's method; the default).
    #[default]
    Binary,
    /// Weight `value - threshold` for every pixel above it.
    Weighted,
}

impl CentroidKind {
    /// firmware-core's centroid mode.
    pub fn mode(self) -> firmware_core::centroid::Mode {
        match self {
            CentroidKind::Binary => firmware_core::centroid::Mode::Binary,
            CentroidKind::Weighted => firmware_core::centroid::Mode::Weighted,
        }
    }

    /// `binary` or `weighted`.
    pub fn name(self) -> &'static str {
        match self {
            CentroidKind::Binary => "binary",
            CentroidKind::Weighted => "weighted",
        }
    }
}

/// Optional image-formation effects (method.md §3.1), all off by default. The `[imaging]` table
/// of a study file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
pub struct ImagingOptions {
    /// Contrast gain applied to the image (1 = none).
    pub gain: Option<f64>,
    /// Quadratic radial distortion coefficient k1 (1/px^2 relative to the frame centre).
    pub distortion_k1: Option<f64>,
    /// Cubic radial distortion coefficient k2.
    pub distortion_k2: Option<f64>,
    /// Optical blur: Gaussian sigma in px.
    pub optical_blur_sigma_px: Option<f64>,
    /// Sensor read noise, std in grey levels.
    pub read_noise: Option<f64>,
    /// Shot noise: electrons per grey level (full well / full scale); none when absent.
    pub shot_noise_e_per_level: Option<f64>,
    /// Quantisation bit depth (8, 12 or 16); 8 when absent.
    pub bits: Option<u32>,
    /// The firmware's centroid; binary when absent.
    pub centroid: Option<CentroidKind>,
    /// Whether identity-effect binary-centroid frames take the fast path
    /// ([`fastpath`](crate::imaging::fastpath), the same pixels as rendering them); true when
    /// absent. `false` renders every frame (the reference, about 4 times slower), e.g. to check
    /// the fast path on a study.
    pub fast_path: Option<bool>,
}

/// A target's image-plane motion: `path_px[i]` is its displacement (px, positive **down**, image
/// `y`) at fine step `i`, linear in between; fine step `pad` is the time of frame 0 and frame `k`
/// is at fine step `pad + k * fine_per_frame`. `pad` steps either side of the frames cover the
/// longest exposure window.
#[derive(Debug, Clone, PartialEq)]
pub struct TargetPath {
    /// Displacement, px (positive down), one value per fine step.
    pub path_px: Vec<f64>,
    /// Fine steps before frame 0 (and at least as many after the last frame).
    pub pad: usize,
    /// Fine steps per frame period.
    pub fine_per_frame: usize,
    /// Rate of the fine time base, Hz.
    pub fine_hz: f64,
}

impl TargetPath {
    /// Fine steps needed either side of a frame for an exposure of `exposure_ms` at `fine_hz`,
    /// plus a margin of two steps.
    pub fn pad_for(exposure_ms: f64, fine_hz: f64) -> usize {
        (exposure_ms / 2000.0 * fine_hz).ceil() as usize + 2
    }

    /// The path of a periodic motion given over one period (`period_px`, one value per fine
    /// step), extended by `pad` steps of its own wrap-around either side.
    pub fn periodic(period_px: &[f64], pad: usize, fine_per_frame: usize, fine_hz: f64) -> Self {
        let n = period_px.len();
        TargetPath {
            path_px: (0..n + 2 * pad)
                .map(|i| period_px[(i + n - pad % n) % n])
                .collect(),
            pad,
            fine_per_frame,
            fine_hz,
        }
    }

    /// The fine-step window `(a, b)` a frame at fine step `centre` integrates over an exposure of
    /// `exposure_ms` centred on it (method.md §2.6).
    pub fn window(&self, centre: f64, exposure_ms: f64) -> (f64, f64) {
        let half = exposure_ms / 2000.0 * self.fine_hz;
        (centre - half, centre + half)
    }

    /// The window of frame `k` (see [`window`](Self::window)).
    pub fn frame_window(&self, k: usize, exposure_ms: f64) -> (f64, f64) {
        self.window((self.pad + k * self.fine_per_frame) as f64, exposure_ms)
    }
}
