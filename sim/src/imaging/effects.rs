//! Optional image-formation effects of method.md §3.1, applied to the float frame after the EPSA
//! blur and before quantisation, each off by default: contrast gain, quadratic/cubic radial lens
//! distortion (resampling), optical blur (Gaussian filter), sensor noise (shot + read) and the
//! quantisation bit depth (8, 12 or 16 bits).
//!
//! Order (as light goes through a camera): lens distortion, optical blur, gain, shot noise,
//! read noise, quantisation. Grey levels are on the 8-bit scale until quantisation, which maps
//! level `v` to code `round(v * (2^bits - 1) / 255)`; the binary threshold is scaled the same
//! way, so the same scene gives the same centroid at any bit depth without noise.

use super::render::BlurRenderer;
use super::tracker::FrameTracker;
use super::ImagingOptions;
use firmware_core::centroid::FrameError;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, StandardNormal};

/// One simulated camera: EPSA exposure of a [`BlurRenderer`] path, the [`Effects`] and the
/// firmware's measurement ([`FrameTracker`]: a centroid or Lucas-Kanade), with its frame
/// buffers reused between frames. Identity effects give 8-bit frames (and the binary centroid
/// of a plain disk the fast path); otherwise the float frame goes through [`Effects::apply`]
/// and [`Effects::quantise`] to codes of the bit depth, the threshold scaled alike.
#[derive(Debug)]
pub struct Camera {
    effects: Effects,
    measurement: Measurement,
    tracker: FrameTracker,
    plain: bool,
    w: usize,
    h: usize,
    frame: Vec<u8>,
    fimg: Vec<f32>,
    frame16: Vec<u16>,
    scratch: Vec<f32>,
    /// Seed of the noise streams (one per exposure); 0 and unused for identity effects.
    noise_seed: u64,
    noise: rand_chacha::ChaCha8Rng,
    /// The fast binary-centroid path (identity effects only), when enabled.
    fast: Option<super::fastpath::FastDiskCamera>,
}

impl Camera {
    /// A `w x h` camera looking at `target` with `effects`, measuring with `measurement` at the
    /// threshold `threshold` on the 8-bit scale. With effects, the seed of its noise streams
    /// is drawn from `rng` (nothing is drawn otherwise, so the identity camera leaves a run's
    /// stream as it was). Refused when the tracker cannot hold the target's window.
    pub fn new(
        effects: &Effects,
        measurement: &Measurement,
        (target, threshold): (&super::DiskTarget, u16),
        w: usize,
        h: usize,
        rng: &mut impl Rng,
    ) -> anyhow::Result<Camera> {
        let plain = effects.is_identity();
        let noise_seed: u64 = if plain { 0 } else { rng.random() };
        let tracker = FrameTracker::new(
            measurement.tracker,
            if plain {
                threshold
            } else {
                effects.threshold(threshold)
            },
            measurement.frame_range_frac,
            target,
            effects.full_scale() as u16,
        )?;
        let (fimg, frame16) = if plain {
            (Vec::new(), Vec::new())
        } else {
            (vec![0.0f32; w * h], vec![0u16; w * h])
        };
        Ok(Camera {
            effects: effects.clone(),
            measurement: *measurement,
            tracker,
            plain,
            w,
            h,
            frame: if plain { vec![0u8; w * h] } else { Vec::new() },
            fimg,
            frame16,
            scratch: Vec::new(),
            noise_seed,
            noise: rand_chacha::ChaCha8Rng::seed_from_u64(noise_seed),
            fast: None,
        })
    }

    /// Uses the fast path ([`super::fastpath::FastDiskCamera`]: the binary centroid of the EPSA
    /// frame computed from the rows that matter, the same pixels as rendering the frame) for
    /// `target` seen by `renderer`, when the effects are the identity and the firmware takes
    /// the binary centroid at a fixed threshold; otherwise nothing changes.
    pub fn use_fast_path(
        &mut self,
        target: &super::DiskTarget,
        threshold: u16,
        renderer: &BlurRenderer,
    ) {
        if self.plain
            && self.measurement.fast_path
            && self.measurement.frame_range_frac.is_none()
            && self.measurement.tracker == super::TrackerKind::Blob
        {
            self.fast = Some(super::fastpath::FastDiskCamera::new(
                target, renderer, threshold,
            ));
        }
    }

