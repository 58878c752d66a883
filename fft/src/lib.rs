//! # vibcam-fft
//!
//! The FFTs of the host side, planned here and nowhere else. rustfft's and realfft's planners
//! are generic: each crate that calls `FftPlanner::<f64>::new()` compiles every algorithm of
//! the planner for itself (85 % of `vibcam-model`'s code was rustfft's), once for its library
//! and once for its unit tests, in every profile. The planners below are not generic: their
//! algorithms are compiled once, in this crate, and the crates above call the plans through
//! `dyn Fft` (docs/performance.md, "Building").
//!
//! The plans are rustfft's and realfft's own, for the same sizes, so every transform is the
//! one the planners gave before, to the bit.

use std::sync::Arc;

pub use realfft::num_complex::Complex;
pub use realfft::{ComplexToReal, RealToComplex};
pub use rustfft::Fft;

/// Complex f64 transforms (rustfft's planner).
pub struct Planner(rustfft::FftPlanner<f64>);

/// Real f64 transforms (realfft's planner).
pub struct RealPlanner(realfft::RealFftPlanner<f64>);

/// Real f32 transforms (realfft's planner), for the renderer.
pub struct RealPlanner32(realfft::RealFftPlanner<f32>);

impl Planner {
    /// A planner; it keeps the plans it made, so plan each size from the same one.
    #[inline(never)]
    pub fn new() -> Self {
        Self(rustfft::FftPlanner::new())
    }

    /// The forward transform of length `n`.
    #[inline(never)]
    pub fn forward(&mut self, n: usize) -> Arc<dyn Fft<f64>> {
        self.0.plan_fft_forward(n)
    }

    /// The inverse transform of length `n` (not normalised).
    #[inline(never)]
    pub fn inverse(&mut self, n: usize) -> Arc<dyn Fft<f64>> {
        self.0.plan_fft_inverse(n)
    }
}

impl RealPlanner {
    /// A planner; it keeps the plans it made.
    #[inline(never)]
    pub fn new() -> Self {
        Self(realfft::RealFftPlanner::new())
    }

    /// Real input of length `n` to its `n / 2 + 1` complex coefficients.
    #[inline(never)]
    pub fn forward(&mut self, n: usize) -> Arc<dyn RealToComplex<f64>> {
        self.0.plan_fft_forward(n)
    }

    /// `n / 2 + 1` complex coefficients back to `n` real values (not normalised).
    #[inline(never)]
    pub fn inverse(&mut self, n: usize) -> Arc<dyn ComplexToReal<f64>> {
        self.0.plan_fft_inverse(n)
    }
}

impl RealPlanner32 {
    /// A planner; it keeps the plans it made.
    #[inline(never)]
    pub fn new() -> Self {
        Self(realfft::RealFftPlanner::new())
    }

    /// Real input of length `n` to its `n / 2 + 1` complex coefficients.
    #[inline(never)]
    pub fn forward(&mut self, n: usize) -> Arc<dyn RealToComplex<f32>> {
        self.0.plan_fft_forward(n)
    }

    /// `n / 2 + 1` complex coefficients back to `n` real values (not normalised).
    #[inline(never)]
    pub fn inverse(&mut self, n: usize) -> Arc<dyn ComplexToReal<f32>> {
        self.0.plan_fft_inverse(n)
    }
}

macro_rules! planner_traits {
    ($($t:ident),*) => {$(
        impl Default for $t {
            fn default() -> Self {
                Self::new()
            }
        }

        impl std::fmt::Debug for $t {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(stringify!($t))
            }
        }
    )*};
}

planner_traits!(Planner, RealPlanner, RealPlanner32);
