//! Poles of a set of FRFs by the least-squares complex frequency-domain method (LSCF; Guillaume,
//! Verboven, Vanlanduit, Van der Auweraer & Peeters, IMAC 2003; with one reference it is the
//! poly-reference method's single-input case), at every model order up to the highest, each
//! pole marked stable or not against the order below (docs/method.md §3.13). One kernel for
//! both families of functions with a common denominator: `ema`'s FRFs (re-exported there as
//! `ema::lscf`) and the output-only half-spectra of [`super::plscf`] (§3.12).
//!
//! # The model
//!
//! Every FRF `H_o` (one per response) is a ratio of polynomials in `z = exp(i w Ts)` with a
//! common denominator: `H_o(w) = B_o(z) / A(z)`, `A(z) = sum_j a_j z^j`, real coefficients,
//! `Ts = 1 / (2 f_hi)` (the band's top at the unit circle's half turn). The linearised error
//! `B_o(z_k) - H_o(w_k) A(z_k)` over the band's lines, least squares in the coefficients, gives
//! per response the blocks `R = Re(X^H X)`, `S_o = Re(X^H Y_o)`, `T_o = Re(Y_o^H Y_o)` (`X`
//! the lines' powers of `z`, `Y_o = -H_o X`); the numerators eliminated, the denominator solves
//! `M a = 0` with `M = sum_o (T_o - S_o^T R^-1 S_o)`, its highest coefficient fixed at 1. The
//! poles are `ln(z_r) / Ts` of `A`'s roots inside the unit circle (a decaying mode), upper half
//! plane; each pole's shape is `B_o(z_r)` over the responses (the residues' common factor
//! `1 / A'(z_r)` left out), with `B_o = -R^-1 S_o a`.
//!
//! Each FRF is divided by its RMS over the band first (the poles do not change; without it a
//! response in other units, or far from the excitation, would weigh nothing), and the shapes
//! multiplied back.
//!
//! # Stability
//!
//! A pole of order `n` is stable when a pole of order `n - 1` lies within 1 % in frequency,
//! 5 % in damping (of [`crate::oma::ssi::DAMPING_FLOOR`] below it) and has a shape with a MAC
//! of at least 0.98 with it: the rules of the SSI-cov diagram of `modal`, so that
//! [`crate::oma::cluster`] groups LSCF's stable poles into modes by the same rules.

use super::ssi::{Pole, Stability};
use nalgebra::DMatrix;
use num_complex::Complex64;
use std::f64::consts::PI;

/// The stability rules and the physical range of a pole.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LscfRule {
    /// Highest model order (the denominator's degree).
    pub max_order: usize,
    /// Stable: frequency within this fraction of the order below's pole.
    pub df_max: f64,
    /// Stable: damping within this fraction (of [`crate::oma::ssi::DAMPING_FLOOR`] below it).
    pub dz_max: f64,
    /// Stable: shapes' MAC at least this.
    pub mac_min: f64,
    /// Physical poles only: damping in `(0, zeta_max)`.
    pub zeta_max: f64,
    /// Added to every pole's real part, 1/s, before its frequency and damping are taken: an
    /// exponential window's decay (`1 / tau`) undone (0: none).
    pub decay_per_s: f64,
}

impl Default for LscfRule {
    /// Orders to 48, stability 1 % / 5 % / MAC 0.98, damping below 0.2, no window's decay.
    fn default() -> Self {
        LscfRule {
            max_order: 48,
            df_max: 0.01,
            dz_max: 0.05,
            mac_min: 0.98,
            zeta_max: 0.2,
            decay_per_s: 0.0,
        }
    }
}

