//! `host-harness analyze`: the flags translated into an [`AnalyzeInput`], checked by
//! [`AnalyzeSpec::new`], the job run, its report printed.

use super::args::{parse_bands, Bands, CentroidArgs, WelchArgs};
use crate::analysis::twin::TwinSettings;
use crate::analysis::Axis;
use crate::jobs::{AccelSettings, AnalyzeInput, AnalyzeSpec, SpecError, TimeOffset};
use crate::lost_frames::LostFramePolicy;
use crate::study::runner::Shard;
use std::path::PathBuf;

/// Arguments of `host-harness analyze`.
///
/// Sign convention: image `y` grows down; with `--axis y` (default) the displacement is
/// positive upwards in the image, with `--axis x` positive to the right; `--invert` flips it.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The recording: its frames, their rate, a retiming and a range.
    #[command(flatten)]
    pub recording: super::args::Recording,
    /// Accelerometer CSV with a header row: the input column (base acceleration in m/s^2, or
    /// any input such as a force) and the output (tip) acceleration in m/s^2, the unit the
    /// vision acceleration is computed in. Without it: output-only modal analysis of the
    /// targets' displacements (FDD, EFDD, SSI-cov; as `modal`, docs/method.md §3.12).
    #[arg(long, value_name = "FILE.csv")]
    pub accel: Option<PathBuf>,
    /// Accelerometer sample rate, Hz (with --accel). `N * fs / fps` must be an integer.
    #[arg(long, value_name = "HZ", requires = "accel")]
    pub fs: Option<f64>,
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
    /// Static references, the camera's motion model, the scale and the axis measured.
    #[command(flatten)]
    pub view: super::args::ViewArgs,
    /// Flip the sign of the displacement.
    #[arg(long)]
    pub invert: bool,
    /// Camera exposure time, ms (for the E2PR of each mode). Default: the shutter a camera
    /// file states (Photron, Phantom).
    #[arg(long, value_name = "MS")]
    pub exposure_ms: Option<f64>,
    /// Divide the vision H1 by the exposure's transfer sinc(pi f --exposure-ms) up to E2PR 0.8
    /// (exact for --mode weighted with the threshold at the background; an approximation,
    /// noted in the report, for binary); writes compensation.csv.
    #[arg(long)]
    pub compensate_exposure: bool,
    /// Welch estimator settings (default: the rig's single whole-record Hann segment).
    #[command(flatten)]
    pub welch: WelchArgs,
    /// Frequency bands of the modes, Hz: LO-HI,LO-HI,... [default with --accel: 5-15,25-45;
    /// without: peaks picked automatically]
    #[arg(long, value_name = "LO-HI,...", value_parser = parse_bands)]
    pub bands: Option<Bands>,
    /// `$magnify_px`.
    #[arg(long, value_name = "PX", default_value = super::args::given("magnify_px"), value_parser = super::args::number("magnify_px"), help = super::args::help("magnify_px"))]
    pub magnify_px: f64,
    /// Output directory (created).
    #[arg(long, value_name = "DIR", default_value = "analysis")]
    pub out: PathBuf,
    /// `$lost_frames`.
    #[arg(long, default_value = super::args::given("lost_frames"), value_parser = super::args::choice(&LostFramePolicy::ALL, LostFramePolicy::name), help = super::args::help("lost_frames"))]
    pub lost_frames: LostFramePolicy,
    /// Take the displacement record as periodic in the Fourier upsampling (no end matching):
    /// by default the line through its first and last samples is subtracted first, since a
    /// real record is not periodic (docs/method.md §3.2).
    #[arg(long)]
    pub no_end_match: bool,
    /// Replace --out if it is an earlier output of `analyze` (its manifest lists every file in
    /// it, and it holds no input of this run), as a whole. A failed run replaces nothing.
    #[arg(long)]
    pub force: bool,
    /// `--pdf` and `--geometry`: what the page is printed to and drawn on.
    #[command(flatten)]
    pub page: super::args::PageArgs,
    /// The targets: `$targets` blobs or `$points` windows.
    #[command(flatten)]
    pub targets: super::args::TargetArgs,
    /// With --targets or --points: the target (1..K) co-located with the output accelerometer,
    /// compared with it in the report (default: the last, K).
    #[arg(long, value_name = "J")]
    pub accel_target: Option<usize>,
    /// With --targets: a reference mode shape CSV (header `mode,target,re[,im]`, e.g. an
    /// earlier shapes.csv or a model's): the MAC of each fitted shape against it goes into the
    /// report and mac.csv, the reference into the shape plot.
    #[arg(long, value_name = "FILE.csv")]
    pub shape_reference: Option<PathBuf>,
    /// With --accel and one target: re-render this recording N times (its stillest frame's
    /// region moved along the tracked motion, the stated exposure, the frames' measured noise)
    /// through the same centroid and analysis, and report each vision mode's amplitude bias
    /// and its 95 % interval from the runs (JCGM 101; docs/method.md §3.10.3); writes twin.csv.
    #[arg(long, value_name = "N", requires = "accel")]
    pub twin: Option<usize>,
    /// With --twin: the seed of run 0 (run r is seeded SEED + r).
    #[arg(long, value_name = "SEED", requires = "twin", default_value_t = 1)]
    pub twin_seed: u64,
    /// With --twin: only the runs r with r mod N = I - 1 (a shard; the shards' twin.csv rows
    /// together are the whole's).
    #[arg(long, value_name = "I/N", requires = "twin")]
    pub twin_shard: Option<String>,
}

