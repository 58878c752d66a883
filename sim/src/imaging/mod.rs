//! The camera: what a target moving in front of it looks like in a frame, and the frame's
//! centroid as the firmware computes it (method.md §3.1 "Image formation").
//!
//! - [`render`]: the reference image of a [`DiskTarget`] and the EPSA renderer
//!   ([`BlurRenderer`]), the only renderer: studies, `render` and synthetic recordings all use it;
//! - [`effects`]: optional image-formation effects (gain, lens distortion, optical blur, sensor
//!   noise, bit depth) and the [`Camera`] that chains renderer -> effects -> quantisation ->
//!   firmware-core centroid;
//! - [`TargetPath`]: the motion of a target in pixels on a fine time base, and which part of it a
//!   frame of a given exposure integrates;
//! - [`compensation`] and [`exposure`]: the exposure transfer the vision amplitudes are divided
//!   by (sinc for the weighted centroid, a measured table for the binary one).

pub mod compensation;
pub mod effects;
pub mod exposure;
pub mod fastpath;
pub mod render;
pub mod tracker;

pub use effects::{Camera, Effects, Measurement};
pub use render::BlurRenderer;
pub use vibcam_model::DiskTarget;

use serde::{Deserialize, Serialize};

/// When a frame's exposure happens relative to its timestamp (`[imaging] exposure_alignment`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ExposureAlignment {
    /// Centred on the frame's instant (the default; also what a camera that starts at the
    /// trigger gives once its timestamps are corrected to mid-exposure).
    #[default]
    Centred,
    /// Starting at the frame's instant (the trigger) and the timestamps left there: the
    /// displacement is late by half the exposure, a phase lag of `pi f Te` in the vision H1.
    Trigger,
}

/// How the binary threshold is set in each frame (`[imaging] threshold_rule`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ThresholdRule {
    /// One grey level for every frame (`threshold_frac` of the target level; the default).
    #[default]
    Fixed,
    /// Per frame, `min + threshold_frac (max - min)` of that frame's grey levels: a camera that
    /// stretches each frame's contrast to its full range (auto levels) before a fixed
    /// threshold, or a firmware that thresholds at a fraction of the frame's peak above its
    /// background. A blurred target whose peak falls (a long exposure spreads its light) keeps
    /// its pixels instead of fading below a fixed level.
    FrameRange,
}

/// The centroid the camera's firmware computes (`[imaging] centroid` of a study file).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
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

    /// The tracker a centroid names (`centroid = "binary" | "weighted"`, the older field).
    pub fn tracker(self) -> TrackerKind {
        match self {
            CentroidKind::Binary => TrackerKind::Blob,
            CentroidKind::Weighted => TrackerKind::Weighted,
        }
    }
}

/// What the camera's firmware measures in each frame: the one tracker enum of the toolkit
/// (`vibcam_chain::tracker`), here as a study's `[imaging] tracker` names it.
pub use vibcam_chain::tracker::TrackerKind;

/// What a study's `[imaging]` table resolves to, each part in its own type: the effects on the
/// image, how the firmware measures it, when the exposure happens, where on the rig the camera
/// looks, and what a lost frame becomes.
#[derive(Debug, Clone, PartialEq)]
pub struct Setup {
    /// The image-formation effects.
    pub effects: Effects,
    /// The centroid and its threshold rule.
    pub measurement: Measurement,
    /// When the exposure happens relative to the frame's timestamp.
    pub alignment: ExposureAlignment,
    /// `Some(N)`: an exposure is the mean of `N` sharp images, its ends included; `None`: the
    /// continuous integration ([`BlurRenderer::set_epsa_images`]).
    pub epsa_images: Option<usize>,
    /// Where the camera sees the cantilever (the tip, without a lever, by default; the
    /// grandstand accepts only the default).
    pub view: vibcam_model::cantilever::View,
    /// What a lost frame's value becomes.
    pub lost_frame_policy: vibcam_common::lost_frames::LostFramePolicy,
}

