//! # firmware-core
//!
//! The part of the vision-based vibration measurement chain that runs **on the camera**:
//! it is what an MCU camera firmware links, so it is `#![no_std]`, uses no allocator and no
//! `unsafe`, keeps every buffer at a size fixed at compile time (const generics) and never
//! panics on any input.
//!
//! The host-side Monte Carlo studies (`host-harness`) push their simulated frames and signals
//! through this very crate, so every study validates the code that ships.
//!
//! One module per stage of the measurement chain (see the repository's `docs/method.md` section 2):
//!
//! | module | stage | state (RAM) |
//! |---|---|---|
//! | [`centroid`] | thresholded centre of gravity of the target(s) in each frame, row-streaming; [`centroid::track`]: the tracking window | `Centroider`, `Tracker`: about 100 B; `MultiCentroider<W, N>`: `2 W + 64 N` B |
//! | [`lk`] | Lucas-Kanade (inverse-compositional) sub-pixel translation of a textured window, with a coarse integer search | `LkTracker<N, W>`: `21 N + 40 W` B + 2.7 KiB |
//! | [`dft`] | exact DFT of any length on top of power-of-two `microfft` (mixed radix + Bluestein) | caller buffers |
//! | [`upsample`] | Fourier (zero-padding) resampling of camera-rate displacement to the ADC rate | `Upsampler<M, S>`: `8 M + 8 S` B |
//! | [`exposure`] | exposure (box) transfer, E2PR, and its compensation (sinc or a binary-centroid table) | none (a `CorrectionTable<N>`: `4 N` B) |
//! | [`convert`] | displacement to acceleration: spectrum times -omega^2, pixel to SI scaling | as `upsample` |
//! | [`spectrum`] | streaming Welch estimator of H1 and coherence | `WelchH1<SEG, NFFT, S>`: `8 SEG + 16 NFFT + 8 S` B |
//! | [`peaks`] | resonance frequency and amplitude by peak picking of Im H1 in bands | none |
//! | [`pipeline`] | the whole vision channel in one fixed working set: frames + ADC samples in, H1 out | `VisionH1<CAM, HIST, WORK, S>`: `4 CAM + 8 HIST + 16 WORK + 8 S` B |
//! | [`sync`] | camera trigger / ADC conversion schedule from one time base (`embedded-hal` 1.0) | a few words |
//!
//! Flash per stage and instruction counts on a Cortex-M4 are measured by `mcu-demo/bench.sh`
//! and listed in the crate README (measured figures go stale in a doc comment).
//!
//! # Linking it
//!
//! `firmware-core = { version = "0.1", default-features = false }` (add `features =
//! ["defmt"]` for `defmt::Format` on the public types). It builds for any `thumbv6m`/`thumbv7em`
//! target; on 32-bit ARM the centroid row kernels are word-at-a-time SWAR versions (safe
//! Rust). Float maths goes through `libm`. Use the re-exported [`heapless`] (the version the
//! crate's types use).
//!
//! # One configuration pattern
//!
//! Every stage has a plain, `Copy` configuration type with public fields (units and valid
//! ranges on each): [`centroid::CentroidConfig`], [`centroid::track::TrackConfig`],
//! [`spectrum::WelchConfig`], [`pipeline::PipelineConfig`], [`sync::SyncConfig`] (the
//! upsampler's is its plan, [`upsample::UpsamplePlan`]), with `const` constructors for the
//! usual settings. Settings are checked **once**: by the state's `const fn try_new(config)`
//! (usable in a `static` initialiser: an invalid setting is then a compile error), or by
//! `configure(&mut self, config)` in place. Configuration errors are each module's
//! `ConfigError`; after that the per-row and per-sample paths have no error case left, except
//! capacity refusals that hand the item back (`pipeline::PushError`, heapless style) and
//! wrong caller buffers ([`BufferError`]).
//!
//! Every stateful type also has a `const fn new()` whose bytes are all zero, so a `static`
//! holding it lands in `.bss`: built in place, no stack copy and no flash image of a 57 KiB
//! pipeline, then `configure`d. Capacities come from the settings through `const fn`s
//! ([`pipeline::PipelineConfig::camera_capacity`] and its siblings): no capacity numbers to
//! copy from the documentation.
//!
//! # How a firmware uses it
//!
//! A camera DMA raises a line interrupt per row; an ADC DMA raises a half-transfer interrupt
//! per chunk. The line interrupt hands the row (its DMA buffer index) to the main loop through
//! a `heapless::spsc::Queue`; the main loop centroids it with the tracking window and, at the
//! end of each frame, pushes the centroid and the ADC chunks that arrived into the pipeline.
//! Here the interrupts are simulated by plain calls (a 64 x 48 camera at 12 fps, a 64 Hz ADC):
//!
//! ```
//! use firmware_core::centroid::{track::{TrackConfig, Tracker}, CentroidConfig};
//! use firmware_core::heapless::spsc::Queue;
//! use firmware_core::pipeline::{PipelineConfig, VisionH1};
//!
//! const WIDTH: usize = 64;
//! const HEIGHT: usize = 48;
//! const FPS: usize = 12;
//! const ADC_HZ: usize = 64;
//! const TRACK: TrackConfig = TrackConfig::new(CentroidConfig::binary(100), 64, 48, 4);
//! const PIPELINE: PipelineConfig = PipelineConfig::one_second_blocks(FPS, ADC_HZ, None);
//! type Pipeline = VisionH1<
//!     { PIPELINE.camera_capacity() },
//!     { PIPELINE.history_capacity(ADC_HZ / FPS) },
//!     { PIPELINE.work_capacity() },
//!     { PIPELINE.scratch_capacity() },
//! >;
//! // On the MCU: `static mut` items (in `.bss`), configured once at boot.
//! let mut pipeline = Pipeline::new();
//! pipeline.configure(PIPELINE).unwrap();
//! let mut tracker = Tracker::new();
//! tracker.configure(TRACK).unwrap();
//!
//! /// The structure's position (px) at time `t` (s): 2 px at 3 Hz around row 24.
//! fn centre(t: f32) -> f32 {
//!     24.0 + 2.0 * libm::sinf(2.0 * core::f32::consts::PI * 3.0 * t)
//! }
//! /// Row `y` of frame `j`: a 5 px high bar at the structure's (whole-pixel) position.
//! fn sensor_row(j: usize, y: usize, row: &mut [u8; WIDTH]) {
//!     let lit = (y as f32 - libm::roundf(centre(j as f32 / FPS as f32))).abs() <= 2.0;
//!     for (x, p) in row.iter_mut().enumerate() {
//!         *p = if lit && (20..40).contains(&x) { 200 } else { 10 };
//!     }
//! }
//!
//! let mut dma = [[0u8; WIDTH]; 4]; // line buffers the camera DMA writes in turn
//! let mut lines: Queue<(u16, u8), 4> = Queue::new();
//! let (mut line_irq, mut main_loop) = lines.split();
//! let mut adc_sample = 0;
//! for j in 0..FPS * 4 {
//!     for y in 0..HEIGHT {
//!         // line interrupt: the DMA wrote row y into buffer y % 4; hand it over
//!         let slot = y % dma.len();
//!         sensor_row(j, y, &mut dma[slot]);
//!         line_irq.enqueue((y as u16, slot as u8)).unwrap();
//!         // main loop: centroid every queued row, release its buffer after reading it
//!         while let Some(&(_, slot)) = main_loop.peek() {
//!             tracker.push_row(&dma[usize::from(slot)]);
//!             main_loop.dequeue();
//!         }
//!     }
//!     let c = tracker.finish_frame();
//!     pipeline.push_frame(c.cy).unwrap();
//!     // ADC DMA half-transfer: the samples up to the end of frame j
//!     let until = (j + 1) * ADC_HZ / FPS;
//!     // (a displacement transducer here, in px, to keep the example short)
//!     let chunk: Vec<f32> = (adc_sample..until).map(|i| centre(i as f32 / ADC_HZ as f32)).collect();
//!     pipeline.push_adc(&chunk).unwrap();
//!     adc_sample = until;
//! }
//! assert_eq!(pipeline.blocks(), 6);
//! // the camera sees whole-pixel steps of the motion: H1 at 3 Hz close to 1
//! let h = pipeline.welch().h1(3).unwrap();
//! assert!((h.norm_sqr().sqrt() - 1.0).abs() < 0.1, "{h}");
//! ```
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

