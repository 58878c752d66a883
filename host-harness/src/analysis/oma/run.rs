//! `modal` (and `analyze` without an accelerometer): output-only analysis of displacement
//! records, its outputs written into a staged directory (complete or absent): `modes.csv`,
//! `shapes.csv`, `svd.csv`, `shapes.uff`, `svd.png`/`.svg`, `stabilisation.png`/`.svg` and
//! `report.txt`.

use super::input::Records;
use super::uncertainty::Interval;
use super::{analyze, Method, OmaResult, OmaSettings};
use crate::analysis::run::Outcome;
use crate::export::oma::{self as export, OmaModeRow, OmaShapeRow, OmaShapeSet};
use crate::outdir::Staged;
use crate::plots::PoleKind;
use num_complex::Complex64;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What to write where.
#[derive(Debug, Clone)]
pub struct Output<'a> {
    /// The output directory.
    pub out: &'a Path,
    /// Replace an earlier output of the same command.
    pub force: bool,
    /// Also print `report.pdf`.
    pub pdf: bool,
    /// The command writing it (`modal` or `analyze`).
    pub command: &'static str,
    /// The run's inputs (never inside a directory that is replaced).
    pub inputs: Vec<PathBuf>,
    /// Write the figures.
    pub plots: bool,
    /// The motion's image axis (`x` or `y`), for the UFF's direction.
    pub along_x: bool,
    /// Lines opening the report (the input, the tracking).
    pub preamble: String,
    /// Further files to write beside the results (`displacement.csv` of `analyze`).
    pub extra: Vec<(String, Vec<u8>)>,
    /// The first frame, for `report.html` (`analyze`; none from a displacement file).
    pub frame: Option<crate::export::html::FrameImage>,
    /// The camera's view (references, scale) and the frame rate, from frames.
    pub view: Option<(&'a crate::analysis::view::Viewed, f64)>,
    /// The frame scrubber, from frames.
    pub scrub: Option<crate::export::scrub::Scrubber>,
    /// The lines the shapes are drawn with (on the records' targets).
    pub wire: crate::export::wire::Wire,
    /// Each mode's magnified video (`analyze` from frames).
    pub magnify: Option<super::magnified::Magnify>,
}

/// Analyses `records` with `settings` and writes the outputs; the report is returned.
pub fn run(records: &Records, settings: &OmaSettings, o: &Output<'_>) -> anyhow::Result<Outcome> {
    let r = analyze(&records.channels, settings)?;
    write(records, settings, &r, o)
}

/// Writes the outputs of an analysis `r` of `records` (what [`run`] computed); the report is
/// returned.
pub fn write(
    records: &Records,
    settings: &OmaSettings,
    r: &OmaResult,
    o: &Output<'_>,
) -> anyhow::Result<Outcome> {
    let inputs: Vec<&Path> = o.inputs.iter().map(PathBuf::as_path).collect();
    let out = Staged::new(o.out, o.force, o.command, &inputs)?;
    out.write("modes.csv", export::modes_csv(&mode_rows(r)))?;
    out.write("shapes.csv", export::shapes_csv(&shape_rows(r, records)))?;
    out.write("svd.csv", export::svd_csv(&r.svd.freq_hz, &r.svd.s))?;
    for (name, bytes) in &o.extra {
        out.write(name, bytes)?;
    }
    let (camera, camera_figure) = match o.view {
        Some((v, fps)) => crate::analysis::view::write_camera_outputs(&out, v, fps, o.plots)?,
        None => (String::new(), None),
    };
    out.write(
        "shapes.uff",
        export::shapes_uff(&shape_sets(r, records, o.along_x))?,
    )?;
    let mut figures = if o.plots {
        figures(r, settings)?
    } else {
        Vec::new()
    };
    figures.extend(camera_figure);
    for f in &figures {
        f.write_staged(&out)?;
    }
    let (videos, magnified, _) = match &o.magnify {
        Some(m) => {
            let points: Vec<Option<(f64, f64)>> = records.targets.iter().map(|t| t.1).collect();
            super::magnified::write_videos(out.dir(), r, &points, m)
        }
        None => (Vec::new(), String::new(), Vec::new()),
    };
    let report = report(r, records, settings, &format!("{}{camera}", o.preamble));
    let report = format!("{report}{magnified}");
    let figures = crate::plots::page_figures(&figures);
    let report = crate::analysis::write_report(&out, &report, o.pdf, |report| {
        page(
            r,
            records,
            (o.command, o.along_x),
            (
                o.frame.clone(),
                o.view
                    .map(|v| crate::analysis::view::reference_markers(v.0))
                    .unwrap_or_default(),
                o.scrub.clone(),
            ),
            (figures, o.wire.clone()),
            report,
        )
        .with_videos(videos)
    })?;
    out.commit()?;
    Ok(Outcome {
        report,
        result: Ok(()),
    })
}

