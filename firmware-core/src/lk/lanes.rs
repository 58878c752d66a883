//! The LK kernels for targets with SIMD registers (x86-64, AArch64), written with the `wide`
//! crate's safe vector types so that the compiler's choices do not decide the layout. Cross
//! moments: each lag's products accumulated in eight lanes (two registers of four) across the
//! whole window, the lanes added once at the end; the same sums as the M4's kernels, in
//! another order (f32 rounding differs in the last bits). The window's `[1 2 1]` smoothing:
//! an 8-bit window inside the frame in one pass of eight-column strips walked down it
//! ([`smooth_window3_bytes`]), with its clip count sixteen pixels at a time; other windows
//! row by row from the nine source pixels, eight 8-bit pixels at a time in 16-bit lanes (other
//! pixel types in a loop the compiler vectorises), instead of the M4's rolling pass. The
//! iterations' template forms four lags per vector ([`tap_forms`]), exactly as the M4's scalar
//! forms.
//! Only slices come in; this backend knows nothing of its caller.

use crate::centroid::Pixel;
use wide::f32x4;

/// The eight lanes of an accumulator added, pairwise.
#[inline(always)]
fn total([a0, a1, a2, a3, a4, a5, a6, a7]: [f32; 8]) -> f32 {
    ((a0 + a4) + (a2 + a6)) + ((a1 + a5) + (a3 + a7))
}

/// The four values of `s` from `at` in one register, if there are that many.
#[inline(always)]
fn four(s: &[f32], at: usize) -> Option<f32x4> {
    s.get(at..at + 4)
        .and_then(|s| <[f32; 4]>::try_from(s).ok())
        .map(f32x4::from)
}

/// [`total`] of each accumulator's eight lanes, held as two registers (`lo`, `hi`).
#[inline(always)]
fn totals<const K: usize>(lo: [f32x4; K], hi: [f32x4; K]) -> [f32; K] {
    let mut out = [0.0; K];
    for ((o, lo), hi) in out.iter_mut().zip(lo).zip(hi) {
        let ([a0, a1, a2, a3], [a4, a5, a6, a7]) = (lo.to_array(), hi.to_array());
        *o = total([a0, a1, a2, a3, a4, a5, a6, a7]);
    }
    out
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
    // lanes 0..4 and 4..8 of each lag's accumulator
    let (mut lo, mut hi) = ([f32x4::ZERO; V], [f32x4::ZERO; V]);
    let gs = gs.max(4);
    for (j, row) in g.chunks_exact(gs).take(th).enumerate() {
        for (v, (lo, hi)) in lo.iter_mut().zip(hi.iter_mut()).enumerate() {
            let start = (j + v) * pw;
            let Some(cr) = c.get(start..start + gs) else {
                continue;
            };
            let mut n = 0;
            while let (Some(g0), Some(g1), Some(c0), Some(c1)) =
                (four(row, n), four(row, n + 4), four(cr, n), four(cr, n + 4))
            {
                *lo += g0 * c0;
                *hi += g1 * c1;
                n += 8;
            }
            if let (Some(g0), Some(c0)) = (four(row, n), four(cr, n)) {
                *lo += g0 * c0;
            }
        }
    }
    totals(lo, hi)
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
    // lanes 0..4 and 4..8 of each lag's accumulator
    let (mut lo, mut hi) = ([f32x4::ZERO; L], [f32x4::ZERO; L]);
    let gs = gs.max(4);
    for (j, row) in g.chunks_exact(gs).take(th).enumerate() {
        let start = j * pw;
        let Some(cr) = c.get(start..start + gs + L - 1) else {
            break;
        };
        let mut n = 0;
        // the step's coefficients for all the lags in one slice of a known length: one bound
        // check per step
        while let (Some(g0), Some(g1), Some(cs)) =
            (four(row, n), four(row, n + 4), cr.get(n..n + 7 + L))
        {
            for (k, (lo, hi)) in lo.iter_mut().zip(hi.iter_mut()).enumerate() {
                if let (Some(c0), Some(c1)) = (four(cs, k), four(cs, k + 4)) {
                    *lo += g0 * c0;
                    *hi += g1 * c1;
                }
            }
            n += 8;
        }
        if let Some(g0) = four(row, n) {
            for (k, lo) in lo.iter_mut().enumerate() {
                if let Some(c0) = four(cr, n + k) {
                    *lo += g0 * c0;
                }
            }
        }
    }
    totals(lo, hi)
}

