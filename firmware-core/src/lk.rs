//! Lucas-Kanade tracking of one textured window (docs/method.md §2.11): the sub-pixel
//! translation of a template taken from a reference frame, for targets a threshold cannot
//! separate (speckle, bolts, a beam's edge, tags barely brighter than the wall) and at the
//! noise limit for any target.
//!
//! # Method
//!
//! * **Template**: the `width x height` pixels of the window in the reference frame
//!   ([`LkTracker::set_template`]), with their gradients by central differences (which reads
//!   one pixel around the window) and the 2 x 2 Hessian `H = sum [gx gx, gx gy; gx gy, gy gy]`,
//!   computed once per template: the **inverse-compositional** form (Baker and Matthews, 2004)
//!   for a translation, so an iteration costs one interpolation of the window and two
//!   multiply-adds per pixel.
//! * **Refinement** ([`LkTracker::track`]): from the start `p`, with the error
//!   `e = I(x + p) - T(x)`, `dp = H^-1 sum [gx e, gy e]` and `p <- p - dp`, until `|dp|` is
//!   below [`LkConfig::tolerance`] or after [`LkConfig::max_iterations`] (for a template that
//!   measures one direction only, the step along the other scaled down: [`APERTURE`]).
//!   `I(x + p) - T(x)` is formed in one of two ways ([`Interpolation`]): by default the frame
//!   is read at whole pixels (the window at the whole-pixel part `q` of `p`) and the
//!   template's cubic B-spline (prefiltered once per template, gradients from the spline) is
//!   shifted by `q - p`, as pyidi interpolates its reference; or the frame is interpolated at
//!   `x + p` by Keys' cubic convolution or bilinearly (cheaper on an MCU, more pixel
//!   locking). Every template pixel shares the fractional part, so the interpolation is
//!   separable with the same weights.
//! * **Where to start**: the last displacement. When that does not converge to a match (its
//!   zero-normalised cross-correlation, ZNCC, below [`LkConfig::accept_score`]) and
//!   [`LkConfig::search`] is not 0, a **coarse integer search** over `+-search` pixels around
//!   it: ZNCC of `b x b` block sums of the template and the frame at offsets `b` apart (`b` the
//!   largest of 1, `search / 8` and no more than a third of the window), then of the pixels at
//!   every offset within `+-b` of the best one; the refinement starts there.
//! * **Template refresh**: never by default, so every frame is measured against the reference
//!   frame and no drift accumulates (right for vibration, where the target's appearance does
//!   not change). With [`LkConfig::refresh_below`] above the acceptance level, a match whose
//!   score falls below it (but not below [`LkConfig::min_score`]) re-takes the template at the
//!   current position (appearance change, e.g. slow rotation or lighting); each refresh adds
//!   that frame's refinement error to every later position (drift).
//!
//! # When a result is lost
//!
//! A result has no displacement ([`LkResult::displacement`] is `None`) and the reason in its
//! [`Flags`] when: the window (with the interpolation's support) leaves the frame
//! ([`Flags::BORDER`]); the template has too little texture in some direction (the smaller
//! eigenvalue of `H` per pixel below [`LkConfig::min_texture`]: [`Flags::FLAT`], a uniform
//! window or a straight edge moving along itself); more than `2 + n / 50` of the window's `n`
//! pixels are at or above the saturation level where the template is dark (below 3/4 of that
//! level at the pixel and its eight neighbours: a mask made once per template):
//! [`Flags::SATURATED`], the target brighter than in the reference frame, or a neighbour's
//! clipped pixels: brightness constancy fails (a clipped plateau that moves with the template
//! is tracked);
//! the match is poor (ZNCC below [`LkConfig::min_score`]), the refinement does not settle
//! (last step above 0.1 px), or the coarse search's best offset is on the edge of its range
//! (the motion may exceed it): [`Flags::DIVERGED`]; the coarse search finds a second match
//! at least half the template's larger side from the best that scores within
//! [`LkConfig::ambiguity`] of it (look-alike targets within the search range, the best not
//! clearly the target): [`Flags::AMBIGUOUS`]. A lost frame keeps the last displacement
//! as the next start. Nothing here panics; memory is the tracker's five `N`-value arrays,
//! its `N`-pixel mask of dark template pixels and `10 W` values of row buffers (capacities as
//! const generics).

