//! Householder QR for the linear least-squares solves of the pole fit.

use super::LINEAR;

/// Householder QR of a tall column-major matrix, for least squares with several right-hand
/// sides.
pub(super) struct Qr {
    pub(super) m: usize,
    pub(super) n: usize,
    /// R in the upper triangle (diagonal in `diag`), Householder vectors below.
    pub(super) a: Vec<f64>,
    pub(super) diag: Vec<f64>,
}

impl Qr {
    pub(super) fn new(mut a: Vec<f64>, m: usize, n: usize) -> Option<Qr> {
        let mut diag = vec![0.0; n];
        for j in 0..n {
            let col_scale: f64 = (0..m).map(|r| a[j * m + r].abs()).fold(0.0, f64::max);
            let norm: f64 = (j..m).map(|r| a[j * m + r].powi(2)).sum::<f64>().sqrt();
            if col_scale == 0.0 || norm.is_nan() || norm <= 1e-13 * col_scale {
                return None;
            }
            let alpha = if a[j * m + j] > 0.0 { -norm } else { norm };
            a[j * m + j] -= alpha;
            let vnorm2: f64 = (j..m).map(|r| a[j * m + r].powi(2)).sum();
            for c in j + 1..n {
                let dot: f64 = (j..m).map(|r| a[j * m + r] * a[c * m + r]).sum();
                let f = 2.0 * dot / vnorm2;
                for r in j..m {
                    a[c * m + r] -= f * a[j * m + r];
                }
            }
            diag[j] = alpha;
        }
        Some(Qr { m, n, a, diag })
    }

    pub(super) fn solve(&self, y: &[f64]) -> [f64; LINEAR] {
        let (m, n) = (self.m, self.n);
        let mut y = y.to_vec();
        for j in 0..n {
            let v = &self.a[j * m + j..(j + 1) * m];
            let vnorm2: f64 = v.iter().map(|e| e * e).sum();
            let dot: f64 = v.iter().zip(&y[j..]).map(|(e, yr)| e * yr).sum();
            let f = 2.0 * dot / vnorm2;
            for (yr, e) in y[j..].iter_mut().zip(v) {
                *yr -= f * e;
            }
        }
        let mut x = [0.0; LINEAR];
        for j in (0..n).rev() {
            let upper: f64 = (j + 1..n).map(|c| self.a[c * m + j] * x[c]).sum();
            x[j] = (y[j] - upper) / self.diag[j];
        }
        x
    }
}
