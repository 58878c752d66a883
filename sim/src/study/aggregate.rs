//! From run records to the study outputs: the summary (mean and standard deviation per system,
//! exposure and mode), the realizations, the FRF band and the lost frames, as typed rows; and
//! writing them. Everything here is deterministic: the records come sorted by run.

use super::{checkpoint::files, PeakRecord, RunRecord, Scenario, StudyConfig, SystemRecord};
use crate::imaging::exposure::ExposureCorrection;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use vibcam_common::stats;
use vibcam_common::uncertainty::{coverage_summary, CoverageSummary};
use vibcam_readers::bad_input;
use vibcam_report::export::study::{CoverageRow, FrfBandRow, RealizationRow, SummaryRow, System};

pub use vibcam_report::export::study::LostFrames;

/// Lost frames of all runs at one exposure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LostByExposure {
    /// Exposure time, ms.
    pub exposure_ms: f64,
    /// Frames without a centroid, summed over the runs.
    pub lost: u64,
    /// Frames, summed over the runs.
    pub frames: u64,
    /// Runs reported as failed at this exposure.
    pub failed_runs: u64,
}

/// The study outputs computed from a complete, sorted set of run records.
#[derive(Debug, Clone, PartialEq)]
pub struct Outputs {
    /// `summary.csv` rows.
    pub summary: Vec<SummaryRow>,
    /// `realizations.csv` rows.
    pub realizations: Vec<RealizationRow>,
    /// `frf_band.csv` rows.
    pub frf_band: Vec<FrfBandRow>,
    /// `lost_frames.csv` rows.
    pub lost: Vec<LostFrames>,
    /// `coverage.csv` rows.
    pub coverage: Vec<CoverageRow>,
    /// What the `vision_compensated` rows divide by.
    pub correction: String,
}

impl Outputs {
    /// A `coverage.csv` row of `system` at `exposure_ms`, mode index `m` (from 0).
    fn push_coverage(
        &mut self,
        (system, exposure_ms, m): (System, f64, usize),
        quantity: &'static str,
        coverage: CoverageSummary,
    ) {
        self.coverage.push(CoverageRow {
            system,
            exposure_ms,
            mode: m + 1,
            quantity,
            coverage,
        });
    }
}

fn peak_of(sys: &SystemRecord, mode: usize) -> Option<PeakRecord> {
    sys.peaks.get(mode).copied().flatten()
}

/// Mean natural frequency of each mode over the runs (for the E2PR).
fn mean_natural_frequencies(records: &[RunRecord], modes: usize) -> Vec<f64> {
    (0..modes)
        .map(|m| {
            let v: Vec<f64> = records
                .iter()
                .filter_map(|r| r.natural_f_hz.get(m).copied())
                .collect();
            stats::mean(&v).unwrap_or(f64::NAN)
        })
        .collect()
}

/// The summary row of one system, exposure and mode from its picked peaks, with the JCGM 101
/// statements at coverage probability `p` (none when the runs are too few).
fn summary_row(
    system: System,
    exposure_ms: f64,
    mode: usize,
    nat_hz: f64,
    p: &[PeakRecord],
    coverage: f64,
) -> SummaryRow {
    let f: Vec<f64> = p.iter().map(|p| p.f_hz).collect();
    let a: Vec<f64> = p.iter().map(|p| p.a).collect();
    SummaryRow {
        system,
        exposure_ms,
        mode: mode + 1,
        runs: p.len(),
        mu_f_hz: stats::mean(&f).unwrap_or(f64::NAN),
        sigma_f_hz: stats::std_dev(&f).unwrap_or(f64::NAN),
        mu_a: stats::mean(&a).unwrap_or(f64::NAN),
        sigma_a: stats::std_dev(&a).unwrap_or(f64::NAN),
        e2pr: exposure_ms / 1000.0 * nat_hz,
        chi_mu: None,
        chi_sigma: None,
        a_coverage: coverage_summary(&a, coverage).ok(),
        f_coverage: coverage_summary(&f, coverage).ok(),
    }
}

