//! The adaptive Monte Carlo procedure of JCGM 101 7.9 on a study (method.md §3.3): runs come in
//! batches of `M` (batch `b` is runs `b M .. (b + 1) M`); after each batch from the second on,
//! every reported quantity (per system, exposure and mode: the frequency and the amplitude; or
//! the one chosen with `--adaptive-on`) is checked with [`vibcam_common::uncertainty::AdaptiveQuantity`]
//! and the study stops at the first batch count `h` where all are stable. The batch values of a
//! quantity are its mean, standard deviation and shortest coverage interval over the batch's
//! runs (failed vision runs left out, as in the summary).
//!
//! The stop point is a function of the records alone, so a study computed in one process and
//! the same batches computed as shards (`--shard K/N` deals whole batches) and merged stop at
//! the same `h` and give identical outputs.

use super::aggregate::{picks, SYSTEMS};
use super::{RunRecord, StudyConfig};
use crate::imaging::exposure::ExposureCorrection;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use vibcam_common::uncertainty::{
    coverage_summary, AdaptiveQuantity, BatchResult, IntervalKind, Stability,
};
use vibcam_readers::bad_input;
use vibcam_report::export::study::{AdaptiveRow, System};

/// The adaptive procedure's settings (`[adaptive]` of `config.toml`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdaptiveConfig {
    /// Significant decimal digits wanted in the standard uncertainty (`n_dig`, 7.9.2).
    pub digits: u32,
    /// Runs per batch (`M`).
    pub batch: u64,
    /// Only this quantity decides (`SYSTEM:MODE:a` or `SYSTEM:MODE:f`, every exposure);
    /// every reported quantity when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub on: Option<String>,
}

/// One quantity the criterion watches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuantityKey {
    /// Measurement system.
    pub system: System,
    /// Exposure, ms.
    pub exposure_ms: f64,
    /// Exposure index in the configuration.
    pub exposure: usize,
    /// Mode, 0-based.
    pub mode: usize,
    /// `true`: the amplitude; `false`: the frequency.
    pub amplitude: bool,
}

impl QuantityKey {
    /// `system exposure_ms ms mode M a|f_hz`.
    pub fn label(&self) -> String {
        format!(
            "{} {} ms mode {} {}",
            self.system.name(),
            self.exposure_ms,
            self.mode + 1,
            if self.amplitude { "a" } else { "f_hz" }
        )
    }
}

/// The state of one quantity after the batches used.
#[derive(Debug, Clone, PartialEq)]
pub struct QuantityState {
    /// Which quantity.
    pub key: QuantityKey,
    /// The procedure's state; `None` when a batch had too few values for an interval or the
    /// standard uncertainty is zero (the quantity cannot be assessed and does not decide).
    pub status: Option<Stability>,
}

/// Where the procedure stands on a set of records.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Batches used (`h`).
    pub batches: usize,
    /// Runs used (`h M`): the outputs are computed from these.
    pub runs: usize,
    /// Whether every assessed quantity is stable at `h`.
    pub stable: bool,
    /// More batches expected to be needed (0 when stable).
    pub more_batches: usize,
    /// Per quantity.
    pub quantities: Vec<QuantityState>,
}

impl AdaptiveConfig {
    /// Checks the settings against the study's run cap and coverage probability.
    pub fn validate(&self, runs: u64, coverage: f64) -> anyhow::Result<()> {
        if self.digits == 0 {
            return Err(bad_input("adaptive.digits: must be at least 1"));
        }
        let need = vibcam_common::uncertainty::min_values(coverage).unwrap_or(2) as u64;
        if self.batch < need {
            return Err(bad_input(format!(
                "adaptive.batch: {} runs cannot give a {coverage} coverage interval per batch; \
                 at least {need} are needed (JCGM 101 7.7.2)",
                self.batch
            )));
        }
        if runs < 2 * self.batch {
            return Err(bad_input(format!(
                "runs: the adaptive procedure needs at least two batches of {} runs, but runs \
                 (the cap) is {runs}",
                self.batch
            )));
        }
        if let Some(on) = &self.on {
            parse_on(on)?;
        }
        Ok(())
    }
}

