//! `host-harness pick`: the page where the points `track --points` follows are chosen with
//! the mouse ([`crate::analysis::pick`]).

use crate::analysis::pick::{run as pick, PickRequest};
use crate::analysis::region::{Direction, Selection, Shape};
use std::path::PathBuf;

/// Arguments of `host-harness pick`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The recording (anything `track --frames` reads).
    #[arg(long, value_name = "FRAMES")]
    pub frames: String,
    /// Frame rate, Hz (a video without a stated rate needs it to be read).
    #[arg(long, value_name = "HZ", value_parser = super::args::parse_rate)]
    pub fps: Option<f64>,
    /// --fps retimes a slow-motion video's container rate (as `track --retime`).
    #[arg(long, requires = "fps")]
    pub retime: bool,
    /// Frames A..B only (`$frame_range`).
    #[arg(long, value_name = "A..B", value_parser = crate::frames::FrameRange::parse, help = super::args::help("frame_range"))]
    pub frame_range: Option<crate::frames::FrameRange>,
    /// Points to show at the start (`track --points`'s format).
    #[arg(long, value_name = "FILE.csv")]
    pub points: Option<PathBuf>,
    /// Frames on the page's slider, evenly spaced through the recording.
    #[arg(long, value_name = "N", default_value_t = 8)]
    pub frames_shown: usize,
    /// The page.
    #[arg(long, value_name = "FILE.html", default_value = "pick.html")]
    pub out: PathBuf,
    /// Replace --out (and --points-out) if it exists.
    #[arg(long)]
    pub force: bool,
    /// Points from a region of the first frame: `X,Y;X,Y;...` (a polygon), `line:X,Y;X,Y;...`
    /// (along a line) or `brush:R:X,Y;...` (within R px of a stroke), in px; written to
    /// --points-out (after the --points given) and shown on the page.
    #[arg(long, value_name = "REGION", value_parser = Shape::parse)]
    pub region: Option<Shape>,
    /// The region's grid spacing (a line's step), px.
    #[arg(long, value_name = "PX", default_value_t = 10.0, requires = "region")]
    pub spacing: f64,
    /// The side of each region point's window, px (odd, 5 to 255).
    #[arg(long, value_name = "PX", default_value_t = 21, requires = "region")]
    pub window_px: usize,
    /// Keep a region's point when its window's texture is at least this fraction of the
    /// region's best (0 to 1; OpenCV's quality level).
    #[arg(long, value_name = "Q", default_value_t = 0.05, requires = "region")]
    pub min_texture: f64,
    /// The texture the points need: `both` (the structure tensor's smaller eigenvalue,
    /// Shi-Tomasi: motion in any direction), `x`, `y` or an angle in degrees from x toward y
    /// (the gradient energy along it: motion in that direction only).
    #[arg(long, value_name = "both|x|y|DEG", default_value = "both", value_parser = Direction::parse, requires = "region")]
    pub direction: Direction,
    /// The points file a --region writes (`track --points`'s format).
    #[arg(
        long,
        value_name = "FILE.csv",
        default_value = "points.csv",
        requires = "region"
    )]
    pub points_out: PathBuf,
}

/// Runs `host-harness pick`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let line = pick(&PickRequest {
        frames: a.frames,
        fps: a.fps,
        retime: a.retime,
        frame_range: a.frame_range,
        points: a.points,
        shown: a.frames_shown,
        out: a.out,
        force: a.force,
        region: a.region.map(|shape| {
            let sel = Selection {
                shape,
                spacing: a.spacing,
                window: a.window_px,
                min_texture: a.min_texture,
                direction: a.direction,
            };
            (sel, a.points_out)
        }),
    })?;
    super::stdout(&line)
}
