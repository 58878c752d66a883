//! The estimate itself, without segment or transform buffers: [`WelchAccumulator`] takes one
//! segment of each channel at a time (one transform of both, packed as one complex sequence)
//! and keeps the auto and cross spectra in a mirrored half-complex layout.

#[cfg(doc)]
use super::WelchH1;
use super::{ConfigError, Detrend, WelchConfig, Window, MAX_SAMPLE_ABS};
use crate::dft::{Dft, Direction};
use crate::BufferError;
use crate::Complex32;
use core::fmt;

/// Why a call on a configured estimator cannot be served (nothing was consumed or written).
/// Configuration errors are [`ConfigError`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum WelchError {
    /// [`WelchH1::push`] got chunks of different lengths for `x` and `y` (nothing was consumed).
    ChunkLengths {
        /// Length of the `x` chunk.
        x: usize,
        /// Length of the `y` chunk.
        y: usize,
    },
    /// No segment has been accumulated yet: H1 and the coherence are not available.
    NoSegments,
    /// The estimator was built by `new()` and not configured yet (nothing was consumed).
    NotConfigured,
    /// A buffer passed to [`WelchAccumulator::add_segment`] has the wrong length (nothing was
    /// accumulated): `nperseg` for the segments, at least `nfft` for the work buffer, at least
    /// [`WelchAccumulator::scratch_len`] for the scratch.
    Buffer(BufferError),
}

error_display!(WelchError, f, {
    WelchError::ChunkLengths { x, y } => write!(
        f,
        "x and y chunks differ in length ({x} and {y} samples); nothing was consumed"
    ),
    WelchError::NoSegments => write!(f, "no complete segment has been accumulated yet"),
    WelchError::NotConfigured => write!(f, "the estimator is not configured yet"),
    WelchError::Buffer(e) => write!(f, "{e}"),
});

impl From<BufferError> for WelchError {
    fn from(e: BufferError) -> Self {
        WelchError::Buffer(e)
    }
}

/// Accumulated (unscaled) spectra at one bin: sums over the segments of `|X|^2`, `|Y|^2` and
/// `conj(X) Y`, with `X` and `Y` the DFTs of the detrended, windowed segments.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sums {
    /// Sum of `|X[k]|^2`.
    pub pxx: f32,
    /// Sum of `|Y[k]|^2`.
    pub pyy: f32,
    /// Sum of `conj(X[k]) Y[k]`.
    pub pxy: Complex32,
}

#[cfg(feature = "defmt")]
impl defmt::Format for Sums {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(
            f,
            "Sums {{ pxx: {}, pyy: {}, pxy: ({}, {}) }}",
            self.pxx,
            self.pyy,
            self.pxy.re,
            self.pxy.im
        )
    }
}

/// The accumulating half of a Welch H1 estimate: settings, the DFT plan and the accumulated
/// spectra of [`NFFT`](Self) bins, **without** segment buffers or transform work space. Whole
/// segments are added with [`add_segment`](Self::add_segment) from caller buffers, so a
/// firmware can share one complex work buffer between this estimate and other transforms (an
/// upsampler, see [`crate::pipeline`]) and cut segments straight out of its own sample
/// history. [`WelchH1`] wraps it with the segment buffers for sample-by-sample streaming.
///
/// The accumulators use a half-complex layout: `auto[k] = Pxx[k]` for `k <= nfft/2` and
/// `auto[nfft - k] = Pyy[k]` for `0 < k < nfft/2`, likewise `cross[k] = Re Pxy[k]` and
/// `cross[nfft - k] = Im Pxy[k]`; `Pyy` at DC and Nyquist live in two scalars and `Im Pxy` there
/// is exactly zero (real signals). This stores the `2 nfft + 4` accumulated values in `2 NFFT`
/// floats plus two. The window is evaluated per sample ([`crate::dft::cos_sin_turns`], `f32`)
/// rather than stored, which saves `4 nperseg` bytes for about 30 instructions per sample on a
/// Cortex-M4F.
#[derive(Clone)]
pub struct WelchAccumulator<const NFFT: usize> {
    pub(super) config: WelchConfig,
    dft: Dft,
    auto: [f32; NFFT],
    cross: [f32; NFFT],
    pyy_dc: f32,
    pyy_nyquist: f32,
    pub(super) segments: u32,
    pub(super) skipped: u32,
}

