//! Frames of a recording from disk: a directory of numbered PNG/TIFF files, a file-name pattern,
//! or one multi-page TIFF; 8- or 16-bit grey; decoded one at a time and centroided with
//! firmware-core. Errors name the file (and page); a gap in numbered file names is a missing
//! frame, never skipped silently.

use crate::bad_input;
use crate::frames::GreyFrame;
use firmware_core::centroid::{Centroid, CentroidConfig};
use std::cmp::Ordering;
use std::path::{Path, PathBuf};

/// Where the frames come from.
#[derive(Debug, Clone, PartialEq)]
pub enum FrameSource {
    /// One file per frame, in order.
    Files(Vec<PathBuf>),
    /// One multi-page TIFF, one page per frame.
    MultiPageTiff(PathBuf),
    /// One video file (AVI, MKV, MP4, MOV, ...), decoded frame by frame by FFmpeg
    /// ([`crate::frames::video`]); `retime`: its container may play at another constant rate
    /// than the one it is read at (`--retime`, [`FrameSource::retimed`]).
    Video {
        /// The file.
        path: PathBuf,
        /// Whether the rate given retimes the container's ([`VideoFrames::open_retimed`]).
        ///
        /// [`VideoFrames::open_retimed`]: crate::frames::video::VideoFrames::open_retimed
        retime: bool,
    },
    /// A Photron recording, named by its header (`.cih` / `.cihx`; frames in the `.mraw`
    /// beside it, [`crate::frames::photron`]).
    Photron(PathBuf),
    /// A Phantom `.cine` recording ([`crate::frames::phantom`]).
    Cine(PathBuf),
    /// Frames already in memory (an array handed over by the Python package), in order;
    /// labelled `frames[K]` (0-based, as the array is indexed).
    Memory(std::sync::Arc<[GreyFrame]>),
    /// Frames `first..=last` (1-based) of a camera file, a multi-page TIFF or a video
    /// (`--frame-range`, [`FrameSource::ranged`]); labels as the whole recording's.
    Range(Box<FrameSource>, FrameRange),
}

/// `--frame-range A..B`: frames A to B of a recording, 1-based and inclusive (as `FILE#N` and
/// the labels `frame K of N` count them); `A..` to the last frame, `..B` from the first.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameRange {
    /// The first frame, 1-based.
    pub first: usize,
    /// The last frame, 1-based, inclusive; `None`: the recording's last.
    pub last: Option<usize>,
}

impl FrameRange {
    /// Parses `A..B`, `A..` or `..B` (whole numbers, `1 <= A <= B`).
    pub fn parse(s: &str) -> Result<FrameRange, String> {
        let t = s.trim();
        let Some((a, b)) = t.split_once("..") else {
            return Err(format!(
                "`{s}`: expected A..B (frames A to B, 1-based and inclusive; A.. or ..B)"
            ));
        };
        let num = |v: &str, what: &str| -> Result<Option<usize>, String> {
            let v = v.trim().trim_start_matches('=');
            if v.is_empty() {
                return Ok(None);
            }
            match v.parse::<usize>() {
                Ok(n) if n >= 1 => Ok(Some(n)),
                _ => Err(format!(
                    "`{s}`: the {what} frame `{v}` is not a whole number of at least 1 (frames \
                     count from 1)"
                )),
            }
        };
        let first = num(a, "first")?.unwrap_or(1);
        let last = num(b, "last")?;
        if let Some(l) = last {
            if l < first {
                return Err(format!(
                    "`{s}`: the last frame {l} comes before the first {first}"
                ));
            }
        }
        Ok(FrameRange { first, last })
    }

    /// `A..B` as the user writes it.
    pub fn describe(&self) -> String {
        match self.last {
            Some(l) => format!("{}..{l}", self.first),
            None => format!("{}..", self.first),
        }
    }

    /// The time of the range's first frame in the recording's own time, s: frame A at
    /// `(A - 1) / fps` (no range: 0).
    pub fn start_s(range: Option<FrameRange>, fps: f64) -> f64 {
        range.map_or(0.0, |r| (r.first - 1) as f64 / fps)
    }

    /// Whether 0-based frame `k` is in the range.
    fn holds(&self, k: usize) -> bool {
        k + 1 >= self.first && self.last.is_none_or(|l| k < l)
    }

    /// The frames of a recording of `n` that the range takes; an error naming `what` when it
    /// reaches past the end (or takes none).
    fn of(&self, n: usize, what: &str) -> anyhow::Result<std::ops::Range<usize>> {
        let last = self.last.unwrap_or(n);
        if self.first > n || last > n {
            return Err(bad_input(format!(
                "$frame_range {}: {what} has {n} frames (1..{n})",
                self.describe()
            )));
        }
        Ok(self.first - 1..last)
    }
}

