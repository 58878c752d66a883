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
/// not finite there. One reference: the common-denominator model ([`poles_matrix`] with one
/// reference).
pub fn poles(
    freq_hz: &[f64],
    frfs: &[Vec<Complex64>],
    band_hz: (f64, f64),
    rule: LscfRule,
) -> anyhow::Result<Vec<Pole>> {
    poles_matrix(freq_hz, frfs, 1, band_hz, rule)
}

/// With several references, the matrix orders fitted are at least this many (when
/// `rule.max_order` divided by the references is fewer): a mode needs several orders to show
/// stable poles, and the upper modes of a record appear only from order 9 or 10. Measured with
/// four references (docs/method.md §3.12; docs/validation.md §3 and §10): to 14, the damped
/// chain's fifth and sixth modes were found in 28 and 1 of 40 records (four stable poles, fewer
/// than a mode needs); to 20 (pyOMA-2's `ordmax`), in 40 and 34, and pyOMA-2's 5-DOF example
/// gives its five modes either way (to 12, three). The price: on a record of two noisy
/// oscillators a mode's damping rises with the order (0.0181 at orders 3-9, 0.0207 at 19).
pub const MIN_MATRIX_ORDERS: usize = 20;

/// The highest matrix order for `references` references under `rule`: `rule.max_order` divided
/// by the references (the same number of poles), at least [`MIN_MATRIX_ORDERS`] (and never over
/// `rule.max_order`).
pub fn matrix_order(rule: LscfRule, references: usize) -> usize {
    let r = references.max(1);
    if r == 1 {
        return rule.max_order;
    }
    (rule.max_order / r).max(MIN_MATRIX_ORDERS.min(rule.max_order))
}

/// The orders fitted for `references` references under `rule`: from 2 with one (the scalar
/// denominator's least order with a pole pair), from 1 with several, to [`matrix_order`].
pub fn orders(rule: LscfRule, references: usize) -> std::ops::RangeInclusive<usize> {
    let first = if references.max(1) == 1 { 2 } else { 1 };
    first..=matrix_order(rule, references)
}