/// The singular values' figure (FDD's picks marked) and the SSI-cov stabilisation diagram.
pub fn figures(r: &OmaResult, settings: &OmaSettings) -> anyhow::Result<Vec<crate::plots::Figure>> {
    let mut figures = Vec::new();
    let picks: Vec<(f64, f64, String)> = r
        .modes
        .iter()
        .filter(|m| m.method == Method::Fdd)
        .map(|m| {
            let s1 = m.amplitude.unwrap_or(0.0);
            (m.f_hz, s1, format!("{:.3} Hz", m.f_hz))
        })
        .collect();
    // many channels: the matrix is the reference channels' (`oma::many`)
    let channels = r.modes.iter().map(|m| m.shape.len()).max().unwrap_or(0);
    let title = match r.csd.k < channels {
        true => format!(
            "singular values of the cross-spectral matrix of {} reference channels",
            r.csd.k
        ),
        false => "singular values of the cross-spectral matrix".to_string(),
    };
    figures.push(crate::plots::svd_figure(
        "svd",
        &title,
        &r.svd.freq_hz,
        &r.svd.s,
        &picks,
    )?);
    let poles = pole_kinds(&r.poles, &r.clusters);
    let ssi: Vec<f64> = r
        .modes
        .iter()
        .filter(|m| m.method == Method::Ssi)
        .map(|m| m.f_hz)
        .collect();
    figures.push(crate::plots::stabilisation_figure(
        crate::export::html::STABILISATION,
        &format!("{} stabilisation diagram", settings.ssi.kind.label()),
        &poles,
        &ssi,
        settings.fs_hz / 2.0,
    )?);
    Ok(figures)
}

/// `report.html`: the targets (on the first frame when there is one), the modes with their
/// intervals, the MAC of their shapes, each shape animated on `wire`, the figures (caption,
/// SVG), the report `text`. `command` names the page (`modal`, `analyze`); `along_x` the motion's axis.
pub fn page(
    r: &OmaResult,
    records: &Records,
    (command, along_x): (&str, bool),
    (frame, references, scrub): (
        Option<crate::export::html::FrameImage>,
        Vec<crate::export::html::ReferenceMarker>,
        Option<crate::export::scrub::Scrubber>,
    ),
    (figures, wire): (Vec<(String, String)>, crate::export::wire::Wire),
    text: &str,
) -> crate::export::html::Report {
    use crate::export::html::{mac_and_animations, Report};
    let markers = markers(records);
    let (head, rows) = modes_table(r);
    let modes: Vec<(String, &[Complex64])> = r
        .modes
        .iter()
        .map(|m| {
            let label = format!("{} {} {:.2} Hz", m.method.name(), m.mode, m.f_hz);
            (label, m.shape.as_slice())
        })
        .collect();
    let (mac, shapes) = mac_and_animations(&modes, "");
    // `modal` takes the poles picked back ($poles); the picker draws its diagram
    let ssi = r.modes.iter().filter(|m| m.method == Method::Ssi);
    let picker = match command {
        "modal" => picker(
            (&r.poles, &r.clusters),
            (0.0, r.svd.freq_hz.last().copied().unwrap_or(1.0)),
            ssi.map(|m| m.f_hz).collect(),
            |p| crate::analysis::modal::Pole {
                f_hz: p.f_hz,
                damping: p.damping,
            },
            "Saved as <code>poles.csv</code>, the file <code>modal</code> takes with \
             <code>$poles</code> to give exactly these SSI modes, each with the shape of its \
             pole.",
        ),
        _ => None,
    };
    Report {
        title: format!("{command}: output-only modal analysis"),
        frame,
        markers,
        references,
        direction: if along_x { (1.0, 0.0) } else { (0.0, -1.0) },
        figures,
        modes: (!rows.is_empty()).then_some((head, rows)),
        mac,
        shapes,
        wire,
        text: text.to_string(),
        scrub,
        picker,
        banner: no_mode_banner(r.modes.is_empty(), &r.rejected),
        provenance: None,
        videos: Vec::new(),
    }
}

