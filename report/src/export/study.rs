//! A study's outputs: `summary.csv`, `coverage.csv`, `realizations.csv`, `frf_band.csv`,
//! `lost_frames.csv`, `adaptive.csv` as rows -> bytes, and the table a study prints. Plots live
//! in [`crate::plots`].

use super::{csv_bytes, num};
use std::fmt::Write as _;
use vibcam_common::uncertainty::{CoverageSummary, Stability};

/// Which measurement system a row describes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum System {
    /// The contact transducer path (load cell + laser, or accelerometers).
    Transducer,
    /// The camera path (image formation, centroid, H1).
    Vision,
    /// The camera path with its exposure transfer divided out (method.md §2.8): each picked
    /// amplitude divided by the centroid's transfer at `E2PR = Te f` of its peak, left as it
    /// was beyond `E2PR` 0.8.
    VisionCompensated,
}

impl System {
    /// Name used in CSV files (`transducer` / `vision`).
    pub fn name(self) -> &'static str {
        match self {
            System::Transducer => "transducer",
            System::Vision => "vision",
            System::VisionCompensated => "vision_compensated",
        }
    }

    /// Parses a CSV name.
    pub fn parse(s: &str) -> Option<System> {
        match s {
            "transducer" => Some(System::Transducer),
            "vision" => Some(System::Vision),
            "vision_compensated" => Some(System::VisionCompensated),
            _ => None,
        }
    }
}

/// One row of `summary.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct SummaryRow {
    /// Measurement system.
    pub system: System,
    /// Camera exposure time, ms (the transducer rows repeat the exposure they are compared with).
    pub exposure_ms: f64,
    /// Mode number, 1-based.
    pub mode: usize,
    /// Runs that contributed (runs whose vision path failed are left out of vision rows).
    pub runs: usize,
    /// Mean resonance frequency, Hz.
    pub mu_f_hz: f64,
    /// Standard deviation of the resonance frequency, Hz.
    pub sigma_f_hz: f64,
    /// Mean resonant amplitude (study units: mm/kN grandstand, (m/s^2)/(m/s^2) cantilever).
    pub mu_a: f64,
    /// Standard deviation of the resonant amplitude.
    pub sigma_a: f64,
    /// Exposure-to-period ratio: exposure time x mean natural frequency of the mode.
    pub e2pr: f64,
    /// Cantilever only, vision rows: mean vision amplitude / mean transducer amplitude.
    pub chi_mu: Option<f64>,
    /// Cantilever only, vision rows: std vision amplitude / std transducer amplitude.
    pub chi_sigma: Option<f64>,
    /// The amplitudes' JCGM 101 statement (standard uncertainty of the mean, coverage
    /// intervals); `None` when the runs are too few for the coverage probability.
    pub a_coverage: Option<CoverageSummary>,
    /// The frequencies' JCGM 101 statement, as for the amplitudes.
    pub f_coverage: Option<CoverageSummary>,
}

/// One row of `realizations.csv`: one picked mode of one system in one run.
#[derive(Debug, Clone, PartialEq)]
pub struct RealizationRow {
    /// Run index (0-based, global across shards).
    pub run: u64,
    /// Exposure time, ms.
    pub exposure_ms: f64,
    /// Measurement system.
    pub system: System,
    /// Mode number, 1-based.
    pub mode: usize,
    /// Picked resonance frequency, Hz.
    pub f_hz: f64,
    /// Picked amplitude.
    pub a: f64,
}

/// One row of `frf_band.csv`: statistics of |FRF| over the runs at one frequency bin.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfBandRow {
    /// Measurement system.
    pub system: System,
    /// Exposure time, ms.
    pub exposure_ms: f64,
    /// Bin frequency, Hz.
    pub freq_hz: f64,
    /// Mean |FRF| over the runs.
    pub mean_abs: f64,
    /// 5th percentile of |FRF|.
    pub p05_abs: f64,
    /// 95th percentile of |FRF|.
    pub p95_abs: f64,
}

/// The coverage columns appended to `summary.csv`: the standard uncertainty of the mean and
/// the shortest coverage interval (JCGM 101 7.6, 7.7.2) of the amplitude, then of the
/// frequency. The names say 95 whatever the coverage probability (recorded in `config.toml`).
pub const COVERAGE_COLUMNS: &str = "u_mu_a,a_lo95,a_hi95,u_mu_f,f_lo95,f_hi95";

