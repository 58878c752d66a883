//! Every tracked position carries its evidence, and a position the evidence does not support is
//! taken away (a lost frame, with the reason) rather than passed on silently wrong.
//!
//! Per target and frame ([`Evidence`]): the match score of the final position against the
//! first frame's template (Lucas-Kanade's ZNCC; none for a centroid), and the forward-backward
//! disagreement: the window at the new position tracked back into the previous frame, which
//! must land where the target was there ([`FB_BOUND_PX`]). Over the whole record, two more
//! checks ([`verify_record`]):
//! - **the target's own score**: a score far below the target's own distribution over the
//!   record (below its median by more than [`SCORE_DROP`] and [`SCORE_SIGMAS`] robust standard
//!   deviations) is lost: the window no longer holds what it held in the first frame;
//! - **the group's geometry**: in a group of targets that move together (a storey, a beam),
//!   each member's offset from the group's shared motion (the members' median displacement)
//!   is what the group's own deformation allows: an offset beyond the larger of
//!   [`GROUP_FLOOR_PX`] and [`GROUP_SIGMAS`] times the group's scatter (the median over members
//!   of each one's robust deviation), plus [`GROUP_SHARE`] of the shared motion, is lost: the
//!   window has left its tag (a neighbour, the rod between tags, the wall), even when it stays
//!   there for the rest of the record.
//!
//! The checks only take positions away; what is left is what the evidence supports.

use crate::tracks::Tracks;
pub use vibcam_common::evidence::{cells, Doubt, Evidence};

/// A forward-backward disagreement above this, px, takes the position away.
pub const FB_BOUND_PX: f32 = 1.0;
/// A score at least this far below the target's median score over the record can be lost.
pub const SCORE_DROP: f32 = 0.15;
/// ... and at least this many robust standard deviations (1.4826 MAD) below it.
pub const SCORE_SIGMAS: f32 = 6.0;
/// A member's offset from its group's shared motion (counted from the first frame) beyond
/// this, px, ...
pub const GROUP_FLOOR_PX: f32 = 2.0;
/// ... or beyond this many times the group's scatter (robust standard deviations), whichever
/// is larger, ...
pub const GROUP_SIGMAS: f32 = 6.0;
/// ... plus this share of the group's shared motion in that frame (a group bends and turns in
/// proportion to its motion), is lost.
pub const GROUP_SHARE: f32 = 0.1;

/// Median of `v` (sorted in place); `None` when empty.
fn median(v: &mut [f32]) -> Option<f32> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f32::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    })
}

/// Median and robust standard deviation (1.4826 MAD) of `v`.
fn robust(mut v: Vec<f32>) -> Option<(f32, f32)> {
    let m = median(&mut v)?;
    let mut dev: Vec<f32> = v.iter().map(|x| (x - m).abs()).collect();
    Some((m, 1.4826 * median(&mut dev).unwrap_or(0.0)))
}

/// Takes away target `t`'s position in frame `k` for `why`.
fn take_away(tracks: &mut Tracks, t: usize, k: usize, why: Doubt) {
    tracks.centroids[t][k] = crate::tracks::lost();
    tracks.evidence[t][k].doubt = Some(why);
}

/// The record-wide checks (module documentation) on `tracks`, whose `evidence` holds each
/// position's score; `groups` the groups of targets that move together (0-based). Returns how
/// many positions each check took away, `[score, group]`.
pub fn verify_record(tracks: &mut Tracks, groups: &[Vec<usize>]) -> [usize; 2] {
    let mut taken = [0usize; 2];
    let tracked = |tracks: &Tracks, t: usize, k: usize| tracks.centroids[t][k].position();
    for t in 0..tracks.centroids.len() {
        if tracks.evidence[t].is_empty() {
            continue;
        }
        let frames = tracks.centroids[t].len();
        let scores: Vec<f32> = (0..frames)
            .filter(|&k| tracked(tracks, t, k).is_some())
            .filter_map(|k| tracks.evidence[t][k].score)
            .collect();
        let Some((m, s)) = robust(scores) else {
            continue;
        };
        let bound = m - SCORE_DROP.max(SCORE_SIGMAS * s);
        for k in 0..frames {
            let low = tracks.evidence[t][k].score.is_some_and(|x| x < bound);
            if low && tracked(tracks, t, k).is_some() {
                take_away(tracks, t, k, Doubt::Score);
                taken[0] += 1;
            }
        }
    }
    for members in groups.iter().filter(|g| g.len() >= 3) {
        taken[1] += verify_group(tracks, members);
    }
    taken
}