/// One window row smoothed by `[1 2 1]` down the columns of the source rows `a`, `b`, `c`
/// (each `out.len() + 2` pixels) and then along the row, stored as `v - mean`; returns the
/// row's sum and sum of squares of the stored values and the largest pixel of `b`, or `None`
/// (and nothing stored) when the rows are not that long or the row is longer than 2047
/// pixels. Each value from the nine source pixels around it, in one pass (a buffer of column
/// sums between two passes measured slower). 8-bit pixels: see [`smooth_bytes`]; others: a
/// loop the compiler vectorises, then the squares of the stored values in four `f64` lanes.
/// Exact: a value is below 2^20 in magnitude, so its square below 2^40 and a row's sum of
/// squares below 2^51, exact in `f64`; the sum in `i32`.
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
    if let (Some(a), Some(b), Some(c)) = (P::bytes(a), P::bytes(b), P::bytes(c)) {
        // 8-bit pixels and a mean on their scale (16 x 255): 16-bit lanes hold every value
        if n >= 8 && (0..=BYTE_MAX).contains(&mean) {
            let (rs, sq) = smooth_bytes(a, b, c, out, mean);
            return Some((rs, sq, top));
        }
    }
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

/// The largest `[1 2 1]`-smoothed 8-bit value, 16 x 255.
const BYTE_MAX: i32 = 16 * 255;

