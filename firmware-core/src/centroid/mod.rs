//! Thresholded centre of gravity of the bright target(s) in a frame, row by row (method.md §2.1).
//!
//! # Conventions
//!
//! Pixel (0,0) is the top-left pixel, `x` grows to the right and `y` downwards, both in pixels
//! of the **full frame** (a region of interest does not move the origin). The centroid of a
//! single pixel at column `i`, row `j` is exactly `(i, j)`.
//!
//! * [`Mode::Binary`] (the paper's): every pixel with value `> T` has weight 1.
//! * [`Mode::Weighted`]: every pixel with value `> T` has weight `value - T` (linear in the image
//!   when `T` is the background level, so the centroid of a blurred frame is the time average of
//!   the instantaneous centroids).
//!
//! # Streaming
//!
//! A camera DMA delivers lines, so everything works one row at a time:
//! [`Centroider`] (one target: the centre of gravity of *all* pixels above `T`, O(1) memory) and
//! [`MultiCentroider`] (connected components with 8-connectivity, a label buffer of one row of
//! at most `W` pixels and at most `N` targets; results as a `heapless::Vec`), and
//! [`track::Tracker`] (one target in a tracking window: only the rows and columns around the
//! last position). Every function is generic over the pixel type ([`Pixel`]: `u8`, `u16`); a
//! whole frame is a checked view, [`Frame`] (pixels, width, height, stride validated once), and
//! [`centroid`] is the one-shot whole-frame convenience on top of the single-target streamer.
//! Configuration ([`CentroidConfig`], checked once by [`CentroidConfig::validate`], which every
//! `try_new` calls) and state are separate types; after validation nothing can fail, nothing
//! panics and nothing allocates.
//!
//! ```
//! use firmware_core::centroid::{CentroidConfig, Centroider, Flags};
//! // a 3 x 3 target centred on column 5, row 2 of an 8-bit frame, pushed row by row
//! let mut c = Centroider::try_new(CentroidConfig::binary(100)).unwrap();
//! let dark = [0u8; 10];
//! let lit = [0u8, 0, 0, 0, 200, 200, 200, 0, 0, 0];
//! for row in [&dark, &lit, &lit, &lit, &dark] {
//!     c.push_row(row);
//! }
//! let r = c.result();
//! assert_eq!(r.position(), Some((5.0, 2.0)));
//! assert_eq!((r.pixels(), r.flags), (9, Flags::NONE));
//! ```
//!
//! # Exactness and overflow
//!
//! The moments are exact integers ([`Moments`]): frames and ROIs are limited to
//! [`MAX_DIM`] x [`MAX_DIM`] = 65 536 x 65 536 pixels (longer rows are clipped and flagged
//! [`Flags::CLIPPED`], rows past [`MAX_DIM`] are ignored), so with `x, y <= 65 535` and
//! weights `<= 65 535`:
//!
//! * `pixels <= 2^32` and `weight <= 2^32 * 65 535 < 2^48`;
//! * `sum_x = sum x * w <= 65 535 * 65 536 * (65 535 * 65 536 / 2) < 2^63`, same for `sum_y`.
//!
//! `u64` therefore cannot overflow even for the largest frame; a 4096 x 4096 frame of
//! full-scale 16-bit pixels reaches `sum_x = 65 535 * 4096 * 4095 * 2048 < 2^51` (first moments
//! do not need `u128`; second moments would). The position is computed from the integer sums
//! as `q + r / weight` with `q, r` the integer quotient and remainder, in `f64`, then rounded
//! to `f32`, so it is correctly rounded to within one `f32` ulp. A frame without any pixel above
//! the threshold has no centroid: the result carries [`Flags::EMPTY`], `cx = cy = 0` and
//! [`Centroid::position`] is `None`. No NaN ever leaves this module.
//!
//! # Flags
//!
//! Every result carries [`Flags`]: [`Flags::EMPTY`] (no pixel above threshold),
//! [`Flags::BORDER`] (the target touches the first/last row or column of the ROI, or of the
//! frame without ROI: the centroid is biased), [`Flags::SATURATED`] (a pixel of the target is at
//! or above the saturation level), [`Flags::CAPACITY`] (multi-target only: more components than
//! the capacity; pixels of the excess components were dropped), [`Flags::CLIPPED`] (a row wider
//! than the supported width: the columns past it were ignored).

