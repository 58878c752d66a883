//! Chosen points (`--points FILE.csv`): each target followed in its own window, which moves with
//! it, through firmware-core's centroid restricted to the window (its ROI) at the window's own
//! threshold. Nothing outside a window is ever looked at, so a bright wall, a phone or a hand
//! elsewhere in a cluttered scene cannot be taken for a target.
//!
//! The file: header `target,x,y,w,h` and optionally `threshold` and `group` (a whole number:
//! targets that move together, used by `--tracker lk`); `target` the integers 1..K,
//! each once; `x, y` the target's centre in the first frame, px (origin at the centre of the
//! top-left pixel, x right, y down; fractions allowed); `w, h` the window, px (>= 3). A window
//! of `w` columns centred on `x` starts at column `round(x - (w - 1) / 2)`: an odd `w` is
//! centred on the nearest pixel, an even one has its extra column on the right when `x` is a
//! whole pixel. Every window must lie inside the first frame.
//!
//! Per frame and target: the window is centred on where the target was last seen; the centroid
//! of the pixels above the threshold in it is the target's position. A target that touches
//! the window's edge may reach past it: the window is re-centred on that partial centroid and
//! measured once more in the same frame (so a motion of up to about half a window per frame is
//! followed); still at the edge, or nothing above the threshold, or a window that would leave
//! the frame: a lost frame of that target, counted, and the window stays where the target was
//! last seen (never a search of the whole frame, which in a cluttered scene finds the wall).
//! Thresholds: `--threshold T` for all, the file's `threshold` column per target, or `--threshold
//! auto`: Otsu's threshold of each window in the first frame.

use crate::shared_motion::{shared_offset, BlockTemplate, Integral};
use crate::tracks::{lost, Tracks};
use crate::verify::{forward_backward_textured, Doubt, Evidence, FB_BOUND_PX};
use firmware_core::centroid::{Centroid, CentroidConfig, Flags, Roi};
use std::path::Path;
use vibcam_readers::bad_input;
use vibcam_readers::frames::{FrameSource, GreyFrame};

/// One chosen point.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Target number, 1..=K.
    pub target: usize,
    /// Centre in the first frame, px.
    pub xy: (f64, f64),
    /// Window size, px.
    pub size: (u32, u32),
    /// The file's threshold for this target, if it has the column.
    pub threshold: Option<u16>,
    /// The file's group for this target, if it has the column: targets of one group move
    /// together (a storey, a beam), and `--tracker lk` catches their large jumps by the motion
    /// they share ([`crate::shared_motion`]).
    pub group: Option<u32>,
}

/// How each window's threshold is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ThresholdRule {
    /// One level for every window (the file's `threshold` column overrides it per target).
    Level(u16),
    /// Otsu's threshold of each window in the first frame (the file's column overrides it).
    Auto,
    /// Each window's own, from the file's `threshold` column, which every row must then have.
    FromFile,
}

/// Reads and checks a points file; errors name the file and row (the header is row 1).
pub fn read_points(path: &Path) -> anyhow::Result<Vec<Point>> {
    let name = path.display().to_string();
    let (mut rdr, header) = vibcam_readers::csvio::open_with_header(path, &name, false)?;
    let cols = PointColumns::of(&header, &name)?;
    let mut points: Vec<Point> = Vec::new();
    for (i, rec) in rdr.records().enumerate() {
        let row = i + 2;
        let rec = rec.map_err(|e| bad_input(format!("{name}: row {row}: {e}")))?;
        let p = cols.point(&rec, (&name, row))?;
        if points.iter().any(|q| q.target == p.target) {
            return Err(bad_input(format!(
                "{name}: row {row}: target {} is given twice",
                p.target
            )));
        }
        points.push(p);
    }
    if points.is_empty() {
        return Err(bad_input(format!("{name}: no points (only a header)")));
    }
    points.sort_by_key(|p| p.target);
    if let Some((k, p)) = points.iter().enumerate().find(|(k, p)| p.target != k + 1) {
        return Err(bad_input(format!(
            "{name}: targets must be numbered 1 to {} without gaps; target {} is missing",
            points.len(),
            p.target.min(k + 1)
        )));
    }
    Ok(points)
}

/// The columns of a points file: `target,x,y,w,h` (needed) and the optional `threshold` and
/// `group`.
struct PointColumns {
    needed: [usize; 5],
    threshold: Option<usize>,
    group: Option<usize>,
}

impl PointColumns {
    /// The columns of `header`; a needed one missing is an error naming the file `name`.
    fn of(header: &[String], name: &str) -> anyhow::Result<Self> {
        let col = |c: &str| header.iter().position(|h| h == c);
        let mut needed = [0; 5];
        for (slot, c) in needed.iter_mut().zip(["target", "x", "y", "w", "h"]) {
            *slot = col(c).ok_or_else(|| {
                bad_input(format!(
                    "{name}: no column `{c}` (the header must be target,x,y,w,h[,threshold][,group]; \
                     it is \
                     {})",
                    header.join(",")
                ))
            })?;
        }
        Ok(PointColumns {
            needed,
            threshold: col("threshold"),
            group: col("group"),
        })
    }

    /// The point of one row (`row` its number in the file `name`, the header row 1).
    fn point(&self, rec: &csv::StringRecord, (name, row): (&str, usize)) -> anyhow::Result<Point> {
        let cell = |j: usize, c: &str| -> anyhow::Result<&str> {
            rec.get(j)
                .filter(|v| !v.is_empty())
                .ok_or_else(|| bad_input(format!("{name}: row {row}: `{c}` is empty")))
        };
        let num = |j: usize, c: &str| -> anyhow::Result<f64> {
            let v = cell(j, c)?;
            v.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    bad_input(format!("{name}: row {row}: `{c}` is `{v}`, not a number"))
                })
        };
        let whole = |j: usize, c: &str, min: f64| -> anyhow::Result<f64> {
            let v = num(j, c)?;
            if v.fract() != 0.0 || v < min || v > 65_536.0 {
                return Err(bad_input(format!(
                    "{name}: row {row}: `{c}` is {v}: a whole number from {min} to 65536 is \
                     needed"
                )));
            }
            Ok(v)
        };
        let optional = |j: Option<usize>, c: &str| -> anyhow::Result<Option<f64>> {
            match j {
                Some(j) if !rec.get(j).unwrap_or("").is_empty() => Ok(Some(whole(j, c, 0.0)?)),
                _ => Ok(None),
            }
        };
        let [target, x, y, w, h] = self.needed;
        Ok(Point {
            target: whole(target, "target", 1.0)? as usize,
            xy: (num(x, "x")?, num(y, "y")?),
            size: (whole(w, "w", 3.0)? as u32, whole(h, "h", 3.0)? as u32),
            threshold: optional(self.threshold, "threshold")?.map(|t| t.min(65_535.0) as u16),
            group: optional(self.group, "group")?.map(|g| g as u32),
        })
    }
}

/// The window of `size` centred on `(x, y)`, if it lies inside a `w x h` frame.
pub fn window(xy: (f64, f64), size: (u32, u32), (w, h): (usize, usize)) -> Option<Roi> {
    let x0 = (xy.0 - (f64::from(size.0) - 1.0) / 2.0).round();
    let y0 = (xy.1 - (f64::from(size.1) - 1.0) / 2.0).round();
    let fits = x0 >= 0.0
        && y0 >= 0.0
        && x0 + f64::from(size.0) <= w as f64
        && y0 + f64::from(size.1) <= h as f64;
    fits.then_some(Roi {
        x: x0 as u32,
        y: y0 as u32,
        width: size.0,
        height: size.1,
    })
}

