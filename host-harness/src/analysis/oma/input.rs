//! Displacement records for output-only analysis, read from a CSV file: `track`'s and
//! `analyze`'s `displacement.csv` (`frame,t_s,target,cx,cy,...,disp_mm,lost`, one row per frame
//! and target), or a wide file from any other tool (a time column `t_s`, `time` or `t`, then one
//! column per target; an empty cell is a lost sample).

use crate::analysis::MAX_LOST_FRACTION;
use crate::bad_input;
use crate::lost_frames::fill_lost_frames;
use std::path::Path;

/// Which coordinate of `displacement.csv` is the motion when it has no `disp_mm`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PixelAxis {
    /// `-cy` (positive up in the image).
    Y,
    /// `cx` (positive right).
    X,
}

/// The records read: one per target kept, and why the others were left out.
#[derive(Debug, Clone, PartialEq)]
pub struct Records {
    /// Sample rate, Hz.
    pub fs_hz: f64,
    /// Unit of the values (`mm` or `px`; a wide file's are its own).
    pub unit: String,
    /// Targets kept: their number (as in the file) and first position (px, when known).
    pub targets: Vec<(usize, Option<(f64, f64)>)>,
    /// One record per kept target, lost samples filled by linear interpolation.
    pub channels: Vec<Vec<f64>>,
    /// Lost samples filled, per kept target.
    pub filled: Vec<usize>,
    /// Targets left out, with the reason.
    pub left_out: Vec<(usize, String)>,
}

/// Per target (its number) the samples (`None`: lost).
type Columns = Vec<(usize, Vec<Option<f64>>)>;

/// One row of `displacement.csv`: frame, target, millimetres, pixels along the axis, `(cx, cy)`.
type Cell = (usize, usize, Option<f64>, Option<f64>, Option<(f64, f64)>);

/// What a file gives: times, columns, unit, first positions.
type Parsed = (Vec<f64>, Columns, String, Vec<Option<(f64, f64)>>);

/// Reads `path` (see the module documentation). `fps`: the sample rate when given, else from
/// the time column (which must then be regular within 1 % of a period). Targets with more than
/// [`MAX_LOST_FRACTION`] lost samples, or constant, are left out and named; a cell that is not
/// a number is an error naming the row and column.
pub fn read(path: &Path, axis: PixelAxis, fps: Option<f64>) -> anyhow::Result<Records> {
    let table = Table::read(path)?;
    let (times, columns, unit, firsts): Parsed =
        match (table.column("frame"), table.column("target")) {
            (Some(frame), Some(target)) => long_file(&table, (frame, target), axis, fps)?,
            _ => wide_file(&table, fps)?,
        };
    let samples = columns.first().map_or(0, |c| c.1.len());
    if columns.is_empty() || samples < 2 {
        return Err(bad_input(format!(
            "{}: no records to analyse ({} targets, {samples} samples)",
            path.display(),
            columns.len()
        )));
    }
    let fs_hz = sample_rate(fps, &times, path)?;
    keep_records(columns, firsts, (fs_hz, unit), path)
}

/// A CSV file's header and rows, its cells read as numbers with errors naming the row and
/// column.
struct Table<'a> {
    path: &'a Path,
    header: Vec<String>,
    rows: Vec<csv::StringRecord>,
}

impl<'a> Table<'a> {
    /// Reads `path`.
    fn read(path: &'a Path) -> anyhow::Result<Self> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| bad_input(format!("{}: cannot read: {e}", path.display())))?;
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(true)
            .from_reader(text.as_bytes());
        let header: Vec<String> = reader
            .headers()
            .map_err(|e| bad_input(format!("{}: {e}", path.display())))?
            .iter()
            .map(|h| h.trim().to_string())
            .collect();
        let rows: Vec<csv::StringRecord> = reader
            .records()
            .collect::<Result<_, _>>()
            .map_err(|e| bad_input(format!("{}: {e}", path.display())))?;
        Ok(Table { path, header, rows })
    }