#[cfg(any(test, target_arch = "arm"))]
mod m4;
mod multi;
mod pixel;
mod portable;
mod sums;
pub mod track;

#[cfg(test)]
mod tests;

use core::fmt;

pub use multi::{BoundingBox, MultiCentroider, Target};
pub use pixel::{row_binary_u16, row_binary_u8, row_weighted_u16, row_weighted_u8, Pixel};
pub use sums::{RowSums, BLOCK};

/// Largest frame width and height (pixels) the moments are proven not to overflow for.
pub const MAX_DIM: usize = 65_536;

/// How pixels above the threshold are weighted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Mode {
    /// Weight 1 for every pixel with value `> T` (the paper's method).
    #[default]
    Binary,
    /// Weight `value - T` for every pixel with value `> T`.
    Weighted,
}

/// Region of interest, in full-frame pixel coordinates: columns `x .. x + width`, rows
/// `y .. y + height`. Valid when `width, height >= 1` and `x + width, y + height <= MAX_DIM`.
/// The [`track`] module moves one from frame to frame (the tracking window).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Roi {
    /// First column (pixels from the left edge).
    pub x: u32,
    /// First row (pixels from the top edge).
    pub y: u32,
    /// Number of columns, >= 1.
    pub width: u32,
    /// Number of rows, >= 1.
    pub height: u32,
}

impl Roi {
    /// One past the last column.
    pub const fn x_end(&self) -> u32 {
        self.x.saturating_add(self.width)
    }

    /// One past the last row.
    pub const fn y_end(&self) -> u32 {
        self.y.saturating_add(self.height)
    }
}

/// Why a [`CentroidConfig`] (or a [`MultiCentroider`]) cannot be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ConfigError {
    /// The ROI has zero width or height.
    EmptyRoi,
    /// The ROI reaches past [`MAX_DIM`] in x or y.
    RoiTooLarge,
    /// The ROI is wider than the row label buffer of a [`MultiCentroider`].
    RoiTooWide {
        /// ROI width (pixels).
        width: u32,
        /// Label buffer width `W` (pixels).
        max: usize,
    },
    /// The saturation level is not above the threshold (every target pixel would be saturated).
    SaturationNotAboveThreshold {
        /// Threshold `T`.
        threshold: u16,
        /// Saturation level.
        saturation: u16,
    },
}

error_display!(ConfigError, f, {
    ConfigError::EmptyRoi => write!(f, "region of interest has zero width or height"),
    ConfigError::RoiTooLarge => {
        write!(f, "region of interest reaches past {MAX_DIM} pixels")
    }
    ConfigError::RoiTooWide { width, max } => write!(
        f,
        "region of interest is {width} pixels wide, the label buffer holds {max}"
    ),
    ConfigError::SaturationNotAboveThreshold {
        threshold,
        saturation,
    } => write!(
        f,
        "saturation level {saturation} must be above the threshold {threshold}"
    ),
});

/// Why a whole frame cannot be processed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FrameError {
    /// Width or height is zero.
    Empty,
    /// Width or height above [`MAX_DIM`] (or the label buffer width of a [`MultiCentroider`]).
    TooLarge {
        /// Frame width (pixels).
        width: usize,
        /// Frame height (pixels).
        height: usize,
    },
    /// The stride (pixels from one row start to the next) is smaller than the width.
    Stride {
        /// Stride (pixels).
        stride: usize,
        /// Width (pixels).
        width: usize,
    },
    /// The pixel slice is shorter than `(height - 1) * stride + width`.
    BufferTooShort {
        /// Pixels needed.
        needed: usize,
        /// Pixels given.
        got: usize,
    },
    /// The configured ROI does not lie inside the frame.
    RoiOutsideFrame,
    /// The settings are invalid (only from the one-shot [`centroid`], which takes an
    /// unchecked [`CentroidConfig`]).
    Config(ConfigError),
}

