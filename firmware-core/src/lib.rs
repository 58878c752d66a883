//! # firmware-core
//!
//! The part of the vision-based vibration measurement chain that runs **on the camera**:
//! it is what an MCU camera firmware links, so it is `#![no_std]`, uses no allocator and no
//! `unsafe`, keeps every buffer at a size fixed at compile time (const generics) and never
//! panics on any input. Invalid settings are rejected once, by a `try_new` constructor; after
//! that the per-pixel and per-sample paths have no error cases left.
//!
//! The host-side Monte Carlo studies (`host-harness`) push their simulated frames and signals
//! through this very crate, so every study validates the code that ships.
//!
//! One module per stage of the measurement chain (see `SPEC.md` section 2):
//!
//! | module | stage |
//! |---|---|
//! | [`centroid`] | thresholded centre of gravity of the target(s) in each frame, row-streaming |
//! | [`dft`] | exact DFT of any length on top of power-of-two `microfft` (mixed radix + Bluestein) |
//! | [`upsample`] | Fourier (zero-padding) resampling of camera-rate displacement to the ADC rate |
//! | [`convert`] | displacement to acceleration: spectrum times -omega^2, pixel to SI scaling |
//! | [`spectrum`] | streaming Welch estimator of H1 and coherence |
//! | [`peaks`] | resonance frequency and amplitude by peak picking of Im H1 in bands |
//! | [`pipeline`] | the whole vision channel in one fixed working set: frames + ADC samples in, H1 out |
//! | [`sync`] | camera trigger / ADC conversion schedule from one time base (`embedded-hal` 1.0) |
//!
//! Float maths goes through `libm`, so the same code compiles for the host and for
//! `thumbv7em-none-eabihf`. The optional `defmt` feature derives `defmt::Format` on the public
//! types for firmware logging.
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod centroid;
pub mod convert;
pub mod dft;
pub mod peaks;
pub mod pipeline;
pub mod spectrum;
pub mod sync;
pub mod upsample;

/// Single-precision complex number used throughout the crate (the one `microfft` uses).
pub use num_complex::Complex32;

/// The `heapless` version this crate's types use (`MultiCentroider::targets` returns a
/// `heapless::Vec`): use it through this re-export and one build never holds two versions.
pub use heapless;

/// A caller buffer has the wrong length: the one **run-time** error of the functions that work
/// in caller-provided buffers ([`dft::Dft::process`], [`upsample::UpsamplePlan::process_with`],
/// [`spectrum::WelchAccumulator::add_segment`]). Nothing was written when it is returned.
/// Settings are checked once, by each stage's `try_new`, and have their own `ConfigError`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BufferError {
    /// Length needed (for a scratch buffer: the least length).
    pub expected: usize,
    /// Length passed.
    pub got: usize,
}

impl core::fmt::Display for BufferError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "buffer has {} values, {} expected",
            self.got, self.expected
        )
    }
}

impl core::error::Error for BufferError {}
