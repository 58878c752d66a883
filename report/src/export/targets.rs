//! The outputs of `analyze --targets K`: `frf.csv`, `displacement.csv`, `modes.csv`,
//! `shapes.csv`, `mac.csv` and `compensation.csv` (the UFF is [`super::uff`]). Targets are
//! numbered 1..=K left to right in the first frame; target 0 is the accelerometer.

use super::analysis::{push_compensation_row, round_e2pr, CompensationRow, Spectrum};
pub use super::analysis::{tracks_displacement_csv as displacement_csv, Track};
use super::{opt, push_intervals, INTERVAL_COLUMNS};
use num_complex::Complex64;
use std::fmt::Write as _;

/// `frf.csv`: `target,freq_hz,h1_re,h1_im,h1_abs,coherence`, one row per line of each
/// `(target, H1)` in the order given.
pub fn frf_csv<'a>(frfs: impl IntoIterator<Item = (usize, Spectrum<'a>)>) -> Vec<u8> {
    let mut s = String::from("target,freq_hz,h1_re,h1_im,h1_abs,coherence\n");
    for (t, frf) in frfs {
        for ((f, h), c) in frf.freq_hz.iter().zip(frf.h1).zip(frf.coherence) {
            let _ = writeln!(s, "{t},{f},{},{},{},{c}", h.re, h.im, h.norm());
        }
    }
    s.into_bytes()
}

/// One row of the multi-target `modes.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeRow {
    /// 0 for the accelerometer, else the target, 1-based.
    pub target: usize,
    /// Mode (band) number, 1-based.
    pub mode: usize,
    /// The band, Hz.
    pub band_hz: (f64, f64),
    /// Fitted natural frequency, Hz (`None`: the fit failed).
    pub f_hz: Option<f64>,
    /// |H1| at the picked peak.
    pub amplitude: f64,
    /// Fitted damping ratio (`None`: the fit failed).
    pub damping: Option<f64>,
    /// E2PR (`None` without an exposure).
    pub e2pr: Option<f64>,
    /// The standard uncertainty and 95 % interval (`u`, `lo`, `hi`) of the frequency, the
    /// damping and the amplitude, where estimated.
    pub intervals: [Option<(f64, f64, f64)>; 3],
}

/// `modes.csv`: `system,target,mode,band_lo_hz,band_hi_hz,f_hz,amplitude,damping,e2pr,method`
/// (`system` `accelerometer` for target 0, else `vision`; empty cells where absent; `method`
/// `h1`: the modes of the FRFs; output-only analysis writes the same columns), then
/// [`INTERVAL_COLUMNS`] (empty where not estimated).
pub fn modes_csv(rows: &[ModeRow]) -> Vec<u8> {
    modes_lines(rows.iter().map(|m| ModesLine {
        system: if m.target == 0 {
            "accelerometer"
        } else {
            "vision"
        },
        target: Some(m.target),
        mode: m.mode,
        band_hz: Some(m.band_hz),
        f_hz: m.f_hz,
        amplitude: Some(m.amplitude),
        damping: m.damping,
        e2pr: m.e2pr.map(round_e2pr),
        method: "h1",
        intervals: m.intervals,
    }))
}

/// One line of the multi-target `modes.csv`, as every analysis writes it (an empty cell for
/// each `None`).
#[derive(Debug, Clone, PartialEq)]
pub struct ModesLine<'a> {
    /// `accelerometer` or `vision`.
    pub system: &'a str,
    /// Target number.
    pub target: Option<usize>,
    /// Mode, 1-based.
    pub mode: usize,
    /// The band searched, Hz.
    pub band_hz: Option<(f64, f64)>,
    /// Natural frequency, Hz.
    pub f_hz: Option<f64>,
    /// Amplitude.
    pub amplitude: Option<f64>,
    /// Damping ratio.
    pub damping: Option<f64>,
    /// E2PR.
    pub e2pr: Option<f64>,
    /// The method (`h1`, `fdd`, `efdd`, `ssi`, `lscf`).
    pub method: &'a str,
    /// `(u, lo, hi)` of the frequency, the damping and the amplitude.
    pub intervals: [Option<(f64, f64, f64)>; 3],
}

