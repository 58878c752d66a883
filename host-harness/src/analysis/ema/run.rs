//! `ema` as one call: a checked request (records read and aligned, settings resolved) ->
//! the analysis -> its outputs in a staged directory (complete or absent): `frf.csv`,
//! `modes.csv`, `shapes.csv`, `frf.uff`, `frf.png`/`.svg` and `frf_phase.png`/`.svg` (the
//! FRFs' magnitude and phase with the fit),
//! `stabilisation.png`/`.svg` and `report.txt`.

use super::input::{Aligned, Series};
use super::{analyse, EmaResult, EmaSettings, Excitation};
use crate::analysis::modal::FrfForm;
use crate::analysis::oma::uncertainty::Interval;
use crate::analysis::request::Outcome;
use crate::export::ema::{self as export, EmaModeRow};
use crate::export::oma::{shapes_csv, OmaShapeRow};
use crate::export::uff::{AxisCharacteristics, Dataset58, Dof, Quantity};
use crate::outdir::Staged;
use num_complex::Complex64;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What `ema` is asked: the records (read, at one rate and start), the settings, the outputs.
#[derive(Debug, Clone)]
pub struct EmaRequest {
    /// The responses as read (names, unit, rate, notes; their samples are in `aligned`).
    pub response: Series,
    /// The force as read.
    pub force: Series,
    /// Both at one rate and one start.
    pub aligned: Aligned,
    /// A roving-hammer test's records, the first (`aligned`) too (empty: one test).
    pub roving: Vec<RovingRead>,
    /// The forces after the first (shakers at once): each as read, and its samples aligned
    /// as `aligned.force`.
    pub more_forces: Vec<(Series, Vec<f64>)>,
    /// The analysis settings.
    pub settings: EmaSettings,
    /// The input files: the response, the excitation, then the poles and the geometry files
    /// when given.
    pub inputs: Vec<PathBuf>,
    /// Output directory.
    pub out: PathBuf,
    /// Also print `report.pdf`.
    pub pdf: bool,
    /// Replace an earlier `ema` output there.
    pub force_out: bool,
    /// Draw the figures.
    pub plots: bool,
    /// The lines the page draws the shapes with (on the responses).
    pub wire: crate::export::wire::Wire,
}

/// One record of a roving-hammer test, read and aligned.
#[derive(Debug, Clone)]
pub struct RovingRead {
    /// The point hit.
    pub point: usize,
    /// The record's name (its responses' file).
    pub name: String,
    /// What reading it said (the first record's are the request's).
    pub notes: Vec<String>,
    /// Its force and responses at the first record's rate.
    pub aligned: Aligned,
}

/// The FRF matrix's second index in `frf.csv`: a roving hammer's hit points (`hit_point`), or
/// several forces' numbers (`force`); none for one force.
pub fn frf_inputs(req: &EmaRequest) -> (&'static str, Vec<usize>) {
    if !req.roving.is_empty() {
        ("hit_point", req.roving.iter().map(|r| r.point).collect())
    } else if !req.more_forces.is_empty() {
        ("force", (1..=req.more_forces.len() + 1).collect())
    } else {
        ("", Vec::new())
    }
}

/// The number of the point a shape's component `i` stands at: the hit point's when the shapes
/// are over the hit points, else the response's (1-based).
pub fn shape_at(req: &EmaRequest, r: &EmaResult, i: usize) -> usize {
    if r.layout.over_inputs() {
        req.roving.get(i).map_or(i + 1, |x| x.point)
    } else {
        i + 1
    }
}

/// FRF `i`'s name: the response's, with several hit points "name @ hit P", with several
/// forces "name / force".
fn frf_label(req: &EmaRequest, r: &EmaResult, i: usize) -> String {
    let outputs = r.layout.outputs.max(1);
    let (name, j) = (&req.response.names[i % outputs], i / outputs);
    if let Some(x) = req.roving.get(j).filter(|_| r.layout.inputs > 1) {
        format!("{name} @ hit {}", x.point)
    } else if !req.more_forces.is_empty() {
        format!("{name} / {}", force_name(req, j))
    } else {
        name.clone()
    }
}

