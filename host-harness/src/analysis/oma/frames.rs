//! `analyze` without an accelerometer: the frames' targets tracked as `analyze` tracks them
//! (`--targets K`, `--points`, or one target), their displacements (mm with a scale, else
//! pixels) analysed output-only ([`super::run`]), `displacement.csv` written beside the modes.

use super::input::Records;
use super::run::Output;
use super::{OmaResult, OmaSettings};
use crate::analysis::run::Outcome;
use crate::analysis::targets::Tracks;
use crate::analysis::track_run::Targets;
use crate::analysis::view::track_view;
use crate::chain::displacement::DisplacementSettings;
use crate::export::targets as export;
use crate::frames::FrameSource;
use firmware_core::centroid::CentroidConfig;
use std::path::PathBuf;

/// What `analyze` without `--accel` asks for.
#[derive(Debug, Clone)]
pub struct FramesRequest {
    /// The frames (as `--frames`).
    pub frames: String,
    /// `--retime`.
    pub retime: bool,
    /// Frames A..B only (`--frame-range`).
    pub frame_range: Option<crate::frames::FrameRange>,
    /// Frame rate, Hz.
    pub fps: f64,
    /// Centroid settings.
    pub centroid: CentroidConfig,
    /// Sign, axis, lost frames; `mm_per_px` 1 when no scale was given (pixels).
    pub displacement: DisplacementSettings,
    /// Whether a scale was given (`mm`), else the values are pixels.
    pub scaled: bool,
    /// The targets and how they are followed.
    pub targets: Targets,
    /// The points file (an input).
    pub points_file: Option<PathBuf>,
    /// The Welch flags, resolved against the record when it is read.
    pub welch: crate::chain::frf::WelchSettings,
    /// Bands, Hz (empty: automatic peaks).
    pub bands: Vec<(f64, f64)>,
    /// Output directory and `--force`.
    pub out: PathBuf,
    /// `--force`.
    pub force: bool,
    /// Also print `report.pdf`.
    pub pdf: bool,
    /// `$magnify_px`: each mode's magnified video, 0 none.
    pub magnify_px: f64,
    /// `$geometry`: the structure's nodes and lines the page draws the shapes on (its path,
    /// its content; checked against the targets).
    pub geometry: Option<(PathBuf, vibcam_readers::geometry::Geometry)>,
    /// Notes on the frames' rate.
    pub notes: Vec<String>,
    /// Static references and the scale from the scene.
    pub view: crate::analysis::view::ViewSettings,
}

/// What the output-only analysis of frames found, before anything is written.
#[derive(Debug, Clone)]
pub struct Computed {
    /// Each target's centroid per frame.
    pub tracks: Tracks,
    /// The displacement records analysed (the targets kept) and why others were left out.
    pub records: Records,
    /// The analysis settings, resolved against the record.
    pub settings: OmaSettings,
    /// Modes, shapes, singular values, poles.
    pub result: OmaResult,
    /// Per target: its displacement (`None` when it was left out).
    pub displacement: Vec<Option<Vec<f64>>>,
    /// Per target and frame: lost (no position; filled in its displacement).
    pub lost: Vec<Vec<bool>>,
    /// The camera's view: the tracks as measured, its motion, the scale.
    pub viewed: crate::analysis::view::Viewed,
}

/// Tracks the targets of `req` in `source` and analyses their displacements output-only;
/// `req.out` and `req.force` play no part.
pub fn compute(req: &FramesRequest, source: &FrameSource) -> anyhow::Result<Computed> {
    let along_x = req.displacement.axis == crate::analysis::Axis::X;
    let viewed = track_view(
        source,
        req.fps,
        &req.centroid,
        &req.targets,
        &req.view,
        along_x,
    )?;
    let tracks = viewed.tracks.clone();
    let (records, mm, lost) = records_of(req, &viewed)?;
    let settings = settings(req, &records.channels, &viewed)?;
    let mut result = super::analyze(&records.channels, &settings)?;
    if let Some(sc) = &viewed.scales {
        let u: Vec<f64> = records
            .targets
            .iter()
            .map(|(t, _)| sc.per_target.get(t - 1).map_or(0.0, |p| p.1))
            .collect();
        if super::uncertainty::fold_scale(&mut result.modes, &u) {
            result.notes.push(
                "the scale's standard uncertainty (each target's, above) is folded into the \
                 amplitude and shape-magnitude intervals, taken as fully correlated between \
                 the targets: the amplitude (a power) gets twice the shape-weighted mean"
                    .to_string(),
            );
        }
    }
    Ok(Computed {
        tracks,
        records,
        settings,
        result,
        displacement: mm,
        lost,
        viewed,
    })
}