error_display!(FrameError, f, {
    FrameError::Empty => write!(f, "frame has zero width or height"),
    FrameError::TooLarge { width, height } => {
        write!(f, "frame of {width} x {height} pixels is too large")
    }
    FrameError::Stride { stride, width } => {
        write!(f, "row stride {stride} is smaller than the width {width}")
    }
    FrameError::BufferTooShort { needed, got } => {
        write!(f, "frame buffer has {got} pixels, the frame needs {needed}")
    }
    FrameError::RoiOutsideFrame => {
        write!(f, "region of interest does not lie inside the frame")
    }
    FrameError::Config(e) => write!(f, "invalid settings: {e}"),
});

/// Result flags, a small bit set. `as u8` / [`Flags::bits`] give the bit mask printed by the
/// command line; [`fmt::Display`] prints the names joined by `|` (`none` for no flag).
///
/// | bit | value | name | meaning |
/// |---|---|---|---|
/// | 0 | 1 | `empty` | no pixel above the threshold: no centroid |
/// | 1 | 2 | `border` | the target touches the first/last row or column of the ROI (or frame) |
/// | 2 | 4 | `saturated` | a target pixel is at or above the saturation level |
/// | 3 | 8 | `capacity` | more components than the target capacity (multi-target) |
/// | 4 | 16 | `clipped` | a row was wider than supported; columns past it were ignored |
/// | 5 | 32 | `flat` | gradient tracker: too little texture in the window (lost) |
/// | 6 | 64 | `diverged` | gradient tracker: no match, or the motion may exceed the search (lost) |
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Flags(u8);

impl Flags {
    /// No flag set.
    pub const NONE: Flags = Flags(0);
    /// No pixel above the threshold: there is no centroid.
    pub const EMPTY: Flags = Flags(1);
    /// The target touches the border of the ROI (or of the frame): its centroid is biased.
    pub const BORDER: Flags = Flags(2);
    /// At least one target pixel is at or above the saturation level.
    pub const SATURATED: Flags = Flags(4);
    /// More connected components than the target capacity: pixels were dropped.
    pub const CAPACITY: Flags = Flags(8);
    /// A row was wider than supported ([`MAX_DIM`] or the label buffer): columns were ignored.
    pub const CLIPPED: Flags = Flags(16);
    /// Gradient tracker ([`crate::lk`]): the template has too little texture in some direction.
    pub const FLAT: Flags = Flags(32);
    /// Gradient tracker ([`crate::lk`]): no match (score below the minimum, the refinement did
    /// not settle, or the motion may exceed the search range).
    pub const DIVERGED: Flags = Flags(64);
    /// Gradient tracker ([`crate::lk`]): the coarse search found a second match, away from the
    /// best, nearly as good as it (a look-alike target): which one is the target is not known.
    pub const AMBIGUOUS: Flags = Flags(128);

