//! The camera's view of the targets: its own motion, removed with static references
//! ([`crate::camera_motion`]), and the scale from what the scene shows (docs/method.md §3.14):
//! one `mm_per_px` given, the known distance between two tracked points (`--scale A,B,MM`),
//! each target's known size (`--target-size-mm`), or the structure's plane from four or more
//! points of known coordinates (`--world`: a homography, each target converted with its own
//! local scale and direction). Each scale comes with its standard uncertainty from the
//! positions it came from.

use crate::camera_motion::CameraMotion;
use crate::follow::{track_targets, Targets};
use crate::points::{Point, PointTracker, PointsInfo};
use crate::tracks::Tracks;
use firmware_core::centroid::{Centroid, CentroidConfig};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use vibcam_chain::displacement::{displacement_mm, Displacement, DisplacementSettings};
use vibcam_common::evidence::Doubt;
use vibcam_common::geometry::{fit, Homography, Model};
use vibcam_readers::bad_input;
use vibcam_readers::frames::FrameSource;

/// Static references and the model of the camera's motion.
#[derive(Debug, Clone, PartialEq)]
pub struct References {
    /// The references' windows (numbered r1, r2, ... in the file's order of `target`).
    pub points: Vec<Point>,
    /// The model asked for (`None`: a similarity with two references or more).
    pub model: Option<Model>,
    /// The file they came from (an input).
    pub file: Option<PathBuf>,
}

/// A tracked point a scale is measured between: a target or a reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PointRef {
    /// Target `k` (1-based).
    Target(usize),
    /// Reference `k` (1-based, `rK`).
    Reference(usize),
}

impl PointRef {
    /// Parses `K` (a target) or `rK` (a reference).
    pub fn parse(s: &str) -> Option<PointRef> {
        let s = s.trim();
        match s.strip_prefix(['r', 'R']) {
            Some(k) => k.parse().ok().filter(|k| *k > 0).map(PointRef::Reference),
            None => s.parse().ok().filter(|k| *k > 0).map(PointRef::Target),
        }
    }

    fn label(self) -> String {
        match self {
            PointRef::Target(k) => format!("target {k}"),
            PointRef::Reference(k) => format!("reference r{k}"),
        }
    }
}

/// One point of the structure's plane: where it is in the image and in the plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldPoint {
    /// Image position, px.
    pub px: (f64, f64),
    /// Plane position, mm.
    pub mm: (f64, f64),
    /// Standard uncertainty of the image position, px.
    pub u_px: f64,
}

/// A world point's image position uncertainty when the file does not give one, px (a point
/// picked by hand).
pub const DEFAULT_WORLD_U_PX: f64 = 0.5;
/// Monte Carlo draws of the plane's homography for each target's scale uncertainty.
const WORLD_DRAWS: usize = 400;

/// The scale as given (checked: one of these).
#[derive(Debug, Clone, PartialEq)]
pub enum ScaleInput {
    /// One `mm_per_px` for the whole frame.
    PerPx(f64),
    /// The known distance between two tracked points, mm.
    Between(PointRef, PointRef, f64),
    /// Each target's known diameter, mm (a centroid tracker: the blob's area gives its size).
    TargetSize(f64),
    /// Points of the structure's plane and the file they came from.
    World(Vec<WorldPoint>, Option<PathBuf>),
}

/// What is asked of the view besides the targets.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ViewSettings {
    /// Static references (`--reference`).
    pub references: Option<References>,
    /// The scale (`None`: pixels).
    pub scale: Option<ScaleInput>,
}

impl ViewSettings {
    /// Input files read besides the frames.
    pub fn inputs(&self) -> Vec<PathBuf> {
        let mut v: Vec<PathBuf> = Vec::new();
        if let Some(f) = self.references.as_ref().and_then(|r| r.file.clone()) {
            v.push(f);
        }
        if let Some(ScaleInput::World(_, Some(f))) = &self.scale {
            v.push(f.clone());
        }
        v
    }
}