/// The group check for one group of three or more members: the positions taken away.
fn verify_group(tracks: &mut Tracks, members: &[usize]) -> usize {
    let frames = members
        .iter()
        .map(|&t| tracks.centroids[t].len())
        .min()
        .unwrap_or(0);
    // each member's displacement from its first position, per frame
    let disp = |tracks: &Tracks, t: usize, k: usize| {
        tracks.centroids[t][k]
            .position()
            .map(|(x, y)| (x - tracks.first[t].0 as f32, y - tracks.first[t].1 as f32))
    };
    // the shared motion per frame: the members' median displacement (half of them at least)
    let shared: Vec<Option<(f32, f32)>> = (0..frames)
        .map(|k| {
            let d: Vec<(f32, f32)> = members.iter().filter_map(|&t| disp(tracks, t, k)).collect();
            if 2 * d.len() < members.len() + 1 {
                return None;
            }
            let (mut xs, mut ys): (Vec<f32>, Vec<f32>) = d.into_iter().unzip();
            Some((median(&mut xs)?, median(&mut ys)?))
        })
        .collect();
    let offset = |tracks: &Tracks, t: usize, k: usize| -> Option<f32> {
        let (d, s) = (disp(tracks, t, k)?, shared[k]?);
        Some((d.0 - s.0).hypot(d.1 - s.1))
    };
    // the group's own scatter: the median over members of each one's robust deviation
    let mut spreads: Vec<f32> = members
        .iter()
        .filter_map(|&t| robust((0..frames).filter_map(|k| offset(tracks, t, k)).collect()))
        .map(|(_, s)| s)
        .collect();
    let scatter = median(&mut spreads).unwrap_or(0.0);
    let mut taken = 0;
    for &t in members {
        for (k, sh) in shared.iter().enumerate() {
            let (Some(r), Some(sh)) = (offset(tracks, t, k), sh) else {
                continue;
            };
            let allowed =
                GROUP_FLOOR_PX.max(GROUP_SIGMAS * scatter) + GROUP_SHARE * sh.0.hypot(sh.1);
            if r > allowed {
                take_away(tracks, t, k, Doubt::Group);
                taken += 1;
            }
        }
    }
    taken
}

/// The forward-backward disagreement of a position: `d_now` and `d_before` the target's
/// displacements (px) in this frame and the previous one, `back` the displacement the window at
/// `d_now` was found at in the previous frame, counted from where it was taken (so that a
/// consistent track gives `back = d_before - d_now`).
pub fn forward_backward(d_now: (f32, f32), d_before: (f32, f32), back: (f32, f32)) -> f32 {
    (d_now.0 + back.0 - d_before.0).hypot(d_now.1 + back.1 - d_before.1)
}

/// The eigenvalues `(l1, l2)`, `l1 >= l2 >= 0`, of a window's gradient structure tensor
/// `[sxx, sxy, syy]`: how well its texture fixes its position in its strongest and weakest
/// direction.
pub fn eigenvalues(structure: [f32; 3]) -> (f64, f64) {
    let [a, b, c] = structure.map(f64::from);
    let half_tr = 0.5 * (a + c);
    let disc = (0.25 * (a - c).powi(2) + b * b).sqrt();
    (half_tr + disc, (half_tr - disc).max(0.0))
}

/// [`forward_backward`] measured along what the window's texture measures: `structure` is the
/// window's gradient structure tensor `[sxx, sxy, syy]` (eigenvalues `l1 >= l2`); the
/// disagreement's component along the weaker direction counts by `sqrt(l2 / l1)`. A window
/// of edges in one direction only (a stripe, a beam's edge) does not fix its position along
/// the edge: a disagreement there is the aperture, not a wrong match (it is zero weight for a
/// pure edge, full weight for texture alike in every direction).
pub fn forward_backward_textured(
    d_now: (f32, f32),
    d_before: (f32, f32),
    back: (f32, f32),
    structure: [f32; 3],
) -> f32 {
    let e = (d_now.0 + back.0 - d_before.0, d_now.1 + back.1 - d_before.1);
    let [a, b, c] = structure.map(f64::from);
    let (l1, l2) = eigenvalues(structure);
    if !(l1 > 0.0 && l1.is_finite()) {
        return e.0.hypot(e.1);
    }
    // the strong direction's unit vector (of the larger eigenvalue)
    let v1 = if b.abs() > 1e-12 * l1 {
        let (x, y) = (l1 - c, b);
        let n = x.hypot(y);
        (x / n, y / n)
    } else if a >= c {
        (1.0, 0.0)
    } else {
        (0.0, 1.0)
    };
    let (ex, ey) = (f64::from(e.0), f64::from(e.1));
    let along = ex * v1.0 + ey * v1.1;
    let across = -ex * v1.1 + ey * v1.0;
    (along.powi(2) + across.powi(2) * l2 / l1).sqrt() as f32
}

