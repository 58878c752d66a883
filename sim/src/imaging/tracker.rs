//! What the simulated camera's firmware measures in each frame (`[imaging] tracker`): the
//! centroid above the threshold (`blob`, `weighted`), or the Lucas-Kanade displacement of the
//! target (`lk`, firmware-core's [`firmware_core::lk::LkTracker`]). A record's first frame is
//! the LK template: a square window around the target, centred on that frame's binary centroid
//! (where a user would put the window): `radius + 3 sigma + 2` px either side (the target's
//! edge and a margin of background), and along the motion (image `y`) as much more as the
//! record's longest blur reaches: a template that cuts a blurred target's tails matches the
//! other frames' differently blurred target badly, and the iteration jumps between
//! whole-pixel positions instead of settling. Every position is then the window's centre plus the
//! displacement since that frame; a constant offset (the first frame's position is not known
//! better than a pixel) is no error of a displacement.

use super::{DiskTarget, TrackerKind};
use firmware_core::centroid::{centroid, CentroidConfig, Frame, FrameError, Pixel};
use firmware_core::lk::LkConfig;

pub use vibcam_chain::lk::{HostLk, LK_PIXELS, LK_ROW};

/// One camera's measurement of a frame, with the state the LK tracker keeps between frames.
#[derive(Debug, Clone)]
pub struct FrameTracker {
    /// The centroid (the measurement of `blob` and `weighted`, and where `lk` puts its
    /// window in the first frame).
    config: CentroidConfig,
    /// With a frame-range threshold rule, the fraction of each frame's range.
    frame_range_frac: Option<f64>,
    lk: Option<Lk>,
}

#[derive(Debug, Clone)]
struct Lk {
    tracker: Box<HostLk>,
    /// Half-sizes of the window, px: across the motion (x) and along it (y).
    half: (i32, i32),
    /// The template window's centre in the record's first frame; `None` before it.
    origin: Option<(f32, f32)>,
}

impl FrameTracker {
    /// The measurement `kind` of `target`'s frames: `threshold` in the frame's codes
    /// (`saturation` the largest code, where LK's brightness constancy ends).
    pub fn new(
        kind: TrackerKind,
        threshold: u16,
        frame_range_frac: Option<f64>,
        target: &DiskTarget,
        saturation: u16,
    ) -> anyhow::Result<FrameTracker> {
        let config = CentroidConfig {
            mode: kind.mode(),
            ..CentroidConfig::binary(threshold)
        };
        let lk = match kind {
            TrackerKind::Lk => {
                let half = (target.radius_px + 3.0 * target.edge_sigma_px).ceil() as i32 + 2;
                Some(Lk {
                    tracker: Box::new(lk_tracker((half, half), saturation)?),
                    half: (half, half),
                    origin: None,
                })
            }
            _ => None,
        };
        Ok(FrameTracker {
            config,
            frame_range_frac,
            lk,
        })
    }

    /// Starts a new record whose longest blur is `blur_px` (the largest path range within one
    /// exposure): the next frame is LK's template, its window `blur_px / 2` taller each side
    /// than the sharp target's. Refused when the tracker cannot hold that window.
    pub fn restart(&mut self, blur_px: f64) -> anyhow::Result<()> {
        if let Some(lk) = &mut self.lk {
            let reach = (blur_px.max(0.0) / 2.0).ceil() as i32;
            let half = (lk.half.0, lk.half.0 + reach);
            if half != lk.half {
                let saturation = lk.tracker.config().saturation;
                *lk.tracker = lk_tracker(half, saturation)?;
                lk.half = half;
            }
            lk.origin = None;
        }
        Ok(())
    }

    /// The target's position `(x, y)` in `data` (`w x h`, row-major), `None` when it is lost.
    pub fn measure<P: Pixel + Copy + Into<u32>>(
        &mut self,
        data: &[P],
        w: usize,
        h: usize,
    ) -> Result<Option<(f32, f32)>, FrameError> {
        let frame = Frame::new(data, w, h, w)?;
        let config = match self.frame_range_frac {
            None => self.config,
            Some(frac) => CentroidConfig {
                threshold: frame_range_threshold(data, frac),
                ..self.config
            },
        };
        let Some(lk) = &mut self.lk else {
            return Ok(centroid(&config, &frame)?.position());
        };
        match lk.origin {
            Some((x, y)) => Ok(lk
                .tracker
                .track(&frame)
                .displacement()
                .map(|(dx, dy)| (x + dx, y + dy))),
            None => {
                let Some((cx, cy)) = centroid(&config, &frame)?.position() else {
                    return Ok(None);
                };
                let (x, y) = (cx.round() as i32, cy.round() as i32);
                let taken = lk
                    .tracker
                    .set_template(&frame, x - lk.half.0, y - lk.half.1)
                    .is_ok();
                // a window that cannot be a template (at the edge, flat): the next frame tries
                lk.origin = taken.then_some((x as f32, y as f32));
                Ok(lk.origin)
            }
        }
    }
}

/// An LK tracker of a window `2 half + 1` px wide and high.
fn lk_tracker((hx, hy): (i32, i32), saturation: u16) -> anyhow::Result<HostLk> {
    let side = |h: i32| u16::try_from(2 * h + 1).unwrap_or(u16::MAX);
    let (w, h) = (side(hx), side(hy));
    let cfg = LkConfig {
        saturation,
        ..LkConfig::new(w, h)
    };
    HostLk::try_new(cfg).map_err(|e| {
        vibcam_readers::bad_input(format!(
            "imaging.tracker = \"lk\": the target's window of {w} x {h} px (the target and its \
             longest blur): {e} (at most {} px wide and {LK_PIXELS} pixels with the spline's \
             margin: a smaller target or a shorter exposure)",
            LK_ROW - 7
        ))
    })
}

/// The threshold of a frame-range rule: `min + frac (max - min)` of the frame's grey levels,
/// rounded down (a flat frame gets its one level, so nothing is above it and it is lost).
pub fn frame_range_threshold<P: Copy + Into<u32>>(frame: &[P], frac: f64) -> u16 {
    let (lo, hi) = frame.iter().fold((u32::MAX, 0u32), |(lo, hi), &v| {
        let v = v.into();
        (lo.min(v), hi.max(v))
    });
    let lo = lo.min(hi);
    let threshold = lo + (frac * (hi - lo) as f64).floor() as u32;
    threshold.min(u16::MAX as u32) as u16
}