/// Reads `--world POINTS.csv`: `x,y,x_mm,y_mm[,u_px]` (image px, plane mm, the image
/// position's standard uncertainty); errors name the file and row.
pub fn read_world(path: &Path) -> anyhow::Result<Vec<WorldPoint>> {
    let name = path.display().to_string();
    let (mut rdr, header) = vibcam_readers::csvio::open_with_header(path, &name, false)?;
    let col = |c: &str| header.iter().position(|h| h == c);
    let need = ["x", "y", "x_mm", "y_mm"];
    let mut idx = [0usize; 4];
    for (i, c) in need.iter().enumerate() {
        idx[i] = col(c).ok_or_else(|| {
            bad_input(format!(
                "{name}: no `{c}` column (a world points file has x,y,x_mm,y_mm[,u_px]: each \
                 point's image position in px and its position in the structure's plane in mm)"
            ))
        })?;
    }
    let u_col = col("u_px");
    let mut out = Vec::new();
    for (i, rec) in rdr.records().enumerate() {
        let row = i + 2;
        let rec = rec.map_err(|e| bad_input(format!("{name}: row {row}: {e}")))?;
        let num = |j: usize, c: &str| -> anyhow::Result<f64> {
            let s = rec.get(j).unwrap_or("");
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad_input(format!("{name}: row {row}: {c} `{s}` is not a number")))
        };
        let u_px = match u_col {
            Some(j) if !rec.get(j).unwrap_or("").is_empty() => {
                let u = num(j, "u_px")?;
                if u < 0.0 {
                    return Err(bad_input(format!(
                        "{name}: row {row}: u_px {u} is negative"
                    )));
                }
                u
            }
            _ => DEFAULT_WORLD_U_PX,
        };
        out.push(WorldPoint {
            px: (num(idx[0], "x")?, num(idx[1], "y")?),
            mm: (num(idx[2], "x_mm")?, num(idx[3], "y_mm")?),
            u_px,
        });
    }
    check_world(&out).map_err(|e| bad_input(format!("{name}: {e}")))?;
    Ok(out)
}

/// Four or more points, not three on a line (a plane's homography needs them).
pub fn check_world(points: &[WorldPoint]) -> Result<Homography, String> {
    if points.len() < 4 {
        return Err(format!(
            "{} point(s): the plane's homography needs 4 or more, not three on a line",
            points.len()
        ));
    }
    for (i, a) in points.iter().enumerate() {
        for (j, b) in points.iter().enumerate().skip(i + 1) {
            let same_px = (a.px.0 - b.px.0).hypot(a.px.1 - b.px.1) < 0.5;
            let same_mm = (a.mm.0 - b.mm.0).hypot(a.mm.1 - b.mm.1) < 1e-9;
            if same_px || same_mm {
                return Err(format!(
                    "points {} and {} are the same point {} ({}, {}){}",
                    i + 1,
                    j + 1,
                    if same_px {
                        "in the image"
                    } else {
                        "on the plane"
                    },
                    if same_px { a.px.0 } else { a.mm.0 },
                    if same_px { a.px.1 } else { a.mm.1 },
                    if same_px != same_mm {
                        ", with different coordinates in the other: a point listed twice?"
                    } else {
                        ""
                    }
                ));
            }
        }
    }
    let (px, mm): (Vec<_>, Vec<_>) = points.iter().map(|p| (p.px, p.mm)).unzip();
    fit(Model::Homography, &px, &mm).ok_or_else(|| {
        format!(
            "the {} points do not determine the plane (three or more on one line in the image \
             or in the plane, or two alike)",
            points.len()
        )
    })
}

/// The targets as the view gives them.
#[derive(Debug, Clone)]
pub struct Viewed {
    /// The targets' tracks as the analysis uses them (the camera's motion removed, when
    /// references were given).
    pub tracks: Tracks,
    /// The tracks as measured (`None`: same as `tracks`).
    pub raw: Option<Tracks>,
    /// The references' tracks.
    pub references: Option<Tracks>,
    /// The camera's motion.
    pub motion: Option<CameraMotion>,
    /// Each target's scale (`None`: pixels).
    pub scales: Option<Scales>,
    /// With chosen points: what their windows used.
    pub windows: Option<PointsInfo>,
}

/// Each target's scale and where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Scales {
    /// Per target: mm per px along the axis analysed, and its relative standard uncertainty.
    pub per_target: Vec<(f64, f64)>,
    /// The plane's homography (image px -> plane mm) when `--world` was given.
    pub world: Option<Homography>,
    /// How the scale was found (the report's lines).
    pub text: String,
}

