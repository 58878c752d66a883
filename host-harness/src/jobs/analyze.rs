//! `analyze`: a recording's targets tracked, then FRFs against an accelerometer, or an
//! output-only modal analysis without one.

use super::{FramesInput, Rates, SpecError, SpecResult, Tracking, TrackingInput};
use crate::analysis::oma::frames::FramesRequest;
use crate::analysis::run::{AccelInput, Request, TargetsRequest};
use crate::analysis::track_run::Targets;
use crate::analysis::{Axis, DisplacementSettings, Settings, WelchSettings};
use crate::lost_frames::LostFramePolicy;
use std::path::PathBuf;

/// The accelerometer record as given.
#[derive(Debug, Clone, PartialEq)]
pub struct AccelSettings {
    /// `$accel`: the CSV file.
    pub path: PathBuf,
    /// `$fs`: its sample rate, Hz (needed).
    pub fs: Option<f64>,
    /// Column of the FRF input (base acceleration, or a force).
    pub input_col: String,
    /// Column of the output (tip) acceleration.
    pub output_col: String,
    /// Optional time column, s.
    pub time_col: Option<String>,
}

/// The first frame's time after the first accelerometer sample, as given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeOffset {
    /// `$time_offset_s`.
    Seconds(f64),
    /// `$tick_offset` ticks of a `$tick_hz` time base.
    Ticks(i64, f64),
}

/// The bands used with an accelerometer when none are given, Hz (the rigs' two modes).
pub const DEFAULT_ACCEL_BANDS: [(f64, f64); 2] = [(5.0, 15.0), (25.0, 45.0)];

/// `analyze`'s settings as given.
#[derive(Debug, Clone, PartialEq)]
pub struct AnalyzeInput {
    /// The frames.
    pub frames: FramesInput,
    /// The targets and the tracker.
    pub tracking: TrackingInput,
    /// `$mm_per_px` (needed with an accelerometer; without, the analysis stays in pixels).
    pub mm_per_px: Option<f64>,
    /// Static references and the scale from the scene (output-only).
    pub view: super::ViewInput,
    /// `$axis` of the motion.
    pub axis: Axis,
    /// Flip the displacement's sign.
    pub invert: bool,
    /// What a lost frame's value becomes.
    pub lost_frames: LostFramePolicy,
    /// The Welch estimator's settings (sizes resolved against the record).
    pub welch: WelchSettings,
    /// `$bands`, Hz (default with an accelerometer: [`DEFAULT_ACCEL_BANDS`]; without: peaks
    /// picked automatically).
    pub bands: Option<Vec<(f64, f64)>>,
    /// `$accel`: with it, FRFs against the accelerometer; without, output-only.
    pub accel: Option<AccelSettings>,
    /// The frames' time offset (with an accelerometer).
    pub time_offset: Option<TimeOffset>,
    /// `$compensate_exposure` (with an accelerometer).
    pub compensate_exposure: bool,
    /// Subtract the line through the record's ends before the Fourier upsampling.
    pub end_match: bool,
    /// `$accel_target` (with an accelerometer and several targets).
    pub accel_target: Option<usize>,
    /// `$shape_reference` (with an accelerometer and several targets).
    pub shape_reference: Option<PathBuf>,
    /// `$twin` (with an accelerometer and one target): re-render the recording.
    pub twin: Option<crate::analysis::twin::TwinSettings>,
    /// Output directory.
    pub out: PathBuf,
    /// Replace an earlier `analyze` output there.
    pub force: bool,
    /// Also print `report.pdf` (headless Chromium).
    pub pdf: bool,
    /// `$magnify_px` (output-only): each mode's magnified video, 0 none.
    pub magnify_px: f64,
    /// `$geometry`: the structure's nodes and lines the page draws the shapes on (several
    /// targets).
    pub geometry: Option<PathBuf>,
}

