//! Fast motion-blurred frames of a disk target moving along the image `y` axis, by EPSA (exact
//! phase shift and averaging, SPEC 3.1) made separable.
//!
//! The target moves vertically only, so translating the reference image by `d` pixels is, for
//! every column, multiplying the column's 1-D DFT along `y` by `exp(-2 pi i k d / H)`; and the
//! blurred frame, the average of the translated images over the exposure, is every column's
//! spectrum times the averaged ramp
//!
//! ```text
//! A[k] = (1/T) integral over the exposure of exp(-2 pi i k d(t) / H) dt .
//! ```
//!
//! The path `d(t)` is taken piecewise linear between the fine simulation steps, so each segment
//! contributes exactly `w_s exp(-i w_k m_s) sinc(w_k D_s / 2)` (midpoint `m_s`, length `D_s`,
//! `w_k = 2 pi k / H`): the blur is exact for that path, however fast the motion. Powers of
//! `exp(-i w_1 m_s)` and `exp(i w_1 D_s / 2)` are built by recurrence over `k`, vectorised over
//! the segments. Per frame: one `A` (segments x bins), one inverse real FFT per target column
//! (half of them: the disk is symmetric about its centre column), 8-bit quantisation.
//! Nothing allocates per frame.
//!
//! The reference image is the disk of radius `R` and level `L` with its edge smoothed by a
//! Gaussian of `sigma`: `I(r) = L erfc((r - R) / (sigma sqrt 2)) / 2`, the radial error-function
//! profile (the exact 2-D convolution differs from it by a curvature term of order
//! `sigma^2 / (2 R)`, 0.09 px at R = 12, sigma = 1.5, which shifts the edge symmetrically and no
//! centroid). Its spectrum falls as `exp(-(2 pi f sigma)^2 / 2)`, 1.5e-5 of the DC at the
//! Nyquist frequency: band-limited, so the phase-shift translation is exact.

use num_complex::Complex32;
use realfft::{ComplexToReal, RealFftPlanner};
use std::sync::Arc;

/// A bright disk with a Gaussian-smoothed edge on a black background.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiskTarget {
    /// Disk radius, px.
    pub radius_px: f64,
    /// Grey level of the disk (8-bit scale).
    pub level: f64,
    /// Gaussian sigma of the edge, px.
    pub edge_sigma_px: f64,
}

impl DiskTarget {
    /// Grey level at distance `r` (px) from the centre.
    pub fn profile(&self, r: f64) -> f64 {
        self.level * 0.5 * libm::erfc((r - self.radius_px) / (self.edge_sigma_px * 2f64.sqrt()))
    }

    /// Half-extent (px) beyond which the profile is below 1e-6 of the level.
    pub fn extent(&self) -> f64 {
        self.radius_px + 7.0 * self.edge_sigma_px
    }
}

/// Renders motion-blurred 8-bit frames of a [`DiskTarget`] moving along `y`.
pub struct BlurRenderer {
    width: usize,
    height: usize,
    rest_x: usize,
    rest_y: f64,
    /// Columns `rest_x - half_cols ..= rest_x + half_cols` hold the target.
    half_cols: usize,
    /// Reference column spectra for columns `rest_x + j`, `j = 0 ..= half_cols` (bins 0..=H/2).
    spectra: Vec<Vec<Complex32>>,
    ifft: Arc<dyn ComplexToReal<f32>>,
    // per-frame work buffers
    ramp: Vec<Complex32>,
    spec: Vec<Complex32>,
    column: Vec<f32>,
    scratch: Vec<Complex32>,
    seg: Segments,
}

impl std::fmt::Debug for BlurRenderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BlurRenderer")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("rest_y", &self.rest_y)
            .finish()
    }
}

/// Segment coefficients, structure of arrays for vectorisation.
#[derive(Debug, Default)]
struct Segments {
    /// weight / theta
    c: Vec<f32>,
    zr: Vec<f32>,
    zi: Vec<f32>,
    rr: Vec<f32>,
    ri: Vec<f32>,
    // running powers
    pzr: Vec<f32>,
    pzi: Vec<f32>,
    prr: Vec<f32>,
    pri: Vec<f32>,
}

