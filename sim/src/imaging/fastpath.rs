//! The fast imaging path of the grandstand study: the binary centroid of an EPSA frame
//! (one disk target moving along `y`, 8-bit quantisation, no other effect) without rendering
//! the frame.
//!
//! # What it computes
//!
//! Exactly what [`BlurRenderer::render`] followed by `centroid_u8` (binary) gives, pixel for
//! pixel, up to ties: a pixel is selected when the inverse DFT of the renderer's own `f32`
//! column spectrum (reference column spectrum times the renderer's averaged ramp, the same
//! `f32` operations), summed directly at that row in `f32`, rounds above the threshold. The
//! renderer inverts that spectrum with an `f32` FFT, so the two can differ only for a pixel
//! whose value lies within the two sums' rounding (about 1e-4 grey levels each) of the decision
//! level `T + 0.5` (the tests allow 2e-3 grey levels for such ties and have seen none). We reproduce EPSA rather than an analytic model (an erf-smoothed disk
//! averaged over the path): EPSA is the periodic band-limited interpolation of the sampled
//! disk, which differs from the closed-form profile by up to about 0.01 grey level at the edge
//! (tested); with some 30 rows per frame near the threshold and about 50 grey levels per pixel
//! across it, that flips a pixel in roughly one frame in a hundred, and a flipped pixel moves
//! the centroid by about 0.02 px, far above the 1e-4 px agreement the study needs.
//!
//! # How
//!
//! Every column `j` of the frame is the average over the exposure of the translated reference
//! column `q_j(y - d(t))` (`q_j` the band-limited interpolant of the sharp column, `d(t)` the
//! displacement). `q_j` equals the analytic profile `p_j(s) = L erfc((sqrt(j^2 + s^2) - R) /
//! (sigma sqrt 2)) / 2` to within a small aliasing error `eps` (checked when the camera is
//! built), and `p_j` falls monotonically with `|s|`. So with the displacement range
//! `[dmin, dmax]` of the exposure and the half-widths `c_in(j)` (where `p_j > T + 0.5 + m`)
//! and `c_out(j)` (where `p_j >= T + 0.5 - m`), margin `m` above `eps` plus the `f32` error:
//!
//! * rows `u = y - rest_y` in `(dmax - c_in, dmin + c_in)` are above the threshold in every
//!   translate, hence in the average: counted in closed form (a run of rows);
//! * rows outside `[dmin - c_out, dmax + c_out]` are below it in every translate: skipped, as
//!   are whole columns whose peak never reaches `T + 0.5 - m`;
//! * only the rows in between (one or two per edge for a slow target, the swept band for a
//!   fast one) are evaluated: the inverse DFT at one row, `O(H)`; a column with more than
//!   [`ROWS_PER_FFT`] of them is inverted whole by the renderer's own `f32` inverse FFT
//!   (same plan, same input: bit for bit the renderer's values).
//!
//! The mirror columns `rest_x +/- j` are equal in the renderer, so `sum_x = rest_x * pixels`.
//! A frame outside the fast path's domain (the possibly selected rows reaching the frame's
//! first or last row, or a target too bright or too faint for the margins) is rendered and
//! centroided the ordinary way, so the result is always the reference one.
//!
//! Only the binary centroid: the weighted one needs the quantised value of every selected pixel,
//! and per-pixel rounding has no closed-form sum.

use crate::imaging::{BlurRenderer, DiskTarget};
use firmware_core::centroid::{
    centroid, Centroid, CentroidConfig, Flags, Frame, FrameError, Moments,
};
use num_complex::Complex32;
use std::sync::Arc;
use vibcam_fft::ComplexToReal;

/// Margin (grey levels) between the analytic profile's level crossings and the decision
/// level: covers the band-limited interpolant's aliasing error (at most `MARGIN / 4`, checked
/// at construction; below 0.01 for the study's disk, tested) and the renderer's `f32` rounding
/// of the averaged ramp (below 2e-3, the renderer's block-sum test).
const MARGIN: f64 = 0.5;

/// Above this many uncertain rows in a column (a fast target sweeping many rows during the
/// exposure), the column is inverted whole by the same `f32` inverse FFT as the renderer's
/// (same length, same plan: the same values) instead of row by row.
pub const ROWS_PER_FFT: i64 = 8;

