//! `host-harness centroid`: thresholded centroid of the target in PNG/TIFF/JPEG frames and
//! Photron and Phantom recordings, through `firmware_core::centroid` (the single-target
//! whole-frame path the firmware runs).
//!
//! Output: CSV on stdout, `file,cx,cy,pixels,flags`, one row per frame that could be read;
//! every page of a multi-page TIFF and every frame of a Photron recording (named by its
//! `.cih`/`.cihx`) or a Phantom `.cine` is measured, each a row named `file#N` (1-based).
//! Colour frames are read as their BT.601 luma (0.299 R + 0.587 G + 0.114 B, rounded; alpha
//! ignored).
//! A file (or page) that cannot be read, is not 8- or 16-bit, or does not hold the ROI gets
//! an error naming it on stderr; the other files are still processed, and the command exits with
//! code 2 at the end.

use super::args::CentroidArgs;
use crate::bad_input;
use crate::export::signals;
use crate::frames::FrameRange;
use crate::frames::{for_each_tiff_page, load_frame};
use firmware_core::centroid::{Centroid, CentroidConfig};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `host-harness centroid`.
#[derive(Debug, clap::Args)]
#[command(after_long_help = FLAGS_HELP, after_help = FLAGS_HELP)]
pub struct Args {
    /// Centroid settings.
    #[command(flatten)]
    pub centroid: CentroidArgs,
    /// With a video file: its frame rate, Hz (the timestamps are checked against it).
    #[arg(long, value_name = "HZ", value_parser = super::args::parse_rate)]
    pub fps: Option<f64>,
    /// `$retime`.
    #[arg(long, requires = "fps", help = super::args::help("retime"))]
    pub retime: bool,
    /// Frames A..B of each recording only (a camera file, a video or a multi-page TIFF),
    /// 1-based and inclusive, as the rows' `FILE#N` count them (`A..` to the end, `..B` from
    /// the start).
    #[arg(long, value_name = "A..B", value_parser = crate::frames::FrameRange::parse)]
    pub frame_range: Option<crate::frames::FrameRange>,
    /// Grey level at or above which a pixel counts as saturated (default: 255 for 8-bit, 65535
    /// for 16-bit frames); must be above T.
    #[arg(long, value_name = "LEVEL")]
    pub saturation: Option<u16>,
    /// PNG, TIFF or JPEG frames (8- or 16-bit grey, or colour read as its BT.601 luma
    /// 0.299 R + 0.587 G + 0.114 B, rounded, alpha ignored), Photron recordings named by
    /// their .cih/.cihx, Phantom .cine files, or videos with --fps (one row per frame,
    /// FILE#N).
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
}

const FLAGS_HELP: &str = "\
Output (stdout): CSV with header file,cx,cy,pixels,flags
  cx, cy  centroid in pixels; (0,0) is the centre of the top-left pixel, x right, y down;
          empty when no pixel is above the threshold
  pixels  number of pixels above the threshold
  flags   bit mask, 0 = clean result; the sum of
            1  empty      no pixel above the threshold (no centroid)
            2  border     the target touches the first/last row or column of the ROI (or of
                          the frame without --roi): the centroid is biased
            4  saturated  a target pixel is at or above the saturation level
            8  capacity   more targets than the capacity (multi-target only; never here)
           16  clipped    the frame is wider than 65536 pixels (never here: rejected)
Files that cannot be read or are not grey are reported on stderr; the others are still
processed and the exit code is then 2.";

/// Centroid of one grey frame file (its first page); errors name the file.
pub fn centroid_file(config: &CentroidConfig, path: &Path) -> anyhow::Result<Centroid> {
    load_frame(path)?.centroid(config, &path.display().to_string())
}