/// Per target, the frames (1-based) whose positions were taken away, by reason: the report's
/// lines (`names[t]` the target's number).
pub fn describe(tracks: &Tracks, names: &[usize]) -> Vec<String> {
    let mut lines = Vec::new();
    for (t, ev) in tracks.evidence.iter().enumerate() {
        for why in [Doubt::ForwardBackward, Doubt::Score, Doubt::Group] {
            let frames: Vec<usize> = ev
                .iter()
                .enumerate()
                .filter(|(_, e)| e.doubt == Some(why))
                .map(|(k, _)| k + 1)
                .collect();
            if !frames.is_empty() {
                lines.push(format!(
                    "target {}: {} position(s) taken away by the {} check, frames {}",
                    names.get(t).copied().unwrap_or(t + 1),
                    frames.len(),
                    why.word(),
                    ranges(&frames)
                ));
            }
        }
    }
    lines
}

/// `1-3, 7, 9-10` for `[1, 2, 3, 7, 9, 10]` (ascending).
fn ranges(v: &[usize]) -> String {
    let mut out: Vec<String> = Vec::new();
    let mut i = 0;
    while i < v.len() {
        let mut j = i;
        while j + 1 < v.len() && v[j + 1] == v[j] + 1 {
            j += 1;
        }
        out.push(if i == j {
            v[i].to_string()
        } else {
            format!("{}-{}", v[i], v[j])
        });
        i = j + 1;
    }
    out.join(", ")
}

