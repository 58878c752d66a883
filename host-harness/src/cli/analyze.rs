//! `host-harness analyze`: a real recording (frames + accelerometer CSV) through the chain of
//! [`crate::analysis`]. This file only parses arguments, loads the inputs, calls the chain and
//! writes the outputs.

use crate::analysis::{self, Axis, DisplacementSettings, GreyFrame, Settings, WelchSettings};
use crate::{bad_input, csvio};
use anyhow::Context as _;
use firmware_core::centroid::{Centroid, CentroidConfig, Mode, Roi};
use std::cmp::Ordering;
use std::path::{Path, PathBuf};

/// Arguments of `host-harness analyze`.
///
/// Sign convention: image `y` grows down; with `--axis y` (default) the displacement is
/// positive upwards in the image, with `--axis x` positive to the right; `--invert` flips it.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Frames: a directory (all *.png, *.tif, *.tiff in it, in natural name order, so
    /// frame_2 comes before frame_10), a pattern with `*`/`?` in the file name part
    /// (`rec/frame_*.png`), or one multi-page TIFF. 8- or 16-bit grey. Numbered files must
    /// be consecutive (a gap is an error).
    #[arg(long, value_name = "DIR|GLOB|FILE.tif")]
    pub frames: String,
    /// Camera frame rate, frames per second.
    #[arg(long, value_name = "HZ")]
    pub fps: f64,
    /// Accelerometer CSV with a header row: the input column (base acceleration in m/s^2, or
    /// any input such as a force) and the output (tip) acceleration in m/s^2, the unit the
    /// vision acceleration is computed in.
    #[arg(long, value_name = "FILE.csv")]
    pub accel: PathBuf,
    /// Accelerometer sample rate, Hz. `N * fs / fps` must be an integer.
    #[arg(long, value_name = "HZ")]
    pub fs: f64,
    /// Column of the input (base) acceleration, the FRF input of both systems.
    #[arg(long, value_name = "NAME", default_value = "base_acc")]
    pub input_col: String,
    /// Column of the output (tip) acceleration: the accelerometer system's FRF output.
    #[arg(long, value_name = "NAME", default_value = "tip_acc")]
    pub output_col: String,
    /// Optional time column (s): rows must be strictly increasing in steps of 1/fs.
    #[arg(long, value_name = "NAME")]
    pub time_col: Option<String>,
    /// Time of the first frame minus time of the first accelerometer sample, s (>= 0; rounded
    /// to the nearest sample, the residual delay is removed from the vision H1). Default 0.
    #[arg(
        long,
        value_name = "S",
        allow_negative_numbers = true,
        conflicts_with = "tick_offset"
    )]
    pub time_offset_s: Option<f64>,
    /// Same as --time-offset-s in ticks of the common time base --tick-hz (SPEC 2.7).
    #[arg(
        long,
        value_name = "TICKS",
        allow_negative_numbers = true,
        requires = "tick_hz"
    )]
    pub tick_offset: Option<i64>,
    /// Rate of the common time base of --tick-offset, Hz (30720 for 2048 Hz / 120 fps).
    #[arg(long, value_name = "HZ", requires = "tick_offset")]
    pub tick_hz: Option<f64>,
    /// Centroid threshold T in grey levels: pixels with value > T count.
    #[arg(long, value_name = "T")]
    pub threshold: u16,
    /// Centroid weighting.
    #[arg(long, value_enum, default_value_t = ModeArg::Binary)]
    pub mode: ModeArg,
    /// Region of interest X,Y,W,H in full-frame pixels.
    #[arg(long, value_name = "X,Y,W,H", value_parser = parse_roi)]
    pub roi: Option<Roi>,
    /// Scale, millimetres per pixel.
    #[arg(long, value_name = "MM")]
    pub mm_per_px: f64,
    /// Image axis of the motion (`y`: positive up in the image; `x`: positive right).
    #[arg(long, value_enum, default_value_t = AxisArg::Y)]
    pub axis: AxisArg,
    /// Flip the sign of the displacement.
    #[arg(long)]
    pub invert: bool,
    /// Camera exposure time, ms (for the E2PR of each mode).
    #[arg(long, value_name = "MS")]
    pub exposure_ms: Option<f64>,
    /// Welch window (periodic).
    #[arg(long, value_enum, default_value_t = WindowArg::Hann)]
    pub window: WindowArg,
    /// Welch segment length, samples (default: the whole record, one segment).
    #[arg(long, value_name = "N")]
    pub nperseg: Option<usize>,
    /// Welch overlap, samples (default: 0 for one segment, else nperseg/2).
    #[arg(long, value_name = "N")]
    pub noverlap: Option<usize>,
    /// FFT length >= nperseg (default: nperseg).
    #[arg(long, value_name = "N")]
    pub nfft: Option<usize>,
    /// Per-segment detrending.
    #[arg(long, value_enum, default_value_t = DetrendArg::Constant)]
    pub detrend: DetrendArg,
    /// Frequency bands of the modes, Hz: LO-HI,LO-HI,...
    #[arg(long, value_name = "LO-HI,...", default_value = "5-15,25-45", value_parser = parse_bands)]
    pub bands: Bands,
    /// Output directory (created).
    #[arg(long, value_name = "DIR", default_value = "analysis")]
    pub out: PathBuf,
}

