//! The LK kernels for the Cortex-M4 (and the host's tests). Cross moments: per window row, a
//! tree of eight products per lag added to the row's sum, the window's sum of the rows' sums.
//! The M4's FPU is scalar: eight pixels a step reuse each loaded value for every lag, which
//! costs fewer instructions there than lanes would (3.7 instructions per multiply-add). The
//! `[1 2 1]` smoothing in one rolling pass; the clip count reads the mask only at clipped
//! pixels. Only slices come in; this backend knows nothing of its caller.

use crate::centroid::Pixel;

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
    let mut a = [0.0f32; V];
    // the coefficients' rows from the lag, the V of window row j slid down one per row
    let mut rows = c.chunks(pw.max(1));
    let mut c: [&[f32]; V] = [&[]; V];
    for cv in c.iter_mut().skip(1) {
        *cv = rows.next().unwrap_or(&[]);
    }
    for row in g.chunks_exact(gs.max(4)).take(th) {
        c.rotate_left(1);
        if let Some(last) = c.last_mut() {
            *last = rows.next().unwrap_or(&[]);
        }
        for (o, v) in a.iter_mut().zip(column_dots::<V>(row, &c)) {
            *o += v;
        }
    }
    a
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
    let mut a = [0.0f32; L];
    for (g, c) in g.chunks_exact(gs.max(4)).take(th).zip(c.chunks(pw.max(1))) {
        let r = lag_dots::<L>(g, c);
        for (o, v) in a.iter_mut().zip(r) {
            *o += v;
        }
    }
    a
}

/// `r[v] = sum_i g[i] c[v][i]` for `V` rows of coefficients as long as `g` (a whole number
/// of groups of four), eight pixels at a time (one row's sums: rounding grows with the row,
/// not the window). A shorter `c[v]` (never, for the rows [`column_sums`] passes) ends its
/// sum.
#[inline(always)]
fn column_dots<const V: usize>(g: &[f32], c: &[&[f32]; V]) -> [f32; V] {
    let mut r = [0.0f32; V];
    let mut eights = g.chunks_exact(8);
    for (n, gw) in (&mut eights).enumerate() {
        let &[g0, g1, g2, g3, g4, g5, g6, g7] = gw else {
            return r;
        };
        for (rv, cv) in r.iter_mut().zip(c) {
            if let Some(&[c0, c1, c2, c3, c4, c5, c6, c7]) = cv.get(8 * n..8 * n + 8) {
                *rv += (g0 * c0 + g1 * c1 + g2 * c2 + g3 * c3)
                    + (g4 * c4 + g5 * c5 + g6 * c6 + g7 * c7);
            }
        }
    }
    let i = g.len() - eights.remainder().len();
    if let &[g0, g1, g2, g3] = eights.remainder() {
        for (rv, cv) in r.iter_mut().zip(c) {
            if let Some(&[c0, c1, c2, c3]) = cv.get(i..i + 4) {
                *rv += g0 * c0 + g1 * c1 + g2 * c2 + g3 * c3;
            }
        }
    }
    r
}

/// `sum_i g[i] c[i + k]` for the lags `k = 0..L` (`L <= 4`; `g` a whole number of groups of
/// four, `c` at least `L - 1` longer), eight pixels at a time so that the products reuse the
/// loaded values (one row's sums: rounding grows with the row, not the window). A shorter
/// `c` (never, for the rows [`lag_sums`] passes) ends the sums.
#[inline(always)]
fn lag_dots<const L: usize>(g: &[f32], c: &[f32]) -> [f32; L] {
    let mut r = [0.0f32; L];
    let mut eights = g.chunks_exact(8);
    for (n, gw) in (&mut eights).enumerate() {
        let (&[g0, g1, g2, g3, g4, g5, g6, g7], Some(cw)) = (gw, c.get(8 * n..8 * n + 7 + L))
        else {
            return r;
        };
        for (k, rk) in r.iter_mut().enumerate() {
            if let Some(&[c0, c1, c2, c3, c4, c5, c6, c7]) = cw.get(k..k + 8) {
                *rk += (g0 * c0 + g1 * c1 + g2 * c2 + g3 * c3)
                    + (g4 * c4 + g5 * c5 + g6 * c6 + g7 * c7);
            }
        }
    }
    // a last group of four
    let i = g.len() - eights.remainder().len();
    if let (&[g0, g1, g2, g3], Some(cw)) = (eights.remainder(), c.get(i..i + 3 + L)) {
        for (k, rk) in r.iter_mut().enumerate() {
            if let Some(&[c0, c1, c2, c3]) = cw.get(k..k + 4) {
                *rk += g0 * c0 + g1 * c1 + g2 * c2 + g3 * c3;
            }
        }
    }
    r
}

