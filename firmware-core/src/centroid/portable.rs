//! The portable row kernels: one pass per row with branchless arithmetic (`(p > t) as u32`,
//! `p.saturating_sub(t)`) into 32-bit accumulators, the shape LLVM's loop vectoriser turns into
//! SIMD code (SSE2 on x86-64: about 16 pixels per handful of instructions). The 32-bit
//! accumulators are proven not to overflow (see each kernel in `pixel`), which is what lets
//! the loop stay in 32-bit lanes. The backend of every target but 32-bit ARM, where `m4`
//! replaces the row kernels (the host tests compare both); the tracking window's column test
//! of 16-bit frames is this one everywhere.

// on 32-bit ARM the `m4` row kernels are used; these stay for the column test and the tests
#![cfg_attr(target_arch = "arm", allow(dead_code))]

use super::sums::{clip, Level, RowSums, BLOCK};

/// Binary 8-bit row sums.
#[inline(always)]
pub(super) fn row_binary_u8(row: &[u8], t: u8) -> RowSums {
    row_binary(row, t)
}

/// Binary 16-bit row sums.
#[inline(always)]
pub(super) fn row_binary_u16(row: &[u16], t: u16) -> RowSums {
    row_binary(row, t)
}

/// Weighted 8-bit row sums.
#[inline(always)]
pub(super) fn row_weighted_u8(row: &[u8], t: u8) -> RowSums {
    row_weighted(row, t)
}

/// Weighted 16-bit row sums.
#[inline(always)]
pub(super) fn row_weighted_u16(row: &[u16], t: u16) -> RowSums {
    row_weighted(row, t)
}

/// Bit `i` (`0..4`): column `start + i` has a pixel above `t` in `rows` rows of `pixels`
/// `stride` apart from `start` (the tracking window's x extent; rows that do not fit count
/// as no hit).
#[inline(always)]
pub fn column_group<P: Level>(pixels: &[P], start: usize, stride: usize, rows: usize, t: P) -> u32 {
    let mut bits = 0u32;
    let mut i = start;
    for _ in 0..rows {
        if let Some(g) = pixels.get(i..i + 4) {
            for (k, &p) in (0u32..).zip(g) {
                bits |= u32::from(p > t) << k;
            }
        }
        i += stride;
    }
    bits
}

#[inline(always)]
fn row_binary<P: Level>(row: &[P], t: P) -> RowSums {
    let mut pixels = 0u32;
    let mut sum_x = 0u32;
    let mut max = P::default();
    for (x, &p) in (0u32..).zip(clip(row)) {
        let sel = u32::from(p > t);
        pixels += sel;
        sum_x += sel * x;
        max = max.max(p);
    }
    RowSums {
        pixels,
        weight: pixels,
        sum_x: u64::from(sum_x),
        max: max.into(),
    }
}

#[inline(always)]
fn row_weighted<P: Level>(row: &[P], t: P) -> RowSums {
    let mut pixels = 0u32;
    let mut weight = 0u32;
    let mut sum_x = 0u64;
    let mut max = P::default();
    let mut x0 = 0u64;
    for block in clip(row).chunks(BLOCK) {
        let mut w = 0u32;
        let mut s = 0u32;
        for (x, &p) in (0u32..).zip(block) {
            let e = p.excess(t);
            pixels += u32::from(p > t);
            w += e;
            s += e * x;
            max = max.max(p);
        }
        weight += w;
        sum_x += u64::from(s) + x0 * u64::from(w);
        x0 += BLOCK as u64;
    }
    RowSums {
        pixels,
        weight,
        sum_x,
        max: max.into(),
    }
}
