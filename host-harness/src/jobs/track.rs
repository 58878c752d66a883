//! `track`: frames in, each target's position per frame out.

use super::{FramesInput, Rates, SpecResult, TrackingInput};
use crate::analysis::track_run::Request;
use crate::analysis::{Axis, DisplacementSettings};
use crate::lost_frames::LostFramePolicy;
use std::path::PathBuf;

/// `track`'s settings as given.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackInput {
    /// The frames.
    pub frames: FramesInput,
    /// The targets and the tracker.
    pub tracking: TrackingInput,
    /// `$mm_per_px`: the displacement in mm beside the pixels.
    pub mm_per_px: Option<f64>,
    /// Static references and the scale from the scene.
    pub view: super::ViewInput,
    /// `$axis` of the displacement.
    pub axis: Axis,
    /// What a lost frame's displacement becomes.
    pub lost_frames: LostFramePolicy,
    /// Draw the tracks.
    pub plots: bool,
    /// Output directory.
    pub out: PathBuf,
    /// Replace an earlier `track` output there.
    pub force: bool,
    /// Also print `report.pdf` (headless Chromium).
    pub pdf: bool,
}

/// A checked `track` job.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackSpec {
    request: Request,
}

impl TrackSpec {
    /// Checks `input` at `rates` (from [`crate::frames::resolve_rates`]).
    pub fn new(input: TrackInput, rates: Rates) -> SpecResult<Self> {
        let (tracking, view, scaled) =
            super::view::tracking_and_view(input.tracking, input.view, input.mm_per_px)?;
        // the scene's scale, per target: 1 stands in
        let mm_per_px = input.mm_per_px.or(scaled.then_some(1.0));
        let displacement = mm_per_px.map(|mm_per_px| DisplacementSettings {
            lost_frames: input.lost_frames,
            mm_per_px,
            axis: input.axis,
            invert: false,
        });
        super::positive("fps", rates.fps, "frames per second")?;
        Ok(TrackSpec {
            request: Request {
                frames: input.frames.frames,
                retime: input.frames.retime,
                frame_range: input.frames.frame_range,
                fps: rates.fps,
                centroid: tracking.centroid,
                targets: tracking.targets,
                displacement,
                axis: input.axis,
                plots: input.plots,
                notes: rates.notes,
                out: input.out,
                force: input.force,
                pdf: input.pdf,
                inputs: tracking.points_file.into_iter().collect(),
                view,
            },
        })
    }

    /// The checked request.
    pub fn request(&self) -> &Request {
        &self.request
    }

    /// Runs the job; returns the report (also written to `report.txt`).
    pub fn run(&self) -> anyhow::Result<String> {
        crate::analysis::track_run::run(&self.request)
    }
}