/// The targets on the page: each one's position and lost samples (none when a target has no
/// position: the shapes are then drawn on a line of their own).
fn markers(records: &Records) -> Vec<crate::export::html::Marker> {
    use crate::export::html::Marker;
    let markers: Vec<Marker> = records
        .targets
        .iter()
        .zip(&records.filled)
        .filter_map(|((t, xy), lost)| {
            xy.map(|xy| Marker {
                target: *t,
                xy,
                window: None,
                lost: *lost,
            })
        })
        .collect();
    // without every target's position, the shapes are drawn on a line of their own
    if markers.len() == records.targets.len() {
        markers
    } else {
        Vec::new()
    }
}

/// The page's table of modes: method, frequency, damping and their 95 % intervals.
fn modes_table(r: &OmaResult) -> (Vec<String>, Vec<Vec<String>>) {
    let iv = |i: Option<Interval>| i.map(|i| (i.lo, i.hi));
    let cells: Vec<crate::export::html::ModeCells> = r
        .modes
        .iter()
        .map(|m| crate::export::html::ModeCells {
            mode: m.mode,
            method: Some(m.method.name()),
            f_hz: (m.f_hz, iv(m.uncertainty.f_hz)),
            damping: (m.damping, iv(m.uncertainty.damping)),
        })
        .collect();
    crate::export::html::modes_table(&cells, true)
}

/// Every pole of the stabilisation diagram and what it is: in a cluster reported or
/// rejected (the clusters hold their poles' frequencies and orders), stable, or neither.
pub fn pole_kinds(
    poles: &[super::ssi::Pole],
    clusters: &[(super::cluster::SsiMode, bool)],
) -> Vec<(f64, usize, PoleKind)> {
    poles
        .iter()
        .map(|p| {
            let home = clusters.iter().find(|(c, _)| {
                c.poles > 1 && c.members.iter().any(|&(f, o)| o == p.order && f == p.f_hz)
            });
            let kind = match home {
                Some((_, true)) => PoleKind::Mode,
                Some((_, false)) => PoleKind::Rejected,
                None if p.stable => PoleKind::Stable,
                None => PoleKind::Pole,
            };
            (p.f_hz, p.order, kind)
        })
        .collect()
}

/// The reasons a banner lists at the most; the rest are in the report.
pub const BANNER_REASONS: usize = 8;

/// The page's banner when an identification found no mode (`none`): the peaks and clusters
/// not taken with their reasons (`rejected`, the first [`BANNER_REASONS`]), or that none
/// stood out.
pub fn no_mode_banner(none: bool, rejected: &[String]) -> Option<(String, Vec<String>)> {
    if !none {
        return None;
    }
    let mut reasons: Vec<String> = rejected.iter().take(BANNER_REASONS).cloned().collect();
    if rejected.len() > BANNER_REASONS {
        reasons.push(format!(
            "and {} more in the report below",
            rejected.len() - BANNER_REASONS
        ));
    }
    if reasons.is_empty() {
        reasons.push(
            "no peak stood out and no cluster of stable poles formed: see the report's notes"
                .into(),
        );
    }
    Some((
        "No mode was found. What was seen and why it was not taken:".into(),
        reasons,
    ))
}

/// The page's pole picker ([`crate::export::picker`]) of a diagram's `poles` and `clusters`
/// over `f_range` Hz, the modes found at `modes_hz`; `structure` the pole `poles.csv` saves
/// for a pole of the diagram (an exponential window's damping removed); `rerun` how the file
/// is used. None without poles.
pub fn picker(
    (poles, clusters): (&[super::ssi::Pole], &[(super::cluster::SsiMode, bool)]),
    f_range: (f64, f64),
    modes_hz: Vec<f64>,
    structure: impl Fn(&super::ssi::Pole) -> crate::analysis::modal::Pole,
    rerun: &str,
) -> Option<crate::export::picker::Picker> {
    use crate::export::picker::{PickPole, Picker};
    let picks: Vec<PickPole> = poles
        .iter()
        .zip(pole_kinds(poles, clusters))
        .map(|(p, (_, order, kind))| {
            let s = structure(p);
            PickPole {
                at_hz: p.f_hz,
                order,
                kind,
                f_hz: s.f_hz,
                damping: s.damping,
                mpc: super::cluster::mpc(&p.shape),
            }
        })
        .collect();
    (!picks.is_empty()).then(|| Picker {
        poles: picks,
        f_range,
        modes_hz,
        rerun: rerun.to_string(),
    })
}

