//! `host-harness analyze`: a real recording (frames + accelerometer CSV) through the chain of
//! [`crate::analysis`]. This file only parses arguments, loads the inputs, calls the chain and
//! writes the outputs.

use super::args::{parse_bands, Bands, CentroidArgs, ModeArg, WelchArgs};
use crate::analysis::compensate::{compensate, Compensated};
use crate::analysis::{self, Axis, DisplacementSettings, Settings};
use crate::bad_input;
use crate::frames::{centroid_source, discover_frames, FrameSource};
use crate::outdir::Staged;
use std::path::{Path, PathBuf};

/// Arguments of `host-harness analyze`.
///
/// Sign convention: image `y` grows down; with `--axis y` (default) the displacement is
/// positive upwards in the image, with `--axis x` positive to the right; `--invert` flips it.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Frames: a directory (all *.png, *.tif, *.tiff in it, in natural name order, so
    /// frame_2 comes before frame_10), a pattern with `*`/`?` in the file name part
    /// (`rec/frame_*.png`), one multi-page TIFF, or a video file (.avi, .mkv, .mp4, .mov,
    /// .m4v, .webm, .mxf; decoded by the `ffmpeg` program, luma, its timestamps checked against
    /// --fps). 8- or 16-bit grey. Numbered files must be consecutive (a gap is an error).
    #[arg(long, value_name = "DIR|GLOB|FILE.tif|VIDEO")]
    pub frames: String,
    /// Camera frame rate, frames per second: a number or a ratio (`30000/1001`).
    #[arg(long, value_name = "HZ", value_parser = super::args::parse_rate)]
    pub fps: f64,
    /// Accelerometer CSV with a header row: the input column (base acceleration in m/s^2, or
    /// any input such as a force) and the output (tip) acceleration in m/s^2, the unit the
    /// vision acceleration is computed in.
    #[arg(long, value_name = "FILE.csv")]
    pub accel: PathBuf,
    /// Accelerometer sample rate, Hz. `N * fs / fps` must be an integer.
    #[arg(long, value_name = "HZ")]
    pub fs: f64,
    /// Column of the input (base) acceleration, the FRF input of both systems.
    #[arg(long, value_name = "NAME", default_value = "base_acc")]
    pub input_col: String,
    /// Column of the output (tip) acceleration: the accelerometer system's FRF output.
    #[arg(long, value_name = "NAME", default_value = "tip_acc")]
    pub output_col: String,
    /// Optional time column (s): rows must be strictly increasing in steps of 1/fs.
    #[arg(long, value_name = "NAME")]
    pub time_col: Option<String>,
    /// Time of the first frame minus time of the first accelerometer sample, s (>= 0; rounded
    /// to the nearest sample, the residual delay is removed from the vision H1). Default 0.
    #[arg(
        long,
        value_name = "S",
        allow_negative_numbers = true,
        conflicts_with = "tick_offset"
    )]
    pub time_offset_s: Option<f64>,
    /// Same as --time-offset-s in ticks of the common time base --tick-hz (method.md §2.7).
    #[arg(
        long,
        value_name = "TICKS",
        allow_negative_numbers = true,
        requires = "tick_hz"
    )]
    pub tick_offset: Option<i64>,
    /// Rate of the common time base of --tick-offset, Hz (30720 for 2048 Hz / 120 fps).
    #[arg(long, value_name = "HZ", requires = "tick_offset")]
    pub tick_hz: Option<f64>,
    /// Centroid settings.
    #[command(flatten)]
    pub centroid: CentroidArgs,
    /// Scale, millimetres per pixel.
    #[arg(long, value_name = "MM")]
    pub mm_per_px: f64,
    /// Image axis of the motion (`y`: positive up in the image; `x`: positive right).
    #[arg(long, value_enum, default_value_t = AxisArg::Y)]
    pub axis: AxisArg,
    /// Flip the sign of the displacement.
    #[arg(long)]
    pub invert: bool,
    /// Camera exposure time, ms (for the E2PR of each mode).
    #[arg(long, value_name = "MS")]
    pub exposure_ms: Option<f64>,
    /// Divide the vision H1 by the exposure's transfer sinc(pi f --exposure-ms) up to E2PR 0.8
    /// (exact for --mode weighted with the threshold at the background; an approximation,
    /// noted in the report, for binary); writes compensation.csv.
    #[arg(long, requires = "exposure_ms")]
    pub compensate_exposure: bool,
    /// Welch estimator settings (default: the rig's single whole-record Hann segment).
    #[command(flatten)]
    pub welch: WelchArgs,
    /// Frequency bands of the modes, Hz: LO-HI,LO-HI,...
    #[arg(long, value_name = "LO-HI,...", default_value = "5-15,25-45", value_parser = parse_bands)]
    pub bands: Bands,
    /// Output directory (created).
    #[arg(long, value_name = "DIR", default_value = "analysis")]
    pub out: PathBuf,
    /// What a lost frame's value becomes: `interpolate` (linearly between its valid
    /// neighbours) or `hold` (the last valid value, as firmware repeating its last output).
    #[arg(long, value_enum, default_value_t = crate::lost_frames::LostFramePolicy::Interpolate)]
    pub lost_frames: crate::lost_frames::LostFramePolicy,
    /// Take the displacement record as periodic in the Fourier upsampling (no end matching):
    /// by default the line through its first and last samples is subtracted first, since a
    /// real record is not periodic (docs/method.md §3.2).
    #[arg(long)]
    pub no_end_match: bool,
    /// Replace --out if it is an earlier output of `analyze` (its manifest lists every file in
    /// it, and it holds no input of this run), as a whole. A failed run replaces nothing.
    #[arg(long)]
    pub force: bool,
    /// Several targets (2-32): numbered left to right (then top to bottom) in the first frame
    /// and followed frame to frame; writes modes.csv with a target column and the fitted
    /// damping, shapes.csv and frf.uff (docs/cli.md).
    #[arg(long, value_name = "K")]
    pub targets: Option<usize>,
    /// With --targets: how far a target may move between frames and still be the same, px
    /// (> 0; default 10).
    #[arg(
        long,
        value_name = "PX",
        requires = "targets",
        allow_negative_numbers = true
    )]
    pub gate_px: Option<f64>,
    /// With --targets: the target (1..K) co-located with the output accelerometer, compared
    /// with it in the report (default: the last, K).
    #[arg(long, value_name = "J", requires = "targets")]
    pub accel_target: Option<usize>,
    /// With --targets: a reference mode shape CSV (header `mode,target,re[,im]`, e.g. an
    /// earlier shapes.csv or a model's): the MAC of each fitted shape against it goes into the
    /// report and mac.csv, the reference into the shape plot.
    #[arg(long, value_name = "FILE.csv", requires = "targets")]
    pub shape_reference: Option<PathBuf>,
}

