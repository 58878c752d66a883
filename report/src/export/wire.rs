//! The lines a page's mode shapes are drawn with ([`Wire`]): a geometry file's lines and nodes
//! ([`vibcam_readers::geometry`]), the groups tracking followed targets in (each group's
//! targets joined in order), or, with neither, the points in number order broken at long steps
//! ([`number_order`]).

use vibcam_readers::geometry::Geometry;
/// A geometry's unit.
pub use vibcam_readers::geometry::Unit;

/// The lines a page's mode shapes are drawn with, and the points' own coordinates when a
/// geometry gives them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Wire {
    /// Lines between the shape's points (0-based indices, in the order of
    /// [`super::html::ShapeAnimation::shape`]).
    pub lines: Vec<(usize, usize)>,
    /// Each point's coordinates from a geometry, and their unit (millimetres: a plain view,
    /// y up; pixels: on the frame when there is one); none: where the targets were tracked.
    pub nodes: Option<(Vec<(f64, f64)>, Unit)>,
    /// Where the lines come from, said under the shapes; empty when nothing gave them: the
    /// page then joins the points in number order, broken at long steps ([`number_order`]).
    pub from: String,
}

/// Lines joining `points` in number order, except a step longer than 1.5 times the median
/// step (a jump from the end of one beam to the start of the next, as a tag row ends).
pub fn number_order(points: &[(f64, f64)]) -> Vec<(usize, usize)> {
    let steps: Vec<f64> = points
        .windows(2)
        .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
        .collect();
    let mut sorted: Vec<f64> = steps.iter().copied().filter(|d| d.is_finite()).collect();
    sorted.sort_by(f64::total_cmp);
    let Some(&median) = sorted.get(sorted.len() / 2) else {
        return Vec::new();
    };
    steps
        .iter()
        .enumerate()
        .filter(|(_, d)| **d <= 1.5 * median)
        .map(|(i, _)| (i, i + 1))
        .collect()
}

impl Wire {
    /// The lines on `points` (their numbers in the shapes' order; `what`: "target" or
    /// "response"): the `geometry`'s (its path and content) when given, else each of `groups`
    /// (point numbers) joined in order, else none said (the page's number order). An error
    /// names the geometry file and the node that fits none of the points.
    pub fn on(
        geometry: Option<&(std::path::PathBuf, Geometry)>,
        points: &[usize],
        what: &str,
        groups: Option<&[Vec<usize>]>,
    ) -> anyhow::Result<Wire> {
        if let Some((path, g)) = geometry {
            return Wire::of_geometry(g, points, what, &path.display().to_string());
        }
        let index = |n: &usize| points.iter().position(|p| p == n);
        let groups: Vec<Vec<usize>> = groups
            .unwrap_or_default()
            .iter()
            .map(|g| g.iter().filter_map(index).collect())
            .collect();
        Ok(Wire::of_groups(&groups).unwrap_or_default())
    }

    /// `g` (read from `file`) on the shape's `points` (their numbers in the shape's order;
    /// `what`: "target" or "response"); an error names the file and the node that does not fit.
    pub fn of_geometry(
        g: &Geometry,
        points: &[usize],
        what: &str,
        file: &str,
    ) -> anyhow::Result<Wire> {
        let (lines, nodes) = g.on(points, what, file)?;
        let kind = match &nodes {
            Some((_, Unit::Mm)) => "its nodes in millimetres, drawn in a plain view, y up",
            Some((_, Unit::Px)) => "its nodes in the image's pixels",
            None => "lines alone, between the points where they were tracked",
        };
        Ok(Wire {
            from: format!(
                "Lines of the geometry {file} ({} line{}; {kind}).",
                lines.len(),
                if lines.len() == 1 { "" } else { "s" }
            ),
            lines,
            nodes,
        })
    }

    /// The wire on a subset of its points: `kept` holds the indices kept, in their new order
    /// (targets left out of an analysis); a line with an end left out is dropped.
    pub fn keep(&self, kept: &[usize]) -> Wire {
        let at = |i: usize| kept.iter().position(|&k| k == i);
        Wire {
            lines: self
                .lines
                .iter()
                .filter_map(|&(a, b)| Some((at(a)?, at(b)?)))
                .collect(),
            nodes: self.nodes.as_ref().map(|(xy, unit)| {
                (
                    kept.iter().filter_map(|&k| xy.get(k).copied()).collect(),
                    *unit,
                )
            }),
            from: self.from.clone(),
        }
    }

    /// Each group's points (0-based indices, in order) joined in order: the rigid parts
    /// tracking found or was given; none when no group has two points.
    pub fn of_groups(groups: &[Vec<usize>]) -> Option<Wire> {
        let lines: Vec<(usize, usize)> = groups
            .iter()
            .flat_map(|g| g.windows(2).map(|w| (w[0], w[1])))
            .collect();
        (!lines.is_empty()).then(|| Wire {
            from: format!(
                "Lines join the targets of each group tracking followed together ({} groups), \
                 in order; no geometry was given.",
                groups.len()
            ),
            lines,
            nodes: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn number_order_breaks_at_the_jump_between_rows() {
        // two rows of three tags 100 px apart, the second 300 px below
        let pts = [
            (0.0, 0.0),
            (100.0, 0.0),
            (200.0, 0.0),
            (0.0, 300.0),
            (100.0, 300.0),
            (200.0, 300.0),
        ];
        assert_eq!(number_order(&pts), vec![(0, 1), (1, 2), (3, 4), (4, 5)]);
        assert_eq!(number_order(&pts[..2]), vec![(0, 1)]);
        assert!(number_order(&pts[..1]).is_empty());
    }

    #[test]
    fn groups_are_joined_in_order_and_a_geometry_says_its_lines() {
        let w = Wire::of_groups(&[vec![0, 2, 3], vec![1, 4]]).unwrap();
        assert_eq!(w.lines, vec![(0, 2), (2, 3), (1, 4)]);
        assert!(Wire::of_groups(&[]).is_none());
        let g = vibcam_readers::geometry::parse("from,to\n1,3\n", "g.csv").unwrap();
        let w = Wire::of_geometry(&g, &[1, 2, 3], "target", "g.csv").unwrap();
        assert_eq!(w.lines, vec![(0, 2)]);
        assert!(w.from.contains("g.csv (1 line;"), "{}", w.from);
        // target 2 left out: the line 1-3 stays, between the two kept
        assert_eq!(w.keep(&[0, 2]).lines, vec![(0, 1)]);
        assert!(w.keep(&[0, 1]).lines.is_empty());
    }
}