/// The picks of one system at exposure `ei` and mode `m`, by run (failed vision runs left
/// out); `vision_compensated` divides each vision amplitude by `correction` at its peak.
pub(crate) fn picks(
    records: &[RunRecord],
    system: System,
    ei: usize,
    exposure_ms: f64,
    m: usize,
    correction: &ExposureCorrection,
) -> Vec<(u64, PeakRecord)> {
    records
        .iter()
        .filter_map(|r| {
            let p = match system {
                System::Transducer => peak_of(&r.transducer, m),
                _ if r.vision[ei].failed => None,
                _ => peak_of(&r.vision[ei].system, m),
            }?;
            let p = match system {
                System::VisionCompensated => PeakRecord {
                    a: correction.compensate(p.a, p.f_hz, exposure_ms),
                    ..p
                },
                _ => p,
            };
            Some((r.run, p))
        })
        .collect()
}

/// The three systems in the order of the outputs.
pub(crate) const SYSTEMS: [System; 3] = [
    System::Transducer,
    System::Vision,
    System::VisionCompensated,
];

/// The summary and coverage rows of every system and mode at exposure `ei`.
#[allow(clippy::too_many_arguments)]
fn summary_at(
    records: &[RunRecord],
    ei: usize,
    exposure_ms: f64,
    nat: &[f64],
    with_chi: bool,
    cfg: &StudyConfig,
    correction: &ExposureCorrection,
    out: &mut Outputs,
) {
    for (m, nat_m) in nat.iter().enumerate() {
        let tr = picks(records, System::Transducer, ei, exposure_ms, m, correction);
        let mut t_row = None;
        for system in SYSTEMS {
            let p = picks(records, system, ei, exposure_ms, m, correction);
            let peaks: Vec<PeakRecord> = p.iter().map(|(_, p)| *p).collect();
            let mut row = summary_row(system, exposure_ms, m, *nat_m, &peaks, cfg.coverage);
            let t: &SummaryRow = t_row.get_or_insert_with(|| row.clone());
            if with_chi && system != System::Transducer {
                row.chi_mu = Some(row.mu_a / t.mu_a);
                row.chi_sigma = Some(row.sigma_a / t.sigma_a);
            }
            let mut quantities: Vec<(&'static str, Vec<f64>)> = vec![
                ("f_hz", peaks.iter().map(|p| p.f_hz).collect()),
                ("a", peaks.iter().map(|p| p.a).collect()),
            ];
            if system != System::Transducer {
                // paired by run: what one test would show as vision / transducer
                let by_run: BTreeMap<u64, f64> = tr.iter().map(|(r, p)| (*r, p.a)).collect();
                let ratio = p
                    .iter()
                    .filter_map(|(r, p)| by_run.get(r).map(|t| p.a / t))
                    .collect();
                quantities.push(("ratio", ratio));
                if with_chi {
                    let seed = chi_seed(cfg.seed, ei, m, system);
                    chi_coverage(&tr, &p, (system, exposure_ms, m), cfg.coverage, seed, out);
                }
            }
            for (quantity, values) in quantities {
                if let Ok(coverage) = coverage_summary(&values, cfg.coverage) {
                    out.push_coverage((system, exposure_ms, m), quantity, coverage);
                }
            }
            out.summary.push(row);
        }
    }
}

/// One line per vision `chi_mu` and `chi_sigma` coverage row: the index, its bootstrap
/// interval and standard uncertainty, and about how many runs would make the interval's
/// half-width one point (0.01), the uncertainty falling as one over the root of the runs.
pub fn chi_statements(out: &Outputs) -> Vec<String> {
    out.coverage
        .iter()
        .filter(|r| r.system == System::Vision && r.quantity.starts_with("chi_"))
        .map(|r| {
            let c = &r.coverage;
            let half = (c.short_hi - c.short_lo) / 2.0;
            let runs = (c.n as f64 * (half / 0.01).powi(2)).ceil();
            format!(
                "{} vision {} ms mode {}: {:.4} ({:.0} % bootstrap interval {:.4} .. {:.4}, u {:.4}, \
                 {} runs); +/- 0.01 at {:.0} % needs about {runs} runs",
                r.quantity,
                r.exposure_ms,
                r.mode,
                c.mean,
                100.0 * c.p,
                c.short_lo,
                c.short_hi,
                c.u_mean,
                c.n,
                100.0 * c.p
            )
        })
        .collect()
}

