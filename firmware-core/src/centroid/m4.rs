//! 32-bit ARM (Cortex-M4) versions of the single-target row kernels: four pixels per word
//! load, SWAR byte compares and per-block sums, in safe Rust. The binary 8-bit kernel is
//! described here; the weighted 8-bit one adds SWAR weights ([`weights`]) and 16-bit lane sums
//! ([`block_weighted`]); the 16-bit kernels use the same block skip around the portable
//! per-pixel pass ([`row_sparse`]).
//!
//! Cortex-M has no vector unit LLVM can target from safe code (the DSP extension's `USUB8`/`SEL`
//! are reachable only through unstable intrinsics or `asm!`, and the crate forbids `unsafe`), so
//! the kernel works in plain 32-bit registers ("SIMD within a register"):
//!
//! * **compare**: with `H = 0x80808080` and `t < 128`, the top bit of each byte of
//!   `((w | H) - (t + 1) * 0x01010101) | w` is set exactly for the bytes `> t` (setting the top
//!   bit keeps every byte `>= 128 > t + 1 - 1`, so no byte borrows from its neighbour); for
//!   `t >= 128`, `((w | H) - (t - 127) * 0x01010101) & w`. Shifted down and masked, that is a
//!   word `m` of four 0/1 bytes: 4 instructions (ORR, SUB, ORR/AND, AND with shifted operand).
//! * **sums**: per block of 16 words (64 pixels) `S += m` and `T += S` bytewise (`S <= 16`,
//!   `T <= 136`, no carries); then `count = sum S_i`, and since `T_i = sum_j (16 - j) m_ji`,
//!   `sum_x = x0 count + 4 (16 count - sum T_i) + sum i S_i`, each horizontal sum one multiply.
//! * **skip**: a block whose 16 words OR-ed together have no byte above `t` has no pixel above
//!   `t` (the OR is at least every byte): it costs one OR per word and one compare.
//!
//! The row maximum is computed exactly over the blocks that have a pixel above `t` (one more
//! SWAR compare per word against the running maximum, a scalar pass only when it rises),
//! which is all [`Centroider`](super::Centroider) reads it for (its saturation flag needs the
//! largest value of a row with a hit, and every pixel above `t` is in such a block). For a row
//! without any pixel above `t` the returned `max` is 0 on this path (documented on
//! [`row_binary_u8`](super::row_binary_u8)).

use super::sums::{Level, RowSums, WindowSums};
use super::MAX_DIM;

const H: u32 = 0x8080_8080;
const ONES: u32 = 0x0101_0101;
/// Pixels per block (16 words): keeps the bytewise running sums below 256.
const BLOCK_PX: usize = 64;

/// 0x01 in each byte of `w` that is `> t` (the `HIGH` variant is for `t >= 128`); `k` is the
/// per-byte constant (`t + 1` or `t - 127`) times [`ONES`].
#[inline(always)]
fn mask<const HIGH: bool>(w: u32, k: u32) -> u32 {
    let d = (w | H).wrapping_sub(k);
    let top = if HIGH { d & w } else { d | w };
    (top >> 7) & ONES
}

/// Binary 8-bit row sums (see the module documentation); same `pixels`, `weight`, `sum_x` as
/// the portable kernel, `max` exact when `pixels > 0`, else 0.
pub(super) fn row_binary_u8(row: &[u8], t: u8) -> RowSums {
    let row = row.get(..MAX_DIM).unwrap_or(row);
    match constant(t) {
        (k, true) => row_binary::<true>(row, t, k),
        (k, false) => row_binary::<false>(row, t, k),
    }
}