/// Parses `SYSTEM:MODE:a|f` into (system, 0-based mode, amplitude?).
pub fn parse_on(s: &str) -> anyhow::Result<(System, usize, bool)> {
    let err = || {
        bad_input(format!(
            "$adaptive_on: `{s}` is not SYSTEM:MODE:QUANTITY (e.g. vision:2:a; systems \
             transducer, vision, vision_compensated; quantities a, f)"
        ))
    };
    let parts: Vec<&str> = s.split(':').collect();
    let [system, mode, q] = parts[..] else {
        return Err(err());
    };
    let system = System::parse(system).ok_or_else(err)?;
    let mode: usize = mode.parse().ok().filter(|m| *m >= 1).ok_or_else(err)?;
    let amplitude = match q {
        "a" => true,
        "f" | "f_hz" => false,
        _ => return Err(err()),
    };
    Ok((system, mode - 1, amplitude))
}

/// The quantities the criterion watches: every system, exposure, mode and quantity (the
/// transducer, which does not depend on the exposure, once), or the `on` selection.
fn watched(cfg: &StudyConfig, modes: usize, on: Option<&str>) -> anyhow::Result<Vec<QuantityKey>> {
    let sel = on.map(parse_on).transpose()?;
    if let Some((_, m, _)) = sel {
        if m >= modes {
            return Err(bad_input(format!(
                "$adaptive_on: mode {} does not exist (the study reports {modes})",
                m + 1
            )));
        }
    }
    let mut keys = Vec::new();
    for (exposure, &exposure_ms) in cfg.exposures_ms.iter().enumerate() {
        for system in SYSTEMS {
            if system == System::Transducer && exposure > 0 && sel.is_none() {
                continue;
            }
            for mode in 0..modes {
                for amplitude in [false, true] {
                    let key = QuantityKey {
                        system,
                        exposure_ms,
                        exposure,
                        mode,
                        amplitude,
                    };
                    if sel.is_none_or(|(s, m, a)| s == system && m == mode && a == amplitude) {
                        keys.push(key);
                    }
                }
            }
        }
    }
    Ok(keys)
}

/// The batch values of one quantity over `batch` (records of one batch).
fn batch_result(
    batch: &[RunRecord],
    key: &QuantityKey,
    correction: &ExposureCorrection,
    coverage: f64,
) -> Option<BatchResult> {
    let p = picks(
        batch,
        key.system,
        key.exposure,
        key.exposure_ms,
        key.mode,
        correction,
    );
    let v: Vec<f64> = p
        .iter()
        .map(|(_, p)| if key.amplitude { p.a } else { p.f_hz })
        .collect();
    let s = coverage_summary(&v, coverage).ok()?;
    Some(BatchResult::from_summary(&s, IntervalKind::Shortest))
}

