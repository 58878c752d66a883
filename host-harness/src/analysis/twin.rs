//! `analyze --twin N`: the paper's Monte Carlo method (JCGM 101) on the user's own recording
//! (docs/method.md §3.10.3). The recording's scene is rendered again `N` times and each
//! rendering goes through the same centroid and the same analysis; what the imaging does to
//! each vision mode's frequency and amplitude is the spread of those runs about the motion
//! they were given.
//!
//! One run:
//! - **The scene**: the centroid's region of the recording's stillest frame (the least change
//!   of the centroid between its neighbours: the least blurred; the whole frame without `--roi`),
//!   taken as an image that translates along the analysed axis; it is padded along that axis
//!   with a blend from its last row back to its first, so the phase-shift translation of
//!   [`BlurRenderer`] (exact for a band-limited image) wraps nothing abrupt in.
//! - **The motion**: the tracked coordinate along the axis, relative to that frame's; with a
//!   stated exposure, divided by the box transfer `sinc(pi f Te)` up to E2PR 0.5 (the motion
//!   before the recording's own blur; beyond, the division would raise noise more than it
//!   restores); Fourier-interpolated to 64 steps a frame, linear
//!   between them; the whole path shifted by a sub-pixel offset drawn per run, uniform in
//!   +-1/2 px (where the target sits on the pixel grid is no more known than that).
//! - **The camera**: each frame the average of the image over the stated exposure centred on
//!   the frame's instant (exact for the piecewise linear path, [`BlurRenderer`]); Gaussian noise
//!   of the frames' measured standard deviation ([`super::imaging_share::FrameNoise`]) drawn
//!   per run (none when the frames gave no fair sample of it, `NoiseEstimate::weak`: the
//!   twin then holds the blur and the tracker alone); rounded and clipped to the frames'
//!   codes.
//! - **The analysis**: the same centroid (threshold, mode), the same displacement settings, the
//!   same chain against the same accelerometer record, compensated when the recording's was.
//! - **The truth**: the motion itself at the frames' instants through the same chain without
//!   any imaging. Each run gives, per vision mode, the ratio of its amplitude to the truth's
//!   and the difference of its frequency.
//!
//! The report gives the mean ratio (the imaging's bias of the amplitude, with the standard
//! uncertainty of that mean) and the 2.5 and 97.5 percentiles of the runs (the coverage
//! interval of one recording's imaging factor), and the recording's vision amplitude with
//! the bias divided out. Runs are independent and seeded `seed + run`, so shards
//! (`--twin-shard I/N`: the runs `r` with `r mod N = I - 1`) give the rows of the whole
//! when their `twin.csv` are put together.

use super::imaging_share::NoiseEstimate;
use super::{Analysis, Axis, Displacement, DisplacementSettings};
use crate::frames::GreyFrame;
use crate::imaging::BlurRenderer;
use crate::lost_frames::LostFramePolicy;
use crate::study::runner::Shard;
use firmware_core::centroid::CentroidConfig;
use firmware_core::exposure::{BoxTransfer, ExposureTransfer};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;

/// Path steps per frame. The exposure averages the path linear between steps, whose average
/// over a step of a sinusoid is `cos(theta / 2)` of its value where the true average is
/// `sinc(theta / 2)`, `theta = 2 pi f / (fc STEPS)`: about `theta^2 / 12` low, 2e-4 at the
/// Nyquist frequency with 64 steps (with 8, 0.35 % at a rig mode of 32 Hz at 120 fps, which
/// showed as a twin 0.35 % below the study).
const STEPS: usize = 64;

/// The motion's blur is divided out up to this E2PR (a gain of at most 1.57): beyond, the
/// division would raise the record's noise and the sawtooth of its end-to-end line (which the
/// Fourier interpolation takes as periodic) more than it restores; those lines keep the
/// recording's blur (the ratio of a linear tracker does not depend on it).
const DEBLUR_E2PR: f64 = 0.5;