use crate::centroid::{Flags, Frame, Pixel};
use libm::{fabsf, floorf, sqrtf};

// The per-pixel kernels (cross moments, `[1 2 1]` row smoothing, clip count; on hosts also a
// whole-window smoothing pass and the template forms in vectors): the M4's on 32-bit ARM (a
// scalar FPU: trees of products per row, one rolling pass), vector registers (the `wide`
// crate's types) elsewhere; both in the host's tests.
#[cfg(any(test, not(target_arch = "arm")))]
mod lanes;
#[cfg(any(test, target_arch = "arm"))]
mod m4;

#[cfg(not(target_arch = "arm"))]
use lanes as kernels;
#[cfg(target_arch = "arm")]
use m4 as kernels;

// The tracker by concern: the template, the spline path's moments, the refinement, the frame's
// window, the coarse search (each adds its methods to `LkTracker`).
mod iterate;
mod moments;
mod search;
mod template;
#[cfg(test)]
mod tests;
mod window;

use moments::{window_stride, Cross, Moments};
pub use search::JUMP_FACTOR;
use template::*;

/// How the frame is sampled between pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Interpolation {
    /// Two taps per axis: cheap, but it smooths sharp edges by a shift-dependent amount, a bias
    /// of a few hundredths of a pixel on a hard-edged target.
    Bilinear,
    /// Keys' cubic convolution (`a = -0.5`), four taps per axis: exact for quadratics.
    Bicubic,
    /// The template's cubic B-spline interpolant (prefiltered once per template, as pyidi's
    /// `RectBivariateSpline` of the reference): the template is shifted, the frame read at
    /// whole pixels. Much less pixel locking than the convolution kernels on a sharp target;
    /// the template needs `(width + 8) (height + 8)` of the capacity `N`.
    Spline,
}

/// Margin of the spline's padded template, px: the prefilter's edge effect decays as
/// `0.268^k`, and the shift reads up to 3 coefficients past the window.
const SPLINE_MARGIN: usize = 4;

/// Offsets of the spline's taps from a whole pixel, `-2..=2`: the shift `s` of the template
/// stays below one pixel ([`KEEP`], see `LkTracker::spline_error`), so its four taps
/// `floor(s) - 1 ..= floor(s) + 2` are among these five.
const LAGS: usize = 5;

/// How far, px per axis, `p` may move from the whole pixel of the window already read before
/// the window is read again at the new nearest pixel (see `LkTracker::spline_error`): any
/// shift below one pixel keeps the spline's taps among the [`LAGS`], so the window is kept as
/// long as it can be; 0.95 leaves the taps' floor clear of rounding. (It was 3/4: a third of
/// the frames of a broadband motion then read, smoothed and correlated a second window.)
const KEEP: f32 = 0.95;

/// Below this ratio of its structure tensor's eigenvalues a template measures one direction
/// only (stripes, a straight edge: the aperture problem): its refinement's steps along the
/// weak direction count scaled by `sqrt(lambda_2 / lambda_1)` against
/// [`LkConfig::tolerance`] and the settling bound, so the iteration stops once the measured
/// direction has settled instead of wandering along the stripes to its cap. Above it (a
/// textured window) the step is `|dp|`, as always.
pub const APERTURE: f32 = 0.05;

