//! Fast motion-blurred frames of a disk target moving along the image `y` axis, by EPSA (exact
//! phase shift and averaging, method.md §3.1) made separable.
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
use std::sync::Arc;
use vibcam_fft::ComplexToReal;
use vibcam_model::DiskTarget;

/// Renders motion-blurred 8-bit frames of a [`DiskTarget`] moving along `y`.
pub struct BlurRenderer {
    width: usize,
    height: usize,
    rest_x: usize,
    rest_y: f64,
    /// Columns `rest_x - half_cols ..= rest_x + half_cols` hold the target.
    half_cols: usize,
    /// Whether the target is symmetric about its centre column (then only the columns right
    /// of it are transformed, each put on both sides).
    symmetric: bool,
    /// Reference column spectra (bins 0..=H/2): for columns `rest_x + j`, `j = 0 ..= half_cols`
    /// of a symmetric target, else for columns `rest_x - half_cols + i`, `i = 0 ..= 2 half_cols`.
    spectra: Vec<Vec<Complex32>>,
    ifft: Arc<dyn ComplexToReal<f32>>,
    // per-frame work buffers
    ramp: Vec<Complex32>,
    spec: Vec<Complex32>,
    column: Vec<f32>,
    scratch: Vec<Complex32>,
    seg: Segments,
    path: Vec<f64>,
    block: usize,
    /// Ramp sums of consecutive blocks of path segments, `bins` values per block.
    blocks: Vec<Complex32>,
    /// Smallest and largest displacement of each block's samples (its `block + 1` samples).
    block_range: Vec<(f64, f64)>,
    /// `Some(n)`: an exposure is the average of `n` sharp images spread evenly over it, first
    /// and last at its ends ([`set_epsa_images`](Self::set_epsa_images)); `None`: the exact
    /// continuous integration.
    epsa_images: Option<usize>,
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
    /// weight
    w: Vec<f32>,
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
            &mut self.w,
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
        self.w.push(weight as f32);
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
        let pad = ext.ceil() + 3.0;
        let span = (hi - lo).max(0.0);
        let height = (((span + 2.0 * pad) / 16.0).ceil() as usize * 16).max(32);
        let rest_y = (pad - lo).round();
        let mut planner = vibcam_fft::RealPlanner32::new();
        let fwd = planner.forward(height);
        let ifft = planner.inverse(height);
        let bins = height / 2 + 1;
        // a symmetric target needs the columns right of its centre only
        let first = if target.is_symmetric() {
            0
        } else {
            -(half_cols as i64)
        };
        let mut spectra = Vec::with_capacity(2 * half_cols + 1);
        let mut col = vec![0.0f32; height];
        for j in first..=half_cols as i64 {
            let dx = j as f64;
            for (y, v) in col.iter_mut().enumerate() {
                *v = target.value(dx, y as f64 - rest_y) as f32;
            }
            let mut s = vec![Complex32::new(0.0, 0.0); bins];
            let mut input = col.clone();
            fwd.process(&mut input, &mut s)
                .expect("buffer sizes from the same plan");
            spectra.push(s);
        }
        BlurRenderer::of_spectra(
            (half_cols, height),
            rest_y,
            target.is_symmetric(),
            spectra,
            ifft,
        )
    }

    /// The renderer of the column spectra `spectra` (a target of `2 half_cols + 1` columns at
    /// rest at (`half_cols + 2`, `rest_y`) in a frame two columns wider on either side, `height`
    /// rows), their inverse transform `ifft` of length `height`, and empty work buffers.
    fn of_spectra(
        (half_cols, height): (usize, usize),
        rest_y: f64,
        symmetric: bool,
        spectra: Vec<Vec<Complex32>>,
        ifft: Arc<dyn ComplexToReal<f32>>,
    ) -> BlurRenderer {
        let bins = height / 2 + 1;
        let scratch = vec![Complex32::new(0.0, 0.0); ifft.get_scratch_len()];
        BlurRenderer {
            width: 2 * half_cols + 5,
            height,
            rest_x: half_cols + 2,
            rest_y,
            half_cols,
            symmetric,
            spectra,
            ifft,
            ramp: vec![Complex32::new(0.0, 0.0); bins],
            spec: vec![Complex32::new(0.0, 0.0); bins],
            column: vec![0.0; height],
            scratch,
            seg: Segments::default(),
            path: Vec::new(),
            block: 1,
            blocks: Vec::new(),
            block_range: Vec::new(),
            epsa_images: None,
        }
    }

    /// A renderer of any image: `columns` (an odd number of them, each of the same length `H`,
    /// the frame height) at displacement 0, drawn at frame columns `2 ..` (the frame is two
    /// columns wider on either side, left at 0). The image is translated along `y` by the
    /// phase shift, so it is taken as periodic in `y`: its last row should blend into its
    /// first (what a twin of a recording pads it with). `None` for an even or empty set of
    /// columns or a height below 2.
    pub fn from_columns(columns: &[Vec<f32>]) -> Option<BlurRenderer> {
        let height = columns.first()?.len();
        if columns.len().is_multiple_of(2)
            || height < 2
            || columns.iter().any(|c| c.len() != height)
        {
            return None;
        }
        let half_cols = columns.len() / 2;
        let mut planner = vibcam_fft::RealPlanner32::new();
        let fwd = planner.forward(height);
        let ifft = planner.inverse(height);
        let bins = height / 2 + 1;
        let spectra = columns
            .iter()
            .map(|c| {
                let mut s = vec![Complex32::new(0.0, 0.0); bins];
                let mut input = c.clone();
                fwd.process(&mut input, &mut s)
                    .expect("buffer sizes from the same plan");
                s
            })
            .collect();
        Some(BlurRenderer::of_spectra(
            (half_cols, height),
            0.0,
            false,
            spectra,
            ifft,
        ))
    }

    /// A renderer sized for the displacement range of `path` (px, positive down) with `path`
    /// set (see [`set_path`](Self::set_path) for `block`): what a camera looking at a target
    /// that follows `path` needs.
    pub fn for_path(target: &DiskTarget, path: &[f64], block: usize) -> BlurRenderer {
        let (lo, hi) = path
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
        let mut r = BlurRenderer::new(target, lo, hi);
        r.set_path(path, block);
        r
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

    /// How an exposure from `a` to `b` is formed: `None` (the default), the exact average over
    /// the path (a real sensor's continuous exposure); `Some(n)`, `n >= 2`, the discrete EPSA
    /// averaging of `n` sharp images at `a + i (b - a) / (n - 1)`, `i = 0 .. n`, the exposure's
    /// ends included (docs/method.md §2.6: the paper's averaging; its transfer for a linear
    /// centroid is the Dirichlet kernel `sin(pi f N dt) / (N sin(pi f dt))`, `dt = Te / (N -
    /// 1)`, where the continuous exposure gives `sin(pi f Te) / (pi f Te)`). `Some(0)` and
    /// `Some(1)` are taken as `Some(2)`.
    pub fn set_epsa_images(&mut self, images: Option<usize>) {
        self.epsa_images = images.map(|n| n.max(2));
    }

    /// Sets the displacement path (px, positive down, at equally spaced instants, linear in
    /// between) and precomputes the ramp sums of blocks of `block` consecutive path segments,
    /// so a frame's averaged ramp costs one add per block inside its exposure window instead of
    /// one recurrence per segment (the same blocks serve every exposure and frame).
    pub fn set_path(&mut self, path: &[f64], block: usize) {
        self.path.clear();
        self.path.extend_from_slice(path);
        let block = block.max(1);
        self.block = block;
        let bins = self.ramp.len();
        let segs = path.len().saturating_sub(1);
        let nblocks = segs / block;
        self.blocks.clear();
        self.blocks.reserve(nblocks * bins);
        let h = self.height as f64;
        let mut acc = vec![Complex32::new(0.0, 0.0); bins];
        self.block_range.clear();
        self.block_range.extend((0..nblocks).map(|j| {
            path[j * block..=(j + 1) * block]
                .iter()
                .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)))
        }));
        for j in 0..nblocks {
            self.seg.clear();
            for i in j * block..(j + 1) * block {
                let (da, db) = (path[i], path[i + 1]);
                self.seg.push(1.0, 0.5 * (da + db), db - da, h);
            }
            ramp_sum(&mut self.seg, &mut acc);
            self.blocks.extend_from_slice(&acc);
        }
    }

    /// Renders the frame exposed from fractional path index `a` to `b` (see
    /// [`set_path`](Self::set_path)) into `out` (`width * height`, row-major, 8-bit, rounded
    /// to nearest and clamped). `a == b` gives a sharp frame.
    pub fn render(&mut self, a: f64, b: f64, out: &mut [u8]) {
        self.averaged_ramp(a, b);
        let w = self.width;
        self.columns(|x, col| {
            for (y, v) in col.iter().enumerate() {
                out[y * w + x] = (v + 0.5).clamp(0.0, 255.0) as u8;
            }
        });
    }

    /// Renders the float image (before quantisation) into `out` (`width * height`).
    pub fn render_float(&mut self, a: f64, b: f64, out: &mut [f32]) {
        self.averaged_ramp(a, b);
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

    /// Columns `rest_x - half_cols ..= rest_x + half_cols` hold the target.
    pub fn half_cols(&self) -> usize {
        self.half_cols
    }

    /// Reference spectrum (bins `0 ..= H/2`, forward real FFT of the sharp column at rest) of
    /// column `rest_x + j` and `rest_x - j`, `j = 0 ..= half_cols`, of a target symmetric about
    /// its centre column ([`DiskTarget::is_symmetric`]; of another, the spectrum of column
    /// `rest_x - half_cols + j`).
    pub fn column_spectrum(&self, j: usize) -> &[Complex32] {
        &self.spectra[j]
    }

    /// The ramp averaged over the exposure from `a` to `b` (what [`render`](Self::render)
    /// multiplies every column spectrum by, bins `0 ..= H/2`).
    pub fn exposure_ramp(&mut self, a: f64, b: f64) -> &[Complex32] {
        self.averaged_ramp(a, b);
        &self.ramp
    }

    /// Smallest and largest displacement (px) of the path between fractional indices `a` and
    /// `b` (linear between samples, clamped like the exposure).
    pub fn path_range(&self, a: f64, b: f64) -> (f64, f64) {
        let (pa, pb) = (at(&self.path, a), at(&self.path, b.max(a)));
        let (mut lo, mut hi) = (pa.min(pb), pa.max(pb));
        let last = self.path.len().saturating_sub(1) as f64;
        let (i0, i1) = (a.max(0.0).ceil(), b.min(last).floor());
        if i0 <= i1 {
            // the samples i0 ..= i1: whole blocks from their precomputed extremes, the rest one
            // by one (the same minimum and maximum as a plain scan)
            let (mut i, end, bl) = (i0 as usize, i1 as usize, self.block);
            while i <= end {
                let j = i / bl;
                if i % bl == 0 && i + bl <= end && j < self.block_range.len() {
                    let (l, h) = self.block_range[j];
                    (lo, hi) = (lo.min(l), hi.max(h));
                    i += bl;
                } else {
                    let v = self.path[i];
                    (lo, hi) = (lo.min(v), hi.max(v));
                    i += 1;
                }
            }
        }
        (lo, hi)
    }

    /// Inverse-transforms every target column (spectrum x ramp) and hands it to `put` (for
    /// both mirror columns of a symmetric target).
    fn columns(&mut self, mut put: impl FnMut(usize, &[f32])) {
        let scale = 1.0 / self.height as f32;
        let last = self.spec.len() - 1;
        for j in 0..self.spectra.len() {
            for ((s, r), f) in self.spec.iter_mut().zip(&self.ramp).zip(&self.spectra[j]) {
                *s = f * r * scale;
            }
            self.spec[0].im = 0.0;
            if self.height.is_multiple_of(2) {
                self.spec[last].im = 0.0;
            }
            // sizes come from the same plan, so this cannot fail
            let _ =
                self.ifft
                    .process_with_scratch(&mut self.spec, &mut self.column, &mut self.scratch);
            if self.symmetric {
                put(self.rest_x + j, &self.column);
                if j > 0 {
                    put(self.rest_x - j, &self.column);
                }
            } else {
                put(self.rest_x - self.half_cols + j, &self.column);
            }
        }
    }

    /// A[k] for k = 0 ..= H/2: the ramp averaged over the path between indices a and b.
    fn averaged_ramp(&mut self, a: f64, b: f64) {
        let h = self.height as f64;
        let bins = self.ramp.len();
        self.seg.clear();
        if b <= a {
            self.seg.push(1.0, at(&self.path, a), 0.0, h);
            ramp_sum(&mut self.seg, &mut self.ramp);
            return;
        }
        if let Some(n) = self.epsa_images {
            // sharp images at n instants, the ends included, each of weight 1 / n
            let step = (b - a) / (n - 1) as f64;
            for i in 0..n {
                let t = if i + 1 == n { b } else { a + i as f64 * step };
                self.seg.push(1.0 / n as f64, at(&self.path, t), 0.0, h);
            }
            ramp_sum(&mut self.seg, &mut self.ramp);
            return;
        }
        // whole blocks inside [a, b]
        let bl = self.block as f64;
        let nblocks = self.blocks.len() / bins.max(1);
        let first_block = ((a / bl).ceil().max(0.0) as usize).min(nblocks);
        let last_block = ((b / bl).floor().max(0.0) as usize).clamp(first_block, nblocks);
        let (lo, hi) = if first_block < last_block {
            (first_block as f64 * bl, last_block as f64 * bl)
        } else {
            (b, b)
        };
        // the rest as single (possibly partial) segments, weight = duration in path steps
        let mut seg = std::mem::take(&mut self.seg);
        push_range(&self.path, &mut seg, a, lo.min(b), h);
        if hi < b {
            push_range(&self.path, &mut seg, hi, b, h);
        }
        ramp_sum(&mut seg, &mut self.ramp);
        self.seg = seg;
        for j in first_block..last_block {
            for (r, v) in self
                .ramp
                .iter_mut()
                .zip(&self.blocks[j * bins..(j + 1) * bins])
            {
                *r += v;
            }
        }
        let inv = 1.0 / (b - a) as f32;
        for r in self.ramp.iter_mut() {
            *r *= inv;
        }
    }
}

