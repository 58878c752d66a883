//! Reading numeric columns from CSV files, with errors that name the file, row and column.
//!
//! Rows are numbered as a spreadsheet shows them: the header is row 1, the first data row is
//! row 2. A cell that is empty, not a number, NaN or infinite is an error; so is a row with
//! fewer cells than the header.

use crate::bad_input;
use std::path::Path;

/// Named numeric columns read from one CSV file.
#[derive(Debug, Clone, PartialEq)]
pub struct Columns {
    /// Column names, in the order they were asked for.
    pub names: Vec<String>,
    /// One vector per requested column, all of the same length.
    pub values: Vec<Vec<f64>>,
}

/// A CSV file opened for reading, cells trimmed (`flexible`: rows may differ in length), and
/// its header row; errors name the file as `name`.
pub fn open_with_header(
    path: &Path,
    name: &str,
    flexible: bool,
) -> anyhow::Result<(csv::Reader<std::fs::File>, Vec<String>)> {
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .flexible(flexible)
        .from_path(path)
        .map_err(|e| bad_input(format!("{name}: cannot read: {e}")))?;
    let header = rdr
        .headers()
        .map_err(|e| bad_input(format!("{name}: cannot read the header: {e}")))?
        .iter()
        .map(str::to_string)
        .collect();
    Ok((rdr, header))
}

/// Reads the columns `wanted` (by header name) from the CSV file at `path`.
///
/// Errors (all [`crate::BadInput`]): the file cannot be opened, a column is missing from the
/// header (the message lists the header), a cell is missing, empty, non-numeric or not finite
/// (the message names the file, row and column).
pub fn read_columns(path: &Path, wanted: &[&str]) -> anyhow::Result<Columns> {
    let file = std::fs::File::open(path)
        .map_err(|e| bad_input(format!("cannot open {}: {e}", path.display())))?;
    read_columns_from(file, &path.display().to_string(), wanted)
}

/// The names of the header row of CSV `bytes`, as the csv crate reads them (a UTF-8 byte-order
/// mark stripped, quotes removed, spaces trimmed); empty when there is no readable header.
pub fn header_names(bytes: &[u8]) -> Vec<String> {
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(bytes);
    rdr.headers()
        .map(|h| h.iter().map(String::from).collect())
        .unwrap_or_default()
}

/// Same as [`read_columns`] from any reader; `source` names it in error messages.
pub fn read_columns_from(
    reader: impl std::io::Read,
    source: &str,
    wanted: &[&str],
) -> anyhow::Result<Columns> {
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(reader);
    let header = rdr
        .headers()
        .map_err(|e| bad_input(format!("{source}: cannot read the header row: {e}")))?
        .clone();
    let mut index = Vec::with_capacity(wanted.len());
    for w in wanted {
        match header.iter().position(|h| h == *w) {
            Some(i) => index.push(i),
            None => {
                let have: Vec<&str> = header.iter().collect();
                return Err(bad_input(format!(
                    "{source}: no column named `{w}` (the header has: {})",
                    have.join(", ")
                )));
            }
        }
    }
    let mut values = vec![Vec::new(); wanted.len()];
    for (i, rec) in rdr.records().enumerate() {
        let row = i + 2;
        let rec = rec.map_err(|e| bad_input(format!("{source}: row {row}: {e}")))?;
        // a completely empty line at the end of a file is not data
        if rec.len() == 1 && rec.get(0) == Some("") {
            continue;
        }
        for ((col, &ci), out) in wanted.iter().zip(&index).zip(values.iter_mut()) {
            let cell = rec.get(ci).ok_or_else(|| {
                bad_input(format!(
                    "{source}: row {row}, column `{col}`: missing cell (the row has {} cells)",
                    rec.len()
                ))
            })?;
            let v: f64 = cell.parse().map_err(|_| {
                bad_input(format!(
                    "{source}: row {row}, column `{col}`: `{cell}` is not a number"
                ))
            })?;
            if !v.is_finite() {
                return Err(bad_input(format!(
                    "{source}: row {row}, column `{col}`: `{cell}` is not a finite number"
                )));
            }
            out.push(v);
        }
    }
    if values.first().is_none_or(|v| v.is_empty()) {
        return Err(bad_input(format!("{source}: no data rows")));
    }
    Ok(Columns {
        names: wanted.iter().map(|s| s.to_string()).collect(),
        values,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str, cols: &[&str]) -> anyhow::Result<Columns> {
        read_columns_from(text.as_bytes(), "t.csv", cols)
    }

    #[test]
    fn reads_named_columns_in_requested_order() {
        let c = read("a,b,c\n1,2,3\n4,5,6\n", &["c", "a"]).unwrap();
        assert_eq!(c.values, vec![vec![3.0, 6.0], vec![1.0, 4.0]]);
    }

    #[test]
    fn errors_name_row_and_column() {
        let e = read("a,b\n1,2\n3,x\n", &["a", "b"]).unwrap_err();
        let msg = format!("{e:#}");
        assert!(
            msg.contains("t.csv") && msg.contains("row 3") && msg.contains("`b`"),
            "{msg}"
        );
        assert!(e.is::<crate::BadInput>());

        let msg = format!("{:#}", read("a,b\n1,NaN\n", &["a", "b"]).unwrap_err());
        assert!(
            msg.contains("row 2") && msg.contains("not a finite"),
            "{msg}"
        );

        let msg = format!("{:#}", read("a,b\n1,2\n3\n", &["a", "b"]).unwrap_err());
        assert!(
            msg.contains("row 3") && msg.contains("missing cell"),
            "{msg}"
        );

        let msg = format!("{:#}", read("a,b\n1,2\n", &["z"]).unwrap_err());
        assert!(
            msg.contains("no column named `z`") && msg.contains("a, b"),
            "{msg}"
        );

        let msg = format!("{:#}", read("a,b\n", &["a"]).unwrap_err());
        assert!(msg.contains("no data rows"), "{msg}");
    }
}
