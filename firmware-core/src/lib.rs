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
//! | [`exposure`] | exposure (box) transfer, E2PR, and its compensation (sinc or a binary-centroid table) |
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
pub mod exposure;
pub mod peaks;
pub mod pipeline;
pub mod spectrum;
pub mod sync;
pub mod upsample;

/// Single-precision complex number used throughout the crate (the one `microfft` uses).
pub use num_complex::Complex32;