/// Force `j`'s channel name (0: the first).
fn force_name(req: &EmaRequest, j: usize) -> &str {
    match j {
        0 => &req.force.names[0],
        _ => req
            .more_forces
            .get(j - 1)
            .map_or("", |m| m.0.names[0].as_str()),
    }
}

/// The analysis of `req` and its report, nothing written.
pub fn compute(req: &EmaRequest) -> anyhow::Result<(EmaResult, String)> {
    let a = &req.aligned;
    let r = if !req.more_forces.is_empty() {
        let forces: Vec<Vec<f64>> = std::iter::once(a.force.clone())
            .chain(req.more_forces.iter().map(|m| m.1.clone()))
            .collect();
        super::mimo::analyse(&forces, &a.responses, a.fs_hz, &req.settings)?
    } else if req.roving.is_empty() {
        analyse(
            &a.force,
            &a.responses,
            a.fs_hz,
            &req.force.names[0],
            &req.settings,
        )?
    } else {
        let records: Vec<super::roving::Record> = req
            .roving
            .iter()
            .map(|r| super::roving::Record {
                force: &r.aligned.force,
                responses: &r.aligned.responses,
                point: r.point,
                name: &r.name,
            })
            .collect();
        super::roving::analyse(&records, a.fs_hz, &req.settings)?
    };
    let report = report(req, &r);
    Ok((r, report))
}

/// Runs the analysis and writes its outputs; the report is returned.
pub fn run(req: &EmaRequest) -> anyhow::Result<Outcome> {
    let (r, report) = compute(req)?;
    let inputs: Vec<&Path> = req.inputs.iter().map(PathBuf::as_path).collect();
    let out = Staged::new(&req.out, req.force_out, "ema", &inputs)?;
    out.write(
        "frf.csv",
        export::frf_matrix_csv(&r.freq_hz, &r.frfs.h1, &r.frfs.coherence, frf_inputs(req)),
    )?;
    let system = if req.response.camera { "vision" } else { "daq" };
    let cells = |i: Option<Interval>| i.map(|i| (i.u, i.lo, i.hi));
    let rows: Vec<EmaModeRow> = r
        .modes
        .iter()
        .map(|m| EmaModeRow {
            system,
            mode: m.mode,
            band_hz: m.band_hz,
            f_hz: m.pole.f_hz,
            damping: m.pole.damping,
            intervals: [cells(m.f_interval), cells(m.damping_interval)],
        })
        .collect();
    out.write("modes.csv", export::modes_csv(&rows))?;
    let result = &r;
    let shapes: Vec<OmaShapeRow> = r
        .modes
        .iter()
        .flat_map(|m| {
            m.shape.iter().enumerate().map(move |(o, c)| OmaShapeRow {
                mode: m.mode,
                target: shape_at(req, result, o),
                xy_px: None,
                value: *c,
                method: "lscf",
                abs_u: m
                    .shape_abs_u
                    .as_ref()
                    .and_then(|u| u.get(o).copied())
                    .filter(|v| v.is_finite()),
            })
        })
        .collect();
    out.write("shapes.csv", shapes_csv(&shapes))?;
    out.write("frf.uff", uff(req, &r)?)?;
    let figures = if req.plots {
        figures(req, &r)?
    } else {
        Vec::new()
    };
    for f in &figures {
        f.write_staged(&out)?;
    }
    let report = crate::analysis::write_report(&out, &report, req.pdf, |report| {
        page(req, &r, report, crate::plots::page_figures(&figures))
    })?;
    out.commit()?;
    Ok(Outcome {
        report,
        result: Ok(()),
    })
}

