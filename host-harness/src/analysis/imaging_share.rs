//! The imaging share of a recording's uncertainty (docs/method.md §3.10.2): how much noise the
//! frames carry, what it does to the tracker's position in one frame (the *tracking noise
//! floor*), and what that floor does to an amplitude of the H1.
//!
//! - **Noise in the frames** ([`FrameNoise`]): from the second differences in time of every
//!   pixel of the centroid's region, `d = I[k+1] - 2 I[k] + I[k-1]`, whose variance is
//!   `6 sigma^2` for noise white in time, while a motion smooth at the frame rate leaves it
//!   nearly zero (its second difference is `(2 pi f / fc)^2` of the motion). The pixels at a
//!   moving edge change over the triple by the gradient times the motion and are left out
//!   (only pixels whose `|I[k+1] - I[k-1]|` is within `3 sqrt(2) sigma` count, iterated), and
//!   the rest is a standard deviation trimmed at 4 sd. Pixels at 0 or at the top code in any
//!   frame of a triple are left out (clipping removes their noise); when more than half of the
//!   region is clipped the estimate is flagged weak (the rest is no fair sample). Quantised
//!   frames without noise give 0: then the quantisation's own `1/12` code^2 is used, which a
//!   moving target dithers into noise.
//! - **Tracking noise floor** ([`tracker_floor`]): the centroid linearised in the pixel values
//!   of one frame. Weighted (weights `I - T`): `var(cx) = sigma^2 sum (x - cx)^2 / W^2`. Binary
//!   (weight 1 above `T`): a pixel of value `v` crosses the threshold with probability
//!   `p = Phi((v - T - 1/2) / sigma)`, so `var(cx) = sum (x - cx)^2 p (1 - p) / N^2`. Beside it
//!   the Cramer-Rao bound of a translation of the whole region, `sigma^2 / sum (dI/dx)^2`
//!   (what Lucas-Kanade's Gauss-Newton covariance is, and what no unbiased tracker beats).
//! - **Share of an amplitude** ([`h1_share`]): a floor `s` (m per frame, white) is a vision
//!   acceleration noise of one-sided density `(2 pi f)^4 2 s^2 / fc` below `fc / 2`; against the
//!   vision acceleration's density `G_yy` at the mode's line it is the incoherent part
//!   `1 - gamma^2 = G_nn / G_yy` of Bendat & Piersol's random error of `|H1|`,
//!   `sqrt(1 - gamma^2) / (|gamma| sqrt(2 n_d))`, `n_d` the segments.

use crate::frames::GreyFrame;
use firmware_core::centroid::{CentroidConfig, Mode, Roi};

/// Second differences of up to this many pixels are taken per frame triple (rows are skipped
/// evenly in a larger region).
const PIXELS_PER_TRIPLE: usize = 1 << 18;

/// The noise in a recording's frames, estimated from second differences in time
/// (see the module documentation). Frames are added in order.
#[derive(Debug, Clone)]
pub struct FrameNoise {
    roi: Option<Roi>,
    every: usize,
    index: usize,
    /// The crops of the last two frames of the current triple.
    prev: Vec<Vec<i32>>,
    /// Per pixel taken: `|I[k+1] - I[k-1]|` and the second difference.
    pairs: Vec<(i32, i32)>,
    /// Pixels looked at, and those left out as clipped.
    looked: u64,
    clipped: u64,
    triples: usize,
}

/// Pixels of one triple taken into the estimate (evenly spread over the region).
const PAIRS_PER_TRIPLE: usize = 4096;

/// Most differences kept (16 MB): 256 triples' worth.
pub const MAX_PAIRS: usize = 256 * PAIRS_PER_TRIPLE;

/// One noise estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseEstimate {
    /// Standard deviation of a pixel's noise, grey levels (codes of the frames).
    pub sigma: f64,
    /// Second differences it was taken from.
    pub samples: usize,
    /// Frame triples they came from.
    pub triples: usize,
    /// Share of the pixels looked at that were clipped (at 0 or the top code) in a frame of
    /// their triple, left out: clipping takes a pixel's noise, and where most of a region is
    /// clipped the rest is no fair sample of it.
    pub clipped: f64,
}

