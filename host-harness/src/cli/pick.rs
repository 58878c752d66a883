//! `host-harness pick`: the page where the points `track --points` follows are chosen with
//! the mouse ([`crate::analysis::pick`]).

use crate::analysis::pick::{run as pick, PickRequest};
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
    /// Points to show at the start (`track --points`'s format).
    #[arg(long, value_name = "FILE.csv")]
    pub points: Option<PathBuf>,
    /// Frames on the page's slider, evenly spaced through the recording.
    #[arg(long, value_name = "N", default_value_t = 8)]
    pub frames_shown: usize,
    /// The page.
    #[arg(long, value_name = "FILE.html", default_value = "pick.html")]
    pub out: PathBuf,
    /// Replace --out if it exists.
    #[arg(long)]
    pub force: bool,
}

/// Runs `host-harness pick`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let line = pick(&PickRequest {
        frames: a.frames,
        fps: a.fps,
        retime: a.retime,
        points: a.points,
        shown: a.frames_shown,
        out: a.out,
        force: a.force,
    })?;
    super::stdout(&line)
}