/// `--mode`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ModeArg {
    /// Every pixel above T has weight 1 (the paper's).
    Binary,
    /// Weight value - T.
    Weighted,
}

/// `--axis`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum AxisArg {
    /// Horizontal, positive to the right.
    X,
    /// Vertical, positive upwards in the image.
    Y,
}

/// `--window`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum WindowArg {
    /// Periodic Hann.
    Hann,
    /// Periodic Hamming.
    Hamming,
    /// Rectangular.
    Rect,
}

/// `--detrend` (shared with the other subcommands that run Welch).
pub use super::args::DetrendArg;

/// Parsed `--bands`.
#[derive(Debug, Clone, PartialEq)]
pub struct Bands(pub Vec<(f64, f64)>);

fn parse_bands(s: &str) -> Result<Bands, String> {
    let mut out = Vec::new();
    for part in s.split(',') {
        let (lo, hi) = part
            .trim()
            .split_once('-')
            .ok_or_else(|| format!("band `{part}`: expected LO-HI in Hz"))?;
        let lo: f64 = lo
            .trim()
            .parse()
            .map_err(|_| format!("band `{part}`: `{lo}` is not a number"))?;
        let hi: f64 = hi
            .trim()
            .parse()
            .map_err(|_| format!("band `{part}`: `{hi}` is not a number"))?;
        if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo < hi) {
            return Err(format!("band `{part}`: need 0 <= LO < HI"));
        }
        out.push((lo, hi));
    }
    Ok(Bands(out))
}

fn parse_roi(s: &str) -> Result<Roi, String> {
    let v: Vec<u32> = s
        .split(',')
        .map(|p| {
            p.trim()
                .parse()
                .map_err(|_| format!("`{p}` is not a non-negative integer"))
        })
        .collect::<Result<_, _>>()?;
    match v[..] {
        [x, y, width, height] => Ok(Roi {
            x,
            y,
            width,
            height,
        }),
        _ => Err(format!(
            "expected X,Y,W,H (4 integers), got {} values",
            v.len()
        )),
    }
}

// ---------------------------------------------------------------------------------------------
// Frame discovery and loading.

/// Where the frames come from.
#[derive(Debug, Clone, PartialEq)]
pub enum FrameSource {
    /// One file per frame, in order.
    Files(Vec<PathBuf>),
    /// One multi-page TIFF, one page per frame.
    MultiPageTiff(PathBuf),
}

fn has_frame_ext(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| matches!(e.to_ascii_lowercase().as_str(), "png" | "tif" | "tiff"))
}

fn is_tiff(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| matches!(e.to_ascii_lowercase().as_str(), "tif" | "tiff"))
}

