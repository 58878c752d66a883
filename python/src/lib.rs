//! `vibcam._vibcam`: the native half of the `vibcam` Python package (docs/python.md). Each
//! function is a library call of host-harness or firmware-core with numpy arrays in and out;
//! the Python half (`python/vibcam/__init__.py`) gives them their documented signatures and
//! result types. Every function releases the GIL while it works; errors are Python exceptions
//! carrying the command line's messages: [`InputError`] (a `ValueError`) for the user's input,
//! [`VibcamError`] (a `RuntimeError`) for anything else.

use firmware_core::centroid::{Centroid, Flags};
use host_harness::analysis::oma::frames as oma_frames;
use host_harness::analysis::oma::uncertainty::Interval;
use host_harness::analysis::points::Point;
use host_harness::analysis::{Axis, WelchSettings};
use host_harness::frames::files::{luma, LumaLevel};
use host_harness::frames::{open_frames, FrameRange, FrameSource, GreyFrame};
use host_harness::jobs::{
    AnalyzeInput, AnalyzeSpec, FramesInput, PointsInput, Rates, Threshold, Tracker, Tracking,
    TrackingInput, ViewInput, WorldInput,
};
use host_harness::lost_frames::LostFramePolicy;
use host_harness::setting::{Naming, SpecError};
use numpy::ndarray::{Array2, Array3, ArrayViewD, Axis as NdAxis};
use numpy::{Complex64, IntoPyArray, PyArray1, PyArrayDyn, PyArrayMethods, PyReadonlyArray1};
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::mpsc::{sync_channel, Receiver};
use std::sync::{Arc, Mutex};

create_exception!(
    _vibcam,
    InputError,
    PyValueError,
    "The input was refused (a file, an array, an argument): the message names what and why, \
     as the command line's does."
);
create_exception!(
    _vibcam,
    VibcamError,
    PyRuntimeError,
    "A failure that is not the input's fault (an output that cannot be written, a decoder \
     that failed)."
);

/// An error of the library as the Python exception the command line's exit code stands for;
/// settings named as Python's arguments.
fn py_err(e: anyhow::Error) -> PyErr {
    let msg = host_harness::setting::message(&e, Naming::Python);
    if host_harness::setting::is_bad_input(&e) {
        InputError::new_err(msg)
    } else {
        VibcamError::new_err(msg)
    }
}

/// A text of the library (a report, a page, a note) with the settings it names (`$nperseg`)
/// spelled as Python's arguments.
fn spelled(text: &str) -> String {
    host_harness::setting::spell(text, Naming::Python)
}

/// A refused spec as Python's [`InputError`], naming Python's arguments.
fn spec_err(e: SpecError) -> PyErr {
    py_err(e.into_anyhow())
}

/// An [`InputError`] with `msg`.
fn bad(msg: impl Into<String>) -> PyErr {
    InputError::new_err(msg.into())
}

/// The frames of a numpy array: `(H, W)` one frame, `(N, H, W)` grey frames, `(N, H, W, 3|4)`
/// colour frames (their BT.601 luma, alpha ignored, as the files' reader does); `uint8` or
/// `uint16`.
fn frames_of_array(obj: &Bound<'_, PyAny>) -> PyResult<Vec<GreyFrame>> {
    if let Ok(a) = obj.downcast::<PyArrayDyn<u8>>() {
        let ro = a.readonly();
        return grey_frames(ro.as_array(), |width, height, data| GreyFrame::U8 {
            width,
            height,
            data,
        });
    }
    if let Ok(a) = obj.downcast::<PyArrayDyn<u16>>() {
        let ro = a.readonly();
        return grey_frames(ro.as_array(), |width, height, data| GreyFrame::U16 {
            width,
            height,
            data,
        });
    }
    let dtype = obj
        .getattr("dtype")
        .map(|d| d.to_string())
        .unwrap_or_else(|_| obj.get_type().to_string());
    Err(bad(format!(
        "frames: an array of uint8 or uint16 pixels is needed, got {dtype} (scale and convert \
         it: a float image's levels are not a camera's)"
    )))
}

/// Splits `a` into frames (see [`frames_of_array`]).
fn grey_frames<T: Copy + Into<f64> + LumaLevel>(
    a: ArrayViewD<'_, T>,
    make: impl Fn(usize, usize, Vec<T>) -> GreyFrame,
) -> PyResult<Vec<GreyFrame>> {
    let shape = a.shape().to_vec();
    let (n, h, w, channels) = match shape.as_slice() {
        [h, w] => (1, *h, *w, 1),
        [n, h, w] => (*n, *h, *w, 1),
        [n, h, w, c] if *c == 3 || *c == 4 => (*n, *h, *w, *c),
        _ => {
            return Err(bad(format!(
                "frames: an array of shape (H, W), (N, H, W) or (N, H, W, 3|4) is needed, got \
                 {shape:?}"
            )))
        }
    };
    if n == 0 || h == 0 || w == 0 {
        return Err(bad(format!(
            "frames: the array of shape {shape:?} is empty"
        )));
    }
    let standard = a.as_standard_layout();
    let flat = standard
        .as_slice()
        .ok_or_else(|| VibcamError::new_err("internal: a standard-layout array has no slice"))?;
    let per_frame = h * w * channels;
    Ok(flat
        .chunks_exact(per_frame)
        .map(|f| {
            let data = if channels == 1 {
                f.to_vec()
            } else {
                luma(f, channels)
            };
            make(w, h, data)
        })
        .collect())
}

/// Where frames come from: a path as `--frames` takes it, or an array.
#[derive(Debug)]
enum Frames {
    /// `--frames`.
    Path(String),
    /// In memory.
    Array(Arc<[GreyFrame]>),
}

impl Frames {
    /// The input files for a report's provenance: the path, none for frames in memory.
    fn paths(&self) -> Vec<std::path::PathBuf> {
        match self {
            Frames::Path(p) => vec![p.into()],
            Frames::Array(_) => Vec::new(),
        }
    }
}

/// `frames` as given to a function: a `str` (the Python half turns path-like objects into
/// one) or an array.
fn frames_arg(obj: &Bound<'_, PyAny>) -> PyResult<Frames> {
    if let Ok(s) = obj.extract::<String>() {
        return Ok(Frames::Path(s));
    }
    Ok(Frames::Array(frames_of_array(obj)?.into()))
}

impl Frames {
    /// The source and its frame rate: `fps`, else the rate a camera file states; with `needed`
    /// a rate is required (an error as the command line's when none is known), else a source
    /// that states none is read without one (only a video needs it, to check its timestamps).
    fn resolve(
        self,
        fps: Option<f64>,
        retime: bool,
        needed: bool,
        range: Option<FrameRange>,
    ) -> anyhow::Result<(FrameSource, Rates)> {
        let given = |fps: f64| Rates {
            fps,
            exposure_ms: None,
            notes: Vec::new(),
        };
        match self {
            Frames::Array(a) => {
                let source = FrameSource::Memory(a).ranged(range)?;
                if retime {
                    return Err(host_harness::bad_input(
                        "retime applies to a video file, not to frames in an array",
                    ));
                }
                match fps {
                    Some(f) => {
                        host_harness::setting::positive("fps", f, "frames per second")
                            .map_err(SpecError::into_anyhow)?;
                        Ok((source, given(f)))
                    }
                    None if needed => Err(host_harness::bad_input(
                        "fps is needed: frames in an array state no rate",
                    )),
                    None => Ok((source, given(1.0))),
                }
            }
            Frames::Path(p) => {
                let source = open_frames(&p, retime, range)?.source;
                let unknown = fps.is_none() && source.recorded_rate()?.is_none();
                if unknown && !needed && !matches!(source.inner(), FrameSource::Video { .. }) {
                    return Ok((source, given(1.0)));
                }
                let rates = host_harness::frames::resolve_rates(&p, fps, None, retime, range)?;
                Ok((source, rates))
            }
        }
    }
}

/// The tracker named in Python.
fn tracker_of(tracker: &str) -> PyResult<Tracker> {
    match tracker.to_ascii_lowercase().as_str() {
        "auto" => Ok(Tracker::Auto),
        "binary" | "blob" => Ok(Tracker::Blob),
        "weighted" => Ok(Tracker::Weighted),
        "lk" => Ok(Tracker::Lk),
        _ => Err(bad(format!(
            "tracker `{tracker}`: one of auto, binary (alias blob), weighted, lk"
        ))),
    }
}

