//! The analysis chain of a real (or synthetic) recording, as on the rig (SPEC 3.2): pure
//! functions on in-memory frames and arrays, shared by `host-harness analyze` and anyone who
//! wants to run the chain from code.
//!
//! ```text
//! frames ──> centroid (firmware-core, threshold, binary/weighted, ROI) ──> displacement, mm
//!        ──> lost frames filled by linear interpolation (counted; > 5 % lost = failed)
//!        ──> Fourier upsampling fc -> fa fused with -omega^2 (firmware-core) ──> m/s^2
//! accelerometer CSV ──> cut to the span the frames cover (alignment) ──┐
//!        H1(base -> tip) and H1(base -> vision) (firmware-core Welch) <─┘
//!        ──> peaks in bands (firmware-core) ──> modes of both systems, E2PR
//! ```
//!
//! # Conventions
//!
//! * **Displacement sign.** Image `x` grows to the right and `y` grows *down* (SPEC 2.1). With
//!   [`Axis::Y`] (the default) the displacement is positive **upwards in the image**:
//!   `d = -(cy - cy_ref) * mm_per_px`; with [`Axis::X`] it is positive to the right:
//!   `d = (cx - cx_ref) * mm_per_px`. `invert` flips either. The reference `c_ref` is the mean
//!   centroid of the valid frames (the DC level plays no role in the FRF: the -omega^2 step
//!   zeroes it).
//! * **Lost frames.** A frame without any pixel above the threshold has no centroid. Its
//!   displacement is interpolated linearly between the nearest valid frames before and after;
//!   lost frames at the start or the end of the record take the value of the nearest valid frame.
//!   More than [`MAX_LOST_FRACTION`] of lost frames makes the analysis fail.
//! * **Alignment.** `time_offset_s` is the time of the first frame minus the time of the first
//!   accelerometer sample. The upsampled vision record starts at the accelerometer sample
//!   `round(time_offset_s * fa)` and has `M = N * fa / fc` samples; the rounding residual
//!   (at most half an accelerometer period) is a pure delay of the vision channel, which is
//!   removed from the vision H1 exactly (`H1 * exp(-i omega residual)`), and reported.
//! * **Units.** Accelerations are in m/s^2 (the accelerometer CSV must be in m/s^2); the FRFs are
//!   dimensionless (acceleration over acceleration).

use crate::bad_input;
use firmware_core::centroid::{self, Centroid, CentroidConfig};
use num_complex::Complex64;

/// Largest fraction of lost frames (no centroid) an analysis accepts: 5 % (SPEC 3.1).
pub const MAX_LOST_FRACTION: f64 = 0.05;

/// A grey frame in memory, 8 or 16 bits per pixel, row-major without padding.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum GreyFrame {
    /// 8-bit pixels.
    U8 {
        /// Columns.
        width: usize,
        /// Rows.
        height: usize,
        /// `width * height` pixels, row 0 first.
        data: Vec<u8>,
    },
    /// 16-bit pixels.
    U16 {
        /// Columns.
        width: usize,
        /// Rows.
        height: usize,
        /// `width * height` pixels, row 0 first.
        data: Vec<u16>,
    },
}

impl GreyFrame {
    /// `(width, height)` in pixels.
    pub fn dimensions(&self) -> (usize, usize) {
        match self {
            GreyFrame::U8 { width, height, .. } | GreyFrame::U16 { width, height, .. } => {
                (*width, *height)
            }
        }
    }
}

/// Centroid of one frame with the firmware-core single-target centroider.
///
/// `label` names the frame (file, page) in the error when the frame's shape is inconsistent.
pub fn centroid_frame(
    frame: &GreyFrame,
    config: &CentroidConfig,
    label: &str,
) -> anyhow::Result<Centroid> {
    let r = match frame {
        GreyFrame::U8 {
            width,
            height,
            data,
        } => centroid::Frame::new(data, *width, *height, *width)
            .and_then(|f| centroid::centroid(config, &f)),
        GreyFrame::U16 {
            width,
            height,
            data,
        } => centroid::Frame::new(data, *width, *height, *width)
            .and_then(|f| centroid::centroid(config, &f)),
    };
    r.map_err(|e| bad_input(format!("{label}: cannot centroid the frame: {e}")))
}

/// Which image axis carries the displacement (see the module documentation for the sign).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Axis {
    /// Horizontal: positive to the right.
    X,
    /// Vertical: positive upwards in the image (image `y` grows down).
    #[default]
    Y,
}

impl Axis {
    /// `"x"` or `"y"`.
    pub fn name(self) -> &'static str {
        match self {
            Axis::X => "x",
            Axis::Y => "y",
        }
    }
}

/// Pixel-to-millimetre conversion of the centroids.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DisplacementSettings {
    /// Scale, millimetres per pixel (> 0).
    pub mm_per_px: f64,
    /// Image axis of the motion.
    pub axis: Axis,
    /// Flip the sign.
    pub invert: bool,
}

/// Displacement record of the camera, one value per frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Displacement {
    /// Displacement, mm (lost frames interpolated), one per frame.
    pub mm: Vec<f64>,
    /// `true` for the frames that had no centroid.
    pub lost: Vec<bool>,
    /// Number of lost frames.
    pub lost_count: usize,
    /// Reference centroid coordinate along the axis (mean of the valid frames), pixels.
    pub reference_px: f64,
}

impl Displacement {
    /// Fraction of lost frames, 0..=1.
    pub fn lost_fraction(&self) -> f64 {
        if self.mm.is_empty() {
            0.0
        } else {
            self.lost_count as f64 / self.mm.len() as f64
        }
    }
}

/// Fills the `None` entries by linear interpolation between the nearest `Some` neighbours;
/// leading and trailing `None`s take the nearest value. `None` when there is no value at all.
pub fn interpolate_lost(values: &[Option<f64>]) -> Option<Vec<f64>> {
    let known: Vec<(usize, f64)> = values
        .iter()
        .enumerate()
        .filter_map(|(i, v)| v.map(|v| (i, v)))
        .collect();
    let (&(i_first, v_first), &(i_last, v_last)) = (known.first()?, known.last()?);
    let mut out = vec![0.0; values.len()];
    for (o, v) in out.iter_mut().zip(values).take(i_first) {
        debug_assert!(v.is_none());
        *o = v_first;
    }
    for w in known.windows(2) {
        let ((i0, v0), (i1, v1)) = (w[0], w[1]);
        for (k, o) in out.iter_mut().enumerate().take(i1).skip(i0) {
            let t = (k - i0) as f64 / (i1 - i0) as f64;
            *o = v0 + t * (v1 - v0);
        }
    }
    for o in out.iter_mut().skip(i_last) {
        *o = v_last;
    }
    Some(out)
}

