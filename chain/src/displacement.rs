//! Frames -> centroids -> displacement (method.md §2.1 and "Lost frames"): firmware-core's
//! centroid of each frame, the pixel-to-millimetre conversion with its sign convention, and the
//! one lost-frame policy of the toolkit.
//!
//! * **Sign.** Image `x` grows to the right and `y` grows *down*. With [`Axis::Y`] (the default)
//!   the displacement is positive **upwards in the image**: `d = -(cy - cy_ref) * mm_per_px`;
//!   with [`Axis::X`] it is positive to the right: `d = (cx - cx_ref) * mm_per_px`. `invert`
//!   flips either.
//! * **Lost frames.** A frame without any pixel above the threshold has no centroid. Its value
//!   is interpolated linearly between the nearest valid frames before and after; lost frames at
//!   the start or the end take the value of the nearest valid frame ([`fill_lost_frames`]); or,
//!   with [`LostFramePolicy::Hold`], it holds the last valid value (as firmware that repeats its
//!   last output does). There is no "drop" policy: the chain is a uniform-rate Fourier
//!   upsampling, and a dropped sample would shift every later frame by one period. More
//!   than [`MAX_LOST_FRACTION`] of lost frames makes a measurement fail: a study reports the run
//!   as failed and leaves it out, an analysis stops with an error.

use firmware_core::centroid::{Centroid, Flags};
use vibcam_readers::bad_input;

pub use vibcam_common::lost_frames::{
    fill_lost_frames, fill_lost_frames_with, too_many_lost, LostFramePolicy, MAX_LOST_FRACTION,
};

/// Which image axis carries the displacement (see the module documentation for the sign).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Axis {
    /// Horizontal: positive to the right.
    X,
    /// Vertical: positive upwards in the image (image `y` grows down).
    #[default]
    Y,
}

impl Axis {
    /// `"x"` or `"y"`.
    pub fn name(self) -> &'static str {
        match self {
            Axis::X => "x",
            Axis::Y => "y",
        }
    }
}

/// Pixel-to-millimetre conversion of the centroids.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DisplacementSettings {
    /// Scale, millimetres per pixel (> 0).
    pub mm_per_px: f64,
    /// Image axis of the motion.
    pub axis: Axis,
    /// Flip the sign.
    pub invert: bool,
    /// What a lost frame's value becomes.
    pub lost_frames: LostFramePolicy,
}

/// Displacement record of the camera, one value per frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Displacement {
    /// Displacement, mm (lost frames interpolated), one per frame.
    pub mm: Vec<f64>,
    /// `true` for the frames that had no centroid.
    pub lost: Vec<bool>,
    /// Number of lost frames.
    pub lost_count: usize,
    /// Reference centroid coordinate along the axis (mean of the valid frames), pixels.
    pub reference_px: f64,
    /// How the lost frames were filled.
    pub policy: LostFramePolicy,
}

impl Displacement {
    /// Fraction of lost frames, 0..=1.
    pub fn lost_fraction(&self) -> f64 {
        if self.mm.is_empty() {
            0.0
        } else {
            self.lost_count as f64 / self.mm.len() as f64
        }
    }

    /// Whether more than [`MAX_LOST_FRACTION`] of the frames were lost.
    pub fn failed(&self) -> bool {
        too_many_lost(self.lost_count, self.mm.len())
    }
}

/// Converts per-frame centroids to a displacement in mm (sign and reference: see the module
/// documentation), filling the lost frames. Errors when no frame has a centroid. The lost
/// fraction is *not* checked here ([`Displacement::failed`]).
pub fn displacement_mm(
    centroids: &[Centroid],
    s: &DisplacementSettings,
) -> anyhow::Result<Displacement> {
    if !(s.mm_per_px.is_finite() && s.mm_per_px > 0.0) {
        return Err(bad_input(format!(
            "the scale must be a positive number of mm per pixel, got {}",
            s.mm_per_px
        )));
    }
    let mut coord: Vec<f64> = Vec::with_capacity(centroids.len());
    let mut valid: Vec<bool> = Vec::with_capacity(centroids.len());
    for c in centroids {
        let p = c.position().map(|(x, y)| match s.axis {
            Axis::X => f64::from(x),
            Axis::Y => f64::from(y),
        });
        coord.push(p.unwrap_or(0.0));
        valid.push(p.is_some());
    }
    let valid_count = valid.iter().filter(|v| **v).count();
    if valid_count == 0 {
        return Err(bad_input(format!(
            "none of the {} frames has a centroid: {}",
            centroids.len(),
            why_lost(centroids)
        )));
    }
    let reference_px = coord
        .iter()
        .zip(&valid)
        .filter(|(_, v)| **v)
        .map(|(c, _)| c)
        .sum::<f64>()
        / valid_count as f64;
    let lost_count = fill_lost_frames_with(&mut coord, &valid, s.lost_frames);
    let sign = match (s.axis, s.invert) {
        (Axis::X, false) | (Axis::Y, true) => 1.0,
        (Axis::X, true) | (Axis::Y, false) => -1.0,
    };
    Ok(Displacement {
        mm: coord
            .iter()
            .map(|c| sign * (c - reference_px) * s.mm_per_px)
            .collect(),
        lost: valid.iter().map(|v| !v).collect(),
        lost_count,
        reference_px,
        policy: s.lost_frames,
    })
}