/// A region of interest `(x, y, w, h)`.
fn roi_of(roi: Option<(u32, u32, u32, u32)>) -> Option<firmware_core::centroid::Roi> {
    roi.map(|(x, y, width, height)| firmware_core::centroid::Roi {
        x,
        y,
        width,
        height,
    })
}

/// A point given as `(x, y, w, h, threshold, group)` (the Python half fills the optional ones
/// with `None`).
type PointTuple = (f64, f64, u32, u32, Option<u16>, Option<u32>);

/// The Welch settings as the command line's flags name them.
fn welch_settings(
    window: &str,
    nperseg: Option<usize>,
    noverlap: Option<usize>,
    nfft: Option<usize>,
    detrend: &str,
) -> PyResult<WelchSettings> {
    use firmware_core::spectrum::{Detrend, Window};
    Ok(WelchSettings {
        window: match window.to_ascii_lowercase().as_str() {
            "hann" => Window::Hann,
            "hamming" => Window::Hamming,
            "rect" | "boxcar" => Window::Rect,
            w => {
                return Err(bad(format!(
                    "window `{w}`: one of hann, hamming, rect (boxcar)"
                )))
            }
        },
        nperseg,
        noverlap,
        nfft,
        detrend: match detrend.to_ascii_lowercase().as_str() {
            "constant" => Detrend::Constant,
            "none" | "false" => Detrend::None,
            d => return Err(bad(format!("detrend `{d}`: one of constant, none"))),
        },
    })
}

/// The names of the flags set in `f`.
fn flag_names(f: Flags) -> Vec<&'static str> {
    Flags::NAMES
        .iter()
        .filter(|(g, _)| f.contains(*g))
        .map(|(_, n)| *n)
        .collect()
}

/// `centroid(frame, threshold, mode, roi)`: one frame's centroid by firmware-core; returns
/// `(x, y, pixels, flags)`, `x` and `y` NaN when no pixel passed the threshold.
#[pyfunction]
#[pyo3(signature = (frame, threshold, mode="binary", roi=None))]
fn centroid(
    py: Python<'_>,
    frame: &Bound<'_, PyAny>,
    threshold: u16,
    mode: &str,
    roi: Option<(u32, u32, u32, u32)>,
) -> PyResult<(f64, f64, u64, Vec<&'static str>)> {
    let frames = frames_of_array(frame)?;
    let [frame] = frames.as_slice() else {
        return Err(bad(format!(
            "frame: one frame (H, W) or (H, W, 3|4) is needed, got {} frames",
            frames.len()
        )));
    };
    let tracker = tracker_of(mode)?;
    if tracker == Tracker::Lk {
        return Err(bad(
            "mode lk: Lucas-Kanade follows a window through frames (track with points)",
        ));
    }
    let config = host_harness::jobs::tracking::centroid_config(
        Some(Threshold::Level(threshold)),
        tracker,
        roi_of(roi),
        false,
    )
    .map_err(spec_err)?;
    let c: Centroid = py
        .allow_threads(|| frame.centroid(&config, "frame"))
        .map_err(py_err)?;
    let (x, y) = c
        .position()
        .map_or((f64::NAN, f64::NAN), |(x, y)| (f64::from(x), f64::from(y)));
    Ok((x, y, c.moments.pixels, flag_names(c.flags)))
}

/// `region_points(frame, region, spacing, window_px, min_texture, direction)`: the windows a
/// region of `frame` gives (docs/method.md §2.12), as `pick --region` chooses them: the kept
/// centres `(x, y)` and the line saying how many places were kept and why the others were not.
#[pyfunction]
#[pyo3(signature = (frame, region, spacing, window_px, min_texture, direction))]
fn region_points(
    py: Python<'_>,
    frame: &Bound<'_, PyAny>,
    region: &str,
    spacing: f64,
    window_px: usize,
    min_texture: f64,
    direction: &str,
) -> PyResult<(Vec<(f64, f64)>, String)> {
    use host_harness::analysis::region::{select, Direction, Selection, Shape};
    let frames = frames_of_array(frame)?;
    let [frame] = frames.as_slice() else {
        return Err(bad(format!(
            "frame: one frame (H, W) or (H, W, 3|4) is needed, got {} frames",
            frames.len()
        )));
    };
    let sel = Selection {
        shape: Shape::parse(region).map_err(|e| bad(format!("region: {e}")))?,
        spacing,
        window: window_px,
        min_texture,
        direction: Direction::parse(direction).map_err(|e| bad(format!("direction: {e}")))?,
    };
    let found = py.allow_threads(|| select(frame, &sel)).map_err(py_err)?;
    Ok((found.kept(), found.describe(&sel)))
}

/// How the targets are found and followed, as `track` and `analyze` take it (the Python half
/// builds this dict; every key present).
#[derive(Debug, FromPyObject)]
#[pyo3(from_item_all)]
struct TrackingArgs {
    /// Frame rate, Hz (else the file's).
    fps: Option<f64>,
    /// A video's container rate retimed to `fps`.
    retime: bool,
    /// Chosen windows.
    points: Option<Vec<PointTuple>>,
    /// A points CSV file.
    points_file: Option<String>,
    /// The K blobs of the first frame.
    targets: Option<usize>,
    /// With `targets`: the gate, px (default 10).
    gate_px: Option<f64>,
    /// A grey level.
    threshold: Option<u16>,
    /// Otsu's threshold per window.
    auto_threshold: bool,
    /// binary, weighted or lk.
    tracker: String,
    /// With lk: the coarse search range, px.
    search_px: Option<u16>,
    /// `(x, y, w, h)`.
    roi: Option<(u32, u32, u32, u32)>,
}

impl TrackingArgs {
    /// The tracking settings as the library takes them (checked by [`Tracking::new`]).
    fn input(self) -> PyResult<TrackingInput> {
        let points = points_input(self.points, self.points_file, "points")?;
        Ok(TrackingInput {
            threshold: match (self.auto_threshold, self.threshold) {
                (true, _) => Some(Threshold::Auto),
                (false, t) => t.map(Threshold::Level),
            },
            tracker: tracker_of(&self.tracker)?,
            roi: roi_of(self.roi),
            points,
            targets: self.targets,
            gate_px: self.gate_px,
            search_px: self.search_px,
        })
    }
}

/// Windows given as a list or as a file (`what` names them in the error when both are).
fn points_input(
    list: Option<Vec<PointTuple>>,
    file: Option<String>,
    what: &str,
) -> PyResult<Option<PointsInput>> {
    match (list, file) {
        (Some(p), None) => Ok(Some(PointsInput::List(points_of(p)))),
        (None, Some(f)) => Ok(Some(PointsInput::File(f.into()))),
        (None, None) => Ok(None),
        (Some(_), Some(_)) => Err(bad(format!("give {what} or a file, not both"))),
    }
}

/// A point of the structure's plane: `(x, y, x_mm, y_mm, u_px)`.
type WorldTuple = (f64, f64, f64, f64, f64);

/// Windows as the Python half gives them, numbered 1, 2, ... in their order.
fn points_of(p: Vec<PointTuple>) -> Vec<Point> {
    p.into_iter()
        .enumerate()
        .map(|(i, (x, y, w, h, threshold, group))| Point {
            target: i + 1,
            xy: (x, y),
            size: (w, h),
            threshold,
            group,
        })
        .collect()
}

/// The camera's view as `track` and `analyze` take it (the Python half builds this dict;
/// every key present).
#[derive(Debug, FromPyObject)]
#[pyo3(from_item_all)]
struct ViewArgs {
    /// Static references' windows.
    reference: Option<Vec<PointTuple>>,
    /// A references CSV file.
    reference_file: Option<String>,
    /// translation, similarity or homography.
    camera_model: Option<String>,
    /// `(A, B, mm)`.
    scale: Option<(String, String, f64)>,
    /// Each target's diameter, mm.
    target_size_mm: Option<f64>,
    /// `(x, y, x_mm, y_mm, u_px)` points of the plane.
    world: Option<Vec<WorldTuple>>,
    /// A world points CSV file.
    world_file: Option<String>,
}

