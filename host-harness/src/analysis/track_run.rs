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
    /// Also print `report.pdf`.
    pub pdf: bool,
    /// Input files besides the frames (the points file).
    pub inputs: Vec<PathBuf>,
    /// Static references and the scale from the scene.
    pub view: super::view::ViewSettings,
}

/// Runs `track`: the targets tracked in the camera's view, then every output written; returns
/// the report (also written to `report.txt`).
pub fn run(req: &Request) -> anyhow::Result<String> {
    // the output directory is checked before the frames are read (a refusal costs nothing)
    let inputs = req.all_inputs();
    let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    let out = Staged::new(&req.out, req.force, "track", &inputs)?;
    let source = crate::frames::open_frames(&req.frames, req.retime, req.frame_range)?.source;
    let viewed = compute(req, &source)?;
    let o = outputs(req, &source, &viewed)?;
    write(out, o, req.pdf)
}

/// The targets tracked in the camera's view of `source`; a record where no target has a
/// position is refused.
pub fn compute(
    req: &Request,
    source: &crate::frames::FrameSource,
) -> anyhow::Result<super::view::Viewed> {
    let viewed = super::view::track_view(
        source,
        req.fps,
        &req.centroid,
        &req.targets,
        &req.view,
        req.axis == super::Axis::X,
    )?;
    refuse_nothing_measured(&viewed.tracks)?;
    Ok(viewed)
}

impl Request {
    /// The frames and every other input file (points, references, world points).
    fn all_inputs(&self) -> Vec<PathBuf> {
        let mut inputs = vec![PathBuf::from(&self.frames)];
        inputs.extend(self.inputs.iter().cloned());
        inputs.extend(self.view.inputs());
        inputs
    }
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

/// Everything `track` writes, in memory: `displacement.csv`, the camera's motion, the figures,
/// the report (settings named by key) and what `report.html` shows ([`Outputs::page`]).
#[derive(Debug)]
pub struct Outputs {
    /// `displacement.csv`.
    pub displacement_csv: Vec<u8>,
    /// `camera_motion.csv`, its figure and its report line.
    pub camera: super::view::CameraOutputs,
    /// `tracks.png`/`.svg` (with `plots`).
    pub tracks_figure: Option<crate::plots::Figure>,
    /// The report's text.
    pub report: String,
    /// The page's title, the first frame, the targets' and the references' markers.
    title: String,
    frame: Option<crate::export::html::FrameImage>,
    markers: Vec<crate::export::html::Marker>,
    references: Vec<crate::export::html::ReferenceMarker>,
    scrub: Option<crate::export::scrub::Scrubber>,
}

impl Outputs {
    /// `report.html` with the report `text` as written (its settings spelled for the reader).
    pub fn page(&self, text: &str) -> crate::export::html::Report {
        use crate::export::html::Report;
        let figures: Vec<crate::plots::Figure> = self
            .tracks_figure
            .iter()
            .chain(&self.camera.figure)
            .cloned()
            .collect();
        Report {
            title: self.title.clone(),
            frame: self.frame.clone(),
            markers: self.markers.clone(),
            references: self.references.clone(),
            scrub: self.scrub.clone(),
            direction: (0.0, -1.0),
            figures: crate::plots::page_figures(&figures),
            text: text.to_string(),
            ..Report::default()
        }
    }
}

/// Every output of `track` for the tracks in `viewed`, computed in memory (the command's
/// writer and Python's `track` both take them from here).
pub fn outputs(
    req: &Request,
    source: &crate::frames::FrameSource,
    viewed: &super::view::Viewed,
) -> anyhow::Result<Outputs> {
    let along_x = req.axis == super::Axis::X;
    let (tracks, windows) = (&viewed.tracks, viewed.windows.as_ref());
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
            evidence: tracks.evidence.get(t).map(Vec::as_slice),
        })
        .collect();
    let start_s = crate::frames::FrameRange::start_s(req.frame_range, req.fps);
    let displacement_csv = displacement_csv(&rows, req.fps, start_s);
    let mut report = report(req, tracks, windows, &failures);
    report.push_str(&viewed.describe(along_x));
    let camera = super::view::camera_outputs(viewed, req.fps, req.plots)?;
    report.push_str(&camera.text);
    let tracks_figure = if req.plots {
        let f = plot(tracks, req.fps, start_s, along_x)?;
        let _ = writeln!(report, "plots: {0}.png, {0}.svg", f.name);
        Some(f)
    } else {
        None
    };
    let frame = source
        .frame_at(req.fps, 0)
        .ok()
        .flatten()
        .and_then(|(_, f)| f.to_image().ok());
    Ok(Outputs {
        displacement_csv,
        camera,
        tracks_figure,
        report,
        title: format!("track: {}", req.frames),
        frame,
        markers: markers(tracks, windows),
        references: super::view::reference_markers(viewed),
        scrub: scrubber(source, req.fps, viewed),
    })
}

