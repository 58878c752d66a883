//! Photron high-speed recordings: a header (`rec.cih`, text; or `rec.cihx`, XML, possibly after
//! a binary prefix) and the frames in `rec.mraw` beside it, read one frame at a time.
//!
//! What is read, as pyMRAW reads it (our CI compares the two pixel for pixel on its sample files
//! and on files our tests write):
//! - the header's `Image Width`, `Image Height`, `Total Frame`, `Color Bit` (8, 12 or 16) and
//!   `File Format` (`MRaw`); `Record Rate(fps)` and the shutter (`Shutter Speed(s)`, e.g.
//!   `1/5000`; in a `.cihx`, `shutterSpeedNsec`, else `1 / shutterSpeed`) are the recording's
//!   frame rate and exposure;
//! - 8-bit frames: one byte a pixel; 16-bit: little-endian words; 12-bit packed: two pixels in
//!   three bytes, most significant bit first (`p0 = b0 << 4 | b1 >> 4`,
//!   `p1 = (b1 & 15) << 8 | b2`); rows top first;
//! - values exactly as stored: never shifted by `EffectiveBit Side` (a 12-bit camera writing
//!   16-bit words gives 0..=4095 with `Lower`); 12- and 16-bit frames are 16-bit grey frames;
//! - a `Raw` colour type (a Bayer sensor's mosaic) is kept as its grey mosaic, as pyMRAW does
//!   ([`PhotronHeader::note`] says so); `Color` (interleaved RGB) is refused.
//!
//! The `.mraw` must hold exactly `Total Frame` frames of the header's size: a shorter or longer
//! file is an error naming both counts, before any frame is read.

use super::GreyFrame;
use crate::bad_input;
use std::io::Read as _;
use std::path::{Path, PathBuf};

/// What a Photron header states.
#[derive(Debug, Clone, PartialEq)]
pub struct PhotronHeader {
    /// The header file.
    pub header: PathBuf,
    /// The frames file beside it.
    pub mraw: PathBuf,
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Frames in the file.
    pub frames: usize,
    /// Bits per pixel as stored: 8, 12 (packed) or 16.
    pub bits: u32,
    /// Frame rate, frames per second.
    pub fps: Option<f64>,
    /// Exposure (shutter), seconds.
    pub shutter_s: Option<f64>,
    /// Colour type as stated (`Mono`, `Raw`, ...).
    pub colour: String,
}

impl PhotronHeader {
    /// Bytes of one frame in the `.mraw`.
    pub fn frame_bytes(&self) -> usize {
        self.width * self.height * self.bits as usize / 8
    }

    /// A remark for the report (a Bayer mosaic read as grey), if any.
    pub fn note(&self) -> Option<String> {
        self.colour.eq_ignore_ascii_case("raw").then(|| {
            format!(
                "{}: colour type Raw (a Bayer sensor's mosaic): read as the grey mosaic, one \
                 colour filter per pixel, as pyMRAW does",
                self.header.display()
            )
        })
    }
}

/// Whether `p` names a Photron header (`.cih` or `.cihx`).
pub fn is_header(p: &Path) -> bool {
    ext(p).is_some_and(|e| e == "cih" || e == "cihx")
}

/// Whether `p` names a Photron frames file (`.mraw`).
pub fn is_mraw(p: &Path) -> bool {
    ext(p).is_some_and(|e| e == "mraw")
}

fn ext(p: &Path) -> Option<String> {
    p.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}

/// The error for `--frames rec.mraw`: the recording is named by its header.
pub fn mraw_named(p: &Path) -> anyhow::Error {
    let cih = p.with_extension("cih");
    let cihx = p.with_extension("cihx");
    let found = [&cihx, &cih].into_iter().find(|h| h.is_file());
    match found {
        Some(h) => bad_input(format!(
            "{}: a Photron recording is named by its header: give {}",
            p.display(),
            h.display()
        )),
        None => bad_input(format!(
            "{}: a Photron recording is named by its header ({} or {}), which is not there",
            p.display(),
            cih.display(),
            cihx.display()
        )),
    }
}

/// Reads and checks the header `path` and the size of the `.mraw` beside it.
pub fn read_header(path: &Path) -> anyhow::Result<PhotronHeader> {
    let bytes = std::fs::read(path)
        .map_err(|e| bad_input(format!("{}: cannot read: {e}", path.display())))?;
    let text = String::from_utf8_lossy(&bytes);
    let fields = if ext(path).as_deref() == Some("cihx") {
        cihx_fields(&text).map_err(|e| bad_input(format!("{}: {e}", path.display())))?
    } else {
        cih_fields(&text)
    };
    let h = header_of(path, &fields)?;
    check_mraw(&h)?;
    Ok(h)
}