/// The centroids of every frame in `path`, each with its row label: the file name, or
/// `file#N` for page `N` of a TIFF of several pages. The pages measured before a page that
/// fails are returned with the error.
fn centroid_pages(
    config: &CentroidConfig,
    path: &Path,
    fps: Option<f64>,
    retime: bool,
    range: Option<FrameRange>,
) -> (Vec<(String, Centroid)>, Option<anyhow::Error>) {
    let name = path.to_string_lossy().into_owned();
    let is_tiff = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("tif") || e.eq_ignore_ascii_case("tiff"));
    if crate::frames::photron::is_header(path)
        || crate::frames::photron::is_mraw(path)
        || crate::frames::phantom::is_cine(path)
        || (is_tiff && range.is_some())
    {
        return recording_frames(config, &name, 1.0, retime, range);
    }
    if crate::frames::files::is_video(path) {
        return match fps {
            Some(fps) => recording_frames(config, &name, fps, retime, range),
            None => (
                Vec::new(),
                Some(bad_input(format!(
                    "{name}: a video needs --fps (its timestamps are checked against it)"
                ))),
            ),
        };
    }
    if let (false, Some(r)) = (is_tiff, range) {
        return (
            Vec::new(),
            Some(bad_input(format!(
                "--frame-range {}: {name} is one image (a range applies to a camera file, a \
                 video or a multi-page TIFF)",
                r.describe()
            ))),
        );
    }
    if !is_tiff {
        return match centroid_file(config, path) {
            Ok(c) => (vec![(name, c)], None),
            Err(e) => (Vec::new(), Some(e)),
        };
    }
    let mut pages = Vec::new();
    let result = for_each_tiff_page(path, |label, frame| {
        pages.push(frame.centroid(config, &label)?);
        Ok(())
    });
    let several = pages.len() > 1 || result.is_err();
    let rows = pages
        .into_iter()
        .enumerate()
        .map(|(i, c)| match several {
            true => (format!("{name}#{}", i + 1), c),
            false => (name.clone(), c),
        })
        .collect();
    (rows, result.err())
}

/// Every frame of a camera recording (Photron, Phantom) or a video (timestamps checked against
/// `fps`), labelled `file#N` from 1.
fn recording_frames(
    config: &CentroidConfig,
    name: &str,
    fps: f64,
    retime: bool,
    range: Option<FrameRange>,
) -> (Vec<(String, Centroid)>, Option<anyhow::Error>) {
    let mut rows = Vec::new();
    let first = range.map_or(1, |r| r.first);
    let result = crate::frames::open_frames(name, retime, range).and_then(|found| {
        found.source.for_each(fps, |label, frame| {
            rows.push((
                format!("{name}#{}", first + rows.len()),
                frame.centroid(config, &label)?,
            ));
            Ok(())
        })
    });
    (rows, result.err())
}

/// Runs `host-harness centroid`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let config = args.centroid.config(args.saturation)?;
    if let Some(p) = args
        .files
        .iter()
        .find(|p| args.retime && !crate::frames::files::is_video(p))
    {
        return Err(bad_input(format!(
            "--retime applies to a video file (its container's rate), not to {}",
            p.display()
        )));
    }
    let print = |bytes: Vec<u8>| super::stdout(&String::from_utf8_lossy(&bytes));
    print(signals::centroid_header())?;
    let mut failed = 0usize;
    let (mut empty, mut flagged) = (0usize, 0usize);
    let mut frames = 0usize;
    for path in &args.files {
        let (rows, error) = centroid_pages(&config, path, args.fps, args.retime, args.frame_range);
        for (label, c) in &rows {
            print(signals::centroid_row(label, c))?;
            empty += usize::from(c.position().is_none());
            flagged += usize::from(!c.flags.is_clear());
        }
        frames += rows.len();
        if let Some(e) = error {
            failed += 1;
            eprintln!(
                "error: {}",
                crate::setting::message(&e, crate::setting::Naming::Cli)
            );
        }
    }
    let total = args.files.len();
    eprintln!(
        "centroid: {frames} frame(s) of {} of {total} file(s) measured ({empty} without centroid, \
         {flagged} flagged), {failed} file(s) failed",
        total - failed
    );
    std::io::stderr().flush().ok();
    if failed > 0 {
        return Err(bad_input(format!(
            "{failed} of {total} file(s) could not be processed (see the errors above)"
        )));
    }
    Ok(())
}
