//! Test signals and error metrics shared by the unit tests, the integration tests and the
//! benchmarks (which include this file with `#[path]`): one home for each, so a fixture test and
//! a unit test measure the same thing the same way. Compiled only for tests and benchmarks.
#![allow(dead_code)] // each includer uses a part

use std::vec;
use std::vec::Vec;

/// A hard-edged 8-bit disk: `level` where the pixel centre is within `r` of `(cx, cy)`, else
/// `background`; a `w x h` frame, row stride `w`.
pub fn disk(
    w: usize,
    h: usize,
    (cx, cy): (f64, f64),
    r: f64,
    background: u8,
    level: u8,
) -> Vec<u8> {
    let mut f = vec![background; w * h];
    for y in 0..h {
        for x in 0..w {
            let (dx, dy) = (x as f64 - cx, y as f64 - cy);
            if dx * dx + dy * dy <= r * r {
                f[y * w + x] = level;
            }
        }
    }
    f
}

/// The largest `|got - want|` and the RMS of `want`: the relative-error metric of the
/// resampling tests (max error / RMS).
pub fn max_error_and_rms(got: &[f32], want: &[f64]) -> (f64, f64) {
    let rms = (want.iter().map(|v| v * v).sum::<f64>() / want.len() as f64).sqrt();
    let err = got
        .iter()
        .zip(want)
        .map(|(a, b)| (*a as f64 - b).abs())
        .fold(0.0, f64::max);
    (err, rms)
}
