//! NumPy `.npy` arrays, as pyidi's users save its displacements (`np.save`): the magic
//! `\x93NUMPY`, the format version, the header's length (2 bytes in version 1, 4 in versions 2
//! and 3) and the header, a Python dict literal with `descr` (the type: `<f8`, `>f4`, `<i2`,
//! ...), `fortran_order` and `shape`; then the data.
//!
//! Channels: an array of shape `(points, samples, 2)` is pyidi's displacement (per point, the
//! two image directions in pyidi's `[row, column]` order): channels `point P y` and `point P x`,
//! `P` from 1. `(points, samples)`: `point P`. `(samples,)`: `values`. Floats and integers of
//! either byte order, C or Fortran order; anything else (objects, complex, strings, more
//! dimensions) is refused by name. An `.npy` states no rate: the caller gives it.

use super::{Channel, Record};
use crate::bad_input;
use std::path::Path;

/// Reads the `.npy` file `path`.
pub fn read(path: &Path) -> anyhow::Result<Record> {
    let bytes = std::fs::read(path)
        .map_err(|e| bad_input(format!("{}: cannot read: {e}", path.display())))?;
    parse(&bytes, &path.display().to_string())
}

/// The value of `key` in the header dict (`'key': value`), up to the next top-level comma.
fn entry<'a>(header: &'a str, key: &str) -> Option<&'a str> {
    let at = header.find(&format!("'{key}'"))? + key.len() + 2;
    let rest = header[at..].trim_start().strip_prefix(':')?.trim_start();
    let mut depth = 0;
    for (i, c) in rest.char_indices() {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth -= 1,
            ',' | '}' if depth == 0 => return Some(rest[..i].trim()),
            _ => {}
        }
    }
    Some(rest.trim())
}

