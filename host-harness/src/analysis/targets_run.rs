//! `analyze --targets K` ([`super::run`] with a [`TargetsRequest`]): the targets tracked and
//! analysed ([`crate::analysis::targets`]), then `modes.csv`, `shapes.csv`, `frf.csv`,
//! `displacement.csv`, `frf.uff`, `shapes.png`/`.svg`, `mac.csv` (with a shape reference),
//! `compensation.csv` (with the compensation) and `report.txt` written into the staged output
//! directory.

use super::request::{Outcome, Request, TargetsRequest};
use crate::analysis::targets::{self, TargetAnalysis, Tracks};
use crate::analysis::Axis;
use crate::export::targets as export;
use crate::export::uff;
use crate::frames::FrameSource;
use crate::outdir::Staged;
use std::fmt::Write as _;

/// Runs the multi-target analysis `t` of the request.
pub fn run(
    (req, out): (&Request, Staged),
    t: &TargetsRequest,
    source: &FrameSource,
    (base, tip): (&[f64], &[f64]),
    ignored: Option<&str>,
) -> anyhow::Result<Outcome> {
    let c = compute(req, t, source, (base, tip))?;
    write((req, out), t, source, &c, ignored)
}

/// What a multi-target analysis computes before anything is written: the reference shapes,
/// the targets tracked in the camera's view, each target's analysis.
#[derive(Debug)]
struct Computed {
    reference: Option<targets::ShapeReference>,
    viewed: super::view::Viewed,
    analysis: TargetAnalysis,
}

fn compute(
    req: &Request,
    t: &TargetsRequest,
    source: &FrameSource,
    (base, tip): (&[f64], &[f64]),
) -> anyhow::Result<Computed> {
    let (settings, k) = (&req.settings, t.targets.count());
    // the reference is read before the frames: a bad file fails at once
    let reference = t
        .shape_reference
        .as_deref()
        .map(|p| targets::read_shape_reference(p, k, settings.bands.len()))
        .transpose()?;
    let along_x = req.displacement.axis == Axis::X;
    let viewed = super::view::track_view(
        source,
        settings.frame_rate_hz,
        &req.centroid,
        &t.targets,
        &t.view,
        along_x,
    )?;
    let compensate = match (req.compensate_exposure, settings.exposure_s) {
        (true, Some(exposure_s)) => Some(targets::CompensationRequest {
            exposure_s,
            binary: req.binary,
        }),
        _ => None,
    };
    let analysis = targets::analyze_targets(
        &viewed.tracks,
        &req.displacement,
        (base, tip),
        settings,
        compensate,
    )?;
    Ok(Computed {
        reference,
        viewed,
        analysis,
    })
}

/// Writes every output of a multi-target analysis into the staged directory, and commits it
/// (a run with failed targets never replaces an earlier output).
fn write(
    (req, out): (&Request, Staged),
    t: &TargetsRequest,
    source: &FrameSource,
    c: &Computed,
    ignored: Option<&str>,
) -> anyhow::Result<Outcome> {
    let (settings, a, viewed) = (&req.settings, &c.analysis, &c.viewed);
    let (tracks, windows) = (&viewed.tracks, viewed.windows.as_ref());
    let along_x = req.displacement.axis == Axis::X;
    let macs = c.reference.as_ref().map(|r| targets::macs(a, r));
    write_tables(&out, req, a, (tracks, viewed.raw.as_ref()), macs.as_deref())?;
    let shapes = shape_plot(&out, a, tracks, c.reference.as_ref(), along_x)?;
    let mut report = full_report(req, t, a, tracks, macs.as_deref(), ignored);
    report.push_str(&viewed.describe(along_x));
    let (camera, _) =
        super::view::write_camera_outputs(&out, viewed, settings.frame_rate_hz, true)?;
    report.push_str(&camera);
    if let Some(w) = windows {
        report.push_str(&super::points::windows_report(w, tracks));
    }
    let failed = a.failures();
    let report = super::write_report(&out, &report, req.pdf, |report| {
        page(
            req,
            source,
            a,
            tracks,
            (windows, super::view::reference_markers(viewed)),
            report,
            std::slice::from_ref(&shapes),
        )
    })?;
    // a run with failed targets exits 2: it never replaces an earlier output
    let written = if failed.is_empty() {
        out.commit().map(|()| true)?
    } else {
        out.commit_unless_replacing()?
    };
    let result = if failed.is_empty() {
        Ok(())
    } else {
        Err(failed_targets(&failed, t.targets.count(), written, req))
    };
    Ok(Outcome { report, result })
}