/// Counters of a [`FastDiskCamera`]'s work, for benchmarks and tests.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FastStats {
    /// Frames centroided.
    pub frames: u64,
    /// Frames that went through the renderer (outside the fast path's domain).
    pub rendered: u64,
    /// Rows evaluated by an inverse DFT (summed over columns and frames).
    pub evaluated: u64,
    /// Columns inverted whole by an inverse FFT (summed over frames).
    pub columns_fft: u64,
}

/// Binary centroid of [`BlurRenderer`] frames of a [`DiskTarget`] without rendering them (see
/// the module documentation): `frame(renderer, a, b)` returns what
/// `renderer.render(a, b, frame)` followed by `centroid_u8` with `CentroidConfig::binary(T)`
/// returns, from the same renderer (its path and averaged ramps).
pub struct FastDiskCamera {
    config: CentroidConfig,
    /// Whether the margins hold for this target and threshold (else every frame is rendered).
    enabled: bool,
    width: usize,
    height: usize,
    rest_x: u64,
    rest_y: f64,
    /// Per column offset `j = 0 ..= last_col`: half-width of the certainly selected rows
    /// (negative: none) and of the possibly selected rows.
    c_in: Vec<f64>,
    c_out: Vec<f64>,
    /// Twiddles `cos`, `sin` of `2 pi k y / H` (rounded to `f32`), row `y` at `y * bins`.
    cos: Vec<f32>,
    sin: Vec<f32>,
    /// Reference column spectra of columns `0 ..= last_col`, real and imaginary parts, `bins`
    /// per column (copies of the renderer's, laid out for SIMD).
    ref_re: Vec<f32>,
    ref_im: Vec<f32>,
    /// The frame's averaged ramp (a copy of the renderer's), real and imaginary parts.
    ramp_re: Vec<f32>,
    ramp_im: Vec<f32>,
    /// One column's spectrum (`f32`, as the renderer computes it), and its parts.
    spec: Vec<Complex32>,
    spec_re: Vec<f32>,
    spec_im: Vec<f32>,
    /// Frame buffer for frames outside the domain.
    frame: Vec<u8>,
    /// The renderer's inverse FFT (planned alike) and its buffers, for swept columns.
    ifft: Arc<dyn ComplexToReal<f32>>,
    column: Vec<f32>,
    scratch: Vec<Complex32>,
    stats: FastStats,
}

impl std::fmt::Debug for FastDiskCamera {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FastDiskCamera")
            .field("enabled", &self.enabled)
            .field("width", &self.width)
            .field("height", &self.height)
            .field("stats", &self.stats)
            .finish()
    }
}

