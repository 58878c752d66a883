//! Per-row kernels of the single-target path: count, weight and first x moment of the pixels
//! above the threshold in one row, plus the row maximum (for the saturation flag).
//!
//! These are the hot loops (a few operations per pixel) and are written so that the compiler
//! vectorises them: the row is cut into chunks of [`LANES`] pixels, each lane keeps its own
//! accumulators, and nothing branches on pixel values. The x moment avoids a multiply per pixel
//! with a running-sum identity: per lane, with `m_k` the weight in chunk `k` (of `K` chunks),
//! `A` the running sum of `m` and `B` the running sum of `A`,
//!
//! ```text
//! sum_k k * m_k = K * A_K - B_K        (A_K = sum_k m_k,  B_K = sum_k A_k after chunk k)
//! ```
//!
//! so every pixel costs one compare (or saturating subtract) and two adds. Lane accumulators
//! are flushed into wider totals every [`BLOCK`] pixels, which bounds them (see the proofs on
//! each kernel). `row_binary_u8` is the one a Cortex-M4 DSP port will replace.

use super::MAX_DIM;

/// Pixels processed side by side (one 128-bit vector of 8-bit pixels).
pub const LANES: usize = 16;

/// Chunks per block: lane accumulators are flushed into the row totals after this many.
const BLOCK_CHUNKS: usize = 256;

/// Pixels per block (`LANES * 256 = 4096`).
pub const BLOCK: usize = LANES * BLOCK_CHUNKS;

/// Sums over one row (or row segment) of the pixels above the threshold, with `x` counted from
/// the first pixel of the slice.
///
/// Bounds (rows are clipped to [`MAX_DIM`] = 65 536 pixels): `pixels <= 65 536`,
/// `weight <= 65 536 * 65 535 < 2^32`, `sum_x <= 65 535 * (65 535 * 65 536 / 2) < 2^47`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RowSums {
    /// Number of pixels above the threshold.
    pub pixels: u32,
    /// Sum of the weights: equals `pixels` in binary mode, sum of `value - T` in weighted mode.
    pub weight: u32,
    /// Sum of `x * weight`, `x` = index in the slice (0-based).
    pub sum_x: u64,
    /// Largest pixel value in the slice (above threshold or not); 0 for an empty slice.
    pub max: u16,
}

/// Pixel types the kernels accept (8- and 16-bit grey).
pub(crate) trait Pixel: Copy + Ord + Default + Into<u16> {
    /// `self - t` if `self > t`, else 0 (the weighted-mode weight).
    fn excess(self, t: Self) -> u32;
}

impl Pixel for u8 {
    #[inline(always)]
    fn excess(self, t: Self) -> u32 {
        u32::from(self.saturating_sub(t))
    }
}

impl Pixel for u16 {
    #[inline(always)]
    fn excess(self, t: Self) -> u32 {
        u32::from(self.saturating_sub(t))
    }
}

/// At most [`MAX_DIM`] pixels of `row` (the bounds above rely on it).
#[inline(always)]
fn clip<P>(row: &[P]) -> &[P] {
    row.get(..MAX_DIM).unwrap_or(row)
}

/// x moment of a flushed block: lanes' running sums `a` (total weight per lane) and `b` (sum of
/// running sums) over `k` chunks. Returns `sum_x` relative to the block start.
#[inline(always)]
fn block_moment(a: &[u64; LANES], b: &[u64; LANES], k: u64) -> u64 {
    let mut s = 0u64;
    for (lane, (&ai, &bi)) in (0u64..).zip(a.iter().zip(b.iter())) {
        // sum over chunks of chunk_index * m = k * a - b (exact, >= 0); x = 16 * chunk + lane.
        s += LANES as u64 * (k * ai - bi) + lane * ai;
    }
    s
}

/// Binary mode, 8-bit pixels: count and x moment of the pixels with value `> t`.
///
/// This is the single-target hot loop (a compare and two adds per pixel, vectorised).
/// Lane bounds per block of 256 chunks: `A <= 256`, `B <= 256 * 257 / 2 = 32 896`, so 16-bit
/// lanes suffice. Rows longer than [`MAX_DIM`] pixels are clipped to it.
pub fn row_binary_u8(row: &[u8], t: u8) -> RowSums {
    row_binary(row, t)
}

