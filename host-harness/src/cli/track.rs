//! `host-harness track`: frames in, each target's position per frame out, no accelerometer
//! needed; the flags translated into a
//! [`TrackSpec`], which checks them and runs the job.

use super::analyze::AxisArg;
use super::args::CentroidArgs;
use crate::jobs::{FramesInput, SpecError, TrackInput, TrackSpec};
use crate::lost_frames::LostFramePolicy;
use std::path::PathBuf;

/// Arguments of `host-harness track`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The recording: its frames, their rate, a retiming and a range (as `analyze`'s).
    #[command(flatten)]
    pub recording: super::args::Recording,
    /// Chosen points: CSV `target,x,y,w,h[,threshold]` (as `analyze --points`).
    #[arg(
        long,
        value_name = "FILE.csv",
        conflicts_with = "targets",
        required_unless_present = "targets"
    )]
    pub points: Option<PathBuf>,
    /// With --points and --tracker lk: the largest motion between two frames to catch, px (a
    /// coarse search over +-R before the sub-pixel refinement, when the refinement from the
    /// last position finds no match; default: half the window's larger side). A best match on
    /// the edge of the range is a lost frame (the motion may be larger).
    #[arg(long, value_name = "R", requires = "points")]
    pub search_px: Option<u16>,
    /// The K blobs of the first frame (global threshold), numbered left to right.
    #[arg(long, value_name = "K", value_parser = super::args::int_range(1..=crate::jobs::tracking::MAX_TARGETS as u64))]
    pub targets: Option<usize>,
    /// With --targets: how far a target may move between frames and still be the same, px
    /// (> 0; default 10). Not with --points (each window follows its own target).
    #[arg(
        long,
        value_name = "PX",
        requires = "targets",
        allow_negative_numbers = true,
        value_parser = super::args::parse_gate_px
    )]
    pub gate_px: Option<f64>,
    /// Centroid settings (`--threshold T|auto`, `--tracker binary|blob|weighted`, `--roi`).
    #[command(flatten)]
    pub centroid: CentroidArgs,
    /// Static references, the camera's motion model and the scale from the scene.
    #[command(flatten)]
    pub view: super::args::ViewArgs,
    /// Millimetres per pixel: fills `disp_mm` (empty without it).
    #[arg(long, value_name = "MM")]
    pub mm_per_px: Option<f64>,
    /// Image axis of the displacement (and of the plot).
    #[arg(long, value_enum, default_value_t = AxisArg::Y)]
    pub axis: AxisArg,
    /// What a lost frame's displacement becomes (as `analyze`).
    #[arg(long, default_value = "interpolate", value_parser = super::args::choice(&LostFramePolicy::ALL, LostFramePolicy::name))]
    pub lost_frames: LostFramePolicy,
    /// No tracks.png/.svg.
    #[arg(long)]
    pub no_plots: bool,
    /// Output directory (new or empty).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Replace --out if it is an earlier output of `track`, as a whole.
    #[arg(long)]
    pub force: bool,
}

/// Runs `host-harness track`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let rates = crate::frames::resolve_rates(
        &args.recording.frames,
        args.recording.fps,
        None,
        args.recording.retime,
        args.recording.frame_range,
    )?;
    let input = TrackInput {
        frames: FramesInput {
            frames: args.recording.frames.clone(),
            retime: args.recording.retime,
            frame_range: args.recording.frame_range,
        },
        tracking: args.centroid.tracking(
            args.points.as_deref(),
            args.targets,
            args.gate_px,
            args.search_px,
        ),
        mm_per_px: args.mm_per_px,
        view: args.view.view(),
        axis: args.axis.axis(),
        lost_frames: args.lost_frames,
        plots: !args.no_plots,
        out: args.out.clone(),
        force: args.force,
    };
    let report = TrackSpec::new(input, rates)
        .map_err(SpecError::into_anyhow)?
        .run()?;
    super::stdout(&report)?;
    super::outputs_in(&args.out)
}
