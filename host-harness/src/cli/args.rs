//! Argument types shared by several subcommands, so that a flag spelled the same way parses,
//! validates and is described in `--help` the same way everywhere: the Welch settings
//! ([`WelchArgs`]), the centroid settings ([`CentroidArgs`]), `--bands` and `--roi`.

use crate::chain::frf::WelchSettings;
use firmware_core::centroid::{CentroidConfig, Mode, Roi};
use firmware_core::spectrum::{Detrend, Window};

/// Segment window (periodic, as scipy's default).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum WindowArg {
    /// Periodic Hann.
    Hann,
    /// Periodic Hamming.
    Hamming,
    /// Rectangular (scipy's `boxcar`).
    Rect,
}

/// Segment detrending (`--detrend`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum DetrendArg {
    /// Subtract each segment's mean.
    Constant,
    /// No detrending.
    None,
}

/// The Welch estimator's flags (`frf`, `analyze`).
#[derive(Debug, Clone, clap::Args)]
pub struct WelchArgs {
    /// Segment window (periodic).
    #[arg(long, value_enum, default_value_t = WindowArg::Hann)]
    pub window: WindowArg,
    /// Samples per segment, 1..=65536 [default: `frf` min(256, record length) as scipy;
    /// `analyze` the whole record, one segment].
    #[arg(long, value_name = "N")]
    pub nperseg: Option<usize>,
    /// Samples shared by consecutive segments, < nperseg [default: nperseg / 2; 0 for one
    /// whole-record segment].
    #[arg(long, value_name = "N")]
    pub noverlap: Option<usize>,
    /// Transform length (zero padding), nperseg..=65536 [default: nperseg].
    #[arg(long, value_name = "N")]
    pub nfft: Option<usize>,
    /// Segment detrending.
    #[arg(long, value_enum, default_value_t = DetrendArg::Constant)]
    pub detrend: DetrendArg,
}

impl WelchArgs {
    /// The settings these flags describe (sizes resolved later against the record).
    pub fn settings(&self) -> WelchSettings {
        WelchSettings {
            window: match self.window {
                WindowArg::Hann => Window::Hann,
                WindowArg::Hamming => Window::Hamming,
                WindowArg::Rect => Window::Rect,
            },
            nperseg: self.nperseg,
            noverlap: self.noverlap,
            nfft: self.nfft,
            detrend: match self.detrend {
                DetrendArg::Constant => Detrend::Constant,
                DetrendArg::None => Detrend::None,
            },
        }
    }
}

/// Weighting of the pixels above the threshold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ModeArg {
    /// Chosen for you (the default): with --points, per target the blob centroid where a
    /// threshold separates the target in its first-frame window (a compact spot clearly
    /// brighter than the rest, not filling the window), Lucas-Kanade otherwise, the report
    /// saying which and why; without --points the binary centroid.
    Auto,
    /// Weight 1 for every pixel with value > T (the paper's method; also `blob`).
    #[value(alias = "blob")]
    Binary,
    /// Weight value - T for every pixel with value > T.
    Weighted,
    /// Lucas-Kanade (firmware-core's gradient tracker): each `--points` window of the first
    /// frame is its target's template; no threshold (`track` and `analyze` with `--points`).
    Lk,
}

impl ModeArg {
    /// The firmware's centroid mode (`lk` has none: binary stands in, unused).
    pub fn mode(self) -> Mode {
        match self {
            ModeArg::Auto | ModeArg::Binary | ModeArg::Lk => Mode::Binary,
            ModeArg::Weighted => Mode::Weighted,
        }
    }
}

/// The centroid's flags (`centroid`, `analyze`).
#[derive(Debug, Clone, clap::Args)]
pub struct CentroidArgs {
    /// Threshold T in grey levels (0-65535): a pixel counts when its value is > T. For 8-bit
    /// frames a T of 255 or more selects nothing. With --points also `auto`: Otsu's threshold
    /// of each window in the first frame.
    /// Needed without --points; with them `--tracker auto` (the default) and `binary` take
    /// Otsu's of each window when none is given (or the file's `threshold` column), and `lk`
    /// uses none.
    #[arg(long, value_name = "T|auto", value_parser = parse_threshold)]
    pub threshold: Option<ThresholdArg>,
    /// The tracker: `auto` (with --points each target's own choice of blob or Lucas-Kanade,
    /// said in the report; without, the binary centroid), pixel weighting of the centroid
    /// (`binary`, also called `blob`, or `weighted`), or `lk` (Lucas-Kanade in `--points`
    /// windows, `track` and `analyze` only); `--mode` is the same flag.
    #[arg(long, alias = "tracker", value_enum, default_value_t = ModeArg::Auto)]
    pub mode: ModeArg,
    /// Region of interest X,Y,W,H in pixels (X, Y of the top-left pixel, from the top-left of
    /// the frame; W, H >= 1); coordinates stay those of the full frame. Must lie inside every
    /// frame.
    #[arg(long, value_name = "X,Y,W,H", value_parser = parse_roi)]
    pub roi: Option<Roi>,
}

