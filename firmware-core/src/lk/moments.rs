//! The spline path's moments: the template's ([`Moments`], once per template) and the frame
//! window's with it ([`Cross`], formed lag by lag as an iteration needs them).

use super::*;

/// The template moments of the spline path: with `c'` the padded template's coefficients
/// less the template's mean and `c'_o` them displaced by the lag `o = (ox, oy)` (`-2..=2`
/// each) over the template's pixels, `s[o] = sum c'_o` and `c[o][o'] = sum c'_o c'_o'`.
/// The shifted template is `T_s - m = sum_o w_o c'_o` with the shift's separable spline
/// weights `w` (they sum to one; its slopes' weights sum to zero), so every sum of an
/// iteration (the error weighted by the shifted template's slopes and the ZNCC) is a
/// quadratic form in the weights: an iteration costs a few hundred multiply-adds instead of
/// passes over the window.
#[derive(Debug, Clone, Copy)]
pub(super) struct Moments {
    pub(super) s: [f32; LAGS * LAGS],
    pub(super) c: [f32; LAGS * LAGS * LAGS * LAGS],
}

impl Moments {
    pub(super) const ZERO: Moments = Moments {
        s: [0.0; LAGS * LAGS],
        c: [0.0; LAGS * LAGS * LAGS * LAGS],
    };

    /// The moments of the `tw x th` template whose padded coefficients (`tw + 2 margin`
    /// wide, mean removed) are `coef`. Each row's sums are formed apart and then added
    /// (rounding grows with the row, not the window).
    pub(super) fn of(coef: &[f32], (tw, th): (usize, usize)) -> Moments {
        let mut out = Moments::ZERO;
        let pw = tw + 2 * SPLINE_MARGIN;
        let first = SPLINE_MARGIN - LAGS / 2;
        // the template's row `j` at the vertical lag `oy`, from its horizontal lag 0
        let row = |j: usize, oy: usize| -> &[f32] {
            let start = (j + first + oy) * pw + first;
            coef.get(start..start + tw + LAGS - 1).unwrap_or(&[])
        };
        for oy in 0..LAGS {
            for oy2 in oy..LAGS {
                let mut c = [[0.0f32; LAGS]; LAGS];
                let mut s = [0.0f32; LAGS];
                for j in 0..th {
                    let (r1, r2) = (row(j, oy), row(j, oy2));
                    for (ox, cx) in c.iter_mut().enumerate() {
                        let a = r1.get(ox..ox + tw).unwrap_or(&[]);
                        // on one row of lags the products are symmetric: the upper half
                        // only (the same products in the same order), mirrored below
                        let from = if oy2 == oy { ox } else { 0 };
                        for (ox2, cxy) in cx.iter_mut().enumerate().skip(from) {
                            let b = r2.get(ox2..ox2 + tw).unwrap_or(&[]);
                            let mut d = 0.0f32;
                            for (u, v) in a.iter().zip(b) {
                                d += u * v;
                            }
                            *cxy += d;
                        }
                        if oy2 == oy {
                            s[ox] += a.iter().sum::<f32>();
                        }
                    }
                }
                if oy2 == oy {
                    let upper = c;
                    for (ox, cx) in c.iter_mut().enumerate() {
                        for (ox2, v) in cx.iter_mut().enumerate().take(ox) {
                            *v = upper[ox2][ox];
                        }
                    }
                }
                for (ox, cx) in c.iter().enumerate() {
                    for (ox2, &v) in cx.iter().enumerate() {
                        let (i1, i2) = (oy * LAGS + ox, oy2 * LAGS + ox2);
                        if let Some(o) = out.c.get_mut(i1 * LAGS * LAGS + i2) {
                            *o = v;
                        }
                        if let Some(o) = out.c.get_mut(i2 * LAGS * LAGS + i1) {
                            *o = v;
                        }
                    }
                    if oy2 == oy {
                        if let (Some(o), Some(&v)) = (out.s.get_mut(oy * LAGS + ox), s.get(ox)) {
                            *o = v;
                        }
                    }
                }
            }
        }
        out
    }
}

/// The frame window's moments with the template (spline path): with `g'` the window less
/// the template's mean, `a[o] = sum g' c'_o` (see [`Moments`]), `sum g'` and the sum of the
/// squares about its mean.
/// A cross moment is formed when an iteration first needs it: the 4 x 4 lags of the shift's
/// taps (3 x 3 at a whole-pixel shift, where the fourth tap's weights are zero), and one more
/// column or row of lags when the shift's sign changes.
#[derive(Debug, Clone, Copy)]
pub(super) struct Cross {
    pub(super) a: [f32; LAGS * LAGS],
    /// Bit `oy * LAGS + ox` set: the cross moment of the lag `(ox, oy)` is formed.
    pub(super) formed: u32,
    /// `sum g'` and `sum (g' - mean g')^2` over the window.
    pub(super) sum: f32,
    pub(super) var: f32,
    /// The window is stored as integers `G` with `g' = scale G + offset` (see
    /// `LkTracker::smooth_window`): `a[o] = scale sum G c'_o + offset s[o]`.
    pub(super) scale: f32,
    pub(super) offset: f32,
}

/// The window's row stride in `LkTracker::g`: its width rounded up to four pixels (the pad is
/// zero), so that the cross moments' kernel runs over whole groups of four.
pub(super) const fn window_stride(tw: usize) -> usize {
    (tw + 3) & !3
}