/// Tracks `targets` (and the references) through `source`, removes the camera's motion,
/// resolves the scale; `along_x` the axis analysed.
pub fn track_view(
    source: &FrameSource,
    fps: f64,
    centroid: &CentroidConfig,
    targets: &Targets,
    view: &ViewSettings,
    along_x: bool,
) -> anyhow::Result<Viewed> {
    let (tracks, windows) = track_targets(source, fps, centroid, targets)?;
    refuse_targets_never_seen(&tracks, targets)?;
    let (tracks, raw, references, motion) = match &view.references {
        Some(r) => {
            let refs = Targets::Points(r.points.clone(), PointTracker::Lk { search_px: None });
            let (rt, _) = track_targets(source, fps, centroid, &refs)
                .map_err(|e| e.context("tracking the references ($reference)"))?;
            let m = crate::camera_motion::estimate(&rt, r.model, frame_size(source, fps)?)?;
            let comp = m.compensate(&tracks);
            (comp, Some(tracks), Some(rt), Some(m))
        }
        None => (tracks, None, None, None),
    };
    let mut viewed = Viewed {
        tracks,
        raw,
        references,
        motion,
        scales: None,
        windows,
    };
    if let Some(s) = &view.scale {
        let size = frame_size(source, fps)?;
        viewed.scales = Some(resolve_scale(&viewed, s, along_x, size)?);
    }
    Ok(viewed)
}

/// A chosen point a threshold or `--tracker auto` loses in every frame measured nothing: an
/// error naming it, why (its frames' flags, the check that took its positions away) and what
/// to do, not a run that ends well with empty columns.
pub fn refuse_targets_never_seen(tracks: &Tracks, targets: &Targets) -> anyhow::Result<()> {
    // `--tracker lk`, named by the user, flags each frame's loss and goes on (the report
    // names the target); a threshold, or the tracker chosen for the user, must not end well
    // with nothing measured
    let Targets::Points(_, tracker @ (PointTracker::Centroid(_) | PointTracker::Auto { .. })) =
        targets
    else {
        return Ok(());
    };
    let never: Vec<usize> = tracks
        .centroids
        .iter()
        .enumerate()
        .filter(|(_, c)| !c.is_empty() && c.iter().all(|c| c.position().is_none()))
        .map(|(t, _)| t)
        .collect();
    let Some(&first) = never.first() else {
        return Ok(());
    };
    let frames = tracks.centroids[first].len();
    let names: Vec<String> = never.iter().map(|t| (t + 1).to_string()).collect();
    let checks: Vec<&str> = tracks
        .evidence
        .get(first)
        .map(|e| e.iter().filter_map(|e| e.doubt.map(Doubt::word)).collect())
        .unwrap_or_default();
    let why = if checks.is_empty() {
        vibcam_chain::displacement::why_lost(&tracks.centroids[first])
    } else {
        let mut words = checks.clone();
        words.sort_unstable();
        words.dedup();
        format!(
            "{} position(s) taken away by the {} check(s)",
            checks.len(),
            words.join(", ")
        )
    };
    let advice = match tracker {
        PointTracker::Centroid(_) => {
            "a threshold finds no single bright blob in such windows (a dot on a tag, a \
             pattern, a dark target?): $tracker lk follows any texture, or give each window a \
             threshold of its own"
        }
        _ => {
            "Lucas-Kanade found no trustworthy match for the window (a flat or saturated \
             window, one at the frame's edge, or a motion beyond $search_px): move the window \
             onto the target's texture, widen $search_px, or leave the target out"
        }
    };
    Err(bad_input(format!(
        "target(s) {} of {} lost in every one of the {frames} frames: nothing is measured of \
         them (target {}: {why}); {advice}",
        names.join(", "),
        tracks.centroids.len(),
        first + 1,
    )))
}

/// The frames' width and height, px (the first frame's; (0, 0) without one).
fn frame_size(source: &FrameSource, fps: f64) -> anyhow::Result<(usize, usize)> {
    Ok(source
        .frame_at(fps, 0)?
        .map(|(_, f)| f.dimensions())
        .unwrap_or((0, 0)))
}

