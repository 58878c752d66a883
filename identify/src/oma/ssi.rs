//! Covariance-driven stochastic subspace identification (SSI-cov) with a stabilisation
//! diagram (docs/method.md §3.12): output correlations, their block Toeplitz matrix, its SVD,
//! a state-space model per order, the model's poles and shapes, and poles stable from one order
//! to the next (clustered into modes by [`super::cluster`]).

use super::ssi_dat::{centred, grams, projection, HankelGrams};
use crate::modal::mac;
use nalgebra::{DMatrix, DVector};
use num_complex::Complex64;
use std::f64::consts::PI;

/// Settings of SSI-cov.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SsiRule {
    /// Block rows `i` of the Toeplitz matrix (correlation lags 1 .. 2i - 1).
    pub block_rows: usize,
    /// Highest model order (even); orders 2, 4, ... up to it.
    pub max_order: usize,
    /// Stable in frequency: relative change from the order below at most this.
    pub df_max: f64,
    /// Stable in damping: relative change at most this.
    pub dz_max: f64,
    /// Stable in shape: MAC with the order below's pole at least this.
    pub mac_min: f64,
    /// Physical poles only: damping ratio in `(0, zeta_max)`.
    pub zeta_max: f64,
    /// Frequency range of the poles kept, Hz.
    pub f_range_hz: (f64, f64),
    /// Covariance- or data-driven.
    pub kind: SsiKind,
}

/// Which matrix of the records SSI takes its model's column space from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SsiKind {
    /// SSI-cov: the block Toeplitz matrix of the output correlations.
    #[default]
    Cov,
    /// SSI-dat: the projection of the future outputs on the past ones ([`super::ssi_dat`]).
    Dat,
}

impl SsiKind {
    /// Its name in the report (`SSI-cov`, `SSI-dat`).
    pub fn label(self) -> &'static str {
        match self {
            SsiKind::Cov => "SSI-cov",
            SsiKind::Dat => "SSI-dat",
        }
    }
}

impl SsiRule {
    /// The rule's stability criteria.
    pub fn stability(&self) -> Stability {
        Stability {
            df_max: self.df_max,
            dz_max: self.dz_max,
            mac_min: self.mac_min,
        }
    }
}

/// One pole of one model order.
#[derive(Debug, Clone, PartialEq)]
pub struct Pole {
    /// Model order.
    pub order: usize,
    /// Undamped natural frequency, Hz.
    pub f_hz: f64,
    /// Damping ratio.
    pub damping: f64,
    /// Shape at the channels (unnormalised).
    pub shape: Vec<Complex64>,
    /// Stable with a pole of the order below (frequency, damping and shape).
    pub stable: bool,
}

/// Below this damping ratio the damping's stability tolerance is `dz_max` of this, not of the
/// pole's own damping ([`Stability`]).
pub const DAMPING_FLOOR: f64 = 0.002;

/// The stability rule of a stabilisation diagram: a pole is stable when one of the order
/// below lies within `df_max` in frequency and `dz_max` in damping (relative; below a damping
/// of [`DAMPING_FLOOR`], `dz_max` of that floor) and their shapes' MAC is at least `mac_min`.
/// A lightly damped mode's damping (a tuning fork's, a few 1e-4) estimated from a short record
/// scatters between orders by more than 5 % of itself while its frequency holds to 1e-5; a
/// relative rule alone left such a mode with one or two stable poles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stability {
    /// Relative change of frequency at most this.
    pub df_max: f64,
    /// Relative change of damping at most this.
    pub dz_max: f64,
    /// MAC of the shapes at least this.
    pub mac_min: f64,
}

