//! The files of an output-only modal analysis (`modal`, `analyze` without an accelerometer):
//! `modes.csv` and `shapes.csv` in the multi-target columns, `svd.csv`, `shapes.uff`. Typed
//! rows in, bytes out; `analysis::oma::run` builds the rows from its results.

use super::opt;
use super::targets::{modes_lines, ModesLine, SHAPES_HEADER};
use super::uff::{write_dataset55, Shape55};
use num_complex::Complex64;
use std::fmt::Write as _;

/// One mode of one method.
#[derive(Debug, Clone, PartialEq)]
pub struct OmaModeRow {
    /// Mode number, 1-based, per method.
    pub mode: usize,
    /// The band, Hz (with bands).
    pub band_hz: Option<(f64, f64)>,
    /// Natural frequency, Hz.
    pub f_hz: f64,
    /// First singular value at the peak (FDD and EFDD).
    pub amplitude: Option<f64>,
    /// Damping ratio (EFDD and SSI).
    pub damping: Option<f64>,
    /// `fdd`, `efdd` or `ssi`.
    pub method: &'static str,
    /// The standard uncertainty and 95 % interval (`u`, `lo`, `hi`) of the frequency, the
    /// damping and the amplitude, where estimated.
    pub intervals: [Option<(f64, f64, f64)>; 3],
}

/// `modes.csv`: the multi-target columns, one row per mode and method, `system` `vision`,
/// `target` and `e2pr` empty; then [`super::INTERVAL_COLUMNS`] (empty where not estimated).
pub fn modes_csv(rows: &[OmaModeRow]) -> Vec<u8> {
    modes_lines(rows.iter().map(|m| ModesLine {
        system: "vision",
        target: None,
        mode: m.mode,
        band_hz: m.band_hz,
        f_hz: Some(m.f_hz),
        amplitude: m.amplitude,
        damping: m.damping,
        e2pr: None,
        method: m.method,
        intervals: m.intervals,
    }))
}

/// One target's coefficient in one mode of one method.
#[derive(Debug, Clone, PartialEq)]
pub struct OmaShapeRow {
    /// Mode number, 1-based, per method.
    pub mode: usize,
    /// Target number.
    pub target: usize,
    /// Its position in the first frame, px, when known.
    pub xy_px: Option<(f64, f64)>,
    /// The normalised coefficient.
    pub value: Complex64,
    /// `fdd`, `efdd` or `ssi`.
    pub method: &'static str,
    /// The standard uncertainty of its magnitude, where estimated.
    pub abs_u: Option<f64>,
}

/// `shapes.csv`: one row per mode, method and target (`x_px`, `y_px` empty when unknown),
/// then `abs_u` (the standard uncertainty of `abs`; empty where not estimated).
pub fn shapes_csv(rows: &[OmaShapeRow]) -> Vec<u8> {
    let mut s = String::from(SHAPES_HEADER.trim_end());
    s.push_str(",abs_u\n");
    for r in rows {
        let (x, y) = r.xy_px.map_or((None, None), |p| (Some(p.0), Some(p.1)));
        let c = r.value;
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{}",
            r.mode,
            r.target,
            opt(x),
            opt(y),
            c.re,
            c.im,
            c.norm(),
            r.method,
            opt(r.abs_u)
        );
    }
    s.into_bytes()
}

/// One setup's part in one merged mode of several setups.
#[derive(Debug, Clone, PartialEq)]
pub struct OmaSetupRow {
    /// `fdd`, `efdd`, `ssi` or `decay`.
    pub method: &'static str,
    /// The merged mode's number.
    pub mode: usize,
    /// The setup, 1-based.
    pub setup: usize,
    /// Its frequency, Hz.
    pub f_hz: f64,
    /// Its damping ratio, where its method gives one.
    pub damping: Option<f64>,
    /// The factor its shape was scaled by onto the first setup's at the references.
    pub scale: Complex64,
    /// MAC at the references with the first setup's (two references or more).
    pub reference_mac: Option<f64>,
}

/// `setups.csv`: `method,mode,setup,f_hz,damping,scale_re,scale_im,reference_mac`, one row per
/// merged mode and setup.
pub fn setups_csv(rows: &[OmaSetupRow]) -> Vec<u8> {
    let mut s = String::from("method,mode,setup,f_hz,damping,scale_re,scale_im,reference_mac\n");
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{}",
            r.method,
            r.mode,
            r.setup,
            r.f_hz,
            opt(r.damping),
            r.scale.re,
            r.scale.im,
            opt(r.reference_mac)
        );
    }
    s.into_bytes()
}

/// `svd.csv`: `freq_hz,s1,...,sK`, one row per line of the cross-spectral matrix.
pub fn svd_csv(freq_hz: &[f64], s: &[Vec<f64>]) -> Vec<u8> {
    let k = s.first().map_or(0, Vec::len);
    let mut out = String::from("freq_hz");
    for i in 1..=k {
        let _ = write!(out, ",s{i}");
    }
    out.push('\n');
    for (f, sv) in freq_hz.iter().zip(s) {
        let _ = write!(out, "{f}");
        for v in sv {
            let _ = write!(out, ",{v}");
        }
        out.push('\n');
    }
    out.into_bytes()
}

/// One mode's shape as a UFF dataset 55.
#[derive(Debug, Clone, PartialEq)]
pub struct OmaShapeSet {
    /// `fdd`, `efdd` or `ssi` (in the title).
    pub method: &'static str,
    /// Load case: 1 FDD, 2 EFDD, 3 SSI.
    pub load_case: u32,
    /// Mode number.
    pub mode: usize,
    /// Natural frequency, Hz.
    pub f_hz: f64,
    /// Damping ratio (0 when the method gives none).
    pub damping: f64,
    /// Each target's node number and its (x, y, z) coefficients.
    pub nodes: Vec<(u32, [Complex64; 3])>,
}

/// `shapes.uff`: one dataset 55 per mode and method.
pub fn shapes_uff(sets: &[OmaShapeSet]) -> anyhow::Result<Vec<u8>> {
    let mut bytes = Vec::new();
    for m in sets {
        let title = format!("vibcam output-only modal analysis: {}", m.method);
        let what = format!("mode {} at {:.6} Hz", m.mode, m.f_hz);
        let d = Shape55 {
            id_lines: [&title, &what, "", "", ""],
            load_case: m.load_case,
            mode: m.mode as u32,
            f_hz: m.f_hz,
            damping: m.damping,
            nodes: &m.nodes,
        };
        bytes.extend(write_dataset55(&d)?);
    }
    Ok(bytes)
}
