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
//!   below [`LkConfig::tolerance`] or after [`LkConfig::max_iterations`]. `I(x + p) - T(x)` is
//!   formed in one of two ways ([`Interpolation`]): by default the frame is read at whole
//!   pixels (the window at the whole-pixel part `q` of `p`) and the template's cubic B-spline
//!   (prefiltered once per template, gradients from the spline) is shifted by `q - p`, as
//!   pyidi interpolates its reference; or the frame is interpolated at `x + p` by Keys' cubic
//!   convolution or bilinearly (cheaper on an MCU, more pixel locking). Every template pixel
//!   shares the fractional part, so the interpolation is separable with the same weights.
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

/// The template moments of the spline path: with `c'` the padded template's coefficients
/// less the template's mean and `c'_o` them displaced by the lag `o = (ox, oy)` (`-2..=2`
/// each) over the template's pixels, `s[o] = sum c'_o` and `c[o][o'] = sum c'_o c'_o'`.
/// The shifted template is `T_s - m = sum_o w_o c'_o` with the shift's separable spline
/// weights `w` (they sum to one; its slopes' weights sum to zero), so every sum of an
/// iteration (the error weighted by the shifted template's slopes and the ZNCC) is a
/// quadratic form in the weights: an iteration costs a few hundred multiply-adds instead of
/// passes over the window.
#[derive(Debug, Clone, Copy)]
struct Moments {
    s: [f32; LAGS * LAGS],
    c: [f32; LAGS * LAGS * LAGS * LAGS],
}

impl Moments {
    const ZERO: Moments = Moments {
        s: [0.0; LAGS * LAGS],
        c: [0.0; LAGS * LAGS * LAGS * LAGS],
    };

    /// The moments of the `tw x th` template whose padded coefficients (`tw + 2 margin`
    /// wide, mean removed) are `coef`. Each row's sums are formed apart and then added
    /// (rounding grows with the row, not the window).
    fn of(coef: &[f32], (tw, th): (usize, usize)) -> Moments {
        let mut out = Moments::ZERO;
        let pw = tw + 2 * SPLINE_MARGIN;
        let first = SPLINE_MARGIN - LAGS / 2;
        // the template's row `j` at the vertical lag `oy`, from its horizontal lag 0
        let row = |j: usize, oy: usize| -> &[f32] {
            let start = (j + first + oy) * pw + first;
            coef.get(start..start + tw + LAGS - 1).unwrap_or(&[])
        };
        for oy in 0..LAGS {
            for oy2 in oy..LAGS {
                let mut c = [[0.0f32; LAGS]; LAGS];
                let mut s = [0.0f32; LAGS];
                for j in 0..th {
                    let (r1, r2) = (row(j, oy), row(j, oy2));
                    for (ox, cx) in c.iter_mut().enumerate() {
                        let a = r1.get(ox..ox + tw).unwrap_or(&[]);
                        for (ox2, cxy) in cx.iter_mut().enumerate() {
                            let b = r2.get(ox2..ox2 + tw).unwrap_or(&[]);
                            let mut d = 0.0f32;
                            for (u, v) in a.iter().zip(b) {
                                d += u * v;
                            }
                            *cxy += d;
                        }
                        if oy2 == oy {
                            s[ox] += a.iter().sum::<f32>();
                        }
                    }
                }
                for (ox, cx) in c.iter().enumerate() {
                    for (ox2, &v) in cx.iter().enumerate() {
                        let (i1, i2) = (oy * LAGS + ox, oy2 * LAGS + ox2);
                        if let Some(o) = out.c.get_mut(i1 * LAGS * LAGS + i2) {
                            *o = v;
                        }
                        if let Some(o) = out.c.get_mut(i2 * LAGS * LAGS + i1) {
                            *o = v;
                        }
                    }
                    if oy2 == oy {
                        if let (Some(o), Some(&v)) = (out.s.get_mut(oy * LAGS + ox), s.get(ox)) {
                            *o = v;
                        }
                    }
                }
            }
        }
        out
    }
}

/// The frame window's moments with the template (spline path): with `g'` the window less
/// the template's mean, `a[o] = sum g' c'_o` (see [`Moments`]), `sum g'` and the sum of the
/// squares about its mean.
/// A cross moment is formed when an iteration first needs it: the 4 x 4 lags of the shift's
/// taps (3 x 3 at a whole-pixel shift, where the fourth tap's weights are zero), and one more
/// column or row of lags when the shift's sign changes.
#[derive(Debug, Clone, Copy)]
struct Cross {
    a: [f32; LAGS * LAGS],
    /// Bit `oy * LAGS + ox` set: the cross moment of the lag `(ox, oy)` is formed.
    formed: u32,
    /// `sum g'` and `sum (g' - mean g')^2` over the window.
    sum: f32,
    var: f32,
    /// The window is stored as integers `G` with `g' = scale G + offset` (see
    /// `LkTracker::smooth_window`): `a[o] = scale sum G c'_o + offset s[o]`.
    scale: f32,
    offset: f32,
}

/// The window's row stride in `LkTracker::g`: its width rounded up to four pixels (the pad is
/// zero), so that the cross moments' kernel runs over whole groups of four.
const fn window_stride(tw: usize) -> usize {
    (tw + 3) & !3
}

impl Cross {
    const ZERO: Cross = Cross {
        a: [0.0; LAGS * LAGS],
        formed: 0,
        sum: 0.0,
        var: 0.0,
        scale: 1.0,
        offset: 0.0,
    };

    /// A window of `n` integers `G = v - mean` (`v` the smoothed pixels on the integer scale,
    /// `scale` back to the template's) whose sum is `sum` and sum of squares `sq` (exact), and
    /// `t_mean` the template's mean: no cross moment formed yet.
    fn window(sum: i64, sq: i128, mean: i32, scale: f32, t_mean: f32, n: f32) -> Cross {
        // sum (G - mean G)^2 in f64 (relative rounding 1e-16)
        let (s1, s2) = (sum as f64, sq as f64);
        let var = (s2 - s1 * s1 / f64::from(n)) * f64::from(scale) * f64::from(scale);
        let offset = mean as f32 * scale - t_mean;
        Cross {
            sum: scale * s1 as f32 + n * offset,
            var: var.max(0.0) as f32,
            scale,
            offset,
            ..Cross::ZERO
        }
    }

    /// Forms the cross moments of the lags `xs x ys` (indices `0..LAGS`, at most four each)
    /// not formed yet, from the window `g` (rows [`window_stride`] apart) and the padded
    /// coefficients `coef` of a `tw x th` template: per vertical lag, each run of missing
    /// horizontal lags in one pass over the window.
    fn need(
        &mut self,
        xs: core::ops::Range<usize>,
        ys: core::ops::Range<usize>,
        (g, coef, s): (&[f32], &[f32], &[f32; LAGS * LAGS]),
        (tw, th): (usize, usize),
    ) {
        let all = ((1u32 << xs.len()) - 1) << xs.start;
        let missing = |formed: u32, oy: usize| !(formed >> (oy * LAGS)) & all;
        let mut oy = ys.start;
        while oy < ys.end {
            let m = missing(self.formed, oy);
            let mut end = oy + 1;
            while end < ys.end && missing(self.formed, end) == m {
                end += 1;
            }
            let (data, size) = ((g, coef, s), (tw, th));
            if m.count_ones() == 1 && end - oy > 1 {
                // one horizontal lag missing from several vertical lags (the shift's sign
                // changed along x): that column in one pass over the window
                let at = (m.trailing_zeros() as usize, oy);
                match end - oy {
                    2 => self.column::<2>(at, data, size),
                    3 => self.column::<3>(at, data, size),
                    _ => self.column::<4>(at, data, size),
                }
                oy = end;
                continue;
            }
            for oy in oy..end {
                // each run of missing horizontal lags of this vertical lag in one pass
                let mut bits = m;
                while bits != 0 {
                    let lo = bits.trailing_zeros() as usize;
                    let len = (!(bits >> lo)).trailing_zeros() as usize;
                    let at = (lo, oy);
                    match len {
                        1 => self.row::<1>(at, data, size),
                        2 => self.row::<2>(at, data, size),
                        3 => self.row::<3>(at, data, size),
                        _ => self.row::<4>(at, data, size),
                    }
                    bits &= !(((1u32 << len) - 1) << lo);
                }
            }
            oy = end;
        }
    }

    /// Forms the cross moments of the horizontal lag `lx` at the `V` vertical lags from `ly`
    /// (at most four) in one pass over the window (the backend's `column_sums`).
    #[inline(never)]
    fn column<const V: usize>(
        &mut self,
        (lx, ly): (usize, usize),
        (g, coef, s): (&[f32], &[f32], &[f32; LAGS * LAGS]),
        (tw, th): (usize, usize),
    ) {
        let pw = tw + 2 * SPLINE_MARGIN;
        let first = SPLINE_MARGIN - LAGS / 2;
        let start = (first + ly) * pw + first + lx;
        let c = coef.get(start..).unwrap_or(&[]);
        let a = kernels::column_sums::<V>(g, window_stride(tw), c, pw, th);
        let (scale, offset) = (self.scale, self.offset);
        for (v, av) in a.iter().enumerate() {
            let at = (ly + v) * LAGS + lx;
            if let (Some(o), Some(s)) = (self.a.get_mut(at), s.get(at)) {
                *o = scale * av + offset * s;
            }
            self.formed |= 1 << at;
        }
    }

    /// Forms the cross moments of the `L` horizontal lags from `lx` at the vertical lag `oy`
    /// in one pass over the window (the backend's `lag_sums`).
    #[inline(never)]
    fn row<const L: usize>(
        &mut self,
        (lx, oy): (usize, usize),
        (g, coef, s): (&[f32], &[f32], &[f32; LAGS * LAGS]),
        (tw, th): (usize, usize),
    ) {
        let pw = tw + 2 * SPLINE_MARGIN;
        let first = SPLINE_MARGIN - LAGS / 2;
        let start = (first + oy) * pw + first + lx;
        let c = coef.get(start..).unwrap_or(&[]);
        let a = kernels::lag_sums::<L>(g, window_stride(tw), c, pw, th);
        let at = oy * LAGS + lx;
        let (scale, offset) = (self.scale, self.offset);
        if let (Some(out), Some(s)) = (self.a.get_mut(at..at + L), s.get(at..at + L)) {
            for ((o, v), s) in out.iter_mut().zip(a).zip(s) {
                *o = scale * v + offset * s;
            }
        }
        self.formed |= ((1u32 << L) - 1) << at;
    }
}

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

/// Cubic B-spline interpolation coefficients of the `w x h` image in `c` (row-major), in place:
/// the causal and anticausal recursive filters of Unser (1999) along the rows, then the
/// columns, pole `sqrt(3) - 2`, mirror-symmetric ends (the causal start summed over the first
/// 12 samples: `0.268^12 < 1e-6`).
fn prefilter(c: &mut [f32], w: usize, h: usize) {
    fn line(c: &mut [f32], start: usize, step: usize, n: usize) {
        const Z: f32 = -0.267_949_2; // sqrt(3) - 2
        if n < 2 {
            return;
        }
        let at = |k: usize| start + k * step;
        for k in 0..n {
            if let Some(v) = c.get_mut(at(k)) {
                *v *= 6.0;
            }
        }
        let get = |c: &[f32], k: usize| c.get(at(k)).copied().unwrap_or(0.0);
        // causal: c+[0] from the mirrored start, then c+[k] = c[k] + z c+[k-1]
        let mut zk = 1.0f32;
        let mut first = 0.0f32;
        for k in 0..n.min(12) {
            first += zk * get(c, k);
            zk *= Z;
        }
        if let Some(v) = c.get_mut(at(0)) {
            *v = first;
        }
        for k in 1..n {
            let prev = get(c, k - 1);
            if let Some(v) = c.get_mut(at(k)) {
                *v += Z * prev;
            }
        }
        // anticausal: c[n-1] = z / (z^2 - 1) (c+[n-1] + z c+[n-2]), c[k] = z (c[k+1] - c+[k])
        let last = Z / (Z * Z - 1.0) * (get(c, n - 1) + Z * get(c, n - 2));
        if let Some(v) = c.get_mut(at(n - 1)) {
            *v = last;
        }
        for k in (0..n - 1).rev() {
            let next = get(c, k + 1);
            if let Some(v) = c.get_mut(at(k)) {
                *v = Z * (next - *v);
            }
        }
    }
    for j in 0..h {
        line(c, j * w, 1, w);
    }
    for i in 0..w {
        line(c, i, w, h);
    }
}

