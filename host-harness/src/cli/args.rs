//! Argument types shared by several subcommands, so that a flag spelled the same way parses,
//! validates and is described in `--help` the same way everywhere: the Welch settings
//! ([`WelchArgs`]), the centroid settings ([`CentroidArgs`]), `--bands` and `--roi`.

use crate::chain::frf::WelchSettings;
// The flags checked against the settings table, shared with the study's binary.
use firmware_core::centroid::{CentroidConfig, Mode, Roi};
use firmware_core::spectrum::{Detrend, Window};
pub use vibcam_cli::flags::*;

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
    /// `$window`.
    #[arg(long, value_enum, default_value = given("window"), help = help("window"))]
    pub window: WindowArg,
    /// `$nperseg`.
    #[arg(long, value_name = "N", value_parser = whole::<usize>("nperseg"), help = help("nperseg"))]
    pub nperseg: Option<usize>,
    /// `$noverlap`.
    #[arg(long, value_name = "N", value_parser = whole::<usize>("noverlap"), help = help("noverlap"))]
    pub noverlap: Option<usize>,
    /// `$nfft`.
    #[arg(long, value_name = "N", value_parser = whole::<usize>("nfft"), help = help("nfft"))]
    pub nfft: Option<usize>,
    /// `$detrend`.
    #[arg(long, value_enum, default_value = given("detrend"), help = help("detrend"))]
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
    /// `$threshold`: a grey level or `auto`.
    #[arg(long, value_name = "T|auto", value_parser = parse_threshold, help = help("threshold"))]
    pub threshold: Option<ThresholdArg>,
    /// `$tracker` (also `--mode`).
    #[arg(long, alias = "tracker", value_enum, default_value = given("tracker"), help = help("tracker"))]
    pub mode: ModeArg,
    /// `$roi`.
    #[arg(long, value_name = "X,Y,W,H", value_parser = parse_roi, help = help("roi"))]
    pub roi: Option<Roi>,
}

/// The targets of a recording (`track`, `analyze`): `$targets` blobs or `$points` windows,
/// and how far each may move.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct TargetArgs {
    /// `$points`: chosen windows.
    #[arg(long, value_name = "FILE.csv", conflicts_with = "targets", help = help("points"))]
    pub points: Option<std::path::PathBuf>,
    /// `$targets`: the K blobs of the first frame.
    #[arg(long, value_name = "K", value_parser = whole::<usize>("targets"), help = help("targets"))]
    pub targets: Option<usize>,
    /// `$gate_px`.
    #[arg(
        long,
        value_name = "PX",
        requires = "targets",
        allow_negative_numbers = true,
        value_parser = number("gate_px"),
        help = help("gate_px")
    )]
    pub gate_px: Option<f64>,
    /// `$search_px`.
    #[arg(long, value_name = "R", requires = "points", value_parser = whole::<u16>("search_px"), help = help("search_px"))]
    pub search_px: Option<u16>,
}

/// `--threshold`: a grey level, or `auto` (Otsu's threshold of each `--points` window).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ThresholdArg {
    /// A grey level.
    Level(u16),
    /// Otsu's threshold per window.
    Auto,
}

/// Parses `--threshold`: a grey level in its row's range, or `auto`.
pub fn parse_threshold(s: &str) -> Result<ThresholdArg, String> {
    if s.trim().eq_ignore_ascii_case("auto") {
        return Ok(ThresholdArg::Auto);
    }
    whole::<u16>("threshold")(s).map(ThresholdArg::Level)
}