impl NoiseEstimate {
    /// Whether the estimate stands on too little: fewer than 1000 second differences, or more
    /// than half the pixels clipped (then the unclipped rest is mostly a moving edge, no still
    /// background: on a noise-free rendered rig, 97 % clipped, it read 35 grey levels).
    pub fn weak(&self) -> bool {
        self.samples < 1000 || self.clipped > 0.5
    }

    /// The noise to use: the estimate, or 0 (the quantisation only) when it is [`weak`](Self::weak).
    pub fn usable(&self) -> f64 {
        if self.weak() {
            0.0
        } else {
            self.sigma
        }
    }
}

impl FrameNoise {
    /// An estimator of the noise in `roi` (the whole frame when `None`) taking one triple of
    /// consecutive frames out of every `every` frames (at least 3: every frame in a triple).
    pub fn new(roi: Option<Roi>, every: usize) -> FrameNoise {
        FrameNoise {
            roi,
            every: every.max(3),
            index: 0,
            prev: Vec::new(),
            pairs: Vec::new(),
            looked: 0,
            clipped: 0,
            triples: 0,
        }
    }

    /// The stride for a record of `frames` frames: about 128 triples spread over it.
    pub fn stride_for(frames: Option<usize>) -> usize {
        frames.map_or(3, |n| (n / 128).max(3))
    }

    /// Takes the next frame of the record (beyond [`MAX_PAIRS`] differences, a record of unknown
    /// length, the rest is not looked at).
    pub fn add(&mut self, frame: &GreyFrame) {
        if self.pairs.len() >= MAX_PAIRS {
            return;
        }
        let phase = self.index % self.every;
        self.index += 1;
        if phase > 2 {
            return;
        }
        let crop = crop(frame, self.roi);
        if phase == 0 {
            self.prev.clear();
        }
        if phase == 2 && self.prev.len() == 2 && self.prev[0].len() == crop.len() {
            let top = match frame {
                GreyFrame::U8 { .. } => 255,
                GreyFrame::U16 { .. } => 65_535,
            };
            let (a, b) = (&self.prev[0], &self.prev[1]);
            let step = crop.len().div_ceil(PAIRS_PER_TRIPLE).max(1);
            for i in (0..crop.len()).step_by(step) {
                let (x, y, z) = (a[i], b[i], crop[i]);
                self.looked += 1;
                if [x, y, z].iter().any(|&v| v == 0 || v == top) {
                    self.clipped += 1;
                    continue;
                }
                self.pairs.push(((z - x).abs(), z - 2 * y + x));
            }
            self.triples += 1;
            return;
        }
        self.prev.push(crop);
    }

    /// The estimate; `None` before the first whole triple or when every pixel was clipped.
    ///
    /// The second differences' standard deviation over 6^(1/2), trimmed at 4 of it, of the
    /// pixels that hardly moved: those whose change over the triple `|I[k+1] - I[k-1]|`, which
    /// noise alone makes about `2^(1/2) sigma`, is within `3 2^(1/2) sigma` (a moving edge's
    /// pixels change by the gradient times the motion and are left out); iterated from all
    /// pixels until sigma settles.
    pub fn estimate(&self) -> Option<NoiseEstimate> {
        if self.triples == 0 || self.pairs.is_empty() {
            return None;
        }
        let mut sigma = trimmed_sd(self.pairs.iter().map(|p| p.1)) / 6f64.sqrt();
        let mut samples = self.pairs.len();
        for _ in 0..20 {
            let still = (3.0 * std::f64::consts::SQRT_2 * sigma).max(1.0);
            let kept = self.pairs.iter().filter(|p| f64::from(p.0) <= still);
            samples = kept.clone().count();
            let next = trimmed_sd(kept.map(|p| p.1)) / 6f64.sqrt();
            let settled = (next - sigma).abs() <= 1e-3 * sigma.max(1e-9);
            sigma = next;
            if settled {
                break;
            }
        }
        Some(NoiseEstimate {
            sigma,
            samples,
            triples: self.triples,
            clipped: self.clipped as f64 / self.looked.max(1) as f64,
        })
    }
}