    /// The column named `name`.
    fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// Row `row` (0-based after the header) of `r`, column `col`: a finite number, `None` when
    /// empty.
    fn num(&self, row: usize, col: usize, r: &csv::StringRecord) -> anyhow::Result<Option<f64>> {
        let cell = r.get(col).unwrap_or("").trim();
        if cell.is_empty() {
            return Ok(None);
        }
        match cell.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Some(v)),
            _ => Err(bad_input(format!(
                "{}: row {}: column {}: {cell:?} is not a finite number",
                self.path.display(),
                row + 2,
                self.header[col]
            ))),
        }
    }

    /// A frame or target number of row `i`: a whole number from 0 to the row count (a number
    /// beyond it would stand for more missing frames than the file has rows, and their
    /// allocation).
    fn whole(
        &self,
        i: usize,
        col: usize,
        r: &csv::StringRecord,
        what: &str,
    ) -> anyhow::Result<usize> {
        let path = self.path.display();
        let v = self
            .num(i, col, r)?
            .ok_or_else(|| bad_input(format!("{path}: row {}: no {what}", i + 2)))?;
        if v.fract() != 0.0 || v < 0.0 || v > self.rows.len() as f64 {
            return Err(bad_input(format!(
                "{path}: row {}: the {what} is {v}: a whole number from 0 to {} (the file's row \
                 count) is needed",
                i + 2,
                self.rows.len()
            )));
        }
        Ok(v as usize)
    }
}

/// The cells of a long file (`displacement.csv`: one row per frame and target), duplicates
/// checked: the cells, the targets (sorted), the frame count and each frame's time.
struct LongCells {
    cells: Vec<Cell>,
    ids: Vec<usize>,
    frames: usize,
    t_of: Vec<Option<f64>>,
}

/// Reads the rows of a long file (`frame`, `target` the columns of those numbers).
fn long_cells(
    t: &Table<'_>,
    (frame, target): (usize, usize),
    axis: PixelAxis,
) -> anyhow::Result<LongCells> {
    let t_col = t.column("t_s");
    let (cx, cy, mm, lost) = (
        t.column("cx"),
        t.column("cy"),
        t.column("disp_mm"),
        t.column("lost"),
    );
    let mut out = LongCells {
        cells: Vec::new(),
        ids: Vec::new(),
        frames: 0,
        t_of: Vec::new(),
    };
    // the row (0-based) of each (frame, target) seen, for duplicates
    let mut seen: std::collections::HashMap<(usize, usize), usize> =
        std::collections::HashMap::new();
    for (i, r) in t.rows.iter().enumerate() {
        let f = t.whole(i, frame, r, "frame number")?;
        let id = t.whole(i, target, r, "target number")?;
        if let Some(&j) = seen.get(&(f, id)) {
            let same = t.rows[j].iter().map(str::trim).eq(r.iter().map(str::trim));
            if !same {
                return Err(bad_input(format!(
                    "{}: rows {} and {} both give frame {f} of target {id}, with different \
                     values: which one is the measurement is not known (remove one)",
                    t.path.display(),
                    j + 2,
                    i + 2
                )));
            }
            continue;
        }
        seen.insert((f, id), i);
        if !out.ids.contains(&id) {
            out.ids.push(id);
        }
        out.frames = out.frames.max(f + 1);
        if out.t_of.len() < out.frames {
            out.t_of.resize(out.frames, None);
        }
        if let Some(c) = t_col {
            out.t_of[f] = t.num(i, c, r)?;
        }
        let is_lost = match lost {
            Some(c) => t.num(i, c, r)? == Some(1.0),
            None => false,
        };
        let xy = match (cx, cy) {
            (Some(a), Some(b)) => t.num(i, a, r)?.zip(t.num(i, b, r)?),
            _ => None,
        };
        let pixel = xy.map(|(x, y)| match axis {
            PixelAxis::Y => -y,
            PixelAxis::X => x,
        });
        let disp = match mm {
            Some(c) => t.num(i, c, r)?,
            None => None,
        };
        let (disp, pixel) = if is_lost { (None, None) } else { (disp, pixel) };
        out.cells.push((f, id, disp, pixel, xy));
    }
    out.ids.sort_unstable();
    Ok(out)
}

