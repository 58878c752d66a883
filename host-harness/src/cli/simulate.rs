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
    let model = case.model();
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
        };
        let bar = crate::study::runner::progress_bar(n as u64, true, "frames");
        let report = write_field_recording(&rec, &args.out, args.force, |done| {
            bar.set_position(done as u64)
        });
        bar.finish_and_clear();
        return super::stdout(&with_warnings(report?, &warnings));
    }
    let rec = simulate(&model, args.fps, n, noise, args.seed);
    let report =
        crate::recording::field::write_field(&args.out, args.force, &model, &rec, args.fps)?;
    super::stdout(&with_warnings(report, &warnings))
}

/// The report with the warnings after it.
fn with_warnings(mut report: String, warnings: &[String]) -> String {
    for w in warnings {
        report.push_str(&format!("warning: {w}\n"));
    }
    report
}
