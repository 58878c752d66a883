//! The pole fit by variable projection: the scaled problem, its linear solve per pole and the
//! nonlinear search over the pole.

use super::linalg::Qr;
use super::*;

/// The fit's data in scaled units: `s = i w / wc`.
pub(super) struct Problem {
    pub(super) band: (f64, f64),
    pub(super) form: FrfForm,
    /// Scale, rad/s (2 pi times the band centre).
    pub(super) wc: f64,
    /// Scaled `i w` per in-band bin.
    pub(super) s: Vec<Complex64>,
    /// Per FRF, the in-band values stacked as [Re..., Im...].
    pub(super) y: Vec<Vec<f64>>,
    /// Bin spacing in scaled units (mean over the band).
    pub(super) dw: f64,
    /// In-band bin of largest summed |H|^2.
    pub(super) peak: usize,
    /// The Welch kernel the model is smoothed with, in scaled units: `(offset, weight)`
    /// (`None`: the model as it is).
    pub(super) smooth: Option<Vec<(f64, f64)>>,
}

/// The linear solve for one pole: coefficients per FRF and the stacked residual.
pub(super) struct Eval {
    pub(super) coef: Vec<[f64; LINEAR]>,
    pub(super) residual: Vec<f64>,
    pub(super) cost: f64,
}

impl Problem {
    pub(super) fn new(
        freq_hz: &[f64],
        frfs: &[&[Complex64]],
        band: (f64, f64),
        form: FrfForm,
        smoothing: Option<&Smoothing>,
    ) -> Result<Problem, ModalError> {
        let (lo, hi) = band;
        let idx = band_lines(freq_hz, frfs, band)?;
        let wc = PI * (lo + hi);
        let s: Vec<Complex64> = idx
            .iter()
            .map(|&k| Complex64::new(0.0, 2.0 * PI * freq_hz[k] / wc))
            .collect();
        let n = idx.len();
        let y: Vec<Vec<f64>> = frfs
            .iter()
            .map(|h| {
                let mut v = Vec::with_capacity(2 * n);
                v.extend(idx.iter().map(|&k| h[k].re));
                v.extend(idx.iter().map(|&k| h[k].im));
                v
            })
            .collect();
        let power = |m: usize| -> f64 { frfs.iter().map(|h| h[idx[m]].norm_sqr()).sum() };
        let peak = (0..n)
            .max_by(|&a, &b| power(a).total_cmp(&power(b)))
            .unwrap_or(0);
        let dw = (s[n - 1].im - s[0].im) / (n - 1) as f64;
        let smooth = smoothing.map(|k| {
            k.offsets_hz
                .iter()
                .zip(&k.weights)
                .map(|(o, w)| (2.0 * PI * o / wc, *w))
                .collect()
        });
        Ok(Problem {
            band,
            form,
            wc,
            s,
            y,
            dw,
            peak,
            smooth,
        })
    }

    pub(super) fn singular(&self) -> ModalError {
        ModalError::Singular {
            lo: self.band.0,
            hi: self.band.1,
        }
    }

    /// Design matrix (column-major, 2n x 6) for the scaled pole `theta = [Re p, Im p]`.
    pub(super) fn design(&self, theta: [f64; 2]) -> Vec<f64> {
        let n = self.s.len();
        let m = 2 * n;
        let p = Complex64::new(theta[0], theta[1]);
        let (ea, eb) = self.form.residual_exponents();
        let i = Complex64::i();
        let mut a = vec![0.0; m * LINEAR];
        let terms = |s: Complex64| {
            let u = 1.0 / (s - p);
            let v = 1.0 / (s - p.conj());
            [u, v, s.powi(ea), s.powi(eb)]
        };
        for (k, &s) in self.s.iter().enumerate() {
            let [u, v, sa, sb] = match &self.smooth {
                None => terms(s),
                // (K * f)(w) = sum_q K_q f(w - o_q)
                Some(kernel) => kernel
                    .iter()
                    .fold([Complex64::default(); 4], |mut acc, (o, w)| {
                        let t = terms(s - Complex64::new(0.0, *o));
                        for (a, b) in acc.iter_mut().zip(t) {
                            *a += b * w;
                        }
                        acc
                    }),
            };
            let cols = [u + v, i * (u - v), sa, i * sa, sb, i * sb];
            for (c, val) in cols.iter().enumerate() {
                a[c * m + k] = val.re;
                a[c * m + n + k] = val.im;
            }
        }
        a
    }

