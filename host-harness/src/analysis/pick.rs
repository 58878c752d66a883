//! `pick` as one call: a recording's frames (evenly spaced through it) and an existing points
//! file into `pick.html` ([`crate::export::pick`]), the page where the points `track --points`
//! follows are chosen with the mouse.

use crate::export::pick::{pick_html, points_csv, PickPoint};
use crate::frames::GreyFrame;

/// The longest side of a frame as the page holds it, px: larger frames are shown scaled down
/// (clicks still give full-resolution pixels), so that 50 frames of a 6000 x 6000 camera make a
/// page of tens, not hundreds, of megabytes.
pub const SHOWN_MAX_SIDE: u32 = 2048;

/// What `pick` is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct PickRequest {
    /// `--frames` as given.
    pub frames: String,
    /// The frame rate, when the recording needs one to be read (a video; without it a video
    /// is read at its container's own rate).
    pub fps: Option<f64>,
    /// `--retime`: `fps` retimes a video's container rate (slow motion).
    pub retime: bool,
    /// Frames A..B only (a camera file with a damaged time stamp at one end).
    pub frame_range: Option<crate::frames::FrameRange>,
    /// Points to show at the start.
    pub points: Option<std::path::PathBuf>,
    /// Frames on the page's slider (1 to 50).
    pub shown: usize,
    /// The page.
    pub out: std::path::PathBuf,
    /// Replace an existing file.
    pub force: bool,
    /// Points chosen from a region of the first frame ([`crate::analysis::region`]), numbered
    /// after `points`, and the points file they are written to with `points`.
    pub region: Option<(crate::analysis::region::Selection, std::path::PathBuf)>,
}

/// A frame as the page shows it, with its label.
type ShownFrame = (String, crate::export::html::FrameImage);

/// Whether `path` begins as the pages [`run`] writes do (`--force` replaces only those).
fn is_pick_page(path: &std::path::Path) -> bool {
    use std::io::Read as _;
    let mut head = [0u8; 512];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut head))
        .unwrap_or(0);
    let head = String::from_utf8_lossy(&head[..n]);
    head.starts_with("<!DOCTYPE html>") && head.contains("<title>pick: ")
}

/// The rate the recording is read at: `--fps`, else the one its file states, else a video's
/// container's own (the page shows frames; their capture rate plays no part).
fn reading_rate(req: &PickRequest, source: &crate::frames::FrameSource) -> anyhow::Result<f64> {
    Ok(match (req.fps, source.recorded_rate()?, source.inner()) {
        (Some(f), _, _) => f,
        (None, Some(r), _) => r.0,
        // the page shows frames: a video's own container rate reads them as they are
        (None, None, crate::frames::FrameSource::Video { path, .. }) => {
            crate::frames::video::container_rate(path)
                .map_err(|e| e.into_anyhow())?
                .ok_or_else(|| {
                    crate::bad_input(format!(
                        "{}: its frames' times give no rate: give $fps",
                        req.frames
                    ))
                })?
        }
        // image files: the rate plays no part in reading them
        (None, None, _) => 1.0,
    })
}

/// Writes the page; returns a line saying what it holds.
pub fn run(req: &PickRequest) -> anyhow::Result<String> {
    if !(1..=50).contains(&req.shown) {
        return Err(crate::bad_input(format!(
            "$frames_shown {}: 1 to 50",
            req.shown
        )));
    }
    refuse_replacing(req)?;
    let points: Vec<PickPoint> = match &req.points {
        Some(p) => crate::analysis::points::read_points(p)?
            .into_iter()
            .map(|p| PickPoint {
                target: p.target,
                xy: p.xy,
                size: p.size,
                group: p.group,
            })
            .collect(),
        None => Vec::new(),
    };
    let source = crate::frames::open_frames(&req.frames, req.retime, req.frame_range)?.source;
    let (frames, full) = spread_frames(req, &source)?;
    let Some(first) = frames.first() else {
        return Err(crate::bad_input(format!("{}: no frames", req.frames)));
    };
    windows_inside(&points, (first.1.width, first.1.height))?;
    let mut points = points;
    let mut text = String::new();
    let chosen = match (&req.region, full) {
        (Some((sel, path)), Some(full)) => {
            text.push_str(&add_region_points(sel, &full, &mut points)?);
            Some((path, points_csv(&points)))
        }
        _ => None,
    };
    let html = pick_html(&format!("pick: {}", req.frames), &frames, &points);
    if let Some((path, csv)) = &chosen {
        crate::export::write_atomic(path, csv.as_bytes())?;
        text.push_str(&format!(
            "wrote {} ({} points for track --points)\n",
            path.display(),
            points.len()
        ));
    }
    crate::export::write_atomic(&req.out, html.as_bytes())?;
    text.push_str(&format!(
        "wrote {} ({} frames, {} points, {:.1} MB): open it in a browser, click to add windows, \
         save points.csv for track --points\n",
        req.out.display(),
        frames.len(),
        points.len(),
        html.len() as f64 / 1e6
    ));
    Ok(text)
}