pub use super::request::{TwinSettings, MAX_RUNS};

/// One vision mode of one run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwinRow {
    /// Run number, from 0.
    pub run: usize,
    /// Its seed.
    pub seed: u64,
    /// The sub-pixel offset of its path, px.
    pub shift_px: f64,
    /// Mode, from 1 in band order.
    pub mode: usize,
    /// Picked frequency of the run's vision H1, Hz.
    pub f_hz: f64,
    /// Its amplitude.
    pub amplitude: f64,
    /// The truth's picked frequency, Hz.
    pub truth_f_hz: f64,
    /// The truth's amplitude.
    pub truth_amplitude: f64,
}

/// What the twin found.
#[derive(Debug, Clone, PartialEq)]
pub struct Twin {
    /// The settings.
    pub settings: TwinSettings,
    /// Rows of the runs that succeeded, by run then mode.
    pub rows: Vec<TwinRow>,
    /// Runs that failed, and why.
    pub failed: Vec<(usize, String)>,
    /// The noise the frames were given, grey levels.
    pub sigma: f64,
    /// The exposure, ms (0: sharp frames).
    pub exposure_ms: f64,
    /// The recording's vision amplitudes per mode (what the bias is divided out of).
    pub recorded: Vec<f64>,
}

/// The recording as the twin needs it.
#[derive(Debug, Clone, Copy)]
pub struct Recording<'a> {
    /// The recording's analysis (its vision modes and amplitudes).
    pub analysis: &'a Analysis,
    /// The recording's displacement.
    pub disp: &'a Displacement,
    /// The frame the scene is taken from (the stillest, `StillestFrame`) and its index.
    pub template: (usize, &'a GreyFrame),
    /// The frames' noise.
    pub noise: NoiseEstimate,
    /// The accelerometer's input and output channels (whole records).
    pub accel: (&'a [f64], &'a [f64]),
}

/// Runs this shard's runs of the twin of `rec` as `req` analysed it; `tick` is called after
/// each run (a progress bar).
pub fn run(
    req: &super::request::Request,
    rec: Recording<'_>,
    settings: TwinSettings,
    tick: &(dyn Fn() + Sync),
) -> anyhow::Result<Twin> {
    let d = &req.displacement;
    let (index, template) = rec.template;
    let scene = Scene::new(template, req.centroid.roi, d.axis)?;
    let coord = coordinates(rec.disp, d, index);
    let fc = req.settings.frame_rate_hz;
    let exposure_s = req.settings.exposure_s.unwrap_or(0.0);
    let motion = motion(&coord, fc, exposure_s)?;
    // the truth: the motion at the frames' instants through the chain
    let at_frames: Vec<f64> = (0..coord.len()).map(|k| motion[k * STEPS]).collect();
    let (base, tip) = rec.accel;
    let truth = analyse(req, &at_frames, false, (base, tip))?;
    // a noise the frames do not show fairly is not put into the twin
    let sigma = rec.noise.usable();
    let config = CentroidConfig {
        roi: None,
        ..req.centroid
    };
    let results: Vec<(usize, anyhow::Result<Vec<TwinRow>>)> = settings
        .mine()
        .into_par_iter()
        .map(|r| {
            let seed = settings.seed.wrapping_add(r as u64);
            let out = one_run(
                req,
                (&scene, &motion, &config),
                (seed, sigma, exposure_s),
                (base, tip),
            )
            .map(|(shift, modes)| {
                modes
                    .iter()
                    .zip(&truth)
                    .enumerate()
                    .map(|(i, (m, t))| TwinRow {
                        run: r,
                        seed,
                        shift_px: shift,
                        mode: i + 1,
                        f_hz: m.f_hz,
                        amplitude: m.amplitude,
                        truth_f_hz: t.f_hz,
                        truth_amplitude: t.amplitude,
                    })
                    .collect()
            });
            tick();
            (r, out)
        })
        .collect();
    let mut rows = Vec::new();
    let mut failed = Vec::new();
    for (r, out) in results {
        match out {
            Ok(v) => rows.extend(v),
            Err(e) => failed.push((r, format!("{e:#}"))),
        }
    }
    Ok(Twin {
        settings,
        rows,
        failed,
        sigma,
        exposure_ms: exposure_s * 1000.0,
        recorded: rec.analysis.vis_modes.iter().map(|m| m.amplitude).collect(),
    })
}