/// Implements `Display` (one `match self` over the variants, writing to the formatter named by
/// the second argument) and the empty `core::error::Error` for an error enum of this crate.
macro_rules! error_display {
    ($ty:ident, $f:ident, { $($arms:tt)* }) => {
        impl core::fmt::Display for $ty {
            fn fmt(&self, $f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                match self {
                    $($arms)*
                }
            }
        }

        impl core::error::Error for $ty {}
    };
}

/// `?` for a `const fn`, where the operator is not allowed: the `Ok` value, or an early return
/// of the error unchanged.
macro_rules! const_try {
    ($result:expr) => {
        match $result {
            Ok(v) => v,
            Err(e) => return Err(e),
        }
    };
}

pub mod centroid;
pub mod convert;
pub mod dft;
pub mod exposure;
pub mod lk;
pub mod peaks;
pub mod pipeline;
pub mod spectrum;
pub mod sync;
pub mod upsample;

#[cfg(test)]
mod test_support;

/// Single-precision complex number used throughout the crate (the one `microfft` uses).
pub use num_complex::Complex32;

/// The `heapless` version this crate's types use (`MultiCentroider::targets` returns a
/// `heapless::Vec`): use it through this re-export and one build never holds two versions.
pub use heapless;

/// A caller buffer has the wrong length: the one **run-time** error of the functions that work
/// in caller-provided buffers ([`dft::Dft::process`], [`upsample::UpsamplePlan::process`],
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