/// `--threshold`: a grey level, or `auto` (Otsu's threshold of each `--points` window).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ThresholdArg {
    /// A grey level.
    Level(u16),
    /// Otsu's threshold per window.
    Auto,
}

/// Parses `--threshold`: 0-65535 or `auto`.
pub fn parse_threshold(s: &str) -> Result<ThresholdArg, String> {
    if s.trim().eq_ignore_ascii_case("auto") {
        return Ok(ThresholdArg::Auto);
    }
    s.trim()
        .parse::<u16>()
        .map(ThresholdArg::Level)
        .map_err(|_| format!("`{s}`: a grey level 0-65535, or `auto` (with --points)"))
}

impl CentroidArgs {
    /// The tracking settings these flags give, with the targets' flags (checked by
    /// [`crate::jobs::Tracking::new`]).
    pub fn tracking(
        &self,
        points: Option<&std::path::Path>,
        targets: Option<usize>,
        gate_px: Option<f64>,
        search_px: Option<u16>,
    ) -> crate::jobs::TrackingInput {
        use crate::jobs::{PointsInput, Threshold, Tracker, TrackingInput};
        TrackingInput {
            threshold: self.threshold.map(|t| match t {
                ThresholdArg::Level(l) => Threshold::Level(l),
                ThresholdArg::Auto => Threshold::Auto,
            }),
            tracker: match self.mode {
                ModeArg::Auto => Tracker::Auto,
                ModeArg::Binary => Tracker::Blob,
                ModeArg::Weighted => Tracker::Weighted,
                ModeArg::Lk => Tracker::Lk,
            },
            roi: self.roi,
            points: points.map(|p| PointsInput::File(p.to_path_buf())),
            targets,
            gate_px,
            search_px,
        }
    }

    /// The firmware configuration of a single target (`centroid`), with an optional
    /// saturation level.
    pub fn config(&self, saturation: Option<u16>) -> anyhow::Result<CentroidConfig> {
        let t = self.tracking(None, None, None, None);
        let mut c = crate::jobs::tracking::centroid_config(t.threshold, t.tracker, t.roi, false)
            .map_err(crate::jobs::SpecError::into_anyhow)?;
        c.saturation = saturation;
        c.validate()
            .map_err(|e| crate::bad_input(format!("centroid settings: {e}")))
    }
}

/// Parses `--coverage P`: a probability strictly between 0 and 1 (study and merge).
pub fn parse_coverage(s: &str) -> Result<f64, String> {
    let p: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a number"))?;
    if p > 0.0 && p < 1.0 {
        Ok(p)
    } else {
        Err(format!(
            "{p} must lie strictly between 0 and 1 (0.95 for 95 %)"
        ))
    }
}

/// Parses `--roi X,Y,W,H`.
pub fn parse_roi(s: &str) -> Result<Roi, String> {
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

/// One band of `--bands`, with its text as given (its label in outputs).
#[derive(Debug, Clone, PartialEq)]
pub struct Band {
    /// The band as the user wrote it (trimmed).
    pub label: String,
    /// Lower edge, Hz.
    pub lo_hz: f64,
    /// Upper edge, Hz.
    pub hi_hz: f64,
}

/// Parsed `--bands LO-HI,LO-HI,...` (finite, `0 <= LO < HI`).
#[derive(Debug, Clone, PartialEq)]
pub struct Bands(pub Vec<Band>);

impl Bands {
    /// `(lo, hi)` pairs in Hz.
    pub fn pairs(&self) -> Vec<(f64, f64)> {
        self.0.iter().map(|b| (b.lo_hz, b.hi_hz)).collect()
    }
}

/// Parses `--bands`.
pub fn parse_bands(s: &str) -> Result<Bands, String> {
    let mut out = Vec::new();
    for part in s.split(',') {
        let label = part.trim();
        let (lo, hi) = label
            .split_once('-')
            .ok_or_else(|| format!("band `{label}`: expected LO-HI in Hz, e.g. 1.5-2.25"))?;
        let num = |v: &str| -> Result<f64, String> {
            let x: f64 = v
                .trim()
                .parse()
                .map_err(|_| format!("band `{label}`: `{}` is not a number", v.trim()))?;
            if !x.is_finite() || x < 0.0 {
                return Err(format!(
                    "band `{label}`: `{}` is not a finite frequency >= 0",
                    v.trim()
                ));
            }
            Ok(x)
        };
        let (lo_hz, hi_hz) = (num(lo)?, num(hi)?);
        if lo_hz >= hi_hz {
            return Err(format!("band `{label}`: need LO < HI"));
        }
        if let Some(b) = out
            .iter()
            .find(|b: &&Band| lo_hz < b.hi_hz && b.lo_hz < hi_hz)
        {
            return Err(format!(
                "bands `{}` and `{label}` overlap: each band holds one mode, and a mode in two \
                 bands would be reported twice; make them disjoint",
                b.label
            ));
        }
        out.push(Band {
            label: label.to_string(),
            lo_hz,
            hi_hz,
        });
    }
    Ok(Bands(out))
}

/// `--gate-px`: how far a target may move between two frames, a positive number of pixels.
pub fn parse_gate_px(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!(
            "--gate-px {s}: must be a positive number of pixels (how far a target may move \
             between two frames and still be the same)"
        )),
    }
}