impl Args {
    /// The files and folders the run reads (an output directory holding one is never
    /// replaced).
    pub fn inputs(&self) -> Vec<&Path> {
        let mut v = vec![Path::new(self.frames.as_str()), self.accel.as_path()];
        v.extend(self.shape_reference.as_deref());
        v
    }

    /// Whether the motion is measured along the image's x axis.
    pub fn axis_is_x(&self) -> bool {
        self.axis == AxisArg::X
    }
}

/// `--axis`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum AxisArg {
    /// Horizontal, positive to the right.
    X,
    /// Vertical, positive upwards in the image.
    Y,
}

/// Runs `host-harness analyze`.
pub fn run(args: Args) -> anyhow::Result<()> {
    for (name, v) in [("--fps", args.fps), ("--mm-per-px", args.mm_per_px)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(bad_input(format!("{name} must be positive, got {v}")));
        }
    }
    if let Some(e) = args.exposure_ms {
        if !(e.is_finite() && e >= 0.0) {
            return Err(bad_input(format!("--exposure-ms must be >= 0, got {e}")));
        }
        let period_ms = 1000.0 / args.fps;
        if e > period_ms {
            let why = format!(
                "--exposure-ms {e} is longer than the frame period ({period_ms:.3} ms at {} \
                 fps): no camera exposes longer than it records; check --exposure-ms (in ms) \
                 and --fps",
                args.fps
            );
            // dividing by the transfer of an impossible exposure would be a wrong number
            if args.compensate_exposure {
                return Err(bad_input(format!("{why}; --compensate-exposure refused")));
            }
            eprintln!("warning: {why}");
        }
    }
    for &(lo, hi) in &args.bands.pairs() {
        if hi > args.fps / 2.0 {
            return Err(bad_input(format!(
                "--bands {lo}-{hi}: reaches above the camera's Nyquist frequency ({} Hz at {} \
                 fps), where the vision record has no content; keep every band below it",
                args.fps / 2.0,
                args.fps
            )));
        }
    }
    let time_offset_s = match (args.time_offset_s, args.tick_offset, args.tick_hz) {
        (Some(t), _, _) => t,
        (None, Some(k), Some(hz)) => analysis::tick_offset_to_seconds(k, hz)?,
        _ => 0.0,
    };
    let config = args.centroid.config(None)?;
    let settings = Settings {
        frame_rate_hz: args.fps,
        accel_rate_hz: args.fs,
        time_offset_s,
        welch: args.welch.settings(),
        bands: args.bands.pairs(),
        exposure_s: args.exposure_ms.map(|e| e / 1000.0),
        end_match: !args.no_end_match,
    };
    let dsettings = DisplacementSettings {
        lost_frames: args.lost_frames,
        mm_per_px: args.mm_per_px,
        axis: match args.axis {
            AxisArg::X => Axis::X,
            AxisArg::Y => Axis::Y,
        },
        invert: args.invert,
    };

    // Inputs first (cheap checks before the frames are decoded).
    let (base, tip) = analysis::load_accel(
        &args.accel,
        args.fs,
        &args.input_col,
        &args.output_col,
        args.time_col.as_deref(),
    )?;
    let found = discover_frames(&args.frames)?;
    let source = found.source.clone();
    let ignored = ignored_note(&found.ignored);
    if let Some(n) = &ignored {
        eprintln!("warning: {n}");
    }
    if let Some(n) = source.count(args.fps)? {
        // The frame count is known before decoding: check the record lengths now.
        let n = analysis::usable_frames_or_error(n, args.fps, args.fs)?;
        analysis::align(n, args.fps, base.len(), args.fs, time_offset_s)?;
    }
    if let Some(k) = args.targets {
        return super::analyze_targets::run(
            &args,
            &source,
            (&base, &tip),
            (&settings, &dsettings),
            k,
            ignored.as_deref(),
        );
    }
    let (centroids, depth) = centroid_source(&source, args.fps, &config)?;
    let depth_warning = depth.threshold_warning(args.centroid.threshold);
    if let Some(w) = &depth_warning {
        eprintln!("warning: {w}");
    }
    let disp = analysis::displacement_mm(&centroids, &dsettings)?;

    // every output is staged and the directory moved into place at the end (complete or absent)
    let out = Staged::new(&args.out, args.force, "analyze", &args.inputs())?;
    let mut inputs = describe_inputs(&args, &source, centroids.len(), base.len(), time_offset_s);
    if let Some(n) = ignored {
        inputs.push(("ignored".into(), n));
    }
    inputs.push(("frame depth".into(), depth.describe()));
    if let Some(w) = depth_warning {
        inputs.push(("WARNING".into(), w));
    }
    out.write(
        "displacement.csv",
        analysis::displacement_csv(&centroids, &disp, args.fps, time_offset_s),
    )?;
    let (result, compensation) = analyze_and_compensate(&args, &disp, (&base, &tip), &settings)?;
    let (a, failure) = match &result {
        Ok(a) => (Some(a), None),
        Err(e) => (None, Some(format!("{e:#}"))),
    };
    let mut report = analysis::report_text(&inputs, &disp, a, failure.as_deref());
    append_compensation(&out, compensation.as_ref(), &mut report)?;
    if let Some(a) = a {
        out.write("frf.csv", analysis::frf_csv(a))?;
        out.write("modes.csv", analysis::modes_csv(a))?;
        let plots = write_plot(out.dir(), a, args.fps)?;
        let mut files = vec!["frf.csv", "modes.csv", "displacement.csv", "report.txt"];
        let names: Vec<String> = plots
            .iter()
            .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
            .collect();
        files.extend(names.iter().map(String::as_str));
        let files: Vec<String> = files
            .iter()
            .map(|f| args.out.join(f).display().to_string())
            .collect();
        report.push_str(&format!("\nwritten: {}\n", files.join(", ")));
    }
    out.write("report.txt", &report)?;
    if result.is_ok() {
        out.commit()?;
    } else if !out.commit_unless_replacing()? {
        report.push_str(&format!(
            "\nthe analysis failed: the earlier output in {} was left as it was\n",
            args.out.display()
        ));
    }
    print!("{report}");
    result.map(|_| ())
}

