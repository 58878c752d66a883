//! `analyze` as one library call: a checked [`Request`] (what `cli::analyze` builds from its
//! flags) -> the inputs loaded and checked -> the chain for one target or several
//! ([`super::targets_run`]) -> every output file staged and moved into place (`outdir`) -> the
//! report text, which the caller prints.

use super::compensate::{compensate, Compensated};
use super::imaging_share::{FrameNoise, Share, StillestFrame};
use super::Axis;
use crate::export::analysis as export;
use crate::frames::{centroid_source_seen, FrameSource};
use crate::outdir::Staged;

pub use super::request::{AccelInput, Outcome, Request, TargetsRequest};

/// Runs the analysis the request describes; see the module documentation.
pub fn run(req: &Request) -> anyhow::Result<Outcome> {
    // the output directory is checked before anything is read (a refusal costs nothing)
    let out = Staged::new(&req.out, req.force, "analyze", &req.inputs())?;
    let settings = &req.settings;
    let time_offset_s = settings.time_offset_s;
    // Inputs first (cheap checks before the frames are decoded).
    let a = &req.accel;
    let (base, tip) = super::load_accel(
        &a.path,
        a.fs,
        &a.input_col,
        &a.output_col,
        a.time_col.as_deref(),
    )?;
    let found = crate::frames::open_frames(&req.frames, req.retime, req.frame_range)?;
    let source = found.source.clone();
    let ignored = crate::frames::ignored_note(&found.ignored);
    if let Some(n) = &ignored {
        super::warn(n);
    }
    // remarks on the frames and their rate go into the report with the note on ignored files
    let mut notes: Vec<String> = req.notes.clone();
    notes.extend(source.note()?);
    notes.extend(ignored);
    let ignored = (!notes.is_empty()).then(|| notes.join("; "));
    let fps = settings.frame_rate_hz;
    if let Some(n) = source.count(fps)? {
        // The frame count is known before decoding: check the record lengths now.
        let n = super::usable_frames_or_error(n, fps, a.fs)?;
        super::align(n, fps, base.len(), a.fs, time_offset_s)?;
    }
    match &req.targets {
        Some(t) => {
            super::targets_run::run((req, out), t, &source, (&base, &tip), ignored.as_deref())
        }
        None => one_target((req, out), &source, (&base, &tip), ignored),
    }
}

/// The single-target analysis of `source` (see [`run`]): computed, then written.
fn one_target(
    (req, out): (&Request, Staged),
    source: &FrameSource,
    accel: (&[f64], &[f64]),
    ignored: Option<String>,
) -> anyhow::Result<Outcome> {
    let c = compute(req, source, accel, ignored)?;
    write(req, source, out, c)
}

/// What a one-target analysis computed, before anything is written.
struct Computed {
    centroids: Vec<firmware_core::centroid::Centroid>,
    inputs: Vec<(String, String)>,
    disp: super::Displacement,
    result: anyhow::Result<super::Analysis>,
    compensation: Option<Compensated>,
    /// The imaging's share (`None`: the stillest frame has no pixel above the threshold),
    /// when the analysis succeeded and the frames' noise could be measured.
    share: Option<Option<Share>>,
    twin: Option<super::twin::Twin>,
    figure: Option<crate::plots::Figure>,
}

