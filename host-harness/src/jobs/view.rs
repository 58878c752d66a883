//! The camera's view as `track`, `analyze` and Python take it: static references
//! (`$reference`, `$camera_model`) and the scale from the scene (`$mm_per_px`, `$scale`,
//! `$target_size_mm`, `$world`: one of them).

use super::{SpecError, SpecResult, Tracker};
use crate::analysis::points::{read_points, Point};
use crate::analysis::track_run::Targets;
use crate::analysis::view::{
    check_world, read_world, PointRef, References, ScaleInput, ViewSettings, WorldPoint,
};
use crate::geometry::Model;
use std::path::PathBuf;

/// The most references (`$reference`): the consensus tries sets of them.
pub const MAX_REFERENCES: usize = 64;

/// Points of the structure's plane as given.
#[derive(Debug, Clone, PartialEq)]
pub enum WorldInput {
    /// A CSV file `x,y,x_mm,y_mm[,u_px]`.
    File(PathBuf),
    /// Points in memory (Python).
    List(Vec<WorldPoint>),
}

/// The view's settings as given, unchecked.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ViewInput {
    /// `$reference`: windows on static parts of the scene.
    pub reference: Option<super::PointsInput>,
    /// `$camera_model` (`None`: a similarity with two references or more).
    pub camera_model: Option<Model>,
    /// `$scale`: `(A, B, mm)`, A and B a target `K` or a reference `rK`.
    pub scale: Option<(String, String, f64)>,
    /// `$target_size_mm`: each target's diameter.
    pub target_size_mm: Option<f64>,
    /// `$world`: points of the structure's plane.
    pub world: Option<WorldInput>,
}

impl ViewInput {
    /// Whether any scale other than `$mm_per_px` was asked for.
    pub fn has_scale(&self) -> bool {
        self.scale.is_some() || self.target_size_mm.is_some() || self.world.is_some()
    }
}

/// The targets and the view checked together (`track`, `analyze`): `$mm_per_px` in its range,
/// the targets, then the view against them and the one scale; with whether a scale was given.
pub fn tracking_and_view(
    tracking: super::TrackingInput,
    view: ViewInput,
    mm_per_px: Option<f64>,
) -> SpecResult<(super::Tracking, ViewSettings, bool)> {
    if let Some(s) = mm_per_px {
        crate::setting::table::number("track", "mm_per_px", s)?;
    }
    let tracking = super::Tracking::new(tracking)?;
    let scaled = mm_per_px.is_some() || view.has_scale();
    let view = check(view, mm_per_px, &tracking.targets, tracking.tracker)?;
    Ok((tracking, view, scaled))
}

/// Checks `input` against the targets and the tracker; `mm_per_px` the one scale given.
pub fn check(
    input: ViewInput,
    mm_per_px: Option<f64>,
    targets: &Targets,
    tracker: Tracker,
) -> SpecResult<ViewSettings> {
    let given: Vec<&str> = [
        ("$mm_per_px", mm_per_px.is_some()),
        ("$scale", input.scale.is_some()),
        ("$target_size_mm", input.target_size_mm.is_some()),
        ("$world", input.world.is_some()),
    ]
    .iter()
    .filter(|(_, g)| *g)
    .map(|(k, _)| *k)
    .collect();
    if given.len() > 1 {
        return Err(SpecError::setting(format!(
            "{}: one scale only",
            given.join(" and ")
        )));
    }
    if input.camera_model.is_some() && input.reference.is_none() {
        return Err(SpecError::setting(
            "$camera_model is the model of the camera's motion from $reference: give \
             $reference (windows on parts of the scene that do not move)",
        ));
    }
    let references = references(input.reference, input.camera_model, targets)?;
    let n_refs = references.as_ref().map_or(0, |r| r.points.len());
    let scale = scale(
        input.scale,
        input.target_size_mm,
        input.world,
        (targets, n_refs, tracker),
    )?;
    Ok(ViewSettings { references, scale })
}

/// The static references read or taken from a list, checked against the targets and the
/// camera's model.
fn references(
    reference: Option<super::PointsInput>,
    camera_model: Option<Model>,
    targets: &Targets,
) -> SpecResult<Option<References>> {
    let references = match reference {
        Some(r) => {
            let (points, file) = match r {
                super::PointsInput::File(f) => {
                    (read_points(&f).map_err(SpecError::Input)?, Some(f))
                }
                super::PointsInput::List(p) => (checked(p)?, None),
            };
            if points.len() > MAX_REFERENCES {
                return Err(SpecError::setting(format!(
                    "$reference: {} references; at most {MAX_REFERENCES} (a few on static \
                     parts around the scene suffice)",
                    points.len()
                )));
            }
            check_reference_layout(&points, camera_model, targets)?;
            if let Some(m) = camera_model {
                if points.len() < m.minimum() {
                    return Err(SpecError::setting(format!(
                        "$camera_model {}: needs {} references or more; $reference has {}",
                        m.name(),
                        m.minimum(),
                        points.len()
                    )));
                }
            }
            Some(References {
                points,
                model: camera_model,
                file,
            })
        }
        None => None,
    };
    Ok(references)
}