/// The poles of every order from 2 to `rule.max_order` of the FRFs `frfs[o][line]` at the
/// lines `freq_hz`, fitted over the lines within `band_hz`; poles outside the band are left out.
/// Errors when the band holds fewer lines than the highest order needs, or an FRF is zero or
/// not finite there.
pub fn poles(
    freq_hz: &[f64],
    frfs: &[Vec<Complex64>],
    band_hz: (f64, f64),
    rule: LscfRule,
) -> anyhow::Result<Vec<Pole>> {
    let (lo, hi) = band_hz;
    let lines: Vec<usize> = (0..freq_hz.len())
        .filter(|&k| freq_hz[k] >= lo && freq_hz[k] <= hi)
        .collect();
    let n = rule.max_order;
    if n < 2 || lines.len() < n + 2 {
        return Err(vibcam_readers::bad_input(format!(
            "LSCF: {} lines in {lo}..{hi} Hz, an order-{n} model needs at least {} (a wider \
             band, longer blocks or a lower highest order)",
            lines.len(),
            n + 2
        )));
    }
    let ts = 1.0 / (2.0 * hi);
    // powers of z at each line: x[k][j] = z_k^j
    let x: Vec<Vec<Complex64>> = lines
        .iter()
        .map(|&k| {
            let z = Complex64::from_polar(1.0, 2.0 * PI * freq_hz[k] * ts);
            let mut p = Vec::with_capacity(n + 1);
            let mut zj = Complex64::new(1.0, 0.0);
            for _ in 0..=n {
                p.push(zj);
                zj *= z;
            }
            p
        })
        .collect();
    let mut scales = Vec::with_capacity(frfs.len());
    for (o, h) in frfs.iter().enumerate() {
        let rms = (lines.iter().map(|&k| h[k].norm_sqr()).sum::<f64>() / lines.len() as f64).sqrt();
        if !(rms.is_finite() && rms > 0.0) {
            anyhow::bail!("LSCF: FRF {} is zero or not finite in {lo}..{hi} Hz", o + 1);
        }
        scales.push(rms);
    }
    let m1 = n + 1;
    // R, S_o and T_o are Toeplitz: conj(z^i) z^j = z^(j - i) on the unit circle, so each is
    // the real part of a sum over the lines of z^d (times -H, |H|^2) at the lag d = j - i
    let lag = |sums: &[Complex64], i: usize, j: usize| -> Complex64 {
        if j >= i {
            sums[j - i]
        } else {
            // z^-d = conj(z^d): the sum of conj(z^d) w = conj(sum of z^d conj(w))
            sums[m1 + (i - j)]
        }
    };
    // sums[d] for d = 0..=n, then sums[m1 + d] = sum conj(z^d) w for d = 1..=n
    let lag_sums = |w: &dyn Fn(usize) -> Complex64| -> Vec<Complex64> {
        let mut sums = vec![Complex64::new(0.0, 0.0); 2 * m1];
        for (row, p) in x.iter().enumerate() {
            let wk = w(row);
            for d in 0..m1 {
                sums[d] += p[d] * wk;
                if d > 0 {
                    sums[m1 + d] += p[d].conj() * wk;
                }
            }
        }
        sums
    };
    let toeplitz = |sums: &[Complex64], sign: f64| -> DMatrix<f64> {
        DMatrix::from_fn(m1, m1, |i, j| sign * lag(sums, i, j).re)
    };
    let r = toeplitz(&lag_sums(&|_| Complex64::new(1.0, 0.0)), 1.0);
    let mut s_blocks = Vec::with_capacity(frfs.len());
    let mut t_blocks = Vec::with_capacity(frfs.len());
    for (h, scale) in frfs.iter().zip(&scales) {
        let hs: Vec<Complex64> = lines.iter().map(|&k| h[k] / scale).collect();
        s_blocks.push(toeplitz(&lag_sums(&|row| hs[row]), -1.0));
        t_blocks.push(toeplitz(
            &lag_sums(&|row| Complex64::new(hs[row].norm_sqr(), 0.0)),
            1.0,
        ));
    }
    let mut all: Vec<Pole> = Vec::new();
    let mut below: Vec<Pole> = Vec::new();
    for order in 2..=n {
        let m = order + 1;
        let r_inv = r
            .view((0, 0), (m, m))
            .into_owned()
            .try_inverse()
            .ok_or_else(|| {
                anyhow::anyhow!("LSCF: the order-{order} normal equations are singular")
            })?;
        let mut big = DMatrix::<f64>::zeros(m, m);
        for (s, t) in s_blocks.iter().zip(&t_blocks) {
            let s = s.view((0, 0), (m, m));
            big += t.view((0, 0), (m, m)) - s.transpose() * &r_inv * s;
        }
        let lhs = big.view((0, 0), (order, order)).into_owned();
        let rhs = -big.view((0, order), (order, 1)).into_owned();
        let Some(alpha) = lhs.lu().solve(&rhs) else {
            continue;
        };
        let mut a = DMatrix::<f64>::zeros(m, 1);
        for j in 0..order {
            a[(j, 0)] = alpha[(j, 0)];
        }
        a[(order, 0)] = 1.0;
        let numerators: Vec<DMatrix<f64>> = s_blocks
            .iter()
            .map(|s| -(&r_inv * s.view((0, 0), (m, m)) * &a))
            .collect();
        let mut here = Vec::new();
        for z in roots(a.as_slice()) {
            if !(z.norm() < 1.0 && z.im > 0.0) {
                continue;
            }
            let s = z.ln() / ts + rule.decay_per_s;
            let wn = s.norm();
            let (f_hz, damping) = (wn / (2.0 * PI), -s.re / wn);
            if !(damping > 0.0 && damping < rule.zeta_max && f_hz >= lo && f_hz <= hi) {
                continue;
            }
            let shape: Vec<Complex64> = numerators
                .iter()
                .zip(&scales)
                .map(|(b, scale)| {
                    let mut v = Complex64::new(0.0, 0.0);
                    let mut zj = Complex64::new(1.0, 0.0);
                    for j in 0..m {
                        v += zj * b[(j, 0)];
                        zj *= z;
                    }
                    v * scale
                })
                .collect();
            let stability = Stability {
                df_max: rule.df_max,
                dz_max: rule.dz_max,
                mac_min: rule.mac_min,
            };
            here.push(Pole::judged(
                (order, f_hz, damping),
                shape,
                &below,
                stability,
            ));
        }
        all.extend(here.iter().cloned());
        below = here;
    }
    Ok(all)
}

