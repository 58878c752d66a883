//! What `analyze` with an accelerometer is asked (a [`Request`], built and checked by
//! [`crate::jobs::AnalyzeSpec`]) and what a run gives back ([`Outcome`]): the types
//! `analysis::run` and `analysis::targets_run` share, in a file of their own so that neither
//! of the two imports the other's.

use super::track_run::Targets;
use super::{DisplacementSettings, Settings};
use crate::study::runner::Shard;
use firmware_core::centroid::CentroidConfig;
use std::path::{Path, PathBuf};

/// The accelerometer record of a recording.
#[derive(Debug, Clone, PartialEq)]
pub struct AccelInput {
    /// The CSV file.
    pub path: PathBuf,
    /// Its sample rate, Hz.
    pub fs: f64,
    /// Column of the FRF input (base acceleration, or a force).
    pub input_col: String,
    /// Column of the output (tip) acceleration.
    pub output_col: String,
    /// Optional time column, s.
    pub time_col: Option<String>,
}

/// Several targets (`--targets K` or `--points`) and what the accelerometer is compared with.
#[derive(Debug, Clone, PartialEq)]
pub struct TargetsRequest {
    /// The targets and how they are followed (never [`Targets::Whole`]: that is no request).
    pub targets: Targets,
    /// The target co-located with the output accelerometer, 1..=K.
    pub accel_target: usize,
    /// Reference shapes to compute the MAC against.
    pub shape_reference: Option<PathBuf>,
    /// Static references: the camera's motion removed from the targets (no scale: the
    /// request's `mm_per_px`).
    pub view: super::view::ViewSettings,
}

/// An `analyze` request with an accelerometer, as [`crate::jobs::AnalyzeSpec`] checks it: every
/// value in range, nothing read yet.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// `--frames` as the user wrote it.
    pub frames: String,
    /// `--retime`: the frame rate retimes a video's container rate (slow motion).
    pub retime: bool,
    /// Frames A..B only (`--frame-range`).
    pub frame_range: Option<crate::frames::FrameRange>,
    /// The accelerometer record.
    pub accel: AccelInput,
    /// The chain's settings (rates, alignment, Welch, bands, exposure, end matching).
    pub settings: Settings,
    /// Pixels to millimetres, axis, sign, lost-frame policy.
    pub displacement: DisplacementSettings,
    /// The centroid's settings.
    pub centroid: CentroidConfig,
    /// Whether the centroid is the binary one (the compensation's transfer is then approximate).
    pub binary: bool,
    /// Divide the vision H1 by the exposure's transfer.
    pub compensate_exposure: bool,
    /// The exposure as the user gave it, ms (`settings.exposure_s` is computed from it; this
    /// is how the report states it).
    pub exposure_ms: Option<f64>,
    /// Remarks for the report (where the frame rate or exposure came from).
    pub notes: Vec<String>,
    /// The points file, when `--points` was given (an input: never overwritten).
    pub points_file: Option<PathBuf>,
    /// Several targets, or one.
    pub targets: Option<TargetsRequest>,
    /// `--twin`: re-render the recording (one target only).
    pub twin: Option<TwinSettings>,
    /// Output directory, and whether an earlier analysis there may be replaced.
    pub out: PathBuf,
    /// `--force`.
    pub force: bool,
    /// Also print `report.pdf`.
    pub pdf: bool,
    /// `$geometry`: the structure's nodes and lines the page draws the shapes on (its path,
    /// its content; checked against the targets).
    pub geometry: Option<(PathBuf, vibcam_readers::geometry::Geometry)>,
}

impl Request {
    /// The files and folders the run reads (an output directory holding one is never
    /// replaced).
    pub fn inputs(&self) -> Vec<&Path> {
        let mut v = vec![Path::new(self.frames.as_str()), self.accel.path.as_path()];
        if let Some(t) = &self.targets {
            v.extend(t.shape_reference.as_deref());
            v.extend(t.view.references.as_ref().and_then(|r| r.file.as_deref()));
        }
        v.extend(self.points_file.as_deref());
        v.extend(self.geometry.as_ref().map(|g| g.0.as_path()));
        v
    }
}

/// What an analysis printed, and whether it succeeded (a failure's report is printed too).
#[derive(Debug)]
pub struct Outcome {
    /// The report (as written to `report.txt` when it was written).
    pub report: String,
    /// `Err` when the analysis failed (bad input: exit 2).
    pub result: anyhow::Result<()>,
}

/// `--twin N [--twin-seed S] [--twin-shard I/N]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TwinSettings {
    /// Runs in all (1 ..= [`MAX_RUNS`]).
    pub runs: usize,
    /// Seed of run 0; run `r` is seeded `seed + r`.
    pub seed: u64,
    /// This shard's runs (`Shard::ALL`: every run).
    pub shard: Shard,
}

/// Most runs one request may ask for.
pub const MAX_RUNS: usize = 100_000;

impl TwinSettings {
    /// The runs of this shard.
    pub fn mine(&self) -> Vec<usize> {
        (0..self.runs)
            .filter(|&r| self.shard.contains(r as u64))
            .collect()
    }
}