/// An integer flag's range, checked by clap (the message names the flag and the range).
pub fn int_range(
    range: std::ops::RangeInclusive<u64>,
) -> clap::builder::RangedU64ValueParser<usize> {
    clap::builder::RangedU64ValueParser::<usize>::new().range(range)
}

/// A rate as users write it: a decimal (`120`, `29.97`) or a ratio (`30000/1001`, as video
/// containers state NTSC rates), finite and > 0.
pub fn parse_rate(s: &str) -> Result<f64, String> {
    let v = match s.split_once('/') {
        Some((n, d)) => {
            let (n, d): (f64, f64) = (
                n.trim()
                    .parse()
                    .map_err(|_| format!("`{s}`: expected N or N/D"))?,
                d.trim()
                    .parse()
                    .map_err(|_| format!("`{s}`: expected N or N/D"))?,
            );
            n / d
        }
        None => s
            .trim()
            .parse()
            .map_err(|_| format!("`{s}`: expected a number or a ratio N/D"))?,
    };
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("`{s}`: must be a positive rate"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_parse_and_name_the_bad_one() {
        let b = parse_bands("5-15, 25-45").unwrap();
        assert_eq!(b.pairs(), vec![(5.0, 15.0), (25.0, 45.0)]);
        assert_eq!(b.0[1].label, "25-45");
        for (bad, why) in [
            ("15-5", "LO < HI"),
            ("5", "expected LO-HI"),
            ("a-3", "not a number"),
            ("1-inf", "finite"),
            ("2-2", "LO < HI"),
        ] {
            let e = parse_bands(bad).unwrap_err();
            assert!(e.contains(why) && e.contains(bad.trim()), "{bad}: {e}");
        }
    }

    #[test]
    fn roi_parses_four_integers() {
        let r = parse_roi("1,2,30,40").unwrap();
        assert_eq!((r.x, r.y, r.width, r.height), (1, 2, 30, 40));
        for bad in ["1,2,3", "1,2,3,x", "-1,2,3,4", "0,0,0,4"] {
            assert!(parse_roi(bad).is_err(), "{bad}");
        }
    }
}

/// The camera's view: static references and the scale from the scene (`track`, `analyze`).
#[derive(Debug, Clone, clap::Args)]
pub struct ViewArgs {
    /// Windows on parts of the scene that do not move (a wall, the ground, another building):
    /// CSV `target,x,y,w,h` as --points, numbered r1, r2, ... in the report. Followed by
    /// Lucas-Kanade; from them the camera's own motion per frame is estimated (a robust fit:
    /// a reference that moves or is lost is left out and named) and removed from every
    /// target; camera_motion.csv holds it, displacement.csv the raw position too.
    #[arg(long, value_name = "FILE.csv")]
    pub reference: Option<std::path::PathBuf>,
    /// With --reference: the camera's motion in the image: `translation` (one reference or
    /// more), `similarity` (rotation, scale and shift: two or more; the default with two or
    /// more) or `homography` (four or more: a camera that pans or tilts).
    #[arg(long, value_enum, requires = "reference")]
    pub camera_model: Option<CameraModelArg>,
    /// The scale from a known distance: `A,B,MM`, the distance in mm between two tracked
    /// points, A and B a target (`3`) or a reference (`r2`); one scale for the whole frame.
    #[arg(long, value_name = "A,B,MM", value_parser = parse_scale)]
    pub scale: Option<(String, String, f64)>,
    /// The scale from each target's known diameter, mm (its blob's area in the image; a
    /// centroid tracker): each target its own scale.
    #[arg(long, value_name = "MM")]
    pub target_size_mm: Option<f64>,
    /// The structure's plane: CSV `x,y,x_mm,y_mm[,u_px]`, four or more points with their
    /// image position (px) and their position in the plane (mm; `u_px` the image position's
    /// standard uncertainty, default 0.5). A homography converts each target's motion with
    /// its own local scale and direction (a structure seen at an angle); the displacement is
    /// along the plane's y_mm (or x_mm with --axis x).
    #[arg(long, value_name = "FILE.csv")]
    pub world: Option<std::path::PathBuf>,
}

/// `--camera-model`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CameraModelArg {
    /// A shift.
    Translation,
    /// Rotation, scale and shift.
    Similarity,
    /// A projective homography.
    Homography,
}

