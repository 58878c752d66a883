//! The files of a synthetic field record (`simulate-field`, with or without `--render`):
//! `displacement.csv` (a wide file `modal` reads), `truth.csv` (the true modes) and the
//! rendered recording's `points.csv` (a window per target, as `track --points` reads it).

use std::fmt::Write as _;

/// `displacement.csv` of records `rec` (one per point) sampled at `fs_hz`: `t_s,1,...,K`.
pub fn displacement_csv(rec: &[Vec<f64>], fs_hz: f64) -> String {
    let n = rec.first().map_or(0, Vec::len);
    let mut d = String::from("t_s");
    for t in 1..=rec.len() {
        let _ = write!(d, ",{t}");
    }
    d.push('\n');
    for i in 0..n {
        let _ = write!(d, "{}", i as f64 / fs_hz);
        for r in rec {
            let _ = write!(d, ",{}", r[i]);
        }
        d.push('\n');
    }
    d
}

/// One true mode: frequency, damping ratio and its shape at every point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrueMode<'a> {
    /// Natural frequency, Hz.
    pub f_hz: f64,
    /// Damping ratio.
    pub damping: f64,
    /// The shape, one value per point.
    pub shape: &'a [f64],
}

/// `truth.csv`: `mode,f_hz,damping,target,shape`, one row per mode and point.
pub fn truth_csv(modes: &[TrueMode<'_>]) -> String {
    let mut t = String::from("mode,f_hz,damping,target,shape\n");
    for (m, mode) in modes.iter().enumerate() {
        for (j, v) in mode.shape.iter().enumerate() {
            let _ = writeln!(t, "{},{},{},{},{v}", m + 1, mode.f_hz, mode.damping, j + 1);
        }
    }
    t
}

/// `points.csv`: `target,x,y,w,h`, each target's centre in the first frame (px) and one window
/// size for all.
pub fn points_csv(centres: &[(f64, f64)], (w, h): (usize, usize)) -> String {
    let mut points = String::from("target,x,y,w,h\n");
    for (t, (x, y)) in centres.iter().enumerate() {
        let _ = writeln!(points, "{},{x},{y},{w},{h}", t + 1);
    }
    points
}