/// The standard deviation of `d` (zero mean taken) over the values within 4 of it (iterated
/// from all; at least one code either side kept, so small integer noise is not cut to nothing).
fn trimmed_sd(d: impl Iterator<Item = i32> + Clone) -> f64 {
    let mut cut = f64::INFINITY;
    let mut sd = 0.0;
    for _ in 0..20 {
        let (mut n, mut s2) = (0u64, 0.0f64);
        for v in d.clone() {
            let v = f64::from(v);
            if v.abs() <= cut {
                n += 1;
                s2 += v * v;
            }
        }
        sd = if n > 0 { (s2 / n as f64).sqrt() } else { 0.0 };
        let next = (4.0 * sd).max(1.0);
        if next == cut {
            break;
        }
        cut = next;
    }
    sd
}

/// The region of `frame` the centroid sees, as integers (rows skipped evenly beyond
/// [`PIXELS_PER_TRIPLE`]).
fn crop(frame: &GreyFrame, roi: Option<Roi>) -> Vec<i32> {
    let (w, h) = frame.dimensions();
    let (x0, y0, cw, ch) = region(w, h, roi);
    let step = (cw * ch).div_ceil(PIXELS_PER_TRIPLE).max(1);
    let mut out = Vec::with_capacity(cw * ch / step + cw);
    for y in (y0..y0 + ch).step_by(step) {
        let row = y * w + x0..y * w + x0 + cw;
        match frame {
            GreyFrame::U8 { data, .. } => out.extend(data[row].iter().map(|&v| i32::from(v))),
            GreyFrame::U16 { data, .. } => out.extend(data[row].iter().map(|&v| i32::from(v))),
        }
    }
    out
}

/// `(x0, y0, width, height)` of `roi` clipped to a `w x h` frame (the whole frame for `None`).
pub(crate) fn region(w: usize, h: usize, roi: Option<Roi>) -> (usize, usize, usize, usize) {
    match roi {
        None => (0, 0, w, h),
        Some(r) => {
            let x0 = (r.x as usize).min(w);
            let y0 = (r.y as usize).min(h);
            (
                x0,
                y0,
                (r.width as usize).min(w - x0),
                (r.height as usize).min(h - y0),
            )
        }
    }
}

/// The frame of a recording whose target moved least during it (the smallest change of the
/// centroid along the axis between its neighbours; the first frame until there are three):
/// the least blurred picture of the target, which the floor and the twin take.
#[derive(Debug, Clone)]
pub struct StillestFrame {
    axis: crate::analysis::Axis,
    /// Frames seen.
    seen: usize,
    /// The last frame (its buffer reused frame after frame) and the last two positions.
    prev: Option<GreyFrame>,
    positions: [Option<f64>; 2],
    /// The stillest frame so far: its index, itself and its change.
    best: Option<(usize, GreyFrame, f64)>,
    first: Option<GreyFrame>,
}

impl StillestFrame {
    /// Follows the motion along `axis`.
    pub fn new(axis: crate::analysis::Axis) -> StillestFrame {
        StillestFrame {
            axis,
            seen: 0,
            prev: None,
            positions: [None; 2],
            best: None,
            first: None,
        }
    }

    /// Takes the next frame and its centroid.
    pub fn add(&mut self, frame: &GreyFrame, c: &firmware_core::centroid::Centroid) {
        let p = c.position().map(|(x, y)| match self.axis {
            crate::analysis::Axis::X => f64::from(x),
            crate::analysis::Axis::Y => f64::from(y),
        });
        if self.first.is_none() {
            self.first = Some(frame.clone());
        }
        // the previous frame, between positions[0] and p
        if let (Some(prev), Some(a), Some(b)) = (&self.prev, self.positions[0], p) {
            let change = (b - a).abs();
            if self.seen >= 2 && self.best.as_ref().is_none_or(|(_, _, v)| change < *v) {
                match &mut self.best {
                    Some((i, f, v)) => {
                        f.clone_from(prev);
                        (*i, *v) = (self.seen - 1, change);
                    }
                    None => self.best = Some((self.seen - 1, prev.clone(), change)),
                }
            }
        }
        match &mut self.prev {
            Some(f) => f.clone_from(frame),
            None => self.prev = Some(frame.clone()),
        }
        self.positions = [self.positions[1], p];
        self.seen += 1;
    }

    /// The stillest frame and its index from 0 (the first when no frame has two neighbours
    /// with a centroid).
    pub fn frame(self) -> Option<(usize, GreyFrame)> {
        self.best
            .map(|(i, f, _)| (i, f))
            .or(self.first.map(|f| (0, f)))
    }
}