    /// Every flag with its name, in bit order.
    pub const NAMES: [(Flags, &'static str); 8] = [
        (Flags::EMPTY, "empty"),
        (Flags::BORDER, "border"),
        (Flags::SATURATED, "saturated"),
        (Flags::CAPACITY, "capacity"),
        (Flags::CLIPPED, "clipped"),
        (Flags::FLAT, "flat"),
        (Flags::DIVERGED, "diverged"),
        (Flags::AMBIGUOUS, "ambiguous"),
    ];

    /// The bit mask (see the table above).
    pub const fn bits(self) -> u8 {
        self.0
    }

    /// Flags from a bit mask; unknown bits are dropped.
    pub const fn from_bits_truncate(bits: u8) -> Self {
        Flags(bits & 0x7f)
    }

    /// Whether every flag of `other` is set in `self`.
    pub const fn contains(self, other: Flags) -> bool {
        self.0 & other.0 == other.0
    }

    /// Whether no flag is set (a clean result).
    pub const fn is_clear(self) -> bool {
        self.0 == 0
    }

    /// The flags of both.
    #[must_use]
    pub const fn union(self, other: Flags) -> Flags {
        Flags(self.0 | other.0)
    }

    /// Sets the flags of `other`.
    pub fn insert(&mut self, other: Flags) {
        self.0 |= other.0;
    }

    /// Sets the flags of `other` when `on`.
    fn set_if(&mut self, other: Flags, on: bool) {
        self.0 |= other.0 * u8::from(on);
    }
}

impl core::ops::BitOr for Flags {
    type Output = Flags;
    fn bitor(self, rhs: Flags) -> Flags {
        self.union(rhs)
    }
}

impl core::ops::BitOrAssign for Flags {
    fn bitor_assign(&mut self, rhs: Flags) {
        self.insert(rhs);
    }
}

impl From<Flags> for u8 {
    fn from(f: Flags) -> u8 {
        f.0
    }
}

impl fmt::Display for Flags {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_clear() {
            return f.write_str("none");
        }
        let mut first = true;
        for (flag, name) in Flags::NAMES {
            if self.contains(flag) {
                if !first {
                    f.write_str("|")?;
                }
                f.write_str(name)?;
                first = false;
            }
        }
        Ok(())
    }
}

impl fmt::Debug for Flags {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Flags({self})")
    }
}

/// Centroiding settings: plain data, `const` constructors for the usual cases, checked once
/// by [`validate`](Self::validate) (which [`Centroider::try_new`],
/// [`MultiCentroider::try_new`] and [`track::Tracker::try_new`] call). `Copy`.
///
/// ```
/// use firmware_core::centroid::{CentroidConfig, Mode, Roi};
/// const CONFIG: CentroidConfig = CentroidConfig::weighted(100)
///     .with_roi(Roi { x: 8, y: 4, width: 64, height: 48 })
///     .with_saturation(250);
/// const _: () = assert!(CONFIG.validate().is_ok()); // checked at compile time
/// assert_eq!(CONFIG.mode, Mode::Weighted);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CentroidConfig {
    /// Threshold `T`, grey levels (0 ..= 65 535): a pixel counts when its value is `> T`.
    /// For 8-bit frames a `T >= 255` selects nothing.
    pub threshold: u16,
    /// Weighting of the pixels above `T`.
    pub mode: Mode,
    /// Region of interest (non-empty, inside [`MAX_DIM`] x [`MAX_DIM`]); `None`: the whole
    /// frame.
    pub roi: Option<Roi>,
    /// Grey level at or above which a pixel is saturated, above `threshold`; `None`: the
    /// largest code of the pixel type (255 or 65 535). For 8-bit frames a level above 255
    /// acts as 255.
    pub saturation: Option<u16>,
}

impl CentroidConfig {
    /// Binary mode (the paper's) with threshold `T`, no ROI, the default saturation level
    /// (always valid).
    pub const fn binary(threshold: u16) -> Self {
        CentroidConfig {
            threshold,
            mode: Mode::Binary,
            roi: None,
            saturation: None,
        }
    }

    /// Weighted mode with threshold `T`, no ROI, the default saturation level (always valid).
    pub const fn weighted(threshold: u16) -> Self {
        CentroidConfig {
            mode: Mode::Weighted,
            ..Self::binary(threshold)
        }
    }

    /// The same settings restricted to `roi`.
    #[must_use]
    pub const fn with_roi(self, roi: Roi) -> Self {
        CentroidConfig {
            roi: Some(roi),
            ..self
        }
    }

    /// The same settings with saturation level `level`.
    #[must_use]
    pub const fn with_saturation(self, level: u16) -> Self {
        CentroidConfig {
            saturation: Some(level),
            ..self
        }
    }

