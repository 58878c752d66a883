//! The outputs of a one-target `analyze`: `frf.csv`, `modes.csv`, `displacement.csv` and
//! `compensation.csv`. The columns are documented in `docs/cli.md`.

use super::{opt, INTERVAL_COLUMNS};
use firmware_core::centroid::Centroid;
use num_complex::Complex64;
use std::fmt::Write as _;

/// One H1 estimate on its frequency lines: `h1[k]` and `coherence[k]` at `freq_hz[k]`.
#[derive(Debug, Clone, Copy)]
pub struct Spectrum<'a> {
    /// Frequency of each line, Hz.
    pub freq_hz: &'a [f64],
    /// H1 at each line.
    pub h1: &'a [Complex64],
    /// Coherence at each line.
    pub coherence: &'a [f64],
}

/// `frf.csv`: `freq_hz,acc_h1_re,acc_h1_im,acc_h1_abs,acc_coherence,vis_h1_re,vis_h1_im,
/// vis_h1_abs,vis_coherence`, one row per line of `acc` (the accelerometer's H1; `vis`, the
/// vision H1, on the same lines).
pub fn frf_csv(acc: Spectrum<'_>, vis: Spectrum<'_>) -> Vec<u8> {
    let mut s = String::from(
        "freq_hz,acc_h1_re,acc_h1_im,acc_h1_abs,acc_coherence,vis_h1_re,vis_h1_im,vis_h1_abs,\
         vis_coherence\n",
    );
    for (k, f) in acc.freq_hz.iter().enumerate() {
        let (ha, ca) = (acc.h1[k], acc.coherence[k]);
        let (hv, cv) = (vis.h1[k], vis.coherence[k]);
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
    s.into_bytes()
}

/// One row of `modes.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeRow {
    /// `accelerometer` or `vision`.
    pub system: &'static str,
    /// Mode number, 1-based.
    pub mode: usize,
    /// The band searched, Hz.
    pub band_hz: (f64, f64),
    /// The picked peak's frequency, Hz.
    pub f_hz: f64,
    /// The picked peak's |H1|.
    pub amplitude: f64,
    /// Damping ratio of the single-mode fit (`None`: the fit failed).
    pub damping: Option<f64>,
    /// The E2PR (`None` without an exposure).
    pub e2pr: Option<f64>,
    /// The standard uncertainty and 95 % interval (`u`, `lo`, `hi`) of the frequency, the
    /// damping and the FRF's magnitude at the line, where estimated.
    pub intervals: [Option<(f64, f64, f64)>; 3],
}

/// `modes.csv`: `system,mode,band_lo_hz,band_hi_hz,f_hz,amplitude,damping,e2pr,method`, then
/// [`INTERVAL_COLUMNS`] (`damping`, `e2pr` and the intervals empty where absent; the E2PR
/// rounded by [`round_e2pr`]; `method` `h1`: the modes of the FRFs).
pub fn modes_csv(rows: &[ModeRow]) -> Vec<u8> {
    let mut s = format!(
        "system,mode,band_lo_hz,band_hi_hz,f_hz,amplitude,damping,e2pr,method,{INTERVAL_COLUMNS}\n"
    );
    for m in rows {
        let _ = write!(
            s,
            "{},{},{},{},{},{},{},{},h1",
            m.system,
            m.mode,
            m.band_hz.0,
            m.band_hz.1,
            m.f_hz,
            m.amplitude,
            opt(m.damping),
            opt(m.e2pr.map(round_e2pr))
        );
        super::push_intervals(&mut s, &m.intervals);
        s.push('\n');
    }
    s.into_bytes()
}

/// `displacement.csv` of one target: the columns of several targets
/// ([`tracks_displacement_csv`]), `target` 1.
pub fn displacement_csv(
    centroids: &[Centroid],
    (mm, lost): (&[f64], &[bool]),
    frame_rate_hz: f64,
    time_offset_s: f64,
) -> Vec<u8> {
    let track = Track {
        centroids,
        mm: Some(mm),
        lost: Some(lost),
        raw: None,
        evidence: None,
    };
    tracks_displacement_csv(&[track], frame_rate_hz, time_offset_s)
}

/// A centroid's `cx`, `cy` cells (`f32` text), empty when the frame has none.
pub(crate) fn position(c: &Centroid) -> (String, String) {
    match c.position() {
        Some((x, y)) => (x.to_string(), y.to_string()),
        None => (String::new(), String::new()),
    }
}

/// One row of `compensation.csv`: how one vision mode was divided by the exposure's transfer.
#[derive(Debug, Clone, PartialEq)]
pub struct CompensationRow {
    /// Mode number, 1-based.
    pub mode: usize,
    /// The mode's frequency, Hz.
    pub f_hz: f64,
    /// Its E2PR.
    pub e2pr: f64,
    /// The transfer divided by (`None`: the mode was flagged and left as it was).
    pub transfer: Option<f64>,
    /// The factor applied (1 when not compensated).
    pub factor: f64,
}

