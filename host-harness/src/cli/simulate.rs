//! `host-harness simulate-field`: a synthetic field record ([`crate::model::field`]): the
//! displacements of a structure's points under a broadband random force, and the true modes;
//! with `--render`, the frames a camera filming the points would record
//! ([`crate::recording::field`]).

use crate::model::field::{simulate, FieldCase};
use crate::recording::field::{write_field_recording, FieldRecording};
use std::path::PathBuf;

/// Arguments of `host-harness simulate-field`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The structure: a five-storey shear frame (five modes, 1.5 to 10.1 Hz), two modes 2 %
    /// apart and a third (2.00, 2.04, 5.00 Hz), five points each; or four modes at six points,
    /// the highest weak (1.95, 5.79, 9.57, 13.08 Hz).
    #[arg(long, value_enum, default_value_t = CaseArg::ShearFrame)]
    pub case: CaseArg,
    /// Record length, minutes (> 0) [default: 30; 5 with --render].
    #[arg(long, value_name = "MIN")]
    pub minutes: Option<f64>,
    /// Sample rate (the camera's frame rate), Hz.
    #[arg(long, value_name = "HZ", default_value_t = 60.0)]
    pub fps: f64,
    /// Measurement noise of the displacement record, relative to each record's RMS [default:
    /// 0.02]. Not with --render (its noise is the camera's --read-noise).
    #[arg(long, value_name = "REL")]
    pub noise: Option<f64>,
    /// Render the frames of the motion: one white disk per point, side by side, filmed at
    /// --fps with --exposure-ms and --read-noise (frames/, displacement.csv with the exact
    /// exposure-averaged motion in px, truth.csv, points.csv, README.txt with the analyze
    /// command). Keep such records short: 5 minutes at 60 fps are 18 000 PNG frames.
    #[arg(long)]
    pub render: bool,
    /// With --render: exposure, ms, centred on each frame's instant (< the frame period).
    #[arg(long, value_name = "MS", default_value_t = 5.0, requires = "render")]
    pub exposure_ms: f64,
    /// With --render: read noise, grey levels (std of Gaussian noise on the 8-bit scale).
    #[arg(long, value_name = "GREY", default_value_t = 1.0, requires = "render")]
    pub read_noise: f64,
    /// With --render: RMS displacement of the point that moves most, px.
    #[arg(long, value_name = "PX", default_value_t = 0.5, requires = "render")]
    pub rms_px: f64,
    /// With --render: also write frames.mkv (FFV1, lossless; ffmpeg needed).
    #[arg(long, requires = "render")]
    pub video: bool,
    /// With --render: N static reference disks (0-8) above and below the row of targets, in
    /// the structure's plane (references.csv and world.csv written for `--reference` and
    /// `--world`). Any of --references, --shake-px, --roll-deg, --oblique-deg draws the scene
    /// as a plane seen by a pinhole camera (targets in a row, truth_motion.csv and
    /// camera_truth.csv beside the frames) instead of one strip per target.
    #[arg(long, value_name = "N", requires = "render")]
    pub references: Option<usize>,
    /// With --render: the camera's shake, RMS px along each image axis (band-limited noise
    /// over --shake-hz).
    #[arg(long, value_name = "PX", requires = "render")]
    pub shake_px: Option<f64>,
    /// With --render: the camera's roll about the image centre, RMS degrees (over --shake-hz).
    #[arg(long, value_name = "DEG", requires = "render")]
    pub roll_deg: Option<f64>,
    /// With --render: the shake's band, Hz (a flat spectrum between A and B).
    #[arg(long, value_name = "A,B", value_parser = parse_band, requires = "render")]
    pub shake_hz: Option<(f64, f64)>,
    /// With --render: the structure's plane turned by this angle about its vertical axis,
    /// degrees (a camera looking at it obliquely: each target at its own scale).
    #[arg(long, value_name = "DEG", requires = "render")]
    pub oblique_deg: Option<f64>,
    /// With --render: `speckle` films a speckle-painted simply supported beam side-on instead
    /// (modes 2.5, 10, 22.5 Hz; the shapes known at every pixel column: shapes.csv, motion.csv,
    /// region.txt for `pick --region`), not with --case or the camera's flags.
    #[arg(long, value_enum, requires = "render", conflicts_with_all = ["case", "references", "shake_px", "roll_deg", "shake_hz", "oblique_deg"])]
    pub scene: Option<SceneArg>,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output directory (created): displacement.csv (`t_s,1,...,5`) and truth.csv
    /// (`mode,f_hz,damping,target,shape`).
    #[arg(long, value_name = "DIR", default_value = "field")]
    pub out: PathBuf,
    /// Replace --out if it is an earlier output of `simulate-field`.
    #[arg(long)]
    pub force: bool,
}