/// The points `sel` finds in the first frame `full`, numbered after `points` and added to
/// them; returns the report's line on what was kept and left out.
fn add_region_points(
    sel: &crate::analysis::region::Selection,
    full: &GreyFrame,
    points: &mut Vec<PickPoint>,
) -> anyhow::Result<String> {
    let found = crate::analysis::region::select(full, sel)?;
    let kept = found.kept();
    if kept.is_empty() {
        return Err(crate::bad_input(format!(
            "$region: none of its {} places has the texture $min_texture asks for ({})",
            found.candidates.len(),
            found.describe(sel)
        )));
    }
    let size = u32::try_from(sel.window).unwrap_or(u32::MAX);
    let first_new = points.iter().map(|p| p.target).max().unwrap_or(0) + 1;
    points.extend(kept.iter().enumerate().map(|(i, &xy)| PickPoint {
        target: first_new + i,
        xy,
        size: (size, size),
        group: None,
    }));
    Ok(format!("{}\n", found.describe(sel)))
}

/// `--out` is never an input, never inside the frames' folder, and replaced (with `--force`)
/// only when it is a page `pick` wrote.
fn refuse_replacing(req: &PickRequest) -> anyhow::Result<()> {
    let frames_path = std::path::Path::new(&req.frames);
    let mut inputs = vec![frames_path];
    inputs.extend(req.points.as_deref());
    crate::outdir::refuse_output_file_among_inputs(&req.out, &inputs)?;
    if let Some((_, path)) = &req.region {
        crate::outdir::refuse_output_file_among_inputs(path, &inputs)?;
        if path == &req.out {
            return Err(crate::bad_input(format!(
                "$points_out {}: the page's own $out",
                path.display()
            )));
        }
        if path.exists() && !req.force {
            return Err(crate::bad_input(format!(
                "{} exists: $force replaces it",
                path.display()
            )));
        }
    }
    if req.out.exists() && !req.force {
        return Err(crate::bad_input(format!(
            "{} exists: $force replaces it",
            req.out.display()
        )));
    }
    if req.out.exists() && !is_pick_page(&req.out) {
        // a frame, a camera's raw data beside its header, anyone's file: never replaced
        return Err(crate::bad_input(format!(
            "$out {}: exists and is not a page `pick` wrote: not replaced even with $force; \
             choose another $out",
            req.out.display()
        )));
    }
    Ok(())
}

/// Up to `--frames-shown` frames spread evenly over the recording, each downscaled for the
/// page, with their labels.
fn spread_frames(
    req: &PickRequest,
    source: &crate::frames::FrameSource,
) -> anyhow::Result<(Vec<ShownFrame>, Option<GreyFrame>)> {
    let fps = reading_rate(req, source)?;
    let count = source.count(fps)?;
    let step = count.map_or(1, |n| (n / req.shown).max(1));
    let mut frames = Vec::new();
    // the first frame at full resolution, for the texture of a region's points (asked only
    // with a region)
    let mut first = None;
    source.decode_while(fps, |k, label, frame| {
        if k == 0 && req.region.is_some() {
            first = Some(frame.clone());
        }
        if k.is_multiple_of(step) {
            frames.push((label, frame.to_image_within(SHOWN_MAX_SIDE)?));
        }
        Ok(frames.len() < req.shown)
    })?;
    Ok((frames, first))
}

/// Every given window lies inside the `(width, height)` frame.
fn windows_inside(points: &[PickPoint], (width, height): (u32, u32)) -> anyhow::Result<()> {
    let (w, h) = (f64::from(width), f64::from(height));
    for p in points {
        let (hw, hh) = (
            (f64::from(p.size.0) - 1.0) / 2.0,
            (f64::from(p.size.1) - 1.0) / 2.0,
        );
        if p.xy.0 - hw < -0.5
            || p.xy.1 - hh < -0.5
            || p.xy.0 + hw > w - 0.5
            || p.xy.1 + hh > h - 0.5
        {
            return Err(crate::bad_input(format!(
                "target {}: its window leaves the {w} x {h} frame",
                p.target
            )));
        }
    }
    Ok(())
}
