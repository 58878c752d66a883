//! The whole vision channel of a camera firmware in one fixed working set: camera samples at
//! the frame rate and ADC samples at the ADC rate in, streaming H1 and coherence out
//! (SPEC 2.2 -> 2.3 -> 2.4).
//!
//! Frames arrive one displacement (or centroid) at a time; every `n` of them form a block that
//! is Fourier-upsampled to `m` samples at the ADC rate ([`crate::upsample`], optionally fused
//! with the displacement-to-acceleration conversion). ADC samples arrive in chunks of any size.
//! Both channels are kept in a sample history aligned in time (index `i` of both is the same
//! instant), and as soon as both hold `nperseg` samples a segment is cut straight out of the
//! histories and accumulated ([`crate::spectrum::WelchAccumulator`]); the histories then drop
//! `nperseg - noverlap` samples. The ADC history is also the delay line that waits for the
//! camera: a block of frames is only complete `n` frames after its first one.
//!
//! # Memory
//! One complex work buffer (`WORK >= max(m, nfft)` values) serves the upsampler and the Welch
//! transform in turn, the window is computed rather than stored, and segments are not copied:
//! the state is `4 CAM + 8 HIST + 16 WORK + 8 SCRATCH` bytes plus a few words. For 120 fps ->
//! 2048 Hz blocks of one second, 2048-point segments with 50 % overlap and 256 samples of ADC
//! lead that is `VisionH1<120, 3328, 2048, 150>`: 61 344 B (under 64 KiB; the mcu-demo prints
//! it). The two separate owning types, `WelchH1<2048, 2048, 0>` and
//! `Upsampler<2048, 150>`, would need 66 KiB before any sample buffer.
//!
//! # Capacities
//! `CAM >= n`; `WORK >= m` and `>= nfft`; `SCRATCH >=` the larger DFT scratch of the
//! upsampler and of the Welch transform (0 for powers of two; 150 for a 120-sample block);
//! `HIST >= m + c` where `c < nperseg` is the largest vision history that can be left over
//! after a segment ([`PipelineConfig::min_history`]). What `HIST` holds beyond that is the
//! ADC's allowed lead over the camera ([`VisionH1::adc_headroom`]).
//!
//! # Lost frames and bad samples
//! The pipeline assumes one value per frame period: fill a lost frame before pushing it (the
//! host studies interpolate). A non-finite frame makes its whole upsampled block non-finite,
//! and a non-finite ADC sample its neighbourhood: every segment that touches them is skipped
//! and counted by [`WelchAccumulator::skipped_segments`], the rest of the estimate is kept.
//!
//! # Block edges
//! Each block is upsampled on its own, as one period of a periodic signal (SPEC 2.2's
//! definition applied per block): a response that does not complete whole periods in a block
//! shows Gibbs ringing at the block edges. Longer blocks (`n` frames) make the edges a smaller
//! part of the record.

use crate::dft;
use crate::spectrum::{WelchAccumulator, WelchConfig, WelchError};
use crate::upsample::{UpsampleError, UpsamplePlan};
use crate::Complex32;
use core::fmt;

/// Settings of a [`VisionH1`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PipelineConfig {
    /// Frames per upsampling block (`n`, e.g. 120 for one second at 120 fps).
    pub frames_per_block: usize,
    /// Samples at the ADC rate per block (`m = n * fs_adc / fps`, e.g. 2048).
    pub samples_per_block: usize,
    /// Welch settings; `fs_hz` is the ADC rate. `x` is the ADC channel (the reference, e.g.
    /// base acceleration or force), `y` the vision channel, so H1 is vision over ADC.
    pub welch: WelchConfig,
    /// `Some(scale)`: convert the camera displacement to acceleration during upsampling
    /// (spectrum times `-(2 pi f)^2 * scale`, e.g. `1e-3` for mm in, m/s^2 out). `None`: keep
    /// the camera unit.
    pub acceleration_scale: Option<f32>,
}

impl PipelineConfig {
    /// Camera frame rate implied by the settings: `fs_adc * n / m`.
    pub fn frame_rate_hz(&self) -> f32 {
        if self.samples_per_block == 0 {
            0.0
        } else {
            self.welch.fs_hz * self.frames_per_block as f32 / self.samples_per_block as f32
        }
    }

