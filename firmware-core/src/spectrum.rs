//! Streaming Welch estimator of the H1 frequency response and the coherence (method.md §2.4).
//!
//! Samples of the input channel `x` (force, base acceleration) and the output channel `y`
//! (displacement, tip acceleration) are pushed as they arrive, in chunks of any size. The
//! estimator keeps one segment of each channel and the accumulated spectra
//!
//! ```text
//! Pxx[k] = sum_s |X_s[k]|^2      Pyy[k] = sum_s |Y_s[k]|^2      Pxy[k] = sum_s conj(X_s[k]) Y_s[k]
//! ```
//!
//! over the segments `s`, never the whole record. Per segment of `nperseg` samples the
//! estimator subtracts the segment mean (detrend [`Detrend::Constant`], optional), multiplies by
//! the window (periodic Hann, periodic Hamming or rectangular, as `scipy.signal.get_window`),
//! zero-pads to `nfft` and transforms with the exact arbitrary-length [`crate::dft`].
//! Then
//!
//! ```text
//! H1[k] = Pxy[k] / Pxx[k]        coherence[k] = |Pxy[k]|^2 / (Pxx[k] Pyy[k])
//! ```
//!
//! at the bin frequencies `f_k = k fs / nfft`, `k = 0 ..= nfft / 2`. This is exactly what
//! `scipy.signal.csd` / `scipy.signal.welch` compute with the same window, `nperseg`,
//! `noverlap`, `nfft` and `detrend` and default arguments otherwise (`average='mean'`, no
//! boundary extension, no padding of the last segment): segments start at sample 0 and every
//! `nperseg - noverlap` samples after it, and only complete segments are used (the trailing
//! samples wait in the buffer for more data). scipy's density scaling and one-sided doubling are
//! common factors of all three spectra and cancel in H1 and the coherence; scipy's convention
//! `Pxy = conj(X) Y` is used, so H1 is the transfer function from `x` to `y`.
//!
//! # Numerics
//! Both channels go through **one** complex DFT as `x + i y`; the two spectra are separated by
//! Hermitian symmetry (`X[k] = (Z[k] + conj Z[n-k]) / 2`, `Y[k] = (Z[k] - conj Z[n-k]) / 2i`),
//! which halves the work. Before the transform each channel is scaled by a power of two so
//! that its largest sample lies in `[0.5, 1)`: the scaling is exact, and it keeps a small channel
//! (displacement in metres) from drowning in the rounding errors of a large one (force in
//! newtons) that shares the transform. The spectra are accumulated in `f32`; H1 and the
//! coherence are formed in `f64` on read-out, so they cannot overflow.
//!
//! # Robustness
//! Nothing panics and no accessor returns NaN. A segment that contains a non-finite sample, or
//! one whose magnitude exceeds [`MAX_SAMPLE_ABS`] (which could overflow the `f32` sums), is not
//! accumulated: it is counted by [`WelchH1::skipped_segments`]. Before the first accumulated
//! segment H1 and the coherence are "not available" (`None` / [`WelchError::NoSegments`]).
//! At a bin where `Pxx == 0` (an input with no energy there) H1 is reported as 0 and the
//! coherence as 0; where `Pyy == 0` the coherence is 0.
//!
//! # Memory
//! The capacities are const generics: `SEG >= nperseg` samples per channel, `NFFT >= nfft`
//! (the transform buffer and the accumulators), `SCRATCH >=` [`crate::dft::scratch_len`]`(nfft)`
//! (zero for powers of two). The state holds the two segment buffers (`2 SEG` `f32`; the
//! window is evaluated per sample, not stored), the transform buffer (`NFFT` complex), the
//! accumulators packed in a "half-complex" layout (`2 NFFT` `f32`, see [`WelchAccumulator`])
//! and the DFT scratch (`SCRATCH` complex): about `8 SEG + 16 NFFT + 8 SCRATCH` bytes, e.g.
//! 48 KiB for `WelchH1<2048, 2048, 0>`. Large instances belong in a `static` (MCU) or a `Box`
//! (host). [`WelchAccumulator`] is the estimate without the segment and transform buffers
//! (`8 NFFT` bytes), for firmware that shares one work buffer between several transforms and
//! cuts segments out of its own sample history ([`crate::pipeline`]).
//!
//! ```
//! use firmware_core::spectrum::{Detrend, Window, WelchConfig, WelchH1};
//! let config = WelchConfig {
//!     fs_hz: 100.0,
//!     nperseg: 64,
//!     noverlap: 32,
//!     nfft: 64,
//!     window: Window::Hann,
//!     detrend: Detrend::Constant,
//! };
//! let mut welch = WelchH1::<64, 64, 0>::try_new(config).unwrap();
//! let x: Vec<f32> = (0..640).map(|i| libm::sinf(0.37 * i as f32) + libm::cosf(1.3 * i as f32)).collect();
//! let y: Vec<f32> = x.iter().map(|v| 2.0 * v).collect();
//! welch.push(&x, &y).unwrap();
//! assert_eq!(welch.segments(), 19);
//! let h = welch.h1(10).unwrap();
//! assert!((h.re - 2.0).abs() < 1e-5 && h.im.abs() < 1e-5);
//! ```

use crate::dft::{self, Dft, DftError, Direction};
use crate::BufferError;
use crate::Complex32;
use core::fmt;

/// Largest sample magnitude that is accumulated. A segment with a larger (or non-finite) sample
/// is skipped, so that the `f32` spectra cannot overflow (|X|^2 stays below about
/// `(nperseg 1e9)^2`, far from `f32::MAX` for any practical number of segments).
pub const MAX_SAMPLE_ABS: f32 = 1.0e9;

/// Window applied to each segment. Periodic ("DFT-even") windows, as scipy's default
/// `scipy.signal.get_window(name, nperseg)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Window {
    /// Periodic Hann: `w[n] = 0.5 - 0.5 cos(2 pi n / nperseg)` (scipy `'hann'`).
    #[default]
    Hann,
    /// Periodic Hamming: `w[n] = 0.54 - 0.46 cos(2 pi n / nperseg)` (scipy `'hamming'`).
    Hamming,
    /// Rectangular, all ones (scipy `'boxcar'`).
    Rect,
}

