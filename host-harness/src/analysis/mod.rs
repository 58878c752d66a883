//! The analysis chain of a real (or synthetic) recording, as on the rig (method.md §3.2): pure
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
//! * **Displacement sign.** Image `x` grows to the right and `y` grows *down* (method.md §2.1). With
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

pub mod columns;
pub mod compensate;
pub mod ema;
pub mod frf_uncertainty;
pub mod imaging_share;
pub use vibcam_identify::modal;
// Tracking, under the paths it had here.
pub use vibcam_track::{camera_motion, follow, points, region, shared_motion};
pub mod oma;
pub mod pick;
pub mod report;
pub mod request;
pub mod run;
pub mod targets;
pub mod targets_run;
pub mod track_run;
pub mod twin;
pub mod view;

pub use crate::chain::displacement::{
    displacement_mm, Axis, Displacement, DisplacementSettings, MAX_LOST_FRACTION,
};
pub use crate::chain::frf::{Defaults, Frf, PickedMode, WelchSettings};
pub use firmware_core::spectrum::Window;
pub use report::{mode_rows, report_text, spectrum};

use crate::bad_input;
use crate::chain::{self, frf};
use firmware_core::spectrum::WelchConfig;
use num_complex::Complex64;
use std::path::Path;

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

/// Writes a job's `report.txt` and its `report.html` (`page` makes it from the report's text),
/// both opened by the run's provenance (the inputs `out` was given, the invocation the front
/// end stated), the settings they name spelled as the command line's flags (`$nperseg`:
/// `--nperseg`); with `pdf`, `report.pdf` too, printed by a headless Chromium (a warning when
/// none is installed or it fails: the other outputs stand). Returns the report without its
/// provenance (what the terminal shows: the command was just typed there).
pub fn write_report(
    out: &vibcam_report::outdir::Staged,
    report: &str,
    pdf: bool,
    page: impl FnOnce(&str) -> crate::export::html::Report,
) -> anyhow::Result<String> {
    use crate::setting::{spell, Naming};
    let inputs: Vec<&Path> = out.inputs().iter().map(|p| p.as_path()).collect();
    let provenance = vibcam_report::provenance::Provenance::now(&inputs);
    let report = spell(report, Naming::Cli);
    let page = signed_page(&provenance, &report, page);
    out.write("report.txt", format!("{}\n{report}", provenance.text()))?;
    out.write("report.html", spell(&page, Naming::Cli))?;
    if pdf {
        // the page as staged (the target directory holds it only after the commit)
        let html = out.dir().join("report.html");
        use vibcam_report::pdf::{browser, print, PdfError};
        let printed = browser()
            .ok_or(PdfError::NoBrowser)
            .and_then(|b| print(&b, &html, &out.dir().join(".report.pdf.partial")));
        match printed {
            Ok(bytes) => {
                out.write("report.pdf", bytes)?;
            }
            Err(e) => warn(&e.to_string()),
        }
    }
    Ok(report)
}

/// A job's page (`page` made from the report's text) with `provenance` as its header.
pub fn signed_page(
    provenance: &vibcam_report::provenance::Provenance,
    report: &str,
    page: impl FnOnce(&str) -> crate::export::html::Report,
) -> String {
    let mut r = page(report);
    r.provenance = Some(provenance.clone());
    crate::export::html::report_html(&r)
}

/// Prints a warning on standard error beside the progress, with the settings it names spelled
/// as the command line's flags (`$threshold`: `--threshold`).
pub fn warn(text: &str) {
    let text = crate::setting::spell(text, crate::setting::Naming::Cli);
    eprintln!("warning: {text}");
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
/// of `tick_hz` (method.md §2.7).
pub fn tick_offset_to_seconds(ticks: i64, tick_hz: f64) -> crate::setting::SpecResult<f64> {
    let hz = crate::setting::positive("tick_hz", tick_hz, "the time base's rate, Hz")?;
    Ok(ticks as f64 / hz)
}

/// Checks an accelerometer time column: strictly increasing, steps of `1 / fs` (within 5 %),
/// and no drift from `t[0] + i / fs` of more than half a sample over the whole record (a wrong
/// `--fs` by a few percent passes the step check but not this one). `first_row` is the
/// spreadsheet row of `t[0]` (2 after a header), so errors name the row.
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
                "{source}: row {row}: time step {step} s does not match $fs {fs} Hz \
                 (expected {dt} s)"
            )));
        }
        let drift = w[1] - t[0] - (i + 1) as f64 * dt;
        if drift.abs() > 0.5 * dt {
            let rate = (i + 1) as f64 / (w[1] - t[0]);
            return Err(bad_input(format!(
                "{source}: row {row}: time {} s is {drift:+.6} s from the {} s that $fs {fs} \
                 Hz gives (more than half a sample): the file's own rate is about {rate:.6} Hz",
                w[1],
                t[0] + (i + 1) as f64 * dt
            )));
        }
    }
    Ok(())
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
    /// Subtract the line through the displacement record's first and last samples before
    /// the Fourier upsampling ([`chain::vision_acceleration_end_matched`]): a real record is
    /// not periodic. `false` takes the record as periodic .
    pub end_match: bool,
}