/// Settings of an [`LkTracker`]: plain data, checked by [`LkConfig::validate`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LkConfig {
    /// Template width, pixels (>= 3; `width * height` at most the capacity `N`, `width + 7`
    /// at most the row capacity `W`: a row with the interpolation's support).
    pub width: u16,
    /// Template height, pixels (>= 3).
    pub height: u16,
    /// Coarse search range, pixels: the largest motion between two frames to catch (0: no
    /// search, the refinement alone, which converges within about a feature's size).
    pub search: u16,
    /// Most refinement iterations per start (1-50).
    pub max_iterations: u8,
    /// Convergence: a step `|dp|` below this, px (> 0).
    pub tolerance: f32,
    /// A match from the last displacement with a ZNCC at least this is taken without the
    /// coarse search (in `[min_score, 1]`).
    pub accept_score: f32,
    /// Below this ZNCC a result is lost (in `[-1, 1]`).
    pub min_score: f32,
    /// Template refresh: a match scoring below this (and at least `min_score`) re-takes the
    /// template where it is; at or below `min_score`: never (the default, no drift).
    pub refresh_below: f32,
    /// Smallest eigenvalue of the Hessian per template pixel, grey levels^2 / px^2, below which
    /// the template is flat (>= 0).
    pub min_texture: f32,
    /// Saturation level: a window pixel at or above it makes the result lost (0: the pixel
    /// type's full scale).
    pub saturation: u16,
    /// A coarse search whose best match has a rival at least half the template's larger side
    /// away scoring within this of it (ZNCC) is ambiguous: lost, [`Flags::AMBIGUOUS`]
    /// (in `[0, 1]`; 0: never).
    pub ambiguity: f32,
    /// Sampling between pixels.
    pub interpolation: Interpolation,
    /// Smoothing of the template and the frame before matching (see [`Smoothing`]).
    pub smoothing: Smoothing,
}

/// A binomial smoothing of the template and the frame before matching. A sharp target's
/// pixels alias, and interpolating an aliased image shifts it by an amount that depends on the
/// sub-pixel phase (pixel locking: on a disk with a 0.5 px edge, +-0.013 px with bicubic
/// sampling alone, +-0.006 px with `Binomial3`, +-0.004 px with `Binomial5`); smoothing
/// removes most of it at a small cost in noise, and adds two (four) taps per axis to the
/// interpolation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Smoothing {
    /// None.
    None,
    /// `[1 2 1] / 4` per axis (sigma 0.71 px).
    Binomial3,
    /// `[1 4 6 4 1] / 16` per axis (sigma 1 px).
    Binomial5,
}

impl Smoothing {
    /// The kernel's taps (centred) and how many there are.
    const fn kernel(self) -> ([f32; 5], usize) {
        match self {
            Smoothing::None => ([1.0, 0.0, 0.0, 0.0, 0.0], 1),
            Smoothing::Binomial3 => ([0.25, 0.5, 0.25, 0.0, 0.0], 3),
            Smoothing::Binomial5 => ([0.0625, 0.25, 0.375, 0.25, 0.0625], 5),
        }
    }
}

impl LkConfig {
    /// A `width x height` template with the defaults: a search of half the larger side,
    /// the template's B-spline after `Binomial3` smoothing, 20 iterations, tolerance 0.001 px, acceptance 0.9, lost below 0.5, no
    /// refresh, minimum texture 0.5 grey levels^2/px^2 per pixel, saturation at full scale.
    pub const fn new(width: u16, height: u16) -> Self {
        let larger = if width > height { width } else { height };
        LkConfig {
            width,
            height,
            search: larger / 2,
            max_iterations: 20,
            tolerance: 0.001,
            accept_score: 0.9,
            min_score: 0.5,
            refresh_below: 0.5,
            min_texture: 0.5,
            saturation: 0,
            ambiguity: 0.05,
            interpolation: Interpolation::Spline,
            smoothing: Smoothing::Binomial3,
        }
    }

    /// Checks every field against the capacities `n` (pixels) and `w` (row length).
    pub fn validate(self, n: usize, w: usize) -> Result<Self, LkError> {
        let (tw, th) = (usize::from(self.width), usize::from(self.height));
        if tw < 3 || th < 3 {
            return Err(LkError::WindowTooSmall);
        }
        let padded = match self.interpolation {
            Interpolation::Spline => (tw + 2 * SPLINE_MARGIN) * (th + 2 * SPLINE_MARGIN),
            _ => tw * th,
        };
        if padded > n || tw + 7 > w {
            return Err(LkError::WindowTooLarge {
                pixels: padded,
                capacity: n,
            });
        }
        let unit = |v: f32| (-1.0..=1.0).contains(&v);
        let ok = (1..=50).contains(&self.max_iterations)
            && self.tolerance > 0.0
            && self.tolerance.is_finite()
            && unit(self.min_score)
            && unit(self.accept_score)
            && unit(self.refresh_below)
            && self.accept_score >= self.min_score
            && self.min_texture >= 0.0
            && self.min_texture.is_finite()
            && (0.0..=1.0).contains(&self.ambiguity);
        if ok {
            Ok(self)
        } else {
            Err(LkError::Setting)
        }
    }
}

