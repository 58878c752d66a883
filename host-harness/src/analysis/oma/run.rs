//! `modal` (and `analyze` without an accelerometer): output-only analysis of displacement
//! records, its outputs written into a staged directory (complete or absent): `modes.csv`,
//! `shapes.csv`, `svd.csv`, `shapes.uff`, `svd.png`/`.svg`, `stabilisation.png`/`.svg` and
//! `report.txt`.

use super::input::Records;
use super::{analyze, Method, OmaResult, OmaSettings};
use crate::analysis::run::Outcome;
use crate::export::opt;
use crate::export::targets::{MODES_HEADER, SHAPES_HEADER};
use crate::export::uff::{write_dataset55, Shape55};
use crate::outdir::Staged;
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
    out.write("modes.csv", modes_csv(r))?;
    out.write("shapes.csv", shapes_csv(r, records))?;
    out.write("svd.csv", svd_csv(r))?;
    for (name, bytes) in &o.extra {
        out.write(name, bytes)?;
    }
    out.write("shapes.uff", shapes_uff(r, records, o.along_x)?)?;
    if o.plots {
        let picks: Vec<(f64, f64, String)> = r
            .modes
            .iter()
            .filter(|m| m.method == Method::Fdd)
            .map(|m| {
                let s1 = m.amplitude.unwrap_or(0.0);
                (m.f_hz, s1, format!("{:.3} Hz", m.f_hz))
            })
            .collect();
        crate::plots::write_svd_plot(
            &out.dir().join("svd"),
            "singular values of the cross-spectral matrix",
            &r.svd.freq_hz,
            &r.svd.s,
            &picks,
        )?;
        let poles: Vec<(f64, usize, bool)> = r
            .poles
            .iter()
            .map(|p| (p.f_hz, p.order, p.stable))
            .collect();
        let ssi: Vec<f64> = r
            .modes
            .iter()
            .filter(|m| m.method == Method::Ssi)
            .map(|m| m.f_hz)
            .collect();
        crate::plots::write_stabilisation_plot(
            &out.dir().join("stabilisation"),
            "SSI-cov stabilisation diagram",
            &poles,
            &ssi,
            settings.fs_hz / 2.0,
        )?;
    }
    let report = report(r, records, settings, &o.preamble);
    out.write("report.txt", &report)?;
    out.commit()?;
    Ok(Outcome {
        report,
        result: Ok(()),
    })
}

/// `modes.csv`: the multi-target columns, one row per mode and method, `system` `vision`,
/// `target` empty.
pub fn modes_csv(r: &OmaResult) -> Vec<u8> {
    let mut s = String::from(MODES_HEADER);
    for m in &r.modes {
        let (lo, hi) = m.band_hz.map_or((None, None), |b| (Some(b.0), Some(b.1)));
        let _ = writeln!(
            s,
            "vision,,{},{},{},{},{},{},,{}",
            m.mode,
            opt(lo),
            opt(hi),
            m.f_hz,
            opt(m.amplitude),
            opt(m.damping),
            m.method.name()
        );
    }
    s.into_bytes()
}

/// `shapes.csv`: one row per mode, method and target.
pub fn shapes_csv(r: &OmaResult, records: &Records) -> Vec<u8> {
    let mut s = String::from(SHAPES_HEADER);
    for m in &r.modes {
        for ((t, xy), c) in records.targets.iter().zip(&m.shape) {
            let (x, y) = xy.map_or((None, None), |p| (Some(p.0), Some(p.1)));
            let _ = writeln!(
                s,
                "{},{t},{},{},{},{},{},{}",
                m.mode,
                opt(x),
                opt(y),
                c.re,
                c.im,
                c.norm(),
                m.method.name()
            );
        }
    }
    s.into_bytes()
}

/// `svd.csv`: `freq_hz,s1,...,sK`.
pub fn svd_csv(r: &OmaResult) -> Vec<u8> {
    let k = r.svd.s.first().map_or(0, Vec::len);
    let mut s = String::from("freq_hz");
    for i in 1..=k {
        let _ = write!(s, ",s{i}");
    }
    s.push('\n');
    for (f, sv) in r.svd.freq_hz.iter().zip(&r.svd.s) {
        let _ = write!(s, "{f}");
        for v in sv {
            let _ = write!(s, ",{v}");
        }
        s.push('\n');
    }
    s.into_bytes()
}

/// `shapes.uff`: one dataset 55 per mode and method (load case 1 FDD, 2 EFDD, 3 SSI), the
/// targets as nodes, the shape in the motion's direction (x or y).
pub fn shapes_uff(r: &OmaResult, records: &Records, along_x: bool) -> anyhow::Result<Vec<u8>> {
    let mut bytes = Vec::new();
    for m in &r.modes {
        let nodes: Vec<(u32, [Complex64; 3])> = records
            .targets
            .iter()
            .zip(&m.shape)
            .map(|((t, _), &c)| {
                let zero = Complex64::new(0.0, 0.0);
                let v = if along_x {
                    [c, zero, zero]
                } else {
                    [zero, c, zero]
                };
                (*t as u32, v)
            })
            .collect();
        let title = format!("vibcam output-only modal analysis: {}", m.method.name());
        let what = format!("mode {} at {:.6} Hz", m.mode, m.f_hz);
        let d = Shape55 {
            id_lines: [&title, &what, "", "", ""],
            load_case: match m.method {
                Method::Fdd => 1,
                Method::Efdd => 2,
                Method::Ssi => 3,
            },
            mode: m.mode as u32,
            f_hz: m.f_hz,
            damping: m.damping.unwrap_or(0.0),
            nodes: &nodes,
        };
        bytes.extend(write_dataset55(&d)?);
    }
    Ok(bytes)
}

/// The report: the records, the settings, the modes per method, the notes.
pub fn report(r: &OmaResult, records: &Records, s: &OmaSettings, preamble: &str) -> String {
    let mut o = String::from(preamble);
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
             of prominence and {} dB over the median (the floor)",
            s.peaks.f_min_hz, s.peaks.f_max_hz, s.peaks.prominence_db, s.peaks.over_floor_db
        );
    }
    let _ = writeln!(
        o,
        "SSI-cov: {} block rows, orders 2 to {}; stable: frequency within {} %, damping within \
         {} %, MAC >= {}; a mode from {} stable poles",
        s.ssi.block_rows,
        s.ssi.max_order,
        100.0 * s.ssi.df_max,
        100.0 * s.ssi.dz_max,
        s.ssi.mac_min,
        s.ssi_min_poles
    );
    let _ = writeln!(o, "\nmethod  mode  f_hz        damping   amplitude");
    for m in &r.modes {
        let _ = writeln!(
            o,
            "{:<7} {:>4}  {:<10.5} {:<9} {}",
            m.method.name(),
            m.mode,
            m.f_hz,
            m.damping.map_or("-".to_string(), |z| format!("{:.4}", z)),
            m.amplitude.map_or("-".to_string(), |a| format!("{a:.4e}"))
        );
    }
    for note in &r.notes {
        let _ = writeln!(o, "note: {note}");
    }
    o
}