/// Extensions read as video files.
const VIDEO_EXTENSIONS: [&str; 7] = ["avi", "mkv", "mp4", "mov", "m4v", "webm", "mxf"];

/// Whether `p` names a video file (by its extension).
pub fn is_video(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| VIDEO_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
}

fn has_frame_ext(p: &Path) -> bool {
    p.extension().and_then(|e| e.to_str()).is_some_and(|e| {
        matches!(
            e.to_ascii_lowercase().as_str(),
            "png" | "tif" | "tiff" | "jpg" | "jpeg"
        )
    })
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

/// The frames `--frames` names, and the image files beside them that are not frames.
#[derive(Debug, Clone, PartialEq)]
pub struct Discovered {
    /// The frames.
    pub source: FrameSource,
    /// Image files in the folder (or matching the pattern) whose names are not of the numbered
    /// sequence (`background.png` beside `frame_00000.png ...`): ignored, named in the report.
    pub ignored: Vec<PathBuf>,
}

/// The numbered sequence among `files`: the names `prefix<number>suffix` of the most common
/// prefix and suffix are the frames, every other file is returned as ignored. Names without
/// any number, when no name has one, are all frames (natural order). Two sequences of the
/// same size are an error (say which with a pattern).
fn numbered_sequence(
    files: Vec<PathBuf>,
    what: &str,
) -> anyhow::Result<(Vec<PathBuf>, Vec<PathBuf>)> {
    let key = |p: &PathBuf| {
        p.file_name()
            .and_then(|n| n.to_str())
            .and_then(split_number)
            .map(|(pre, _, suf)| (pre.to_string(), suf.to_string()))
    };
    let mut counts: Vec<((String, String), usize)> = Vec::new();
    for k in files.iter().filter_map(key) {
        match counts.iter_mut().find(|(c, _)| *c == k) {
            Some((_, n)) => *n += 1,
            None => counts.push((k, 1)),
        }
    }
    let Some(best) = counts.iter().map(|(_, n)| *n).max() else {
        return Ok((files, Vec::new()));
    };
    let top: Vec<&(String, String)> = counts
        .iter()
        .filter(|(_, n)| *n == best)
        .map(|(k, _)| k)
        .collect();
    if top.len() > 1 {
        let seqs: Vec<String> = top.iter().map(|(p, s)| format!("{p}N{s}")).collect();
        return Err(bad_input(format!(
            "{what}: {} numbered sequences of {best} files each ({}); name the frames with a \
             pattern, e.g. $frames 'DIR/{}*{}'",
            top.len(),
            seqs.join(", "),
            top[0].0,
            top[0].1
        )));
    }
    let chosen = top[0].clone();
    let (frames, ignored) = files
        .into_iter()
        .partition(|p| key(p).as_ref() == Some(&chosen));
    Ok((frames, ignored))
}

/// [`discover_frames`], a video retimed (`--retime`, [`FrameSource::retimed`]) and frames
/// `range` taken (`--frame-range`, [`FrameSource::ranged`]): what every command that reads a
/// recording reads.
pub fn open_frames(
    spec: &str,
    retime: bool,
    range: Option<FrameRange>,
) -> anyhow::Result<Discovered> {
    let found = discover_frames(spec)?;
    if let Some(note) = ignored_note(&found.ignored) {
        eprintln!("warning: {note}");
    }
    Ok(Discovered {
        source: found.source.retimed(retime)?.ranged(range)?,
        ignored: found.ignored,
    })
}

/// The line naming the files beside the frames that are not read (`None`: none).
pub fn ignored_note(ignored: &[PathBuf]) -> Option<String> {
    if ignored.is_empty() {
        return None;
    }
    let names: Vec<String> = ignored.iter().map(|p| p.display().to_string()).collect();
    Some(format!(
        "{} file(s) beside the frames are not of their numbered sequence and were ignored: {}",
        names.len(),
        names.join(", ")
    ))
}

/// Resolves `--frames`: a directory, a file-name pattern, or a multi-page TIFF.
pub fn discover_frames(spec: &str) -> anyhow::Result<Discovered> {
    let path = Path::new(spec);
    if path.is_dir() {
        let files = sorted_files(path, |n| has_frame_ext(Path::new(n)))?;
        if files.is_empty() {
            return Err(bad_input(format!(
                "{}: no *.png, *.tif, *.tiff, *.jpg or *.jpeg frames in this directory",
                path.display()
            )));
        }
        let (files, mut ignored) = numbered_sequence(files, &path.display().to_string())?;
        check_numbering(&files)?;
        // files of other kinds (notes.txt, Thumbs.db) are named too
        ignored.extend(sorted_files(path, |n| !has_frame_ext(Path::new(n)))?);
        return Ok(Discovered {
            source: FrameSource::Files(files),
            ignored,
        });
    }
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
    if name.contains(['*', '?']) {
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        if dir.to_string_lossy().contains(['*', '?']) {
            return Err(bad_input(format!(
                "$frames {spec}: wildcards are only supported in the file name, not in the \
                 directory part"
            )));
        }
        let files = sorted_files(dir, |n| wildcard_match(name, n))?;
        if files.is_empty() {
            return Err(bad_input(format!("$frames {spec}: no file matches")));
        }
        let (files, ignored) = numbered_sequence(files, &format!("$frames {spec}"))?;
        check_numbering(&files)?;
        return Ok(Discovered {
            source: FrameSource::Files(files),
            ignored,
        });
    }
    let whole = |source| Discovered {
        source,
        ignored: Vec::new(),
    };
    if path.is_file() {
        if super::photron::is_header(path) {
            super::photron::read_header(path)?;
            return Ok(whole(FrameSource::Photron(path.to_path_buf())));
        }
        if super::photron::is_mraw(path) {
            return Err(super::photron::mraw_named(path));
        }
        if super::phantom::is_cine(path) {
            super::phantom::read_header(path)?;
            return Ok(whole(FrameSource::Cine(path.to_path_buf())));
        }
        if is_tiff(path) {
            return Ok(whole(FrameSource::MultiPageTiff(path.to_path_buf())));
        }
        if is_video(path) {
            return Ok(whole(FrameSource::Video {
                path: path.to_path_buf(),
                retime: false,
            }));
        }
        return Err(bad_input(format!(
            "$frames {spec}: a single {} file is one frame; give a directory of frames, a \
             pattern like dir/frame_*.png, a multi-page TIFF or a video file (.{})",
            path.extension().and_then(|e| e.to_str()).unwrap_or("image"),
            VIDEO_EXTENSIONS.join(", .")
        )));
    }
    Err(bad_input(format!(
        "$frames {spec}: no such file or directory"
    )))
}

/// Refuses a grey PNG of 1, 2 or 4 bits per pixel: the decoder widens it to 8 bits with levels
/// the threshold was not chosen for (and reports it as 8-bit, so the header is read here).
fn refuse_low_bit_png(path: &Path) -> anyhow::Result<()> {
    use std::io::Read as _;
    let mut head = [0u8; 26];
    let read = std::fs::File::open(path).and_then(|mut f| f.read_exact(&mut head));
    // signature, IHDR length and type, width, height, then bit depth and colour type
    if read.is_ok() && head[..8] == *b"\x89PNG\r\n\x1a\n" && head[12..16] == *b"IHDR" {
        let (depth, colour) = (head[24], head[25]);
        if colour == 0 && depth < 8 {
            return Err(bad_input(format!(
                "{}: a {depth}-bit grey PNG; 8- or 16-bit grey images are needed (convert it, \
                 e.g. `magick IN -depth 8 OUT`)",
                path.display()
            )));
        }
    }
    Ok(())
}

/// Why a JPEG file (`bytes`, starting with its SOI marker) is not whole, if it is not: its
/// marker segments must lie inside the file and an end-of-image marker (`FF D9`) must follow
/// the first scan. The decoder fills what a cut file lacks with grey and reports no error (a
/// 1686-byte frame cut to 1300 bytes gave a centroid 6.6 px off with no flag), so a truncated
/// frame would be a wrong number. Files that do not start as a JPEG are left to the decoder.
pub fn jpeg_truncation(bytes: &[u8]) -> Option<String> {
    if !bytes.starts_with(&[0xFF, 0xD8]) {
        return None;
    }
    let mut i = 2usize;
    loop {
        // a marker: 0xFF (fill bytes may repeat it), then its code
        while bytes.get(i) == Some(&0xFF) && bytes.get(i + 1) == Some(&0xFF) {
            i += 1;
        }
        let (Some(&0xFF), Some(&code)) = (bytes.get(i), bytes.get(i + 1)) else {
            return Some(format!(
                "it ends at byte {} inside its headers, before any image data (truncated)",
                bytes.len()
            ));
        };
        match code {
            0xD9 => return None,
            0x01 | 0xD0..=0xD7 => i += 2,
            _ => {
                let len = match (bytes.get(i + 2), bytes.get(i + 3)) {
                    (Some(&a), Some(&b)) => usize::from(u16::from_be_bytes([a, b])),
                    _ => 0,
                };
                if len < 2 || i + 2 + len > bytes.len() {
                    return Some(format!(
                        "its segment at byte {i} reaches past the end of the file ({} bytes): \
                         truncated",
                        bytes.len()
                    ));
                }
                if code == 0xDA {
                    // the scans: entropy-coded data never holds FF D9 (an FF there is followed
                    // by 00 or a restart marker), so the first one is the end of the image
                    let rest = &bytes[i + 2 + len..];
                    return match rest.windows(2).any(|w| w == [0xFF, 0xD9]) {
                        true => None,
                        false => Some(format!(
                            "its image data ends at byte {} without the end-of-image marker \
                             (FF D9): truncated",
                            bytes.len()
                        )),
                    };
                }
                i += 2 + len;
            }
        }
    }
}

/// Loads one PNG, TIFF or JPEG frame (baseline or progressive) as grey: 8- or 16-bit grey as
/// stored, colour as its BT.601 luma ([`luma`]; alpha ignored); errors name the file. A JPEG
/// cut short is refused ([`jpeg_truncation`]).
pub fn load_frame(path: &Path) -> anyhow::Result<GreyFrame> {
    refuse_low_bit_png(path)?;
    let bytes = std::fs::read(path)
        .map_err(|e| bad_input(format!("{}: cannot open the frame: {e}", path.display())))?;
    if let Some(why) = jpeg_truncation(&bytes) {
        return Err(bad_input(format!(
            "{}: a JPEG frame that is not whole: {why}",
            path.display()
        )));
    }
    let img = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| bad_input(format!("{}: cannot open the frame: {e}", path.display())))?
        .decode()
        .map_err(|e| bad_input(format!("{}: cannot decode the frame: {e}", path.display())))?;
    let (width, height) = (img.width() as usize, img.height() as usize);
    let u8 = |data: Vec<u8>| {
        Ok(GreyFrame::U8 {
            width,
            height,
            data,
        })
    };
    let u16 = |data: Vec<u16>| {
        Ok(GreyFrame::U16 {
            width,
            height,
            data,
        })
    };
    match img {
        image::DynamicImage::ImageLuma8(b) => u8(b.into_raw()),
        image::DynamicImage::ImageLuma16(b) => u16(b.into_raw()),
        image::DynamicImage::ImageLumaA8(b) => u8(b.pixels().map(|p| p.0[0]).collect()),
        image::DynamicImage::ImageLumaA16(b) => u16(b.pixels().map(|p| p.0[0]).collect()),
        image::DynamicImage::ImageRgb8(b) => u8(luma(b.as_raw(), 3)),
        image::DynamicImage::ImageRgba8(b) => u8(luma(b.as_raw(), 4)),
        image::DynamicImage::ImageRgb16(b) => u16(luma(b.as_raw(), 3)),
        image::DynamicImage::ImageRgba16(b) => u16(luma(b.as_raw(), 4)),
        other => Err(bad_input(format!(
            "{}: unsupported pixel format {:?}; 8- or 16-bit grey or colour images are needed",
            path.display(),
            other.color()
        ))),
    }
}