/// `--case`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CaseArg {
    /// Five-storey shear frame.
    ShearFrame,
    /// Two close modes and a third.
    CloseModes,
    /// Four modes at six points, the highest weak.
    WeakHighMode,
}

/// `--scene`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SceneArg {
    /// A speckle-painted beam.
    Speckle,
}

/// Runs `host-harness simulate-field`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let minutes = args.minutes.unwrap_or(if args.render { 5.0 } else { 30.0 });
    if args.render && args.noise.is_some() {
        return Err(crate::bad_input(
            "--noise is the displacement record's noise: a rendered recording's noise is the \
             camera's --read-noise",
        ));
    }
    let noise = args.noise.unwrap_or(0.02);
    if !(noise.is_finite() && noise >= 0.0) {
        return Err(crate::bad_input(format!(
            "--noise must be >= 0, got {noise}"
        )));
    }
    let case = match args.case {
        CaseArg::ShearFrame => FieldCase::ShearFrame,
        CaseArg::CloseModes => FieldCase::CloseModes,
        CaseArg::WeakHighMode => FieldCase::WeakHighMode,
    };
    let model = match args.scene {
        Some(SceneArg::Speckle) => crate::recording::speckle::model(),
        None => case.model(),
    };
    let (n, warnings) = crate::model::field::record_length(&model, minutes, args.fps, args.render)?;
    if args.render {
        let rec = FieldRecording {
            model,
            fps: args.fps,
            frames: n,
            seed: args.seed,
            exposure_ms: args.exposure_ms,
            read_noise: args.read_noise,
            rms_px: args.rms_px,
            video: args.video,
            view: view(&args),
        };
        let bar = crate::study::runner::progress_bar(n as u64, true, "frames");
        let progress = |done: usize| bar.set_position(done as u64);
        let report = match args.scene {
            Some(SceneArg::Speckle) => {
                crate::recording::speckle::write_speckle_beam(&rec, &args.out, args.force, progress)
            }
            None => write_field_recording(&rec, &args.out, args.force, progress),
        };
        bar.finish_and_clear();
        return super::stdout(&with_warnings(report?, &warnings));
    }
    let rec = simulate(&model, args.fps, n, noise, args.seed);
    let report =
        crate::recording::field::write_field(&args.out, args.force, &model, &rec, args.fps)?;
    super::stdout(&with_warnings(report, &warnings))
}

/// The camera's view when any of its flags was given.
fn view(args: &Args) -> Option<crate::recording::camera_view::CameraView> {
    let any = args.references.is_some()
        || args.shake_px.is_some()
        || args.roll_deg.is_some()
        || args.shake_hz.is_some()
        || args.oblique_deg.is_some();
    any.then(|| {
        let band = args.shake_hz.unwrap_or((1.0, 5.0));
        crate::recording::camera_view::CameraView {
            references: args.references.unwrap_or(4),
            shake_px: args.shake_px.unwrap_or(0.0),
            roll_deg: args.roll_deg.unwrap_or(0.0),
            shake_band_hz: band,
            oblique_deg: args.oblique_deg.unwrap_or(0.0),
        }
    })
}

/// `--shake-hz A,B`.
fn parse_band(s: &str) -> Result<(f64, f64), String> {
    let v: Vec<Option<f64>> = s.split(',').map(|p| p.trim().parse().ok()).collect();
    match v.as_slice() {
        [Some(a), Some(b)] => Ok((*a, *b)),
        _ => Err(format!("`{s}`: give the band as A,B in Hz")),
    }
}

/// The report with the warnings after it.
fn with_warnings(mut report: String, warnings: &[String]) -> String {
    for w in warnings {
        report.push_str(&format!("warning: {w}\n"));
    }
    report
}