/// The tracked coordinate along the axis, px, relative to frame `index` (the scene's),
/// growing as the image axis grows (down for `y`).
fn coordinates(disp: &Displacement, d: &DisplacementSettings, index: usize) -> Vec<f64> {
    let sign = image_sign(d.axis, d.invert);
    let c: Vec<f64> = disp.mm.iter().map(|m| sign * m / d.mm_per_px).collect();
    let c0 = c.get(index).or(c.first()).copied().unwrap_or(0.0);
    c.iter().map(|v| v - c0).collect()
}

/// The sign taking a displacement (as `analysis::displacement_mm` makes it) to the image
/// coordinate: `y` grows down while a displacement along `y` is positive up.
fn image_sign(axis: Axis, invert: bool) -> f64 {
    let s = match axis {
        Axis::X => 1.0,
        Axis::Y => -1.0,
    };
    if invert {
        -s
    } else {
        s
    }
}

/// The motion at [`STEPS`] steps a frame (`coord.len() * STEPS` values, step `k * STEPS` at
/// frame `k`): the line through the record's ends taken out, the rest divided by the box
/// transfer of `exposure_s` (up to [`DEBLUR_E2PR`]) and Fourier-interpolated, the line put
/// back.
fn motion(coord: &[f64], fc: f64, exposure_s: f64) -> anyhow::Result<Vec<f64>> {
    let n = coord.len();
    if n < 4 {
        return Err(crate::bad_input(format!(
            "$twin: {n} frames are too few to re-render"
        )));
    }
    let (first, last) = (coord[0], coord[n - 1]);
    let slope = (last - first) / (n - 1) as f64;
    let mut x: Vec<f64> = (0..n)
        .map(|k| coord[k] - first - slope * k as f64)
        .collect();
    let mut planner = vibcam_fft::RealPlanner::new();
    let fwd = planner.forward(n);
    let mut spec = fwd.make_output_vec();
    fwd.process(&mut x, &mut spec)
        .map_err(|e| anyhow::anyhow!("internal: {e}"))?;
    for (k, s) in spec.iter_mut().enumerate() {
        let e2pr = k as f64 * fc / n as f64 * exposure_s;
        if e2pr <= DEBLUR_E2PR {
            if let Some(r) = BoxTransfer.ratio(e2pr as f32) {
                *s /= f64::from(r);
            }
        }
    }
    let m = n * STEPS;
    let inv = planner.inverse(m);
    let mut big = inv.make_input_vec();
    let bins = spec.len();
    big[..bins].copy_from_slice(&spec);
    if n.is_multiple_of(2) {
        // the Nyquist line of the short record is split between +- fc/2 in the long one
        big[bins - 1] *= 0.5;
    }
    big[0].im = 0.0;
    let last_bin = big.len() - 1;
    big[last_bin].im = 0.0;
    let mut out = inv.make_output_vec();
    inv.process(&mut big, &mut out)
        .map_err(|e| anyhow::anyhow!("internal: {e}"))?;
    Ok(out
        .iter()
        .enumerate()
        .map(|(i, v)| v / n as f64 + first + slope * i as f64 / STEPS as f64)
        .collect())
}

/// The scene: the region as columns along the motion (transposed for `x`), padded.
#[derive(Debug, Clone)]
struct Scene {
    /// Columns (odd count), each padded to the renderer's height.
    columns: Vec<Vec<f32>>,
    /// Rows of the region (the frame the tracker sees is `columns.len() x rows`).
    rows: usize,
    /// Largest code.
    top: f64,
    /// 16-bit frames.
    wide: bool,
}