/// Shows the settings and counters, not the accumulators.
impl<const NFFT: usize> fmt::Debug for WelchAccumulator<NFFT> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("WelchAccumulator")
            .field("capacity", &NFFT)
            .field("config", &self.config)
            .field("segments", &self.segments)
            .field("skipped", &self.skipped)
            .finish_non_exhaustive()
    }
}

/// Logs the settings and counters, not the accumulators.
#[cfg(feature = "defmt")]
impl<const NFFT: usize> defmt::Format for WelchAccumulator<NFFT> {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(
            f,
            "WelchAccumulator {{ config: {}, segments: {}, skipped: {} }}",
            self.config,
            self.segments,
            self.skipped
        )
    }
}

impl<const NFFT: usize> WelchAccumulator<NFFT> {
    /// An unconfigured estimate (accumulates nothing) to build in place in a `static` (all
    /// zero bytes: `.bss`), then [`configure`](Self::configure).
    pub const fn new() -> Self {
        Self::empty(WelchConfig::NONE, Dft::NONE)
    }

    /// An estimate with checked settings and no segment.
    const fn empty(config: WelchConfig, dft: Dft) -> Self {
        WelchAccumulator {
            config,
            dft,
            auto: [0.0; NFFT],
            cross: [0.0; NFFT],
            pyy_dc: 0.0,
            pyy_nyquist: 0.0,
            segments: 0,
            skipped: 0,
        }
    }

    /// Whether the settings were set (by [`try_new`](Self::try_new) or
    /// [`configure`](Self::configure)).
    pub const fn is_configured(&self) -> bool {
        self.config.nperseg > 0
    }

    /// Checks `config` against the capacity and builds an empty estimate. `nperseg` is only
    /// bounded by `nfft` here (the caller owns the segments).
    ///
    /// Errors: [`ConfigError::SampleRate`], [`ConfigError::SegmentLength`],
    /// [`ConfigError::Overlap`], [`ConfigError::FftLength`], [`ConfigError::Dft`].
    /// `const`: a `static` initialiser builds it in place, checked at compile time.
    pub const fn try_new(config: WelchConfig) -> Result<Self, ConfigError> {
        let dft = const_try!(Self::check(&config));
        Ok(Self::empty(config, dft))
    }

    /// Replaces the settings (checked as in [`try_new`](Self::try_new)) and clears the
    /// estimate. On error the estimate is left unchanged.
    pub fn configure(&mut self, config: WelchConfig) -> Result<(), ConfigError> {
        self.dft = Self::check(&config)?;
        self.config = config;
        self.reset();
        Ok(())
    }

    /// Forgets all accumulated segments; keeps the settings.
    pub fn reset(&mut self) {
        self.auto.iter_mut().for_each(|v| *v = 0.0);
        self.cross.iter_mut().for_each(|v| *v = 0.0);
        self.pyy_dc = 0.0;
        self.pyy_nyquist = 0.0;
        self.segments = 0;
        self.skipped = 0;
    }

    pub(crate) const fn check(c: &WelchConfig) -> Result<Dft, ConfigError> {
        c.check_within(NFFT)
    }

    /// An empty estimate for settings [`check`](Self::check) accepted (`dft` its result).
    pub(crate) const fn from_checked(config: WelchConfig, dft: Dft) -> Self {
        Self::empty(config, dft)
    }

    /// [`configure`](Self::configure) for settings [`check`](Self::check) accepted, in place:
    /// no estimate is built on the stack (its spectra are `8 NFFT` bytes).
    pub(crate) fn configure_checked(&mut self, config: WelchConfig, dft: Dft) {
        self.dft = dft;
        self.config = config;
        self.reset();
    }

    /// The settings in force.
    pub const fn config(&self) -> &WelchConfig {
        &self.config
    }

    /// Scratch values [`add_segment`](Self::add_segment) needs
    /// ([`crate::dft::scratch_len`]`(nfft)`, zero for powers of two).
    pub const fn scratch_len(&self) -> usize {
        self.dft.scratch_len()
    }

    /// Number of output bins, `nfft / 2 + 1`.
    pub const fn bins(&self) -> usize {
        self.config.bins()
    }

    /// Bin spacing `fs / nfft`, in Hz.
    pub const fn df_hz(&self) -> f32 {
        self.config.df_hz()
    }

