//! Several targets in one recording analysed (`analyze --targets K`; their tracking is
//! `vibcam_track::tracks`, re-exported here): per target the chain of [`super::analyze`]; per
//! band the modal fit ([`super::modal`]): the accelerometer's and each target's pole
//! (frequency, damping) and the shape across targets from one pole fitted to all their FRFs.

use super::frf_uncertainty::FrfModeUncertainty;
use super::modal::{self, FrfForm};
use super::oma::uncertainty::Interval;
use super::{Analysis, Displacement, DisplacementSettings, Settings};
use crate::bad_input;
use crate::export::analysis::Spectrum;
use crate::export::targets::{ShapeRow, Track};
use num_complex::Complex64;
pub use vibcam_track::tracks::*;

/// One mode of one system (accelerometer: target 0; vision: targets 1..K): a row of
/// `modes.csv`.
pub use crate::export::targets::ModeRow as TargetMode;

/// Per target: the displacement and the analysis.
#[derive(Debug)]
pub struct TargetAnalysis {
    /// Per target, its displacement.
    pub displacements: Vec<Displacement>,
    /// Per target, the chain's result, or why it failed (too many lost frames, ...): a failed
    /// target has no modes and no shape component; the others are analysed.
    pub analyses: Vec<Result<Analysis, String>>,
    /// The accelerometer's H1 (the same from every target's analysis).
    pub acc_frf: crate::chain::frf::Frf,
    /// The accelerometer's picked modes, one per band.
    pub acc_modes: Vec<crate::chain::frf::PickedMode>,
    /// Accelerometer and every target, every band (failed targets left out).
    pub modes: Vec<TargetMode>,
    /// Per band, the shape across targets (normalised; `None` for a failed target) and the
    /// shared pole; `None` when the fit failed.
    pub shapes: Vec<Option<(modal::Pole, Vec<Option<Complex64>>)>>,
    /// Per target, the exposure compensation applied to its vision H1 before the fits
    /// (`analyze --compensate-exposure`); `None` without it or for a failed target.
    pub compensation: Vec<Option<super::compensate::Compensated>>,
}

/// The exposure compensation asked of [`analyze_targets`]: every target's vision H1 divided
/// by the exposure's transfer before the modal fits ([`super::compensate`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CompensationRequest {
    /// Exposure, s.
    pub exposure_s: f64,
    /// Binary centroid (the sinc is then an approximation, noted).
    pub binary: bool,
}

impl TargetAnalysis {
    /// The targets (1-based) whose analysis failed, with the reason.
    pub fn failures(&self) -> Vec<(usize, &str)> {
        self.analyses
            .iter()
            .enumerate()
            .filter_map(|(t, a)| a.as_ref().err().map(|e| (t + 1, e.as_str())))
            .collect()
    }

    /// Per-target fits that disagree with the shared pole of their band by more than three
    /// half-power bandwidths (`2 zeta f`): typically a target near a node of that mode, whose
    /// own FRF hardly shows it. `(target, mode, own f_hz, shared pole)`.
    pub fn doubtful_fits(&self) -> Vec<(usize, usize, Option<f64>, modal::Pole)> {
        let mut v = Vec::new();
        for m in self.modes.iter().filter(|m| m.target > 0) {
            let Some(Some((pole, _))) = self.shapes.get(m.mode - 1) else {
                continue;
            };
            let width = 2.0 * pole.damping * pole.f_hz;
            let off = m.f_hz.is_none_or(|f| (f - pole.f_hz).abs() > 3.0 * width);
            if off {
                v.push((m.target, m.mode, m.f_hz, *pole));
            }
        }
        v
    }
}

/// Whether a fitted pole is one the FRF can show: inside the band, not on its edges, and with
/// a half-power bandwidth (`2 zeta f`) of at least half a bin. A narrower "resonance" is one
/// spurious bin (noise where the input is weak), not a mode: its fit is left empty.
fn resolvable(pole: &modal::Pole, band: (f64, f64), freq_hz: &[f64]) -> bool {
    let df = freq_hz.get(1).copied().unwrap_or(0.0) - freq_hz.first().copied().unwrap_or(0.0);
    pole.f_hz > band.0 + df && pole.f_hz < band.1 - df && 2.0 * pole.damping * pole.f_hz >= 0.5 * df
}