/// One window row smoothed by `[1 2 1]` down the columns of the source rows `a`, `b`, `c`
/// (each `out.len() + 2` pixels) and then along the row, stored as `v - mean`; returns the
/// row's sum and sum of squares of the stored values and the largest pixel of `b`, or `None`
/// (and nothing stored) when the rows are not that long or the row is longer than 2047
/// pixels (its sum then might not fit the `i32` kept here: values are below 2^20).
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
    let mut top = 0u16;
    let mut cols = a.iter().zip(b).zip(c).map(|((&a, &b), &c)| {
        let b = b.into();
        top = top.max(b);
        u32::from(a.into()) + 2 * u32::from(b) + u32::from(c.into())
    });
    let (Some(mut p0), Some(mut p1)) = (cols.next(), cols.next()) else {
        return None;
    };
    let (mut rs, mut sq) = (0i32, 0i64);
    for (o, c2) in out.iter_mut().zip(cols) {
        let d = (p0 + 2 * p1 + c2) as i32 - mean;
        *o = d as f32;
        rs += d;
        sq += i64::from(d) * i64::from(d);
        (p0, p1) = (p1, c2);
    }
    Some((i64::from(rs), sq, top))
}

/// Pixels of a window row (`row`) at or above `sat` where the template is dark around them
/// (`dark`, the template's row of the tracker's mask): the mask read only at the (few)
/// clipped pixels.
#[inline(always)]
pub(super) fn newly_clipped<P: Pixel>(row: &[P], dark: &[bool], sat: u16) -> u32 {
    let mut n = 0;
    for (i, &v) in row.iter().enumerate() {
        if v.into() >= sat && dark.get(i).is_some_and(|&d| d) {
            n += 1;
        }
    }
    n
}

/// No whole-window smoothing here: the M4 smooths row by row ([`smooth_row3`]), which costs
/// it fewer instructions (no vector lanes to fill). Always `None`.
#[inline(always)]
pub(super) fn smooth_window3_bytes(
    _src: &[u8],
    _stride: usize,
    _size: (usize, usize),
    _g: (&mut [f32], usize),
    _mean: i32,
) -> Option<(i64, i64, u16)> {
    None
}

/// No whole-window clip count here (see [`smooth_window3_bytes`]). Always `None`.
#[inline(always)]
pub(super) fn clipped_window_bytes(
    _src: &[u8],
    _stride: usize,
    _size: (usize, usize),
    _dark: &[bool],
    _sat: u16,
) -> Option<u32> {
    None
}

/// The frame's sums of a search's ZNCC at one offset: `[sum vf, sum vf^2, sum vf vt]` with
/// `vf = f - m`, `vt = t - m`, over the template `t` (rows of `tw`) and the frame window's
/// `rows` (each `tw` long).
#[inline(always)]
pub(super) fn zncc_sums<'a, P: Pixel>(
    t: &[f32],
    tw: usize,
    rows: impl Iterator<Item = &'a [P]>,
    m: f32,
) -> [f32; 3] {
    let (mut a, mut b, mut c) = (0.0f32, 0.0f32, 0.0f32);
    for (t, f) in t.chunks_exact(tw.max(1)).zip(rows) {
        for (t, f) in t.iter().zip(f) {
            let vt = t - m;
            let vf = f32::from((*f).into()) - m;
            a += vf;
            b += vf * vf;
            c += vf * vt;
        }
    }
    [a, b, c]
}