    /// Checks the settings and returns them: a non-empty ROI inside [`MAX_DIM`] x
    /// [`MAX_DIM`], a saturation level above the threshold.
    pub const fn validate(self) -> Result<Self, ConfigError> {
        if let Some(r) = self.roi {
            if r.width == 0 || r.height == 0 {
                return Err(ConfigError::EmptyRoi);
            }
            if r.x as u64 + r.width as u64 > MAX_DIM as u64
                || r.y as u64 + r.height as u64 > MAX_DIM as u64
            {
                return Err(ConfigError::RoiTooLarge);
            }
        }
        if let Some(s) = self.saturation {
            if s <= self.threshold {
                return Err(ConfigError::SaturationNotAboveThreshold {
                    threshold: self.threshold,
                    saturation: s,
                });
            }
        }
        Ok(self)
    }

    /// Saturation level for pixels whose largest code is `full`.
    const fn saturation_for(&self, full: u16) -> u16 {
        match self.saturation {
            Some(s) if s < full => s,
            _ => full,
        }
    }

    /// Region rows `y0 .. y1` (frame coordinates).
    const fn rows(&self) -> (u32, u32) {
        match self.roi {
            Some(r) => (r.y, r.y_end()),
            None => (0, MAX_DIM as u32),
        }
    }

    /// Counts the row `*next_y` of a frame and returns it with the region's first row `y0` when
    /// it lies in the region; a row outside is skipped, and flagged [`Flags::CLIPPED`] when it
    /// lies past [`MAX_DIM`] with no ROI (beyond the proven accumulator range).
    #[inline(always)]
    fn enter_row(&self, next_y: &mut u32, flags: &mut Flags) -> Option<(u32, u32)> {
        let y = *next_y;
        *next_y = y.saturating_add(1);
        let (y0, y1) = self.rows();
        if y < y0 || y >= y1 {
            flags.set_if(Flags::CLIPPED, self.roi.is_none() && y >= y1);
            return None;
        }
        Some((y, y0))
    }

    /// Region columns `x0 .. x1` (frame coordinates).
    const fn cols(&self) -> (usize, usize) {
        match self.roi {
            Some(r) => (r.x as usize, r.x_end() as usize),
            None => (0, MAX_DIM),
        }
    }

    /// Checks that the region (ROI, or the frame) fits a frame and a label buffer of
    /// `max_width` pixels.
    fn check_region<P>(&self, frame: &Frame<'_, P>, max_width: usize) -> Result<(), FrameError> {
        let (width, height) = (frame.width(), frame.height());
        let region_width = match self.roi {
            Some(r) => r.width as usize,
            None => width,
        };
        if region_width > max_width {
            return Err(FrameError::TooLarge { width, height });
        }
        if let Some(r) = self.roi {
            if r.x_end() as usize > width || r.y_end() as usize > height {
                return Err(FrameError::RoiOutsideFrame);
            }
        }
        Ok(())
    }
}

/// A checked view of a whole frame: `height` rows of `width` pixels, row `j` starting at
/// `pixels[j * stride]` (`stride >= width` lets a frame live inside a wider buffer). The shape
/// is validated once, by [`Frame::new`]; every function that takes a `Frame` then trusts it.
///
/// ```
/// use firmware_core::centroid::{centroid, CentroidConfig, Frame};
/// let mut pixels = [0u8; 6 * 4];
/// pixels[2 * 6 + 3] = 200; // column 3, row 2
/// let frame = Frame::new(&pixels, 6, 4, 6).unwrap();
/// let c = centroid(&CentroidConfig::binary(100), &frame).unwrap();
/// assert_eq!(c.position(), Some((3.0, 2.0)));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Frame<'a, P> {
    pixels: &'a [P],
    width: usize,
    height: usize,
    stride: usize,
}