/// A checked `analyze` job.
#[derive(Debug, Clone)]
pub enum AnalyzeSpec {
    /// FRFs against an accelerometer.
    Reference(Box<Request>),
    /// Output-only modal analysis of the targets' displacements.
    OutputOnly(Box<FramesRequest>),
}

impl AnalyzeSpec {
    /// Checks `input` at `rates` (from [`crate::frames::resolve_rates`]: `exposure_ms` the
    /// one given, else the file's); reads a points file. Returns the spec and warnings (an
    /// exposure longer than the frame period without compensation; each names settings as
    /// `$key`, spelled for the caller by `SpecError::setting(w).message(naming)`).
    pub fn new(mut input: AnalyzeInput, rates: Rates) -> SpecResult<(Self, Vec<String>)> {
        match input.accel.take() {
            Some(accel) => {
                common(&input, &rates)?;
                with_reference(input, accel, rates)
            }
            None => Self::output_only(input, rates)
                .map(|r| (AnalyzeSpec::OutputOnly(Box::new(r)), Vec::new())),
        }
    }

    /// The output-only request of `input` (Python's `analyze`, which computes without writing);
    /// `input.accel` must be `None`.
    pub fn output_only(input: AnalyzeInput, rates: Rates) -> SpecResult<FramesRequest> {
        if input.accel.is_some() {
            return Err(SpecError::setting(
                "$accel: this call analyses output-only; the analysis with an accelerometer is \
                 AnalyzeSpec::new",
            ));
        }
        common(&input, &rates)?;
        output_only(input, rates)
    }

    /// Runs the job: the report it printed, and whether it succeeded.
    pub fn run(&self) -> anyhow::Result<crate::analysis::run::Outcome> {
        match self {
            AnalyzeSpec::Reference(r) => crate::analysis::run::run(r),
            AnalyzeSpec::OutputOnly(r) => crate::analysis::oma::frames::run(r),
        }
    }
}

/// What both analyses check first: a positive frame rate, ordered bands.
fn common(input: &AnalyzeInput, rates: &Rates) -> SpecResult<()> {
    super::positive("fps", rates.fps, "frames per second")?;
    match &input.bands {
        Some(b) => super::bands_ordered(b),
        None => Ok(()),
    }
}

/// With an accelerometer.
fn with_reference(
    input: AnalyzeInput,
    accel: AccelSettings,
    rates: Rates,
) -> SpecResult<(AnalyzeSpec, Vec<String>)> {
    let fps = rates.fps;
    let fs = accel
        .fs
        .ok_or_else(|| SpecError::setting("$accel needs $fs (its sample rate, Hz)"))?;
    let fs = super::positive("fs", fs, "the accelerometer's sample rate, Hz")?;
    if input.view.has_scale() {
        return Err(SpecError::setting(
            "$scale, $target_size_mm and $world are those of the output-only analysis (and of \
             track) for now; with $accel give $mm_per_px",
        ));
    }
    let mm_per_px = input
        .mm_per_px
        .ok_or_else(|| SpecError::setting("$accel needs $mm_per_px (the scale, mm per pixel)"))?;
    let mm_per_px = super::positive("mm_per_px", mm_per_px, "millimetres per pixel")?;
    let bands = input.bands.unwrap_or_else(|| DEFAULT_ACCEL_BANDS.to_vec());
    let exposure_ms = rates.exposure_ms;
    let warnings = check_exposure(exposure_ms, fps, input.compensate_exposure)?;
    super::bands_below_nyquist(&bands, fps, "the camera's")?;
    let time_offset_s = time_offset_s(input.time_offset, input.frames.frame_range, fps)?;
    let tracking = Tracking::new(input.tracking)?;
    let view = super::view::check(input.view, None, &tracking.targets, tracking.tracker)?;
    let mut targets =
        targets_request(&tracking.targets, input.accel_target, input.shape_reference)?;
    match (&mut targets, view.references.is_some()) {
        (Some(t), _) => t.view = view,
        (None, true) => return Err(SpecError::setting(REFERENCE_NEEDS_TARGETS)),
        (None, false) => {}
    }
    if let Some(t) = &input.twin {
        check_twin(t, targets.is_some(), tracking.points_file.is_some())?;
    }
    let geometry = geometry(input.geometry.as_deref(), &tracking.targets)?;
    let request = Request {
        frames: input.frames.frames,
        retime: input.frames.retime,
        frame_range: input.frames.frame_range,
        accel: AccelInput {
            path: accel.path,
            fs,
            input_col: accel.input_col,
            output_col: accel.output_col,
            time_col: accel.time_col,
        },
        settings: Settings {
            frame_rate_hz: fps,
            accel_rate_hz: fs,
            time_offset_s,
            welch: input.welch,
            bands,
            exposure_s: exposure_ms.map(|e| e / 1000.0),
            end_match: input.end_match,
        },
        displacement: DisplacementSettings {
            lost_frames: input.lost_frames,
            mm_per_px,
            axis: input.axis,
            invert: input.invert,
        },
        binary: tracking.binary(),
        centroid: tracking.centroid,
        compensate_exposure: input.compensate_exposure,
        exposure_ms,
        notes: rates.notes,
        points_file: tracking.points_file,
        targets,
        twin: input.twin,
        out: input.out,
        force: input.force,
        pdf: input.pdf,
        geometry,
    };
    Ok((AnalyzeSpec::Reference(Box::new(request)), warnings))
}