/// The rows of `modes.csv`.
fn mode_rows(r: &OmaResult) -> Vec<OmaModeRow> {
    let cells = |i: Option<Interval>| i.map(|i| (i.u, i.lo, i.hi));
    r.modes
        .iter()
        .map(|m| OmaModeRow {
            mode: m.mode,
            band_hz: m.band_hz,
            f_hz: m.f_hz,
            amplitude: m.amplitude,
            damping: m.damping,
            method: m.method.name(),
            intervals: [
                cells(m.uncertainty.f_hz),
                cells(m.uncertainty.damping),
                cells(m.uncertainty.amplitude),
            ],
        })
        .collect()
}

/// The rows of `shapes.csv`: per mode and method, each target kept.
fn shape_rows(r: &OmaResult, records: &Records) -> Vec<OmaShapeRow> {
    r.modes
        .iter()
        .flat_map(|m| {
            records
                .targets
                .iter()
                .zip(&m.shape)
                .enumerate()
                .map(|(j, ((t, xy), c))| OmaShapeRow {
                    mode: m.mode,
                    target: *t,
                    xy_px: *xy,
                    value: *c,
                    method: m.method.name(),
                    abs_u: m
                        .uncertainty
                        .shape_abs
                        .as_ref()
                        .and_then(|u| u.get(j).copied())
                        .filter(|v| v.is_finite()),
                })
        })
        .collect()
}

/// The datasets of `shapes.uff`: each target a node, the shape in the motion's direction (x
/// or y); load case 1 FDD, 2 EFDD, 3 SSI, 4 the free decays, 5 pLSCF.
fn shape_sets(r: &OmaResult, records: &Records, along_x: bool) -> Vec<OmaShapeSet> {
    let zero = Complex64::new(0.0, 0.0);
    r.modes
        .iter()
        .map(|m| OmaShapeSet {
            method: m.method.name(),
            load_case: match m.method {
                Method::Fdd => 1,
                Method::Efdd => 2,
                Method::Ssi => 3,
                Method::Decay => 4,
                Method::Plscf => 5,
            },
            mode: m.mode,
            f_hz: m.f_hz,
            damping: m.damping.unwrap_or(0.0),
            nodes: records
                .targets
                .iter()
                .zip(&m.shape)
                .map(|((t, _), &c)| {
                    let v = if along_x {
                        [c, zero, zero]
                    } else {
                        [zero, c, zero]
                    };
                    (*t as u32, v)
                })
                .collect(),
        })
        .collect()
}

/// The report: the records, the settings, the modes per method, the notes.
pub fn report(r: &OmaResult, records: &Records, s: &OmaSettings, preamble: &str) -> String {
    let mut o = String::from(preamble);
    records_text(&mut o, records, s);
    methods_text(&mut o, r, s);
    modes_text(&mut o, r, s);
    if !r.rejected.is_empty() {
        let _ = writeln!(o, "\nnot modes:");
        for why in &r.rejected {
            let _ = writeln!(o, "  {why}");
        }
    }
    for note in &r.notes {
        if note.starts_with("warning: ") {
            let _ = writeln!(o, "{note}");
        } else {
            let _ = writeln!(o, "note: {note}");
        }
    }
    o
}

/// The report's lines on the records: targets, samples, rate, unit, lost samples, targets left
/// out.
fn records_text(o: &mut String, records: &Records, s: &OmaSettings) {
    let n = records.channels.first().map_or(0, Vec::len);
    let _ = writeln!(
        o,
        "output-only modal analysis: {} targets, {n} samples at {} Hz ({:.1} s), values in {}",
        records.channels.len(),
        s.fs_hz,
        n as f64 / s.fs_hz,
        records.unit
    );
    for ((t, _), f) in records.targets.iter().zip(&records.filled) {
        if *f > 0 {
            let _ = writeln!(o, "  target {t}: {f} lost samples filled by interpolation");
        }
    }
    for (t, why) in &records.left_out {
        let _ = writeln!(o, "  target {t} left out: {why}");
    }
}