impl Scene {
    fn new(
        first: &GreyFrame,
        roi: Option<firmware_core::centroid::Roi>,
        axis: Axis,
    ) -> anyhow::Result<Scene> {
        let (w, h) = first.dimensions();
        let (x0, y0, cw, ch) = super::imaging_share::region(w, h, roi);
        let value = |x: usize, y: usize| -> f32 {
            let i = (y0 + y) * w + x0 + x;
            match first {
                GreyFrame::U8 { data, .. } => f32::from(data[i]),
                GreyFrame::U16 { data, .. } => f32::from(data[i]),
            }
        };
        // along the motion: rows of the region for y, its columns for x
        let (cols, rows) = match axis {
            Axis::Y => (cw, ch),
            Axis::X => (ch, cw),
        };
        if cols == 0 || rows < 4 {
            return Err(crate::bad_input(format!(
                "$twin: the centroid's region ({cw} x {ch} px) is too small to re-render"
            )));
        }
        let mut columns: Vec<Vec<f32>> = (0..cols)
            .map(|c| {
                (0..rows)
                    .map(|r| match axis {
                        Axis::Y => value(c, r),
                        Axis::X => value(r, c),
                    })
                    .collect()
            })
            .collect();
        if cols.is_multiple_of(2) {
            columns.push(columns[cols - 1].clone());
        }
        let (top, wide) = match first {
            GreyFrame::U8 { .. } => (255.0, false),
            GreyFrame::U16 { .. } => (65_535.0, true),
        };
        Ok(Scene {
            columns,
            rows,
            top,
            wide,
        })
    }

    /// A renderer for `path` (px, along the motion): the columns padded by a cosine blend from
    /// their last value back to their first over at least the path's reach and 16 rows.
    fn renderer(&self, path: &[f64]) -> anyhow::Result<BlurRenderer> {
        let reach = path.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let pad = (2.0 * reach).ceil() as usize + 16;
        let height = (self.rows + pad).div_ceil(16) * 16;
        let padded: Vec<Vec<f32>> = self
            .columns
            .iter()
            .map(|c| {
                let (a, b) = (c[self.rows - 1], c[0]);
                let extra = height - self.rows;
                let mut v = c.clone();
                v.extend((0..extra).map(|i| {
                    let t = (i as f32 + 1.0) / (extra as f32 + 1.0);
                    let s = 0.5 - 0.5 * (std::f32::consts::PI * t).cos();
                    a + (b - a) * s
                }));
                v
            })
            .collect();
        let mut r = BlurRenderer::from_columns(&padded)
            .ok_or_else(|| anyhow::anyhow!("internal: the twin's scene has no columns"))?;
        r.set_path(path, 64);
        Ok(r)
    }
}