/// Writes the outputs of `track` into the staged directory `out` (with `pdf`, `report.pdf`
/// too) and commits it; returns the report as written.
fn write(out: Staged, o: Outputs, pdf: bool) -> anyhow::Result<String> {
    out.write("displacement.csv", &o.displacement_csv)?;
    o.camera.write_staged(&out)?;
    if let Some(f) = &o.tracks_figure {
        f.write_staged(&out)?;
    }
    let report = super::write_report(&out, &o.report, pdf, |report| o.page(report))?;
    out.commit()?;
    Ok(report)
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
    let k = tracks.centroids.len();
    let shown = shown_tracks(k);
    let series: Vec<(String, Vec<f64>, Vec<f64>)> = shown
        .iter()
        .map(|&t| (t, &tracks.centroids[t]))
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
    let axis = if along_x {
        "x - x(first frame), image x right"
    } else {
        "y - y(first frame), image y down"
    };
    let title = if shown.len() < k {
        format!(
            "Tracks of {} of {k} targets (evenly by number): {axis}",
            shown.len()
        )
    } else {
        format!("Tracks: {axis}")
    };
    crate::plots::lines_figure("tracks", &title, "px", &curves, crate::plots::Lines::Tracks)
}

/// The most targets the tracks' figure draws: a dense field's hundreds of curves hide each
/// other (and took a tenth of `track`'s time to draw); `displacement.csv` has them all.
const TRACKS_SHOWN: usize = 48;