/// `summary.csv` bytes. `with_chi` adds the `chi_mu,chi_sigma` columns (cantilever); the
/// [`COVERAGE_COLUMNS`] come last.
pub fn summary_csv(rows: &[SummaryRow], with_chi: bool) -> Vec<u8> {
    let mut s = String::from("system,exposure_ms,mode,runs,mu_f_hz,sigma_f_hz,mu_a,sigma_a,e2pr");
    if with_chi {
        s.push_str(",chi_mu,chi_sigma");
    }
    s.push(',');
    s.push_str(COVERAGE_COLUMNS);
    s.push('\n');
    for r in rows {
        let _ = write!(
            s,
            "{},{},{},{},{},{},{},{},{}",
            r.system.name(),
            num(r.exposure_ms),
            r.mode,
            r.runs,
            num(r.mu_f_hz),
            num(r.sigma_f_hz),
            num(r.mu_a),
            num(r.sigma_a),
            num(r.e2pr)
        );
        let opt = |v: Option<f64>| v.map(num).unwrap_or_default();
        if with_chi {
            let _ = write!(s, ",{},{}", opt(r.chi_mu), opt(r.chi_sigma));
        }
        for c in [&r.a_coverage, &r.f_coverage] {
            let _ = write!(
                s,
                ",{},{},{}",
                opt(c.as_ref().map(|c| c.u_mean)),
                opt(c.as_ref().map(|c| c.short_lo)),
                opt(c.as_ref().map(|c| c.short_hi))
            );
        }
        s.push('\n');
    }
    s.into_bytes()
}

/// One row of `coverage.csv`: the whole JCGM 101 statement of one reported quantity.
#[derive(Debug, Clone, PartialEq)]
pub struct CoverageRow {
    /// Measurement system.
    pub system: System,
    /// Exposure time, ms.
    pub exposure_ms: f64,
    /// Mode number, 1-based.
    pub mode: usize,
    /// `f_hz`, `a`, or `ratio` (per run: this system's amplitude over the transducer's).
    pub quantity: &'static str,
    /// The statement.
    pub coverage: CoverageSummary,
}

/// `coverage.csv` bytes.
pub fn coverage_csv(rows: &[CoverageRow]) -> Vec<u8> {
    const HEADER: &str = "system,exposure_ms,mode,quantity,runs,coverage,estimate,\
                          std_uncertainty,u_mean,shortest_lo,shortest_hi,symmetric_lo,symmetric_hi";
    csv_bytes(HEADER, rows, |r| {
        let c = &r.coverage;
        [
            r.system.name().to_string(),
            num(r.exposure_ms),
            r.mode.to_string(),
            r.quantity.to_string(),
            c.n.to_string(),
            num(c.p),
            num(c.mean),
            num(c.std),
            num(c.u_mean),
            num(c.short_lo),
            num(c.short_hi),
            num(c.sym_lo),
            num(c.sym_hi),
        ]
    })
}

/// `realizations.csv` bytes.
pub fn realizations_csv(rows: &[RealizationRow]) -> Vec<u8> {
    csv_bytes("run,exposure_ms,system,mode,f_hz,a", rows, |r| {
        [
            r.run.to_string(),
            num(r.exposure_ms),
            r.system.name().to_string(),
            r.mode.to_string(),
            num(r.f_hz),
            num(r.a),
        ]
    })
}

/// `frf_band.csv` bytes.
pub fn frf_band_csv(rows: &[FrfBandRow]) -> Vec<u8> {
    csv_bytes(
        "system,exposure_ms,freq_hz,mean_abs,p05_abs,p95_abs",
        rows,
        |r| {
            [
                r.system.name().to_string(),
                num(r.exposure_ms),
                num(r.freq_hz),
                num(r.mean_abs),
                num(r.p05_abs),
                num(r.p95_abs),
            ]
        },
    )
}