/// Otsu's threshold of the pixels of `roi`: the level that best splits them into two classes
/// (largest between-class variance), on a 256-bin histogram of the window's range.
pub fn otsu(frame: &GreyFrame, roi: Roi) -> u16 {
    let (w, _) = frame.dimensions();
    let value = |x: u32, y: u32| -> u32 {
        let i = y as usize * w + x as usize;
        match frame {
            GreyFrame::U8 { data, .. } => u32::from(data[i]),
            GreyFrame::U16 { data, .. } => u32::from(data[i]),
        }
    };
    let pixels: Vec<u32> = (roi.y..roi.y + roi.height)
        .flat_map(|y| (roi.x..roi.x + roi.width).map(move |x| (x, y)))
        .map(|(x, y)| value(x, y))
        .collect();
    let (lo, hi) = pixels
        .iter()
        .fold((u32::MAX, 0), |(a, b), &v| (a.min(v), b.max(v)));
    if hi <= lo {
        return hi.min(65_535) as u16;
    }
    let bins = 256usize;
    let span = f64::from(hi - lo);
    let bin =
        |v: u32| (((f64::from(v - lo)) / span * (bins - 1) as f64).round() as usize).min(bins - 1);
    let mut hist = vec![0f64; bins];
    for &v in &pixels {
        hist[bin(v)] += 1.0;
    }
    let total = pixels.len() as f64;
    let sum_all: f64 = hist.iter().enumerate().map(|(i, n)| i as f64 * n).sum();
    let (mut w0, mut sum0, mut best, mut best_i) = (0.0, 0.0, -1.0, 0usize);
    for (i, n) in hist.iter().enumerate() {
        w0 += n;
        sum0 += i as f64 * n;
        let w1 = total - w0;
        if w0 == 0.0 || w1 == 0.0 {
            continue;
        }
        let (m0, m1) = (sum0 / w0, (sum_all - sum0) / w1);
        let between = w0 * w1 * (m0 - m1).powi(2);
        if between > best {
            (best, best_i) = (between, i);
        }
    }
    // pixels of bin <= best_i are the dark class: the threshold is the top of that bin
    let level = f64::from(lo) + (best_i as f64 + 0.5) * span / (bins - 1) as f64;
    (level.floor() as u32).min(65_535) as u16
}

/// How each window is followed: the thresholded centroid (the default), or Lucas-Kanade.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PointTracker {
    /// firmware-core's centroid in the window at the window's threshold (module documentation).
    Centroid(ThresholdRule),
    /// firmware-core's Lucas-Kanade tracker ([`firmware_core::lk`]): the window in the first
    /// frame is the template; `search_px` the coarse search range (default: half the window's
    /// larger side).
    Lk {
        /// `--search-px`.
        search_px: Option<u16>,
    },
    /// Per target, the centroid where its first-frame window holds a blob at its threshold,
    /// Lucas-Kanade otherwise ([`crate::choose`]).
    Auto {
        /// The blob's threshold (the file's `threshold` column overrides it per target).
        rule: ThresholdRule,
        /// `--search-px` of the Lucas-Kanade targets.
        search_px: Option<u16>,
    },
}

use vibcam_chain::lk::{AnyLk, LK_PIXELS, LK_ROW};

/// What tracking the points found, beside the tracks.
#[derive(Debug, Clone, PartialEq)]
pub struct PointsInfo {
    /// Each target's threshold, as used (`None` for a target Lucas-Kanade followed: it has
    /// none; empty when Lucas-Kanade followed every target).
    pub thresholds: Vec<Option<u16>>,
    /// With `--tracker auto`: each target's tracker and why (empty when the tracker was named).
    pub chosen: Vec<String>,
    /// Each target's window size, px.
    pub sizes: Vec<(u32, u32)>,
    /// The groups of targets that moved together (0-based target indices; Lucas-Kanade), and
    /// how they were found.
    pub groups: Option<Grouping>,
    /// Warnings on how the targets were followed (look-alikes followed alone).
    pub warnings: Vec<String>,
}

/// Pairs of targets whose windows in `frame` look alike (ZNCC of the pixels at least 0.9,
/// windows of one size): a target followed alone can be taken for such a neighbour after a
/// lost frame, when the neighbour passes where it was last seen. 0-based indices.
pub fn look_alikes(frame: &GreyFrame, points: &[Point]) -> Vec<(usize, usize)> {
    let dims = frame.dimensions();
    let pixels = |p: &Point| -> Option<Vec<f64>> {
        let roi = window(p.xy, p.size, dims)?;
        let mut v = Vec::with_capacity((roi.width * roi.height) as usize);
        for y in roi.y..roi.y + roi.height {
            for x in roi.x..roi.x + roi.width {
                let i = y as usize * dims.0 + x as usize;
                v.push(match frame {
                    GreyFrame::U8 { data, .. } => f64::from(data[i]),
                    GreyFrame::U16 { data, .. } => f64::from(data[i]),
                });
            }
        }
        let m = v.iter().sum::<f64>() / v.len().max(1) as f64;
        let norm = v.iter().map(|x| (x - m).powi(2)).sum::<f64>().sqrt();
        (norm > 0.0).then(|| v.iter().map(|x| (x - m) / norm).collect())
    };
    let windows: Vec<Option<Vec<f64>>> = points.iter().map(pixels).collect();
    // every pair (hundreds of thousands for a dense field): each target's row of pairs on
    // its own core, in target order
    use rayon::prelude::*;
    (0..points.len())
        .into_par_iter()
        .flat_map_iter(|a| {
            let windows = &windows;
            (a + 1..points.len()).filter_map(move |b| {
                let (Some(wa), Some(wb), true) =
                    (&windows[a], &windows[b], points[a].size == points[b].size)
                else {
                    return None;
                };
                (dot(wa, wb) >= 0.9).then_some((a, b))
            })
        })
        .collect()
}

/// `sum x_i y_i` in four running sums (so that it vectorises), added pairwise at the end.
fn dot(x: &[f64], y: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let (xc, yc) = (x.chunks_exact(4), y.chunks_exact(4));
    let tail: f64 = xc
        .remainder()
        .iter()
        .zip(yc.remainder())
        .map(|(a, b)| a * b)
        .sum();
    for (a, b) in xc.zip(yc) {
        for ((s, a), b) in acc.iter_mut().zip(a).zip(b) {
            *s += a * b;
        }
    }
    (acc[0] + acc[2]) + (acc[1] + acc[3]) + tail
}

/// The groups `--tracker lk` followed targets in.
#[derive(Debug, Clone, PartialEq)]
pub struct Grouping {
    /// Groups of two or more targets (0-based indices), in order of their first target.
    pub groups: Vec<Vec<usize>>,
    /// `None`: from the points file's `group` column; `Some(frames)`: found from the motion of
    /// the first `frames` frames ([`motion_groups`]); `Some(0)`: the targets moved too little
    /// for groups to be found, so none were used.
    pub found_in: Option<usize>,
}

impl Grouping {
    /// The report's line on the groups.
    pub fn describe(&self, targets: &[usize]) -> String {
        let list: Vec<String> = self
            .groups
            .iter()
            .map(|g| {
                let names: Vec<String> = g.iter().map(|&t| targets[t].to_string()).collect();
                format!("[{}]", names.join(" "))
            })
            .collect();
        let list = if list.is_empty() {
            "none".to_string()
        } else {
            list.join(", ")
        };
        match self.found_in {
            None => format!("groups (the points file's `group` column): {list}"),
            Some(0) => "groups: none (the targets moved less than a quarter of their window; \
                 no look-alike could be reached)"
                .to_string(),
            Some(n) => format!(
                "groups found from the motion of the first {n} frames (each target's track \
                 within 5 % of its motion and 0.2 px of a member's, the group moving as one \
                 rigid part, turning allowed, within the same bound; each group's shared \
                 motion catches its members' large jumps; a `group` column in the points file \
                 sets them instead): {list}"
            ),
        }
    }
}

