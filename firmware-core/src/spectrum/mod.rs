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
//! accumulated: it is counted by [`WelchAccumulator::skipped_segments`]. Before the first accumulated
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
//! assert_eq!(welch.accumulator().segments(), 19);
//! let h = welch.accumulator().h1(10).unwrap();
//! assert!((h.re - 2.0).abs() < 1e-5 && h.im.abs() < 1e-5);
//! ```

mod accumulator;
mod config;
pub mod cross;
mod streaming;
#[cfg(test)]
mod tests;

pub use accumulator::{Sums, WelchAccumulator, WelchError};
pub use config::{scratch_capacity, ConfigError, Detrend, WelchConfig, Window};
pub use streaming::WelchH1;

/// Largest sample magnitude that is accumulated. A segment with a larger (or non-finite) sample
/// is skipped, so that the `f32` spectra cannot overflow (|X|^2 stays below about
/// `(nperseg 1e9)^2`, far from `f32::MAX` for any practical number of segments).
pub const MAX_SAMPLE_ABS: f32 = 1.0e9;
