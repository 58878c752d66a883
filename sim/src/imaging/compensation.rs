//! Exposure transfer of the centroid computed with the imaging model, and the correction
//! tables the firmware divides by (method.md §2.8).
//!
//! For the weighted centroid with its threshold at the background level the transfer of a
//! centred exposure is the sinc of `firmware_core::exposure`. The binary centroid is not
//! linear in the image: its transfer depends on the motion amplitude against the target size
//! and on the threshold, so it is *measured* here: a sinusoid `A sin(2 pi t)` (one period per
//! unit time) is rendered through the study's EPSA renderer ([`BlurRenderer`]) with a centred
//! exposure of `E2PR` periods, each frame quantised to 8 bits as the study's camera does and
//! centroided by `firmware_core::centroid`, and the centroid's component at the sinusoid's
//! frequency is fitted by least squares over one whole period of frames. The transfer ratio is
//! the in-phase amplitude over `A` (signed: negative means antiphase). Only the frame
//! *positions in the period* matter, not the frequency or the frame rate, so one curve serves
//! every mode with the same amplitude.
//!
//! By the symmetry of a centred exposure of a sinusoid (see `firmware_core::exposure`) the
//! quadrature component is zero; [`TransferPoint::quadrature`] reports it as a check.
//! The odd harmonics the binary centroid creates are not in the ratio.

use super::tracker::FrameTracker;
use crate::imaging::{BlurRenderer, DiskTarget, TrackerKind};
use firmware_core::centroid::Mode;
use firmware_core::exposure::{CorrectionTable, TableError};

/// What to measure the transfer of: target, centroid and motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TransferSetup {
    /// The target image.
    pub target: DiskTarget,
    /// Threshold `T` (8-bit grey levels; a pixel counts when its value is `> T`).
    pub threshold: u16,
    /// Binary or weighted centroid.
    pub mode: Mode,
    /// Track with Lucas-Kanade instead ([`super::tracker::FrameTracker`]; the binary centroid
    /// at `threshold` places its window in the first frame of each E2PR's record).
    pub lk: bool,
    /// Motion amplitude `A` (px, along the image `y` axis).
    pub amplitude_px: f64,
    /// Frames per period of the sinusoid (uniform phases; at least 8). Harmonic `m` of the
    /// centroid aliases onto the fundamental only when `m = K - 1` or `K + 1`.
    pub frames_per_period: usize,
    /// Path samples per period given to the renderer (linear in between; at least 64).
    /// The chord error of the linearised sinusoid is `A (1 - cos(pi / P))`.
    pub path_steps_per_period: usize,
    /// With a frame-range threshold rule ([`crate::imaging::ThresholdRule::FrameRange`]), the
    /// fraction of each frame's grey-level range the threshold sits at (`threshold` unused).
    pub frame_range_frac: Option<f64>,
    /// How the camera forms an exposure ([`BlurRenderer::set_epsa_images`]): `None`
    /// continuous, `Some(N)` the mean of `N` sharp images; the table then describes that camera
    /// (for the weighted centroid at the background: the Dirichlet kernel, not the sinc).
    pub epsa_images: Option<usize>,
}

impl TransferSetup {
    /// A setup with 64 frames and 1024 path steps per period (chord error `4.7e-6 A`).
    pub fn new(target: DiskTarget, threshold: u16, mode: Mode, amplitude_px: f64) -> Self {
        TransferSetup {
            target,
            threshold,
            mode,
            lk: false,
            amplitude_px,
            frames_per_period: 64,
            path_steps_per_period: 1024,
            frame_range_frac: None,
            epsa_images: None,
        }
    }
}

/// The transfer at one E2PR.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TransferPoint {
    /// Exposure-to-period ratio.
    pub e2pr: f64,
    /// In-phase amplitude of the centroid at the sinusoid's frequency over `A` (measured /
    /// true amplitude).
    pub ratio: f64,
    /// Quadrature amplitude over `A` (zero by symmetry; a check of the computation).
    pub quadrature: f64,
    /// Frames of the period without a centroid (no pixel above the threshold); the fit uses
    /// the others (ratio and quadrature are 0 when fewer than three frames are left).
    pub lost_frames: usize,
    /// Frames in the period.
    pub frames: usize,
}

