//! Residues of known poles in a set of FRFs by the least-squares frequency-domain method (LSFD),
//! with lower and upper residual terms for the modes outside the band (docs/method.md §3.13).
//!
//! Per FRF, over the band's lines, linear least squares in the real and imaginary parts of
//!
//! ```text
//! H(w) = sum_r [ A_r / (iw - p_r) + conj(A_r) / (iw - conj(p_r)) ] + L (iw)^a + U (iw)^b
//! ```
//!
//! with complex residues `A_r` and complex residuals `L`, `U` whose exponents follow the FRF's
//! form ([`FrfForm::residual_exponents`]: receptance `-2, 0`). All FRFs share one design matrix:
//! one SVD (columns scaled to unit norm first), every FRF a right-hand side.

use crate::modal::{FrfForm, Pole};
use nalgebra::DMatrix;
use num_complex::Complex64;
use std::f64::consts::PI;

/// What LSFD gives one FRF.
#[derive(Debug, Clone, PartialEq)]
pub struct Constants {
    /// Residue of each pole (that of its conjugate is the conjugate).
    pub residues: Vec<Complex64>,
    /// Lower residual `L`.
    pub lower: Complex64,
    /// Upper residual `U`.
    pub upper: Complex64,
    /// `||model - data|| / ||data||` over the band.
    pub misfit: f64,
}

impl Constants {
    /// The fitted FRF at `f_hz`.
    pub fn evaluate(&self, poles: &[Pole], form: FrfForm, f_hz: f64) -> Complex64 {
        let s = Complex64::new(0.0, 2.0 * PI * f_hz);
        let (a, b) = form.residual_exponents();
        let mut h = self.lower * s.powi(a) + self.upper * s.powi(b);
        for (p, r) in poles.iter().zip(&self.residues) {
            let p = p.s();
            h += r / (s - p) + r.conj() / (s - p.conj());
        }
        h
    }
}

/// The residues of `poles` in each of `frfs` over the lines of `freq_hz` within `band_hz`.
/// Errors when the band has fewer lines than unknowns or the design is singular.
pub fn fit(
    freq_hz: &[f64],
    frfs: &[Vec<Complex64>],
    band_hz: (f64, f64),
    poles: &[Pole],
    form: FrfForm,
) -> anyhow::Result<Vec<Constants>> {
    let lines: Vec<usize> = (0..freq_hz.len())
        .filter(|&k| freq_hz[k] >= band_hz.0 && freq_hz[k] <= band_hz.1 && freq_hz[k] > 0.0)
        .collect();
    let unknowns = 2 * poles.len() + 4;
    if 2 * lines.len() < unknowns + 1 {
        anyhow::bail!(
            "LSFD: {} lines in {}..{} Hz for {} poles and two residuals",
            lines.len(),
            band_hz.0,
            band_hz.1,
            poles.len()
        );
    }
    let (ea, eb) = form.residual_exponents();
    let rows = 2 * lines.len();
    let mut design = DMatrix::<f64>::zeros(rows, unknowns);
    for (i, &k) in lines.iter().enumerate() {
        let s = Complex64::new(0.0, 2.0 * PI * freq_hz[k]);
        let mut cols: Vec<Complex64> = Vec::with_capacity(unknowns);
        for p in poles {
            let p = p.s();
            let (u, v) = (1.0 / (s - p), 1.0 / (s - p.conj()));
            cols.push(u + v); // d/d Re A
            cols.push(Complex64::i() * (u - v)); // d/d Im A
        }
        let (sa, sb) = (s.powi(ea), s.powi(eb));
        cols.extend([sa, Complex64::i() * sa, sb, Complex64::i() * sb]);
        for (j, c) in cols.iter().enumerate() {
            design[(2 * i, j)] = c.re;
            design[(2 * i + 1, j)] = c.im;
        }
    }
    let norms: Vec<f64> = (0..unknowns)
        .map(|j| design.column(j).norm().max(f64::MIN_POSITIVE))
        .collect();
    for (j, n) in norms.iter().enumerate() {
        design.column_mut(j).scale_mut(1.0 / n);
    }
    let mut rhs = DMatrix::<f64>::zeros(rows, frfs.len());
    for (o, h) in frfs.iter().enumerate() {
        for (i, &k) in lines.iter().enumerate() {
            rhs[(2 * i, o)] = h[k].re;
            rhs[(2 * i + 1, o)] = h[k].im;
        }
    }
    let svd = nalgebra::SVD::try_new(
        design.clone(),
        true,
        true,
        f64::EPSILON,
        crate::oma::MAX_ITERATIONS,
    )
    .ok_or_else(|| anyhow::anyhow!("LSFD: the decomposition did not converge"))?;
    let smax = svd.singular_values.max();
    let sol = svd
        .solve(&rhs, smax * 1e-12)
        .map_err(|e| anyhow::anyhow!("LSFD: {e}"))?;
    let fitted = &design * &sol;
    let mut out = Vec::with_capacity(frfs.len());
    for o in 0..frfs.len() {
        let c = |j: usize| sol[(j, o)] / norms[j];
        let residues = (0..poles.len())
            .map(|r| Complex64::new(c(2 * r), c(2 * r + 1)))
            .collect();
        let n = 2 * poles.len();
        let data = rhs.column(o).norm();
        let misfit = (fitted.column(o) - rhs.column(o)).norm() / data.max(f64::MIN_POSITIVE);
        out.push(Constants {
            residues,
            lower: Complex64::new(c(n), c(n + 1)),
            upper: Complex64::new(c(n + 2), c(n + 3)),
            misfit,
        });
    }
    Ok(out)
}