/// The human table printed at the end of a study:
/// `system | exposure_ms | mode | runs | mu_a | sigma_a | u_mu_a | a interval | mu_f | sigma_f |
/// e2pr [| chi_mu | chi_sigma]`, the interval being the shortest `coverage` one (JCGM 101
/// 7.7.2; empty when the runs are too few).
pub fn table(rows: &[SummaryRow], unit: &str, coverage: f64) -> String {
    let with_chi = rows.iter().any(|r| r.chi_mu.is_some());
    let pct = format!("{}", coverage * 100.0);
    let mut s = String::new();
    let _ = write!(
        s,
        "{:<18} | {:>11} | {:>4} | {:>5} | {:>10} | {:>9} | {:>8} | {:>19} | {:>8} | {:>8} | {:>6}",
        "system",
        "exposure_ms",
        "mode",
        "runs",
        "mu_a",
        "sigma_a",
        "u_mu_a",
        format!("a {pct} % interval"),
        "mu_f",
        "sigma_f",
        "e2pr"
    );
    if with_chi {
        let _ = write!(s, " | {:>7} | {:>9}", "chi_mu", "chi_sigma");
    }
    s.push('\n');
    let width = s.len() - 1;
    s.push_str(&"-".repeat(width));
    s.push('\n');
    for r in rows {
        let (u, interval) = match &r.a_coverage {
            Some(c) => (
                format!("{:.4}", c.u_mean),
                format!("{:.4} .. {:.4}", c.short_lo, c.short_hi),
            ),
            None => (String::new(), String::new()),
        };
        // a statistic without runs (or of one run: sigma) is an empty cell, as in the files
        let num = |v: f64| {
            if v.is_finite() {
                format!("{v:.4}")
            } else {
                String::new()
            }
        };
        let _ = write!(
            s,
            "{:<18} | {:>11} | {:>4} | {:>5} | {:>10} | {:>9} | {:>8} | {:>19} | {:>8} | {:>8} | {:>6.3}",
            r.system.name(),
            r.exposure_ms,
            r.mode,
            r.runs,
            num(r.mu_a),
            num(r.sigma_a),
            u,
            interval,
            num(r.mu_f_hz),
            num(r.sigma_f_hz),
            r.e2pr
        );
        if with_chi {
            let f = |v: Option<f64>| v.map(|v| format!("{v:.4}")).unwrap_or_default();
            let _ = write!(s, " | {:>7} | {:>9}", f(r.chi_mu), f(r.chi_sigma));
        }
        s.push('\n');
    }
    if rows.iter().any(|r| r.runs == 0) {
        s.push_str(
            "(runs 0: every run of that row failed or none was in this shard; its statistics \
             are empty)\n",
        );
    }
    let _ = writeln!(
        s,
        "(amplitudes in {unit}; frequencies in Hz; u_mu_a: standard uncertainty of mu_a from \
         the runs, JCGM 101 7.6; interval: shortest {pct} % coverage interval of one run's \
         amplitude, JCGM 101 7.7.2; coverage.csv has both intervals of every quantity)"
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(system: System, chi: Option<f64>) -> SummaryRow {
        SummaryRow {
            system,
            exposure_ms: 40.0,
            mode: 1,
            runs: 10,
            mu_f_hz: 2.0,
            sigma_f_hz: 0.1,
            mu_a: 0.5,
            sigma_a: 0.05,
            e2pr: 0.08,
            chi_mu: chi,
            chi_sigma: chi,
            a_coverage: None,
            f_coverage: None,
        }
    }

    #[test]
    fn summary_csv_has_the_contract_header_and_exact_numbers() {
        let rows = [
            row(System::Transducer, None),
            row(System::Vision, Some(0.9)),
        ];
        let text = String::from_utf8(summary_csv(&rows, false)).unwrap();
        let mut lines = text.lines();
        assert_eq!(
            lines.next(),
            Some(
                "system,exposure_ms,mode,runs,mu_f_hz,sigma_f_hz,mu_a,sigma_a,e2pr,\
                 u_mu_a,a_lo95,a_hi95,u_mu_f,f_lo95,f_hi95"
            )
        );
        assert_eq!(
            lines.next(),
            Some("transducer,40,1,10,2,0.1,0.5,0.05,0.08,,,,,,")
        );
        let mut with_cov = rows.clone();
        with_cov[1].a_coverage =
            Some(vibcam_common::uncertainty::coverage_summary(&[1.0, 2.0, 3.0, 4.0], 0.5).unwrap());
        let text = String::from_utf8(summary_csv(&with_cov, true)).unwrap();
        assert!(text
            .lines()
            .next()
            .unwrap()
            .ends_with(",chi_mu,chi_sigma,u_mu_a,a_lo95,a_hi95,u_mu_f,f_lo95,f_hi95"));
        assert!(text.lines().nth(1).unwrap().ends_with(",,,,,,,,"));
        // 4 values, p = 0.5: q = 2, shortest [y1, y3] (first on ties), u_mean = s / 2
        let u = (5.0f64 / 3.0).sqrt() / 2.0;
        assert!(
            text.lines()
                .nth(2)
                .unwrap()
                .ends_with(&format!(",0.9,0.9,{u},1,3,,,")),
            "{text}"
        );
    }

    #[test]
    fn other_csv_headers_follow_the_contract() {
        let r = String::from_utf8(realizations_csv(&[])).unwrap();
        assert_eq!(r, "run,exposure_ms,system,mode,f_hz,a\n");
        let f = String::from_utf8(frf_band_csv(&[])).unwrap();
        assert_eq!(f, "system,exposure_ms,freq_hz,mean_abs,p05_abs,p95_abs\n");
    }

    #[test]
    fn table_lists_every_row() {
        let t = table(
            &[row(System::Transducer, None), row(System::Vision, None)],
            "mm/kN",
            0.95,
        );
        assert_eq!(t.lines().count(), 5);
        assert!(t.contains("a 95 % interval"), "{t}");
        assert!(t.contains("vision") && t.contains("mm/kN"));
    }
}

/// Lost frames of one run at one exposure (a row of `lost_frames.csv`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LostFrames {
    /// Run index.
    pub run: u64,
    /// Exposure time, ms.
    pub exposure_ms: f64,
    /// Frames without a centroid (filled by interpolation).
    pub lost: u64,
    /// Frames in the record.
    pub frames: u64,
    /// More than 5 % lost: the run is left out at this exposure.
    pub failed: bool,
}