impl Viewed {
    /// Target `t`'s displacement (mm with a scale, with `settings`' axis, sign and lost-frame
    /// policy; without a scale `settings.mm_per_px` as given).
    pub fn displacement(
        &self,
        t: usize,
        settings: &DisplacementSettings,
    ) -> anyhow::Result<Displacement> {
        let c = &self.tracks.centroids[t];
        match &self.scales {
            Some(Scales { world: Some(h), .. }) => {
                // the plane's coordinates in mm as an image's (x right, y down): the
                // displacement along y is then +y_mm
                let w: Vec<Centroid> = c
                    .iter()
                    .map(|c| match c.position() {
                        Some((x, y)) => {
                            let (u, v) = h.apply((f64::from(x), f64::from(y)));
                            Centroid {
                                cx: u as f32,
                                cy: -v as f32,
                                ..*c
                            }
                        }
                        None => *c,
                    })
                    .collect();
                displacement_mm(
                    &w,
                    &DisplacementSettings {
                        mm_per_px: 1.0,
                        ..*settings
                    },
                )
            }
            Some(s) => displacement_mm(
                c,
                &DisplacementSettings {
                    mm_per_px: s.per_target[t].0,
                    ..*settings
                },
            ),
            None => displacement_mm(c, settings),
        }
    }

    /// The report's paragraphs on the camera's motion and the scale (empty without either).
    pub fn describe(&self, along_x: bool) -> String {
        let mut s = String::new();
        if let (Some(m), Some(raw)) = (&self.motion, &self.raw) {
            s.push_str(&m.describe(raw, &self.tracks, along_x));
        }
        if let Some(sc) = &self.scales {
            s.push_str(&sc.text);
        }
        s
    }
}

/// The median position of a track (compensated), px.
pub fn median_position(c: &[Centroid]) -> Option<(f64, f64)> {
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    for p in c.iter().filter_map(Centroid::position) {
        xs.push(f64::from(p.0));
        ys.push(f64::from(p.1));
    }
    Some((
        vibcam_common::stats::median(&xs)?,
        vibcam_common::stats::median(&ys)?,
    ))
}

/// A track's position noise per frame, px: from second differences in time
/// (`sqrt(mean(d2^2) / 6)` per axis, their RMS), which the motion raises: an upper bound.
fn position_noise(c: &[Centroid]) -> f64 {
    let p: Vec<Option<(f32, f32)>> = c.iter().map(Centroid::position).collect();
    let (mut s, mut n) = (0.0, 0usize);
    for w in p.windows(3) {
        if let [Some(a), Some(b), Some(c)] = w {
            let dx = f64::from(a.0) - 2.0 * f64::from(b.0) + f64::from(c.0);
            let dy = f64::from(a.1) - 2.0 * f64::from(b.1) + f64::from(c.1);
            s += 0.5 * (dx * dx + dy * dy);
            n += 1;
        }
    }
    if n == 0 {
        0.0
    } else {
        (s / n as f64 / 6.0).sqrt()
    }
}

fn resolve_scale(
    v: &Viewed,
    s: &ScaleInput,
    along_x: bool,
    size: (usize, usize),
) -> anyhow::Result<Scales> {
    let k = v.tracks.centroids.len();
    let mut text = String::new();
    let scales = match s {
        ScaleInput::PerPx(m) => {
            let _ = writeln!(
                text,
                "scale: {m} mm/px given for the whole frame (right only where the structure is \
                 square to the camera at the distance it was measured at)"
            );
            Scales {
                per_target: vec![(*m, 0.0); k],
                world: None,
                text,
            }
        }
        ScaleInput::Between(a, b, mm) => scale_between(v, (*a, *b), *mm)?,
        ScaleInput::TargetSize(mm) => scale_of_sizes(v, *mm)?,
        ScaleInput::World(points, _) => world_scales(v, points, along_x, size)?,
    };
    Ok(scales)
}