/// `$geometry` read and checked against the targets: a node for each, lines between them.
#[allow(clippy::type_complexity)]
fn geometry(
    path: Option<&std::path::Path>,
    targets: &Targets,
) -> SpecResult<Option<(PathBuf, vibcam_readers::geometry::Geometry)>> {
    if path.is_some() && *targets == Targets::Whole {
        return Err(SpecError::setting(
            "$geometry draws the shapes of several targets: give $targets K or $points",
        ));
    }
    let g = super::read_geometry(path)?;
    crate::analysis::track_run::wire(g.as_ref(), targets.count(), None)
        .map_err(SpecError::Input)?;
    Ok(g)
}

/// References take the camera's motion out of several targets only.
const REFERENCE_NEEDS_TARGETS: &str = "$reference with $accel: the camera's motion is taken out \
     of $targets K or $points (the one target of the frame keeps its own chain)";

/// The time of the first frame analysed after the accelerometer's first sample, s: the offset
/// given (seconds, or ticks of a clock) plus the start of `--frame-range`.
fn time_offset_s(
    offset: Option<TimeOffset>,
    range: Option<crate::frames::FrameRange>,
    fps: f64,
) -> SpecResult<f64> {
    let t = match offset {
        Some(TimeOffset::Seconds(t)) if t.is_finite() => t,
        Some(TimeOffset::Seconds(t)) => {
            return Err(SpecError::setting(format!(
                "$time_offset_s {t}: not a finite time"
            )))
        }
        Some(TimeOffset::Ticks(k, hz)) => crate::analysis::tick_offset_to_seconds(k, hz)?,
        None => 0.0,
    };
    // the time offset is the recording's first frame's; a range starts later in it
    Ok(t + crate::frames::FrameRange::start_s(range, fps))
}

/// The exposure against the frame period: an exposure longer than the period is a warning,
/// and an error when the amplitudes would be divided by its transfer.
fn check_exposure(exposure_ms: Option<f64>, fps: f64, compensate: bool) -> SpecResult<Vec<String>> {
    let Some(e) = exposure_ms else {
        if compensate {
            return Err(SpecError::setting(
                "$compensate_exposure needs the exposure: give $exposure_ms (the frames do not \
                 state it)",
            ));
        }
        return Ok(Vec::new());
    };
    if !(e.is_finite() && e >= 0.0) {
        return Err(SpecError::setting(format!(
            "$exposure_ms must be >= 0, got {e}"
        )));
    }
    let period_ms = 1000.0 / fps;
    if e <= period_ms {
        return Ok(Vec::new());
    }
    let why = format!(
        "$exposure_ms {e} is longer than the frame period ({period_ms:.3} ms at {fps} fps): no \
         camera exposes longer than it records; check $exposure_ms (in ms) and $fps"
    );
    // dividing by the transfer of an impossible exposure would be a wrong number
    if compensate {
        return Err(SpecError::setting(format!(
            "{why}; $compensate_exposure refused"
        )));
    }
    Ok(vec![why])
}