/// Natural order of names: runs of digits compare as numbers (`f2` < `f10`), the rest as text.
pub fn natural_cmp(a: &str, b: &str) -> Ordering {
    let (mut a, mut b) = (a.as_bytes(), b.as_bytes());
    loop {
        match (a.first(), b.first()) {
            (None, None) => return Ordering::Equal,
            (None, Some(_)) => return Ordering::Less,
            (Some(_), None) => return Ordering::Greater,
            (Some(x), Some(y)) if x.is_ascii_digit() && y.is_ascii_digit() => {
                let na = a.iter().take_while(|c| c.is_ascii_digit()).count();
                let nb = b.iter().take_while(|c| c.is_ascii_digit()).count();
                let (da, db) = (&a[..na], &b[..nb]);
                let ta = trim_zeros(da);
                let tb = trim_zeros(db);
                let ord = ta.len().cmp(&tb.len()).then(ta.cmp(tb)).then(na.cmp(&nb));
                if ord != Ordering::Equal {
                    return ord;
                }
                a = &a[na..];
                b = &b[nb..];
            }
            (Some(x), Some(y)) => {
                if x != y {
                    return x.cmp(y);
                }
                a = &a[1..];
                b = &b[1..];
            }
        }
    }
}

fn trim_zeros(d: &[u8]) -> &[u8] {
    let z = d.iter().take_while(|&&c| c == b'0').count();
    &d[z..]
}

/// Shell-like match of a file name against a pattern with `*` (any run) and `?` (one char).
pub fn wildcard_match(pattern: &str, name: &str) -> bool {
    let (p, n): (Vec<char>, Vec<char>) = (pattern.chars().collect(), name.chars().collect());
    let (mut pi, mut ni) = (0, 0);
    let mut star: Option<(usize, usize)> = None;
    while ni < n.len() {
        if pi < p.len() && (p[pi] == '?' || p[pi] == n[ni]) {
            pi += 1;
            ni += 1;
        } else if pi < p.len() && p[pi] == '*' {
            star = Some((pi, ni));
            pi += 1;
        } else if let Some((sp, sn)) = star {
            pi = sp + 1;
            ni = sn + 1;
            star = Some((sp, sn + 1));
        } else {
            return false;
        }
    }
    p[pi..].iter().all(|&c| c == '*')
}

fn sorted_files(dir: &Path, keep: impl Fn(&str) -> bool) -> anyhow::Result<Vec<PathBuf>> {
    let rd = std::fs::read_dir(dir)
        .map_err(|e| bad_input(format!("cannot list {}: {e}", dir.display())))?;
    let mut files: Vec<(String, PathBuf)> = Vec::new();
    for entry in rd {
        let entry = entry.map_err(|e| bad_input(format!("cannot list {}: {e}", dir.display())))?;
        let path = entry.path();
        let Some(name) = path.file_name().and_then(|n| n.to_str()) else {
            continue;
        };
        if path.is_file() && keep(name) {
            files.push((name.to_string(), path));
        }
    }
    files.sort_by(|a, b| natural_cmp(&a.0, &b.0));
    Ok(files.into_iter().map(|(_, p)| p).collect())
}

/// `(prefix, number, suffix)` around the last run of digits of a file name.
fn split_number(name: &str) -> Option<(&str, u64, &str)> {
    let end = name.rfind(|c: char| c.is_ascii_digit())? + 1;
    let start = name[..end]
        .rfind(|c: char| !c.is_ascii_digit())
        .map_or(0, |i| i + 1);
    let n = name[start..end].parse().ok()?;
    Some((&name[..start], n, &name[end..]))
}

/// Missing frames in a numbered sequence: when every name is `prefix<number>suffix` with one
/// prefix and suffix, the numbers must be consecutive; a gap is an error naming the missing
/// frame (a silently skipped frame would shift every later frame in time).
pub fn check_numbering(files: &[PathBuf]) -> anyhow::Result<()> {
    let names: Vec<&str> = files
        .iter()
        .filter_map(|p| p.file_name().and_then(|n| n.to_str()))
        .collect();
    let parts: Option<Vec<(&str, u64, &str)>> = names.iter().map(|n| split_number(n)).collect();
    let Some(parts) = parts else {
        return Ok(());
    };
    let Some(&(prefix, _, suffix)) = parts.first() else {
        return Ok(());
    };
    if parts.iter().any(|&(p, _, s)| p != prefix || s != suffix) {
        return Ok(());
    }
    for (w, n) in parts.windows(2).zip(names.windows(2)) {
        if w[1].1 != w[0].1 + 1 {
            return Err(bad_input(format!(
                "frame numbering has a gap: {} is followed by {} (frame number {} is missing; \
                 every frame must be present, a skipped frame would shift all later frames)",
                n[0],
                n[1],
                w[0].1 + 1
            )));
        }
    }
    Ok(())
}