/// `modes.csv` of `lines`: [`MODES_HEADER`], then [`INTERVAL_COLUMNS`].
pub fn modes_lines<'a>(lines: impl IntoIterator<Item = ModesLine<'a>>) -> Vec<u8> {
    let mut s = String::from(MODES_HEADER.trim_end());
    s.push(',');
    s.push_str(INTERVAL_COLUMNS);
    s.push('\n');
    for m in lines {
        let _ = write!(
            s,
            "{},{},{},{},{},{},{},{},{},{}",
            m.system,
            opt(m.target),
            m.mode,
            opt(m.band_hz.map(|b| b.0)),
            opt(m.band_hz.map(|b| b.1)),
            opt(m.f_hz),
            opt(m.amplitude),
            opt(m.damping),
            opt(m.e2pr),
            m.method
        );
        push_intervals(&mut s, &m.intervals);
        s.push('\n');
    }
    s.into_bytes()
}

/// One row of `shapes.csv`: one target's complex modal coefficient in one mode.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeRow {
    /// Mode (band), 1-based.
    pub mode: usize,
    /// Target, 1-based.
    pub target: usize,
    /// The target's position in the first frame, px.
    pub xy_px: (f64, f64),
    /// The normalised coefficient.
    pub value: Complex64,
}

/// The header of the multi-target `modes.csv`.
pub const MODES_HEADER: &str =
    "system,target,mode,band_lo_hz,band_hi_hz,f_hz,amplitude,damping,e2pr,method\n";

/// The header of `shapes.csv`.
pub const SHAPES_HEADER: &str = "mode,target,x_px,y_px,re,im,abs,method\n";

/// `shapes.csv`: `mode,target,x_px,y_px,re,im,abs,method` (`method` `h1`: the shapes of the
/// FRFs' fitted residues).
pub fn shapes_csv(rows: &[ShapeRow]) -> Vec<u8> {
    let mut s = String::from(SHAPES_HEADER);
    for r in rows {
        let (x, y) = r.xy_px;
        let c = r.value;
        let _ = writeln!(
            s,
            "{},{},{x},{y},{},{},{},h1",
            r.mode,
            r.target,
            c.re,
            c.im,
            c.norm()
        );
    }
    s.into_bytes()
}

/// `mac.csv`: `mode,mac`, one row per `(mode, MAC)` against the reference shape.
pub fn mac_csv(macs: &[(usize, f64)]) -> Vec<u8> {
    let mut s = String::from("mode,mac\n");
    for (mode, v) in macs {
        let _ = writeln!(s, "{mode},{v}");
    }
    s.into_bytes()
}

/// `compensation.csv`: `target,mode,f_hz,e2pr,transfer,factor,compensated`, the rows of each
/// compensated target (`(target, rows)`, target 1-based).
pub fn compensation_csv<'a>(
    targets: impl IntoIterator<Item = (usize, &'a [CompensationRow])>,
) -> Vec<u8> {
    let mut s = String::from("target,mode,f_hz,e2pr,transfer,factor,compensated\n");
    for (t, rows) in targets {
        for r in rows {
            push_compensation_row(&mut s, &format!("{t},"), r);
        }
    }
    s.into_bytes()
}

/// One frame of `camera_motion.csv`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraRow {
    /// Seconds from the first frame.
    pub t_s: f64,
    /// The image centre's shift (x, y, px), the roll (degrees, clockwise on the image) and the
    /// scale; `None` where no reference was seen.
    pub motion: Option<(f64, f64, f64, f64)>,
    /// References the frame's fit used.
    pub references: usize,
    /// Their RMS residual, px (NaN: none).
    pub residual_px: f64,
}

/// `camera_motion.csv`: `frame,t_s,dx_px,dy_px,rotation_deg,scale,references,residual_px`, one
/// row per frame (the motion cells empty where it is unknown).
pub fn camera_motion_csv(rows: &[CameraRow]) -> Vec<u8> {
    let mut s = String::from("frame,t_s,dx_px,dy_px,rotation_deg,scale,references,residual_px\n");
    for (k, r) in rows.iter().enumerate() {
        match r.motion {
            Some((x, y, a, m)) => {
                let _ = write!(s, "{k},{},{x},{y},{a},{m}", r.t_s);
            }
            None => {
                let _ = write!(s, "{k},{},,,,", r.t_s);
            }
        }
        let _ = writeln!(
            s,
            ",{},{}",
            r.references,
            if r.residual_px.is_finite() {
                r.residual_px.to_string()
            } else {
                String::new()
            }
        );
    }
    s.into_bytes()
}
