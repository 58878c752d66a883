//! Each setting the command line and Python share, declared once: its key, the values it takes
//! (kind and range), its unit, its default and its help. The command line's flags take their
//! help, value parser and default from here (`host_harness::cli::args`), Python's argument
//! checks their ranges and defaults (`vibcam._vibcam.settings()`), the jobs their range checks
//! ([`whole`], [`number`]), and docs/settings.md is this table written out ([`markdown`]); the
//! tests read clap's arguments and Python's signatures and fail where they depart from it.
//!
//! A row applies to the commands it lists (the Python function of the same name included);
//! a flag of another command with the same name is that command's own setting, declared
//! where it is. Help texts name other settings as `$key` ([`super::spell`]).

use super::{spell, Naming, SpecError, SpecResult};

/// What values a setting takes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Values {
    /// A switch: present or not.
    Switch,
    /// A file or directory.
    Path,
    /// Text in the stated form (`A..B`, `X,Y,W,H`, a column's name).
    Text(&'static str),
    /// One of these words.
    Choice(&'static [&'static str]),
    /// A whole number from `min` to `max`.
    Whole {
        /// Smallest allowed.
        min: u64,
        /// Largest allowed.
        max: u64,
    },
    /// A finite number within the bounds.
    Number {
        /// Lower bound.
        min: Bound,
        /// Upper bound.
        max: Bound,
    },
}

/// One end of a number's range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    /// None (any finite number).
    Free,
    /// The value itself allowed.
    Closed(f64),
    /// Only values beyond it.
    Open(f64),
}

/// Where a row's default comes from, if it has one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DefaultValue {
    /// No default: absent means absent (or the help says what the job does without it).
    None,
    /// The command line fills it in (clap states `[default: X]`); Python's argument defaults
    /// to the same value.
    Given(&'static str),
    /// The job applies it when the setting is absent (Python's argument is `None`); the help
    /// states it.
    Job(&'static str),
}

/// One setting.
#[derive(Debug, Clone, Copy)]
pub struct Setting {
    /// The key: Python's argument, `--` and the key with `-` for `_` on the command line.
    pub key: &'static str,
    /// The commands (and Python functions of the same name) this row describes.
    pub commands: &'static [&'static str],
    /// The values it takes.
    pub values: Values,
    /// Words taken besides a number (`auto`, `off`).
    pub words: &'static [&'static str],
    /// The unit (`px`, `Hz`, `s`), empty for none.
    pub unit: &'static str,
    /// Its default.
    pub default: DefaultValue,
    /// What it does, naming other settings as `$key`.
    pub help: &'static str,
}

/// The most targets a recording's tracking follows (`$targets`).
pub const MAX_TARGETS: u64 = 32;

/// The smallest value at a block's end an exponential window may have (`$exp_window`): below
/// 0.1 % the window adds a damping that swamps every mode's own.
pub const MIN_EXP_END: f64 = 1e-3;

const RECORDING: &[&str] = &["analyze", "track"];
const FRAMES: &[&str] = &["analyze", "track", "open_frames"];
const CENTROID: &[&str] = &["centroid", "analyze", "track"];
const WELCH: &[&str] = &["frf", "analyze", "modal"];
const EMA: &[&str] = &["ema"];
const POSITIVE: Values = Values::Number {
    min: Bound::Open(0.0),
    max: Bound::Free,
};
const FINITE: Values = Values::Number {
    min: Bound::Free,
    max: Bound::Free,
};