/// Converts the per-frame centroids to a displacement in mm (sign and reference: see the module
/// documentation), filling the lost frames. Errors when no frame has a centroid. The lost
/// fraction is *not* checked here (see [`MAX_LOST_FRACTION`] and [`analyze`]).
pub fn displacement_mm(
    centroids: &[Centroid],
    s: &DisplacementSettings,
) -> anyhow::Result<Displacement> {
    if !(s.mm_per_px.is_finite() && s.mm_per_px > 0.0) {
        return Err(bad_input(format!(
            "the scale must be a positive number of mm per pixel, got {}",
            s.mm_per_px
        )));
    }
    let coord: Vec<Option<f64>> = centroids
        .iter()
        .map(|c| {
            c.position().map(|(x, y)| match s.axis {
                Axis::X => f64::from(x),
                Axis::Y => f64::from(y),
            })
        })
        .collect();
    let lost: Vec<bool> = coord.iter().map(Option::is_none).collect();
    let lost_count = lost.iter().filter(|&&l| l).count();
    let filled = interpolate_lost(&coord).ok_or_else(|| {
        bad_input(format!(
            "none of the {} frames has a pixel above the threshold: no centroid at all \
             (check --threshold and --roi)",
            centroids.len()
        ))
    })?;
    let valid: Vec<f64> = coord.iter().flatten().copied().collect();
    let reference_px = valid.iter().sum::<f64>() / valid.len() as f64;
    let sign = match (s.axis, s.invert) {
        (Axis::X, false) | (Axis::Y, true) => 1.0,
        (Axis::X, true) | (Axis::Y, false) => -1.0,
    };
    let mm = filled
        .iter()
        .map(|c| sign * (c - reference_px) * s.mm_per_px)
        .collect();
    Ok(Displacement {
        mm,
        lost,
        lost_count,
        reference_px,
    })
}

/// `x / y` as an integer when it is one (relative tolerance 1e-9), else `None`.
fn integer_ratio(x: f64, y: f64) -> Option<usize> {
    let r = x / y;
    if !r.is_finite() || r < 0.5 {
        return None;
    }
    let n = r.round();
    ((r - n).abs() <= 1e-9 * n.max(1.0)).then_some(n as usize)
}

/// Where the frames sit in the accelerometer record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Alignment {
    /// Accelerometer sample index of the first upsampled vision sample.
    pub start: usize,
    /// Number of accelerometer samples covered by the frames, `M = N * fa / fc`.
    pub len: usize,
    /// Time of the first frame minus the time of accelerometer sample `start`, seconds
    /// (`|residual| <= 0.5 / fa`): the rounding of the alignment to whole samples.
    pub residual_s: f64,
}

/// Places `frames` frames at `fc` Hz, the first at `time_offset_s` after the first of
/// `samples` accelerometer samples at `fa` Hz (see the module documentation).
///
/// Errors: rates not positive, `N * fa / fc` not an integer, the frames start before the
/// accelerometer record, or the accelerometer record is too short for the frames (the message
/// names both counts and durations).
pub fn align(
    frames: usize,
    fc: f64,
    samples: usize,
    fa: f64,
    time_offset_s: f64,
) -> anyhow::Result<Alignment> {
    if !(fc.is_finite() && fc > 0.0 && fa.is_finite() && fa > 0.0) {
        return Err(bad_input(format!(
            "the frame rate ({fc} Hz) and the accelerometer rate ({fa} Hz) must be positive"
        )));
    }
    if !time_offset_s.is_finite() {
        return Err(bad_input(
            "the time offset must be a finite number of seconds",
        ));
    }
    let len = integer_ratio(frames as f64 * fa, fc).ok_or_else(|| {
        bad_input(format!(
            "{frames} frames at {fc} fps span {} s, which is {} accelerometer samples at {fa} Hz: \
             not a whole number (the Fourier upsampling needs N * fa / fc to be an integer)",
            frames as f64 / fc,
            frames as f64 * fa / fc
        ))
    })?;
    let exact = time_offset_s * fa;
    let start_f = exact.round();
    if start_f < 0.0 {
        return Err(bad_input(format!(
            "the first frame is {} s before the first accelerometer sample: the accelerometer \
             record must cover the frames (time offset = first frame - first sample >= 0)",
            -time_offset_s
        )));
    }
    let start = start_f as usize;
    if start.saturating_add(len) > samples {
        return Err(bad_input(format!(
            "the frame count does not match the accelerometer record: {frames} frames at {fc} fps \
             ({:.6} s) starting {time_offset_s} s after the first sample need samples {start}..{} \
             at {fa} Hz ({:.6} s), but the accelerometer CSV has {samples} samples ({:.6} s)",
            frames as f64 / fc,
            start + len,
            (start + len) as f64 / fa,
            samples as f64 / fa
        )));
    }
    Ok(Alignment {
        start,
        len,
        residual_s: (exact - start_f) / fa,
    })
}

/// Time offset (first frame minus first sample, s) from a tick offset on a common time base
/// of `tick_hz` (SPEC 2.7).
pub fn tick_offset_to_seconds(ticks: i64, tick_hz: f64) -> anyhow::Result<f64> {
    if !(tick_hz.is_finite() && tick_hz > 0.0) {
        return Err(bad_input(format!(
            "--tick-hz must be a positive rate, got {tick_hz}"
        )));
    }
    Ok(ticks as f64 / tick_hz)
}