impl Window {
    /// Value of the window of length `len` at sample `n` (`0 <= n < len`; other `n` give the
    /// periodic continuation). Computed in `f64` and rounded once, so it matches scipy to the
    /// last bit of `f32` in practice.
    pub fn value(self, n: usize, len: usize) -> f32 {
        let c = || {
            if len == 0 {
                1.0
            } else {
                libm::cos(2.0 * core::f64::consts::PI * (n % len) as f64 / len as f64)
            }
        };
        match self {
            Window::Hann => (0.5 - 0.5 * c()) as f32,
            Window::Hamming => (0.54 - 0.46 * c()) as f32,
            Window::Rect => 1.0,
        }
    }

    /// The same value in `f32` arithmetic only ([`crate::dft::cos_sin_turns`]): within about
    /// 1e-7 of [`value`](Self::value), and cheap on a single-precision FPU. The estimators use
    /// this one, per sample, instead of storing the window.
    #[inline]
    pub fn value_f32(self, n: usize, len: usize) -> f32 {
        let c = || dft::cos_turns(n, len);
        match self {
            Window::Hann => 0.5 - 0.5 * c(),
            Window::Hamming => 0.54 - 0.46 * c(),
            Window::Rect => 1.0,
        }
    }
}

/// Detrending applied to each segment before windowing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Detrend {
    /// Subtract the segment mean (scipy `detrend='constant'`, its default).
    #[default]
    Constant,
    /// Use the samples as they are (scipy `detrend=False`).
    None,
}

/// Settings of a Welch estimate: plain data with units and ranges on every field, `const`
/// constructors for the usual cases, checked once by [`validate`](Self::validate) and, with
/// the capacities, by [`WelchH1::try_new`] / [`WelchAccumulator::try_new`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WelchConfig {
    /// Sampling rate of both channels, in Hz. Finite and > 0; only used for the bin
    /// frequencies.
    pub fs_hz: f32,
    /// Samples per segment, `1 ..= SEG`.
    pub nperseg: usize,
    /// Samples shared by consecutive segments, `0 ..= nperseg - 1` (segments start every
    /// `nperseg - noverlap` samples).
    pub noverlap: usize,
    /// Transform length (segment zero-padded to it), `nperseg ..= NFFT`, and a length that
    /// [`crate::dft`] supports (any length whose odd part is small; all lengths up to 32768 and
    /// every power of two up to 32768).
    pub nfft: usize,
    /// Segment window.
    pub window: Window,
    /// Segment detrending.
    pub detrend: Detrend,
}

impl WelchConfig {
    /// All zero: the settings of an unconfigured estimator (not valid).
    pub(crate) const NONE: WelchConfig = WelchConfig::hann(0.0, 0);

    /// scipy's defaults for a record of `len` samples: Hann window, `nperseg = min(256, len)`,
    /// `noverlap = nperseg / 2`, `nfft = nperseg`, constant detrend.
    pub const fn scipy_default(fs_hz: f32, len: usize) -> Self {
        WelchConfig::hann(fs_hz, if len < 256 { len } else { 256 })
    }

    /// `nperseg`-sample segments transformed without zero padding (`nfft = nperseg`), 50 %
    /// overlap, periodic Hann, constant detrend: the usual setting.
    pub const fn hann(fs_hz: f32, nperseg: usize) -> Self {
        WelchConfig {
            fs_hz,
            nperseg,
            noverlap: nperseg / 2,
            nfft: nperseg,
            window: Window::Hann,
            detrend: Detrend::Constant,
        }
    }

    /// Checks the settings that do not depend on a capacity: `fs_hz` finite and positive,
    /// `nperseg >= 1`, `noverlap < nperseg`, `nfft >= nperseg` and supported by
    /// [`crate::dft`]. Returns the transform plan. (The `capacity` of an error found here is
    /// `usize::MAX`: no capacity is involved.)
    pub const fn validate(&self) -> Result<Dft, ConfigError> {
        self.check_within(usize::MAX)
    }

    /// [`validate`](Self::validate) with `nfft` bounded by a transform capacity, in the
    /// order the errors are documented.
    const fn check_within(&self, capacity: usize) -> Result<Dft, ConfigError> {
        if !(self.fs_hz.is_finite() && self.fs_hz > 0.0) {
            return Err(ConfigError::SampleRate);
        }
        if self.nperseg == 0 {
            return Err(ConfigError::SegmentLength {
                nperseg: self.nperseg,
                capacity,
            });
        }
        if self.noverlap >= self.nperseg {
            return Err(ConfigError::Overlap {
                noverlap: self.noverlap,
                nperseg: self.nperseg,
            });
        }
        if self.nfft < self.nperseg || self.nfft > capacity {
            return Err(ConfigError::FftLength {
                nfft: self.nfft,
                nperseg: self.nperseg,
                capacity,
            });
        }
        match Dft::try_new(self.nfft) {
            Ok(d) => Ok(d),
            Err(e) => Err(ConfigError::Dft(e)),
        }
    }

    /// Number of output bins, `nfft / 2 + 1` (DC to Nyquist, one-sided).
    pub const fn bins(&self) -> usize {
        self.nfft / 2 + 1
    }

    /// Bin spacing `fs / nfft`, in Hz.
    pub const fn df_hz(&self) -> f32 {
        if self.nfft == 0 {
            0.0
        } else {
            self.fs_hz / self.nfft as f32
        }
    }

    /// Number of complete segments a record of `len` samples yields (what scipy averages).
    pub const fn segments_in(&self, len: usize) -> usize {
        if self.nperseg == 0 || self.noverlap >= self.nperseg || len < self.nperseg {
            0
        } else {
            (len - self.nperseg) / (self.nperseg - self.noverlap) + 1
        }
    }
}