/// The table.
pub const SETTINGS: &[Setting] = &[
    Setting {
        key: "frames",
        commands: RECORDING,
        values: Values::Path,
        words: &[],
        unit: "",
        default: DefaultValue::None,
        help: "Frames: a directory (its numbered *.png, *.tif, *.tiff, *.jpg sequence in natural \
               name order, so frame_2 comes before frame_10; other images beside it are named and \
               ignored), a pattern with `*`/`?` in the file name part (`rec/frame_*.png`), one \
               multi-page TIFF, a Photron recording named by its .cih/.cihx (8, 12-bit packed or \
               16 bit; the .mraw beside it), a Phantom .cine (8, 16, packed 10-bit linearised to \
               12, packed 12), or a video file (.avi, .mkv, .mp4, .mov, .m4v, .webm, .mxf; \
               decoded by the `ffmpeg` program, luma, its timestamps checked against $fps). Grey \
               frames as stored (8 or 16 bits); colour frames as their BT.601 luma, 0.299 R + \
               0.587 G + 0.114 B rounded, alpha ignored. Numbered files must be consecutive (a \
               gap is an error).",
    },
    Setting {
        key: "fps",
        commands: FRAMES,
        values: POSITIVE,
        words: &[],
        unit: "Hz",
        default: DefaultValue::None,
        help: "Camera frame rate, frames per second: a number or a ratio (`30000/1001`). \
               Default: the rate a camera file states (Photron, Phantom); needed for image files \
               and videos (a container's rate is often not the capture rate: phone slow motion \
               stores 30 fps for 240). Given with a camera file, it overrides the file's rate \
               (the report names both).",
    },
    Setting {
        key: "retime",
        commands: &["centroid", "analyze", "track", "open_frames"],
        values: Values::Switch,
        words: &[],
        unit: "",
        default: DefaultValue::None,
        help: "With a video whose container plays at another constant rate than the camera \
               recorded at (phone slow motion: 240 fps stored as 30; a high-speed camera's AVI \
               export at 25 fps): read its frames 1/$fps apart. The timestamps are still checked \
               regular, at the container's rate, and the report names both rates. Without it a \
               rate other than the container's is an error (29.97 read as 30 is a mistake, not a \
               retiming).",
    },
    Setting {
        key: "frame_range",
        commands: &["analyze", "track", "open_frames", "pick"],
        values: Values::Text("A..B"),
        words: &[],
        unit: "",
        default: DefaultValue::None,
        help: "Frames A..B of the recording only, 1-based and inclusive (as `FILE#N` and the \
               labels `frame K of N` count them; `A..` to the end, `..B` from the start): a \
               camera file with a damaged time stamp or a bad frame at one end, or one part of a \
               long recording.",
    },
    Setting {
        key: "points",
        commands: RECORDING,
        values: Values::Path,
        words: &[],
        unit: "",
        default: DefaultValue::None,
        help: "Chosen points (a cluttered scene): CSV `target,x,y,w,h[,threshold]`, target 1..K, \
               the centre (px) in the first frame and a window (px, >= 3) that follows each \
               target; the threshold per window from the column, $threshold T, or $threshold \
               auto (Otsu's of the window in the first frame). A target lost in its window (or a \
               window at the frame edge) is a lost frame of it; the window stays where the \
               target was last seen. Outputs as with $targets.",
    },
    Setting {
        key: "targets",
        commands: RECORDING,
        values: Values::Whole {
            min: 1,
            max: MAX_TARGETS,
        },
        words: &[],
        unit: "",
        default: DefaultValue::None,
        help: "The K blobs of the first frame above a global $threshold, numbered left to right \
               (then top to bottom) and followed frame to frame.",
    },
    Setting {
        key: "gate_px",
        commands: RECORDING,
        values: POSITIVE,
        words: &[],
        unit: "px",
        default: DefaultValue::Job("10"),
        help: "With $targets: how far a target may move between frames and still be the same. \
               Not with $points (each window follows its own target).",
    },
    Setting {
        key: "search_px",
        commands: RECORDING,
        values: Values::Whole { min: 0, max: 65535 },
        words: &[],
        unit: "px",
        default: DefaultValue::None,
        help: "With $points and $tracker lk: the largest motion between two frames to catch (a \
               coarse search over +-R before the sub-pixel refinement, when the refinement from \
               the last position finds no match; default: half the window's larger side). A best \
               match on the edge of the range is a lost frame (the motion may be larger).",
    },
    Setting {
        key: "threshold",
        commands: CENTROID,
        values: Values::Whole { min: 0, max: 65535 },
        words: &["auto"],
        unit: "grey level",
        default: DefaultValue::None,
        help: "Threshold T: a pixel counts when its value is > T. For 8-bit frames a T of 255 or \
               more selects nothing. With $points also `auto`: Otsu's threshold of each window in \
               the first frame. Needed without $points; with them $tracker auto (the default) and \
               binary take Otsu's of each window when none is given (or the file's `threshold` \
               column), and lk uses none.",
    },
    Setting {
        key: "tracker",
        commands: CENTROID,
        values: Values::Choice(&["auto", "binary", "weighted", "lk"]),
        words: &[],
        unit: "",
        default: DefaultValue::Given("auto"),
        help: "The tracker: `auto` (with $points each target's own choice of blob or \
               Lucas-Kanade, said in the report; without, the binary centroid), pixel weighting \
               of the centroid (`binary`, also called `blob`, or `weighted`), or `lk` \
               (Lucas-Kanade in $points windows, `track` and `analyze` only); also called \
               `mode`.",
    },
    Setting {
        key: "roi",
        commands: CENTROID,
        values: Values::Text("X,Y,W,H"),
        words: &[],
        unit: "px",
        default: DefaultValue::None,
        help: "Region of interest X,Y,W,H (X, Y of the top-left pixel, from the top-left of the \
               frame; W, H >= 1); coordinates stay those of the full frame. Must lie inside every \
               frame.",
    },
    Setting {
        key: "mm_per_px",
        commands: RECORDING,
        values: POSITIVE,
        words: &[],
        unit: "mm/px",
        default: DefaultValue::None,
        help: "Scale, millimetres per pixel: fills `disp_mm` (needed with $accel; without it the \
               output-only analysis stays in pixels).",
    },
    Setting {
        key: "axis",
        commands: RECORDING,
        values: Values::Choice(&["x", "y"]),
        words: &[],
        unit: "",
        default: DefaultValue::Given("y"),
        help: "Image axis of the motion (`y`: positive up in the image; `x`: positive right), \
               and of the plot.",
    },
    Setting {
        key: "magnify_px",
        commands: &["analyze"],
        values: Values::Number {
            min: Bound::Closed(0.0),
            max: Bound::Closed(100.0),
        },
        words: &[],
        unit: "px",
        default: DefaultValue::Given("4"),
        help: "Without $accel: per mode a video of the first frame moving in that mode alone \
               (`magnified_<method>_<mode>.webm`, VP9 written by the `ffmpeg` program, played in \
               report.html), magnified so that the point moving most moves this many pixels; 0 \
               writes none.",
    },
    Setting {
        key: "lost_frames",
        commands: RECORDING,
        values: Values::Choice(&["interpolate", "hold"]),
        words: &[],
        unit: "",
        default: DefaultValue::Given("interpolate"),
        help: "What a lost frame's value becomes: `interpolate` (linearly between its valid \
               neighbours) or `hold` (the last valid value, as firmware repeating its last \
               output).",
    },
    Setting {
        key: "reference",
        commands: RECORDING,
        values: Values::Path,
        words: &[],
        unit: "",
        default: DefaultValue::None,
        help: "Windows on parts of the scene that do not move (a wall, the ground, another \
               building): CSV `target,x,y,w,h` as $points, numbered r1, r2, ... in the report. \
               Followed by Lucas-Kanade; from them the camera's own motion per frame is estimated \
               (a robust fit: a reference that moves or is lost is left out and named) and \
               removed from every target; camera_motion.csv holds it, displacement.csv the raw \
               position too.",
    },
    Setting {
        key: "camera_model",
        commands: RECORDING,
        values: Values::Choice(&["translation", "similarity", "homography"]),
        words: &[],
        unit: "",
        default: DefaultValue::None,
        help: "With $reference: the camera's motion in the image: `translation` (one reference or \
               more), `similarity` (rotation, scale and shift: two or more; the default with two \
               or more) or `homography` (four or more: a camera that pans or tilts).",
    },
    Setting {
        key: "scale",
        commands: RECORDING,
        values: Values::Text("A,B,MM"),
        words: &[],
        unit: "mm",
        default: DefaultValue::None,
        help: "The scale from a known distance: `A,B,MM`, the distance in mm between two tracked \
               points, A and B a target (`3`) or a reference (`r2`); one scale for the whole \
               frame.",
    },
    Setting {
        key: "target_size_mm",
        commands: RECORDING,
        values: POSITIVE,
        words: &[],
        unit: "mm",
        default: DefaultValue::None,
        help: "The scale from each target's known diameter (its blob's area in the image; a \
               centroid tracker): each target its own scale.",
    },
    Setting {
        key: "world",
        commands: RECORDING,
        values: Values::Path,
        words: &[],
        unit: "",
        default: DefaultValue::None,
        help: "The structure's plane: CSV `x,y,x_mm,y_mm[,u_px]`, four or more points with their \
               image position (px) and their position in the plane (mm; `u_px` the image \
               position's standard uncertainty, default 0.5). A homography converts each target's \
               motion with its own local scale and direction (a structure seen at an angle); the \
               displacement is along the plane's y_mm (or x_mm with $axis x).",
    },
    Setting {
        key: "window",
        commands: WELCH,
        values: Values::Choice(&["hann", "hamming", "rect"]),
        words: &[],
        unit: "",
        default: DefaultValue::Given("hann"),
        help: "Segment window (periodic, as scipy's; `rect` is scipy's `boxcar`).",
    },
    Setting {
        key: "nperseg",
        commands: WELCH,
        values: Values::Whole { min: 1, max: 65536 },
        words: &[],
        unit: "samples",
        default: DefaultValue::None,
        help: "Samples per segment [default: `frf` min(256, record length) as scipy; `analyze` \
               the whole record, one segment; `modal` a few segments of the record].",
    },
    Setting {
        key: "noverlap",
        commands: WELCH,
        values: Values::Whole { min: 0, max: 65535 },
        words: &[],
        unit: "samples",
        default: DefaultValue::None,
        help: "Samples shared by consecutive segments, < $nperseg [default: $nperseg / 2; 0 for \
               one whole-record segment].",
    },
    Setting {
        key: "nfft",
        commands: WELCH,
        values: Values::Whole { min: 1, max: 65536 },
        words: &[],
        unit: "samples",
        default: DefaultValue::None,
        help: "Transform length (zero padding), at least $nperseg [default: $nperseg].",
    },
    Setting {
        key: "detrend",
        commands: WELCH,
        values: Values::Choice(&["constant", "none"]),
        words: &[],
        unit: "",
        default: DefaultValue::Given("constant"),
        help: "Segment detrending: subtract each segment's mean, or none.",
    },
    Setting {
        key: "fs",
        commands: &["frf"],
        values: POSITIVE,
        words: &[],
        unit: "Hz",
        default: DefaultValue::None,
        help: "Sampling rate of both columns.",
    },
    Setting {
        key: "response_fs",
        commands: EMA,
        values: POSITIVE,
        words: &[],
        unit: "Hz",
        default: DefaultValue::None,
        help: "The responses' sample rate, when the file states none.",
    },
    Setting {
        key: "excitation_fs",
        commands: EMA,
        values: POSITIVE,
        words: &[],
        unit: "Hz",
        default: DefaultValue::None,
        help: "The force's sample rate, when the file states none.",
    },
    Setting {
        key: "excitation_col",
        commands: EMA,
        values: Values::Text("NAME"),
        words: &[],
        unit: "",
        default: DefaultValue::None,
        help: "The force's channel (default: the file's only channel); repeated, several \
               forces at once (shakers), each a channel of the same file.",
    },
    Setting {
        key: "impact",
        commands: EMA,
        values: Values::Switch,
        words: &[],
        unit: "",
        default: DefaultValue::None,
        help: "An impact test: hits found in the force, double hits and clipped hits left out and \
               named, the rest averaged (default: a continuous force, Welch segments).",
    },
    Setting {
        key: "exp_window",
        commands: EMA,
        values: Values::Number {
            min: Bound::Closed(MIN_EXP_END),
            max: Bound::Open(1.0),
        },
        words: &["off", "auto"],
        unit: "",
        default: DefaultValue::Given("auto"),
        help: "Impact: the exponential window (`off`, `auto`: when a response has not decayed by \
               the block's end, or its value at the block's end, e.g. 0.01; a smaller end value \
               damps the modes away); its damping is removed.",
    },
    Setting {
        key: "block_s",
        commands: EMA,
        values: POSITIVE,
        words: &[],
        unit: "s",
        default: DefaultValue::None,
        help: "Impact: the longest block after a hit (default: the hits' spacing).",
    },
    Setting {
        key: "delay_s",
        commands: EMA,
        values: FINITE,
        words: &[],
        unit: "s",
        default: DefaultValue::None,
        help: "The responses' first sample came this long after the force's (negative: before; \
               default: as the files state, else, of an impact test, from when the responses \
               start to move after the pulse, else 0).",
    },
    Setting {
        key: "response_quantity",
        commands: EMA,
        values: Values::Choice(&["displacement", "velocity", "acceleration"]),
        words: &[],
        unit: "",
        default: DefaultValue::Given("displacement"),
        help: "What the responses measure (sets the FRF's form and residual terms: receptance, \
               mobility, accelerance).",
    },
    Setting {
        key: "f_min_hz",
        commands: EMA,
        values: Values::Number {
            min: Bound::Closed(0.0),
            max: Bound::Free,
        },
        words: &[],
        unit: "Hz",
        default: DefaultValue::None,
        help: "Lowest frequency fitted (default: the bands', else of an impact test the lowest \
               the hits excited above the noise / 1.25, at least 1 % of the top and 0.5).",
    },
    Setting {
        key: "f_max_hz",
        commands: EMA,
        values: POSITIVE,
        words: &[],
        unit: "Hz",
        default: DefaultValue::None,
        help: "Highest frequency fitted (default: the bands', else of an impact test the highest \
               the hits excited above the noise x 1.25, at most 0.8 x the slower record's \
               Nyquist frequency).",
    },
    Setting {
        key: "max_order",
        commands: EMA,
        values: Values::Whole { min: 2, max: 200 },
        words: &[],
        unit: "",
        default: DefaultValue::Given("48"),
        help: "LSCF's highest model order.",
    },
    Setting {
        key: "nperseg",
        commands: EMA,
        values: Values::Whole {
            min: 64,
            max: 1 << 20,
        },
        words: &[],
        unit: "samples",
        default: DefaultValue::None,
        help: "Continuous force: samples per Welch segment (default: the largest power of two \
               with at least 8 half-overlapping segments, up to 65536).",
    },
    Setting {
        key: "efdd_quantity",
        commands: &["modal"],
        values: Values::Choice(&["auto", "displacement", "velocity", "acceleration"]),
        words: &[],
        unit: "",
        default: DefaultValue::Given("auto"),
        help: "What the records measure, for EFDD's bell model (`auto`: the quantity whose model \
               fits the resolved bells best, said in the report).",
    },
    Setting {
        key: "prominence_db",
        commands: &["modal"],
        values: Values::Number {
            min: Bound::Closed(0.0),
            max: Bound::Free,
        },
        words: &[],
        unit: "dB",
        default: DefaultValue::Given("6"),
        help: "Without bands: the least prominence of a peak of the first singular value.",
    },
    Setting {
        key: "merge",
        commands: &["modal"],
        values: Values::Choice(&["poser", "preger"]),
        words: &[],
        unit: "",
        default: DefaultValue::Given("poser"),
        help: "How several setups are merged: `poser` (each setup identified alone, its modes \
               matched and scaled at the references) or `preger` (SSI identifies every setup's \
               records together, each setup's observability matrix mapped onto the first's at \
               the references; FDD, EFDD and pLSCF on one global cross-spectral matrix, each \
               setup's spectra carried onto the references' mean; free decays still by \
               PoSER).",
    },
    Setting {
        key: "plscf",
        commands: &["modal"],
        values: Values::Switch,
        words: &[],
        unit: "",
        default: DefaultValue::None,
        help: "Also identify by LSCF on the half-spectra of up to four reference channels (modes \
               `plscf`, with intervals from the jackknife over segments).",
    },
    Setting {
        key: "ssi",
        commands: &["modal"],
        values: Values::Choice(&["cov", "dat"]),
        words: &[],
        unit: "",
        default: DefaultValue::Given("cov"),
        help: "Stochastic subspace identification from the outputs' correlations (`cov`) or \
               from the projection of their future on their past (`dat`, data-driven).",
    },
    Setting {
        key: "ssi_block_rows",
        commands: &["modal"],
        values: Values::Whole { min: 2, max: 500 },
        words: &[],
        unit: "",
        default: DefaultValue::Job("30"),
        help: "SSI: block rows of the Toeplitz matrix, or of the past and of the future in the \
               Hankel matrix (fewer for short records).",
    },
    Setting {
        key: "ssi_max_order",
        commands: &["modal"],
        values: Values::Whole { min: 2, max: 400 },
        words: &[],
        unit: "",
        default: DefaultValue::Job("40"),
        help: "SSI: the highest model order (even).",
    },
    Setting {
        key: "threads",
        commands: &["study"],
        values: Values::Whole {
            min: 0,
            max: 1 << 20,
        },
        words: &[],
        unit: "",
        default: DefaultValue::Given("0"),
        help: "Worker threads (0: all cores; more than a few per core are capped, with a \
               warning).",
    },
];