#[inline(always)]
fn row_binary<const HIGH: bool>(row: &[u8], t: u8, k: u32) -> RowSums {
    let mut pixels = 0u32;
    let mut sum_x = 0u64;
    // running maximum, starting at t: only the pixels above t can be a hit row's maximum
    let mut max = t;
    let mut x0 = 0u32;
    let mut blocks = row.chunks_exact(BLOCK_PX);
    for block in &mut blocks {
        // skip test: no byte of the OR of the block's words above t => no pixel above t
        let any = block.chunks_exact(4).fold(0u32, |a, b| {
            a | <[u8; 4]>::try_from(b).map_or(0, u32::from_le_bytes)
        });
        if mask::<HIGH>(any, k) != 0 {
            let (count, inner, m) = block_sums::<HIGH>(block, k, max);
            pixels += count;
            sum_x += u64::from(x0) * u64::from(count) + u64::from(inner);
            max = m;
        }
        x0 += BLOCK_PX as u32;
    }
    for (x, &p) in (x0..).zip(blocks.remainder()) {
        if p > t {
            pixels += 1;
            sum_x += u64::from(x);
            max = max.max(p);
        }
    }
    RowSums {
        pixels,
        weight: pixels,
        sum_x,
        max: if pixels > 0 { u16::from(max) } else { 0 },
    }
}

/// Per-byte constant for [`mask`] with threshold `t`, and whether it is the `HIGH` variant.
#[inline(always)]
fn constant(t: u8) -> (u32, bool) {
    if t >= 128 {
        (u32::from(t - 127) * ONES, true)
    } else {
        (u32::from(t + 1) * ONES, false)
    }
}

/// Count, `sum_x` relative to the block start, and the largest of `cur` and the block's
/// pixels, for one block of [`BLOCK_PX`] pixels (kept out of line so the skip loop keeps its
/// words in registers). The maximum costs one more SWAR compare per word against `cur`, and a
/// scalar pass only when some pixel exceeds `cur`.
#[inline(never)]
fn block_sums<const HIGH: bool>(block: &[u8], k: u32, cur: u8) -> (u32, u32, u8) {
    let (kc, high_c) = constant(cur);
    let (mut s, mut tt, mut above) = (0u32, 0u32, 0u32);
    for b in block.chunks_exact(4) {
        let w = <[u8; 4]>::try_from(b).map_or(0, u32::from_le_bytes);
        s = s.wrapping_add(mask::<HIGH>(w, k));
        tt = tt.wrapping_add(s);
        above |= if high_c {
            mask::<true>(w, kc)
        } else {
            mask::<false>(w, kc)
        };
    }
    // horizontal sums (no carries between bytes: S_i <= 16, T_i <= 136)
    let count = s.wrapping_mul(ONES) >> 24;
    let lane_x = s.wrapping_mul(0x0001_0203) >> 24;
    let t16 = (tt & 0x00ff_00ff) + ((tt >> 8) & 0x00ff_00ff);
    let tsum = t16.wrapping_mul(0x0001_0001) >> 16;
    // sum_j j m_ji = 16 S_i - T_i >= 0
    let inner = (16 * count).wrapping_sub(tsum).wrapping_mul(4) + lane_x;
    let max = if above != 0 {
        block.iter().fold(cur, |m, &p| m.max(p))
    } else {
        cur
    };
    (count, inner, max)
}

// ---------------------------------------------------------------------------------------------
// Weighted 8-bit and both 16-bit kernels: the same block skip, a scalar pass inside hit blocks

/// OR of a block's 8-bit pixels, four per word load.
#[inline(always)]
fn or_u8(block: &[u8]) -> u8 {
    let w = block.chunks_exact(4).fold(0u32, |a, b| {
        a | <[u8; 4]>::try_from(b).map_or(0, u32::from_le_bytes)
    });
    let w = w | (w >> 16);
    (w | (w >> 8)) as u8
}

/// OR of a block's 16-bit pixels, two per word.
#[inline(always)]
fn or_u16(block: &[u16]) -> u16 {
    let w = block.chunks_exact(2).fold(0u32, |a, c| match *c {
        [lo, hi] => a | u32::from(lo) | (u32::from(hi) << 16),
        _ => a,
    });
    (w | (w >> 16)) as u16
}

/// Weighted 8-bit row sums: blocks of [`BLOCK_PX`] pixels whose OR is not above `t` have no
/// pixel above `t` and are skipped; the others take the SWAR pass of [`block_weighted`] (the
/// row's remainder the scalar one). Same `pixels`, `weight`, `sum_x` as the portable kernel,
/// `max` exact when `pixels > 0`, else 0.
#[inline(always)]
pub(super) fn row_weighted_u8(row: &[u8], t: u8) -> RowSums {
    match constant(t) {
        (k, true) => {
            row_sparse::<u8, true>(row, t, or_u8, |b, cur| block_weighted::<true>(b, t, k, cur))
        }
        (k, false) => row_sparse::<u8, true>(row, t, or_u8, |b, cur| {
            block_weighted::<false>(b, t, k, cur)
        }),
    }
}