impl Cross {
    pub(super) const ZERO: Cross = Cross {
        a: [0.0; LAGS * LAGS],
        formed: 0,
        sum: 0.0,
        var: 0.0,
        scale: 1.0,
        offset: 0.0,
    };

    /// A window of `n` integers `G = v - mean` (`v` the smoothed pixels on the integer scale,
    /// `scale` back to the template's) whose sum is `sum` and sum of squares `sq` (exact), and
    /// `t_mean` the template's mean: no cross moment formed yet.
    pub(super) fn window(sum: i64, sq: i128, mean: i32, scale: f32, t_mean: f32, n: f32) -> Cross {
        // sum (G - mean G)^2 in f64 (relative rounding 1e-16)
        let (s1, s2) = (sum as f64, sq as f64);
        let var = (s2 - s1 * s1 / f64::from(n)) * f64::from(scale) * f64::from(scale);
        let offset = mean as f32 * scale - t_mean;
        Cross {
            sum: scale * s1 as f32 + n * offset,
            var: var.max(0.0) as f32,
            scale,
            offset,
            ..Cross::ZERO
        }
    }

    /// Forms the cross moments of the lags `xs x ys` (indices `0..LAGS`, at most four each)
    /// not formed yet, from the window `g` (rows [`window_stride`] apart) and the padded
    /// coefficients `coef` of a `tw x th` template: per vertical lag, each run of missing
    /// horizontal lags in one pass over the window.
    pub(super) fn need(
        &mut self,
        xs: core::ops::Range<usize>,
        ys: core::ops::Range<usize>,
        (g, coef, s): (&[f32], &[f32], &[f32; LAGS * LAGS]),
        (tw, th): (usize, usize),
    ) {
        let all = ((1u32 << xs.len()) - 1) << xs.start;
        let missing = |formed: u32, oy: usize| !(formed >> (oy * LAGS)) & all;
        let mut oy = ys.start;
        while oy < ys.end {
            let m = missing(self.formed, oy);
            let mut end = oy + 1;
            while end < ys.end && missing(self.formed, end) == m {
                end += 1;
            }
            let (data, size) = ((g, coef, s), (tw, th));
            if m.count_ones() == 1 && end - oy > 1 {
                // one horizontal lag missing from several vertical lags (the shift's sign
                // changed along x): that column in one pass over the window
                let at = (m.trailing_zeros() as usize, oy);
                match end - oy {
                    2 => self.column::<2>(at, data, size),
                    3 => self.column::<3>(at, data, size),
                    _ => self.column::<4>(at, data, size),
                }
                oy = end;
                continue;
            }
            for oy in oy..end {
                // each run of missing horizontal lags of this vertical lag in one pass
                let mut bits = m;
                while bits != 0 {
                    let lo = bits.trailing_zeros() as usize;
                    let len = (!(bits >> lo)).trailing_zeros() as usize;
                    let at = (lo, oy);
                    match len {
                        1 => self.row::<1>(at, data, size),
                        2 => self.row::<2>(at, data, size),
                        3 => self.row::<3>(at, data, size),
                        _ => self.row::<4>(at, data, size),
                    }
                    bits &= !(((1u32 << len) - 1) << lo);
                }
            }
            oy = end;
        }
    }

    /// Forms the cross moments of the horizontal lag `lx` at the `V` vertical lags from `ly`
    /// (at most four) in one pass over the window (the backend's `column_sums`).
    #[inline(never)]
    pub(super) fn column<const V: usize>(
        &mut self,
        (lx, ly): (usize, usize),
        (g, coef, s): (&[f32], &[f32], &[f32; LAGS * LAGS]),
        (tw, th): (usize, usize),
    ) {
        let pw = tw + 2 * SPLINE_MARGIN;
        let first = SPLINE_MARGIN - LAGS / 2;
        let start = (first + ly) * pw + first + lx;
        let c = coef.get(start..).unwrap_or(&[]);
        let a = kernels::column_sums::<V>(g, window_stride(tw), c, pw, th);
        let (scale, offset) = (self.scale, self.offset);
        for (v, av) in a.iter().enumerate() {
            let at = (ly + v) * LAGS + lx;
            if let (Some(o), Some(s)) = (self.a.get_mut(at), s.get(at)) {
                *o = scale * av + offset * s;
            }
            self.formed |= 1 << at;
        }
    }

    /// Forms the cross moments of the `L` horizontal lags from `lx` at the vertical lag `oy`
    /// in one pass over the window (the backend's `lag_sums`).
    #[inline(never)]
    pub(super) fn row<const L: usize>(
        &mut self,
        (lx, oy): (usize, usize),
        (g, coef, s): (&[f32], &[f32], &[f32; LAGS * LAGS]),
        (tw, th): (usize, usize),
    ) {
        let pw = tw + 2 * SPLINE_MARGIN;
        let first = SPLINE_MARGIN - LAGS / 2;
        let start = (first + oy) * pw + first + lx;
        let c = coef.get(start..).unwrap_or(&[]);
        let a = kernels::lag_sums::<L>(g, window_stride(tw), c, pw, th);
        let at = oy * LAGS + lx;
        let (scale, offset) = (self.scale, self.offset);
        if let (Some(out), Some(s)) = (self.a.get_mut(at..at + L), s.get(at..at + L)) {
            for ((o, v), s) in out.iter_mut().zip(a).zip(s) {
                *o = scale * v + offset * s;
            }
        }
        self.formed |= ((1u32 << L) - 1) << at;
    }
}