/// Groups of targets that moved together over the tracks so far (`history[t][f]`: target
/// `t`'s displacement in frame `f`, `None` when lost; `at[t]` its first-frame position, px):
/// a target joins a group when its track differs from some member's by an RMS of at most 5 %
/// of their motion's RMS plus 0.2 px (tracking noise; over at least three frames both were
/// tracked in), and the group with it still moves as one rigid part: per frame a translation
/// and a small rotation about the members' centre explain every member's displacement within
/// the same bound ([`rigid_misfit`]). So a beam that turns as it moves (its ends apart by more
/// than the bound, each tag close to its neighbour) stays one group, and parts that move
/// differently (two storeys of one mode, at 75 % of each other's amplitude; storeys one above
/// the other, whose difference a turn of one tag pair could explain but not of a whole row)
/// stay apart. Groups of one are left out.
pub fn motion_groups(history: &[Vec<Option<(f32, f32)>>], at: &[(f64, f64)]) -> Vec<Vec<usize>> {
    let close = |a: usize, b: usize| {
        let (mut d2, mut m2, mut n) = (0.0f64, 0.0f64, 0usize);
        for (p, q) in history[a].iter().zip(&history[b]) {
            if let (Some(p), Some(q)) = (p, q) {
                let (px, py, qx, qy) = (
                    f64::from(p.0),
                    f64::from(p.1),
                    f64::from(q.0),
                    f64::from(q.1),
                );
                d2 += (px - qx).powi(2) + (py - qy).powi(2);
                m2 += (px * px + py * py + qx * qx + qy * qy) / 2.0;
                n += 1;
            }
        }
        if n < 3 {
            return false;
        }
        let (d, m) = ((d2 / n as f64).sqrt(), (m2 / n as f64).sqrt());
        d <= 0.05 * m + 0.2
    };
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for t in 0..history.len() {
        let joins = |g: &Vec<usize>| {
            if !g.iter().any(|&m| close(m, t)) {
                return false;
            }
            let mut with = g.clone();
            with.push(t);
            let (misfit, motion) = rigid_misfit(history, at, &with);
            misfit <= 0.05 * motion + 0.2
        };
        match groups.iter().position(joins) {
            Some(g) => groups[g].push(t),
            None => groups.push(vec![t]),
        }
    }
    groups.retain(|g| g.len() > 1);
    groups
}

/// How far `members` are from moving as one rigid part: per frame, the least-squares
/// translation and small rotation (about the members' centre in `at`) of the members tracked
/// there (two or more); the RMS of what they leave, and the RMS of the motion, px, over every
/// member-frame fitted.
pub fn rigid_misfit(
    history: &[Vec<Option<(f32, f32)>>],
    at: &[(f64, f64)],
    members: &[usize],
) -> (f64, f64) {
    let frames = members.iter().map(|&m| history[m].len()).min().unwrap_or(0);
    let (mut r2, mut m2, mut n) = (0.0f64, 0.0f64, 0usize);
    // frame `f` of every member's track
    #[allow(clippy::needless_range_loop)]
    for f in 0..frames {
        let seen: Vec<((f64, f64), (f64, f64))> = members
            .iter()
            .filter_map(|&m| history[m][f].map(|d| (at[m], (f64::from(d.0), f64::from(d.1)))))
            .collect();
        if seen.len() < 2 {
            continue;
        }
        let k = seen.len() as f64;
        let c = seen
            .iter()
            .fold((0.0, 0.0), |a, (p, _)| (a.0 + p.0 / k, a.1 + p.1 / k));
        let t = seen
            .iter()
            .fold((0.0, 0.0), |a, (_, d)| (a.0 + d.0 / k, a.1 + d.1 / k));
        // a small rotation w moves (x, y) about c by w (-(y - cy), x - cx)
        let (mut num, mut den) = (0.0, 0.0);
        for ((x, y), (dx, dy)) in &seen {
            let (rx, ry) = (x - c.0, y - c.1);
            num += rx * (dy - t.1) - ry * (dx - t.0);
            den += rx * rx + ry * ry;
        }
        let w = if den > 0.0 { num / den } else { 0.0 };
        for ((x, y), (dx, dy)) in &seen {
            let (rx, ry) = (x - c.0, y - c.1);
            r2 += (dx - t.0 + w * ry).powi(2) + (dy - t.1 - w * rx).powi(2);
            m2 += dx * dx + dy * dy;
            n += 1;
        }
    }
    if n == 0 {
        return (f64::INFINITY, 0.0);
    }
    ((r2 / n as f64).sqrt(), (m2 / n as f64).sqrt())
}

/// Follows every point through `source` (see the module documentation). `config` gives the
/// centroid's mode and saturation.
pub fn track_points(
    source: &FrameSource,
    fps: f64,
    points: &[Point],
    config: &CentroidConfig,
    tracker: PointTracker,
) -> anyhow::Result<(Tracks, PointsInfo)> {
    let rule = match tracker {
        PointTracker::Centroid(rule) => rule,
        PointTracker::Lk { search_px } => {
            return track_points_lk(source, fps, points, config, search_px)
        }
        PointTracker::Auto { rule, search_px } => {
            return track_points_auto(source, fps, points, config, (rule, search_px))
        }
    };
    let mut tracks = empty_tracks(points);
    let mut last: Vec<(f64, f64)> = tracks.first.clone();
    let mut thresholds: Vec<u16> = Vec::new();
    let mut size0: Option<(usize, usize)> = None;
    source.for_each(fps, |label, frame| {
        tracks.depth.add(frame);
        if is_first(&mut size0, frame, &label)? {
            thresholds = first_windows(points, frame, rule, &label)?;
        }
        for (t, p) in points.iter().enumerate() {
            let cfg = CentroidConfig {
                threshold: thresholds[t],
                ..*config
            };
            let c = follow(frame, &cfg, last[t], p.size, &label)?;
            if let Some((x, y)) = c.position() {
                last[t] = (f64::from(x), f64::from(y));
                // where the target is, as `--targets` states it: its centroid in frame 1
                if tracks.centroids[t].is_empty() {
                    tracks.first[t] = last[t];
                }
            }
            tracks.centroids[t].push(c);
        }
        Ok(())
    })?;
    Ok((
        tracks,
        PointsInfo {
            thresholds: thresholds.into_iter().map(Some).collect(),
            sizes: points.iter().map(|p| p.size).collect(),
            groups: None,
            warnings: Vec::new(),
            chosen: Vec::new(),
        },
    ))
}