/// Radius where the disk profile equals `level`, `None` when the profile's peak is below it.
fn radius_at(target: &DiskTarget, level: f64) -> Option<f64> {
    if level <= 0.0 || target.profile(0.0) <= level {
        return None;
    }
    // profile falls monotonically with r: bisection to 1e-12 px
    let (mut lo, mut hi) = (0.0, target.extent() + 10.0 * target.edge_sigma_px);
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if target.profile(mid) > level {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(lo)
}

impl FastDiskCamera {
    /// The fast camera for `renderer` (built for `target`) and the binary threshold
    /// `threshold` (8-bit grey levels). Costs a few tenths of a millisecond (the twiddle table and
    /// the check of the interpolant against the analytic profile).
    pub fn new(target: &DiskTarget, renderer: &BlurRenderer, threshold: u16) -> FastDiskCamera {
        let (width, height) = (renderer.width(), renderer.height());
        let bins = height / 2 + 1;
        let mut cos = vec![0.0; height * bins];
        let mut sin = vec![0.0; height * bins];
        for y in 0..height {
            for k in 0..bins {
                // exact reduction of k y mod H keeps the twiddles accurate for every row
                let ph = std::f64::consts::TAU * ((k * y) % height) as f64 / height as f64;
                cos[y * bins + k] = ph.cos() as f32;
                sin[y * bins + k] = ph.sin() as f32;
            }
        }
        let ifft = vibcam_fft::RealPlanner32::new().inverse(height);
        let decision = threshold as f64 + 0.5;
        let r_in = radius_at(target, decision + MARGIN);
        let r_out = radius_at(target, decision - MARGIN);
        // no 255 pixel (SATURATED flag) can occur, and the threshold is inside the profile
        // (a speckled target is not a disk's level set: rendered)
        let mut enabled = threshold < 255
            && target.is_symmetric()
            && target.level + MARGIN < 254.5
            && decision - MARGIN > 0.0
            && r_out.is_some();
        let (mut c_in, mut c_out) = (Vec::new(), Vec::new());
        if let Some(r_out) = r_out {
            let last = (r_out.floor() as usize).min(renderer.half_cols());
            enabled &= r_out < renderer.half_cols() as f64;
            for j in 0..=last {
                let jj = (j * j) as f64;
                c_out.push((r_out * r_out - jj).max(0.0).sqrt());
                c_in.push(match r_in {
                    Some(r) if r * r > jj => (r * r - jj).sqrt(),
                    _ => -1.0,
                });
            }
        }
        let mut cam = FastDiskCamera {
            config: CentroidConfig::binary(threshold),
            enabled,
            width,
            height,
            rest_x: renderer.rest_x() as u64,
            rest_y: renderer.rest_y(),
            c_in,
            c_out,
            cos,
            sin,
            ref_re: Vec::new(),
            ref_im: Vec::new(),
            ramp_re: vec![0.0; bins],
            ramp_im: vec![0.0; bins],
            spec: vec![Complex32::new(0.0, 0.0); bins],
            spec_re: vec![0.0; bins],
            spec_im: vec![0.0; bins],
            frame: Vec::new(),
            scratch: vec![Complex32::new(0.0, 0.0); ifft.get_scratch_len()],
            ifft,
            column: vec![0.0; height],
            stats: FastStats::default(),
        };
        for j in 0..cam.c_out.len() {
            for c in renderer.column_spectrum(j) {
                cam.ref_re.push(c.re);
                cam.ref_im.push(c.im);
            }
        }
        if cam.enabled {
            cam.enabled = cam.interpolation_error(target, renderer) < MARGIN / 4.0;
        }
        cam
    }

    /// Whether frames take the fast path (false: every frame is rendered, e.g. for a target
    /// whose edge is too sharp for the sampled image to be band-limited).
    pub fn enabled(&self) -> bool {
        self.enabled
    }

    /// Work counters since construction.
    pub fn stats(&self) -> FastStats {
        self.stats
    }

    /// Largest deviation (grey levels) of the band-limited interpolant of the sharp columns
    /// from the analytic profile, at half-integer offsets (midway between the samples, where
    /// the aliasing error peaks) over the whole period.
    fn interpolation_error(&self, target: &DiskTarget, renderer: &BlurRenderer) -> f64 {
        let h = self.height;
        let bins = h / 2 + 1;
        // exp(2 pi i k (row + 1/2) / H) in f64, with k (2 row + 1) reduced mod 2 H
        let twiddle: Vec<(f64, f64)> = (0..h * bins)
            .map(|i| {
                let (y, k) = (i / bins, i % bins);
                let turn = ((k * (2 * y + 1)) % (2 * h)) as f64 / (2 * h) as f64;
                let (s, c) = (std::f64::consts::TAU * turn).sin_cos();
                (c, s)
            })
            .collect();
        let mut worst = 0.0f64;
        for j in 0..self.c_out.len() {
            let spec = renderer.column_spectrum(j);
            for y in 0..h {
                let mut v = spec[0].re as f64;
                for (k, (c, &(tc, ts))) in spec
                    .iter()
                    .zip(&twiddle[y * bins..(y + 1) * bins])
                    .enumerate()
                    .skip(1)
                {
                    if 2 * k == h {
                        // the renderer keeps the Nyquist bin real
                        v += c.re as f64 * tc;
                    } else {
                        v += 2.0 * (c.re as f64 * tc - c.im as f64 * ts);
                    }
                }
                // offset from the centre on the nearest copy of the periodic image
                let s = y as f64 + 0.5 - self.rest_y;
                let s = s - h as f64 * (s / h as f64).round();
                let want = target.profile(((j * j) as f64 + s * s).sqrt());
                worst = worst.max((v / h as f64 - want).abs());
            }
        }
        worst
    }

    /// The binary centroid of the frame `renderer` would render for the exposure from `a` to
    /// `b` (fractional path indices), i.e. `renderer.render(a, b, buf)` then `centroid_u8`.
    pub fn frame(
        &mut self,
        renderer: &mut BlurRenderer,
        a: f64,
        b: f64,
    ) -> Result<Centroid, FrameError> {
        let (mut pixels, mut sum_y) = (0u64, 0u64);
        let fast = self.scan(renderer, a, b, |j, y0, y1| {
            // rows y0 ..= y1 of columns rest_x +/- j
            let mult = if j == 0 { 1 } else { 2 };
            pixels += mult * (y1 - y0 + 1);
            sum_y += mult * ((y0 + y1) * (y1 - y0 + 1) / 2);
        });
        if !fast {
            return self.rendered(renderer, a, b);
        }
        let moments = Moments {
            pixels,
            weight: pixels,
            sum_x: self.rest_x * pixels,
            sum_y,
        };
        Ok(match moments.position() {
            Some((cx, cy)) => Centroid {
                cx,
                cy,
                moments,
                flags: Flags::NONE,
            },
            None => Centroid {
                cx: 0.0,
                cy: 0.0,
                moments,
                flags: Flags::EMPTY,
            },
        })
    }

    /// Hands the selected pixels of the frame to `sink(j, y0, y1)` (rows `y0 ..= y1` of the
    /// columns `rest_x +/- j`), or returns false without calling it when the frame is outside
    /// the fast path's domain.
    fn scan(
        &mut self,
        renderer: &mut BlurRenderer,
        a: f64,
        b: f64,
        mut sink: impl FnMut(usize, u64, u64),
    ) -> bool {
        self.stats.frames += 1;
        let (dmin, dmax) = renderer.path_range(a, b);
        let reach = self.c_out.first().copied().unwrap_or(0.0);
        let inside = self.rest_y + dmin - reach >= 1.0
            && self.rest_y + dmax + reach <= (self.height - 2) as f64;
        if !(self.enabled && inside) {
            return false;
        }
        for ((r, re), im) in renderer
            .exposure_ramp(a, b)
            .iter()
            .zip(&mut self.ramp_re)
            .zip(&mut self.ramp_im)
        {
            *re = r.re;
            *im = r.im;
        }
        let bins = self.ramp_re.len();
        let scale = 1.0 / self.height as f32;
        let rest_y = self.rest_y as i64;
        for j in 0..self.c_out.len() {
            let (c_in, c_out) = (self.c_in[j], self.c_out[j]);
            let lo = (dmin - c_out).ceil() as i64;
            let hi = (dmax + c_out).floor() as i64;
            if lo > hi {
                continue;
            }
            // certainly selected rows sure_lo ..= sure_hi (none when sure_lo > sure_hi)
            let (sure_lo, sure_hi) = if c_in > 0.0 {
                (
                    ((dmax - c_in).floor() as i64 + 1).max(lo),
                    ((dmin + c_in).ceil() as i64 - 1).min(hi),
                )
            } else {
                (hi + 1, hi)
            };
            let ranges = if sure_lo <= sure_hi {
                sink(j, (rest_y + sure_lo) as u64, (rest_y + sure_hi) as u64);
                [(lo, sure_lo - 1), (sure_hi + 1, hi)]
            } else {
                [(lo, hi), (1, 0)]
            };
            let uncertain: i64 = ranges.iter().map(|(f, t)| (t - f + 1).max(0)).sum();
            if uncertain == 0 {
                continue;
            }
            // the renderer's column spectrum, reference x ramp x 1/H with the same f32
            // operations in the same order as its Complex32 products (hence the same values)
            let (fr, fi) = (
                &self.ref_re[j * bins..(j + 1) * bins],
                &self.ref_im[j * bins..(j + 1) * bins],
            );
            // (zipped slices: no bounds checks, no reloads of the fields, vectorised)
            for (((((sr, si), fr), fi), rr), ri) in self
                .spec_re
                .iter_mut()
                .zip(self.spec_im.iter_mut())
                .zip(fr)
                .zip(fi)
                .zip(&self.ramp_re)
                .zip(&self.ramp_im)
            {
                *sr = (fr * rr - fi * ri) * scale;
                *si = (fr * ri + fi * rr) * scale;
            }
            let whole = uncertain > ROWS_PER_FFT;
            if whole {
                // exactly the renderer's column: same spectrum (f32 values are exact in f64),
                // same inverse FFT
                for ((s, re), im) in self.spec.iter_mut().zip(&self.spec_re).zip(&self.spec_im) {
                    *s = Complex32::new(*re, *im);
                }
                let last = bins - 1;
                self.spec[0].im = 0.0;
                self.spec[last].im = 0.0;
                // sizes come from the same plan, so this cannot fail
                let _ = self.ifft.process_with_scratch(
                    &mut self.spec,
                    &mut self.column,
                    &mut self.scratch,
                );
                self.stats.columns_fft += 1;
            }
            for (from, to) in ranges {
                for u in from..=to {
                    let y = (rest_y + u) as usize;
                    let above = if whole {
                        above(self.column[y], self.config.threshold)
                    } else {
                        self.stats.evaluated += 1;
                        self.selected(y)
                    };
                    if above {
                        sink(j, y as u64, y as u64);
                    }
                }
            }
        }
        true
    }

    /// Whether row `y` of the column whose spectrum is in `self.spec` rounds above the
    /// threshold: the inverse real DFT at one row (as the renderer's inverse FFT, which ignores
    /// the imaginary parts of the DC and Nyquist bins), rounded to 8 bits as the renderer does.
    fn selected(&self, y: usize) -> bool {
        let bins = self.spec_re.len();
        let last = bins - 1;
        let row = y * bins;
        let (cos, sin) = (
            &self.cos[row + 1..row + last],
            &self.sin[row + 1..row + last],
        );
        let (re, im) = (&self.spec_re[1..last], &self.spec_im[1..last]);
        // eight partial sums in f32 (two four-lane SIMD registers): the rounding, about 1e-4
        // grey levels for the study's disk, is that of the renderer's own f32 inverse FFT
        let mut acc = [0.0f32; 8];
        let mut chunks = re
            .chunks_exact(8)
            .zip(im.chunks_exact(8))
            .zip(cos.chunks_exact(8).zip(sin.chunks_exact(8)));
        for ((r, i), (c, s)) in chunks.by_ref() {
            for l in 0..8 {
                acc[l] += r[l] * c[l] - i[l] * s[l];
            }
        }
        let n8 = re.len() / 8 * 8;
        for k in n8..re.len() {
            acc[k - n8] += re[k] * cos[k] - im[k] * sin[k];
        }
        let sum = ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7]));
        let v = self.spec_re[0] + 2.0 * sum + self.spec_re[last] * self.cos[row + last];
        above(v, self.config.threshold)
    }

    fn rendered(
        &mut self,
        renderer: &mut BlurRenderer,
        a: f64,
        b: f64,
    ) -> Result<Centroid, FrameError> {
        self.stats.rendered += 1;
        let (w, h) = (self.width, self.height);
        self.frame.resize(w * h, 0);
        renderer.render(a, b, &mut self.frame);
        Frame::new(&self.frame, w, h, w).and_then(|f| centroid(&self.config, &f))
    }
}

