//! The pixel types the centroiders accept ([`Pixel`]: `u8`, `u16`), the public row kernels,
//! and the one place a backend is chosen:
//!
//! * row kernels: `m4` (SWAR, four pixels per word) on 32-bit ARM, `portable` elsewhere;
//! * the tracking window's one-pass binary 8-bit kernel and its column test: `m4` on 32-bit
//!   ARM and in the host's tests (so that every tracking test runs the kernel the MCU runs);
//!   elsewhere the window goes row by row through the row kernels.
//!
//! Each backend uses only `sums`; neither knows the other or this module.

use super::sums::RowSums;
#[cfg(any(test, target_arch = "arm"))]
use super::sums::WindowSums;

#[cfg(target_arch = "arm")]
use super::m4 as backend;
#[cfg(not(target_arch = "arm"))]
use super::portable as backend;

#[cfg(any(test, target_arch = "arm"))]
use super::m4 as window;

pub(crate) mod sealed {
    use super::super::sums::{Level, RowSums, WindowSums};

    /// The kernels of a pixel type (sealed: implemented for `u8` and `u16` only, not
    /// nameable outside the crate).
    pub trait Kernels: Level {
        /// The threshold `t` for this pixel type (8-bit: `t >= 255` selects nothing).
        fn threshold(t: u16) -> Self;

        /// The pixels as bytes when they are 8-bit (the kernels that pack them 16 to a
        /// register).
        #[inline(always)]
        fn bytes(_row: &[Self]) -> Option<&[u8]> {
            None
        }

        /// The row kernel of this type and mode.
        fn row_sums(row: &[Self], t: Self, binary: bool) -> RowSums;

        /// The one-pass kernel of the tracking window for this type and mode, if the backend
        /// has one; `sat` is the saturation level.
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

        /// Bit `i` (`0..4`): column `start + i` has a pixel above `t` in `rows` rows of
        /// `pixels`, `stride` apart from `start`.
        #[inline(always)]
        fn column_group(pixels: &[Self], start: usize, stride: usize, rows: usize, t: Self) -> u32 {
            super::super::portable::column_group(pixels, start, stride, rows, t)
        }
    }
}

/// Grey pixel types the centroiders accept: `u8` and `u16` (sealed). Every function that
/// takes rows or a [`Frame`](super::Frame) is generic over it, in place of `_u8` / `_u16`
/// twins; each type keeps its own kernels ([`row_binary_u8`], [`row_weighted_u16`], ...).
pub trait Pixel: sealed::Kernels {
    /// The largest code (255 or 65 535): the default saturation level.
    const FULL: u16;
}

impl Pixel for u8 {
    const FULL: u16 = 255;
}

impl Pixel for u16 {
    const FULL: u16 = u16::MAX;
}

impl sealed::Kernels for u8 {
    #[inline(always)]
    fn bytes(row: &[u8]) -> Option<&[u8]> {
        Some(row)
    }

    #[inline(always)]
    fn threshold(t: u16) -> Self {
        if t > 255 {
            255
        } else {
            t as u8
        }
    }

    #[inline(always)]
    fn row_sums(row: &[Self], t: Self, binary: bool) -> RowSums {
        if binary {
            row_binary_u8(row, t)
        } else {
            row_weighted_u8(row, t)
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
            Some(window::window_binary_u8(seg, t, sat, left, right))
        } else {
            None
        }
    }

    #[cfg(any(test, target_arch = "arm"))]
    #[inline(always)]
    fn column_group(pixels: &[Self], start: usize, stride: usize, rows: usize, t: Self) -> u32 {
        window::column_group_u8(pixels, start, stride, rows, t)
    }
}

impl sealed::Kernels for u16 {
    #[inline(always)]
    fn threshold(t: u16) -> Self {
        t
    }

    #[inline(always)]
    fn row_sums(row: &[Self], t: Self, binary: bool) -> RowSums {
        if binary {
            row_binary_u16(row, t)
        } else {
            row_weighted_u16(row, t)
        }
    }
}

/// Binary mode, 8-bit pixels: count and x moment of the pixels with value `> t`.
///
/// The single-target hot loop: per pixel a compare, two adds (count, masked x) and a max.
/// 32-bit accumulators: `pixels <= 65 536`, `sum_x <= 65 535 * 65 536 / 2 < 2^31`.
/// Rows longer than [`MAX_DIM`](super::MAX_DIM) pixels are clipped to it.
///
/// On 32-bit ARM (Cortex-M) this is the word-at-a-time SWAR kernel of the `m4` submodule
/// (1.1 instructions per pixel on a one-target 320 x 240 frame on a Cortex-M4, 5.4 when every
/// 64-pixel block has a pixel above `t`; `mcu-demo/bench.sh`); there `max` is exact when
/// `pixels > 0` (all the centroider reads it for) and 0 otherwise.
#[inline(always)]
pub fn row_binary_u8(row: &[u8], t: u8) -> RowSums {
    backend::row_binary_u8(row, t)
}

/// Binary mode, 16-bit pixels (same as [`row_binary_u8`]). On 32-bit ARM: blocks of 64 pixels
/// whose OR is not above `t` are skipped (two pixels per word), `max` as on that path.
#[inline(always)]
pub fn row_binary_u16(row: &[u16], t: u16) -> RowSums {
    backend::row_binary_u16(row, t)
}

/// Weighted mode, 8-bit pixels: weight `value - t` for value `> t` (see [`row_weighted_u16`]).
/// On 32-bit ARM: blocks of 64 pixels whose OR is not above `t` are skipped (four pixels per
/// word load), `max` as on the binary ARM path.
#[inline(always)]
pub fn row_weighted_u8(row: &[u8], t: u8) -> RowSums {
    backend::row_weighted_u8(row, t)
}

/// Weighted mode, 16-bit pixels: weight `value - t` for value `> t`.
///
/// Blocks of [`BLOCK`](super::BLOCK) pixels keep a 32-bit block-local moment
/// (`<= 65 535 * (255 * 256 / 2) < 2^31`), added to the 64-bit row moment as
/// `local + x_block * weight_block`. Rows longer than [`MAX_DIM`](super::MAX_DIM) pixels are clipped to it.
/// On 32-bit ARM: the block skip of [`row_binary_u16`].
#[inline(always)]
pub fn row_weighted_u16(row: &[u16], t: u16) -> RowSums {
    backend::row_weighted_u16(row, t)
}
