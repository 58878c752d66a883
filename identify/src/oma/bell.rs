//! EFDD's bell fitted (docs/method.md §3.12): the first singular value over a mode's bell
//! against the spectrum one damped mode makes in the Welch estimate, so that neither where the
//! bell is cut nor the window's broadening biases the damping.
//!
//! A mode of natural frequency `f0` and damping ratio `zeta` under white excitation has the
//! displacement correlation `r(t) = exp(-zeta w0 |t|) (cos(wd t) + zeta / sqrt(1 - zeta^2)
//! sin(wd |t|))` (`w0 = 2 pi f0`, `wd = w0 sqrt(1 - zeta^2)`); a Welch estimate of segments
//! `w` sees it times the lag window `w_c` ([`super::fdd::lag_window`]), sampled and wrapped
//! on the transform length: `K(f) = DFT[r(t) w_c(t)]`. The bell's values `y_l` are fitted by
//! `A K(f_l) + c` (`c >= 0` the floor under it: noise, other modes' tails) in the least
//! squares of `ln y_l` (each line's estimate scatters by a constant fraction), by
//! Levenberg-Marquardt on `(ln A, f0, ln zeta, ln c)`. The inverse transform of a cut bell
//! (the classic EFDD) loses the tails beyond the cut and rings at its edges: on a weak mode
//! whose bell ends at a tenth of its peak the damping came out 44 % low.

use realfft::{RealFftPlanner, RealToComplex};
use std::f64::consts::PI;
use std::sync::Arc;

/// The least damping ratio the fit takes.
pub const ZETA_MIN: f64 = 1e-5;

/// A fitted bell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BellFit {
    /// Undamped natural frequency, Hz.
    pub f_hz: f64,
    /// Damping ratio (at [`ZETA_MIN`] when the bell is narrower than the fit can tell).
    pub damping: f64,
    /// The floor `c`, relative to the bell's largest value.
    pub floor: f64,
    /// RMS of the residuals of `ln y`.
    pub rms_log: f64,
}

/// The single mode's spectrum in a Welch estimate, for any frequency and damping.
struct Kernel<'a> {
    nfft: usize,
    fs_hz: f64,
    lag: &'a [f64],
    fft: Arc<dyn RealToComplex<f64>>,
    x: Vec<f64>,
    spectrum: Vec<num_complex::Complex64>,
}

impl<'a> Kernel<'a> {
    fn new(nfft: usize, fs_hz: f64, lag: &'a [f64]) -> Self {
        let fft = RealFftPlanner::<f64>::new().plan_fft_forward(nfft);
        let spectrum = fft.make_output_vec();
        Kernel {
            nfft,
            fs_hz,
            lag,
            fft,
            x: vec![0.0; nfft],
            spectrum,
        }
    }

    /// `K(f_l)` for the lines `first .. first + n` of a mode at `f0_hz` with `zeta`.
    fn values(&mut self, f0_hz: f64, zeta: f64, first: usize, n: usize) -> Option<Vec<f64>> {
        let w0 = 2.0 * PI * f0_hz / self.fs_hz;
        let root = (1.0 - zeta * zeta).sqrt();
        let (wd, q) = (w0 * root, zeta / root);
        self.x.iter_mut().for_each(|v| *v = 0.0);
        // exp((-zeta w0 + i wd) t) by repeated multiplication (a sine and a cosine per lag
        // were most of the fit's time), renormalised every 256 lags against the closed form
        let step = num_complex::Complex64::from_polar((-zeta * w0).exp(), wd);
        let mut z = num_complex::Complex64::new(1.0, 0.0);
        for (t, w) in self.lag.iter().enumerate() {
            if t > 0 {
                z = if t % 256 == 0 {
                    num_complex::Complex64::from_polar((-zeta * w0 * t as f64).exp(), wd * t as f64)
                } else {
                    z * step
                };
            }
            if z.norm_sqr() < 1e-28 {
                break;
            }
            let v = (z.re + q * z.im) * w;
            self.x[t % self.nfft] += v;
            if t > 0 {
                self.x[(self.nfft - t % self.nfft) % self.nfft] += v;
            }
        }
        self.fft.process(&mut self.x, &mut self.spectrum).ok()?;
        self.spectrum
            .get(first..first + n)
            .map(|s| s.iter().map(|c| c.re.max(0.0)).collect())
    }
}