/// The centroids, the displacement, the analysis, its compensation, the imaging share, the
/// twin runs and the FRF figure of a one-target analysis; no file written.
fn compute(
    req: &Request,
    source: &FrameSource,
    (base, tip): (&[f64], &[f64]),
    ignored: Option<String>,
) -> anyhow::Result<Computed> {
    let fps = req.settings.frame_rate_hz;
    // the frames' noise and the first frame (the imaging share) seen as they are centroided
    let mut noise = FrameNoise::new(req.centroid.roi, FrameNoise::stride_for(source.count(fps)?));
    let mut still = StillestFrame::new(req.displacement.axis);
    let (centroids, depth) = centroid_source_seen(source, fps, &req.centroid, &mut |f, c| {
        noise.add(f);
        still.add(f, c);
    })?;
    let template = still.frame();
    let depth_warning = depth.threshold_warning(req.centroid.threshold);
    if let Some(w) = &depth_warning {
        super::warn(w);
    }
    let disp = super::displacement_mm(&centroids, &req.displacement)?;
    let mut inputs = describe_inputs(req, source, centroids.len(), base.len());
    if let Some(n) = ignored {
        inputs.push(("note".into(), n));
    }
    inputs.push(("frame depth".into(), depth.describe()));
    if let Some(w) = depth_warning {
        inputs.push(("WARNING".into(), w));
    }
    let (result, compensation) = analyze_and_compensate(req, &disp, (base, tip))?;
    let (mut share, mut twin) = (None, None);
    if let (Ok(a), Some((index, first)), Some(noise)) = (&result, &template, noise.estimate()) {
        let rec = super::twin::Recording {
            analysis: a,
            disp: &disp,
            template: (*index, first),
            noise,
            accel: (base, tip),
        };
        (share, twin) = share_and_twin(req, rec)?;
    }
    let figure = match &result {
        Ok(a) => Some(frf_figure(a, fps)?),
        Err(_) => None,
    };
    Ok(Computed {
        centroids,
        inputs,
        disp,
        result,
        compensation,
        share,
        twin,
        figure,
    })
}

/// Writes every output of a computed one-target analysis into `out` and commits it (a failed
/// analysis never replaces an earlier output); returns the report.
fn write(req: &Request, source: &FrameSource, out: Staged, c: Computed) -> anyhow::Result<Outcome> {
    let fps = req.settings.frame_rate_hz;
    out.write(
        "displacement.csv",
        export::displacement_csv(
            &c.centroids,
            (&c.disp.mm, &c.disp.lost),
            fps,
            req.settings.time_offset_s,
        ),
    )?;
    let a = c.result.as_ref().ok();
    let failure = c.result.as_ref().err().map(|e| format!("{e:#}"));
    let mut report = super::report_text(&c.inputs, &c.disp, a, failure.as_deref());
    if let Some(comp) = &c.compensation {
        let p = out.write("compensation.csv", export::compensation_csv(&comp.rows()))?;
        report.push_str(&comp.report());
        report.push_str(&format!("  written: {}\n", p.display()));
    }
    match &c.share {
        Some(share) => report.push_str(&share.as_ref().map_or_else(
            || "\nimaging share: the stillest frame has no pixel above the threshold\n".into(),
            Share::report,
        )),
        None if req.twin.is_some() => report.push_str(
            "\ntwin: not run (the analysis failed, or the record has fewer than 3 frames to \
             measure the noise from)\n",
        ),
        None => {}
    }
    if let Some(twin) = &c.twin {
        let p = out.write("twin.csv", twin.csv())?;
        report.push_str(&twin.report());
        report.push_str(&format!("  written: {}\n", p.display()));
    }
    let figures = match (a, c.figure) {
        (Some(a), Some(figure)) => write_results(&out, req, a, figure, &mut report)?,
        _ => Vec::new(),
    };
    let mut report = super::write_report(&out, &report, req.pdf, |report| {
        one_target_page(req, source, &c.centroids, a, report, &figures)
    })?;
    if c.result.is_ok() {
        out.commit()?;
    } else if !out.commit_unless_replacing()? {
        report.push_str(&format!(
            "\nthe analysis failed: the earlier output in {} was left as it was\n",
            req.out.display()
        ));
    }
    Ok(Outcome {
        report,
        result: c.result.map(|_| ()),
    })
}

/// The imaging's share of |H1| (from the stillest frame and the frames' noise) and, with
/// `--twin`, the recording's twin runs.
fn share_and_twin(
    req: &Request,
    rec: super::twin::Recording<'_>,
) -> anyhow::Result<(Option<Option<Share>>, Option<super::twin::Twin>)> {
    let (d, fps) = (&req.displacement, req.settings.frame_rate_hz);
    let share = Share::of(
        rec.analysis,
        rec.template.1,
        rec.noise,
        &req.centroid,
        (d.axis, d.mm_per_px),
        fps,
    )?;
    let twin = match req.twin {
        Some(t) => {
            let bar = crate::study::runner::progress_bar(t.mine().len() as u64, true, "twin runs");
            let twin = super::twin::run(req, rec, t, &|| bar.inc(1))?;
            bar.finish_and_clear();
            Some(twin)
        }
        None => None,
    };
    Ok((Some(share), twin))
}