/// Which of `k` targets the tracks' figure draws: all, or [`TRACKS_SHOWN`] evenly spread by
/// number from the first to the last.
fn shown_tracks(k: usize) -> Vec<usize> {
    if k <= TRACKS_SHOWN {
        return (0..k).collect();
    }
    (0..TRACKS_SHOWN)
        .map(|i| i * (k - 1) / (TRACKS_SHOWN - 1))
        .collect()
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

/// The lines `report.html` draws the shapes of the `k` targets with: `$geometry`'s when given,
/// else the groups tracking followed targets in ([`PointsInfo::groups`]), else none said.
pub fn wire(
    geometry: Option<&(std::path::PathBuf, vibcam_readers::geometry::Geometry)>,
    k: usize,
    windows: Option<&PointsInfo>,
) -> anyhow::Result<crate::export::wire::Wire> {
    let points: Vec<usize> = (1..=k).collect();
    let groups: Option<Vec<Vec<usize>>> = windows.and_then(|w| w.groups.as_ref()).map(|g| {
        g.groups
            .iter()
            .map(|grp| grp.iter().map(|t| t + 1).collect())
            .collect()
    });
    crate::export::wire::Wire::on(geometry, &points, "target", groups.as_deref())
}

/// The most frames the scrubber spreads through the record, and the most first frames of a
/// loss it adds.
const SCRUB_SPREAD: usize = 16;
const SCRUB_LOSSES: usize = 8;
/// The longer side of a scrubber frame's image, px.
const SCRUB_SIDE: u32 = 480;

/// The frames of `report.html`'s scrubber: 16 (`SCRUB_SPREAD`) spread through the record and the
/// first frame of up to 8 (`SCRUB_LOSSES`) losses, each target where the tracker put it in the
/// image (before the camera's motion is removed) or lost with its reason; `None` when the
/// frames cannot be read again (the page then has no scrubber).
pub fn scrubber(
    source: &crate::frames::FrameSource,
    fps: f64,
    viewed: &super::view::Viewed,
) -> Option<crate::export::scrub::Scrubber> {
    use crate::export::scrub::{ScrubFrame, Scrubber};
    let tracks = viewed.raw.as_ref().unwrap_or(&viewed.tracks);
    let n = tracks.centroids.first().map_or(0, Vec::len);
    if n == 0 {
        return None;
    }
    let mut wanted: Vec<usize> = (0..SCRUB_SPREAD.min(n))
        .map(|i| i * (n - 1) / (SCRUB_SPREAD.min(n) - 1).max(1))
        .collect();
    let mut losses: Vec<usize> = (1..n)
        .filter(|&f| {
            tracks
                .centroids
                .iter()
                .any(|c| c[f].position().is_none() && c[f - 1].position().is_some())
        })
        .collect();
    losses.truncate(SCRUB_LOSSES);
    wanted.extend(losses);
    wanted.sort_unstable();
    wanted.dedup();
    let frames = source.frames_at(fps, &wanted).ok()?;
    let (w, h) = frames.first()?.1.dimensions();
    let why = |t: usize, f: usize| -> String {
        let c = &tracks.centroids[t][f];
        if c.position().is_some() {
            return String::new();
        }
        let checked = viewed.tracks.evidence.get(t).and_then(|e| e.get(f)?.doubt);
        match checked {
            Some(d) => format!("{} check", d.word()),
            None => {
                let words = crate::chain::displacement::lost_flags(std::slice::from_ref(c));
                words.trim_start_matches("1 ").to_string()
            }
        }
    };
    let scrub_frames = frames
        .iter()
        .map(|(f, frame)| {
            Some(ScrubFrame {
                index: *f,
                png: frame.to_image_within(SCRUB_SIDE).ok()?.png,
                positions: tracks
                    .centroids
                    .iter()
                    .map(|c| c[*f].position().map(|(x, y)| (f64::from(x), f64::from(y))))
                    .collect(),
                why: (0..tracks.centroids.len()).map(|t| why(t, *f)).collect(),
            })
        })
        .collect::<Option<Vec<_>>>()?;
    let windows = viewed.windows.as_ref();
    Some(Scrubber {
        size: (w as u32, h as u32),
        targets: (0..tracks.centroids.len())
            .map(|t| {
                let size = windows
                    .and_then(|w| w.sizes.get(t))
                    .map_or((15.0, 15.0), |(a, b)| (f64::from(*a), f64::from(*b)));
                (t + 1, size)
            })
            .collect(),
        first: tracks.first.clone(),
        frames: scrub_frames,
        scores: viewed
            .tracks
            .evidence
            .iter()
            .map(|e| e.iter().map(|e| e.score).collect())
            .collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tracks_figure_draws_every_target_or_an_even_spread_with_both_ends() {
        assert_eq!(shown_tracks(3), vec![0, 1, 2]);
        assert_eq!(shown_tracks(TRACKS_SHOWN).len(), TRACKS_SHOWN);
        for k in [TRACKS_SHOWN + 1, 100, 768, 5000] {
            let s = shown_tracks(k);
            assert_eq!(s.len(), TRACKS_SHOWN);
            assert_eq!((s[0], s[TRACKS_SHOWN - 1]), (0, k - 1));
            assert!(s.windows(2).all(|w| w[0] < w[1]), "{k}: {s:?}");
        }
    }
}
