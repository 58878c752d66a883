//! The LK kernels for targets with SIMD registers (x86-64, AArch64). Cross moments: each lag's
//! products accumulated in eight lanes across the whole window (two SSE or one AVX register
//! per lag, which the compiler vectorises), the lanes added once at the end. The same sums as
//! the M4's kernels, in another order (f32 rounding differs in the last bits).
//! The window's `[1 2 1]` smoothing likewise in one vectorisable loop instead of the M4's
//! rolling pass.
//! Only slices come in; this backend knows nothing of its caller.

use crate::centroid::Pixel;

/// The eight lanes of an accumulator added, pairwise.
#[inline(always)]
fn total([a0, a1, a2, a3, a4, a5, a6, a7]: [f32; 8]) -> f32 {
    ((a0 + a4) + (a2 + a6)) + ((a1 + a5) + (a3 + a7))
}

/// `acc[lane] += g[lane] c[lane]` for the eight lanes.
#[inline(always)]
fn madd(acc: &mut [f32; 8], g: &[f32; 8], c: &[f32; 8]) {
    for ((a, g), c) in acc.iter_mut().zip(g).zip(c) {
        *a += g * c;
    }
}

/// [`madd`] for the first four lanes (a row's last group of four).
#[inline(always)]
fn madd4(acc: &mut [f32; 8], g: &[f32; 4], c: &[f32; 4]) {
    for ((a, g), c) in acc.iter_mut().zip(g).zip(c) {
        *a += g * c;
    }
}

/// The `N` values of `s` from `at`, if there are that many.
#[inline(always)]
fn at<const N: usize>(s: &[f32], at: usize) -> Option<&[f32; N]> {
    s.get(at..at + N).and_then(|s| s.try_into().ok())
}

/// `sum_j sum_i g[j gs + i] c[(j + v) pw + i]` over the `th` rows of the window `g` (rows
/// `gs` apart, a multiple of four, zero-padded) for the `V` (at most four) vertical lags
/// `v` of the coefficients `c` (rows `pw` apart, starting at the column's first lag).
#[inline(always)]
pub(super) fn column_sums<const V: usize>(
    g: &[f32],
    gs: usize,
    c: &[f32],
    pw: usize,
    th: usize,
) -> [f32; V] {
    let mut acc = [[0.0f32; 8]; V];
    let gs = gs.max(4);
    for (j, row) in g.chunks_exact(gs).take(th).enumerate() {
        for (v, av) in acc.iter_mut().enumerate() {
            let start = (j + v) * pw;
            let Some(cr) = c.get(start..start + gs) else {
                continue;
            };
            let mut n = 0;
            while let (Some(gw), Some(cw)) = (at::<8>(row, n), at::<8>(cr, n)) {
                madd(av, gw, cw);
                n += 8;
            }
            if let (Some(gw), Some(cw)) = (at::<4>(row, n), at::<4>(cr, n)) {
                madd4(av, gw, cw);
            }
        }
    }
    acc.map(total)
}

/// `sum_j sum_i g[j gs + i] c[j pw + i + k]` over the `th` rows of the window `g` (rows `gs`
/// apart, a multiple of four, zero-padded) for the `L` (at most four) horizontal lags `k`
/// of the coefficients `c` (rows `pw` apart, starting at the first lag; over the row's zero
/// pad too: the padded template reaches that far).
#[inline(always)]
pub(super) fn lag_sums<const L: usize>(
    g: &[f32],
    gs: usize,
    c: &[f32],
    pw: usize,
    th: usize,
) -> [f32; L] {
    let mut acc = [[0.0f32; 8]; L];
    let gs = gs.max(4);
    for (j, row) in g.chunks_exact(gs).take(th).enumerate() {
        let start = j * pw;
        let Some(cr) = c.get(start..start + gs + L - 1) else {
            break;
        };
        let mut n = 0;
        while let Some(gw) = at::<8>(row, n) {
            for (k, ak) in acc.iter_mut().enumerate() {
                if let Some(cw) = at::<8>(cr, n + k) {
                    madd(ak, gw, cw);
                }
            }
            n += 8;
        }
        if let Some(gw) = at::<4>(row, n) {
            for (k, ak) in acc.iter_mut().enumerate() {
                if let Some(cw) = at::<4>(cr, n + k) {
                    madd4(ak, gw, cw);
                }
            }
        }
    }
    acc.map(total)
}

/// One window row smoothed by `[1 2 1]` down the columns of the source rows `a`, `b`, `c`
/// (each `out.len() + 2` pixels) and then along the row, stored as `v - mean`; returns the
/// row's sum and sum of squares of the stored values and the largest pixel of `b`, or `None`
/// (and nothing stored) when the rows are not that long or the row is longer than 2047
/// pixels. Each value from the nine source pixels around it, in one loop the compiler
/// vectorises (a buffer of column sums between two passes measured slower), then the squares
/// of the stored values in four `f64` lanes. Exact: a value is below 2^20 in magnitude, so its
/// square below 2^40 and a row's sum of squares below 2^51, exact in `f64`; the sum in `i32`.
#[inline(always)]
pub(super) fn smooth_row3<P: Pixel>(
    a: &[P],
    b: &[P],
    c: &[P],
    out: &mut [f32],
    mean: i32,
) -> Option<(i64, i64, u16)> {
    let n = out.len();
    if n > 2047 || a.len() != n + 2 || b.len() != n + 2 || c.len() != n + 2 {
        return None;
    }
    let top = b.iter().fold(0u16, |m, &v| m.max(v.into()));
    // the column sums a + 2 b + c from the offsets 0, 1, 2, each n long
    fn from<P>(r: &[P], s: usize, n: usize) -> &[P] {
        r.get(s..s + n).unwrap_or(&[])
    }
    let cols = |s: usize| {
        from(a, s, n)
            .iter()
            .zip(from(b, s, n))
            .zip(from(c, s, n))
            .map(|((&a, &b), &c)| {
                i32::from(a.into()) + 2 * i32::from(b.into()) + i32::from(c.into())
            })
    };
    let mut rs = 0i32;
    for (((o, x0), x1), x2) in out.iter_mut().zip(cols(0)).zip(cols(1)).zip(cols(2)) {
        let d = x0 + 2 * x1 + x2 - mean;
        *o = d as f32;
        rs += d;
    }
    let (mut q0, mut q1, mut q2, mut q3) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut quads = out.chunks_exact(4);
    for o4 in &mut quads {
        if let &[d0, d1, d2, d3] = o4 {
            q0 += f64::from(d0) * f64::from(d0);
            q1 += f64::from(d1) * f64::from(d1);
            q2 += f64::from(d2) * f64::from(d2);
            q3 += f64::from(d3) * f64::from(d3);
        }
    }
    for &d in quads.remainder() {
        q0 += f64::from(d) * f64::from(d);
    }
    Some((i64::from(rs), ((q0 + q1) + (q2 + q3)) as i64, top))
}

/// Pixels of a window row (`row`) at or above `sat` where the template is dark around them
/// (`dark`, the template's row of the tracker's mask): without branches, so it vectorises.
#[inline(always)]
pub(super) fn newly_clipped<P: Pixel>(row: &[P], dark: &[bool], sat: u16) -> u32 {
    row.iter()
        .zip(dark)
        .map(|(&v, &d)| u32::from(v.into() >= sat && d))
        .sum()
}