/// The analysis (its failure is reported, not returned) and, with `--compensate-exposure`,
/// its vision H1 divided by the exposure's transfer (`analysis::compensate`).
fn analyze_and_compensate(
    args: &Args,
    disp: &analysis::Displacement,
    (base, tip): (&[f64], &[f64]),
    settings: &Settings,
) -> anyhow::Result<(anyhow::Result<analysis::Analysis>, Option<Compensated>)> {
    let mut result = analysis::analyze(disp, base, tip, settings);
    let compensation = match (&mut result, settings.exposure_s) {
        (Ok(a), Some(e)) if args.compensate_exposure => {
            let binary = args.centroid.mode == ModeArg::Binary;
            Some(compensate(a, e, &settings.bands, binary)?)
        }
        _ => None,
    };
    Ok((result, compensation))
}

/// Appends the compensation's section to the report and writes `compensation.csv`.
fn append_compensation(
    out: &Staged,
    c: Option<&Compensated>,
    report: &mut String,
) -> anyhow::Result<()> {
    if let Some(c) = c {
        let p = out.write("compensation.csv", c.csv())?;
        report.push_str(&c.report());
        report.push_str(&format!("  written: {}\n", p.display()));
    }
    Ok(())
}

/// The sentence naming image files beside the frames that are not of their numbered sequence.
pub fn ignored_note(ignored: &[PathBuf]) -> Option<String> {
    if ignored.is_empty() {
        return None;
    }
    let names: Vec<String> = ignored.iter().map(|p| p.display().to_string()).collect();
    Some(format!(
        "{} image file(s) beside the frames are not of their numbered sequence and were \
         ignored: {}",
        names.len(),
        names.join(", ")
    ))
}

