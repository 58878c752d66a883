//! Universal file format records, dataset 58 (function at a nodal DOF: a time record, or an
//! FRF), in its ASCII form and its binary form `58b` (what test software and pyuff write).
//!
//! A dataset sits between lines `    -1`; its second line is the dataset number (`    58`, or
//! `    58b` with the byte order, the byte count of the data and the count of ASCII header lines
//! after it). Then records 1-5 (80-character ID lines), record 6 (function type, response and
//! reference node and direction, fixed columns 5, 10, 5, 10, 1+10, 10, 4, 1+10, 10, 4), record 7
//! (ordinate data type: 2 real single, 4 real double, 5 complex single, 6 complex double; the
//! number of points; even abscissa spacing or not; the abscissa's start and increment), records
//! 8-11 (axis labels and units), then the data: fixed-width fields (13 characters single, 20
//! double; uneven spacing puts each abscissa value, 13 characters, before its ordinate), or the
//! binary block of the stated byte count. Other datasets are skipped.
//!
//! Each dataset 58 becomes a [`Channel`] named `NODE:DIR` of its response (`1:3`, `12:-2`),
//! its unit the ordinate's unit label, `delta_x` the abscissa increment (even spacing) and `x`
//! the abscissa values (uneven). A complex dataset (an FRF) gives its real parts as `values`
//! and is refused by [`read`] unless asked for with [`read_complex`]. Checked against pyuff's
//! own reading of files pyuff wrote (`tests/data/uff`, `scripts/uff_fixtures.py`).

use super::{Channel, Record};
use crate::bad_input;
use num_complex::Complex64;
use std::path::Path;

/// One dataset 58.
#[derive(Debug, Clone, PartialEq)]
pub struct Function {
    /// Function type (1 time response, 4 FRF, ...).
    pub func_type: i64,
    /// Response node and direction.
    pub response: (i64, i64),
    /// Reference node and direction.
    pub reference: (i64, i64),
    /// The ordinate's unit label.
    pub unit: String,
    /// Abscissa start and increment (even spacing), or `None` (then `x` holds them).
    pub even: Option<(f64, f64)>,
    /// The abscissa values of an uneven dataset.
    pub x: Option<Vec<f64>>,
    /// The ordinate values (complex; the imaginary parts 0 for a real dataset).
    pub data: Vec<Complex64>,
    /// Whether the dataset is complex.
    pub complex: bool,
}

/// Reads every dataset 58 of the universal file `path` as channels of one segment; a complex
/// dataset is an error (a time record is real).
pub fn read(path: &Path) -> anyhow::Result<Record> {
    let name = path.display().to_string();
    let functions = read_complex(path)?;
    let mut channels = Vec::with_capacity(functions.len());
    for f in functions {
        let id = format!("{}:{}", f.response.0, f.response.1);
        if f.complex {
            return Err(bad_input(format!(
                "{name}: dataset 58 of `{id}` is complex (function type {}), not a time record",
                f.func_type
            )));
        }
        if channels.iter().any(|c: &Channel| c.name == id) {
            return Err(bad_input(format!(
                "{name}: two datasets 58 for the response `{id}`"
            )));
        }
        channels.push(Channel {
            name: id,
            unit: Some(f.unit.clone()).filter(|u| !u.is_empty() && u != "NONE"),
            delta_x: f.even.map(|e| e.1),
            x0: Some(f.even.map_or_else(
                || f.x.as_ref().and_then(|x| x.first().copied()).unwrap_or(0.0),
                |e| e.0,
            )),
            values: f.data.iter().map(|c| c.re).collect(),
            x: f.x,
            start_time: None,
        });
    }
    Ok(Record {
        segments: vec![channels],
        notes: Vec::new(),
    })
}

/// Every dataset 58 of `path`, real or complex.
pub fn read_complex(path: &Path) -> anyhow::Result<Vec<Function>> {
    let bytes = std::fs::read(path)
        .map_err(|e| bad_input(format!("{}: cannot read: {e}", path.display())))?;
    parse(&bytes, &path.display().to_string())
}

/// A cursor over the file's lines (binary blocks taken by byte count).
struct Lines<'a> {
    b: &'a [u8],
    at: usize,
    line: usize,
}

