//! The camera's own motion from static references (`--reference POINTS.csv`), removed from
//! every target's track (docs/method.md §3.14).
//!
//! The references are windows on parts of the scene that do not move (a wall, the ground),
//! followed by Lucas-Kanade like chosen points. The anchors are the references' positions in
//! the frame nearest their median positions (of those that see the most of them); per frame
//! the map from the anchors to where the references are (a
//! translation, a similarity: rotation, scale and shift, or a homography) is fitted by least
//! squares, and every target's position is taken back through its inverse.
//!
//! Nothing is used silently:
//! - a reference lost in more than 5 % of the frames is left out, named;
//! - a reference that moves against the others is found by consensus over the whole record
//!   (every minimal set of references fitted per frame, the set the most references agree with
//!   kept: agreeing means an RMS deviation under [`TOLERANCE_PX`], then under 5 times the kept
//!   references' own deviation if that is larger than [`MIN_TOLERANCE_PX`]) and left out,
//!   named with its deviation; when two sets of references disagree equally (two references,
//!   one moving) the run stops naming them;
//! - a model asked for with fewer references than it needs stops the run naming them; a frame
//!   with fewer references seen than the model needs is fitted with a translation (counted), a
//!   frame with none is a lost frame of every target (counted).

use crate::tracks::Tracks;
use firmware_core::centroid::{Centroid, Flags};
use std::fmt::Write as _;
use vibcam_common::geometry::{fit, Homography, Model};

/// A reference agrees with the others' camera motion when its RMS deviation from it is below
/// this, px (first pass).
pub const TOLERANCE_PX: f64 = 0.25;
/// The smallest tolerance of the second pass, px.
pub const MIN_TOLERANCE_PX: f64 = 0.05;
/// Frames the consensus looks at (evenly spread).
const CONSENSUS_FRAMES: usize = 400;
/// Minimal sets of references tried at most (evenly spread over all).
const MAX_SETS: usize = 2000;

/// The camera's motion per frame.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraMotion {
    /// The model fitted.
    pub model: Model,
    /// Per frame: the map from the anchors' image to the frame (`None`: no reference seen).
    pub transforms: Vec<Option<Homography>>,
    /// Per frame: the RMS residual of the references used, px (NaN where none).
    pub residual_px: Vec<f64>,
    /// Per frame: the references used.
    pub seen: Vec<usize>,
    /// References used (1-based).
    pub used: Vec<usize>,
    /// References left out and why (1-based).
    pub left_out: Vec<(usize, String)>,
    /// Per reference: its RMS deviation from the camera's motion, px (NaN: not measured).
    pub deviation_px: Vec<f64>,
    /// The tolerance applied in the end, px.
    pub tolerance_px: f64,
    /// Frames fitted with a translation, fewer references being seen than the model needs.
    pub fallback_frames: usize,
    /// Frames with no reference seen (every target lost there).
    pub frames_without: usize,
    /// The point the motion is described at (`camera_motion.csv`): the image centre, px.
    pub centre: (f64, f64),
    /// Remarks (no redundancy to find a moving reference, ...).
    pub notes: Vec<String>,
}

/// One frame's description of the camera's motion at `centre`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionRow {
    /// Shift of the centre, px (image x right, y down).
    pub dx_px: f64,
    /// Shift of the centre, px.
    pub dy_px: f64,
    /// Roll, degrees (clockwise on the image).
    pub rotation_deg: f64,
    /// Scale (1: none).
    pub scale: f64,
}

impl CameraMotion {
    /// Frame `k`'s motion at the centre (`None`: unknown there).
    pub fn row(&self, k: usize) -> Option<MotionRow> {
        let h = self.transforms.get(k).copied().flatten()?;
        let c = self.centre;
        let (x, y) = h.apply(c);
        let (angle, scale) = h.rotation_scale(c);
        Some(MotionRow {
            dx_px: x - c.0,
            dy_px: y - c.1,
            rotation_deg: angle.to_degrees(),
            scale,
        })
    }