/// The tracking noise floor of one frame: the centroid's standard deviation from the pixels'
/// noise, and the Cramer-Rao bound of a translation of the region, px.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackerFloor {
    /// Per-pixel noise used, grey levels (the measured one, at least the quantisation's).
    pub sigma: f64,
    /// Centroid's standard deviation along x, px.
    pub x_px: f64,
    /// Along y, px.
    pub y_px: f64,
    /// Cramer-Rao bound along x, px.
    pub crb_x_px: f64,
    /// Along y, px.
    pub crb_y_px: f64,
    /// Pixels above the threshold.
    pub pixels: usize,
}

impl TrackerFloor {
    /// The centroid's standard deviation along the image axis `axis`.
    pub fn along(&self, axis: crate::analysis::Axis) -> (f64, f64) {
        match axis {
            crate::analysis::Axis::X => (self.x_px, self.crb_x_px),
            crate::analysis::Axis::Y => (self.y_px, self.crb_y_px),
        }
    }
}

/// The floor of the centroid `config` on `frame` with pixel noise `sigma` (grey levels; taken at
/// least `sqrt(1/12)`, the quantisation's): see the module documentation. `None` when no pixel
/// of the region is above the threshold.
pub fn tracker_floor(
    frame: &GreyFrame,
    config: &CentroidConfig,
    sigma: f64,
) -> Option<TrackerFloor> {
    let (w, h) = frame.dimensions();
    let (x0, y0, cw, ch) = region(w, h, config.roi);
    let r = Window {
        frame,
        w,
        x0,
        y0,
        cw,
        ch,
    };
    let s = sigma.max((1.0f64 / 12.0).sqrt());
    let t = f64::from(config.threshold);
    // first pass: the centroid itself
    let (sw, cx, cy, n) = r.centroid(t, config.mode)?;
    let (mut vx, mut vy, mut gx2, mut gy2) = (0.0, 0.0, 0.0, 0.0);
    for y in 0..ch {
        for x in 0..cw {
            let v = r.value(x, y);
            let (dx, dy) = (x as f64 - cx, y as f64 - cy);
            let (gx, gy) = r.gradient(x, y);
            let k = match config.mode {
                Mode::Weighted if v > t => s * s,
                Mode::Weighted => 0.0,
                Mode::Binary if sigma > 0.0 => flip_variance(v, gx.hypot(gy), t, sigma),
                Mode::Binary => 0.0,
            };
            vx += k * dx * dx;
            vy += k * dy * dy;
            gx2 += gx * gx;
            gy2 += gy * gy;
        }
    }
    let crb = |g2: f64| {
        if g2 > 0.0 {
            s / g2.sqrt()
        } else {
            f64::INFINITY
        }
    };
    Some(TrackerFloor {
        sigma: s,
        x_px: vx.sqrt() / sw,
        y_px: vy.sqrt() / sw,
        crb_x_px: crb(gx2),
        crb_y_px: crb(gy2),
        pixels: n,
    })
}

/// The centroid's region of a frame: its values and central differences.
struct Window<'a> {
    frame: &'a GreyFrame,
    w: usize,
    x0: usize,
    y0: usize,
    cw: usize,
    ch: usize,
}

impl Window<'_> {
    fn value(&self, x: usize, y: usize) -> f64 {
        let i = (self.y0 + y) * self.w + self.x0 + x;
        match self.frame {
            GreyFrame::U8 { data, .. } => f64::from(data[i]),
            GreyFrame::U16 { data, .. } => f64::from(data[i]),
        }
    }

    /// Central differences inside the region, 0 on its border.
    fn gradient(&self, x: usize, y: usize) -> (f64, f64) {
        let gx = if x > 0 && x + 1 < self.cw {
            0.5 * (self.value(x + 1, y) - self.value(x - 1, y))
        } else {
            0.0
        };
        let gy = if y > 0 && y + 1 < self.ch {
            0.5 * (self.value(x, y + 1) - self.value(x, y - 1))
        } else {
            0.0
        };
        (gx, gy)
    }

    /// The centroid above threshold `t`: its weight, position and pixel count (`None`: no
    /// pixel above it).
    fn centroid(&self, t: f64, mode: Mode) -> Option<(f64, f64, f64, usize)> {
        let (mut sw, mut sx, mut sy, mut n) = (0.0, 0.0, 0.0, 0usize);
        for y in 0..self.ch {
            for x in 0..self.cw {
                let v = self.value(x, y);
                if v > t {
                    let wt = match mode {
                        Mode::Binary => 1.0,
                        Mode::Weighted => v - t,
                    };
                    sw += wt;
                    sx += wt * x as f64;
                    sy += wt * y as f64;
                    n += 1;
                }
            }
        }
        (n > 0 && sw > 0.0).then(|| (sw, sx / sw, sy / sw, n))
    }
}