/// One run: its sub-pixel offset and the vision modes of its analysis.
fn one_run(
    req: &super::request::Request,
    (scene, motion, config): (&Scene, &[f64], &CentroidConfig),
    (seed, sigma, exposure_s): (u64, f64, f64),
    (base, tip): (&[f64], &[f64]),
) -> anyhow::Result<(f64, Vec<crate::chain::frf::PickedMode>)> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let shift = rng.random::<f64>() - 0.5;
    let path: Vec<f64> = motion.iter().map(|v| v + shift).collect();
    let mut renderer = scene.renderer(&path)?;
    let noise = Normal::new(0.0, sigma.max(0.0)).map_err(|e| anyhow::anyhow!("{e}"))?;
    let fc = req.settings.frame_rate_hz;
    let half = 0.5 * exposure_s * fc * STEPS as f64;
    let frames = motion.len() / STEPS;
    let (w, h) = (renderer.width(), renderer.height());
    let mut img = vec![0.0f32; w * h];
    let mut frame = if scene.wide {
        GreyFrame::U16 {
            width: scene.columns.len(),
            height: scene.rows,
            data: Vec::new(),
        }
    } else {
        GreyFrame::U8 {
            width: scene.columns.len(),
            height: scene.rows,
            data: Vec::new(),
        }
    };
    let mut centroids = Vec::with_capacity(frames);
    let (fw, fh) = (scene.columns.len(), scene.rows);
    for k in 0..frames {
        let t = (k * STEPS) as f64;
        renderer.render_float(t - half, t + half, &mut img);
        let mut px = |x: usize, y: usize| -> f64 {
            let v = f64::from(img[y * w + x + 2])
                + if sigma > 0.0 {
                    noise.sample(&mut rng)
                } else {
                    0.0
                };
            v.round().clamp(0.0, scene.top)
        };
        match &mut frame {
            GreyFrame::U8 { .. } => {
                let mut vals = Vec::with_capacity(fw * fh);
                for y in 0..fh {
                    for x in 0..fw {
                        vals.push(px(x, y) as u8);
                    }
                }
                frame.u8_pixels(fw, fh).copy_from_slice(&vals);
            }
            GreyFrame::U16 { .. } => {
                let mut vals = Vec::with_capacity(fw * fh);
                for y in 0..fh {
                    for x in 0..fw {
                        vals.push(px(x, y) as u16);
                    }
                }
                frame.u16_pixels(fw, fh).copy_from_slice(&vals);
            }
        }
        centroids.push(frame.centroid(config, &format!("twin frame {}", k + 1))?);
    }
    // the motion runs along the frame's rows: the analysed axis's sign taken over
    let d = &req.displacement;
    let settings = DisplacementSettings {
        axis: Axis::Y,
        invert: image_sign(d.axis, d.invert) != image_sign(Axis::Y, false),
        ..*d
    };
    let disp = super::displacement_mm(&centroids, &settings)?;
    let modes = analyse_disp(req, &disp, true, (base, tip))?;
    Ok((shift, modes))
}

/// The vision modes of the chain on a coordinate record (px, image axis growing, at the
/// frames' instants), without imaging.
fn analyse(
    req: &super::request::Request,
    coord: &[f64],
    compensate: bool,
    accel: (&[f64], &[f64]),
) -> anyhow::Result<Vec<crate::chain::frf::PickedMode>> {
    let d = &req.displacement;
    let sign = image_sign(d.axis, d.invert);
    let mean = coord.iter().sum::<f64>() / coord.len().max(1) as f64;
    let disp = Displacement {
        mm: coord
            .iter()
            .map(|c| sign * (c - mean) * d.mm_per_px)
            .collect(),
        lost: vec![false; coord.len()],
        lost_count: 0,
        reference_px: mean,
        policy: LostFramePolicy::Interpolate,
    };
    analyse_disp(req, &disp, compensate, accel)
}

/// The vision modes of `req`'s chain on `disp`, compensated as the recording's were when
/// `compensate`.
fn analyse_disp(
    req: &super::request::Request,
    disp: &Displacement,
    compensate: bool,
    (base, tip): (&[f64], &[f64]),
) -> anyhow::Result<Vec<crate::chain::frf::PickedMode>> {
    if disp.failed() {
        return Err(crate::bad_input(format!(
            "{} of {} twin frames lost their target",
            disp.lost_count,
            disp.mm.len()
        )));
    }
    let mut a = super::analyze(disp, base, tip, &req.settings)?;
    if let (true, true, Some(e)) = (compensate, req.compensate_exposure, req.settings.exposure_s) {
        super::compensate::compensate(&mut a, e, &req.settings.bands, req.binary)?;
    }
    Ok(a.vis_modes)
}