/// `lost_frames.csv` bytes: `run,exposure_ms,lost_frames,frames,failed`.
pub fn lost_frames_csv(lost: &[LostFrames]) -> Vec<u8> {
    let mut s = String::from("run,exposure_ms,lost_frames,frames,failed\n");
    for l in lost {
        s.push_str(&format!(
            "{},{},{},{},{}\n",
            l.run, l.exposure_ms, l.lost, l.frames, l.failed
        ));
    }
    s.into_bytes()
}

/// One row of `adaptive.csv`: a quantity the adaptive procedure watches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdaptiveRow<'a> {
    /// Measurement system.
    pub system: System,
    /// Exposure, ms.
    pub exposure_ms: f64,
    /// Mode, 1-based.
    pub mode: usize,
    /// `a` or `f_hz`.
    pub quantity: &'static str,
    /// The procedure's state at the stop point (`None`: not assessable).
    pub stability: Option<&'a Stability>,
}

/// `adaptive.csv` bytes: per watched quantity the procedure's state at the stop point;
/// `(batches, runs)` are the study's, written for a quantity that is not assessable.
pub fn adaptive_csv(rows: &[AdaptiveRow<'_>], (batches, runs): (usize, usize)) -> Vec<u8> {
    let mut s = String::from(
        "system,exposure_ms,mode,quantity,batches,runs,estimate,std_uncertainty,delta,\
         twice_s_estimate,twice_s_u,twice_s_lo,twice_s_hi,stable\n",
    );
    for r in rows {
        let _ = write!(
            s,
            "{},{},{},{},",
            r.system.name(),
            r.exposure_ms,
            r.mode,
            r.quantity
        );
        match r.stability {
            Some(st) => {
                let t = &st.twice_std;
                let _ = writeln!(
                    s,
                    "{},{},{},{},{},{},{},{},{},{}",
                    st.batches,
                    st.runs,
                    st.estimate,
                    st.std_uncertainty,
                    st.delta,
                    t.estimate,
                    t.std_uncertainty,
                    t.lo,
                    t.hi,
                    st.is_stable()
                );
            }
            None => {
                let _ = writeln!(s, "{batches},{runs},,,,,,,,not assessable");
            }
        }
    }
    s.into_bytes()
}
