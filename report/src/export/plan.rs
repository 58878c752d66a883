//! `plan --out`: the plan's rows as CSV (header [`PLAN_CSV_HEADER`], the command-line
//! contract), and the row type itself.

use firmware_core::centroid::Mode;

/// One row of the plan (CSV `mode,f_hz,centroid,max_exposure_ms,e2pr,predicted_ratio,
/// compensated_residual,lost_frame_risk`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanRow {
    /// Mode number.
    pub mode: usize,
    /// Natural frequency, Hz.
    pub f_hz: f64,
    /// Centroid mode.
    pub centroid: Mode,
    /// Longest exposure keeping the predicted ratio `>= 1 - tolerance`, ms, at most the frame
    /// period; `None` when even the shortest exposure misses the tolerance (an empty cell).
    pub max_exposure_ms: Option<f64>,
    /// `f Te` at the evaluated exposure.
    pub e2pr: f64,
    /// Predicted vision / true amplitude at the evaluated exposure.
    pub predicted_ratio: f64,
    /// Relative amplitude error left after compensation at the evaluated exposure.
    pub compensated_residual: f64,
    /// Lost-frame risk at the evaluated exposure (> 1: frames expected to be lost).
    pub lost_frame_risk: f64,
}

/// The CSV header of the plan's rows (the command-line contract).
pub const PLAN_CSV_HEADER: [&str; 8] = [
    "mode",
    "f_hz",
    "centroid",
    "max_exposure_ms",
    "e2pr",
    "predicted_ratio",
    "compensated_residual",
    "lost_frame_risk",
];

impl PlanRow {
    /// The row's CSV fields in the order of [`PLAN_CSV_HEADER`] (centroid as `binary` or
    /// `weighted`; numbers with Rust's shortest round-trip formatting).
    pub fn csv_record(&self) -> [String; 8] {
        [
            self.mode.to_string(),
            self.f_hz.to_string(),
            match self.centroid {
                Mode::Weighted => "weighted",
                _ => "binary",
            }
            .to_string(),
            self.max_exposure_ms
                .map(|e| e.to_string())
                .unwrap_or_default(),
            self.e2pr.to_string(),
            self.predicted_ratio.to_string(),
            self.compensated_residual.to_string(),
            self.lost_frame_risk.to_string(),
        ]
    }
}

/// `plan --out` bytes: the header, then every row of every plan (`rows`).
pub fn plan_csv<'a>(rows: impl IntoIterator<Item = &'a PlanRow>) -> anyhow::Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(PLAN_CSV_HEADER)?;
    for r in rows {
        w.write_record(r.csv_record())?;
    }
    Ok(w.into_inner()?)
}