/// The fields of a header, by their `.cih` names.
type Fields = Vec<(String, String)>;

/// `Key : Value` lines up to the first empty line.
fn cih_fields(text: &str) -> Fields {
    text.lines()
        .take_while(|l| !l.trim().is_empty())
        .filter_map(|l| l.split_once(" : "))
        .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
        .collect()
}

/// The XML between `<cih>` and `</cih>` (after any binary prefix), as `.cih` fields.
fn cihx_fields(text: &str) -> Result<Fields, String> {
    let (Some(a), Some(b)) = (text.find("<cih>"), text.rfind("</cih>")) else {
        return Err("no <cih> ... </cih> element: not a Photron .cihx header".into());
    };
    let xml = &text[a..b + "</cih>".len()];
    let doc = roxmltree::Document::parse(xml).map_err(|e| format!("malformed XML: {e}"))?;
    let at = |path: &[&str]| -> Option<String> {
        let mut node = doc.root_element();
        for name in path {
            node = node.children().find(|c| c.has_tag_name(*name))?;
        }
        Some(node.text().unwrap_or("").trim().to_string())
    };
    let mut f = Fields::new();
    let mut put = |key: &str, path: &[&str]| {
        if let Some(v) = at(path) {
            f.push((key.to_string(), v));
        }
    };
    put("Image Width", &["imageDataInfo", "resolution", "width"]);
    put("Image Height", &["imageDataInfo", "resolution", "height"]);
    put("Total Frame", &["frameInfo", "totalFrame"]);
    put("Color Bit", &["imageDataInfo", "colorInfo", "bit"]);
    put("Color Type", &["imageDataInfo", "colorInfo", "type"]);
    put("File Format", &["imageFileInfo", "fileFormat"]);
    put("Record Rate(fps)", &["recordInfo", "recordRate"]);
    put("shutterSpeedNsec", &["recordInfo", "shutterSpeedNsec"]);
    put("shutterSpeed", &["recordInfo", "shutterSpeed"]);
    Ok(f)
}

fn header_of(path: &Path, f: &Fields) -> anyhow::Result<PhotronHeader> {
    let get = |k: &str| f.iter().find(|(key, _)| key == k).map(|(_, v)| v.as_str());
    let need = |k: &str| {
        get(k).ok_or_else(|| {
            bad_input(format!(
                "{}: no `{k}` in the header: not a Photron header, or a damaged one",
                path.display()
            ))
        })
    };
    let int = |k: &str| -> anyhow::Result<usize> {
        let v = need(k)?;
        v.parse::<usize>().map_err(|_| {
            bad_input(format!(
                "{}: `{k}` is `{v}`, not a whole number",
                path.display()
            ))
        })
    };
    let format = need("File Format")?;
    if !format.eq_ignore_ascii_case("mraw") {
        return Err(bad_input(format!(
            "{}: file format `{format}`: only MRaw recordings are read (export the recording \
             as MRaw, or as TIFF frames)",
            path.display()
        )));
    }
    let bits = int("Color Bit")? as u32;
    if ![8, 12, 16].contains(&bits) {
        return Err(bad_input(format!(
            "{}: {bits} bits per pixel: 8, 12 (packed) and 16 are read",
            path.display()
        )));
    }
    let colour = get("Color Type").unwrap_or("Mono").to_string();
    if colour.eq_ignore_ascii_case("color") {
        return Err(bad_input(format!(
            "{}: colour type Color (interleaved RGB): only Mono and Raw (Bayer) recordings \
             are read",
            path.display()
        )));
    }
    let (width, height, frames) = (
        int("Image Width")?,
        int("Image Height")?,
        int("Total Frame")?,
    );
    if width == 0 || height == 0 || frames == 0 {
        return Err(bad_input(format!(
            "{}: {width} x {height} pixels, {frames} frames: an empty recording",
            path.display()
        )));
    }
    let name = path.display().to_string();
    let frames = super::checked_frame_count(&name, frames as u64)?;
    super::checked_frame_bytes(&name, width as u64, height as u64, u64::from(bits))?;
    if bits == 12 && (width * height) % 2 != 0 {
        return Err(bad_input(format!(
            "{}: 12-bit packed frames of {width} x {height} (an odd number of pixels) do not \
             fill whole bytes",
            path.display()
        )));
    }
    let shutter_s = match (get("shutterSpeedNsec"), get("shutterSpeed")) {
        (Some(ns), _) => ns.parse::<f64>().ok().map(|ns| ns * 1e-9),
        (None, Some(per_s)) => per_s.parse::<f64>().ok().map(|r| 1.0 / r),
        (None, None) => get("Shutter Speed(s)").and_then(seconds),
    }
    .filter(|s| s.is_finite() && *s > 0.0);
    let fps = get("Record Rate(fps)")
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|v| v.is_finite() && *v > 0.0);
    Ok(PhotronHeader {
        header: path.to_path_buf(),
        mraw: path.with_extension("mraw"),
        width,
        height,
        frames,
        bits,
        fps,
        shutter_s,
        colour,
    })
}