/// Why a [`WelchConfig`] is rejected (by [`WelchConfig::validate`], or against the capacities
/// by [`WelchAccumulator::try_new`] and [`WelchH1::try_new`]). Checked once; run-time errors
/// are [`WelchError`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ConfigError {
    /// `fs_hz` is not finite or not positive.
    SampleRate,
    /// `nperseg` is 0 or larger than the segment capacity `SEG`.
    SegmentLength {
        /// Requested `nperseg`.
        nperseg: usize,
        /// Capacity `SEG` of the estimator.
        capacity: usize,
    },
    /// `noverlap >= nperseg`.
    Overlap {
        /// Requested `noverlap`.
        noverlap: usize,
        /// Requested `nperseg`.
        nperseg: usize,
    },
    /// `nfft < nperseg` or `nfft` larger than the transform capacity `NFFT`.
    FftLength {
        /// Requested `nfft`.
        nfft: usize,
        /// Requested `nperseg` (lower bound).
        nperseg: usize,
        /// Capacity `NFFT` of the estimator (upper bound).
        capacity: usize,
    },
    /// The DFT of length `nfft` cannot be planned.
    Dft(DftError),
    /// The DFT of length `nfft` needs more scratch than the capacity `SCRATCH`.
    Scratch {
        /// Scratch values the transform needs ([`crate::dft::scratch_len`]).
        needed: usize,
        /// Capacity `SCRATCH` of the estimator.
        capacity: usize,
    },
}

error_display!(ConfigError, f, {
    ConfigError::SampleRate => write!(f, "sampling rate must be finite and positive"),
    ConfigError::SegmentLength { nperseg, capacity } => write!(
        f,
        "nperseg = {nperseg} is outside 1..={capacity} (the segment capacity)"
    ),
    ConfigError::Overlap { noverlap, nperseg } => write!(
        f,
        "noverlap = {noverlap} must be smaller than nperseg = {nperseg}"
    ),
    ConfigError::FftLength {
        nfft,
        nperseg,
        capacity,
    } => write!(
        f,
        "nfft = {nfft} is outside {nperseg}..={capacity} (nperseg ..= transform capacity)"
    ),
    ConfigError::Dft(e) => write!(f, "nfft: {e}"),
    ConfigError::Scratch { needed, capacity } => write!(
        f,
        "the transform needs {needed} scratch values, the capacity is {capacity}"
    ),
});

impl From<DftError> for ConfigError {
    fn from(e: DftError) -> Self {
        ConfigError::Dft(e)
    }
}

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

