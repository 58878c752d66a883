//! How targets are found and followed, as `track`, `analyze` and Python's `track`/`analyze`
//! take it: chosen points, the K blobs of the first frame, or the one target of the frame
//! (or ROI); the centroid's threshold rule or Lucas-Kanade. One set of rules for all of them.

use super::{SpecError, SpecResult};
use crate::analysis::points::{read_points, Point, PointTracker, ThresholdRule};
use crate::analysis::track_run::Targets;
use crate::setting::table;
use firmware_core::centroid::{CentroidConfig, Mode, Roi};
use std::path::PathBuf;

/// The tracker (`--tracker`, Python's `tracker`): the toolkit's one tracker enum.
pub use crate::chain::tracker::TrackerKind as Tracker;

/// A threshold as given: a grey level, or Otsu's of each window (`auto`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Threshold {
    /// A grey level (a pixel counts when above it).
    Level(u16),
    /// Otsu's threshold of each point's window in the first frame.
    Auto,
}

/// Chosen points as given: a points file, or a list (target `k` the `k`-th).
#[derive(Debug, Clone, PartialEq)]
pub enum PointsInput {
    /// A points CSV (read and checked by the constructor; errors name the file and row).
    File(PathBuf),
    /// Points given in memory (Python).
    List(Vec<Point>),
}

/// The tracking settings as given, unchecked.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackingInput {
    /// `$threshold`.
    pub threshold: Option<Threshold>,
    /// `$tracker`.
    pub tracker: Tracker,
    /// `$roi` (the one target's region, without points or targets; the K blobs' region).
    pub roi: Option<Roi>,
    /// `$points`.
    pub points: Option<PointsInput>,
    /// `$targets` (K blobs).
    pub targets: Option<usize>,
    /// `$gate_px` (with targets).
    pub gate_px: Option<f64>,
    /// `$search_px` (with points and Lucas-Kanade).
    pub search_px: Option<u16>,
}

impl Default for TrackingInput {
    fn default() -> Self {
        TrackingInput {
            threshold: None,
            tracker: Tracker::Auto,
            roi: None,
            points: None,
            targets: None,
            gate_px: None,
            search_px: None,
        }
    }
}

/// The blobs' gate when none is given, px (the settings table's default of `$gate_px`).
fn default_gate_px() -> f64 {
    table::row("gate_px")
        .job_default()
        .expect("the table states the gate's default")
}

/// The most blobs followed (`$targets`, the settings table's range).
pub const MAX_TARGETS: usize = table::MAX_TARGETS as usize;

/// Checked tracking: which targets, and the centroid's configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct Tracking {
    /// The targets and how they are followed.
    pub targets: Targets,
    /// The centroid's settings (the threshold of the blobs or the one target; 0 stands in for
    /// points, whose windows carry their own, and for Lucas-Kanade).
    pub centroid: CentroidConfig,
    /// The tracker asked for.
    pub tracker: Tracker,
    /// The points file read, when one was given (an input: never overwritten).
    pub points_file: Option<PathBuf>,
}