/// Why a frame has no position, by flag: the flag, its name and what it means, in the order a
/// lost frame is counted under its first reason (the one table every command's wording of a
/// lost frame comes from).
pub const LOST_REASONS: [(Flags, &str, &str); 6] = [
    (
        Flags::BORDER,
        "border",
        "with the target at the edge of its window or ROI, or filling it (pixels above the \
         threshold all the way to the edge: a threshold below the background, or a window \
         smaller than the target; or the window reaching the frame's edge)",
    ),
    (Flags::SATURATED, "saturated", "saturated"),
    (
        Flags::FLAT,
        "flat",
        "with too little texture in the window (flat)",
    ),
    (
        Flags::AMBIGUOUS,
        "ambiguous",
        "ambiguous (a look-alike within the search range matched nearly as well, or a jump the \
         motion so far does not explain: group the targets that move together, or a smaller \
         $search_px)",
    ),
    (
        Flags::DIVERGED,
        "diverged",
        "without a match (diverged: the motion may exceed the search range)",
    ),
    (
        Flags::EMPTY,
        "empty",
        "with no pixel above the threshold (check $threshold and the window or $roi)",
    ),
];

/// The lost frames of `centroids` counted by their first reason in [`LOST_REASONS`]; and
/// those with none of these.
fn lost_reasons(centroids: &[Centroid]) -> ([usize; 6], usize) {
    let mut counts = [0usize; 6];
    let mut other = 0usize;
    for c in centroids.iter().filter(|c| c.position().is_none()) {
        match LOST_REASONS.iter().position(|(f, ..)| c.flags.contains(*f)) {
            Some(i) => counts[i] += 1,
            None => other += 1,
        }
    }
    (counts, other)
}

/// The lost frames counted by reason, each reason as `name` gives it, joined by `sep`.
fn counted(
    centroids: &[Centroid],
    name: impl Fn(&(Flags, &str, &str)) -> String,
    sep: &str,
) -> String {
    let (counts, other) = lost_reasons(centroids);
    let mut parts: Vec<String> = LOST_REASONS
        .iter()
        .zip(counts)
        .filter(|(_, n)| *n > 0)
        .map(|(reason, n)| format!("{n} {}", name(reason)))
        .collect();
    if other > 0 {
        parts.push(format!("{other} lost for another reason (see the flags)"));
    }
    parts.join(sep)
}

/// [`why_lost`] in the flags' names (`26 ambiguous, 4 diverged`), for a line per target.
pub fn lost_flags(centroids: &[Centroid]) -> String {
    counted(centroids, |(_, name, _)| name.to_string(), ", ")
}

/// Why frames without a centroid have none, from their flags, counted (the same words for
/// every command, [`LOST_REASONS`]).
pub fn why_lost(centroids: &[Centroid]) -> String {
    counted(centroids, |(_, _, what)| what.to_string(), "; ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lost_frames_are_interpolated_linearly() {
        // (values, valid, lost count, filled values)
        type Case<'a> = (&'a [f64], &'a [bool], usize, &'a [f64]);
        let cases: [Case; 3] = [
            (
                &[9.0, 1.0, 9.0, 9.0, 4.0, 9.0],
                &[false, true, false, false, true, false],
                4,
                &[1.0, 1.0, 2.0, 3.0, 4.0, 4.0],
            ),
            (&[5.0, 6.0], &[false, false], 2, &[5.0, 6.0]),
            (&[1.0, 7.0, 3.0], &[true, true, true], 0, &[1.0, 7.0, 3.0]),
        ];
        for (values, valid, lost, want) in cases {
            let mut v = values.to_vec();
            assert_eq!(fill_lost_frames(&mut v, valid), lost, "{values:?}");
            assert_eq!(v, want, "{values:?}");
        }
    }

    #[test]
    fn lost_frames_can_hold_the_last_value() {
        let mut v = vec![9.0, 1.0, 9.0, 9.0, 4.0, 9.0];
        let valid = [false, true, false, false, true, false];
        assert_eq!(
            fill_lost_frames_with(&mut v, &valid, LostFramePolicy::Hold),
            4
        );
        assert_eq!(v, [1.0, 1.0, 1.0, 1.0, 4.0, 4.0]);
        let mut v = vec![1.0, 9.0, 3.0];
        fill_lost_frames_with(&mut v, &[true, false, true], LostFramePolicy::Interpolate);
        assert_eq!(v, [1.0, 2.0, 3.0]);
    }

    #[test]
    fn the_five_percent_rule() {
        assert!(!too_many_lost(5, 100));
        assert!(too_many_lost(6, 100));
        assert!(!too_many_lost(0, 0));
    }
}