    /// Starts exposure `index`'s record, whose longest blur is `blur_px` (the largest path
    /// range within one exposure; only LK's window uses it): every exposure of a run gets its
    /// own stream of the run's noise seed, so the exposures do not depend on each other's
    /// draws, and the tracker starts afresh (LK's template is the record's first frame).
    pub fn start_exposure(&mut self, index: usize, blur_px: f64) -> anyhow::Result<()> {
        self.noise = rand_chacha::ChaCha8Rng::seed_from_u64(self.noise_seed);
        self.noise.set_stream(index as u64);
        self.tracker.restart(blur_px)
    }

    /// Exposes the path from `a` to `b` (renderer steps), applies the effects (noise from the
    /// current exposure's stream) and measures the frame: the target's position `(x, y)`, px,
    /// `None` when it is lost.
    pub fn frame(
        &mut self,
        renderer: &mut BlurRenderer,
        a: f64,
        b: f64,
    ) -> Result<Option<(f32, f32)>, FrameError> {
        let (w, h) = (self.w, self.h);
        if let Some(fast) = &mut self.fast {
            return Ok(fast.frame(renderer, a, b)?.position());
        }
        if self.plain {
            renderer.render(a, b, &mut self.frame);
            self.tracker.measure(&self.frame, w, h)
        } else {
            renderer.render_float(a, b, &mut self.fimg);
            self.effects
                .apply(&mut self.fimg, w, h, &mut self.noise, &mut self.scratch);
            self.effects.quantise(&self.fimg, &mut self.frame16);
            self.tracker.measure(&self.frame16, w, h)
        }
    }
}

/// How the firmware measures a frame (the `[imaging]` fields that are not an effect on the
/// image): which centroid, whether the identity camera may take the fast path (the same
/// pixels either way), and the threshold rule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement {
    /// What the firmware measures in each frame.
    pub tracker: super::TrackerKind,
    /// Whether identity effects with the binary centroid take the fast path.
    pub fast_path: bool,
    /// With [`super::ThresholdRule::FrameRange`], the fraction of each frame's grey-level range
    /// the threshold sits at; `None`: the fixed threshold.
    pub frame_range_frac: Option<f64>,
}

impl Measurement {
    /// Resolves and checks the options; the message names the field.
    pub fn from_options(o: &ImagingOptions) -> anyhow::Result<Measurement> {
        let tracker = match (o.tracker, o.centroid.map(super::CentroidKind::tracker)) {
            (Some(t), Some(c)) if t != c => {
                return Err(vibcam_readers::bad_input(format!(
                    "imaging.tracker = \"{}\" and imaging.centroid = \"{}\" disagree: give \
                     tracker alone (centroid is its older name)",
                    t.name(),
                    c.name()
                )))
            }
            (t, c) => t.or(c).unwrap_or_default().without_points(),
        };
        let m = Measurement {
            tracker,
            fast_path: o.fast_path.unwrap_or(true),
            frame_range_frac: match o.threshold_rule.unwrap_or_default() {
                super::ThresholdRule::Fixed => None,
                super::ThresholdRule::FrameRange => Some(o.threshold_frac.unwrap_or(0.5)),
            },
        };
        if let Some(f) = m.frame_range_frac {
            if !(f.is_finite() && f > 0.0 && f < 1.0) {
                return Err(vibcam_readers::bad_input(
                    "imaging.threshold_frac: must be a fraction in (0, 1)",
                ));
            }
        }
        Ok(m)
    }
}

impl Default for Measurement {
    /// The binary centroid at a fixed threshold, fast path allowed.
    fn default() -> Measurement {
        Measurement {
            tracker: super::TrackerKind::default(),
            fast_path: true,
            frame_range_frac: None,
        }
    }
}