    /// Frequency of bin `k`, in Hz: `k * df_hz()` (in `f32`; the same formula
    /// [`crate::peaks::pick`] uses). Meaningful for `k < bins()`.
    pub fn freq(&self, k: usize) -> f32 {
        k as f32 * self.df_hz()
    }

    /// Segments accumulated so far.
    pub const fn segments(&self) -> u32 {
        self.segments
    }

    /// Complete segments that were not accumulated because they contained a non-finite sample
    /// or one larger than [`MAX_SAMPLE_ABS`] in magnitude.
    pub const fn skipped_segments(&self) -> u32 {
        self.skipped
    }

    /// Detrends, windows, transforms and accumulates one segment: `x` and `y` hold exactly
    /// `nperseg` samples of the two channels, `work` at least `nfft` values and `scratch` at
    /// least [`scratch_len`](Self::scratch_len) (both are overwritten). Returns `Ok(true)` if
    /// the segment was accumulated, `Ok(false)` if it was skipped (non-finite or too large a
    /// sample, see [`skipped_segments`](Self::skipped_segments)).
    ///
    /// Errors (nothing accumulated): [`WelchError::Buffer`] for a wrong `x`, `y` or `work`
    /// length or too small a `scratch`.
    pub fn add_segment(
        &mut self,
        x: &[f32],
        y: &[f32],
        work: &mut [Complex32],
        scratch: &mut [Complex32],
    ) -> Result<bool, WelchError> {
        let n = self.config.nperseg;
        let nfft = self.config.nfft;
        for got in [x.len(), y.len()] {
            if got != n {
                return Err(BufferError { expected: n, got }.into());
            }
        }
        if work.len() < nfft {
            return Err(BufferError {
                expected: nfft,
                got: work.len(),
            }
            .into());
        }
        if scratch.len() < self.dft.scratch_len() {
            return Err(BufferError {
                expected: self.dft.scratch_len(),
                got: scratch.len(),
            }
            .into());
        }
        Ok(self.accumulate(x, y, work, scratch))
    }

    /// [`add_segment`](Self::add_segment) for the crate's own callers, whose buffers follow
    /// from a validated configuration: infallible (buffers of the wrong length, impossible
    /// there, accumulate nothing and return `false`).
    pub(crate) fn accumulate(
        &mut self,
        x: &[f32],
        y: &[f32],
        work: &mut [Complex32],
        scratch: &mut [Complex32],
    ) -> bool {
        let n = self.config.nperseg;
        let nfft = self.config.nfft;
        if n == 0 || x.len() != n || y.len() != n || scratch.len() < self.dft.scratch_len() {
            return false;
        }
        let Some(work) = work.get_mut(..nfft) else {
            return false;
        };
        let detrend = self.config.detrend == Detrend::Constant;
        let (Some(px), Some(py)) = (prepare(x, detrend), prepare(y, detrend)) else {
            self.skipped = self.skipped.saturating_add(1);
            return false;
        };
        let (sx, sy) = (px.scale, py.scale);
        pack_segment(work, (x, y), (&px, &py), self.config.window);
        self.dft.run(work, scratch, Direction::Forward);
        self.add_spectra(work, sx, sy);
        self.segments = self.segments.saturating_add(1);
        true
    }

    /// Unpacks the transform of [`pack_segment`]'s sequence into both channels' spectra
    /// (`X = (Zk + conj Zn) / 2`, `Y = (Zk - conj Zn) / 2i`, the scalings undone) and adds
    /// `Pxx`, `Pyy` and `Pxy` of every bin to the sums in their mirrored layout.
    #[inline(always)]
    fn add_spectra(&mut self, work: &[Complex32], sx: f32, sy: f32) {
        let nfft = self.config.nfft;
        let Some(work) = work.get(..nfft) else {
            return;
        };
        let bins = nfft / 2 + 1;
        for k in 0..bins {
            let zk = work.get(k).copied().unwrap_or_default();
            let zn = work
                .get((nfft - k).checked_rem(nfft).unwrap_or(0))
                .copied()
                .unwrap_or_default()
                .conj();
            // X = (Zk + conj Zn) / 2, Y = (Zk - conj Zn) / 2i, then undo the exact scalings
            let xk = (zk + zn) * 0.5;
            let d = zk - zn;
            let yk = Complex32::new(d.im * 0.5, -d.re * 0.5);
            let pxx = xk.norm_sqr() * sx * sx;
            let pyy = yk.norm_sqr() * sy * sy;
            let pxy = Complex32::new(
                (xk.re * yk.re + xk.im * yk.im) * sx * sy,
                (xk.re * yk.im - xk.im * yk.re) * sx * sy,
            );
            if let Some(a) = self.auto.get_mut(k) {
                *a += pxx;
            }
            if let Some(c) = self.cross.get_mut(k) {
                *c += pxy.re;
            }
            match mirror(k, nfft) {
                Some(m) => {
                    if let Some(a) = self.auto.get_mut(m) {
                        *a += pyy;
                    }
                    if let Some(c) = self.cross.get_mut(m) {
                        *c += pxy.im;
                    }
                }
                None if k == 0 => self.pyy_dc += pyy,
                None => self.pyy_nyquist += pyy,
            }
        }
    }