/// `report.html` of `ema`: the modes with their intervals, the MAC of their shapes, each shape
/// animated along the responses (in their order: a camera's targets have no positions here),
/// the figures (caption, SVG), the report `text`.
pub fn page(
    req: &EmaRequest,
    r: &EmaResult,
    text: &str,
    figures: Vec<(String, String)>,
) -> crate::export::html::Report {
    use crate::export::html::{mac_and_animations, modes_table, ModeCells, Report};
    let iv = |i: Option<Interval>| i.map(|i| (i.lo, i.hi));
    let cells: Vec<ModeCells> = r
        .modes
        .iter()
        .map(|m| ModeCells {
            mode: m.mode,
            method: None,
            f_hz: (m.pole.f_hz, iv(m.f_interval)),
            damping: (Some(m.pole.damping), iv(m.damping_interval)),
        })
        .collect();
    let (head, rows) = modes_table(&cells, false);
    let modes: Vec<(String, &[num_complex::Complex64])> = r
        .modes
        .iter()
        .map(|m| {
            (
                format!("{} {:.2} Hz", m.mode, m.pole.f_hz),
                m.shape.as_slice(),
            )
        })
        .collect();
    let (mac, shapes) = mac_and_animations(&modes, "mode ");
    let picker = picker(r);
    Report {
        title: format!(
            "ema: {} over {}",
            req.inputs[0].display(),
            req.force.names[0]
        ),
        direction: (0.0, -1.0),
        figures,
        modes: (!rows.is_empty()).then_some((head, rows)),
        mac,
        shapes,
        wire: req.wire.clone(),
        text: text.to_string(),
        picker,
        banner: crate::analysis::oma::run::no_mode_banner(r.modes.is_empty(), &rejected(r)),
        ..Report::default()
    }
}

/// The notes that say a band holds no mode, then the clusters not taken for modes, the
/// fullest first, each with its size and reason.
fn rejected(r: &EmaResult) -> Vec<String> {
    let mut clusters: Vec<_> = r.rejected.iter().collect();
    clusters.sort_by_key(|c| std::cmp::Reverse(c.cluster.poles));
    let clusters = clusters.into_iter().map(|c| {
        format!(
            "cluster at {:.4} Hz ({} stable poles): {}",
            c.cluster.f_hz, c.cluster.poles, c.reason
        )
    });
    r.notes
        .iter()
        .filter(|n| n.contains("no mode"))
        .cloned()
        .chain(clusters)
        .collect()
}

/// The page's pole picker: every pole of the diagram, drawn where the fit found it, its
/// structure's frequency and damping what `poles.csv` saves (none without poles).
fn picker(r: &EmaResult) -> Option<crate::export::picker::Picker> {
    crate::analysis::oma::run::picker(
        (&r.poles, &r.clusters),
        r.band_hz,
        r.modes.iter().map(|m| m.fitted.f_hz).collect(),
        |p| r.structure_pole(p),
        "Saved as <code>poles.csv</code>, the file <code>ema</code> takes with \
         <code>$poles</code> to give exactly these modes, with their shapes, intervals and \
         report.",
    )
}

/// `s` within a universal file's text field of `max` characters: line breaks as spaces, cut
/// to `max` (the report says so: [`uff_cut_notes`]).
fn uff_field(s: &str, max: usize) -> String {
    s.chars()
        .map(|c| if c == '\n' || c == '\r' { ' ' } else { c })
        .take(max)
        .collect()
}

/// The report's lines for the units and names `frf.uff` cuts to its fields' widths.
fn uff_cut_notes(req: &EmaRequest) -> Vec<String> {
    let mut notes = Vec::new();
    for u in [&req.response.unit, &req.force.unit].into_iter().flatten() {
        if u.chars().count() > 20 {
            notes.push(format!(
                "note: the unit `{u}` is cut to its first 20 characters in frf.uff (the \
                 format's field width)"
            ));
        }
    }
    for name in &req.response.names {
        let line = format!("H1 {name} / {}", req.force.names[0]);
        if line.chars().count() > 80 {
            notes.push(format!(
                "note: `{line}` is cut to 80 characters in frf.uff's ID line (the format's \
                 line width)"
            ));
        }
    }
    notes
}