    /// Solves the linear part for every FRF at the scaled pole `theta`; `None` if singular or
    /// the pole is not a damped oscillation.
    pub(super) fn solve(&self, theta: [f64; 2]) -> Option<Eval> {
        if !(theta[0] < 0.0 && theta[1] > 0.0 && theta[0].is_finite() && theta[1].is_finite()) {
            return None;
        }
        let m = 2 * self.s.len();
        let a = self.design(theta);
        let qr = Qr::new(a.clone(), m, LINEAR)?;
        let mut coef = Vec::with_capacity(self.y.len());
        let mut residual = Vec::with_capacity(m * self.y.len());
        let mut cost = 0.0;
        for y in &self.y {
            let x = qr.solve(y);
            for (r, yr) in y.iter().enumerate() {
                let fit: f64 = (0..LINEAR).map(|c| a[c * m + r] * x[c]).sum();
                let e = yr - fit;
                cost += e * e;
                residual.push(e);
            }
            coef.push(x);
        }
        Some(Eval {
            coef,
            residual,
            cost,
        })
    }

    pub(super) fn cost(&self, theta: [f64; 2]) -> f64 {
        self.solve(theta).map_or(f64::INFINITY, |e| e.cost)
    }

    /// Grid start, then Levenberg-Marquardt on the projected residual. Returns the scaled pole
    /// and the iteration count.
    pub(super) fn fit_pole(&self) -> ([f64; 2], usize) {
        let (theta, cost) = self.grid_start();
        self.refine(theta, cost)
    }

    /// Levenberg-Marquardt from the scaled pole `theta` of cost `cost`.
    pub(super) fn refine(&self, mut theta: [f64; 2], mut cost: f64) -> ([f64; 2], usize) {
        let Some(mut eval) = self.solve(theta) else {
            return (theta, 0);
        };
        let mut lambda = 1e-3;
        let mut iterations = 0;
        for it in 1..=200 {
            iterations = it;
            // Central-difference Jacobian of the projected residual; the residual varies on the
            // scale of |Re p| (the half-power half-width), so steps are a small fraction of it.
            let step = 1e-4 * theta[0].abs();
            let Some(jac) = self.jacobian(theta, step, eval.residual.len()) else {
                break;
            };
            let dot = |a: &[f64], b: &[f64]| -> f64 { a.iter().zip(b).map(|(x, y)| x * y).sum() };
            let jtj = [
                [dot(&jac[0], &jac[0]), dot(&jac[0], &jac[1])],
                [dot(&jac[1], &jac[0]), dot(&jac[1], &jac[1])],
            ];
            let g = [dot(&jac[0], &eval.residual), dot(&jac[1], &eval.residual)];
            let mut accepted = false;
            let mut delta = [0.0; 2];
            while lambda < 1e12 {
                let a00 = jtj[0][0] * (1.0 + lambda);
                let a11 = jtj[1][1] * (1.0 + lambda);
                let a01 = jtj[0][1];
                let det = a00 * a11 - a01 * a01;
                if det <= 0.0 || !det.is_finite() {
                    lambda *= 4.0;
                    continue;
                }
                // r(theta + delta) ~ r + J delta: minimise, (J^T J + lambda diag) delta = -J^T r.
                delta = [
                    -(a11 * g[0] - a01 * g[1]) / det,
                    -(a00 * g[1] - a01 * g[0]) / det,
                ];
                let cand = [theta[0] + delta[0], theta[1] + delta[1]];
                match self.solve(cand) {
                    Some(e) if e.cost < cost => {
                        theta = cand;
                        cost = e.cost;
                        eval = e;
                        lambda = (lambda / 3.0).max(1e-12);
                        accepted = true;
                        break;
                    }
                    _ => lambda *= 4.0,
                }
            }
            let small =
                delta[0].abs() <= 1e-10 * theta[0].abs() && delta[1].abs() <= 1e-13 * theta[1];
            if !accepted || small {
                break;
            }
        }
        (theta, iterations)
    }

    /// The grid start of the pole fit: the best of 33 frequencies around the peak (steps of an
    /// eighth of a bin) times 30 damping ratios (1e-4 to 0.3, log-spaced). Returns the scaled
    /// pole and its cost.
    fn grid_start(&self) -> ([f64; 2], f64) {
        let w_peak = self.s[self.peak].im;
        let mut best = ([-0.01 * w_peak, w_peak], f64::INFINITY);
        const ZETAS: usize = 30;
        for t in -16..=16 {
            let wr = w_peak + t as f64 * self.dw / 8.0;
            if wr <= 0.0 {
                continue;
            }
            for z in 0..ZETAS {
                let zeta =
                    10f64.powf(-4.0 + z as f64 * (0.3f64.log10() + 4.0) / (ZETAS - 1) as f64);
                let theta = [-zeta * wr, wr * (1.0 - zeta * zeta).sqrt()];
                let c = self.cost(theta);
                if c < best.1 {
                    best = (theta, c);
                }
            }
        }
        best
    }