    /// Accumulated spectra at bin `k` (`None` if `k >= bins()`). Divide by
    /// [`segments`](Self::segments) for the mean over segments.
    pub fn sums(&self, k: usize) -> Option<Sums> {
        let nfft = self.config.nfft;
        if k >= self.bins() {
            return None;
        }
        let pxx = self.auto.get(k).copied()?;
        let re = self.cross.get(k).copied()?;
        let (pyy, im) = match mirror(k, nfft) {
            Some(m) => (self.auto.get(m).copied()?, self.cross.get(m).copied()?),
            None if k == 0 => (self.pyy_dc, 0.0),
            None => (self.pyy_nyquist, 0.0),
        };
        Some(Sums {
            pxx,
            pyy,
            pxy: Complex32::new(re, im),
        })
    }

    /// H1 at bin `k`: `Pxy / Pxx` (formed in `f64`). `None` before the first accumulated
    /// segment or if `k >= bins()`. A bin where `Pxx == 0` gives 0.
    pub fn h1(&self, k: usize) -> Option<Complex32> {
        if self.segments == 0 {
            return None;
        }
        self.sums(k).map(|s| h1_of(&s))
    }

    /// Magnitude-squared coherence at bin `k`: `|Pxy|^2 / (Pxx Pyy)` (in `f64`, clamped to
    /// `[0, 1]`). `None` before the first accumulated segment or if `k >= bins()`. A bin where
    /// `Pxx == 0` or `Pyy == 0` gives 0.
    pub fn coherence(&self, k: usize) -> Option<f32> {
        if self.segments == 0 {
            return None;
        }
        self.sums(k).map(|s| coherence_of(&s))
    }

    /// Writes H1 of bins `0 .. min(out.len(), bins())` into `out` and returns how many were
    /// written. Error: [`WelchError::NoSegments`] before the first accumulated segment.
    pub fn fill_h1(&self, out: &mut [Complex32]) -> Result<usize, WelchError> {
        self.fill_with(out, h1_of)
    }

    /// Writes the coherence of bins `0 .. min(out.len(), bins())` into `out` and returns how
    /// many were written. Error: [`WelchError::NoSegments`] before the first accumulated
    /// segment.
    pub fn fill_coherence(&self, out: &mut [f32]) -> Result<usize, WelchError> {
        self.fill_with(out, coherence_of)
    }

    fn fill_with<T>(&self, out: &mut [T], f: fn(&Sums) -> T) -> Result<usize, WelchError> {
        if self.segments == 0 {
            return Err(WelchError::NoSegments);
        }
        let mut n = 0;
        for (k, o) in out.iter_mut().enumerate().take(self.bins()) {
            if let Some(s) = self.sums(k) {
                *o = f(&s);
                n += 1;
            }
        }
        Ok(n)
    }
}

impl<const NFFT: usize> Default for WelchAccumulator<NFFT> {
    fn default() -> Self {
        Self::new()
    }
}