/// The FRFs as universal-file datasets 58 (function type 4): response `o` node `o`, the force
/// node 0 (a roving hammer's: the point hit); the numerator's quantity from the FRF's form, units as the files state them.
fn uff(req: &EmaRequest, r: &EmaResult) -> anyhow::Result<Vec<u8>> {
    let (quantity, label) = match req.settings.form {
        FrfForm::Receptance => (Quantity::Displacement, "Displacement"),
        FrfForm::Mobility => (Quantity::Velocity, "Velocity"),
        FrfForm::Accelerance => (Quantity::Acceleration, "Acceleration"),
    };
    let df = r.freq_hz.get(1).copied().unwrap_or(1.0);
    let sets: Vec<Dataset58<'_>> = r
        .frfs
        .h1
        .iter()
        .enumerate()
        .map(|(o, h)| Dataset58 {
            id_lines: [
                uff_field(
                    &if req.more_forces.is_empty() {
                        format!("H1 {} / {}", frf_label(req, r, o), req.force.names[0])
                    } else {
                        format!("H1 {}", frf_label(req, r, o))
                    },
                    80,
                ),
                "vibcam ema".into(),
                String::new(),
                String::new(),
                String::new(),
            ],
            function_id: o as u32 + 1,
            response: Dof {
                node: (o % r.layout.outputs.max(1)) as u32 + 1,
                direction: 0,
            },
            // one force: node 0; a roving hammer: the point hit; several forces: their number
            reference: Dof {
                node: frf_inputs(req)
                    .1
                    .get(o / r.layout.outputs.max(1))
                    .map_or(0, |&x| x as u32),
                direction: 0,
            },
            f0_hz: 0.0,
            df_hz: df,
            numerator: AxisCharacteristics {
                quantity,
                label: label.into(),
                units: uff_field(req.response.unit.as_deref().unwrap_or_default(), 20),
            },
            denominator: AxisCharacteristics {
                quantity: Quantity::ExcitationForce,
                label: "Force".into(),
                units: uff_field(req.force.unit.as_deref().unwrap_or_default(), 20),
            },
            values: h,
        })
        .collect();
    Ok(crate::export::uff::write_file(&sets)?)
}

/// The figures: the first four FRFs' |H1| with the fit, and the stabilisation diagram.
pub fn figures(req: &EmaRequest, r: &EmaResult) -> anyhow::Result<Vec<crate::plots::Figure>> {
    let (lo, hi) = r.band_hz;
    let k: Vec<usize> = (0..r.freq_hz.len())
        .filter(|&k| r.freq_hz[k] >= lo && r.freq_hz[k] <= hi)
        .collect();
    let f: Vec<f64> = k.iter().map(|&i| r.freq_hz[i]).collect();
    let fitted: Vec<crate::analysis::modal::Pole> = r.modes.iter().map(|m| m.fitted).collect();
    // the first four responses' H1 and fit, each complex value drawn as `value` makes it
    let draw = |stem: &str, title: &str, y_label: &str, value: fn(Complex64) -> f64| {
        let mut owned: Vec<(String, Vec<f64>)> = Vec::new();
        for (o, h) in r.frfs.h1.iter().enumerate().take(4) {
            owned.push((
                frf_label(req, r, o),
                k.iter().map(|&i| value(h[i])).collect(),
            ));
            if let Some(c) = r.constants.get(o) {
                owned.push((
                    format!("{}{}", frf_label(req, r, o), crate::plots::FIT),
                    f.iter()
                        .map(|&fr| value(c.evaluate(&fitted, req.settings.form, fr)))
                        .collect(),
                ));
            }
        }
        let curves: Vec<(&str, &[f64], &[f64])> = owned
            .iter()
            .map(|(l, v)| (l.as_str(), f.as_slice(), v.as_slice()))
            .collect();
        crate::plots::lines_figure(stem, title, y_label, &curves, crate::plots::Lines::FrfFit)
    };
    let magnitude = draw(
        "frf",
        "H1 and the LSCF/LSFD fit",
        &format!("|H1|, dB (re 1 {})", frf_unit(req)),
        |c| db(c.norm()),
    )?;
    let phase = draw(
        "frf_phase",
        "H1's phase and the fit's",
        "phase of H1, degrees (wrapped to -180..180)",
        |c| c.arg().to_degrees(),
    )?;
    let poles = crate::analysis::oma::run::pole_kinds(&r.poles, &r.clusters);
    let modes: Vec<f64> = r.modes.iter().map(|m| m.fitted.f_hz).collect();
    let stabilisation = crate::plots::stabilisation_figure(
        crate::export::html::STABILISATION,
        "LSCF stabilisation diagram",
        &poles,
        &modes,
        hi,
    )?;
    Ok(vec![magnitude, phase, stabilisation])
}