impl Setup {
    /// Resolves and checks the options; the message names the field.
    pub fn from_options(o: &ImagingOptions) -> anyhow::Result<Setup> {
        let effects = Effects::from_options(o)?;
        let view = vibcam_model::cantilever::View {
            lever: o.tip_rotation_lever.unwrap_or(0.0),
            xi: o.target_position_xi.unwrap_or(1.0),
        };
        let bad = |f: &str, why: &str| vibcam_readers::bad_input(format!("imaging.{f}: {why}"));
        if !(view.lever.is_finite() && view.lever.abs() <= 0.5) {
            return Err(bad(
                "tip_rotation_lever",
                "must be between -0.5 and 0.5 beam lengths",
            ));
        }
        if !(view.xi > 0.0 && view.xi <= 1.0) {
            return Err(bad(
                "target_position_xi",
                "must be a position along the beam in (0, 1] (1 = the tip)",
            ));
        }
        if let Some(n) = o.epsa_images {
            if !(2..=1000).contains(&n) {
                return Err(bad(
                    "epsa_images",
                    "must be between 2 and 1000 images per exposure (absent: continuous)",
                ));
            }
        }
        Ok(Setup {
            effects,
            measurement: Measurement::from_options(o)?,
            alignment: o.exposure_alignment.unwrap_or_default(),
            epsa_images: o.epsa_images,
            view,
            lost_frame_policy: o.lost_frame_policy.unwrap_or_default(),
        })
    }

    /// Whether the camera looks at the tip without a lever (the only view the grandstand
    /// has).
    pub fn sees_the_tip(&self) -> bool {
        self.view.lever == 0.0 && self.view.xi == 1.0
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
    /// What the firmware measures in each frame: `blob` (the binary centroid), `weighted` or
    /// `lk`; blob when absent.
    pub tracker: Option<TrackerKind>,
    /// The older name of `tracker` for the centroids (`binary` = `blob`, `weighted`), still
    /// accepted; both given must agree.
    pub centroid: Option<CentroidKind>,
    /// What is painted on the target: `plain` (the default) or `speckle` (a texture for the
    /// gradient tracker).
    pub target_texture: Option<vibcam_model::Texture>,
    /// Whether identity-effect binary-centroid frames take the fast path
    /// ([`fastpath`], the same pixels as rendering them); true when
    /// absent. `false` renders every frame (the reference, about 4 times slower), e.g. to check
    /// the fast path on a study.
    pub fast_path: Option<bool>,
    /// Target disk radius, px; the rig's when absent.
    pub target_radius_px: Option<f64>,
    /// Gaussian sigma of the target's edge, px; the rig's when absent.
    pub target_edge_sigma_px: Option<f64>,
    /// Binary threshold as a fraction of the target's grey level (rounded to a grey level);
    /// the rig's when absent.
    pub threshold_frac: Option<f64>,
    /// When the exposure happens relative to the frame's timestamp; centred when absent.
    pub exposure_alignment: Option<ExposureAlignment>,
    /// How an exposure is formed: absent, the exact continuous integration over the path (a
    /// real sensor); `N` (2 to 1000), the discrete EPSA averaging of `N` sharp images spread
    /// evenly over the exposure, its ends included (the paper's simulation; method.md §2.6).
    pub epsa_images: Option<usize>,
    /// How the threshold is set in each frame; fixed when absent.
    pub threshold_rule: Option<ThresholdRule>,
    /// Cantilever only: the beam's rotation projected on the image plane, as a lever in beam
    /// lengths (`model::cantilever::View`): the camera sees the tip's deflection plus this lever
    /// times the tip's slope. 0 (none) when absent.
    pub tip_rotation_lever: Option<f64>,
    /// Cantilever only: where the target sits along the beam, `x / L` (the accelerometer is at
    /// the tip, 1); the tip when absent.
    pub target_position_xi: Option<f64>,
    /// What a lost frame's value becomes (`interpolate` or `hold`); interpolate when absent.
    pub lost_frame_policy: Option<vibcam_common::lost_frames::LostFramePolicy>,
}

impl ImagingOptions {
    /// The scenario's target and threshold (8-bit grey levels) with this table's overrides:
    /// the rig's `target` and `threshold` where a field is absent; the message names the field.
    pub fn target_and_threshold(
        &self,
        target: DiskTarget,
        threshold: u16,
    ) -> anyhow::Result<(DiskTarget, u16)> {
        let bad = |f: &str, why: &str| vibcam_readers::bad_input(format!("imaging.{f}: {why}"));
        let mut t = target;
        if let Some(texture) = self.target_texture {
            t.texture = texture;
        }
        if let Some(r) = self.target_radius_px {
            if !(r.is_finite() && (1.0..=100.0).contains(&r)) {
                return Err(bad("target_radius_px", "must be between 1 and 100 px"));
            }
            t.radius_px = r;
        }
        if let Some(s) = self.target_edge_sigma_px {
            // below about 0.5 px the sampled disk is not band-limited and the phase-shift
            // translation rings
            if !(s.is_finite() && (0.5..=10.0).contains(&s)) {
                return Err(bad("target_edge_sigma_px", "must be between 0.5 and 10 px"));
            }
            t.edge_sigma_px = s;
        }
        let threshold = match self.threshold_frac {
            None => threshold,
            Some(f) => {
                let level = (f * t.level).round();
                if !(f.is_finite() && f > 0.0 && f < 1.0 && level >= 1.0 && level < t.level) {
                    return Err(bad(
                        "threshold_frac",
                        &format!(
                            "must be a fraction in (0, 1) of the target level {} that rounds to \
                             a grey level between 1 and the level",
                            t.level
                        ),
                    ));
                }
                level as u16
            }
        };
        Ok((t, threshold))
    }
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