impl Pole {
    /// The pole of `order` at `f_hz` with `damping` and `shape`, marked stable by `rule`
    /// against the poles `below` of the order below.
    pub fn judged(
        (order, f_hz, damping): (usize, f64, f64),
        shape: Vec<Complex64>,
        below: &[Pole],
        rule: Stability,
    ) -> Pole {
        let stable = below.iter().any(|p| {
            (p.f_hz - f_hz).abs() <= rule.df_max * f_hz
                && (p.damping - damping).abs() <= rule.dz_max * damping.max(DAMPING_FLOOR)
                && mac(&p.shape, &shape) >= rule.mac_min
        });
        Pole {
            order,
            f_hz,
            damping,
            shape,
            stable,
        }
    }
}

/// The poles of every order of the records `channels` (mean removed here) sampled at
/// `fs_hz`, each marked stable or not; then the poles that only the lower end of
/// `rule.f_range_hz` left out (physical, below it), marked stable among themselves: what the
/// range cut, for the report. SSI-cov or SSI-dat as `rule.kind` says.
pub fn poles(
    channels: &[Vec<f64>],
    fs_hz: f64,
    rule: SsiRule,
) -> anyhow::Result<(Vec<Pole>, Vec<Pole>)> {
    Parts::of(channels, rule, 1)?.poles(&[], fs_hz, rule)
}

/// What SSI's matrix is made of, per block of the record, for either kind: the whole record's
/// poles, or those of the record without one block (the jackknife).
#[derive(Debug, Clone)]
pub enum Parts {
    /// SSI-cov's correlation sums.
    Cov(CorrelationSums),
    /// SSI-dat's Hankel Gram matrices.
    Dat(HankelGrams),
}

impl Parts {
    /// The parts of `channels` in `blocks` blocks for `rule` (its kind and block rows).
    pub fn of(channels: &[Vec<f64>], rule: SsiRule, blocks: usize) -> anyhow::Result<Parts> {
        Ok(match rule.kind {
            SsiKind::Cov => Parts::Cov(correlation_sums(channels, rule.block_rows, blocks)?),
            SsiKind::Dat => Parts::Dat(grams(channels, rule.block_rows, blocks)?),
        })
    }

    /// The poles of every order of the record without the blocks `left_out` (all with none).
    pub fn poles(
        &self,
        left_out: &[usize],
        fs_hz: f64,
        rule: SsiRule,
    ) -> anyhow::Result<(Vec<Pole>, Vec<Pole>)> {
        let (t, k) = self.matrix(left_out, rule)?;
        poles_from(t, k, fs_hz, rule)
    }

    /// The matrix whose column space is the observability matrix's (SSI-cov's block Toeplitz
    /// matrix, SSI-dat's projection factor) of the record without the blocks `left_out` (all
    /// with none), and its channels.
    pub fn matrix(
        &self,
        left_out: &[usize],
        rule: SsiRule,
    ) -> anyhow::Result<(DMatrix<f64>, usize)> {
        match self {
            Parts::Cov(sums) => {
                let r = sums.without(left_out);
                let k = r.first().map_or(0, |m| m.nrows());
                Ok((toeplitz(&r, rule.block_rows), k))
            }
            Parts::Dat(grams) => Ok((
                projection(&grams.without(left_out), grams.block_rows, grams.channels)?,
                grams.channels,
            )),
        }
    }
}

/// The output correlations' sums `sum_t y(t + l) y(t)^T` (means removed) for the lags
/// `0 .. 2i` of `i` block rows, per block of the record (`blocks` contiguous parts, a product
/// counted in the block of its `t`), with the number of products: what the correlations of the
/// whole record, or of the record without one block (the jackknife), are made of.
#[derive(Debug, Clone)]
pub struct CorrelationSums {
    /// Per block, per lag, the K x K sum.
    pub sums: Vec<Vec<DMatrix<f64>>>,
    /// Per block, per lag, the number of products.
    pub counts: Vec<Vec<usize>>,
}

impl CorrelationSums {
    /// The correlations of the whole record.
    pub fn all(&self) -> Vec<DMatrix<f64>> {
        self.without(&[])
    }