/// Position on `path` at fractional index `t` (clamped to the path; 0 for an empty path).
fn at(p: &[f64], t: f64) -> f64 {
    if p.is_empty() {
        return 0.0;
    }
    let i = t.floor().clamp(0.0, (p.len() - 1) as f64) as usize;
    let j = (i + 1).min(p.len() - 1);
    let f = (t - i as f64).clamp(0.0, 1.0);
    p[i] * (1.0 - f) + p[j] * f
}

/// Appends the path segments between fractional indices `from` and `to`, split at the path's
/// samples, each weighted by its duration in path steps.
fn push_range(path: &[f64], seg: &mut Segments, from: f64, to: f64, h: f64) {
    let mut t = from;
    while t < to {
        let next = (t.floor() + 1.0).min(to);
        let (da, db) = (at(path, t), at(path, next));
        seg.push(next - t, 0.5 * (da + db), db - da, h);
        t = next;
    }
}

/// `out[k] = sum_s w_s exp(-i k a_s) sinc(k theta_s)` for the segments in `seg` (k = 0 ..
/// out.len()), by recurrence over k, vectorised over the segments.
fn ramp_sum(s: &mut Segments, out: &mut [Complex32]) {
    let n = s.c.len();
    s.pzr.clear();
    s.pzr.resize(n, 1.0);
    s.pzi.clear();
    s.pzi.resize(n, 0.0);
    s.prr.clear();
    s.prr.resize(n, 1.0);
    s.pri.clear();
    s.pri.resize(n, 0.0);
    if let Some(o) = out.first_mut() {
        *o = Complex32::new(s.w.iter().sum(), 0.0);
    }
    for (k, o) in out.iter_mut().enumerate().skip(1) {
        let (mut re, mut im) = (0.0f32, 0.0f32);
        let it = s
            .pzr
            .iter_mut()
            .zip(s.pzi.iter_mut())
            .zip(s.prr.iter_mut().zip(s.pri.iter_mut()))
            .zip(s.zr.iter().zip(&s.zi))
            .zip(s.rr.iter().zip(&s.ri).zip(&s.c));
        for ((((pzr, pzi), (prr, pri)), (zr, zi)), ((rr, ri), c)) in it {
            let (a, b) = (*pzr * zr - *pzi * zi, *pzr * zi + *pzi * zr);
            let (e, f) = (*prr * rr - *pri * ri, *prr * ri + *pri * rr);
            *pzr = a;
            *pzi = b;
            *prr = e;
            *pri = f;
            let cf = c * f;
            re += cf * a;
            im += cf * b;
        }
        let kk = 1.0 / k as f32;
        *o = Complex32::new(re * kk, im * kk);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // the grandstand target (method.md §3.1)
    use vibcam_model::grandstand::TARGET;

    /// `r`'s float frame of the exposure from `a` to `b` along `path` (blocks of `block`).
    fn frame(r: &mut BlurRenderer, path: &[f64], block: usize, a: f64, b: f64) -> Vec<f32> {
        let mut img = vec![0.0f32; r.width() * r.height()];
        r.set_path(path, block);
        r.render_float(a, b, &mut img);
        img
    }

    /// Largest pixel difference of two frames.
    fn max_abs_diff(a: &[f32], b: &[f32]) -> f32 {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0f32, f32::max)
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
        let t = TARGET;
        let mut r = BlurRenderer::new(&t, -10.0, 10.0);
        let (w, h) = (r.width(), r.height());
        let mut img = vec![0.0f32; w * h];
        r.set_path(&[2.25], 1);
        r.render_float(0.0, 0.0, &mut img);
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
    fn sharp_speckled_frame_matches_the_analytic_pattern() {
        // not symmetric about its centre column: every column is transformed
        let t = vibcam_model::DiskTarget {
            texture: vibcam_model::Texture::Speckle,
            ..TARGET
        };
        let mut r = BlurRenderer::new(&t, -10.0, 10.0);
        let (w, h) = (r.width(), r.height());
        let mut img = vec![0.0f32; w * h];
        r.set_path(&[-3.6], 1);
        r.render_float(0.0, 0.0, &mut img);
        let (cx, cy) = (r.rest_x(), r.rest_y() - 3.6);
        let (mut worst, mut range) = (0.0f64, (f64::MAX, f64::MIN));
        for y in 0..h {
            for x in 0..w {
                let want = t.value(x as f64 - cx, y as f64 - cy);
                worst = worst.max((img[y * w + x] as f64 - want).abs());
                if (x as f64 - cx).hypot(y as f64 - cy) < t.radius_px - 2.0 {
                    range = (range.0.min(want), range.1.max(want));
                }
            }
        }
        assert!(worst < 0.05, "max deviation {worst} grey levels");
        // and the pattern is there: dark dots on the bright paint
        assert!(range.1 - range.0 > 0.5 * t.level, "{range:?}");
    }

    #[test]
    fn block_sums_equal_the_segment_by_segment_average() {
        let path: Vec<f64> = (0..300)
            .map(|i| 8.0 * (i as f64 * 0.05).sin() + 0.01 * i as f64)
            .collect();
        let mut r = BlurRenderer::new(&TARGET, -9.0, 12.0);
        for (lo, hi) in [(12.3, 95.8), (40.0, 160.0), (0.0, 299.0), (5.5, 6.25)] {
            let a = frame(&mut r, &path, 1, lo, hi);
            let worst = max_abs_diff(&a, &frame(&mut r, &path, 7, lo, hi));
            assert!(worst < 2e-3, "window {lo}..{hi}: {worst}");
        }
    }

    #[test]
    fn path_range_from_block_extremes_equals_a_plain_scan() {
        let path: Vec<f64> = (0..403)
            .map(|i| 8.0 * (i as f64 * 0.37).sin() + 3.0 * (i as f64 * 0.051).cos())
            .collect();
        let mut r = BlurRenderer::new(&TARGET, -12.0, 12.0);
        let plain = |a: f64, b: f64| {
            let (pa, pb) = (at(&path, a), at(&path, b.max(a)));
            let (i0, i1) = (a.max(0.0).ceil() as usize, b.min(402.0).floor() as usize);
            path.get(i0..=i1.max(i0).min(402))
                .unwrap_or(&[])
                .iter()
                .filter(|_| i0 <= i1)
                .fold((pa.min(pb), pa.max(pb)), |(l, h), v| (l.min(*v), h.max(*v)))
        };
        for block in [1, 3, 10, 16] {
            r.set_path(&path, block);
            for (a, b) in [
                (0.0, 402.0),
                (12.3, 95.8),
                (40.0, 160.0),
                (5.5, 6.25),
                (-3.0, 33.0),
                (390.5, 410.0),
                (7.0, 7.0),
            ] {
                assert_eq!(
                    r.path_range(a, b),
                    plain(a, b),
                    "block {block}, window {a}..{b}"
                );
            }
        }
    }

    #[test]
    fn integer_shift_equals_rotating_rows() {
        let mut r = BlurRenderer::new(&TARGET, -10.0, 10.0);
        let mut a = frame(&mut r, &[0.0, 3.0], 1, 0.0, 0.0);
        let b = frame(&mut r, &[0.0, 3.0], 1, 1.0, 1.0);
        a.rotate_right(3 * r.width());
        let worst = max_abs_diff(&a, &b);
        assert!(worst < 1e-3, "{worst}");
    }

    #[test]
    fn subpixel_shift_moves_the_weighted_centroid_exactly() {
        let mut r = BlurRenderer::new(&TARGET, -10.0, 10.0);
        let w = r.width();
        let c0 = weighted_cy(&frame(&mut r, &[0.0], 1, 0.0, 0.0), w);
        for d in [0.1, 0.37, -0.73, 4.5] {
            let c = weighted_cy(&frame(&mut r, &[d], 1, 0.0, 0.0), w);
            assert!((c - c0 - d).abs() < 1e-3, "shift {d}: moved {}", c - c0);
        }
    }

    /// A renderer on a 1 kHz path of 4 s: a sinusoid of `amp` px at `f` Hz; and the weighted
    /// centroid of the target at rest.
    fn sinusoid_renderer(amp: f64, f: f64) -> (BlurRenderer, f64) {
        let path: Vec<f64> = (0..4000)
            .map(|i| amp * (std::f64::consts::TAU * f * i as f64 / 1000.0).sin())
            .collect();
        let mut r = BlurRenderer::new(&TARGET, -6.0, 6.0);
        let rest = weighted_cy(&frame(&mut r, &[0.0], 1, 0.0, 0.0), r.width());
        r.set_path(&path, 10);
        (r, rest)
    }

    /// The least-squares amplitude at `f` Hz of the weighted centroid over 300 frames 10 ms
    /// apart (whole periods), each exposed `te` s centred on its instant.
    fn weighted_amplitude(r: &mut BlurRenderer, rest: f64, f: f64, te: f64) -> f64 {
        let (w, fine) = (r.width(), 1000.0);
        let mut img = vec![0.0f32; w * r.height()];
        let (mut ss, mut sc) = (0.0, 0.0);
        let frames = 300;
        for i in 0..frames {
            let centre = 500.0 + i as f64 * 10.0;
            r.render_float(centre - te * fine / 2.0, centre + te * fine / 2.0, &mut img);
            let y = weighted_cy(&img, w) - rest;
            let ph = std::f64::consts::TAU * f * centre / fine;
            ss += y * ph.sin();
            sc += y * ph.cos();
        }
        2.0 * (ss * ss + sc * sc).sqrt() / frames as f64
    }

    #[test]
    fn blur_of_a_sinusoid_scales_the_weighted_centroid_by_sinc() {
        // 1 kHz path, sinusoid of amplitude 5 px at f Hz; exposure Te centred on the frames
        let (amp, f, te) = (5.0, 3.0, 0.1);
        let (mut r, rest) = sinusoid_renderer(amp, f);
        let got = weighted_amplitude(&mut r, rest, f, te);
        let x = std::f64::consts::PI * f * te;
        let want = amp * x.sin() / x;
        assert!(
            (got / want - 1.0).abs() < 0.005,
            "amplitude {got} vs sinc prediction {want}"
        );
    }

    #[test]
    fn discrete_epsa_is_the_mean_of_sharp_images_and_follows_the_dirichlet_kernel() {
        let (amp, f, te, n) = (5.0, 2.0, 0.18, 5usize);
        let fine = 1000.0;
        let (mut r, rest) = sinusoid_renderer(amp, f);
        let (w, h) = (r.width(), r.height());
        r.set_epsa_images(Some(n));
        // the frame is the mean of n sharp frames at the exposure's ends and evenly between
        let (a, b) = (1234.5, 1234.5 + te * fine);
        let mut img = vec![0.0f32; w * h];
        r.render_float(a, b, &mut img);
        let mut mean = vec![0.0f32; w * h];
        let mut sharp = vec![0.0f32; w * h];
        for i in 0..n {
            let t = a + i as f64 * (b - a) / (n - 1) as f64;
            r.render_float(t, t, &mut sharp);
            for (m, v) in mean.iter_mut().zip(&sharp) {
                *m += v / n as f32;
            }
        }
        let worst = img
            .iter()
            .zip(&mean)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0f32, f32::max);
        assert!(worst < 2e-3, "{worst} grey levels");
        // and the weighted centroid of a sinusoid is scaled by the Dirichlet kernel, not the sinc
        let got = weighted_amplitude(&mut r, rest, f, te);
        let pi = std::f64::consts::PI;
        let dt = te / (n - 1) as f64;
        let want = amp * (pi * f * n as f64 * dt).sin() / (n as f64 * (pi * f * dt).sin());
        let sinc = amp * (pi * f * te).sin() / (pi * f * te);
        assert!(
            (got / want - 1.0).abs() < 0.005,
            "{got} vs Dirichlet {want}"
        );
        assert!((got / sinc - 1.0).abs() > 0.05, "{got} vs sinc {sinc}");
    }
}
