//! `modal` over several setups (docs/method.md §3.12, "Several setups"): each setup's records
//! analysed alone, merged by PoSER ([`vibcam_identify::oma::setups`]), written as one output
//! whose targets are the global points (the references first, then each setup's others) plus
//! `setups.csv` (each setup's part in each mode); the figures are the first setup's.

use super::input::Records;
use super::run::Output;
use super::{analyze, OmaResult, OmaSettings};
use crate::analysis::run::Outcome;
use crate::export::oma::{setups_csv, OmaSetupRow};
use std::fmt::Write as _;
use vibcam_identify::oma::setups::{layout, poser, Setup};

/// One setup of a `modal` job: its records, settings, file (for the report) and reference
/// channels (0-based, in the common order).
#[derive(Debug, Clone)]
pub struct SetupRecords {
    /// The records read.
    pub records: Records,
    /// Its analysis settings.
    pub settings: OmaSettings,
    /// The file, as the user named it.
    pub file: String,
    /// Its channels that are the references.
    pub references: Vec<usize>,
}

/// Analyses every setup, merges them and writes the outputs (`o`'s preamble opens the report).
pub fn run(setups: &[SetupRecords], o: &Output<'_>) -> anyhow::Result<Outcome> {
    let results: Vec<OmaResult> = setups
        .iter()
        .map(|s| analyze(&s.records.channels, &s.settings))
        .collect::<anyhow::Result<_>>()?;
    let parts: Vec<Setup<'_>> = setups
        .iter()
        .zip(&results)
        .map(|(s, r)| Setup {
            result: r,
            references: &s.references,
            channels: s.records.channels.len(),
        })
        .collect();
    let merged = poser(&parts);
    let points = layout(&parts);
    let first = &setups[0];
    let records = Records {
        fs_hz: first.records.fs_hz,
        unit: first.records.unit.clone(),
        targets: (1..=points.len()).map(|g| (g, None)).collect(),
        channels: points
            .iter()
            .map(|&(s, c)| setups[s].records.channels[c].clone())
            .collect(),
        filled: vec![0; points.len()],
        left_out: Vec::new(),
    };
    let mut result = results[0].clone();
    result.modes = merged.modes;
    result.rejected = results
        .iter()
        .enumerate()
        .flat_map(|(i, r)| {
            r.rejected
                .iter()
                .map(move |w| format!("setup {}: {w}", i + 1))
        })
        .collect();
    result.notes = merged.notes;
    for (i, r) in results.iter().enumerate() {
        result
            .notes
            .extend(r.notes.iter().map(|n| format!("setup {}: {n}", i + 1)));
    }
    let rows: Vec<OmaSetupRow> = merged
        .parts
        .iter()
        .map(|p| OmaSetupRow {
            method: p.method.name(),
            mode: p.mode,
            setup: p.setup + 1,
            f_hz: p.f_hz,
            damping: p.damping,
            scale: p.scale,
            reference_mac: p.reference_mac,
        })
        .collect();
    let mut extra = o.extra.clone();
    extra.push(("setups.csv".to_string(), setups_csv(&rows)));
    let preamble = format!("{}{}", o.preamble, setups_text(setups, &results, &points));
    let o = Output {
        extra,
        preamble,
        ..o.clone()
    };
    super::run::write(&records, &first.settings, &result, &o)
}

/// The report's lines on the setups: each file's targets, samples and references, what each
/// alone found, and where each global target comes from.
fn setups_text(
    setups: &[SetupRecords],
    results: &[OmaResult],
    points: &[(usize, usize)],
) -> String {
    let mut o = format!(
        "{} setups merged by PoSER (each analysed alone; modes of setup 1 matched in every other \
         by method, frequency and the shape at the references; shapes scaled onto setup 1's at \
         the references); the figures are setup 1's\n",
        setups.len()
    );
    for (i, (s, r)) in setups.iter().zip(results).enumerate() {
        let n = s.records.channels.first().map_or(0, Vec::len);
        let refs: Vec<String> = s
            .references
            .iter()
            .map(|&c| s.records.targets[c].0.to_string())
            .collect();
        let _ = writeln!(
            o,
            "  setup {}: {} ({} targets, {n} samples at {} Hz; references: targets {}): {} \
             modes alone",
            i + 1,
            s.file,
            s.records.channels.len(),
            s.records.fs_hz,
            refs.join(", "),
            r.modes.len()
        );
        for (t, why) in &s.records.left_out {
            let _ = writeln!(o, "    target {t} left out: {why}");
        }
    }
    let map: Vec<String> = points
        .iter()
        .enumerate()
        .map(|(g, &(s, c))| {
            let t = setups[s].records.targets[c].0;
            let role = if g < setups[0].references.len() {
                " (reference)"
            } else {
                ""
            };
            format!("{} = setup {} target {t}{role}", g + 1, s + 1)
        })
        .collect();
    let _ = writeln!(o, "  global targets: {}", map.join("; "));
    o
}