/// A long file (`displacement.csv`) as records: millimetres when every target has them
/// wherever it is not lost, else pixels along `axis`.
fn long_file(
    t: &Table<'_>,
    columns: (usize, usize),
    axis: PixelAxis,
    fps: Option<f64>,
) -> anyhow::Result<Parsed> {
    let LongCells {
        cells,
        ids,
        frames,
        t_of,
    } = long_cells(t, columns, axis)?;
    let use_mm = t.column("disp_mm").is_some()
        && cells.iter().all(|c| c.2.is_some() || c.3.is_none())
        && cells.iter().any(|c| c.2.is_some());
    let mut cols: Vec<(usize, Vec<Option<f64>>)> =
        ids.iter().map(|&t| (t, vec![None; frames])).collect();
    let mut firsts: Vec<Option<(f64, f64)>> = vec![None; ids.len()];
    for (f, id, disp, pixel, xy) in cells {
        let Ok(k) = ids.binary_search(&id) else {
            continue;
        };
        cols[k].1[f] = if use_mm { disp } else { pixel };
        if firsts[k].is_none() {
            firsts[k] = xy;
        }
    }
    let times = match t.column("t_s") {
        // every frame's time, to check --fps against when it is given
        Some(_) if fps.is_some() && t_of.iter().all(Option::is_some) => {
            t_of.iter().flatten().copied().collect()
        }
        Some(_) if fps.is_none() => t_of
            .iter()
            .enumerate()
            .map(|(f, time)| {
                time.ok_or_else(|| {
                    bad_input(format!(
                        "{}: frame {f} has no time (t_s); give $fps",
                        t.path.display()
                    ))
                })
            })
            .collect::<anyhow::Result<_>>()?,
        _ => Vec::new(),
    };
    let unit = if use_mm { "mm" } else { "px" };
    Ok((times, cols, unit.to_string(), firsts))
}

/// A wide file: a time column (`t_s`, `time` or `t`; none with `fps`), then one column per
/// target in the file's own units.
fn wide_file(t: &Table<'_>, fps: Option<f64>) -> anyhow::Result<Parsed> {
    let t_col = ["t_s", "time", "t"].iter().find_map(|n| t.column(n));
    let mut cols: Vec<(usize, Vec<Option<f64>>)> = Vec::new();
    for (c, _) in t
        .header
        .iter()
        .enumerate()
        .filter(|(c, _)| Some(*c) != t_col)
    {
        let mut v = Vec::with_capacity(t.rows.len());
        for (i, r) in t.rows.iter().enumerate() {
            v.push(t.num(i, c, r)?);
        }
        cols.push((cols.len() + 1, v));
    }
    let times = match t_col {
        Some(c) => t
            .rows
            .iter()
            .enumerate()
            .map(|(i, r)| {
                t.num(i, c, r)?.ok_or_else(|| {
                    bad_input(format!("{}: row {}: no time", t.path.display(), i + 2))
                })
            })
            .collect::<anyhow::Result<_>>()?,
        None if fps.is_some() => Vec::new(),
        None => {
            return Err(bad_input(format!(
                "{}: no time column (t_s, time or t) and no $fps",
                t.path.display()
            )))
        }
    };
    let n = cols.len();
    Ok((times, cols, "the file's units".to_string(), vec![None; n]))
}