/// `--axis`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum AxisArg {
    /// Horizontal, positive to the right.
    X,
    /// Vertical, positive upwards in the image.
    Y,
}

impl AxisArg {
    /// The library's axis.
    pub fn axis(self) -> Axis {
        match self {
            AxisArg::X => Axis::X,
            AxisArg::Y => Axis::Y,
        }
    }
}

/// Runs `host-harness analyze`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let out = args.out.clone();
    let rates = args.recording.rates(args.exposure_ms)?;
    let (spec, warnings) = AnalyzeSpec::new(input(args)?, rates).map_err(SpecError::into_anyhow)?;
    for w in warnings {
        eprintln!("warning: {}", crate::jobs::SpecError::setting(w));
    }
    super::finish(spec.run()?, &out)
}

/// The flags as the library's [`AnalyzeInput`].
fn input(args: Args) -> anyhow::Result<AnalyzeInput> {
    let shard = match &args.twin_shard {
        Some(s) => Shard::parse(s).map_err(|e| {
            crate::bad_input(format!(
                "--twin-shard: {}",
                e.to_string().replace("--shard: ", "")
            ))
        })?,
        None => Shard::ALL,
    };
    Ok(AnalyzeInput {
        frames: args.recording.input(),
        tracking: args.centroid.tracking(&args.targets),
        mm_per_px: args.view.mm_per_px,
        view: args.view.view(),
        axis: args.view.axis.axis(),
        invert: args.invert,
        lost_frames: args.lost_frames,
        welch: args.welch.settings(),
        bands: args.bands.as_ref().map(Bands::pairs),
        accel: args.accel.map(|path| AccelSettings {
            path,
            fs: args.fs,
            input_col: args.input_col,
            output_col: args.output_col,
            time_col: args.time_col,
        }),
        time_offset: match (args.time_offset_s, args.tick_offset, args.tick_hz) {
            (Some(t), _, _) => Some(TimeOffset::Seconds(t)),
            (None, Some(k), Some(hz)) => Some(TimeOffset::Ticks(k, hz)),
            _ => None,
        },
        compensate_exposure: args.compensate_exposure,
        end_match: !args.no_end_match,
        accel_target: args.accel_target,
        shape_reference: args.shape_reference,
        twin: args.twin.map(|runs| TwinSettings {
            runs,
            seed: args.twin_seed,
            shard,
        }),
        out: args.out,
        force: args.force,
        pdf: args.page.pdf,
        magnify_px: args.magnify_px,
        geometry: args.page.geometry.clone(),
    })
}