/// Checks an accelerometer time column: strictly increasing, steps of `1 / fs` (within 5 %).
/// `first_row` is the spreadsheet row of `t[0]` (2 after a header), so errors name the row.
pub fn check_time_column(t: &[f64], fs: f64, source: &str, first_row: usize) -> anyhow::Result<()> {
    let dt = 1.0 / fs;
    for (i, w) in t.windows(2).enumerate() {
        let row = first_row + i + 1;
        let step = w[1] - w[0];
        if step <= 0.0 {
            return Err(bad_input(format!(
                "{source}: row {row}: time {} is not after the previous row's {}: the time \
                 column must be strictly increasing",
                w[1], w[0]
            )));
        }
        if (step - dt).abs() > 0.05 * dt {
            return Err(bad_input(format!(
                "{source}: row {row}: time step {step} s does not match --fs {fs} Hz \
                 (expected {dt} s)"
            )));
        }
    }
    Ok(())
}

/// Welch window: firmware-core's own type (periodic Hann, the default; periodic Hamming;
/// rectangular), so the settings reach the estimator in [`h1`] unchanged.
pub use firmware_core::spectrum::Window;

/// Welch H1 settings. The defaults are the cantilever rig's: one periodic Hann segment over the
/// whole record (`nperseg = nfft =` record length), mean removed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WelchSettings {
    /// Window of each segment.
    pub window: Window,
    /// Segment length, samples; `None` = the whole record.
    pub nperseg: Option<usize>,
    /// Overlap, samples; `None` = 0 for a single whole-record segment, else `nperseg / 2`.
    pub noverlap: Option<usize>,
    /// FFT length (>= nperseg, zero padding); `None` = `nperseg`.
    pub nfft: Option<usize>,
    /// Subtract each segment's mean ("constant" detrend).
    pub detrend: bool,
}

impl Default for WelchSettings {
    fn default() -> Self {
        WelchSettings {
            window: Window::Hann,
            nperseg: None,
            noverlap: None,
            nfft: None,
            detrend: true,
        }
    }
}

/// The Welch settings resolved for a record of `len` samples: `(nperseg, noverlap, nfft)`.
pub fn resolve_welch(w: &WelchSettings, len: usize) -> anyhow::Result<(usize, usize, usize)> {
    let nperseg = w.nperseg.unwrap_or(len);
    if nperseg == 0 || nperseg > len {
        return Err(bad_input(format!(
            "--nperseg {nperseg} must be between 1 and the record length {len}"
        )));
    }
    let noverlap = w
        .noverlap
        .unwrap_or(if nperseg == len { 0 } else { nperseg / 2 });
    if noverlap >= nperseg {
        return Err(bad_input(format!(
            "--noverlap {noverlap} must be smaller than --nperseg {nperseg}"
        )));
    }
    let nfft = w.nfft.unwrap_or(nperseg);
    if nfft < nperseg {
        return Err(bad_input(format!(
            "--nfft {nfft} must be at least --nperseg {nperseg}"
        )));
    }
    Ok((nperseg, noverlap, nfft))
}

/// An H1 frequency response with its coherence.
#[derive(Debug, Clone, PartialEq)]
pub struct Frf {
    /// Bin frequencies, Hz (`k fs / nfft`, `k = 0..=nfft/2`).
    pub freq_hz: Vec<f64>,
    /// H1 = Pxy / Pxx per bin.
    pub h1: Vec<Complex64>,
    /// |Pxy|^2 / (Pxx Pyy) per bin, 0..=1.
    pub coherence: Vec<f64>,
}

/// One picked mode: the bin of largest |Im H1| in a band (SPEC 2.5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PickedMode {
    /// Band searched, Hz.
    pub band_hz: (f64, f64),
    /// Resonance frequency, Hz.
    pub f_hz: f64,
    /// |H1| at that bin.
    pub amplitude: f64,
    /// Bin index in the FRF.
    pub bin: usize,
    /// Exposure-to-period ratio (exposure x `f_hz`), when the exposure is known.
    pub e2pr: Option<f64>,
}

/// Everything the chain needs besides the data.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// Camera frame rate `fc`, Hz.
    pub frame_rate_hz: f64,
    /// Accelerometer sample rate `fa`, Hz.
    pub accel_rate_hz: f64,
    /// Time of the first frame minus time of the first accelerometer sample, s.
    pub time_offset_s: f64,
    /// Welch H1 settings (applied to both systems).
    pub welch: WelchSettings,
    /// Frequency bands of the modes, Hz, `lo < hi`.
    pub bands: Vec<(f64, f64)>,
    /// Camera exposure time, s (for the E2PR), when known.
    pub exposure_s: Option<f64>,
}

/// The cantilever bands: mode 1 in [5, 15] Hz, mode 2 in [25, 45] Hz (SPEC 3.2).
pub const CANTILEVER_BANDS: [(f64, f64); 2] = [(5.0, 15.0), (25.0, 45.0)];

/// Result of [`analyze`].
#[derive(Debug, Clone, PartialEq)]
pub struct Analysis {
    /// Where the frames sit in the accelerometer record.
    pub alignment: Alignment,
    /// `(nperseg, noverlap, nfft)` actually used.
    pub welch: (usize, usize, usize),
    /// Vision acceleration at the accelerometer rate, m/s^2 (`alignment.len` samples).
    pub vision_acc: Vec<f64>,
    /// Accelerometer system: H1(base -> tip).
    pub acc_frf: Frf,
    /// Vision system: H1(base -> vision), delay residual removed.
    pub vis_frf: Frf,
    /// Modes of the accelerometer system, one per band.
    pub acc_modes: Vec<PickedMode>,
    /// Modes of the vision system, one per band.
    pub vis_modes: Vec<PickedMode>,
}