/// The FRF's unit as the files state theirs: `g/N`, `m/N`; a side not stated is named so.
fn frf_unit(req: &EmaRequest) -> String {
    let side = |u: &Option<String>, what: &str| {
        u.as_deref()
            .map(str::trim)
            .filter(|u| !u.is_empty())
            .map_or(format!("unit of the {what}"), str::to_string)
    };
    format!(
        "{} per {}",
        side(&req.response.unit, "response"),
        side(&req.force.unit, "force")
    )
}

/// `20 log10 v` (a floor at -400 dB for 0).
fn db(v: f64) -> f64 {
    20.0 * v.max(1e-20).log10()
}

/// An interval as `lo..hi`, or `-`.
fn range(i: Option<Interval>, digits: usize) -> String {
    i.map_or("-".into(), |i| {
        format!("{:.*}..{:.*}", digits, i.lo, digits, i.hi)
    })
}

/// The human report: the inputs, the excitation, the fit and its modes, the responses.
pub fn report(req: &EmaRequest, r: &EmaResult) -> String {
    let mut s = String::from("ema: experimental modal analysis (LSCF poles, LSFD residues)\n");
    inputs_text(&mut s, req);
    let df = r.freq_hz.get(1).copied().unwrap_or(0.0);
    match (&req.settings.excitation, &r.hits) {
        (Excitation::Impact { .. }, Some(_)) if !r.roving.is_empty() => {
            for (x, h) in req.roving.iter().zip(&r.roving) {
                let _ = writeln!(s, "hit point {} ({}):", x.point, x.name);
                hits_text(&mut s, &x.aligned, r, h, df);
            }
        }
        (Excitation::Impact { .. }, Some(h)) => hits_text(&mut s, &req.aligned, r, h, df),
        (Excitation::Continuous { nperseg }, _) => {
            let _ = writeln!(
                s,
                "continuous excitation: Welch H1, Hann segments of {nperseg} samples, half \
                 overlapping ({} segments in {} groups), lines every {df:.5} Hz",
                r.unit_sizes.iter().sum::<usize>(),
                r.unit_sizes.len()
            );
        }
        _ => {}
    }
    modes_text(&mut s, req, r);
    responses_text(&mut s, req, r);
    for n in &r.notes {
        let _ = writeln!(s, "note: {n}");
    }
    s
}

/// The report's lines on the files read: the responses, the force, the notes of their reading
/// and alignment.
fn inputs_text(s: &mut String, req: &EmaRequest) {
    let a = &req.aligned;
    let unit = |u: &Option<String>| u.clone().unwrap_or_else(|| "unit not stated".into());
    let _ = writeln!(
        s,
        "responses: {} ({} channel{}, {}, {} Hz{})",
        req.inputs[0].display(),
        req.response.names.len(),
        if req.response.names.len() == 1 {
            ""
        } else {
            "s"
        },
        unit(&req.response.unit),
        super::input::rate_text(req.response.fs_hz),
        if req.response.camera {
            ", a camera's"
        } else {
            ""
        }
    );
    let _ = writeln!(
        s,
        "force: {} channel `{}` ({}, {} Hz)",
        req.inputs[1].display(),
        req.force.names[0],
        unit(&req.force.unit),
        super::input::rate_text(req.force.fs_hz)
    );
    for n in req
        .response
        .notes
        .iter()
        .chain(&req.force.notes)
        .chain(&a.notes)
        .chain(&uff_cut_notes(req))
    {
        let _ = writeln!(s, "  {n}");
    }
    several_inputs_text(s, req);
}