/// The row of `key` for `command` (a subcommand's or a Python function's name).
pub fn find(command: &str, key: &str) -> Option<&'static Setting> {
    SETTINGS
        .iter()
        .find(|s| s.key == key && s.commands.contains(&command))
}

/// The row of `key` that the first of its commands uses (the flags of a shared group of
/// arguments: every command listed uses the same row). Panics on a key with no row: the
/// command line's declarations name only keys of the table (its tests parse every command).
pub fn row(key: &str) -> &'static Setting {
    SETTINGS
        .iter()
        .find(|s| s.key == key)
        .unwrap_or_else(|| panic!("no setting `{key}` in the table"))
}

impl Bound {
    fn admits_above(self, v: f64) -> bool {
        match self {
            Bound::Free => true,
            Bound::Closed(b) => v >= b,
            Bound::Open(b) => v > b,
        }
    }

    fn admits_below(self, v: f64) -> bool {
        match self {
            Bound::Free => true,
            Bound::Closed(b) => v <= b,
            Bound::Open(b) => v < b,
        }
    }
}

impl Setting {
    /// The range in words: `a whole number from 1 to 32`, `a number > 0`.
    pub fn range(&self) -> String {
        let or = self
            .words
            .iter()
            .map(|w| format!(" or `{w}`"))
            .collect::<String>();
        match self.values {
            Values::Whole { min, max } => format!("a whole number from {min} to {max}{or}"),
            Values::Number { min, max } => {
                let lo = match min {
                    Bound::Free => None,
                    Bound::Closed(b) => Some(format!(">= {b}")),
                    Bound::Open(b) => Some(format!("> {b}")),
                };
                let hi = match max {
                    Bound::Free => None,
                    Bound::Closed(b) => Some(format!("<= {b}")),
                    Bound::Open(b) => Some(format!("< {b}")),
                };
                match (lo, hi) {
                    (None, None) => format!("a finite number{or}"),
                    (Some(l), None) | (None, Some(l)) => format!("a number {l}{or}"),
                    (Some(l), Some(h)) => format!("a number {l} and {h}{or}"),
                }
            }
            Values::Choice(c) => format!("one of {}", c.join(", ")),
            Values::Text(form) => form.to_string(),
            Values::Path => "a path".to_string(),
            Values::Switch => "a switch".to_string(),
        }
    }