/// A shutter as `.cih` writes it: `1/5000` or a decimal, in seconds.
fn seconds(v: &str) -> Option<f64> {
    match v.split_once('/') {
        Some((n, d)) => Some(n.trim().parse::<f64>().ok()? / d.trim().parse::<f64>().ok()?),
        None => v.trim().parse().ok(),
    }
}

fn check_mraw(h: &PhotronHeader) -> anyhow::Result<()> {
    let len = std::fs::metadata(&h.mraw)
        .map_err(|e| {
            bad_input(format!(
                "{}: the frames file of {} cannot be read: {e}",
                h.mraw.display(),
                h.header.display()
            ))
        })?
        .len();
    let per = h.frame_bytes() as u64;
    let want = per * h.frames as u64;
    if len != want {
        let whole = len / per;
        return Err(bad_input(format!(
            "{}: {len} bytes, but {} states {} frames of {} x {} at {} bits ({want} bytes); \
             the file holds {whole} whole frame(s){}",
            h.mraw.display(),
            h.header.display(),
            h.frames,
            h.width,
            h.height,
            h.bits,
            if len < want {
                ": truncated"
            } else {
                " and more"
            }
        )));
    }
    Ok(())
}

/// The frames of a Photron recording, read one at a time into the caller's buffer.
#[derive(Debug)]
pub struct MrawFrames {
    header: PhotronHeader,
    file: std::io::BufReader<std::fs::File>,
    bytes: Vec<u8>,
    next: usize,
}

impl MrawFrames {
    /// Opens the recording named by its header `path`.
    pub fn open(path: &Path) -> anyhow::Result<MrawFrames> {
        let header = read_header(path)?;
        let file = std::fs::File::open(&header.mraw)
            .map_err(|e| bad_input(format!("{}: cannot open: {e}", header.mraw.display())))?;
        Ok(MrawFrames {
            bytes: vec![0; header.frame_bytes()],
            header,
            file: std::io::BufReader::with_capacity(1 << 20, file),
            next: 0,
        })
    }

    /// The header.
    pub fn header(&self) -> &PhotronHeader {
        &self.header
    }

    /// Places the reader at frame `k` (0-based): the next one read (frames are `frame_bytes`
    /// apart in the `.mraw`, so nothing before it is read).
    pub fn skip_to(&mut self, k: usize) -> anyhow::Result<()> {
        use std::io::Seek as _;
        let at = (k.min(self.header.frames) as u64) * self.header.frame_bytes() as u64;
        self.file
            .seek(std::io::SeekFrom::Start(at))
            .map_err(|e| bad_input(format!("{}: cannot seek: {e}", self.header.mraw.display())))?;
        self.next = k.min(self.header.frames);
        Ok(())
    }

    /// Reads the next frame into `frame` (its buffer reused); `Ok(None)` after the last one.
    /// Returns the frame's 0-based index.
    pub fn next_frame(&mut self, frame: &mut GreyFrame) -> anyhow::Result<Option<usize>> {
        let h = &self.header;
        if self.next >= h.frames {
            return Ok(None);
        }
        let k = self.next;
        self.file.read_exact(&mut self.bytes).map_err(|e| {
            bad_input(format!(
                "{} frame {} of {}: cannot read: {e}",
                h.mraw.display(),
                k + 1,
                h.frames
            ))
        })?;
        let (width, height) = (h.width, h.height);
        match h.bits {
            8 => frame.u8_pixels(width, height).copy_from_slice(&self.bytes),
            16 => unpack_16_into(&self.bytes, frame.u16_pixels(width, height)),
            _ => unpack_12_into(&self.bytes, frame.u16_pixels(width, height)),
        }
        self.next += 1;
        Ok(Some(k))
    }
}

/// Little-endian 16-bit words (appended to `out`).
pub fn unpack_16(bytes: &[u8], out: &mut Vec<u16>) {
    let at = out.len();
    out.resize(at + bytes.len() / 2, 0);
    unpack_16_into(bytes, &mut out[at..]);
}