impl ViewArgs {
    /// The view's settings as the library takes them (checked by the spec).
    fn input(self) -> PyResult<ViewInput> {
        use host_harness::analysis::view::WorldPoint;
        use host_harness::geometry::Model;
        let reference = points_input(self.reference, self.reference_file, "reference points")?;
        let world = match (self.world, self.world_file) {
            (Some(p), None) => Some(WorldInput::List(
                p.into_iter()
                    .map(|(x, y, xm, ym, u)| WorldPoint {
                        px: (x, y),
                        mm: (xm, ym),
                        u_px: u,
                    })
                    .collect(),
            )),
            (None, Some(f)) => Some(WorldInput::File(f.into())),
            (None, None) => None,
            (Some(_), Some(_)) => return Err(bad("give world points or a file, not both")),
        };
        let camera_model = match self.camera_model.as_deref() {
            None => None,
            Some("translation") => Some(Model::Translation),
            Some("similarity") => Some(Model::Similarity),
            Some("homography") => Some(Model::Homography),
            Some(m) => {
                return Err(bad(format!(
                    "camera_model `{m}`: translation, similarity or homography"
                )))
            }
        };
        Ok(ViewInput {
            reference,
            camera_model,
            scale: self.scale,
            target_size_mm: self.target_size_mm,
            world,
        })
    }
}

/// The camera's motion per frame, `(N, 4)`: the image centre's shift x, y (px), the roll
/// (degrees) and the scale; NaN where unknown (empty `(0, 4)` without references).
fn camera_motion_array(v: &host_harness::analysis::view::Viewed) -> Array2<f64> {
    let Some(m) = &v.motion else {
        return Array2::<f64>::zeros((0, 4));
    };
    let n = m.transforms.len();
    let mut a = Array2::<f64>::from_elem((n, 4), f64::NAN);
    for k in 0..n {
        if let Some(r) = m.row(k) {
            a[[k, 0]] = r.dx_px;
            a[[k, 1]] = r.dy_px;
            a[[k, 2]] = r.rotation_deg;
            a[[k, 3]] = r.scale;
        }
    }
    a
}

/// Positions `(N, K, 2)` (NaN where lost) and flags `(N, K)` of `tracks`.
fn positions_of(tracks: &host_harness::analysis::targets::Tracks) -> (Array3<f64>, Array2<u8>) {
    let n = tracks.centroids.first().map_or(0, Vec::len);
    let k = tracks.centroids.len();
    let mut pos = Array3::<f64>::from_elem((n, k, 2), f64::NAN);
    let mut flags = Array2::<u8>::zeros((n, k));
    for (t, cs) in tracks.centroids.iter().enumerate() {
        for (i, c) in cs.iter().enumerate() {
            if let Some((x, y)) = c.position() {
                pos[[i, t, 0]] = f64::from(x);
                pos[[i, t, 1]] = f64::from(y);
            }
            flags[[i, t]] = c.flags.bits();
        }
    }
    (pos, flags)
}

/// Each position's evidence (frame by target): the score against the first frame's template
/// and the forward-backward disagreement (NaN where none), and the check that took it away
/// (`""`: none), row by row.
type EvidenceArrays = (Array2<f64>, Array2<f64>, Vec<String>);

fn evidence_of(tracks: &host_harness::analysis::targets::Tracks) -> EvidenceArrays {
    let n = tracks.centroids.first().map_or(0, Vec::len);
    let k = tracks.centroids.len();
    let mut score = Array2::<f64>::from_elem((n, k), f64::NAN);
    let mut fb = Array2::<f64>::from_elem((n, k), f64::NAN);
    let mut check = vec![String::new(); n * k];
    for (t, ev) in tracks.evidence.iter().enumerate() {
        for (i, e) in ev.iter().enumerate().take(n) {
            score[[i, t]] = e.score.map_or(f64::NAN, f64::from);
            fb[[i, t]] = e.fb_px.map_or(f64::NAN, f64::from);
            check[i * k + t] = e.doubt.map_or("", |d| d.word()).to_string();
        }
    }
    (score, fb, check)
}

/// How a Python call was made, as the package's wrapper states it: the call as written and
/// each keyword (name, value shown, whether it was left at its default).
type Call = Option<(String, Vec<(String, String, bool)>)>;

/// The invocation a report's header names for `call` (not stated without one).
fn invocation(call: Call) -> Option<host_harness::provenance::Invocation> {
    use host_harness::provenance::{Invocation, Setting};
    call.map(|(command, settings)| Invocation {
        command,
        settings: settings
            .into_iter()
            .map(|(name, value, default)| Setting {
                name,
                value,
                default,
            })
            .collect(),
    })
}

/// `job` with `call` stated for the reports it writes (nothing stated without one).
fn stated<T>(call: Call, job: impl FnOnce() -> T) -> T {
    match invocation(call) {
        Some(inv) => host_harness::provenance::with_invocation(inv, job),
        None => job(),
    }
}

/// The report and the page of a job whose inputs are `inputs`, the page opened by their
/// provenance (and the call stated around it), settings spelled Python's way.
fn signed_spelled(
    inputs: &[std::path::PathBuf],
    report: &str,
    page: impl FnOnce(&str) -> host_harness::export::html::Report,
) -> (String, String) {
    let inputs: Vec<&std::path::Path> = inputs.iter().map(|p| p.as_path()).collect();
    let p = host_harness::provenance::Provenance::now(&inputs);
    let html = host_harness::analysis::signed_page(&p, report, page);
    (spelled(report), spelled(&html))
}

/// Which of `words` the argument `name` = `v` is (an error listing them otherwise).
fn choice(name: &str, v: &str, words: &[&str]) -> PyResult<usize> {
    words
        .iter()
        .position(|w| *w == v)
        .ok_or_else(|| bad(format!("{name} `{v}`: {}", words.join(", "))))
}

/// `track(frames, tracking)`: every target's position per frame, `(N, K, 2)` pixels (NaN where
/// lost), and the firmware's flags `(N, K)`; also the frame rate used.
#[pyfunction]
#[pyo3(signature = (frames, tracking, view=None, axis="y", call=None))]
fn track<'py>(
    py: Python<'py>,
    frames: &Bound<'py, PyAny>,
    tracking: TrackingArgs,
    view: Option<ViewArgs>,
    axis: &str,
    call: Call,
) -> PyResult<Bound<'py, PyDict>> {
    let frames = frames_arg(frames)?;
    let (fps, retime) = (tracking.fps, tracking.retime);
    let input = tracking.input()?;
    let view = view.map(ViewArgs::input).transpose()?.unwrap_or_default();
    let axis = match axis {
        "x" => Axis::X,
        "y" => Axis::Y,
        a => return Err(bad(format!("axis `{a}`: x or y"))),
    };
    type Tracked = (
        (Array3<f64>, Array2<u8>),
        Option<Array3<f64>>,
        Array2<f64>,
        Option<Array2<f64>>,
        (String, String, String),
        f64,
        EvidenceArrays,
    );
    let label = match &frames {
        Frames::Path(p) => p.clone(),
        Frames::Array(a) => format!("an array of {} frames", a.len()),
    };
    let inputs = frames.paths();
    let tracked = py
        .allow_threads(|| {
            stated(call, || -> anyhow::Result<Tracked> {
                let (source, rates) = frames.resolve(fps, retime, false, None)?;
                let t = Tracking::new(input).map_err(SpecError::into_anyhow)?;
                let has_scale = view.has_scale();
                let settings = host_harness::jobs::view::check(view, None, &t.targets, t.tracker)
                    .map_err(SpecError::into_anyhow)?;
                let req = track_request(label, (retime, &rates), t, settings, axis);
                let v = host_harness::analysis::track_run::compute(&req, &source)?;
                let o = host_harness::analysis::track_run::outputs(&req, &source, &v)?;
                let (report, html) = signed_spelled(&inputs, &o.report, |r| o.page(r));
                let raw = v.raw.as_ref().map(|r| positions_of(r).0);
                let mm = has_scale.then(|| scaled_displacements(&v, axis));
                Ok((
                    positions_of(&v.tracks),
                    raw,
                    camera_motion_array(&v),
                    mm,
                    (v.describe(axis == Axis::X), report, html),
                    rates.fps,
                    evidence_of(&v.tracks),
                ))
            })
        })
        .map_err(py_err)?;
    let ((positions, flags), raw, camera, mm, (view_report, report, html), fps, evidence) = tracked;
    let d = PyDict::new(py);
    d.set_item("positions", positions.into_pyarray(py))?;
    d.set_item("flags", flags.into_pyarray(py))?;
    d.set_item("fps", fps)?;
    d.set_item("raw_positions", raw.map(|r| r.into_pyarray(py)))?;
    d.set_item("camera_motion", camera.into_pyarray(py))?;
    d.set_item("displacement_mm", mm.map(|m| m.into_pyarray(py)))?;
    d.set_item("view_report", spelled(&view_report))?;
    d.set_item("report", report)?;
    d.set_item("html", html)?;
    let (score, fb, check) = evidence;
    d.set_item("score", score.into_pyarray(py))?;
    d.set_item("fb_px", fb.into_pyarray(py))?;
    d.set_item("check", check)?;
    Ok(d)
}