/// Parses the bytes of an `.npy` file; `file` names it in errors.
pub fn parse(bytes: &[u8], file: &str) -> anyhow::Result<Record> {
    let bad = |why: &str| bad_input(format!("{file}: {why}"));
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(bad("not a NumPy .npy file (no `\\x93NUMPY` magic)"));
    }
    let (len, start) = match bytes[6] {
        1 => (usize::from(u16::from_le_bytes([bytes[8], bytes[9]])), 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => return Err(bad(&format!("format version {v} (1, 2 or 3 are read)"))),
    };
    let header = bytes
        .get(start..start + len)
        .map(String::from_utf8_lossy)
        .ok_or_else(|| bad("cut short inside its header"))?;
    let descr = entry(&header, "descr")
        .map(|d| d.trim_matches(|c| c == '\'' || c == '"').to_string())
        .ok_or_else(|| bad("header without `descr`"))?;
    let fortran = entry(&header, "fortran_order") == Some("True");
    let shape: Vec<usize> = entry(&header, "shape")
        .ok_or_else(|| bad("header without `shape`"))?
        .trim_matches(|c| c == '(' || c == ')')
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad("a `shape` that is not whole numbers"))?;
    let (big, kind, size) = {
        let b = descr.as_bytes();
        if b.len() < 3 || !descr.is_ascii() {
            return Err(bad(&format!("data type `{descr}`")));
        }
        let size: usize = descr[2..]
            .parse()
            .map_err(|_| bad(&format!("data type `{descr}`")))?;
        (b[0] == b'>', b[1], size)
    };
    if !matches!((kind, size), (b'f', 4 | 8) | (b'i' | b'u', 1 | 2 | 4 | 8)) {
        return Err(bad(&format!(
            "data type `{descr}` (floats of 4 or 8 bytes and integers are read)"
        )));
    }
    if shape.contains(&0) {
        return Err(bad(&format!(
            "a {shape:?} array holds no samples (a dimension of length 0)"
        )));
    }
    let data = &bytes[start + len..];
    let count = shape
        .iter()
        .try_fold(1usize, |a, &d| a.checked_mul(d))
        .filter(|c| c.checked_mul(size).is_some())
        .ok_or_else(|| bad(&format!("a {shape:?} array: its size overflows")))?;
    if data.len() < count * size {
        return Err(bad(&format!(
            "holds {} bytes of data for a {shape:?} array of {size}-byte values ({} needed)",
            data.len(),
            count * size
        )));
    }
    let value = |i: usize| -> f64 {
        let c = &data[i * size..(i + 1) * size];
        let mut a = [0u8; 8];
        if big {
            a[..size].copy_from_slice(c);
            a[..size].reverse();
        } else {
            a[..size].copy_from_slice(c);
        }
        let le8 = u64::from_le_bytes(a);
        match (kind, size) {
            (b'f', 4) => f64::from(f32::from_bits(le8 as u32)),
            (b'f', _) => f64::from_bits(le8),
            (b'u', _) => le8 as f64,
            // sign-extend from `size` bytes
            _ => ((le8 << (64 - 8 * size)) as i64 >> (64 - 8 * size)) as f64,
        }
    };
    // element at a multi-index, in C or Fortran order
    let at = |idx: &[usize]| -> f64 {
        let mut flat = 0;
        if fortran {
            for d in (0..shape.len()).rev() {
                flat = flat * shape[d] + idx[d];
            }
        } else {
            for d in 0..shape.len() {
                flat = flat * shape[d] + idx[d];
            }
        }
        value(flat)
    };
    let channel = |name: String, values: Vec<f64>| Channel {
        name,
        unit: None,
        delta_x: None,
        x0: None,
        values,
        x: None,
        start_time: None,
    };
    let channels = match shape.as_slice() {
        [n] => vec![channel(
            "values".into(),
            (0..*n).map(|i| at(&[i])).collect(),
        )],
        [p, n] => (0..*p)
            .map(|j| {
                channel(
                    format!("point {}", j + 1),
                    (0..*n).map(|i| at(&[j, i])).collect(),
                )
            })
            .collect(),
        [p, n, 2] => (0..*p)
            .flat_map(|j| {
                [("y", 0), ("x", 1)].map(|(axis, k)| {
                    channel(
                        format!("point {} {axis}", j + 1),
                        (0..*n).map(|i| at(&[j, i, k])).collect(),
                    )
                })
            })
            .collect(),
        other => {
            return Err(bad(&format!(
                "an array of shape {other:?}: read are (samples,), (points, samples) and \
                 pyidi's (points, samples, 2)"
            )))
        }
    };
    Ok(Record {
        segments: vec![channels],
        notes: Vec::new(),
    })
}

/// The bytes of an `.npy` file of version 1: the magic, the header dictionary `header` (e.g.
/// `{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }`) padded with spaces and a
/// newline to a multiple of 64 bytes as NumPy pads it, then `data` as given. What this
/// crate's tests and the command line's tests give the reader (a file it did not write).
pub fn encode_v1(header: &str, data: &[u8]) -> Vec<u8> {
    let mut h = header.as_bytes().to_vec();
    while !(10 + h.len() + 1).is_multiple_of(64) {
        h.push(b' ');
    }
    h.push(b'\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend((h.len() as u16).to_le_bytes());
    out.extend(h);
    out.extend(data);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use encode_v1 as npy;

    #[test]
    fn a_non_ascii_type_and_empty_or_huge_empty_arrays_are_refused() {
        let e = parse(
            &npy(
                "{'descr': '<fé', 'fortran_order': False, 'shape': (2,), }",
                &[0; 16],
            ),
            "a.npy",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("data type `<fé`"), "{e}");
        for shape in ["(5, 0, 2)", "(1000000000000, 0, 2)", "(0,)"] {
            let h = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': {shape}, }}");
            let e = parse(&npy(&h, &[]), "e.npy").unwrap_err().to_string();
            assert!(e.contains("holds no samples"), "{shape}: {e}");
        }
    }
}