/// The sample rate: `fps` when given (checked against a time column: within half a sample
/// over the record, a 30 given for a 60 Hz column would halve every frequency), else the time
/// column's.
fn sample_rate(fps: Option<f64>, times: &[f64], path: &Path) -> anyhow::Result<f64> {
    match fps {
        Some(f) if !(f.is_finite() && f > 0.0) => {
            Err(bad_input(format!("$fps must be positive, got {f}")))
        }
        Some(f) if times.len() > 1 => {
            let rate = rate_of(times, path)?;
            let drift = (times.len() - 1) as f64 * (1.0 / f - 1.0 / rate).abs() * rate;
            if drift > 0.5 {
                return Err(bad_input(format!(
                    "$fps {f} contradicts the time column of {}, whose samples are {} s \
                     apart ({rate:.6} Hz): leave $fps out, or correct the file",
                    path.display(),
                    1.0 / rate
                )));
            }
            Ok(f)
        }
        Some(f) => Ok(f),
        None => rate_of(times, path),
    }
}

/// The records kept: a target with more than [`MAX_LOST_FRACTION`] of its samples lost, or
/// constant, is left out with the reason; the others' lost samples are filled by
/// interpolation. No target left is an error naming each one's reason.
fn keep_records(
    columns: Columns,
    firsts: Vec<Option<(f64, f64)>>,
    (fs_hz, unit): (f64, String),
    path: &Path,
) -> anyhow::Result<Records> {
    let samples = columns.first().map_or(0, |c| c.1.len());
    let mut out = Records {
        fs_hz,
        unit,
        targets: Vec::new(),
        channels: Vec::new(),
        filled: Vec::new(),
        left_out: Vec::new(),
    };
    for ((t, col), first) in columns.into_iter().zip(firsts) {
        let valid: Vec<bool> = col.iter().map(Option::is_some).collect();
        let lost = valid.iter().filter(|v| !**v).count();
        if lost as f64 > MAX_LOST_FRACTION * samples as f64 {
            out.left_out.push((
                t,
                format!(
                    "{lost} of {samples} samples lost (more than {:.0} %)",
                    100.0 * MAX_LOST_FRACTION
                ),
            ));
            continue;
        }
        let mut v: Vec<f64> = col.iter().map(|x| x.unwrap_or(0.0)).collect();
        let filled = fill_lost_frames(&mut v, &valid);
        let (lo, hi) = v
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        if hi - lo <= 1e-12 * hi.abs().max(lo.abs()).max(1e-300) {
            out.left_out
                .push((t, "constant: it does not move (a dead target?)".to_string()));
            continue;
        }
        out.targets.push((t, first));
        out.channels.push(v);
        out.filled.push(filled);
    }
    if out.channels.is_empty() {
        let why: Vec<String> = out
            .left_out
            .iter()
            .map(|(t, w)| format!("target {t}: {w}"))
            .collect();
        return Err(bad_input(format!(
            "{}: no target left to analyse ({})",
            path.display(),
            why.join("; ")
        )));
    }
    Ok(out)
}

/// The sample rate of a regular time column: `(n - 1) / (t_last - t_first)`, every step within
/// 1 % of the period.
fn rate_of(times: &[f64], path: &Path) -> anyhow::Result<f64> {
    let n = times.len();
    let span = times[n - 1] - times[0];
    if span.is_nan() || span <= 0.0 {
        return Err(bad_input(format!(
            "{}: the time column does not increase (correct it, or remove it and give $fps)",
            path.display()
        )));
    }
    let period = span / (n - 1) as f64;
    for (i, w) in times.windows(2).enumerate() {
        if ((w[1] - w[0]) - period).abs() > 0.01 * period {
            return Err(bad_input(format!(
                "{}: sample {} is {} s after the one before, the record's period is {period} s: \
                 the samples must be regular (a gap or a dropped sample: resample the record \
                 first, or analyse the regular part)",
                path.display(),
                i + 1,
                w[1] - w[0]
            )));
        }
    }
    Ok(1.0 / period)
}