/// [`track_points`] with Lucas-Kanade: each window of the first frame is its target's template
/// (firmware-core's [`firmware_core::lk::LkTracker`]); a frame where a target is lost (a flat
/// template, the window at the frame's edge, saturation, no match within the search range) is a
/// lost frame of that target with the reason in its flags. It has no threshold: `thresholds` is empty.
pub fn track_points_lk(
    source: &FrameSource,
    fps: f64,
    points: &[Point],
    config: &CentroidConfig,
    search_px: Option<u16>,
) -> anyhow::Result<(Tracks, PointsInfo)> {
    let k = points.len();
    let mut trackers = lk_trackers(points, config, search_px)?;
    let mut tracks = empty_tracks(points);
    // per target: the template could not be taken (why), so every frame is lost
    let mut refused: Vec<Option<Flags>> = vec![None; k];
    // targets that move together: the file's groups, or found from the first frames' motion
    let explicit = points.iter().any(|p| p.group.is_some());
    let mut groups = file_groups(points);
    let mut finding = (!explicit && k > 1).then(|| MotionGroups::new(points));
    let mut alike: Vec<(usize, usize)> = Vec::new();
    let mut templates: Vec<BlockTemplate> = Vec::new();
    let mut size0: Option<(usize, usize)> = None;
    // until the groups are found, no search reaches past half a window
    let caps: Vec<u16> = trackers
        .iter()
        .map(|t| t.config().width.max(t.config().height) / 2)
        .collect();
    let mut checks = Checks::new(points, config)?;
    tracks.evidence = vec![Vec::new(); k];
    source.for_each(fps, |label, frame| {
        tracks.depth.add(frame);
        if is_first(&mut size0, frame, &label)? {
            refused = set_templates(&mut trackers, points, frame, &label)?;
            checks.origins = points
                .iter()
                .map(|p| first_window(p, frame.dimensions(), &label).map(|r| (r.x, r.y)))
                .collect::<anyhow::Result<_>>()?;
            alike = look_alikes(frame, points);
            if !groups.is_empty() || finding.is_some() {
                templates = block_templates(points, frame, &label)?;
            }
        }
        let deciding = finding.as_ref().is_some_and(|f| f.found_in.is_none());
        let checked = track_frame_lk(
            frame,
            (&mut trackers, &mut checks),
            &refused,
            (&groups, &templates),
            deciding.then_some(caps.as_slice()),
        )?;
        if let (true, Some(f)) = (deciding, finding.as_mut()) {
            if let Some(found) = f.observe(checked.iter().map(|(r, e)| (r, e.doubt.is_none()))) {
                groups = found;
            }
        }
        for (t, p) in points.iter().enumerate() {
            let (c, e) = checks.take(t, p, refused[t], &checked[t]);
            tracks.centroids[t].push(c);
            tracks.evidence[t].push(e);
        }
        checks.prev = Some(frame.clone());
        Ok(())
    })?;
    crate::verify::verify_record(&mut tracks, &groups);
    let mut warnings = alone_warning(points, &alike, &groups);
    warnings.extend(aperture_warning(points, &trackers, &refused));
    let grouping = Grouping {
        groups,
        found_in: finding.map(|f| f.found_in.unwrap_or(0)),
    };
    Ok((
        tracks,
        PointsInfo {
            thresholds: Vec::new(),
            sizes: points.iter().map(|p| p.size).collect(),
            groups: (k > 1).then_some(grouping),
            warnings,
            chosen: Vec::new(),
        },
    ))
}

/// Per target, the tracker its first-frame window asks for (at its threshold in `levels`): the
/// reasons in words, and the targets the blob centroid follows.
fn choose_trackers(
    points: &[Point],
    frame: &GreyFrame,
    levels: &[u16],
    label: &str,
) -> anyhow::Result<(Vec<String>, Vec<usize>)> {
    let mut chosen = Vec::with_capacity(points.len());
    let mut blob = Vec::new();
    for (t, p) in points.iter().enumerate() {
        let roi = first_window(p, frame.dimensions(), label)?;
        chosen.push(match crate::choose::separates(frame, roi, levels[t]) {
            Ok(why) => {
                blob.push(t);
                format!("blob centroid: {why}")
            }
            Err(why) => format!("Lucas-Kanade: {why}"),
        });
    }
    Ok((chosen, blob))
}

/// [`track_points`] with `--tracker auto`: each target's first-frame window decides
/// ([`crate::choose::separates`]); the blob targets are followed by the centroid, and those
/// whose blob does not hold through the record ([`crate::choose::blob_holds`]) join the rest,
/// followed by Lucas-Kanade with its checks and groups. `chosen` says per target which and why.
fn track_points_auto(
    source: &FrameSource,
    fps: f64,
    points: &[Point],
    config: &CentroidConfig,
    (rule, search_px): (ThresholdRule, Option<u16>),
) -> anyhow::Result<(Tracks, PointsInfo)> {
    let k = points.len();
    let (label, frame) = source
        .frame_at(fps, 0)?
        .ok_or_else(|| bad_input("the recording has no frame to choose the trackers in"))?;
    let levels = first_windows(points, &frame, rule, &label)?;
    let (mut chosen, blob) = choose_trackers(points, &frame, &levels, &label)?;
    let mut tracks = empty_tracks(points);
    tracks.evidence = vec![Vec::new(); k];
    let mut thresholds = vec![None; k];
    let mut by_lk: Vec<usize> = (0..k).filter(|t| !blob.contains(t)).collect();
    if !blob.is_empty() {
        let sub: Vec<Point> = blob
            .iter()
            .map(|&t| Point {
                threshold: Some(levels[t]),
                ..points[t].clone()
            })
            .collect();
        let centroid = PointTracker::Centroid(ThresholdRule::FromFile);
        let (mut bt, _) = track_points(source, fps, &sub, config, centroid)?;
        for (i, &t) in blob.iter().enumerate() {
            match crate::choose::blob_holds(&bt.centroids[i]) {
                Ok(()) => {
                    tracks.evidence[t] = vec![Evidence::default(); bt.centroids[i].len()];
                    tracks.centroids[t] = std::mem::take(&mut bt.centroids[i]);
                    tracks.first[t] = bt.first[i];
                    thresholds[t] = Some(levels[t]);
                }
                Err(e) => {
                    chosen[t] = format!("Lucas-Kanade: the blob at threshold {} {e}", levels[t]);
                    by_lk.push(t);
                }
            }
        }
        tracks.depth = bt.depth;
    }
    by_lk.sort_unstable();
    let (mut groups, mut warnings) = (None, Vec::new());
    if !by_lk.is_empty() {
        let sub: Vec<Point> = by_lk.iter().map(|&t| points[t].clone()).collect();
        let (mut lt, li) = track_points_lk(source, fps, &sub, config, search_px)?;
        for (i, &t) in by_lk.iter().enumerate() {
            tracks.centroids[t] = std::mem::take(&mut lt.centroids[i]);
            tracks.evidence[t] = std::mem::take(&mut lt.evidence[i]);
            tracks.refused[t] = lt.refused[i];
        }
        tracks.depth = lt.depth;
        groups = li.groups.map(|g| Grouping {
            groups: g
                .groups
                .iter()
                .map(|grp| grp.iter().map(|&i| by_lk[i]).collect())
                .collect(),
            found_in: g.found_in,
        });
        warnings = li.warnings;
    }
    Ok((
        tracks,
        PointsInfo {
            thresholds,
            sizes: points.iter().map(|p| p.size).collect(),
            groups,
            warnings,
            chosen,
        },
    ))
}

/// One Lucas-Kanade tracker per point, its window the point's, `search_px` its search.
fn lk_trackers(
    points: &[Point],
    config: &CentroidConfig,
    search_px: Option<u16>,
) -> anyhow::Result<Vec<AnyLk>> {
    lk_trackers_sampled(points, config, search_px, None)
}

/// [`lk_trackers`] sampling between pixels by `interpolation` (`None`: the default, the
/// template's spline).
fn lk_trackers_sampled(
    points: &[Point],
    config: &CentroidConfig,
    search_px: Option<u16>,
    interpolation: Option<firmware_core::lk::Interpolation>,
) -> anyhow::Result<Vec<AnyLk>> {
    use firmware_core::lk::LkConfig;
    points
        .iter()
        .map(|p| {
            let (w, h) = (
                u16::try_from(p.size.0).unwrap_or(u16::MAX),
                u16::try_from(p.size.1).unwrap_or(u16::MAX),
            );
            let mut cfg = LkConfig::new(w, h);
            if let Some(r) = search_px {
                cfg.search = r;
            }
            if let Some(i) = interpolation {
                cfg.interpolation = i;
            }
            cfg.saturation = config.saturation.unwrap_or(0);
            AnyLk::try_new(cfg).map_err(|e| {
                bad_input(format!(
                    "target {}: {e} ($tracker lk windows: at most {} pixels wide and \
                     {LK_PIXELS} pixels in all)",
                    p.target,
                    LK_ROW - 7
                ))
            })
        })
        .collect()
}

