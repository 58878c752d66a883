//! A DAQ record written as CSV: a header row of channel names, one row per sample, optionally a
//! time column. Every other column is a channel ([`crate::csvio`]'s rules: a cell that is
//! empty, not a number or not finite is an error naming the file, row and column). With a time
//! column the sample interval is its mean step, and a step that departs from it by more than
//! 10 %, or a time more than half a sample off the even grid, is an error naming the row (an
//! unevenly sampled record would need resampling first); without one the record states no rate.

use super::{Channel, Record};
use crate::bad_input;
use std::path::Path;

/// Reads the CSV file `path`, `time_col` naming its time column (s) if it has one.
pub fn read(path: &Path, time_col: Option<&str>) -> anyhow::Result<Record> {
    let text = std::fs::read(path)
        .map_err(|e| bad_input(format!("{}: cannot read: {e}", path.display())))?;
    parse(&text, &path.display().to_string(), time_col)
}

/// Parses CSV bytes; `file` names them in errors.
pub fn parse(bytes: &[u8], file: &str, time_col: Option<&str>) -> anyhow::Result<Record> {
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(csv::Trim::All)
        .from_reader(bytes);
    let header: Vec<String> = rdr
        .headers()
        .map_err(|e| bad_input(format!("{file}: cannot read the header row: {e}")))?
        .iter()
        .map(String::from)
        .collect();
    let names: Vec<&str> = header.iter().map(String::as_str).collect();
    let cols = crate::csvio::read_columns_from(bytes, file, &names)?;
    let (t, dt) = match time_col {
        None => (None, None),
        Some(name) => {
            let i = names.iter().position(|n| *n == name).ok_or_else(|| {
                bad_input(format!(
                    "{file}: no time column `{name}` (the header has: {})",
                    names.join(", ")
                ))
            })?;
            let t = cols.values[i].clone();
            if t.len() < 2 {
                return Err(bad_input(format!(
                    "{file}: one row: no sample interval from the time column `{name}`"
                )));
            }
            let dt = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
            if dt.is_nan() || dt <= 0.0 {
                return Err(bad_input(format!(
                    "{file}: the time column `{name}` does not increase"
                )));
            }
            // each step within 10 % of the mean and each time within half a sample of the
            // even grid: times rounded to fewer digits than the rate needs (a step of 66 or 67
            // us at 15 kHz) are still evenly sampled; a skipped, doubled or late sample is not
            for (k, w) in t.windows(2).enumerate() {
                let step = w[1] - w[0];
                let drift = t[k + 1] - (t[0] + (k + 1) as f64 * dt);
                if step.is_nan() || (step - dt).abs() > 0.1 * dt || drift.abs() > 0.5 * dt {
                    return Err(bad_input(format!(
                        "{file}: row {}: time step {step} s in `{name}` where the record's mean \
                         is {dt} s (the time {} s is {drift:+e} s off the even grid, more than \
                         half a sample): not evenly sampled (resample it first)",
                        k + 3,
                        t[k + 1]
                    )));
                }
            }
            (Some((i, t)), Some(dt))
        }
    };
    let channels = names
        .iter()
        .zip(cols.values)
        .enumerate()
        .filter(|(i, _)| t.as_ref().is_none_or(|(ti, _)| ti != i))
        .map(|(_, (n, values))| Channel {
            name: (*n).to_string(),
            unit: None,
            delta_x: dt,
            x0: t.as_ref().map(|(_, t)| t[0]),
            values,
            x: t.as_ref().map(|(_, t)| t.clone()),
            start_time: None,
        })
        .collect();
    Ok(Record {
        segments: vec![channels],
        notes: Vec::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channels_and_the_rate_of_the_time_column() {
        let text = b"t_s,force,acc\n0,1.5,-2\n0.0005,2.5,-3\n0.001,3.5,-4\n";
        let r = parse(text, "d.csv", Some("t_s")).unwrap();
        assert_eq!(r.segments[0].len(), 2);
        let f = r.channel("force", "d.csv").unwrap();
        assert_eq!(f.values, vec![1.5, 2.5, 3.5]);
        assert!((f.rate_hz().unwrap() - 2000.0).abs() < 1e-9);
        let r = parse(text, "d.csv", None).unwrap();
        assert_eq!(r.segments[0].len(), 3);
        assert_eq!(r.channel("acc", "d.csv").unwrap().rate_hz(), None);
    }

    #[test]
    fn uneven_time_bad_cells_and_missing_columns_are_named() {
        let e = format!(
            "{:#}",
            parse(b"t,a\n0,1\n0.001,2\n0.0025,3\n", "u.csv", Some("t")).unwrap_err()
        );
        assert!(e.contains("u.csv: row 3: time step 0.001 s"), "{e}");
        let e = format!(
            "{:#}",
            parse(b"t,a\n0,1\n1,x\n", "b.csv", None).unwrap_err()
        );
        assert!(e.contains("b.csv: row 3, column `a`"), "{e}");
        let e = format!(
            "{:#}",
            parse(b"t,a\n0,1\n1,2\n", "m.csv", Some("time")).unwrap_err()
        );
        assert!(
            e.contains("no time column `time` (the header has: t, a)"),
            "{e}"
        );
    }
}