impl ViewArgs {
    /// The flags as the library's [`crate::jobs::ViewInput`].
    pub fn view(&self) -> crate::jobs::ViewInput {
        use crate::geometry::Model;
        crate::jobs::ViewInput {
            reference: self.reference.clone().map(crate::jobs::PointsInput::File),
            camera_model: self.camera_model.map(|m| match m {
                CameraModelArg::Translation => Model::Translation,
                CameraModelArg::Similarity => Model::Similarity,
                CameraModelArg::Homography => Model::Homography,
            }),
            scale: self.scale.clone(),
            target_size_mm: self.target_size_mm,
            world: self.world.clone().map(crate::jobs::WorldInput::File),
        }
    }
}

/// `--scale A,B,MM`.
fn parse_scale(s: &str) -> Result<(String, String, f64), String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    match parts.as_slice() {
        [a, b, mm] => {
            let mm: f64 = mm
                .parse()
                .map_err(|_| format!("`{mm}` is not a distance in mm (A,B,MM)"))?;
            Ok((a.to_string(), b.to_string(), mm))
        }
        _ => Err(format!(
            "`{s}`: give A,B,MM (two tracked points, a target `3` or a reference `r2`, and \
             their distance in mm)"
        )),
    }
}

/// A flag whose values are a library type's choices, spelled by its `name` (declared once,
/// in the library): clap lists them in `--help` and refuses any other.
pub fn choice<T: Copy + Send + Sync + 'static>(
    all: &'static [T],
    name: fn(T) -> &'static str,
) -> impl clap::builder::TypedValueParser<Value = T> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(all.iter().map(|t| name(*t))).try_map(
        move |s: String| {
            all.iter()
                .copied()
                .find(|t| name(*t) == s)
                .ok_or_else(|| format!("no choice {s}"))
        },
    )
}

/// The recording a command reads: its frames, their rate, a retiming and a range; declared
/// once for `analyze` and `track`.
#[derive(Debug, Clone, clap::Args)]
pub struct Recording {
    /// Frames: a directory (its numbered *.png, *.tif, *.tiff, *.jpg sequence in natural name
    /// order, so frame_2 comes before frame_10; other images beside it are named and ignored),
    /// a pattern with `*`/`?` in the file name part (`rec/frame_*.png`), one multi-page TIFF, a
    /// Photron recording named by its .cih/.cihx (8, 12-bit packed or 16 bit; the .mraw beside
    /// it), a Phantom .cine (8, 16, packed 10-bit linearised to 12, packed 12), or a video file
    /// (.avi, .mkv, .mp4, .mov, .m4v, .webm, .mxf; decoded by the `ffmpeg` program, luma, its
    /// timestamps checked against --fps). Grey frames as stored (8 or 16 bits); colour frames
    /// as their BT.601 luma, 0.299 R + 0.587 G + 0.114 B rounded, alpha ignored. Numbered files
    /// must be consecutive (a gap is an error).
    #[arg(long, value_name = "DIR|GLOB|FILE.tif|REC.cih|REC.cine|VIDEO")]
    pub frames: String,
    /// Camera frame rate, frames per second: a number or a ratio (`30000/1001`). Default: the
    /// rate a camera file states (Photron, Phantom); needed for image files and videos (a
    /// container's rate is often not the capture rate: phone slow motion stores 30 fps for
    /// 240). Given with a camera file, it overrides the file's rate (the report names both).
    #[arg(long, value_name = "HZ", value_parser = super::args::parse_rate)]
    pub fps: Option<f64>,
    /// With a video whose container plays at another constant rate than the camera recorded
    /// at (phone slow motion: 240 fps stored as 30; a high-speed camera's AVI export at 25 fps):
    /// read its frames 1/--fps apart. The timestamps are still checked regular, at the
    /// container's rate, and the report names both rates. Without it a rate other than the
    /// container's is an error (29.97 read as 30 is a mistake, not a retiming).
    #[arg(long, requires = "fps")]
    pub retime: bool,
    /// Frames A..B of the recording only, 1-based and inclusive (as `FILE#N` and the labels
    /// `frame K of N` count them; `A..` to the end, `..B` from the start): a camera file with a
    /// damaged time stamp or a bad frame at one end, or one part of a long recording.
    #[arg(long, value_name = "A..B", value_parser = crate::frames::FrameRange::parse)]
    pub frame_range: Option<crate::frames::FrameRange>,
}