/// `compensation.csv`: `mode,f_hz,e2pr,transfer,factor,compensated` (`transfer` empty and
/// `compensated` false for a flagged mode).
pub fn compensation_csv(rows: &[CompensationRow]) -> Vec<u8> {
    let mut s = String::from("mode,f_hz,e2pr,transfer,factor,compensated\n");
    for r in rows {
        push_compensation_row(&mut s, "", r);
    }
    s.into_bytes()
}

/// One `compensation.csv` row after `prefix` (e.g. `3,`, the target column).
pub(crate) fn push_compensation_row(s: &mut String, prefix: &str, r: &CompensationRow) {
    let _ = writeln!(
        s,
        "{prefix}{},{},{},{},{},{}",
        r.mode,
        r.f_hz,
        round_e2pr(r.e2pr),
        opt(r.transfer),
        r.factor,
        r.transfer.is_some()
    );
}

/// An E2PR as written in CSV files: rounded to 9 significant digits, so that the product of a
/// frequency and an exposure is `0.0646`, not `0.06459999999999999`.
pub fn round_e2pr(e: f64) -> f64 {
    if e == 0.0 || !e.is_finite() {
        return e;
    }
    let digits = 9 - 1 - e.abs().log10().floor() as i32;
    let scale = 10f64.powi(digits);
    (e * scale).round() / scale
}

/// One target's track as `displacement.csv` shows it: its centroid per frame, and, when
/// computed, the displacement (mm) and the lost flag per frame (else lost = no centroid).
#[derive(Debug, Clone, Copy)]
pub struct Track<'a> {
    /// Centroid per frame (an empty one where the target was lost).
    pub centroids: &'a [Centroid],
    /// Displacement per frame, mm (`None`: no scale, or too many frames lost to fill them).
    pub mm: Option<&'a [f64]>,
    /// Lost per frame (`None`: the frames without a centroid).
    pub lost: Option<&'a [bool]>,
    /// The centroid as measured, when `centroids` has the camera's motion removed.
    pub raw: Option<&'a [Centroid]>,
    /// Per frame, what supports the position (a tracker that gathers evidence: Lucas-Kanade).
    pub evidence: Option<&'a [vibcam_common::evidence::Evidence]>,
}

/// `displacement.csv` of `analyze` (one target or several) and `track`:
/// `frame,t_s,target,cx,cy,pixels,flags,disp_mm,lost`, one row per frame and target (`tracks[t]`
/// is target `t + 1`); `t_s = time_offset_s + frame / fps`; `cx`, `cy` in pixels of the full
/// frame, empty where the target was lost; `flags` the firmware-core flag byte; `disp_mm` empty
/// where it was not computed; `lost` 0 or 1. When the camera's motion was removed (`raw`
/// given), `cx`, `cy` are the compensated position and `cx_raw,cy_raw` end each row with the
/// position as measured. When a tracker gave evidence, `score,fb_px,check` end each row: the
/// match score against the first frame's template, the forward-backward disagreement (px) and
/// the check that took the position away (`forward-backward`, `score`, `group`; empty: none),
/// each empty where there is none.
pub fn tracks_displacement_csv(
    tracks: &[Track<'_>],
    frame_rate_hz: f64,
    time_offset_s: f64,
) -> Vec<u8> {
    let raw = tracks.iter().any(|t| t.raw.is_some());
    let evidence = tracks.iter().any(|t| t.evidence.is_some());
    let mut s = String::from("frame,t_s,target,cx,cy,pixels,flags,disp_mm,lost");
    s.push_str(if raw { ",cx_raw,cy_raw" } else { "" });
    s.push_str(if evidence {
        ",score,fb_px,check\n"
    } else {
        "\n"
    });
    let frames = tracks.first().map_or(0, |t| t.centroids.len());
    for k in 0..frames {
        let t_s = time_offset_s + k as f64 / frame_rate_hz;
        for (t, tr) in tracks.iter().enumerate() {
            let c = &tr.centroids[k];
            let (cx, cy) = position(c);
            let lost = tr.lost.map_or(c.position().is_none(), |l| l[k]);
            let _ = write!(
                s,
                "{k},{t_s},{},{cx},{cy},{},{},{},{}",
                t + 1,
                c.pixels(),
                c.flags.bits(),
                opt(tr.mm.map(|m| m[k])),
                u8::from(lost)
            );
            if raw {
                let (x, y) = tr
                    .raw
                    .map_or((String::new(), String::new()), |r| position(&r[k]));
                let _ = write!(s, ",{x},{y}");
            }
            if evidence {
                let cells = vibcam_common::evidence::cells(tr.evidence.and_then(|e| e.get(k)));
                let _ = write!(s, ",{cells}");
            }
            s.push('\n');
        }
    }
    s.into_bytes()
}