/// Result of [`analyze`].
#[derive(Debug, Clone, PartialEq)]
pub struct Analysis {
    /// Where the frames sit in the accelerometer record.
    pub alignment: Alignment,
    /// The Welch settings actually used.
    pub welch: WelchConfig,
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
    /// Frames analysed: all of them, or the longest leading part whose span is a whole number
    /// of accelerometer samples ([`usable_frames`]); the rest were left out.
    pub frames_used: usize,
    /// The modes' intervals ([`frf_uncertainty::of_analysis`]), when computed.
    pub intervals: Option<frf_uncertainty::Intervals>,
}

/// The longest record of at most `frames` frames at `fc` Hz whose span is a whole number of
/// samples at `fa` Hz (the Fourier upsampling needs `N fa / fc` to be an integer: with
/// `fc = 30000/1001` and `fa = 2048`, N a multiple of 1875). `None` when no such length exists.
pub fn usable_frames(frames: usize, fc: f64, fa: f64) -> Option<usize> {
    (1..=frames)
        .rev()
        .find(|&n| integer_ratio(n as f64 * fa, fc).is_some())
}

/// [`usable_frames`], or an error saying what the rates need.
pub fn usable_frames_or_error(frames: usize, fc: f64, fa: f64) -> anyhow::Result<usize> {
    usable_frames(frames, fc, fa).ok_or_else(|| {
        bad_input(format!(
            "{frames} frames at {fc} fps: no record of up to {frames} frames spans a whole \
             number of accelerometer samples at {fa} Hz (the Fourier upsampling needs N * fa / \
             fc to be an integer); check $fps and $fs, or record longer"
        ))
    })
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
    if disp.failed() {
        return Err(bad_input(format!(
            "{} of {} frames ({:.1} %) have no centroid, more than the {} % \
             allowed (check $threshold, $roi, with $targets $gate_px, the exposure and the \
             lighting)",
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
    let frames_used = usable_frames_or_error(disp.mm.len(), s.frame_rate_hz, fa)?;
    let mm = &disp.mm[..frames_used];
    let alignment = align(
        frames_used,
        s.frame_rate_hz,
        base.len(),
        fa,
        s.time_offset_s,
    )?;
    let span = alignment.start..alignment.start + alignment.len;
    let (base, tip) = (&base[span.clone()], &tip[span]);
    let vision_acc = if s.end_match {
        chain::vision_acceleration_end_matched(mm, s.frame_rate_hz, alignment.len)?
    } else {
        chain::vision_acceleration(mm, s.frame_rate_hz, alignment.len)?
    };
    let welch = s.welch.resolve(alignment.len, fa, Defaults::WholeRecord)?;
    let acc_frf = checked_h1(base, tip, welch)?;
    let mut vis_frf = checked_h1(base, &vision_acc, welch)?;
    if alignment.residual_s != 0.0 {
        for (h, f) in vis_frf.h1.iter_mut().zip(&vis_frf.freq_hz) {
            *h *=
                Complex64::from_polar(1.0, -2.0 * std::f64::consts::PI * f * alignment.residual_s);
        }
    }
    let acc_modes = frf::pick_modes(&acc_frf, &s.bands, s.exposure_s)?;
    let vis_modes = frf::pick_modes(&vis_frf, &s.bands, s.exposure_s)?;
    Ok(Analysis {
        alignment,
        welch,
        vision_acc,
        acc_frf,
        vis_frf,
        acc_modes,
        vis_modes,
        frames_used,
        intervals: None,
    })
}

/// H1 through [`frf::estimate`]; a skipped segment is an error here (one whole-record segment
/// is the usual setting, and a partial average would silently change the estimator).
fn checked_h1(x: &[f64], y: &[f64], config: WelchConfig) -> anyhow::Result<Frf> {
    let h = frf::estimate(x, y, config)?;
    if h.skipped > 0 {
        return Err(bad_input(format!(
            "H1: {} segment(s) contain non-finite samples",
            h.skipped
        )));
    }
    Ok(h)
}

/// The transducer channels of an accelerometer CSV: `(input, output)` columns (m/s^2), the time
/// column (when named) checked against `fs`. Errors name the file, row and column.
pub fn load_accel(
    path: &Path,
    fs: f64,
    input_col: &str,
    output_col: &str,
    time_col: Option<&str>,
) -> anyhow::Result<(Vec<f64>, Vec<f64>)> {
    if !(fs.is_finite() && fs > 0.0) {
        return Err(bad_input(format!("$fs must be a positive rate, got {fs}")));
    }
    let mut wanted = vec![input_col, output_col];
    wanted.extend(time_col);
    let mut cols = crate::csvio::read_columns(path, &wanted)?.values;
    if time_col.is_some() {
        let t = cols.pop().unwrap_or_default();
        check_time_column(&t, fs, &path.display().to_string(), 2)?;
    }
    let output = cols.pop().unwrap_or_default();
    let input = cols.pop().unwrap_or_default();
    let file = path.display();
    check_channel(
        &input,
        &format!("{file}: column `{input_col}` ($input_col)"),
    )?;
    check_channel(
        &output,
        &format!("{file}: column `{output_col}` ($output_col)"),
    )?;
    Ok((input, output))
}

/// The smallest standard deviation a channel may have: below it the squares summed by the
/// Welch estimator (about std^2 x segment length) fall out of `f64`'s normal range and H1 is
/// no longer computed to full precision (1e-300 underflows to no spectrum at all).
pub const CHANNEL_STD_MIN: f64 = 1e-140;

/// Refuses a channel that cannot carry a measurement: a value that is not finite (named by
/// row), no variance at all (constant: a dead or disconnected sensor; an FRF against it would
/// divide by nothing), or a variation far below the floating-point range. `what` names the file
/// and column.
pub fn check_channel(values: &[f64], what: &str) -> anyhow::Result<()> {
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(bad_input(format!(
            "{what}: row {} is {}, not a finite number",
            i + 2,
            values[i]
        )));
    }
    let n = values.len() as f64;
    if values.is_empty() {
        return Err(bad_input(format!("{what}: no samples")));
    }
    // in units of the largest magnitude, so that tiny values do not underflow here
    let scale = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let unit = if scale > 0.0 { scale } else { 1.0 };
    let mean = values.iter().map(|v| v / unit).sum::<f64>() / n;
    let std = (values
        .iter()
        .map(|v| (v / unit - mean).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    let (mean, std) = (mean * unit, std * unit);
    // a constant column, up to the rounding of its mean
    if std <= mean.abs() * 1e-12 || std == 0.0 {
        return Err(bad_input(format!(
            "{what}: every sample is {} (no variation): a dead, disconnected or clipped \
             channel cannot be analysed",
            values[0]
        )));
    }
    if std < CHANNEL_STD_MIN {
        return Err(bad_input(format!(
            "{what}: its standard deviation {std:e} is far below the range the spectra can be \
             computed in (>= {CHANNEL_STD_MIN:e}); scale the column (e.g. to m/s^2)"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frames::GreyFrame;

    #[test]
    fn records_are_trimmed_to_a_whole_number_of_samples() {
        let ntsc = 30000.0 / 1001.0;
        // 100.1 samples a frame at 3000 Hz: every tenth length is whole
        assert_eq!(usable_frames(1203, ntsc, 3000.0), Some(1200));
        assert_eq!(usable_frames(1200, 120.0, 2048.0), Some(1200));
        // at 2048 Hz a whole number needs a multiple of 1875 frames
        assert_eq!(usable_frames(1200, ntsc, 2048.0), None);
        assert_eq!(usable_frames(3800, ntsc, 2048.0), Some(3750));
        let e = usable_frames_or_error(1200, ntsc, 2048.0).unwrap_err();
        assert!(e.to_string().contains("check $fps and $fs"), "{e}");
    }

    use firmware_core::centroid::{Centroid, CentroidConfig};

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
            .map(|f| f.centroid(&cfg, "f").unwrap())
            .collect();
        let s = DisplacementSettings {
            lost_frames: Default::default(),
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
        assert!(e.contains("row 4") && e.contains("$fs"), "{e}");
        // a rate 2.4 % off passes every step (within 5 %) but drifts by half a sample after
        // 22 samples (2048 Hz data read as 2000 Hz, t[22] on row 24): the row is named
        let t: Vec<f64> = (0..100).map(|i| i as f64 / 2048.0).collect();
        check_time_column(&t, 2048.0, "a.csv", 2).unwrap();
        let e = format!(
            "{:#}",
            check_time_column(&t, 2000.0, "a.csv", 2).unwrap_err()
        );
        assert!(
            e.contains("row 24") && e.contains("half a sample") && e.contains("2048.0"),
            "{e}"
        );
    }

    /// A sinusoidal displacement that is periodic in the record upsamples to the closed-form
    /// acceleration -omega^2 A sin(omega t) at every accelerometer sample.
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
            policy: Default::default(),
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
            // whole periods of an 8 Hz line: the record is periodic, and the end-matching line
            // (through samples one step apart) would add a kink of its own at the wrap
            end_match: false,
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
}