/// Per mode: the runs' amplitude ratios and frequency differences.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwinMode {
    /// Mode, from 1.
    pub mode: usize,
    /// Runs.
    pub runs: usize,
    /// Mean of the runs' amplitude / the truth's.
    pub ratio: f64,
    /// Standard uncertainty of that mean.
    pub ratio_u: f64,
    /// 2.5 and 97.5 percentiles of the runs' ratios.
    pub ratio_lo: f64,
    /// See `ratio_lo`.
    pub ratio_hi: f64,
    /// Mean frequency difference, run - truth, Hz.
    pub df_hz: f64,
    /// Standard deviation of the runs' frequency differences, Hz.
    pub df_sd_hz: f64,
}

impl Twin {
    /// The summary per mode (modes without rows are left out).
    pub fn modes(&self) -> Vec<TwinMode> {
        let modes = self.rows.iter().map(|r| r.mode).max().unwrap_or(0);
        (1..=modes)
            .filter_map(|m| {
                let rows: Vec<&TwinRow> = self.rows.iter().filter(|r| r.mode == m).collect();
                if rows.is_empty() {
                    return None;
                }
                let mut ratios: Vec<f64> = rows
                    .iter()
                    .map(|r| r.amplitude / r.truth_amplitude)
                    .collect();
                let df: Vec<f64> = rows.iter().map(|r| r.f_hz - r.truth_f_hz).collect();
                let n = ratios.len();
                let mean = ratios.iter().sum::<f64>() / n as f64;
                let sd = crate::stats::std_dev(&ratios).unwrap_or(0.0);
                ratios.sort_by(f64::total_cmp);
                let q = |p: f64| ratios[((p * (n - 1) as f64).round() as usize).min(n - 1)];
                Some(TwinMode {
                    mode: m,
                    runs: n,
                    ratio: mean,
                    ratio_u: sd / (n as f64).sqrt(),
                    ratio_lo: q(0.025),
                    ratio_hi: q(0.975),
                    df_hz: df.iter().sum::<f64>() / n as f64,
                    df_sd_hz: crate::stats::std_dev(&df).unwrap_or(0.0),
                })
            })
            .collect()
    }

    /// `twin.csv`: one row per run and mode.
    pub fn csv(&self) -> String {
        let mut s = String::from(
            "run,seed,shift_px,mode,f_hz,amplitude,truth_f_hz,truth_amplitude,ratio\n",
        );
        for r in &self.rows {
            s += &format!(
                "{},{},{},{},{},{},{},{},{}\n",
                r.run,
                r.seed,
                r.shift_px,
                r.mode,
                r.f_hz,
                r.amplitude,
                r.truth_f_hz,
                r.truth_amplitude,
                r.amplitude / r.truth_amplitude
            );
        }
        s
    }