/// Whether the renderer's 8-bit quantisation of `v` (round to nearest, clamp) is above `t`.
fn above(v: f32, t: u16) -> bool {
    u16::from((v + 0.5).clamp(0.0, 255.0) as u8) > t
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    const T: u16 = 100;

    // the grandstand target (method.md §3.1)
    use vibcam_model::grandstand::TARGET;

    /// A 1 kHz path of `n` samples: a few random sinusoids (up to `amp` px, 0.5 - 6 Hz) on a
    /// random offset, plus a smoothed impulse-like step, so that slow and fast frames occur.
    fn random_path(rng: &mut ChaCha8Rng, n: usize, amp: f64) -> Vec<f64> {
        let offset = rng.random_range(-3.0..3.0);
        let comps: Vec<(f64, f64, f64)> = (0..3)
            .map(|_| {
                (
                    amp * rng.random::<f64>(),
                    rng.random_range(0.5..6.0),
                    rng.random_range(0.0..std::f64::consts::TAU),
                )
            })
            .collect();
        (0..n)
            .map(|i| {
                let t = i as f64 / 1000.0;
                offset
                    + comps
                        .iter()
                        .map(|(a, f, p)| a * (std::f64::consts::TAU * f * t + p).sin())
                        .sum::<f64>()
            })
            .collect()
    }

    /// Compares the fast path's selected pixels with the rendered frame's, frame by frame.
    /// Returns (frames compared, frames on the fast path, mismatching pixels). Every mismatch
    /// must be a tie: the renderer's float value within `TIE` of the decision level `T + 0.5`
    /// (the `f32` inverse FFT's rounding error, measured below 1e-4 grey levels).
    fn compare(
        target: &DiskTarget,
        renderer: &mut BlurRenderer,
        windows: &[(f64, f64)],
    ) -> (u64, u64, u64, FastStats) {
        const TIE: f32 = 2e-3;
        let mut fast = FastDiskCamera::new(target, renderer, T);
        assert!(fast.enabled());
        let (w, h) = (renderer.width(), renderer.height());
        let mut img = vec![0u8; w * h];
        let mut fimg = vec![0.0f32; w * h];
        let mut mask = vec![false; w * h];
        let mut mismatches = 0;
        let mut on_fast_path = 0;
        let rest_x = renderer.rest_x() as usize;
        let config = CentroidConfig::binary(T);
        for &(a, b) in windows {
            mask.iter_mut().for_each(|m| *m = false);
            let ok = fast.scan(renderer, a, b, |j, y0, y1| {
                for y in y0..=y1 {
                    mask[y as usize * w + rest_x + j] = true;
                    mask[y as usize * w + rest_x - j] = true;
                }
            });
            renderer.render(a, b, &mut img);
            let want = Frame::new(&img, w, h, w)
                .and_then(|f| centroid(&config, &f))
                .unwrap();
            let got = fast.frame(renderer, a, b).unwrap();
            if !ok {
                assert_eq!(got, want, "rendered frame {a}..{b}");
                continue;
            }
            on_fast_path += 1;
            let differ: Vec<usize> = (0..w * h)
                .filter(|&i| mask[i] != (img[i] as u16 > T))
                .collect();
            if differ.is_empty() {
                assert_eq!(got, want, "window {a}..{b}: same pixels, same centroid");
                continue;
            }
            renderer.render_float(a, b, &mut fimg);
            for i in differ {
                let v = fimg[i];
                assert!(
                    (v - (T as f32 + 0.5)).abs() < TIE,
                    "window {a}..{b}: pixel ({}, {}) value {v} selected {} by the fast path",
                    i % w,
                    i / w,
                    mask[i]
                );
                mismatches += 1;
            }
        }
        (windows.len() as u64, on_fast_path, mismatches, fast.stats())
    }

    #[test]
    fn same_pixels_as_the_renderer_over_random_paths_and_exposures() {
        let target = TARGET;
        let mut rng = ChaCha8Rng::seed_from_u64(16);
        let (mut frames, mut fast_frames, mut ties, mut rows, mut columns) = (0, 0, 0, 0, 0);
        for case in 0..12 {
            // slow to fast targets: up to 2 ... 40 px amplitude at up to 6 Hz
            let amp = [2.0, 10.0, 40.0][case % 3];
            let path = random_path(&mut rng, 3000, amp);
            let block = [1, 5, 10, 20][case % 4];
            let mut renderer = BlurRenderer::for_path(&target, &path, block);
            // exposures from a sharp frame to 250 ms, anywhere on the path, fractional ends
            let windows: Vec<(f64, f64)> = (0..150)
                .map(|_| {
                    let e = if rng.random::<f64>() < 0.1 {
                        0.0
                    } else {
                        rng.random_range(0.0..250.0)
                    };
                    let c = rng.random_range(e / 2.0..2999.0 - e / 2.0);
                    (c - e / 2.0, c + e / 2.0)
                })
                .collect();
            let (n, f, m, st) = compare(&target, &mut renderer, &windows);
            frames += n;
            fast_frames += f;
            ties += m;
            rows += st.evaluated;
            columns += st.columns_fft;
        }
        eprintln!(
            "{frames} frames, {ties} tie pixels, {rows} rows evaluated, {columns} columns by FFT"
        );
        // both kinds of uncertain rows occurred: evaluated one by one, and whole columns
        assert!(rows > 0 && columns > 0, "{rows} rows, {columns} columns");
        // for_path sizes the frame to the path, so every frame takes the fast path
        assert_eq!(fast_frames, frames);
        // ties (float value within 2e-3 of the level) are rare: at most one in 200 frames
        assert!(ties * 200 <= frames, "{ties} tie pixels in {frames} frames");
    }

    #[test]
    fn same_pixels_as_the_renderer_with_discrete_epsa_exposures() {
        // the paper's averaging of a few sharp images: the fast path reads the renderer's ramp,
        // so it must agree there too
        let target = TARGET;
        let mut rng = ChaCha8Rng::seed_from_u64(29);
        let (mut frames, mut fast_frames, mut ties) = (0, 0, 0);
        for case in 0..6 {
            let amp = [2.0, 10.0, 40.0][case % 3];
            let path = random_path(&mut rng, 3000, amp);
            let mut renderer = BlurRenderer::for_path(&target, &path, 10);
            renderer.set_epsa_images(Some([2, 3, 5][case % 3]));
            let windows: Vec<(f64, f64)> = (0..150)
                .map(|_| {
                    let e = rng.random_range(0.0..250.0);
                    let c = rng.random_range(e / 2.0..2999.0 - e / 2.0);
                    (c - e / 2.0, c + e / 2.0)
                })
                .collect();
            let (n, f, m, _) = compare(&target, &mut renderer, &windows);
            frames += n;
            fast_frames += f;
            ties += m;
        }
        assert_eq!(fast_frames, frames);
        assert!(ties * 200 <= frames, "{ties} tie pixels in {frames} frames");
    }

    #[test]
    fn frames_near_the_border_are_rendered() {
        let target = TARGET;
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let path = random_path(&mut rng, 2000, 10.0);
        // a frame sized for a smaller range than the path covers: the disk nears the border
        let mut renderer = BlurRenderer::new(&target, -2.0, 2.0);
        renderer.set_path(&path, 10);
        let windows: Vec<(f64, f64)> = (0..60)
            .map(|i| (30.0 * i as f64, 30.0 * i as f64 + 120.0))
            .collect();
        let (n, f, _, _) = compare(&target, &mut renderer, &windows);
        assert!(f < n, "some frames must leave the fast path's domain");
        assert!(f > 0, "and some stay in it");
    }

    #[test]
    fn other_targets_and_thresholds_match_too() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for (radius, level, sigma, t) in [(6.0, 180.0, 1.0, 60u16), (20.0, 240.0, 2.5, 200)] {
            let target = DiskTarget {
                radius_px: radius,
                level,
                edge_sigma_px: sigma,
                texture: vibcam_model::Texture::Plain,
            };
            let path = random_path(&mut rng, 2000, 15.0);
            let mut renderer = BlurRenderer::for_path(&target, &path, 10);
            let mut fast = FastDiskCamera::new(&target, &renderer, t);
            assert!(fast.enabled(), "target {target:?}");
            let (w, h) = (renderer.width(), renderer.height());
            let mut img = vec![0u8; w * h];
            let config = CentroidConfig::binary(t);
            let mut same = 0;
            for i in 0..100 {
                let (a, b) = (15.0 * i as f64 + 100.0, 15.0 * i as f64 + 100.0 + i as f64);
                renderer.render(a, b, &mut img);
                let want = Frame::new(&img, w, h, w)
                    .and_then(|f| centroid(&config, &f))
                    .unwrap();
                let got = fast.frame(&mut renderer, a, b).unwrap();
                // a tie (see above) moves the centroid by one pixel's share
                if got == want {
                    same += 1;
                } else {
                    assert!(
                        (got.cy - want.cy).abs() < 0.05
                            && got.pixels().abs_diff(want.pixels()) <= 2
                    );
                }
            }
            assert!(same >= 99, "{same} of 100 frames identical");
        }
    }

    #[test]
    fn interpolant_stays_within_a_quarter_margin_of_the_analytic_disk() {
        // the premise of the certain rows: the band-limited interpolant of the sharp columns
        // is within MARGIN / 4 of the analytic profile everywhere, here on a 1/16 px grid
        let target = TARGET;
        let renderer = BlurRenderer::new(&target, -20.0, 20.0);
        let h = renderer.height();
        let rest = renderer.rest_y();
        let mut worst = 0.0f64;
        for j in 0..=13 {
            let spec = renderer.column_spectrum(j);
            for i in 0..h * 16 {
                // offset s from the centre, frame row rest + s
                let s = i as f64 / 16.0 - h as f64 / 2.0;
                let mut v = spec[0].re as f64;
                for (k, c) in spec.iter().enumerate().skip(1) {
                    let ph = std::f64::consts::TAU * k as f64 * (rest + s) / h as f64;
                    let term = if 2 * k == h {
                        c.re as f64 * ph.cos()
                    } else {
                        2.0 * (c.re as f64 * ph.cos() - c.im as f64 * ph.sin())
                    };
                    v += term;
                }
                let want = target.profile(((j * j) as f64 + s * s).sqrt());
                worst = worst.max((v / h as f64 - want).abs());
            }
        }
        assert!(worst < MARGIN / 4.0, "interpolation error {worst}");
        // and it is far smaller: the margin is generous
        assert!(worst < 0.01, "interpolation error {worst}");
    }
}