/// The weights `p - t` of the bytes of `w` above `t` (0 elsewhere), four lanes at once, given
/// the lane mask `m` of [`mask`] (0x01 per lane above `t`). With the top bit of every lane set,
/// `(w | H) - c` cannot borrow between lanes when `c < 128` per lane: for `t < 128`, `c = t`
/// and a lane above `t` holds `p - t` (`p >= 128`) or `p - t + 128` (`p < 128`, top bit set);
/// for `t >= 128`, `c = t - 128` and a lane above `t` (so `p >= 129`) holds `p - t + 128`.
/// Clearing the added 128 is an XOR of the top bit, masked by the lanes where it was added.
#[inline(always)]
fn weights<const HIGH: bool>(w: u32, t: u8, m: u32) -> u32 {
    let d = if HIGH {
        ((w | H).wrapping_sub(u32::from(t.wrapping_sub(128)) * ONES)) ^ H
    } else {
        (w | H).wrapping_sub(u32::from(t) * ONES) ^ (H & !w)
    };
    d & m.wrapping_mul(0xff)
}

/// Count, weight, block-local x moment and running maximum of one block of [`BLOCK_PX`]
/// 8-bit pixels, weighted mode, four pixels per word: the weights of even and odd lanes are
/// summed in 16-bit halves (`S <= 16 * 255`, `T <= 136 * 255 < 2^16`, no carries), and as in
/// [`block_sums`] `sum_x = 4 (16 weight - sum T_i) + sum i S_i`.
#[inline(never)]
fn block_weighted<const HIGH: bool>(block: &[u8], t: u8, k: u32, cur: u8) -> (u32, u32, u32, u8) {
    const LO: u32 = 0x00ff_00ff;
    let (kc, high_c) = constant(cur);
    let (mut cnt, mut s_lo, mut s_hi, mut t_lo, mut t_hi, mut above) =
        (0u32, 0u32, 0u32, 0u32, 0u32, 0u32);
    for b in block.chunks_exact(4) {
        let w = <[u8; 4]>::try_from(b).map_or(0, u32::from_le_bytes);
        let m = mask::<HIGH>(w, k);
        let e = weights::<HIGH>(w, t, m);
        cnt = cnt.wrapping_add(m);
        s_lo = s_lo.wrapping_add(e & LO);
        s_hi = s_hi.wrapping_add((e >> 8) & LO);
        t_lo = t_lo.wrapping_add(s_lo);
        t_hi = t_hi.wrapping_add(s_hi);
        above |= if high_c {
            mask::<true>(w, kc)
        } else {
            mask::<false>(w, kc)
        };
    }
    let half = |v: u32| (v & 0xffff, v >> 16);
    let ((s0, s2), (s1, s3)) = (half(s_lo), half(s_hi));
    let ((t0, t2), (t1, t3)) = (half(t_lo), half(t_hi));
    let count = cnt.wrapping_mul(ONES) >> 24;
    let weight = s0 + s1 + s2 + s3;
    // sum_j j e_ji = 16 S_i - T_i >= 0
    let inner = (16 * weight - (t0 + t1 + t2 + t3)) * 4 + s1 + 2 * s2 + 3 * s3;
    let max = if above != 0 {
        block.iter().fold(cur, |m, &p| m.max(p))
    } else {
        cur
    };
    (count, weight, inner, max)
}

/// Binary 16-bit row sums (see [`row_weighted_u8`]; the per-pixel pass inside hit blocks).
pub(super) fn row_binary_u16(row: &[u16], t: u16) -> RowSums {
    row_sparse::<u16, false>(row, t, or_u16, |b, cur| block_pass::<u16, false>(b, t, cur))
}

/// Weighted 16-bit row sums (see [`row_binary_u16`]).
pub(super) fn row_weighted_u16(row: &[u16], t: u16) -> RowSums {
    row_sparse::<u16, true>(row, t, or_u16, |b, cur| block_pass::<u16, true>(b, t, cur))
}