    /// The report's section.
    pub fn report(&self) -> String {
        let mine = self.settings.mine().len();
        let sh = self.settings.shard;
        let shard = if sh == Shard::ALL {
            String::new()
        } else {
            format!(", shard {} of {}: {mine} of the runs", sh.index, sh.count)
        };
        let mut s = format!(
            "\ntwin (method.md 3.10.3): {} runs seeded {}..{}{shard}: the stillest frame's \
             region moved along the tracked motion{}, exposed {} ms, {}, through the same \
             centroid and analysis{}; ratio = the run's vision amplitude over the \
             truth's (the motion through the chain without imaging)\n",
            self.settings.runs,
            self.settings.seed,
            self.settings.seed + self.settings.runs as u64 - 1,
            if self.exposure_ms > 0.0 {
                " (its own blur divided out)"
            } else {
                ""
            },
            self.exposure_ms,
            if self.sigma > 0.0 {
                format!("noise {:.3} grey levels", self.sigma)
            } else {
                "no noise (the frames gave no fair sample of theirs)".to_string()
            },
            if self.failed.is_empty() {
                String::new()
            } else {
                format!("; {} run(s) FAILED", self.failed.len())
            }
        );
        for m in self.modes() {
            let bias = m.ratio - 1.0;
            if m.runs < 2 {
                // one run has no spread: an interval of zero width would claim an exact bias
                s += &format!(
                    "  mode {}: amplitude ratio {:.5} (bias {:+.3} %) from a single run: no \
                     uncertainty and no interval (2 runs or more give them), and the bias is \
                     not divided out of the recording's amplitude; frequency {:+.4} Hz\n",
                    m.mode,
                    m.ratio,
                    100.0 * bias,
                    m.df_hz
                );
                continue;
            }
            s += &format!(
                "  mode {}: amplitude ratio {:.5} +- {:.5} (bias {:+.3} %; 95 % of the {} runs \
                 within {:.5}..{:.5}); frequency {:+.4} Hz (sd {:.4})\n",
                m.mode,
                m.ratio,
                m.ratio_u,
                100.0 * bias,
                m.runs,
                m.ratio_lo,
                m.ratio_hi,
                m.df_hz,
                m.df_sd_hz
            );
            if let Some(a) = self.recorded.get(m.mode - 1) {
                s += &format!(
                    "    the recording's vision amplitude {a:.5}, the twin's bias divided out: \
                     {:.5} (95 % over the runs: {:.5}..{:.5})\n",
                    a / m.ratio,
                    a / m.ratio_hi,
                    a / m.ratio_lo
                );
            }
        }
        for (r, why) in self.failed.iter().take(5) {
            s += &format!("  run {r} failed: {why}\n");
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_motion_is_interpolated_and_its_blur_divided_out() {
        // a cosine at 10 Hz sampled at 100 fps over whole periods, symmetric about the record's
        // middle (its ends equal: no end-to-end line), blurred by a 20 ms box (E2PR 0.2)
        let (fc, f, te) = (100.0, 10.0, 0.02);
        let n = 200;
        let mid = (n - 1) as f64 / 2.0;
        let blur = (std::f64::consts::PI * f * te).sin() / (std::f64::consts::PI * f * te);
        let wave = |t: f64| 3.0 * (std::f64::consts::TAU * f * (t - mid / fc)).cos();
        let coord: Vec<f64> = (0..n).map(|k| blur * wave(k as f64 / fc)).collect();
        let m = motion(&coord, fc, te).unwrap();
        assert_eq!(m.len(), n * STEPS);
        for (i, v) in m.iter().enumerate() {
            let want = wave(i as f64 / (fc * STEPS as f64));
            // the transfer is firmware-core's, in f32
            assert!((v - want).abs() < 1e-6, "{i}: {v} {want}");
        }
        // without an exposure, the frames' values come back at the frames' steps
        let m = motion(&coord, fc, 0.0).unwrap();
        for k in 0..n {
            assert!((m[k * STEPS] - coord[k]).abs() < 1e-9);
        }
    }

    #[test]
    fn a_renderer_of_columns_translates_the_image() {
        // a smooth bump translated by 2.5 px: its centre of mass moves by 2.5 px
        let h = 64;
        let col: Vec<f32> = (0..h)
            .map(|y| 100.0 * (-((y as f32 - 30.0) / 3.0).powi(2)).exp())
            .collect();
        let cols = vec![col.clone(), col.clone(), col];
        let mut r = BlurRenderer::from_columns(&cols).unwrap();
        r.set_path(&[2.5, 2.5], 1);
        let mut img = vec![0.0f32; r.width() * r.height()];
        r.render_float(0.0, 0.0, &mut img);
        let w = r.width();
        let (mut m0, mut m1) = (0.0, 0.0);
        for y in 0..h {
            let v = f64::from(img[y * w + 3]);
            m0 += v;
            m1 += v * y as f64;
        }
        assert!((m1 / m0 - 32.5).abs() < 1e-3, "{}", m1 / m0);
        assert!(BlurRenderer::from_columns(&[vec![0.0; 8], vec![0.0; 8]]).is_none());
    }
}