/// Little-endian 16-bit words into `out` (`bytes.len() / 2` values).
pub fn unpack_16_into(bytes: &[u8], out: &mut [u16]) {
    for (o, b) in out.iter_mut().zip(bytes.chunks_exact(2)) {
        *o = u16::from_le_bytes([b[0], b[1]]);
    }
}

/// Two 12-bit pixels in three bytes, most significant bit first (appended to `out`).
pub fn unpack_12(bytes: &[u8], out: &mut Vec<u16>) {
    let at = out.len();
    out.resize(at + bytes.len() / 3 * 2, 0);
    unpack_12_into(bytes, &mut out[at..]);
}

/// [`unpack_12`] into `out` (`bytes.len() / 3 * 2` values).
pub fn unpack_12_into(bytes: &[u8], out: &mut [u16]) {
    for (o, b) in out.chunks_exact_mut(2).zip(bytes.chunks_exact(3)) {
        let (b0, b1, b2) = (u16::from(b[0]), u16::from(b[1]), u16::from(b[2]));
        o[0] = b0 << 4 | b1 >> 4;
        o[1] = (b1 & 15) << 8 | b2;
    }
}

/// Writes a Photron recording (`.cih` text header and `.mraw`) of `frames` (`width * height`
/// values each, below `2^bits`) at `bits` = 8, 12 or 16, for tests and synthetic recordings.
pub fn write_recording(
    cih: &Path,
    (width, height): (usize, usize),
    bits: u32,
    fps: f64,
    shutter_s: f64,
    frames: &[Vec<u16>],
) -> anyhow::Result<()> {
    let mut raw = Vec::new();
    for f in frames {
        match bits {
            8 => raw.extend(f.iter().map(|&v| v as u8)),
            16 => raw.extend(f.iter().flat_map(|v| v.to_le_bytes())),
            12 => {
                for p in f.chunks(2) {
                    let (a, b) = (p[0], p.get(1).copied().unwrap_or(0));
                    raw.extend([(a >> 4) as u8, ((a & 15) << 4 | b >> 8) as u8, b as u8]);
                }
            }
            _ => anyhow::bail!("{bits} bits: 8, 12 or 16"),
        }
    }
    let text = format!(
        "#Camera Information Header\nRecord Rate(fps) : {fps}\nShutter Speed(s) : 1/{}\n\
         Total Frame : {}\nImage Width : {width}\nImage Height : {height}\nColor Type : Mono\n\
         Color Bit : {bits}\nFile Format : MRaw\nEffectiveBit Depth : {}\n\
         EffectiveBit Side : Lower\n\n",
        (1.0 / shutter_s).round(),
        frames.len(),
        bits.min(12),
    );
    std::fs::write(cih, text)?;
    std::fs::write(cih.with_extension("mraw"), raw)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn twelve_bit_pixels_are_unpacked_most_significant_bit_first() {
        let mut out = Vec::new();
        unpack_12(&[0xAB, 0xCD, 0xEF, 0x00, 0x1F, 0xFF], &mut out);
        assert_eq!(out, [0xABC, 0xDEF, 0x001, 0xFFF]);
        let mut out = Vec::new();
        unpack_16(&[0x34, 0x12, 0xFF, 0x0F], &mut out);
        assert_eq!(out, [0x1234, 0x0FFF]);
    }

    #[test]
    fn headers_of_both_kinds_are_read() {
        let f =
            cih_fields("#Camera\nRecord Rate(fps) : 60000\nShutter Speed(s) : 1/800000\n\nX : 1");
        assert_eq!(f.len(), 2);
        assert_eq!(seconds("1/800000"), Some(1.0 / 800_000.0));
        let xml = "\u{1}\u{2}binary<cih><imageDataInfo><resolution><width>8</width>\
                   <height>4</height></resolution><colorInfo><type>Raw</type><bit>12</bit>\
                   </colorInfo></imageDataInfo><frameInfo><totalFrame>3</totalFrame></frameInfo>\
                   <imageFileInfo><fileFormat>Mraw</fileFormat></imageFileInfo><recordInfo>\
                   <recordRate>50000</recordRate><shutterSpeed>200000</shutterSpeed>\
                   <shutterSpeedNsec>5000</shutterSpeedNsec></recordInfo></cih>";
        let f = cihx_fields(xml).unwrap();
        let h = header_of(Path::new("r.cihx"), &f).unwrap();
        assert_eq!((h.width, h.height, h.frames, h.bits), (8, 4, 3, 12));
        assert_eq!(h.fps, Some(50_000.0));
        assert!((h.shutter_s.unwrap() - 5e-6).abs() < 1e-15);
        assert!(h.note().unwrap().contains("Bayer"));
    }
}