/// The one scale asked for: between two points, each target's size, or the plane's points;
/// `n_refs` the number of references.
fn scale(
    scale: Option<(String, String, f64)>,
    target_size_mm: Option<f64>,
    world: Option<WorldInput>,
    (targets, n_refs, tracker): (&Targets, usize, Tracker),
) -> SpecResult<Option<ScaleInput>> {
    let scale = if let Some((a, b, mm)) = scale {
        super::positive("scale", mm, "the distance between the two points, mm")?;
        let parse = |s: &str| -> SpecResult<PointRef> {
            let p = PointRef::parse(s).ok_or_else(|| {
                SpecError::setting(format!(
                    "$scale: `{s}` is neither a target (1, 2, ...) nor a reference (r1, r2, ...)"
                ))
            })?;
            match p {
                PointRef::Target(k) if k > targets.count() => Err(SpecError::setting(format!(
                    "$scale: target {k}, but there are {} target(s)",
                    targets.count()
                ))),
                PointRef::Reference(k) if k > n_refs => Err(SpecError::setting(format!(
                    "$scale: reference r{k}, but $reference has {n_refs}"
                ))),
                p => Ok(p),
            }
        };
        let (pa, pb) = (parse(&a)?, parse(&b)?);
        if pa == pb {
            return Err(SpecError::setting(format!(
                "$scale: `{a}` and `{b}` are the same point"
            )));
        }
        Some(ScaleInput::Between(pa, pb, mm))
    } else if let Some(mm) = target_size_mm {
        super::positive("target_size_mm", mm, "each target's diameter, mm")?;
        if tracker == Tracker::Lk {
            return Err(SpecError::setting(
                "$target_size_mm: a target's size in the image is its blob's (pixels above the \
                 threshold); $tracker lk has no blob: give $scale or $world",
            ));
        }
        Some(ScaleInput::TargetSize(mm))
    } else if let Some(w) = world {
        Some(match w {
            WorldInput::File(f) => {
                ScaleInput::World(read_world(&f).map_err(SpecError::Input)?, Some(f))
            }
            WorldInput::List(p) => {
                check_world(&p).map_err(|e| SpecError::setting(format!("$world: {e}")))?;
                ScaleInput::World(p, None)
            }
        })
    } else {
        None
    };
    Ok(scale)
}

/// Whether two windows (centre and size) share a pixel.
fn overlap(a: &Point, b: &Point) -> bool {
    (a.xy.0 - b.xy.0).abs() < f64::from(a.size.0 + b.size.0) / 2.0
        && (a.xy.1 - b.xy.1).abs() < f64::from(a.size.1 + b.size.1) / 2.0
}

/// References the camera's motion can be found from: no two windows on the same part of the
/// scene, none on a target's window (it would take the structure's motion for the camera's),
/// and a layout the model can be fitted from (a homography needs four with no three on a line,
/// a similarity two apart).
fn check_reference_layout(
    refs: &[Point],
    model: Option<Model>,
    targets: &Targets,
) -> SpecResult<()> {
    for (i, a) in refs.iter().enumerate() {
        for (j, b) in refs.iter().enumerate().skip(i + 1) {
            if overlap(a, b) {
                return Err(SpecError::setting(format!(
                    "$reference: r{} at ({}, {}) and r{} at ({}, {}) have overlapping windows: \
                     they follow the same part of the scene, and the camera's roll and scale \
                     cannot be told from them; place references apart, around the scene",
                    i + 1,
                    a.xy.0,
                    a.xy.1,
                    j + 1,
                    b.xy.0,
                    b.xy.1
                )));
            }
        }
        if let Targets::Points(points, _) = targets {
            if let Some(t) = points.iter().find(|t| overlap(a, t)) {
                return Err(SpecError::setting(format!(
                    "$reference: r{} at ({}, {}) overlaps target {}'s window at ({}, {}): a \
                     reference must be on a part of the scene that does not move, or the \
                     structure's own motion is taken for the camera's and removed",
                    i + 1,
                    a.xy.0,
                    a.xy.1,
                    t.target,
                    t.xy.0,
                    t.xy.1
                )));
            }
        }
    }
    let centres: Vec<(f64, f64)> = refs.iter().map(|p| p.xy).collect();
    if model == Some(Model::Homography) && centres.len() >= 4 && !spread_for_a_homography(&centres)
    {
        return Err(SpecError::setting(format!(
            "$camera_model homography: the {} references lie on one line, or no four of them \
             stand apart from each other's lines (by 5 % of their layout's extent): a \
             homography cannot be fitted from them; place four or more around the scene, no \
             three on a line, or use $camera_model similarity",
            centres.len()
        )));
    }
    Ok(())
}