/// Fits the bell `y` (values of lines `first ..`; `peak` the line of its peak) of a spectrum
/// of transform length `nfft` at `fs_hz` with the lag window `lag`, from `start` (frequency
/// and damping: a fit of nearly the same bell, as the jackknife's replicates are) or from the
/// peak line and the half-power width. `None` when the fit does not settle on a damped mode
/// inside the bell.
pub fn fit(
    y: &[f64],
    (first, peak): (usize, usize),
    (nfft, fs_hz): (usize, f64),
    lag: &[f64],
    start: Option<(f64, f64)>,
) -> Option<BellFit> {
    let n = y.len();
    let df = fs_hz / nfft as f64;
    let top = y.iter().copied().fold(0.0, f64::max);
    let positive = |v: f64| v > 0.0 && v.is_finite();
    if n < 4 || !positive(top) || !y.iter().all(|v| positive(*v)) {
        return None;
    }
    let mut kernel = Kernel::new(nfft, fs_hz, lag);
    // start: the peak line, the half-power width, the peak's height, a floor far below
    let half = y[peak - first] / 2.0;
    let width = y.iter().filter(|v| **v >= half).count().max(1) as f64;
    let (f0, zeta0) = start.unwrap_or_else(|| {
        let f0 = peak as f64 * df;
        (f0, (width * df / (2.0 * f0)).clamp(1e-4, 0.3))
    });
    let k0 = kernel.values(f0, zeta0, peak, 1)?[0];
    if !positive(k0) {
        return None;
    }
    let ln_y: Vec<f64> = y.iter().map(|v| v.ln()).collect();
    let (f_lo, f_hi) = (first as f64 * df, (first + n - 1) as f64 * df);
    let floor_min = (top * 1e-9).ln();
    // p = (ln A, f0, ln zeta, ln c)
    let clamp = |p: [f64; 4]| {
        [
            p[0],
            p[1].clamp(f_lo, f_hi),
            p[2].clamp(ZETA_MIN.ln(), (0.5f64).ln()),
            p[3].clamp(floor_min, top.ln()),
        ]
    };
    let mut residuals = |p: &[f64; 4]| -> Option<Vec<f64>> {
        let k = kernel.values(p[1], p[2].exp(), first, n)?;
        let (a, c) = (p[0].exp(), p[3].exp());
        Some(
            ln_y.iter()
                .zip(&k)
                .map(|(ly, kv)| ly - (a * kv + c).max(f64::MIN_POSITIVE).ln())
                .collect(),
        )
    };
    let mut p = clamp([
        (y[peak - first] / k0).ln(),
        f0,
        zeta0.ln(),
        (y.iter().copied().fold(top, f64::min) * 0.05).ln(),
    ]);
    let cost = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    let mut r = residuals(&p)?;
    let mut c = cost(&r);
    let mut lambda = 1e-3;
    let steps = [1e-6, 1e-6 * df, 1e-6, 1e-6];
    for _ in 0..200 {
        // the Jacobian by forward differences
        let mut jac = vec![[0.0f64; 4]; n];
        for (j, h) in steps.iter().enumerate() {
            let mut q = p;
            q[j] += h;
            let rq = residuals(&q)?;
            for (row, (a, b)) in jac.iter_mut().zip(rq.iter().zip(&r)) {
                row[j] = (a - b) / h;
            }
        }
        let mut jtj = nalgebra::Matrix4::<f64>::zeros();
        let mut jtr = nalgebra::Vector4::<f64>::zeros();
        for (row, ri) in jac.iter().zip(&r) {
            for a in 0..4 {
                jtr[a] += row[a] * ri;
                for b in 0..4 {
                    jtj[(a, b)] += row[a] * row[b];
                }
            }
        }
        let mut improved = None;
        while lambda < 1e4 {
            let mut m = jtj;
            for d in 0..4 {
                m[(d, d)] += lambda * jtj[(d, d)].max(1e-12);
            }
            let Some(delta) = m.lu().solve(&(-jtr)) else {
                lambda *= 10.0;
                continue;
            };
            let q = clamp([
                p[0] + delta[0],
                p[1] + delta[1],
                p[2] + delta[2],
                p[3] + delta[3],
            ]);
            let rq = residuals(&q)?;
            let cq = cost(&rq);
            if cq < c {
                improved = Some((q, rq, cq));
                lambda = (lambda / 3.0).max(1e-9);
                break;
            }
            lambda *= 4.0;
        }
        let Some((q, rq, cq)) = improved else {
            break;
        };
        // settled when the cost falls by less than 1e-12 of itself (the damping then within
        // about 4e-5 of the minimum: the cost is flat in it there, and finer steps cost tens
        // of iterations each fit)
        let settled = (c - cq) <= 1e-12 * c.max(1e-300);
        (p, r, c) = (q, rq, cq);
        if settled {
            break;
        }
    }
    let (f_hz, damping) = (p[1], p[2].exp());
    // a fit on the bell's edge or at the damping's upper bound is no mode of the bell; at the
    // lower bound the bell is narrower than the fit can tell (a struck fork ringing through
    // the record): its frequency stands, its damping is not determined
    let inside = f_hz > f_lo && f_hz < f_hi && damping < 0.4999;
    (inside && c.is_finite()).then_some(BellFit {
        f_hz,
        damping,
        floor: p[3].exp() / top,
        rms_log: (c / n as f64).sqrt(),
    })
}

