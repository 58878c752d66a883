//! `analyze`'s magnified videos (output-only, from frames): for each mode, the first frame
//! moving in that mode alone ([`vibcam_track::magnify`]), the point moving most by
//! `$magnify_px`, one period in [`FRAMES_PER_PERIOD`] frames played at [`VIDEO_FPS`], written as
//! WebM (VP9) by the `ffmpeg` program into the output and played on `report.html`; beside it
//! the mode's displacement field over the frame ([`field_svg`]: a colour map, arrows at the
//! points).

use super::{Method, OmaMode, OmaResult};
use std::path::{Path, PathBuf};
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

/// A video per shown mode written into `dir` (the staged output, or Python's folder): the
/// page's videos (label, source: the file embedded or its name), the report's lines (what was
/// written, or why nothing) and the files written.
pub fn write_videos(
    dir: &Path,
    r: &OmaResult,
    points: &[Option<(f64, f64)>],
    m: &Magnify,
) -> (Vec<crate::export::html::Video>, String, Vec<PathBuf>) {
    let modes = shown(r);
    if m.px <= 0.0 || modes.is_empty() {
        return (Vec::new(), String::new(), Vec::new());
    }
    let Some(points) = points.iter().copied().collect::<Option<Vec<_>>>() else {
        return (
            Vec::new(),
            "magnified videos: none (a target without a position in the first frame)\n".into(),
            Vec::new(),
        );
    };
    let mut files = Vec::new();
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
        let figure = field_svg(&reference, &field, (&local, &mode.shape), u).unwrap_or_default();
        match encode(&dir.join(&name), &reference, &field, (m.px, u)) {
            Ok(bytes) => {
                files.push(dir.join(&name));
                text.push_str(&format!(
                    "  {name}: mode {} at {:.4} Hz\n",
                    mode.mode, mode.f_hz
                ));
                videos.push(page_video(mode, m.px, (&name, &bytes), figure));
            }
            Err(e) => {
                let _ = std::fs::remove_file(dir.join(&name));
                text.push_str(&format!("  no {name}: {e:#}\n"));
            }
        }
    }
    (videos, text, files)
}

/// The page's video of `mode` (the file `name` of `bytes`: embedded when at most
/// [`EMBED_BYTES`], else linked) with its field's figure.
fn page_video(
    mode: &OmaMode,
    px: f64,
    (name, bytes): (&str, &[u8]),
    figure: String,
) -> crate::export::html::Video {
    let src = if bytes.len() <= EMBED_BYTES {
        format!(
            "data:video/webm;base64,{}",
            crate::export::html::base64(bytes)
        )
    } else {
        name.to_string()
    };
    crate::export::html::Video {
        label: format!(
            "{} mode {}, {:.3} Hz, magnified to {px} px",
            mode.method.name(),
            mode.mode,
            mode.f_hz
        ),
        src,
        figure,
    }
}

/// Encodes one period of a field's motion into `path`; returns the file's bytes.
fn encode(
    path: &Path,
    (w, h, reference): &(usize, usize, Vec<f32>),
    field: &magnify::Field,
    motion: (f64, (f64, f64)),
) -> anyhow::Result<Vec<u8>> {
    let mut video =
        vibcam_readers::frames::video::Ffv1Writer::create_webm(path, *w, *h, VIDEO_FPS, 10)
            .map_err(|e| e.into_anyhow())?;
    for n in 0..FRAMES_PER_PERIOD {
        let f = magnify::frame(reference, field, motion, (n, FRAMES_PER_PERIOD));
        video.write_frame(&f).map_err(|e| e.into_anyhow())?;
    }
    video.finish().map_err(|e| e.into_anyhow())?;
    Ok(std::fs::read(path)?)
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
    // the crop's pixels only, grey levels as f32 (16 bits scaled by the frame's largest)
    let index = |x: usize, y: usize| y.min(fh - 1) * fw + x.min(fw - 1);
    let mut px = Vec::with_capacity(w * h);
    match frame {
        GreyFrame::U8 { data, .. } => {
            for y in ay..ay + h {
                px.extend((ax..ax + w).map(|x| f32::from(data[index(x, y)])));
            }
        }
        GreyFrame::U16 { data, .. } => {
            let top = f32::from(data.iter().copied().max().unwrap_or(0).max(1));
            for y in ay..ay + h {
                px.extend((ax..ax + w).map(|x| f32::from(data[index(x, y)]) * 255.0 / top));
            }
        }
    }
    ((ax, ay, w, h), (w, h, px))
}