    /// `tracks` with the camera's motion removed from every position (a frame with no
    /// reference loses every target's position).
    pub fn compensate(&self, tracks: &Tracks) -> Tracks {
        // each frame's inverse map once, for every target
        let inverse: Vec<Option<Homography>> = self
            .transforms
            .iter()
            .map(|h| h.and_then(|h| h.inverse()))
            .collect();
        let centroids: Vec<Vec<Centroid>> = tracks
            .centroids
            .iter()
            .map(|c| {
                c.iter()
                    .enumerate()
                    .map(|(k, c)| compensate_one(inverse.get(k).copied().flatten(), c))
                    .collect()
            })
            .collect();
        let first = centroids
            .iter()
            .zip(&tracks.first)
            .map(|(c, f)| {
                c.iter()
                    .find_map(|c| c.position())
                    .map_or(*f, |(x, y)| (f64::from(x), f64::from(y)))
            })
            .collect();
        Tracks {
            centroids,
            first,
            refused: tracks.refused.clone(),
            depth: tracks.depth,
            evidence: tracks.evidence.clone(),
        }
    }

    /// The report's paragraph: the model, the references, the motion's RMS, each target's
    /// share (`raw` and `compensated` the targets' tracks, `along_x` the axis analysed).
    pub fn describe(&self, raw: &Tracks, compensated: &Tracks, along_x: bool) -> String {
        let mut s = format!(
            "camera motion: {} from {} reference(s) ({}), the image centre ({:.0}, {:.0}) px \
             described\n",
            self.model.name(),
            self.used.len(),
            self.used
                .iter()
                .map(|r| format!("r{r}"))
                .collect::<Vec<_>>()
                .join(", "),
            self.centre.0,
            self.centre.1
        );
        let rows: Vec<MotionRow> = (0..self.transforms.len())
            .filter_map(|k| self.row(k))
            .collect();
        let rms = |f: &dyn Fn(&MotionRow) -> f64| {
            let v: Vec<f64> = rows.iter().map(f).collect();
            centred_rms(&v)
        };
        let _ = writeln!(
            s,
            "  RMS about its mean: x {:.3} px, y {:.3} px, roll {:.4} deg, scale {:.2e}; \
             residual of the references used {:.3} px RMS",
            rms(&|r| r.dx_px),
            rms(&|r| r.dy_px),
            rms(&|r| r.rotation_deg),
            rms(&|r| r.scale),
            rms_finite(&self.residual_px)
        );
        for (r, why) in &self.left_out {
            let _ = writeln!(s, "  reference r{r} left out: {why}");
        }
        for (i, d) in self.deviation_px.iter().enumerate() {
            if d.is_finite() && self.used.contains(&(i + 1)) {
                let _ = writeln!(
                    s,
                    "  reference r{}: RMS deviation from the camera's motion {d:.3} px",
                    i + 1
                );
            }
        }
        let _ = writeln!(
            s,
            "  a reference counts as static below {:.3} px RMS deviation",
            self.tolerance_px
        );
        if self.fallback_frames > 0 {
            let _ = writeln!(
                s,
                "  {} frame(s) had fewer references than a {} needs: fitted with a translation",
                self.fallback_frames,
                self.model.name()
            );
        }
        if self.frames_without > 0 {
            let _ = writeln!(
                s,
                "  {} frame(s) had no reference: the camera's motion is unknown there, and \
                 every target's position is counted lost in them",
                self.frames_without
            );
        }
        for n in &self.notes {
            let _ = writeln!(s, "  note: {n}");
        }
        s.push_str(&share_per_target(raw, compensated, along_x));
        s
    }
}