/// Each tracker's template from its point's window in the first frame; per target why it was
/// refused (a flat window, or one at the frame's edge), if it was.
fn set_templates(
    trackers: &mut [AnyLk],
    points: &[Point],
    frame: &GreyFrame,
    label: &str,
) -> anyhow::Result<Vec<Option<Flags>>> {
    use firmware_core::lk::LkError;
    let mut refused = Vec::with_capacity(points.len());
    for (tracker, p) in trackers.iter_mut().zip(points) {
        let roi = first_window(p, frame.dimensions(), label)?;
        let r = with_frame(frame, |f| match f {
            AnyFrame::U8(f) => tracker.set_template(&f, roi.x as i32, roi.y as i32),
            AnyFrame::U16(f) => tracker.set_template(&f, roi.x as i32, roi.y as i32),
        })?;
        refused.push(match r {
            Ok(()) => None,
            Err(LkError::Flat) => Some(Flags::FLAT),
            Err(_) => Some(Flags::BORDER),
        });
    }
    Ok(refused)
}

/// Which of `points` firmware-core's Lucas-Kanade refuses in `frame` with `track`'s default
/// settings (a flat window: too little texture in its weaker direction; or one at the frame's
/// edge): what `track --tracker lk` would follow in no frame.
pub fn lk_refusals(points: &[Point], frame: &GreyFrame) -> anyhow::Result<Vec<Option<Flags>>> {
    // one tracker per window size, its template taken again for each point (a tracker holds
    // buffers for the largest window: one per point of a dense field would be hundreds of MB);
    // the threshold plays no part in Lucas-Kanade; no saturation level: the full scale
    let mut refused = Vec::with_capacity(points.len());
    let mut tracker: Vec<AnyLk> = Vec::new();
    for (i, p) in points.iter().enumerate() {
        let one = std::slice::from_ref(p);
        if i == 0 || points[i - 1].size != p.size {
            tracker = lk_trackers(one, &CentroidConfig::binary(0), None)?;
        }
        refused.extend(set_templates(&mut tracker, one, frame, "the first frame")?);
    }
    Ok(refused)
}

/// The groups the points file states (two or more targets with one `group`).
fn file_groups(points: &[Point]) -> Vec<Vec<usize>> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (t, p) in points.iter().enumerate() {
        if let Some(g) = p.group {
            match groups.iter_mut().find(|m| points[m[0]].group == Some(g)) {
                Some(m) => m.push(t),
                None => groups.push(vec![t]),
            }
        }
    }
    groups.retain(|m| m.len() > 1);
    groups
}

/// Every point's window in the first frame as block sums (the groups' shared search).
fn block_templates(
    points: &[Point],
    frame: &GreyFrame,
    label: &str,
) -> anyhow::Result<Vec<BlockTemplate>> {
    let first = Integral::of(frame);
    points
        .iter()
        .map(|p| {
            let roi = first_window(p, frame.dimensions(), label)?;
            Ok(BlockTemplate::new(
                &first,
                (i64::from(roi.x), i64::from(roi.y)),
                p.size,
            ))
        })
        .collect()
}

/// The groups being found from the first frames' motion: the tracks so far, until the largest
/// motion reaches a quarter of the smallest window ([`motion_groups`]).
struct MotionGroups {
    history: Vec<Vec<Option<(f32, f32)>>>,
    /// Each target's first-frame position, px.
    at: Vec<(f64, f64)>,
    quarter: f32,
    /// The frames the groups were found in, once they are.
    found_in: Option<usize>,
}

impl MotionGroups {
    fn new(points: &[Point]) -> MotionGroups {
        MotionGroups {
            history: vec![Vec::new(); points.len()],
            at: points.iter().map(|p| p.xy).collect(),
            quarter: points
                .iter()
                .map(|p| p.size.0.min(p.size.1) as f32 / 4.0)
                .fold(f32::INFINITY, f32::min),
            found_in: None,
        }
    }

    /// Takes one frame's results (each with whether its position stands); the groups once the
    /// motion is large enough.
    fn observe<'a>(
        &mut self,
        results: impl Iterator<Item = (&'a firmware_core::lk::LkResult, bool)>,
    ) -> Option<Vec<Vec<usize>>> {
        for (h, (r, stands)) in self.history.iter_mut().zip(results) {
            h.push(r.displacement().filter(|_| stands));
        }
        let moved = self
            .history
            .iter()
            .flat_map(|h| h.iter().flatten())
            .any(|d| d.0.abs().max(d.1.abs()) >= self.quarter);
        if !moved {
            return None;
        }
        self.found_in = Some(self.history.first().map_or(0, Vec::len));
        Some(motion_groups(&self.history, &self.at))
    }
}

/// A target's position from its tracker's result, or the lost frame with the reason.
fn lk_centroid(p: &Point, r: &firmware_core::lk::LkResult) -> Centroid {
    match r.displacement() {
        Some((dx, dy)) => Centroid {
            cx: (p.xy.0 + f64::from(dx)) as f32,
            cy: (p.xy.1 + f64::from(dy)) as f32,
            moments: firmware_core::centroid::Moments {
                pixels: u64::from(p.size.0) * u64::from(p.size.1),
                ..Default::default()
            },
            flags: Flags::NONE,
        },
        None => lost_because(r.flags),
    }
}

/// The least ratio of a window's weaker to stronger gradient energy (the eigenvalues of its
/// structure tensor) for its position to be measured in both directions: below it the
/// position along the edges is at least ten times less precise than across them, and
/// wanders (the aperture).
pub const APERTURE_RATIO: f64 = 0.01;

/// The warning on windows whose texture is edges in one direction only (a stripe, a beam's
/// edge): they measure the motion across the edges, not along them.
fn aperture_warning(
    points: &[Point],
    trackers: &[AnyLk],
    refused: &[Option<Flags>],
) -> Vec<String> {
    // per image axis measured: the targets whose window measures that axis only
    let mut only: [Vec<String>; 2] = [Vec::new(), Vec::new()];
    let mut worst = 1.0f64;
    for ((p, tr), no) in points.iter().zip(trackers).zip(refused) {
        if no.is_some() {
            continue;
        }
        let [a, _, c] = tr.structure().map(f64::from);
        let (l1, l2) = crate::verify::eigenvalues(tr.structure());
        if l1.is_nan() || l1 <= 0.0 || l2 / l1 >= APERTURE_RATIO {
            continue;
        }
        worst = worst.min(l2 / l1);
        // the strong direction: gradients mostly along y measure y
        let y_axis = (l1 - a).abs() > (l1 - c).abs();
        only[usize::from(y_axis)].push(p.target.to_string());
    }
    let mut out = Vec::new();
    for (axis, names) in only.iter().enumerate() {
        if names.is_empty() {
            continue;
        }
        let (measured, along) = if axis == 1 { ("y", "x") } else { ("x", "y") };
        out.push(format!(
            "targets {}: the window's texture is edges along {along} only (the weaker \
             direction's gradient energy down to {worst:.4} of the stronger, below {}): it \
             measures the motion in {measured}; its {along} position is not measured and \
             wanders (the aperture): read {measured} only ($axis {measured}), or move the \
             window onto texture in both directions",
            names.join(" "),
            APERTURE_RATIO
        ));
    }
    out
}