/// One scale from the known distance `mm` between two tracked points, its uncertainty from
/// their positions' noise.
fn scale_between(v: &Viewed, (a, b): (PointRef, PointRef), mm: f64) -> anyhow::Result<Scales> {
    let k = v.tracks.centroids.len();
    let mut text = String::new();
    let at = |p: PointRef| -> anyhow::Result<(f64, f64, f64)> {
        let track = match p {
            PointRef::Target(i) => v.tracks.centroids.get(i - 1),
            PointRef::Reference(i) => v.references.as_ref().and_then(|r| r.centroids.get(i - 1)),
        };
        let track = track.ok_or_else(|| {
            bad_input(format!(
                "$scale: there is no {} (targets 1 to {k}{})",
                p.label(),
                match &v.references {
                    Some(r) => format!(", references r1 to r{}", r.centroids.len()),
                    None => ", no $reference".to_string(),
                }
            ))
        })?;
        let (x, y) = median_position(track).ok_or_else(|| {
            bad_input(format!(
                "$scale: {} has no position in any frame",
                p.label()
            ))
        })?;
        Ok((x, y, position_noise(track)))
    };
    let (pa, pb) = (at(a)?, at(b)?);
    let d = ((pa.0 - pb.0).powi(2) + (pa.1 - pb.1).powi(2)).sqrt();
    if d < 1.0 {
        return Err(bad_input(format!(
            "$scale: {} and {} are {d:.2} px apart: too close for a scale",
            a.label(),
            b.label()
        )));
    }
    let u_rel = (pa.2 * pa.2 + pb.2 * pb.2).sqrt() / d;
    let m = mm / d;
    let _ = writeln!(
        text,
        "scale: {mm} mm between {} and {} ({d:.3} px apart): {m:.6} mm/px, standard \
         uncertainty {:.3} % from their positions' noise per frame; one scale for the \
         whole frame (see $world for a structure seen at an angle)",
        a.label(),
        b.label(),
        100.0 * u_rel
    );
    Ok(Scales {
        per_target: vec![(m, u_rel); k],
        world: None,
        text,
    })
}

/// Each target's scale from its known diameter `mm` and its blob's size in the image.
fn scale_of_sizes(v: &Viewed, mm: f64) -> anyhow::Result<Scales> {
    let k = v.tracks.centroids.len();
    let mut text = String::new();
    let mut per = Vec::with_capacity(k);
    let _ = writeln!(
        text,
        "scale: each target {mm} mm across, its size in the image from the blob's \
         pixels (2 sqrt(N / pi), the median over the frames):"
    );
    for (t, c) in v.tracks.centroids.iter().enumerate() {
        let d: Vec<f64> = c
            .iter()
            .filter(|c| c.position().is_some() && c.pixels() > 0)
            .map(|c| 2.0 * (c.pixels() as f64 / std::f64::consts::PI).sqrt())
            .collect();
        if d.is_empty() {
            return Err(bad_input(format!(
                "$target_size_mm: target {} has no blob (its size comes from the \
                 centroid's pixels above the threshold: Lucas-Kanade has none)",
                t + 1
            )));
        }
        let med = vibcam_common::stats::median(&d).unwrap_or(f64::NAN);
        let sd = vibcam_common::stats::std_dev(&d).unwrap_or(0.0);
        let u_rel = sd / med;
        let m = mm / med;
        let _ = writeln!(
            text,
            "  target {}: {med:.3} px across, {m:.6} mm/px, standard uncertainty {:.2} % \
             (its size's spread over the frames; the threshold sets the size too)",
            t + 1,
            100.0 * u_rel
        );
        per.push((m, u_rel));
    }
    Ok(Scales {
        per_target: per,
        world: None,
        text,
    })
}

/// mm per px along the plane's axis (`along_x`: `x_mm`, else `y_mm`) at image point `p` of
/// the plane's homography `h`: the image motion of 1 mm along the axis, inverted.
fn local_scale(h: &Homography, p: (f64, f64), along_x: bool) -> f64 {
    let j = h.jacobian(p);
    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    // the inverse Jacobian's column of the axis: image px per mm along it
    let (a, b) = if along_x {
        (j[1][1] / det, -j[1][0] / det)
    } else {
        (-j[0][1] / det, j[0][0] / det)
    };
    1.0 / (a * a + b * b).sqrt()
}

/// The largest RMS reprojection error of the plane's points, px, when no point states its
/// uncertainty (points clicked on the image are good to about a pixel).
const WORLD_RESIDUAL_PX: f64 = 1.0;

