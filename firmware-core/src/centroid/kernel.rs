//! Per-row kernels of the single-target path: count, weight and first x moment of the pixels
//! above the threshold in one row, plus the row maximum (for the saturation flag).
//!
//! These are the hot loops. Each is one pass over the row with branchless arithmetic
//! (`(p > t) as u32`, `p.saturating_sub(t)`) into 32-bit accumulators, the shape LLVM's loop
//! vectoriser turns into SIMD code (SSE2 on x86-64: about 16 pixels per handful of
//! instructions). The 32-bit accumulators are proven not to overflow (see each kernel), which
//! is what lets the loop stay in 32-bit lanes. `row_binary_u8` is the one a Cortex-M4 DSP port
//! (`USUB8`/`SEL`/`USADA8`) will replace; keep its contract: [`RowSums`] with `x` counted from
//! the slice start.

use super::MAX_DIM;

/// Pixels per block of the weighted kernels: the block-local x moment fits 32 bits.
pub const BLOCK: usize = 256;

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

/// What the tracking window needs from one row segment in binary 8-bit mode: the sums of
/// [`row_binary_u8`] (without `max`), the first column above `t` left of `left` and the last
/// one from `right` on (relative to the segment; `u32::MAX` when there is none: only what can
/// widen the extent found so far is searched) and whether a pixel is at or above the
/// saturation level. (Public only as the return type of a hidden [`Pixel`] method.)
#[doc(hidden)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WindowSums {
    pub pixels: u32,
    pub sum_x: u64,
    pub first: u32,
    pub last: u32,
    pub saturated: bool,
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for u8 {}
    impl Sealed for u16 {}
}

/// Grey pixel types the centroiders accept: `u8` and `u16` (sealed). Every function that
/// takes rows or a [`Frame`](super::Frame) is generic over it, in place of `_u8` / `_u16`
/// twins; each type keeps its own kernels ([`row_binary_u8`], [`row_weighted_u16`], ...).
pub trait Pixel: sealed::Sealed + Copy + Ord + Default + Into<u16> + 'static {
    /// The largest code (255 or 65 535): the default saturation level.
    const FULL: u16;

    /// `self - t` if `self > t`, else 0 (the weighted-mode weight).
    #[doc(hidden)]
    fn excess(self, t: Self) -> u32;

    /// The threshold `t` for this pixel type (8-bit: `t >= 255` selects nothing).
    #[doc(hidden)]
    fn threshold(t: u16) -> Self;

    /// The row kernel of this type and mode.
    #[doc(hidden)]
    fn row_sums(row: &[Self], t: Self, binary: bool) -> RowSums;

    /// The one-pass kernel of the tracking window for this type and mode, if it has one
    /// (binary 8-bit on 32-bit ARM); `sat` is the saturation level.
    #[doc(hidden)]
    #[inline(always)]
    fn window_sums(
        _seg: &[Self],
        _t: Self,
        _sat: u16,
        _binary: bool,
        _left: usize,
        _right: usize,
    ) -> Option<WindowSums> {
        None
    }

    /// Bit `i` (`0..4`): column `start + i` has a pixel above `t` in `rows` rows of `pixels`
    /// `stride` apart from `start` (the tracking window's x extent; rows that do not fit count
    /// as no hit).
    #[doc(hidden)]
    #[inline(always)]
    fn column_group(pixels: &[Self], start: usize, stride: usize, rows: usize, t: Self) -> u32 {
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
}

/// The methods of [`Pixel`] the two types share: the weight above the threshold and the
/// dispatch to the type's own binary and weighted row kernels (the kernels stay separate).
macro_rules! pixel_kernels {
    ($binary:ident, $weighted:ident) => {
        #[inline(always)]
        fn excess(self, t: Self) -> u32 {
            u32::from(self.saturating_sub(t))
        }

        #[inline(always)]
        fn row_sums(row: &[Self], t: Self, binary: bool) -> RowSums {
            if binary {
                $binary(row, t)
            } else {
                $weighted(row, t)
            }
        }
    };
}

impl Pixel for u8 {
    const FULL: u16 = 255;

    pixel_kernels!(row_binary_u8, row_weighted_u8);

    #[inline(always)]
    fn threshold(t: u16) -> Self {
        if t > 255 {
            255
        } else {
            t as u8
        }
    }

    #[cfg(any(test, target_arch = "arm"))]
    #[inline(always)]
    fn window_sums(
        seg: &[Self],
        t: Self,
        sat: u16,
        binary: bool,
        left: usize,
        right: usize,
    ) -> Option<WindowSums> {
        if binary {
            let sat = if sat > 255 { 255 } else { sat as u8 };
            Some(super::m4::window_binary_u8(seg, t, sat, left, right))
        } else {
            None
        }
    }