    /// The correlations of the record without the blocks `left_out` (all with none).
    pub fn without(&self, left_out: &[usize]) -> Vec<DMatrix<f64>> {
        let lags = self.sums.first().map_or(0, Vec::len);
        let k = self
            .sums
            .first()
            .and_then(|b| b.first())
            .map_or(0, |m| m.nrows());
        (0..lags)
            .map(|l| {
                let mut m = DMatrix::<f64>::zeros(k, k);
                let mut n = 0usize;
                for (b, (sum, count)) in self.sums.iter().zip(&self.counts).enumerate() {
                    if !left_out.contains(&b) {
                        m += &sum[l];
                        n += count[l];
                    }
                }
                m / n.max(1) as f64
            })
            .collect()
    }
}

/// The correlation sums of `channels` for `block_rows` block rows in `blocks` blocks
/// ([`CorrelationSums`]). Errors when the record is too short for the block rows.
pub fn correlation_sums(
    channels: &[Vec<f64>],
    block_rows: usize,
    blocks: usize,
) -> anyhow::Result<CorrelationSums> {
    let y = centred(channels, block_rows, "SSI-cov")?;
    let (k, n, i) = (y.len(), y[0].len(), block_rows);
    let lags = 2 * i;
    let blocks = blocks.max(1);
    let edge = |b: usize| b * n / blocks;
    let mut sums = vec![vec![DMatrix::<f64>::zeros(k, k); lags]; blocks];
    let mut counts = vec![vec![0usize; lags]; blocks];
    for (b, (sum, count)) in sums.iter_mut().zip(counts.iter_mut()).enumerate() {
        for (l, (sl, cl)) in sum.iter_mut().zip(count.iter_mut()).enumerate().skip(1) {
            // the products y(t + l) y(t)^T with t in the block and t + l in the record
            let (t0, t1) = (edge(b), edge(b + 1).min(n - l));
            if t1 <= t0 {
                continue;
            }
            for a in 0..k {
                for c in 0..k {
                    sl[(a, c)] = y[a][t0 + l..t1 + l]
                        .iter()
                        .zip(&y[c][t0..t1])
                        .map(|(p, q)| p * q)
                        .sum();
                }
            }
            *cl = t1 - t0;
        }
    }
    Ok(CorrelationSums { sums, counts })
}

/// The poles of every order from the output correlations `r` (lags `0 .. 2i`) of records
/// sampled at `fs_hz` ([`poles`]).
pub fn poles_of(
    r: &[DMatrix<f64>],
    fs_hz: f64,
    rule: SsiRule,
) -> anyhow::Result<(Vec<Pole>, Vec<Pole>)> {
    let k = r.first().map_or(0, |m| m.nrows());
    poles_from(toeplitz(r, rule.block_rows), k, fs_hz, rule)
}

/// The block Toeplitz matrix of `i` block rows of the correlations `r` (lags `0 .. 2i`):
/// block (row a, column b) = `R_{i + a - b}`.
fn toeplitz(r: &[DMatrix<f64>], i: usize) -> DMatrix<f64> {
    let k = r.first().map_or(0, |m| m.nrows());
    let mut t = DMatrix::<f64>::zeros(i * k, i * k);
    for a in 0..i {
        for b in 0..i {
            t.view_mut((a * k, b * k), (k, k)).copy_from(&r[i + a - b]);
        }
    }
    t
}

/// The poles of every order from `t`, a matrix of `i` block rows of `k` channels whose column
/// space is the observability matrix's (SSI-cov's block Toeplitz matrix, SSI-dat's projection
/// factor), for records sampled at `fs_hz`, as [`poles`] returns them.
pub fn poles_from(
    t: DMatrix<f64>,
    k: usize,
    fs_hz: f64,
    rule: SsiRule,
) -> anyhow::Result<(Vec<Pole>, Vec<Pole>)> {
    let i = t.nrows() / k.max(1);
    let o = observability(t, (i * k).saturating_sub(k).min(rule.max_order) & !1)?;
    poles_of_observability(&o, k, fs_hz, rule)
}