/// Each target's displacement in the scene's scale (frame by target; a lost frame NaN).
fn scaled_displacements(v: &host_harness::analysis::view::Viewed, axis: Axis) -> Array2<f64> {
    let n = v.tracks.centroids.first().map_or(0, Vec::len);
    let k = v.tracks.centroids.len();
    let mut a = Array2::<f64>::from_elem((n, k), f64::NAN);
    let s = host_harness::chain::displacement::DisplacementSettings {
        lost_frames: LostFramePolicy::Interpolate,
        mm_per_px: 1.0,
        axis,
        invert: false,
    };
    for t in 0..k {
        if let Ok(d) = v.displacement(t, &s) {
            for (i, (x, lost)) in d.mm.iter().zip(&d.lost).enumerate() {
                if !lost {
                    a[[i, t]] = *x;
                }
            }
        }
    }
    a
}

/// The command's own `track` request for Python's arguments: the same tracking, report and
/// page as `track` writes (nothing is written from Python).
fn track_request(
    label: String,
    (retime, rates): (bool, &Rates),
    t: Tracking,
    view: host_harness::analysis::view::ViewSettings,
    axis: Axis,
) -> host_harness::analysis::track_run::Request {
    host_harness::analysis::track_run::Request {
        frames: label,
        retime,
        frame_range: None,
        fps: rates.fps,
        targets: t.targets,
        centroid: t.centroid,
        displacement: None,
        axis,
        plots: true,
        notes: rates.notes.clone(),
        out: std::path::PathBuf::new(),
        force: false,
        pdf: false,
        inputs: t.points_file.into_iter().collect(),
        view,
    }
}

/// `frf(x, y, fs, ...)`: H1 and coherence by firmware-core's Welch estimator; returns
/// `(freq_hz, h1, coherence, segments)`.
#[pyfunction]
#[pyo3(signature = (x, y, fs, window="hann", nperseg=None, noverlap=None, nfft=None,
    detrend="constant"))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn frf<'py>(
    py: Python<'py>,
    x: PyReadonlyArray1<'py, f64>,
    y: PyReadonlyArray1<'py, f64>,
    fs: f64,
    window: &str,
    nperseg: Option<usize>,
    noverlap: Option<usize>,
    nfft: Option<usize>,
    detrend: &str,
) -> PyResult<(
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<Complex64>>,
    Bound<'py, PyArray1<f64>>,
    u32,
)> {
    use host_harness::analysis::Defaults;
    let welch = welch_settings(window, nperseg, noverlap, nfft, detrend)?;
    let (x, y) = (x.as_array().to_vec(), y.as_array().to_vec());
    if !(fs.is_finite() && fs > 0.0) {
        return Err(bad(format!("fs must be a positive rate, got {fs}")));
    }
    if x.len() != y.len() {
        return Err(bad(format!(
            "x has {} samples and y {}: the two channels must have one length",
            x.len(),
            y.len()
        )));
    }
    for (name, v) in [("x", &x), ("y", &y)] {
        if let Some((i, v)) = v.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(bad(format!("{name}[{i}] is {v}, not a finite number")));
        }
    }
    let frf = py
        .allow_threads(|| -> anyhow::Result<_> {
            host_harness::analysis::check_channel(&x, "x")?;
            host_harness::analysis::check_channel(&y, "y")?;
            let config = welch.resolve(x.len(), fs, Defaults::Scipy)?;
            host_harness::chain::frf::estimate(&x, &y, config)
        })
        .map_err(py_err)?;
    Ok((
        frf.freq_hz.into_pyarray(py),
        frf.h1.into_pyarray(py),
        frf.coherence.into_pyarray(py),
        frf.segments,
    ))
}

/// `upsample(x, from_hz, to_hz)`: firmware-core's Fourier upsampler (`len(x) * to / from`
/// samples, periodic record).
#[pyfunction]
fn upsample<'py>(
    py: Python<'py>,
    x: PyReadonlyArray1<'py, f64>,
    from_hz: f64,
    to_hz: f64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    for (name, hz) in [("from_hz", from_hz), ("to_hz", to_hz)] {
        if !(hz.is_finite() && hz > 0.0) {
            return Err(bad(format!(
                "{name}: must be a positive sample rate in Hz, got {hz}"
            )));
        }
    }
    let x = x.as_array().to_vec();
    if let Some((i, v)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(bad(format!("x[{i}] is {v}, not a finite number")));
    }
    let up = py
        .allow_threads(|| host_harness::chain::resample::upsample_column(&x, from_hz, to_hz))
        .map_err(py_err)?;
    let v: Vec<f64> = up.values.iter().map(|v| f64::from(*v) * up.scale).collect();
    Ok(v.into_pyarray(py))
}

/// `analyze(...)`: the frames' targets tracked and analysed output-only (FDD, EFDD, SSI-cov)
/// as `analyze` without `--accel`; returns a dict of arrays (the Python half's
/// `AnalysisResult`).
#[pyfunction]
#[pyo3(signature = (frames, tracking, mm_per_px=None, axis="y", invert=false,
    lost_frames="interpolate", window="hann", nperseg=None, noverlap=None, nfft=None,
    detrend="constant", bands=None, view=None, geometry=None, magnify=None, call=None))]
#[allow(clippy::too_many_arguments)]
fn analyze<'py>(
    py: Python<'py>,
    frames: &Bound<'py, PyAny>,
    tracking: TrackingArgs,
    mm_per_px: Option<f64>,
    axis: &str,
    invert: bool,
    lost_frames: &str,
    window: &str,
    nperseg: Option<usize>,
    noverlap: Option<usize>,
    nfft: Option<usize>,
    detrend: &str,
    bands: Option<Vec<(f64, f64)>>,
    view: Option<ViewArgs>,
    geometry: Option<String>,
    magnify: Option<(String, f64)>,
    call: Call,
) -> PyResult<Bound<'py, PyDict>> {
    let frames = frames_arg(frames)?;
    let (fps, retime) = (tracking.fps, tracking.retime);
    let input = AnalyzeInput {
        view: view.map(ViewArgs::input).transpose()?.unwrap_or_default(),
        frames: FramesInput {
            frames: String::new(),
            retime: false,
            frame_range: None,
        },
        tracking: tracking.input()?,
        mm_per_px,
        axis: match axis {
            "x" => Axis::X,
            "y" => Axis::Y,
            a => return Err(bad(format!("axis `{a}`: x or y"))),
        },
        invert,
        lost_frames: match lost_frames {
            "interpolate" => LostFramePolicy::Interpolate,
            "hold" => LostFramePolicy::Hold,
            p => return Err(bad(format!("lost_frames `{p}`: interpolate or hold"))),
        },
        welch: welch_settings(window, nperseg, noverlap, nfft, detrend)?,
        bands,
        accel: None,
        time_offset: None,
        compensate_exposure: false,
        end_match: true,
        accel_target: None,
        shape_reference: None,
        twin: None,
        out: std::path::PathBuf::new(),
        force: false,
        pdf: false,
        magnify_px: magnify.as_ref().map_or(0.0, |m| m.1),
        geometry: geometry.clone().map(std::path::PathBuf::from),
    };
    let mut inputs = frames.paths();
    inputs.extend(geometry.map(std::path::PathBuf::from));
    let computed = py
        .allow_threads(|| {
            stated(call, || -> anyhow::Result<_> {
                let (source, rates) = frames.resolve(fps, retime, true, None)?;
                let fps = rates.fps;
                let req = AnalyzeSpec::output_only(input, rates).map_err(SpecError::into_anyhow)?;
                let c = oma_frames::compute(&req, &source)?;
                let dir = magnify.as_ref().map(|m| std::path::PathBuf::from(&m.0));
                let (report, html, videos) =
                    analyze_page(&c, &req, &source, (&inputs, dir.as_deref()))?;
                Ok((c, report, fps, html, videos))
            })
        })
        .map_err(py_err)?;
    let (c, report, fps, html, videos) = computed;
    let d = analysis_dict(py, (c, report, fps))?;
    d.set_item("html", html)?;
    d.set_item("videos", videos)?;
    Ok(d)
}