/// The report's line on EFDD: the bell, the model and the quantity it was fitted as.
fn efdd_text(o: &mut String, r: &OmaResult, s: &OmaSettings) {
    let q = r.quantity;
    let how = match q.rms_log {
        Some([d, v, a]) => format!(
            ", the quantity whose model fits the bells best (RMS residual of ln: displacement \
             {d:.3}, velocity {v:.3}, acceleration {a:.3}; another than the displacement when \
             {:.0} % lower)",
            100.0 * super::modes::QUANTITY_MARGIN
        ),
        None if q.given => " (as given by $efdd_quantity)".to_string(),
        None => format!(
            " (the default: no bell's half-power band spans {} lines or more to tell the \
             quantity by)",
            super::bell::RESOLVED_LINES
        ),
    };
    let _ = writeln!(
        o,
        "EFDD: the bell (lines whose first or second singular vector has the mode's shape, MAC \
         >= {}) fitted by one mode's spectrum of {} in this estimate (its Welch lag window \
         included){how}",
        s.efdd.mac_min,
        q.quantity.name()
    );
}

/// The report's lines on the methods and their settings: the cross-spectra, the peaks, EFDD,
/// SSI-cov.
fn methods_text(o: &mut String, r: &OmaResult, s: &OmaSettings) {
    let _ = writeln!(
        o,
        "cross-spectral matrix: {} segments of {} samples ({:?} window, overlap {}), line \
         spacing {:.5} Hz",
        r.csd.segments,
        s.csd.nperseg,
        s.csd.window,
        s.csd.noverlap,
        r.csd.df_hz()
    );
    if s.bands.is_empty() {
        let _ = writeln!(
            o,
            "peaks: local maxima of the first singular value from {:.3} to {:.3} Hz with {} dB \
             of prominence{}; a mode when its singular vector holds over a bell of {} lines \
             (MAC >= {}), it is no ripple on a stronger peak's bell, and it stands {} dB or \
             SSI-cov finds a mode in its half-power band (MAC >= {}); an SSI-cov mode no peak \
             took gives its bell",
            s.peaks.f_min_hz,
            s.peaks.f_max_hz,
            s.peaks.prominence_db,
            s.peaks
                .over_floor_db
                .map_or(String::new(), |d| format!(" and {d} dB over the median")),
            s.efdd.min_lines,
            s.efdd.mac_min,
            super::modes::STRONG_PEAK_DB,
            super::modes::AGREE_MAC
        );
    }
    efdd_text(o, r, s);
    let c = &s.cluster;
    let _ = writeln!(
        o,
        "{}: {} block rows, orders 2 to {}; stable: frequency within {} %, damping within \
         {} % (of {} below that), MAC >= {}; stable poles clustered (average linkage, distance \
         df/f + 1 - MAC up to {}, one pole per order); a mode from {} poles, median MPC >= {}, \
         MPD <= {} deg, and no fuller cluster of its shape nearby{}",
        s.ssi.kind.label(),
        s.ssi.block_rows,
        s.ssi.max_order,
        100.0 * s.ssi.df_max,
        100.0 * s.ssi.dz_max,
        super::ssi::DAMPING_FLOOR,
        s.ssi.mac_min,
        c.distance_max,
        c.min_poles,
        c.mpc_min,
        c.mpd_max_deg,
        match s.bands.is_empty() {
            true => format!(
                " (from {} poles when it is the only cluster within half a line of a peak of {} dB \
                 that no mode explains)",
                super::modes::LONE_MIN_POLES,
                super::modes::STRONG_PEAK_DB
            ),
            false => String::new(),
        }
    );
    plscf_text(o, r, s);
    decays_text(o, r, s);
}