    /// Central-difference Jacobian (two columns of `n` rows) of the projected residual at
    /// `theta`, with step `step`; `None` when a displaced pole's linear solve fails.
    fn jacobian(&self, theta: [f64; 2], step: f64, n: usize) -> Option<[Vec<f64>; 2]> {
        let mut jac = [vec![0.0; n], vec![0.0; n]];
        for (d, col) in jac.iter_mut().enumerate() {
            let mut tp = theta;
            let mut tm = theta;
            tp[d] += step;
            tm[d] -= step;
            let ep = self.solve(tp)?;
            let em = self.solve(tm)?;
            for (c, (a, b)) in col.iter_mut().zip(ep.residual.iter().zip(&em.residual)) {
                *c = (a - b) / (2.0 * step);
            }
        }
        Some(jac)
    }

    pub(super) fn check_pole(&self, theta: [f64; 2]) -> Result<Pole, ModalError> {
        let pole = Pole::from_s(Complex64::new(theta[0], theta[1]) * self.wc);
        let (lo, hi) = self.band;
        if !(pole.f_hz >= lo && pole.f_hz <= hi) {
            return Err(ModalError::PoleOutsideBand {
                lo,
                hi,
                f_hz: pole.f_hz,
                damping: pole.damping,
            });
        }
        Ok(pole)
    }

    /// FRF `j`'s coefficients in physical units (`w` in rad/s).
    pub(super) fn unscale(&self, eval: &Eval, j: usize) -> ResidueFit {
        let x = eval.coef[j];
        let (ea, eb) = self.form.residual_exponents();
        let m = self.y[j].len();
        let res: f64 = eval.residual[j * m..(j + 1) * m]
            .iter()
            .map(|e| e * e)
            .sum();
        let norm: f64 = self.y[j].iter().map(|v| v * v).sum();
        ResidueFit {
            // r~ / (s~ - p~) = (r~ wc) / (iw - p)
            residue: Complex64::new(x[0], x[1]) * self.wc,
            // R~ s~^a = R~ wc^-a (iw)^a
            lower_residual: Complex64::new(x[2], x[3]) * self.wc.powi(-ea),
            upper_residual: Complex64::new(x[4], x[5]) * self.wc.powi(-eb),
            misfit: if norm > 0.0 { (res / norm).sqrt() } else { 0.0 },
        }
    }
}

/// The lines of `band` (above 0 Hz) every FRF is fitted on, checked: the band valid, the FRFs
/// as long as the frequencies, enough lines, every value finite and the frequencies increasing.
fn band_lines(
    freq_hz: &[f64],
    frfs: &[&[Complex64]],
    (lo, hi): (f64, f64),
) -> Result<Vec<usize>, ModalError> {
    if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi) {
        return Err(ModalError::InvalidBand { lo, hi });
    }
    if frfs.is_empty() {
        return Err(ModalError::NoFrf { lo, hi });
    }
    for (j, h) in frfs.iter().enumerate() {
        if h.len() != freq_hz.len() {
            return Err(ModalError::LengthMismatch {
                frf: j,
                len: h.len(),
                freqs: freq_hz.len(),
            });
        }
    }
    let idx: Vec<usize> = (0..freq_hz.len())
        .filter(|&k| freq_hz[k] >= lo && freq_hz[k] <= hi && freq_hz[k] > 0.0)
        .collect();
    if idx.len() < MIN_BINS {
        return Err(ModalError::TooFewBins {
            lo,
            hi,
            bins: idx.len(),
            needed: MIN_BINS,
        });
    }
    for (j, h) in frfs.iter().enumerate() {
        for (n, &k) in idx.iter().enumerate() {
            let increasing = n == 0 || freq_hz[k] > freq_hz[idx[n - 1]];
            if !(h[k].re.is_finite() && h[k].im.is_finite() && increasing) {
                return Err(ModalError::NotFinite {
                    lo,
                    hi,
                    frf: j,
                    f_hz: freq_hz[k],
                });
            }
        }
    }
    Ok(idx)
}