/// The variance of a binary pixel's weight (value `v`, gradient `g`, threshold `t`, noise
/// `sigma`), averaged over a shift of the target within a pixel (what a moving target does):
/// along the gradient, the value spans v +- |grad| / 2.
fn flip_variance(v: f64, g: f64, t: f64, sigma: f64) -> f64 {
    (0..16)
        .map(|i| {
            let u = (i as f64 + 0.5) / 16.0 - 0.5;
            let z = (v + g * u - t - 0.5) / (sigma * std::f64::consts::SQRT_2);
            let p = 0.5 * libm::erfc(-z);
            p * (1.0 - p)
        })
        .sum::<f64>()
        / 16.0
}

/// What a tracking floor of `floor_m` (m per frame, white) at `fc` frames per second does to
/// `|H1|` at `f_hz`, where the vision acceleration's one-sided density is `gyy` ((m/s^2)^2/Hz)
/// and the H1 averages `segments` segments: `(G_nn / G_yy, relative standard uncertainty of
/// |H1| from it)` (see the module documentation). `None` for `gyy <= 0` or `f_hz >= fc / 2`.
pub fn h1_share(floor_m: f64, fc: f64, f_hz: f64, gyy: f64, segments: usize) -> Option<(f64, f64)> {
    if gyy.is_nan() || gyy <= 0.0 || f_hz >= fc / 2.0 || segments == 0 {
        return None;
    }
    let w2 = (std::f64::consts::TAU * f_hz).powi(2);
    let gnn = w2 * w2 * 2.0 * floor_m * floor_m / fc;
    let ratio = (gnn / gyy).min(1.0);
    let coh = 1.0 - ratio;
    let u = if coh > 0.0 {
        ratio.sqrt() / (coh.sqrt() * (2.0 * segments as f64).sqrt())
    } else {
        f64::INFINITY
    };
    Some((ratio, u))
}

/// The imaging share of one target's recording: the frames' noise, the floor along the
/// analysed axis, and its share of each vision mode's amplitude.
#[derive(Debug, Clone, PartialEq)]
pub struct Share {
    /// The frames' noise.
    pub noise: NoiseEstimate,
    /// The floor of the stillest frame.
    pub floor: TrackerFloor,
    /// The centroid's floor along the analysed axis, px, and the Cramer-Rao bound there.
    pub along_px: (f64, f64),
    /// The same in mm.
    pub along_mm: f64,
    /// Per vision mode: frequency, `G_nn / G_yy` and the relative standard uncertainty of
    /// `|H1|` it gives (`None`: the mode's line holds no vision signal or is above `fc / 2`),
    /// and the jackknife's relative standard uncertainty of the amplitude when it has one.
    pub modes: Vec<ModeShare>,
    /// The centroid's name.
    pub tracker: &'static str,
}

/// [`Share`] of one vision mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeShare {
    /// Picked frequency, Hz.
    pub f_hz: f64,
    /// `(G_nn / G_yy, relative u of |H1|)`.
    pub share: Option<(f64, f64)>,
    /// The amplitude interval's relative standard uncertainty (all sources), when given.
    pub total_u: Option<f64>,
}

