//! `host-harness centroid`: thresholded centroid of the target in PNG/TIFF frames, through
//! `firmware_core::centroid` (the single-target whole-frame path the firmware runs).
//!
//! Output: CSV on stdout, `file,cx,cy,pixels,flags`, one row per frame that could be read.
//! A file that cannot be read, is not 8- or 16-bit grey, or does not hold the ROI gets an error
//! naming it on stderr; the other files are still processed, and the command exits with code 2
//! at the end.

use crate::bad_input;
use firmware_core::centroid::{centroid, Centroid, CentroidConfig, Frame, Mode, Roi};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Weighting of the pixels above the threshold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ModeArg {
    /// Weight 1 for every pixel with value > T (the paper's method).
    Binary,
    /// Weight value - T for every pixel with value > T.
    Weighted,
}

/// Arguments of `host-harness centroid`.
#[derive(Debug, clap::Args)]
#[command(after_long_help = FLAGS_HELP, after_help = FLAGS_HELP)]
pub struct Args {
    /// Threshold T in grey levels (0-65535): a pixel counts when its value is > T. For 8-bit
    /// frames a T of 255 or more selects nothing.
    #[arg(long, value_name = "T")]
    pub threshold: u16,
    /// Pixel weighting.
    #[arg(long, value_enum, default_value_t = ModeArg::Binary)]
    pub mode: ModeArg,
    /// Region of interest X,Y,W,H in pixels (X, Y of the top-left pixel, from the top-left of
    /// the frame; W, H >= 1); coordinates stay those of the full frame. Must lie inside every
    /// frame.
    #[arg(long, value_name = "X,Y,W,H", value_parser = parse_roi)]
    pub roi: Option<Roi>,
    /// Grey level at or above which a pixel counts as saturated (default: 255 for 8-bit, 65535
    /// for 16-bit frames); must be above T.
    #[arg(long, value_name = "LEVEL")]
    pub saturation: Option<u16>,
    /// PNG or TIFF frames, 8- or 16-bit grey.
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

/// Parses `X,Y,W,H`.
fn parse_roi(s: &str) -> Result<Roi, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let [x, y, w, h] = parts.as_slice() else {
        return Err(format!(
            "expected X,Y,W,H (four integers), got {} value(s)",
            parts.len()
        ));
    };
    let num = |name: &str, v: &str| {
        v.parse::<u32>()
            .map_err(|e| format!("{name} = {v:?} is not a non-negative integer: {e}"))
    };
    let roi = Roi {
        x: num("X", x)?,
        y: num("Y", y)?,
        width: num("W", w)?,
        height: num("H", h)?,
    };
    CentroidConfig::binary(0)
        .with_roi(roi)
        .validate()
        .map_err(|e| e.to_string())?;
    Ok(roi)
}

/// Centroid of one grey frame file; errors name the file.
pub fn centroid_file(config: &CentroidConfig, path: &Path) -> anyhow::Result<Centroid> {
    let name = path.display();
    let img = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| bad_input(format!("{name}: cannot open: {e}")))?
        .decode()
        .map_err(|e| bad_input(format!("{name}: cannot decode as PNG or TIFF: {e}")))?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let result = match &img {
        image::DynamicImage::ImageLuma8(b) => {
            Frame::new(b.as_raw(), w, h, w).and_then(|f| centroid(config, &f))
        }
        image::DynamicImage::ImageLuma16(b) => {
            Frame::new(b.as_raw(), w, h, w).and_then(|f| centroid(config, &f))
        }
        other => {
            return Err(bad_input(format!(
                "{name}: not a grey image (colour type {:?}); centroid needs 8- or 16-bit grey",
                other.color()
            )))
        }
    };
    result.map_err(|e| bad_input(format!("{name} ({w} x {h} pixels): {e}")))
}

/// One CSV row: `file,cx,cy,pixels,flags` (cx, cy empty when there is no centroid).
fn row(file: &str, c: &Centroid) -> [String; 5] {
    let (cx, cy) = match c.position() {
        Some((x, y)) => (x.to_string(), y.to_string()),
        None => (String::new(), String::new()),
    };
    [
        file.to_string(),
        cx,
        cy,
        c.pixels().to_string(),
        c.flags.bits().to_string(),
    ]
}

/// Runs `host-harness centroid`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let mode = match args.mode {
        ModeArg::Binary => Mode::Binary,
        ModeArg::Weighted => Mode::Weighted,
    };
    let config = CentroidConfig {
        threshold: args.threshold,
        mode,
        roi: args.roi,
        saturation: args.saturation,
    }
    .validate()
    .map_err(|e| bad_input(format!("invalid settings: {e}")))?;
    let stdout = std::io::stdout();
    let mut out = csv::Writer::from_writer(stdout.lock());
    out.write_record(["file", "cx", "cy", "pixels", "flags"])?;
    out.flush()?;
    let mut failed = 0usize;
    let (mut empty, mut flagged) = (0usize, 0usize);
    for path in &args.files {
        match centroid_file(&config, path) {
            Ok(c) => {
                out.write_record(row(&path.to_string_lossy(), &c))?;
                out.flush()?;
                empty += usize::from(c.position().is_none());
                flagged += usize::from(!c.flags.is_clear());
            }
            Err(e) => {
                failed += 1;
                out.flush()?;
                eprintln!("error: {e:#}");
            }
        }
    }
    drop(out);
    let total = args.files.len();
    eprintln!(
        "centroid: {} of {total} file(s) measured ({empty} without centroid, {flagged} flagged), \
         {failed} failed",
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
