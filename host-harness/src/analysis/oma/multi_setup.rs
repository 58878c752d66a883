//! `modal` over several setups (docs/method.md §3.12, "Several setups"): each setup's records
//! analysed alone, merged by PoSER ([`vibcam_identify::oma::setups`]), or SSI's, FDD's,
//! EFDD's and pLSCF's modes from every setup's records together by PreGER
//! ([`vibcam_identify::oma::preger`], [`vibcam_identify::oma::preger_spectral`]) and the
//! other methods' by PoSER; one result whose targets are the global points (the references
//! first, then each setup's others) and the rows of `setups.csv` (each setup's part in each
//! mode PoSER merged); the figures are the first setup's (PreGER's stabilisation diagram and
//! singular values).

use super::input::Records;
use super::{analyze, Method, OmaResult, OmaSettings};
use crate::export::oma::OmaSetupRow;
use std::fmt::Write as _;
use vibcam_identify::oma::preger::{self, Record};
use vibcam_identify::oma::preger_spectral;
use vibcam_identify::oma::setups::{layout, poser, Setup};

/// How several setups are merged (`$merge`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Merge {
    /// Every method's modes by PoSER.
    Poser,
    /// SSI's, FDD's, EFDD's and pLSCF's by PreGER, the free decays' by PoSER.
    Preger,
}

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
    /// The first setup's: PreGER's block rows, with `$merge preger`.
    pub preger_block_rows: Option<usize>,
}

/// What several setups merged give: the global records (one channel per global point), the
/// merged result, the report's lines on the setups and `setups.csv`'s rows.
#[derive(Debug, Clone)]
pub struct Merged {
    /// The global points' records (each point's channel from the setup it comes from).
    pub records: Records,
    /// The merged modes (with the first setup's spectra, or PreGER's poles).
    pub result: OmaResult,
    /// The report's lines on the setups: how they were merged, what each alone found, where
    /// each global target comes from.
    pub text: String,
    /// Each setup's part in each mode PoSER merged.
    pub rows: Vec<OmaSetupRow>,
}

/// Analyses every setup and merges them as `merge` says (no file written).
pub fn compute(setups: &[SetupRecords], merge: Merge) -> anyhow::Result<Merged> {
    let results: Vec<OmaResult> = setups
        .iter()
        .map(|s| analyze(&s.records.channels, &s.settings))
        .collect::<anyhow::Result<_>>()?;
    // with PreGER, PoSER merges the other methods' modes only
    let for_poser: Vec<OmaResult> = match merge {
        Merge::Poser => results.clone(),
        Merge::Preger => results
            .iter()
            .map(|r| {
                let mut r = r.clone();
                r.modes.retain(|m| !together_by_preger(m.method));
                r
            })
            .collect(),
    };
    let parts: Vec<Setup<'_>> = setups
        .iter()
        .zip(&for_poser)
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
    result.notes = merged.notes;
    result.rejected.clear();
    for (i, r) in results.iter().enumerate() {
        let setup = |w: &String| format!("setup {}: {w}", i + 1);
        result.rejected.extend(r.rejected.iter().map(setup));
        result.notes.extend(r.notes.iter().map(setup));
    }
    if merge == Merge::Preger {
        together(setups, &mut result)?;
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
    Ok(Merged {
        text: setups_text(setups, merge, &results, &points),
        records,
        result,
        rows,
    })
}

/// Whether `$merge preger` identifies the method's modes on every setup's records together
/// (SSI by PreGER, FDD, EFDD and pLSCF by the spectral PreGER); the others (the free decays')
/// are merged by PoSER.
fn together_by_preger(m: Method) -> bool {
    matches!(m, Method::Ssi | Method::Fdd | Method::Efdd | Method::Plscf)
}

/// SSI's, FDD's, EFDD's and pLSCF's modes of every setup's records together (PreGER, with
/// setup 1's settings and PreGER's block rows; the spectral PreGER) in `result`, with the SSI
/// poles and clusters and the global spectra; their notes and rejected peaks and clusters
/// added.
fn together(setups: &[SetupRecords], result: &mut OmaResult) -> anyhow::Result<()> {
    let records: Vec<Record<'_>> = setups
        .iter()
        .map(|s| Record {
            channels: &s.records.channels,
            references: &s.references,
        })
        .collect();
    let (mut notes, mut rejected) = (Vec::new(), Vec::new());
    let mut s = setups[0].settings.clone();
    s.ssi.block_rows = setups[0].preger_block_rows.unwrap_or(s.ssi.block_rows);
    if s.ssi.block_rows != setups[0].settings.ssi.block_rows {
        notes.push(format!(
            "PreGER: {} block rows (SSI's {} raised so that the references' rows are {} times \
             the highest order; or $ssi_block_rows)",
            s.ssi.block_rows,
            setups[0].settings.ssi.block_rows,
            preger::REFERENCE_ROWS_OVER_ORDER
        ));
    }
    let found = preger::identify(&records, &s, &mut notes, &mut rejected)?;
    let spectral =
        preger_spectral::identify(&records, &s, &found.modes, &mut notes, &mut rejected)?;
    result.notes.extend(notes);
    result.rejected.extend(rejected);
    result.modes.retain(|m| !together_by_preger(m.method));
    result.modes.extend(found.modes);
    result.modes.extend(spectral.modes);
    result.csd = spectral.csd;
    result.svd = spectral.svd;
    result.peaks = spectral.peaks.iter().map(|p| p.line).collect();
    result.quantity = spectral.quantity;
    result.plscf_references = spectral.plscf_references;
    result
        .modes
        .sort_by(|a, b| a.method.cmp(&b.method).then(a.f_hz.total_cmp(&b.f_hz)));
    result.poles = found.poles;
    result.clusters = found.clusters;
    Ok(())
}

/// The report's lines on the setups: how they were merged, each file's targets, samples and
/// references, what each alone found, and where each global target comes from.
fn setups_text(
    setups: &[SetupRecords],
    merge: Merge,
    results: &[OmaResult],
    points: &[(usize, usize)],
) -> String {
    let poser = "each analysed alone; modes of setup 1 matched in every other by method, \
                 frequency and the shape at the references; shapes scaled onto setup 1's at the \
                 references";
    let mut o = match merge {
        Merge::Poser => format!(
            "{} setups merged by PoSER ({poser}); the figures are setup 1's\n",
            setups.len()
        ),
        Merge::Preger => format!(
            "{} setups: SSI's modes by PreGER (one model of every setup's records: each setup's \
             observability matrix mapped onto setup 1's at the references; the stabilisation \
             diagram is this model's); FDD's, EFDD's and pLSCF's by the spectral PreGER (one \
             global cross-spectral matrix: each setup's spectra at its other points carried \
             onto the references' mean spectrum by its transmissibility to them; the singular \
             values plotted are this matrix's); the free decays' merged by PoSER ({poser}); \
             the other figures are setup 1's\n",
            setups.len()
        ),
    };
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
