//! Which targets are followed and the one tracking dispatcher of `track`, `analyze` (with and
//! without an accelerometer) and Python: the whole frame, the K blobs of the first frame or
//! chosen points.

use crate::points::{Point, PointsInfo};
use crate::tracks::Tracks;
use firmware_core::centroid::CentroidConfig;
use vibcam_readers::frames::FrameSource;

/// Which targets are followed.
#[derive(Debug, Clone, PartialEq)]
pub enum Targets {
    /// The one target of the whole frame (or the centroid's ROI).
    Whole,
    /// Chosen points and their threshold rule.
    Points(Vec<Point>, crate::points::PointTracker),
    /// The K blobs of the first frame, with the gate (px).
    Blobs(usize, f64),
}

impl Targets {
    /// How many targets are followed.
    pub fn count(&self) -> usize {
        match self {
            Targets::Whole => 1,
            Targets::Points(p, _) => p.len(),
            Targets::Blobs(k, _) => *k,
        }
    }
}

/// Follows `targets` through `source`: the one tracking dispatcher of `track`, `analyze` (with
/// and without an accelerometer) and Python's `track`/`analyze`. The tracks, and with chosen
/// points what their windows used.
pub fn track_targets(
    source: &FrameSource,
    fps: f64,
    centroid: &CentroidConfig,
    targets: &Targets,
) -> anyhow::Result<(Tracks, Option<PointsInfo>)> {
    Ok(match targets {
        Targets::Whole => {
            let (c, depth) = vibcam_readers::frames::centroid_source(source, fps, centroid)?;
            let first = c
                .iter()
                .find_map(|c| c.position())
                .map(|(x, y)| (f64::from(x), f64::from(y)))
                .unwrap_or((f64::NAN, f64::NAN));
            let tracks = Tracks {
                centroids: vec![c],
                first: vec![first],
                refused: vec![0],
                depth,
                evidence: Vec::new(),
            };
            (tracks, None)
        }
        Targets::Points(points, rule) => {
            let (t, w) = crate::points::track_points(source, fps, points, centroid, *rule)?;
            (t, Some(w))
        }
        Targets::Blobs(k, gate) => (
            crate::tracks::track(source, fps, centroid, *k, *gate)?,
            None,
        ),
    })
}