/// The block skip around `full`, the sums of one block of [`BLOCK_PX`] pixels given the running
/// maximum; the row's remainder takes the per-pixel pass.
#[inline(always)]
fn row_sparse<P: Level, const WEIGHTED: bool>(
    row: &[P],
    t: P,
    or: fn(&[P]) -> P,
    full: impl Fn(&[P], P) -> (u32, u32, u32, P),
) -> RowSums {
    let row = row.get(..MAX_DIM).unwrap_or(row);
    let (mut pixels, mut weight, mut sum_x, mut max) = (0u32, 0u32, 0u64, t);
    let mut x0 = 0u32;
    let mut blocks = row.chunks_exact(BLOCK_PX);
    for block in &mut blocks {
        if or(block) > t {
            let (n, w, s, m) = full(block, max);
            pixels += n;
            weight += w;
            sum_x += u64::from(x0) * u64::from(w) + u64::from(s);
            max = m;
        }
        x0 += BLOCK_PX as u32;
    }
    let (n, w, s, m) = block_pass::<P, WEIGHTED>(blocks.remainder(), t, max);
    pixels += n;
    weight += w;
    sum_x += u64::from(x0) * u64::from(w) + u64::from(s);
    RowSums {
        pixels,
        weight,
        sum_x,
        max: if pixels > 0 { m.into() } else { 0 },
    }
}

/// Count, weight, block-local x moment (`<= 65 535 * 2016 < 2^27` for a block of 64) and the
/// running maximum over one block (or the row's remainder, fewer than 64 pixels).
#[inline(never)]
fn block_pass<P: Level, const WEIGHTED: bool>(block: &[P], t: P, cur: P) -> (u32, u32, u32, P) {
    let (mut n, mut w, mut s, mut m) = (0u32, 0u32, 0u32, cur);
    for (x, &p) in (0u32..).zip(block) {
        let above = u32::from(p > t);
        let e = if WEIGHTED { p.excess(t) } else { above };
        n += above;
        w += e;
        s += e * x;
        m = m.max(p);
    }
    (n, w, s, m)
}

// ---------------------------------------------------------------------------------------------
// Tracking window: binary 8-bit sums plus the hit extent in one pass

/// [`WindowSums`] of `seg` (at most [`MAX_DIM`] pixels): blocks of up to 16 words with the
/// bytewise running sums of [`block_sums`] for any number of words `n` (`sum_j j m_j =
/// n S - T`), a bitmap of the words with a hit for the extent (the first and last hit word's
/// mask are recomputed once per block), and the saturation test on the OR of the words (no
/// byte of the OR at or above `sat`: no pixel is; otherwise an exact scalar pass). Inlined
/// into the tracker's row loop: a window row is short, the call would be a good part of it.
#[inline(always)]
pub(crate) fn window_binary_u8(
    seg: &[u8],
    t: u8,
    sat: u8,
    left: usize,
    right: usize,
) -> WindowSums {
    let seg = seg.get(..MAX_DIM).unwrap_or(seg);
    match constant(t) {
        (k, true) => window_binary::<true>(seg, t, k, sat, left, right),
        (k, false) => window_binary::<false>(seg, t, k, sat, left, right),
    }
}