/// [`smooth_row3`]'s values for 8-bit rows (`n = out.len() >= 8`, the rows `n + 2` long,
/// `0 <= mean <= 16 x 255`), eight at a time in 16-bit lanes (a value and its difference from
/// the mean are at most 16 x 255 in magnitude); returns the sum and the sum of squares of the
/// stored values, in integers (the squares in pairs of 32-bit lanes, `pmaddwd`, moved to `i64`
/// every 32 steps: a lane then holds at most 64 x 4080^2 < 2^31). When `n` is not a multiple
/// of eight the last eight overlap the ones before: the same values written again, counted
/// once.
#[inline(always)]
fn smooth_bytes(a: &[u8], b: &[u8], c: &[u8], out: &mut [f32], mean: i32) -> (i64, i64) {
    use wide::{i16x8, i32x4, i32x8, u8x16};
    let n = out.len();
    // the eight pixels of `r` from `at` as 16-bit lanes
    let px = |r: &[u8], at: usize| -> i16x8 {
        let mut v = [0u8; 16];
        if let (Some(d), Some(s)) = (v.get_mut(..8), r.get(at..at + 8)) {
            d.copy_from_slice(s);
        }
        i16x8::from_u8x16_low(u8x16::from(v))
    };
    let row = |r: &[u8], at: usize| px(r, at) + (px(r, at + 1) << 1) + px(r, at + 2);
    let m = i16x8::splat(mean as i16);
    // the eight values from `at`, stored; returned as differences from the mean, in 16 and in
    // 32-bit lanes
    let block = |at: usize, out: &mut [f32]| -> (i16x8, i32x8) {
        let d = row(a, at) + (row(b, at) << 1) + row(c, at) - m;
        let d32 = i32x8::from_i16x8(d);
        if let Some(o) = out.get_mut(at..at + 8) {
            o.copy_from_slice(&d32.round_float().to_array());
        }
        (d, d32)
    };
    // the sum in 32-bit lanes (at most 256 x 4080 each), the squares as above
    let (mut sum, mut sq, mut total) = (i32x8::splat(0), i32x4::splat(0), 0i64);
    let flush = |sq: &mut i32x4, total: &mut i64| {
        *total += sq.to_array().iter().map(|&v| i64::from(v)).sum::<i64>();
        *sq = i32x4::splat(0);
    };
    let mut at = 0;
    let mut steps = 0u32;
    while at + 8 <= n {
        let (d, d32) = block(at, out);
        sum += d32;
        sq += d.dot(d);
        at += 8;
        steps += 1;
        if steps % 32 == 0 {
            flush(&mut sq, &mut total);
        }
    }
    if at < n {
        // the last n - at values from a block ending at n: its first 8 - (n - at) lanes were
        // counted already
        let skip = 8 - (n - at);
        let keep = core::array::from_fn::<i16, 8, _>(|i| if i < skip { 0 } else { -1 });
        let (d, _) = block(n - 8, out);
        let d = d & i16x8::from(keep);
        sum += i32x8::from_i16x8(d);
        sq += d.dot(d);
    }
    flush(&mut sq, &mut total);
    (i64::from(sum.reduce_add()), total)
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

/// The `tw x th` window smoothed by `[1 2 1]` down and along (as [`smooth_row3`], the same
/// exact integers), from 8-bit pixels: `src` from the top-left of the source (one pixel up and
/// left of the window), rows `stride` apart. Each strip of eight columns is walked down the
/// window, the two source rows' horizontal sums before it kept in registers, so a source
/// row's pixels are read three times (not nine) and nothing is set up per row. Values are
/// stored as `v - mean` in `g` (rows `gs` apart, the pad beyond `tw` zeroed). Returns the
/// sum and the sum of squares of the stored values and the largest window pixel (margins
/// aside), or `None` (nothing stored) when `tw < 8`, the rows are closer than the source is
/// wide, the mean is off the 8-bit scale or a slice is too short.
pub(super) fn smooth_window3_bytes(
    src: &[u8],
    stride: usize,
    (tw, th): (usize, usize),
    (g, gs): (&mut [f32], usize),
    mean: i32,
) -> Option<(i64, i64, u16)> {
    use wide::{i16x8, i32x4, i32x8, u8x16};
    let rows_needed = (th + 1).checked_mul(stride)?.checked_add(tw + 2)?;
    if tw < 8
        || th == 0
        || stride < tw + 2
        || gs < tw
        || !(0..=BYTE_MAX).contains(&mean)
        || src.len() < rows_needed
        || g.len() < th.checked_mul(gs)?
    {
        return None;
    }
    // the horizontal [1 2 1] of the ten pixels from `at` of row `r`, and their middle eight
    let hrow = |r: &[u8]| -> (i16x8, i16x8) {
        let s = r.get(..10).unwrap_or(&[]);
        let px = |k: usize| {
            let mut v = [0u8; 16];
            if let (Some(d), Some(s)) = (v.get_mut(..8), s.get(k..k + 8)) {
                d.copy_from_slice(s);
            }
            i16x8::from_u8x16_low(u8x16::from(v))
        };
        let (p0, p1, p2) = (px(0), px(1), px(2));
        (p0 + (p1 << 1) + p2, p1)
    };
    let m = i16x8::splat(mean as i16);
    let ones = i16x8::splat(1);
    let (mut total, mut total_sq) = (0i64, 0i64);
    let mut top = i16x8::splat(0);
    let last = tw - 8;
    let mut at = 0;
    loop {
        let at0 = at.min(last);
        // lanes already counted by the strip before (the last strip overlaps it); opaque, so
        // the mask is made once per strip, not per row
        let skip = at - at0;
        let keep = core::hint::black_box(i16x8::from(core::array::from_fn::<i16, 8, _>(|i| {
            if i < skip {
                0
            } else {
                -1
            }
        })));
        let col = src.get(at0..).unwrap_or(&[]);
        let mut rows = col.chunks(stride);
        let (mut h0, _) = hrow(rows.next().unwrap_or(&[]));
        let (mut h1, mut c1) = hrow(rows.next().unwrap_or(&[]));
        let (mut sum, mut sq) = (i32x4::splat(0), i32x4::splat(0));
        for (j, (r, out)) in rows.zip(g.chunks_exact_mut(gs)).take(th).enumerate() {
            let (h2, c2) = hrow(r);
            let d = h0 + (h1 << 1) + h2 - m;
            if let Some(o) = out.get_mut(at0..at0 + 8) {
                o.copy_from_slice(&i32x8::from_i16x8(d).round_float().to_array());
            }
            let d = d & keep;
            top = top.max(c1 & keep);
            sum += d.dot(ones);
            sq += d.dot(d);
            // a lane holds at most 32 x 2 x 4080^2 < 2^31
            if j % 32 == 31 {
                total_sq += sq.to_array().iter().map(|&v| i64::from(v)).sum::<i64>();
                sq = i32x4::splat(0);
            }
            (h0, h1, c1) = (h1, h2, c2);
        }
        total += sum.to_array().iter().map(|&v| i64::from(v)).sum::<i64>();
        total_sq += sq.to_array().iter().map(|&v| i64::from(v)).sum::<i64>();
        if at0 == last {
            break;
        }
        at += 8;
    }
    for row in g.chunks_exact_mut(gs).take(th) {
        if let Some(pad) = row.get_mut(tw..) {
            pad.fill(0.0);
        }
    }
    Some((total, total_sq, top.reduce_max().max(0) as u16))
}

/// [`newly_clipped`] over a whole `tw x th` window of 8-bit pixels (`src` from the window's
/// top-left, rows `stride` apart; `dark` the template's mask, rows `tw` apart), sixteen
/// pixels at a time; `None` when a slice is too short or `tw < 16`.
pub(super) fn clipped_window_bytes(
    src: &[u8],
    stride: usize,
    (tw, th): (usize, usize),
    dark: &[bool],
    sat: u16,
) -> Option<u32> {
    use wide::u8x16;
    if !(16..=4080).contains(&tw)
        || th == 0
        || src.len() < (th - 1).checked_mul(stride)?.checked_add(tw)?
    {
        return None;
    }
    if dark.len() < th.checked_mul(tw)? {
        return None;
    }
    if sat > 255 {
        return Some(0);
    }
    let s = u8x16::splat(sat as u8);
    let sixteen = |r: &[u8], at: usize| -> u8x16 {
        let mut v = [0u8; 16];
        if let Some(x) = r.get(at..at + 16) {
            v.copy_from_slice(x);
        }
        u8x16::from(v)
    };
    let marks = |d: &[bool], at: usize| -> u8x16 {
        let mut v = [0u8; 16];
        if let Some(x) = d.get(at..at + 16) {
            for (o, &b) in v.iter_mut().zip(x) {
                *o = u8::from(b);
            }
        }
        u8x16::from(v)
    };
    let last = tw - 16;
    let skip = (tw % 16) as u8;
    // the last block overlaps the one before by 16 - tw % 16 lanes: those are not counted
    let tail = u8x16::from(core::array::from_fn::<u8, 16, _>(|i| {
        if skip != 0 && (i as u8) < 16 - skip {
            0
        } else {
            1
        }
    }));
    let (mut acc, mut total, mut steps) = (u8x16::splat(0), 0u32, 0u32);
    let blocks = tw.div_ceil(16) as u32;
    for j in 0..th {
        // a byte lane holds at most one count per block: flushed before it could pass 255
        if steps + blocks > 255 {
            total += acc.to_array().iter().map(|&v| u32::from(v)).sum::<u32>();
            acc = u8x16::splat(0);
            steps = 0;
        }
        steps += blocks;
        let (r, d) = (
            src.get(j * stride..j * stride + tw)?,
            dark.get(j * tw..j * tw + tw)?,
        );
        let mut at = 0;
        while at < last {
            let v = sixteen(r, at);
            acc += v.max(s).cmp_eq(v) & marks(d, at);
            at += 16;
        }
        let v = sixteen(r, last);
        acc += v.max(s).cmp_eq(v) & marks(d, last) & tail;
    }
    Some(total + acc.to_array().iter().map(|&v| u32::from(v)).sum::<u32>())
}

/// The template's quadratic forms of one iteration, four lags at a time: for the 16 lags
/// `i = (ly + l) lags + lx + k` (`n = 4 l + k`), `sum_l' wy[l'] (c[i][j0] wx[0] + c[i][j1]
/// wx[1] + c[i][j2] wx[2] + c[i][j3] wx[3])` with `j_m = (ly + l') lags + lx + m`, `c` the
/// `lags^2 x lags^2` moments (row-major). `c` is symmetric (exactly: its mirrored halves are
/// copies and its diagonal blocks the same products in the same order), so `c[i][j] =
/// c[j][i]` and the four lags `k` of one `l` are neighbours in row `j`: one register, each
/// lane doing the scalar form's operations in its order (the same `f32` results).
#[inline(always)]
pub(super) fn tap_forms(
    c: &[f32],
    lags: usize,
    (lx, ly): (usize, usize),
    wx: [f32; 4],
    wy: [f32; 4],
) -> [f32; 16] {
    let mut out = [0.0f32; 16];
    let w = wx.map(f32x4::splat);
    for (l, o) in out.chunks_exact_mut(4).enumerate() {
        let i0 = (ly + l) * lags + lx;
        let mut cu = f32x4::ZERO;
        for (l2, &wyl) in wy.iter().enumerate() {
            let j0 = (ly + l2) * lags + lx;
            let col = |m: usize| four(c, (j0 + m) * lags * lags + i0).unwrap_or(f32x4::ZERO);
            let [w0, w1, w2, w3] = w;
            cu += f32x4::splat(wyl) * (col(0) * w0 + col(1) * w1 + col(2) * w2 + col(3) * w3);
        }
        o.copy_from_slice(&cu.to_array());
    }
    out
}

/// The frame's sums of a search's ZNCC at one offset: `[sum vf, sum vf^2, sum vf vt]` with
/// `vf = f - m`, `vt = t - m`, over the template `t` (rows of `tw`) and the frame window's
/// `rows` (each `tw` long), in four lanes carried across the rows and added once at the end.
#[inline(always)]
pub(super) fn zncc_sums<'a, P: Pixel>(
    t: &[f32],
    tw: usize,
    rows: impl Iterator<Item = &'a [P]>,
    m: f32,
) -> [f32; 3] {
    let (mut sf, mut sff, mut sft) = (f32x4::ZERO, f32x4::ZERO, f32x4::ZERO);
    let (mut a, mut b, mut c) = (0.0f32, 0.0f32, 0.0f32);
    let mv = f32x4::splat(m);
    for (t, f) in t.chunks_exact(tw.max(1)).zip(rows) {
        let (tc, fc) = (t.chunks_exact(4), f.chunks_exact(4));
        let (tr, fr) = (tc.remainder(), fc.remainder());
        for (t4, f4) in tc.zip(fc) {
            let (Ok(t4), Ok([f0, f1, f2, f3])) = (<[f32; 4]>::try_from(t4), <[P; 4]>::try_from(f4))
            else {
                continue;
            };
            let vt = f32x4::from(t4) - mv;
            let vf = f32x4::from([f0, f1, f2, f3].map(|p| f32::from(p.into()))) - mv;
            sf += vf;
            sff += vf * vf;
            sft += vf * vt;
        }
        for (t, f) in tr.iter().zip(fr) {
            let vt = t - m;
            let vf = f32::from((*f).into()) - m;
            a += vf;
            b += vf * vf;
            c += vf * vt;
        }
    }
    let sum = |v: f32x4| {
        let [x0, x1, x2, x3] = v.to_array();
        (x0 + x2) + (x1 + x3)
    };
    [a + sum(sf), b + sum(sff), c + sum(sft)]
}
