//! `host-harness centroid`: thresholded centroid of the target in PNG/TIFF frames, through
//! `firmware_core::centroid` (the single-target whole-frame path the firmware runs).
//!
//! Output: CSV on stdout, `file,cx,cy,pixels,flags`, one row per frame that could be read.
//! A file that cannot be read, is not 8- or 16-bit grey, or does not hold the ROI gets an error
//! naming it on stderr; the other files are still processed, and the command exits with code 2
//! at the end.

use super::args::CentroidArgs;
use crate::analysis::frames::load_frame;
use crate::bad_input;
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

/// Centroid of one grey frame file (its first page); errors name the file.
pub fn centroid_file(config: &CentroidConfig, path: &Path) -> anyhow::Result<Centroid> {
    load_frame(path)?.centroid(config, &path.display().to_string())
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
    let config = args.centroid.config(args.saturation)?;
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