/// The bootstrap stream of the chi statements of one system, exposure and mode (deterministic,
/// distinct per row).
fn chi_seed(seed: u64, ei: usize, mode: usize, system: System) -> u64 {
    let row = ((ei as u64) << 16) | ((mode as u64) << 8) | system as u64;
    seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ row
}

/// `chi_mu` and `chi_sigma` coverage rows of `system` against the transducer (bootstrap over
/// the runs, [`vibcam_common::uncertainty::bootstrap_chi`]); nothing when they are undefined.
fn chi_coverage(
    transducer: &[(u64, PeakRecord)],
    vision: &[(u64, PeakRecord)],
    (system, exposure_ms, m): (System, f64, usize),
    p: f64,
    seed: u64,
    out: &mut Outputs,
) {
    let by_run: BTreeMap<u64, f64> = vision.iter().map(|(r, p)| (*r, p.a)).collect();
    let pairs: Vec<(f64, Option<f64>)> = transducer
        .iter()
        .map(|(r, t)| (t.a, by_run.get(r).copied()))
        .collect();
    if let Ok((mu, sigma)) = vibcam_common::uncertainty::bootstrap_chi(&pairs, p, seed) {
        for (quantity, coverage) in [("chi_mu", mu), ("chi_sigma", sigma)] {
            out.push_coverage((system, exposure_ms, m), quantity, coverage);
        }
    }
}

/// Picks of every run at exposure `ei` per system (failed vision runs left out).
fn realizations_at(
    records: &[RunRecord],
    ei: usize,
    exposure_ms: f64,
    modes: usize,
    correction: &ExposureCorrection,
    out: &mut Vec<RealizationRow>,
) {
    for r in records {
        for (system, sys, ok) in [
            (System::Transducer, &r.transducer, true),
            (System::Vision, &r.vision[ei].system, !r.vision[ei].failed),
            (
                System::VisionCompensated,
                &r.vision[ei].system,
                !r.vision[ei].failed,
            ),
        ] {
            if !ok {
                continue;
            }
            for m in 0..modes {
                if let Some(p) = peak_of(sys, m) {
                    let a = if system == System::VisionCompensated {
                        correction.compensate(p.a, p.f_hz, exposure_ms)
                    } else {
                        p.a
                    };
                    out.push(RealizationRow {
                        run: r.run,
                        exposure_ms,
                        system,
                        mode: m + 1,
                        f_hz: p.f_hz,
                        a,
                    });
                }
            }
        }
    }
}

/// Mean |FRF| and its 5th/95th percentiles per bin up to `max_hz`, per system, at exposure `ei`
/// (`vision_compensated`: each bin divided by `correction` at its frequency).
fn frf_band_at(
    records: &[RunRecord],
    ei: usize,
    exposure_ms: f64,
    freqs: &[f64],
    max_hz: f64,
    correction: &ExposureCorrection,
    out: &mut Vec<FrfBandRow>,
) {
    let transducer: Vec<&Vec<f32>> = records.iter().map(|r| &r.transducer.frf_abs).collect();
    let vision: Vec<&Vec<f32>> = records
        .iter()
        .filter(|r| !r.vision[ei].failed)
        .map(|r| &r.vision[ei].system.frf_abs)
        .collect();
    for (system, curves) in [
        (System::Transducer, transducer),
        (System::Vision, vision.clone()),
        (System::VisionCompensated, vision),
    ] {
        if curves.is_empty() {
            continue;
        }
        let mut col = Vec::with_capacity(curves.len());
        for (k, &f) in freqs.iter().enumerate() {
            if f > max_hz {
                break;
            }
            let gain = match system {
                System::VisionCompensated => correction.compensate(1.0, f, exposure_ms),
                _ => 1.0,
            };
            col.clear();
            col.extend(
                curves
                    .iter()
                    .filter_map(|c| c.get(k).map(|v| *v as f64 * gain)),
            );
            col.sort_by(f64::total_cmp);
            out.push(FrfBandRow {
                system,
                exposure_ms,
                freq_hz: f,
                mean_abs: stats::mean(&col).unwrap_or(f64::NAN),
                p05_abs: stats::percentile_sorted(&col, 5.0).unwrap_or(f64::NAN),
                p95_abs: stats::percentile_sorted(&col, 95.0).unwrap_or(f64::NAN),
            });
        }
    }
}