    /// Whether `v` lies in a number's range (any finite number for a whole or a text).
    pub fn admits(&self, v: f64) -> bool {
        v.is_finite()
            && match self.values {
                Values::Whole { min, max } => {
                    v.fract() == 0.0 && v >= min as f64 && v <= max as f64
                }
                Values::Number { min, max } => min.admits_above(v) && max.admits_below(v),
                _ => true,
            }
    }

    /// The help as `naming`'s users read it: the text, its settings spelled their way, then
    /// the unit and a default the job applies.
    pub fn help_for(&self, naming: Naming) -> String {
        let mut h = spell(self.help, naming);
        if !self.unit.is_empty()
            && matches!(self.values, Values::Number { .. } | Values::Whole { .. })
        {
            h.push_str(&format!(" Unit: {}.", self.unit));
        }
        if let DefaultValue::Job(d) = self.default {
            h.push_str(&format!(" [default: {d}]"));
        }
        h
    }

    /// The default the job applies, as a number.
    pub fn job_default(&self) -> Option<f64> {
        match self.default {
            DefaultValue::Job(d) | DefaultValue::Given(d) => d.parse().ok(),
            DefaultValue::None => None,
        }
    }
}

/// `v` if it lies in `key`'s range for `command`, else an error naming the setting.
pub fn number(command: &str, key: &str, v: f64) -> SpecResult<f64> {
    let s = find(command, key).unwrap_or_else(|| row(key));
    if s.admits(v) {
        Ok(v)
    } else {
        Err(SpecError::setting(format!(
            "${key} {v}: {} is needed",
            s.range()
        )))
    }
}