/// The error of a run in which some targets could not be analysed: which, why, and where the
/// others' results are (or that the earlier output was left as it was).
fn failed_targets(
    failed: &[(usize, &str)],
    k: usize,
    written: bool,
    req: &Request,
) -> anyhow::Error {
    let list: Vec<String> = failed
        .iter()
        .map(|(t, why)| format!("target {t}: {why}"))
        .collect();
    let whereabouts = if written {
        format!("the others' results are in {}", req.out.display())
    } else {
        format!(
            "nothing was written: the earlier output in {} was left as it was",
            req.out.display()
        )
    };
    crate::bad_input(format!(
        "{} of {k} targets could not be analysed ({}); {whereabouts}",
        failed.len(),
        list.join("; "),
    ))
}

/// `report.html` of a multi-target analysis: the first frame with every target's window,
/// number and lost frames; the modes per target with their intervals; the MAC of the fitted
/// shapes, each animated; the shapes' figure; the report.
fn page(
    req: &Request,
    source: &FrameSource,
    a: &TargetAnalysis,
    tracks: &Tracks,
    (windows, references): (
        Option<&super::points::PointsInfo>,
        Vec<crate::export::html::ReferenceMarker>,
    ),
    text: &str,
    figures: &[crate::plots::Figure],
) -> crate::export::html::Report {
    use crate::export::html::{mac_matrix, Report, ShapeAnimation};
    use num_complex::Complex64;
    let frame = source
        .frame_at(req.settings.frame_rate_hz, 0)
        .ok()
        .flatten()
        .and_then(|(_, f)| f.to_image().ok());
    let markers = super::track_run::markers(tracks, windows);
    // the geometry was checked against the targets when the job was
    let wire =
        super::track_run::wire(req.geometry.as_ref(), markers.len(), windows).unwrap_or_default();
    let (head, rows) = modes_table(a);
    let fitted: Vec<(String, Vec<Complex64>)> = a
        .shapes
        .iter()
        .enumerate()
        .filter_map(|(b, s)| {
            s.as_ref().map(|(p, v)| {
                (
                    format!("mode {} {:.3} Hz", b + 1, p.f_hz),
                    v.iter().map(|c| c.unwrap_or_default()).collect(),
                )
            })
        })
        .collect();
    let shapes: Vec<&[Complex64]> = fitted.iter().map(|(_, v)| v.as_slice()).collect();
    let figures = crate::plots::page_figures(figures);
    Report {
        title: format!("analyze: {}", req.frames),
        frame,
        markers,
        direction: if req.displacement.axis == Axis::X {
            (1.0, 0.0)
        } else {
            (0.0, -1.0)
        },
        figures,
        modes: (!rows.is_empty()).then_some((head, rows)),
        mac: (!fitted.is_empty()).then(|| {
            (
                fitted.iter().map(|(l, _)| l.clone()).collect(),
                mac_matrix(&shapes),
            )
        }),
        shapes: fitted
            .iter()
            .map(|(l, v)| ShapeAnimation {
                label: l.clone(),
                shape: v.clone(),
            })
            .collect(),
        wire,
        text: text.to_string(),
        scrub: None,
        references,
        picker: None,
        banner: None,
        provenance: None,
        videos: Vec::new(),
    }
}

/// The page's table of modes: per target and mode, frequency, |H1|, damping and their 95 %
/// intervals.
fn modes_table(a: &TargetAnalysis) -> (Vec<String>, Vec<Vec<String>>) {
    let iv = |i: Option<(f64, f64, f64)>, d: usize| {
        crate::export::html::range_cell(i.map(|(_, lo, hi)| (lo, hi)), d)
    };
    let rows: Vec<Vec<String>> = a
        .modes
        .iter()
        .map(|m| {
            vec![
                m.target.to_string(),
                m.mode.to_string(),
                m.f_hz.map_or(String::new(), |f| format!("{f:.4}")),
                iv(m.intervals[0], 4),
                format!("{:.4}", m.amplitude),
                m.damping.map_or(String::new(), |d| format!("{d:.5}")),
                iv(m.intervals[1], 5),
            ]
        })
        .collect();
    let head = crate::export::html::header(&[
        "target",
        "mode",
        "f (Hz)",
        "95 % interval",
        "|H1|",
        "damping",
        "95 % interval",
    ]);
    (head, rows)
}