/// Where the procedure stops on `records` (sorted by run, runs `0 .. n` without gaps): the
/// first `h >= 2` whole batches at which every assessable watched quantity is stable, or all
/// whole batches when none is.
pub fn outcome(
    cfg: &StudyConfig,
    a: &AdaptiveConfig,
    modes: usize,
    correction: &ExposureCorrection,
    records: &[RunRecord],
) -> anyhow::Result<Outcome> {
    let keys = watched(cfg, modes, a.on.as_deref())?;
    let m = a.batch as usize;
    let whole = records.len() / m;
    if whole < 2 {
        return Err(bad_input(format!(
            "the adaptive procedure needs two whole batches of {m} runs; {} runs are there",
            records.len()
        )));
    }
    // each batch's values of each quantity computed once, the histories grown batch by batch
    // (a quantity a batch cannot give an interval for is dropped: not assessable)
    let mut histories: Vec<Option<AdaptiveQuantity>> = keys
        .iter()
        .map(|_| AdaptiveQuantity::new(a.digits).ok())
        .collect();
    let mut last = None;
    for h in 1..=whole {
        let batch = &records[(h - 1) * m..h * m];
        for (key, q) in keys.iter().zip(histories.iter_mut()) {
            match (
                batch_result(batch, key, correction, cfg.coverage),
                q.as_mut(),
            ) {
                (Some(r), Some(hist)) => hist.push(r),
                _ => *q = None,
            }
        }
        if h < 2 {
            continue;
        }
        let quantities: Vec<QuantityState> = keys
            .iter()
            .zip(&histories)
            .map(|(key, q)| QuantityState {
                key: *key,
                status: q.as_ref().and_then(|q| q.status()),
            })
            .collect();
        let assessed: Vec<&Stability> = quantities
            .iter()
            .filter_map(|q| q.status.as_ref())
            .collect();
        let stable = !assessed.is_empty() && assessed.iter().all(|s| s.is_stable());
        let more = assessed
            .iter()
            .map(|s| s.more_batches_needed())
            .max()
            .unwrap_or(1);
        let o = Outcome {
            batches: h,
            runs: h * m,
            stable,
            more_batches: if stable { 0 } else { more },
            quantities,
        };
        if stable {
            return Ok(o);
        }
        last = Some(o);
    }
    last.ok_or_else(|| bad_input("no whole batch"))
}

/// `adaptive.csv` bytes ([`vibcam_report::export::study::adaptive_csv`]) of `o`.
pub fn adaptive_csv(o: &Outcome) -> Vec<u8> {
    let rows: Vec<AdaptiveRow<'_>> = o
        .quantities
        .iter()
        .map(|q| AdaptiveRow {
            system: q.key.system,
            exposure_ms: q.key.exposure_ms,
            mode: q.key.mode + 1,
            quantity: if q.key.amplitude { "a" } else { "f_hz" },
            stability: q.status.as_ref(),
        })
        .collect();
    vibcam_report::export::study::adaptive_csv(&rows, (o.batches, o.runs))
}

/// The lines printed after an adaptive study: the stop point, then per quantity the achieved
/// `max 2 s_z` against `delta`.
pub fn report(o: &Outcome, a: &AdaptiveConfig) -> String {
    let mut s = String::new();
    if o.stable {
        let _ = writeln!(
            s,
            "adaptive (JCGM 101 7.9, {} significant digit(s), batches of {}): stable after {} \
             batches = {} runs",
            a.digits, a.batch, o.batches, o.runs
        );
    } else {
        let _ = writeln!(
            s,
            "adaptive (JCGM 101 7.9, {} significant digit(s), batches of {}): NOT stable after \
             {} batches = {} runs; about {} more batches needed (raise runs, the cap, to at \
             least {})",
            a.digits,
            a.batch,
            o.batches,
            o.runs,
            o.more_batches,
            (o.batches + o.more_batches) as u64 * a.batch
        );
    }
    for q in &o.quantities {
        match &q.status {
            Some(st) => {
                let _ = writeln!(
                    s,
                    "  {:<44} u {:<10.4e} delta {:<9.2e} max 2s {:<9.2e} {}",
                    q.key.label(),
                    st.std_uncertainty,
                    st.delta,
                    st.twice_std.max(),
                    if st.is_stable() { "ok" } else { "not yet" }
                );
            }
            None => {
                let _ = writeln!(s, "  {:<44} not assessable", q.key.label());
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adaptive_on_names_a_system_a_mode_and_a_quantity() {
        assert_eq!(parse_on("vision:2:a").unwrap(), (System::Vision, 1, true));
        assert_eq!(
            parse_on("vision_compensated:1:f").unwrap(),
            (System::VisionCompensated, 0, false)
        );
        for bad in [
            "vision:0:a",
            "vision:2",
            "camera:1:a",
            "vision:1:x",
            "vision:1:a:b",
        ] {
            let e = parse_on(bad).unwrap_err().to_string();
            assert!(e.contains("$adaptive_on"), "{bad}: {e}");
        }
    }
}
