//! The files of an experimental modal analysis (`ema`): `frf.csv`, `modes.csv` (the
//! multi-target columns, method `lscf`, then the interval columns), `shapes.csv` (as `modal`'s)
//! and `frf.uff` (datasets 58, function type 4). Typed rows in, bytes out;
//! `analysis::ema::run` builds the rows.

use super::targets::{modes_lines, ModesLine};
use num_complex::Complex64;
use std::fmt::Write as _;

/// `frf.csv`: `freq_hz,target,re,im,abs,coherence`, one row per line and response (`target`
/// the response's number, 1-based, in the report's order).
pub fn frf_csv(freq_hz: &[f64], h: &[Vec<Complex64>], coherence: &[Vec<f64>]) -> Vec<u8> {
    frf_matrix_csv(freq_hz, h, coherence, ("", Vec::new()))
}

/// [`frf_csv`] of an FRF matrix: `h[j * outputs + o]` the FRF of response `o` over input `j`
/// (a roving hammer's hit point `points[j]`, or several forces' number), in a column `column`
/// (`hit_point`, `force`) after `target` (none without points).
pub fn frf_matrix_csv(
    freq_hz: &[f64],
    h: &[Vec<Complex64>],
    coherence: &[Vec<f64>],
    (column, points): (&str, Vec<usize>),
) -> Vec<u8> {
    let outputs = if points.is_empty() {
        h.len().max(1)
    } else {
        (h.len() / points.len()).max(1)
    };
    let mut s = if points.is_empty() {
        String::from("freq_hz,target,re,im,abs,coherence\n")
    } else {
        format!("freq_hz,target,{column},re,im,abs,coherence\n")
    };
    for (k, f) in freq_hz.iter().enumerate() {
        for (i, (hi, co)) in h.iter().zip(coherence).enumerate() {
            let v = hi[k];
            let point = points
                .get(i / outputs)
                .map_or(String::new(), |p| format!("{p},"));
            let _ = writeln!(
                s,
                "{f},{},{point}{:e},{:e},{:e},{}",
                i % outputs + 1,
                v.re,
                v.im,
                v.norm(),
                co[k]
            );
        }
    }
    s.into_bytes()
}

/// One mode of `ema`.
#[derive(Debug, Clone, PartialEq)]
pub struct EmaModeRow {
    /// `vision` (a camera's responses) or `daq`.
    pub system: &'static str,
    /// Mode number, 1-based.
    pub mode: usize,
    /// Its band, Hz (with bands).
    pub band_hz: Option<(f64, f64)>,
    /// Natural frequency, Hz.
    pub f_hz: f64,
    /// Damping ratio.
    pub damping: f64,
    /// `(u, lo, hi)` of the frequency and the damping, where estimated.
    pub intervals: [Option<(f64, f64, f64)>; 2],
}

/// `modes.csv`: the multi-target columns (`target`, `amplitude` and `e2pr` empty), method
/// `lscf`; then the interval columns (amplitude's empty).
pub fn modes_csv(rows: &[EmaModeRow]) -> Vec<u8> {
    modes_lines(rows.iter().map(|m| ModesLine {
        system: m.system,
        target: None,
        mode: m.mode,
        band_hz: m.band_hz,
        f_hz: Some(m.f_hz),
        amplitude: None,
        damping: Some(m.damping),
        e2pr: None,
        method: "lscf",
        intervals: [m.intervals[0], m.intervals[1], None],
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_columns_of_frf_and_modes() {
        let f = frf_csv(
            &[0.0, 1.0],
            &[vec![Complex64::new(1.0, -1.0), Complex64::new(0.0, 2.0)]],
            &[vec![0.5, 1.0]],
        );
        let text = String::from_utf8(f).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "freq_hz,target,re,im,abs,coherence");
        assert_eq!(lines[2], "1,1,0e0,2e0,2e0,1");
        let m = modes_csv(&[EmaModeRow {
            system: "vision",
            mode: 1,
            band_hz: None,
            f_hz: 12.5,
            damping: 0.02,
            intervals: [Some((0.1, 12.3, 12.7)), None],
        }]);
        let text = String::from_utf8(m).unwrap();
        let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
        let row: Vec<&str> = text.lines().nth(1).unwrap().split(',').collect();
        assert_eq!(header.len(), row.len());
        let col = |name: &str| row[header.iter().position(|h| *h == name).unwrap()];
        assert_eq!(col("method"), "lscf");
        assert_eq!(col("f_hz"), "12.5");
        assert_eq!(col("f_hz_lo"), "12.3");
        assert_eq!(col("damping_u"), "");
    }
}
