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
//! Levenberg-Marquardt on `(ln A, f0, ln zeta, ln c)` (and the tilt below). The inverse
//! transform of a cut bell (the classic EFDD) loses the tails beyond the cut and rings at its
//! edges: on a weak mode whose bell ends at a tenth of its peak the damping came out 44 % low.
//!
//! A velocity's or an acceleration's spectrum is the displacement's times `(2 pi f)^2` or
//! `(2 pi f)^4`; fitted with the displacement's model such a bell's tilt moved the frequency
//! up by 0.2-0.6 % (four to six standard deviations) on records of a damped chain's velocities,
//! so the model takes the record's [`Quantity`]: `K(f)` times `(f / f_peak)^(2 n)`, `n` its
//! order of derivative. Beyond the quantity, the force's own colour (a force held over each
//! sample falls as `sinc^2(f / fs)`; wind, traffic and a sensor's filter tilt it too) tilts
//! each bell: the model is `A K(f) (f / f_peak)^(2 n + t) + c` with the tilt `t` fitted,
//! under a prior that holds it near 0 where the bell says little ([`TILT_WEIGHT`]). On a
//! chain's accelerations under a held force, a tilt fixed at the quantity's left the
//! frequencies of the upper modes 0.1-0.3 % low (intervals holding 10-50 %); with `t` fitted,
//! within 0.07 % (80-95 %).

use std::f64::consts::PI;
use std::sync::Arc;
use vibcam_fft::RealToComplex;

/// The weight of the tilt's prior: a tilt of one power of `f` costs what one line's residual
/// of this size (natural log) does, about one line's scatter in a Welch estimate of ten
/// segments. Free, the tilt trades against the frequency (both move a bell's sides in
/// opposite directions): the frequency's spread grew up to threefold on a chain's displacement
/// records; held at its prior where the bells say little, it stays within 10 % of the fixed
/// model's there and still takes a real tilt.
pub const TILT_WEIGHT: f64 = 0.3;

/// The narrowest half-power band `2 zeta f0`, in lines, of a bell the spectral window does not
/// make: only such a bell tells a tilt or a quantity.
pub const RESOLVED_LINES: f64 = 3.0;

/// Whether a mode at `f_hz` with `damping` has a half-power band of [`RESOLVED_LINES`] lines
/// of `df` or more.
pub fn resolved(f_hz: f64, damping: f64, df: f64) -> bool {
    2.0 * damping * f_hz >= RESOLVED_LINES * df
}

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
    /// The fitted tilt: the exponent of `f` beyond the quantity's own.
    pub tilt: f64,
}

/// What a record measures, as far as a mode's spectrum is concerned: a displacement's, a
/// velocity's or an acceleration's (the displacement's times `(2 pi f)^(2 n)`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Quantity {
    /// Displacement (`n = 0`): what a camera's tracks measure.
    Displacement,
    /// Velocity (`n = 1`): a geophone's, a laser vibrometer's.
    Velocity,
    /// Acceleration (`n = 2`): an accelerometer's.
    Acceleration,
}

impl Quantity {
    /// All three, displacement first.
    pub const ALL: [Quantity; 3] = [
        Quantity::Displacement,
        Quantity::Velocity,
        Quantity::Acceleration,
    ];

    /// The order of derivative of the displacement.
    pub fn order(self) -> i32 {
        match self {
            Quantity::Displacement => 0,
            Quantity::Velocity => 1,
            Quantity::Acceleration => 2,
        }
    }

    /// The word for it.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Displacement => "displacement",
            Quantity::Velocity => "velocity",
            Quantity::Acceleration => "acceleration",
        }
    }
}

/// The single mode's spectrum in a Welch estimate, for any frequency and damping.
struct Kernel<'a> {
    nfft: usize,
    fs_hz: f64,
    lag: &'a [f64],
    /// The quantity's order of derivative and the line it is referred to: the spectrum is
    /// multiplied by `(l / line)^(2 n)`.
    tilt: (i32, usize),
    fft: Arc<dyn RealToComplex<f64>>,
    x: Vec<f64>,
    spectrum: Vec<num_complex::Complex64>,
}