/// Checks the plane's points against the frame (`size`) and the homography `h` fitted to them:
/// every point inside the frame; their reprojection error within 3 times their stated
/// uncertainty (at least [`WORLD_RESIDUAL_PX`]); the stated uncertainty small beside their
/// spacing (the Monte Carlo propagates small errors). Returns the RMS reprojection error, px.
fn check_world_fit(
    points: &[WorldPoint],
    h: &Homography,
    size: (usize, usize),
) -> anyhow::Result<f64> {
    let (w, hgt) = (size.0 as f64, size.1 as f64);
    if size.0 > 0 {
        if let Some((i, p)) = points.iter().enumerate().find(|(_, p)| {
            !(p.px.0 >= -0.5 && p.px.1 >= -0.5 && p.px.0 <= w - 0.5 && p.px.1 <= hgt - 0.5)
        }) {
            return Err(bad_input(format!(
                "$world: point {} at ({}, {}) px lies outside the {w} x {hgt} frame (measured \
                 on an image of another resolution?)",
                i + 1,
                p.px.0,
                p.px.1
            )));
        }
    }
    let back = h
        .inverse()
        .ok_or_else(|| bad_input("$world: the plane's map cannot be inverted"))?;
    let errors: Vec<f64> = points
        .iter()
        .map(|p| {
            let q = back.apply(p.mm);
            ((q.0 - p.px.0).powi(2) + (q.1 - p.px.1).powi(2)).sqrt()
        })
        .collect();
    let rms = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt();
    let u_rms = (points.iter().map(|p| p.u_px * p.u_px).sum::<f64>() / points.len() as f64).sqrt();
    let tol = (3.0 * u_rms).max(WORLD_RESIDUAL_PX);
    if rms > tol {
        let (worst, e) =
            errors
                .iter()
                .enumerate()
                .fold((0, 0.0), |m, (i, e)| if *e > m.1 { (i, *e) } else { m });
        return Err(bad_input(format!(
            "$world: the {} points do not lie on one plane seen by the camera: their image \
             positions are {rms:.3} px RMS from the fitted plane's, more than {tol:.3} px (3 \
             times their stated uncertainty u_px, at least {WORLD_RESIDUAL_PX} px); the worst \
             is point {} at ({}, {}) px, {e:.3} px off (a point listed twice, or a mistyped \
             coordinate?)",
            points.len(),
            worst + 1,
            points[worst].px.0,
            points[worst].px.1
        )));
    }
    let mut spacing = f64::INFINITY;
    for (i, a) in points.iter().enumerate() {
        for b in &points[i + 1..] {
            spacing = spacing.min(((a.px.0 - b.px.0).powi(2) + (a.px.1 - b.px.1).powi(2)).sqrt());
        }
    }
    let u_max = points.iter().map(|p| p.u_px).fold(0.0, f64::max);
    if u_max > 0.1 * spacing {
        return Err(bad_input(format!(
            "$world: u_px {u_max} beside points {spacing:.1} px apart: an uncertainty above a \
             tenth of the points' spacing is no small error to propagate; the plane is not \
             known from these points"
        )));
    }
    Ok(rms)
}

fn world_scales(
    v: &Viewed,
    points: &[WorldPoint],
    along_x: bool,
    size: (usize, usize),
) -> anyhow::Result<Scales> {
    let h = check_world(points).map_err(|e| bad_input(format!("$world: {e}")))?;
    let reprojection_px = check_world_fit(points, &h, size)?;
    let (px, mm): (Vec<_>, Vec<_>) = points.iter().map(|p| (p.px, p.mm)).unzip();
    let residual = if points.len() > 4 {
        let s: f64 = px
            .iter()
            .zip(&mm)
            .map(|(p, m)| {
                let q = h.apply(*p);
                (q.0 - m.0).powi(2) + (q.1 - m.1).powi(2)
            })
            .sum();
        Some((s / points.len() as f64).sqrt())
    } else {
        None
    };
    let at: Vec<Option<(f64, f64)>> = v
        .tracks
        .centroids
        .iter()
        .map(|c| median_position(c))
        .collect();
    let draws = scale_draws(points, &mm, &at, along_x)?;
    let axis = if along_x { "x_mm" } else { "y_mm" };
    let mut text = format!(
        "scale: the structure's plane from {} points (a homography{}), each target's \
         displacement along its {axis} with its own local scale:\n",
        points.len(),
        match residual {
            Some(r) => format!(", residual {r:.3} mm RMS, {reprojection_px:.3} px in the image"),
            None => ", exact through 4 points".to_string(),
        }
    );
    let mut per = Vec::new();
    for (t, p) in at.iter().enumerate() {
        let Some(p) = p else {
            per.push((f64::NAN, f64::NAN));
            continue;
        };
        let m = local_scale(&h, *p, along_x);
        let sd = vibcam_common::stats::std_dev(&draws[t]).unwrap_or(f64::NAN);
        let _ = writeln!(
            text,
            "  target {} at ({:.1}, {:.1}) px: {m:.6} mm/px, standard uncertainty {:.3} % \
             (Monte Carlo over the plane points' image positions)",
            t + 1,
            p.0,
            p.1,
            100.0 * sd / m
        );
        per.push((m, sd / m));
    }
    text.push_str(&one_scale_spread(&per));
    Ok(Scales {
        per_target: per,
        world: Some(h),
        text,
    })
}