/// A position at `(x, y)` px, as a centroid for tests.
#[cfg(test)]
fn at(x: f32, y: f32) -> firmware_core::centroid::Centroid {
    firmware_core::centroid::Centroid {
        cx: x,
        cy: y,
        moments: firmware_core::centroid::Moments {
            pixels: 1,
            ..Default::default()
        },
        flags: firmware_core::centroid::Flags::NONE,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_disagreement_along_an_edge_only_window_is_its_aperture() {
        // texture alike in x and y: the plain distance
        let iso = forward_backward_textured((1.0, 0.0), (0.0, 0.0), (0.0, 0.0), [4.0, 0.0, 4.0]);
        assert!((iso - 1.0).abs() < 1e-6);
        // edges along x only (gradients in y): 1 px along x is the aperture
        let edge =
            forward_backward_textured((1.0, 0.0), (0.0, 0.0), (0.0, 0.0), [0.04, 0.0, 400.0]);
        assert!((edge - 0.01).abs() < 1e-4, "{edge}");
        // the same window's disagreement across its edges counts in full
        let across =
            forward_backward_textured((0.0, 1.0), (0.0, 0.0), (0.0, 0.0), [0.04, 0.0, 400.0]);
        assert!((across - 1.0).abs() < 1e-6);
        // a diagonal edge (gradients along (1, 1)): along (1, -1) weighs little
        let d =
            forward_backward_textured((0.7, -0.7), (0.0, 0.0), (0.0, 0.0), [200.0, 199.9, 200.0]);
        assert!(d < 0.05, "{d}");
        let d =
            forward_backward_textured((0.7, 0.7), (0.0, 0.0), (0.0, 0.0), [200.0, 199.9, 200.0]);
        assert!((d - 0.99).abs() < 0.01, "{d}");
    }

    /// Tracks of `k` targets 100 px apart moving together by `motion(f)`, with scores `0.98`.
    fn group(k: usize, frames: usize, motion: impl Fn(usize) -> (f32, f32)) -> Tracks {
        let first: Vec<(f64, f64)> = (0..k).map(|t| (100.0 * t as f64 + 50.0, 60.0)).collect();
        Tracks {
            centroids: (0..k)
                .map(|t| {
                    (0..frames)
                        .map(|f| {
                            let (dx, dy) = motion(f);
                            let wobble = 0.05 * ((f * 7 + t * 3) % 5) as f32;
                            at(first[t].0 as f32 + dx + wobble, first[t].1 as f32 + dy)
                        })
                        .collect()
                })
                .collect(),
            first,
            refused: vec![0; k],
            depth: Default::default(),
            evidence: vec![
                vec![
                    Evidence {
                        score: Some(0.98),
                        ..Default::default()
                    };
                    frames
                ];
                k
            ],
        }
    }

    fn release(f: usize) -> (f32, f32) {
        // a pull to 120 px, a release, a decaying swing
        let t = f as f32;
        if f < 20 {
            (6.0 * t, 0.0)
        } else {
            (
                120.0 * (-(t - 20.0) / 30.0).exp() * (0.9 * (t - 20.0)).cos(),
                0.0,
            )
        }
    }

    #[test]
    fn a_member_that_leaves_its_group_is_taken_away_and_the_rest_stays() {
        let mut tracks = group(5, 80, release);
        // target 3 jumps 31 px onto the rod in frame 21 and stays there; target 5 takes its
        // neighbour (+100 px) from frame 60
        for k in 20..80 {
            tracks.centroids[2][k].cx += 31.0;
        }
        for k in 59..80 {
            tracks.centroids[4][k].cx -= 100.0;
        }
        let taken = verify_record(&mut tracks, &[vec![0, 1, 2, 3, 4]]);
        assert_eq!(taken, [0, 60 + 21]);
        for (t, range) in [(2, 20..80), (4, 59..80)] {
            for k in 0..80 {
                let doubted = tracks.evidence[t][k].doubt == Some(Doubt::Group);
                assert_eq!(doubted, range.contains(&k), "target {t} frame {k}");
                assert_eq!(tracks.centroids[t][k].position().is_none(), doubted);
            }
        }
        for t in [0, 1, 3] {
            assert!(tracks.centroids[t].iter().all(|c| c.position().is_some()));
        }
        let lines = describe(&tracks, &[1, 2, 3, 4, 5]);
        assert_eq!(
            lines,
            [
                "target 3: 60 position(s) taken away by the group check, frames 21-80",
                "target 5: 21 position(s) taken away by the group check, frames 60-80"
            ]
        );
    }

    #[test]
    fn a_group_that_bends_with_its_motion_keeps_every_position() {
        // the outer members move 8 % more than the inner ones (a storey turning): within the
        // share of the shared motion a group may deform
        let mut tracks = group(5, 80, release);
        for t in [0, 4] {
            for k in 0..80 {
                let d = release(k).0;
                tracks.centroids[t][k].cx += 0.08 * d;
            }
        }
        assert_eq!(verify_record(&mut tracks, &[vec![0, 1, 2, 3, 4]]), [0, 0]);
    }

    #[test]
    fn a_score_far_below_the_targets_own_is_lost_and_a_small_dip_is_not() {
        let mut tracks = group(1, 50, |_| (0.0, 0.0));
        for k in 0..50 {
            tracks.evidence[0][k].score = Some(0.97 + 0.002 * (k % 5) as f32);
        }
        tracks.evidence[0][10].score = Some(0.90); // a blurred frame: kept
        tracks.evidence[0][30].score = Some(0.55); // the window on the wall: lost
        assert_eq!(verify_record(&mut tracks, &[]), [1, 0]);
        assert_eq!(tracks.evidence[0][30].doubt, Some(Doubt::Score));
        assert!(tracks.centroids[0][10].position().is_some());
        assert_eq!(
            cells(Some(&tracks.evidence[0][30])),
            "0.5500,,score".to_string()
        );
    }

    #[test]
    fn forward_backward_is_zero_for_a_consistent_track() {
        assert_eq!(
            forward_backward((12.0, -3.0), (10.0, -1.0), (-2.0, 2.0)),
            0.0
        );
        let fb = forward_backward((41.0, 0.0), (10.0, 0.0), (0.0, 0.0));
        assert!((fb - 31.0).abs() < 1e-6);
        assert_eq!(ranges(&[1, 2, 3, 7, 9, 10]), "1-3, 7, 9-10");
    }
}
