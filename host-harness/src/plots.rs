//! (under construction: being written)
use crate::report::{FrfBandRow, RealizationRow, SummaryRow};
use std::path::{Path, PathBuf};
/// Inputs of the study figures.
#[derive(Debug)]
pub struct StudyPlots<'a> {
    /// Title.
    pub title: &'a str,
    /// Unit of amplitudes.
    pub amplitude_unit: &'a str,
    /// Summary rows.
    pub summary: &'a [SummaryRow],
    /// Realizations.
    pub realizations: &'a [RealizationRow],
    /// FRF band rows.
    pub frf_band: &'a [FrfBandRow],
}
/// Placeholder until the figures land: writes nothing.
pub fn write_study_plots(_dir: &Path, _p: &StudyPlots) -> anyhow::Result<Vec<PathBuf>> {
    Ok(Vec::new())
}
