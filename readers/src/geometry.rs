//! A structure's geometry: nodes with 2-D coordinates and lines between them, on which mode
//! shapes are drawn as a wireframe (pyOMA-2's sensor coordinates and sensor lines, in 2-D).
//!
//! The file is CSV in two sections, each opened by its header; either may be left out (a file
//! of lines alone joins the targets where they were tracked), not both:
//!
//! ```text
//! # a portal frame (lines starting with # are comments)
//! node,x_mm,y_mm
//! 1,0,0
//! 2,0,500
//! 3,400,500
//! from,to
//! 1,2
//! 2,3
//! ```
//!
//! A node's number is the target's (or the response's) number it stands for. Coordinates are
//! in millimetres (`x_mm,y_mm`, y up) or in the image's pixels (`x_px,y_px`, y down, the
//! frame's coordinates).

use crate::bad_input;
use std::path::Path;

/// The unit of a geometry's coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unit {
    /// Millimetres on the structure, y up.
    Mm,
    /// The image's pixels, y down.
    Px,
}

/// A node: its number, x and y.
pub type Node = (usize, f64, f64);

/// A geometry as read: nodes and lines (node numbers), in the file's order.
#[derive(Debug, Clone, PartialEq)]
pub struct Geometry {
    /// The nodes and their unit (none: the lines join the points where they were measured).
    pub nodes: Option<(Vec<Node>, Unit)>,
    /// The lines, each two node numbers.
    pub lines: Vec<(usize, usize)>,
}

#[derive(Clone, Copy, PartialEq)]
enum Section {
    None,
    Nodes,
    Lines,
}

/// What is read so far: the section, the nodes (with their unit) and the lines (with their
/// rows, for the check that their ends are nodes).
struct Reading {
    section: Section,
    unit: Option<Unit>,
    nodes: Vec<Node>,
    lines: Vec<(usize, usize, usize)>,
    seen: (bool, bool),
}

/// Reads a geometry file; an error names the file and the row (rows numbered from 1, as an
/// editor shows them).
pub fn read(path: &Path) -> anyhow::Result<Geometry> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| bad_input(format!("{file}: cannot read the geometry: {e}")))?;
    parse(&text, &file)
}

/// Parses a geometry's text (see the module's documentation); `file` names it in errors.
pub fn parse(text: &str, file: &str) -> anyhow::Result<Geometry> {
    let mut r = Reading {
        section: Section::None,
        unit: None,
        nodes: Vec::new(),
        lines: Vec::new(),
        seen: (false, false),
    };
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        r.row(line, i + 1)
            .map_err(|msg| bad_input(format!("{file}: row {}: {msg}", i + 1)))?;
    }
    let Reading {
        unit, nodes, lines, ..
    } = r;
    let has = |n: usize| nodes.iter().any(|m| m.0 == n);
    if let Some(&(a, b, row)) = lines
        .iter()
        .find(|(a, b, _)| unit.is_some() && !(has(*a) && has(*b)))
    {
        let missing = if has(a) { b } else { a };
        return Err(bad_input(format!(
            "{file}: row {row}: line {a}-{b} ends at node {missing}, which the node section \
             does not give"
        )));
    }
    if nodes.is_empty() && lines.is_empty() {
        return Err(bad_input(format!(
            "{file}: no node and no line (a geometry has a `node,x_mm,y_mm` or `node,x_px,y_px` \
             section, a `from,to` section, or both)"
        )));
    }
    Ok(Geometry {
        nodes: unit.filter(|_| !nodes.is_empty()).map(|u| (nodes, u)),
        lines: lines.into_iter().map(|(a, b, _)| (a, b)).collect(),
    })
}

impl Reading {
    /// One row that is not blank or a comment: a section's header or one of its rows.
    fn row(&mut self, line: &str, row: usize) -> Result<(), String> {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let header: Vec<String> = cells.iter().map(|c| c.to_ascii_lowercase()).collect();
        match header.iter().map(String::as_str).collect::<Vec<_>>()[..] {
            ["node", "x_mm", "y_mm"] | ["node", "x_px", "y_px"] => {
                if self.seen.0 {
                    return Err("a second node section".into());
                }
                (self.seen.0, self.section) = (true, Section::Nodes);
                self.unit = Some(if header[1] == "x_mm" {
                    Unit::Mm
                } else {
                    Unit::Px
                });
                return Ok(());
            }
            ["from", "to"] => {
                if self.seen.1 {
                    return Err("a second line section".into());
                }
                (self.seen.1, self.section) = (true, Section::Lines);
                return Ok(());
            }
            _ => {}
        }
        match self.section {
            Section::None => Err(format!(
                "`{line}` before any header: a geometry opens with `node,x_mm,y_mm` (or \
                 `node,x_px,y_px`) or with `from,to`"
            )),
            Section::Nodes => {
                let [n, x, y] = cells[..] else {
                    return Err(format!("a node is 3 cells (node,x,y), got {}", cells.len()));
                };
                let n = number(n)?;
                if self.nodes.iter().any(|m| m.0 == n) {
                    return Err(format!("node {n} is given twice"));
                }
                self.nodes.push((n, coordinate(x)?, coordinate(y)?));
                Ok(())
            }
            Section::Lines => {
                let [a, b] = cells[..] else {
                    return Err(format!("a line is 2 cells (from,to), got {}", cells.len()));
                };
                let (a, b) = (number(a)?, number(b)?);
                if a == b {
                    return Err(format!("a line from node {a} to itself"));
                }
                self.lines.push((a, b, row));
                Ok(())
            }
        }
    }
}