    /// Smallest `HIST` that always fits the next upsampled block when the ADC keeps ahead of
    /// the camera: `m` plus the largest vision history left after the segments are cut (a
    /// multiple of `gcd(m, nperseg - noverlap)` below `nperseg`). 0 for invalid settings.
    pub const fn min_history(&self) -> usize {
        let n = self.welch.nperseg;
        let m = self.samples_per_block;
        if n == 0 || self.welch.noverlap >= n || m == 0 {
            return 0;
        }
        let g = gcd(m, n - self.welch.noverlap);
        m + (n - 1) / g * g
    }
}

const fn gcd(mut a: usize, mut b: usize) -> usize {
    while b != 0 {
        let t = a % b;
        a = b;
        b = t;
    }
    a
}

/// Why a pipeline cannot be built, or a push was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum PipelineError {
    /// The upsampling block is invalid (lengths, unsupported transform).
    Upsample(UpsampleError),
    /// The Welch settings are invalid.
    Welch(WelchError),
    /// A capacity (const generic) is too small for the settings.
    Capacity {
        /// Which capacity: `"CAM"`, `"WORK"`, `"SCRATCH"` or `"HIST"`.
        what: &'static str,
        /// Values needed.
        needed: usize,
        /// Capacity.
        capacity: usize,
    },
    /// The ADC history is full: the ADC ran further ahead of the camera than `HIST` allows.
    /// Nothing of the refused chunk was consumed.
    AdcOverflow {
        /// Samples offered.
        offered: usize,
        /// Room left in the ADC history.
        room: usize,
    },
    /// A complete block of frames is waiting for room in the vision history (the camera ran
    /// ahead of the ADC); the frame was not consumed. Push ADC samples first.
    BlockPending,
}

impl fmt::Display for PipelineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PipelineError::Upsample(e) => write!(f, "upsampling block: {e}"),
            PipelineError::Welch(e) => write!(f, "welch: {e}"),
            PipelineError::Capacity {
                what,
                needed,
                capacity,
            } => write!(
                f,
                "capacity {what} = {capacity} is too small: {needed} needed"
            ),
            PipelineError::AdcOverflow { offered, room } => write!(
                f,
                "ADC history full: {offered} samples offered, room for {room}; the ADC is too \
                 far ahead of the camera (nothing consumed)"
            ),
            PipelineError::BlockPending => write!(
                f,
                "a block of frames waits for ADC samples; the frame was not consumed"
            ),
        }
    }
}

impl core::error::Error for PipelineError {}

impl From<UpsampleError> for PipelineError {
    fn from(e: UpsampleError) -> Self {
        PipelineError::Upsample(e)
    }
}

impl From<WelchError> for PipelineError {
    fn from(e: WelchError) -> Self {
        PipelineError::Welch(e)
    }
}

/// Camera + ADC -> upsampling (+ acceleration) -> streaming H1, in `4 CAM + 8 HIST + 16 WORK +
/// 8 SCRATCH` bytes (see the [module documentation](self)).
#[derive(Clone)]
pub struct VisionH1<const CAM: usize, const HIST: usize, const WORK: usize, const SCRATCH: usize> {
    config: PipelineConfig,
    plan: UpsamplePlan,
    welch: WelchAccumulator<WORK>,
    camera: [f32; CAM],
    cam_fill: usize,
    vision: [f32; HIST],
    vis_fill: usize,
    adc: [f32; HIST],
    adc_fill: usize,
    work: [Complex32; WORK],
    scratch: [Complex32; SCRATCH],
    blocks: u32,
}

/// Shows the settings and counters, not the buffers.
impl<const CAM: usize, const HIST: usize, const WORK: usize, const SCRATCH: usize> fmt::Debug
    for VisionH1<CAM, HIST, WORK, SCRATCH>
{
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("VisionH1")
            .field("capacities", &(CAM, HIST, WORK, SCRATCH))
            .field("config", &self.config)
            .field("blocks", &self.blocks)
            .field("segments", &self.welch.segments())
            .field("pending", &(self.cam_fill, self.vis_fill, self.adc_fill))
            .finish_non_exhaustive()
    }
}

/// Logs the settings and counters, not the buffers.
#[cfg(feature = "defmt")]
impl<const CAM: usize, const HIST: usize, const WORK: usize, const SCRATCH: usize> defmt::Format
    for VisionH1<CAM, HIST, WORK, SCRATCH>
{
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(
            f,
            "VisionH1 {{ config: {}, blocks: {}, segments: {}, skipped: {}, pending: ({}, {}, {}) }}",
            self.config,
            self.blocks,
            self.welch.segments(),
            self.welch.skipped_segments(),
            self.cam_fill,
            self.vis_fill,
            self.adc_fill
        )
    }
}