/// Per target, how much of its raw motion along the axis was the camera's; a warning when the
/// references took (nearly) all of every target's motion.
fn share_per_target(raw: &Tracks, compensated: &Tracks, along_x: bool) -> String {
    let mut s = String::new();
    let axis = if along_x { "x" } else { "y" };
    // whether the references took (nearly) all of every target's motion
    let mut all_taken = !raw.centroids.is_empty();
    for (t, (r, c)) in raw.centroids.iter().zip(&compensated.centroids).enumerate() {
        let (mut raw_v, mut cam_v, mut left_v) = (Vec::new(), Vec::new(), Vec::new());
        for (a, b) in r.iter().zip(c) {
            if let (Some(p), Some(q)) = (a.position(), b.position()) {
                let (p, q) = if along_x { (p.0, q.0) } else { (p.1, q.1) };
                raw_v.push(f64::from(p));
                cam_v.push(f64::from(p) - f64::from(q));
                left_v.push(f64::from(q));
            }
        }
        let (cam, all) = (centred_rms(&cam_v), centred_rms(&raw_v));
        all_taken &= all > 0.0 && centred_rms(&left_v) < TAKEN_ALL * all;
        let _ = writeln!(
            s,
            "  target {}: the camera moved it {cam:.3} px RMS along {axis}, {:.0} % of its \
             raw motion's RMS ({all:.3} px)",
            t + 1,
            if all > 0.0 { 100.0 * cam / all } else { 0.0 }
        );
    }
    if all_taken {
        let _ = writeln!(
            s,
            "  warning: the references move with the targets: the camera's motion found \
             from them takes over {:.0} % of every target's motion along {axis}; unless \
             the camera shook and the structure stood still, references are on the \
             structure (or on parts that move with it) and the structure's own motion was \
             removed: place them on parts of the scene that do not move",
            100.0 * (1.0 - TAKEN_ALL)
        );
    }
    s
}

/// A target is taken over by the references when what is left of its motion after the
/// camera's is removed is below this fraction of its raw motion (RMS about the means).
const TAKEN_ALL: f64 = 0.1;

/// `c` taken back through `inverse`, the frame's inverse map (`None`: the frame's motion is
/// unknown, and `c` loses its position).
fn compensate_one(inverse: Option<Homography>, c: &Centroid) -> Centroid {
    let Some((x, y)) = c.position() else {
        return *c;
    };
    match inverse {
        Some(inv) => {
            let (u, v) = inv.apply((f64::from(x), f64::from(y)));
            Centroid {
                cx: u as f32,
                cy: v as f32,
                ..*c
            }
        }
        None => Centroid {
            cx: 0.0,
            cy: 0.0,
            flags: c.flags.union(Flags::EMPTY),
            ..*c
        },
    }
}

fn centred_rms(v: &[f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let m = v.iter().sum::<f64>() / v.len() as f64;
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64).sqrt()
}

fn rms_finite(v: &[f64]) -> f64 {
    let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if f.is_empty() {
        return f64::NAN;
    }
    (f.iter().map(|x| x * x).sum::<f64>() / f.len() as f64).sqrt()
}

/// Estimates the camera's motion from the references' tracks (`refs.centroids[r][k]`);
/// `asked` the model asked for (`None`: a similarity with two references or more, else a
/// translation); `size` the frame's width and height. Errors (the user's to fix) name the
/// references.
pub fn estimate(
    refs: &Tracks,
    asked: Option<Model>,
    size: (usize, usize),
) -> anyhow::Result<CameraMotion> {
    let n_refs = refs.centroids.len();
    let frames = refs.centroids.first().map_or(0, Vec::len);
    let pos: Vec<Vec<Option<(f64, f64)>>> = refs
        .centroids
        .iter()
        .map(|c| {
            c.iter()
                .map(|c| c.position().map(|(x, y)| (f64::from(x), f64::from(y))))
                .collect()
        })
        .collect();
    let (avail, mut left_out) = usable_references(refs, &pos);
    let anchors = anchors(&pos, &avail);
    let model = match asked {
        Some(m) => m,
        None if avail.len() >= 2 => Model::Similarity,
        None => Model::Translation,
    };
    if avail.len() < model.minimum() {
        return Err(too_few(model, &avail, &left_out, n_refs));
    }
    let (kept, tolerance, notes) = consensus(&pos, &anchors, model, &avail, &left_out)?;
    let all_frames: Vec<usize> = (0..frames).collect();
    let dev = per_reference_deviation(&pos, &anchors, model, &kept, &all_frames);
    for &r in &avail {
        if !kept.contains(&r) {
            left_out.push((
                r,
                format!(
                    "moves against the others: RMS {:.3} px from the camera's motion they give \
                     (static below {tolerance:.3} px)",
                    dev[r]
                ),
            ));
        }
    }
    left_out.sort_by_key(|(r, _)| *r);
    let (mut transforms, mut residual_px, mut seen) = (Vec::new(), Vec::new(), Vec::new());
    let (mut fallback_frames, mut frames_without) = (0, 0);
    for k in 0..frames {
        let (h, res, n) = fit_frame(&pos, &anchors, model, &kept, k);
        match (h, n) {
            (None, _) => frames_without += 1,
            (Some(_), n) if n < model.minimum() => fallback_frames += 1,
            _ => {}
        }
        transforms.push(h);
        residual_px.push(res);
        seen.push(n);
    }
    Ok(CameraMotion {
        model,
        transforms,
        residual_px,
        seen,
        used: kept.iter().map(|r| r + 1).collect(),
        left_out: left_out.into_iter().map(|(r, w)| (r + 1, w)).collect(),
        deviation_px: dev,
        tolerance_px: tolerance,
        fallback_frames,
        frames_without,
        centre: (size.0 as f64 / 2.0 - 0.5, size.1 as f64 / 2.0 - 0.5),
        notes,
    })
}

