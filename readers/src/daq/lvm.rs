//! LabVIEW measurement files (`.lvm`, text; NI's "LabVIEW Measurement File (.lvm) format"
//! specification): a file header (`Decimal_Separator`, `X_Columns`, `Separator`, ...) up to
//! `***End_of_Header***`, then one or more segments, each a header of per-channel lines
//! (`Channels`, `Samples`, `Y_Unit_Label`, `X0`, `Delta_X`) up to `***End_of_Header***`, the
//! column names (`X_Value ... Comment`) and the data rows, a blank line ending it.
//!
//! Columns: with `X_Columns` `No` the data rows hold an empty first field then one per channel;
//! `One`, a time column then one per channel; `Multi`, a time column before each channel. The
//! per-channel header lines hold one value per channel at the channel's first column (after
//! the key). A comma decimal separator (`Decimal_Separator ,`, as a European LabVIEW writes)
//! is read as such, in the data and the header. A segment of a file with `Multi_Headings No`
//! that starts without its own header takes the previous segment's.
//!
//! What a reader must not do silently: a field that is not a number is an error naming the
//! file, the line and the channel; an empty field is a channel without that sample (LabVIEW
//! leaves channels with fewer samples blank at the end), and a sample after a blank one in the
//! same channel is an error (a gap would shift every later sample in time). Checked against
//! `lvm_read` (the ladisk reader) on its own test files (`tests/data/lvm`, MIT licence beside
//! them), every value equal.

use super::{Channel, Record};
use crate::bad_input;
use std::path::Path;

/// How the time columns are laid out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum XColumns {
    No,
    One,
    Multi,
}

/// One segment's header: per channel its name, unit, `X0`, `Delta_X`.
#[derive(Debug, Clone, Default)]
struct Header {
    channels: usize,
    units: Vec<Option<String>>,
    x0: Vec<Option<f64>>,
    delta_x: Vec<Option<f64>>,
    /// `Samples`: each channel's count in the segment, when stated.
    samples: Vec<Option<usize>>,
    names: Vec<String>,
}

/// Reads the LabVIEW measurement file `path`.
pub fn read(path: &Path) -> anyhow::Result<Record> {
    let bytes = std::fs::read(path)
        .map_err(|e| bad_input(format!("{}: cannot read: {e}", path.display())))?;
    // LabVIEW on Windows writes the system's code page (a degree sign, 0xB0): Latin-1 then
    let text = match String::from_utf8(bytes) {
        Ok(t) => t,
        Err(e) => e.into_bytes().iter().map(|&b| char::from(b)).collect(),
    };
    parse(&text, &path.display().to_string())
}