    #[cfg(any(test, target_arch = "arm"))]
    #[inline(always)]
    fn column_group(pixels: &[Self], start: usize, stride: usize, rows: usize, t: Self) -> u32 {
        super::m4::column_group_u8(pixels, start, stride, rows, t)
    }
}

impl Pixel for u16 {
    const FULL: u16 = u16::MAX;

    pixel_kernels!(row_binary_u16, row_weighted_u16);

    #[inline(always)]
    fn threshold(t: u16) -> Self {
        t
    }
}

/// At most [`MAX_DIM`] pixels of `row` (the bounds above rely on it).
// portable kernels; on 32-bit ARM the `m4` ones replace them (the host tests compare both)
#[cfg_attr(target_arch = "arm", allow(dead_code))]
#[inline(always)]
fn clip<P>(row: &[P]) -> &[P] {
    row.get(..MAX_DIM).unwrap_or(row)
}

/// Binary mode, 8-bit pixels: count and x moment of the pixels with value `> t`.
///
/// The single-target hot loop: per pixel a compare, two adds (count, masked x) and a max.
/// 32-bit accumulators: `pixels <= 65 536`, `sum_x <= 65 535 * 65 536 / 2 < 2^31`.
/// Rows longer than [`MAX_DIM`] pixels are clipped to it.
///
/// On 32-bit ARM (Cortex-M) this is the word-at-a-time SWAR kernel of the `m4` submodule
/// (1.1 instructions per pixel on a one-target 320 x 240 frame on a Cortex-M4, 5.4 when every
/// 64-pixel block has a pixel above `t`; `mcu-demo/bench.sh`); there `max` is exact when
/// `pixels > 0` (all the centroider reads it for) and 0 otherwise.
#[inline(always)]
pub fn row_binary_u8(row: &[u8], t: u8) -> RowSums {
    #[cfg(target_arch = "arm")]
    {
        super::m4::row_binary_u8(row, t)
    }
    #[cfg(not(target_arch = "arm"))]
    {
        row_binary(row, t)
    }
}

/// Binary mode, 16-bit pixels (same as [`row_binary_u8`]). On 32-bit ARM: blocks of 64 pixels
/// whose OR is not above `t` are skipped (two pixels per word), `max` as on that path.
#[inline(always)]
pub fn row_binary_u16(row: &[u16], t: u16) -> RowSums {
    #[cfg(target_arch = "arm")]
    {
        super::m4::row_binary_u16(row, t)
    }
    #[cfg(not(target_arch = "arm"))]
    {
        row_binary(row, t)
    }
}

/// Weighted mode, 8-bit pixels: weight `value - t` for value `> t` (see [`row_weighted_u16`]).
/// On 32-bit ARM: blocks of 64 pixels whose OR is not above `t` are skipped (four pixels per
/// word load), `max` as on the binary ARM path.
#[inline(always)]
pub fn row_weighted_u8(row: &[u8], t: u8) -> RowSums {
    #[cfg(target_arch = "arm")]
    {
        super::m4::row_weighted_u8(row, t)
    }
    #[cfg(not(target_arch = "arm"))]
    {
        row_weighted(row, t)
    }
}

/// Weighted mode, 16-bit pixels: weight `value - t` for value `> t`.
///
/// Blocks of [`BLOCK`] pixels keep a 32-bit block-local moment
/// (`<= 65 535 * (255 * 256 / 2) < 2^31`), added to the 64-bit row moment as
/// `local + x_block * weight_block`. Rows longer than [`MAX_DIM`] pixels are clipped to it.
/// On 32-bit ARM: the block skip of [`row_binary_u16`].
#[inline(always)]
pub fn row_weighted_u16(row: &[u16], t: u16) -> RowSums {
    #[cfg(target_arch = "arm")]
    {
        super::m4::row_weighted_u16(row, t)
    }
    #[cfg(not(target_arch = "arm"))]
    {
        row_weighted(row, t)
    }
}

// portable kernels; on 32-bit ARM the `m4` ones replace them (the host tests compare both)
#[cfg_attr(target_arch = "arm", allow(dead_code))]
#[inline(always)]
fn row_binary<P: Pixel>(row: &[P], t: P) -> RowSums {
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

// portable kernels; on 32-bit ARM the `m4` ones replace them (the host tests compare both)
#[cfg_attr(target_arch = "arm", allow(dead_code))]
#[inline(always)]
fn row_weighted<P: Pixel>(row: &[P], t: P) -> RowSums {
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