/// The chain on every target and the modal fits. A target whose chain fails (more than 5 %
/// lost frames, ...) is reported in [`TargetAnalysis::analyses`] and left out of the modes and
/// shapes; an error only when every target fails.
pub fn analyze_targets(
    tracks: &Tracks,
    ds: &DisplacementSettings,
    (base, tip): (&[f64], &[f64]),
    s: &Settings,
    compensate: Option<CompensationRequest>,
) -> anyhow::Result<TargetAnalysis> {
    let mut displacements = Vec::new();
    let mut analyses = Vec::new();
    let mut compensation = Vec::new();
    for c in &tracks.centroids {
        let d = super::displacement_mm(c, ds);
        let mut a = match &d {
            Ok(d) => super::analyze(d, base, tip, s).map_err(|e| format!("{e:#}")),
            Err(e) => Err(format!("{e:#}")),
        };
        compensation.push(match (&mut a, compensate) {
            (Ok(an), Some(r)) => Some(super::compensate::compensate(
                an,
                r.exposure_s,
                &s.bands,
                r.binary,
            )?),
            _ => None,
        });
        if let Ok(an) = &mut a {
            an.intervals = Some(super::frf_uncertainty::of_analysis(
                an,
                (base, tip),
                compensate.map(|r| r.exposure_s),
                super::oma::uncertainty::GROUPS,
            )?);
        }
        displacements.push(d.unwrap_or_else(|_| Displacement {
            mm: vec![0.0; c.len()],
            lost: vec![true; c.len()],
            lost_count: c.len(),
            reference_px: 0.0,
            policy: ds.lost_frames,
        }));
        analyses.push(a);
    }
    let Some(first) = analyses.iter().find_map(|a| a.as_ref().ok()) else {
        let why: Vec<String> = analyses
            .iter()
            .enumerate()
            .filter_map(|(t, a)| a.as_ref().err().map(|e| format!("target {}: {e}", t + 1)))
            .collect();
        return Err(bad_input(format!(
            "no target could be analysed: {}",
            why.join("; ")
        )));
    };
    let (acc_frf, acc_modes) = (first.acc_frf.clone(), first.acc_modes.clone());
    let mut modes = Vec::new();
    let mut shapes = Vec::new();
    for (b, &band) in s.bands.iter().enumerate() {
        modes.extend(band_modes(b, band, (&acc_frf, &acc_modes), &analyses));
        shapes.push(band_shape(band, &acc_frf, &analyses));
    }
    Ok(TargetAnalysis {
        displacements,
        analyses,
        acc_frf,
        acc_modes,
        modes,
        shapes,
        compensation,
    })
}

/// Band `b`'s modes: the accelerometer's (target 0) and every analysed target's, each its own
/// pole fit (left empty when it is not [`resolvable`]).
fn band_modes(
    b: usize,
    band: (f64, f64),
    (acc_frf, acc_modes): (&crate::chain::frf::Frf, &[crate::chain::frf::PickedMode]),
    analyses: &[Result<Analysis, String>],
) -> Vec<TargetMode> {
    let fit = |f: &crate::chain::frf::Frf, u: Option<&FrfModeUncertainty>| band_pole(f, u, band);
    let cells = |i: &Option<Interval>| i.map(|i| (i.u, i.lo, i.hi));
    let row_intervals = |u: Option<&FrfModeUncertainty>| {
        u.map_or([None; 3], |u| {
            [
                cells(&u.f_fit_interval),
                cells(&u.damping),
                cells(&u.amplitude),
            ]
        })
    };
    let first = analyses.iter().find_map(|a| a.as_ref().ok());
    let acc_u = first
        .and_then(|a| a.intervals.as_ref())
        .and_then(|i| i.acc.get(b));
    let a = fit(acc_frf, acc_u);
    let mut modes = vec![TargetMode {
        target: 0,
        mode: b + 1,
        band_hz: band,
        f_hz: a.map(|m| m.0),
        amplitude: acc_modes[b].amplitude,
        damping: a.and_then(|m| m.1),
        e2pr: None,
        intervals: if a.is_some() {
            row_intervals(acc_u)
        } else {
            [None; 3]
        },
    }];
    for (t, an) in analyses.iter().enumerate() {
        let Ok(an) = an else { continue };
        let vis_u = an.intervals.as_ref().and_then(|i| i.vis.get(b));
        let v = fit(&an.vis_frf, vis_u);
        modes.push(TargetMode {
            target: t + 1,
            mode: b + 1,
            band_hz: band,
            f_hz: v.map(|m| m.0),
            amplitude: an.vis_modes[b].amplitude,
            damping: v.and_then(|m| m.1),
            intervals: if v.is_some() {
                row_intervals(vis_u)
            } else {
                [None; 3]
            },
            // at the fitted frequency (the picked bin's when the fit failed)
            e2pr: an.vis_modes[b].e2pr.map(|e| {
                let picked = an.vis_modes[b].f_hz;
                match v {
                    Some(m) if picked > 0.0 => e / picked * m.0,
                    _ => e,
                }
            }),
        });
    }
    modes
}