/// The report's lines on a test's forces after the first, or a roving hammer's records (each
/// with what its reading said that the first's did not).
fn several_inputs_text(s: &mut String, req: &EmaRequest) {
    let a = &req.aligned;
    let unit = |u: &Option<String>| u.clone().unwrap_or_else(|| "unit not stated".into());
    for (i, (f, _)) in req.more_forces.iter().enumerate() {
        let _ = writeln!(
            s,
            "force {}: {} channel `{}` ({}, {} Hz)",
            i + 2,
            req.inputs[1].display(),
            f.names[0],
            unit(&f.unit),
            super::input::rate_text(f.fs_hz)
        );
    }
    if !req.more_forces.is_empty() {
        let _ = writeln!(
            s,
            "{} forces at once: the FRF matrix by the multiple-input H1 (Gxf Gff^-1 per line)",
            req.more_forces.len() + 1
        );
    }
    if !req.roving.is_empty() {
        let _ = writeln!(
            s,
            "roving hammer: {} records, one per hit point (the first above), the same responses \
             in each",
            req.roving.len()
        );
        // each record's reading notes but those the first's (above) said already
        let said: Vec<&String> = req
            .response
            .notes
            .iter()
            .chain(&req.force.notes)
            .chain(&a.notes)
            .collect();
        for x in &req.roving {
            let _ = writeln!(s, "  hit point {}: {}", x.point, x.name);
            for n in x.notes.iter().chain(&x.aligned.notes) {
                if !said.contains(&n) {
                    let _ = writeln!(s, "    {n}");
                }
            }
        }
    }
}

/// The report's lines on the hits: each hit, the spikes set aside, the blocks, the exponential
/// window.
fn hits_text(s: &mut String, a: &Aligned, r: &EmaResult, h: &super::impact::Hits, df: f64) {
    let used = h.used().count();
    let _ = writeln!(
        s,
        "impact: {} hit{} found, {used} used and averaged (H1; H2 and coherence beside \
         it); force baseline {:.4}, noise sd {:.4}",
        h.hits.len(),
        if h.hits.len() == 1 { "" } else { "s" },
        h.baseline,
        h.noise_sd
    );
    if !h.spikes.is_empty() {
        let at: Vec<String> = h
            .spikes
            .iter()
            .take(10)
            .map(|&k| format!("{:.4} s", k as f64 / a.fs_hz))
            .collect();
        let _ = writeln!(
            s,
            "  warning: {} single-sample spike(s) of the force set aside, not taken for \
             hits (a glitch of the DAQ or a cable; no hammer's pulse is one sample \
             wide): at {}{}",
            h.spikes.len(),
            at.join(", "),
            if h.spikes.len() > 10 { ", ..." } else { "" }
        );
    }
    for (i, hit) in h.hits.iter().enumerate() {
        let p = hit.pulse();
        let w = (p.end - p.start) as f64 / a.fs_hz * 1e3;
        let _ = writeln!(
            s,
            "  hit {} at {:.4} s: peak {:.4}, pulse {w:.3} ms (force window {:.3} ms){}",
            i + 1,
            p.start as f64 / a.fs_hz,
            p.peak,
            2.0 * w,
            hit.left_out
                .as_ref()
                .map_or(String::new(), |why| format!(": LEFT OUT, {why}"))
        );
    }
    let _ = writeln!(
        s,
        "blocks: {} samples ({:.4} s, {:.4} s before each pulse), lines every {df:.5} Hz",
        h.block,
        h.block as f64 / a.fs_hz,
        h.pre as f64 / a.fs_hz
    );
    match r.exp {
        Some(w) => {
            // its damping at the first mode, or (no mode) at the band's middle
            let f = r
                .modes
                .first()
                .map_or(0.5 * (r.band_hz.0 + r.band_hz.1), |m| m.pole.f_hz);
            let _ = writeln!(
                s,
                "exponential window: tau {:.5} s (ends at {:.2} %), on force and \
                 responses; it adds 1/(tau w) of damping ({:.2e} at {} Hz), removed \
                 from every mode's damping below",
                w.tau_s,
                100.0 * w.at(h.block as f64 / a.fs_hz),
                w.added_damping(f),
                hz_text(f)
            );
        }
        None => {
            let _ = writeln!(s, "exponential window: none");
        }
    }
}