/// The observability matrix of order `n` from `t` (as [`poles_from`] takes it): the left
/// singular vectors of its `n` largest singular values, each times the value's square root,
/// largest first (columns of zeros where `t` has fewer).
pub fn observability(t: DMatrix<f64>, n: usize) -> anyhow::Result<DMatrix<f64>> {
    let rows = t.nrows();
    let svd = nalgebra::SVD::try_new(t, true, false, f64::EPSILON, super::MAX_ITERATIONS)
        .ok_or_else(|| not_converged("the block matrix's SVD", 0))?;
    let (u, sv) = (
        svd.u
            .ok_or_else(|| anyhow::anyhow!("internal: SVD without U"))?,
        svd.singular_values,
    );
    // singular values are not sorted by nalgebra: order them
    let mut order: Vec<usize> = (0..sv.len()).collect();
    order.sort_by(|&a, &b| sv[b].total_cmp(&sv[a]));
    let mut o = DMatrix::<f64>::zeros(rows, n);
    for (c, &j) in order.iter().take(n).enumerate() {
        o.set_column(c, &(u.column(j) * sv[j].max(0.0).sqrt()));
    }
    Ok(o)
}

/// The poles of every even order up to `o`'s columns from the observability matrix `o` (`i`
/// block rows of `k` channels, its columns largest first): each order's state matrix from the
/// shift of its first columns, its output matrix their first block row ([`poles`]).
pub fn poles_of_observability(
    o: &DMatrix<f64>,
    k: usize,
    fs_hz: f64,
    rule: SsiRule,
) -> anyhow::Result<(Vec<Pole>, Vec<Pole>)> {
    let i = o.nrows() / k.max(1);
    let max_order = o.ncols().min((i * k).saturating_sub(k)) & !1;
    poles_of_orders(k, max_order, fs_hz, rule, |ord| {
        Ok(o.columns(0, ord).into_owned())
    })
}

/// The poles of every even order up to `max_order`, `o_of(order)` giving that order's
/// observability matrix (block rows of `k` channels), as [`poles_of_observability`].
pub fn poles_of_orders(
    k: usize,
    max_order: usize,
    fs_hz: f64,
    rule: SsiRule,
    mut o_of: impl FnMut(usize) -> anyhow::Result<DMatrix<f64>>,
) -> anyhow::Result<(Vec<Pole>, Vec<Pole>)> {
    let mut all: Vec<Pole> = Vec::new();
    let mut below: Vec<Pole> = Vec::new();
    let (mut cut, mut cut_below): (Vec<Pole>, Vec<Pole>) = (Vec::new(), Vec::new());
    for ord in (2..=max_order).step_by(2) {
        let o = o_of(ord)?;
        let i = o.nrows() / k.max(1);
        let up = o.rows(0, (i - 1) * k).into_owned();
        let down = o.rows(k, (i - 1) * k).into_owned();
        let pinv = nalgebra::SVD::try_new(up, true, true, f64::EPSILON, super::MAX_ITERATIONS)
            .ok_or_else(|| not_converged("the observability matrix's SVD", ord))?;
        let Ok(pinv) = pinv.pseudo_inverse(1e-12) else {
            continue;
        };
        let a = pinv * down;
        let c = o.rows(0, k).into_owned();
        let (mut here, mut here_cut) = (Vec::new(), Vec::new());
        for (lambda, psi) in eigenpairs(&a).ok_or_else(|| not_converged("the eigenvalues", ord))? {
            if lambda.im <= 0.0 {
                continue;
            }
            let s = lambda.ln() * fs_hz;
            let wn = s.norm();
            let (f_hz, damping) = (wn / (2.0 * PI), -s.re / wn);
            if !(damping > 0.0 && damping < rule.zeta_max) || f_hz >= rule.f_range_hz.1 {
                continue;
            }
            let shape: Vec<Complex64> = (0..k)
                .map(|row| (0..ord).map(|col| psi[col] * c[(row, col)]).sum())
                .collect();
            let (list, previous) = if f_hz < rule.f_range_hz.0 {
                (&mut here_cut, &cut_below)
            } else {
                (&mut here, &below)
            };
            list.push(Pole::judged(
                (ord, f_hz, damping),
                shape,
                previous,
                rule.stability(),
            ));
        }
        all.extend(here.iter().cloned());
        below = here;
        cut.extend(here_cut.iter().cloned());
        cut_below = here_cut;
    }
    Ok((all, cut))
}

