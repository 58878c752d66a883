//! Exposure compensation on the host (method.md §2.8): the transfer the vision amplitudes are
//! divided by, chosen for the camera's centroid. The weighted centroid divides by the sinc of a
//! centred box exposure (`firmware_core::exposure::BoxTransfer`); the binary centroid, which is
//! not linear in the image, by a 17-node firmware correction table measured through the
//! renderer for the target, the threshold and a motion amplitude
//! ([`crate::imaging::compensation::correction_table`]). Beyond `E2PR` 0.8 (or below the
//! firmware's ratio floor) nothing is corrected: [`ExposureCorrection::ratio`] is `None`.

use crate::imaging::compensation::{correction_table, CompensationError, TransferSetup};
use crate::imaging::{DiskTarget, Setup};
use firmware_core::exposure::{BoxTransfer, CorrectionTable, ExposureTransfer};
pub use vibcam_model::{equivalent_amplitude_px, MotionSegment};

/// Nodes of the binary correction table (step 0.05: E2PR 0 ..= 0.8).
pub const TABLE_NODES: usize = 17;
/// E2PR step of the binary correction table.
pub const TABLE_STEP: f64 = 0.05;

/// The transfer a camera's vision amplitudes are divided by.
#[derive(Debug, Clone, PartialEq)]
pub enum ExposureCorrection {
    /// `sinc(pi E2PR)` (exact for the weighted centroid with its threshold at the background).
    Sinc,
    /// A measured table and the (effective) motion amplitude it was measured at, px.
    Table(CorrectionTable<TABLE_NODES>, f64),
}

impl ExposureCorrection {
    /// The transfer an H1 estimate sees when the target moves with different amplitudes in
    /// its segments: `H1 = sum_s |X_s|^2 T_s H / sum_s |X_s|^2`, so the table is the average of
    /// the tables at the segments' amplitudes weighted by the input energy of each segment
    /// (segments within 5 % of each other's amplitude share one measured curve). The weighted
    /// centroid is measured too: with its threshold above the background it is not linear in
    /// the image either, and departs from the sinc by about 1 % at E2PR 0.3.
    pub fn for_segments(
        imaging: &Setup,
        target: DiskTarget,
        threshold: u16,
        segments: &[MotionSegment],
    ) -> Result<ExposureCorrection, CompensationError> {
        let total: f64 = segments.iter().map(|s| s.weight).sum();
        if !(total.is_finite() && total > 0.0) {
            return Err(CompensationError::Setup(
                "the motion segments carry no input energy".into(),
            ));
        }
        let groups = amplitude_groups(segments);
        let mut ratios = [0.0f32; TABLE_NODES];
        let mut eff = 0.0;
        for (a, w) in groups {
            let measurement = &imaging.measurement;
            let setup = TransferSetup {
                frame_range_frac: measurement.frame_range_frac,
                epsa_images: imaging.epsa_images,
                lk: measurement.tracker == crate::imaging::TrackerKind::Lk,
                ..TransferSetup::new(target, threshold, measurement.tracker.mode(), a)
            };
            let t = correction_table::<TABLE_NODES>(&setup, TABLE_STEP)?;
            for (i, r) in ratios.iter_mut().enumerate() {
                let node = t.interpolate((i as f64 * TABLE_STEP) as f32).unwrap_or(0.0);
                *r += (w / total) as f32 * node;
            }
            eff += w / total * a * a;
        }
        let table = CorrectionTable::try_new(TABLE_STEP as f32, ratios)
            .map_err(CompensationError::Table)?;
        Ok(ExposureCorrection::Table(table, eff.sqrt()))
    }

    /// Measured / true amplitude at `e2pr`; `None` where nothing is corrected.
    pub fn ratio(&self, e2pr: f64) -> Option<f64> {
        let e = e2pr.abs() as f32;
        match self {
            ExposureCorrection::Sinc => BoxTransfer.ratio(e),
            ExposureCorrection::Table(t, _) => t.ratio(e),
        }
        .map(f64::from)
    }

    /// `a` at frequency `f_hz` seen with exposure `exposure_ms`, with the transfer divided out;
    /// `a` unchanged where nothing is corrected.
    pub fn compensate(&self, a: f64, f_hz: f64, exposure_ms: f64) -> f64 {
        match self.ratio(f_hz * exposure_ms / 1000.0) {
            Some(r) => a / r,
            None => a,
        }
    }

    /// One line saying what is divided out.
    pub fn describe(&self) -> String {
        match self {
            ExposureCorrection::Sinc => "weighted centroid: divided by sinc(pi f Te)".into(),
            ExposureCorrection::Table(_, a) => format!(
                "divided by the tracker's transfer measured through the renderer at the \
                 motion of a nominal record (input-energy weighted RMS amplitude {a:.2} px; \
                 {TABLE_NODES} nodes, E2PR step {TABLE_STEP})"
            ),
        }
    }
}

/// The segments' amplitudes grouped on a 5 % logarithmic grid, with the summed weight of each
/// group: `(amplitude_px, weight)`, one transfer curve per group.
pub fn amplitude_groups(segments: &[MotionSegment]) -> Vec<(f64, f64)> {
    let mut groups: Vec<(f64, f64)> = Vec::new();
    for s in segments {
        let key = (s.amplitude_px.ln() / 1.05f64.ln()).round();
        let a = 1.05f64.powf(key);
        match groups.iter_mut().find(|g| (g.0 / a - 1.0).abs() < 1e-9) {
            Some(g) => g.1 += s.weight,
            None => groups.push((a, s.weight)),
        }
    }
    groups
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sinc_is_divided_out_below_the_limit_only() {
        let c = ExposureCorrection::Sinc;
        // f Te = 0.5: sinc(pi / 2) = 2 / pi
        let a = c.compensate(2.0 / std::f64::consts::PI, 5.0, 100.0);
        assert!((a - 1.0).abs() < 1e-6, "{a}");
        // f Te = 0.9 > 0.8: left as it is
        assert_eq!(c.compensate(0.3, 9.0, 100.0), 0.3);
    }

    #[test]
    fn equivalent_amplitude_of_a_sinusoid_is_its_amplitude() {
        let p: Vec<f64> = (0..1000)
            .map(|i| 3.0 + 2.5 * (std::f64::consts::TAU * i as f64 / 100.0).sin())
            .collect();
        assert!((equivalent_amplitude_px(&p) - 2.5).abs() < 1e-9);
    }
}