/// `samples` of `channels` interleaved channels as grey: as they are with one channel, else
/// their [`luma`].
fn grey<T: Copy + Into<f64> + LumaLevel>(samples: Vec<T>, channels: usize) -> Vec<T> {
    if channels == 1 {
        samples
    } else {
        luma(&samples, channels)
    }
}

/// Grey levels of interleaved colour pixels of `channels` samples (R, G, B first; alpha
/// ignored): the BT.601 luma `0.299 R + 0.587 G + 0.114 B`, rounded to the nearest level
/// (what PIL's `convert("L")` and most JPEG viewers show, within one level).
pub fn luma<T: Copy + Into<f64> + LumaLevel>(samples: &[T], channels: usize) -> Vec<T> {
    samples
        .chunks_exact(channels)
        .map(|p| T::from_luma(0.299 * p[0].into() + 0.587 * p[1].into() + 0.114 * p[2].into()))
        .collect()
}

/// A grey level built from a luma value (rounded, clamped to the type's range).
pub trait LumaLevel: Sized {
    /// `y` rounded to the nearest level.
    fn from_luma(y: f64) -> Self;
}

impl LumaLevel for u8 {
    fn from_luma(y: f64) -> u8 {
        y.round().clamp(0.0, 255.0) as u8
    }
}