/// `$twin`: runs in range, one target.
fn check_twin(
    t: &crate::analysis::twin::TwinSettings,
    several: bool,
    points: bool,
) -> SpecResult<()> {
    use crate::analysis::twin::MAX_RUNS;
    if !(1..=MAX_RUNS).contains(&t.runs) {
        return Err(SpecError::setting(format!(
            "$twin {}: runs must be 1 to {MAX_RUNS}",
            t.runs
        )));
    }
    if several || points {
        return Err(SpecError::setting(
            "$twin re-renders one target (the whole frame or its ROI); with several targets \
             it is not available yet",
        ));
    }
    Ok(())
}

/// Several targets and what the accelerometer is compared with.
fn targets_request(
    targets: &Targets,
    accel_target: Option<usize>,
    shape_reference: Option<PathBuf>,
) -> SpecResult<Option<TargetsRequest>> {
    if *targets == Targets::Whole {
        if accel_target.is_some() || shape_reference.is_some() {
            return Err(SpecError::setting(
                "$accel_target and $shape_reference need several targets: $targets K or \
                 $points",
            ));
        }
        return Ok(None);
    }
    let k = targets.count();
    let accel_target = accel_target.unwrap_or(k);
    if !(1..=k).contains(&accel_target) {
        return Err(SpecError::setting(format!(
            "$accel_target {accel_target}: targets are numbered 1 to {k}"
        )));
    }
    Ok(Some(TargetsRequest {
        targets: targets.clone(),
        accel_target,
        shape_reference,
        view: Default::default(),
    }))
}

/// Without an accelerometer.
fn output_only(input: AnalyzeInput, rates: Rates) -> SpecResult<FramesRequest> {
    let needs_accel = [
        ("$compensate_exposure", input.compensate_exposure),
        ("$accel_target", input.accel_target.is_some()),
        ("$shape_reference", input.shape_reference.is_some()),
        ("$time_offset_s/$tick_offset", input.time_offset.is_some()),
        ("$twin", input.twin.is_some()),
    ];
    if let Some((flag, _)) = needs_accel.iter().find(|(_, given)| *given) {
        return Err(SpecError::setting(format!(
            "{flag} needs $accel (without it the analysis is output-only)"
        )));
    }
    let bands = input.bands.unwrap_or_default();
    super::bands_below_nyquist(&bands, rates.fps, "the camera's")?;
    vibcam_common::setting::table::number("analyze", "magnify_px", input.magnify_px)?;
    let (tracking, view, scaled) =
        super::view::tracking_and_view(input.tracking, input.view, input.mm_per_px)?;
    let geometry = geometry(input.geometry.as_deref(), &tracking.targets)?;
    Ok(FramesRequest {
        frames: input.frames.frames,
        retime: input.frames.retime,
        frame_range: input.frames.frame_range,
        fps: rates.fps,
        centroid: tracking.centroid,
        displacement: DisplacementSettings {
            lost_frames: input.lost_frames,
            mm_per_px: input.mm_per_px.unwrap_or(1.0),
            axis: input.axis,
            invert: input.invert,
        },
        scaled,
        targets: tracking.targets,
        points_file: tracking.points_file,
        welch: input.welch,
        bands,
        out: input.out,
        force: input.force,
        pdf: input.pdf,
        magnify_px: input.magnify_px,
        notes: rates.notes,
        view,
        geometry,
    })
}
