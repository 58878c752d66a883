//! `analyze`'s magnified videos (output-only, from frames): for each mode, the first frame
//! moving in that mode alone ([`vibcam_track::magnify`]), the point moving most by
//! `$magnify_px`, one period in [`FRAMES_PER_PERIOD`] frames played at [`VIDEO_FPS`], written as
//! WebM (VP9) by the `ffmpeg` program into the output and played on `report.html`.

use super::{Method, OmaMode, OmaResult};
use crate::outdir::Staged;
use vibcam_readers::frames::GreyFrame;
use vibcam_track::magnify::{self, FRAMES_PER_PERIOD};

/// The videos' frame rate: one period in two seconds.
pub const VIDEO_FPS: f64 = 24.0;

/// A video embedded in the page when at most this large, bytes; a larger one is linked (the
/// file beside `report.html`).
pub const EMBED_BYTES: usize = 8 << 20;

/// What the videos are made of.
#[derive(Debug, Clone)]
pub struct Magnify {
    /// `$magnify_px`: the largest motion shown, px (0: no videos).
    pub px: f64,
    /// The first frame.
    pub frame: GreyFrame,
    /// The motion is along the image's x (else y, positive up).
    pub along_x: bool,
}

/// The modes the videos show: SSI-cov's, else those of the decay fit, pLSCF, EFDD or FDD
/// (the first method that found any).
pub fn shown(r: &OmaResult) -> Vec<&OmaMode> {
    [
        Method::Ssi,
        Method::Decay,
        Method::Plscf,
        Method::Efdd,
        Method::Fdd,
    ]
    .iter()
    .map(|&k| r.modes.iter().filter(|m| m.method == k).collect::<Vec<_>>())
    .find(|v| !v.is_empty())
    .unwrap_or_default()
}

/// Writes a video per shown mode into `out`; returns the page's videos (label, source: the
/// file embedded or its name) and the report's lines (what was written, or why nothing).
pub fn write_videos(
    out: &Staged,
    r: &OmaResult,
    points: &[Option<(f64, f64)>],
    m: &Magnify,
) -> (Vec<crate::export::html::Video>, String) {
    let modes = shown(r);
    if m.px <= 0.0 || modes.is_empty() {
        return (Vec::new(), String::new());
    }
    let Some(points) = points.iter().copied().collect::<Option<Vec<_>>>() else {
        return (
            Vec::new(),
            "magnified videos: none (a target without a position in the first frame)\n".into(),
        );
    };
    let (crop, reference) = cropped(&m.frame, &points);
    let local: Vec<(f64, f64)> = points
        .iter()
        .map(|p| (p.0 - crop.0 as f64, p.1 - crop.1 as f64))
        .collect();
    let spread = magnify::spread_px(&local);
    let u = if m.along_x { (1.0, 0.0) } else { (0.0, -1.0) };
    let mut videos = Vec::new();
    let mut text = format!(
        "magnified videos: the first frame ({}x{} px around the points) moved by each {} mode \
         alone, the point moving most by {} px, one period in {FRAMES_PER_PERIOD} frames at \
         {VIDEO_FPS} fps; the motion between the points spread by Gaussian weights of {spread:.1} px, \
         held {:.1} px beyond them\n",
        crop.2,
        crop.3,
        modes[0].method.name(),
        m.px,
        m.px + 2.0 * spread
    );
    for mode in modes {
        let name = format!("magnified_{}_{}.webm", mode.method.name(), mode.mode);
        let field = magnify::field(
            (crop.2, crop.3),
            &local,
            &mode.shape,
            (spread, m.px + 2.0 * spread),
        );
        match encode(out, &name, &reference, &field, (m.px, u)) {
            Ok(bytes) => {
                let src = if bytes.len() <= EMBED_BYTES {
                    format!(
                        "data:video/webm;base64,{}",
                        crate::export::html::base64(&bytes)
                    )
                } else {
                    name.clone()
                };
                text.push_str(&format!(
                    "  {name}: mode {} at {:.4} Hz\n",
                    mode.mode, mode.f_hz
                ));
                videos.push(crate::export::html::Video {
                    label: format!(
                        "{} mode {}, {:.3} Hz, magnified to {} px",
                        mode.method.name(),
                        mode.mode,
                        mode.f_hz,
                        m.px
                    ),
                    src,
                });
            }
            Err(e) => {
                let _ = std::fs::remove_file(out.dir().join(&name));
                text.push_str(&format!("  no {name}: {e:#}\n"));
            }
        }
    }
    (videos, text)
}

/// Encodes one period of a field's motion into `out/name`; returns the file's bytes.
fn encode(
    out: &Staged,
    name: &str,
    (w, h, reference): &(usize, usize, Vec<f32>),
    field: &magnify::Field,
    motion: (f64, (f64, f64)),
) -> anyhow::Result<Vec<u8>> {
    let path = out.dir().join(name);
    let mut video =
        vibcam_readers::frames::video::Ffv1Writer::create_webm(&path, *w, *h, VIDEO_FPS, 10)
            .map_err(|e| e.into_anyhow())?;
    for n in 0..FRAMES_PER_PERIOD {
        let f = magnify::frame(reference, field, motion, (n, FRAMES_PER_PERIOD));
        video.write_frame(&f).map_err(|e| e.into_anyhow())?;
    }
    video.finish().map_err(|e| e.into_anyhow())?;
    Ok(std::fs::read(&path)?)
}

/// The part of `frame` the videos show: the points' bounding box with a margin of a quarter of
/// its larger side (at least 24 px), within the frame; its `(x, y, width, height)` and its
/// pixels `(width, height, grey)` (a 16-bit frame scaled so that its largest value is 255).
#[allow(clippy::type_complexity)]
fn cropped(
    frame: &GreyFrame,
    points: &[(f64, f64)],
) -> ((usize, usize, usize, usize), (usize, usize, Vec<f32>)) {
    let (fw, fh) = frame.dimensions();
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for p in points {
        (x0, y0, x1, y1) = (x0.min(p.0), y0.min(p.1), x1.max(p.0), y1.max(p.1));
    }
    let margin = (0.25 * (x1 - x0).max(y1 - y0)).max(24.0);
    let clamp = |v: f64, hi: usize| v.round().clamp(0.0, hi as f64) as usize;
    let (ax, ay) = (clamp(x0 - margin, fw), clamp(y0 - margin, fh));
    let (bx, by) = (clamp(x1 + margin + 1.0, fw), clamp(y1 + margin + 1.0, fh));
    let (w, h) = ((bx - ax).max(1), (by - ay).max(1));
    let grey: Vec<f32> = match frame {
        GreyFrame::U8 { data, .. } => data.iter().map(|&v| f32::from(v)).collect(),
        GreyFrame::U16 { data, .. } => {
            let top = f32::from(data.iter().copied().max().unwrap_or(0).max(1));
            data.iter().map(|&v| f32::from(v) * 255.0 / top).collect()
        }
    };
    let mut px = Vec::with_capacity(w * h);
    for y in ay..ay + h {
        let row = y.min(fh - 1) * fw;
        px.extend((ax..ax + w).map(|x| grey[row + x.min(fw - 1)]));
    }
    ((ax, ay, w, h), (w, h, px))
}