impl Segments {
    fn clear(&mut self) {
        for v in [
            &mut self.c,
            &mut self.zr,
            &mut self.zi,
            &mut self.rr,
            &mut self.ri,
        ] {
            v.clear();
        }
    }

    fn push(&mut self, weight: f64, mid: f64, delta: f64, h: f64) {
        let tau = std::f64::consts::TAU;
        let mut theta = std::f64::consts::PI * delta / h;
        if theta.abs() < 1e-7 {
            theta = if theta < 0.0 { -1e-7 } else { 1e-7 };
        }
        let (zs, zc) = (-tau * mid / h).sin_cos();
        let (rs, rc) = theta.sin_cos();
        self.c.push((weight / theta) as f32);
        self.zr.push(zc as f32);
        self.zi.push(zs as f32);
        self.rr.push(rc as f32);
        self.ri.push(rs as f32);
    }
}

impl BlurRenderer {
    /// A renderer whose frame holds the target anywhere in the displacement range
    /// `lo ..= hi` (px, positive down) with a margin, so the blurred target never touches the
    /// border. The frame width is fixed by the target; the height by the range.
    pub fn new(target: &DiskTarget, lo: f64, hi: f64) -> BlurRenderer {
        let ext = target.extent();
        let half_cols = ext.ceil() as usize;
        let width = 2 * half_cols + 5;
        let rest_x = half_cols + 2;
        let pad = ext.ceil() + 3.0;
        let span = (hi - lo).max(0.0);
        let height = (((span + 2.0 * pad) / 16.0).ceil() as usize * 16).max(32);
        let rest_y = (pad - lo).round();
        let mut planner = RealFftPlanner::<f32>::new();
        let fwd = planner.plan_fft_forward(height);
        let ifft = planner.plan_fft_inverse(height);
        let bins = height / 2 + 1;
        let mut spectra = Vec::with_capacity(half_cols + 1);
        let mut col = vec![0.0f32; height];
        for j in 0..=half_cols {
            let dx = j as f64;
            for (y, v) in col.iter_mut().enumerate() {
                let dy = y as f64 - rest_y;
                *v = target.profile((dx * dx + dy * dy).sqrt()) as f32;
            }
            let mut s = vec![Complex32::new(0.0, 0.0); bins];
            let mut input = col.clone();
            fwd.process(&mut input, &mut s)
                .expect("buffer sizes from the same plan");
            spectra.push(s);
        }
        let scratch = vec![Complex32::new(0.0, 0.0); ifft.get_scratch_len()];
        BlurRenderer {
            width,
            height,
            rest_x,
            rest_y,
            half_cols,
            spectra,
            ifft,
            ramp: vec![Complex32::new(0.0, 0.0); bins],
            spec: vec![Complex32::new(0.0, 0.0); bins],
            column: vec![0.0; height],
            scratch,
            seg: Segments::default(),
        }
    }

    /// Frame width, px.
    pub fn width(&self) -> usize {
        self.width
    }
    /// Frame height, px.
    pub fn height(&self) -> usize {
        self.height
    }
    /// Row of the target centre at zero displacement.
    pub fn rest_y(&self) -> f64 {
        self.rest_y
    }
    /// Column of the target centre.
    pub fn rest_x(&self) -> f64 {
        self.rest_x as f64
    }

    /// Renders the frame exposed from fractional index `a` to `b` of `path` (displacements in
    /// px at equally spaced instants, linearly interpolated between them) into `out`
    /// (`width * height`, row-major, 8-bit, rounded to nearest and clamped). `a == b` gives a
    /// sharp frame.
    pub fn render(&mut self, path: &[f64], a: f64, b: f64, out: &mut [u8]) {
        self.averaged_ramp(path, a, b);
        self.synthesize(out);
    }