#[inline(always)]
fn window_binary<const HIGH: bool>(
    seg: &[u8],
    t: u8,
    k: u32,
    sat: u8,
    left: usize,
    right: usize,
) -> WindowSums {
    let word = |b: &[u8]| <[u8; 4]>::try_from(b).map_or(0, u32::from_le_bytes);
    // `seg` has at most MAX_DIM pixels: `sum_x <= 65 535 * 65 536 / 2 < 2^31` fits 32 bits
    let (mut pixels, mut sum_x) = (0u32, 0u32);
    let mut or_all = 0u32;
    let mut x0 = 0u32;
    for block in seg.chunks(BLOCK_PX) {
        // four words per iteration (a window row is short: LLVM's own unrolling only pays for
        // whole 64-pixel blocks)
        let quads = block.chunks_exact(16);
        let words = quads.remainder().chunks_exact(4);
        let tail = words.remainder();
        let n = (block.len() / 4) as u32;
        let (mut s, mut tt) = (0u32, 0u32);
        for q in quads {
            for b in q.chunks_exact(4) {
                let w = word(b);
                or_all |= w;
                s = s.wrapping_add(mask::<HIGH>(w, k));
                tt = tt.wrapping_add(s);
            }
        }
        for b in words {
            let w = word(b);
            or_all |= w;
            s = s.wrapping_add(mask::<HIGH>(w, k));
            tt = tt.wrapping_add(s);
        }
        if s != 0 {
            let count = s.wrapping_mul(ONES) >> 24;
            let lane_x = s.wrapping_mul(0x0001_0203) >> 24;
            let t16 = (tt & 0x00ff_00ff) + ((tt >> 8) & 0x00ff_00ff);
            let tsum = t16.wrapping_mul(0x0001_0001) >> 16;
            let inner = (n * count).wrapping_sub(tsum).wrapping_mul(4) + lane_x;
            pixels += count;
            sum_x += x0 * count + inner;
        }
        let xt = x0 + 4 * n;
        for (x, &p) in (xt..).zip(tail) {
            or_all |= u32::from(p);
            if p > t {
                pixels += 1;
                sum_x += x;
            }
        }
        x0 += block.len() as u32;
    }
    if pixels == 0 {
        return WindowSums {
            pixels,
            sum_x: 0,
            first: u32::MAX,
            last: u32::MAX,
            saturated: false,
        };
    }
    // saturation: no byte of the OR at or above `sat` => no pixel is (sat >= 1)
    let (ks, high_s) = constant(sat.wrapping_sub(1));
    let maybe = sat == 0
        || if high_s {
            mask::<true>(or_all, ks)
        } else {
            mask::<false>(or_all, ks)
        } != 0;
    WindowSums {
        pixels,
        sum_x: u64::from(sum_x),
        first: first_hit::<HIGH>(seg.get(..left).unwrap_or(seg), t, k),
        last: match seg.get(right..) {
            Some(r) => last_hit::<HIGH>(r, t, k).map_or(u32::MAX, |i| i + right as u32),
            None => u32::MAX,
        },
        saturated: maybe && seg.iter().any(|&p| p >= sat),
    }
}

/// Bit `i` (`0..4`): column `start + i` has a pixel above `t` in `rows` rows of `pixels`
/// `stride` apart from `start` (a word and one SWAR compare per row; rows that do not fit
/// count as no hit).
#[inline(always)]
pub(crate) fn column_group_u8(
    pixels: &[u8],
    start: usize,
    stride: usize,
    rows: usize,
    t: u8,
) -> u32 {
    let (k, high) = constant(t);
    let mut acc = 0u32;
    let mut i = start;
    for _ in 0..rows {
        let w = pixels
            .get(i..i + 4)
            .and_then(|b| <[u8; 4]>::try_from(b).ok())
            .map_or(0, u32::from_le_bytes);
        acc |= if high {
            mask::<true>(w, k)
        } else {
            mask::<false>(w, k)
        };
        i += stride;
    }
    (acc | acc >> 7 | acc >> 14 | acc >> 21) & 0xf
}

/// Index of the first pixel above `t` (a word at a time from the left), `u32::MAX` if none.
#[inline(always)]
fn first_hit<const HIGH: bool>(seg: &[u8], t: u8, k: u32) -> u32 {
    let words = seg.chunks_exact(4);
    let tail = words.remainder();
    let mut x = 0u32;
    for b in words {
        let m = mask::<HIGH>(<[u8; 4]>::try_from(b).map_or(0, u32::from_le_bytes), k);
        if m != 0 {
            return x + m.trailing_zeros() / 8;
        }
        x += 4;
    }
    for &p in tail {
        if p > t {
            return x;
        }
        x += 1;
    }
    u32::MAX
}