/// Two agreements among the references as large as each other: which are static cannot be
/// told (a hint when the camera's model may be too simple).
fn disagreement(top: &[&Vec<usize>], model: Model, available: usize) -> anyhow::Error {
    let mut all: Vec<usize> = top.iter().flat_map(|t| t.iter().copied()).collect();
    all.sort_unstable();
    all.dedup();
    let groups: Vec<String> = top.iter().map(|t| format!("({})", name(t))).collect();
    let hint = match model {
        Model::Homography => String::new(),
        m if available >= 4 => format!(
            "; or the camera's motion is more than a {}: a camera that pans or tilts \
             is a homography ($camera_model homography)",
            m.name()
        ),
        _ => String::new(),
    };
    vibcam_readers::bad_input(format!(
        "the references disagree: {} each move together, as many in each; which are \
         static cannot be told (give more references on parts of the scene that do not \
         move, or leave out the ones that may move: {}){hint}",
        groups.join(" and "),
        name(&all)
    ))
}

/// The references lost in at most 5 % of the frames, and those left out (index, why).
#[allow(clippy::type_complexity)]
fn usable_references(
    refs: &Tracks,
    pos: &[Vec<Option<(f64, f64)>>],
) -> (Vec<usize>, Vec<(usize, String)>) {
    let frames = pos.first().map_or(0, Vec::len);
    let mut left_out: Vec<(usize, String)> = Vec::new();
    let mut avail: Vec<usize> = Vec::new();
    for (r, p) in pos.iter().enumerate() {
        let lost = p.iter().filter(|p| p.is_none()).count();
        if lost as f64 > vibcam_common::lost_frames::MAX_LOST_FRACTION * frames as f64 {
            let why = vibcam_chain::displacement::why_lost(&refs.centroids[r]);
            left_out.push((
                r,
                format!(
                    "lost in {lost} of {frames} frames (more than {:.0} %: {why})",
                    100.0 * vibcam_common::lost_frames::MAX_LOST_FRACTION
                ),
            ));
        } else {
            avail.push(r);
        }
    }
    (avail, left_out)
}

/// The anchors: the references in one frame (positions of one pose are what one map takes to
/// every other frame), the frame nearest their median positions among those that see the most
/// of them.
fn anchors(pos: &[Vec<Option<(f64, f64)>>], avail: &[usize]) -> Vec<(f64, f64)> {
    let (n_refs, frames) = (pos.len(), pos.first().map_or(0, Vec::len));
    let medians: Vec<(f64, f64)> = pos
        .iter()
        .map(|p| {
            let xs: Vec<f64> = p.iter().flatten().map(|q| q.0).collect();
            let ys: Vec<f64> = p.iter().flatten().map(|q| q.1).collect();
            (
                vibcam_common::stats::median(&xs).unwrap_or(f64::NAN),
                vibcam_common::stats::median(&ys).unwrap_or(f64::NAN),
            )
        })
        .collect();
    let anchor_frame = (0..frames)
        .map(|k| {
            let seen = avail.iter().filter(|&&r| pos[r][k].is_some()).count();
            let d: f64 = avail
                .iter()
                .filter_map(|&r| {
                    pos[r][k].map(|q| (q.0 - medians[r].0).powi(2) + (q.1 - medians[r].1).powi(2))
                })
                .sum();
            (k, seen, d)
        })
        .max_by(|a, b| a.1.cmp(&b.1).then(b.2.total_cmp(&a.2)))
        .map_or(0, |(k, _, _)| k);
    (0..n_refs)
        .map(|r| {
            pos[r]
                .get(anchor_frame)
                .copied()
                .flatten()
                .unwrap_or(medians[r])
        })
        .collect()
}