/// Binary mode, 16-bit pixels (same as [`row_binary_u8`]).
pub fn row_binary_u16(row: &[u16], t: u16) -> RowSums {
    row_binary(row, t)
}

/// Weighted mode, 8-bit pixels: weight `value - t` for value `> t`.
pub fn row_weighted_u8(row: &[u8], t: u8) -> RowSums {
    row_weighted(row, t)
}

/// Weighted mode, 16-bit pixels. Lane bounds per block: `A <= 256 * 65 535 < 2^24`,
/// `B <= 65 535 * 256 * 257 / 2 < 2^32`, so 32-bit lanes suffice.
pub fn row_weighted_u16(row: &[u16], t: u16) -> RowSums {
    row_weighted(row, t)
}

#[inline(always)]
fn row_binary<P: Pixel>(row: &[P], t: P) -> RowSums {
    let row = clip(row);
    let mut pixels = 0u64;
    let mut sum_x = 0u64;
    let mut max = P::default();
    let mut x0 = 0u64;
    for block in row.chunks(BLOCK) {
        let mut a = [0u16; LANES];
        let mut b = [0u16; LANES];
        let mut mx = [P::default(); LANES];
        let chunks = block.chunks_exact(LANES);
        let tail = chunks.remainder();
        let mut k = 0u64;
        for chunk in chunks {
            for (((ai, bi), mi), &p) in a.iter_mut().zip(b.iter_mut()).zip(mx.iter_mut()).zip(chunk)
            {
                *ai += u16::from(p > t);
                *bi += *ai;
                *mi = (*mi).max(p);
            }
            k += 1;
        }
        let a64 = a.map(u64::from);
        let b64 = b.map(u64::from);
        let n: u64 = a64.iter().sum();
        let mut s = block_moment(&a64, &b64, k);
        // The tail (< LANES pixels, last block only) starts at chunk index k.
        let tail_x0 = k * LANES as u64;
        let mut tail_n = 0u64;
        for (x, &p) in (tail_x0..).zip(tail) {
            let m = u64::from(p > t);
            tail_n += m;
            s += m * x;
            max = max.max(p);
        }
        for &m in &mx {
            max = max.max(m);
        }
        pixels += n + tail_n;
        sum_x += s + x0 * (n + tail_n);
        x0 += block.len() as u64;
    }
    RowSums {
        pixels: pixels as u32,
        weight: pixels as u32,
        sum_x,
        max: max.into(),
    }
}

#[inline(always)]
fn row_weighted<P: Pixel>(row: &[P], t: P) -> RowSums {
    let row = clip(row);
    let mut pixels = 0u64;
    let mut weight = 0u64;
    let mut sum_x = 0u64;
    let mut max = P::default();
    let mut x0 = 0u64;
    for block in row.chunks(BLOCK) {
        let mut c = [0u16; LANES];
        let mut a = [0u32; LANES];
        let mut b = [0u32; LANES];
        let mut mx = [P::default(); LANES];
        let chunks = block.chunks_exact(LANES);
        let tail = chunks.remainder();
        let mut k = 0u64;
        for chunk in chunks {
            for ((((ci, ai), bi), mi), &p) in c
                .iter_mut()
                .zip(a.iter_mut())
                .zip(b.iter_mut())
                .zip(mx.iter_mut())
                .zip(chunk)
            {
                *ci += u16::from(p > t);
                *ai += p.excess(t);
                *bi += *ai;
                *mi = (*mi).max(p);
            }
            k += 1;
        }
        let a64 = a.map(u64::from);
        let b64 = b.map(u64::from);
        let n: u64 = c.iter().map(|&v| u64::from(v)).sum();
        let w: u64 = a64.iter().sum();
        let mut s = block_moment(&a64, &b64, k);
        let tail_x0 = k * LANES as u64;
        let (mut tail_n, mut tail_w) = (0u64, 0u64);
        for (x, &p) in (tail_x0..).zip(tail) {
            let e = u64::from(p.excess(t));
            tail_n += u64::from(p > t);
            tail_w += e;
            s += e * x;
            max = max.max(p);
        }
        for &m in &mx {
            max = max.max(m);
        }
        pixels += n + tail_n;
        weight += w + tail_w;
        sum_x += s + x0 * (w + tail_w);
        x0 += block.len() as u64;
    }
    RowSums {
        pixels: pixels as u32,
        weight: weight as u32,
        sum_x,
        max: max.into(),
    }
}