/// Whether four of `p` stand apart from each other's lines: each of the four at least 5 % of
/// the layout's extent (and 10 px) from the line through any two others. Nearly on a line, a
/// homography's fit amplifies the references' noise without bound (four on a line once gave a
/// roll of 110 degrees).
fn spread_for_a_homography(p: &[(f64, f64)]) -> bool {
    let extent = p
        .iter()
        .flat_map(|a| p.iter().map(move |b| (a.0 - b.0).hypot(a.1 - b.1)))
        .fold(0.0, f64::max);
    let least = (0.05 * extent).max(10.0);
    // the distance of `c` from the line through `a` and `b`
    let off = |a: (f64, f64), b: (f64, f64), c: (f64, f64)| {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        ((c.0 - a.0) * dy - (c.1 - a.1) * dx).abs() / dx.hypot(dy).max(1e-300)
    };
    let n = p.len();
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                for l in k + 1..n {
                    let q = [p[i], p[j], p[k], p[l]];
                    let apart = (0..4).all(|m| {
                        let o: Vec<(f64, f64)> = (0..4).filter(|x| *x != m).map(|x| q[x]).collect();
                        off(o[0], o[1], q[m]) >= least
                            && off(o[0], o[2], q[m]) >= least
                            && off(o[1], o[2], q[m]) >= least
                    });
                    if apart {
                        return true;
                    }
                }
            }
        }
    }
    false
}

/// References given in memory, checked as a points file's rows are.
fn checked(points: Vec<Point>) -> SpecResult<Vec<Point>> {
    if points.is_empty() {
        return Err(SpecError::setting("$reference: no points given"));
    }
    for (i, p) in points.iter().enumerate() {
        if !(p.xy.0.is_finite() && p.xy.1.is_finite()) || p.size.0 < 3 || p.size.1 < 3 {
            return Err(SpecError::setting(format!(
                "$reference[{i}]: a finite centre and a window of 3 x 3 px or more"
            )));
        }
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::jobs::Naming;

    fn refs(n: usize) -> Option<super::super::PointsInput> {
        Some(super::super::PointsInput::List(
            (1..=n)
                .map(|k| Point {
                    target: k,
                    xy: (10.0 * k as f64, 5.0),
                    size: (9, 9),
                    threshold: None,
                    group: None,
                })
                .collect(),
        ))
    }

    #[test]
    fn view_settings_that_do_not_go_together_are_named() {
        let t = Targets::Blobs(3, 10.0);
        let cases: Vec<(ViewInput, Option<f64>, Tracker, &str)> = vec![
            (
                ViewInput {
                    target_size_mm: Some(10.0),
                    ..Default::default()
                },
                Some(0.1),
                Tracker::Blob,
                "mm_per_px and target_size_mm: one scale only",
            ),
            (
                ViewInput {
                    reference: refs(MAX_REFERENCES + 1),
                    ..Default::default()
                },
                None,
                Tracker::Blob,
                "reference: 65 references; at most 64",
            ),
            (
                ViewInput {
                    camera_model: Some(Model::Similarity),
                    ..Default::default()
                },
                None,
                Tracker::Blob,
                "camera_model is the model",
            ),
            (
                ViewInput {
                    reference: refs(3),
                    camera_model: Some(Model::Homography),
                    ..Default::default()
                },
                None,
                Tracker::Blob,
                "needs 4 references or more; reference has 3",
            ),
            (
                ViewInput {
                    scale: Some(("1".into(), "r2".into(), 100.0)),
                    reference: refs(1),
                    ..Default::default()
                },
                None,
                Tracker::Blob,
                "reference r2, but reference has 1",
            ),
            (
                ViewInput {
                    scale: Some(("1".into(), "4".into(), 100.0)),
                    ..Default::default()
                },
                None,
                Tracker::Blob,
                "target 4, but there are 3",
            ),
            (
                ViewInput {
                    target_size_mm: Some(10.0),
                    ..Default::default()
                },
                None,
                Tracker::Lk,
                "tracker lk has no blob",
            ),
            (
                ViewInput {
                    world: Some(WorldInput::List(vec![
                        WorldPoint {
                            px: (0.0, 0.0),
                            mm: (0.0, 0.0),
                            u_px: 0.5
                        };
                        3
                    ])),
                    ..Default::default()
                },
                None,
                Tracker::Blob,
                "needs 4 or more",
            ),
        ];
        for (input, mm, tracker, want) in cases {
            let e = check(input.clone(), mm, &t, tracker).unwrap_err();
            assert!(e.message(Naming::Python).contains(want), "{input:?}: {e}");
        }
    }
}