/// Where a fit leaves its residual: over all FRFs and lines of the band.
#[derive(Debug, Clone, PartialEq)]
pub struct Residual {
    /// `||model - data|| / ||data||` over every FRF together.
    pub overall: f64,
    /// The FRF with the largest misfit (0-based) and that misfit.
    pub worst: (usize, f64),
    /// Mean residual power per line near the poles (within 5 half-power bandwidths, at least 3
    /// lines) over the mean elsewhere in the band: near 1 for a noise floor, large when the model
    /// misses at the modes.
    pub near_over_far: f64,
    /// The pole (index) near which the residual is largest.
    pub at_pole: Option<usize>,
    /// The share of the residual's power below the lowest pole's neighbourhood, and that
    /// neighbourhood's lower edge, Hz.
    pub below: (f64, f64),
}

/// Where the fit `constants` of `poles` to `frfs` leaves its residual over `band_hz`.
pub fn residual(
    freq_hz: &[f64],
    frfs: &[Vec<Complex64>],
    band_hz: (f64, f64),
    poles: &[Pole],
    form: FrfForm,
    constants: &[Constants],
) -> Residual {
    let df = if freq_hz.len() > 1 {
        freq_hz[1] - freq_hz[0]
    } else {
        1.0
    };
    let near = |f: f64| {
        poles
            .iter()
            .position(|p| (f - p.f_hz).abs() <= (5.0 * p.damping * p.f_hz).max(3.0 * df))
    };
    let (mut res, mut data) = (0.0, 0.0);
    let (mut near_p, mut near_n, mut far_p, mut far_n) = (0.0, 0usize, 0.0, 0usize);
    let mut per_pole = vec![0.0; poles.len()];
    let lowest = poles
        .iter()
        .map(|p| p.f_hz - (5.0 * p.damping * p.f_hz).max(3.0 * df))
        .fold(f64::INFINITY, f64::min);
    let mut below = 0.0;
    for (h, c) in frfs.iter().zip(constants) {
        for (k, &f) in freq_hz.iter().enumerate() {
            if f < band_hz.0 || f > band_hz.1 || f <= 0.0 {
                continue;
            }
            let r = (h[k] - c.evaluate(poles, form, f)).norm_sqr();
            res += r;
            data += h[k].norm_sqr();
            if f < lowest {
                below += r;
            }
            match near(f) {
                Some(p) => {
                    near_p += r;
                    near_n += 1;
                    per_pole[p] += r;
                }
                None => {
                    far_p += r;
                    far_n += 1;
                }
            }
        }
    }
    let worst = constants
        .iter()
        .enumerate()
        .map(|(i, c)| (i, c.misfit))
        .fold((0, 0.0f64), |a, b| if b.1 > a.1 { b } else { a });
    let mean = |p: f64, n: usize| p / n.max(1) as f64;
    Residual {
        overall: (res / data.max(f64::MIN_POSITIVE)).sqrt(),
        worst,
        near_over_far: mean(near_p, near_n) / mean(far_p, far_n).max(f64::MIN_POSITIVE),
        at_pole: (0..poles.len()).max_by(|&a, &b| per_pole[a].total_cmp(&per_pole[b])),
        below: (below / res.max(f64::MIN_POSITIVE), lowest),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn residues_and_residuals_of_an_exact_model_are_recovered() {
        let poles = [
            Pole {
                f_hz: 30.0,
                damping: 0.01,
            },
            Pole {
                f_hz: 80.0,
                damping: 0.03,
            },
        ];
        let truth = Constants {
            residues: vec![Complex64::new(0.2, -3.0), Complex64::new(-0.1, 1.5)],
            lower: Complex64::new(-2000.0, 0.0),
            upper: Complex64::new(1e-4, 2e-5),
            misfit: 0.0,
        };
        let freq: Vec<f64> = (0..=800).map(|k| k as f64 * 0.25).collect();
        let h: Vec<Complex64> = freq
            .iter()
            .map(|&f| truth.evaluate(&poles, FrfForm::Receptance, f))
            .collect();
        let got = fit(&freq, &[h], (20.0, 120.0), &poles, FrfForm::Receptance).unwrap();
        for (a, b) in got[0].residues.iter().zip(&truth.residues) {
            assert!((a - b).norm() < 1e-9 * b.norm(), "{a} vs {b}");
        }
        assert!((got[0].lower - truth.lower).norm() < 1e-6 * truth.lower.norm());
        assert!((got[0].upper - truth.upper).norm() < 1e-6 * truth.upper.norm());
        assert!(got[0].misfit < 1e-10);
    }
}
