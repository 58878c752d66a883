//! Data-driven stochastic subspace identification (SSI-dat, docs/method.md §3.12): the
//! records' block Hankel matrix of `i` past and `i` future block rows, the orthogonal
//! projection of the future outputs on the past ones, and its column space, from which
//! `super::ssi` takes each order's model as SSI-cov does from its Toeplitz matrix.
//!
//! The projection `O = Y_f / Y_p` is `L21 Q1^T` of the LQ decomposition of `[Y_p; Y_f] /
//! sqrt(j)` (`j` Hankel columns), so its left singular vectors and singular values are those
//! of `L21`. `L` is taken here as the Cholesky factor of the Hankel matrix's Gram matrix
//! `H H^T / j`, which is `L L^T` (the same `L` as the LQ's up to the signs of its columns,
//! which leave `L21`'s singular values and left vectors unchanged). The Gram matrix is summed
//! exactly from the records, per block of Hankel columns (a column counted in the block of its
//! first sample), so that the jackknife leaves a block out as SSI-cov's does. Unlike SSI-cov's
//! Toeplitz matrix of correlations, the projection weighs the future by the inverse of the
//! past's covariance (a model of the data, not of its correlations), and uses each of the
//! record's samples exactly once per block row: the two differ on short records.
//! [`super::ssi::Parts`] takes the model from here.

use nalgebra::DMatrix;

/// The Gram matrix `sum_t h(t) h(t)^T` of the records' block Hankel columns `h(t) = [y(t);
/// y(t + 1); ...; y(t + 2i - 1)]` (means removed), per block of columns, with each block's
/// number of columns: what the projection of the whole record, or of the record without one
/// block (the jackknife), is made of.
#[derive(Debug, Clone)]
pub struct HankelGrams {
    /// Block rows `i` (past and future each).
    pub block_rows: usize,
    /// Channels `K`.
    pub channels: usize,
    /// Per block, the `2iK x 2iK` sum.
    pub sums: Vec<DMatrix<f64>>,
    /// Per block, the number of Hankel columns.
    pub counts: Vec<usize>,
}

impl HankelGrams {
    /// The Gram matrix (divided by the number of columns) of the record without the blocks
    /// `left_out` (all with none).
    pub fn without(&self, left_out: &[usize]) -> DMatrix<f64> {
        let m = 2 * self.block_rows * self.channels;
        let mut g = DMatrix::<f64>::zeros(m, m);
        let mut n = 0usize;
        for (b, (sum, count)) in self.sums.iter().zip(&self.counts).enumerate() {
            if !left_out.contains(&b) {
                g += sum;
                n += count;
            }
        }
        g / n.max(1) as f64
    }
}

/// `channels` with their means removed, for SSI of `block_rows` block rows (`who` names the
/// method in the error): an error when there are none or the record is shorter than four block
/// rows.
pub fn centred(
    channels: &[Vec<f64>],
    block_rows: usize,
    who: &str,
) -> anyhow::Result<Vec<Vec<f64>>> {
    let n = channels.first().map_or(0, Vec::len);
    let i = block_rows;
    if channels.is_empty() || i < 2 || n < 4 * i {
        return Err(vibcam_readers::bad_input(format!(
            "{who}: {n} samples are too few for {i} block rows (at least {})",
            4 * i
        )));
    }
    Ok(channels
        .iter()
        .map(|c| {
            let m = c.iter().sum::<f64>() / n as f64;
            c.iter().map(|v| v - m).collect()
        })
        .collect())
}