impl Tracking {
    /// Checks `input`; reads and checks a points file.
    pub fn new(input: TrackingInput) -> SpecResult<Self> {
        let TrackingInput {
            threshold,
            tracker,
            roi,
            points,
            targets,
            gate_px,
            search_px,
        } = input;
        if points.is_some() && targets.is_some() {
            return Err(SpecError::setting(
                "give $points (chosen windows) or $targets K (the K blobs of the first frame), \
                 not both",
            ));
        }
        if points.is_some() && roi.is_some() {
            return Err(SpecError::setting(
                "$roi with $points: each point's window is its region; leave $roi out",
            ));
        }
        if gate_px.is_some() && targets.is_none() {
            return Err(SpecError::setting(
                "$gate_px is the blobs' gate of $targets K; each $points window follows its \
                 own target: leave $gate_px out",
            ));
        }
        if let Some(g) = gate_px {
            table::number("track", "gate_px", g)?;
        }
        if let Some(k) = targets {
            table::whole("track", "targets", k as u64)?;
        }
        if search_px.is_some()
            && (points.is_none() || !matches!(tracker, Tracker::Lk | Tracker::Auto))
        {
            return Err(SpecError::setting(
                "$search_px: the coarse search of $tracker lk (or auto) with $points (a centroid \
                 window re-centres itself on a partial target, about half a window per frame)",
            ));
        }
        let centroid = centroid_config(threshold, tracker, roi, points.is_some())?;
        let (points, points_file) = match points {
            Some(PointsInput::File(f)) => {
                (Some(read_points(&f).map_err(SpecError::Input)?), Some(f))
            }
            Some(PointsInput::List(p)) => (Some(checked_points(p)?), None),
            None => (None, None),
        };
        let targets = match (points, targets) {
            (Some(points), _) => {
                Targets::Points(points, point_tracker(tracker, threshold, search_px))
            }
            (None, Some(k)) => Targets::Blobs(k, gate_px.unwrap_or_else(default_gate_px)),
            (None, None) => Targets::Whole,
        };
        Ok(Tracking {
            targets,
            centroid,
            tracker,
            points_file,
        })
    }

    /// Whether the tracker is the binary centroid (the exposure compensation is then an
    /// approximation): `blob`, or `auto` with targets that are not chosen points.
    pub fn binary(&self) -> bool {
        let points = matches!(self.targets, Targets::Points(..));
        self.tracker == Tracker::Blob || (self.tracker == Tracker::Auto && !points)
    }
}

/// How chosen points are followed, from the tracker and threshold given.
fn point_tracker(
    tracker: Tracker,
    threshold: Option<Threshold>,
    search_px: Option<u16>,
) -> PointTracker {
    let rule = match threshold {
        Some(Threshold::Level(t)) => ThresholdRule::Level(t),
        Some(Threshold::Auto) => ThresholdRule::Auto,
        // each window's own, from the file's `threshold` column (checked on the first frame);
        // `auto` takes Otsu's of each window where the file gives none
        None if tracker == Tracker::Auto => ThresholdRule::Auto,
        None => ThresholdRule::FromFile,
    };
    match tracker {
        Tracker::Lk => PointTracker::Lk { search_px },
        Tracker::Auto => PointTracker::Auto { rule, search_px },
        Tracker::Blob | Tracker::Weighted => PointTracker::Centroid(rule),
    }
}

/// Points given in memory, checked as a points file's rows are.
fn checked_points(points: Vec<Point>) -> SpecResult<Vec<Point>> {
    if points.is_empty() {
        return Err(SpecError::setting("$points: no points given"));
    }
    for (i, p) in points.iter().enumerate() {
        let (x, y) = p.xy;
        if !(x.is_finite() && y.is_finite()) {
            return Err(SpecError::setting(format!(
                "$points[{i}]: the centre ({x}, {y}) is not finite"
            )));
        }
        if p.size.0 < 3 || p.size.1 < 3 {
            return Err(SpecError::setting(format!(
                "$points[{i}]: the window {} x {} px is smaller than 3 x 3",
                p.size.0, p.size.1
            )));
        }
    }
    Ok(points)
}