    /// The exact mean of the path (linear between its samples) over the fine-step window
    /// `(a, b)`: where an exposure of that window sees the target on average, px. Outside the
    /// path its end values hold.
    pub fn mean_px(&self, (a, b): (f64, f64)) -> f64 {
        let p = &self.path_px;
        let n = p.len();
        if n == 0 {
            return 0.0;
        }
        let at = |t: f64| -> f64 {
            let t = t.clamp(0.0, (n - 1) as f64);
            let i = (t.floor() as usize).min(n - 1);
            let f = t - i as f64;
            let next = p[(i + 1).min(n - 1)];
            p[i] + f * (next - p[i])
        };
        if b - a <= 1e-12 {
            return at(a);
        }
        // the integral piece by piece between the sample instants (trapezoids are exact on a
        // linear segment)
        let mut sum = 0.0;
        let mut t = a;
        while t < b {
            let next = (t.floor() + 1.0).min(b);
            sum += 0.5 * (at(t) + at(next)) * (next - t);
            t = next;
        }
        sum / (b - a)
    }

    /// The window of frame `k` (see [`window`](Self::window)).
    pub fn frame_window(&self, k: usize, exposure_ms: f64) -> (f64, f64) {
        self.window((self.pad + k * self.fine_per_frame) as f64, exposure_ms)
    }

    /// The window of frame `k` for an exposure aligned as `alignment` says: centred on the
    /// frame's instant, or starting there (then `pad` must cover a whole exposure after the
    /// last frame).
    pub fn aligned_window(
        &self,
        k: usize,
        exposure_ms: f64,
        alignment: ExposureAlignment,
    ) -> (f64, f64) {
        match alignment {
            ExposureAlignment::Centred => self.frame_window(k, exposure_ms),
            ExposureAlignment::Trigger => {
                let start = (self.pad + k * self.fine_per_frame) as f64;
                (start, start + exposure_ms / 1000.0 * self.fine_hz)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn target_and_threshold_overrides_name_the_field() {
        let rig = DiskTarget {
            radius_px: 12.0,
            level: 200.0,
            edge_sigma_px: 1.5,
            texture: vibcam_model::Texture::Plain,
        };
        let o = ImagingOptions::default();
        assert_eq!(o.target_and_threshold(rig, 100).unwrap(), (rig, 100));
        let o = ImagingOptions {
            target_radius_px: Some(4.5),
            target_edge_sigma_px: Some(0.75),
            threshold_frac: Some(0.123),
            ..Default::default()
        };
        let (t, th) = o.target_and_threshold(rig, 100).unwrap();
        assert_eq!(
            (t.radius_px, t.edge_sigma_px, t.level, th),
            (4.5, 0.75, 200.0, 25)
        );
        for (o, field) in [
            (
                ImagingOptions {
                    target_radius_px: Some(0.5),
                    ..Default::default()
                },
                "target_radius_px",
            ),
            (
                ImagingOptions {
                    target_edge_sigma_px: Some(0.1),
                    ..Default::default()
                },
                "target_edge_sigma_px",
            ),
            (
                ImagingOptions {
                    threshold_frac: Some(1.0),
                    ..Default::default()
                },
                "threshold_frac",
            ),
            (
                ImagingOptions {
                    threshold_frac: Some(0.001),
                    ..Default::default()
                },
                "threshold_frac",
            ),
            (
                ImagingOptions {
                    threshold_frac: Some(f64::NAN),
                    ..Default::default()
                },
                "threshold_frac",
            ),
        ] {
            let e = o.target_and_threshold(rig, 100).unwrap_err().to_string();
            assert!(e.contains(&format!("imaging.{field}")), "{e}");
        }
    }
}