/// Runs the chain after the centroids: checks the lost fraction, upsamples the displacement to
/// the accelerometer rate as an acceleration, cuts the accelerometer record (`base`, `tip`, in
/// m/s^2, at `fa`) to the frames' span, estimates both H1 and picks the modes.
pub fn analyze(
    disp: &Displacement,
    base: &[f64],
    tip: &[f64],
    s: &Settings,
) -> anyhow::Result<Analysis> {
    if base.len() != tip.len() {
        return Err(bad_input(format!(
            "the accelerometer channels differ in length ({} and {})",
            base.len(),
            tip.len()
        )));
    }
    if disp.lost_fraction() > MAX_LOST_FRACTION {
        return Err(bad_input(format!(
            "analysis FAILED: {} of {} frames ({:.1} %) have no centroid, more than the {} % \
             allowed (check --threshold, --roi, the exposure and the lighting)",
            disp.lost_count,
            disp.mm.len(),
            100.0 * disp.lost_fraction(),
            100.0 * MAX_LOST_FRACTION
        )));
    }
    for &(lo, hi) in &s.bands {
        if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo < hi) {
            return Err(bad_input(format!("band {lo}-{hi} Hz: need 0 <= lo < hi")));
        }
    }
    let fa = s.accel_rate_hz;
    let alignment = align(
        disp.mm.len(),
        s.frame_rate_hz,
        base.len(),
        fa,
        s.time_offset_s,
    )?;
    let span = alignment.start..alignment.start + alignment.len;
    let (base, tip) = (&base[span.clone()], &tip[span]);
    let vision_acc = vision_acceleration(&disp.mm, s.frame_rate_hz, fa, alignment.len)?;
    let welch = resolve_welch(&s.welch, alignment.len)?;
    let acc_frf = h1(base, tip, fa, &s.welch, welch)?;
    let mut vis_frf = h1(base, &vision_acc, fa, &s.welch, welch)?;
    if alignment.residual_s != 0.0 {
        for (h, f) in vis_frf.h1.iter_mut().zip(&vis_frf.freq_hz) {
            *h *=
                Complex64::from_polar(1.0, -2.0 * std::f64::consts::PI * f * alignment.residual_s);
        }
    }
    let acc_modes = pick_modes(&acc_frf, &s.bands, s.exposure_s)?;
    let vis_modes = pick_modes(&vis_frf, &s.bands, s.exposure_s)?;
    Ok(Analysis {
        alignment,
        welch,
        vision_acc,
        acc_frf,
        vis_frf,
        acc_modes,
        vis_modes,
    })
}

/// Fourier upsampling of the displacement (mm, `N` samples at `fc`) to `m` samples at `fa`,
/// fused with the `-omega^2` differentiation and the mm -> m scaling, with firmware-core's
/// [`firmware_core::upsample::Upsampler::process_acceleration`] (`f32`): acceleration in m/s^2.
///
/// Runs on a helper thread with a large stack (the upsampler's fixed buffers are about
/// 1.5 MiB at [`MAX_NFFT`]).
pub fn vision_acceleration(
    disp_mm: &[f64],
    fc: f64,
    fa: f64,
    m: usize,
) -> anyhow::Result<Vec<f64>> {
    use firmware_core::upsample::Upsampler;
    let n = disp_mm.len();
    let _ = fa;
    let input: Vec<f32> = disp_mm.iter().map(|&v| v as f32).collect();
    let run = move || -> Result<Vec<f32>, String> {
        let mut up =
            Upsampler::<MAX_NFFT, WELCH_SCRATCH>::try_new(n, m).map_err(|e| e.to_string())?;
        let mut out = vec![0.0f32; m];
        up.process_acceleration(&input, &mut out, fc as f32, 1.0e-3)
            .map_err(|e| e.to_string())?;
        Ok(out)
    };
    let out = std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(run)
        .map_err(|e| anyhow::anyhow!("cannot start the upsampling thread: {e}"))?
        .join()
        .map_err(|_| anyhow::anyhow!("the upsampler panicked"))?
        .map_err(|e| {
            bad_input(format!(
                "upsampling {n} frames to {m} samples (at most {MAX_NFFT}): {e}"
            ))
        })?;
    Ok(out.into_iter().map(f64::from).collect())
}

/// Capacity of the firmware Welch estimator used on the host: segments and FFTs of up to
/// 65 536 samples (32 s at 2048 Hz in one segment).
pub const MAX_NFFT: usize = 65_536;
/// DFT scratch for any supported length up to [`MAX_NFFT`] (Bluestein: `n + 2 l`, `l <= 32768`).
const WELCH_SCRATCH: usize = MAX_NFFT + 2 * firmware_core::dft::MAX_POW2;

/// Welch H1 and coherence of `y` against `x` (both at `fs`) with firmware-core's streaming
/// estimator ([`firmware_core::spectrum::WelchH1`], `f32`), read out in `f64`.
///
/// The estimator's fixed buffers (a few MiB at [`MAX_NFFT`]) live on the stack of a helper
/// thread with a large stack, so callers on small-stack threads are safe.
pub fn h1(
    x: &[f64],
    y: &[f64],
    fs: f64,
    w: &WelchSettings,
    (nperseg, noverlap, nfft): (usize, usize, usize),
) -> anyhow::Result<Frf> {
    use firmware_core::spectrum::{Detrend, WelchConfig, WelchH1};
    let config = WelchConfig {
        fs_hz: fs as f32,
        nperseg,
        noverlap,
        nfft,
        window: w.window,
        detrend: if w.detrend {
            Detrend::Constant
        } else {
            Detrend::None
        },
    };
    let xf: Vec<f32> = x.iter().map(|&v| v as f32).collect();
    let yf: Vec<f32> = y.iter().map(|&v| v as f32).collect();
    let run = move || -> Result<(Vec<Complex64>, Vec<f64>, u32), String> {
        let mut welch = WelchH1::<MAX_NFFT, MAX_NFFT, WELCH_SCRATCH>::try_new(config)
            .map_err(|e| e.to_string())?;
        welch.push(&xf, &yf).map_err(|e| e.to_string())?;
        let bins = welch.bins();
        let mut h = vec![firmware_core::Complex32::new(0.0, 0.0); bins];
        let mut c = vec![0.0f32; bins];
        welch.fill_h1(&mut h).map_err(|e| e.to_string())?;
        welch.fill_coherence(&mut c).map_err(|e| e.to_string())?;
        Ok((
            h.iter()
                .map(|v| Complex64::new(f64::from(v.re), f64::from(v.im)))
                .collect(),
            c.iter().map(|&v| f64::from(v)).collect(),
            welch.skipped_segments(),
        ))
    };
    let (h1, coherence, skipped) = std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(run)
        .map_err(|e| anyhow::anyhow!("cannot start the Welch thread: {e}"))?
        .join()
        .map_err(|_| anyhow::anyhow!("the Welch estimator panicked"))?
        .map_err(|e| {
            bad_input(format!(
                "H1 (nperseg {nperseg}, noverlap {noverlap}, nfft {nfft}, at most \
                 {MAX_NFFT}): {e}"
            ))
        })?;
    if skipped > 0 {
        return Err(bad_input(format!(
            "H1: {skipped} segment(s) contain non-finite or huge samples"
        )));
    }
    let freq_hz = (0..h1.len()).map(|k| k as f64 * fs / nfft as f64).collect();
    Ok(Frf {
        freq_hz,
        h1,
        coherence,
    })
}