/// Parses the text of a LabVIEW measurement file; `file` names it in errors.
pub fn parse(text: &str, file: &str) -> anyhow::Result<Record> {
    // a byte-order mark (Notepad's "UTF-8") is no part of the first line
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if !text.is_empty() && !text.ends_with('\n') {
        // LabVIEW ends every line: a file without its last line's end was cut (`head -c`),
        // and its last value may be cut inside its digits
        return Err(bad_input(format!(
            "{file}: ends inside a line ({:?}): a file cut short; its last value cannot be \
             trusted",
            text.lines().last().unwrap_or("")
        )));
    }
    let lines: Vec<&str> = text.lines().map(|l| l.trim_end_matches('\r')).collect();
    if !lines
        .first()
        .is_some_and(|l| l.starts_with("LabVIEW Measurement"))
    {
        return Err(bad_input(format!(
            "{file}: not a LabVIEW measurement file (its first line is not `LabVIEW \
             Measurement`)"
        )));
    }
    // the file header
    let mut decimal = '.';
    let mut xcols = XColumns::One;
    let mut sep = '\t';
    let mut i = 1;
    while i < lines.len() && !lines[i].starts_with("***End_of_Header***") {
        // the key, then its value up to the next separator: a tab, or a comma in a file whose
        // `Separator` is `Comma` (its file header is written with commas too)
        let line = lines[i];
        let (key, value) = match line.find(['\t', ',']) {
            Some(at) => {
                let sep_char = line[at..].chars().next().unwrap_or('\t');
                let rest = &line[at + sep_char.len_utf8()..];
                (
                    &line[..at],
                    rest.split(sep_char).next().unwrap_or("").trim(),
                )
            }
            None => (line, ""),
        };
        match key {
            "Decimal_Separator" => {
                decimal = value.chars().next().unwrap_or('.');
            }
            "X_Columns" => {
                xcols = match value {
                    "No" => XColumns::No,
                    "One" => XColumns::One,
                    "Multi" => XColumns::Multi,
                    other => {
                        return Err(bad_input(format!(
                            "{file}: line {}: X_Columns `{other}` (expected No, One or Multi)",
                            i + 1
                        )))
                    }
                }
            }
            "Separator" => {
                sep = match value {
                    "Tab" | "" => '\t',
                    "Comma" => ',',
                    other => {
                        return Err(bad_input(format!(
                            "{file}: line {}: Separator `{other}` (expected Tab or Comma)",
                            i + 1
                        )))
                    }
                }
            }
            _ => {}
        }
        i += 1;
    }
    if i >= lines.len() {
        return Err(bad_input(format!(
            "{file}: the file header has no `***End_of_Header***`"
        )));
    }
    if sep == ',' && decimal == ',' {
        return Err(bad_input(format!(
            "{file}: comma as both the separator and the decimal separator"
        )));
    }
    i += 1;
    let number = |s: &str| -> Option<f64> {
        let s = s.trim();
        if decimal == '.' {
            s.parse().ok()
        } else {
            s.replace(decimal, ".").parse().ok()
        }
    };
    let mut segments: Vec<Vec<Channel>> = Vec::new();
    let mut notes: Vec<String> = Vec::new();
    let mut header: Option<Header> = None;
    while i < lines.len() {
        if lines[i].split(sep).all(|f| f.trim().is_empty()) {
            i += 1;
            continue;
        }
        let first = lines[i].split(sep).next().unwrap_or("");
        let is_data = first.trim().is_empty() || number(first).is_some();
        if !is_data {
            // a segment header, then its column names
            let mut h = Header::default();
            while i < lines.len() && !lines[i].starts_with("***End_of_Header***") {
                let f: Vec<&str> = lines[i].split(sep).collect();
                let per_channel = |k: usize| -> Option<&str> {
                    let at = match xcols {
                        XColumns::Multi => 1 + 2 * k,
                        _ => 1 + k,
                    };
                    f.get(at).map(|v| v.trim()).filter(|v| !v.is_empty())
                };
                match f[0] {
                    "Channels" => {
                        h.channels = f
                            .get(1)
                            .and_then(|v| v.trim().parse().ok())
                            // each channel takes at least a byte of the column names
                            .filter(|n| *n <= text.len())
                            .ok_or_else(|| {
                                bad_input(format!(
                                    "{file}: line {}: `Channels` without a plausible count",
                                    i + 1
                                ))
                            })?;
                    }
                    "Samples" => {
                        h.samples = (0..h.channels)
                            .map(|k| per_channel(k).and_then(|v| v.parse().ok()))
                            .collect()
                    }
                    "Y_Unit_Label" => {
                        h.units = (0..h.channels)
                            .map(|k| per_channel(k).map(String::from))
                            .collect()
                    }
                    "X0" | "Delta_X" => {
                        let mut v = Vec::with_capacity(h.channels);
                        for k in 0..h.channels {
                            v.push(match per_channel(k) {
                                None => None,
                                Some(s) => Some(number(s).ok_or_else(|| {
                                    bad_input(format!(
                                        "{file}: line {}: {} of channel {}: `{s}` is not a \
                                         number (decimal separator `{decimal}`)",
                                        i + 1,
                                        f[0],
                                        k + 1
                                    ))
                                })?),
                            });
                        }
                        if f[0] == "X0" {
                            h.x0 = v;
                        } else {
                            h.delta_x = v;
                        }
                    }
                    _ => {}
                }
                i += 1;
            }
            i += 1;
            let names = lines.get(i).copied().unwrap_or("");
            if !names.starts_with("X_Value") {
                return Err(bad_input(format!(
                    "{file}: line {}: expected the column names (`X_Value ...`) after the \
                     segment header",
                    i + 1
                )));
            }
            if h.channels == 0 {
                return Err(bad_input(format!(
                    "{file}: the segment header before line {} states no `Channels`",
                    i + 1
                )));
            }
            let f: Vec<&str> = names.split(sep).collect();
            if column(xcols, h.channels - 1) >= f.len() {
                return Err(bad_input(format!(
                    "{file}: line {}: the header states {} channels, the column names hold \
                     fewer",
                    i + 1,
                    h.channels
                )));
            }
            h.names = (0..h.channels)
                .map(|k| {
                    f.get(column(xcols, k))
                        .map(|s| s.trim().to_string())
                        .filter(|s| !s.is_empty())
                        .unwrap_or_else(|| format!("channel {}", k + 1))
                })
                .collect();
            header = Some(h);
            i += 1;
        }
        let Some(h) = &header else {
            return Err(bad_input(format!(
                "{file}: line {}: data before any segment header",
                i + 1
            )));
        };
        // the data rows, up to a blank line
        let mut values: Vec<Vec<f64>> = vec![Vec::new(); h.channels];
        let mut xs: Vec<Vec<f64>> = vec![Vec::new(); h.channels];
        let mut ended = vec![false; h.channels];
        while i < lines.len() && !lines[i].split(sep).all(|f| f.trim().is_empty()) {
            let f: Vec<&str> = lines[i].split(sep).collect();
            let first = f[0].trim();
            if !(first.is_empty() || number(first).is_some()) {
                // the next segment's header follows without a blank line
                break;
            }
            for k in 0..h.channels {
                let cell = f.get(column(xcols, k)).map_or("", |s| s.trim());
                if cell.is_empty() {
                    ended[k] = true;
                    continue;
                }
                let v = number(cell).ok_or_else(|| {
                    bad_input(format!(
                        "{file}: line {}, channel `{}`: `{cell}` is not a number (decimal \
                         separator `{decimal}`)",
                        i + 1,
                        h.names[k]
                    ))
                })?;
                if ended[k] {
                    return Err(bad_input(format!(
                        "{file}: line {}, channel `{}`: a sample after an empty field (a gap \
                         would shift every later sample in time)",
                        i + 1,
                        h.names[k]
                    )));
                }
                values[k].push(v);
                let xcol = match xcols {
                    XColumns::No => None,
                    XColumns::One => Some(0),
                    XColumns::Multi => Some(2 * k),
                };
                if let Some(c) = xcol {
                    let t = f.get(c).map_or("", |s| s.trim());
                    xs[k].push(number(t).ok_or_else(|| {
                        bad_input(format!(
                            "{file}: line {}, the time of channel `{}`: `{t}` is not a number",
                            i + 1,
                            h.names[k]
                        ))
                    })?);
                }
            }
            i += 1;
        }
        for (k, got) in values.iter().enumerate() {
            if let Some(n) = h.samples.get(k).copied().flatten() {
                if got.len() < n {
                    // a file cut at a line's end (`head -n`), or shortened by hand (lvm_read's
                    // own test files are): named, not refused
                    notes.push(format!(
                        "warning: {file}: segment {}, channel `{}`: {} samples where its header \
                         states {n} (`Samples`): the file may have been cut short",
                        segments.len() + 1,
                        h.names[k],
                        got.len()
                    ));
                }
            }
        }
        segments.push(
            (0..h.channels)
                .map(|k| Channel {
                    name: h.names[k].clone(),
                    unit: h.units.get(k).cloned().flatten(),
                    delta_x: h.delta_x.get(k).copied().flatten(),
                    x0: h.x0.get(k).copied().flatten(),
                    values: std::mem::take(&mut values[k]),
                    x: (xcols != XColumns::No).then(|| std::mem::take(&mut xs[k])),
                    start_time: None,
                })
                .collect(),
        );
    }
    if segments.is_empty() {
        return Err(bad_input(format!("{file}: no data segment")));
    }
    Ok(Record { segments, notes })
}