/// Resolves `--frames`: a directory, a file-name pattern, or a multi-page TIFF.
pub fn discover_frames(spec: &str) -> anyhow::Result<FrameSource> {
    let path = Path::new(spec);
    if path.is_dir() {
        let files = sorted_files(path, |n| has_frame_ext(Path::new(n)))?;
        if files.is_empty() {
            return Err(bad_input(format!(
                "{}: no *.png, *.tif or *.tiff frames in this directory",
                path.display()
            )));
        }
        check_numbering(&files)?;
        return Ok(FrameSource::Files(files));
    }
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
    if name.contains(['*', '?']) {
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        if dir.to_string_lossy().contains(['*', '?']) {
            return Err(bad_input(format!(
                "--frames {spec}: wildcards are only supported in the file name, not in the \
                 directory part"
            )));
        }
        let files = sorted_files(dir, |n| wildcard_match(name, n))?;
        if files.is_empty() {
            return Err(bad_input(format!("--frames {spec}: no file matches")));
        }
        check_numbering(&files)?;
        return Ok(FrameSource::Files(files));
    }
    if path.is_file() {
        if is_tiff(path) {
            return Ok(FrameSource::MultiPageTiff(path.to_path_buf()));
        }
        return Err(bad_input(format!(
            "--frames {spec}: a single {} file is one frame; give a directory of frames, a \
             pattern like dir/frame_*.png, or a multi-page TIFF",
            path.extension().and_then(|e| e.to_str()).unwrap_or("image")
        )));
    }
    Err(bad_input(format!(
        "--frames {spec}: no such file or directory"
    )))
}

/// Loads one 8- or 16-bit grey PNG/TIFF frame; errors name the file.
pub fn load_frame(path: &Path) -> anyhow::Result<GreyFrame> {
    let img = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| bad_input(format!("{}: cannot open the frame: {e}", path.display())))?
        .decode()
        .map_err(|e| bad_input(format!("{}: cannot decode the frame: {e}", path.display())))?;
    let (width, height) = (img.width() as usize, img.height() as usize);
    match img {
        image::DynamicImage::ImageLuma8(b) => Ok(GreyFrame::U8 {
            width,
            height,
            data: b.into_raw(),
        }),
        image::DynamicImage::ImageLuma16(b) => Ok(GreyFrame::U16 {
            width,
            height,
            data: b.into_raw(),
        }),
        other => Err(bad_input(format!(
            "{}: not a grey frame (colour type {:?}); analyze needs 8- or 16-bit grey images",
            path.display(),
            other.color()
        ))),
    }
}

/// Calls `f(label, frame)` for every page of a multi-page TIFF, in order; errors name the file
/// and the page (1-based).
pub fn for_each_tiff_page(
    path: &Path,
    mut f: impl FnMut(String, GreyFrame) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    use tiff::decoder::{Decoder, DecodingResult};
    use tiff::ColorType;
    let file = std::fs::File::open(path)
        .map_err(|e| bad_input(format!("{}: cannot open: {e}", path.display())))?;
    let mut dec = Decoder::new(std::io::BufReader::new(file))
        .map_err(|e| bad_input(format!("{}: not a readable TIFF: {e}", path.display())))?;
    let mut page = 1usize;
    loop {
        let label = format!("{} page {page}", path.display());
        let err = |e: tiff::TiffError| bad_input(format!("{label}: cannot decode: {e}"));
        let (w, h) = dec.dimensions().map_err(err)?;
        let ct = dec.colortype().map_err(err)?;
        if !matches!(ct, ColorType::Gray(8) | ColorType::Gray(16)) {
            return Err(bad_input(format!(
                "{label}: not a grey frame (colour type {ct:?}); analyze needs 8- or 16-bit grey"
            )));
        }
        let (width, height) = (w as usize, h as usize);
        let frame = match dec.read_image().map_err(err)? {
            DecodingResult::U8(data) => GreyFrame::U8 {
                width,
                height,
                data,
            },
            DecodingResult::U16(data) => GreyFrame::U16 {
                width,
                height,
                data,
            },
            _ => {
                return Err(bad_input(format!(
                    "{label}: unsupported sample format; analyze needs 8- or 16-bit grey"
                )))
            }
        };
        f(label.clone(), frame)?;
        if !dec.more_images() {
            return Ok(());
        }
        dec.next_image().map_err(|e| {
            bad_input(format!(
                "{} page {}: cannot decode: {e}",
                path.display(),
                page + 1
            ))
        })?;
        page += 1;
    }
}