/// The report's line on pLSCF, when it ran: orders, band, references, windows.
fn plscf_text(o: &mut String, r: &OmaResult, s: &OmaSettings) {
    let Some(rule) = s.plscf else {
        return;
    };
    let l = s.csd.nperseg / 2;
    let others: Vec<super::OmaMode> = r
        .modes
        .iter()
        .filter(|m| m.method != Method::Plscf)
        .cloned()
        .collect();
    let band = super::plscf::band(s, &others);
    let (rule, _) = super::plscf::fitted_rule(rule, &r.csd, band);
    let refs = &r.plscf_references;
    let orders = crate::analysis::ema::lscf::orders(rule, refs.len());
    let _ = writeln!(
        o,
        "pLSCF: poly-reference LSCF ({} x {} matrix coefficients, orders {} to {}, stable as \
         SSI's) over {:.3}-{:.3} Hz on the half-spectra of references {} (the cross-spectral \
         matrix's correlations at lags 0 to {} over the Welch lag window, times an exponential \
         window falling to {} %, its decay taken off the poles); its stable poles clustered as \
         SSI's",
        refs.len(),
        refs.len(),
        orders.start(),
        orders.end(),
        band.0,
        band.1,
        refs.iter()
            .map(|c| (c + 1).to_string())
            .collect::<Vec<_>>()
            .join(", "),
        l.saturating_sub(1),
        100.0 * super::plscf::EXP_WINDOW_END
    );
}

/// The report's line on the record's regime: a stationary response, or free decays (each with
/// its samples and amplitude) and how they are identified.
fn decays_text(o: &mut String, r: &OmaResult, s: &OmaSettings) {
    use crate::analysis::oma::decay;
    if r.decays.is_empty() {
        let _ = writeln!(
            o,
            "regime: a stationary response (no free decay: no rise of the motion 30 dB above its \
             quiet level followed by a fall of 20 dB)"
        );
        return;
    }
    let list: Vec<String> = r
        .decays
        .iter()
        .map(|d| {
            format!(
                "samples {}-{} ({:.2} s from {:.2} s, amplitude {:.3e})",
                d.start + 1,
                d.end,
                (d.end - d.start) as f64 / s.fs_hz,
                d.start as f64 / s.fs_hz,
                d.amplitude
            )
        })
        .collect();
    let _ = writeln!(
        o,
        "regime: {} free decay(s) after a pull, release or hit: {}; identified together in the \
         time domain (method decay: the decays' correlations over fixed times, {} block rows, \
         orders 2 to 40, stable and clustered as SSI-cov's, damping up to 30 %), each decay also \
         alone (its frequency and damping in the evidence), intervals from the jackknife over \
         the decays",
        r.decays.len(),
        list.join(", "),
        decay::block_rows(&r.decays)
    );
}

/// The report's table of modes and their 95 % intervals.
fn modes_text(o: &mut String, r: &OmaResult, s: &OmaSettings) {
    let _ = writeln!(
        o,
        "\nmethod  mode  f_hz        damping   amplitude   evidence"
    );
    for m in &r.modes {
        let _ = writeln!(
            o,
            "{:<7} {:>4}  {:<10.5} {:<9} {:<11} {}",
            m.method.name(),
            m.mode,
            m.f_hz,
            m.damping.map_or("-".to_string(), |z| format!("{:.4}", z)),
            m.amplitude.map_or("-".to_string(), |a| format!("{a:.4e}")),
            m.evidence
        );
    }
    let with: Vec<&super::OmaMode> = r
        .modes
        .iter()
        .filter(|m| m.uncertainty.f_hz.is_some() || m.uncertainty.damping.is_some())
        .collect();
    if !with.is_empty() {
        let _ = writeln!(
            o,
            "\n95 % intervals (statistical, from the record: the jackknife over {} groups of its \
             segments or time, SSI's leaving out half of them, the decay method's over its \
             decays; the imaging's own share is not in them):",
            s.groups
        );
        for m in with {
            let f = m.uncertainty.f_hz.map_or(String::new(), |i| {
                format!("f = {:.4} +- {:.4} Hz", m.f_hz, i.half_width())
            });
            let z = match (m.damping, m.uncertainty.damping) {
                (Some(z), Some(i)) => format!(", damping = {:.4} ({:.4} to {:.4})", z, i.lo, i.hi),
                _ => String::new(),
            };
            let _ = writeln!(o, "  {} mode {}: {f}{z}", m.method.name(), m.mode);
        }
    }
}