impl<const CAM: usize, const HIST: usize, const WORK: usize, const SCRATCH: usize>
    VisionH1<CAM, HIST, WORK, SCRATCH>
{
    /// Checks `config` against the capacities and builds an empty pipeline.
    ///
    /// Errors: [`PipelineError::Upsample`], [`PipelineError::Welch`],
    /// [`PipelineError::Capacity`].
    pub fn try_new(config: PipelineConfig) -> Result<Self, PipelineError> {
        let plan = UpsamplePlan::try_new(config.frames_per_block, config.samples_per_block)?;
        let welch = WelchAccumulator::<WORK>::try_new(config.welch)?;
        let (n, m) = (plan.input_len(), plan.output_len());
        let scratch = plan.scratch_len().max(welch.scratch_len());
        let hist = config.min_history();
        for (what, needed, capacity) in [
            ("CAM", n, CAM),
            ("WORK", m, WORK),
            ("SCRATCH", scratch, SCRATCH),
            ("HIST", hist, HIST),
        ] {
            if needed > capacity {
                return Err(PipelineError::Capacity {
                    what,
                    needed,
                    capacity,
                });
            }
        }
        Ok(VisionH1 {
            config,
            plan,
            welch,
            camera: [0.0; CAM],
            cam_fill: 0,
            vision: [0.0; HIST],
            vis_fill: 0,
            adc: [0.0; HIST],
            adc_fill: 0,
            work: [Complex32::new(0.0, 0.0); WORK],
            scratch: [Complex32::new(0.0, 0.0); SCRATCH],
            blocks: 0,
        })
    }

    /// The settings.
    pub fn config(&self) -> &PipelineConfig {
        &self.config
    }

    /// The estimate: H1 (vision over ADC), coherence, bin frequencies, segment counts.
    pub fn welch(&self) -> &WelchAccumulator<WORK> {
        &self.welch
    }

    /// Blocks of frames upsampled so far.
    pub fn blocks(&self) -> u32 {
        self.blocks
    }

    /// Frames waiting for their block to complete (`n` when a complete block waits for room,
    /// see [`PipelineError::BlockPending`]).
    pub fn pending_frames(&self) -> usize {
        self.cam_fill
    }

    /// ADC samples that can be pushed now without [`PipelineError::AdcOverflow`].
    pub fn adc_headroom(&self) -> usize {
        HIST - self.adc_fill.min(HIST)
    }

    /// Forgets all samples and the estimate; keeps the settings.
    pub fn reset(&mut self) {
        self.cam_fill = 0;
        self.vis_fill = 0;
        self.adc_fill = 0;
        self.blocks = 0;
        self.welch.reset();
    }

    /// Pushes ADC samples (any chunk size) and accumulates every segment that both channels
    /// now cover. Error [`PipelineError::AdcOverflow`] (nothing consumed) if the chunk does not
    /// fit: the camera is more than `HIST - min_history` samples behind.
    pub fn push_adc(&mut self, samples: &[f32]) -> Result<(), PipelineError> {
        let room = self.adc_headroom();
        if samples.len() > room {
            return Err(PipelineError::AdcOverflow {
                offered: samples.len(),
                room,
            });
        }
        if let Some(dst) = self
            .adc
            .get_mut(self.adc_fill..self.adc_fill + samples.len())
        {
            for (d, v) in dst.iter_mut().zip(samples) {
                *d = *v;
            }
            self.adc_fill += samples.len();
        }
        self.advance();
        Ok(())
    }

    /// Pushes one camera sample (displacement, or centroid in pixels with a scale folded into
    /// [`PipelineConfig::acceleration_scale`]). Every `n`-th frame completes a block, which is
    /// upsampled and appended to the vision history, and the segments it completes are
    /// accumulated. Error [`PipelineError::BlockPending`] (frame not consumed) while a complete
    /// block waits for room because the ADC is behind.
    pub fn push_frame(&mut self, value: f32) -> Result<(), PipelineError> {
        let n = self.plan.input_len();
        if self.cam_fill >= n {
            self.advance();
            if self.cam_fill >= n {
                return Err(PipelineError::BlockPending);
            }
        }
        if let Some(d) = self.camera.get_mut(self.cam_fill) {
            *d = value;
            self.cam_fill += 1;
        }
        self.advance();
        Ok(())
    }

    /// Pushes frames in order with [`push_frame`](Self::push_frame); on
    /// [`PipelineError::BlockPending`] returns how many were consumed with the error.
    pub fn push_frames(&mut self, values: &[f32]) -> Result<(), (usize, PipelineError)> {
        for (i, v) in values.iter().enumerate() {
            self.push_frame(*v).map_err(|e| (i, e))?;
        }
        Ok(())
    }

    /// Upsamples a complete block when the vision history has room, and cuts every segment
    /// both histories cover, until neither is possible.
    fn advance(&mut self) {
        let (n, m) = (self.plan.input_len(), self.plan.output_len());
        let nperseg = self.config.welch.nperseg;
        let hop = nperseg - self.config.welch.noverlap;
        loop {
            if self.cam_fill >= n && self.vis_fill + m <= HIST {
                let accel = self
                    .config
                    .acceleration_scale
                    .map(|s| (self.config.frame_rate_hz(), s));
                if let (Some(input), Some(out)) = (
                    self.camera.get(..n),
                    self.vision.get_mut(self.vis_fill..self.vis_fill + m),
                ) {
                    // lengths and capacities were checked by try_new: no error case is left
                    let _ = self.plan.process_with(
                        input,
                        out,
                        accel,
                        &mut self.work,
                        &mut self.scratch,
                    );
                }
                self.vis_fill += m;
                self.cam_fill = 0;
                self.blocks = self.blocks.saturating_add(1);
                continue;
            }
            if self.vis_fill >= nperseg && self.adc_fill >= nperseg {
                if let (Some(x), Some(y)) = (self.adc.get(..nperseg), self.vision.get(..nperseg)) {
                    let _ = self
                        .welch
                        .add_segment(x, y, &mut self.work, &mut self.scratch);
                }
                drop_front(&mut self.vision, &mut self.vis_fill, hop);
                drop_front(&mut self.adc, &mut self.adc_fill, hop);
                continue;
            }
            break;
        }
    }
}