/// The mode's displacement field over the frame as an SVG: the frame in grey, the field's real
/// part (the shape normalised to a largest component of 1, so real there) as a colour map, red
/// along the motion's direction and blue against it, faded where it is small; an arrow at up to
/// [`ARROWS`] of the points, its length the point's real part times an eighteenth of the
/// picture's longer side.
pub fn field_svg(
    (w, h, reference): &(usize, usize, Vec<f32>),
    field: &magnify::Field,
    (points, shape): (&[(f64, f64)], &[num_complex::Complex64]),
    u: (f64, f64),
) -> anyhow::Result<String> {
    use std::fmt::Write as _;
    let mut rgb = image::RgbImage::new(*w as u32, *h as u32);
    for (i, px) in rgb.pixels_mut().enumerate() {
        let g = f64::from(reference[i]);
        let v = field.d[i].re.clamp(-1.0, 1.0);
        // diverging: white at 0, red at +1, blue at -1
        let c = if v >= 0.0 {
            [255.0, 255.0 * (1.0 - v), 255.0 * (1.0 - v)]
        } else {
            [255.0 * (1.0 + v), 255.0 * (1.0 + v), 255.0]
        };
        let a = 0.6 * (4.0 * field.d[i].norm()).min(1.0);
        *px = image::Rgb(c.map(|c| (g * (1.0 - a) + c * a).round().clamp(0.0, 255.0) as u8));
    }
    let mut png = std::io::Cursor::new(Vec::new());
    rgb.write_to(&mut png, image::ImageFormat::Png)?;
    let mut s = format!(
        "<svg class=\"field\" viewBox=\"0 0 {w} {h}\" width=\"{w}\" height=\"{h}\" \
         xmlns=\"http://www.w3.org/2000/svg\"><defs><marker id=\"head\" viewBox=\"0 0 6 6\" \
         refX=\"5\" refY=\"3\" markerWidth=\"4\" markerHeight=\"4\" orient=\"auto\">\
         <path d=\"M0,0 L6,3 L0,6 z\" fill=\"#111\"/></marker></defs><image width=\"{w}\" \
         height=\"{h}\" href=\"data:image/png;base64,{}\"/>",
        crate::export::html::base64(&png.into_inner())
    );
    let length = (*w).max(*h) as f64 / 18.0;
    for j in arrow_points(points, (*w, *h)) {
        let (p, v) = (points[j], shape[j]);
        let d = v.re * length;
        if d.abs() < 0.5 {
            continue;
        }
        let _ = write!(
            s,
            "<line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"#111\" \
             stroke-width=\"1\" marker-end=\"url(#head)\"/>",
            p.0 + 0.5,
            p.1 + 0.5,
            p.0 + 0.5 + d * u.0,
            p.1 + 0.5 + d * u.1
        );
    }
    s.push_str("</svg>");
    Ok(s)
}

/// The most arrows a field's figure draws.
pub const ARROWS: usize = 48;

/// The points the arrows stand at: the picture's longer side cut into [`ARROWS`] bins, in each
/// the point nearest the points' middle across it.
fn arrow_points(points: &[(f64, f64)], (w, h): (usize, usize)) -> Vec<usize> {
    let along = |p: &(f64, f64)| if w >= h { (p.0, p.1) } else { (p.1, p.0) };
    let (lo, hi) = points.iter().fold((f64::MAX, f64::MIN), |(l, h), p| {
        (l.min(along(p).1), h.max(along(p).1))
    });
    let middle = (lo + hi) / 2.0;
    let side = w.max(h) as f64;
    let mut best: Vec<Option<(usize, f64)>> = vec![None; ARROWS];
    for (j, p) in points.iter().enumerate() {
        let (a, b) = along(p);
        let bin = ((a / side * ARROWS as f64) as usize).min(ARROWS - 1);
        let off = (b - middle).abs();
        if best[bin].is_none_or(|(_, o)| off < o) {
            best[bin] = Some((j, off));
        }
    }
    best.into_iter().flatten().map(|(j, _)| j).collect()
}