/// The report and the page of `analyze` without an accelerometer, as the command writes them
/// (its figures drawn in memory, the same SVGs embedded; opened by the provenance of
/// `inputs`; settings spelled Python's way), with each mode's magnified video written into
/// `magnify_dir` when given (created; the files written returned).
fn analyze_page(
    c: &oma_frames::Computed,
    req: &oma_frames::FramesRequest,
    source: &host_harness::frames::FrameSource,
    (inputs, magnify_dir): (&[std::path::PathBuf], Option<&std::path::Path>),
) -> anyhow::Result<(String, String, Vec<std::path::PathBuf>)> {
    use host_harness::analysis::oma::{magnified, run};
    let along_x = req.displacement.axis == Axis::X;
    let report = run::report(
        &c.result,
        &c.records,
        &c.settings,
        &c.viewed.describe(along_x),
    );
    let first = source.frame_at(req.fps, 0).ok().flatten().map(|(_, f)| f);
    let frame = first.as_ref().and_then(|f| f.to_image().ok());
    let (videos, text, files) = match (magnify_dir, first) {
        (Some(dir), Some(frame)) if req.magnify_px > 0.0 => {
            std::fs::create_dir_all(dir)
                .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", dir.display()))?;
            let points: Vec<Option<(f64, f64)>> = c.records.targets.iter().map(|t| t.1).collect();
            let m = magnified::Magnify {
                px: req.magnify_px,
                frame,
                along_x,
            };
            magnified::write_videos(dir, &c.result, &points, &m)
        }
        _ => (Vec::new(), String::new(), Vec::new()),
    };
    let report = format!("{report}{text}");
    let figures = run::figures(&c.result, &c.settings)?;
    let wire = oma_frames::wire(req, c)?;
    let (report, html) = signed_spelled(inputs, &report, |report| {
        run::page(
            &c.result,
            &c.records,
            ("analyze", along_x),
            (
                frame,
                host_harness::analysis::view::reference_markers(&c.viewed),
                host_harness::analysis::track_run::scrubber(source, req.fps, &c.viewed),
            ),
            (host_harness::plots::page_figures(&figures), wire),
            report,
        )
        .with_videos(videos)
    });
    Ok((report, html, files))
}

/// The dict `analyze` returns.
fn analysis_dict<'py>(
    py: Python<'py>,
    (c, report, fps): (oma_frames::Computed, String, f64),
) -> PyResult<Bound<'py, PyDict>> {
    let d = oma_dict(py, &c.result, &c.records)?;
    let (disp, lost) = displacement_arrays(&c);
    d.set_item("displacement", disp.into_pyarray(py))?;
    d.set_item("lost", lost.into_pyarray(py))?;
    d.set_item(
        "camera_motion",
        camera_motion_array(&c.viewed).into_pyarray(py),
    )?;
    d.set_item("report", spelled(&report))?;
    d.set_item("fps", fps)?;
    Ok(d)
}

/// The entries of an output-only analysis's dict that come from its result `r` and the
/// records it analysed: modes, shapes and their uncertainty, targets, the singular values,
/// unit, targets left out, notes, rejected peaks and clusters, evidence.
fn oma_dict<'py>(
    py: Python<'py>,
    r: &host_harness::analysis::oma::OmaResult,
    records: &host_harness::analysis::oma::input::Records,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("modes", modes_dict(py, r)?)?;
    let k = records.targets.len();
    let mut shapes = Array2::<Complex64>::zeros((r.modes.len(), k));
    for (i, m) in r.modes.iter().enumerate() {
        for (j, s) in m.shape.iter().enumerate().take(k) {
            shapes[[i, j]] = *s;
        }
    }
    d.set_item("shapes", shapes.into_pyarray(py))?;
    // the standard uncertainty of each shape component's magnitude (NaN where not estimated)
    let mut abs_u = Array2::<f64>::from_elem((r.modes.len(), k), f64::NAN);
    for (i, m) in r.modes.iter().enumerate() {
        if let Some(u) = &m.uncertainty.shape_abs {
            for (j, v) in u.iter().enumerate().take(k) {
                abs_u[[i, j]] = *v;
            }
        }
    }
    d.set_item("shapes_abs_u", abs_u.into_pyarray(py))?;
    d.set_item(
        "targets",
        records
            .targets
            .iter()
            .map(|(t, _)| *t as i64)
            .collect::<Vec<_>>()
            .into_pyarray(py),
    )?;
    let mut xy = Array2::<f64>::from_elem((k, 2), f64::NAN);
    for (j, (_, p)) in records.targets.iter().enumerate() {
        if let Some((x, y)) = p {
            xy[[j, 0]] = *x;
            xy[[j, 1]] = *y;
        }
    }
    d.set_item("first_xy", xy.into_pyarray(py))?;
    let lines = r.svd.freq_hz.len();
    let kk = r.svd.s.first().map_or(0, Vec::len);
    let mut s = Array2::<f64>::zeros((lines, kk));
    for (i, row) in r.svd.s.iter().enumerate() {
        for (j, v) in row.iter().enumerate().take(kk) {
            s[[i, j]] = *v;
        }
    }
    d.set_item("svd_freq_hz", r.svd.freq_hz.clone().into_pyarray(py))?;
    d.set_item("svd", s.into_pyarray(py))?;
    d.set_item("unit", records.unit.clone())?;
    d.set_item("left_out", records.left_out.clone())?;
    d.set_item(
        "notes",
        r.notes.iter().map(|n| spelled(n)).collect::<Vec<_>>(),
    )?;
    d.set_item("rejected", r.rejected.clone())?;
    d.set_item(
        "evidence",
        r.modes
            .iter()
            .map(|m| m.evidence.clone())
            .collect::<Vec<_>>(),
    )?;
    Ok(d)
}

/// The modes as a dict of columns (`method`, `mode`, `band_lo_hz`, `band_hi_hz`, `f_hz`,
/// `amplitude`, `damping`, and `f_hz_u`, `f_hz_lo`, `f_hz_hi` and the same of `damping` and
/// `amplitude`; NaN where a method gives none).
fn modes_dict<'py>(
    py: Python<'py>,
    r: &host_harness::analysis::oma::OmaResult,
) -> PyResult<Bound<'py, PyDict>> {
    let modes = PyDict::new(py);
    let col = |f: &dyn Fn(&host_harness::analysis::oma::OmaMode) -> f64| -> Vec<f64> {
        r.modes.iter().map(f).collect()
    };
    modes.set_item(
        "method",
        r.modes.iter().map(|m| m.method.name()).collect::<Vec<_>>(),
    )?;
    set_numbers(py, &modes, r.modes.iter().map(|m| m.mode))?;
    let nan = f64::NAN;
    for (name, v) in [
        ("band_lo_hz", col(&|m| m.band_hz.map_or(nan, |b| b.0))),
        ("band_hi_hz", col(&|m| m.band_hz.map_or(nan, |b| b.1))),
        ("f_hz", col(&|m| m.f_hz)),
        ("amplitude", col(&|m| m.amplitude.unwrap_or(nan))),
        ("damping", col(&|m| m.damping.unwrap_or(nan))),
    ] {
        modes.set_item(name, v.into_pyarray(py))?;
    }
    // each estimate's standard uncertainty and 95 % interval (NaN where not estimated)
    type Pick = fn(&host_harness::analysis::oma::OmaMode) -> Option<Interval>;
    let quantities: [(&str, Pick); 3] = [
        ("f_hz", |m| m.uncertainty.f_hz),
        ("damping", |m| m.uncertainty.damping),
        ("amplitude", |m| m.uncertainty.amplitude),
    ];
    for (name, pick) in quantities {
        set_intervals(py, &modes, name, r.modes.iter().map(pick))?;
    }
    Ok(modes)
}

/// The column `mode` of a table of modes: the numbers `modes`.
fn set_numbers(
    py: Python<'_>,
    d: &Bound<'_, PyDict>,
    modes: impl Iterator<Item = usize>,
) -> PyResult<()> {
    let v: Vec<i64> = modes.map(|m| m as i64).collect();
    d.set_item("mode", v.into_pyarray(py))
}

/// The columns `{name}_u`, `{name}_lo` and `{name}_hi` of a table of modes: each estimate's
/// standard uncertainty and 95 % interval (NaN where not estimated).
fn set_intervals(
    py: Python<'_>,
    d: &Bound<'_, PyDict>,
    name: &str,
    intervals: impl Iterator<Item = Option<Interval>>,
) -> PyResult<()> {
    let cells: Vec<[f64; 3]> = intervals
        .map(|i| i.map_or([f64::NAN; 3], |i| [i.u, i.lo, i.hi]))
        .collect();
    for (k, suffix) in ["u", "lo", "hi"].iter().enumerate() {
        let v: Vec<f64> = cells.iter().map(|c| c[k]).collect();
        d.set_item(format!("{name}_{suffix}"), v.into_pyarray(py))?;
    }
    Ok(())
}