/// Monte Carlo over the image positions of the plane's points (each moved by its `u_px`): per
/// target at `at`, the local scale of every draw's homography.
fn scale_draws(
    points: &[WorldPoint],
    mm: &[(f64, f64)],
    at: &[Option<(f64, f64)>],
    along_x: bool,
) -> anyhow::Result<Vec<Vec<f64>>> {
    let noise = vibcam_common::testing::gaussian_noise(0x5ca1e, WORLD_DRAWS * points.len() * 2);
    let mut draws: Vec<Vec<f64>> = vec![Vec::new(); at.len()];
    for d in 0..WORLD_DRAWS {
        let moved: Vec<(f64, f64)> = points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let o = 2 * (d * points.len() + i);
                (p.px.0 + p.u_px * noise[o], p.px.1 + p.u_px * noise[o + 1])
            })
            .collect();
        let Some(hd) = fit(Model::Homography, &moved, mm) else {
            // dropping it would narrow the spread: the uncertainty is not known
            return Err(bad_input(format!(
                "$world: with the points moved by their stated u_px the plane could not be \
                 fitted (draw {} of {WORLD_DRAWS}): the uncertainty is too large for these \
                 points",
                d + 1
            )));
        };
        for (t, p) in at.iter().enumerate() {
            if let Some(p) = p {
                draws[t].push(local_scale(&hd, *p, along_x));
            }
        }
    }
    Ok(draws)
}

/// How far one scale for the whole frame (the targets' mean) would be off across the targets.
fn one_scale_spread(per: &[(f64, f64)]) -> String {
    let mut text = String::new();
    let finite: Vec<f64> = per.iter().map(|p| p.0).filter(|m| m.is_finite()).collect();
    if finite.len() >= 2 {
        let mean = finite.iter().sum::<f64>() / finite.len() as f64;
        let (lo, hi) = finite
            .iter()
            .map(|m| 100.0 * (mean - m) / m)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), e| {
                (a.min(e), b.max(e))
            });
        let _ = writeln!(
            text,
            "  one $mm_per_px for the whole frame (their mean, {mean:.6}) would be off by \
             {lo:+.2} % to {hi:+.2} % across the targets (perspective)"
        );
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use vibcam_common::geometry::plane_view;

    #[test]
    fn point_refs_parse_targets_and_references() {
        assert_eq!(PointRef::parse("3"), Some(PointRef::Target(3)));
        assert_eq!(PointRef::parse("r2"), Some(PointRef::Reference(2)));
        assert_eq!(PointRef::parse("r0"), None);
        assert_eq!(PointRef::parse("x"), None);
    }

    #[test]
    fn the_local_scale_is_the_planes_mm_per_px_at_the_point() {
        // a plane square to the camera at 500 mm with f = 1000 px: 0.5 mm/px everywhere
        let img_of_world = plane_view(0.0, 500.0, 1000.0, (100.0, 100.0));
        let h = img_of_world.inverse().unwrap();
        for p in [(100.0, 100.0), (10.0, 190.0)] {
            assert!((local_scale(&h, p, false) - 0.5).abs() < 1e-12);
            assert!((local_scale(&h, p, true) - 0.5).abs() < 1e-12);
        }
        // turned by 30 deg about its vertical axis: along y the scale is depth / f
        let img_of_world = plane_view(30.0, 500.0, 1000.0, (100.0, 100.0));
        let h = img_of_world.inverse().unwrap();
        let p = img_of_world.apply((80.0, 0.0));
        let depth = 500.0 + 80.0 * 0.5;
        assert!((local_scale(&h, p, false) - depth / 1000.0).abs() < 1e-9);
    }
}