/// `report.html` of a one-target analysis: the first frame with the target and its lost
/// frames, the modes of both systems with their intervals, the FRF figure, the report.
fn one_target_page(
    req: &Request,
    source: &FrameSource,
    centroids: &[firmware_core::centroid::Centroid],
    a: Option<&super::Analysis>,
    text: &str,
    figures: &[crate::plots::Figure],
) -> crate::export::html::Report {
    use crate::export::html::{Marker, Report};
    let fps = req.settings.frame_rate_hz;
    let frame = source
        .frame_at(fps, 0)
        .ok()
        .flatten()
        .and_then(|(_, f)| f.to_image().ok());
    let lost = centroids.iter().filter(|c| c.position().is_none()).count();
    let markers: Vec<Marker> = centroids
        .iter()
        .find_map(|c| c.position())
        .map(|(x, y)| Marker {
            target: 1,
            xy: (f64::from(x), f64::from(y)),
            window: None,
            lost,
        })
        .into_iter()
        .collect();
    let iv = |i: Option<(f64, f64, f64)>, d: usize| {
        crate::export::html::range_cell(i.map(|(_, lo, hi)| (lo, hi)), d)
    };
    let rows: Vec<Vec<String>> = a
        .map(|a| {
            super::mode_rows(a)
                .iter()
                .map(|m| {
                    vec![
                        m.system.to_string(),
                        m.mode.to_string(),
                        format!("{:.4}", m.f_hz),
                        iv(m.intervals[0], 4),
                        format!("{:.4}", m.amplitude),
                        iv(m.intervals[2], 4),
                        m.damping.map_or(String::new(), |d| format!("{d:.5}")),
                        iv(m.intervals[1], 5),
                    ]
                })
                .collect()
        })
        .unwrap_or_default();
    let head = crate::export::html::header(&[
        "system",
        "mode",
        "f (Hz)",
        "95 % interval",
        "|H1|",
        "95 % interval",
        "damping",
        "95 % interval",
    ]);
    let figures = crate::plots::page_figures(figures);
    Report {
        title: format!("analyze: {}", req.frames),
        frame,
        markers,
        direction: (0.0, -1.0),
        figures,
        modes: (!rows.is_empty()).then_some((head, rows)),
        text: text.to_string(),
        ..Report::default()
    }
}

/// `frf.csv`, `modes.csv` and the plot of a successful analysis, named in the report.
fn write_results(
    out: &Staged,
    req: &Request,
    a: &super::Analysis,
    figure: crate::plots::Figure,
    report: &mut String,
) -> anyhow::Result<Vec<crate::plots::Figure>> {
    let (acc, vis) = (super::spectrum(&a.acc_frf), super::spectrum(&a.vis_frf));
    out.write("frf.csv", export::frf_csv(acc, vis))?;
    out.write("modes.csv", export::modes_csv(&super::mode_rows(a)))?;
    figure.write_staged(out)?;
    let mut files = vec!["frf.csv", "modes.csv", "displacement.csv", "report.txt"];
    let names = [
        format!("{}.png", figure.name),
        format!("{}.svg", figure.name),
    ];
    files.extend(names.iter().map(String::as_str));
    let files: Vec<String> = files
        .iter()
        .map(|f| req.out.join(f).display().to_string())
        .collect();
    report.push_str(&format!("\nwritten: {}\n", files.join(", ")));
    Ok(vec![figure])
}

/// The analysis (its failure is reported, not returned) and, with `--compensate-exposure`,
/// its vision H1 divided by the exposure's transfer (`analysis::compensate`).
fn analyze_and_compensate(
    req: &Request,
    disp: &super::Displacement,
    (base, tip): (&[f64], &[f64]),
) -> anyhow::Result<(anyhow::Result<super::Analysis>, Option<Compensated>)> {
    let settings = &req.settings;
    let mut result = super::analyze(disp, base, tip, settings);
    let compensation = match (&mut result, settings.exposure_s) {
        (Ok(a), Some(e)) if req.compensate_exposure => {
            Some(compensate(a, e, &settings.bands, req.binary)?)
        }
        _ => None,
    };
    if let Ok(a) = &mut result {
        let exposure = compensation.as_ref().map(|c| c.exposure_s);
        a.intervals = Some(super::frf_uncertainty::of_analysis(
            a,
            (base, tip),
            exposure,
            crate::analysis::oma::uncertainty::GROUPS,
        )?);
    }
    Ok((result, compensation))
}