/// The warning on look-alike targets (`alike`, pairs of indices) followed in no group.
fn alone_warning(points: &[Point], alike: &[(usize, usize)], groups: &[Vec<usize>]) -> Vec<String> {
    let grouped = |t: usize| groups.iter().any(|g| g.contains(&t));
    let mut alone: Vec<usize> = alike
        .iter()
        .flat_map(|&(a, b)| [a, b])
        .filter(|&t| !grouped(t))
        .collect();
    alone.sort_unstable();
    alone.dedup();
    if alone.is_empty() {
        return Vec::new();
    }
    let names: Vec<String> = alone
        .iter()
        .map(|&t| points[t].target.to_string())
        .collect();
    vec![format!(
        "targets {} look like other targets (their first windows match with a ZNCC of 0.9 or \
         more) and are followed alone, in no group: after a lost frame, one can be taken up \
         again on a neighbour that passes where it was last seen (give the targets that move \
         together one `group`, or leave the column out to have groups found)",
        names.join(" ")
    )]
}

/// The forward-backward check's state across frames: a tracker per target for the window at
/// its new position, the previous frame, per target its verified displacement there, its last
/// verified one, whether its last position was taken away, and its window's origin in the
/// first frame.
struct Checks {
    back: Vec<AnyLk>,
    prev: Option<GreyFrame>,
    verified: Vec<Option<(f32, f32)>>,
    last_good: Vec<Option<(f32, f32)>>,
    doubted: Vec<bool>,
    origins: Vec<(u32, u32)>,
}

impl Checks {
    fn new(points: &[Point], config: &CentroidConfig) -> anyhow::Result<Checks> {
        let k = points.len();
        Ok(Checks {
            // a template a frame: Keys' cubic convolution needs none of the spline's per-template
            // moments (most of a template's cost), and its bias of a few hundredths of a pixel
            // is far below the check's bound
            back: lk_trackers_sampled(
                points,
                config,
                Some(0),
                Some(firmware_core::lk::Interpolation::Bicubic),
            )?,
            prev: None,
            verified: vec![None; k],
            last_good: vec![None; k],
            doubted: vec![false; k],
            origins: Vec::new(),
        })
    }

    /// Target `t`'s (point `p`'s) position and evidence in this frame from its checked result
    /// (lost when its template was refused, or a check took the position away), kept for the
    /// next frame's checks.
    fn take(
        &mut self,
        t: usize,
        p: &Point,
        refused: Option<Flags>,
        (r, e): &(firmware_core::lk::LkResult, Evidence),
    ) -> (Centroid, Evidence) {
        let (c, e) = match refused {
            Some(why) => (lost_because(why), Evidence::default()),
            None if e.doubt.is_some() => (lost(), *e),
            None => (lk_centroid(p, r), *e),
        };
        self.doubted[t] = e.doubt.is_some();
        self.verified[t] = match (c.position(), e.doubt) {
            (Some(_), None) => r.displacement(),
            _ => None,
        };
        self.last_good[t] = self.verified[t].or(self.last_good[t]);
        (c, e)
    }

    /// Each target's result in `frame` (in target order) with its evidence
    /// ([`forward_backward_check`]), the targets spread over the cores: each has its own
    /// backward tracker, so the results are those of checking them in turn.
    fn check_all(
        &mut self,
        frame: &GreyFrame,
        results: Vec<firmware_core::lk::LkResult>,
    ) -> anyhow::Result<Checked> {
        use rayon::prelude::*;
        let (prev, verified, origins) = (self.prev.as_ref(), &self.verified, &self.origins);
        self.back
            .par_iter_mut()
            .zip(results)
            .enumerate()
            .with_min_len(8)
            .map(|(t, (back, r))| {
                let e = forward_backward_check((frame, prev), back, (&r, verified[t]), origins[t])?;
                Ok((r, e))
            })
            .collect()
    }

    /// Result `r` of target `t` in `frame`, with its evidence ([`forward_backward_check`]).
    fn check(
        &mut self,
        frame: &GreyFrame,
        t: usize,
        r: firmware_core::lk::LkResult,
    ) -> anyhow::Result<(firmware_core::lk::LkResult, Evidence)> {
        let e = forward_backward_check(
            (frame, self.prev.as_ref()),
            &mut self.back[t],
            (&r, self.verified[t]),
            self.origins[t],
        )?;
        Ok((r, e))
    }
}

/// The state of one frame's Lucas-Kanade: per target its result and its evidence.
type Checked = Vec<(firmware_core::lk::LkResult, Evidence)>;

/// One frame of LK for every target: alone with its own prediction and search (from its last
/// verified displacement when its previous position was taken away), or, in a group, first
/// from its own prediction without a search. Every position is checked forward-backward
/// against the previous frame (`prev`; [`forward_backward_check`]). When a group member does
/// not settle, or fails the check, the group's shared offset from where each member was
/// ([`shared_offset`] over the members' search range) is the start of every such member, with
/// a search of a quarter of its window around it (fine differences between the members'
/// motions; well short of a neighbouring look-alike), and the check runs again. The shared
/// offset is sought within half the members' larger window, the range doubled while its best
/// is below a mean ZNCC of 0.5 or on its edge, up to the frame's size (whatever
/// `--search-px`, which is each target's own search); a best mean ZNCC below 0.5 there leaves
/// those members lost.
fn track_frame_lk(
    frame: &GreyFrame,
    (trackers, checks): (&mut [AnyLk], &mut Checks),
    refused: &[Option<Flags>],
    (groups, templates): (&[Vec<usize>], &[BlockTemplate]),
    search_cap: Option<&[u16]>,
) -> anyhow::Result<Checked> {
    use rayon::prelude::*;
    let k = trackers.len();
    let in_group = |t: usize| groups.iter().any(|m| m.contains(&t));
    // each target's tracker on its own (a dense field of windows spread over the cores); the
    // results in target order, so every output is the one tracking them in turn gives
    let results: Vec<_> = with_frame(frame, |f| {
        let checks = &*checks;
        trackers
            .par_iter_mut()
            .enumerate()
            .with_min_len(8)
            .map(|(t, tracker)| {
                let own = tracker.config().search;
                let search = match (in_group(t), search_cap.and_then(|c| c.get(t))) {
                    (true, _) => 0,
                    (false, Some(&cap)) => own.min(cap),
                    (false, None) => own,
                };
                let start = if checks.doubted[t] {
                    checks.last_good[t]
                } else {
                    None
                };
                match &f {
                    AnyFrame::U8(f) => tracker.track_from(f, start, search),
                    AnyFrame::U16(f) => tracker.track_from(f, start, search),
                }
            })
            .collect()
    })?;
    debug_assert_eq!(results.len(), k);
    let mut checked = checks.check_all(frame, results)?;
    let mut integral: Option<Integral> = None;
    for members in groups {
        let failed: Vec<usize> = members
            .iter()
            .copied()
            .filter(|&t| {
                let (r, e) = &checked[t];
                refused[t].is_none() && (r.displacement().is_none() || e.doubt.is_some())
            })
            .collect();
        if failed.is_empty() {
            continue;
        }
        let integral = integral.get_or_insert_with(|| Integral::of(frame));
        let again = recover(
            frame,
            integral,
            trackers,
            checks,
            (members, &failed),
            (refused, templates),
        )?;
        for (&t, r) in failed.iter().zip(again) {
            checked[t] = checks.check(frame, t, r)?;
        }
    }
    Ok(checked)
}