#[cfg(test)]
mod tests {
    use crate::oma::fdd::lag_window;
    use firmware_core::spectrum::Window;

    /// The Welch expectation of one mode's displacement spectrum computed the other way
    /// round from the fit's model: the continuous spectrum `1 / ((f0^2 - f^2)^2 + (2 zeta f0
    /// f)^2)` on a grid 64 times finer than the lines, convolved with the Hann segment's
    /// spectral window `|W(f)|^2` (a direct transform of the window), at the lines.
    fn welch_expectation(f0: f64, zeta: f64, fs: f64, nperseg: usize, lines: &[usize]) -> Vec<f64> {
        let fine = 64usize;
        let df = fs / nperseg as f64;
        let w: Vec<f64> = (0..nperseg)
            .map(|i| f64::from(Window::Hann.value(i, nperseg)))
            .collect();
        // |W(nu)|^2 for nu = k df / fine, |k| up to 8 lines (the kernel beyond is negligible
        // against the mode's own tail at these offsets)
        let reach = 8 * fine as i64;
        let kernel: Vec<f64> = (-reach..=reach)
            .map(|k| {
                let nu = k as f64 * df / fine as f64;
                let (mut re, mut im) = (0.0, 0.0);
                for (n, v) in w.iter().enumerate() {
                    let a = 2.0 * std::f64::consts::PI * nu * n as f64 / fs;
                    re += v * a.cos();
                    im -= v * a.sin();
                }
                re * re + im * im
            })
            .collect();
        let s = |f: f64| 1.0 / ((f0 * f0 - f * f).powi(2) + (2.0 * zeta * f0 * f).powi(2));
        lines
            .iter()
            .map(|&l| {
                let f = l as f64 * df;
                kernel
                    .iter()
                    .enumerate()
                    .map(|(i, k)| k * s(f - (i as f64 - reach as f64) * df / fine as f64))
                    .sum::<f64>()
            })
            .collect()
    }

    #[test]
    fn the_fit_gives_the_damping_of_a_bell_cut_anywhere() {
        // a mode whose half-power band is 4 lines wide, its bell cut at 3 half-power
        // bandwidths (a tenth of its peak) or at 8: the inverse transform of the cut bell
        // (the classic EFDD) depends on where it is cut; the fit does not
        let (fs, nperseg) = (60.0, 1024usize);
        let df = fs / nperseg as f64;
        let (f0, zeta) = (6.0, 2.0 * df / 6.0);
        let lag = lag_window(Window::Hann, nperseg);
        let peak = (f0 / df).round() as usize;
        for half_width in [6usize, 16] {
            let lines: Vec<usize> = (peak - half_width..=peak + half_width).collect();
            let y = welch_expectation(f0, zeta, fs, nperseg, &lines);
            let got = super::fit(&y, (lines[0], peak), (nperseg, fs), &lag, None).unwrap();
            assert!(
                (got.damping / zeta - 1.0).abs() < 0.01,
                "+-{half_width} lines: {} against {zeta}",
                got.damping
            );
            assert!(
                (got.f_hz - f0).abs() < 0.01 * df,
                "{} against {f0}",
                got.f_hz
            );
            assert!(got.floor < 1e-3, "floor {}", got.floor);
        }
        // a lightly damped mode, its half-power band a third of a line: the window's kernel
        // is most of the bell
        let zeta = df / 3.0 / (2.0 * f0);
        let lines: Vec<usize> = (peak - 8..=peak + 8).collect();
        let y = welch_expectation(f0, zeta, fs, nperseg, &lines);
        let got = super::fit(&y, (lines[0], peak), (nperseg, fs), &lag, None).unwrap();
        assert!(
            (got.damping / zeta - 1.0).abs() < 0.02,
            "{} against {zeta}",
            got.damping
        );
        // and on a floor a twentieth of the peak's height the floor is found
        let lines: Vec<usize> = (peak - 16..=peak + 16).collect();
        let zeta = 2.0 * df / 6.0;
        let mut y = welch_expectation(f0, zeta, fs, nperseg, &lines);
        let top = y.iter().copied().fold(0.0, f64::max);
        y.iter_mut().for_each(|v| *v += 0.05 * top);
        let got = super::fit(&y, (lines[0], peak), (nperseg, fs), &lag, None).unwrap();
        assert!((got.damping / zeta - 1.0).abs() < 0.01, "{}", got.damping);
        assert!(
            (got.floor / (0.05 / 1.05) - 1.0).abs() < 0.05,
            "{}",
            got.floor
        );
    }
}
