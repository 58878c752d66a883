//! `track` as one library call: frames in, each target's position per frame out
//! (`displacement.csv`, `report.txt`, `tracks.png`/`.svg`), no accelerometer needed. The targets
//! are chosen points (`--points`, [`super::points`]) or the K blobs of the first frame
//! (`--targets`, [`super::targets::track`]), exactly as `analyze` follows them.

pub use super::follow::{track_targets, Targets};
use super::points::PointsInfo;
use super::targets::Tracks;
use super::DisplacementSettings;
use crate::export::targets::{displacement_csv, Track};
use crate::outdir::Staged;
use firmware_core::centroid::CentroidConfig;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A checked `track` request.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// `--frames` as given.
    pub frames: String,
    /// `--retime`: the frame rate retimes a video's container rate (slow motion).
    pub retime: bool,
    /// Frames A..B only (`--frame-range`).
    pub frame_range: Option<crate::frames::FrameRange>,
    /// Frame rate, Hz.
    pub fps: f64,
    /// The targets.
    pub targets: Targets,
    /// The centroid's settings (mode, saturation; the threshold of `--targets`).
    pub centroid: CentroidConfig,
    /// Pixels to millimetres, axis and sign, when a scale was given.
    pub displacement: Option<DisplacementSettings>,
    /// The image axis of the motion (`--axis`), with or without a scale: the one the report
    /// and the plots follow.
    pub axis: super::Axis,
    /// Draw the tracks.
    pub plots: bool,
    /// Remarks for the report.
    pub notes: Vec<String>,
    /// Output directory, and whether an earlier `track` output may be replaced.
    pub out: PathBuf,
    /// `--force`.
    pub force: bool,
    /// Input files besides the frames (the points file).
    pub inputs: Vec<PathBuf>,
    /// Static references and the scale from the scene.
    pub view: super::view::ViewSettings,
}

/// Runs `track`: the targets tracked in the camera's view, then every output written; returns
/// the report (also written to `report.txt`).
pub fn run(req: &Request) -> anyhow::Result<String> {
    let source = crate::frames::open_frames(&req.frames, req.retime, req.frame_range)?.source;
    let along_x = req.axis == super::Axis::X;
    let viewed = super::view::track_view(
        &source,
        req.fps,
        &req.centroid,
        &req.targets,
        &req.view,
        along_x,
    )?;
    refuse_nothing_measured(&viewed.tracks)?;
    write(req, &source, &viewed)
}

/// Nothing measured is the user's to fix, as `analyze` says it: exit 2, and why each target
/// was lost.
fn refuse_nothing_measured(tracks: &Tracks) -> anyhow::Result<()> {
    if tracks
        .centroids
        .iter()
        .all(|c| c.iter().all(|c| c.position().is_none()))
    {
        let why: Vec<String> = tracks
            .centroids
            .iter()
            .enumerate()
            .map(|(t, c)| {
                format!(
                    "target {}: {}",
                    t + 1,
                    crate::chain::displacement::why_lost(c)
                )
            })
            .collect();
        return Err(crate::bad_input(format!(
            "no target has a position in any of the frames ({})",
            why.join("; ")
        )));
    }
    Ok(())
}

/// Writes every output of `track` into the staged directory and commits it.
fn write(
    req: &Request,
    source: &crate::frames::FrameSource,
    viewed: &super::view::Viewed,
) -> anyhow::Result<String> {
    let along_x = req.axis == super::Axis::X;
    let (tracks, windows) = (&viewed.tracks, viewed.windows.as_ref());
    let mut inputs: Vec<&Path> = vec![Path::new(req.frames.as_str())];
    inputs.extend(req.inputs.iter().map(PathBuf::as_path));
    let view_inputs = req.view.inputs();
    inputs.extend(view_inputs.iter().map(PathBuf::as_path));
    let out = Staged::new(&req.out, req.force, "track", &inputs)?;
    let (mm, failures) = displacements(viewed, req.displacement.as_ref());
    let rows: Vec<Track<'_>> = tracks
        .centroids
        .iter()
        .zip(&mm)
        .enumerate()
        .map(|(t, (c, m))| Track {
            centroids: c,
            mm: m.as_ref().map(|d| d.0.as_slice()),
            lost: m.as_ref().map(|d| d.1.as_slice()),
            raw: viewed.raw.as_ref().map(|r| r.centroids[t].as_slice()),
        })
        .collect();
    out.write(
        "displacement.csv",
        displacement_csv(
            &rows,
            req.fps,
            crate::frames::FrameRange::start_s(req.frame_range, req.fps),
        ),
    )?;
    let mut report = report(req, tracks, windows, &failures);
    report.push_str(&viewed.describe(along_x));
    let (camera, camera_figure) =
        super::view::write_camera_outputs(&out, viewed, req.fps, req.plots)?;
    report.push_str(&camera);
    let mut figures = Vec::new();
    if req.plots {
        let f = plot(
            tracks,
            req.fps,
            crate::frames::FrameRange::start_s(req.frame_range, req.fps),
            along_x,
        )?;
        f.write_staged(&out)?;
        let _ = writeln!(report, "plots: {0}.png, {0}.svg", f.name);
        figures.push(f);
    }
    figures.extend(camera_figure);
    let frame = source
        .frame_at(req.fps, 0)
        .ok()
        .flatten()
        .and_then(|(_, f)| f.to_image().ok());
    let report = super::write_report(&out, &report, |report| {
        page(
            req,
            (tracks, windows, super::view::reference_markers(viewed)),
            frame,
            report,
            &figures,
        )
    })?;
    out.commit()?;
    Ok(report)
}