/// The resolved image effects (identity when built from default options).
#[derive(Debug, Clone, PartialEq)]
pub struct Effects {
    /// Contrast gain (1 = none).
    pub gain: f64,
    /// Radial distortion: a pixel at radius `r` (px from the frame centre) shows the scene at
    /// radius `r (1 + k1 r^2 + k2 r^3)`.
    pub k1: f64,
    /// Cubic radial distortion coefficient.
    pub k2: f64,
    /// Optical blur sigma, px (0 = none).
    pub blur_sigma: f64,
    /// Read noise std, grey levels (8-bit scale).
    pub read_noise: f64,
    /// Electrons per grey level for shot noise (0 = no shot noise).
    pub shot_e_per_level: f64,
    /// Quantisation bits (8, 12 or 16).
    pub bits: u32,
}

impl Effects {
    /// Resolves and checks the options; the message names the field.
    pub fn from_options(o: &ImagingOptions) -> anyhow::Result<Effects> {
        let e = Effects {
            gain: o.gain.unwrap_or(1.0),
            k1: o.distortion_k1.unwrap_or(0.0),
            k2: o.distortion_k2.unwrap_or(0.0),
            blur_sigma: o.optical_blur_sigma_px.unwrap_or(0.0),
            read_noise: o.read_noise.unwrap_or(0.0),
            shot_e_per_level: o.shot_noise_e_per_level.unwrap_or(0.0),
            bits: o.bits.unwrap_or(8),
        };
        let bad = |f: &str, why: &str| vibcam_readers::bad_input(format!("imaging.{f}: {why}"));
        if !(e.gain.is_finite() && e.gain > 0.0) {
            return Err(bad("gain", "must be a positive number"));
        }
        if !(e.k1.is_finite() && e.k2.is_finite()) {
            return Err(bad("distortion_k1/k2", "must be finite"));
        }
        if !(e.blur_sigma.is_finite() && e.blur_sigma >= 0.0) {
            return Err(bad("optical_blur_sigma_px", "must be >= 0"));
        }
        if !(e.read_noise.is_finite() && e.read_noise >= 0.0) {
            return Err(bad("read_noise", "must be >= 0"));
        }
        if !(e.shot_e_per_level.is_finite() && e.shot_e_per_level >= 0.0) {
            return Err(bad("shot_noise_e_per_level", "must be >= 0"));
        }
        if ![8, 12, 16].contains(&e.bits) {
            return Err(bad("bits", "must be 8, 12 or 16"));
        }
        Ok(e)
    }

    /// True when nothing but 8-bit quantisation happens.
    pub fn is_identity(&self) -> bool {
        self.gain == 1.0
            && self.k1 == 0.0
            && self.k2 == 0.0
            && self.blur_sigma == 0.0
            && self.read_noise == 0.0
            && self.shot_e_per_level == 0.0
            && self.bits == 8
    }

    /// Largest code of the bit depth.
    pub fn full_scale(&self) -> f64 {
        ((1u32 << self.bits) - 1) as f64
    }

    /// The 8-bit-scale threshold `t` expressed in codes of this bit depth.
    pub fn threshold(&self, t: u16) -> u16 {
        (t as f64 * self.full_scale() / 255.0).round() as u16
    }