/// Aggregates run records (sorted by run) into the study outputs. Deterministic.
pub fn aggregate(
    cfg: &StudyConfig,
    scenario: &dyn Scenario,
    records: &[RunRecord],
) -> anyhow::Result<Outputs> {
    aggregate_with(cfg, scenario, records, &scenario.exposure_correction()?)
}

/// [`aggregate`] with the scenario's exposure correction already measured.
pub fn aggregate_with(
    cfg: &StudyConfig,
    scenario: &dyn Scenario,
    records: &[RunRecord],
    correction: &ExposureCorrection,
) -> anyhow::Result<Outputs> {
    if let Some(rec) = records
        .iter()
        .find(|r| r.vision.len() != cfg.exposures_ms.len())
    {
        return Err(bad_input(format!(
            "run {}: {} vision records for {} exposures",
            rec.run,
            rec.vision.len(),
            cfg.exposures_ms.len()
        )));
    }
    let modes = scenario.bands().len();
    let freqs = scenario.frf_freqs();
    let nat = mean_natural_frequencies(records, modes);
    let mut out = Outputs {
        summary: Vec::new(),
        realizations: Vec::new(),
        frf_band: Vec::new(),
        lost: Vec::new(),
        coverage: Vec::new(),
        correction: correction.describe(),
    };
    for (ei, &exp) in cfg.exposures_ms.iter().enumerate() {
        out.lost.extend(records.iter().map(|r| LostFrames {
            run: r.run,
            exposure_ms: exp,
            lost: r.vision[ei].lost_frames,
            frames: r.vision[ei].frames,
            failed: r.vision[ei].failed,
        }));
        summary_at(
            records,
            ei,
            exp,
            &nat,
            scenario.with_chi(),
            cfg,
            correction,
            &mut out,
        );
        realizations_at(records, ei, exp, modes, correction, &mut out.realizations);
        frf_band_at(
            records,
            ei,
            exp,
            &freqs,
            cfg.frf_max_hz,
            correction,
            &mut out.frf_band,
        );
    }
    Ok(out)
}

/// Writes the CSV outputs (and returns their paths). Plots are written separately.
pub fn write_outputs(
    dir: &Path,
    scenario: &dyn Scenario,
    out: &Outputs,
) -> anyhow::Result<Vec<PathBuf>> {
    let items: [(&str, Vec<u8>); 5] = [
        (
            files::SUMMARY,
            vibcam_report::export::study::summary_csv(&out.summary, scenario.with_chi()),
        ),
        (
            files::REALIZATIONS,
            vibcam_report::export::study::realizations_csv(&out.realizations),
        ),
        (
            files::FRF_BAND,
            vibcam_report::export::study::frf_band_csv(&out.frf_band),
        ),
        (
            files::LOST_FRAMES,
            vibcam_report::export::study::lost_frames_csv(&out.lost),
        ),
        (
            files::COVERAGE,
            vibcam_report::export::study::coverage_csv(&out.coverage),
        ),
    ];
    let mut paths = Vec::new();
    for (name, bytes) in items {
        let p = dir.join(name);
        vibcam_report::export::write_atomic(&p, &bytes)?;
        paths.push(p);
    }
    Ok(paths)
}

/// Lost-frame counts per exposure, in increasing exposure.
pub fn lost_by_exposure(out: &Outputs) -> Vec<LostByExposure> {
    let mut m: BTreeMap<u64, LostByExposure> = BTreeMap::new();
    for l in &out.lost {
        let s = m.entry(l.exposure_ms.to_bits()).or_insert(LostByExposure {
            exposure_ms: l.exposure_ms,
            lost: 0,
            frames: 0,
            failed_runs: 0,
        });
        s.lost += l.lost;
        s.frames += l.frames;
        s.failed_runs += u64::from(l.failed);
    }
    let mut v: Vec<_> = m.into_values().collect();
    v.sort_by(|a, b| a.exposure_ms.total_cmp(&b.exposure_ms));
    v
}