/// Removes the first `k` of the `fill` valid samples of `buf`.
fn drop_front(buf: &mut [f32], fill: &mut usize, k: usize) {
    let k = k.min(*fill);
    if let Some(valid) = buf.get_mut(..*fill) {
        valid.copy_within(k.., 0);
    }
    *fill -= k;
}

/// `SCRATCH` for a pipeline with blocks of `n -> m` samples and Welch transforms of `nfft`
/// points (usable in const context).
pub const fn scratch_capacity(n: usize, m: usize, nfft: usize) -> usize {
    let mut s = 0;
    let lens = [n, m, nfft];
    let mut i = 0;
    while i < lens.len() {
        if let Some(v) = dft::scratch_len(lens[i]) {
            if v > s {
                s = v;
            }
        }
        i += 1;
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectrum::{Detrend, WelchH1, Window};
    use crate::upsample::Upsampler;
    use core::f32::consts::PI;
    use proptest::prelude::*;
    use std::vec;
    use std::vec::Vec;

    const N: usize = 12;
    const M: usize = 64;
    const SEG: usize = 64;
    const S: usize = scratch_capacity(N, M, SEG);
    type P = VisionH1<N, 128, M, S>;

    fn config(accel: Option<f32>) -> PipelineConfig {
        PipelineConfig {
            frames_per_block: N,
            samples_per_block: M,
            welch: WelchConfig {
                fs_hz: 64.0,
                nperseg: SEG,
                noverlap: 32,
                nfft: SEG,
                window: Window::Hann,
                detrend: Detrend::Constant,
            },
            acceleration_scale: accel,
        }
    }

    /// Camera (12 fps) and ADC (64 Hz) records of `blocks` seconds: a random-ish camera signal
    /// and an ADC channel that is noise plus a filtered copy.
    fn records(blocks: usize, seed: u32) -> (Vec<f32>, Vec<f32>) {
        let mut s = seed.wrapping_mul(2_654_435_761).wrapping_add(1);
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            (s as f32 / u32::MAX as f32) - 0.5
        };
        let cam: Vec<f32> = (0..blocks * N).map(|_| next()).collect();
        let adc: Vec<f32> = (0..blocks * M).map(|_| next()).collect();
        (cam, adc)
    }

    fn sums_bits(w: &WelchAccumulator<M>) -> Vec<u32> {
        (0..w.bins())
            .flat_map(|k| {
                let s = w.sums(k).unwrap();
                [s.pxx, s.pyy, s.pxy.re, s.pxy.im].map(f32::to_bits)
            })
            .collect()
    }

    /// The same estimate from the owning types: upsample every block, then stream.
    fn reference(cam: &[f32], adc: &[f32], accel: Option<f32>) -> Vec<u32> {
        let mut up = Upsampler::<M, S>::try_new(N, M).unwrap();
        let mut vision = vec![0.0f32; cam.len() / N * M];
        for (blk, out) in cam.chunks(N).zip(vision.chunks_mut(M)) {
            match accel {
                Some(s) => up.process_acceleration(blk, out, 12.0, s).unwrap(),
                None => up.process(blk, out).unwrap(),
            }
        }
        let mut w = WelchH1::<SEG, M, S>::try_new(config(None).welch).unwrap();
        w.push(adc, &vision).unwrap();
        sums_bits(w.accumulator())
    }

    #[test]
    fn equals_upsampling_then_streaming_welch_bit_for_bit() {
        for accel in [None, Some(1e-3)] {
            let (cam, adc) = records(6, 1);
            let mut p = P::try_new(config(accel)).unwrap();
            for (c, a) in cam.chunks(N).zip(adc.chunks(M)) {
                p.push_adc(a).unwrap();
                p.push_frames(c).unwrap();
            }
            assert_eq!(p.blocks(), 6);
            assert_eq!(p.welch().segments(), 11);
            assert_eq!(sums_bits(p.welch()), reference(&cam, &adc, accel));
        }
    }

    #[test]
    fn known_resonance_through_the_acceleration_conversion() {
        // camera: displacement (mm) of a 2-DOF-like response at 2 and 5 Hz (whole periods per
        // block, below the camera's 6 Hz Nyquist); ADC: its exact acceleration in m/s^2. H1 = vision / ADC = 1 at those bins.
        let blocks = 8;
        let disp =
            |t: f32| 2.0 * (2.0 * PI * 5.0 * t + 0.4).sin() + 0.7 * (2.0 * PI * 2.0 * t).cos();
        let acc = |t: f32| {
            let (w1, w2) = (2.0 * PI * 5.0, 2.0 * PI * 2.0);
            -1e-3 * (2.0 * w1 * w1 * (w1 * t + 0.4).sin() + 0.7 * w2 * w2 * (w2 * t).cos())
        };
        let mut p = P::try_new(config(Some(1e-3))).unwrap();
        for b in 0..blocks {
            let adc: Vec<f32> = (0..M).map(|i| acc((b * M + i) as f32 / 64.0)).collect();
            p.push_adc(&adc).unwrap();
            for i in 0..N {
                p.push_frame(disp((b * N + i) as f32 / 12.0)).unwrap();
            }
        }
        let w = p.welch();
        for k in [2, 5] {
            let h = w.h1(k).unwrap();
            assert!(
                (h.re - 1.0).abs() < 1e-3 && h.im.abs() < 1e-3,
                "bin {k}: {h}"
            );
            assert!(w.coherence(k).unwrap() > 0.9999);
        }
    }

    #[test]
    fn refuses_overflow_without_losing_samples() {
        let (cam, adc) = records(4, 2);
        let mut p = P::try_new(config(None)).unwrap();
        // ADC may lead by HIST - ... ; a chunk that does not fit is refused whole
        assert_eq!(p.adc_headroom(), 128);
        assert_eq!(
            p.push_adc(&adc[..129]),
            Err(PipelineError::AdcOverflow {
                offered: 129,
                room: 128
            })
        );
        assert_eq!(p.adc_headroom(), 128);
        // camera ahead of the ADC: the third block waits, its first frame is refused
        let (consumed, e) = p.push_frames(&cam).unwrap_err();
        assert_eq!((consumed, e), (3 * N, PipelineError::BlockPending));
        assert_eq!(p.pending_frames(), N);
        // the ADC catches up, everything resumes, and nothing was lost
        p.push_adc(&adc[..128]).unwrap();
        assert_eq!(p.pending_frames(), 0);
        p.push_frames(&cam[consumed..]).unwrap();
        for chunk in adc[128..].chunks(64) {
            p.push_adc(chunk).unwrap();
        }
        assert_eq!(p.blocks(), 4);
        assert_eq!(sums_bits(p.welch()), reference(&cam, &adc, None));
    }

    #[test]
    fn a_non_finite_frame_skips_the_segments_of_its_block_only() {
        let (mut cam, adc) = records(6, 4);
        cam[3 * N + 5] = f32::NAN;
        let mut p = P::try_new(config(None)).unwrap();
        for (c, a) in cam.chunks(N).zip(adc.chunks(M)) {
            p.push_adc(a).unwrap();
            p.push_frames(c).unwrap();
        }
        // block 3 covers samples 192..256: segments starting at 160, 192, 224 touch it
        let w = p.welch();
        assert_eq!((w.segments(), w.skipped_segments()), (8, 3));
        assert!((0..w.bins()).all(|k| w.h1(k).is_some_and(|h| h.re.is_finite())));
    }

    #[test]
    fn rejects_capacities_and_settings() {
        let c = config(None);
        assert!(matches!(
            VisionH1::<11, 128, M, S>::try_new(c),
            Err(PipelineError::Capacity {
                what: "CAM",
                needed: 12,
                capacity: 11
            })
        ));
        assert!(matches!(
            VisionH1::<N, 128, 32, S>::try_new(c),
            Err(PipelineError::Welch(WelchError::FftLength { .. }))
        ));
        assert!(matches!(
            VisionH1::<N, 128, M, 0>::try_new(c),
            Err(PipelineError::Capacity {
                what: "SCRATCH",
                ..
            })
        ));
        // min_history = m + 32 for hop 32 and m = 64
        assert_eq!(c.min_history(), 96);
        assert!(matches!(
            VisionH1::<N, 95, M, S>::try_new(c),
            Err(PipelineError::Capacity {
                what: "HIST",
                needed: 96,
                capacity: 95
            })
        ));
        let mut bad = c;
        bad.samples_per_block = 5;
        assert!(matches!(
            P::try_new(bad),
            Err(PipelineError::Upsample(UpsampleError::Lengths { .. }))
        ));
    }

    #[test]
    fn the_demo_pipeline_fits_in_64_kib() {
        // one second of 120 fps -> 2048 Hz, 2048-point segments, 256 samples of ADC lead
        let c = PipelineConfig {
            frames_per_block: 120,
            samples_per_block: 2048,
            welch: WelchConfig {
                fs_hz: 2048.0,
                nperseg: 2048,
                noverlap: 1024,
                nfft: 2048,
                window: Window::Hann,
                detrend: Detrend::Constant,
            },
            acceleration_scale: Some(1e-3),
        };
        assert_eq!(c.min_history(), 3072);
        const SC: usize = scratch_capacity(120, 2048, 2048);
        assert_eq!(SC, 150);
        type Demo = VisionH1<120, 3328, 2048, SC>;
        let size = core::mem::size_of::<Demo>();
        let buffers = 4 * 120 + 8 * 3328 + 16 * 2048 + 8 * SC;
        assert!(
            size >= buffers && size <= buffers + 320,
            "{size} vs {buffers}"
        );
        assert!(size < 64 * 1024, "{size}");
        std::println!("size_of VisionH1<120, 3328, 2048, 150> = {size} bytes");
        let p = std::boxed::Box::new(Demo::try_new(c).unwrap());
        assert_eq!(p.adc_headroom(), 3328);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]
        /// Any interleaving of frames and ADC chunks that keeps within the capacities gives the
        /// same estimate, bit for bit.
        #[test]
        fn interleaving_does_not_change_a_bit(
            seed in 0u32..1000,
            blocks in 1usize..7,
            cuts in proptest::collection::vec((0usize..40, 0usize..30), 1..40),
        ) {
            let (cam, adc) = records(blocks, seed);
            let mut p = P::try_new(config(Some(2.0))).unwrap();
            let (mut i, mut j) = (0usize, 0usize);
            for (a, f) in cuts.iter().copied().cycle() {
                if i >= adc.len() && j >= cam.len() {
                    break;
                }
                let a_end = (i + a.max(1)).min(adc.len()).min(i + p.adc_headroom());
                p.push_adc(&adc[i..a_end]).unwrap();
                i = a_end;
                let f_end = (j + f.max(1)).min(cam.len());
                match p.push_frames(&cam[j..f_end]) {
                    Ok(()) => j = f_end,
                    Err((k, e)) => {
                        prop_assert_eq!(e, PipelineError::BlockPending);
                        j += k;
                    }
                }
            }
            prop_assert_eq!(p.blocks() as usize, blocks);
            prop_assert_eq!(sums_bits(p.welch()), reference(&cam, &adc, Some(2.0)));
        }
    }
}