/// The derivatives of [`bspline_weights`] with respect to `f`: the spline's slope at `f`.
fn bspline_slopes(f: f32) -> [f32; 4] {
    let g = 1.0 - f;
    [
        -0.5 * g * g,
        (3.0 * f * f - 4.0 * f) / 2.0,
        (-3.0 * f * f + 2.0 * f + 1.0) / 2.0,
        0.5 * f * f,
    ]
}

/// Cubic B-spline weights of the four coefficients at `-1, 0, 1, 2` for a fraction `f`.
fn bspline_weights(f: f32) -> [f32; 4] {
    let g = 1.0 - f;
    [
        g * g * g / 6.0,
        (3.0 * f * f * f - 6.0 * f * f + 4.0) / 6.0,
        (-3.0 * f * f * f + 3.0 * f * f + 3.0 * f + 1.0) / 6.0,
        f * f * f / 6.0,
    ]
}

/// A frame pixel at or above the saturation level where the template (and its neighbours) is
/// below this fraction of it was clipped by a change (a brighter target, a neighbour's highlight), not by a plateau
/// that moves with the template.
const CLIP_FRACTION: f32 = 0.75;

/// Whether the template is below [`CLIP_FRACTION`] of `sat` at pixel `(i, j)` and its eight
/// neighbours (the frame's window may sit up to a pixel off the template's grid).
fn dark_near(t: &[f32], (tw, th): (usize, usize), (i, j): (usize, usize), sat: u16) -> bool {
    let level = CLIP_FRACTION * f32::from(sat);
    for y in j.saturating_sub(1)..(j + 2).min(th) {
        for x in i.saturating_sub(1)..(i + 2).min(tw) {
            if t.get(y * tw + x).is_some_and(|&v| v >= level) {
                return false;
            }
        }
    }
    true
}

/// Stores the smoothed values `v` (integers) as `v - mean` into `out`; returns their sum and
/// sum of squares, exact (a value is below 2^24 in magnitude: the sum is formed in `i32` over
/// at most 127 values at a time, the squares in `i64`, which holds a row of up to 2^15).
#[inline(always)]
fn emit(out: &mut [f32], mut v: impl Iterator<Item = u32>, mean: i32) -> (i64, i64) {
    let (mut sum, mut sq) = (0i64, 0i64);
    for seg in out.chunks_mut(127) {
        let mut rs = 0i32;
        for (o, v) in seg.iter_mut().zip(&mut v) {
            let d = v as i32 - mean;
            *o = d as f32;
            rs += d;
            sq += i64::from(d) * i64::from(d);
        }
        sum += i64::from(rs);
    }
    (sum, sq)
}

/// More newly clipped pixels than this in a window of `n` pixels lose the frame: two, and 2 %.
fn clip_limit(n: usize) -> u32 {
    2 + (n / 50) as u32
}

/// The first `T` of eight weights.
fn taps_of<const T: usize>(w: &[f32; 8]) -> [f32; T] {
    let mut out = [0.0; T];
    for (o, v) in out.iter_mut().zip(w) {
        *o = *v;
    }
    out
}