/// A frequency at four significant digits (a band chosen from the data is no rounder).
fn hz_text(v: f64) -> String {
    if v <= 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let scale = 10f64.powi(3 - v.log10().floor() as i32);
    format!("{}", (v * scale).round() / scale)
}

/// The LSCF model of the fit: one common denominator (orders 2 to the highest) with one hit
/// point or one response, else the poly-reference model with the fewer of them as references.
fn lscf_text(
    rule: crate::analysis::ema::lscf::LscfRule,
    layout: crate::analysis::ema::Layout,
) -> String {
    let refs = layout.references();
    let orders = crate::analysis::ema::lscf::orders(rule, refs);
    match refs {
        0 | 1 => format!("LSCF orders {}-{}", orders.start(), orders.end()),
        _ => format!(
            "poly-reference LSCF ({refs} references: the {}, {refs} x {refs} matrix \
             coefficients), orders {}-{}",
            if layout.over_inputs() {
                "responses"
            } else {
                "forces"
            },
            orders.start(),
            orders.end()
        ),
    }
}

/// The report's lines on the fit and its modes, and the clusters that are not modes.
fn modes_text(s: &mut String, req: &EmaRequest, r: &EmaResult) {
    let (lo, hi) = r.band_hz;
    let stable = r.poles.iter().filter(|p| p.stable).count();
    let _ = writeln!(
        s,
        "fit: {}-{} Hz ({}), {}: {} poles, {stable} stable; {} mode{}",
        hz_text(lo),
        hz_text(hi),
        match req.settings.form {
            FrfForm::Receptance => "receptance: residuals (iw)^-2 and 1",
            FrfForm::Mobility => "mobility: residuals (iw)^-1 and iw",
            FrfForm::Accelerance => "accelerance: residuals 1 and (iw)^2",
        },
        lscf_text(req.settings.lscf, r.layout),
        r.poles.len(),
        r.modes.len(),
        if r.modes.len() == 1 { "" } else { "s" }
    );
    if !r.modes.is_empty() {
        let _ = writeln!(
            s,
            "\nmode  f_hz        95 % interval           damping    95 % interval       \
             poles  MPC   LSFD misfit"
        );
    }
    for m in &r.modes {
        let misfit = r.constants.iter().map(|c| c.misfit).fold(0.0f64, f64::max);
        let _ = writeln!(
            s,
            "{:<5} {:<11.5} {:<23} {:<10.5} {:<19} {:<6} {:<5.3} {:.3}",
            m.mode,
            m.pole.f_hz,
            range(m.f_interval, 5),
            m.pole.damping,
            range(m.damping_interval, 5),
            m.cluster.poles,
            m.cluster.mpc,
            misfit
        );
    }
    if !r.modes.is_empty() {
        let _ = writeln!(
            s,
            "(f and damping: the medians of each cluster's stable poles; intervals: jackknife \
             over the {}; LSFD misfit: the worst FRF's relative misfit over the band)",
            match (&r.hits, r.roving.is_empty()) {
                (Some(_), false) => "groups of every record's hits",
                (Some(_), true) => "hits",
                (None, _) => "segment groups",
            }
        );
    }
    let few = req.settings.cluster.min_poles;
    for rej in r.rejected.iter().filter(|c| c.cluster.poles >= few) {
        let _ = writeln!(
            s,
            "not a mode: {:.4} Hz ({} poles): {}",
            rej.cluster.f_hz, rej.cluster.poles, rej.reason
        );
    }
    let scattered = r.rejected.iter().filter(|c| c.cluster.poles < few).count();
    if scattered > 0 {
        let _ = writeln!(
            s,
            "not modes: {scattered} clusters of fewer than {few} stable poles (noise or \
             computational poles; the stabilisation diagram shows them)"
        );
    }
}