/// Centroids every frame of `source` (one frame in memory at a time). Frames must all have the
/// size of the first one.
pub fn centroid_source(
    source: &FrameSource,
    config: &CentroidConfig,
) -> anyhow::Result<Vec<Centroid>> {
    let mut out = Vec::new();
    let mut first: Option<(usize, usize, String)> = None;
    let mut one = |label: String, frame: GreyFrame| -> anyhow::Result<()> {
        let dims = frame.dimensions();
        match &first {
            None => first = Some((dims.0, dims.1, label.clone())),
            Some((w, h, l)) if (*w, *h) != dims => {
                return Err(bad_input(format!(
                    "{label}: {}x{} pixels, but {l} is {w}x{h}: all frames must have one size",
                    dims.0, dims.1
                )))
            }
            Some(_) => {}
        }
        out.push(analysis::centroid_frame(&frame, config, &label)?);
        Ok(())
    };
    match source {
        FrameSource::Files(files) => {
            for p in files {
                let frame = load_frame(p)?;
                one(p.display().to_string(), frame)?;
            }
        }
        FrameSource::MultiPageTiff(p) => for_each_tiff_page(p, &mut one)?,
    }
    Ok(out)
}

/// The accelerometer channels: `(base, tip)` in m/s^2, validated.
pub fn load_accel(args: &Args) -> anyhow::Result<(Vec<f64>, Vec<f64>)> {
    if !(args.fs.is_finite() && args.fs > 0.0) {
        return Err(bad_input(format!(
            "--fs must be a positive rate, got {}",
            args.fs
        )));
    }
    let mut wanted = vec![args.input_col.as_str(), args.output_col.as_str()];
    if let Some(t) = &args.time_col {
        wanted.push(t.as_str());
    }
    let mut cols = csvio::read_columns(&args.accel, &wanted)?.values;
    if args.time_col.is_some() {
        let t = cols.pop().unwrap_or_default();
        analysis::check_time_column(&t, args.fs, &args.accel.display().to_string(), 2)?;
    }
    let tip = cols.pop().unwrap_or_default();
    let base = cols.pop().unwrap_or_default();
    Ok((base, tip))
}

fn write(dir: &Path, name: &str, text: &str) -> anyhow::Result<PathBuf> {
    let p = dir.join(name);
    std::fs::write(&p, text).with_context(|| format!("cannot write {}", p.display()))?;
    Ok(p)
}