/// Index of the last pixel above `t` (a word at a time from the right).
#[inline(always)]
fn last_hit<const HIGH: bool>(seg: &[u8], t: u8, k: u32) -> Option<u32> {
    let whole = seg.len() - seg.len() % 4;
    let (head, tail) = seg.split_at(whole.min(seg.len()));
    for (i, &p) in tail.iter().enumerate().rev() {
        if p > t {
            return Some((whole + i) as u32);
        }
    }
    let mut x = whole as u32;
    for b in head.rchunks_exact(4) {
        x -= 4;
        let m = mask::<HIGH>(<[u8; 4]>::try_from(b).map_or(0, u32::from_le_bytes), k);
        if m != 0 {
            return Some(x + (31 - m.leading_zeros()) / 8);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tracking window kernel against a naive pass, on random segments of any length and
    /// alignment, thresholds and saturation levels.
    #[test]
    fn window_kernel_matches_naive() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(15);
        for _ in 0..20_000 {
            let len = rng.random_range(0..300usize);
            let dense = rng.random_range(0..4u8);
            let seg: std::vec::Vec<u8> = (0..len)
                .map(|_| match dense {
                    0 => rng.random_range(0..=255),
                    1 => {
                        if rng.random_range(0..10) == 0 {
                            200
                        } else {
                            10
                        }
                    }
                    _ => rng.random_range(90..=110),
                })
                .collect();
            let t: u8 = rng.random_range(0..=255);
            let sat: u8 = rng.random_range(t.saturating_add(1)..=255).max(1);
            let got = window_binary_u8(&seg, t, sat, seg.len(), 0);
            let hits: std::vec::Vec<u32> = (0u32..)
                .zip(&seg)
                .filter(|(_, &p)| p > t)
                .map(|(x, _)| x)
                .collect();
            assert_eq!(got.pixels as usize, hits.len());
            assert_eq!(got.sum_x, hits.iter().map(|&x| u64::from(x)).sum::<u64>());
            if let (Some(&a), Some(&b)) = (hits.first(), hits.last()) {
                assert_eq!((got.first, got.last), (a, b), "{seg:?} t {t}");
                assert_eq!(got.saturated, seg.iter().any(|&p| p >= sat));
            } else {
                assert!(got.first == u32::MAX && got.last == u32::MAX && !got.saturated);
            }
        }
    }
    use proptest::prelude::*;
    use std::vec::Vec;

    fn naive(row: &[u8], t: u8) -> RowSums {
        let mut r = RowSums::default();
        for (x, &p) in row.iter().enumerate() {
            if p > t {
                r.pixels += 1;
                r.sum_x += x as u64;
            }
        }
        r.weight = r.pixels;
        if r.pixels > 0 {
            r.max = u16::from(*row.iter().max().unwrap());
        }
        r
    }

    #[test]
    fn mask_is_the_bytewise_compare_for_every_value_and_threshold() {
        for t in 0..=255u8 {
            let k = if t >= 128 {
                u32::from(t - 127) * ONES
            } else {
                u32::from(t + 1) * ONES
            };
            for p in 0..=255u8 {
                // the pixel in every lane, with neighbours at both extremes
                for (lane, other) in [(0, 0u8), (1, 255), (2, 0), (3, 255)] {
                    let mut b = [other; 4];
                    b[lane] = p;
                    let w = u32::from_le_bytes(b);
                    let m = if t >= 128 {
                        mask::<true>(w, k)
                    } else {
                        mask::<false>(w, k)
                    };
                    let want = u32::from_le_bytes(b.map(|v| u8::from(v > t)));
                    assert_eq!(m, want, "t {t} p {p} lane {lane}");
                }
            }
        }
    }

    #[test]
    fn weights_are_the_bytewise_excess_for_every_value_and_threshold() {
        for t in 0..=255u8 {
            let (k, high) = constant(t);
            for p in 0..=255u8 {
                for (lane, other) in [(0, 0u8), (1, 255), (2, 0), (3, 255)] {
                    let mut b = [other; 4];
                    b[lane] = p;
                    let w = u32::from_le_bytes(b);
                    let e = if high {
                        weights::<true>(w, t, mask::<true>(w, k))
                    } else {
                        weights::<false>(w, t, mask::<false>(w, k))
                    };
                    let want = u32::from_le_bytes(b.map(|v| v.saturating_sub(t)));
                    assert_eq!(e, want, "t {t} p {p} lane {lane}");
                }
            }
        }
    }

    proptest! {
        #[test]
        fn matches_naive_on_random_rows(
            row in proptest::collection::vec(any::<u8>(), 0..700),
            t in any::<u8>(),
            sparse in any::<bool>(),
        ) {
            // sparse rows exercise the block skip, dense ones the sums
            let row: Vec<u8> = if sparse {
                row.iter().map(|&p| if p > 250 { p } else { p % (t.max(1)) }).collect()
            } else {
                row
            };
            prop_assert_eq!(row_binary_u8(&row, t), naive(&row, t));
        }
    }

    /// Portable kernels with the ARM path's `max` convention (0 for a row without a hit).
    fn portable<P: Copy>(f: fn(&[P], P) -> RowSums, row: &[P], t: P) -> RowSums {
        let mut r = f(row, t);
        if r.pixels == 0 {
            r.max = 0;
        }
        r
    }

    proptest! {
        #[test]
        fn sparse_kernels_match_the_portable_ones(
            row8 in proptest::collection::vec(any::<u8>(), 0..700),
            row16 in proptest::collection::vec(any::<u16>(), 0..700),
            t8 in any::<u8>(),
            t16 in any::<u16>(),
            sparse in any::<bool>(),
        ) {
            // sparse rows exercise the block skip, dense ones the per-pixel pass
            let (row8, row16): (Vec<u8>, Vec<u16>) = if sparse {
                (
                    row8.iter().map(|&p| if p > 250 { p } else { p % t8.max(1) }).collect(),
                    row16.iter().map(|&p| if p > 65_000 { p } else { p % t16.max(1) }).collect(),
                )
            } else {
                (row8, row16)
            };
            use super::super::portable as k;
            prop_assert_eq!(row_weighted_u8(&row8, t8), portable(k::row_weighted_u8, &row8, t8));
            prop_assert_eq!(row_binary_u16(&row16, t16), portable(k::row_binary_u16, &row16, t16));
            prop_assert_eq!(
                row_weighted_u16(&row16, t16),
                portable(k::row_weighted_u16, &row16, t16)
            );
        }
    }

    #[test]
    fn sparse_kernels_at_the_accumulator_bounds() {
        for len in [64, 65_536, 65_600] {
            let n = len.min(MAX_DIM) as u64;
            let r = row_weighted_u16(&std::vec![u16::MAX; len], 0);
            assert_eq!((r.pixels as u64, r.weight as u64), (n, n * 65_535));
            assert_eq!(r.sum_x, 65_535 * n * (n - 1) / 2);
            let r = row_binary_u16(&std::vec![u16::MAX; len], 0);
            assert_eq!(
                (r.pixels as u64, r.sum_x, r.max),
                (n, n * (n - 1) / 2, u16::MAX)
            );
            let r = row_weighted_u8(&std::vec![255u8; len], 0);
            assert_eq!((r.weight as u64, r.sum_x), (n * 255, 255 * n * (n - 1) / 2));
        }
    }

    #[test]
    fn full_rows_at_the_accumulator_bounds() {
        for len in [64, 65_536, 65_600] {
            let row = std::vec![255u8; len];
            let got = row_binary_u8(&row, 0);
            let n = len.min(MAX_DIM) as u64;
            assert_eq!(got.pixels as u64, n);
            assert_eq!(got.sum_x, n * (n - 1) / 2);
            assert_eq!(got.max, 255);
        }
    }

    proptest! {
        /// The four-column group of the tracking window's extent equals a per-pixel check of
        /// the same columns and rows (rows past the end of the pixels count as no hit).
        #[test]
        fn column_group_is_the_per_pixel_check(
            px in proptest::collection::vec(any::<u8>(), 1..400),
            start in 0usize..40,
            stride in 4usize..24,
            rows in 0usize..20,
            t in any::<u8>(),
        ) {
            let mut want = 0u32;
            for r in 0..rows {
                let i = start + r * stride;
                if let Some(g) = px.get(i..i + 4) {
                    for (k, &p) in g.iter().enumerate() {
                        want |= u32::from(p > t) << k;
                    }
                }
            }
            prop_assert_eq!(column_group_u8(&px, start, stride, rows, t), want);
        }
    }
}