/// The members of a group (`members`) that did not settle or failed a check (`failed`), tracked
/// again from the group's shared offset since where each member was last verified, with a
/// search of a quarter of its window (none when no shared offset is found: their results stay).
fn recover(
    frame: &GreyFrame,
    integral: &Integral,
    trackers: &mut [AnyLk],
    checks: &Checks,
    (members, failed): (&[usize], &[usize]),
    (refused, templates): (&[Option<Flags>], &[BlockTemplate]),
) -> anyhow::Result<Vec<firmware_core::lk::LkResult>> {
    let before = |t: usize| checks.last_good[t].unwrap_or_else(|| trackers[t].displacement());
    let list: Vec<(&BlockTemplate, (i64, i64))> = members
        .iter()
        .filter(|&&t| refused[t].is_none())
        .filter_map(|&t| {
            let (dx, dy) = before(t);
            templates
                .get(t)
                .map(|tp| (tp, (dx.round() as i64, dy.round() as i64)))
        })
        .collect();
    let start = members
        .iter()
        .map(|&t| i64::from(trackers[t].config().width.max(trackers[t].config().height) / 2))
        .max()
        .unwrap_or(0);
    let Some(d) = group_offset(integral, &list, start, frame.dimensions()) else {
        return Ok(Vec::new());
    };
    let starts: Vec<(f32, f32)> = failed
        .iter()
        .map(|&t| (before(t).0 + d.0 as f32, before(t).1 + d.1 as f32))
        .collect();
    with_frame(frame, |f| {
        failed
            .iter()
            .zip(starts)
            .map(|(&t, start)| {
                let local = trackers[t].config().width.max(trackers[t].config().height) / 4;
                match &f {
                    AnyFrame::U8(f) => trackers[t].track_from(f, Some(start), local),
                    AnyFrame::U16(f) => trackers[t].track_from(f, Some(start), local),
                }
            })
            .collect()
    })
}

/// A result's evidence: its score, and the forward-backward check against the previous frame
/// `prev` when the target was verified there at `before` (its displacement): the window at the
/// result's position, taken from `frame` by `back`, is tracked into `prev` from where a
/// consistent track puts it (no search); a disagreement above [`FB_BOUND_PX`], or no match
/// there, takes the position away. A window at the frame's edge (no template) is no evidence
/// either way. Target `t` (0-based) names it in errors.
fn forward_backward_check(
    (frame, prev): (&GreyFrame, Option<&GreyFrame>),
    back: &mut AnyLk,
    (r, before): (&firmware_core::lk::LkResult, Option<(f32, f32)>),
    origin: (u32, u32),
) -> anyhow::Result<Evidence> {
    let mut e = Evidence {
        score: r.displacement().map(|_| r.score),
        ..Default::default()
    };
    let (Some(now), Some(before), Some(prev)) = (r.displacement(), before, prev) else {
        return Ok(e);
    };
    // the window's top-left pixel now: its first-frame origin moved by the whole pixels of the
    // displacement; displacements from there are the target's own (the fraction left over
    // moves with it), so a consistent track finds it at `before - now`
    let x0 = i64::from(origin.0) + now.0.round() as i64;
    let y0 = i64::from(origin.1) + now.1.round() as i64;
    let (Ok(x0), Ok(y0)) = (i32::try_from(x0), i32::try_from(y0)) else {
        return Ok(e);
    };
    let taken = with_frame(frame, |f| match f {
        AnyFrame::U8(f) => back.set_template(&f, x0, y0),
        AnyFrame::U16(f) => back.set_template(&f, x0, y0),
    })?;
    if taken.is_err() {
        return Ok(e);
    }
    let start = (before.0 - now.0, before.1 - now.1);
    let b = with_frame(prev, |f| match f {
        AnyFrame::U8(f) => back.track_from(&f, Some(start), 0),
        AnyFrame::U16(f) => back.track_from(&f, Some(start), 0),
    })?;
    match b.displacement() {
        Some(d) => {
            let fb = forward_backward_textured(now, before, d, back.structure());
            e.fb_px = Some(fb);
            if fb > FB_BOUND_PX {
                e.doubt = Some(Doubt::ForwardBackward);
            }
        }
        None if b.flags.contains(Flags::BORDER) => {}
        None => e.doubt = Some(Doubt::ForwardBackward),
    }
    Ok(e)
}

/// A group's shared offset since the last frame: the search starts at half the members'
/// larger window (`start`); a best offset below 0.5 or at the range's edge (the motion may be
/// larger) doubles it, up to the frame's size: the nearest offset that fits the whole group
/// wins, not a far one that puts the group on a row of look-alikes (another storey), which a
/// search of the whole frame at once could take.
fn group_offset(
    integral: &Integral,
    list: &[(&BlockTemplate, (i64, i64))],
    start: i64,
    (fw, fh): (usize, usize),
) -> Option<(i64, i64)> {
    let whole = (fw.max(fh) as i64).max(8);
    let mut range = start.clamp(8, whole);
    loop {
        let r = shared_offset(integral, list, range);
        let inside = |d: (i64, i64)| d.0.abs().max(d.1.abs()) + 4 < range;
        match r {
            Some((d, score)) if score >= 0.5 && inside(d) => break Some(d),
            _ if range >= whole => break r.filter(|(_, s)| *s >= 0.5).map(|(d, _)| d),
            _ => range = (range * 2).min(whole),
        }
    }
}

/// A lost result with the tracker's reason beside `empty` (no position).
fn lost_because(why: Flags) -> Centroid {
    let mut c = lost();
    c.flags.insert(why);
    c
}