/// The report's lines on each response: its number and its mean coherence in the band (a
/// roving hammer's: per hit point too).
fn responses_text(s: &mut String, req: &EmaRequest, r: &EmaResult) {
    let (lo, hi) = r.band_hz;
    let coherence = |i: usize| {
        let coh: Vec<f64> = (0..r.freq_hz.len())
            .filter(|&k| r.freq_hz[k] >= lo && r.freq_hz[k] <= hi)
            .map(|k| r.frfs.coherence[i][k])
            .collect();
        coh.iter().sum::<f64>() / coh.len().max(1) as f64
    };
    if r.layout.inputs > 1 {
        return matrix_responses_text(s, req, r, &coherence);
    }
    let _ = writeln!(s, "\nresponses (the `target` of frf.csv and shapes.csv):");
    for (o, n) in req.response.names.iter().enumerate() {
        let _ = writeln!(
            s,
            "  {}: {n} (mean coherence in the band {:.3})",
            o + 1,
            coherence(o)
        );
    }
    if r.unit_sizes.len() == 1 {
        let _ = writeln!(
            s,
            "  (one hit: the coherence is 1 by construction and says nothing)"
        );
    }
}

/// [`responses_text`] of an FRF matrix: each response (its multiple coherence with several
/// forces), and the forces or a roving hammer's hit points (each FRF's coherence); `coherence`
/// gives FRF `i`'s mean coherence in the band.
fn matrix_responses_text(
    s: &mut String,
    req: &EmaRequest,
    r: &EmaResult,
    coherence: &dyn Fn(usize) -> f64,
) {
    if !req.more_forces.is_empty() {
        let _ = writeln!(
            s,
            "\nresponses (the `target` of frf.csv{}), each one's mean multiple coherence with \
             the forces in the band:",
            if r.layout.over_inputs() {
                ""
            } else {
                " and shapes.csv"
            }
        );
        for (o, n) in req.response.names.iter().enumerate() {
            let _ = writeln!(s, "  {}: {n} ({:.3})", o + 1, coherence(o));
        }
        let _ = writeln!(
            s,
            "forces (the `force` of frf.csv{}): {}",
            if r.layout.over_inputs() {
                ", the `target` of shapes.csv"
            } else {
                ""
            },
            (0..r.layout.inputs)
                .map(|j| format!("{}: {}", j + 1, force_name(req, j)))
                .collect::<Vec<_>>()
                .join(", ")
        );
        return;
    }
    let over = r.layout.over_inputs();
    let _ = writeln!(
        s,
        "\nresponses (the `target` of frf.csv{}):",
        if over { "" } else { " and shapes.csv" }
    );
    for (o, n) in req.response.names.iter().enumerate() {
        let _ = writeln!(s, "  {}: {n}", o + 1);
    }
    let _ = writeln!(
        s,
        "hit points (the `hit_point` of frf.csv{}), each FRF's mean coherence in the band:",
        if over {
            ", the `target` of shapes.csv"
        } else {
            ""
        }
    );
    for (j, x) in req.roving.iter().enumerate() {
        let each: Vec<String> = (0..r.layout.outputs)
            .map(|o| format!("{:.3}", coherence(j * r.layout.outputs + o)))
            .collect();
        let _ = writeln!(s, "  {}: {} ({})", x.point, x.name, each.join(", "));
    }
}