/// Why a configuration or a template is refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LkError {
    /// The template is narrower or lower than 3 pixels.
    WindowTooSmall,
    /// The template has more pixels than the capacity, or a row (plus 7) longer than the row
    /// capacity.
    WindowTooLarge {
        /// Pixels asked for.
        pixels: usize,
        /// The capacity `N`.
        capacity: usize,
    },
    /// A setting outside its range (see [`LkConfig`]).
    Setting,
    /// The template is not inside the frame.
    Outside,
    /// The template is flat: too little texture to track ([`LkConfig::min_texture`]).
    Flat,
}

impl core::fmt::Display for LkError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            LkError::WindowTooSmall => write!(f, "the window must be at least 3 x 3 pixels"),
            LkError::WindowTooLarge { pixels, capacity } => write!(
                f,
                "the window has {pixels} pixels, more than the capacity of {capacity} (or a row \
                 longer than the row capacity)"
            ),
            LkError::Setting => write!(f, "a tracker setting is out of range"),
            LkError::Outside => write!(f, "the window is not inside the frame"),
            LkError::Flat => write!(
                f,
                "the window is flat: too little texture in some direction to track"
            ),
        }
    }
}

/// One frame's result.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LkResult {
    /// Displacement since the reference frame, columns (px; valid unless lost).
    pub dx: f32,
    /// Displacement since the reference frame, rows (px, down; valid unless lost).
    pub dy: f32,
    /// Why the result is lost, if it is (see the module documentation).
    pub flags: Flags,
    /// Refinement iterations used (all starts).
    pub iterations: u8,
    /// ZNCC of the template and the frame at the result.
    pub score: f32,
    /// Whether the coarse search ran.
    pub searched: bool,
}

impl LkResult {
    /// The displacement, `None` when the result is lost (any flag set: a tracker result
    /// carries a flag only when it is lost).
    pub fn displacement(&self) -> Option<(f32, f32)> {
        if self.flags.is_clear() {
            Some((self.dx, self.dy))
        } else {
            None
        }
    }
}

/// A Lucas-Kanade tracker of one window of up to `N` pixels and rows of up to `W` pixels.
/// RAM: `21 N + 40 W` bytes and 2.7 KiB (the spline's template moments) and a few words;
/// `N` holds the spline's padded template, `(width + 8) (height + 8)` (a 31 x 31 window in
/// `LkTracker<1521, 38>`: 36 304 B).
#[derive(Debug, Clone)]
pub struct LkTracker<const N: usize, const W: usize> {
    config: LkConfig,
    /// Template values, row-major.
    t: [f32; N],
    /// Template gradients.
    gx: [f32; N],
    gy: [f32; N],
    /// Mean and root sum of squares about it of the template.
    t_mean: f32,
    t_norm: f32,
    /// Per template pixel: the template is dark around it ([`dark_near`]) for the
    /// saturation level `dark_sat` (a frame pixel clipped there is a change, not the target).
    dark: [bool; N],
    dark_sat: u16,
    /// Inverse Hessian `[a, b, c]` of `[[a, b], [b, c]]`.
    h_inv: [f32; 3],
    /// Top-left pixel of the template in the frame it was taken from.
    origin: (i32, i32),
    /// Displacement of the target in the current template since the reference frame.
    base: (f32, f32),
    /// Displacement since the template was taken (the state between frames).
    p: (f32, f32),
    /// Its change over the last frame (the prediction's velocity; zero after a loss).
    v: (f32, f32),
    /// The largest step between two consecutive tracked frames since the template was taken
    /// (the larger axis), px: how far the target has been seen to move.
    max_step: f32,
    /// The padded template's B-spline coefficients less the template's mean
    /// (`Interpolation::Spline`).
    coef: [f32; N],
    /// The spline path's template moments (see [`Moments`]).
    moments: Moments,
    /// The frame's window at whole pixels less the template's mean (`Interpolation::Spline`),
    /// and where it was read (the whole-pixel displacement; `None`: not for this frame).
    g: [f32; N],
    g_at: Option<(i64, i64)>,
    /// The window's cross moments with the template (see [`Cross`]), valid for `g_at`.
    cross: Cross,
    /// Horizontally interpolated rows (a ring of eight: the most taps).
    ring: [[f32; W]; 8],
    /// One source row as floats (the window's width plus up to 7 taps).
    src: [f32; W],
    /// One row of the vertical pass.
    acc: [f32; W],
    ready: bool,
}