impl<'a, P> Frame<'a, P> {
    /// Checks the shape: `width, height` in `1 ..= MAX_DIM`, `stride >= width`, and
    /// `pixels` holding at least `(height - 1) * stride + width` values.
    pub const fn new(
        pixels: &'a [P],
        width: usize,
        height: usize,
        stride: usize,
    ) -> Result<Self, FrameError> {
        if width == 0 || height == 0 {
            return Err(FrameError::Empty);
        }
        if width > MAX_DIM || height > MAX_DIM {
            return Err(FrameError::TooLarge { width, height });
        }
        if stride < width {
            return Err(FrameError::Stride { stride, width });
        }
        let needed = match (height - 1).checked_mul(stride) {
            Some(v) => match v.checked_add(width) {
                Some(n) => n,
                None => usize::MAX,
            },
            None => usize::MAX,
        };
        if pixels.len() < needed {
            return Err(FrameError::BufferTooShort {
                needed,
                got: pixels.len(),
            });
        }
        Ok(Frame {
            pixels,
            width,
            height,
            stride,
        })
    }

    /// Width, pixels.
    pub const fn width(&self) -> usize {
        self.width
    }

    /// Height, rows.
    pub const fn height(&self) -> usize {
        self.height
    }

    /// Pixels from one row start to the next.
    pub const fn stride(&self) -> usize {
        self.stride
    }

    /// The pixel buffer.
    pub const fn pixels(&self) -> &'a [P] {
        self.pixels
    }

    /// Row `y` (exactly `width` pixels), `None` past the last row.
    pub fn row(&self, y: usize) -> Option<&'a [P]> {
        if y >= self.height {
            return None;
        }
        let start = y * self.stride;
        self.pixels.get(start..start + self.width)
    }

    /// The rows top to bottom, each exactly `width` pixels.
    pub fn rows(&self) -> impl Iterator<Item = &'a [P]> + 'a {
        let width = self.width;
        self.pixels
            .chunks(self.stride.max(1))
            .take(self.height)
            .map(move |r| r.get(..width).unwrap_or(r))
    }
}

/// Exact integer moments of the pixels above the threshold (coordinates in full-frame pixels).
/// See the module documentation for why `u64` cannot overflow.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Moments {
    /// Number of pixels above the threshold.
    pub pixels: u64,
    /// Sum of the weights (equals `pixels` in binary mode).
    pub weight: u64,
    /// Sum of `x * weight`.
    pub sum_x: u64,
    /// Sum of `y * weight`.
    pub sum_y: u64,
}

/// `num / den` correctly rounded to `f32` (within one ulp); 0 when `den == 0`.
fn ratio(num: u64, den: u64) -> f32 {
    match (num.checked_div(den), num.checked_rem(den)) {
        (Some(q), Some(r)) => (q as f64 + r as f64 / den as f64) as f32,
        _ => 0.0,
    }
}

impl Moments {
    /// Adds one row's sums: `x0` is the frame column of the slice's first pixel, `y` the row.
    #[inline]
    fn add_row(&mut self, s: &RowSums, x0: u64, y: u64) {
        let w = u64::from(s.weight);
        self.pixels += u64::from(s.pixels);
        self.weight += w;
        self.sum_x += s.sum_x + x0 * w;
        self.sum_y += y * w;
    }

    /// Adds another set of moments.
    fn merge(&mut self, o: &Moments) {
        self.pixels += o.pixels;
        self.weight += o.weight;
        self.sum_x += o.sum_x;
        self.sum_y += o.sum_y;
    }

    /// Centre of gravity `(cx, cy)` in pixels, `None` when no pixel is above the threshold.
    pub fn position(&self) -> Option<(f32, f32)> {
        if self.weight == 0 {
            None
        } else {
            Some((
                ratio(self.sum_x, self.weight),
                ratio(self.sum_y, self.weight),
            ))
        }
    }
}

/// Centroid of one target (or of all pixels above the threshold, for [`Centroider`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Centroid {
    /// Centre of gravity, column (pixels, 0 = centre of the left column); 0 when
    /// [`Flags::EMPTY`].
    pub cx: f32,
    /// Centre of gravity, row (pixels, 0 = centre of the top row); 0 when [`Flags::EMPTY`].
    pub cy: f32,
    /// The exact integer sums `cx` and `cy` come from.
    pub moments: Moments,
    /// Result flags.
    pub flags: Flags,
}