/// `frf.png` / `frf.svg`: |H1| of both systems up to 1.1 x the highest band edge, at most the
/// camera's Nyquist frequency (the vision path has no content above it, and outside the
/// excitation band H1 is noise over noise).
fn write_plot(out: &Path, a: &analysis::Analysis, fps: f64) -> anyhow::Result<Vec<PathBuf>> {
    let top = a
        .acc_modes
        .iter()
        .map(|m| m.band_hz.1 * 1.1)
        .fold(0.0, f64::max);
    let top = if top > 0.0 {
        top.min(fps / 2.0)
    } else {
        fps / 2.0
    };
    let keep = a.acc_frf.freq_hz.iter().take_while(|&&f| f <= top).count();
    let freq = &a.acc_frf.freq_hz[..keep];
    let abs = |h: &[num_complex::Complex64]| h[..keep].iter().map(|v| v.norm()).collect();
    let acc: Vec<f64> = abs(&a.acc_frf.h1);
    let vis: Vec<f64> = abs(&a.vis_frf.h1);
    crate::plots::write_frf_plot(
        &out.join("frf"),
        "H1 of the recording: accelerometer and vision",
        "|H1|",
        &[("accelerometer", freq, &acc), ("vision", freq, &vis)],
    )
}

fn describe_inputs(
    args: &Args,
    source: &FrameSource,
    frames: usize,
    samples: usize,
    time_offset_s: f64,
) -> Vec<(String, String)> {
    let src = match source {
        FrameSource::Files(f) => format!(
            "{} ({} files, {} .. {})",
            args.frames,
            f.len(),
            f.first()
                .map(|p| p.display().to_string())
                .unwrap_or_default(),
            f.last()
                .map(|p| p.display().to_string())
                .unwrap_or_default()
        ),
        FrameSource::MultiPageTiff(p) => format!("{} (multi-page TIFF)", p.display()),
        FrameSource::Video(p) => format!("{} (video, decoded by FFmpeg)", p.display()),
    };
    let mut v = vec![
        ("frames".to_string(), src),
        (
            "frame count".into(),
            format!(
                "{frames} at {} fps ({:.4} s)",
                args.fps,
                frames as f64 / args.fps
            ),
        ),
        (
            "accelerometer".into(),
            format!(
                "{}: input `{}`, output `{}`, {samples} samples at {} Hz ({:.4} s)",
                args.accel.display(),
                args.input_col,
                args.output_col,
                args.fs,
                samples as f64 / args.fs
            ),
        ),
        (
            "alignment".into(),
            format!("first frame at {time_offset_s} s after the first sample"),
        ),
        (
            "centroid".into(),
            format!(
                "threshold {}, {:?}, ROI {}",
                args.centroid.threshold,
                args.centroid.mode,
                args.centroid
                    .roi
                    .map(|r| format!("{},{},{},{}", r.x, r.y, r.width, r.height))
                    .unwrap_or_else(|| "none".into())
            ),
        ),
        (
            "displacement".into(),
            format!(
                "{} mm/px, axis {}{}",
                args.mm_per_px,
                match args.axis {
                    AxisArg::X => "x (positive right)",
                    AxisArg::Y => "y (positive up in the image)",
                },
                if args.invert { ", inverted" } else { "" }
            ),
        ),
    ];
    if let Some(e) = args.exposure_ms {
        v.push(("exposure".into(), format!("{e} ms")));
    }
    v
}