    /// Renders the float image (before quantisation) into `out` (`width * height`).
    pub fn render_float(&mut self, path: &[f64], a: f64, b: f64, out: &mut [f32]) {
        self.averaged_ramp(path, a, b);
        for v in out.iter_mut() {
            *v = 0.0;
        }
        let w = self.width;
        self.columns(|x, col| {
            for (y, v) in col.iter().enumerate() {
                out[y * w + x] = *v;
            }
        });
    }

    fn synthesize(&mut self, out: &mut [u8]) {
        let w = self.width;
        self.columns(|x, col| {
            for (y, v) in col.iter().enumerate() {
                out[y * w + x] = (v + 0.5).clamp(0.0, 255.0) as u8;
            }
        });
    }

    /// Inverse-transforms every target column (spectrum x ramp) and hands it to `put` for both
    /// mirror columns.
    fn columns(&mut self, mut put: impl FnMut(usize, &[f32])) {
        let scale = 1.0 / self.height as f32;
        let last = self.spec.len() - 1;
        for j in 0..=self.half_cols {
            for ((s, r), f) in self.spec.iter_mut().zip(&self.ramp).zip(&self.spectra[j]) {
                *s = f * r * scale;
            }
            self.spec[0].im = 0.0;
            if self.height % 2 == 0 {
                self.spec[last].im = 0.0;
            }
            // sizes come from the same plan, so this cannot fail
            let _ =
                self.ifft
                    .process_with_scratch(&mut self.spec, &mut self.column, &mut self.scratch);
            put(self.rest_x + j, &self.column);
            if j > 0 {
                put(self.rest_x - j, &self.column);
            }
        }
    }