/// The error of a decomposition that did not converge within [`super::MAX_ITERATIONS`]
/// (`order` 0: before the model orders).
fn not_converged(what: &str, order: usize) -> anyhow::Error {
    let at = if order > 0 {
        format!(" of the order-{order} model")
    } else {
        String::new()
    };
    anyhow::anyhow!(
        "SSI: {what}{at} did not converge in {} iterations (degenerate or non-finite \
         values)",
        super::MAX_ITERATIONS
    )
}

/// Eigenvalues of a real square matrix with a unit eigenvector each (inverse iteration);
/// `None` when the Schur decomposition does not converge within [`super::MAX_ITERATIONS`].
fn eigenpairs(a: &DMatrix<f64>) -> Option<Vec<(Complex64, DVector<Complex64>)>> {
    let schur = nalgebra::Schur::try_new(a.clone(), f64::EPSILON, super::MAX_ITERATIONS)?;
    Some(
        schur
            .complex_eigenvalues()
            .iter()
            .filter_map(|&l| eigenvector(a, l).map(|v| (l, v)))
            .collect(),
    )
}

/// A unit eigenvector of `a` for the eigenvalue `l` by inverse iteration.
fn eigenvector(a: &DMatrix<f64>, l: Complex64) -> Option<DVector<Complex64>> {
    let n = a.nrows();
    // shifted a little off the eigenvalue so that the solve is not singular
    let shift = l + Complex64::new(1e-10 * (1.0 + l.norm()), 1e-10 * (1.0 + l.norm()));
    let m = DMatrix::<Complex64>::from_fn(n, n, |i, j| {
        Complex64::new(a[(i, j)], 0.0)
            - if i == j {
                shift
            } else {
                Complex64::new(0.0, 0.0)
            }
    });
    let lu = m.lu();
    let mut v = DVector::<Complex64>::from_element(n, Complex64::new(1.0, 0.0));
    for _ in 0..3 {
        let w = lu.solve(&v)?;
        let norm = w.norm();
        if !(norm.is_finite() && norm > 0.0) {
            return None;
        }
        v = w / Complex64::new(norm, 0.0);
    }
    Some(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn damping_is_stable_within_five_percent_or_five_percent_of_the_floor() {
        let rule = Stability {
            df_max: 0.01,
            dz_max: 0.05,
            mac_min: 0.98,
        };
        let shape = vec![Complex64::new(1.0, 0.0), Complex64::new(0.5, 0.0)];
        let below = |z: f64| vec![Pole::judged((4, 32.0, z), shape.clone(), &[], rule)];
        let stable = |z_below: f64, z: f64| {
            Pole::judged((6, 32.0, z), shape.clone(), &below(z_below), rule).stable
        };
        // a fork's damping: 3e-4 and 3.9e-4 differ by 30 %, below 1e-4 absolute (5 % of 0.2 %)
        assert!(stable(3e-4, 3.9e-4));
        assert!(!stable(3e-4, 4.2e-4));
        // above the floor the rule is relative as before: 4 % stable, 6 % not
        assert!(stable(0.02, 0.0208));
        assert!(!stable(0.02, 0.0212));
        // the frequency still decides
        assert!(!Pole::judged((6, 32.4, 4e-4), shape.clone(), &below(3e-4), rule).stable);
    }
}