/// Runs `host-harness analyze`.
pub fn run(args: Args) -> anyhow::Result<()> {
    for (name, v) in [("--fps", args.fps), ("--mm-per-px", args.mm_per_px)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(bad_input(format!("{name} must be positive, got {v}")));
        }
    }
    if let Some(e) = args.exposure_ms {
        if !(e.is_finite() && e >= 0.0) {
            return Err(bad_input(format!("--exposure-ms must be >= 0, got {e}")));
        }
    }
    let time_offset_s = match (args.time_offset_s, args.tick_offset, args.tick_hz) {
        (Some(t), _, _) => t,
        (None, Some(k), Some(hz)) => analysis::tick_offset_to_seconds(k, hz)?,
        _ => 0.0,
    };
    let mode = match args.mode {
        ModeArg::Binary => Mode::Binary,
        ModeArg::Weighted => Mode::Weighted,
    };
    let config = CentroidConfig {
        threshold: args.threshold,
        mode,
        roi: args.roi,
        saturation: None,
    }
    .validate()
    .map_err(|e| bad_input(format!("centroid settings: {e}")))?;
    let settings = Settings {
        frame_rate_hz: args.fps,
        accel_rate_hz: args.fs,
        time_offset_s,
        welch: WelchSettings {
            window: match args.window {
                WindowArg::Hann => analysis::Window::Hann,
                WindowArg::Hamming => analysis::Window::Hamming,
                WindowArg::Rect => analysis::Window::Rect,
            },
            nperseg: args.nperseg,
            noverlap: args.noverlap,
            nfft: args.nfft,
            detrend: args.detrend == DetrendArg::Constant,
        },
        bands: args.bands.0.clone(),
        exposure_s: args.exposure_ms.map(|e| e / 1000.0),
    };
    let dsettings = DisplacementSettings {
        mm_per_px: args.mm_per_px,
        axis: match args.axis {
            AxisArg::X => Axis::X,
            AxisArg::Y => Axis::Y,
        },
        invert: args.invert,
    };

    // Inputs first (cheap checks before the frames are decoded).
    let (base, tip) = load_accel(&args)?;
    let source = discover_frames(&args.frames)?;
    if let FrameSource::Files(f) = &source {
        // The frame count is known before decoding: check the record lengths now.
        analysis::align(f.len(), args.fps, base.len(), args.fs, time_offset_s)?;
    }
    let centroids = centroid_source(&source, &config)?;
    let disp = analysis::displacement_mm(&centroids, &dsettings)?;

    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let inputs = describe_inputs(&args, &source, centroids.len(), base.len(), time_offset_s);
    write(
        &args.out,
        "displacement.csv",
        &analysis::displacement_csv(&centroids, &disp, args.fps, time_offset_s),
    )?;
    let result = analysis::analyze(&disp, &base, &tip, &settings);
    let (a, failure) = match &result {
        Ok(a) => (Some(a), None),
        Err(e) => (None, Some(format!("{e:#}"))),
    };
    let mut report = analysis::report_text(&inputs, &disp, a, failure.as_deref());
    if let Some(a) = a {
        write(&args.out, "frf.csv", &analysis::frf_csv(a))?;
        write(&args.out, "modes.csv", &analysis::modes_csv(a))?;
        let plots = write_plot(&args.out, a, args.fps)?;
        let mut files = vec!["frf.csv", "modes.csv", "displacement.csv", "report.txt"]
            .into_iter()
            .map(|f| args.out.join(f).display().to_string())
            .collect::<Vec<_>>();
        files.extend(plots.iter().map(|p| p.display().to_string()));
        report.push_str(&format!("\nwritten: {}\n", files.join(", ")));
    }
    write(&args.out, "report.txt", &report)?;
    print!("{report}");
    result.map(|_| ())
}

/// `frf.png` / `frf.svg`: |H1| of both systems up to 1.1 x the highest band edge, at most the
/// camera's Nyquist frequency (the vision path has no content above it, and outside the
/// excitation band H1 is noise over noise).
fn write_plot(out: &Path, a: &analysis::Analysis, fps: f64) -> anyhow::Result<Vec<PathBuf>> {
    let top = a
        .acc_modes
        .iter()
        .map(|m| m.band_hz.1 * 1.1)
        .fold(0.0, f64::max);
    let top = if top > 0.0 {
        top.min(fps / 2.0)
    } else {
        fps / 2.0
    };
    let keep = a.acc_frf.freq_hz.iter().take_while(|&&f| f <= top).count();
    let freq = &a.acc_frf.freq_hz[..keep];
    let abs = |h: &[num_complex::Complex64]| h[..keep].iter().map(|v| v.norm()).collect();
    let acc: Vec<f64> = abs(&a.acc_frf.h1);
    let vis: Vec<f64> = abs(&a.vis_frf.h1);
    crate::plots::write_frf_plot(
        &out.join("frf"),
        "H1 of the recording: accelerometer and vision",
        "|H1|",
        &[("accelerometer", freq, &acc), ("vision", freq, &vis)],
    )
}