impl LumaLevel for u16 {
    fn from_luma(y: f64) -> u16 {
        y.round().clamp(0.0, 65_535.0) as u16
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
        let channels = match ct {
            ColorType::Gray(8) | ColorType::Gray(16) => 1,
            ColorType::RGB(8) | ColorType::RGB(16) => 3,
            ColorType::RGBA(8) | ColorType::RGBA(16) => 4,
            _ => {
                return Err(bad_input(format!(
                    "{label}: unsupported colour type {ct:?}; 8- or 16-bit grey, RGB or RGBA \
                     is needed"
                )))
            }
        };
        let (width, height) = (w as usize, h as usize);
        let frame = match dec.read_image().map_err(err)? {
            DecodingResult::U8(data) => GreyFrame::U8 {
                width,
                height,
                data: grey(data, channels),
            },
            DecodingResult::U16(data) => GreyFrame::U16 {
                width,
                height,
                data: grey(data, channels),
            },
            _ => {
                return Err(bad_input(format!(
                    "{label}: unsupported sample format; 8- or 16-bit grey is needed"
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

/// What stops [`FrameSource::for_each`] of a range after its last frame.
#[derive(Debug)]
struct PastTheRange;

impl std::fmt::Display for PastTheRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("past the frame range")
    }
}

impl std::error::Error for PastTheRange {}

impl FrameSource {
    /// Frames `range` of this source (`--frame-range`): files and frames in memory are cut at
    /// once, a camera file's range is checked against its header's count; a multi-page TIFF's
    /// or a video's when its frames are read. Errors name the recording's frame count.
    pub fn ranged(self, range: Option<FrameRange>) -> anyhow::Result<Self> {
        let Some(range) = range else {
            return Ok(self);
        };
        match self {
            FrameSource::Files(files) => {
                let r = range.of(files.len(), "the sequence")?;
                Ok(FrameSource::Files(files[r].to_vec()))
            }
            FrameSource::Memory(frames) => {
                let r = range.of(frames.len(), "the array")?;
                Ok(FrameSource::Memory(frames[r].iter().cloned().collect()))
            }
            // a camera file's count is its header's (the rate plays no part)
            FrameSource::Photron(_) | FrameSource::Cine(_) => {
                if let Some(n) = self.count(1.0)? {
                    range.of(n, &self.describe())?;
                }
                Ok(FrameSource::Range(Box::new(self), range))
            }
            FrameSource::Range(inner, _) => Err(bad_input(format!(
                "$frame_range {}: {} is already a range",
                range.describe(),
                inner.describe()
            ))),
            other => Ok(FrameSource::Range(Box::new(other), range)),
        }
    }

    /// A camera's own file (Photron, Phantom), whose header states the recording's rate.
    pub fn is_camera_file(&self) -> bool {
        matches!(self, FrameSource::Photron(_) | FrameSource::Cine(_))
    }

    /// The source a range was cut from (this source itself when it is not a range).
    pub fn inner(&self) -> &FrameSource {
        match self {
            FrameSource::Range(inner, _) => inner,
            other => other,
        }
    }

    /// How a report names the frames.
    pub fn describe(&self) -> String {
        match self {
            FrameSource::Files(f) => match (f.first(), f.last()) {
                (Some(a), Some(b)) if f.len() > 1 => {
                    format!("{} files, {} .. {}", f.len(), a.display(), b.display())
                }
                (Some(a), _) => a.display().to_string(),
                _ => "no files".to_string(),
            },
            FrameSource::MultiPageTiff(p) => format!("{} (multi-page TIFF)", p.display()),
            FrameSource::Video { path: p, .. } => {
                format!("{} (video, decoded by FFmpeg)", p.display())
            }
            FrameSource::Photron(p) => format!("{} (Photron MRAW recording)", p.display()),
            FrameSource::Cine(p) => format!("{} (Phantom cine recording)", p.display()),
            FrameSource::Memory(f) => format!("{} frames in memory", f.len()),
            FrameSource::Range(inner, r) => {
                format!("frames {} of {}", r.describe(), inner.describe())
            }
        }
    }

    /// The number of frames when it is known before decoding (files, and a video from its
    /// container's timestamps, checked against `fps` by opening it); `None` for a multi-page
    /// TIFF.
    pub fn count(&self, fps: f64) -> anyhow::Result<Option<usize>> {
        match self {
            FrameSource::Files(f) => Ok(Some(f.len())),
            FrameSource::Memory(f) => Ok(Some(f.len())),
            FrameSource::MultiPageTiff(_) => Ok(None),
            FrameSource::Photron(p) => Ok(Some(super::photron::read_header(p)?.frames)),
            FrameSource::Cine(p) => Ok(Some(super::phantom::read_header(p)?.offsets.len())),
            FrameSource::Video { path, retime } => {
                let v = open_video(path, fps, *retime)?;
                Ok(Some(v.info().frames))
            }
            FrameSource::Range(inner, r) => match inner.count(fps)? {
                Some(n) => Ok(Some(r.of(n, &inner.describe())?.len())),
                None => Ok(None),
            },
        }
    }

    /// The frame rate (Hz) and exposure (s) the recording's own header states: a camera file's
    /// (Photron, Phantom); `None` for image files and videos, whose container rate is not trusted as
    /// the capture rate.
    pub fn recorded_rate(&self) -> anyhow::Result<Option<(f64, Option<f64>)>> {
        match self {
            FrameSource::Photron(p) => {
                let h = super::photron::read_header(p)?;
                Ok(h.fps.map(|fps| (fps, h.shutter_s)))
            }
            FrameSource::Cine(p) => cine_rate(p, None),
            FrameSource::Range(inner, r) => match &**inner {
                FrameSource::Cine(p) => cine_rate(p, Some(*r)),
                other => other.recorded_rate(),
            },
            _ => Ok(None),
        }
    }

    /// This source with a video's container rate retimed to the rate it is read at (`--retime`:
    /// a slow-motion or time-lapse file); `on == false` leaves it as it is. Refused for a
    /// source that is not a video (image files and camera files have no container rate).
    pub fn retimed(self, on: bool) -> anyhow::Result<Self> {
        match self {
            _ if !on => Ok(self),
            FrameSource::Video { path, .. } => Ok(FrameSource::Video { path, retime: true }),
            FrameSource::Range(inner, r) => Ok(FrameSource::Range(Box::new(inner.retimed(on)?), r)),
            _ => Err(bad_input(
                "$retime applies to a video file (its container's rate), not to image files \
                 or camera files: give their capture rate as $fps",
            )),
        }
    }

    /// A remark on how the frames are read (a Bayer mosaic kept as grey), if any.
    pub fn note(&self) -> anyhow::Result<Option<String>> {
        match self {
            FrameSource::Photron(p) => Ok(super::photron::read_header(p)?.note()),
            FrameSource::Cine(p) => Ok(super::phantom::read_header(p)?.note()),
            FrameSource::Range(inner, _) => inner.note(),
            _ => Ok(None),
        }
    }

    /// Calls `f(index, label, frame)` for the frames in order (as [`FrameSource::for_each`])
    /// until it returns `false`: no frame after that one is decoded.
    pub fn decode_while(
        &self,
        fps: f64,
        mut f: impl FnMut(usize, String, &GreyFrame) -> anyhow::Result<bool>,
    ) -> anyhow::Result<()> {
        let mut k = 0usize;
        let r = self.for_each(fps, |label, frame| {
            let go_on = f(k, label, frame)?;
            k += 1;
            match go_on {
                true => Ok(()),
                false => Err(anyhow::Error::new(PastTheRange)),
            }
        });
        match r {
            Err(e) if e.is::<PastTheRange>() => Ok(()),
            r => r,
        }
    }

    /// The `index`-th frame (0-based) and its label, decoding no further; `None` when the
    /// source has fewer frames.
    pub fn frame_at(&self, fps: f64, index: usize) -> anyhow::Result<Option<(String, GreyFrame)>> {
        let mut got = None;
        self.decode_while(fps, |k, label, frame| {
            if k == index {
                got = Some((label, frame.clone()));
            }
            Ok(k < index)
        })?;
        Ok(got)
    }

    /// The frames of `indices` (0-based, ascending), each with its index: files and frames in
    /// memory are read alone, other sources decoded in order up to the last one wanted; indices
    /// past the source's end are left out.
    pub fn frames_at(
        &self,
        fps: f64,
        indices: &[usize],
    ) -> anyhow::Result<Vec<(usize, GreyFrame)>> {
        match self {
            FrameSource::Files(files) => {
                return indices
                    .iter()
                    .filter_map(|&i| files.get(i).map(|p| (i, p)))
                    .map(|(i, p)| Ok((i, load_frame(p)?)))
                    .collect()
            }
            FrameSource::Memory(frames) => {
                return Ok(indices
                    .iter()
                    .filter_map(|&i| frames.get(i).map(|f| (i, f.clone())))
                    .collect())
            }
            _ => {}
        }
        let Some(&last) = indices.last() else {
            return Ok(Vec::new());
        };
        let mut got = Vec::with_capacity(indices.len());
        self.decode_while(fps, |k, _, frame| {
            if indices.binary_search(&k).is_ok() {
                got.push((k, frame.clone()));
            }
            Ok(k < last)
        })?;
        Ok(got)
    }

    /// Calls `f(label, frame)` for every frame in order, one frame in memory at a time (a
    /// video's frames decoded into one reused buffer); a video is opened with its timestamps
    /// checked against `fps`. Labels name the file (and page, or 0-based video frame). Frames
    /// must all have the first one's bit depth: an 8-bit frame among 16-bit ones (or the
    /// reverse) is an error naming both, never a frame measured at another threshold's scale.
    pub fn for_each(
        &self,
        fps: f64,
        mut f: impl FnMut(String, &GreyFrame) -> anyhow::Result<()>,
    ) -> anyhow::Result<()> {
        let mut first: Option<(bool, String)> = None;
        self.each_frame(fps, &mut |label, frame| {
            let eight = matches!(frame, GreyFrame::U8 { .. });
            match &first {
                None => first = Some((eight, label.clone())),
                Some((e, l)) if *e != eight => {
                    let bits = |e: bool| if e { 8 } else { 16 };
                    return Err(bad_input(format!(
                        "{label}: a {}-bit frame, but {l} is {}-bit: a recording's frames must \
                         all have one bit depth (convert them, or leave this one out)",
                        bits(eight),
                        bits(*e)
                    )));
                }
                Some(_) => {}
            }
            f(label, frame)
        })
    }

    /// [`for_each`](Self::for_each) through a trait object (a range calls its source's).
    fn each_frame(
        &self,
        fps: f64,
        f: &mut dyn FnMut(String, &GreyFrame) -> anyhow::Result<()>,
    ) -> anyhow::Result<()> {
        match self {
            FrameSource::Files(files) => {
                for p in files {
                    f(p.display().to_string(), &load_frame(p)?)?;
                }
                Ok(())
            }
            FrameSource::MultiPageTiff(p) => for_each_tiff_page(p, |label, frame| f(label, &frame)),
            FrameSource::Memory(frames) => {
                for (k, frame) in frames.iter().enumerate() {
                    f(format!("frames[{k}]"), frame)?;
                }
                Ok(())
            }
            FrameSource::Photron(_) | FrameSource::Cine(_) => each_camera_frame(self, None, f),
            FrameSource::Video { path: p, retime } => {
                let mut v = open_video(p, fps, *retime)?;
                let mut frame = GreyFrame::U8 {
                    width: 0,
                    height: 0,
                    data: Vec::new(),
                };
                while let Some(info) = v.next_frame(&mut frame).map_err(|e| e.into_anyhow())? {
                    f(
                        format!("{} frame {} (0-based)", p.display(), info.index),
                        &frame,
                    )?;
                }
                Ok(())
            }
            // a camera file's reader starts at the range's first frame (no frame before it is
            // read); a TIFF's or a video's frames before it are decoded and passed over
            FrameSource::Range(inner, r) if inner.is_camera_file() => {
                each_camera_frame(inner, Some(*r), f)
            }
            FrameSource::Range(inner, r) => {
                let mut k = 0usize;
                let all = inner.each_frame(fps, &mut |label, frame| {
                    k += 1;
                    if r.last.is_some_and(|l| k > l) {
                        return Err(anyhow::Error::new(PastTheRange));
                    }
                    if r.holds(k - 1) {
                        f(label, frame)?;
                    }
                    Ok(())
                });
                match all {
                    Err(e) if e.is::<PastTheRange>() => Ok(()),
                    Err(e) => Err(e),
                    Ok(()) => r.of(k, &inner.describe()).map(|_| ()),
                }
            }
        }
    }
}

/// Opens a video at `fps`, retimed when `retime` ([`FrameSource::Video`]).
fn open_video(
    path: &Path,
    fps: f64,
    retime: bool,
) -> anyhow::Result<crate::frames::video::VideoFrames> {
    let v = if retime {
        crate::frames::video::VideoFrames::open_retimed(path, fps)
    } else {
        crate::frames::video::VideoFrames::open(path, fps)
    };
    v.map_err(|e| e.into_anyhow())
}

/// The rate and exposure a cine's header states, its time stamps checked over `range` (the
/// whole file without one).
fn cine_rate(path: &Path, range: Option<FrameRange>) -> anyhow::Result<Option<(f64, Option<f64>)>> {
    let h = super::phantom::read_header(path)?;
    let n = h.offsets.len();
    let frames = match range {
        Some(r) => r.of(n, &path.display().to_string())?,
        None => 0..n,
    };
    super::phantom::check_times(&h, frames)?;
    Ok(h.fps.map(|fps| (fps, h.shutter_s)))
}

/// Calls `f` for every frame of a camera file (`source`: Photron or Phantom), or for the
/// frames `range` of it, read into one reused buffer, the reader placed at the first one;
/// labelled `PATH frame K of N` (K from 1).
fn each_camera_frame(
    source: &FrameSource,
    range: Option<FrameRange>,
    f: &mut dyn FnMut(String, &GreyFrame) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let mut frame = GreyFrame::U8 {
        width: 0,
        height: 0,
        data: Vec::new(),
    };
    let mut each = |path: &Path,
                    n: usize,
                    next: &mut dyn FnMut(&mut GreyFrame) -> anyhow::Result<Option<usize>>|
     -> anyhow::Result<()> {
        let last = match range {
            Some(r) => r.of(n, &path.display().to_string())?.end,
            None => n,
        };
        while let Some(k) = next(&mut frame)?.filter(|&k| k < last) {
            f(format!("{} frame {} of {n}", path.display(), k + 1), &frame)?;
        }
        Ok(())
    };
    let first = range.map_or(0, |r| r.first - 1);
    match source {
        FrameSource::Photron(p) => {
            let mut r = super::photron::MrawFrames::open(p)?;
            r.skip_to(first)?;
            let n = r.header().frames;
            each(p, n, &mut |frame| r.next_frame(frame))
        }
        FrameSource::Cine(p) => {
            let mut r = super::phantom::CineFrames::open(p)?;
            r.skip_to(first);
            let n = r.header().offsets.len();
            each(p, n, &mut |frame| r.next_frame(frame))
        }
        _ => Err(anyhow::anyhow!("internal: not a camera file")),
    }
}

/// Centroids every frame of `source` (one frame in memory at a time; a video's timestamps are
/// checked against `fps`). Frames must all have the size of the first one.
pub fn centroid_source(
    source: &FrameSource,
    fps: f64,
    config: &CentroidConfig,
) -> anyhow::Result<(Vec<Centroid>, FrameDepth)> {
    centroid_source_seen(source, fps, config, &mut |_, _| {})
}

/// [`centroid_source`], every frame also shown to `seen` with its centroid (in order).
pub fn centroid_source_seen(
    source: &FrameSource,
    fps: f64,
    config: &CentroidConfig,
    seen: &mut dyn FnMut(&GreyFrame, &Centroid),
) -> anyhow::Result<(Vec<Centroid>, FrameDepth)> {
    let mut out = Vec::new();
    let mut first: Option<(usize, usize, String)> = None;
    let mut depth = FrameDepth::default();
    let mut one = |label: String, frame: &GreyFrame| -> anyhow::Result<()> {
        let dims = frame.dimensions();
        depth.add(frame);
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
        let c = frame.centroid(config, &label)?;
        seen(frame, &c);
        out.push(c);
        Ok(())
    };
    source.for_each(fps, &mut one)?;
    Ok((out, depth))
}

/// The bit depth of a recording's frames and the largest value in them, for the report and
/// for a threshold that does not fit them.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameDepth {
    /// 8 or 16 (0 before the first frame).
    pub bits: u8,
    /// The largest pixel value seen.
    pub max: u16,
}

impl FrameDepth {
    /// Takes one frame into account.
    pub fn add(&mut self, frame: &GreyFrame) {
        let (bits, max) = match frame {
            GreyFrame::U8 { data, .. } => (8, data.iter().copied().max().map_or(0, u16::from)),
            GreyFrame::U16 { data, .. } => (16, data.iter().copied().max().unwrap_or(0)),
        };
        self.bits = self.bits.max(bits);
        self.max = self.max.max(max);
    }

    /// How the report names the frames' depth.
    pub fn describe(&self) -> String {
        format!("{}-bit, largest value {}", self.bits, self.max)
    }

    /// A warning when `threshold` looks meant for 8-bit frames but the frames are 16-bit with
    /// values far above 255 (the threshold then selects nearly everything but the darkest
    /// background).
    pub fn threshold_warning(&self, threshold: u16) -> Option<String> {
        (self.bits == 16 && threshold <= 255 && self.max > 1023).then(|| {
            format!(
                "$threshold {threshold} on 16-bit frames whose values reach {}: a threshold \
                 for 8-bit frames? On 16-bit frames it is in their own units (x257 maps 8-bit \
                 levels to 16-bit: {})",
                self.max,
                u32::from(threshold) * 257
            )
        })
    }
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
    fn frames_in_memory_are_a_source_like_files() {
        let frames: Vec<GreyFrame> = (0..3u8)
            .map(|k| GreyFrame::U8 {
                width: 4,
                height: 2,
                data: vec![k; 8],
            })
            .collect();
        let source = FrameSource::Memory(frames.clone().into());
        assert_eq!(source.count(1.0).unwrap(), Some(3));
        assert_eq!(source.recorded_rate().unwrap(), None);
        assert!(source.clone().retimed(true).is_err());
        let mut seen = Vec::new();
        source
            .for_each(1.0, |label, f| {
                seen.push((label, f.clone()));
                Ok(())
            })
            .unwrap();
        let labels: Vec<&str> = seen.iter().map(|(l, _)| l.as_str()).collect();
        assert_eq!(labels, ["frames[0]", "frames[1]", "frames[2]"]);
        assert!(seen.iter().map(|(_, f)| f).eq(frames.iter()));
        // an error of the callback stops the iteration and is returned
        let mut calls = 0;
        let e = source.for_each(1.0, |label, _| {
            calls += 1;
            Err(crate::bad_input(format!("{label}: refused")))
        });
        assert_eq!(calls, 1);
        assert_eq!(e.unwrap_err().to_string(), "frames[0]: refused");
    }
}