/// Why a transfer or a table cannot be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CompensationError {
    /// A setting is out of range; the message names it.
    #[error("transfer setup: {0}")]
    Setup(String),
    /// Frames were lost at this E2PR: a table built on them would not describe the camera.
    #[error("{lost} of {frames} frames lost at E2PR {e2pr}: the target fades below the threshold")]
    LostFrames {
        /// Exposure-to-period ratio.
        e2pr: f64,
        /// Frames without a centroid.
        lost: usize,
        /// Frames in the period.
        frames: usize,
    },
    /// The firmware rejected the table.
    #[error("correction table: {0}")]
    Table(TableError),
}

impl TransferSetup {
    fn check(&self, e2prs: &[f64]) -> Result<(), CompensationError> {
        let bad = |m: &str| Err(CompensationError::Setup(m.to_string()));
        if !(self.amplitude_px.is_finite() && self.amplitude_px > 0.0) {
            return bad("amplitude_px must be a positive number");
        }
        if self.frames_per_period < 8 {
            return bad("frames_per_period must be at least 8");
        }
        if self.path_steps_per_period < 64 {
            return bad("path_steps_per_period must be at least 64");
        }
        let t = &self.target;
        if !(t.radius_px > 0.0 && t.edge_sigma_px > 0.0 && t.level > 0.0 && t.level <= 255.0) {
            return bad("target needs radius and edge sigma > 0 and a level in (0, 255]");
        }
        if let Some(e) = e2prs
            .iter()
            .find(|e| !(e.is_finite() && **e >= 0.0 && **e <= 4.0))
        {
            return Err(CompensationError::Setup(format!(
                "E2PR {e} must lie in 0 ..= 4"
            )));
        }
        Ok(())
    }
}

/// Least-squares fit of `c + s sin(2 pi t) + k cos(2 pi t)` to `(t, y)`: `(s, k)`.
/// Over whole periods of uniform phases this is one DFT bin; with missing frames it is the
/// general 3 x 3 normal-equation solution.
pub fn fit_sinusoid(t: &[f64], y: &[f64]) -> Option<(f64, f64)> {
    let mut a = [[0.0f64; 3]; 3];
    let mut b = [0.0f64; 3];
    for (&ti, &yi) in t.iter().zip(y) {
        let (sn, cs) = (std::f64::consts::TAU * ti).sin_cos();
        let row = [1.0, sn, cs];
        for i in 0..3 {
            for j in 0..3 {
                a[i][j] += row[i] * row[j];
            }
            b[i] += row[i] * yi;
        }
    }
    let x = solve3(a, b)?;
    Some((x[1], x[2]))
}