impl<'a> Kernel<'a> {
    fn new(nfft: usize, fs_hz: f64, lag: &'a [f64], tilt: (i32, usize)) -> Self {
        let fft = vibcam_fft::RealPlanner::new().forward(nfft);
        let spectrum = fft.make_output_vec();
        Kernel {
            nfft,
            fs_hz,
            lag,
            tilt,
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
        let (order, line) = self.tilt;
        let reference = line.max(1) as f64;
        self.spectrum.get(first..first + n).map(|s| {
            s.iter()
                .enumerate()
                .map(|(i, c)| c.re.max(0.0) * ((first + i) as f64 / reference).powi(2 * order))
                .collect()
        })
    }
}

/// Fits the bell `y` (values of lines `first ..`; `peak` the line of its peak) of a spectrum
/// of transform length `nfft` at `fs_hz` with the lag window `lag`, a mode of `quantity` (its
/// tilt fitted when `tilt`), from
/// `start` (frequency and damping: a fit of nearly the same bell, as the jackknife's replicates
/// are) or from the peak line and the half-power width. `None` when the fit does not settle on
/// a damped mode inside the bell.
pub fn fit(
    y: &[f64],
    (first, peak): (usize, usize),
    (nfft, fs_hz): (usize, f64),
    (lag, quantity, tilt): (&[f64], Quantity, bool),
    start: Option<(f64, f64)>,
) -> Option<BellFit> {
    let n = y.len();
    let df = fs_hz / nfft as f64;
    let top = y.iter().copied().fold(0.0, f64::max);
    let positive = |v: f64| v > 0.0 && v.is_finite();
    if n < 4 || !positive(top) || !y.iter().all(|v| positive(*v)) {
        return None;
    }
    let mut kernel = Kernel::new(nfft, fs_hz, lag, (quantity.order(), peak));
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
    // p = (ln A, f0, ln zeta, ln c, tilt)
    let clamp = |p: [f64; 5]| {
        [
            p[0],
            p[1].clamp(f_lo, f_hi),
            p[2].clamp(ZETA_MIN.ln(), (0.5f64).ln()),
            p[3].clamp(floor_min, top.ln()),
            p[4].clamp(-8.0, 8.0),
        ]
    };
    let mut residuals = |p: &[f64; 5]| -> Option<Vec<f64>> {
        let k = kernel.values(p[1], p[2].exp(), first, n)?;
        let (a, c) = (p[0].exp(), p[3].exp());
        Some(
            ln_y.iter()
                .zip(&k)
                .enumerate()
                .map(|(i, (ly, kv))| {
                    let t = (p[4] * ((first + i) as f64 / peak.max(1) as f64).ln()).exp();
                    ly - (a * kv * t + c).max(f64::MIN_POSITIVE).ln()
                })
                .collect(),
        )
    };
    let p = clamp([
        (y[peak - first] / k0).ln(),
        f0,
        zeta0.ln(),
        (y.iter().copied().fold(top, f64::min) * 0.05).ln(),
        0.0,
    ]);
    // first with the tilt held at the quantity's, then, on a bell resolved by the lines
    // ([`RESOLVED_LINES`]: the spectral window's bell has no tilt of its own), free from
    // there; the tilt is kept only when it lowers the cost by more than an F test's 4 (two
    // standard deviations of a one-parameter improvement): a bell that says little of it
    // keeps the plain model's frequency (on a short record's bells the tilt went to +-3.3)
    let (p0, r0, c0) = settle(&mut residuals, &clamp, p, (df, false))?;
    let resolved = resolved(p0[1], p0[2].exp(), df);
    let (p, r, c) = match tilt && resolved {
        true => {
            let (p1, r1, c1) = settle(&mut residuals, &clamp, p0, (df, true))?;
            let dof = n.saturating_sub(5).max(1) as f64;
            match c0 - c1 > 4.0 * c1 / dof {
                true => (p1, r1, c1),
                false => (p0, r0, c0),
            }
        }
        false => (p0, r0, c0),
    };
    let (f_hz, damping) = (p[1], p[2].exp());
    // a fit on the bell's edge or at the damping's upper bound is no mode of the bell; at the
    // lower bound the bell is narrower than the fit can tell (a struck fork ringing through
    // the record): its frequency stands, its damping is not determined
    let inside = f_hz > f_lo && f_hz < f_hi && damping < 0.4999;
    (inside && c.is_finite()).then_some(BellFit {
        f_hz,
        damping,
        floor: p[3].exp() / top,
        rms_log: (cost_of(&r, 0.0) / n as f64).sqrt(),
        tilt: p[4],
    })
}

/// The cost of the residuals `r` and the tilt `t`'s prior (a residual of [`TILT_WEIGHT`] per
/// unit of exponent).
fn cost_of(r: &[f64], t: f64) -> f64 {
    r.iter().map(|v| v * v).sum::<f64>() + (TILT_WEIGHT * t).powi(2)
}

/// The normal equations `(J^T J, J^T r)` of the Jacobian `jac` and residuals `r`, the tilt's
/// prior (at the tilt `t`) added, or the tilt's row and column taken out when it is held.
fn normal_equations(
    jac: &[[f64; 5]],
    r: &[f64],
    t: f64,
    free_tilt: bool,
) -> (nalgebra::SMatrix<f64, 5, 5>, nalgebra::SVector<f64, 5>) {
    let mut jtj = nalgebra::SMatrix::<f64, 5, 5>::zeros();
    let mut jtr = nalgebra::SVector::<f64, 5>::zeros();
    for (row, ri) in jac.iter().zip(r) {
        for a in 0..5 {
            jtr[a] += row[a] * ri;
            for b in 0..5 {
                jtj[(a, b)] += row[a] * row[b];
            }
        }
    }
    jtj[(4, 4)] += TILT_WEIGHT * TILT_WEIGHT;
    jtr[4] += TILT_WEIGHT * TILT_WEIGHT * t;
    if !free_tilt {
        // its step is then zero
        for d in 0..5 {
            jtj[(4, d)] = 0.0;
            jtj[(d, 4)] = 0.0;
        }
        jtj[(4, 4)] = 1.0;
        jtr[4] = 0.0;
    }
    (jtj, jtr)
}

/// Levenberg-Marquardt from `p` (with `free_tilt` false the tilt stays as it is; `df` the line
/// spacing, the frequency's scale): the parameters, residuals and cost where it settles.
fn settle(
    residuals: &mut impl FnMut(&[f64; 5]) -> Option<Vec<f64>>,
    clamp: &impl Fn([f64; 5]) -> [f64; 5],
    mut p: [f64; 5],
    (df, free_tilt): (f64, bool),
) -> Option<([f64; 5], Vec<f64>, f64)> {
    let mut r = residuals(&p)?;
    let mut c = cost_of(&r, p[4]);
    let mut lambda = 1e-3;
    let steps = [1e-6, 1e-6 * df, 1e-6, 1e-6, 1e-6];
    let free = if free_tilt { 5 } else { 4 };
    for _ in 0..200 {
        // the Jacobian by forward differences
        let mut jac = vec![[0.0f64; 5]; r.len()];
        for (j, h) in steps.iter().enumerate().take(free) {
            let mut q = p;
            q[j] += h;
            let rq = residuals(&q)?;
            for (row, (a, b)) in jac.iter_mut().zip(rq.iter().zip(&r)) {
                row[j] = (a - b) / h;
            }
        }
        let (jtj, jtr) = normal_equations(&jac, &r, p[4], free_tilt);
        let mut improved = None;
        while lambda < 1e4 {
            let mut m = jtj;
            for d in 0..5 {
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
                p[4] + delta[4],
            ]);
            let rq = residuals(&q)?;
            let cq = cost_of(&rq, q[4]);
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
    Some((p, r, c))
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
        coloured_expectation(f0, zeta, (fs, nperseg), lines, |_| 1.0)
    }

    /// [`welch_expectation`] of the spectrum times `colour(f)` (a velocity's `f^2`, a force's
    /// colour).
    fn coloured_expectation(
        f0: f64,
        zeta: f64,
        (fs, nperseg): (f64, usize),
        lines: &[usize],
        colour: impl Fn(f64) -> f64,
    ) -> Vec<f64> {
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
        let s = |f: f64| colour(f) / ((f0 * f0 - f * f).powi(2) + (2.0 * zeta * f0 * f).powi(2));
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
        let fit = |y: &[f64], first, peak| {
            let at = (nperseg, fs);
            super::fit(
                y,
                (first, peak),
                at,
                (&lag, super::Quantity::Displacement, true),
                None,
            )
            .unwrap()
        };
        let peak = (f0 / df).round() as usize;
        for half_width in [6usize, 16] {
            let lines: Vec<usize> = (peak - half_width..=peak + half_width).collect();
            let y = welch_expectation(f0, zeta, fs, nperseg, &lines);
            let got = fit(&y, lines[0], peak);
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
        let got = fit(&y, lines[0], peak);
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
        let got = fit(&y, lines[0], peak);
        assert!((got.damping / zeta - 1.0).abs() < 0.01, "{}", got.damping);
        assert!(
            (got.floor / (0.05 / 1.05) - 1.0).abs() < 0.05,
            "{}",
            got.floor
        );
    }

    /// A damped mode's velocity bell (9.4 Hz, damping 2.5 %, 0.012 Hz lines, the bell over 10
    /// half-power half-widths either side, as wide as the MAC gives on a chain's records):
    /// fitted as a displacement's, its frequency comes out 5.7 lines high; as a velocity's,
    /// within a hundredth of a line. And a displacement's bell under a force
    /// that falls as `1 / f` (a colour no quantity has) is given its frequency by the fitted
    /// tilt.
    #[test]
    fn a_bell_is_fitted_as_its_quantity_and_its_colour() {
        let (fs, nperseg) = (50.0, 4096usize);
        let df = fs / nperseg as f64;
        let lag = lag_window(Window::Hann, nperseg);
        let (f0, zeta) = (9.4, 0.025);
        let peak = (f0 / df).round() as usize;
        let reach = (10.0 * zeta * f0 / df) as usize;
        let lines: Vec<usize> = (peak - reach..=peak + reach).collect();
        let fit = |y: &[f64], quantity, tilt| {
            let top = (0..y.len()).max_by(|&i, &j| y[i].total_cmp(&y[j])).unwrap();
            super::fit(
                y,
                (lines[0], lines[0] + top),
                (nperseg, fs),
                (&lag, quantity, tilt),
                None,
            )
            .unwrap()
        };
        let velocity = coloured_expectation(f0, zeta, (fs, nperseg), &lines, |f| f * f);
        let as_displacement = fit(&velocity, super::Quantity::Displacement, false);
        assert!(
            as_displacement.f_hz - f0 > 2.0 * df,
            "{}",
            as_displacement.f_hz
        );
        let as_velocity = fit(&velocity, super::Quantity::Velocity, true);
        assert!(
            (as_velocity.f_hz - f0).abs() < 0.01 * df,
            "{}",
            as_velocity.f_hz
        );
        assert!((as_velocity.damping / zeta - 1.0).abs() < 0.01);
        let coloured = coloured_expectation(f0, zeta, (fs, nperseg), &lines, |f| 1.0 / f);
        let held = fit(&coloured, super::Quantity::Displacement, false);
        let tilted = fit(&coloured, super::Quantity::Displacement, true);
        // held: 3 lines low; fitted: 0.05 of a line (the prior holds the tilt at -0.985 on
        // this noiseless bell, and the model tilts after the window's smoothing, the
        // expectation before)
        assert!(held.f_hz - f0 < -df, "{}", held.f_hz);
        assert!((tilted.f_hz - f0).abs() < 0.1 * df, "{}", tilted.f_hz);
        assert!((tilted.tilt + 1.0).abs() < 0.05, "{}", tilted.tilt);
    }
}