    /// Applies distortion, blur, gain and noise to `img` (`w * h`, row-major, 8-bit scale) in
    /// place; `scratch` is reused between calls.
    pub fn apply(
        &self,
        img: &mut [f32],
        w: usize,
        h: usize,
        rng: &mut impl Rng,
        scratch: &mut Vec<f32>,
    ) {
        if self.k1 != 0.0 || self.k2 != 0.0 {
            scratch.clear();
            scratch.extend_from_slice(img);
            let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
            for y in 0..h {
                for x in 0..w {
                    let (dx, dy) = (x as f64 - cx, y as f64 - cy);
                    let r = (dx * dx + dy * dy).sqrt();
                    let s = 1.0 + self.k1 * r * r + self.k2 * r * r * r;
                    img[y * w + x] = bilinear(scratch, w, h, cx + dx * s, cy + dy * s);
                }
            }
        }
        if self.blur_sigma > 0.0 {
            gaussian_blur(img, w, h, self.blur_sigma, scratch);
        }
        if self.gain != 1.0 {
            for v in img.iter_mut() {
                *v *= self.gain as f32;
            }
        }
        if self.shot_e_per_level > 0.0 || self.read_noise > 0.0 {
            for v in img.iter_mut() {
                let mut val = *v as f64;
                if self.shot_e_per_level > 0.0 && val > 0.0 {
                    // Poisson photo-electrons, normal approximation (std = sqrt(mean))
                    let e = val * self.shot_e_per_level;
                    let z: f64 = StandardNormal.sample(rng);
                    val = (e + e.sqrt() * z) / self.shot_e_per_level;
                }
                if self.read_noise > 0.0 {
                    let z: f64 = StandardNormal.sample(rng);
                    val += self.read_noise * z;
                }
                *v = val as f32;
            }
        }
    }

    /// Quantises the 8-bit-scale image to codes of the bit depth (round, clamp).
    pub fn quantise(&self, img: &[f32], out: &mut [u16]) {
        let k = (self.full_scale() / 255.0) as f32;
        let fs = self.full_scale() as f32;
        for (o, v) in out.iter_mut().zip(img) {
            *o = (v * k + 0.5).clamp(0.0, fs) as u16;
        }
    }
}

fn bilinear(img: &[f32], w: usize, h: usize, x: f64, y: f64) -> f32 {
    if !(x >= 0.0 && y >= 0.0 && x <= (w - 1) as f64 && y <= (h - 1) as f64) {
        return 0.0;
    }
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = ((x - x0 as f64) as f32, (y - y0 as f64) as f32);
    let p = |xx: usize, yy: usize| img[yy * w + xx];
    p(x0, y0) * (1.0 - fx) * (1.0 - fy)
        + p(x1, y0) * fx * (1.0 - fy)
        + p(x0, y1) * (1.0 - fx) * fy
        + p(x1, y1) * fx * fy
}

/// Separable Gaussian filter (kernel radius ceil(4 sigma), normalised, zero outside).
fn gaussian_blur(img: &mut [f32], w: usize, h: usize, sigma: f64, scratch: &mut Vec<f32>) {
    let r = (4.0 * sigma).ceil() as isize;
    let kernel: Vec<f32> = (-r..=r)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp() as f32)
        .collect();
    let sum: f32 = kernel.iter().sum();
    let kernel: Vec<f32> = kernel.iter().map(|k| k / sum).collect();
    scratch.clear();
    scratch.resize(img.len(), 0.0);
    // rows into scratch, columns back into img
    convolve_1d(img, scratch, w, h, &kernel, true);
    convolve_1d(scratch, img, w, h, &kernel, false);
}