/// The pole of `band` in one FRF, `(f_hz, damping)`: the plain fit's, or with several segments
/// the smoothed fit's of the intervals (the window's resolution bias removed; the intervals are
/// of it), when the plain fit is resolvable; `None` when it is not.
fn band_pole(
    f: &crate::chain::frf::Frf,
    u: Option<&FrfModeUncertainty>,
    band: (f64, f64),
) -> Option<(f64, Option<f64>)> {
    let plain = modal::fit_mode(&f.freq_hz, &f.h1, band, FrfForm::Accelerance)
        .ok()
        .filter(|m| resolvable(&m.pole, band, &f.freq_hz))?;
    Some(match u {
        // enough segments for intervals but none of the damping: the mode is narrower
        // than a segment's line (or the fit failed), and no fit's damping is to be trusted
        Some(FrfModeUncertainty {
            f_fit: Some(fh),
            damping: None,
            ..
        }) if f.segments as usize >= super::frf_uncertainty::MIN_SEGMENTS => (*fh, None),
        Some(FrfModeUncertainty {
            f_fit: Some(fh),
            damping_fit: Some(z),
            ..
        }) if f.segments > 1 => (*fh, Some(*z)),
        _ => (plain.pole.f_hz, Some(plain.pole.damping)),
    })
}

/// The shape in `band`: one pole fitted over every analysed target's FRF, the components of
/// failed targets `None`; `None` when the fit fails.
fn band_shape(
    band: (f64, f64),
    acc_frf: &crate::chain::frf::Frf,
    analyses: &[Result<Analysis, String>],
) -> Option<(modal::Pole, Vec<Option<Complex64>>)> {
    let good: Vec<usize> = (0..analyses.len())
        .filter(|&t| analyses[t].is_ok())
        .collect();
    let frfs: Vec<&[Complex64]> = good
        .iter()
        .filter_map(|&t| analyses[t].as_ref().ok())
        .map(|a| a.vis_frf.h1.as_slice())
        .collect();
    let shape = modal::fit_shape(&acc_frf.freq_hz, &frfs, band, FrfForm::Accelerance, None).ok();
    shape.map(|sh| {
        let mut full = vec![None; analyses.len()];
        for (&t, c) in good.iter().zip(sh.shape) {
            full[t] = Some(c);
        }
        (sh.pole, full)
    })
}

/// A reference mode shape per mode (`--shape-reference`): `mode -> components of targets
/// 1..K` (complex; a missing `im` column is 0).
pub type ShapeReference = std::collections::BTreeMap<usize, Vec<Complex64>>;

/// One row of a shape reference: `(mode, target, component)`, checked against `k` targets and
/// `bands` modes; `at` names the file and row. `[mode, target, re]` and `im` are column indices.
fn reference_row(
    record: &csv::StringRecord,
    ([cm, ct, cr], ci): ([usize; 3], Option<usize>),
    (k, bands): (usize, usize),
    at: &str,
) -> anyhow::Result<(usize, usize, Complex64)> {
    let line = record.iter().collect::<Vec<_>>().join(",");
    let cell = |c: usize, what: &str| -> anyhow::Result<&str> {
        record
            .get(c)
            .ok_or_else(|| bad_input(format!("{at}: no {what} column ({line:?})")))
    };
    let int = |c: usize, what: &str| -> anyhow::Result<usize> {
        let v = cell(c, what)?;
        v.parse().map_err(|_| {
            bad_input(format!(
                "{at}, column {what}: {v:?} is not a positive integer"
            ))
        })
    };
    let num = |c: usize, what: &str| -> anyhow::Result<f64> {
        let v = cell(c, what)?;
        v.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| bad_input(format!("{at}, column {what}: {v:?} is not a finite number")))
    };
    let (mode, target) = (int(cm, "mode")?, int(ct, "target")?);
    if !(1..=bands).contains(&mode) || !(1..=k).contains(&target) {
        return Err(bad_input(format!(
            "{at}: mode {mode}, target {target}: modes count from 1 to {bands} (one per \
             $bands band) and targets from 1 to {k} ($targets {k})"
        )));
    }
    let im = match ci {
        Some(c) => num(c, "im")?,
        None => 0.0,
    };
    Ok((mode, target, Complex64::new(num(cr, "re")?, im)))
}