/// `report.html` of `track`: the first frame with each target's window, number and lost
/// frames; the tracks' figure; the report.
fn page(
    req: &Request,
    (tracks, windows, references): (
        &Tracks,
        Option<&PointsInfo>,
        Vec<crate::export::html::ReferenceMarker>,
    ),
    frame: Option<crate::export::html::FrameImage>,
    text: &str,
    figures: &[crate::plots::Figure],
) -> String {
    use crate::export::html::{report_html, Report};
    let markers = markers(tracks, windows);
    let figures = crate::plots::page_figures(figures);
    report_html(&Report {
        title: format!("track: {}", req.frames),
        frame,
        markers,
        references,
        direction: (0.0, -1.0),
        figures,
        text: text.to_string(),
        ..Report::default()
    })
}

/// Each target's displacement (mm, lost frames filled by the policy) and lost flags when a
/// scale was given; a target with too many lost frames gets none, and the reason.
#[allow(clippy::type_complexity)]
fn displacements(
    viewed: &super::view::Viewed,
    settings: Option<&DisplacementSettings>,
) -> (Vec<Option<(Vec<f64>, Vec<bool>)>>, Vec<String>) {
    let mut failures = Vec::new();
    let mm = (0..viewed.tracks.centroids.len())
        .map(|t| {
            let s = settings?;
            match viewed.displacement(t, s) {
                Ok(d) => Some((d.mm, d.lost)),
                Err(e) => {
                    failures.push(format!("target {}: {e:#}", t + 1));
                    None
                }
            }
        })
        .collect();
    (mm, failures)
}

fn report(
    req: &Request,
    tracks: &Tracks,
    windows: Option<&PointsInfo>,
    failures: &[String],
) -> String {
    let frames = tracks.centroids.first().map_or(0, Vec::len);
    let mut s = format!(
        "track: {} ({frames} frames at {} fps, {}), {} target(s)\n",
        req.frames,
        req.fps,
        tracks.depth.describe(),
        tracks.centroids.len()
    );
    for n in &req.notes {
        let _ = writeln!(s, "note: {n}");
    }
    match windows {
        Some(w) => s.push_str(&super::points::windows_report(w, tracks)),
        None => {
            for (t, c) in tracks.centroids.iter().enumerate() {
                let lost = c.iter().filter(|c| c.position().is_none()).count();
                let _ = writeln!(
                    s,
                    "  target {}: first seen at ({:.2}, {:.2}) px, {lost} of {frames} frames \
                     lost ({} refused as implausible)",
                    t + 1,
                    tracks.first[t].0,
                    tracks.first[t].1,
                    tracks.refused[t]
                );
            }
        }
    }
    if req.displacement.is_none() {
        s.push_str("disp_mm: empty (no scale: $mm_per_px, $scale, $target_size_mm or $world)\n");
    }
    for f in failures {
        let _ = writeln!(s, "no displacement for {f}");
    }
    let mut any = false;
    for (t, c) in tracks.centroids.iter().enumerate() {
        if c.iter().any(|c| c.position().is_none()) {
            let why = crate::chain::displacement::lost_flags(c);
            let _ = writeln!(s, "target {} lost frames: {why}", t + 1);
            any = true;
        }
    }
    if any {
        let legend: Vec<String> = crate::chain::displacement::LOST_REASONS
            .iter()
            .map(|(_, name, what)| format!("{name}: {what}"))
            .collect();
        let _ = writeln!(s, "({})", legend.join("; "));
    }
    s
}

/// Each target's motion from its first position along the image's y (or x), px, against time.
fn plot(
    tracks: &Tracks,
    fps: f64,
    start_s: f64,
    along_x: bool,
) -> anyhow::Result<crate::plots::Figure> {
    let series: Vec<(String, Vec<f64>, Vec<f64>)> = tracks
        .centroids
        .iter()
        .enumerate()
        .map(|(t, c)| {
            let (x0, y0) = tracks.first[t];
            let (mut ts, mut d) = (Vec::new(), Vec::new());
            for (k, c) in c.iter().enumerate() {
                if let Some((x, y)) = c.position() {
                    ts.push(start_s + k as f64 / fps);
                    d.push(if along_x {
                        f64::from(x) - x0
                    } else {
                        f64::from(y) - y0
                    });
                }
            }
            (format!("target {}", t + 1), ts, d)
        })
        .collect();
    let curves: Vec<(&str, &[f64], &[f64])> = series
        .iter()
        .map(|(l, t, d)| (l.as_str(), t.as_slice(), d.as_slice()))
        .collect();
    crate::plots::tracks_figure(
        "tracks",
        if along_x {
            "Tracks: x - x(first frame), image x right"
        } else {
            "Tracks: y - y(first frame), image y down"
        },
        "px",
        &curves,
    )
}

/// The targets for `report.html`: first positions, windows (chosen points) and lost frames.
pub fn markers(tracks: &Tracks, windows: Option<&PointsInfo>) -> Vec<crate::export::html::Marker> {
    tracks
        .first
        .iter()
        .enumerate()
        .map(|(t, xy)| crate::export::html::Marker {
            target: t + 1,
            xy: *xy,
            window: windows
                .and_then(|w| w.sizes.get(t))
                .map(|(w, h)| (f64::from(*w), f64::from(*h))),
            lost: tracks.centroids[t]
                .iter()
                .filter(|c| c.position().is_none())
                .count(),
        })
        .collect()
}