/// Each target's displacement `(N, K)` (NaN for a target left out) and lost flags.
fn displacement_arrays(c: &oma_frames::Computed) -> (Array2<f64>, Array2<bool>) {
    let nan = f64::NAN;
    let n = c.lost.first().map_or(0, Vec::len);
    let all = c.displacement.len();
    let mut disp = Array2::<f64>::from_elem((n, all), nan);
    let mut lost = Array2::<bool>::from_elem((n, all), false);
    for (t, (dv, l)) in c.displacement.iter().zip(&c.lost).enumerate() {
        if let Some(dv) = dv {
            disp.index_axis_mut(NdAxis(1), t)
                .iter_mut()
                .zip(dv)
                .for_each(|(o, v)| *o = *v);
        }
        lost.index_axis_mut(NdAxis(1), t)
            .iter_mut()
            .zip(l)
            .for_each(|(o, v)| *o = *v);
    }
    (disp, lost)
}

/// `study(...)`: a Monte Carlo study run (or resumed) in `out`; returns the printed table and
/// `summary.csv`'s text.
#[pyfunction]
#[pyo3(signature = (out, config=None, preset=None, runs=None, exposures_ms=None, seed=None,
    threads=0, progress=true, plots=false))]
#[allow(clippy::too_many_arguments)]
fn study(
    py: Python<'_>,
    out: String,
    config: Option<String>,
    preset: Option<String>,
    runs: Option<u64>,
    exposures_ms: Option<Vec<f64>>,
    seed: Option<u64>,
    threads: usize,
    progress: bool,
    plots: bool,
) -> PyResult<(String, String)> {
    use host_harness::study::{self as st, Execution, Preset, Shard, StudyConfig};
    if config.is_some() && preset.is_some() {
        return Err(bad("give a config file or a preset, not both"));
    }
    let preset = match preset.as_deref() {
        None | Some("grandstand") => Preset::Grandstand,
        Some("cantilever") => Preset::Cantilever,
        Some(p) => return Err(bad(format!("preset `{p}`: grandstand or cantilever"))),
    };
    py.allow_threads(|| -> anyhow::Result<(String, String)> {
        let mut cfg = match &config {
            Some(p) => StudyConfig::from_toml_file(std::path::Path::new(p))?,
            None => StudyConfig::preset(preset),
        };
        if let Some(r) = runs {
            cfg.runs = r;
        }
        if let Some(e) = exposures_ms {
            cfg.exposures_ms = e;
        }
        if let Some(s) = seed {
            cfg.seed = s;
        }
        cfg.validate()?;
        let scenario = st::scenario_for(&cfg)?;
        let out = std::path::PathBuf::from(out);
        let exec = Execution {
            out: out.clone(),
            resume: true,
            threads,
            shard: Shard::ALL,
            progress,
        };
        let done = st::execute(&cfg, scenario.as_ref(), &exec)?;
        let table = st::finish(&cfg, scenario.as_ref(), &done.records, &out, plots)?;
        let summary = std::fs::read_to_string(out.join(st::files::SUMMARY))
            .map_err(|e| anyhow::anyhow!("{}: {e}", out.join(st::files::SUMMARY).display()))?;
        Ok((table, summary))
    })
    .map_err(py_err)
}

/// `modal(...)`: output-only modal analysis of a displacement file (or of several setups), as
/// `host-harness modal`; returns the dict `analyze` returns (without the camera's motion and
/// the lost flags: `filled` counts each column's filled samples), its `displacement` the
/// records analysed (with `setups`, one column per global point) and `setups` each setup's
/// part in each mode PoSER merged. With `out` the command's files are
/// written there too.
#[pyfunction]
#[pyo3(signature = (displacement, fps=None, axis="y", window="hann", nperseg=None,
    noverlap=None, nfft=None, detrend="constant", bands=None, prominence_db=6.0, f_min_hz=None,
    efdd_quantity="auto", plscf=false, ssi="cov", ssi_block_rows=None, ssi_max_order=None,
    references=None, setups=Vec::new(), merge="poser", out=None, force=false, poles=None,
    pdf=false, geometry=None, call=None))]
#[allow(clippy::too_many_arguments)]
fn modal<'py>(
    py: Python<'py>,
    displacement: String,
    fps: Option<f64>,
    axis: &str,
    window: &str,
    nperseg: Option<usize>,
    noverlap: Option<usize>,
    nfft: Option<usize>,
    detrend: &str,
    bands: Option<Vec<(f64, f64)>>,
    prominence_db: f64,
    f_min_hz: Option<f64>,
    efdd_quantity: &str,
    plscf: bool,
    ssi: &str,
    ssi_block_rows: Option<usize>,
    ssi_max_order: Option<usize>,
    references: Option<Vec<usize>>,
    setups: Vec<(String, Vec<usize>)>,
    merge: &str,
    out: Option<String>,
    force: bool,
    poles: Option<String>,
    pdf: bool,
    geometry: Option<String>,
    call: Call,
) -> PyResult<Bound<'py, PyDict>> {
    use host_harness::analysis::oma::{bell::Quantity, input::PixelAxis};
    use host_harness::analysis::oma::{multi_setup::Merge, ssi::SsiKind};
    use host_harness::jobs::{ModalInput, ModalSpec};
    let write = out.is_some();
    let input = ModalInput {
        displacement: displacement.into(),
        fps,
        axis: [PixelAxis::Y, PixelAxis::X][choice("axis", axis, &["y", "x"])?],
        welch: welch_settings(window, nperseg, noverlap, nfft, detrend)?,
        bands,
        prominence_db,
        f_min_hz,
        efdd_quantity: [
            None,
            Some(Quantity::Displacement),
            Some(Quantity::Velocity),
            Some(Quantity::Acceleration),
        ][choice(
            "efdd_quantity",
            efdd_quantity,
            &["auto", "displacement", "velocity", "acceleration"],
        )?],
        plscf,
        poles: poles.map(std::path::PathBuf::from),
        ssi: [SsiKind::Cov, SsiKind::Dat][choice("ssi", ssi, &["cov", "dat"])?],
        ssi_block_rows,
        ssi_max_order,
        references,
        setups: setups.into_iter().map(|(f, t)| (f.into(), t)).collect(),
        merge: [Merge::Poser, Merge::Preger][choice("merge", merge, &["poser", "preger"])?],
        out: out.map(std::path::PathBuf::from).unwrap_or_default(),
        force,
        plots: write,
        pdf,
        geometry: geometry.map(std::path::PathBuf::from),
    };
    let (c, report, html) = py
        .allow_threads(|| {
            stated(call, || -> anyhow::Result<_> {
                let spec = ModalSpec::new(input).map_err(SpecError::into_anyhow)?;
                let c = spec.compute()?;
                if write {
                    spec.write(&c)?;
                }
                let (report, html) = spec.report_and_page(&c)?;
                Ok((c, report, html))
            })
        })
        .map_err(py_err)?;
    modal_dict(py, &c, &report, &html)
}

/// The dict `modal` returns: [`oma_dict`]'s entries, the records as `displacement`, the filled
/// samples' counts, the report and page, the sample rate and the setups' rows.
fn modal_dict<'py>(
    py: Python<'py>,
    c: &host_harness::jobs::ModalComputed,
    report: &str,
    html: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let d = oma_dict(py, &c.result, &c.records)?;
    let n = c.records.channels.first().map_or(0, Vec::len);
    let k = c.records.channels.len();
    let mut disp = Array2::<f64>::zeros((n, k));
    for (j, ch) in c.records.channels.iter().enumerate() {
        disp.index_axis_mut(NdAxis(1), j)
            .iter_mut()
            .zip(ch)
            .for_each(|(o, v)| *o = *v);
    }
    d.set_item("displacement", disp.into_pyarray(py))?;
    // a displacement file says how many samples of each target were filled, not which
    d.set_item("filled", c.records.filled.clone())?;
    d.set_item("report", spelled(report))?;
    d.set_item("html", spelled(html))?;
    d.set_item("fps", c.records.fs_hz)?;
    let rows: Vec<Bound<'py, PyDict>> = c
        .setups
        .iter()
        .flat_map(|(_, rows)| rows)
        .map(|r| -> PyResult<_> {
            let row = PyDict::new(py);
            row.set_item("method", r.method)?;
            row.set_item("mode", r.mode)?;
            row.set_item("setup", r.setup)?;
            row.set_item("f_hz", r.f_hz)?;
            row.set_item("damping", r.damping)?;
            row.set_item("scale", (r.scale.re, r.scale.im))?;
            row.set_item("reference_mac", r.reference_mac)?;
            Ok(row)
        })
        .collect::<PyResult<_>>()?;
    d.set_item("setups", rows)?;
    Ok(d)
}