    /// A[k] for k = 0 ..= H/2 from the path between fractional indices a and b.
    fn averaged_ramp(&mut self, path: &[f64], a: f64, b: f64) {
        let h = self.height as f64;
        let at = |t: f64| -> f64 {
            let i = t.floor().clamp(0.0, (path.len() - 1) as f64) as usize;
            let j = (i + 1).min(path.len() - 1);
            let f = (t - i as f64).clamp(0.0, 1.0);
            path[i] * (1.0 - f) + path[j] * f
        };
        self.seg.clear();
        if b <= a {
            self.seg.push(1.0, at(a), 0.0, h);
        } else {
            let total = b - a;
            let mut t = a;
            while t < b {
                let next = (t.floor() + 1.0).min(b);
                let (da, db) = (at(t), at(next));
                self.seg
                    .push((next - t) / total, 0.5 * (da + db), db - da, h);
                t = next;
            }
        }
        let s = &mut self.seg;
        let n = s.c.len();
        s.pzr.clear();
        s.pzr.resize(n, 1.0);
        s.pzi.clear();
        s.pzi.resize(n, 0.0);
        s.prr.clear();
        s.prr.resize(n, 1.0);
        s.pri.clear();
        s.pri.resize(n, 0.0);
        self.ramp[0] = Complex32::new(1.0, 0.0);
        for k in 1..self.ramp.len() {
            let (mut re, mut im) = (0.0f32, 0.0f32);
            for i in 0..n {
                let (zr, zi) = (
                    s.pzr[i] * s.zr[i] - s.pzi[i] * s.zi[i],
                    s.pzr[i] * s.zi[i] + s.pzi[i] * s.zr[i],
                );
                let (rr, ri) = (
                    s.prr[i] * s.rr[i] - s.pri[i] * s.ri[i],
                    s.prr[i] * s.ri[i] + s.pri[i] * s.rr[i],
                );
                s.pzr[i] = zr;
                s.pzi[i] = zi;
                s.prr[i] = rr;
                s.pri[i] = ri;
                let c = s.c[i] * ri;
                re += c * zr;
                im += c * zi;
            }
            let kk = 1.0 / k as f32;
            self.ramp[k] = Complex32::new(re * kk, im * kk);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn target() -> DiskTarget {
        DiskTarget {
            radius_px: 12.0,
            level: 200.0,
            edge_sigma_px: 1.5,
        }
    }

    /// Weighted centroid (threshold 0) of a float image, naive double loop.
    fn weighted_cy(img: &[f32], w: usize) -> f64 {
        let (mut s, mut sy) = (0.0f64, 0.0f64);
        for (i, v) in img.iter().enumerate() {
            s += *v as f64;
            sy += *v as f64 * (i / w) as f64;
        }
        sy / s
    }

    #[test]
    fn sharp_frame_matches_the_analytic_disk() {
        let t = target();
        let mut r = BlurRenderer::new(&t, -10.0, 10.0);
        let (w, h) = (r.width(), r.height());
        let mut img = vec![0.0f32; w * h];
        r.render_float(&[2.25], 0.0, 0.0, &mut img);
        let (cx, cy) = (r.rest_x(), r.rest_y() + 2.25);
        let mut worst = 0.0f64;
        for y in 0..h {
            for x in 0..w {
                let d = ((x as f64 - cx).powi(2) + (y as f64 - cy).powi(2)).sqrt();
                worst = worst.max((img[y * w + x] as f64 - t.profile(d)).abs());
            }
        }
        // the phase-shifted band-limited image equals the image drawn at the shifted centre
        assert!(worst < 0.02, "max deviation {worst} grey levels");
    }

    #[test]
    fn integer_shift_equals_rotating_rows() {
        let mut r = BlurRenderer::new(&target(), -10.0, 10.0);
        let (w, h) = (r.width(), r.height());
        let mut a = vec![0.0f32; w * h];
        let mut b = vec![0.0f32; w * h];
        r.render_float(&[0.0], 0.0, 0.0, &mut a);
        r.render_float(&[3.0], 0.0, 0.0, &mut b);
        a.rotate_right(3 * w);
        let worst = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-3, "{worst}");
    }

    #[test]
    fn subpixel_shift_moves_the_weighted_centroid_exactly() {
        let mut r = BlurRenderer::new(&target(), -10.0, 10.0);
        let (w, h) = (r.width(), r.height());
        let mut img = vec![0.0f32; w * h];
        r.render_float(&[0.0], 0.0, 0.0, &mut img);
        let c0 = weighted_cy(&img, w);
        for d in [0.1, 0.37, -0.73, 4.5] {
            r.render_float(&[d], 0.0, 0.0, &mut img);
            let c = weighted_cy(&img, w);
            assert!((c - c0 - d).abs() < 1e-3, "shift {d}: moved {}", c - c0);
        }
    }

    #[test]
    fn blur_of_a_sinusoid_scales_the_weighted_centroid_by_sinc() {
        // 1 kHz path, sinusoid of amplitude 5 px at f Hz; exposure Te centred on the frames
        let (amp, f, te) = (5.0, 3.0, 0.1);
        let fine = 1000.0;
        let path: Vec<f64> = (0..4000)
            .map(|i| amp * (std::f64::consts::TAU * f * i as f64 / fine).sin())
            .collect();
        let mut r = BlurRenderer::new(&target(), -6.0, 6.0);
        let (w, h) = (r.width(), r.height());
        let mut img = vec![0.0f32; w * h];
        let mut c0 = vec![0.0f32; w * h];
        r.render_float(&[0.0], 0.0, 0.0, &mut c0);
        let rest = weighted_cy(&c0, w);
        // least-squares amplitude of the centroid sinusoid over whole periods
        let (mut ss, mut sc) = (0.0, 0.0);
        let frames = 300;
        for i in 0..frames {
            let centre = 500.0 + i as f64 * 10.0;
            r.render_float(
                &path,
                centre - te * fine / 2.0,
                centre + te * fine / 2.0,
                &mut img,
            );
            let y = weighted_cy(&img, w) - rest;
            let ph = std::f64::consts::TAU * f * centre / fine;
            ss += y * ph.sin();
            sc += y * ph.cos();
        }
        let got = 2.0 * (ss * ss + sc * sc).sqrt() / frames as f64;
        let x = std::f64::consts::PI * f * te;
        let want = amp * x.sin() / x;
        assert!(
            (got / want - 1.0).abs() < 0.005,
            "amplitude {got} vs sinc prediction {want}"
        );
    }
}