fn describe_inputs(
    args: &Args,
    source: &FrameSource,
    frames: usize,
    samples: usize,
    time_offset_s: f64,
) -> Vec<(String, String)> {
    let src = match source {
        FrameSource::Files(f) => format!(
            "{} ({} files, {} .. {})",
            args.frames,
            f.len(),
            f.first()
                .map(|p| p.display().to_string())
                .unwrap_or_default(),
            f.last()
                .map(|p| p.display().to_string())
                .unwrap_or_default()
        ),
        FrameSource::MultiPageTiff(p) => format!("{} (multi-page TIFF)", p.display()),
    };
    let mut v = vec![
        ("frames".to_string(), src),
        (
            "frame count".into(),
            format!(
                "{frames} at {} fps ({:.4} s)",
                args.fps,
                frames as f64 / args.fps
            ),
        ),
        (
            "accelerometer".into(),
            format!(
                "{}: input `{}`, output `{}`, {samples} samples at {} Hz ({:.4} s)",
                args.accel.display(),
                args.input_col,
                args.output_col,
                args.fs,
                samples as f64 / args.fs
            ),
        ),
        (
            "alignment".into(),
            format!("first frame at {time_offset_s} s after the first sample"),
        ),
        (
            "centroid".into(),
            format!(
                "threshold {}, {:?}, ROI {}",
                args.threshold,
                args.mode,
                args.roi
                    .map(|r| format!("{},{},{},{}", r.x, r.y, r.width, r.height))
                    .unwrap_or_else(|| "none".into())
            ),
        ),
        (
            "displacement".into(),
            format!(
                "{} mm/px, axis {}{}",
                args.mm_per_px,
                match args.axis {
                    AxisArg::X => "x (positive right)",
                    AxisArg::Y => "y (positive up in the image)",
                },
                if args.invert { ", inverted" } else { "" }
            ),
        ),
    ];
    if let Some(e) = args.exposure_ms {
        v.push(("exposure".into(), format!("{e} ms")));
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn natural_order_compares_digit_runs_as_numbers() {
        let mut v = vec![
            "f10.png", "f2.png", "f1.png", "f02.png", "g1.png", "f1a.png",
        ];
        v.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(
            v,
            ["f1.png", "f1a.png", "f2.png", "f02.png", "f10.png", "g1.png"]
        );
    }

    #[test]
    fn wildcards_match_like_a_shell() {
        assert!(wildcard_match("frame_*.png", "frame_00012.png"));
        assert!(!wildcard_match("frame_*.png", "frame_00012.tif"));
        assert!(wildcard_match("f?.tif", "f1.tif"));
        assert!(!wildcard_match("f?.tif", "f12.tif"));
        assert!(wildcard_match("*", "anything"));
        assert!(wildcard_match("a*b*c", "aXXbYYc"));
        assert!(!wildcard_match("a*b*c", "aXXbYY"));
    }

    #[test]
    fn numbering_gaps_are_found() {
        let p = |v: &[&str]| v.iter().map(PathBuf::from).collect::<Vec<_>>();
        check_numbering(&p(&["f_008.png", "f_009.png", "f_010.png"])).unwrap();
        let e = check_numbering(&p(&["f_008.png", "f_010.png"])).unwrap_err();
        assert!(
            format!("{e}").contains("f_008.png is followed by f_010.png"),
            "{e}"
        );
        // mixed names: no numbering to check
        check_numbering(&p(&["a1.png", "b7.png"])).unwrap();
        check_numbering(&p(&["x.png", "y.png"])).unwrap();
        assert_eq!(
            split_number("cam2_frame_0012.tif"),
            Some(("cam2_frame_", 12, ".tif"))
        );
    }

    #[test]
    fn bands_and_roi_parse() {
        assert_eq!(
            parse_bands("5-15, 25-45").unwrap(),
            Bands(vec![(5.0, 15.0), (25.0, 45.0)])
        );
        assert!(parse_bands("15-5").is_err());
        assert!(parse_bands("5").is_err());
        let r = parse_roi("1,2,30,40").unwrap();
        assert_eq!((r.x, r.y, r.width, r.height), (1, 2, 30, 40));
        assert!(parse_roi("1,2,3").is_err());
    }
}