/// Packs the two channels of a segment into one complex sequence for one transform:
/// `z = (x - mean) w / sx + i (y - mean) w / sy`, zero-padded to `work.len()` (the `prepare`d
/// means and exact power-of-two scales of each channel; `w` the periodic window).
#[inline(always)]
fn pack_segment(
    work: &mut [Complex32],
    (x, y): (&[f32], &[f32]),
    (px, py): (&Prep, &Prep),
    window: Window,
) {
    let n = x.len();
    let Some(y) = y.get(..n) else {
        return;
    };
    let (sx, sy) = (px.scale, py.scale);
    // z = (x - mean) * w / sx + i (y - mean) * w / sy, zero-padded to nfft
    let (isx, isy) = (1.0 / sx, 1.0 / sy);
    let (mx, lx, my, ly) = (px.hi, px.lo, py.hi, py.lo);
    let z = |j: usize, wj: f32| match (x.get(j), y.get(j)) {
        (Some(&a), Some(&b)) => {
            Complex32::new(((a - mx) - lx) * wj * isx, ((b - my) - ly) * wj * isy)
        }
        _ => Complex32::new(0.0, 0.0),
    };
    for v in work.iter_mut().skip(n) {
        *v = Complex32::new(0.0, 0.0);
    }
    // periodic windows are symmetric, w[j] = w[n - j]: one evaluation serves both samples
    for j in 0..=n / 2 {
        let wj = window.value_f32(j, n);
        if let Some(v) = work.get_mut(j) {
            *v = z(j, wj);
        }
        let k = n - j;
        if k != j && k < n {
            if let Some(v) = work.get_mut(k) {
                *v = z(k, wj);
            }
        }
    }
}

/// Index of the mirrored slot of bin `k` in the half-complex layout, `None` at DC and Nyquist.
fn mirror(k: usize, nfft: usize) -> Option<usize> {
    if k > 0 && 2 * k < nfft {
        Some(nfft - k)
    } else {
        None
    }
}

/// What a segment of one channel needs before the transform.
#[derive(Debug, Clone, Copy)]
struct Prep {
    /// Segment mean as an unevaluated sum `hi + lo` (0 without detrending).
    hi: f32,
    lo: f32,
    /// Power of two that brings the largest detrended magnitude into `[0.5, 1)`.
    scale: f32,
}

/// Mean and scale of one channel's segment; `None` if a sample is non-finite or larger than
/// [`MAX_SAMPLE_ABS`].
///
/// The mean is kept in twice the `f32` precision (`hi + lo`): rounding it to one `f32` would
/// shift every sample by the same error, and the window sums that bias into the lowest bins
/// (`nperseg/2` times it at DC for Hann). The sum is an error-free-transformation ("TwoSum")
/// accumulation, and the residual of the division is recovered exactly with an FMA.
fn prepare(s: &[f32], detrend: bool) -> Option<Prep> {
    let (mut sum, mut comp) = (0.0f32, 0.0f32);
    for &v in s {
        if v.is_nan() || libm::fabsf(v) > MAX_SAMPLE_ABS {
            return None;
        }
        // TwoSum: t + err == sum + v exactly
        let t = sum + v;
        let bp = t - sum;
        comp += (sum - (t - bp)) + (v - bp);
        sum = t;
    }
    let (hi, lo) = if detrend && !s.is_empty() {
        let n = s.len() as f32;
        let hi = sum / n;
        // sum - hi n is exact in one FMA (the remainder of a rounded division is representable)
        let rem = libm::fmaf(-hi, n, sum) + comp;
        (hi, rem / n)
    } else {
        (0.0, 0.0)
    };
    let peak = s
        .iter()
        .fold(0.0f32, |m, &v| m.max(libm::fabsf((v - hi) - lo)));
    let scale = if peak > 0.0 {
        // exponent e with peak = f 2^e, f in [0.5, 1); clamp so 2^e is a normal f32
        let (_, e) = libm::frexpf(peak);
        libm::ldexpf(1.0, e.clamp(-120, 120))
    } else {
        1.0
    };
    Some(Prep { hi, lo, scale })
}

fn h1_of(s: &Sums) -> Complex32 {
    if s.pxx.is_nan() || s.pxx <= 0.0 {
        return Complex32::new(0.0, 0.0);
    }
    let d = s.pxx as f64;
    Complex32::new((s.pxy.re as f64 / d) as f32, (s.pxy.im as f64 / d) as f32)
}

fn coherence_of(s: &Sums) -> f32 {
    if s.pxx.is_nan() || s.pyy.is_nan() || s.pxx <= 0.0 || s.pyy <= 0.0 {
        return 0.0;
    }
    let (re, im) = (s.pxy.re as f64, s.pxy.im as f64);
    let c = (re * re + im * im) / (s.pxx as f64 * s.pyy as f64);
    if c > 1.0 {
        1.0
    } else if c >= 0.0 {
        c as f32
    } else {
        0.0
    }
}