/// Each target's displacement as a record of the analysis, or why it was left out; with each
/// target's displacement (`None` left out) and lost frames. No target left: an error naming
/// why each was left out.
#[allow(clippy::type_complexity)]
fn records_of(
    req: &FramesRequest,
    viewed: &crate::analysis::view::Viewed,
) -> anyhow::Result<(Records, Vec<Option<Vec<f64>>>, Vec<Vec<bool>>)> {
    let tracks = &viewed.tracks;
    let mut records = Records {
        fs_hz: req.fps,
        unit: if req.scaled { "mm" } else { "px" }.to_string(),
        targets: Vec::new(),
        channels: Vec::new(),
        filled: Vec::new(),
        left_out: Vec::new(),
    };
    let mut mm: Vec<Option<Vec<f64>>> = Vec::new();
    let mut lost: Vec<Vec<bool>> = Vec::new();
    for (t, c) in tracks.centroids.iter().enumerate() {
        let d = match viewed.displacement(t, &req.displacement) {
            Ok(d) => d,
            Err(e) => {
                records.left_out.push((t + 1, format!("{e:#}")));
                mm.push(None);
                lost.push(c.iter().map(|c| c.position().is_none()).collect());
                continue;
            }
        };
        lost.push(d.lost.clone());
        if d.failed() {
            records.left_out.push((
                t + 1,
                format!(
                    "{} of {} frames lost (more than {:.0} %)",
                    d.lost_count,
                    d.mm.len(),
                    100.0 * crate::analysis::MAX_LOST_FRACTION
                ),
            ));
            mm.push(None);
            continue;
        }
        mm.push(Some(d.mm.clone()));
        records.targets.push((t + 1, tracks.first.get(t).copied()));
        records.channels.push(d.mm);
        records.filled.push(d.lost_count);
    }
    if records.channels.is_empty() {
        let why: Vec<String> = records
            .left_out
            .iter()
            .map(|(t, w)| format!("target {t}: {w}"))
            .collect();
        return Err(crate::bad_input(format!(
            "no target could be analysed ({})",
            why.join("; ")
        )));
    }
    Ok((records, mm, lost))
}

/// The lines the page draws the shapes with: on every target (`$geometry`'s, or the groups
/// tracking followed), then on the targets kept (the shapes' points).
pub fn wire(req: &FramesRequest, c: &Computed) -> anyhow::Result<crate::export::wire::Wire> {
    let kept: Vec<usize> = c.records.targets.iter().map(|t| t.0 - 1).collect();
    let all = crate::analysis::track_run::wire(
        req.geometry.as_ref(),
        c.tracks.first.len(),
        c.viewed.windows.as_ref(),
    )?;
    Ok(all.keep(&kept))
}

/// Tracks the targets and runs the output-only analysis; writes its outputs.
pub fn run(req: &FramesRequest) -> anyhow::Result<Outcome> {
    let found = crate::frames::open_frames(&req.frames, req.retime, req.frame_range)?;
    let source = found.source.clone();
    let c = compute(req, &source)?;
    let n = c.records.channels[0].len();
    let rows: Vec<export::Track<'_>> = c
        .tracks
        .centroids
        .iter()
        .zip(&c.displacement)
        .zip(&c.lost)
        .enumerate()
        .map(|(t, ((cent, m), l))| export::Track {
            centroids: cent,
            mm: m.as_deref().filter(|_| req.scaled),
            lost: Some(l),
            raw: c.viewed.raw.as_ref().map(|r| r.centroids[t].as_slice()),
            evidence: c.tracks.evidence.get(t).map(Vec::as_slice),
        })
        .collect();
    let displacement = export::displacement_csv(
        &rows,
        req.fps,
        crate::frames::FrameRange::start_s(req.frame_range, req.fps),
    );
    let mut inputs = vec![PathBuf::from(&req.frames)];
    inputs.extend(req.points_file.clone());
    inputs.extend(req.geometry.as_ref().map(|g| g.0.clone()));
    let wire = wire(req, &c)?;
    let first = source.frame_at(req.fps, 0).ok().flatten().map(|(_, f)| f);
    let mut preamble = format!(
        "frames: {} ({} frames at {} fps), no accelerometer: output-only analysis\n",
        req.frames, n, req.fps
    );
    for note in &req.notes {
        preamble.push_str(&format!("note: {note}\n"));
    }
    preamble.push_str(
        &c.viewed
            .describe(req.displacement.axis == crate::analysis::Axis::X),
    );
    super::run::write(
        &c.records,
        &c.settings,
        &c.result,
        &Output {
            out: &req.out,
            force: req.force,
            pdf: req.pdf,
            command: "analyze",
            inputs,
            plots: true,
            along_x: req.displacement.axis == crate::analysis::Axis::X,
            preamble,
            extra: vec![("displacement.csv".to_string(), displacement)],
            frame: first.as_ref().and_then(|f| f.to_image().ok()),
            view: Some((&c.viewed, req.fps)),
            scrub: crate::analysis::track_run::scrubber(&source, req.fps, &c.viewed),
            wire,
            magnify: first.filter(|_| req.magnify_px > 0.0).map(|frame| {
                super::magnified::Magnify {
                    px: req.magnify_px,
                    frame,
                    along_x: req.displacement.axis == crate::analysis::Axis::X,
                }
            }),
        },
    )
}

/// The analysis settings of the records of the frames.
fn settings(
    req: &FramesRequest,
    channels: &[Vec<f64>],
    viewed: &crate::analysis::view::Viewed,
) -> anyhow::Result<OmaSettings> {
    let mut s = super::segment_settings(req.fps, channels, &req.welch, "the record of the frames")?;
    let n = channels.first().map_or(0, Vec::len);
    s.bands = req.bands.clone();
    // `auto`: Lucas-Kanade when it followed every target (no target kept a threshold)
    let lk = match &req.targets {
        Targets::Points(_, crate::analysis::points::PointTracker::Lk { .. }) => true,
        Targets::Points(_, crate::analysis::points::PointTracker::Auto { .. }) => viewed
            .windows
            .as_ref()
            .is_some_and(|w| w.thresholds.iter().all(Option::is_none)),
        _ => false,
    };
    s.source = match (lk, req.centroid.mode) {
        (true, _) => super::RecordSource::Linear("Lucas-Kanade"),
        (false, firmware_core::centroid::Mode::Weighted) => {
            super::RecordSource::Linear("weighted centroid")
        }
        (false, firmware_core::centroid::Mode::Binary) => super::RecordSource::Blob,
    };
    if n < 4 * s.ssi.block_rows {
        s.ssi.block_rows = (n / 4).max(2);
    }
    Ok(s)
}