/// One pass of a separable filter: `dst` = `src` convolved with `kernel` (odd length, centred)
/// along the rows (`along_rows`) or the columns of the `w` x `h` image, zero outside.
fn convolve_1d(src: &[f32], dst: &mut [f32], w: usize, h: usize, kernel: &[f32], along_rows: bool) {
    let r = (kernel.len() / 2) as isize;
    // length of the filtered line and the step between its pixels
    let (n, step) = if along_rows { (w, 1) } else { (h, w) };
    for y in 0..h {
        for x in 0..w {
            let i = if along_rows { x } else { y };
            let line_start = y * w + x - i * step;
            let mut acc = 0.0;
            for (j, k) in kernel.iter().enumerate() {
                let ii = i as isize + j as isize - r;
                if ii >= 0 && (ii as usize) < n {
                    acc += k * src[line_start + ii as usize * step];
                }
            }
            dst[y * w + x] = acc;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn effects(f: impl FnOnce(&mut ImagingOptions)) -> Effects {
        let mut o = ImagingOptions::default();
        f(&mut o);
        Effects::from_options(&o).unwrap()
    }

    /// Applies the effects that `f` sets to the `w` x `h` image `img`.
    fn apply(
        f: impl FnOnce(&mut ImagingOptions),
        img: &mut [f32],
        (w, h): (usize, usize),
        rng: &mut ChaCha8Rng,
    ) {
        effects(f).apply(img, w, h, rng, &mut Vec::new());
    }

    /// A 3x3 bright square at (cx, cy) in a w x h frame.
    fn square(w: usize, h: usize, cx: usize, cy: usize) -> Vec<f32> {
        let mut img = vec![0.0f32; w * h];
        for y in cy - 1..=cy + 1 {
            for x in cx - 1..=cx + 1 {
                img[y * w + x] = 200.0;
            }
        }
        img
    }

    fn moments(img: &[f32], w: usize) -> (f64, f64, f64) {
        let (mut s, mut sx, mut sy) = (0.0, 0.0, 0.0);
        for (i, v) in img.iter().enumerate() {
            s += *v as f64;
            sx += *v as f64 * (i % w) as f64;
            sy += *v as f64 * (i / w) as f64;
        }
        (s, sx / s, sy / s)
    }

    #[test]
    fn defaults_are_the_identity_and_bad_values_name_the_field() {
        assert!(effects(|_| {}).is_identity());
        let e = Effects::from_options(&ImagingOptions {
            bits: Some(10),
            ..Default::default()
        })
        .unwrap_err();
        assert!(format!("{e}").contains("imaging.bits"));
    }

    #[test]
    fn gain_scales_the_light() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut img = square(20, 20, 10, 10);
        apply(|o| o.gain = Some(1.5), &mut img, (20, 20), &mut rng);
        assert_eq!(img[10 * 20 + 10], 300.0);
    }

    #[test]
    fn optical_blur_keeps_light_and_centroid_and_spreads_it() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut img = square(30, 30, 15, 14);
        let before = moments(&img, 30);
        apply(
            |o| o.optical_blur_sigma_px = Some(1.2),
            &mut img,
            (30, 30),
            &mut rng,
        );
        let after = moments(&img, 30);
        assert!((after.0 / before.0 - 1.0).abs() < 1e-5);
        assert!((after.1 - before.1).abs() < 1e-4 && (after.2 - before.2).abs() < 1e-4);
        assert!(img[14 * 30 + 15] < 200.0 && img[14 * 30 + 18] > 1.0);
    }

    #[test]
    fn radial_distortion_moves_an_off_centre_target_by_the_model() {
        // frame centre (20, 20); target at x = 30 (r = 10). With k1 the pixel at radius r shows
        // the scene at r (1 + k1 r^2), so the target appears at r' with r' (1 + k1 r'^2) = 10.
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let k1 = 1e-3;
        let mut img = square(41, 41, 30, 20);
        apply(|o| o.distortion_k1 = Some(k1), &mut img, (41, 41), &mut rng);
        let (_, cx, cy) = moments(&img, 41);
        // solve r' + k1 r'^3 = 10 by Newton
        let mut r = 10.0f64;
        for _ in 0..20 {
            r -= (r + k1 * r * r * r - 10.0) / (1.0 + 3.0 * k1 * r * r);
        }
        assert!(
            (cx - 20.0 - r).abs() < 0.05,
            "target at {cx}, model {}",
            20.0 + r
        );
        assert!((cy - 20.0).abs() < 1e-6);
    }

    #[test]
    fn sensor_noise_has_the_stated_statistics() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let n = 40_000;
        // read noise on black
        let mut img = vec![0.0f32; n];
        apply(|o| o.read_noise = Some(2.0), &mut img, (200, 200), &mut rng);
        let var = img.iter().map(|v| (*v as f64).powi(2)).sum::<f64>() / n as f64;
        assert!(
            (var.sqrt() / 2.0 - 1.0).abs() < 0.02,
            "read noise std {}",
            var.sqrt()
        );
        // shot noise on a flat 100-level field with 10 e-/level: std = sqrt(1000)/10 levels
        let mut img = vec![100.0f32; n];
        apply(
            |o| o.shot_noise_e_per_level = Some(10.0),
            &mut img,
            (200, 200),
            &mut rng,
        );
        let mean = img.iter().map(|v| *v as f64).sum::<f64>() / n as f64;
        let sd = (img.iter().map(|v| (*v as f64 - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
        let want = 1000f64.sqrt() / 10.0;
        assert!(
            (mean - 100.0).abs() < 0.1 && (sd / want - 1.0).abs() < 0.02,
            "{mean} {sd}"
        );
    }

    #[test]
    fn quantisation_uses_the_bit_depth() {
        let e = effects(|o| o.bits = Some(12));
        let mut out = [0u16; 3];
        e.quantise(&[0.0, 200.0, 300.0], &mut out);
        assert_eq!(out, [0, (200.0f64 * 4095.0 / 255.0).round() as u16, 4095]);
        assert_eq!(e.threshold(100), 1606);
        let e8 = effects(|_| {});
        e8.quantise(&[99.4, 99.6, 255.0], &mut out);
        assert_eq!(out, [99, 100, 255]);
    }

    /// A small target smeared over a path much longer than itself: its peak falls to about
    /// 200 * 6 / 40 = 30 grey levels, below a fixed threshold at half the level (the frame is
    /// lost), while a threshold at half of each frame's range keeps it and centres it on the
    /// path. Both with and without sensor effects (8- and 16-bit frames).
    #[test]
    fn a_frame_range_threshold_keeps_a_smeared_target_a_fixed_one_loses() {
        use super::super::{DiskTarget, ThresholdRule};
        let target = DiskTarget {
            radius_px: 3.0,
            level: 200.0,
            edge_sigma_px: 0.7,
            texture: vibcam_model::Texture::Plain,
        };
        let path: Vec<f64> = (0..=400).map(|i| i as f64 * 0.1).collect();
        let mut renderer = BlurRenderer::for_path(&target, &path, 1);
        let (w, h, rest_y) = (renderer.width(), renderer.height(), renderer.rest_y());
        for bits in [8, 12] {
            let mut rng = ChaCha8Rng::seed_from_u64(1);
            let fixed = effects(|o| o.bits = Some(bits));
            let fixed_rule = Measurement::default();
            let mut camera =
                Camera::new(&fixed, &fixed_rule, (&target, 100), w, h, &mut rng).unwrap();
            let c = camera.frame(&mut renderer, 0.0, 400.0).unwrap();
            assert!(c.is_none(), "{bits} bits: {c:?}");
            let range_options = ImagingOptions {
                bits: Some(bits),
                threshold_rule: Some(ThresholdRule::FrameRange),
                ..ImagingOptions::default()
            };
            let range = Effects::from_options(&range_options).unwrap();
            let range_rule = Measurement::from_options(&range_options).unwrap();
            assert_eq!(range.is_identity(), bits == 8);
            let mut camera =
                Camera::new(&range, &range_rule, (&target, 100), w, h, &mut rng).unwrap();
            camera.use_fast_path(&target, 100, &renderer);
            let c = camera.frame(&mut renderer, 0.0, 400.0).unwrap();
            let Some((_, cy)) = c else {
                panic!("{bits} bits: lost")
            };
            let y = cy as f64 - rest_y;
            assert!(
                (y - 20.0).abs() < 0.5,
                "{bits} bits: centroid {y} px, path middle 20"
            );
            // a short exposure sees the whole target: range 0..200, the same threshold of 100
            // as the fixed rule and the same centroid
            let short = camera.frame(&mut renderer, 0.0, 1.0).unwrap();
            let mut camera =
                Camera::new(&fixed, &fixed_rule, (&target, 100), w, h, &mut rng).unwrap();
            assert_eq!(short, camera.frame(&mut renderer, 0.0, 1.0).unwrap());
        }
        let bad = Measurement::from_options(&ImagingOptions {
            threshold_rule: Some(ThresholdRule::FrameRange),
            threshold_frac: Some(1.5),
            ..ImagingOptions::default()
        });
        assert!(bad.unwrap_err().to_string().contains("threshold_frac"));
    }
}