/// The poly-reference LSCF (PolyMAX; Peeters, Van der Auweraer, Guillaume & Leuridan, Shock and
/// Vibration 11, 2004) of the FRF matrix `frfs[o * references + r][line]` (output `o`'s FRF for
/// reference `r`): the right matrix-fraction model `H(w) = B(z) A(z)^-1`, `A` a polynomial of
/// `references x references` real matrix coefficients, its highest the identity, fitted by
/// least squares over the band's lines at every matrix order up to
/// [`matrix_order`]`(rule, references)` (module documentation for one reference). The poles are
/// the roots of `det A` (the eigenvalues of its block companion matrix) inside the unit circle,
/// upper half plane; a pole's shape is `B(z_r) v` over the outputs, `v` the null vector of
/// `A(z_r)`. With several references two modes at one frequency (a symmetric structure's pair)
/// are two poles with their own shapes, which one common denominator cannot give.
///
/// The references are at most the outputs (else the fraction is not determined: transpose the
/// matrix, by reciprocity). Each FRF is scaled by its reference's RMS and then its output's (a row and a column scale
/// keep the matrix-fraction form), the shapes scaled back.
pub fn poles_matrix(
    freq_hz: &[f64],
    frfs: &[Vec<Complex64>],
    references: usize,
    band_hz: (f64, f64),
    rule: LscfRule,
) -> anyhow::Result<Vec<Pole>> {
    let (lo, hi) = band_hz;
    let rr = references.max(1);
    // more references than outputs leave the fraction undetermined: the caller transposes
    if frfs.is_empty() || !frfs.len().is_multiple_of(rr) || frfs.len() < rr * rr {
        anyhow::bail!(
            "internal: LSCF: {} FRFs do not make at least {rr} rows of {rr} references",
            frfs.len()
        );
    }
    let lines: Vec<usize> = (0..freq_hz.len())
        .filter(|&k| freq_hz[k] >= lo && freq_hz[k] <= hi)
        .collect();
    let n = matrix_order(rule, rr);
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
    let (col, scales) = scales(frfs, &lines, rr, band_hz)?;
    let (r, s_blocks, t_blocks) = normal_blocks(&x, (frfs, &lines), rr, (&col, &scales));
    let stability = Stability {
        df_max: rule.df_max,
        dz_max: rule.dz_max,
        mac_min: rule.mac_min,
    };
    let mut all: Vec<Pole> = Vec::new();
    let mut below: Vec<Pole> = Vec::new();
    for order in orders(rule, rr) {
        let m = order + 1;
        let r_inv = r
            .view((0, 0), (m, m))
            .into_owned()
            .try_inverse()
            .ok_or_else(|| {
                anyhow::anyhow!("LSCF: the order-{order} normal equations are singular")
            })?;
        let (mr, nr) = (m * rr, order * rr);
        let mut big = DMatrix::<f64>::zeros(mr, mr);
        for (s, t) in s_blocks.iter().zip(&t_blocks) {
            let s = s.view((0, 0), (m, mr));
            big += t.view((0, 0), (mr, mr)) - s.transpose() * &r_inv * s;
        }
        let lhs = big.view((0, 0), (nr, nr)).into_owned();
        let rhs = -big.view((0, nr), (nr, rr)).into_owned();
        let Some(alpha) = lhs.lu().solve(&rhs) else {
            continue;
        };
        let mut a = DMatrix::<f64>::zeros(mr, rr);
        a.view_mut((0, 0), (nr, rr)).copy_from(&alpha);
        for c in 0..rr {
            a[(nr + c, c)] = 1.0;
        }
        let numerators: Vec<DMatrix<f64>> = s_blocks
            .iter()
            .map(|s| -(&r_inv * s.view((0, 0), (m, mr)) * &a))
            .collect();
        let mut here = Vec::new();
        for z in matrix_roots(&a, rr) {
            if !(z.norm() < 1.0 && z.im > 0.0) {
                continue;
            }
            let s = z.ln() / ts + rule.decay_per_s;
            let wn = s.norm();
            let (f_hz, damping) = (wn / (2.0 * PI), -s.re / wn);
            if !(damping > 0.0 && damping < rule.zeta_max && f_hz >= lo && f_hz <= hi) {
                continue;
            }
            let Some(v) = null_vector(&a, rr, z) else {
                continue;
            };
            let shape: Vec<Complex64> = numerators
                .iter()
                .zip(&scales)
                .map(|(b, scale)| {
                    let mut sum = Complex64::new(0.0, 0.0);
                    let mut zj = Complex64::new(1.0, 0.0);
                    for j in 0..m {
                        for (c, vc) in v.iter().enumerate() {
                            sum += zj * b[(j, c)] * vc;
                        }
                        zj *= z;
                    }
                    sum * scale
                })
                .collect();
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

/// The column (per reference: 1 with one) and row (per output) scales of the FRF matrix
/// `frfs` over `lines` (module documentation); errors name a reference or FRF that is zero.
fn scales(
    frfs: &[Vec<Complex64>],
    lines: &[usize],
    rr: usize,
    (lo, hi): (f64, f64),
) -> anyhow::Result<(Vec<f64>, Vec<f64>)> {
    let outputs = frfs.len() / rr;
    let rms = |h: &[Complex64], by: f64| {
        (lines.iter().map(|&k| (h[k] / by).norm_sqr()).sum::<f64>() / lines.len() as f64).sqrt()
    };
    // column scales (one reference: none, the row scale is the FRF's own RMS)
    let col: Vec<f64> = (0..rr)
        .map(|r| match rr {
            1 => 1.0,
            _ => {
                let ms = (0..outputs)
                    .map(|o| rms(&frfs[o * rr + r], 1.0).powi(2))
                    .sum::<f64>()
                    / outputs as f64;
                ms.sqrt()
            }
        })
        .collect();
    if let Some(r) = col.iter().position(|c| !(c.is_finite() && *c > 0.0)) {
        anyhow::bail!(
            "LSCF: the FRFs of reference {} are zero or not finite in {lo}..{hi} Hz",
            r + 1
        );
    }
    let mut scales = Vec::with_capacity(outputs);
    for o in 0..outputs {
        let rms = match rr {
            1 => rms(&frfs[o], 1.0),
            _ => {
                let ms = (0..rr)
                    .map(|r| rms(&frfs[o * rr + r], col[r]).powi(2))
                    .sum::<f64>();
                (ms / rr as f64).sqrt()
            }
        };
        if !(rms.is_finite() && rms > 0.0) {
            match rr {
                1 => anyhow::bail!("LSCF: FRF {} is zero or not finite in {lo}..{hi} Hz", o + 1),
                _ => anyhow::bail!(
                    "LSCF: the FRFs of output {} are zero or not finite in {lo}..{hi} Hz",
                    o + 1
                ),
            }
        }
        scales.push(rms);
    }
    Ok((col, scales))
}

/// The reduced problem's blocks of the FRF matrix `frfs` over `lines` (`x` their powers of
/// `z`), scaled by `col` and `rows`: `R`, and per output `S_o` and `T_o` (module documentation).
#[allow(clippy::type_complexity)]
fn normal_blocks(
    x: &[Vec<Complex64>],
    (frfs, lines): (&[Vec<Complex64>], &[usize]),
    rr: usize,
    (col, scales): (&[f64], &[f64]),
) -> (DMatrix<f64>, Vec<DMatrix<f64>>, Vec<DMatrix<f64>>) {
    let outputs = frfs.len() / rr;
    let m1 = x.first().map_or(1, Vec::len);
    // R, S_o and T_o are block Toeplitz: conj(z^i) z^j = z^(j - i) on the unit circle, so each
    // entry is the real part of a sum over the lines of z^d (times -H, conj(H) H) at the lag
    // d = j - i
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
    let ones = lag_sums(&|_| Complex64::new(1.0, 0.0));
    let r = DMatrix::from_fn(m1, m1, |i, j| lag(&ones, i, j).re);
    // the stacked unknowns of A: index j * rr + s for coefficient j, column s of the row
    let mut s_blocks = Vec::with_capacity(outputs);
    let mut t_blocks = Vec::with_capacity(outputs);
    for o in 0..outputs {
        let hs: Vec<Vec<Complex64>> = (0..rr)
            .map(|c| {
                let by = scales[o] * col[c];
                lines.iter().map(|&k| frfs[o * rr + c][k] / by).collect()
            })
            .collect();
        let s_sums: Vec<Vec<Complex64>> = (0..rr).map(|c| lag_sums(&|row| hs[c][row])).collect();
        s_blocks.push(DMatrix::from_fn(m1, m1 * rr, |i, jt| {
            -lag(&s_sums[jt % rr], i, jt / rr).re
        }));
        let t_sums: Vec<Vec<Complex64>> = (0..rr * rr)
            .map(|st| lag_sums(&|row| hs[st / rr][row].conj() * hs[st % rr][row]))
            .collect();
        t_blocks.push(DMatrix::from_fn(m1 * rr, m1 * rr, |is, jt| {
            lag(&t_sums[(is % rr) * rr + jt % rr], is / rr, jt / rr).re
        }));
    }
    (r, s_blocks, t_blocks)
}

/// The roots of `det A(z)`, `A(z) = sum_j z^j A_j` with `a` the coefficients stacked (row
/// `j * refs + s` is row `s` of `A_j`), the last the identity: with one reference the roots of
/// the polynomial, else the eigenvalues of the block companion matrix.
fn matrix_roots(a: &DMatrix<f64>, refs: usize) -> Vec<Complex64> {
    if refs == 1 {
        return roots(a.as_slice());
    }
    let n = a.nrows() / refs - 1;
    let nr = n * refs;
    let mut comp = DMatrix::<f64>::zeros(nr, nr);
    for i in refs..nr {
        comp[(i - refs, i)] = 1.0;
    }
    // the last block row: -A_j (A(z) v = 0 with state v, z v, ..., z^(n-1) v)
    for j in 0..n {
        for s in 0..refs {
            for c in 0..refs {
                comp[((n - 1) * refs + s, j * refs + c)] = -a[(j * refs + s, c)];
            }
        }
    }
    nalgebra::Schur::try_new(comp, f64::EPSILON, crate::oma::MAX_ITERATIONS)
        .map(|s| s.complex_eigenvalues().iter().copied().collect())
        .unwrap_or_default()
}

/// The null vector of `A(z)` (coefficients `a` stacked as [`matrix_roots`] takes them): the
/// right singular vector of its least singular value; one reference: 1. `None` when the SVD
/// does not converge (the pole is left out rather than given a shape it does not have).
fn null_vector(a: &DMatrix<f64>, refs: usize, z: Complex64) -> Option<Vec<Complex64>> {
    if refs == 1 {
        return Some(vec![Complex64::new(1.0, 0.0)]);
    }
    let coefficients = a.nrows() / refs;
    let mut at = DMatrix::<Complex64>::zeros(refs, refs);
    let mut zj = Complex64::new(1.0, 0.0);
    for j in 0..coefficients {
        for s in 0..refs {
            for c in 0..refs {
                at[(s, c)] += zj * a[(j * refs + s, c)];
            }
        }
        zj *= z;
    }
    let svd = nalgebra::SVD::try_new(at, false, true, f64::EPSILON, crate::oma::MAX_ITERATIONS)?;
    let least = (0..svd.singular_values.len())
        .min_by(|&x, &y| svd.singular_values[x].total_cmp(&svd.singular_values[y]))?;
    // A = U S V^H: the null vector is the conjugate of V^H's row
    let vt = svd.v_t?;
    Some((0..refs).map(|c| vt[(least, c)].conj()).collect())
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
        receptance_between(modes, phi, (o, 0), f)
    }

    /// Receptance from a force at point `r` to the response at point `o`.
    fn receptance_between(
        modes: &[(f64, f64)],
        phi: &[Vec<f64>],
        (o, r): (usize, usize),
        f: f64,
    ) -> Complex64 {
        let w = 2.0 * PI * f;
        modes
            .iter()
            .zip(phi)
            .map(|(&(fr, z), p)| {
                let wr = 2.0 * PI * fr;
                p[o] * p[r] / Complex64::new(wr * wr - w * w, 2.0 * z * wr * w)
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

    /// The receptance matrix `frfs[o * refs + r]` of `modes` with shapes `phi`, the forces at
    /// points `0..refs`.
    fn receptance_matrix(
        modes: &[(f64, f64)],
        phi: &[Vec<f64>],
        refs: usize,
        freq: &[f64],
    ) -> Vec<Vec<Complex64>> {
        let outputs = phi[0].len();
        (0..outputs * refs)
            .map(|or| {
                freq.iter()
                    .map(|&f| receptance_between(modes, phi, (or / refs, or % refs), f))
                    .collect()
            })
            .collect()
    }

    /// Four modes, two of them 0.3 Hz apart (within their half-power bandwidths), seen at
    /// five outputs from two references: modes, shapes, frequencies, FRFs.
    #[allow(clippy::type_complexity)]
    fn close_pair() -> (
        [(f64, f64); 4],
        Vec<Vec<f64>>,
        Vec<f64>,
        Vec<Vec<Complex64>>,
    ) {
        let modes = [(21.0, 0.012), (40.0, 0.02), (40.3, 0.02), (77.0, 0.01)];
        let phi = vec![
            vec![1.0, 0.8, 0.3, -0.4, 0.2],
            vec![0.9, -0.2, -0.9, 0.6, 0.4],
            vec![0.1, 1.0, 0.5, 0.3, -0.8],
            vec![0.4, -0.9, 0.8, 0.5, 0.6],
        ];
        let freq: Vec<f64> = (0..=1000).map(|k| k as f64 * 0.125).collect();
        let frfs = receptance_matrix(&modes, &phi, 2, &freq);
        (modes, phi, freq, frfs)
    }

    /// Each mode of `modes` (shapes `phi`) has at least `count` stable poles within a
    /// fraction `window` of its frequency, and the highest order's is exact.
    fn assert_exact(
        p: &[Pole],
        modes: &[(f64, f64)],
        phi: &[Vec<f64>],
        (window, count): (f64, usize),
    ) {
        for (m, &(f, z)) in modes.iter().enumerate() {
            let at: Vec<&Pole> = p
                .iter()
                .filter(|q| q.stable && (q.f_hz - f).abs() < window * f)
                .collect();
            assert!(
                at.len() >= count,
                "mode at {f} Hz: {} stable poles",
                at.len()
            );
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

    #[test]
    fn poly_reference_separates_two_modes_within_their_bandwidth_with_their_own_shapes() {
        // 40.0 and 40.3 Hz at 2 % damping: half-power bandwidths of 1.6 Hz, five times their
        // spacing; two references (forces at points 1 and 2)
        let (modes, phi, freq, frfs) = close_pair();
        let rule = LscfRule {
            max_order: 24,
            ..LscfRule::default()
        };
        assert_eq!(matrix_order(rule, 2), 20);
        let p = poles_matrix(&freq, &frfs, 2, (5.0, 110.0), rule).unwrap();
        assert!(p.iter().all(|q| q.shape.len() == 5 && q.order <= 20));
        assert_exact(&p, &modes, &phi, (0.002, 5));
        // a reference whose FRFs are all zero is named
        let mut dead = frfs.clone();
        for o in 0..5 {
            dead[o * 2 + 1]
                .iter_mut()
                .for_each(|v| *v = Complex64::new(0.0, 0.0));
        }
        let e = poles_matrix(&freq, &dead, 2, (5.0, 110.0), rule).unwrap_err();
        assert!(e.to_string().contains("reference 2"), "{e}");
    }

    #[test]
    fn poly_reference_keeps_two_close_modes_apart_in_noise_where_one_denominator_merges_them() {
        // the FRF matrix above with complex noise of 10 % of its mean magnitude (uniform, a
        // fixed sequence); the common denominator over the same 10 FRFs gave one mode at
        // 40.16 Hz for the pair (and a spurious one), docs/method.md §3.13
        let (modes, phi, freq, exact) = close_pair();
        let level = exact.iter().flatten().map(|v| v.norm()).sum::<f64>()
            / (exact.len() * freq.len()) as f64;
        let mut seed = 12345u64;
        let mut uniform = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let noisy: Vec<Vec<Complex64>> = exact
            .iter()
            .map(|h| {
                h.iter()
                    .map(|v| v + Complex64::new(uniform(), uniform()) * 0.1 * level)
                    .collect()
            })
            .collect();
        let rule = LscfRule::default();
        let p = poles_matrix(&freq, &noisy, 2, (5.0, 110.0), rule).unwrap();
        let (found, _) =
            crate::oma::cluster::cluster(&p, crate::oma::cluster::ClusterRule::default());
        assert_eq!(found.len(), 4, "{found:?}");
        for (m, &(f, z)) in modes.iter().enumerate() {
            let got = found
                .iter()
                .min_by(|a, b| (a.f_hz - f).abs().total_cmp(&(b.f_hz - f).abs()))
                .unwrap();
            assert!((got.f_hz - f).abs() < 1e-3 * f, "{} vs {f}", got.f_hz);
            assert!((got.damping - z).abs() < 0.05 * z, "{} vs {z}", got.damping);
            let want: Vec<Complex64> = phi[m].iter().map(|&v| Complex64::new(v, 0.0)).collect();
            assert!(mac(&got.shape, &want) > 0.99, "shape of mode {m}");
        }
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
        assert_exact(&p, &modes, &phi, (0.01, 10));
    }
}