/// Picks one mode per band with firmware-core's [`firmware_core::peaks::pick`]: the bin of
/// largest |Im H1| with `lo <= f <= hi`, no sub-bin refinement (the paper's method).
pub fn pick_modes(
    frf: &Frf,
    bands: &[(f64, f64)],
    exposure_s: Option<f64>,
) -> anyhow::Result<Vec<PickedMode>> {
    let h: Vec<firmware_core::Complex32> = frf
        .h1
        .iter()
        .map(|v| firmware_core::Complex32::new(v.re as f32, v.im as f32))
        .collect();
    let df = frf.freq_hz.get(1).copied().unwrap_or(0.0);
    bands
        .iter()
        .map(|&(lo, hi)| {
            let p = firmware_core::peaks::pick(&h, df as f32, (lo as f32, hi as f32), false)
                .ok_or_else(|| bad_input(format!("band {lo}-{hi} Hz contains no FRF bin")))?;
            let f_hz = frf.freq_hz.get(p.bin).copied().unwrap_or(f64::from(p.f_hz));
            Ok(PickedMode {
                band_hz: (lo, hi),
                f_hz,
                amplitude: frf
                    .h1
                    .get(p.bin)
                    .map_or(f64::from(p.amplitude), |v| v.norm()),
                bin: p.bin,
                e2pr: exposure_s.map(|e| e * f_hz),
            })
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Pure writers: results in, text out (the caller writes the files).

/// `frf.csv`: `freq_hz,acc_h1_re,acc_h1_im,acc_h1_abs,acc_coherence,vis_h1_re,vis_h1_im,
/// vis_h1_abs,vis_coherence`, one row per bin.
pub fn frf_csv(a: &Analysis) -> String {
    use std::fmt::Write as _;
    let mut s = String::from(
        "freq_hz,acc_h1_re,acc_h1_im,acc_h1_abs,acc_coherence,vis_h1_re,vis_h1_im,vis_h1_abs,\
         vis_coherence\n",
    );
    for (k, f) in a.acc_frf.freq_hz.iter().enumerate() {
        let (ha, ca) = (a.acc_frf.h1[k], a.acc_frf.coherence[k]);
        let (hv, cv) = (a.vis_frf.h1[k], a.vis_frf.coherence[k]);
        let _ = writeln!(
            s,
            "{f},{},{},{},{ca},{},{},{},{cv}",
            ha.re,
            ha.im,
            ha.norm(),
            hv.re,
            hv.im,
            hv.norm()
        );
    }
    s
}

/// `modes.csv`: `system,mode,band_lo_hz,band_hi_hz,f_hz,amplitude,e2pr` (`system` is
/// `accelerometer` or `vision`, `mode` is 1-based, `e2pr` is empty without an exposure).
pub fn modes_csv(a: &Analysis) -> String {
    use std::fmt::Write as _;
    let mut s = String::from("system,mode,band_lo_hz,band_hi_hz,f_hz,amplitude,e2pr\n");
    for (system, modes) in [("accelerometer", &a.acc_modes), ("vision", &a.vis_modes)] {
        for (i, m) in modes.iter().enumerate() {
            let e2pr = m.e2pr.map(|e| e.to_string()).unwrap_or_default();
            let _ = writeln!(
                s,
                "{system},{},{},{},{},{},{e2pr}",
                i + 1,
                m.band_hz.0,
                m.band_hz.1,
                m.f_hz,
                m.amplitude
            );
        }
    }
    s
}

/// `displacement.csv`: `frame,t_s,cx,cy,pixels,flags,disp_mm,lost`, one row per frame. `t_s` is
/// the frame time from the first accelerometer sample (`time_offset_s + frame / fc`); `cx`,
/// `cy` are empty for lost frames, `flags` is the firmware-core flag byte, `lost` is 0 or 1.
pub fn displacement_csv(
    centroids: &[Centroid],
    disp: &Displacement,
    frame_rate_hz: f64,
    time_offset_s: f64,
) -> String {
    use std::fmt::Write as _;
    let mut s = String::from("frame,t_s,cx,cy,pixels,flags,disp_mm,lost\n");
    for (k, (c, (d, lost))) in centroids
        .iter()
        .zip(disp.mm.iter().zip(&disp.lost))
        .enumerate()
    {
        let t = time_offset_s + k as f64 / frame_rate_hz;
        let (cx, cy) = match c.position() {
            Some((x, y)) => (x.to_string(), y.to_string()),
            None => (String::new(), String::new()),
        };
        let _ = writeln!(
            s,
            "{k},{t},{cx},{cy},{},{},{d},{}",
            c.pixels(),
            c.flags.bits(),
            u8::from(*lost)
        );
    }
    s
}

/// `x` with about 5 significant digits: fixed notation between 0.01 and 1e5, else scientific.
fn significant(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || (0.01..1e5).contains(&a) {
        format!("{x:.4}")
    } else {
        format!("{x:.4e}")
    }
}

/// The short human report: `inputs` (label, value) lines, lost frames, the modes of both
/// systems and the vision / accelerometer ratios. `analysis` is `None` when the analysis
/// failed before the FRFs (`failure` then says why).
pub fn report_text(
    inputs: &[(String, String)],
    disp: &Displacement,
    analysis: Option<&Analysis>,
    failure: Option<&str>,
) -> String {
    use std::fmt::Write as _;
    let mut s = String::from("host-harness analyze\n\ninputs\n");
    let w = inputs.iter().map(|(k, _)| k.len()).max().unwrap_or(0);
    for (k, v) in inputs {
        let _ = writeln!(s, "  {k:<w$}  {v}");
    }
    let _ = writeln!(
        s,
        "\nlost frames: {} of {} ({:.2} %, limit {} %){}",
        disp.lost_count,
        disp.mm.len(),
        100.0 * disp.lost_fraction(),
        100.0 * MAX_LOST_FRACTION,
        if disp.lost_count > 0 {
            " - filled by linear interpolation"
        } else {
            ""
        }
    );
    if let Some(f) = failure {
        let _ = writeln!(s, "\nANALYSIS FAILED: {f}");
    }
    let Some(a) = analysis else {
        return s;
    };
    let (nperseg, noverlap, nfft) = a.welch;
    let df = a.acc_frf.freq_hz.get(1).copied().unwrap_or(0.0);
    let _ = writeln!(
        s,
        "aligned: frames cover accelerometer samples {}..{} ({} samples); alignment rounding \
         residual {:.3e} s (removed from the vision H1)\n\
         H1: nperseg {nperseg}, noverlap {noverlap}, nfft {nfft}, bin {df} Hz",
        a.alignment.start,
        a.alignment.start + a.alignment.len,
        a.alignment.len,
        a.alignment.residual_s
    );
    let _ = writeln!(
        s,
        "\nmode  band_hz        acc_f_hz  acc_amp     vis_f_hz  vis_amp     vis/acc_amp  \
         vis-acc_f_hz  e2pr"
    );
    for (i, (am, vm)) in a.acc_modes.iter().zip(&a.vis_modes).enumerate() {
        let e2pr = vm
            .e2pr
            .map(|e| format!("{e:.4}"))
            .unwrap_or_else(|| "-".into());
        let _ = writeln!(
            s,
            "{:<4}  {:<13}  {:<8.3}  {:<10}  {:<8.3}  {:<10}  {:<11.4}  {:<12.3}  {e2pr}",
            i + 1,
            format!("{}-{}", am.band_hz.0, am.band_hz.1),
            am.f_hz,
            significant(am.amplitude),
            vm.f_hz,
            significant(vm.amplitude),
            vm.amplitude / am.amplitude,
            vm.f_hz - am.f_hz
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference upsampling + -omega^2 (rustfft, f64, written from SPEC 2.2/2.3).
    fn reference_vision_acceleration(
        disp_mm: &[f64],
        fc: f64,
        fa: f64,
        m: usize,
    ) -> anyhow::Result<Vec<f64>> {
        use rustfft::FftPlanner;
        let n = disp_mm.len();
        let _ = fc;
        if n == 0 || m < n {
            return Err(bad_input(format!(
                "cannot upsample {n} frames to {m} samples"
            )));
        }
        let mut planner = FftPlanner::<f64>::new();
        let mut x: Vec<Complex64> = disp_mm.iter().map(|&v| Complex64::new(v, 0.0)).collect();
        planner.plan_fft_forward(n).process(&mut x);
        let mut y = vec![Complex64::new(0.0, 0.0); m];
        let half = n / 2;
        for k in 1..n.div_ceil(2) {
            y[k] = x[k];
            y[m - k] = x[n - k];
        }
        if n % 2 == 0 && half > 0 {
            y[half] = x[half] * 0.5;
            y[m - half] += x[half] * 0.5;
        }
        let two_pi = 2.0 * std::f64::consts::PI;
        for (k, v) in y.iter_mut().enumerate() {
            let signed = if k <= m / 2 {
                k as f64
            } else {
                k as f64 - m as f64
            };
            let w = two_pi * signed * fa / m as f64;
            *v *= -w * w;
        }
        y[0] = Complex64::new(0.0, 0.0);
        planner.plan_fft_inverse(m).process(&mut y);
        Ok(y.iter().map(|v| v.re / n as f64 / 1000.0).collect())
    }

    /// Window coefficients, periodic (scipy `get_window(..., fftbins=True)`).
    fn window_coeffs(w: Window, n: usize) -> Vec<f64> {
        let two_pi = 2.0 * std::f64::consts::PI;
        (0..n)
            .map(|i| {
                let c = (two_pi * i as f64 / n as f64).cos();
                match w {
                    Window::Hann => 0.5 - 0.5 * c,
                    Window::Hamming => 0.54 - 0.46 * c,
                    Window::Rect => 1.0,
                }
            })
            .collect()
    }

    /// Reference Welch H1 (rustfft, f64, written from SPEC 2.4).
    fn reference_h1(
        x: &[f64],
        y: &[f64],
        fs: f64,
        w: &WelchSettings,
        (nperseg, noverlap, nfft): (usize, usize, usize),
    ) -> anyhow::Result<Frf> {
        use rustfft::FftPlanner;
        let win = window_coeffs(w.window, nperseg);
        let fft = FftPlanner::<f64>::new().plan_fft_forward(nfft);
        let bins = nfft / 2 + 1;
        let mut pxx = vec![0.0; bins];
        let mut pyy = vec![0.0; bins];
        let mut pxy = vec![Complex64::new(0.0, 0.0); bins];
        let step = nperseg - noverlap;
        let mut start = 0;
        while start + nperseg <= x.len().min(y.len()) {
            let seg = |s: &[f64]| {
                let s = &s[start..start + nperseg];
                let mean = if w.detrend {
                    s.iter().sum::<f64>() / nperseg as f64
                } else {
                    0.0
                };
                let mut buf = vec![Complex64::new(0.0, 0.0); nfft];
                for ((b, v), c) in buf.iter_mut().zip(s).zip(&win) {
                    *b = Complex64::new((v - mean) * c, 0.0);
                }
                fft.process(&mut buf);
                buf
            };
            let (fx, fy) = (seg(x), seg(y));
            for k in 0..bins {
                pxx[k] += fx[k].norm_sqr();
                pyy[k] += fy[k].norm_sqr();
                pxy[k] += fx[k].conj() * fy[k];
            }
            start += step;
        }
        let freq_hz = (0..bins).map(|k| k as f64 * fs / nfft as f64).collect();
        let h1 = pxy
            .iter()
            .zip(&pxx)
            .map(|(c, &p)| {
                if p > 0.0 {
                    c / p
                } else {
                    Complex64::new(0.0, 0.0)
                }
            })
            .collect();
        let coherence = pxy
            .iter()
            .zip(pxx.iter().zip(&pyy))
            .map(|(c, (&a, &b))| {
                if a * b > 0.0 {
                    c.norm_sqr() / (a * b)
                } else {
                    0.0
                }
            })
            .collect();
        Ok(Frf {
            freq_hz,
            h1,
            coherence,
        })
    }

    #[test]
    fn interpolation_is_linear_between_neighbours_and_holds_at_the_ends() {
        let v = [None, Some(1.0), None, None, Some(4.0), None];
        assert_eq!(
            interpolate_lost(&v).unwrap(),
            vec![1.0, 1.0, 2.0, 3.0, 4.0, 4.0]
        );
        assert_eq!(interpolate_lost(&[None, None]), None);
        assert_eq!(interpolate_lost(&[Some(2.0)]).unwrap(), vec![2.0]);
    }

    fn disk_frame(w: usize, h: usize, cx: f64, cy: f64, r: f64) -> GreyFrame {
        let mut data = vec![0u8; w * h];
        for j in 0..h {
            for i in 0..w {
                if (i as f64 - cx).powi(2) + (j as f64 - cy).powi(2) <= r * r {
                    data[j * w + i] = 200;
                }
            }
        }
        GreyFrame::U8 {
            width: w,
            height: h,
            data,
        }
    }

    #[test]
    fn displacement_sign_follows_the_documented_convention() {
        let cfg = CentroidConfig::binary(100);
        // the target moves down the image by 2 px, then a lost frame, then back
        let frames = [
            disk_frame(32, 32, 15.0, 14.0, 4.0),
            disk_frame(32, 32, 15.0, 16.0, 4.0),
            GreyFrame::U8 {
                width: 32,
                height: 32,
                data: vec![0; 32 * 32],
            },
            disk_frame(32, 32, 15.0, 14.0, 4.0),
        ];
        let c: Vec<Centroid> = frames
            .iter()
            .map(|f| centroid_frame(f, &cfg, "f").unwrap())
            .collect();
        let s = DisplacementSettings {
            mm_per_px: 0.5,
            axis: Axis::Y,
            invert: false,
        };
        let d = displacement_mm(&c, &s).unwrap();
        assert_eq!(d.lost, vec![false, false, true, false]);
        assert_eq!(d.lost_count, 1);
        // reference = mean of valid cy = (14 + 16 + 14) / 3; y down => displacement negative
        let r = 44.0 / 3.0;
        let want = [
            -(14.0 - r) * 0.5,
            -(16.0 - r) * 0.5,
            -(15.0 - r) * 0.5,
            -(14.0 - r) * 0.5,
        ];
        for (g, w) in d.mm.iter().zip(want) {
            assert!((g - w).abs() < 1e-6, "{:?} vs {want:?}", d.mm);
        }
        let inv = displacement_mm(&c, &DisplacementSettings { invert: true, ..s }).unwrap();
        assert!(inv.mm.iter().zip(&d.mm).all(|(a, b)| (a + b).abs() < 1e-12));
        let x = displacement_mm(&c, &DisplacementSettings { axis: Axis::X, ..s }).unwrap();
        assert!(x.mm.iter().all(|v| v.abs() < 1e-6));
    }

    #[test]
    fn alignment_counts_and_errors() {
        let a = align(1200, 120.0, 20480, 2048.0, 0.0).unwrap();
        assert_eq!((a.start, a.len, a.residual_s), (0, 20480, 0.0));
        // 256 ticks of 30720 Hz = 17.0666 samples -> start 17, residual 0.0666 samples
        let t = tick_offset_to_seconds(256, 30720.0).unwrap();
        let a = align(120, 120.0, 4096, 2048.0, t).unwrap();
        assert_eq!((a.start, a.len), (17, 2048));
        assert!((a.residual_s * 2048.0 - (256.0 * 2048.0 / 30720.0 - 17.0)).abs() < 1e-9);
        let e = format!("{:#}", align(1200, 120.0, 20479, 2048.0, 0.0).unwrap_err());
        assert!(
            e.contains("1200 frames") && e.contains("20479 samples"),
            "{e}"
        );
        assert!(align(1201, 120.0, 30000, 2048.0, 0.0).is_err()); // 20497.07 samples
        assert!(align(10, 120.0, 30000, 2048.0, -0.1).is_err());
    }

    #[test]
    fn time_column_must_increase_in_steps_of_one_over_fs() {
        check_time_column(&[0.0, 0.5, 1.0], 2.0, "a.csv", 2).unwrap();
        let e = format!(
            "{:#}",
            check_time_column(&[0.0, 0.5, 0.5, 1.0], 2.0, "a.csv", 2).unwrap_err()
        );
        assert!(
            e.contains("a.csv") && e.contains("row 4") && e.contains("increasing"),
            "{e}"
        );
        let e = format!(
            "{:#}",
            check_time_column(&[0.0, 0.5, 1.2], 2.0, "a.csv", 2).unwrap_err()
        );
        assert!(e.contains("row 4") && e.contains("--fs"), "{e}");
    }

    /// A sinusoidal displacement that is periodic in the record upsamples to the closed-form
    /// acceleration -omega^2 A sin(omega t) at every accelerometer sample.
    #[test]
    fn vision_acceleration_matches_the_closed_form() {
        let (fc, fa, n) = (120.0, 2048.0, 1200usize);
        let m = n * 2048 / 120;
        let (f, amp_mm) = (7.3, 2.0);
        let w = 2.0 * std::f64::consts::PI * f;
        let x: Vec<f64> = (0..n)
            .map(|k| amp_mm * (w * k as f64 / fc).sin() + 0.7)
            .collect();
        let acc = vision_acceleration(&x, fc, fa, m).unwrap();
        assert_eq!(acc.len(), m);
        let peak = w * w * amp_mm / 1000.0;
        let worst = acc
            .iter()
            .enumerate()
            .map(|(j, a)| (a + peak * (w * j as f64 / fa).sin()).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-4 * peak, "worst error {worst} of peak {peak}");
    }

    /// H1 of a system y = 2 x (delayed by a whole number of samples on a periodic record) is
    /// 2 exp(-i omega d), coherence 1; peaks pick the band maxima of |Im H1|.
    #[test]
    fn h1_of_a_scaled_copy_and_peak_picking() {
        let n = 2048;
        let mut state = 12345u64;
        let x: Vec<f64> = (0..n)
            .map(|_| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
                (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect();
        let y: Vec<f64> = x.iter().map(|v| 2.0 * v).collect();
        let w = WelchSettings::default();
        let r = resolve_welch(&w, n).unwrap();
        assert_eq!(r, (n, 0, n));
        let frf = h1(&x, &y, 2048.0, &w, r).unwrap();
        for (h, c) in frf.h1.iter().zip(&frf.coherence).skip(1) {
            assert!((h - Complex64::new(2.0, 0.0)).norm() < 1e-6);
            assert!((c - 1.0).abs() < 1e-6);
        }
        let mut fake = frf.clone();
        fake.h1[10] = Complex64::new(0.5, -3.0);
        fake.h1[30] = Complex64::new(0.0, 5.0);
        let m = pick_modes(&fake, &[(5.0, 15.0), (25.0, 35.0)], Some(0.002)).unwrap();
        assert_eq!((m[0].bin, m[1].bin), (10, 30));
        assert!((m[0].amplitude - (0.25f64 + 9.0).sqrt()).abs() < 1e-12);
        assert!((m[1].e2pr.unwrap() - 0.002 * 30.0).abs() < 1e-12);
        assert!(pick_modes(&fake, &[(0.1, 0.2)], None).is_err());
    }

    /// The firmware Welch estimator agrees with the f64 reference on a noisy two-channel record
    /// (Hamming, overlapping segments, zero padding to a non-power-of-two nfft).
    #[test]
    fn firmware_h1_matches_the_reference() {
        let n = 4096;
        let mut state = 99u64;
        let mut rnd = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let x: Vec<f64> = (0..n).map(|_| rnd()).collect();
        // y: a 3-tap filter of x plus independent noise
        let y: Vec<f64> = (0..n)
            .map(|i| {
                let a = x[i];
                let b = if i > 0 { x[i - 1] } else { 0.0 };
                let c = if i > 1 { x[i - 2] } else { 0.0 };
                0.5 * a - 0.8 * b + 0.3 * c + 0.2 * rnd()
            })
            .collect();
        let w = WelchSettings {
            window: Window::Hamming,
            nperseg: Some(512),
            noverlap: Some(256),
            nfft: Some(600),
            detrend: true,
        };
        let r = resolve_welch(&w, n).unwrap();
        let got = h1(&x, &y, 1000.0, &w, r).unwrap();
        let want = reference_h1(&x, &y, 1000.0, &w, r).unwrap();
        assert_eq!(got.h1.len(), 301);
        assert_eq!(got.freq_hz, want.freq_hz);
        for k in 1..got.h1.len() {
            let e = (got.h1[k] - want.h1[k]).norm();
            assert!(
                e < 1e-4 * (1.0 + want.h1[k].norm()),
                "bin {k}: {} vs {}",
                got.h1[k],
                want.h1[k]
            );
            assert!(
                (got.coherence[k] - want.coherence[k]).abs() < 1e-4,
                "bin {k}"
            );
        }
    }

    /// A fractional alignment (first frame 3.4 samples after the first accelerometer sample) is
    /// rounded to sample 3 and the 0.4-sample residual delay is removed from the vision H1, so
    /// both systems see the same complex H1 of a periodic test signal.
    #[test]
    fn fractional_alignment_residual_is_removed_from_the_vision_h1() {
        let (fc, fa, n) = (120.0, 2048.0, 120usize);
        let (f, amp) = (8.0, 3.0); // tip acceleration amplitude, m/s^2
        let w = 2.0 * std::f64::consts::PI * f;
        let offset = 3.4 / fa;
        let tip = |t: f64| amp * (w * t).cos();
        let samples = 2048 + 10;
        let base: Vec<f64> = (0..samples)
            .map(|j| (w * j as f64 / fa).sin() + 0.3 * (2.0 * w * j as f64 / fa).cos())
            .collect();
        let tip_acc: Vec<f64> = (0..samples).map(|j| tip(j as f64 / fa)).collect();
        // displacement of the tip (mm): -a / w^2
        let mm: Vec<f64> = (0..n)
            .map(|k| -tip(offset + k as f64 / fc) / (w * w) * 1000.0)
            .collect();
        let disp = Displacement {
            lost: vec![false; n],
            lost_count: 0,
            reference_px: 0.0,
            mm,
        };
        let s = Settings {
            frame_rate_hz: fc,
            accel_rate_hz: fa,
            time_offset_s: offset,
            welch: WelchSettings {
                window: Window::Rect,
                ..WelchSettings::default()
            },
            bands: vec![(5.0, 10.0)],
            exposure_s: None,
        };
        let a = analyze(&disp, &base, &tip_acc, &s).unwrap();
        assert_eq!(a.alignment.start, 3);
        assert!((a.alignment.residual_s * fa - 0.4).abs() < 1e-9);
        let (ha, hv) = (a.acc_frf.h1[8], a.vis_frf.h1[8]);
        assert!((hv - ha).norm() < 1e-3 * ha.norm(), "acc {ha} vs vis {hv}");
        // without the correction the phase would differ by w * 0.4 / fa = 9.8 mrad
        let uncorrected = hv * Complex64::from_polar(1.0, w * a.alignment.residual_s);
        assert!((uncorrected - ha).norm() > 5e-3 * ha.norm());
        assert_eq!(a.acc_modes[0].bin, 8);
        assert_eq!(a.vis_modes[0].bin, 8);
    }

    /// The firmware upsampler (f32) agrees with the f64 reference on a random record, 1200
    /// frames at 120 fps to 2048 Hz.
    #[test]
    fn firmware_upsampling_matches_the_reference() {
        let mut state = 5u64;
        let x: Vec<f64> = (0..1200)
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect();
        let got = vision_acceleration(&x, 120.0, 2048.0, 20480).unwrap();
        let want = reference_vision_acceleration(&x, 120.0, 2048.0, 20480).unwrap();
        let peak = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let worst = got
            .iter()
            .zip(&want)
            .fold(0.0f64, |a, (g, w)| a.max((g - w).abs()));
        assert!(worst < 1e-4 * peak, "worst {worst} of peak {peak}");
    }
}