/// The firmware's centroid configuration for `tracker` and `threshold` (`points`: the windows
/// of chosen points are followed, which may take `auto`, a file's column, or Lucas-Kanade).
pub fn centroid_config(
    threshold: Option<Threshold>,
    tracker: Tracker,
    roi: Option<Roi>,
    points: bool,
) -> SpecResult<CentroidConfig> {
    if tracker == Tracker::Lk && !points {
        return Err(SpecError::setting(
            "$tracker lk follows the windows of $points (each window is its template): give \
             $points (a single target and $targets K take binary or weighted)",
        ));
    }
    if tracker == Tracker::Lk && threshold.is_some() {
        return Err(SpecError::setting(
            "$threshold with $tracker lk: Lucas-Kanade matches each window's template and uses \
             no threshold; leave $threshold out",
        ));
    }
    let level = match (threshold, points) {
        (Some(Threshold::Level(t)), _) => t,
        // chosen per window (Otsu's, or the file's column): 0 stands in here
        (Some(Threshold::Auto), true) | (None, true) => 0,
        (Some(Threshold::Auto), false) => {
            return Err(SpecError::setting(
                "$threshold auto: only with $points (Otsu's threshold of each window)",
            ))
        }
        (None, false) => {
            return Err(SpecError::setting(
                "$threshold T (a grey level, or `auto` with $points) is needed by the \
                 centroid; only $tracker lk has none",
            ))
        }
    };
    CentroidConfig {
        threshold: level,
        mode: match tracker {
            Tracker::Weighted => Mode::Weighted,
            // Lucas-Kanade has no centroid: binary stands in, unused
            Tracker::Blob | Tracker::Lk | Tracker::Auto => Mode::Binary,
        },
        roi,
        saturation: None,
    }
    .validate()
    .map_err(|e| SpecError::setting(format!("centroid settings ($threshold, $roi): {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::jobs::Naming;

    fn point() -> Point {
        Point {
            target: 1,
            xy: (10.0, 10.0),
            size: (9, 9),
            threshold: None,
            group: None,
        }
    }

    #[test]
    fn settings_that_do_not_go_together_are_named() {
        let cases: Vec<(TrackingInput, &str)> = vec![
            (
                TrackingInput {
                    gate_px: Some(5.0),
                    threshold: Some(Threshold::Level(9)),
                    ..Default::default()
                },
                "gate_px is the blobs' gate of targets",
            ),
            (
                TrackingInput {
                    tracker: Tracker::Lk,
                    ..Default::default()
                },
                "tracker lk follows the windows of points",
            ),
            (
                TrackingInput {
                    tracker: Tracker::Lk,
                    threshold: Some(Threshold::Level(3)),
                    points: Some(PointsInput::List(vec![point()])),
                    ..Default::default()
                },
                "threshold with tracker lk",
            ),
            (
                TrackingInput {
                    threshold: Some(Threshold::Auto),
                    ..Default::default()
                },
                "threshold auto: only with points",
            ),
            (
                TrackingInput {
                    threshold: Some(Threshold::Level(3)),
                    targets: Some(33),
                    ..Default::default()
                },
                "targets 33",
            ),
            (
                TrackingInput {
                    threshold: Some(Threshold::Level(3)),
                    tracker: Tracker::Blob,
                    search_px: Some(4),
                    points: Some(PointsInput::List(vec![point()])),
                    ..Default::default()
                },
                "search_px: the coarse search of tracker lk",
            ),
        ];
        for (input, want) in cases {
            let e = Tracking::new(input.clone()).unwrap_err();
            assert!(e.message(Naming::Python).contains(want), "{input:?}: {e}");
        }
    }

    #[test]
    fn targets_follow_from_the_settings() {
        let t = Tracking::new(TrackingInput {
            threshold: Some(Threshold::Level(50)),
            targets: Some(3),
            ..Default::default()
        })
        .unwrap();
        assert_eq!(t.targets, Targets::Blobs(3, 10.0));
        let t = Tracking::new(TrackingInput {
            tracker: Tracker::Lk,
            points: Some(PointsInput::List(vec![point()])),
            search_px: Some(7),
            ..Default::default()
        })
        .unwrap();
        assert_eq!(
            t.targets,
            Targets::Points(vec![point()], PointTracker::Lk { search_px: Some(7) })
        );
        let t = Tracking::new(TrackingInput {
            threshold: Some(Threshold::Level(50)),
            ..Default::default()
        })
        .unwrap();
        assert_eq!(t.targets, Targets::Whole);
    }
}