impl CentroidArgs {
    /// The tracking settings these flags give, with the targets' flags (checked by
    /// [`crate::jobs::Tracking::new`]).
    pub fn tracking(&self, t: &TargetArgs) -> crate::jobs::TrackingInput {
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
            points: t.points.clone().map(PointsInput::File),
            targets: t.targets,
            gate_px: t.gate_px,
            search_px: t.search_px,
        }
    }

    /// The firmware configuration of a single target (`centroid`), with an optional
    /// saturation level.
    pub fn config(&self, saturation: Option<u16>) -> anyhow::Result<CentroidConfig> {
        let t = self.tracking(&TargetArgs::default());
        let mut c = crate::jobs::tracking::centroid_config(t.threshold, t.tracker, t.roi, false)
            .map_err(crate::jobs::SpecError::into_anyhow)?;
        c.saturation = saturation;
        c.validate()
            .map_err(|e| crate::bad_input(format!("centroid settings: {e}")))
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

/// The camera's view: static references, the scale (given or from the scene) and the image
/// axis measured (`track`, `analyze`).
#[derive(Debug, Clone, clap::Args)]
pub struct ViewArgs {
    /// `$mm_per_px`.
    #[arg(long, value_name = "MM", value_parser = number("mm_per_px"), help = help("mm_per_px"))]
    pub mm_per_px: Option<f64>,
    /// `$axis`.
    #[arg(long, value_enum, default_value = given("axis"), help = help("axis"))]
    pub axis: super::analyze::AxisArg,
    /// `$reference`: static windows.
    #[arg(long, value_name = "FILE.csv", help = help("reference"))]
    pub reference: Option<std::path::PathBuf>,
    /// `$camera_model`.
    #[arg(long, value_enum, requires = "reference", help = help("camera_model"))]
    pub camera_model: Option<CameraModelArg>,
    /// `$scale`: `A,B,MM`.
    #[arg(long, value_name = "A,B,MM", value_parser = parse_scale, help = help("scale"))]
    pub scale: Option<(String, String, f64)>,
    /// `$target_size_mm`.
    #[arg(long, value_name = "MM", value_parser = number("target_size_mm"), help = help("target_size_mm"))]
    pub target_size_mm: Option<f64>,
    /// `$world`: the structure's plane.
    #[arg(long, value_name = "FILE.csv", help = help("world"))]
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

/// The recording a command reads: its frames, their rate, a retiming and a range; declared
/// once for `analyze` and `track`.
#[derive(Debug, Clone, clap::Args)]
pub struct Recording {
    /// The frames (`$frames` in the settings table).
    #[arg(long, value_name = "DIR|GLOB|FILE.tif|REC.cih|REC.cine|VIDEO", help = help("frames"))]
    pub frames: String,
    /// The camera's frame rate, Hz (`$fps`).
    #[arg(long, value_name = "HZ", value_parser = number("fps"), help = help("fps"))]
    pub fps: Option<f64>,
    /// Read a slow-motion video's frames 1/fps apart (`$retime`).
    #[arg(long, requires = "fps", help = help("retime"))]
    pub retime: bool,
    /// Frames A..B only (`$frame_range`).
    #[arg(long, value_name = "A..B", value_parser = crate::frames::FrameRange::parse, help = help("frame_range"))]
    pub frame_range: Option<crate::frames::FrameRange>,
}

impl Recording {
    /// The frames as the library's [`crate::jobs::FramesInput`].
    pub fn input(&self) -> crate::jobs::FramesInput {
        crate::jobs::FramesInput {
            frames: self.frames.clone(),
            retime: self.retime,
            frame_range: self.frame_range,
        }
    }

    /// The frame rate and exposure resolved against the recording's own (with `exposure_ms`,
    /// the user's).
    pub fn rates(&self, exposure_ms: Option<f64>) -> anyhow::Result<crate::frames::Rates> {
        crate::frames::resolve_rates(
            &self.frames,
            self.fps,
            exposure_ms,
            self.retime,
            self.frame_range,
        )
    }
}

/// The page's flags of `analyze`, `modal` and `ema`: printed to PDF, drawn on a geometry.
#[derive(Debug, Clone, clap::Args)]
pub struct PageArgs {
    /// Also write report.pdf, report.html printed by a headless Chromium (chromium or
    /// google-chrome on PATH, or VIBCAM_CHROMIUM); a warning when there is none.
    #[arg(long)]
    pub pdf: bool,
    /// The structure's geometry: nodes (`node,x_mm,y_mm` or `node,x_px,y_px`, a node per
    /// target, for `ema` per response) and lines (`from,to`) on which report.html draws the
    /// shapes (default: the groups tracking followed, else the points in number order, broken
    /// at long steps).
    #[arg(long, value_name = "FILE.csv")]
    pub geometry: Option<std::path::PathBuf>,
}