impl Centroid {
    /// Builds a result from moments and flags (sets [`Flags::EMPTY`] when there is no weight).
    fn from_moments(moments: Moments, mut flags: Flags) -> Self {
        match moments.position() {
            Some((cx, cy)) => Centroid {
                cx,
                cy,
                moments,
                flags,
            },
            None => {
                flags.insert(Flags::EMPTY);
                Centroid {
                    cx: 0.0,
                    cy: 0.0,
                    moments,
                    flags,
                }
            }
        }
    }

    /// `(cx, cy)`, or `None` when no pixel was above the threshold.
    pub fn position(&self) -> Option<(f32, f32)> {
        if self.flags.contains(Flags::EMPTY) {
            None
        } else {
            Some((self.cx, self.cy))
        }
    }

    /// Number of pixels above the threshold.
    pub fn pixels(&self) -> u64 {
        self.moments.pixels
    }
}

/// Streaming single-target centroider: push the rows of a frame top to bottom, read the
/// [`result`](Self::result), [`reset`](Self::reset) for the next frame. O(1) memory.
///
/// Rows are full frame rows (column 0 first); the ROI, if any, selects rows and columns.
/// The bottom border of the region is the last row pushed inside it (the ROI's last row, or
/// the frame's last row when the frame ends first). A row shorter than the ROI is used up to
/// its end (that end is then the right border for this row).
#[derive(Debug, Clone)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Centroider {
    config: CentroidConfig,
    /// Frame row index of the next pushed row.
    next_y: u32,
    moments: Moments,
    flags: Flags,
    /// Whether the last processed region row had a pixel above the threshold.
    last_row_hit: bool,
}

impl Centroider {
    /// A centroider with the all-zero settings [`CentroidConfig::binary`]`(0)` (valid, but
    /// rarely what a firmware wants): a `static` built in place, then
    /// [`configure`](Self::configure)d.
    pub const fn new() -> Self {
        Self::with(CentroidConfig::binary(0))
    }

    /// A centroider for one frame at a time with the given settings (checked by
    /// [`CentroidConfig::validate`]). `const`: a `static` initialiser builds it in place,
    /// checked at compile time.
    pub const fn try_new(config: CentroidConfig) -> Result<Self, ConfigError> {
        match config.validate() {
            Ok(config) => Ok(Self::with(config)),
            Err(e) => Err(e),
        }
    }

    /// Replaces the settings in place (checked as in [`try_new`](Self::try_new)) and forgets
    /// the current frame. On error nothing changes.
    pub fn configure(&mut self, config: CentroidConfig) -> Result<(), ConfigError> {
        *self = Self::with(config.validate()?);
        Ok(())
    }

    /// A fresh state for already validated settings.
    const fn with(config: CentroidConfig) -> Self {
        Centroider {
            config,
            next_y: 0,
            moments: Moments {
                pixels: 0,
                weight: 0,
                sum_x: 0,
                sum_y: 0,
            },
            flags: Flags::NONE,
            last_row_hit: false,
        }
    }

    /// The settings.
    pub const fn config(&self) -> &CentroidConfig {
        &self.config
    }

    /// Forgets the current frame; the next pushed row is row 0.
    pub fn reset(&mut self) {
        *self = Centroider::with(self.config);
    }

    /// Number of rows pushed since the last reset (saturates at `u32::MAX`).
    pub const fn rows(&self) -> u32 {
        self.next_y
    }

    /// Pushes the next row of the frame (8- or 16-bit pixels, column 0 first). O(1) memory,
    /// infallible: rows past the region are skipped, columns past [`MAX_DIM`] are ignored and
    /// flagged [`Flags::CLIPPED`].
    #[inline(always)]
    pub fn push_row<P: Pixel>(&mut self, row: &[P]) {
        let t = P::threshold(self.config.threshold);
        let sat = self.config.saturation_for(P::FULL);
        let binary = self.config.mode == Mode::Binary;
        self.push(row, t, sat, |seg| P::row_sums(seg, t, binary));
    }