/// `ema(...)`: experimental modal analysis of responses over a measured force, as
/// `host-harness ema`; returns a dict of arrays (the Python half's `EmaResult`). With `out`
/// the command's files are written there too.
#[pyfunction]
#[pyo3(signature = (response, excitation, roving=Vec::new(), response_cols=Vec::new(), response_fs=None,
    excitation_col=Vec::new(), excitation_fs=None, impact=false, exp_window="auto", block_s=None,
    delay_s=None, response_quantity="displacement", bands=None, f_min_hz=None, f_max_hz=None,
    max_order=48, nperseg=None, out=None, force=false, poles=None, pdf=false, geometry=None,
    call=None))]
#[allow(clippy::too_many_arguments)]
fn ema<'py>(
    py: Python<'py>,
    response: String,
    excitation: String,
    roving: Vec<(usize, String, String)>,
    response_cols: Vec<String>,
    response_fs: Option<f64>,
    excitation_col: Vec<String>,
    excitation_fs: Option<f64>,
    impact: bool,
    exp_window: &str,
    block_s: Option<f64>,
    delay_s: Option<f64>,
    response_quantity: &str,
    bands: Option<Vec<(f64, f64)>>,
    f_min_hz: Option<f64>,
    f_max_hz: Option<f64>,
    max_order: usize,
    nperseg: Option<usize>,
    out: Option<String>,
    force: bool,
    poles: Option<String>,
    pdf: bool,
    geometry: Option<String>,
    call: Call,
) -> PyResult<Bound<'py, PyDict>> {
    use host_harness::jobs::EmaInput;
    let (exp, form) = ema_choices(exp_window, response_quantity)?;
    let write = out.is_some();
    let input = EmaInput {
        response: response.into(),
        response_cols,
        response_fs,
        excitation: excitation.into(),
        roving: roving
            .into_iter()
            .map(
                |(point, response, excitation)| host_harness::jobs::RovingRecord {
                    point,
                    response: response.into(),
                    excitation: excitation.into(),
                },
            )
            .collect(),
        excitation_cols: excitation_col,
        excitation_fs,
        impact,
        exp_window: exp,
        block_s,
        delay_s,
        form,
        bands,
        f_min_hz,
        f_max_hz,
        poles: poles.map(std::path::PathBuf::from),
        max_order,
        nperseg,
        out: out.map(std::path::PathBuf::from).unwrap_or_default(),
        force,
        plots: write,
        pdf,
        geometry: geometry.map(std::path::PathBuf::from),
    };
    let done = py
        .allow_threads(|| stated(call, || ema_computed(input, write)))
        .map_err(py_err)?;
    ema_dict(py, done)
}

/// What `ema` computed: the result, the report and the page (each setting spelled for
/// Python), the responses' names and the points the shapes stand at.
struct EmaDone {
    r: host_harness::analysis::ema::EmaResult,
    report: String,
    html: String,
    names: Vec<String>,
    points: Vec<usize>,
}

/// `ema`'s job of `input` run (its files written too with `write`) and its page built.
fn ema_computed(input: host_harness::jobs::EmaInput, write: bool) -> anyhow::Result<EmaDone> {
    use host_harness::analysis::ema::run;
    let spec = host_harness::jobs::EmaSpec::new(input).map_err(SpecError::into_anyhow)?;
    if write {
        spec.run()?;
    }
    let (r, report) = spec.compute()?;
    // the command's page, its figures drawn in memory
    let figures = run::figures(spec.request(), &r)?;
    let (report, html) = signed_spelled(&spec.request().inputs, &report, |report| {
        run::page(
            spec.request(),
            &r,
            report,
            host_harness::plots::page_figures(&figures),
        )
    });
    let points = (0..r.modes.first().map_or(0, |m| m.shape.len()))
        .map(|i| run::shape_at(spec.request(), &r, i))
        .collect();
    Ok(EmaDone {
        names: spec.request().response.names.clone(),
        points,
        r,
        report,
        html,
    })
}

/// The dict `ema` returns: modes, shapes, spectra, notes, the hits left out, the report and
/// the page.
fn ema_dict(py: Python<'_>, done: EmaDone) -> PyResult<Bound<'_, PyDict>> {
    let EmaDone {
        r,
        report,
        html,
        names,
        points,
    } = done;
    let r = &r;
    let d = PyDict::new(py);
    d.set_item("modes", ema_modes(py, r)?)?;
    let (shapes, abs_u) = ema_shapes(r, points.len().max(names.len()));
    d.set_item("shape_points", points)?;
    d.set_item("shapes", shapes.into_pyarray(py))?;
    d.set_item("shapes_abs_u", abs_u.into_pyarray(py))?;
    d.set_item("responses", names)?;
    d.set_item("freq_hz", r.freq_hz.clone().into_pyarray(py))?;
    ema_spectra(py, r, &d)?;
    d.set_item(
        "notes",
        r.notes.iter().map(|n| spelled(n)).collect::<Vec<_>>(),
    )?;
    d.set_item(
        "hits_left_out",
        r.hits
            .as_ref()
            .map(|h| {
                h.hits
                    .iter()
                    .filter_map(|x| x.left_out.clone())
                    .collect::<Vec<_>>()
            })
            .unwrap_or_default(),
    )?;
    d.set_item("report", spelled(&report))?;
    d.set_item("html", spelled(&html))?;
    Ok(d)
}

/// `exp_window` and `response_quantity` as the library's choices.
fn ema_choices(
    exp_window: &str,
    response_quantity: &str,
) -> PyResult<(
    host_harness::analysis::ema::ExpChoice,
    host_harness::analysis::modal::FrfForm,
)> {
    use host_harness::analysis::ema::ExpChoice;
    use host_harness::analysis::modal::FrfForm;
    let exp = match exp_window {
        "off" => ExpChoice::Off,
        "auto" => ExpChoice::Auto,
        v => ExpChoice::End(v.parse::<f64>().map_err(|_| {
            bad(format!(
                "exp_window `{v}`: \"off\", \"auto\" or the window's value at the block's end"
            ))
        })?),
    };
    let form = match response_quantity {
        "displacement" => FrfForm::Receptance,
        "velocity" => FrfForm::Mobility,
        "acceleration" => FrfForm::Accelerance,
        q => {
            return Err(bad(format!(
                "response_quantity `{q}`: displacement, velocity or acceleration"
            )))
        }
    };
    Ok((exp, form))
}

/// The modes' columns: number, frequency, damping, band, and each interval's u, lo and hi.
fn ema_modes<'py>(
    py: Python<'py>,
    r: &host_harness::analysis::ema::EmaResult,
) -> PyResult<Bound<'py, PyDict>> {
    let modes = PyDict::new(py);
    let col = |f: &dyn Fn(&host_harness::analysis::ema::EmaMode) -> f64| -> Vec<f64> {
        r.modes.iter().map(f).collect()
    };
    set_numbers(py, &modes, r.modes.iter().map(|m| m.mode))?;
    modes.set_item("f_hz", col(&|m| m.pole.f_hz).into_pyarray(py))?;
    modes.set_item("damping", col(&|m| m.pole.damping).into_pyarray(py))?;
    modes.set_item(
        "band_lo_hz",
        col(&|m| m.band_hz.map_or(f64::NAN, |b| b.0)).into_pyarray(py),
    )?;
    modes.set_item(
        "band_hi_hz",
        col(&|m| m.band_hz.map_or(f64::NAN, |b| b.1)).into_pyarray(py),
    )?;
    set_intervals(py, &modes, "f_hz", r.modes.iter().map(|m| m.f_interval))?;
    set_intervals(
        py,
        &modes,
        "damping",
        r.modes.iter().map(|m| m.damping_interval),
    )?;
    Ok(modes)
}

/// Each mode's shape over its `k` points (responses, or a roving hammer's hit points), and its
/// modulus's standard uncertainty.
fn ema_shapes(
    r: &host_harness::analysis::ema::EmaResult,
    k: usize,
) -> (Array2<Complex64>, Array2<f64>) {
    let n = r.modes.len();
    let mut shapes = Array2::<Complex64>::zeros((n, k));
    let mut abs_u = Array2::<f64>::from_elem((n, k), f64::NAN);
    for (i, m) in r.modes.iter().enumerate() {
        for (j, v) in m.shape.iter().enumerate().take(k) {
            shapes[[i, j]] = *v;
        }
        if let Some(u) = &m.shape_abs_u {
            for (j, v) in u.iter().enumerate().take(k) {
                abs_u[[i, j]] = *v;
            }
        }
    }
    (shapes, abs_u)
}

