//! Exposure compensation of an analysis (`analyze --compensate-exposure`, method.md §2.8): the
//! vision H1 (its numerator, the vision acceleration's spectrum) is divided bin by bin by the
//! exposure's amplitude transfer at `|f| Te`, through firmware-core's [`ExposureTransfer`] (no
//! ratio beyond [`E2PR_LIMIT`]: those bins are left as they were), and the vision modes are
//! picked again.
//!
//! The transfer is the box exposure's `sinc(pi f Te)` ([`BoxTransfer`]): exact for the weighted
//! centroid with the threshold at the background level. The binary centroid's transfer depends
//! on the target, the threshold and the motion amplitude (`imaging::compensation`), which a
//! recording does not state, so it is divided by the sinc too, with a note in the report.
//! The vision acceleration and displacement series are left uncompensated.

use super::Analysis;
use crate::chain::frf;
use crate::export::analysis::CompensationRow;
use firmware_core::exposure::{BoxTransfer, ExposureTransfer, E2PR_LIMIT};

/// What the compensation did to one vision mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeCompensation {
    /// Mode number, from 1 in band order.
    pub mode: usize,
    /// The compensated vision H1's picked frequency, Hz.
    pub f_hz: f64,
    /// `f_hz` x exposure.
    pub e2pr: f64,
    /// The transfer ratio the mode's bin was divided by; `None`: E2PR above [`E2PR_LIMIT`],
    /// left uncorrected.
    pub ratio: Option<f64>,
}

impl ModeCompensation {
    /// The factor the vision amplitude was multiplied by (1 when uncorrected).
    pub fn factor(&self) -> f64 {
        self.ratio.map_or(1.0, |r| 1.0 / r)
    }
}

/// The compensation of an analysis: per vision mode, and the bins divided.
#[derive(Debug, Clone, PartialEq)]
pub struct Compensated {
    /// Per vision mode.
    pub modes: Vec<ModeCompensation>,
    /// Bins of the vision H1 divided by the transfer.
    pub corrected_bins: usize,
    /// Bins left uncorrected (E2PR above the limit).
    pub uncorrected_bins: usize,
    /// Exposure, s.
    pub exposure_s: f64,
    /// A note on the transfer used (binary centroid: the sinc as an approximation).
    pub note: Option<String>,
}

/// Divides the vision H1 of `a` by the box transfer of `exposure_s` and picks its modes again
/// in `bands`; `binary` adds the note that the sinc only approximates the binary centroid.
pub fn compensate(
    a: &mut Analysis,
    exposure_s: f64,
    bands: &[(f64, f64)],
    binary: bool,
) -> anyhow::Result<Compensated> {
    let (mut corrected_bins, mut uncorrected_bins) = (0, 0);
    for (h, f) in a.vis_frf.h1.iter_mut().zip(&a.vis_frf.freq_hz) {
        match BoxTransfer.ratio((f.abs() * exposure_s) as f32) {
            Some(r) => {
                *h /= f64::from(r);
                corrected_bins += 1;
            }
            None => uncorrected_bins += 1,
        }
    }
    a.vis_modes = frf::pick_modes(&a.vis_frf, bands, Some(exposure_s))?;
    let modes = a
        .vis_modes
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let e2pr = m.f_hz * exposure_s;
            ModeCompensation {
                mode: i + 1,
                f_hz: m.f_hz,
                e2pr,
                ratio: BoxTransfer.ratio(e2pr as f32).map(f64::from),
            }
        })
        .collect();
    let note = binary.then(|| {
        "binary centroid: divided by sinc(pi f Te), the weighted centroid's transfer; the binary \
         centroid's own transfer depends on the target, threshold and motion amplitude \
         (host-harness plan), which the recording does not state; $twin N measures it for \
         this recording's target and motion (the twin's amplitude ratio per mode)"
            .to_string()
    });
    Ok(Compensated {
        modes,
        corrected_bins,
        uncorrected_bins,
        exposure_s,
        note,
    })
}

impl Compensated {
    /// The report's section: the bins divided, and per mode the E2PR, the ratio and the factor
    /// (or the flag for a mode left uncorrected).
    pub fn report(&self) -> String {
        let mut s = format!(
            "\nexposure compensation ({} ms, vision H1 divided by sinc(pi f Te) up to E2PR {}): \
             {} bins corrected, {} left uncorrected\n",
            self.exposure_s * 1000.0,
            E2PR_LIMIT,
            self.corrected_bins,
            self.uncorrected_bins
        );
        for m in &self.modes {
            s += &match m.ratio {
                Some(r) => format!(
                    "  mode {}: {} Hz, E2PR {:.4}: compensated, transfer {r:.4}, amplitude x {:.4}\n",
                    m.mode,
                    m.f_hz,
                    m.e2pr,
                    m.factor()
                ),
                None => format!(
                    "  mode {}: {} Hz, E2PR {:.4} > {}: NOT compensated (flagged)\n",
                    m.mode, m.f_hz, m.e2pr, E2PR_LIMIT
                ),
            };
        }
        if let Some(n) = &self.note {
            s += &format!("  note: {n}\n");
        }
        s
    }

    /// The rows of `compensation.csv` ([`crate::export::analysis::compensation_csv`]).
    pub fn rows(&self) -> Vec<CompensationRow> {
        self.modes
            .iter()
            .map(|m| CompensationRow {
                mode: m.mode,
                f_hz: m.f_hz,
                e2pr: m.e2pr,
                transfer: m.ratio,
                factor: m.factor(),
            })
            .collect()
    }
}