/// The CSV files and the UFF of a multi-target analysis.
fn write_tables(
    out: &Staged,
    req: &Request,
    a: &TargetAnalysis,
    (tracks, raw): (&Tracks, Option<&Tracks>),
    macs: Option<&[(usize, f64)]>,
) -> anyhow::Result<()> {
    let s = &req.settings;
    out.write("modes.csv", export::modes_csv(&a.modes))?;
    out.write(
        "shapes.csv",
        export::shapes_csv(&targets::shape_rows(a, &tracks.first)),
    )?;
    out.write("frf.csv", export::frf_csv(targets::frf_spectra(a)))?;
    out.write(
        "displacement.csv",
        export::displacement_csv(
            &targets::track_rows(tracks, raw, a),
            s.frame_rate_hz,
            s.time_offset_s,
        ),
    )?;
    out.write("frf.uff", uff_bytes(a)?)?;
    if a.compensation.iter().any(Option::is_some) {
        let rows: Vec<(usize, Vec<_>)> = a
            .compensation
            .iter()
            .enumerate()
            .filter_map(|(t, c)| c.as_ref().map(|c| (t + 1, c.rows())))
            .collect();
        let csv = export::compensation_csv(rows.iter().map(|(t, r)| (*t, r.as_slice())));
        out.write("compensation.csv", csv)?;
    }
    if let Some(m) = macs {
        out.write("mac.csv", export::mac_csv(m))?;
    }
    Ok(())
}

/// The whole report: [`report`], then the notes on the frames and the compensation.
fn full_report(
    req: &Request,
    t: &TargetsRequest,
    a: &TargetAnalysis,
    tracks: &Tracks,
    macs: Option<&[(usize, f64)]>,
    ignored: Option<&str>,
) -> String {
    let mut report = report(a, tracks, (t.targets.count(), t.accel_target), macs);
    if let Some(n) = ignored {
        report.push_str(&format!("\nnote: {n}\n"));
    }
    report.push_str(&format!("\nframes: {}\n", tracks.depth.describe()));
    let total = tracks.centroids.first().map_or(0, Vec::len);
    if let Some(used) = a.analyses.iter().flatten().map(|an| an.frames_used).next() {
        if used < total {
            report.push_str(&format!(
                "note: the last {} of {total} frames were left out: the first {used} are the \
                 longest record that spans a whole number of accelerometer samples\n",
                total - used
            ));
        }
    }
    if let Some(w) = tracks.depth.threshold_warning(req.centroid.threshold) {
        super::warn(&w);
        report.push_str(&format!("WARNING: {w}\n"));
    }
    for (t, c) in a.compensation.iter().enumerate() {
        if let Some(c) = c {
            report.push_str(&format!("\ntarget {}:", t + 1));
            report.push_str(&c.report());
        }
    }
    report
}

/// One dataset 58 per FRF: the accelerometer (node 100) and each analysed target (node
/// 1..K), all over the base acceleration (node 1000), direction +Z (image up).
fn uff_bytes(a: &TargetAnalysis) -> anyhow::Result<Vec<u8>> {
    let acc = &a.acc_frf;
    let df = acc.freq_hz.get(1).copied().unwrap_or(0.0) - acc.freq_hz[0];
    let targets: Vec<_> = a
        .analyses
        .iter()
        .map(|an| {
            an.as_ref()
                .ok()
                .map(|an| (an.vis_frf.freq_hz[0], an.vis_frf.h1.as_slice()))
        })
        .collect();
    let accel = (
        "accelerometer / base acceleration",
        100,
        acc.freq_hz[0],
        &acc.h1[..],
    );
    let sets = uff::vision_frfs(1000, accel, &targets, df);
    Ok(uff::write_file(&sets)?)
}