/// `frf.png` / `frf.svg`: |H1| of both systems up to 1.1 x the highest band edge, at most the
/// camera's Nyquist frequency (the vision path has no content above it, and outside the
/// excitation band H1 is noise over noise).
fn frf_figure(a: &super::Analysis, fps: f64) -> anyhow::Result<crate::plots::Figure> {
    let top = a
        .acc_modes
        .iter()
        .map(|m| m.band_hz.1 * 1.1)
        .fold(0.0, f64::max);
    let top = if top > 0.0 {
        top.min(fps / 2.0)
    } else {
        fps / 2.0
    };
    let keep = a.acc_frf.freq_hz.iter().take_while(|&&f| f <= top).count();
    let freq = &a.acc_frf.freq_hz[..keep];
    let abs = |h: &[num_complex::Complex64]| h[..keep].iter().map(|v| v.norm()).collect();
    let acc: Vec<f64> = abs(&a.acc_frf.h1);
    let vis: Vec<f64> = abs(&a.vis_frf.h1);
    crate::plots::lines_figure(
        "frf",
        "H1 of the recording: accelerometer and vision",
        "|H1|",
        &[("accelerometer", freq, &acc), ("vision", freq, &vis)],
        crate::plots::Lines::Frf,
    )
}

/// The frames as the page names them: a folder's or pattern's files with the first and last,
/// or the camera file or video.
fn source_text(frames: &str, source: &FrameSource) -> String {
    match source {
        FrameSource::Files(f) => format!(
            "{} ({} files, {} .. {})",
            frames,
            f.len(),
            f.first()
                .map(|p| p.display().to_string())
                .unwrap_or_default(),
            f.last()
                .map(|p| p.display().to_string())
                .unwrap_or_default()
        ),
        other => other.describe(),
    }
}

/// The centroid's settings in one line: threshold, mode, region of interest.
fn centroid_text(c: &firmware_core::centroid::CentroidConfig) -> String {
    format!(
        "threshold {}, {:?}, ROI {}",
        c.threshold,
        c.mode,
        c.roi
            .map(|r| format!("{},{},{},{}", r.x, r.y, r.width, r.height))
            .unwrap_or_else(|| "none".into())
    )
}

/// The displacement's settings in one line: scale, axis, sign.
fn displacement_text(d: &super::DisplacementSettings) -> String {
    format!(
        "{} mm/px, axis {}{}",
        d.mm_per_px,
        match d.axis {
            Axis::X => "x (positive right)",
            Axis::Y => "y (positive up in the image)",
        },
        if d.invert { ", inverted" } else { "" }
    )
}

fn describe_inputs(
    req: &Request,
    source: &FrameSource,
    frames: usize,
    samples: usize,
) -> Vec<(String, String)> {
    let src = source_text(&req.frames, source);
    let (fps, a, d, c) = (
        req.settings.frame_rate_hz,
        &req.accel,
        &req.displacement,
        &req.centroid,
    );
    let mut v = vec![
        ("frames".to_string(), src),
        (
            "frame count".into(),
            format!("{frames} at {fps} fps ({:.4} s)", frames as f64 / fps),
        ),
        (
            "accelerometer".into(),
            format!(
                "{}: input `{}`, output `{}`, {samples} samples at {} Hz ({:.4} s)",
                a.path.display(),
                a.input_col,
                a.output_col,
                a.fs,
                samples as f64 / a.fs
            ),
        ),
        (
            "alignment".into(),
            format!(
                "first frame{} at {} s after the first sample",
                req.frame_range.map_or(String::new(), |r| format!(
                    " analysed (frame {} of the recording)",
                    r.first
                )),
                req.settings.time_offset_s
            ),
        ),
        ("centroid".into(), centroid_text(c)),
        ("displacement".into(), displacement_text(d)),
    ];
    if let Some(e) = req.exposure_ms {
        v.push(("exposure".into(), format!("{e} ms")));
    }
    v
}