/// H1, H2 and the coherence per response and line, into `d`.
fn ema_spectra(
    py: Python<'_>,
    r: &host_harness::analysis::ema::EmaResult,
    d: &Bound<'_, PyDict>,
) -> PyResult<()> {
    let lines = r.freq_hz.len();
    let matrix = |rows: &[Vec<Complex64>]| {
        let mut a = Array2::<Complex64>::zeros((rows.len(), lines));
        for (o, row) in rows.iter().enumerate() {
            for (l, v) in row.iter().enumerate() {
                a[[o, l]] = *v;
            }
        }
        a
    };
    d.set_item("h1", matrix(&r.frfs.h1).into_pyarray(py))?;
    d.set_item("h2", matrix(&r.frfs.h2).into_pyarray(py))?;
    let mut coh = Array2::<f64>::zeros((r.frfs.coherence.len(), lines));
    for (o, row) in r.frfs.coherence.iter().enumerate() {
        for (l, v) in row.iter().enumerate() {
            coh[[o, l]] = *v;
        }
    }
    d.set_item("coherence", coh.into_pyarray(py))?;
    Ok(())
}

/// What the decoder thread of a [`FrameReader`] sends: a labelled frame, or its error (whether
/// it is the input's fault, and the message).
type Decoded = Receiver<Result<(String, GreyFrame), (bool, String)>>;

/// Frames of a recording one at a time (`open_frames`): decoded on a thread of their own, two
/// frames ahead, handed over as numpy arrays without a copy.
#[pyclass(module = "vibcam._vibcam")]
#[derive(Debug)]
struct FrameReader {
    /// The decoder's frames, or its error (`None` once done or closed).
    rx: Mutex<Option<Decoded>>,
    /// The frame rate (`fps`, or the file's), Hz; `None` when neither states one.
    #[pyo3(get)]
    fps: Option<f64>,
    /// Frames in the recording when known before decoding.
    #[pyo3(get)]
    count: Option<usize>,
    /// The label of the frame last returned (file, page or frame number).
    #[pyo3(get)]
    label: Option<String>,
}

#[pymethods]
impl FrameReader {
    #[new]
    #[pyo3(signature = (path, fps=None, retime=false, frame_range=None))]
    fn new(
        py: Python<'_>,
        path: String,
        fps: Option<f64>,
        retime: bool,
        frame_range: Option<String>,
    ) -> PyResult<Self> {
        let range = frame_range
            .map(|r| FrameRange::parse(&r).map_err(|e| bad(format!("frame_range {e}"))))
            .transpose()?;
        let (source, rate, count) = py
            .allow_threads(|| -> anyhow::Result<_> {
                let (source, rates) = Frames::Path(path).resolve(fps, retime, false, range)?;
                let rate = rates.fps;
                let stated = fps.is_some() || source.recorded_rate()?.is_some();
                let count = source.count(rate)?;
                Ok((source, stated.then_some(rate), count))
            })
            .map_err(py_err)?;
        let (tx, rx) = sync_channel(2);
        std::thread::spawn(move || {
            let r = source.for_each(rate.unwrap_or(1.0), |label, frame| {
                tx.send(Ok((label, frame.clone())))
                    .map_err(|_| anyhow::anyhow!("the reader was closed"))
            });
            if let Err(e) = r {
                let bad = e.chain().any(|c| c.is::<host_harness::BadInput>());
                let _ = tx.send(Err((bad, format!("{e:#}"))));
            }
        });
        Ok(FrameReader {
            rx: Mutex::new(Some(rx)),
            fps: rate,
            count,
            label: None,
        })
    }

    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__<'py>(&mut self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let taken = self.rx.lock().ok().and_then(|mut r| r.take());
        let Some(rx) = taken else {
            return Ok(None);
        };
        let (rx, got) = py.allow_threads(move || {
            let got = rx.recv();
            (rx, got)
        });
        let (label, frame) = match got {
            Err(_) => return Ok(None),
            Ok(Err((bad_input, msg))) => {
                return Err(if bad_input {
                    InputError::new_err(msg)
                } else {
                    VibcamError::new_err(msg)
                });
            }
            Ok(Ok(f)) => f,
        };
        if let Ok(mut r) = self.rx.lock() {
            *r = Some(rx);
        }
        self.label = Some(label);
        let a = match frame {
            GreyFrame::U8 {
                width,
                height,
                data,
            } => data.into_pyarray(py).reshape([height, width])?.into_any(),
            GreyFrame::U16 {
                width,
                height,
                data,
            } => data.into_pyarray(py).reshape([height, width])?.into_any(),
        };
        Ok(Some(a))
    }

    /// Stops decoding (the decoder thread ends at its next frame).
    fn close(&mut self) {
        if let Ok(mut r) = self.rx.lock() {
            *r = None;
        }
    }
}

/// Flag bits and names, as the `flags` column of the command line's outputs names them.
fn flag_table() -> Vec<(u8, &'static str)> {
    Flags::NAMES.iter().map(|(f, n)| (f.bits(), *n)).collect()
}

/// The settings table (`vibcam-common`'s `setting::table`) as Python checks its arguments by
/// it: one dict per row (`key`, `commands`, `kind`, `choices`, `words`, `min`, `max`,
/// `min_open`, `max_open`, `range`, `unit`, `default`, `given`, `help`).
fn settings_table(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    use host_harness::setting::table::{Bound as End, DefaultValue, Values, SETTINGS};
    let end = |b: End| match b {
        End::Free => (None, false),
        End::Closed(v) => (Some(v), false),
        End::Open(v) => (Some(v), true),
    };
    SETTINGS
        .iter()
        .map(|s| {
            let d = PyDict::new(py);
            d.set_item("key", s.key)?;
            d.set_item("commands", s.commands.to_vec())?;
            let (kind, choices, (min, min_open), (max, max_open)) = match s.values {
                Values::Switch => ("switch", &[][..], (None, false), (None, false)),
                Values::Path => ("path", &[][..], (None, false), (None, false)),
                Values::Text(_) => ("text", &[][..], (None, false), (None, false)),
                Values::Choice(c) => ("choice", c, (None, false), (None, false)),
                Values::Whole { min, max } => (
                    "whole",
                    &[][..],
                    (Some(min as f64), false),
                    (Some(max as f64), false),
                ),
                Values::Number { min, max } => ("number", &[][..], end(min), end(max)),
            };
            d.set_item("kind", kind)?;
            d.set_item("choices", choices.to_vec())?;
            d.set_item("words", s.words.to_vec())?;
            d.set_item("min", min)?;
            d.set_item("min_open", min_open)?;
            d.set_item("max", max)?;
            d.set_item("max_open", max_open)?;
            d.set_item("range", s.range())?;
            d.set_item("unit", s.unit)?;
            let (default, given) = match s.default {
                DefaultValue::None => (None, false),
                DefaultValue::Given(v) => (Some(v), true),
                DefaultValue::Job(v) => (Some(v), false),
            };
            d.set_item("default", default)?;
            d.set_item("given", given)?;
            d.set_item("help", s.help_for(Naming::Python))?;
            Ok(d)
        })
        .collect()
}

/// The native module.
#[pymodule]
fn _vibcam(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("InputError", m.py().get_type::<InputError>())?;
    m.add("VibcamError", m.py().get_type::<VibcamError>())?;
    m.add("FLAGS", flag_table())?;
    m.add("MODEL_REVISION", host_harness::study::MODEL_REVISION)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("MAX_TARGETS", host_harness::jobs::tracking::MAX_TARGETS)?;
    m.add("SETTINGS", settings_table(m.py())?)?;
    m.add_function(wrap_pyfunction!(centroid, m)?)?;
    m.add_function(wrap_pyfunction!(region_points, m)?)?;
    m.add_function(wrap_pyfunction!(track, m)?)?;
    m.add_function(wrap_pyfunction!(frf, m)?)?;
    m.add_function(wrap_pyfunction!(upsample, m)?)?;
    m.add_function(wrap_pyfunction!(analyze, m)?)?;
    m.add_function(wrap_pyfunction!(ema, m)?)?;
    m.add_function(wrap_pyfunction!(modal, m)?)?;
    m.add_function(wrap_pyfunction!(study, m)?)?;
    m.add_class::<FrameReader>()?;
    Ok(())
}