/// Reads a reference shape CSV with a header naming at least `mode`, `target` and `re` (and
/// optionally `im`): the layout of `shapes.csv`, or a hand-written table. With a `method`
/// column, the rows of one method (`h1`, else `ssi`, `efdd`, `fdd`). Every mode present
/// must give all `k` targets once. Errors name the file, the row and the column.
pub fn read_shape_reference(
    path: &std::path::Path,
    k: usize,
    bands: usize,
) -> anyhow::Result<ShapeReference> {
    let name = path.display();
    let (mut reader, header) =
        crate::csvio::open_with_header(path, &format!("$shape_reference {name}"), true)?;
    let col = |c: &str| header.iter().position(|h| h == c);
    let (Some(cm), Some(ct), Some(cr)) = (col("mode"), col("target"), col("re")) else {
        return Err(bad_input(format!(
            "{name}: the header must name the columns mode, target and re (and optionally \
             im), as shapes.csv does; found {header:?}"
        )));
    };
    let cols = [cm, ct, cr];
    let records: Vec<csv::StringRecord> = reader
        .records()
        .collect::<Result<_, _>>()
        .map_err(|e| bad_input(format!("{name}: {e}")))?;
    let method = col("method").and_then(|c| preferred_method(&records, c));
    let mut raw: std::collections::BTreeMap<usize, Vec<Option<Complex64>>> = Default::default();
    for record in records {
        if let Some((c, m)) = &method {
            if record.get(*c) != Some(m.as_str()) {
                continue;
            }
        }
        let row = record.position().map_or(0, |p| p.line());
        let (mode, target, c) = reference_row(
            &record,
            (cols, col("im")),
            (k, bands),
            &format!("{name} row {row}"),
        )?;
        let v = raw.entry(mode).or_insert_with(|| vec![None; k]);
        if v[target - 1].is_some() {
            return Err(bad_input(format!(
                "{name} row {row}: mode {mode}, target {target} is given twice"
            )));
        }
        v[target - 1] = Some(c);
    }
    if raw.is_empty() {
        return Err(bad_input(format!("{name}: no shape rows")));
    }
    complete_shapes(raw, k, &name.to_string())
}

/// In a shapes.csv with a `method` column (an output-only analysis gives one shape per mode
/// and method), the rows of one method: h1 first, then ssi, decay, efdd, fdd, else the first seen.
fn preferred_method(records: &[csv::StringRecord], c: usize) -> Option<(usize, String)> {
    let seen: Vec<&str> = records.iter().filter_map(|r| r.get(c)).collect();
    ["h1", "ssi", "decay", "efdd", "fdd"]
        .into_iter()
        .find(|m| seen.contains(m))
        .or(seen.first().copied())
        .map(|m| (c, m.to_string()))
}

/// Every mode's reference shape, complete (a component for each of the `k` targets) and not
/// all zero.
fn complete_shapes(
    raw: std::collections::BTreeMap<usize, Vec<Option<Complex64>>>,
    k: usize,
    name: &str,
) -> anyhow::Result<ShapeReference> {
    raw.into_iter()
        .map(|(mode, v)| {
            let missing: Vec<usize> = (0..k).filter(|&t| v[t].is_none()).map(|t| t + 1).collect();
            if !missing.is_empty() {
                return Err(bad_input(format!(
                    "{name}: mode {mode} has no component for target(s) {missing:?}"
                )));
            }
            if v.iter().flatten().all(|c| c.norm() == 0.0) {
                return Err(bad_input(format!(
                    "{name}: every component of mode {mode} is zero: no shape to compare with"
                )));
            }
            Ok((mode, v.into_iter().flatten().collect()))
        })
        .collect()
}