/// Keys' cubic convolution weights of the four taps at `-1, 0, 1, 2` for a fraction `f`.
fn cubic_weights(f: f32) -> [f32; 4] {
    const A: f32 = -0.5;
    let near = |t: f32| ((A + 2.0) * t - (A + 3.0)) * t * t + 1.0;
    let far = |t: f32| ((A * t - 5.0 * A) * t + 8.0 * A) * t - 4.0 * A;
    [far(1.0 + f), near(f), near(1.0 - f), far(2.0 - f)]
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

    /// The template's dark pixels ([`LkTracker::dark`]) for the saturation level `sat`,
    /// unless marked for it already.
    fn mark_dark(&mut self, sat: u16) {
        if self.dark_sat == sat {
            return;
        }
        let (tw, th) = (
            usize::from(self.config.width),
            usize::from(self.config.height),
        );
        for (j, row) in self.dark.chunks_mut(tw.max(1)).take(th).enumerate() {
            for (i, d) in row.iter_mut().enumerate() {
                *d = dark_near(&self.t, (tw, th), (i, j), sat);
            }
        }
        self.dark_sat = sat;
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

    /// The template at `(x0, y0)`, its gradients and inverse Hessian.
    fn take<P: Pixel>(&mut self, frame: &Frame<'_, P>, x0: i32, y0: i32) -> Result<(), LkError> {
        let (tw, th) = (
            usize::from(self.config.width),
            usize::from(self.config.height),
        );
        let (fw, fh) = (frame.width() as i64, frame.height() as i64);
        let (x0l, y0l) = (i64::from(x0), i64::from(y0));
        if x0l < 0 || y0l < 0 || x0l + tw as i64 > fw || y0l + th as i64 > fh {
            return Err(LkError::Outside);
        }
        // the gradients read one pixel around the window, the smoothing up to two more, the
        // spline's padding four: past the frame's edge the edge pixels repeat (coordinates
        // offset by 8 so they stay unsigned)
        let (x0u, y0u) = (x0 as usize + 8, y0 as usize + 8);
        let raw = |x: usize, y: usize| -> f32 {
            let (x, y) = (
                (x as i64 - 8).min(fw - 1).max(0) as usize,
                (y as i64 - 8).min(fh - 1).max(0) as usize,
            );
            frame
                .row(y)
                .and_then(|r| r.get(x))
                .map_or(0.0, |&v| f32::from(v.into()))
        };
        let (kernel, taps) = self.config.smoothing.kernel();
        let half = taps / 2;
        let at = |x: usize, y: usize| -> f32 {
            let row = |y: usize| -> f32 {
                let mut v = 0.0;
                for (k, w) in kernel.iter().take(taps).enumerate() {
                    v += w * raw(x + k - half, y);
                }
                v
            };
            let mut v = 0.0;
            for (k, w) in kernel.iter().take(taps).enumerate() {
                v += w * row(y + k - half);
            }
            v
        };
        let spline = self.config.interpolation == Interpolation::Spline;
        let (pw, ph) = (tw + 2 * SPLINE_MARGIN, th + 2 * SPLINE_MARGIN);
        if spline {
            for j in 0..ph {
                for i in 0..pw {
                    if let Some(c) = self.coef.get_mut(j * pw + i) {
                        *c = at(x0u + i - SPLINE_MARGIN, y0u + j - SPLINE_MARGIN);
                    }
                }
            }
            prefilter(&mut self.coef, pw, ph);
        }
        // the interpolant's derivative at whole pixels: [1 4 1] / 6 across, [-1 0 1] / 2 along
        let coef = &self.coef;
        // coefficient of template pixel (i, j), which may be up to the margin outside it
        let c = |i: i64, j: i64| {
            let m = SPLINE_MARGIN as i64;
            coef.get(((j + m) * pw as i64 + i + m) as usize)
                .copied()
                .unwrap_or(0.0)
        };
        let spline_grad = |i: i64, j: i64| -> (f32, f32) {
            let dx = |j: i64| 0.5 * (c(i + 1, j) - c(i - 1, j));
            let dy = |i: i64| 0.5 * (c(i, j + 1) - c(i, j - 1));
            (
                (dx(j - 1) + 4.0 * dx(j) + dx(j + 1)) / 6.0,
                (dy(i - 1) + 4.0 * dy(i) + dy(i + 1)) / 6.0,
            )
        };
        let (mut sxx, mut sxy, mut syy, mut sum) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for j in 0..th {
            for i in 0..tw {
                let (x, y) = (x0u + i, y0u + j);
                let (gx, gy) = if spline {
                    spline_grad(i as i64, j as i64)
                } else {
                    (
                        0.5 * (at(x + 1, y) - at(x - 1, y)),
                        0.5 * (at(x, y + 1) - at(x, y - 1)),
                    )
                };
                let v = at(x, y);
                let k = j * tw + i;
                if let (Some(t), Some(a), Some(b)) =
                    (self.t.get_mut(k), self.gx.get_mut(k), self.gy.get_mut(k))
                {
                    *t = v;
                    *a = gx;
                    *b = gy;
                }
                sum += v;
                sxx += gx * gx;
                sxy += gx * gy;
                syy += gy * gy;
            }
        }
        let n = (tw * th) as f32;
        // smaller eigenvalue of [[sxx, sxy], [sxy, syy]], per pixel
        let half_tr = 0.5 * (sxx + syy);
        let det = sxx * syy - sxy * sxy;
        let disc = sqrtf((half_tr * half_tr - det).max(0.0));
        let lambda_min = half_tr - disc;
        // written so that a NaN (no texture at all) is flat too
        let textured = lambda_min / n >= self.config.min_texture && det > 0.0;
        if !textured {
            return Err(LkError::Flat);
        }
        self.h_inv = [syy / det, -sxy / det, sxx / det];
        let mean = sum / n;
        let mut ss = 0.0f32;
        for v in self.t.iter().take(tw * th) {
            ss += (v - mean) * (v - mean);
        }
        self.t_mean = mean;
        self.t_norm = sqrtf(ss);
        // a new template: its own mask
        self.dark_sat = 0;
        self.mark_dark(match self.config.saturation {
            0 => P::FULL,
            s => s,
        });
        if spline {
            // the spline's weights sum to one: the mean comes off the coefficients
            for c in self.coef.iter_mut().take(pw * ph) {
                *c -= mean;
            }
            self.moments = Moments::of(&self.coef, (tw, th));
        }
        self.origin = (x0, y0);
        self.g_at = None;
        self.ready = true;
        Ok(())
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

    fn track_inner<P: Pixel>(
        &mut self,
        frame: &Frame<'_, P>,
        given: Option<(f32, f32)>,
    ) -> LkResult {
        let mut out = LkResult {
            dx: 0.0,
            dy: 0.0,
            flags: Flags::NONE,
            iterations: 0,
            score: 0.0,
            searched: false,
        };
        if !self.ready {
            out.flags = Flags::DIVERGED;
            return out;
        }
        // a new frame: the spline path's window buffer holds the last one's
        self.g_at = None;
        let sat = match self.config.saturation {
            0 => P::FULL,
            s => s,
        };
        // (a template taken from frames of another pixel type)
        self.mark_dark(sat);
        // constant-velocity prediction from the last two tracked frames (none after a loss),
        // unless the caller gives the start
        let mut start = match given {
            Some((dx, dy)) if dx.is_finite() && dy.is_finite() => {
                (dx - self.base.0, dy - self.base.1)
            }
            Some(_) => {
                out.flags = Flags::DIVERGED;
                return out;
            }
            None => (self.p.0 + self.v.0, self.p.1 + self.v.1),
        };
        let mut first = self.refine(frame, start, sat, &mut out);
        if first == Err(Flags::BORDER) && start != self.p {
            // the prediction overshoots past the frame's edge: start where the target was
            start = self.p;
            first = self.refine(frame, start, sat, &mut out);
        }
        let accepted = match first {
            Ok((p, score, settled)) if settled && score >= self.config.accept_score => {
                Some((p, score))
            }
            _ => None,
        };
        let result = match accepted {
            Some(r) => Ok(r),
            // the window at the last position reaches past the frame's edge: the target is
            // leaving; a search would find something else
            None if first == Err(Flags::BORDER) => Err(Flags::BORDER),
            None if self.config.search > 0 => {
                out.searched = true;
                match self.search(frame, start) {
                    Err(flags) => Err(flags),
                    Ok(q) => match self.refine(frame, q, sat, &mut out) {
                        Ok((p, _, true)) if self.unexplained(p, start) => Err(Flags::AMBIGUOUS),
                        Ok((p, score, true)) if score >= self.config.min_score => Ok((p, score)),
                        Ok((_, score, _)) => {
                            out.score = score;
                            Err(Flags::DIVERGED)
                        }
                        Err(f) => Err(f),
                    },
                }
            }
            None => match first {
                Ok((p, score, true)) if score >= self.config.min_score => Ok((p, score)),
                Ok((_, score, _)) => {
                    out.score = score;
                    Err(Flags::DIVERGED)
                }
                Err(f) => Err(f),
            },
        };
        match result {
            Ok((p, score)) => {
                self.v = (p.0 - self.p.0, p.1 - self.p.1);
                self.max_step = self.max_step.max(fabsf(self.v.0).max(fabsf(self.v.1)));
                self.p = p;
                out.score = score;
                let (dx, dy) = self.displacement();
                out.dx = dx;
                out.dy = dy;
                if score < self.config.refresh_below {
                    self.refresh(frame);
                }
            }
            Err(f) => {
                self.v = (0.0, 0.0);
                out.flags.insert(f);
            }
        }
        out
    }

    /// Whether a match the search found at `p` lies further from where the search started
    /// (`start`: the prediction, or the caller's start) than the motion seen so far explains:
    /// more than [`JUMP_FACTOR`] times the largest step between two tracked frames, and more
    /// than half the template's larger side (the default search range: a search within it is
    /// always explained). A look-alike neighbour found by a long search is taken for a
    /// jump of the target no more: the frame is lost ([`Flags::AMBIGUOUS`]).
    fn unexplained(&self, p: (f32, f32), start: (f32, f32)) -> bool {
        let jump = fabsf(p.0 - start.0).max(fabsf(p.1 - start.1));
        let half = f32::from(self.config.width.max(self.config.height)) / 2.0;
        jump > half && jump > JUMP_FACTOR * self.max_step
    }

    /// Re-takes the template at the current position (the refresh rule); a refused template
    /// keeps the old one.
    fn refresh<P: Pixel>(&mut self, frame: &Frame<'_, P>) {
        let (rx, ry) = (floorf(self.p.0 + 0.5), floorf(self.p.1 + 0.5));
        let (x0, y0) = (self.origin.0 + rx as i32, self.origin.1 + ry as i32);
        // a refused template (flat, outside) must leave the old one whole: keep a copy
        let saved = (
            self.origin,
            self.h_inv,
            self.t_mean,
            self.t_norm,
            self.moments,
        );
        let (t, gx, gy, coef) = (self.t, self.gx, self.gy, self.coef);
        if self.take(frame, x0, y0).is_ok() {
            self.base = (self.base.0 + rx, self.base.1 + ry);
            self.p = (self.p.0 - rx, self.p.1 - ry);
        } else {
            (
                self.origin,
                self.h_inv,
                self.t_mean,
                self.t_norm,
                self.moments,
            ) = saved;
            (self.t, self.gx, self.gy, self.coef) = (t, gx, gy, coef);
            self.g_at = None;
            self.ready = true;
        }
    }

    /// The taps of one axis for a fraction `f` (interpolation, with the smoothing folded in):
    /// the weights, how many lead the whole-pixel position, and how many there are.
    fn weights(&self, f: f32) -> ([f32; 8], i64, usize) {
        let (base, lead, n): ([f32; 4], i64, usize) = match self.config.interpolation {
            Interpolation::Bicubic | Interpolation::Spline => (cubic_weights(f), 1, 4),
            Interpolation::Bilinear => ([1.0 - f, f, 0.0, 0.0], 0, 2),
        };
        let (kernel, taps) = self.config.smoothing.kernel();
        // the smoothing kernel convolved with the interpolation taps
        let mut w = [0.0f32; 8];
        for (i, b) in base.iter().take(n).enumerate() {
            for (k, s) in kernel.iter().take(taps).enumerate() {
                if let Some(o) = w.get_mut(i + k) {
                    *o += b * s;
                }
            }
        }
        (w, lead + (taps / 2) as i64, n + taps - 1)
    }

    /// Inverse-compositional refinement from `p`: the displacement, its ZNCC and whether the
    /// last step was below 0.1 px; `Err(flags)` when the window leaves the frame or saturates.
    fn refine<P: Pixel>(
        &mut self,
        frame: &Frame<'_, P>,
        mut p: (f32, f32),
        sat: u16,
        out: &mut LkResult,
    ) -> Result<((f32, f32), f32, bool), Flags> {
        let mut step = f32::INFINITY;
        let mut score = 0.0;
        let from = p;
        for _ in 0..self.config.max_iterations {
            out.iterations = out.iterations.saturating_add(1);
            let (b, s) = if self.config.interpolation == Interpolation::Spline {
                self.spline_error(frame, p, sat)?
            } else {
                self.warp_error(frame, p, sat)?
            };
            score = s;
            let dx = self.h_inv[0] * b.0 + self.h_inv[1] * b.1;
            let dy = self.h_inv[1] * b.0 + self.h_inv[2] * b.1;
            p = (p.0 - dx, p.1 - dy);
            step = sqrtf(dx * dx + dy * dy);
            if !step.is_finite() {
                return Err(Flags::DIVERGED);
            }
            if step < self.config.tolerance {
                break;
            }
            // a refinement that runs away from its start (more than the window) has lost the
            // target
            if fabsf(p.0 - from.0) > f32::from(self.config.width) + f32::from(self.config.search)
                || fabsf(p.1 - from.1)
                    > f32::from(self.config.height) + f32::from(self.config.search)
            {
                return Err(Flags::DIVERGED);
            }
        }
        Ok((p, score, step < 0.1))
    }

    /// Interpolates the frame at the template's pixels shifted by `p`: returns
    /// `sum [gx e, gy e]` with `e = I(x + p) - T(x)`, and the ZNCC of the warped window and the
    /// template.
    fn warp_error<P: Pixel>(
        &mut self,
        frame: &Frame<'_, P>,
        p: (f32, f32),
        sat: u16,
    ) -> Result<((f32, f32), f32), Flags> {
        let (ix, iy) = (floorf(p.0), floorf(p.1));
        if !(ix.is_finite() && iy.is_finite()) || fabsf(ix) > 1e6 || fabsf(iy) > 1e6 {
            return Err(Flags::DIVERGED);
        }
        let (fx, fy) = (p.0 - ix, p.1 - iy);
        let (wx, lead, taps) = self.weights(fx);
        let (wy, _, _) = self.weights(fy);
        let at = (ix as i64, iy as i64, lead);
        // one monomorphised pass per tap count, so every inner loop has a constant length
        match taps {
            2 => self.warp::<P, 2>(frame, at, (&wx, &wy), sat),
            4 => self.warp::<P, 4>(frame, at, (&wx, &wy), sat),
            6 => self.warp::<P, 6>(frame, at, (&wx, &wy), sat),
            _ => self.warp::<P, 8>(frame, at, (&wx, &wy), sat),
        }
    }

    /// [`warp_error`](Self::warp_error) with `T` taps per axis: the window's top-left source
    /// pixel at the template's origin plus `(ix, iy)` less `lead`.
    fn warp<P: Pixel, const T: usize>(
        &mut self,
        frame: &Frame<'_, P>,
        (ix, iy, lead): (i64, i64, i64),
        (wx, wy): (&[f32; 8], &[f32; 8]),
        sat: u16,
    ) -> Result<((f32, f32), f32), Flags> {
        let (tw, th) = (
            usize::from(self.config.width),
            usize::from(self.config.height),
        );
        let (wx, wy): ([f32; T], [f32; T]) = (taps_of(wx), taps_of(wy));
        // source columns x_first .. x_first + tw + T - 1, rows likewise; the window itself must
        // be inside the frame, the interpolation's support beyond it repeats the edge pixels
        let x_first = i64::from(self.origin.0) + ix - lead;
        let y_first = i64::from(self.origin.1) + iy - lead;
        let (fw, fh) = (frame.width() as i64, frame.height() as i64);
        let (x_win, y_win) = (x_first + lead, y_first + lead);
        if x_win < 0 || y_win < 0 || x_win + tw as i64 > fw || y_win + th as i64 > fh {
            return Err(Flags::BORDER);
        }
        let span = tw + T - 1;
        let lead = lead as usize;
        let mut saturated = 0u32;
        let (bx, by, sd, sdd, sdt) = {
            let LkTracker {
                t,
                dark,
                gx,
                gy,
                ring,
                src,
                acc,
                t_mean,
                ..
            } = self;
            let m = *t_mean;
            // source row `r` to floats (edge pixels repeated), then its horizontal pass into
            // ring slot `r % 8`
            let mut fill = |ring: &mut [[f32; W]; 8], r: usize| {
                let y = (y_first + r as i64).min(fh - 1).max(0) as usize;
                let row = frame.row(y).unwrap_or(&[]);
                let Some(src) = src.get_mut(..span) else {
                    return;
                };
                let inside = x_first >= 0 && x_first + span as i64 <= fw;
                match row.get(x_first.max(0) as usize..).filter(|_| inside) {
                    Some(seg) => {
                        for (o, v) in src.iter_mut().zip(seg) {
                            *o = f32::from((*v).into());
                        }
                        if (lead..lead + th).contains(&r) {
                            let whole = seg.get(lead..lead + tw).unwrap_or(&[]);
                            let j = (r - lead) * tw;
                            let dark = dark.get(j..j + tw).unwrap_or(&[]);
                            saturated += kernels::newly_clipped(whole, dark, sat);
                        }
                    }
                    None => {
                        for (c, o) in src.iter_mut().enumerate() {
                            let x = (x_first + c as i64).min(fw - 1).max(0) as usize;
                            let v = row.get(x).map_or(0, |v| (*v).into());
                            *o = f32::from(v);
                            let in_window =
                                (lead..lead + tw).contains(&c) && (lead..lead + th).contains(&r);
                            saturated += u32::from(
                                in_window
                                    && v >= sat
                                    && dark.get((r - lead) * tw + c - lead).is_some_and(|&d| d),
                            );
                        }
                    }
                }
                let slot = &mut ring[r % 8];
                for (o, win) in slot.iter_mut().zip(src.windows(T)) {
                    let mut v = 0.0;
                    for (a, b) in wx.iter().zip(win) {
                        v += a * b;
                    }
                    *o = v;
                }
            };
            for r in 0..T - 1 {
                fill(ring, r);
            }
            let (mut bx, mut by) = (0.0f32, 0.0f32);
            let (mut sd, mut sdd, mut sdt) = (0.0f32, 0.0f32, 0.0f32);
            for j in 0..th {
                fill(ring, j + T - 1);
                let Some(acc) = acc.get_mut(..tw) else {
                    break;
                };
                // the vertical pass, the first tap's row written, the others added
                let mut first = true;
                for (k, w) in wy.iter().enumerate() {
                    let row = &ring[(j + k) % 8];
                    if first {
                        for (a, r) in acc.iter_mut().zip(row.iter()) {
                            *a = w * r;
                        }
                        first = false;
                    } else {
                        for (a, r) in acc.iter_mut().zip(row.iter()) {
                            *a += w * r;
                        }
                    }
                }
                let rows = j * tw..(j + 1) * tw;
                let (Some(t), Some(gx), Some(gy)) =
                    (t.get(rows.clone()), gx.get(rows.clone()), gy.get(rows))
                else {
                    break;
                };
                for (((&v, &t), &gx), &gy) in acc.iter().zip(t).zip(gx).zip(gy) {
                    let e = v - t;
                    bx += gx * e;
                    by += gy * e;
                    // the ZNCC's sums about the template mean (small numbers: no cancellation)
                    let d = v - m;
                    sd += d;
                    sdd += d * d;
                    sdt += d * (t - m);
                }
            }
            (bx, by, sd, sdd, sdt)
        };
        // a clipped plateau that moves with the template is tracked; more clipped pixels than
        // the template had (brighter, or a neighbour's) break brightness constancy
        if saturated > clip_limit(tw * th) {
            return Err(Flags::SATURATED);
        }
        let n = (tw * th) as f32;
        let var = sdd - sd * sd / n;
        let score = if var > 0.0 && self.t_norm > 0.0 {
            sdt / (sqrtf(var) * self.t_norm)
        } else {
            0.0
        };
        Ok(((bx, by), score))
    }

    /// [`warp_error`](Self::warp_error) for [`Interpolation::Spline`]: the frame's window at
    /// the whole-pixel part `q` of `p` against the template's spline shifted by `q - p`;
    /// returns `sum [gx e, gy e]` with `e = I(x + q) - T(x - (p - q))` and the ZNCC.
    ///
    /// `q` is the nearest whole pixel, except that within a frame the window already read is
    /// kept while `p` stays within [`KEEP`] px of it (hysteresis): when the template does not
    /// match the frame exactly (a blur that changes from frame to frame), the error measured on
    /// two neighbouring windows differs slightly, and with the plain nearest pixel an optimum
    /// near a half pixel made the iteration jump between the two windows without settling.
    fn spline_error<P: Pixel>(
        &mut self,
        frame: &Frame<'_, P>,
        p: (f32, f32),
        sat: u16,
    ) -> Result<((f32, f32), f32), Flags> {
        let (qx, qy) = match self.g_at {
            Some((x, y)) if fabsf(p.0 - x as f32) <= KEEP && fabsf(p.1 - y as f32) <= KEEP => {
                (x as f32, y as f32)
            }
            _ => (floorf(p.0 + 0.5), floorf(p.1 + 0.5)),
        };
        if !(qx.is_finite() && qy.is_finite()) || fabsf(qx) > 1e6 || fabsf(qy) > 1e6 {
            return Err(Flags::DIVERGED);
        }
        let (tw, th) = (
            usize::from(self.config.width),
            usize::from(self.config.height),
        );
        let q = (qx as i64, qy as i64);
        if self.g_at != Some(q) {
            self.load_window(frame, q, sat)?;
            self.g_at = Some(q);
        }
        // the template's pixels shifted by s = q - p, |s| <= KEEP < 1: taps at a - 1 .. a + 2,
        // among the lags -2 ..= 2
        let (sx, sy) = (qx - p.0, qy - p.1);
        let (ax, ay) = (floorf(sx), floorf(sy));
        if !(-1.0..=0.0).contains(&ax) || !(-1.0..=0.0).contains(&ay) {
            return Err(Flags::DIVERGED);
        }
        let (wx, wy) = (bspline_weights(sx - ax), bspline_weights(sy - ay));
        let (dwx, dwy) = (bspline_slopes(sx - ax), bspline_slopes(sy - ay));
        // the first tap's lag index: a - 1 + 2
        let (lx, ly) = ((ax + 1.0) as usize, (ay + 1.0) as usize);
        let LkTracker {
            g,
            coef,
            cross,
            moments,
            ..
        } = self;
        // the lags of the taps with a weight: at a whole-pixel shift the fourth tap's weights
        // (the spline's and its slope's) are zero, and its lags are not formed
        let used = |l: usize, w: &[f32; 4], dw: &[f32; 4]| {
            l..l + if w[3] == 0.0 && dw[3] == 0.0 { 3 } else { 4 }
        };
        let data = (&g[..], &coef[..], &moments.s);
        cross.need(used(lx, &wx, &dwx), used(ly, &wy, &dwy), data, (tw, th));
        // the weights of the shifted template (u), of its x and y slopes (vx, vy), at the
        // lags `at`
        let mut at = [0usize; 16];
        let (mut u, mut vx, mut vy) = ([0.0f32; 16], [0.0f32; 16], [0.0f32; 16]);
        for (l, (&wyl, &dwyl)) in wy.iter().zip(&dwy).enumerate() {
            for (k, (&wxk, &dwxk)) in wx.iter().zip(&dwx).enumerate() {
                let n = l * 4 + k;
                if let (Some(a), Some(u), Some(vx), Some(vy)) =
                    (at.get_mut(n), u.get_mut(n), vx.get_mut(n), vy.get_mut(n))
                {
                    *a = (ly + l) * LAGS + lx + k;
                    *u = wxk * wyl;
                    *vx = dwxk * wyl;
                    *vy = wxk * dwyl;
                }
            }
        }
        // sums with the window: sum g' T_s', sum g' d/dx T_s, sum g' d/dy T_s, sum T_s'
        let (mut sdt, mut gdx, mut gdy, mut ss) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        // the template's quadratic forms: sum T_s'^2, sum T_s' d/dx T_s, sum T_s' d/dy T_s
        let (mut sss, mut tdx, mut tdy) = (0.0f32, 0.0f32, 0.0f32);
        #[cfg(not(target_arch = "arm"))]
        let forms = kernels::tap_forms(&moments.c, LAGS, (lx, ly), wx, wy);
        for (n, &i) in at.iter().enumerate() {
            let (a, sm) = (
                cross.a.get(i).copied().unwrap_or(0.0),
                moments.s.get(i).copied().unwrap_or(0.0),
            );
            let (un, vxn, vyn) = (
                u.get(n).copied().unwrap_or(0.0),
                vx.get(n).copied().unwrap_or(0.0),
                vy.get(n).copied().unwrap_or(0.0),
            );
            sdt += un * a;
            gdx += vxn * a;
            gdy += vyn * a;
            ss += un * sm;
            // sum over the taps of c[i][tap] u[tap], u separable: the four lags of a
            // vertical tap are neighbours in the row of c (on hosts formed above, four lags
            // at a time, the same operations in each lane)
            #[cfg(not(target_arch = "arm"))]
            let cu = forms.get(n).copied().unwrap_or(0.0);
            #[cfg(target_arch = "arm")]
            let cu = {
                let row = moments.c.get(i * LAGS * LAGS..).unwrap_or(&[]);
                let mut cu = 0.0f32;
                for (l, &wyl) in wy.iter().enumerate() {
                    let at = (ly + l) * LAGS + lx;
                    if let Some(&[c0, c1, c2, c3]) = row.get(at..at + 4) {
                        let [w0, w1, w2, w3] = wx;
                        cu += wyl * (c0 * w0 + c1 * w1 + c2 * w2 + c3 * w3);
                    }
                }
                cu
            };
            sss += un * cu;
            tdx += vxn * cu;
            tdy += vyn * cu;
        }
        // the error e = I(x + q) - T(x - s) weighted by the shifted template's slopes (not
        // the reference's): the update is then the gradient of the squared error itself,
        // whose zero does not depend on the whole-pixel window when the frame differs from
        // the template (blur)
        let (bx, by) = (gdx - tdx, gdy - tdy);
        let n = (tw * th) as f32;
        let (sd, var_g) = (cross.sum, cross.var);
        let var_s = sss - ss * ss / n;
        let score = if var_g > 0.0 && var_s > 0.0 {
            (sdt - sd * ss / n) / sqrtf(var_g * var_s)
        } else {
            0.0
        };
        Ok(((bx, by), score))
    }

    /// The frame's window at the template's origin plus `q` into `g` (smoothed as the template
    /// was; past the frame's edge the edge pixels repeat), less the template's mean, and its
    /// own moments into `cross`; `Err` when the window leaves the frame or has more clipped
    /// pixels than the template.
    fn load_window<P: Pixel>(
        &mut self,
        frame: &Frame<'_, P>,
        q: (i64, i64),
        sat: u16,
    ) -> Result<(), Flags> {
        let (tw, th) = (
            usize::from(self.config.width),
            usize::from(self.config.height),
        );
        let (fw, fh) = (frame.width() as i64, frame.height() as i64);
        let (x0, y0) = (
            i64::from(self.origin.0) + q.0,
            i64::from(self.origin.1) + q.1,
        );
        if x0 < 0 || y0 < 0 || x0 + tw as i64 > fw || y0 + th as i64 > fh {
            return Err(Flags::BORDER);
        }
        // one monomorphised pass per kernel length, so every inner loop has a constant length
        let at = (x0, y0, sat);
        let saturated = match self.config.smoothing {
            Smoothing::None => self.smooth_window::<P, 1>(frame, at, [1]),
            Smoothing::Binomial3 => self.smooth_window::<P, 3>(frame, at, [1, 2, 1]),
            Smoothing::Binomial5 => self.smooth_window::<P, 5>(frame, at, [1, 4, 6, 4, 1]),
        };
        if saturated > clip_limit(tw * th) {
            return Err(Flags::SATURATED);
        }
        Ok(())
    }

    /// [`load_window`](Self::load_window) with the `T`-tap binomial kernel `k` (its sum a
    /// power of two), in integers: per window row, the `T` source rows summed down each
    /// column, then along the row; the smoothed value `v` (the template's scale times the
    /// kernel's total squared) is stored as `v - M`, `M` the nearest integer to the template's
    /// mean on that scale, exact in `f32` (the cross moments and the window's sums are formed
    /// from these, see [`Cross::window`]). Returns the count of newly clipped pixels.
    fn smooth_window<P: Pixel, const T: usize>(
        &mut self,
        frame: &Frame<'_, P>,
        (x0, y0, sat): (i64, i64, u16),
        k: [u32; T],
    ) -> u32 {
        let (tw, th) = (
            usize::from(self.config.width),
            usize::from(self.config.height),
        );
        let (fw, fh) = (frame.width() as i64, frame.height() as i64);
        let half = (T / 2) as i64;
        let total: u32 = k.iter().sum();
        let scale = 1.0 / (total * total) as f32;
        // the template's mean on the integer scale (at most 2^24: a u16 pixel times 256)
        let mean = (self.t_mean / scale + 0.5).max(0.0) as i32;
        let gs = window_stride(tw);
        let inside = x0 - half >= 0 && x0 + tw as i64 + half <= fw;
        let LkTracker {
            g,
            dark,
            t_mean,
            cross,
            ..
        } = self;
        let n = (tw * th) as f32;
        // 8-bit frames with the whole source inside: the backend's whole-window pass, if it
        // has one (the same exact integers as the rows below)
        let stride = frame.stride();
        let whole = (T == 3 && inside && y0 >= half && y0 + th as i64 + half <= fh)
            .then(|| P::bytes(frame.pixels()))
            .flatten()
            .and_then(|px| {
                let at = (y0 - half) as usize * stride + (x0 - half) as usize;
                let src = px.get(at..)?;
                let (s, q, top) =
                    kernels::smooth_window3_bytes(src, stride, (tw, th), (&mut g[..], gs), mean)?;
                Some((s, q, top, src.get(stride + 1..).unwrap_or(&[])))
            });
        if let Some((s, q, top, win)) = whole {
            let mut saturated = 0;
            if top >= sat {
                saturated = match kernels::clipped_window_bytes(win, stride, (tw, th), dark, sat) {
                    Some(c) => c,
                    None => (0..th)
                        .map(|j| {
                            let row = win.get(j * stride..j * stride + tw).unwrap_or(&[]);
                            kernels::newly_clipped(row, dark.get(j * tw..).unwrap_or(&[]), sat)
                        })
                        .sum(),
                };
            }
            *cross = Cross::window(s, i128::from(q), mean, scale, *t_mean, n);
            return saturated;
        }
        // the window's sum and sum of squares: rows' sums in i64, the total of the squares in
        // i128 (any window size)
        let (mut sum, mut sq) = (0i64, 0i128);
        let mut saturated = 0u32;
        // source row `r` (frame row y0 - half + r), repeated at the frame's top and bottom
        let source = |r: usize| {
            let y = (y0 - half + r as i64).min(fh - 1).max(0) as usize;
            frame.row(y).unwrap_or(&[])
        };
        // the T source rows of window row j, slid down one row per window row
        let mut rows: [&[P]; T] = [&[]; T];
        for (n, r) in rows.iter_mut().enumerate().skip(1) {
            *r = source(n - 1);
        }
        let start = (x0 - half).max(0) as usize;
        for (j, row) in g.chunks_exact_mut(gs.max(4)).take(th).enumerate() {
            rows.rotate_left(1);
            if let Some(last) = rows.last_mut() {
                *last = source(j + T - 1);
            }
            let (out, pad) = row.split_at_mut(tw.min(row.len()));
            pad.fill(0.0);
            let segs = rows.map(|r| r.get(start..start + tw + T - 1).filter(|_| inside));
            // the brightest pixel of the centre row (the window's row and its margin), on the way
            let mut top = 0u16;
            let fast = match (T, segs.as_slice()) {
                (1, [Some(a)]) => {
                    let v = a.iter().map(|&a| {
                        let a = a.into();
                        top = top.max(a);
                        u32::from(a)
                    });
                    let (rs, rq) = emit(out, v, mean);
                    sum += rs;
                    sq += i128::from(rq);
                    true
                }
                (3, [Some(a), Some(b), Some(c)]) => {
                    match kernels::smooth_row3(a, b, c, out, mean) {
                        Some((rs, rq, rt)) => {
                            top = rt;
                            sum += rs;
                            sq += i128::from(rq);
                            true
                        }
                        None => false,
                    }
                }
                (5, [Some(a), Some(b), Some(c), Some(d), Some(e)]) => {
                    let mut cols = a
                        .iter()
                        .zip(b.iter())
                        .zip(c.iter())
                        .zip(d.iter())
                        .zip(e.iter())
                        .map(|((((&a, &b), &c), &d), &e)| {
                            let w = |p: P| u32::from(p.into());
                            let c = c.into();
                            top = top.max(c);
                            w(a) + 4 * w(b) + 6 * u32::from(c) + 4 * w(d) + w(e)
                        });
                    let mut p = [0u32; 4];
                    for v in p.iter_mut() {
                        *v = cols.next().unwrap_or(0);
                    }
                    let v = cols.map(|c4| {
                        let [p0, p1, p2, p3] = p;
                        p = [p1, p2, p3, c4];
                        p0 + 4 * p1 + 6 * p2 + 4 * p3 + c4
                    });
                    let (rs, rq) = emit(out, v, mean);
                    sum += rs;
                    sq += i128::from(rq);
                    true
                }
                _ => false,
            };
            if fast {
                // the common case: nothing at the saturation level in the row
                if top >= sat {
                    let centre = match segs.get(T / 2) {
                        Some(Some(c)) => c.get(T / 2..T / 2 + tw).unwrap_or(&[]),
                        _ => &[],
                    };
                    let dark = dark.get(j * tw..j * tw + tw).unwrap_or(&[]);
                    saturated += kernels::newly_clipped(centre, dark, sat);
                }
                continue;
            }
            // at the frame's left or right edge: the edge pixels repeat
            let px = |r: &[P], x: i64| -> u32 {
                let x = x.min(fw - 1).max(0) as usize;
                r.get(x).map_or(0, |p| u32::from((*p).into()))
            };
            for (i, o) in out.iter_mut().enumerate() {
                let x = x0 + i as i64;
                let mut v = 0u32;
                for (kx, dx) in k.iter().zip(-half..) {
                    for (ky, r) in k.iter().zip(&rows) {
                        v += kx * ky * px(r, x + dx);
                    }
                }
                let (rs, rq) = emit(core::slice::from_mut(o), [v].into_iter(), mean);
                sum += rs;
                sq += i128::from(rq);
                let raw = rows.get(T / 2).map_or(0, |r| px(r, x)) as u16;
                let dark = dark.get(j * tw + i).is_some_and(|&d| d);
                saturated += u32::from(raw >= sat && dark);
            }
        }
        *cross = Cross::window(sum, sq, mean, scale, *t_mean, n);
        saturated
    }

    /// The coarse integer search around `p` (see the module documentation): the best integer
    /// displacement, or `Err(flags)` when no offset fits in the frame, the best one is on the
    /// edge of the range, or a rival match away from it scores nearly as well (ambiguous).
    fn search<P: Pixel>(&self, frame: &Frame<'_, P>, p: (f32, f32)) -> Result<(f32, f32), Flags> {
        let (tw, th) = (i64::from(self.config.width), i64::from(self.config.height));
        // no window displaced further than the frame is wide lies in it: a range beyond that
        // (65535) would only cost time
        let side = frame.width().max(frame.height()) as i64;
        let r = i64::from(self.config.search).min(side);
        let b = (r / 8).min(tw.min(th) / 3).max(1);
        let (cx, cy) = (floorf(p.0 + 0.5) as i64, floorf(p.1 + 0.5) as i64);
        // a rival is a match at least half the template's larger side from the best
        let apart = (tw.max(th) / 2).max(2);
        let mut best = Ranked::default();
        let consider = |dx: i64, dy: i64, block: i64, best: &mut Ranked| {
            if (dx - cx).abs() > r || (dy - cy).abs() > r {
                return;
            }
            if let Some(s) = self.zncc_at(frame, dx, dy, block) {
                best.offer((s, dx, dy), apart);
            }
        };
        if b > 1 {
            let steps = r / b;
            for sy in -steps..=steps {
                for sx in -steps..=steps {
                    consider(cx + sx * b, cy + sy * b, b, &mut best);
                }
            }
        }
        let (fx, fy, span) = match best.best {
            Some((_, x, y)) => (x, y, b),
            None => (cx, cy, r),
        };
        let mut fine = Ranked::default();
        for dy in fy - span..=fy + span {
            for dx in fx - span..=fx + span {
                consider(dx, dy, 1, &mut fine);
            }
        }
        let Some((score, x, y)) = fine.best else {
            return Err(Flags::BORDER);
        };
        if score < self.config.min_score {
            return Err(Flags::DIVERGED);
        }
        // the rival of the pass that saw the whole range (block sums compared with block sums)
        let whole = if b > 1 { &best } else { &fine };
        if let (Some((top, ..)), Some((rival, ..))) = (whole.best, whole.rival) {
            if self.config.ambiguity > 0.0 && rival >= top - self.config.ambiguity {
                return Err(Flags::AMBIGUOUS);
            }
        }
        if r > 0 && r < side && ((x - cx).abs() == r || (y - cy).abs() == r) {
            return Err(Flags::DIVERGED);
        }
        // saturation is judged by the refinement that follows
        Ok((x as f32, y as f32))
    }

    /// ZNCC of `block x block` sums of the template and of the frame window displaced by
    /// `(dx, dy)` whole pixels; `None` when the window leaves the frame.
    fn zncc_at<P: Pixel>(&self, frame: &Frame<'_, P>, dx: i64, dy: i64, block: i64) -> Option<f32> {
        let (tw, th) = (i64::from(self.config.width), i64::from(self.config.height));
        let (x0, y0) = (i64::from(self.origin.0) + dx, i64::from(self.origin.1) + dy);
        if x0 < 0 || y0 < 0 || x0 + tw > frame.width() as i64 || y0 + th > frame.height() as i64 {
            return None;
        }
        let (bw, bh) = (tw / block, th / block);
        let m = self.t_mean;
        let (mut st, mut stt, mut sf, mut sff, mut sft) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for by in 0..bh {
            for bx in 0..bw {
                let (mut vt, mut vf) = (0.0f32, 0.0f32);
                for j in by * block..(by + 1) * block {
                    let row = frame.row((y0 + j) as usize)?;
                    for i in bx * block..(bx + 1) * block {
                        let k = (j * tw + i) as usize;
                        vt += self.t.get(k).copied().unwrap_or(0.0) - m;
                        vf += f32::from(row.get((x0 + i) as usize).copied()?.into()) - m;
                    }
                }
                st += vt;
                stt += vt * vt;
                sf += vf;
                sff += vf * vf;
                sft += vf * vt;
            }
        }
        let n = (bw * bh) as f32;
        let (vt, vf) = (stt - st * st / n, sff - sf * sf / n);
        if vt > 0.0 && vf > 0.0 {
            Some((sft - st * sf / n) / sqrtf(vt * vf))
        } else {
            Some(0.0)
        }
    }
}

/// A search's match further from its start than this many times the largest step seen so
/// far (and than half the template) is a jump the motion does not explain
/// ([`LkTracker::track`]).
pub const JUMP_FACTOR: f32 = 3.0;

/// The best match of a search and its best rival: the best-scoring offset at least `apart`
/// px (in either axis) from the best.
#[derive(Debug, Clone, Copy, Default)]
struct Ranked {
    best: Option<(f32, i64, i64)>,
    rival: Option<(f32, i64, i64)>,
}

impl Ranked {
    /// Takes a scored offset into account: a new best keeps the old one as the rival if it is
    /// apart from it (else the rival stays, if it is apart from the new best).
    fn offer(&mut self, c: (f32, i64, i64), apart: i64) {
        let far = |a: (f32, i64, i64), b: (f32, i64, i64)| {
            (a.1 - b.1).abs() >= apart || (a.2 - b.2).abs() >= apart
        };
        match self.best {
            None => self.best = Some(c),
            Some(b) if c.0 > b.0 => {
                // the old best outranks every rival
                self.rival = match far(b, c) {
                    true => Some(b),
                    false => self.rival.filter(|&r| far(r, c)),
                };
                self.best = Some(c);
            }
            Some(b) => {
                if far(c, b) && self.rival.is_none_or(|r| c.0 > r.0) {
                    self.rival = Some(c);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    extern crate std;
    use std::vec::Vec;

    const FW: usize = 96;
    const FH: usize = 80;

    /// A speckle pattern (a few Gaussian spots of sigma 2 px) displaced by `(dx, dy)`, sampled
    /// at the pixel centres, 8-bit with `gain` (values up to about `40 + gain`).
    fn speckle(dx: f64, dy: f64, gain: f64) -> Vec<u8> {
        let spots = [
            (40.0, 35.0, 1.0),
            (47.0, 38.0, 0.7),
            (43.0, 44.0, 0.9),
            (52.0, 33.0, 0.6),
            (36.0, 42.0, 0.8),
            (50.0, 46.0, 0.5),
        ];
        let mut px = Vec::with_capacity(FW * FH);
        for y in 0..FH {
            for x in 0..FW {
                let mut v = 40.0;
                for (sx, sy, a) in spots {
                    let (ex, ey) = (x as f64 - sx - dx, y as f64 - sy - dy);
                    v += gain * a * libm::exp(-(ex * ex + ey * ey) / 8.0);
                }
                px.push(libm::round(v).clamp(0.0, 255.0) as u8);
            }
        }
        px
    }

    fn frame(px: &[u8]) -> Frame<'_, u8> {
        Frame::new(px, FW, FH, FW).unwrap()
    }

    type Lk = LkTracker<{ 39 * 39 }, 38>;

    fn tracker(search: u16, interpolation: Interpolation) -> Lk {
        let mut cfg = LkConfig::new(31, 31);
        cfg.search = search;
        cfg.interpolation = interpolation;
        let mut t = Lk::try_new(cfg).unwrap();
        let reference = speckle(0.0, 0.0, 200.0);
        t.set_template(&frame(&reference), 44 - 15, 40 - 15)
            .unwrap();
        t
    }

    #[test]
    fn sub_pixel_shifts_are_measured_to_a_few_thousandths() {
        for interpolation in [
            Interpolation::Spline,
            Interpolation::Bicubic,
            Interpolation::Bilinear,
        ] {
            let mut worst = 0.0f32;
            // (0.93, -0.93): refined on the first window, kept up to `KEEP` px
            let shifts = [
                (0.3, -0.7),
                (-0.45, 0.25),
                (0.5, 0.5),
                (1.2, -0.9),
                (0.93, -0.93),
            ];
            for &(dx, dy) in &shifts {
                let mut t = tracker(0, interpolation);
                let img = speckle(dx, dy, 200.0);
                let r = t.track(&frame(&img));
                let (mx, my) = r.displacement().expect("tracked");
                worst = worst
                    .max((mx - dx as f32).abs())
                    .max((my - dy as f32).abs());
                assert!(r.score > 0.99, "{r:?}");
                assert!(!r.searched);
            }
            // rounding to 8 bits alone limits it; bilinear smooths the pattern (a bias)
            let limit = match interpolation {
                Interpolation::Bicubic | Interpolation::Spline => 0.01,
                Interpolation::Bilinear => 0.05,
            };
            assert!(worst < limit, "{interpolation:?}: {worst}");
        }
    }

    #[test]
    fn a_template_blurred_unlike_the_frame_settles_at_every_half_pixel() {
        // the template smeared over 6 px along y (a long exposure at speed), the frames sharp:
        // no shift matches exactly, and the window read at whole pixels changes at the half
        // pixels; the estimate must still settle, and move with the target smoothly
        let (w, h) = (FW, FH);
        let mut acc = std::vec![0.0f64; w * h];
        for s in 0..13 {
            let img = speckle(0.0, -3.0 + 0.5 * s as f64, 200.0);
            for (a, v) in acc.iter_mut().zip(&img) {
                *a += f64::from(*v) / 13.0;
            }
        }
        let blurred: Vec<u8> = acc.iter().map(|v| libm::round(*v) as u8).collect();
        let mut cfg = LkConfig::new(31, 31);
        cfg.search = 0;
        let mut t = Lk::try_new(cfg).unwrap();
        t.set_template(&frame(&blurred), 44 - 15, 40 - 15).unwrap();
        let mut last: Option<f32> = None;
        for k in 0..=20 {
            let dy = 2.0 + 0.05 * f64::from(k);
            let r = t.track(&frame(&speckle(0.1, dy, 200.0)));
            let (_, my) = r
                .displacement()
                .unwrap_or_else(|| panic!("lost at {dy}: {r:?}"));
            assert!((f64::from(my) - dy).abs() < 0.06, "{dy}: {my}");
            if let Some(l) = last {
                let step = my - l;
                assert!((0.03..0.07).contains(&step), "{dy}: step {step}");
            }
            last = Some(my);
        }
    }

    /// The window read, smoothed and stored in integers equals the smoothing done in f64 at
    /// every kernel, for 8- and 16-bit frames, inside the frame and at its left edge (the
    /// edge pixels repeat), and its sums are the sums over those values.
    fn window_matches_f64<P: Pixel>(px: &[P], smoothing: Smoothing, q: (i64, i64)) {
        let f = Frame::new(px, FW, FH, FW).unwrap();
        let mut cfg = LkConfig::new(31, 31);
        cfg.smoothing = smoothing;
        let mut t = Lk::try_new(cfg).unwrap();
        t.set_template(&f, 29, 25).unwrap();
        t.load_window(&f, q, u16::MAX).unwrap();
        let (k, half): (&[f64], i64) = match smoothing {
            Smoothing::None => (&[1.0], 0),
            Smoothing::Binomial3 => (&[1.0, 2.0, 1.0], 1),
            Smoothing::Binomial5 => (&[1.0, 4.0, 6.0, 4.0, 1.0], 2),
        };
        let total: f64 = k.iter().sum();
        let at = |x: i64, y: i64| {
            let (x, y) = (x.clamp(0, FW as i64 - 1), y.clamp(0, FH as i64 - 1));
            f64::from(px[y as usize * FW + x as usize].into())
        };
        let (x0, y0) = (29 + q.0, 25 + q.1);
        let (mut sum, mut sq, mut worst) = (0.0f64, 0.0f64, 0.0f64);
        let mut values = Vec::new();
        for j in 0..31i64 {
            for i in 0..31i64 {
                let mut v = 0.0;
                for (dy, ky) in (-half..).zip(k) {
                    for (dx, kx) in (-half..).zip(k) {
                        v += ky * kx * at(x0 + i + dx, y0 + j + dy);
                    }
                }
                let g = v / (total * total) - f64::from(t.t_mean);
                let stored = f64::from(t.g[j as usize * window_stride(31) + i as usize]);
                let back = f64::from(t.cross.scale) * stored + f64::from(t.cross.offset);
                worst = worst.max((back - g).abs());
                sum += g;
                values.push(g);
            }
        }
        let mean = sum / values.len() as f64;
        for g in &values {
            sq += (g - mean) * (g - mean);
        }
        let level = f64::from(P::FULL);
        assert!(worst < 1e-6 * level, "{smoothing:?} at {q:?}: {worst}");
        assert!(
            (f64::from(t.cross.sum) - sum).abs() < 1e-6 * level * 961.0,
            "{smoothing:?} at {q:?}: sum {} {sum}",
            t.cross.sum
        );
        assert!(
            (f64::from(t.cross.var) - sq).abs() < 1e-6 * sq,
            "{smoothing:?} at {q:?}: var {} {sq}",
            t.cross.var
        );
        // the row pad the cross moments' kernels run over is zero
        for j in 0..31 {
            assert_eq!(t.g[j * window_stride(31) + 31], 0.0);
        }
    }

    #[test]
    fn the_window_is_smoothed_exactly_for_every_kernel_and_at_the_frame_edge() {
        let px8 = speckle(0.3, -0.2, 200.0);
        // 16-bit: the same scene on the whole range, and a level near the top
        let px16: Vec<u16> = px8.iter().map(|&v| u16::from(v) * 257).collect();
        for smoothing in [Smoothing::None, Smoothing::Binomial3, Smoothing::Binomial5] {
            // inside; the window's left column on the frame's first column (the kernel's
            // margin repeats it); its top row on the frame's first row
            for q in [(2, -1), (-29, 0), (0, -25)] {
                window_matches_f64(&px8, smoothing, q);
                window_matches_f64(&px16, smoothing, q);
            }
        }
    }

    #[test]
    fn the_spline_moments_equal_the_sums_over_the_pixels() {
        // every iteration's sums come from moments formed once per template and per window:
        // check them against the sums over the shifted template's pixels, in f64
        let mut t = tracker(0, Interpolation::Spline);
        let img = speckle(0.37, -0.61, 190.0);
        let f = frame(&img);
        let (tw, th) = (31usize, 31usize);
        let pw = tw + 2 * SPLINE_MARGIN;
        let m = SPLINE_MARGIN as i64;
        for &(px, py) in &[(0.3f32, -0.7f32), (0.74, 0.1), (-0.2, -0.74), (0.0, 0.5)] {
            let (b, score) = t.spline_error(&f, (px, py), u16::MAX).unwrap();
            let (qx, qy) = t.g_at.unwrap();
            let (sx, sy) = (qx as f64 - f64::from(px), qy as f64 - f64::from(py));
            let (ax, ay) = (sx.floor(), sy.floor());
            let wts = |f: f64| bspline_weights(f as f32).map(f64::from);
            let slopes = |f: f64| bspline_slopes(f as f32).map(f64::from);
            let (wx, wy, dwx, dwy) = (wts(sx - ax), wts(sy - ay), slopes(sx - ax), slopes(sy - ay));
            let c = |i: i64, j: i64| f64::from(t.coef[((j + m) * pw as i64 + i + m) as usize]);
            let (mut bx, mut by) = (0.0f64, 0.0f64);
            let (mut g1, mut g2, mut s1, mut s2, mut gs) = (0.0f64, 0.0, 0.0, 0.0, 0.0);
            for j in 0..th as i64 {
                for i in 0..tw as i64 {
                    let (mut v, mut dx, mut dy) = (0.0, 0.0, 0.0);
                    for l in 0..4 {
                        for k in 0..4 {
                            let cv = c(i + ax as i64 - 1 + k, j + ay as i64 - 1 + l);
                            let (k, l) = (k as usize, l as usize);
                            v += wx[k] * wy[l] * cv;
                            dx += dwx[k] * wy[l] * cv;
                            dy += wx[k] * dwy[l] * cv;
                        }
                    }
                    // the window as stored (integers, rows padded to the stride) back on the
                    // template's scale
                    let stored = f64::from(t.g[j as usize * window_stride(tw) + i as usize]);
                    let g = f64::from(t.cross.scale) * stored + f64::from(t.cross.offset);
                    bx += dx * (g - v);
                    by += dy * (g - v);
                    g1 += g;
                    g2 += g * g;
                    s1 += v;
                    s2 += v * v;
                    gs += g * v;
                }
            }
            let n = (tw * th) as f64;
            let zncc = (gs - g1 * s1 / n) / ((g2 - g1 * g1 / n) * (s2 - s1 * s1 / n)).sqrt();
            // relative to the terms' scale (sum of |slope| |g|): f32 moments against f64 sums
            let scale = t.h_inv[0].abs().recip() as f64;
            assert!(
                (f64::from(b.0) - bx).abs() < 1e-4 * scale,
                "{px},{py}: {} {bx}",
                b.0
            );
            assert!(
                (f64::from(b.1) - by).abs() < 1e-4 * scale,
                "{px},{py}: {} {by}",
                b.1
            );
            assert!((f64::from(score) - zncc).abs() < 1e-5, "{score} {zncc}");
            assert!(
                bx.abs() > 1e-3 * scale,
                "a shift away from the optimum has an error"
            );
        }
    }

    #[test]
    fn a_start_given_far_from_the_last_position_is_refined_there() {
        // what a caller that knows the shared motion of several targets does: the target
        // jumped 20.4 px, further than the refinement reaches and with no search of its own
        let mut t = tracker(0, Interpolation::Spline);
        let img = speckle(20.4, -12.3, 200.0);
        assert!(t.track(&frame(&img)).displacement().is_none());
        let r = t.track_from(&frame(&img), Some((19.0, -11.0)), 3);
        let (x, y) = r.displacement().expect("tracked from the given start");
        assert!((x - 20.4).abs() < 0.01 && (y + 12.3).abs() < 0.01, "{r:?}");
        // the configured search is back
        assert_eq!(t.config().search, 0);
        assert!(t
            .track_from(&frame(&img), Some((f32::NAN, 0.0)), 3)
            .displacement()
            .is_none());
    }

    #[test]
    fn the_coarse_search_catches_motions_of_many_pixels_and_its_edge_is_a_loss() {
        let mut t = tracker(24, Interpolation::Bicubic);
        // from rest, a jump of 20 px is more than the motion so far explains (and than half
        // the template): lost, whatever the search found (a look-alike or the target)
        let img = speckle(20.4, -12.3, 200.0);
        let r = t.track(&frame(&img));
        assert!(r.searched);
        assert!(r.flags.contains(Flags::AMBIGUOUS), "{r:?}");
        assert_eq!(t.displacement(), (0.0, 0.0));
        // a target seen moving 7.3 px a frame: the search finds it 21.4 px from the
        // prediction (within three of its steps)
        for dx in [7.3, 14.6] {
            let r = t.track(&frame(&speckle(dx, 0.0, 200.0)));
            assert!((r.dx - dx as f32).abs() < 0.01, "{r:?}");
        }
        let r = t.track(&frame(&speckle(0.5, -1.0, 200.0)));
        assert!(r.searched, "{r:?}");
        let (mx, my) = r.displacement().expect("found by the search");
        assert!((mx - 0.5).abs() < 0.01 && (my + 1.0).abs() < 0.01, "{r:?}");
        // and the next frame at a small step from there, its prediction 14 px off (the last
        // step's velocity): a search within half the template, explained
        let img = speckle(1.0, -0.7, 200.0);
        let r = t.track(&frame(&img));
        assert!((r.dx - 1.0).abs() < 0.01 && r.flags.is_clear(), "{r:?}");
        // 22.5 px from the prediction of the same target: more than three of its steps
        let mut t = tracker(24, Interpolation::Bicubic);
        for dx in [7.3, 14.6] {
            t.track(&frame(&speckle(dx, 0.0, 200.0)));
        }
        let r = t.track(&frame(&speckle(-0.6, 0.0, 200.0)));
        assert!(r.flags.contains(Flags::AMBIGUOUS), "{r:?}");
        // a jump beyond the range (and beyond where the refinement alone converges): lost,
        // flagged, and the state kept
        let mut t = tracker(6, Interpolation::Bicubic);
        let img = speckle(25.0, 0.0, 200.0);
        let r = t.track(&frame(&img));
        assert_eq!(r.displacement(), None, "{r:?}");
        assert!(r.flags.contains(Flags::DIVERGED), "{r:?}");
        assert_eq!(t.displacement(), (0.0, 0.0));
    }

    #[test]
    fn a_search_that_sees_two_look_alikes_is_ambiguous_not_a_jump_onto_one() {
        // the target gone from where it was, and two copies of it 12 px either side (within
        // half the template of the start: a jump the search range explains): the search
        // cannot tell which is the target (a tag among tags of a structure)
        let (left, right) = (speckle(-12.0, 0.0, 200.0), speckle(12.0, 0.0, 200.0));
        let img: Vec<u8> = left
            .iter()
            .zip(&right)
            .map(|(&a, &b)| (u16::from(a) + u16::from(b) - 40).min(255) as u8)
            .collect();
        let mut t = tracker(24, Interpolation::Bicubic);
        let r = t.track(&frame(&img));
        assert!(r.searched, "{r:?}");
        assert_eq!(r.displacement(), None, "{r:?}");
        assert!(r.flags.contains(Flags::AMBIGUOUS), "{r:?}");
        assert_eq!(t.displacement(), (0.0, 0.0));
        // without the check the search takes one of them: the silent jump this flag prevents
        let mut cfg = *t.config();
        cfg.ambiguity = 0.0;
        let mut t = Lk::try_new(cfg).unwrap();
        t.set_template(&frame(&speckle(0.0, 0.0, 200.0)), 44 - 15, 40 - 15)
            .unwrap();
        let (dx, _) = t.track(&frame(&img)).displacement().expect("a jump");
        assert!((dx.abs() - 12.0).abs() < 0.5, "{dx}");
        // one copy alone, as far: found, not ambiguous
        let mut t = tracker(24, Interpolation::Bicubic);
        let r = t.track(&frame(&right));
        assert!((r.dx - 12.0).abs() < 0.01 && r.flags.is_clear(), "{r:?}");
        // the setting is checked
        cfg.ambiguity = 1.5;
        assert_eq!(cfg.validate(39 * 39, 38), Err(LkError::Setting));
    }

    #[test]
    fn flat_windows_edges_and_saturation_are_refused_or_lost() {
        let mut t = Lk::try_new(LkConfig::new(31, 31)).unwrap();
        let flat = [77u8; FW * FH];
        assert_eq!(t.set_template(&frame(&flat), 10, 10), Err(LkError::Flat));
        // a straight edge moving along itself has no texture across one axis
        let edge: Vec<u8> = (0..FW * FH)
            .map(|i| if i % FW < 48 { 30 } else { 200 })
            .collect();
        assert_eq!(t.set_template(&frame(&edge), 30, 20), Err(LkError::Flat));
        // the template must be inside the frame (at its edge the edge pixels repeat)
        let img = speckle(0.0, 0.0, 200.0);
        assert_eq!(t.set_template(&frame(&img), -1, 10), Err(LkError::Outside));
        assert_eq!(t.set_template(&frame(&img), 66, 10), Err(LkError::Outside));
        let texture: Vec<u8> = (0..FW * FH).map(|i| (i * 37 % 251) as u8).collect();
        assert_eq!(t.set_template(&frame(&texture), 65, 49), Ok(()));
        // followed to the frame's edge, then further: the window would leave the frame
        let mut t = tracker(0, Interpolation::Bicubic);
        for dx in [-7.0, -14.0, -21.0, -27.5] {
            let img = speckle(dx, 0.0, 200.0);
            let r = t.track(&frame(&img));
            assert!((r.dx - dx as f32).abs() < 0.02, "{dx}: {r:?}");
        }
        let img = speckle(-30.5, 0.0, 200.0);
        let r = t.track(&frame(&img));
        assert_eq!(r.displacement(), None, "{r:?}");
        assert!(r.flags.contains(Flags::BORDER), "{r:?}");
        // brighter and clipped at 255: the clipped pixels do not move with the template
        let mut t = tracker(4, Interpolation::Bicubic);
        let img = speckle(0.2, 0.1, 400.0);
        let r = t.track(&frame(&img));
        assert!(r.flags.contains(Flags::SATURATED), "{r:?}");
        assert_eq!(r.displacement(), None);
        // the same clipped frame against a template taken again, from a dim frame, after one
        // taken from a clipped frame (where those pixels were bright): the new template's
        // mask decides, on both paths
        for interpolation in [Interpolation::Bicubic, Interpolation::Spline] {
            let mut t = tracker(4, interpolation);
            let bright = speckle(0.0, 0.0, 400.0);
            t.set_template(&frame(&bright), 29, 25).unwrap();
            let r = t.track(&frame(&speckle(0.2, 0.1, 400.0)));
            assert!(
                !r.flags.contains(Flags::SATURATED),
                "{interpolation:?} {r:?}"
            );
            let dim = speckle(0.0, 0.0, 100.0);
            t.set_template(&frame(&dim), 29, 25).unwrap();
            let r = t.track(&frame(&speckle(0.2, 0.1, 400.0)));
            assert!(
                r.flags.contains(Flags::SATURATED),
                "{interpolation:?} {r:?}"
            );
        }
        // a tracker without a template reports no displacement
        let mut t = Lk::try_new(LkConfig::new(31, 31)).unwrap();
        assert_eq!(t.track(&frame(&img)).displacement(), None);
    }

    #[test]
    fn settings_are_checked_against_the_capacities() {
        assert_eq!(
            Lk::try_new(LkConfig::new(2, 31)).err(),
            Some(LkError::WindowTooSmall)
        );
        assert!(matches!(
            Lk::try_new(LkConfig::new(32, 29)).err(),
            Some(LkError::WindowTooLarge { .. })
        ));
        let mut c = LkConfig::new(31, 31);
        c.tolerance = 0.0;
        assert_eq!(Lk::try_new(c).err(), Some(LkError::Setting));
        let mut c = LkConfig::new(31, 31);
        c.accept_score = 0.2;
        assert_eq!(Lk::try_new(c).err(), Some(LkError::Setting));
    }

    #[test]
    fn sixteen_bit_frames_track_as_eight_bit_ones() {
        let img8 = speckle(0.35, -0.6, 200.0);
        let img16: Vec<u16> = img8.iter().map(|&v| u16::from(v) * 16).collect();
        let mut t = LkTracker::<{ 39 * 39 }, 38>::try_new(LkConfig::new(31, 31)).unwrap();
        let reference: Vec<u16> = speckle(0.0, 0.0, 200.0)
            .iter()
            .map(|&v| u16::from(v) * 16)
            .collect();
        fn f16(p: &[u16]) -> Frame<'_, u16> {
            Frame::new(p, FW, FH, FW).unwrap()
        }
        t.set_template(&f16(&reference), 29, 25).unwrap();
        let a = t.track(&f16(&img16)).displacement().unwrap();
        let b = tracker(15, Interpolation::Spline)
            .track(&frame(&img8))
            .displacement()
            .unwrap();
        assert!(
            (a.0 - b.0).abs() < 1e-3 && (a.1 - b.1).abs() < 1e-3,
            "{a:?} {b:?}"
        );
    }

    /// Both backends' cross-moment kernels against the sums in f64, for every lag count, on
    /// a window whose rows are padded with zeros (as `LkTracker::g` is).
    #[test]
    fn both_backends_form_the_cross_moments_of_every_lag_count() {
        fn check<const K: usize>(tw: usize, th: usize) {
            let (gs, pw) = (window_stride(tw), tw + 2 * SPLINE_MARGIN);
            let mut g = std::vec![0.0f32; gs * th];
            for (k, v) in g.iter_mut().enumerate() {
                if k % gs < tw {
                    *v = ((k * 7919) % 513) as f32 - 256.0;
                }
            }
            let c: Vec<f32> = (0..pw * (th + 4))
                .map(|k| (((k * 104729) % 1001) as f32 - 500.0) / 37.0)
                .collect();
            let (mut lag, mut col, mut scale) = ([0.0f64; K], [0.0f64; K], [0.0f64; K]);
            for j in 0..th {
                for i in 0..gs {
                    let gv = f64::from(g[j * gs + i]);
                    for k in 0..K {
                        let (a, b) = (f64::from(c[j * pw + i + k]), f64::from(c[(j + k) * pw + i]));
                        lag[k] += gv * a;
                        col[k] += gv * b;
                        scale[k] += (gv * a).abs() + (gv * b).abs();
                    }
                }
            }
            let got = [
                (m4::lag_sums::<K>(&g, gs, &c, pw, th), lag),
                (lanes::lag_sums::<K>(&g, gs, &c, pw, th), lag),
                (m4::column_sums::<K>(&g, gs, &c, pw, th), col),
                (lanes::column_sums::<K>(&g, gs, &c, pw, th), col),
            ];
            for (n, (sums, want)) in got.iter().enumerate() {
                for k in 0..K {
                    let err = (f64::from(sums[k]) - want[k]).abs();
                    assert!(
                        err <= 1e-6 * scale[k],
                        "kernel {n}, {K} lags, {tw} x {th}, lag {k}: {} against {}",
                        sums[k],
                        want[k]
                    );
                }
            }
        }
        for (tw, th) in [(3, 3), (4, 5), (9, 7), (31, 31), (37, 12), (64, 3)] {
            check::<1>(tw, th);
            check::<2>(tw, th);
            check::<3>(tw, th);
            check::<4>(tw, th);
        }
    }

    /// Both backends' `[1 2 1]` row smoothing against the integer sums, exactly (8- and
    /// 16-bit pixels, rows shorter and longer than a block, the longest row), and their
    /// refusals; both backends' count of newly clipped pixels against the mask read per pixel.
    #[test]
    fn both_backends_smooth_a_row_exactly_and_count_clipped_pixels_alike() {
        fn check<P: Pixel + Copy>(px: &[P], n: usize, mean: i32) {
            let v = |k: usize| i64::from(px[k].into());
            let rows = [
                &px[..n + 2],
                &px[n + 2..2 * n + 4],
                &px[2 * n + 4..3 * n + 6],
            ];
            let (mut sum, mut sq, mut top) = (0i64, 0i64, 0u16);
            let mut want = std::vec![0.0f32; n];
            let col = |i: usize| v(i) + 2 * v(n + 2 + i) + v(2 * n + 4 + i);
            for (i, w) in want.iter_mut().enumerate() {
                let d = col(i) + 2 * col(i + 1) + col(i + 2) - i64::from(mean);
                *w = d as f32;
                sum += d;
                sq += d * d;
            }
            for &b in rows[1] {
                top = top.max(b.into());
            }
            for backend in 0..2 {
                let mut out = std::vec![f32::NAN; n];
                let r = match backend {
                    0 => m4::smooth_row3(rows[0], rows[1], rows[2], &mut out, mean),
                    _ => lanes::smooth_row3(rows[0], rows[1], rows[2], &mut out, mean),
                };
                assert_eq!(r, Some((sum, sq, top)), "backend {backend}, {n} pixels");
                assert_eq!(out, want, "backend {backend}, {n} pixels");
                // rows of the wrong length, or too long a row: refused, nothing stored
                let mut short = std::vec![f32::NAN; n + 1];
                let r = match backend {
                    0 => m4::smooth_row3(rows[0], rows[1], rows[2], &mut short, mean),
                    _ => lanes::smooth_row3(rows[0], rows[1], rows[2], &mut short, mean),
                };
                assert_eq!(r, None);
                assert!(short.iter().all(|v| v.is_nan()));
            }
        }
        let noise = |k: usize, top: u64| ((k as u64 * 2654435761) % (top + 1)) as u32;
        for n in [1, 3, 4, 31, 63, 64, 65, 130, 2047] {
            let p8: Vec<u8> = (0..3 * n + 6).map(|k| noise(k, 255) as u8).collect();
            check(&p8, n, 2040);
            check(&p8, n, 0);
            // the extremes of 8-bit values against the mean (the largest squares: the 16-bit
            // lanes' sums must not overflow), and a mean beyond 8-bit values (a template
            // taken from 16-bit frames)
            check(&std::vec![255u8; 3 * n + 6], n, 0);
            check(&std::vec![0u8; 3 * n + 6], n, 16 * 255);
            check(&p8, n, 1 << 19);
            let p16: Vec<u16> = (0..3 * n + 6).map(|k| noise(k, 65535) as u16).collect();
            check(&p16, n, 1 << 19);
        }
        // longer than 2047 pixels: refused by both
        let long = std::vec![7u8; 2050];
        let mut out = std::vec![0.0f32; 2048];
        assert_eq!(m4::smooth_row3(&long, &long, &long, &mut out, 0), None);
        assert_eq!(lanes::smooth_row3(&long, &long, &long, &mut out, 0), None);

        let row: Vec<u16> = (0..70).map(|k| [65535, 3, 65000, 65535][k % 4]).collect();
        let dark: Vec<bool> = (0..70).map(|k| k % 3 != 0).collect();
        let want = (0..70).filter(|&k| row[k] >= 65000 && dark[k]).count() as u32;
        assert!(want > 0);
        assert_eq!(m4::newly_clipped(&row, &dark, 65000), want);
        assert_eq!(lanes::newly_clipped(&row, &dark, 65000), want);
        // a mask shorter than the row: the pixels past it are not counted
        let want = (0..10).filter(|&k| row[k] >= 65000 && dark[k]).count() as u32;
        assert_eq!(m4::newly_clipped(&row, &dark[..10], 65000), want);
        assert_eq!(lanes::newly_clipped(&row, &dark[..10], 65000), want);
    }

    #[test]
    fn the_hosts_whole_window_pass_equals_the_rows_and_counts_clipped_pixels_alike() {
        let noise = |k: usize, top: u64| ((k as u64 * 2654435761 + 12345) % (top + 1)) as u8;
        for (tw, th) in [
            (8, 1),
            (9, 3),
            (15, 7),
            (16, 16),
            (31, 31),
            (33, 40),
            (40, 100),
        ] {
            let stride = tw + 2 + 5;
            for (mean, px) in [
                (
                    2040,
                    (0..(th + 2) * stride)
                        .map(|k| noise(k, 255))
                        .collect::<Vec<u8>>(),
                ),
                (0, std::vec![255u8; (th + 2) * stride]),
                (16 * 255, std::vec![0u8; (th + 2) * stride]),
            ] {
                // the rows' smoothing (the M4's, tested above against the sums themselves)
                let gs = window_stride(tw) + 4;
                let mut want = std::vec![0.0f32; th * gs];
                let (mut sum, mut sq, mut top) = (0i64, 0i64, 0u16);
                for j in 0..th {
                    let row = |r: usize| &px[r * stride..r * stride + tw + 2];
                    let out = &mut want[j * gs..j * gs + tw];
                    let (s, q, _) = m4::smooth_row3(row(j), row(j + 1), row(j + 2), out, mean)
                        .expect("rows of the right length");
                    (sum, sq) = (sum + s, sq + q);
                    let window_row = &row(j + 1)[1..tw + 1];
                    top = top.max(window_row.iter().map(|&v| u16::from(v)).max().unwrap_or(0));
                }
                let mut g = std::vec![f32::NAN; th * gs];
                let r = lanes::smooth_window3_bytes(&px, stride, (tw, th), (&mut g, gs), mean);
                assert_eq!(r, Some((sum, sq, top)), "{tw} x {th}, mean {mean}");
                assert_eq!(g, want, "{tw} x {th}, mean {mean}");
                // the whole window's clip count, against the rows' (masks and levels varied)
                let dark: Vec<bool> = (0..tw * th).map(|k| (k * 7) % 5 != 0).collect();
                let win = &px[stride + 1..];
                for sat in [0u16, 1, 128, 255, 256] {
                    let rows: u32 = (0..th)
                        .map(|j| {
                            let row = &win[j * stride..j * stride + tw];
                            m4::newly_clipped(row, &dark[j * tw..j * tw + tw], sat)
                        })
                        .sum();
                    let whole = lanes::clipped_window_bytes(win, stride, (tw, th), &dark, sat);
                    assert_eq!(whole, (tw >= 16).then_some(rows), "{tw} x {th}, sat {sat}");
                }
            }
        }
        // refused, nothing stored: too narrow a window, a mean off the 8-bit scale, too short
        // a source or buffer
        let px = std::vec![9u8; 40 * 40];
        let mut g = std::vec![f32::NAN; 40 * 40];
        assert_eq!(
            lanes::smooth_window3_bytes(&px, 40, (7, 5), (&mut g, 8), 0),
            None
        );
        assert_eq!(
            lanes::smooth_window3_bytes(&px, 40, (8, 5), (&mut g, 8), -1),
            None
        );
        assert_eq!(
            lanes::smooth_window3_bytes(&px, 40, (8, 5), (&mut g, 8), 4081),
            None
        );
        assert_eq!(
            lanes::smooth_window3_bytes(&px[..200], 40, (8, 5), (&mut g, 8), 0),
            None
        );
        assert_eq!(
            lanes::smooth_window3_bytes(&px, 40, (8, 5), (&mut g[..39], 8), 0),
            None
        );
        // rows closer than the source is wide (a stride of 0 among them)
        for stride in [0, 9] {
            let r = lanes::smooth_window3_bytes(&px, stride, (8, 5), (&mut g, 8), 0);
            assert_eq!(r, None);
        }
        assert!(g.iter().all(|v| v.is_nan()));
        assert_eq!(
            m4::smooth_window3_bytes(&px, 40, (8, 5), (&mut g, 8), 0),
            None
        );
        let dark = std::vec![true; 40 * 40];
        assert_eq!(
            lanes::clipped_window_bytes(&px, 40, (16, 40), &dark[..100], 0),
            None
        );
        assert_eq!(
            lanes::clipped_window_bytes(&px[..100], 40, (16, 40), &dark, 0),
            None
        );
        assert_eq!(
            lanes::clipped_window_bytes(&px, 40, (16, 40), &dark, 0),
            Some(16 * 40)
        );
        assert_eq!(m4::clipped_window_bytes(&px, 40, (16, 40), &dark, 0), None);
    }

    #[test]
    fn the_hosts_tap_forms_equal_the_scalar_forms() {
        // a symmetric matrix of moments (as `Moments::of` makes them) with values of many
        // magnitudes, and weights of a spline's shifts
        let n = LAGS * LAGS;
        let mut c = std::vec![0.0f32; n * n];
        for i in 0..n {
            for j in i..n {
                let v = ((i * 31 + j * 17) % 23) as f32 * 1.37e3 - 9.1e3 + (i * j) as f32 * 0.013;
                c[i * n + j] = v;
                c[j * n + i] = v;
            }
        }
        for (fx, fy) in [(0.0, 0.0), (0.3, 0.9), (0.999, 0.5), (0.125, 0.0)] {
            let (wx, wy) = (bspline_weights(fx), bspline_weights(fy));
            for (lx, ly) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let forms = lanes::tap_forms(&c, LAGS, (lx, ly), wx, wy);
                for (m, &got) in forms.iter().enumerate() {
                    let (l, k) = (m / 4, m % 4);
                    let i = (ly + l) * LAGS + lx + k;
                    let mut cu = 0.0f32;
                    for (l2, &wyl) in wy.iter().enumerate() {
                        let at = i * n + (ly + l2) * LAGS + lx;
                        let [c0, c1, c2, c3] = [c[at], c[at + 1], c[at + 2], c[at + 3]];
                        let [w0, w1, w2, w3] = wx;
                        cu += wyl * (c0 * w0 + c1 * w1 + c2 * w2 + c3 * w3);
                    }
                    assert_eq!(got.to_bits(), cu.to_bits(), "lag {i} at ({lx}, {ly})");
                }
            }
        }
    }

    proptest::proptest! {
        #[test]
        fn nothing_panics_on_any_frame_or_setting(
            seed in proptest::collection::vec(0u8..=255, FW * FH),
            x0 in -5i32..100,
            y0 in -5i32..90,
            w in 0u16..40,
            h in 0u16..40,
            search in 0u16..40,
            bilinear in proptest::bool::ANY,
        ) {
            let mut cfg = LkConfig::new(w, h);
            cfg.search = search;
            if bilinear {
                cfg.interpolation = Interpolation::Bilinear;
            }
            if let Ok(mut t) = LkTracker::<{ 39 * 39 }, 38>::try_new(cfg) {
                let f = frame(&seed);
                let _ = t.set_template(&f, x0, y0);
                let r = t.track(&f);
                if let Some((dx, dy)) = r.displacement() {
                    proptest::prop_assert!(dx.is_finite() && dy.is_finite());
                }
            }
        }
    }
}