/// The Hankel Gram matrices of `channels` for `block_rows` block rows in `blocks` blocks of
/// columns ([`HankelGrams`]). Errors when the record is too short for the block rows.
pub fn grams(
    channels: &[Vec<f64>],
    block_rows: usize,
    blocks: usize,
) -> anyhow::Result<HankelGrams> {
    let y = centred(channels, block_rows, "SSI-dat")?;
    let (k, n, i) = (y.len(), y[0].len(), block_rows);
    let rows = 2 * i;
    let columns = n - rows + 1;
    let blocks = blocks.clamp(1, columns);
    let edge = |b: usize| b * columns / blocks;
    // sum_{s in s0..s1} y(s) y(s + d)^T, entry (a, c) = sum y_a(s) y_c(s + d)
    let lagged = |s0: usize, s1: usize, d: usize| {
        DMatrix::<f64>::from_fn(k, k, |a, c| {
            y[a][s0..s1]
                .iter()
                .zip(&y[c][s0 + d..s1 + d])
                .map(|(p, q)| p * q)
                .sum()
        })
    };
    let mut sums = Vec::with_capacity(blocks);
    let mut counts = Vec::with_capacity(blocks);
    for b in 0..blocks {
        let (t0, t1) = (edge(b), edge(b + 1));
        let mut g = DMatrix::<f64>::zeros(rows * k, rows * k);
        for d in 0..rows {
            // block (p, p + d) sums y(t + p) y(t + p + d)^T over t in t0..t1: the lag-d sum
            // over t0..t1 moved by p samples, its ends mended
            let mut s = lagged(t0, t1, d);
            for p in 0..rows - d {
                if p > 0 {
                    s -= lagged(t0 + p - 1, t0 + p, d);
                    s += lagged(t1 + p - 1, t1 + p, d);
                }
                g.view_mut((p * k, (p + d) * k), (k, k)).copy_from(&s);
                if d > 0 {
                    g.view_mut(((p + d) * k, p * k), (k, k))
                        .copy_from(&s.transpose());
                }
            }
        }
        sums.push(g);
        counts.push(t1 - t0);
    }
    Ok(HankelGrams {
        block_rows: i,
        channels: k,
        sums,
        counts,
    })
}

