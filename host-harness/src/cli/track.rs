//! `host-harness track`: frames in, each target's position per frame out, no accelerometer
//! needed; the flags translated into a
//! [`TrackSpec`], which checks them and runs the job.

use super::args::CentroidArgs;
use crate::jobs::{SpecError, TrackInput, TrackSpec};
use crate::lost_frames::LostFramePolicy;
use std::path::PathBuf;

/// Arguments of `host-harness track`.
#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("which_targets").args(["points", "targets"]).required(true)))]
pub struct Args {
    /// The recording: its frames, their rate, a retiming and a range (as `analyze`'s).
    #[command(flatten)]
    pub recording: super::args::Recording,
    /// The targets: `$targets` blobs or `$points` windows (one of them).
    #[command(flatten)]
    pub targets: super::args::TargetArgs,
    /// Centroid settings (`--threshold T|auto`, `--tracker binary|blob|weighted`, `--roi`).
    #[command(flatten)]
    pub centroid: CentroidArgs,
    /// Static references, the camera's motion model, the scale and the axis measured.
    #[command(flatten)]
    pub view: super::args::ViewArgs,
    /// `$lost_frames`.
    #[arg(long, default_value = super::args::given("lost_frames"), value_parser = super::args::choice(&LostFramePolicy::ALL, LostFramePolicy::name), help = super::args::help("lost_frames"))]
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
    /// Also write report.pdf, report.html printed by a headless Chromium (chromium or
    /// google-chrome on PATH, or VIBCAM_CHROMIUM); a warning when there is none.
    #[arg(long)]
    pub pdf: bool,
}

/// Runs `host-harness track`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let rates = args.recording.rates(None)?;
    let input = TrackInput {
        frames: args.recording.input(),
        tracking: args.centroid.tracking(&args.targets),
        mm_per_px: args.view.mm_per_px,
        view: args.view.view(),
        axis: args.view.axis.axis(),
        lost_frames: args.lost_frames,
        plots: !args.no_plots,
        out: args.out.clone(),
        force: args.force,
        pdf: args.pdf,
    };
    let report = TrackSpec::new(input, rates)
        .map_err(SpecError::into_anyhow)?
        .run()?;
    super::stdout(&report)?;
    super::outputs_in(&args.out)
}