impl<'a> Lines<'a> {
    fn next(&mut self) -> Option<&'a str> {
        if self.at >= self.b.len() {
            return None;
        }
        let rest = &self.b[self.at..];
        let end = rest.iter().position(|&c| c == b'\n').unwrap_or(rest.len());
        self.at += (end + 1).min(rest.len());
        self.line += 1;
        let l = &rest[..end];
        let l = l.strip_suffix(b"\r").unwrap_or(l);
        Some(std::str::from_utf8(l).unwrap_or(""))
    }
}

/// Parses the bytes of a universal file; `file` names it in errors.
pub fn parse(bytes: &[u8], file: &str) -> anyhow::Result<Vec<Function>> {
    let mut out = Vec::new();
    let mut lines = Lines {
        b: bytes,
        at: 0,
        line: 0,
    };
    let err = |line: usize, what: String| bad_input(format!("{file}: line {line}: {what}"));
    while let Some(l) = lines.next() {
        if l.trim() != "-1" {
            continue;
        }
        let Some(head) = lines.next() else { break };
        let start = lines.line;
        let kind = head.get(..6).unwrap_or(head).trim();
        if kind != "58" {
            // another dataset (or the closing -1 of one): up to its end
            if kind.is_empty() || kind == "-1" {
                continue;
            }
            while let Some(l) = lines.next() {
                if l.trim() == "-1" {
                    break;
                }
            }
            continue;
        }
        let binary = head
            .as_bytes()
            .get(6)
            .is_some_and(|c| c.eq_ignore_ascii_case(&b'b'));
        // 58b: byte order (1 little, 2 big), format, ASCII lines, bytes
        let (little, n_bytes) = if binary {
            let f = |a: usize, b: usize| head.get(a..b.min(head.len())).unwrap_or("").trim();
            let order: i64 = f(7, 13).parse().unwrap_or(1);
            let n: usize = f(31, 43)
                .parse()
                .map_err(|_| err(start, "dataset 58b without its byte count".into()))?;
            (order != 2, n)
        } else {
            (true, 0)
        };
        let mut rec = Vec::with_capacity(11);
        for _ in 0..11 {
            rec.push(
                lines
                    .next()
                    .ok_or_else(|| err(lines.line, "dataset 58 ends inside its header".into()))?,
            );
        }
        let field = |s: &str, a: usize, b: usize| -> String {
            s.get(a.min(s.len())..b.min(s.len()))
                .unwrap_or("")
                .trim()
                .to_string()
        };
        let int = |s: &str, a: usize, b: usize, what: &str, line: usize| -> anyhow::Result<i64> {
            let v = field(s, a, b);
            v.parse()
                .map_err(|_| err(line, format!("{what} `{v}` is not a whole number")))
        };
        let r6 = rec[5];
        let l6 = start + 6;
        let func_type = int(r6, 0, 5, "function type", l6)?;
        let response = (
            int(r6, 41, 51, "response node", l6)?,
            int(r6, 51, 55, "response direction", l6)?,
        );
        let reference = (
            int(r6, 66, 76, "reference node", l6)?,
            int(r6, 76, 80, "reference direction", l6)?,
        );
        let r7 = rec[6];
        let l7 = start + 7;
        let ord = int(r7, 0, 10, "ordinate data type", l7)?;
        let n = usize::try_from(int(r7, 10, 20, "number of points", l7)?)
            .map_err(|_| err(l7, "a negative number of points".into()))?;
        let even = int(r7, 20, 30, "abscissa spacing", l7)? == 1;
        let real = |a: usize, b: usize| -> anyhow::Result<f64> {
            let v = field(r7, a, b);
            v.replace(['D', 'd'], "e")
                .parse()
                .map_err(|_| err(l7, format!("`{v}` is not a number")))
        };
        let (x_min, dx) = (real(30, 43)?, real(43, 56)?);
        let unit = field(rec[8], 47, 68);
        let (complex, double) = match ord {
            2 => (false, false),
            4 => (false, true),
            5 => (true, false),
            6 => (true, true),
            other => {
                return Err(err(
                    l7,
                    format!("ordinate data type {other} (expected 2, 4, 5 or 6)"),
                ))
            }
        };
        // per point: an abscissa value when uneven, then the real (and imaginary) parts
        let per_point = usize::from(!even) + 1 + usize::from(complex);
        // the header's count drives no allocation before the values are there to read
        let count = n
            .checked_mul(per_point)
            .filter(|c| *c <= bytes.len())
            .ok_or_else(|| err(l7, format!("{n} points: more than the file can hold")))?;
        let values: Vec<f64> = if binary {
            let size = if double { 8 } else { 4 };
            if n_bytes < count * size || lines.at.saturating_add(n_bytes) > bytes.len() {
                return Err(err(
                    start,
                    format!(
                        "dataset 58b states {n_bytes} bytes for {n} points ({count} values of \
                         {size} bytes), and the file holds {} after the header",
                        bytes.len().saturating_sub(lines.at)
                    ),
                ));
            }
            let block = &bytes[lines.at..lines.at + count * size];
            lines.at += n_bytes;
            block
                .chunks_exact(size)
                .map(|c| match (double, little) {
                    (true, true) => f64::from_le_bytes(c.try_into().unwrap_or([0; 8])),
                    (true, false) => f64::from_be_bytes(c.try_into().unwrap_or([0; 8])),
                    (false, true) => f64::from(f32::from_le_bytes(c.try_into().unwrap_or([0; 4]))),
                    (false, false) => f64::from(f32::from_be_bytes(c.try_into().unwrap_or([0; 4]))),
                })
                .collect()
        } else {
            // fixed widths: 13 for single and for an abscissa value, 20 for double
            let widths: Vec<usize> = (0..per_point)
                .map(|k| if !even && k == 0 || !double { 13 } else { 20 })
                .collect();
            let mut v = Vec::with_capacity(count);
            let mut k = 0;
            while v.len() < count {
                let line_no = lines.line + 1;
                let l = lines.next().ok_or_else(|| {
                    err(
                        lines.line,
                        format!("dataset 58 ends after {} of its {count} values", v.len()),
                    )
                })?;
                if l.trim() == "-1" {
                    return Err(err(
                        line_no,
                        format!("dataset 58 ends after {} of its {count} values", v.len()),
                    ));
                }
                let mut at = 0;
                while at < l.len() && v.len() < count {
                    let w = widths[k % per_point];
                    let s = l.get(at..(at + w).min(l.len())).unwrap_or("").trim();
                    if s.is_empty() {
                        break;
                    }
                    v.push(
                        s.replace(['D', 'd'], "e")
                            .parse()
                            .map_err(|_| err(line_no, format!("`{s}` is not a number")))?,
                    );
                    at += w;
                    k += 1;
                }
            }
            v
        };
        let mut x = Vec::new();
        let mut data = Vec::with_capacity(n);
        for p in values.chunks_exact(per_point) {
            let (xs, rest) = if even {
                (None, p)
            } else {
                (Some(p[0]), &p[1..])
            };
            x.extend(xs);
            data.push(Complex64::new(rest[0], if complex { rest[1] } else { 0.0 }));
        }
        out.push(Function {
            func_type,
            response,
            reference,
            unit,
            even: even.then_some((x_min, dx)),
            x: (!even).then_some(x),
            data,
            complex,
        });
        // the dataset's closing -1; after a 58b's binary block some writers end the block's
        // line first, so the -1 sits on a line of its own (pyuff reads both)
        let mut closing = lines.next();
        while binary && closing.is_some_and(|l| l.trim().is_empty()) {
            closing = lines.next();
        }
        if let Some(l) = closing {
            if l.trim() != "-1" {
                return Err(err(
                    lines.line,
                    format!(
                        "dataset 58 of `{}:{}` has more values than its {n} points",
                        response.0, response.1
                    ),
                ));
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_58b_whose_closing_minus_one_sits_on_its_own_line_is_read() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/uff");
        let bytes = std::fs::read(dir.join("time_binary.uff")).unwrap();
        let want = parse(&bytes, "b.uff").unwrap();
        // the writer's variant: the binary block's line ended before the closing -1
        let mut variant = Vec::new();
        let mut ended = 0;
        for (i, &b) in bytes.iter().enumerate() {
            if i > 0 && bytes[i..].starts_with(b"    -1\n") && bytes[i - 1] != b'\n' {
                variant.push(b'\n');
                ended += 1;
            }
            variant.push(b);
        }
        assert_eq!(ended, 2, "two binary blocks");
        assert_eq!(parse(&variant, "v.uff").unwrap(), want);
    }
}