/// `L21` of the Cholesky factor `L` of the Hankel Gram matrix `gram` (`2iK x 2iK`): the
/// projection's factor whose SVD gives the observability matrix. A Gram matrix singular to
/// rounding (channels that are exact combinations of others, a noise-free record) gets a
/// ridge of `1e-12` of its mean diagonal, doubled up to `1e-6` until it factors.
pub fn projection(
    gram: &DMatrix<f64>,
    block_rows: usize,
    k: usize,
) -> anyhow::Result<DMatrix<f64>> {
    let m = block_rows * k;
    let scale = gram.diagonal().mean().abs().max(f64::MIN_POSITIVE);
    let mut ridge = 0.0;
    loop {
        let mut g = gram.clone();
        for d in 0..2 * m {
            g[(d, d)] += ridge * scale;
        }
        if let Some(c) = nalgebra::Cholesky::new(g) {
            return Ok(c.l().view((m, 0), (m, m)).into_owned());
        }
        ridge = if ridge == 0.0 { 1e-12 } else { 2.0 * ridge };
        if ridge > 1e-6 || !scale.is_finite() {
            return Err(anyhow::anyhow!(
                "SSI-dat: the records' Hankel matrix is singular (channels that are exact \
                 copies or combinations of others, or non-finite values)"
            ));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Gram matrix by its definition: the Hankel matrix built and multiplied out.
    fn naive(channels: &[Vec<f64>], i: usize) -> DMatrix<f64> {
        let y = centred(channels, i, "test").unwrap();
        let (k, n) = (y.len(), y[0].len());
        let j = n - 2 * i + 1;
        let h = DMatrix::<f64>::from_fn(2 * i * k, j, |r, t| y[r % k][t + r / k]);
        &h * h.transpose()
    }

    #[test]
    fn the_gram_matrix_in_blocks_sums_to_the_hankel_matrixs_own() {
        let n = 97;
        let channels: Vec<Vec<f64>> = (0..3)
            .map(|c| vibcam_common::testing::gaussian_noise(7 + c, n))
            .collect();
        let i = 4;
        let g = grams(&channels, i, 5).unwrap();
        assert_eq!(g.counts.iter().sum::<usize>(), n - 2 * i + 1);
        let whole = naive(&channels, i);
        let summed = g.sums.iter().fold(DMatrix::zeros(24, 24), |a, s| a + s);
        assert!(
            (&summed - &whole).amax() < 1e-9 * whole.amax(),
            "{}",
            (&summed - &whole).amax()
        );
        // one block left out: the whole less that block's columns
        let j = n - 2 * i + 1;
        let (t0, t1) = (j / 5, 2 * j / 5);
        let k = 3;
        let part = DMatrix::<f64>::from_fn(2 * i * k, t1 - t0, |r, t| {
            let c = &channels[r % k];
            let m = c.iter().sum::<f64>() / n as f64;
            c[t0 + t + r / k] - m
        });
        let less = (&whole - &part * part.transpose()) / (j - (t1 - t0)) as f64;
        assert!((g.without(&[1]) - less).amax() < 1e-9 * whole.amax());
    }

    #[test]
    fn the_projection_factor_spans_what_the_lq_decomposition_gives() {
        // L21 L21^T is the projection's Gram: Yf Yp^T (Yp Yp^T)^-1 Yp Yf^T / j
        let n = 200;
        let channels: Vec<Vec<f64>> = (0..2)
            .map(|c| vibcam_common::testing::gaussian_noise(20 + c, n))
            .collect();
        let i = 3;
        let g = grams(&channels, i, 1).unwrap().without(&[]);
        let l21 = projection(&g, i, 2).unwrap();
        let m = i * 2;
        let (gpp, gfp) = (g.view((0, 0), (m, m)), g.view((m, 0), (m, m)));
        let want = gfp * gpp.into_owned().try_inverse().unwrap() * gfp.transpose();
        assert!((&l21 * l21.transpose() - &want).amax() < 1e-10 * want.amax());
    }

    /// Two modes as exact discrete oscillators (second-order autoregressions whose poles are
    /// `exp(s dt)` of the stated frequency and damping) driven by white noise, mixed into three
    /// channels by their shapes, 5 % noise, 400 s: SSI-dat's stable poles sit on both (measured
    /// within 0.3 % in frequency and 12 % in damping; SSI-cov's on the same record alike).
    #[test]
    fn ssi_dat_finds_two_oscillators_poles_and_shapes() {
        use super::super::ssi::{self, SsiKind};
        use crate::modal::mac;
        use num_complex::Complex64;
        let (fs, n) = (50.0, 20_000);
        let modes: [(f64, f64, [f64; 3]); 2] = [
            (3.1, 0.015, [1.0, 0.6, -0.4]),
            (7.7, 0.03, [0.3, -1.0, 0.8]),
        ];
        let of: Vec<(f64, f64, &[f64])> = modes.iter().map(|(f, z, v)| (*f, *z, &v[..])).collect();
        let channels = super::super::test_records::oscillators(fs, n, &of, (40, 0.05));
        let rule = ssi::SsiRule {
            block_rows: 10,
            max_order: 20,
            df_max: 0.01,
            dz_max: 0.05,
            mac_min: 0.98,
            zeta_max: 0.2,
            f_range_hz: (0.5, 25.0),
            kind: SsiKind::Dat,
        };
        let (poles, _) = ssi::poles(&channels, fs, rule).unwrap();
        for (f, z, shape) in modes {
            let near: Vec<_> = poles
                .iter()
                .filter(|p| p.stable && (p.f_hz - f).abs() < 0.02 * f)
                .collect();
            assert!(near.len() >= 5, "{f} Hz: {} stable poles", near.len());
            let truth: Vec<Complex64> = shape.iter().map(|&v| Complex64::new(v, 0.0)).collect();
            for p in near {
                assert!((p.f_hz - f).abs() < 0.005 * f, "{f} Hz: {}", p.f_hz);
                assert!((p.damping - z).abs() < 0.25 * z, "{z}: {}", p.damping);
                assert!(
                    mac(&p.shape, &truth) > 0.99,
                    "{f} Hz: MAC {}",
                    mac(&p.shape, &truth)
                );
            }
        }
    }
}