/// Scratch capacity to give [`WelchH1`] for transforms of length `nfft` (0 for powers of two;
/// 0 also for unsupported lengths, which [`WelchH1::try_new`] rejects anyway). Usable in const
/// context: `WelchH1<1111, 5000, { scratch_capacity(5000) }>`.
pub const fn scratch_capacity(nfft: usize) -> usize {
    match dft::scratch_len(nfft) {
        Some(n) => n,
        None => 0,
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
    config: WelchConfig,
    dft: Dft,
    auto: [f32; NFFT],
    cross: [f32; NFFT],
    pyy_dc: f32,
    pyy_nyquist: f32,
    segments: u32,
    skipped: u32,
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

    const fn check(c: &WelchConfig) -> Result<Dft, ConfigError> {
        c.check_within(NFFT)
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
        // z = (x - mean) * w / sx + i (y - mean) * w / sy, zero-padded to nfft
        let (isx, isy) = (1.0 / sx, 1.0 / sy);
        let (mx, lx, my, ly) = (px.hi, px.lo, py.hi, py.lo);
        let window = self.config.window;
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
        self.dft.run(work, scratch, Direction::Forward);
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
        self.segments = self.segments.saturating_add(1);
        true
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

/// Streaming Welch H1 estimator with capacities `SEG` (samples per segment), `NFFT` (transform
/// length) and `SCRATCH` (DFT scratch values, see [`scratch_capacity`]): a
/// [`WelchAccumulator`] plus the two segment buffers, the transform buffer and the scratch.
///
/// Build it with [`try_new`](Self::try_new), feed it with [`push`](Self::push), read it with
/// [`h1`](Self::h1), [`coherence`](Self::coherence), [`freq`](Self::freq) or the slice
/// fillers. [`reset`](Self::reset) starts a new estimate with the same settings and
/// [`configure`](Self::configure) with new ones, so one (boxed or static) instance can serve
/// many records without being moved again.
#[derive(Clone)]
pub struct WelchH1<const SEG: usize, const NFFT: usize, const SCRATCH: usize> {
    acc: WelchAccumulator<NFFT>,
    xseg: [f32; SEG],
    yseg: [f32; SEG],
    /// Samples currently held in `xseg`/`yseg`.
    fill: usize,
    work: [Complex32; NFFT],
    scratch: [Complex32; SCRATCH],
}

/// Shows the settings and counters, not the buffers (tens of thousands of values).
impl<const SEG: usize, const NFFT: usize, const SCRATCH: usize> fmt::Debug
    for WelchH1<SEG, NFFT, SCRATCH>
{
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("WelchH1")
            .field("capacities", &(SEG, NFFT, SCRATCH))
            .field("config", &self.acc.config)
            .field("segments", &self.acc.segments)
            .field("skipped", &self.acc.skipped)
            .field("pending", &self.fill)
            .finish_non_exhaustive()
    }
}

/// Logs the settings and counters, not the buffers.
#[cfg(feature = "defmt")]
impl<const SEG: usize, const NFFT: usize, const SCRATCH: usize> defmt::Format
    for WelchH1<SEG, NFFT, SCRATCH>
{
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(
            f,
            "WelchH1 {{ config: {}, segments: {}, skipped: {}, pending: {} }}",
            self.acc.config,
            self.acc.segments,
            self.acc.skipped,
            self.fill
        )
    }
}

impl<const SEG: usize, const NFFT: usize, const SCRATCH: usize> WelchH1<SEG, NFFT, SCRATCH> {
    /// An unconfigured estimator ([`push`](Self::push) refuses with
    /// [`WelchError::NotConfigured`]) to build in place in a `static` (all zero bytes:
    /// `.bss`, no stack copy), then [`configure`](Self::configure).
    pub const fn new() -> Self {
        WelchH1 {
            acc: WelchAccumulator::new(),
            xseg: [0.0; SEG],
            yseg: [0.0; SEG],
            fill: 0,
            work: [Complex32::new(0.0, 0.0); NFFT],
            scratch: [Complex32::new(0.0, 0.0); SCRATCH],
        }
    }

    /// Checks `config` against the capacities and builds an empty estimator.
    ///
    /// Errors: [`ConfigError::SampleRate`], [`ConfigError::SegmentLength`],
    /// [`ConfigError::Overlap`], [`ConfigError::FftLength`], [`ConfigError::Dft`],
    /// [`ConfigError::Scratch`]. `const`: a `static` initialiser builds it in place, checked
    /// at compile time.
    pub const fn try_new(config: WelchConfig) -> Result<Self, ConfigError> {
        if let Err(e) = Self::check(&config) {
            return Err(e);
        }
        let acc = const_try!(WelchAccumulator::try_new(config));
        Ok(WelchH1 {
            acc,
            xseg: [0.0; SEG],
            yseg: [0.0; SEG],
            fill: 0,
            work: [Complex32::new(0.0, 0.0); NFFT],
            scratch: [Complex32::new(0.0, 0.0); SCRATCH],
        })
    }

    /// Replaces the settings (checked as in [`try_new`](Self::try_new)) and clears the
    /// estimate. On error the estimator is left unchanged.
    pub fn configure(&mut self, config: WelchConfig) -> Result<(), ConfigError> {
        Self::check(&config)?;
        self.acc.configure(config)?;
        self.fill = 0;
        Ok(())
    }

    /// Forgets all pushed samples and accumulated segments; keeps the settings.
    pub fn reset(&mut self) {
        self.fill = 0;
        self.acc.reset();
    }

    /// [`WelchAccumulator::try_new`]'s checks plus the segment and scratch capacities, in the
    /// order the errors are documented.
    const fn check(c: &WelchConfig) -> Result<(), ConfigError> {
        if !(c.fs_hz.is_finite() && c.fs_hz > 0.0) {
            return Err(ConfigError::SampleRate);
        }
        if c.nperseg == 0 || c.nperseg > SEG {
            return Err(ConfigError::SegmentLength {
                nperseg: c.nperseg,
                capacity: SEG,
            });
        }
        let dft = const_try!(WelchAccumulator::<NFFT>::check(c));
        if dft.scratch_len() > SCRATCH {
            return Err(ConfigError::Scratch {
                needed: dft.scratch_len(),
                capacity: SCRATCH,
            });
        }
        Ok(())
    }

    /// The accumulated estimate (settings, spectra, counters).
    pub const fn accumulator(&self) -> &WelchAccumulator<NFFT> {
        &self.acc
    }

    /// The settings in force.
    pub const fn config(&self) -> &WelchConfig {
        self.acc.config()
    }

    /// Number of output bins, `nfft / 2 + 1`.
    pub const fn bins(&self) -> usize {
        self.acc.bins()
    }

    /// Bin spacing `fs / nfft`, in Hz.
    pub const fn df_hz(&self) -> f32 {
        self.acc.df_hz()
    }

    /// Frequency of bin `k`, in Hz (see [`WelchAccumulator::freq`]).
    pub fn freq(&self, k: usize) -> f32 {
        self.acc.freq(k)
    }

    /// Segments accumulated so far.
    pub const fn segments(&self) -> u32 {
        self.acc.segments()
    }

    /// Complete segments that were not accumulated because they contained a non-finite sample
    /// or one larger than [`MAX_SAMPLE_ABS`] in magnitude.
    pub const fn skipped_segments(&self) -> u32 {
        self.acc.skipped_segments()
    }

    /// Samples waiting in the segment buffer (always `< nperseg`).
    pub const fn pending(&self) -> usize {
        self.fill
    }

    /// Pushes a chunk of samples of both channels (`x[i]` and `y[i]` taken at the same time).
    /// Every time `nperseg` samples are buffered a segment is transformed and accumulated, and
    /// the last `noverlap` samples are kept for the next one. The result does not depend on how
    /// the record is cut into chunks: pushing it sample by sample, in random chunks or at once
    /// gives bit-identical spectra.
    ///
    /// Errors (nothing is consumed): [`WelchError::ChunkLengths`] if `x.len() != y.len()`,
    /// [`WelchError::NotConfigured`] before the settings are set.
    pub fn push(&mut self, x: &[f32], y: &[f32]) -> Result<(), WelchError> {
        if !self.acc.is_configured() {
            return Err(WelchError::NotConfigured);
        }
        if x.len() != y.len() {
            return Err(WelchError::ChunkLengths {
                x: x.len(),
                y: y.len(),
            });
        }
        let nperseg = self.acc.config.nperseg;
        let (mut x, mut y) = (x, y);
        while !x.is_empty() {
            let room = nperseg.saturating_sub(self.fill);
            let take = room.min(x.len());
            let (xh, xt) = x.split_at(take);
            let (yh, yt) = y.split_at(take.min(y.len()));
            if let (Some(xd), Some(yd)) = (
                self.xseg.get_mut(self.fill..self.fill + take),
                self.yseg.get_mut(self.fill..self.fill + take),
            ) {
                // element loops: no length-mismatch panic path (the lengths are equal)
                for (d, v) in xd.iter_mut().zip(xh) {
                    *d = *v;
                }
                for (d, v) in yd.iter_mut().zip(yh) {
                    *d = *v;
                }
            }
            self.fill += take;
            (x, y) = (xt, yt);
            if self.fill >= nperseg {
                if let (Some(xs), Some(ys)) =
                    (self.xseg.get_mut(..nperseg), self.yseg.get_mut(..nperseg))
                {
                    // the capacities were checked by try_new: no error case is left (a skipped,
                    // non-finite segment is counted by the accumulator)
                    self.acc
                        .accumulate(xs, ys, &mut self.work, &mut self.scratch);
                    let step = nperseg - self.acc.config.noverlap;
                    if step <= xs.len() && step <= ys.len() {
                        xs.copy_within(step.., 0);
                        ys.copy_within(step.., 0);
                    }
                }
                self.fill = self.acc.config.noverlap;
            }
            if take == 0 && self.fill < nperseg {
                // unreachable with a valid configuration; guarantees termination regardless
                break;
            }
        }
        Ok(())
    }

    /// Accumulated spectra at bin `k` (see [`WelchAccumulator::sums`]).
    pub fn sums(&self, k: usize) -> Option<Sums> {
        self.acc.sums(k)
    }

    /// H1 at bin `k` (see [`WelchAccumulator::h1`]).
    pub fn h1(&self, k: usize) -> Option<Complex32> {
        self.acc.h1(k)
    }

    /// Coherence at bin `k` (see [`WelchAccumulator::coherence`]).
    pub fn coherence(&self, k: usize) -> Option<f32> {
        self.acc.coherence(k)
    }

    /// Writes H1 of bins `0 .. min(out.len(), bins())` into `out` and returns how many were
    /// written. Error: [`WelchError::NoSegments`] before the first accumulated segment.
    pub fn fill_h1(&self, out: &mut [Complex32]) -> Result<usize, WelchError> {
        self.acc.fill_h1(out)
    }

    /// Writes the coherence of bins `0 .. min(out.len(), bins())` into `out` and returns how
    /// many were written. Error: [`WelchError::NoSegments`] before the first accumulated
    /// segment.
    pub fn fill_coherence(&self, out: &mut [f32]) -> Result<usize, WelchError> {
        self.acc.fill_coherence(out)
    }
}

impl<const NFFT: usize> Default for WelchAccumulator<NFFT> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const SEG: usize, const NFFT: usize, const SCRATCH: usize> Default
    for WelchH1<SEG, NFFT, SCRATCH>
{
    fn default() -> Self {
        Self::new()
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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::vec::Vec;

    /// Capacities for every test length (an odd length n <= 128 needs at most 3n scratch).
    type W = WelchH1<64, 128, 384>;

    fn cfg(nperseg: usize, noverlap: usize, nfft: usize, window: Window) -> WelchConfig {
        WelchConfig {
            fs_hz: 100.0,
            nperseg,
            noverlap,
            nfft,
            window,
            detrend: Detrend::Constant,
        }
    }

    /// Deterministic pseudo-random samples in [-0.5, 0.5) (LCG).
    fn noise(n: usize, seed: u64) -> Vec<f32> {
        let mut s = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (0..n)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((s >> 40) as f32 / (1u64 << 24) as f32) - 0.5
            })
            .collect()
    }

    /// y = x through a resonant two-pole filter plus a little independent noise.
    fn system(n: usize, seed: u64) -> (Vec<f32>, Vec<f32>) {
        let x = noise(n, seed);
        let e = noise(n, seed + 1);
        let (mut y1, mut y2) = (0.0f32, 0.0f32);
        let y = x
            .iter()
            .zip(&e)
            .map(|(&xi, &ei)| {
                let v = xi + 1.6 * y1 - 0.8 * y2;
                y2 = y1;
                y1 = v;
                v + 0.2 * ei
            })
            .collect();
        (x, y)
    }

    fn all_bits<const S: usize, const N: usize, const C: usize>(w: &WelchH1<S, N, C>) -> Vec<u32> {
        (0..w.bins())
            .flat_map(|k| {
                let s = w.sums(k).unwrap();
                [
                    s.pxx.to_bits(),
                    s.pyy.to_bits(),
                    s.pxy.re.to_bits(),
                    s.pxy.im.to_bits(),
                ]
            })
            .collect()
    }

    /// Naive f64 reference: direct DFT per segment, separate for x and y.
    fn reference(x: &[f32], y: &[f32], c: &WelchConfig) -> Vec<(f64, f64, (f64, f64))> {
        let bins = c.nfft / 2 + 1;
        let mut acc = vec![(0.0, 0.0, (0.0, 0.0)); bins];
        let step = c.nperseg - c.noverlap;
        let mut start = 0;
        while start + c.nperseg <= x.len() {
            let seg = |s: &[f32]| -> Vec<f64> {
                let s = &s[start..start + c.nperseg];
                let m = if c.detrend == Detrend::Constant {
                    s.iter().map(|&v| v as f64).sum::<f64>() / s.len() as f64
                } else {
                    0.0
                };
                s.iter()
                    .enumerate()
                    .map(|(j, &v)| {
                        let ph = 2.0 * std::f64::consts::PI * j as f64 / c.nperseg as f64;
                        let w = match c.window {
                            Window::Hann => 0.5 - 0.5 * ph.cos(),
                            Window::Hamming => 0.54 - 0.46 * ph.cos(),
                            Window::Rect => 1.0,
                        };
                        (v as f64 - m) * w
                    })
                    .collect()
            };
            let (xs, ys) = (seg(x), seg(y));
            for (k, a) in acc.iter_mut().enumerate() {
                let dft = |s: &[f64]| {
                    s.iter().enumerate().fold((0.0, 0.0), |(re, im), (j, &v)| {
                        let ph =
                            -2.0 * std::f64::consts::PI * ((j * k) % c.nfft) as f64 / c.nfft as f64;
                        (re + v * ph.cos(), im + v * ph.sin())
                    })
                };
                let (xr, xi) = dft(&xs);
                let (yr, yi) = dft(&ys);
                a.0 += xr * xr + xi * xi;
                a.1 += yr * yr + yi * yi;
                a.2 .0 += xr * yr + xi * yi;
                a.2 .1 += xr * yi - xi * yr;
            }
            start += step;
        }
        acc
    }

    #[test]
    fn matches_naive_f64_reference() {
        let (x, y) = system(700, 3);
        for (c, shift) in [
            (cfg(64, 32, 64, Window::Hann), 0.0),
            (cfg(50, 10, 96, Window::Hamming), 3.0),
            (cfg(37, 0, 37, Window::Rect), 0.0),
            (
                WelchConfig {
                    detrend: Detrend::None,
                    ..cfg(60, 45, 75, Window::Hann)
                },
                0.25,
            ),
        ] {
            let xo: Vec<f32> = x.iter().map(|v| v + shift).collect();
            let mut w = W::try_new(c).unwrap();
            w.push(&xo, &y).unwrap();
            let want = reference(&xo, &y, &c);
            assert_eq!(w.segments() as usize, c.segments_in(x.len()));
            let maxx = want.iter().map(|a| a.0).fold(0.0, f64::max);
            let maxy = want.iter().map(|a| a.1).fold(0.0, f64::max);
            for (k, r) in want.iter().enumerate() {
                let s = w.sums(k).unwrap();
                // errors relative to the largest bin (DFT rounding is relative to the energy)
                assert!((s.pxx as f64 - r.0).abs() < 1e-5 * maxx, "{c:?} bin {k}");
                assert!((s.pyy as f64 - r.1).abs() < 1e-5 * maxy, "{c:?} bin {k}");
                let m = (maxx * maxy).sqrt();
                assert!((s.pxy.re as f64 - r.2 .0).abs() < 1e-5 * m, "{c:?} bin {k}");
                assert!((s.pxy.im as f64 - r.2 .1).abs() < 1e-5 * m, "{c:?} bin {k}");
                let h = w.h1(k).unwrap();
                let hr = (r.2 .0 / r.0, r.2 .1 / r.0);
                let habs = (hr.0 * hr.0 + hr.1 * hr.1).sqrt();
                let coh = (r.2 .0 * r.2 .0 + r.2 .1 * r.2 .1) / (r.0 * r.1);
                if coh > 0.1 {
                    let e = ((h.re as f64 - hr.0).powi(2) + (h.im as f64 - hr.1).powi(2)).sqrt();
                    assert!(e < 1e-4 * habs, "{c:?} bin {k}: {h} vs {hr:?}");
                    assert!((w.coherence(k).unwrap() as f64 - coh).abs() < 1e-4);
                }
            }
        }
    }

    #[test]
    fn identity_and_gain() {
        let (x, _) = system(1000, 9);
        for window in [Window::Hann, Window::Hamming, Window::Rect] {
            for gain in [1.0f32, 2.0, -0.5] {
                let y: Vec<f32> = x.iter().map(|v| gain * v).collect();
                let mut w = W::try_new(cfg(64, 16, 96, window)).unwrap();
                w.push(&x, &y).unwrap();
                for k in 0..w.bins() {
                    let h = w.h1(k).unwrap();
                    assert!(
                        (h.re - gain).abs() <= 4.0 * f32::EPSILON * gain.abs()
                            && h.im.abs() <= 4.0 * f32::EPSILON,
                        "{window:?} gain {gain} bin {k}: {h}"
                    );
                    let c = w.coherence(k).unwrap();
                    assert!((c - 1.0).abs() <= 4.0 * f32::EPSILON, "bin {k}: {c}");
                }
            }
        }
    }

    #[test]
    fn very_different_channel_scales() {
        // force in newtons, displacement in metres: the shared transform must not drown y
        let (x, y) = system(700, 5);
        let xs: Vec<f32> = x.iter().map(|v| v * 1000.0).collect();
        let ys: Vec<f32> = y.iter().map(|v| v * 1e-6).collect();
        let c = cfg(64, 32, 64, Window::Hann);
        let mut a = W::try_new(c).unwrap();
        let mut b = W::try_new(c).unwrap();
        a.push(&x, &y).unwrap();
        b.push(&xs, &ys).unwrap();
        for k in 0..a.bins() {
            let (ha, hb) = (a.h1(k).unwrap(), b.h1(k).unwrap() * 1e9);
            assert!(
                (ha - hb).norm_sqr() <= 1e-10 * ha.norm_sqr(),
                "bin {k}: {ha} {hb}"
            );
        }
    }

    #[test]
    fn not_available_before_first_segment_and_zero_input() {
        let c = cfg(64, 32, 64, Window::Hann);
        let mut w = W::try_new(c).unwrap();
        assert_eq!(w.h1(0), None);
        assert_eq!(w.coherence(3), None);
        let mut out = [Complex32::new(9.0, 9.0); 40];
        assert_eq!(w.fill_h1(&mut out), Err(WelchError::NoSegments));
        w.push(&[1.0; 63], &[1.0; 63]).unwrap();
        assert_eq!((w.segments(), w.pending()), (0, 63));
        assert_eq!(w.h1(1), None);
        // a constant removed by the detrend leaves Pxx == 0 everywhere: H1 = 0, coherence 0
        w.push(&[1.0], &[1.0]).unwrap();
        assert_eq!((w.segments(), w.pending()), (1, 32));
        for k in 0..w.bins() {
            assert_eq!(w.h1(k), Some(Complex32::new(0.0, 0.0)));
            assert_eq!(w.coherence(k), Some(0.0));
        }
        assert_eq!(w.h1(w.bins()), None);
        assert_eq!(w.fill_h1(&mut out), Ok(33));
        assert!(out[..33].iter().all(|v| *v == Complex32::new(0.0, 0.0)));
        assert_eq!(out[33], Complex32::new(9.0, 9.0));
        let mut coh = [5.0f32; 10];
        assert_eq!(w.fill_coherence(&mut coh), Ok(10));
        assert!(coh.iter().all(|v| *v == 0.0));
        let dbg = std::format!("{w:?}");
        assert!(dbg.starts_with("WelchH1 {") && dbg.contains("segments: 1") && dbg.len() < 400);
        w.reset();
        assert_eq!((w.segments(), w.pending(), w.h1(0)), (0, 0, None));
    }

    #[test]
    fn non_finite_and_huge_segments_are_skipped() {
        let (x, y) = system(64 * 4, 2);
        let c = cfg(64, 0, 64, Window::Hann);
        let mut clean = W::try_new(c).unwrap();
        clean.push(&x[..64], &y[..64]).unwrap();
        clean.push(&x[192..], &y[192..]).unwrap();
        let mut w = W::try_new(c).unwrap();
        let mut xb = x.clone();
        let mut yb = y.clone();
        xb[70] = f32::NAN;
        yb[150] = 2.0e9;
        w.push(&xb, &yb).unwrap();
        assert_eq!((w.segments(), w.skipped_segments()), (2, 2));
        assert_eq!(all_bits(&w), all_bits(&clean));
        for k in 0..w.bins() {
            assert!(w.h1(k).unwrap().re.is_finite() && w.coherence(k).unwrap().is_finite());
        }
    }

    #[test]
    fn rejects_invalid_configs() {
        let ok = cfg(64, 32, 96, Window::Hann);
        assert!(W::try_new(ok).is_ok());
        for fs in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            let e = W::try_new(WelchConfig { fs_hz: fs, ..ok }).unwrap_err();
            assert_eq!(e, ConfigError::SampleRate);
        }
        // the capacities of `W`: 64-sample segments, 128-point transforms
        let segment = |nperseg| ConfigError::SegmentLength {
            nperseg,
            capacity: 64,
        };
        let overlap = ConfigError::Overlap {
            noverlap: 64,
            nperseg: 64,
        };
        let fft = ConfigError::FftLength {
            nfft: 63,
            nperseg: 64,
            capacity: 128,
        };
        for (bad, want) in [
            (WelchConfig { nperseg: 0, ..ok }, segment(0)),
            (WelchConfig { nperseg: 65, ..ok }, segment(65)),
            (WelchConfig { noverlap: 64, ..ok }, overlap),
            (WelchConfig { nfft: 63, ..ok }, fft),
        ] {
            assert_eq!(W::try_new(bad).unwrap_err(), want, "{bad:?}");
        }
        let e = W::try_new(WelchConfig { nfft: 129, ..ok }).unwrap_err();
        assert!(matches!(e, ConfigError::FftLength { nfft: 129, .. }));
        // 120 = 8 * 15 needs more scratch than scratch_capacity(96) = 96 + 2 * 3 = 102
        let e =
            WelchH1::<64, 128, { scratch_capacity(96) }>::try_new(WelchConfig { nfft: 120, ..ok })
                .unwrap_err();
        assert_eq!(
            e,
            ConfigError::Scratch {
                needed: 150,
                capacity: 102
            }
        );
        assert!(WelchH1::<64, 128, { scratch_capacity(96) }>::try_new(ok).is_ok());
        // a large prime is not supported by the DFT
        let e = WelchH1::<4, 40000, 0>::try_new(WelchConfig {
            nperseg: 4,
            noverlap: 0,
            nfft: 32771,
            ..ok
        })
        .unwrap_err();
        assert_eq!(e, ConfigError::Dft(DftError::Unsupported { len: 32771 }));
        // configure rejects without touching the state
        let mut w = W::try_new(ok).unwrap();
        w.push(&[0.5; 70], &[0.25; 70]).unwrap();
        assert!(w.configure(WelchConfig { noverlap: 99, ..ok }).is_err());
        assert_eq!((w.config(), w.segments()), (&ok, 1));
        let new = cfg(32, 0, 32, Window::Rect);
        w.configure(new).unwrap();
        assert_eq!((w.config(), w.segments(), w.bins()), (&new, 0, 17));
        // unequal chunks consume nothing
        assert_eq!(
            w.push(&[1.0; 3], &[1.0; 2]),
            Err(WelchError::ChunkLengths { x: 3, y: 2 })
        );
        assert_eq!(w.pending(), 0);
        // every error has a message
        assert!(std::format!("{e}").contains("32771"));
    }

    #[test]
    fn windows_are_periodic_like_scipy() {
        // scipy.signal.get_window('hann', 4) = [0, 0.5, 1, 0.5]; ('hamming', 4) = [0.08, 0.54, 1, 0.54]
        let h: Vec<f32> = (0..4).map(|n| Window::Hann.value(n, 4)).collect();
        assert_eq!(h, [0.0, 0.5, 1.0, 0.5]);
        let h: Vec<f32> = (0..4).map(|n| Window::Hamming.value(n, 4)).collect();
        let want = [0.08f32, 0.54, 1.0, 0.54];
        for (a, b) in h.iter().zip(want) {
            assert!((a - b).abs() < 1e-7);
        }
        assert_eq!(Window::Rect.value(3, 4), 1.0);
    }

    #[test]
    fn bins_and_frequencies() {
        let c = WelchConfig {
            fs_hz: 50.0,
            ..cfg(1111, 555, 5000, Window::Hamming)
        };
        assert_eq!(c.bins(), 2501);
        // 100 s at 50 Hz: scipy averages 7 complete segments (the 8th would end at sample 5003)
        assert_eq!(c.segments_in(5000), 7);
        assert_eq!(c.segments_in(1110), 0);
        let w = WelchH1::<1111, 5000, { scratch_capacity(5000) }>::try_new(c).unwrap();
        assert!((w.freq(200) - 2.0).abs() < 1e-6);
        assert!((w.freq(2500) - 25.0).abs() < 1e-5);
        let odd = cfg(5, 2, 7, Window::Hann);
        assert_eq!(odd.bins(), 4);
        let d = WelchConfig::scipy_default(10.0, 100);
        assert_eq!((d.nperseg, d.noverlap, d.nfft), (100, 50, 100));
        let d = WelchConfig::scipy_default(10.0, 1000);
        assert_eq!((d.nperseg, d.noverlap, d.nfft), (256, 128, 256));
    }

    #[test]
    fn odd_nfft_and_tiny_lengths() {
        // odd nfft (no Nyquist bin) and nfft 1 and 2 against the naive reference
        let (x, y) = system(60, 4);
        for c in [
            cfg(5, 2, 7, Window::Hann),
            cfg(1, 0, 1, Window::Rect),
            cfg(2, 1, 2, Window::Rect),
            WelchConfig {
                detrend: Detrend::None,
                ..cfg(1, 0, 2, Window::Rect)
            },
        ] {
            let mut w = W::try_new(c).unwrap();
            w.push(&x, &y).unwrap();
            let want = reference(&x, &y, &c);
            assert_eq!(want.len(), w.bins());
            for (k, r) in want.iter().enumerate() {
                let s = w.sums(k).unwrap();
                let tol = 1e-5 * (1.0 + r.0 + r.1);
                assert!((s.pxx as f64 - r.0).abs() < tol, "{c:?} {k}");
                assert!((s.pyy as f64 - r.1).abs() < tol, "{c:?} {k}");
                assert!((s.pxy.re as f64 - r.2 .0).abs() < tol, "{c:?} {k}");
                assert!((s.pxy.im as f64 - r.2 .1).abs() < tol, "{c:?} {k}");
            }
        }
    }

    #[test]
    fn accumulator_with_caller_buffers_matches_the_streaming_estimator_bit_for_bit() {
        let c = cfg(100, 40, 128, Window::Hann);
        let (x, y) = system(700, 3);
        let mut w = WelchH1::<100, 128, 0>::try_new(c).unwrap();
        w.push(&x, &y).unwrap();
        let mut acc = WelchAccumulator::<128>::try_new(c).unwrap();
        let mut work = vec![Complex32::new(0.0, 0.0); 200];
        let mut start = 0;
        while start + 100 <= x.len() {
            let seg = start..start + 100;
            let ok = acc.add_segment(&x[seg.clone()], &y[seg], &mut work, &mut []);
            assert_eq!(ok, Ok(true));
            start += 60;
        }
        assert_eq!(acc.segments(), w.segments());
        assert_eq!(all_bits(&w), {
            let mut v = Vec::new();
            for k in 0..acc.bins() {
                let s = acc.sums(k).unwrap();
                v.extend([
                    s.pxx.to_bits(),
                    s.pyy.to_bits(),
                    s.pxy.re.to_bits(),
                    s.pxy.im.to_bits(),
                ]);
            }
            v
        });
        // wrong buffers are errors and accumulate nothing
        let before = acc.segments();
        assert_eq!(
            acc.add_segment(&x[..99], &y[..100], &mut work, &mut []),
            Err(WelchError::Buffer(BufferError {
                expected: 100,
                got: 99
            }))
        );
        assert_eq!(
            acc.add_segment(&x[..100], &y[..100], &mut work[..127], &mut []),
            Err(WelchError::Buffer(BufferError {
                expected: 128,
                got: 127
            }))
        );
        let mut odd = WelchAccumulator::<120>::try_new(cfg(100, 40, 120, Window::Hann)).unwrap();
        assert!(odd.scratch_len() > 0);
        assert!(matches!(
            odd.add_segment(&x[..100], &y[..100], &mut work, &mut []),
            Err(WelchError::Buffer(BufferError { .. }))
        ));
        let mut scratch = vec![Complex32::new(0.0, 0.0); odd.scratch_len()];
        assert_eq!(
            odd.add_segment(&x[..100], &y[..100], &mut work, &mut scratch),
            Ok(true)
        );
        // a non-finite sample skips the segment
        let mut bad = x[..100].to_vec();
        bad[7] = f32::NAN;
        assert_eq!(
            acc.add_segment(&bad, &y[..100], &mut work, &mut []),
            Ok(false)
        );
        assert_eq!((acc.segments(), acc.skipped_segments()), (before, 1));
    }

    #[test]
    fn f32_window_values_agree_with_the_f64_ones() {
        for len in [1usize, 2, 7, 100, 1111, 2048, 4096] {
            for n in 0..len {
                for w in [Window::Hann, Window::Hamming, Window::Rect] {
                    let (a, b) = (w.value(n, len), w.value_f32(n, len));
                    assert!((a - b).abs() < 2e-7, "{w:?} {n}/{len}: {a} vs {b}");
                }
            }
        }
    }

    #[test]
    fn state_size_is_the_documented_budget() {
        // 2 SEG f32 (two segments; the window is computed, not stored) + NFFT complex (work)
        // + 2 NFFT f32 (accumulators) + SCRATCH complex + a few words of settings and
        // counters. This is the RAM an MCU needs for the estimator (README "Signal path
        // figures").
        fn check<const S: usize, const N: usize, const C: usize>() -> usize {
            let size = core::mem::size_of::<WelchH1<S, N, C>>();
            let buffers = 8 * S + 16 * N + 8 * C;
            assert!(
                size >= buffers && size <= buffers + 128,
                "WelchH1<{S}, {N}, {C}>: {size} bytes, buffers {buffers}"
            );
            std::println!("size_of WelchH1<{S}, {N}, {C}> = {size} bytes");
            size
        }
        assert!(check::<2048, 2048, 0>() < 49 * 1024);
        assert!(check::<4096, 4096, 0>() < 97 * 1024);
        // the accumulator alone: 2 NFFT f32
        let acc = core::mem::size_of::<WelchAccumulator<2048>>();
        assert!((8 * 2048..8 * 2048 + 128).contains(&acc), "{acc}");
        check::<1111, 5000, { scratch_capacity(5000) }>();
        check::<20480, 20480, { scratch_capacity(20480) }>();
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        #[test]
        fn chunking_does_not_change_a_bit(
            seed in 0u64..1000,
            len in 0usize..400,
            nperseg in 1usize..=64,
            ov in 0.0f64..1.0,
            pad in 0usize..=32,
            cuts in proptest::collection::vec(0usize..80, 0..20),
        ) {
            let noverlap = ((nperseg as f64 * ov) as usize).min(nperseg - 1);
            let c = cfg(nperseg, noverlap, nperseg + pad, Window::Hamming);
            prop_assume!(W::try_new(c).is_ok());
            let (x, y) = system(len, seed);
            let mut once = W::try_new(c).unwrap();
            once.push(&x, &y).unwrap();
            let mut single = W::try_new(c).unwrap();
            for i in 0..len {
                single.push(&x[i..i + 1], &y[i..i + 1]).unwrap();
            }
            let mut chunked = W::try_new(c).unwrap();
            let mut at = 0usize;
            for cut in cuts.iter().chain(std::iter::once(&usize::MAX)) {
                let end = at.saturating_add(*cut).min(len);
                chunked.push(&x[at..end], &y[at..end]).unwrap();
                at = end;
            }
            prop_assert_eq!(once.segments() as usize, c.segments_in(len));
            prop_assert_eq!(single.segments(), once.segments());
            prop_assert_eq!(chunked.segments(), once.segments());
            prop_assert_eq!(all_bits(&single), all_bits(&once));
            prop_assert_eq!(all_bits(&chunked), all_bits(&once));
        }
    }
}