/// A decoded frame as firmware-core's view of it.
enum AnyFrame<'a> {
    U8(firmware_core::centroid::Frame<'a, u8>),
    U16(firmware_core::centroid::Frame<'a, u16>),
}

/// Calls `f` with `frame` as a firmware-core frame.
fn with_frame<R>(frame: &GreyFrame, f: impl FnOnce(AnyFrame<'_>) -> R) -> anyhow::Result<R> {
    use firmware_core::centroid::Frame;
    let (w, h) = frame.dimensions();
    let any = match frame {
        GreyFrame::U8 { data, .. } => AnyFrame::U8(Frame::new(data, w, h, w)?),
        GreyFrame::U16 { data, .. } => AnyFrame::U16(Frame::new(data, w, h, w)?),
    };
    Ok(f(any))
}

/// Tracks of `points` with no frame yet, each target's first position its point.
fn empty_tracks(points: &[Point]) -> Tracks {
    let k = points.len();
    Tracks {
        centroids: vec![Vec::new(); k],
        first: points.iter().map(|p| p.xy).collect(),
        refused: vec![0; k],
        depth: Default::default(),
        evidence: Vec::new(),
    }
}

/// Whether `frame` is the first (its size then kept in `size0`); a later frame of another size
/// is an error naming it.
fn is_first(
    size0: &mut Option<(usize, usize)>,
    frame: &GreyFrame,
    label: &str,
) -> anyhow::Result<bool> {
    let dims = frame.dimensions();
    match *size0 {
        None => {
            *size0 = Some(dims);
            Ok(true)
        }
        Some(d) if d != dims => Err(bad_input(format!(
            "{label}: {}x{} pixels, but the first frame is {}x{}",
            dims.0, dims.1, d.0, d.1
        ))),
        Some(_) => Ok(false),
    }
}

/// Point `p`'s window in the first frame (`dims`, labelled `label`), which must lie inside it.
fn first_window(p: &Point, dims: (usize, usize), label: &str) -> anyhow::Result<Roi> {
    window(p.xy, p.size, dims).ok_or_else(|| {
        bad_input(format!(
            "target {}: the {}x{} window at ({}, {}) does not lie inside the first frame \
             ({label}, {}x{} pixels)",
            p.target, p.size.0, p.size.1, p.xy.0, p.xy.1, dims.0, dims.1
        ))
    })
}

/// The thresholds of the windows in the first frame, every window checked to lie inside it.
fn first_windows(
    points: &[Point],
    frame: &GreyFrame,
    rule: ThresholdRule,
    label: &str,
) -> anyhow::Result<Vec<u16>> {
    points
        .iter()
        .map(|p| {
            let roi = first_window(p, frame.dimensions(), label)?;
            Ok(match (p.threshold, rule) {
                (Some(t), _) => t,
                (None, ThresholdRule::Level(t)) => t,
                (None, ThresholdRule::Auto) => otsu(frame, roi),
                (None, ThresholdRule::FromFile) => {
                    return Err(bad_input(format!(
                        "target {}: no threshold: give $threshold T (or auto), or a \
                         `threshold` for every row of the points file",
                        p.target
                    )))
                }
            })
        })
        .collect()
}

/// One target in one frame: its window at `last`, re-centred once if the target touches the
/// window's edge; a lost centroid when it cannot be measured whole.
fn follow(
    frame: &GreyFrame,
    cfg: &CentroidConfig,
    last: (f64, f64),
    size: (u32, u32),
    label: &str,
) -> anyhow::Result<Centroid> {
    let dims = frame.dimensions();
    let mut at = last;
    for _ in 0..2 {
        // a window that would leave the frame: the target is at its edge
        let Some(roi) = window(at, size, dims) else {
            return Ok(lost_because(Flags::BORDER));
        };
        let c = frame.centroid(
            &CentroidConfig {
                roi: Some(roi),
                ..*cfg
            },
            label,
        )?;
        if c.flags.contains(Flags::EMPTY) {
            return Ok(lost());
        }
        if !c.flags.contains(Flags::BORDER) {
            return Ok(c);
        }
        at = (f64::from(c.cx), f64::from(c.cy));
    }
    // still at the edge after re-centring: too large for its window, or filling it
    Ok(lost_because(Flags::BORDER))
}

/// The `--points` windows: per target its window, threshold and lost frames.
pub fn windows_report(w: &PointsInfo, tracks: &crate::tracks::Tracks) -> String {
    use std::fmt::Write as _;
    let mut s = String::from("\npoints (each target in its own window):\n");
    for (t, (size, c)) in w.sizes.iter().zip(&tracks.centroids).enumerate() {
        let lost = c.iter().filter(|c| c.position().is_none()).count();
        let how = match w.thresholds.get(t).copied().flatten() {
            Some(th) => format!("threshold {th}"),
            None => "Lucas-Kanade".to_string(),
        };
        let _ = writeln!(
            s,
            "  target {}: window {}x{} px, {how}, {lost} of {} frames lost",
            t + 1,
            size.0,
            size.1,
            c.len()
        );
        if let Some(why) = w.chosen.get(t) {
            let _ = writeln!(s, "    tracker (auto): {why}");
        }
    }
    if let Some(g) = &w.groups {
        let _ = writeln!(
            s,
            "  {}",
            g.describe(&(1..=w.sizes.len()).collect::<Vec<_>>())
        );
    }
    // the checks are Lucas-Kanade's: said when it followed a target
    let lk_followed = w.thresholds.is_empty() || w.thresholds.iter().any(Option::is_none);
    if !tracks.evidence.is_empty() && lk_followed {
        let _ = writeln!(
            s,
            "  every position checked: tracked back into the frame before (forward-backward, \
             within {} px), its score against the target's own over the record, its offset \
             from its group's shared motion; positions the checks take away are lost frames",
            crate::verify::FB_BOUND_PX
        );
        let names: Vec<usize> = (1..=w.sizes.len()).collect();
        for line in crate::verify::describe(tracks, &names) {
            let _ = writeln!(s, "  {line}");
        }
    }
    for warning in &w.warnings {
        let _ = writeln!(s, "WARNING: {warning}");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(w: usize, h: usize, f: impl Fn(usize, usize) -> u8) -> GreyFrame {
        GreyFrame::U8 {
            width: w,
            height: h,
            data: (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .map(|(x, y)| f(x, y))
                .collect(),
        }
    }

    /// Tracks of targets at `at` moving by `f(frame, position)` over `frames` frames.
    fn moving(
        at: &[(f64, f64)],
        frames: usize,
        f: impl Fn(usize, (f64, f64)) -> (f64, f64),
    ) -> Vec<Vec<Option<(f32, f32)>>> {
        at.iter()
            .map(|&p| {
                (0..frames)
                    .map(|k| {
                        let d = f(k, p);
                        Some((d.0 as f32, d.1 as f32))
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn a_beam_that_turns_as_it_moves_is_one_group_and_storeys_stay_apart() {
        // two storeys of seven tags, 150 px apart along x, 300 px apart in y; the upper one
        // sways 10 px per frame step, the lower 75 % of it; both turn by 0.1 mrad per px of
        // sway (at 50 px the ends of a row 900 px long are 4.5 px apart in y, 9 % of the
        // motion: beyond 5 % + 0.2 px; neighbours 0.75 px)
        let mut at = Vec::new();
        for row in 0..2 {
            for i in 0..7 {
                at.push((100.0 + 150.0 * i as f64, 100.0 + 300.0 * row as f64));
            }
        }
        let sway = |k: usize, y: f64| {
            let a = 10.0 * k as f64;
            if y < 200.0 {
                a
            } else {
                0.75 * a
            }
        };
        let h = moving(&at, 6, |k, (x, y)| {
            let s = sway(k, y);
            let w = 1e-4 * s;
            let c = (550.0, if y < 200.0 { 100.0 } else { 400.0 });
            (s - w * (y - c.1), w * (x - c.0))
        });
        let g = motion_groups(&h, &at);
        assert_eq!(g, vec![(0..7).collect::<Vec<_>>(), (7..14).collect()]);
        // numbered by column (upper, lower, upper, ...): a vertical pair alone could pass for
        // one part turning; the rows do not
        let order: Vec<usize> = (0..7).flat_map(|i| [i, i + 7]).collect();
        let at2: Vec<(f64, f64)> = order.iter().map(|&i| at[i]).collect();
        let h2: Vec<_> = order.iter().map(|&i| h[i].clone()).collect();
        let g2 = motion_groups(&h2, &at2);
        assert_eq!(
            g2,
            vec![
                (0..7).map(|i| 2 * i).collect::<Vec<_>>(),
                (0..7).map(|i| 2 * i + 1).collect()
            ]
        );
        // the rigid misfit of a turning row is nil, of the two rows together large
        let (m, motion) = rigid_misfit(&h, &at, &(0..7).collect::<Vec<_>>());
        assert!(m < 1e-3 && motion > 10.0, "{m} {motion}");
        let (m, motion) = rigid_misfit(&h, &at, &(0..14).collect::<Vec<_>>());
        assert!(m > 0.05 * motion + 0.2, "{m} {motion}");
    }

    #[test]
    fn windows_are_centred_as_documented() {
        let r = window((10.0, 10.0), (5, 4), (40, 40)).unwrap();
        assert_eq!((r.x, r.y, r.width, r.height), (8, 9, 5, 4));
        assert!(window((1.0, 10.0), (5, 5), (40, 40)).is_none());
        assert!(window((37.0, 10.0), (5, 5), (40, 40)).is_some());
        assert!(window((38.0, 10.0), (5, 5), (40, 40)).is_none());
    }

    #[test]
    fn otsu_splits_a_two_level_window_between_its_levels() {
        let f = frame(20, 20, |x, y| {
            if (5..10).contains(&x) && (5..10).contains(&y) {
                200
            } else {
                30
            }
        });
        let roi = Roi {
            x: 0,
            y: 0,
            width: 20,
            height: 20,
        };
        let t = otsu(&f, roi);
        assert!((30..200).contains(&t), "{t}");
    }
}