/// `shapes.png` / `shapes.svg`: every fitted shape's real part along the targets' first-frame
/// positions (along the image axis across the motion), reference shapes dashed.
fn shape_plot(
    out: &Staged,
    a: &TargetAnalysis,
    tracks: &Tracks,
    reference: Option<&targets::ShapeReference>,
    motion_along_x: bool,
) -> anyhow::Result<crate::plots::Figure> {
    use crate::plots::ShapeCurve;
    // targets lie across the motion: along x for vertical motion, along y for horizontal
    let positions: Vec<f64> = tracks
        .first
        .iter()
        .map(|&(x, y)| if motion_along_x { y } else { x })
        .collect();
    let fitted: Vec<(usize, Vec<f64>)> = a
        .shapes
        .iter()
        .enumerate()
        .filter_map(|(b, s)| {
            s.as_ref().map(|(_, v)| {
                (
                    b + 1,
                    v.iter().map(|c| c.map_or(f64::NAN, |c| c.re)).collect(),
                )
            })
        })
        .collect();
    let refs: Vec<(usize, Vec<f64>)> = reference
        .map(|r| {
            r.iter()
                .map(|(m, v)| (*m, crate::analysis::modal::normalise_shape(v)))
                .map(|(m, v)| (m, v.iter().map(|c| c.re).collect()))
                .collect()
        })
        .unwrap_or_default();
    let mut curves: Vec<ShapeCurve> = Vec::new();
    for (m, v) in &fitted {
        let pole = a.shapes[m - 1].as_ref().map(|(p, _)| p.f_hz).unwrap_or(0.0);
        curves.push(ShapeCurve {
            label: format!("mode {m} ({pole:.3} Hz)"),
            values: v,
            reference: false,
        });
    }
    for (m, v) in &refs {
        curves.push(ShapeCurve {
            label: format!("mode {m}, reference"),
            values: v,
            reference: true,
        });
    }
    let axis = if motion_along_x { "y" } else { "x" };
    let f = crate::plots::shape_figure(
        "shapes",
        "Mode shapes along the targets",
        &format!("target position in the first frame, {axis} (px)"),
        &positions,
        &curves,
    )?;
    f.write_staged(out)?;
    Ok(f)
}

/// The printed report: lost frames per target, failed targets, modes, the co-located target
/// against the accelerometer, shapes, MAC against the reference, doubtful per-target fits.
fn report(
    a: &TargetAnalysis,
    tracks: &Tracks,
    (k, accel_target): (usize, usize),
    macs: Option<&[(usize, f64)]>,
) -> String {
    let mut s = format!("analyze --targets {k}\n\nlost frames per target:");
    for (t, d) in a.displacements.iter().enumerate() {
        let _ = write!(s, " {}: {} of {}", t + 1, d.lost_count, d.mm.len());
    }
    if tracks.refused.iter().any(|&n| n > 0) {
        s.push_str(
            "\nof them refused as implausible for the target's history (pixel count or jump):",
        );
        for (t, n) in tracks.refused.iter().enumerate() {
            let _ = write!(s, " {}: {n}", t + 1);
        }
    }
    for (t, why) in a.failures() {
        let _ = write!(s, "\nTARGET {t} NOT ANALYSED: {why}");
    }
    s.push_str("\n\nsystem        | target | mode |    f_hz | damping  | amplitude\n");
    for m in &a.modes {
        let system = if m.target == 0 {
            "accelerometer"
        } else {
            "vision"
        };
        let f = m.f_hz.map_or("-".into(), |v| format!("{v:.4}"));
        let z = m.damping.map_or("-".into(), |v| format!("{v:.5}"));
        let _ = writeln!(
            s,
            "{system:<13} | {:>6} | {:>4} | {f:>7} | {z:<8} | {:.4}",
            m.target, m.mode, m.amplitude
        );
    }
    intervals_text(&mut s, a);
    colocated(&mut s, a, accel_target);
    shapes_text(&mut s, a, tracks);
    s.push('\n');
    if let Some(m) = macs {
        s.push_str("\nMAC against $shape_reference:");
        for (mode, v) in m {
            let _ = write!(s, " mode {mode}: {v:.6}");
        }
        s.push('\n');
    }
    for (t, mode, f, pole) in a.doubtful_fits() {
        let f = f.map_or("no fit".into(), |f| format!("{f:.4} Hz"));
        let _ = writeln!(
            s,
            "note: target {t}, mode {mode}: its own fit ({f}) is more than three half-power \
             bandwidths from the shared pole ({:.4} Hz): its own FRF shows the mode weakly (a \
             target near a node, or a spurious peak where the input is weak), so its own \
             frequency and damping are not to be trusted (its shape component, from the shared \
             pole, is)",
            pole.f_hz
        );
    }
    s
}