    /// Resets, then processes a whole frame; error only when the configured ROI does not lie
    /// inside the frame (then nothing changes).
    pub fn process<P: Pixel>(&mut self, frame: &Frame<'_, P>) -> Result<Centroid, FrameError> {
        self.config.check_region(frame, MAX_DIM)?;
        self.reset();
        self.push_frame_rows(frame);
        Ok(self.result())
    }

    /// Pushes every row of `frame`, with the settings read once and the loop specialised
    /// for the mode (the per-row overhead is a measurable part of a sparse frame's cost).
    fn push_frame_rows<P: Pixel>(&mut self, frame: &Frame<'_, P>) {
        let t = P::threshold(self.config.threshold);
        let sat = self.config.saturation_for(P::FULL);
        if self.config.mode == Mode::Binary {
            for row in frame.rows() {
                self.push(row, t, sat, |seg| P::row_sums(seg, t, true));
            }
        } else {
            for row in frame.rows() {
                self.push(row, t, sat, |seg| P::row_sums(seg, t, false));
            }
        }
    }

    #[inline(always)]
    fn push<P: Pixel>(&mut self, row: &[P], t: P, sat: u16, kernel: impl FnOnce(&[P]) -> RowSums) {
        let Some((y, y0)) = self.config.enter_row(&mut self.next_y, &mut self.flags) else {
            return;
        };
        let (x0, x1) = self.config.cols();
        let end = x1.min(row.len());
        self.flags.set_if(Flags::CLIPPED, row.len() > MAX_DIM);
        let seg = row.get(x0..end).unwrap_or(&[]);
        let s = kernel(seg);
        self.moments.add_row(&s, x0 as u64, u64::from(y));
        let hit = s.pixels > 0;
        let edge =
            y == y0 || seg.first().is_some_and(|&p| p > t) || seg.last().is_some_and(|&p| p > t);
        self.flags.set_if(Flags::BORDER, hit && edge);
        self.flags.set_if(Flags::SATURATED, hit && s.max >= sat);
        self.last_row_hit = hit;
    }

    /// [`push`](Self::push) for a region row `y` whose segment (`seg_len` pixels from column
    /// `x0` of a row of `row_len`) went through the tracking window's one-pass kernel.
    fn push_window(&mut self, w: &sums::WindowSums, y: u32, x0: usize, ends: bool, row_len: usize) {
        self.next_y = y.saturating_add(1);
        self.flags.set_if(Flags::CLIPPED, row_len > MAX_DIM);
        let s = RowSums {
            pixels: w.pixels,
            weight: w.pixels,
            sum_x: w.sum_x,
            max: 0,
        };
        self.moments.add_row(&s, x0 as u64, u64::from(y));
        let hit = w.pixels > 0;
        let (y0, _) = self.config.rows();
        let edge = y == y0 || ends;
        self.flags.set_if(Flags::BORDER, hit && edge);
        self.flags.set_if(Flags::SATURATED, hit && w.saturated);
        self.last_row_hit = hit;
    }

    /// The centroid of the rows pushed so far (the frame's result once its last row is in).
    pub fn result(&self) -> Centroid {
        let mut flags = self.flags;
        flags.set_if(Flags::BORDER, self.last_row_hit);
        Centroid::from_moments(self.moments, flags)
    }
}

impl Default for Centroider {
    fn default() -> Self {
        Self::new()
    }
}

/// Single-target centroid of a whole frame (8- or 16-bit), a one-shot convenience that
/// checks the settings and the ROI against the frame (a streaming firmware builds a
/// [`Centroider`] once and pushes rows). Allocation-free.
pub fn centroid<P: Pixel>(
    config: &CentroidConfig,
    frame: &Frame<'_, P>,
) -> Result<Centroid, FrameError> {
    let config = config.validate().map_err(FrameError::Config)?;
    config.check_region(frame, MAX_DIM)?;
    let mut c = Centroider::with(config);
    c.push_frame_rows(frame);
    Ok(c.result())
}