/// `v` if it lies in `key`'s whole-number range for `command`, else an error naming it.
pub fn whole(command: &str, key: &str, v: u64) -> SpecResult<u64> {
    number(command, key, v as f64).map(|_| v)
}

/// The table as docs/settings.md shows it.
pub fn markdown() -> String {
    let mut out = String::from(
        "# Settings\n\nEach setting the command line and Python share, as the one table in \
         `vibcam-common` (`setting::table`) declares it: the command line's flags take their \
         help, range and default from it, Python's arguments their checks and defaults, and the \
         jobs their range checks. This page is that table written out (a test fails when they \
         differ). A flag of another command with the same name is that command's own; see \
         [cli.md](cli.md).\n\n\
         | setting | commands | values | unit | default | meaning |\n\
         |---|---|---|---|---|---|\n",
    );
    for s in SETTINGS {
        let default = match s.default {
            DefaultValue::None => String::new(),
            DefaultValue::Given(d) | DefaultValue::Job(d) => format!("`{d}`"),
        };
        out.push_str(&format!(
            "| `{}` / `{}` | {} | {} | {} | {} | {} |\n",
            spell(&format!("${}", s.key), Naming::Cli),
            s.key,
            s.commands.join(", "),
            s.range().replace('|', "\\|"),
            s.unit,
            default,
            spell(s.help, Naming::Cli).replace('|', "\\|"),
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_key_is_a_known_setting_and_each_command_has_one_row_per_key() {
        for (i, s) in SETTINGS.iter().enumerate() {
            assert!(
                super::super::KEYS.contains(&s.key),
                "{} is not in KEYS",
                s.key
            );
            for c in s.commands {
                let twice = SETTINGS[i + 1..]
                    .iter()
                    .any(|t| t.key == s.key && t.commands.contains(c));
                assert!(!twice, "{} has two rows for {c}", s.key);
            }
        }
    }

    #[test]
    fn ranges_admit_their_ends_as_declared() {
        let t = find("track", "targets").unwrap();
        assert!(t.admits(1.0) && t.admits(32.0));
        assert!(!t.admits(0.0) && !t.admits(33.0) && !t.admits(1.5));
        let e = find("ema", "exp_window").unwrap();
        assert!(e.admits(1e-3) && !e.admits(1.0) && !e.admits(5e-4));
        assert!(!find("track", "gate_px").unwrap().admits(0.0));
        assert!(!find("track", "gate_px").unwrap().admits(f64::NAN));
        let m = whole("ema", "max_order", 500).unwrap_err();
        assert_eq!(
            m.message(Naming::Cli),
            "--max-order 500: a whole number from 2 to 200 is needed"
        );
        assert_eq!(
            find("ema", "nperseg").unwrap().values,
            Values::Whole {
                min: 64,
                max: 1 << 20
            }
        );
        assert_eq!(
            find("frf", "nperseg").unwrap().values,
            Values::Whole { min: 1, max: 65536 }
        );
    }
}