/// The 95 % intervals of the rows (modes.csv's interval columns), or why there are none.
fn intervals_text(s: &mut String, a: &TargetAnalysis) {
    let first = a
        .analyses
        .iter()
        .flatten()
        .find_map(|an| an.intervals.as_ref());
    let Some(i) = first else { return };
    if let Some(why) = i.none_why() {
        let _ = writeln!(s, "{why}");
        return;
    }
    let _ = writeln!(
        s,
        "\n95 % intervals (statistical: the jackknife over {} groups of the {} Welch segments; \
         f_hz and damping of the modal fit of the smoothed model, |FRF| at the picked line):",
        i.groups, i.segments
    );
    for m in &a.modes {
        let [f, z, amp] = m.intervals;
        let mut parts = Vec::new();
        if let (Some(v), Some((_, lo, hi))) = (m.f_hz, f) {
            parts.push(format!("f = {v:.4} Hz ({lo:.4} to {hi:.4})"));
        }
        if let (Some(v), Some((_, lo, hi))) = (m.damping, z) {
            parts.push(format!("damping = {v:.4} ({lo:.4} to {hi:.4})"));
        }
        if let Some((_, lo, hi)) = amp {
            parts.push(format!("|FRF| {:.4} to {:.4}", lo, hi));
        }
        let who = if m.target == 0 {
            "accelerometer".to_string()
        } else {
            format!("target {}", m.target)
        };
        if parts.is_empty() {
            let _ = writeln!(
                s,
                "  {who} mode {}: none (not resolved, or the fit failed)",
                m.mode
            );
        } else {
            let _ = writeln!(s, "  {who} mode {}: {}", m.mode, parts.join(", "));
        }
    }
}

/// Each band's shape in the report: its pole and every target's component (`-` for a failed
/// target), or that the fit failed.
fn shapes_text(s: &mut String, a: &TargetAnalysis, tracks: &Tracks) {
    for (b, shape) in a.shapes.iter().enumerate() {
        match shape {
            Some((pole, v)) => {
                let _ = write!(
                    s,
                    "\nmode {} shape (pole {:.4} Hz, damping {:.5}):",
                    b + 1,
                    pole.f_hz,
                    pole.damping
                );
                for (c, (x, _)) in v.iter().zip(&tracks.first) {
                    match c {
                        Some(c) => {
                            let _ = write!(s, " x {x:.0} px: {:+.4}{:+.4}i", c.re, c.im);
                        }
                        None => {
                            let _ = write!(s, " x {x:.0} px: -");
                        }
                    }
                }
            }
            None => {
                let _ = write!(s, "\nmode {}: no shape (the fit failed)", b + 1);
            }
        }
    }
}

/// The target co-located with the accelerometer against it, per mode: fitted frequency
/// difference and amplitude ratio (the chi indices of a vision system against a transducer).
fn colocated(s: &mut String, a: &TargetAnalysis, j: usize) {
    let _ = write!(
        s,
        "\nvision target {j} (co-located with the accelerometer, $accel_target) / accelerometer:"
    );
    if a.analyses[j - 1].is_err() {
        s.push_str(" not analysed\n");
        return;
    }
    let find = |t: usize, mode: usize| a.modes.iter().find(|m| m.target == t && m.mode == mode);
    for mode in 1..=a.shapes.len() {
        let (Some(acc), Some(vis)) = (find(0, mode), find(j, mode)) else {
            continue;
        };
        let df = match (vis.f_hz, acc.f_hz) {
            (Some(v), Some(c)) => format!("{:+.4} Hz", v - c),
            _ => "-".into(),
        };
        let _ = write!(
            s,
            "\n  mode {mode}: amplitude ratio {:.4}, frequency difference {df}",
            vis.amplitude / acc.amplitude
        );
    }
    s.push('\n');
}