impl Share {
    /// The imaging share of analysis `a` of one target along `axis` at `mm_per_px`: its
    /// vision acceleration's density at each vision mode's line against the floor of
    /// `first` (the stillest frame) with the noise `noise`. `None` when that frame has no
    /// pixel above the threshold.
    pub fn of(
        a: &super::Analysis,
        first: &GreyFrame,
        noise: NoiseEstimate,
        config: &CentroidConfig,
        (axis, mm_per_px): (super::Axis, f64),
        fc: f64,
    ) -> anyhow::Result<Option<Share>> {
        let Some(floor) = tracker_floor(first, config, noise.usable()) else {
            return Ok(None);
        };
        let along_px = floor.along(axis);
        let along_mm = along_px.0 * mm_per_px;
        let fa = f64::from(a.welch.fs_hz);
        let gyy = super::oma::csd::csd_matrix(
            std::slice::from_ref(&a.vision_acc),
            fa,
            super::oma::csd::CsdConfig::from(a.welch),
        )?;
        let segments = a.vis_frf.segments as usize;
        let modes = a
            .vis_modes
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let g = gyy.g.get(m.bin).map_or(0.0, |g| g[0].re);
                let total_u = a
                    .intervals
                    .as_ref()
                    .and_then(|iv| iv.vis.get(i))
                    .and_then(|u| u.amplitude.as_ref())
                    .map(|iv| 2.0 * iv.u / (iv.lo + iv.hi));
                ModeShare {
                    f_hz: m.f_hz,
                    share: h1_share(along_mm / 1000.0, fc, m.f_hz, g, segments),
                    total_u,
                }
            })
            .collect();
        Ok(Some(Share {
            noise,
            floor,
            along_px,
            along_mm,
            modes,
            tracker: match config.mode {
                Mode::Binary => "binary centroid",
                Mode::Weighted => "weighted centroid",
            },
        }))
    }

    /// The report's section.
    pub fn report(&self) -> String {
        let mut s = format!(
            "\nimaging share (method.md 3.10.2):\n  noise in the frames: {:.3} grey levels per \
             pixel (second differences in time of {} still pixels over {} frame triples; {:.0} \
             % of the pixels clipped, left out){}{}\n  tracking noise floor ({}, stillest frame, {} pixels above the threshold): \
             {:.5} px = {:.3e} mm per frame along the axis (Cramer-Rao bound of the region: \
             {:.5} px)\n",
            self.noise.sigma,
            self.noise.samples,
            self.noise.triples,
            100.0 * self.noise.clipped,
            if self.noise.weak() {
                "; NOT USED: no fair sample (most of the region clipped, or too few still \
                 pixels), so the floor below is the quantisation's alone"
            } else {
                ""
            },
            if !self.noise.weak() && self.noise.sigma < 0.5 {
                "; below half a grey level: the quantisation's 0.289 is used"
            } else {
                ""
            },
            self.tracker,
            self.floor.pixels,
            self.along_px.0,
            self.along_mm,
            self.along_px.1,
        );
        for (i, m) in self.modes.iter().enumerate() {
            s += &match m.share {
                Some((ratio, u)) => format!(
                    "  mode {}: {:.4} Hz: the floor's noise is {:.2e} of the vision signal's \
                     density there; its share of |H1|: {:.3} %{}\n",
                    i + 1,
                    m.f_hz,
                    ratio,
                    100.0 * u,
                    m.total_u
                        .map(|t| format!(
                            " (the amplitude's interval has {:.3} %, all sources)",
                            100.0 * t
                        ))
                        .unwrap_or_default()
                ),
                None => format!(
                    "  mode {}: {:.4} Hz: no vision signal at its line, or above fc / 2\n",
                    i + 1,
                    m.f_hz
                ),
            };
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{DiskTarget, Texture};
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    fn disk() -> DiskTarget {
        DiskTarget {
            radius_px: 6.0,
            level: 200.0,
            edge_sigma_px: 1.0,
            texture: Texture::Plain,
        }
    }

    /// A 40 x 40 8-bit frame of the disk centred at `(cx, cy)` with Gaussian noise `sigma`
    /// on a background of 20.
    fn frame(cx: f64, cy: f64, sigma: f64, rng: &mut rand_chacha::ChaCha8Rng) -> GreyFrame {
        let d = disk();
        let noise = Normal::new(0.0, sigma.max(1e-12)).unwrap();
        let mut data = vec![0u8; 40 * 40];
        for y in 0..40 {
            for x in 0..40 {
                let v = 20.0 + d.value(x as f64 - cx, y as f64 - cy) + noise.sample(rng);
                data[y * 40 + x] = v.round().clamp(0.0, 255.0) as u8;
            }
        }
        GreyFrame::U8 {
            width: 40,
            height: 40,
            data,
        }
    }

    #[test]
    fn the_frame_noise_is_recovered_from_moving_frames() {
        // a target moving 3 px peak to peak at 1/50 of the frame rate, noise 2 grey levels
        for &sigma in &[1.0, 2.0, 4.0] {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
            let mut est = FrameNoise::new(None, 3);
            for k in 0..300 {
                let y = 20.0 + 1.5 * (std::f64::consts::TAU * k as f64 / 50.0).sin();
                est.add(&frame(19.6, y, sigma, &mut rng));
            }
            let e = est.estimate().unwrap();
            assert_eq!(e.triples, 100);
            // 1/12 of quantisation comes on top of the noise
            let want = (sigma * sigma + 1.0 / 12.0).sqrt();
            assert!((e.sigma / want - 1.0).abs() < 0.05, "{sigma}: {e:?}");
        }
        // frames without noise and without motion: none measured
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut est = FrameNoise::new(None, 5);
        for _ in 0..20 {
            est.add(&frame(19.6, 20.2, 0.0, &mut rng));
        }
        assert_eq!(est.estimate().unwrap().sigma, 0.0);
        assert_eq!(est.estimate().unwrap().triples, 4);
    }

    /// The centroids' spread over noise draws at one place, pooled over many places of the
    /// target within a pixel (the position-dependent error of a still target, pixel locking,
    /// is no noise), and the floor of one frame rounded without noise, given the noise of the
    /// rounded noisy frames.
    fn spread(config: &CentroidConfig, sigma: f64) -> (f64, f64, TrackerFloor) {
        use rand::Rng;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let clean = frame(19.3, 20.4, 0.0, &mut rng);
        let floor = tracker_floor(&clean, config, (sigma * sigma + 1.0 / 12.0).sqrt()).unwrap();
        let (mut vx, mut vy, mut n) = (0.0, 0.0, 0);
        for _ in 0..100 {
            let (cx, cy) = (19.0 + rng.random::<f64>(), 20.0 + rng.random::<f64>());
            let (mut xs, mut ys) = (Vec::new(), Vec::new());
            for _ in 0..40 {
                let c = frame(cx, cy, sigma, &mut rng)
                    .centroid(config, "f")
                    .unwrap();
                let (x, y) = c.position().unwrap();
                xs.push(f64::from(x));
                ys.push(f64::from(y));
            }
            vx += crate::stats::std_dev(&xs).unwrap().powi(2);
            vy += crate::stats::std_dev(&ys).unwrap().powi(2);
            n += 1;
        }
        ((vx / n as f64).sqrt(), (vy / n as f64).sqrt(), floor)
    }

    #[test]
    fn the_floor_predicts_the_centroids_scatter_on_noisy_frames() {
        for mode in [Mode::Weighted, Mode::Binary] {
            let config = CentroidConfig {
                mode,
                ..CentroidConfig::binary(110)
            };
            for &sigma in &[1.0, 3.0] {
                let (sx, sy, f) = spread(&config, sigma);
                // 4000 frames at 100 places: the spread's own sampling error is about 1 %.
                // Weighted: the linearisation leaves out only the pixels near T entering and
                // leaving (a few per cent). Binary: its floor from one frame rests on the few
                // edge pixels within a noise sd or two of T there, averaged over a shift along
                // their gradient; the spread pooled over places differs from it by 3-16 %
                let tol = match mode {
                    Mode::Weighted => 0.05,
                    Mode::Binary => 0.2,
                };
                for (got, want) in [(sx, f.x_px), (sy, f.y_px)] {
                    assert!(
                        (got / want - 1.0).abs() < tol,
                        "{mode:?} sigma {sigma}: scatter {got:.5} px, floor {want:.5} px"
                    );
                }
                assert!(f.crb_x_px < f.x_px && f.crb_y_px < f.y_px, "{f:?}");
            }
        }
    }

    #[test]
    fn the_share_of_an_amplitude_follows_bendat_and_piersol() {
        // equal noise and signal densities: 1 - gamma^2 = 1/2, u = 1 / sqrt(2 n_d)
        let (f, fc, s) = (10.0, 100.0, 1e-6);
        let gnn = (std::f64::consts::TAU * f).powi(4) * 2.0 * s * s / fc;
        let (r, u) = h1_share(s, fc, f, 2.0 * gnn, 8).unwrap();
        assert!((r - 0.5).abs() < 1e-12);
        assert!((u - 1.0 / 4.0).abs() < 1e-12);
        assert!(h1_share(s, fc, 60.0, 1.0, 8).is_none());
        assert!(h1_share(s, fc, 10.0, 0.0, 8).is_none());
    }
}
