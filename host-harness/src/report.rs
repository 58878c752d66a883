//! Study outputs as rows, CSV bytes and a printed table. Writers here are pure (results in,
//! bytes out); putting the bytes on disk is the caller's separate step, so they are testable
//! without the disk. Plots live in [`crate::plots`].

use std::fmt::Write as _;

/// Which measurement system a row describes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum System {
    /// The contact transducer path (load cell + laser, or accelerometers).
    Transducer,
    /// The camera path (image formation, centroid, H1).
    Vision,
}

impl System {
    /// Name used in CSV files (`transducer` / `vision`).
    pub fn name(self) -> &'static str {
        match self {
            System::Transducer => "transducer",
            System::Vision => "vision",
        }
    }

    /// Parses a CSV name.
    pub fn parse(s: &str) -> Option<System> {
        match s {
            "transducer" => Some(System::Transducer),
            "vision" => Some(System::Vision),
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

/// Formats a float for CSV: shortest representation that round-trips (Rust's `Display`), so
/// files are exact and identical for identical numbers. An undefined value (a standard deviation
/// of one run, a mean of none) is an empty cell, never `NaN`.
fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        String::new()
    }
}

/// `summary.csv` bytes. `with_chi` adds the `chi_mu,chi_sigma` columns (cantilever).
pub fn summary_csv(rows: &[SummaryRow], with_chi: bool) -> Vec<u8> {
    let mut s = String::from("system,exposure_ms,mode,runs,mu_f_hz,sigma_f_hz,mu_a,sigma_a,e2pr");
    if with_chi {
        s.push_str(",chi_mu,chi_sigma");
    }
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
        if with_chi {
            let opt = |v: Option<f64>| v.map(num).unwrap_or_default();
            let _ = write!(s, ",{},{}", opt(r.chi_mu), opt(r.chi_sigma));
        }
        s.push('\n');
    }
    s.into_bytes()
}

/// `realizations.csv` bytes.
pub fn realizations_csv(rows: &[RealizationRow]) -> Vec<u8> {
    let mut s = String::from("run,exposure_ms,system,mode,f_hz,a\n");
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{}",
            r.run,
            num(r.exposure_ms),
            r.system.name(),
            r.mode,
            num(r.f_hz),
            num(r.a)
        );
    }
    s.into_bytes()
}

/// `frf_band.csv` bytes.
pub fn frf_band_csv(rows: &[FrfBandRow]) -> Vec<u8> {
    let mut s = String::from("system,exposure_ms,freq_hz,mean_abs,p05_abs,p95_abs\n");
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{}",
            r.system.name(),
            num(r.exposure_ms),
            num(r.freq_hz),
            num(r.mean_abs),
            num(r.p05_abs),
            num(r.p95_abs)
        );
    }
    s.into_bytes()
}

/// The human table printed at the end of a study:
/// `system | exposure_ms | mode | runs | mu_a | sigma_a | mu_f | sigma_f | e2pr [| chi_mu | chi_sigma]`.
pub fn table(rows: &[SummaryRow], unit: &str) -> String {
    let with_chi = rows.iter().any(|r| r.chi_mu.is_some());
    let mut s = String::new();
    let _ = write!(
        s,
        "{:<10} | {:>11} | {:>4} | {:>5} | {:>10} | {:>9} | {:>8} | {:>8} | {:>6}",
        "system", "exposure_ms", "mode", "runs", "mu_a", "sigma_a", "mu_f", "sigma_f", "e2pr"
    );
    if with_chi {
        let _ = write!(s, " | {:>7} | {:>9}", "chi_mu", "chi_sigma");
    }
    s.push('\n');
    let width = s.len() - 1;
    s.push_str(&"-".repeat(width));
    s.push('\n');
    for r in rows {
        let _ = write!(
            s,
            "{:<10} | {:>11} | {:>4} | {:>5} | {:>10.4} | {:>9.4} | {:>8.4} | {:>8.4} | {:>6.3}",
            r.system.name(),
            r.exposure_ms,
            r.mode,
            r.runs,
            r.mu_a,
            r.sigma_a,
            r.mu_f_hz,
            r.sigma_f_hz,
            r.e2pr
        );
        if with_chi {
            let f = |v: Option<f64>| v.map(|v| format!("{v:.4}")).unwrap_or_default();
            let _ = write!(s, " | {:>7} | {:>9}", f(r.chi_mu), f(r.chi_sigma));
        }
        s.push('\n');
    }
    let _ = writeln!(s, "(amplitudes in {unit}; frequencies in Hz)");
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
            Some("system,exposure_ms,mode,runs,mu_f_hz,sigma_f_hz,mu_a,sigma_a,e2pr")
        );
        assert_eq!(lines.next(), Some("transducer,40,1,10,2,0.1,0.5,0.05,0.08"));
        let text = String::from_utf8(summary_csv(&rows, true)).unwrap();
        assert!(text.lines().next().unwrap().ends_with(",chi_mu,chi_sigma"));
        assert!(text.lines().nth(1).unwrap().ends_with(",,"));
        assert!(text.lines().nth(2).unwrap().ends_with(",0.9,0.9"));
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
        );
        assert_eq!(t.lines().count(), 5);
        assert!(t.contains("vision") && t.contains("mm/kN"));
    }
}