/// The roots of the real polynomial `sum_j c_j z^j` (`c` ascending, the last coefficient
/// non-zero): the eigenvalues of its companion matrix.
fn roots(c: &[f64]) -> Vec<Complex64> {
    let n = c.len().saturating_sub(1);
    if n == 0 || c[n] == 0.0 {
        return Vec::new();
    }
    let mut comp = DMatrix::<f64>::zeros(n, n);
    for i in 1..n {
        comp[(i, i - 1)] = 1.0;
    }
    for i in 0..n {
        comp[(i, n - 1)] = -c[i] / c[n];
    }
    nalgebra::Schur::try_new(comp, f64::EPSILON, crate::oma::MAX_ITERATIONS)
        .map(|s| s.complex_eigenvalues().iter().copied().collect())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::modal::mac;

    /// Receptance of a mass-normalised modal model at `f`: sum over modes of
    /// `phi_o phi_in / (w_r^2 - w^2 + 2 i zeta_r w_r w)`.
    pub(crate) fn receptance(
        modes: &[(f64, f64)],
        phi: &[Vec<f64>],
        o: usize,
        f: f64,
    ) -> Complex64 {
        let w = 2.0 * PI * f;
        modes
            .iter()
            .zip(phi)
            .map(|(&(fr, z), p)| {
                let wr = 2.0 * PI * fr;
                p[o] * p[0] / Complex64::new(wr * wr - w * w, 2.0 * z * wr * w)
            })
            .sum()
    }

    #[test]
    fn roots_of_a_known_polynomial() {
        // (z - 0.5)(z^2 + 1) = z^3 - 0.5 z^2 + z - 0.5
        let mut r = roots(&[-0.5, 1.0, -0.5, 1.0]);
        r.sort_by(|a, b| a.im.total_cmp(&b.im));
        assert!((r[0] - Complex64::new(0.0, -1.0)).norm() < 1e-12);
        assert!((r[1] - Complex64::new(0.5, 0.0)).norm() < 1e-12);
        assert!((r[2] - Complex64::new(0.0, 1.0)).norm() < 1e-12);
    }

    #[test]
    fn the_poles_and_shapes_of_exact_frfs_are_found_at_every_stable_order() {
        let modes = [(21.0, 0.012), (57.5, 0.02), (103.0, 0.008)];
        let phi = vec![
            vec![1.0, 0.8, 0.3, -0.4],
            vec![0.7, -0.5, -0.9, 0.6],
            vec![0.4, -0.9, 0.8, 0.5],
        ];
        let freq: Vec<f64> = (0..=1600).map(|k| k as f64 * 0.125).collect();
        let frfs: Vec<Vec<Complex64>> = (0..4)
            .map(|o| {
                freq.iter()
                    .map(|&f| receptance(&modes, &phi, o, f))
                    .collect()
            })
            .collect();
        let rule = LscfRule {
            max_order: 20,
            ..LscfRule::default()
        };
        let p = poles(&freq, &frfs, (5.0, 150.0), rule).unwrap();
        for (m, &(f, z)) in modes.iter().enumerate() {
            let at: Vec<&Pole> = p
                .iter()
                .filter(|q| q.stable && (q.f_hz - f).abs() < 0.01 * f)
                .collect();
            assert!(at.len() >= 10, "mode at {f} Hz: {} stable poles", at.len());
            let best = at.last().unwrap();
            assert!((best.f_hz - f).abs() < 1e-6 * f, "{} vs {f}", best.f_hz);
            assert!(
                (best.damping - z).abs() < 1e-4 * z,
                "{} vs {z}",
                best.damping
            );
            let want: Vec<Complex64> = phi[m].iter().map(|&v| Complex64::new(v, 0.0)).collect();
            assert!(mac(&best.shape, &want) > 0.999_999, "shape of mode {m}");
        }
    }
}