/// References by name: `r1, r3`.
fn name(rs: &[usize]) -> String {
    rs.iter()
        .map(|r| format!("r{}", r + 1))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Too few references stay for `model`: which remain and which were left out, and why.
fn too_few(
    model: Model,
    have: &[usize],
    left_out: &[(usize, String)],
    n_refs: usize,
) -> anyhow::Error {
    let out: Vec<String> = left_out
        .iter()
        .map(|(r, w)| format!("r{} {w}", r + 1))
        .collect();
    vibcam_readers::bad_input(format!(
        "the camera's motion as a {} needs {} reference(s) that stay; {} of {n_refs} \
         remain ({}){}",
        model.name(),
        model.minimum(),
        have.len(),
        if have.is_empty() {
            "none".to_string()
        } else {
            name(have)
        },
        if out.is_empty() {
            String::new()
        } else {
            format!("; left out: {}", out.join("; "))
        }
    ))
}

/// The references kept: the minimal set most references agree with over the record (a
/// sample of its frames), then those within a tolerance set by the kept ones' own deviation;
/// with that tolerance and the notes. Two agreements as large are a disagreement: an error.
fn consensus(
    pos: &[Vec<Option<(f64, f64)>>],
    anchors: &[(f64, f64)],
    model: Model,
    avail: &[usize],
    left_out: &[(usize, String)],
) -> anyhow::Result<(Vec<usize>, f64, Vec<String>)> {
    let frames = pos.first().map_or(0, Vec::len);
    let mut notes = Vec::new();
    // consensus over the record: the minimal set most references agree with
    let step = (frames / CONSENSUS_FRAMES).max(1);
    let sample: Vec<usize> = (0..frames).step_by(step).collect();
    let deviations = |set: &[usize], k_frames: &[usize]| -> Vec<f64> {
        per_reference_deviation(pos, anchors, model, set, k_frames)
    };
    let (kept, tolerance) = if avail.len() > model.minimum() {
        // each minimal set's agreeing references; the largest agreement wins, and two
        // different agreements as large are a disagreement nobody can settle
        let mut found: Vec<(Vec<usize>, f64)> = Vec::new();
        for set in subsets(avail, model.minimum()) {
            let dev = deviations(&set, &sample);
            let inliers: Vec<usize> = avail
                .iter()
                .copied()
                .filter(|&r| dev[r] < TOLERANCE_PX)
                .collect();
            let cost: f64 = inliers.iter().map(|&r| dev[r]).sum();
            match found.iter_mut().find(|(i, _)| *i == inliers) {
                Some(f) => f.1 = f.1.min(cost),
                None => found.push((inliers, cost)),
            }
        }
        let most = found.iter().map(|f| f.0.len()).max().unwrap_or(0);
        let top: Vec<&Vec<usize>> = found
            .iter()
            .filter(|f| f.0.len() == most)
            .map(|f| &f.0)
            .collect();
        if top.len() > 1 {
            return Err(disagreement(&top, model, avail.len()));
        }
        let kept = top.first().map(|t| (*t).clone()).unwrap_or_default();
        if kept.len() < model.minimum() {
            return Err(too_few(model, &kept, left_out, pos.len()));
        }
        // second pass: the kept references' own deviation sets the tolerance
        let dev = deviations(&kept, &sample);
        let own = vibcam_common::stats::median(&kept.iter().map(|&r| dev[r]).collect::<Vec<_>>())
            .unwrap_or(0.0);
        let tol = (5.0 * own).clamp(MIN_TOLERANCE_PX, TOLERANCE_PX);
        let mut kept2: Vec<usize> = kept.iter().copied().filter(|&r| dev[r] < tol).collect();
        if kept2.len() < model.minimum() {
            kept2 = kept;
        }
        (kept2, tol)
    } else {
        notes.push(format!(
            "{} reference(s) for a {}: none to spare, so a reference that moves cannot be \
             found (give {} or more)",
            avail.len(),
            model.name(),
            model.minimum() + 2
        ));
        (avail.to_vec(), TOLERANCE_PX)
    };
    Ok((kept, tolerance, notes))
}

/// Frame `k`'s map fitted to the references of `set` seen there (a translation when fewer than
/// the model needs), its RMS residual and how many were seen.
fn fit_frame(
    pos: &[Vec<Option<(f64, f64)>>],
    anchors: &[(f64, f64)],
    model: Model,
    set: &[usize],
    k: usize,
) -> (Option<Homography>, f64, usize) {
    let (mut src, mut dst) = (Vec::new(), Vec::new());
    for &r in set {
        if let Some(p) = pos[r][k] {
            src.push(anchors[r]);
            dst.push(p);
        }
    }
    let m = if src.len() >= model.minimum() {
        model
    } else {
        Model::Translation
    };
    let Some(h) = fit(m, &src, &dst) else {
        return (None, f64::NAN, src.len());
    };
    let res = if src.is_empty() {
        f64::NAN
    } else {
        let s: f64 = src
            .iter()
            .zip(&dst)
            .map(|(a, b)| {
                let q = h.apply(*a);
                (q.0 - b.0).powi(2) + (q.1 - b.1).powi(2)
            })
            .sum();
        (s / src.len() as f64).sqrt()
    };
    (Some(h), res, src.len())
}

/// Per reference: its RMS deviation (px, both axes) over `frames` from the map fitted to
/// `set` frame by frame (NaN where never seen with a fit).
fn per_reference_deviation(
    pos: &[Vec<Option<(f64, f64)>>],
    anchors: &[(f64, f64)],
    model: Model,
    set: &[usize],
    frames: &[usize],
) -> Vec<f64> {
    let mut sum = vec![0.0; pos.len()];
    let mut n = vec![0usize; pos.len()];
    for &k in frames {
        let (Some(h), _, seen) = fit_frame(pos, anchors, model, set, k) else {
            continue;
        };
        if seen < model.minimum() {
            continue;
        }
        for (r, p) in pos.iter().enumerate() {
            if let Some(p) = p[k] {
                let q = h.apply(anchors[r]);
                sum[r] += (q.0 - p.0).powi(2) + (q.1 - p.1).powi(2);
                n[r] += 1;
            }
        }
    }
    sum.iter()
        .zip(&n)
        .map(|(s, &n)| {
            if n == 0 {
                f64::NAN
            } else {
                (s / n as f64).sqrt()
            }
        })
        .collect()
}

/// The subsets of `size` of `items`, at most [`MAX_SETS`] of them spread over all.
fn subsets(items: &[usize], size: usize) -> Vec<Vec<usize>> {
    let n = items.len();
    if size == 0 || size > n {
        return Vec::new();
    }
    // C(n, size), then every step-th combination kept as they are enumerated (never all
    // held: 64 references make 635 376 sets of four)
    let total = (0..size).fold(1u128, |c, i| c * (n - i) as u128 / (i + 1) as u128);
    let step = total.div_ceil(MAX_SETS as u128).max(1);
    let mut out = Vec::new();
    let mut idx: Vec<usize> = (0..size).collect();
    let mut count = 0u128;
    loop {
        if count.is_multiple_of(step) {
            out.push(idx.iter().map(|&i| items[i]).collect());
        }
        count += 1;
        let mut i = size;
        loop {
            if i == 0 {
                return out;
            }
            i -= 1;
            if idx[i] != i + n - size {
                break;
            }
        }
        idx[i] += 1;
        for j in i + 1..size {
            idx[j] = idx[j - 1] + 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vibcam_readers::frames::FrameDepth;

    fn centroid(p: Option<(f64, f64)>) -> Centroid {
        let mut c = firmware_core::centroid::Centroid::default();
        match p {
            Some((x, y)) => {
                c.cx = x as f32;
                c.cy = y as f32;
                c.flags = Flags::NONE;
            }
            None => c.flags = Flags::EMPTY,
        }
        c
    }

    /// References at `at` seen through a camera that shifts, rolls and zooms a little per
    /// frame; `moving` adds a motion of its own to one of them.
    fn tracks(
        at: &[(f64, f64)],
        frames: usize,
        moving: Option<usize>,
    ) -> (Tracks, Vec<Homography>) {
        let truth: Vec<Homography> = (0..frames)
            .map(|k| {
                let t = k as f64 / 50.0;
                Homography::similarity(
                    (100.0, 80.0),
                    0.003 * (2.0 * t).sin(),
                    1.0 + 1e-4 * t.cos(),
                    (0.6 * (3.1 * t).sin(), 0.5 * (1.7 * t).cos()),
                )
            })
            .collect();
        let centroids = at
            .iter()
            .enumerate()
            .map(|(r, &a)| {
                truth
                    .iter()
                    .enumerate()
                    .map(|(k, h)| {
                        let (x, y) = h.apply(a);
                        let own = if moving == Some(r) {
                            1.5 * (k as f64 / 7.0).sin()
                        } else {
                            0.0
                        };
                        centroid(Some((x, y + own)))
                    })
                    .collect()
            })
            .collect();
        let tracks = Tracks {
            centroids,
            first: at.to_vec(),
            refused: vec![0; at.len()],
            depth: FrameDepth::default(),
            evidence: Vec::new(),
        };
        (tracks, truth)
    }

    const AT: [(f64, f64); 5] = [
        (10.0, 10.0),
        (190.0, 12.0),
        (185.0, 150.0),
        (15.0, 148.0),
        (100.0, 20.0),
    ];

    #[test]
    fn references_that_take_every_targets_motion_are_warned_of() {
        let (refs, truth) = tracks(&AT, 300, None);
        let m = estimate(&refs, None, (200, 160)).unwrap();
        // a target that moves exactly as the references (they are on the structure with it)
        let with = |own: f64| Tracks {
            centroids: vec![truth
                .iter()
                .enumerate()
                .map(|(k, h)| {
                    let (x, y) = h.apply((60.0, 90.0));
                    centroid(Some((x, y + own * (k as f64 / 5.0).sin())))
                })
                .collect()],
            first: vec![(60.0, 90.0)],
            refused: vec![0],
            depth: FrameDepth::default(),
            evidence: Vec::new(),
        };
        let all = with(0.0);
        let text = m.describe(&all, &m.compensate(&all), false);
        assert!(
            text.contains("warning: the references move with the targets"),
            "{text}"
        );
        // a target with a motion of its own beside the camera's: no warning
        let own = with(0.5);
        let text = m.describe(&own, &m.compensate(&own), false);
        assert!(!text.contains("warning"), "{text}");
    }

    #[test]
    fn a_similarity_is_taken_out_exactly_and_a_moving_reference_is_named() {
        let (refs, truth) = tracks(&AT, 300, Some(2));
        let m = estimate(&refs, None, (200, 160)).unwrap();
        assert_eq!(m.model, Model::Similarity);
        assert_eq!(m.used, vec![1, 2, 4, 5]);
        assert_eq!(m.left_out.len(), 1);
        assert!(
            m.left_out[0].1.contains("moves against the others"),
            "{:?}",
            m.left_out
        );
        // a target at (60, 90) in the anchors' image comes back where it was, whatever the
        // camera did (the anchors are the median positions, close to the truth's frame 0)
        let target = Tracks {
            centroids: vec![truth
                .iter()
                .map(|h| centroid(Some(h.apply((60.0, 90.0)))))
                .collect()],
            first: vec![(60.0, 90.0)],
            refused: vec![0],
            depth: FrameDepth::default(),
            evidence: Vec::new(),
        };
        let c = m.compensate(&target);
        let xs: Vec<f64> = c.centroids[0].iter().map(|c| f64::from(c.cx)).collect();
        let ys: Vec<f64> = c.centroids[0].iter().map(|c| f64::from(c.cy)).collect();
        assert!(
            centred_rms(&xs) < 2e-3 && centred_rms(&ys) < 2e-3,
            "{} {}",
            centred_rms(&xs),
            centred_rms(&ys)
        );
    }

    #[test]
    fn too_few_references_for_the_model_and_a_lost_one_are_named() {
        let (mut refs, _) = tracks(&AT[..4], 100, None);
        for c in refs.centroids[1].iter_mut().take(30) {
            *c = centroid(None);
        }
        let e = estimate(&refs, Some(Model::Homography), (200, 160)).unwrap_err();
        let s = format!("{e:#}");
        assert!(
            s.contains("homography needs 4") && s.contains("r2 lost in 30 of 100"),
            "{s}"
        );
        let m = estimate(&refs, None, (200, 160)).unwrap();
        assert_eq!(m.used, vec![1, 3, 4]);
        // two references, one moving: which one cannot be told
        let (two, _) = tracks(&AT[..2], 100, Some(1));
        let e = estimate(&two, Some(Model::Translation), (200, 160)).unwrap_err();
        assert!(format!("{e:#}").contains("cannot be told"), "{e:#}");
    }

    #[test]
    fn a_camera_that_pans_is_a_homography_and_a_similarity_is_refused() {
        // references on a plane seen by a camera that pans a little about its vertical axis
        let at = [
            (10.0, 10.0),
            (190.0, 12.0),
            (185.0, 150.0),
            (15.0, 148.0),
            (100.0, 20.0),
            (60.0, 120.0),
        ];
        let view = |k: usize| {
            // degrees: the plane turns about its vertical axis, a projective map of the image
            let pan = 10.0 * (k as f64 / 9.0).sin();
            let shift =
                Homography::similarity((0.0, 0.0), 0.0, 1.0, (2.0 * (k as f64 / 5.0).cos(), 0.0));
            shift.after(
                &vibcam_common::geometry::plane_view(pan, 800.0, 800.0, (100.0, 80.0)).after(
                    &vibcam_common::geometry::plane_view(0.0, 800.0, 800.0, (100.0, 80.0))
                        .inverse()
                        .unwrap(),
                ),
            )
        };
        let frames = 200;
        let track = |p: (f64, f64)| -> Vec<Centroid> {
            (0..frames)
                .map(|k| centroid(Some(view(k).apply(p))))
                .collect()
        };
        let refs = Tracks {
            centroids: at.iter().map(|&p| track(p)).collect(),
            first: at.to_vec(),
            refused: vec![0; at.len()],
            depth: FrameDepth::default(),
            evidence: Vec::new(),
        };
        let target = Tracks {
            centroids: vec![track((150.0, 60.0))],
            first: vec![(150.0, 60.0)],
            refused: vec![0],
            depth: FrameDepth::default(),
            evidence: Vec::new(),
        };
        let spread = |m: &CameraMotion| {
            let c = m.compensate(&target);
            let xs: Vec<f64> = c.centroids[0].iter().map(|c| f64::from(c.cx)).collect();
            centred_rms(&xs)
        };
        let h = estimate(&refs, Some(Model::Homography), (200, 160)).unwrap();
        assert_eq!(h.used.len(), 6);
        // the pan moves the target by px; the homography takes it out to the f32 text
        let raw: Vec<f64> = target.centroids[0]
            .iter()
            .map(|c| f64::from(c.cx))
            .collect();
        assert!(centred_rms(&raw) > 1.0, "{}", centred_rms(&raw));
        assert!(spread(&h) < 1e-3, "{}", spread(&h));
        // a similarity cannot explain the references: named, with the way out
        let e = estimate(&refs, Some(Model::Similarity), (200, 160)).unwrap_err();
        assert!(
            format!("{e:#}").contains("$camera_model homography"),
            "{e:#}"
        );
    }

    #[test]
    fn subsets_are_all_combinations() {
        let s = subsets(&[3, 5, 7, 9], 2);
        assert_eq!(s.len(), 6);
        assert_eq!(s[0], vec![3, 5]);
        assert_eq!(s[5], vec![7, 9]);
        assert_eq!(subsets(&[1, 2], 4).len(), 0);
        // many references: a spread of at most about MAX_SETS sets
        let many: Vec<usize> = (0..64).collect();
        let s = subsets(&many, 4);
        assert!(
            s.len() <= MAX_SETS + 1 && s.len() > MAX_SETS / 2,
            "{}",
            s.len()
        );
        assert_eq!(s[0], vec![0, 1, 2, 3]);
    }
}
