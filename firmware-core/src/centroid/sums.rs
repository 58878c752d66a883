//! What the row kernels of every backend return ([`RowSums`], [`WindowSums`]), the grey level
//! arithmetic they share ([`Level`]) and the row clip that keeps their accumulators in range.
//! The backends (`portable`, `m4`) use only this module; `pixel` chooses between them.

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
/// `row_binary_u8` (without `max`), the first column above `t` left of `left` and the last
/// one from `right` on (relative to the segment; `u32::MAX` when there is none: only what can
/// widen the extent found so far is searched) and whether a pixel is at or above the
/// saturation level.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WindowSums {
    pub pixels: u32,
    pub sum_x: u64,
    pub first: u32,
    pub last: u32,
    pub saturated: bool,
}

/// A grey level the kernels can work on (`u8`, `u16`): ordered, widened to `u16`, and the
/// weighted mode's weight.
pub trait Level: Copy + Ord + Default + Into<u16> + 'static {
    /// `self - t` if `self > t`, else 0 (the weighted-mode weight).
    fn excess(self, t: Self) -> u32;
}

impl Level for u8 {
    #[inline(always)]
    fn excess(self, t: Self) -> u32 {
        u32::from(self.saturating_sub(t))
    }
}

impl Level for u16 {
    #[inline(always)]
    fn excess(self, t: Self) -> u32 {
        u32::from(self.saturating_sub(t))
    }
}

/// At most [`MAX_DIM`] pixels of `row` (the accumulator bounds rely on it).
#[inline(always)]
pub fn clip<P>(row: &[P]) -> &[P] {
    row.get(..MAX_DIM).unwrap_or(row)
}