/// MAC of each fitted shape against the reference of its mode, over the targets analysed:
/// `(mode, MAC)` for every mode both have.
pub fn macs(a: &TargetAnalysis, reference: &ShapeReference) -> Vec<(usize, f64)> {
    let mut v = Vec::new();
    for (b, shape) in a.shapes.iter().enumerate() {
        let (Some((_, fitted)), Some(r)) = (shape, reference.get(&(b + 1))) else {
            continue;
        };
        let (x, y): (Vec<Complex64>, Vec<Complex64>) = fitted
            .iter()
            .zip(r)
            .filter_map(|(f, r)| f.map(|f| (f, *r)))
            .unzip();
        v.push((b + 1, modal::mac(&x, &y)));
    }
    v
}

/// The H1 of each `(target, H1)` of `frf.csv`: target 0 the accelerometer, then each analysed
/// target.
pub fn frf_spectra(a: &TargetAnalysis) -> Vec<(usize, Spectrum<'_>)> {
    std::iter::once((0, super::spectrum(&a.acc_frf)))
        .chain(a.analyses.iter().enumerate().filter_map(|(t, an)| {
            an.as_ref()
                .ok()
                .map(|an| (t + 1, super::spectrum(&an.vis_frf)))
        }))
        .collect()
}

/// Each target's track for `displacement.csv` (`raw`: the tracks as measured, when the
/// camera's motion was removed from `tracks`).
pub fn track_rows<'a>(
    tracks: &'a Tracks,
    raw: Option<&'a Tracks>,
    a: &'a TargetAnalysis,
) -> Vec<Track<'a>> {
    tracks
        .centroids
        .iter()
        .zip(&a.displacements)
        .enumerate()
        .map(|(t, (c, d))| Track {
            centroids: c,
            mm: Some(&d.mm),
            lost: Some(&d.lost),
            raw: raw.map(|r| r.centroids[t].as_slice()),
            evidence: tracks.evidence.get(t).map(Vec::as_slice),
        })
        .collect()
}

/// The rows of `shapes.csv` (failed targets left out); `first` is each target's position in
/// the first frame.
pub fn shape_rows(a: &TargetAnalysis, first: &[(f64, f64)]) -> Vec<ShapeRow> {
    let mut rows = Vec::new();
    for (b, shape) in a.shapes.iter().enumerate() {
        let Some((_, v)) = shape else { continue };
        for (t, (c, &xy_px)) in v.iter().zip(first).enumerate() {
            let Some(c) = c else { continue };
            rows.push(ShapeRow {
                mode: b + 1,
                target: t + 1,
                xy_px,
                value: *c,
            });
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shape_reference_is_read_as_csv_with_quoted_cells() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("ref.csv");
        // a label column whose cells hold commas: split on ',' would shift every column
        std::fs::write(
            &p,
            "mode,target,label,re\n1,1,\"tip, left\",1\n1,2,\"root, right\",-0.5\n",
        )
        .unwrap();
        let r = read_shape_reference(&p, 2, 2).unwrap();
        assert_eq!(
            r[&1],
            vec![Complex64::new(1.0, 0.0), Complex64::new(-0.5, 0.0)]
        );
        std::fs::write(&p, "mode,target,re\n1,1,1\n1,2,x\n").unwrap();
        let e = read_shape_reference(&p, 2, 2).unwrap_err().to_string();
        assert!(e.contains("row 3, column re"), "{e}");
        // an output-only shapes.csv: one shape per mode and method, SSI's taken
        std::fs::write(
            &p,
            "mode,target,x_px,y_px,re,im,abs,method\n1,1,,,1,0,1,fdd\n1,2,,,0.2,0,0.2,fdd\n\
             1,1,,,1,0,1,ssi\n1,2,,,0.5,0,0.5,ssi\n",
        )
        .unwrap();
        let r = read_shape_reference(&p, 2, 2).unwrap();
        assert_eq!(
            r[&1],
            vec![Complex64::new(1.0, 0.0), Complex64::new(0.5, 0.0)]
        );
    }
}