/// A node's number: a whole number from 1.
fn number(c: &str) -> Result<usize, String> {
    match c.parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(format!("`{c}` is not a node number (1, 2, ...)")),
    }
}

/// A finite coordinate.
fn coordinate(c: &str) -> Result<f64, String> {
    match c.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("`{c}` is not a finite coordinate")),
    }
}

impl Geometry {
    /// The geometry on `points` (their numbers, in the order a shape lists them; `what`
    /// names them, "target" or "response"): the lines as 0-based indices into `points`, and
    /// each point's node coordinates when the file gives nodes. An error when a node or a
    /// line's end is not among the points, or a point has no node.
    #[allow(clippy::type_complexity)]
    pub fn on(
        &self,
        points: &[usize],
        what: &str,
        file: &str,
    ) -> anyhow::Result<(Vec<(usize, usize)>, Option<(Vec<(f64, f64)>, Unit)>)> {
        let index = |n: usize| {
            points.iter().position(|&p| p == n).ok_or_else(|| {
                bad_input(format!(
                    "{file}: node {n} is not a {what} of the input (its {what}s are {})",
                    list(points)
                ))
            })
        };
        let lines = self
            .lines
            .iter()
            .map(|&(a, b)| Ok((index(a)?, index(b)?)))
            .collect::<anyhow::Result<Vec<_>>>()?;
        let nodes = match &self.nodes {
            None => None,
            Some((nodes, unit)) => {
                for n in nodes {
                    index(n.0)?;
                }
                let xy = points
                    .iter()
                    .map(|p| {
                        nodes
                            .iter()
                            .find(|n| n.0 == *p)
                            .map(|n| (n.1, n.2))
                            .ok_or_else(|| {
                                bad_input(format!(
                                    "{file}: {what} {p} has no node (a node section gives every \
                                 {what}: {})",
                                    list(points)
                                ))
                            })
                    })
                    .collect::<anyhow::Result<Vec<_>>>()?;
                Some((xy, *unit))
            }
        };
        Ok((lines, nodes))
    }
}

fn list(points: &[usize]) -> String {
    points
        .iter()
        .map(usize::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    const FRAME: &str =
        "# a portal\nnode,x_mm,y_mm\n1,0,0\n2,0,500\n\n3,400,500\nfrom,to\n1,2\n2,3\n";

    #[test]
    fn a_portal_frame_reads_and_maps_onto_its_targets() {
        let g = parse(FRAME, "g.csv").unwrap();
        assert_eq!(g.lines, vec![(1, 2), (2, 3)]);
        let (nodes, unit) = g.nodes.clone().unwrap();
        assert_eq!(unit, Unit::Mm);
        assert_eq!(nodes[2], (3, 400.0, 500.0));
        // the targets listed in another order: the indices follow them
        let (lines, xy) = g.on(&[3, 1, 2], "target", "g.csv").unwrap();
        assert_eq!(lines, vec![(1, 2), (2, 0)]);
        assert_eq!(
            xy.unwrap().0,
            vec![(400.0, 500.0), (0.0, 0.0), (0.0, 500.0)]
        );
    }

    #[test]
    fn lines_alone_join_the_points_where_they_were_measured() {
        let g = parse("from,to\n1,2\n", "g.csv").unwrap();
        assert!(g.nodes.is_none());
        let (lines, xy) = g.on(&[1, 2, 3], "target", "g.csv").unwrap();
        assert_eq!((lines, xy), (vec![(0, 1)], None));
    }

    #[test]
    fn errors_name_the_file_and_the_row() {
        let cases = [
            ("1,2\n", "row 1: `1,2` before any header"),
            ("node,x_px,y_px\n1,0\n", "row 2: a node is 3 cells"),
            ("node,x_px,y_px\n1,0,nan\n", "row 2: `nan` is not a finite"),
            (
                "node,x_px,y_px\n1,0,0\n1,2,2\n",
                "row 3: node 1 is given twice",
            ),
            ("from,to\n2,2\n", "row 2: a line from node 2 to itself"),
            ("from,to\n0,2\n", "row 2: `0` is not a node number"),
            (
                "node,x_mm,y_mm\n1,0,0\nfrom,to\n1,4\n",
                "row 4: line 1-4 ends at node 4",
            ),
            ("# nothing\n", "no node and no line"),
        ];
        for (text, want) in cases {
            let e = parse(text, "g.csv").unwrap_err().to_string();
            assert!(
                e.starts_with("g.csv: ") && e.contains(want),
                "{text:?}: {e}"
            );
        }
        let g = parse(FRAME, "g.csv").unwrap();
        let e = g.on(&[1, 2], "target", "g.csv").unwrap_err().to_string();
        assert!(
            e.contains("node 3 is not a target of the input (its targets are 1, 2)"),
            "{e}"
        );
        let e = g
            .on(&[1, 2, 3, 4], "response", "g.csv")
            .unwrap_err()
            .to_string();
        assert!(e.contains("response 4 has no node"), "{e}");
    }
}