impl<const N: usize, const W: usize> LkTracker<N, W> {
    /// A tracker with checked settings (no template yet).
    pub fn try_new(config: LkConfig) -> Result<Self, LkError> {
        let config = config.validate(N, W)?;
        Ok(LkTracker {
            config,
            t: [0.0; N],
            gx: [0.0; N],
            gy: [0.0; N],
            t_mean: 0.0,
            t_norm: 0.0,
            dark: [false; N],
            dark_sat: 0,
            h_inv: [0.0; 3],
            origin: (0, 0),
            base: (0.0, 0.0),
            p: (0.0, 0.0),
            v: (0.0, 0.0),
            max_step: 0.0,
            coef: [0.0; N],
            moments: Moments::ZERO,
            g: [0.0; N],
            g_at: None,
            cross: Cross::ZERO,
            ring: [[0.0; W]; 8],
            src: [0.0; W],
            acc: [0.0; W],
            ready: false,
        })
    }

    /// The settings.
    pub fn config(&self) -> &LkConfig {
        &self.config
    }

    /// Takes the template: the window whose top-left pixel is `(x0, y0)` in `frame` (the
    /// reference frame; displacements are counted from it). Refused when the window leaves
    /// the frame, or when it is flat.
    pub fn set_template<P: Pixel>(
        &mut self,
        frame: &Frame<'_, P>,
        x0: i32,
        y0: i32,
    ) -> Result<(), LkError> {
        self.base = (0.0, 0.0);
        self.p = (0.0, 0.0);
        self.v = (0.0, 0.0);
        self.max_step = 0.0;
        self.ready = false;
        self.take(frame, x0, y0)
    }

    /// The template's gradient structure tensor `[sxx, sxy, syy]` (the Hessian of the fit,
    /// summed over the window; zeros before a template): its eigenvectors are the directions
    /// the window's texture measures, its eigenvalues how well.
    pub fn structure(&self) -> [f32; 3] {
        let [a, b, c] = self.h_inv;
        let det = a * c - b * b;
        if det > 0.0 && det.is_finite() {
            [c / det, -b / det, a / det]
        } else {
            [0.0; 3]
        }
    }

    /// The displacement since the reference frame at the last result that was not lost.
    pub fn displacement(&self) -> (f32, f32) {
        (self.base.0 + self.p.0, self.base.1 + self.p.1)
    }

    /// Tracks the template in `frame` (see the module documentation).
    pub fn track<P: Pixel>(&mut self, frame: &Frame<'_, P>) -> LkResult {
        self.track_from(frame, None, self.config.search)
    }

    /// [`track`](Self::track) from `start` (a displacement since the reference frame; `None`:
    /// the constant-velocity prediction) with a coarse search of `+-search` px (0: none)
    /// instead of the configured one: what a caller that knows more than this target's own
    /// past uses, e.g. the motion shared by several targets that move together.
    pub fn track_from<P: Pixel>(
        &mut self,
        frame: &Frame<'_, P>,
        start: Option<(f32, f32)>,
        search: u16,
    ) -> LkResult {
        let configured = self.config.search;
        self.config.search = search;
        let out = self.track_inner(frame, start);
        self.config.search = configured;
        out
    }
}