/// The data column of channel `k`.
fn column(x: XColumns, k: usize) -> usize {
    match x {
        XColumns::No | XColumns::One => 1 + k,
        XColumns::Multi => 1 + 2 * k,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SHORT: &str = "LabVIEW Measurement\t\nWriter_Version\t2\nSeparator\tTab\n\
Decimal_Separator\t,\nMulti_Headings\tYes\nX_Columns\tNo\n***End_of_Header***\t\n\t\n\
Channels\t2\t\t\nSamples\t3\t3\t\nY_Unit_Label\tNewtons\tm/s^2\t\nX0\t0,0E+0\t0,0E+0\t\n\
Delta_X\t3,906250E-5\t3,906250E-5\t\n***End_of_Header***\t\t\t\n\
X_Value\tF\ta\tComment\n\t0,914018\t1,204792\n\t0,537321\t1,208403\n\t0,616905\t1,213915\n";

    #[test]
    fn a_comma_decimal_file_without_time_columns_is_read() {
        let r = parse(SHORT, "short.lvm").unwrap();
        assert_eq!(r.segments.len(), 1);
        let f = r.channel("F", "short.lvm").unwrap();
        assert_eq!(f.values, vec![0.914018, 0.537321, 0.616905]);
        assert_eq!(f.unit.as_deref(), Some("Newtons"));
        assert_eq!(f.delta_x, Some(3.90625e-5));
        assert_eq!(f.rate_hz(), Some(25_600.0));
        assert!(f.x.is_none());
        assert_eq!(r.channel("a", "s").unwrap().values[2], 1.213915);
    }

    #[test]
    fn a_file_cut_short_is_refused_or_named_and_bom_and_comma_files_are_read() {
        // `head -c`: the last value cut inside its digits
        let cut = &SHORT[..SHORT.len() - 4];
        let e = parse(cut, "cut.lvm").unwrap_err().to_string();
        assert!(e.contains("cut.lvm: ends inside a line"), "{e}");
        // `head -n`: whole lines, fewer than `Samples` states: read, named
        let lines: Vec<&str> = SHORT.lines().collect();
        let short = lines[..lines.len() - 1].join("\n") + "\n";
        let r = parse(&short, "short.lvm").unwrap();
        assert_eq!(r.channel("F", "short.lvm").unwrap().values.len(), 2);
        assert!(
            r.notes
                .iter()
                .any(|n| n.contains("2 samples where its header states 3")),
            "{:?}",
            r.notes
        );
        assert!(parse(SHORT, "short.lvm").unwrap().notes.is_empty());
        // a byte-order mark, and a comma-separated file (its header too)
        let bom = format!("\u{feff}{SHORT}");
        assert_eq!(parse(&bom, "bom.lvm").unwrap(), parse(SHORT, "s").unwrap());
        let comma = SHORT
            .replace("Separator\tTab", "Separator\tComma")
            .replace("Decimal_Separator\t,", "Decimal_Separator\t.")
            .replace(',', ".")
            .replace('\t', ",");
        let r = parse(&comma, "comma.lvm").unwrap();
        let f = r.channel("F", "comma.lvm").unwrap();
        assert_eq!(f.values, vec![0.914018, 0.537321, 0.616905]);
        assert_eq!(f.unit.as_deref(), Some("Newtons"));
        assert_eq!(f.delta_x, Some(3.90625e-5));
    }

    #[test]
    fn bad_fields_and_gaps_are_errors_naming_the_line_and_channel() {
        let bad = SHORT.replace("0,537321", "0,53x");
        let e = format!("{:#}", parse(&bad, "s.lvm").unwrap_err());
        assert!(e.contains("s.lvm: line 17, channel `F`: `0,53x`"), "{e}");
        let gap = SHORT.replace("\t0,537321\t", "\t\t");
        let e = format!("{:#}", parse(&gap, "s.lvm").unwrap_err());
        assert!(
            e.contains("line 18, channel `F`: a sample after an empty field"),
            "{e}"
        );
        let e = format!("{:#}", parse("hello\n", "x.lvm").unwrap_err());
        assert!(e.contains("x.lvm: not a LabVIEW measurement file"), "{e}");
        let e = format!(
            "{:#}",
            parse(SHORT, "s.lvm")
                .unwrap()
                .channel("G", "s.lvm")
                .unwrap_err()
        );
        assert!(e.contains("no channel `G` (its channels: F, a)"), "{e}");
    }

    #[test]
    fn two_segments_join_into_one_channel() {
        let two = format!(
            "{SHORT}\n{}",
            SHORT
                .split("***End_of_Header***\t\n")
                .nth(1)
                .unwrap()
                .trim_start_matches("\t\n")
        );
        let r = parse(&two, "two.lvm").unwrap();
        assert_eq!(r.segments.len(), 2);
        assert_eq!(r.channel("F", "two.lvm").unwrap().values.len(), 6);
    }
}