/// Gaussian elimination with partial pivoting; `None` for a singular system.
fn solve3(mut a: [[f64; 3]; 3], mut b: [f64; 3]) -> Option<[f64; 3]> {
    for col in 0..3 {
        let piv = (col..3).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].abs() < 1e-12 {
            return None;
        }
        a.swap(col, piv);
        b.swap(col, piv);
        for r in col + 1..3 {
            let f = a[r][col] / a[col][col];
            let pivot_row = a[col];
            for (x, p) in a[r].iter_mut().zip(pivot_row).skip(col) {
                *x -= f * p;
            }
            b[r] -= f * b[col];
        }
    }
    let mut x = [0.0f64; 3];
    for r in (0..3).rev() {
        let s: f64 = (r + 1..3).map(|c| a[r][c] * x[c]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    Some(x)
}

/// The longest blur of a sinusoid of amplitude `amp` within an exposure of `e` periods: its
/// largest excursion, 2 A sin(pi E2PR) up to E2PR 1/2.
fn blur_px(amp: f64, e: f64) -> f64 {
    2.0 * amp * (std::f64::consts::PI * e.min(0.5)).sin()
}

/// The renderer of the sinusoid's `path` (for LK, a frame wide enough for the window to reach
/// as far as `longest_blur`) and the tracker the setup measures with.
fn renderer_and_tracker(
    setup: &TransferSetup,
    path: &[f64],
    longest_blur: f64,
) -> Result<(BlurRenderer, FrameTracker), CompensationError> {
    let amp = setup.amplitude_px;
    let mut renderer = if setup.lk {
        let extra = (longest_blur / 2.0).ceil() + 8.0;
        let mut r = BlurRenderer::new(&setup.target, -amp - extra, amp + extra);
        r.set_path(path, 16);
        r
    } else {
        BlurRenderer::for_path(&setup.target, path, 16)
    };
    renderer.set_epsa_images(setup.epsa_images);
    let kind = match (setup.lk, setup.mode) {
        (true, _) => TrackerKind::Lk,
        (false, Mode::Binary) => TrackerKind::Blob,
        (false, Mode::Weighted) => TrackerKind::Weighted,
    };
    let tracker = FrameTracker::new(
        kind,
        setup.threshold,
        setup.frame_range_frac,
        &setup.target,
        255,
    )
    .map_err(|e| CompensationError::Setup(e.to_string()))?;
    Ok((renderer, tracker))
}

/// The centroid's transfer at each E2PR of `e2prs` (one renderer for all of them).
pub fn transfer_curve(
    setup: &TransferSetup,
    e2prs: &[f64],
) -> Result<Vec<TransferPoint>, CompensationError> {
    setup.check(e2prs)?;
    let p = setup.path_steps_per_period;
    let max_e = e2prs.iter().copied().fold(0.0f64, f64::max);
    // path from t = -lead to t = 1 + lead periods, lead covering half the longest exposure
    let lead = ((max_e / 2.0) * p as f64).ceil() as usize + 1;
    let amp = setup.amplitude_px;
    let path: Vec<f64> = (0..=p + 2 * lead)
        .map(|i| {
            let t = (i as f64 - lead as f64) / p as f64;
            amp * (std::f64::consts::TAU * t).sin()
        })
        .collect();
    let blur = |e: f64| blur_px(amp, e);
    let (mut renderer, mut tracker) = renderer_and_tracker(setup, &path, blur(max_e))?;
    let (w, h) = (renderer.width(), renderer.height());
    let mut frame = vec![0u8; w * h];
    let k = setup.frames_per_period;
    let mut out = Vec::with_capacity(e2prs.len());
    let (mut ts, mut ys) = (Vec::with_capacity(k), Vec::with_capacity(k));
    for &e in e2prs {
        ts.clear();
        ys.clear();
        let half = 0.5 * e * p as f64;
        tracker
            .restart(blur(e))
            .map_err(|e| CompensationError::Setup(e.to_string()))?;
        if setup.lk {
            // LK's template: the target sharp at rest, as in the first frame of a record that
            // starts at rest (a decay test, the grandstand's); the blur's effect on LK depends
            // on the template's own blur (docs/method.md §2.11)
            renderer.render(lead as f64, lead as f64, &mut frame);
            tracker
                .measure(&frame, w, h)
                .map_err(|e| CompensationError::Setup(format!("frame: {e}")))?;
        }
        for j in 0..k {
            let t = j as f64 / k as f64;
            let centre = lead as f64 + t * p as f64;
            renderer.render(centre - half, centre + half, &mut frame);
            let c = tracker
                .measure(&frame, w, h)
                .map_err(|e| CompensationError::Setup(format!("frame: {e}")))?;
            if let Some((_, cy)) = c {
                ts.push(t);
                ys.push(cy as f64);
            }
        }
        let lost = k - ts.len();
        // too few frames left to fit: the camera sees no motion at all
        let (s, c) = fit_sinusoid(&ts, &ys).unwrap_or((0.0, 0.0));
        out.push(TransferPoint {
            e2pr: e,
            ratio: s / amp,
            quadrature: c / amp,
            lost_frames: lost,
            frames: k,
        });
    }
    Ok(out)
}

/// The centroid's transfer at one E2PR (see [`transfer_curve`]).
pub fn centroid_transfer(
    setup: &TransferSetup,
    e2pr: f64,
) -> Result<TransferPoint, CompensationError> {
    Ok(transfer_curve(setup, &[e2pr])?[0])
}

/// A firmware correction table of `N` nodes at E2PR `0, step, ..., (N - 1) step` for this
/// setup. Errors when a node loses frames (the table would describe a camera that drops
/// them) or the firmware rejects a ratio (not positive: beyond the transfer's first zero).
pub fn correction_table<const N: usize>(
    setup: &TransferSetup,
    step: f64,
) -> Result<CorrectionTable<N>, CompensationError> {
    if !(step.is_finite() && step > 0.0) {
        return Err(CompensationError::Setup(format!(
            "table step {step} must be positive"
        )));
    }
    let e2prs: Vec<f64> = (0..N).map(|i| i as f64 * step).collect();
    let curve = transfer_curve(setup, &e2prs)?;
    let mut ratios = [0.0f32; N];
    for (r, pt) in ratios.iter_mut().zip(&curve) {
        if pt.lost_frames > 0 {
            return Err(CompensationError::LostFrames {
                e2pr: pt.e2pr,
                lost: pt.lost_frames,
                frames: pt.frames,
            });
        }
        // a camera whose transfer reaches zero inside the table (N averaged images: the
        // Dirichlet kernel's first zero at E2PR (N - 1) / N) has nodes at or below zero; they
        // are below the firmware's ratio floor whatever their value, so nothing is corrected
        // there, and the table takes them as 1e-6
        *r = (pt.ratio as f32).max(1e-6);
    }
    CorrectionTable::try_new(step as f32, ratios).map_err(CompensationError::Table)
}

#[cfg(test)]
mod tests {
    use super::*;
    use firmware_core::exposure::{sinc_pi, ExposureTransfer};

    // the grandstand target (method.md §3.1)
    use vibcam_model::grandstand::TARGET;

    #[test]
    fn sinusoid_fit_recovers_known_coefficients_with_missing_frames() {
        let t: Vec<f64> = (0..40)
            .map(|i| i as f64 / 40.0)
            .filter(|t| *t != 0.3)
            .collect();
        let y: Vec<f64> = t
            .iter()
            .map(|t| {
                let a = std::f64::consts::TAU * t;
                1.5 + 0.7 * a.sin() - 0.2 * a.cos() + 0.1 * (3.0 * a).sin()
            })
            .collect();
        let (s, c) = fit_sinusoid(&t, &y).unwrap();
        // one missing frame lets the 3rd harmonic leak a little: 0.1 * 2 / 39 at most
        assert!((s - 0.7).abs() < 6e-3 && (c + 0.2).abs() < 6e-3, "{s} {c}");
        let full: Vec<f64> = (0..40).map(|i| i as f64 / 40.0).collect();
        let y: Vec<f64> = full
            .iter()
            .map(|t| 0.7 * (std::f64::consts::TAU * t).sin())
            .collect();
        let (s, c) = fit_sinusoid(&full, &y).unwrap();
        assert!((s - 0.7).abs() < 1e-12 && c.abs() < 1e-12);
    }

    /// The linear case: the weighted centroid with the threshold at the background level
    /// (0) follows the sinc.
    #[test]
    fn weighted_centroid_at_background_threshold_follows_the_sinc() {
        let setup = TransferSetup::new(TARGET, 0, Mode::Weighted, 5.0);
        let e2prs = [0.0, 0.2, 0.4, 0.6, 0.8, 1.2];
        let curve = transfer_curve(&setup, &e2prs).unwrap();
        for pt in &curve {
            let want = sinc_pi(pt.e2pr as f32) as f64;
            eprintln!("weighted E2PR {}: {} vs sinc {want}", pt.e2pr, pt.ratio);
            // 8-bit rounding of the frame is the only nonlinearity left (tails below 0.5 grey
            // levels vanish); measured below 2e-4 of the amplitude
            assert!((pt.ratio - want).abs() < 5e-4, "{pt:?} vs {want}");
            assert!(pt.quadrature.abs() < 5e-4 && pt.lost_frames == 0, "{pt:?}");
        }
    }

    /// Independent reference: frames drawn directly from the analytic disk profile, averaged
    /// over `sub` instants of the exposure (midpoint rule), quantised, binary-centroided by a
    /// double loop, fitted over the period.
    fn brute_force_binary(setup: &TransferSetup, e2pr: f64, sub: usize) -> f64 {
        let offsets: Vec<f64> = (0..sub)
            .map(|s| (s as f64 + 0.5) / sub as f64 - 0.5)
            .collect();
        brute_force_binary_at(setup, e2pr, &offsets)
    }

    /// [`brute_force_binary`] with the images at `offsets` (fractions of the exposure from
    /// its centre, -0.5 ..= 0.5), equally weighted.
    fn brute_force_binary_at(setup: &TransferSetup, e2pr: f64, offsets: &[f64]) -> f64 {
        let sub = offsets.len();
        let renderer = BlurRenderer::new(&setup.target, -setup.amplitude_px, setup.amplitude_px);
        let (w, h) = (renderer.width(), renderer.height());
        let (rx, ry) = (renderer.rest_x(), renderer.rest_y());
        let k = setup.frames_per_period;
        let mut img = vec![0.0f64; w * h];
        let (mut ts, mut ys) = (Vec::new(), Vec::new());
        for j in 0..k {
            let t = j as f64 / k as f64;
            img.iter_mut().for_each(|v| *v = 0.0);
            for off in offsets {
                let ti = t + e2pr * off;
                let cy = ry + setup.amplitude_px * (std::f64::consts::TAU * ti).sin();
                for y in 0..h {
                    for x in 0..w {
                        let d = ((x as f64 - rx).powi(2) + (y as f64 - cy).powi(2)).sqrt();
                        img[y * w + x] += setup.target.profile(d) / sub as f64;
                    }
                }
            }
            let (mut n, mut sy) = (0.0f64, 0.0f64);
            for y in 0..h {
                for x in 0..w {
                    let v = (img[y * w + x] + 0.5).clamp(0.0, 255.0).floor();
                    if v > setup.threshold as f64 {
                        n += 1.0;
                        sy += y as f64;
                    }
                }
            }
            ts.push(t);
            ys.push(sy / n);
        }
        fit_sinusoid(&ts, &ys).unwrap().0 / setup.amplitude_px
    }

    #[test]
    fn binary_transfer_matches_a_brute_force_rendering_and_departs_from_the_sinc() {
        // large motion against the target: amplitude 12 px = the radius
        let mut setup = TransferSetup::new(TARGET, 100, Mode::Binary, 12.0);
        setup.frames_per_period = 32;
        for e in [0.3, 0.7] {
            let got = centroid_transfer(&setup, e).unwrap();
            let want = brute_force_binary(&setup, e, 240);
            let sinc = sinc_pi(e as f32) as f64;
            eprintln!(
                "binary A=12 E2PR {e}: {} brute force {want} sinc {sinc}",
                got.ratio
            );
            // the two renderings differ by < 0.02 grey levels (EPSA band-limiting) and by the
            // midpoint rule over 240 instants, so a pixel that close to the threshold could
            // flip after quantisation and move one frame by ~0.03 px, the fit by ~1e-4 of A;
            // measured: no flip, 2e-8
            assert!((got.ratio - want).abs() < 1e-4, "{got:?} vs {want}");
            // symmetry of the centred exposure (module doc); measured below 1e-6
            assert!(got.quadrature.abs() < 1e-4, "{got:?}");
        }
        // and the binary transfer is not the sinc at this amplitude
        let pt = centroid_transfer(&setup, 0.7).unwrap();
        let sinc = sinc_pi(0.7) as f64;
        assert!((pt.ratio - sinc).abs() > 0.02, "{pt:?} vs sinc {sinc}");
    }

    #[test]
    fn discrete_epsa_transfers_match_the_dirichlet_kernel_and_a_brute_force_rendering() {
        // the weighted centroid at the background: the Dirichlet kernel of N images
        let n = 5;
        let mut setup = TransferSetup::new(TARGET, 0, Mode::Weighted, 5.0);
        setup.epsa_images = Some(n);
        for pt in transfer_curve(&setup, &[0.2, 0.4, 0.6, 0.8]).unwrap() {
            let x = std::f64::consts::PI * pt.e2pr / (n - 1) as f64;
            let want = (n as f64 * x).sin() / (n as f64 * x.sin());
            assert!((pt.ratio - want).abs() < 5e-4, "{pt:?} vs Dirichlet {want}");
        }
        // the binary centroid of a large motion: N analytic images at the exposure's ends and
        // evenly between
        let mut setup = TransferSetup::new(TARGET, 100, Mode::Binary, 12.0);
        setup.frames_per_period = 32;
        setup.epsa_images = Some(n);
        let offsets: Vec<f64> = (0..n).map(|i| i as f64 / (n - 1) as f64 - 0.5).collect();
        for e in [0.3, 0.7] {
            let got = centroid_transfer(&setup, e).unwrap();
            let want = brute_force_binary_at(&setup, e, &offsets);
            assert!((got.ratio - want).abs() < 1e-4, "{got:?} vs {want}");
        }
    }

    #[test]
    fn table_nodes_are_the_transfer_and_interpolate_between() {
        let setup = TransferSetup::new(TARGET, 100, Mode::Binary, 5.0);
        let table = correction_table::<9>(&setup, 0.1).unwrap();
        assert_eq!(table.ratios().len(), 9);
        let direct = centroid_transfer(&setup, 0.35).unwrap().ratio;
        let interp = table.ratio(0.35).unwrap() as f64;
        // linear interpolation on a 0.1 grid: h^2 |r''| / 8 with |r''| <= pi^2 / 3 (sinc-like
        // curvature) gives 4e-3
        assert!((direct - interp).abs() < 4e-3, "{direct} vs {interp}");
        for (i, r) in table.ratios().iter().enumerate() {
            eprintln!("binary A=5 node E2PR {:.1}: {r}", i as f64 * 0.1);
        }
        // at E2PR 0 the binary centroid follows the sharp target (pixel locking only)
        assert!(
            (table.ratios()[0] - 1.0).abs() < 5e-3,
            "{:?}",
            table.ratios()
        );
    }

    /// End to end, as the firmware would do it: a 2.5 Hz sinusoid filmed at 50 fps with a
    /// centred 180 ms exposure (E2PR 0.45, between table nodes) and the binary centroid,
    /// 10 s of frames, one DFT, divided by the table: the amplitude comes back.
    #[test]
    fn a_binary_table_compensates_a_filmed_sinusoid() {
        let (amp, f, fps, te) = (5.0f64, 2.5f64, 50.0f64, 0.18f64);
        let setup = TransferSetup::new(TARGET, 100, Mode::Binary, amp);
        let table = correction_table::<17>(&setup, 0.05).unwrap();
        // the camera: a 1 kHz path, frames every 20 path steps, exposure 180 steps
        let fine = 1000.0;
        let (n, margin) = (500usize, 200usize);
        let path: Vec<f64> = (0..n * 20 + 2 * margin)
            .map(|i| amp * (std::f64::consts::TAU * f * (i as f64 - margin as f64) / fine).sin())
            .collect();
        let mut r = BlurRenderer::for_path(&setup.target, &path, 10);
        let (w, h) = (r.width(), r.height());
        let mut frame = vec![0u8; w * h];
        let config = firmware_core::centroid::CentroidConfig::binary(100);
        let half = 0.5 * te * fine;
        let y: Vec<f64> = (0..n)
            .map(|j| {
                let c = (margin + 20 * j) as f64;
                r.render(c - half, c + half, &mut frame);
                firmware_core::centroid::Frame::new(&frame, w, h, w)
                    .and_then(|f| firmware_core::centroid::centroid(&config, &f))
                    .unwrap()
                    .cy as f64
            })
            .collect();
        // naive DFT (f64 reference), then the firmware's compensation in f32
        let mut bins: Vec<firmware_core::Complex32> = (0..n)
            .map(|k| {
                let (mut re, mut im) = (0.0, 0.0);
                for (j, v) in y.iter().enumerate() {
                    let a = -std::f64::consts::TAU * (k * j % n) as f64 / n as f64;
                    re += v * a.cos();
                    im += v * a.sin();
                }
                firmware_core::Complex32::new(re as f32, im as f32)
            })
            .collect();
        let k = (f * n as f64 / fps) as usize; // 25 cycles in 500 frames
        let raw = 2.0 * bins[k].norm() as f64 / n as f64;
        let report =
            firmware_core::exposure::compensate_dft(&table, &mut bins, fps as f32, te as f32);
        let fixed = 2.0 * bins[k].norm() as f64 / n as f64;
        eprintln!(
            "filmed: raw {:.4}, compensated {:.4} of {amp}",
            raw / amp,
            fixed / amp
        );
        // the blur costs about a quarter of the amplitude
        assert!(raw / amp < 0.8, "raw {raw}");
        // linear interpolation of a sinc-like curve on a 0.05 grid: h^2 pi^2 / 24 = 1e-3
        assert!((fixed / amp - 1.0).abs() < 2e-3, "compensated {fixed}");
        // bins above 0.8 / 0.18 = 4.44 Hz are left alone: |k| > 44.4
        assert_eq!(report.first_uncorrected, Some(45));
    }

    #[test]
    fn lucas_kanade_loses_the_exposure_sinc_for_small_blur_and_less_for_long_smears() {
        // a gradient tracker's estimate is, to first order in the blur, the exposure-averaged
        // position (linear in the image), so with its template sharp (the record starts at
        // rest) its transfer is sinc(pi E2PR) at a small motion; a smear much longer than the
        // target no longer looks like the template, and the fit is drawn to where the smear is
        // brightest, the turning points, so it loses less (more the longer the smear). The
        // sharp template never matches the blurred frames exactly: every frame must still
        // settle
        let mut at_04 = Vec::new();
        for amp in [1.0, 4.0, 8.0, 16.0] {
            let setup = TransferSetup {
                lk: true,
                ..TransferSetup::new(TARGET, 100, Mode::Binary, amp)
            };
            for p in transfer_curve(&setup, &[0.1, 0.2, 0.4, 0.6]).unwrap() {
                let sinc = sinc_pi(p.e2pr as f32) as f64;
                assert_eq!(p.lost_frames, 0, "{amp} px, E2PR {}", p.e2pr);
                assert!(p.quadrature.abs() < 1e-3, "{p:?}");
                if amp == 1.0 {
                    assert!((p.ratio - sinc).abs() < 0.005, "{amp} px: {p:?} vs {sinc}");
                } else {
                    assert!(p.ratio > sinc - 0.001 && p.ratio < 1.0, "{amp}: {p:?}");
                }
                if p.e2pr == 0.4 {
                    at_04.push(p.ratio);
                }
            }
        }
        assert!(at_04.windows(2).all(|w| w[1] > w[0]), "{at_04:?}");
    }

    #[test]
    fn bad_setups_name_the_field() {
        let mut s = TransferSetup::new(TARGET, 100, Mode::Binary, 0.0);
        let e = transfer_curve(&s, &[0.1]).unwrap_err();
        assert!(e.to_string().contains("amplitude_px"), "{e}");
        s.amplitude_px = 3.0;
        let e = transfer_curve(&s, &[-0.1]).unwrap_err();
        assert!(e.to_string().contains("E2PR"), "{e}");
    }
}
