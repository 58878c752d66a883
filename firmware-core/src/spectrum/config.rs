//! The settings of a Welch estimate: window, detrend, segment and transform lengths, and
//! their checks.

#[cfg(doc)]
use super::{WelchAccumulator, WelchError, WelchH1};
use crate::dft::{self, Dft, DftError};

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
    pub(super) const fn check_within(&self, capacity: usize) -> Result<Dft, ConfigError> {
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

/// Scratch capacity to give [`WelchH1`] for transforms of length `nfft` (0 for powers of two;
/// 0 also for unsupported lengths, which [`WelchH1::try_new`] rejects anyway). Usable in const
/// context: `WelchH1<1111, 5000, { scratch_capacity(5000) }>`.
pub const fn scratch_capacity(nfft: usize) -> usize {
    match dft::scratch_len(nfft) {
        Some(n) => n,
        None => 0,
    }
}
