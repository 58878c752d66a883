//! Phantom (Vision Research) `.cine` recordings, read one frame at a time.
//!
//! The file: a `CINEFILEHEADER` (44 bytes: `"CI"`, the image count and the offsets of the
//! bitmap header, the setup and the image offsets), a `BITMAPINFOHEADER` (width, height, bits per
//! pixel, compression), the `SETUP` (frame rate at byte 768, shutter in ns at 1568, the sensor's
//! real bit depth at 896; layout as pycine's `cine.py`), optional tagged blocks (block 1002: one
//! time stamp per frame, 32.32 fixed point seconds) and a table of 64-bit offsets, one per frame.
//! Each frame is an annotation (its size first, the image size in its last 4 bytes), then the
//! image.
//!
//! What is read (our CI compares it with pycine on files written by our tests):
//! - uncompressed frames (`biCompression` 0) of 8 bits (one byte a pixel) or 16 bits
//!   (little-endian words, the sensor's `RealBPP` levels); stored bottom row first, as the bitmap
//!   header's positive height says, and turned upright here (a negative height: top first);
//! - packed 10-bit frames (`biCompression` 256, "P10"): four pixels in five bytes, read as a
//!   big-endian 40-bit word, most significant bit first, top row first; each code linearised
//!   to 12 bits with the standard table ([`super::phantom_lut::LIN_LUT`]), nothing else (no
//!   black/white-level stretch);
//! - packed 12-bit frames (`biCompression` 1024, "P12L"): two pixels in three bytes, most
//!   significant bit first, top row first, values as stored;
//! - 16-bit frames for everything but 8-bit ones;
//! - a colour camera's recording (`bEnableColor`; its frames are the sensor's Bayer mosaic, one
//!   value a pixel) is read as that grey mosaic, as for Photron's `Raw`, with a note; frames of
//!   more than 16 bits a pixel (interleaved RGB) are refused by the bit-count check;
//! - with a time-stamp block, every frame interval must be one frame period (to 1 µs): a gap
//!   (a dropped frame) is an error naming the frame.

use super::GreyFrame;
use crate::bad_input;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// Byte offsets in the `SETUP` structure (pycine's `cine.py`, software release 792).
const SETUP_FRAME_RATE: usize = 768;
const SETUP_SHUTTER_US: usize = 772;
const SETUP_ENABLE_COLOR: usize = 788;
const SETUP_REAL_BPP: usize = 896;
const SETUP_SHUTTER_NS: usize = 1568;
/// The part of `SETUP` that holds every field read here.
const SETUP_READ: usize = SETUP_SHUTTER_NS + 4;
/// `biCompression` of packed 10-bit and packed 12-bit frames.
const P10: u32 = 256;
const P12L: u32 = 1024;

/// What a cine header states.
#[derive(Debug, Clone, PartialEq)]
pub struct CineHeader {
    /// The file.
    pub path: PathBuf,
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Stored bottom row first (an uncompressed frame of positive height).
    pub bottom_up: bool,
    /// Bits per pixel as stored (8, 16; 10 or 12 for packed frames).
    pub bits: u32,
    /// `biCompression`: 0, 256 (packed 10-bit) or 1024 (packed 12-bit).
    pub compression: u32,
    /// The sensor's bit depth (`RealBPP`).
    pub real_bpp: u32,
    /// Frame rate, Hz.
    pub fps: Option<f64>,
    /// Exposure, s.
    pub shutter_s: Option<f64>,
    /// Where each frame's annotation starts.
    pub offsets: Vec<u64>,
    /// Per-frame time stamps, s (the time-stamp block), if any.
    pub times: Vec<f64>,
    /// A colour camera's recording (`bEnableColor`): the frames are its sensor's Bayer mosaic.
    pub colour: bool,
}

impl CineHeader {
    /// A remark for the report (a Bayer mosaic read as grey), if any.
    pub fn note(&self) -> Option<String> {
        self.colour.then(|| {
            format!(
                "{}: a colour camera's recording (a Bayer sensor's mosaic): read as the grey \
                 mosaic, one colour filter per pixel",
                self.path.display()
            )
        })
    }

    /// Bytes of one stored frame.
    pub fn image_bytes(&self) -> usize {
        let px = self.width * self.height;
        match self.compression {
            P10 => px * 5 / 4,
            P12L => px * 3 / 2,
            _ => px * self.bits as usize / 8,
        }
    }
}

/// Whether `p` names a cine file.
pub fn is_cine(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("cine"))
}

fn u16_at(b: &[u8], o: usize) -> u16 {
    b.get(o..o + 2)
        .map_or(0, |s| u16::from_le_bytes([s[0], s[1]]))
}

fn u32_at(b: &[u8], o: usize) -> u32 {
    b.get(o..o + 4)
        .map_or(0, |s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
}

fn i32_at(b: &[u8], o: usize) -> i32 {
    u32_at(b, o) as i32
}

/// Reads and checks the headers, the frame offsets and the time stamps of `path`.
pub fn read_header(path: &Path) -> anyhow::Result<CineHeader> {
    let name = path.display();
    let mut f =
        std::fs::File::open(path).map_err(|e| bad_input(format!("{name}: cannot open: {e}")))?;
    let len = f.metadata().map(|m| m.len()).unwrap_or(0);
    let mut read_at = |at: u64, n: usize, what: &str| -> anyhow::Result<Vec<u8>> {
        let mut b = vec![0u8; n];
        f.seek(SeekFrom::Start(at))
            .and_then(|_| f.read_exact(&mut b))
            .map_err(|e| bad_input(format!("{name}: cannot read the {what}: {e} (truncated?)")))?;
        Ok(b)
    };
    let fh = read_at(0, 44, "file header")?;
    if &fh[0..2] != b"CI" {
        return Err(bad_input(format!(
            "{name}: not a Phantom cine file (it does not start with \"CI\")"
        )));
    }
    let label = name.to_string();
    let count = super::checked_frame_count(&label, u64::from(u32_at(&fh, 20)))?;
    let (off_bmi, off_setup, off_offsets) = (u32_at(&fh, 24), u32_at(&fh, 28), u32_at(&fh, 32));
    // the offset table (8 bytes a frame) must lie inside the file before it is read
    if u64::from(off_offsets) + 8 * count as u64 > len {
        return Err(bad_input(format!(
            "{name}: its header states {count} frames, whose offset table ({} bytes at byte \
             {off_offsets}) reaches beyond the end of the file ({len} bytes): a damaged header \
             or a truncated file",
            8 * count as u64
        )));
    }
    let bmi = read_at(u64::from(off_bmi), 40, "bitmap header")?;
    let (width, raw_height) = (i32_at(&bmi, 4), i32_at(&bmi, 8));
    let (bits, compression) = (u32::from(u16_at(&bmi, 14)), u32_at(&bmi, 16));
    let setup = read_at(u64::from(off_setup), SETUP_READ, "setup")?;
    let (width, height) = (width.max(0) as usize, raw_height.unsigned_abs() as usize);
    if width == 0 || height == 0 || count == 0 {
        return Err(bad_input(format!(
            "{name}: {width} x {height} pixels, {count} frames: an empty recording"
        )));
    }
    let stored_bits = match compression {
        P10 => 10,
        P12L => 12,
        _ => u64::from(bits).max(8),
    };
    // bounded here; that every frame lies inside the file is check_layout's
    super::checked_frame_bytes(&label, width as u64, height as u64, stored_bits)?;
    let colour = u32_at(&setup, SETUP_ENABLE_COLOR) != 0;
    let bits = match (compression, bits) {
        (0, 8) | (0, 16) => bits,
        (P10, _) => 10,
        (P12L, _) => 12,
        (c, b) => {
            return Err(bad_input(format!(
                "{name}: {b} bits per pixel with compression {c}: uncompressed 8- and 16-bit, \
                 packed 10-bit (256) and packed 12-bit (1024) frames are read"
            )))
        }
    };
    let table = read_at(u64::from(off_offsets), count * 8, "image offsets")?;
    let offsets: Vec<u64> = table
        .chunks_exact(8)
        .map(|c| u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]))
        .collect();
    let rate = u32_at(&setup, SETUP_FRAME_RATE);
    let shutter_ns = u32_at(&setup, SETUP_SHUTTER_NS);
    let shutter_us = u32_at(&setup, SETUP_SHUTTER_US);
    let h = CineHeader {
        path: path.to_path_buf(),
        width,
        height,
        bottom_up: compression == 0 && raw_height > 0,
        bits,
        compression,
        real_bpp: u32_at(&setup, SETUP_REAL_BPP),
        fps: (rate > 0).then_some(f64::from(rate)),
        shutter_s: if shutter_ns > 0 {
            Some(f64::from(shutter_ns) * 1e-9)
        } else {
            (shutter_us > 0).then(|| f64::from(shutter_us) * 1e-6)
        },
        offsets,
        times: read_times(&mut read_at, &fh, off_setup, count)?,
        colour,
    };
    check_layout(&h, len)?;
    Ok(h)
}

/// The time-stamp block (tag 1002) between the setup and the image offsets, if there is one.
fn read_times(
    read_at: &mut impl FnMut(u64, usize, &str) -> anyhow::Result<Vec<u8>>,
    fh: &[u8],
    off_setup: u32,
    count: usize,
) -> anyhow::Result<Vec<f64>> {
    let off_offsets = u64::from(u32_at(fh, 32));
    let setup_len = u16_at(&read_at(u64::from(off_setup) + 142, 2, "setup")?, 0);
    let mut at = u64::from(off_setup) + u64::from(setup_len);
    while at + 8 <= off_offsets {
        let head = read_at(at, 8, "tagged block")?;
        let (size, tag) = (u64::from(u32_at(&head, 0)), u16_at(&head, 4));
        if size < 8 {
            break;
        }
        if tag == 1002 && size >= 8 + 8 * count as u64 {
            let b = read_at(at + 8, 8 * count, "time stamps")?;
            return Ok(b
                .chunks_exact(8)
                .map(|c| f64::from(u32_at(c, 4)) + f64::from(u32_at(c, 0)) / 4_294_967_296.0)
                .collect());
        }
        at += size;
    }
    Ok(Vec::new())
}

/// Every frame inside the file (the time stamps are checked where the rate matters,
/// [`check_times`]: a centroid of each frame needs none).
fn check_layout(h: &CineHeader, len: u64) -> anyhow::Result<()> {
    let name = h.path.display();
    for (k, &o) in h.offsets.iter().enumerate() {
        if o.saturating_add(8 + h.image_bytes() as u64) > len {
            return Err(bad_input(format!(
                "{name}: frame {} of {} lies beyond the end of the file ({len} bytes): \
                 truncated",
                k + 1,
                h.offsets.len()
            )));
        }
    }
    Ok(())
}

/// The time stamps of frames `range` (0-based) one frame period apart (to 1 µs), when the file
/// has them; an irregular interval is an error naming the frames, and the longest run of
/// regular frames as a `--frame-range` to analyse instead (a junk stamp on one frame of a
/// real camera's file would otherwise refuse the whole recording).
pub fn check_times(h: &CineHeader, range: std::ops::Range<usize>) -> anyhow::Result<()> {
    let Some(fps) = h.fps else {
        return Ok(());
    };
    let Some(times) = h.times.get(range.clone()) else {
        return Ok(());
    };
    let regular = |w: &[f64]| ((w[1] - w[0]) - 1.0 / fps).abs() <= 1e-6;
    let Some(bad) = times.windows(2).position(|w| !regular(w)) else {
        return Ok(());
    };
    // the longest run of frames (1-based, whole file) whose intervals are all regular
    let (mut best, mut start) = ((1usize, 1usize), 0usize);
    for (k, w) in h.times.windows(2).enumerate() {
        if regular(w) {
            if k + 2 - start > best.1 + 1 - best.0 {
                best = (start + 1, k + 2);
            }
        } else {
            start = k + 1;
        }
    }
    let k = range.start + bad;
    let dt = times[bad + 1] - times[bad];
    Err(bad_input(format!(
        "{}: frame {} comes {:.3} ms after frame {}, not one frame period ({:.3} ms at {fps} \
         fps): a dropped frame, a damaged time stamp or an irregular recording; frames {}..{} \
         are regular: analyse them with $frame_range {}..{}",
        h.path.display(),
        k + 2,
        dt * 1e3,
        k + 1,
        1e3 / fps,
        best.0,
        best.1,
        best.0,
        best.1
    )))
}

/// The frames of a cine file, read one at a time into the caller's buffer.
#[derive(Debug)]
pub struct CineFrames {
    header: CineHeader,
    file: std::fs::File,
    bytes: Vec<u8>,
    next: usize,
}

impl CineFrames {
    /// Opens `path`.
    pub fn open(path: &Path) -> anyhow::Result<CineFrames> {
        let header = read_header(path)?;
        let file = std::fs::File::open(path)
            .map_err(|e| bad_input(format!("{}: cannot open: {e}", path.display())))?;
        Ok(CineFrames {
            bytes: vec![0; header.image_bytes()],
            header,
            file,
            next: 0,
        })
    }

    /// The header.
    pub fn header(&self) -> &CineHeader {
        &self.header
    }

    /// Places the reader at frame `k` (0-based): the next one read (the offset table gives
    /// every frame's place, so nothing before it is read).
    pub fn skip_to(&mut self, k: usize) {
        self.next = k;
    }

    /// Reads the next frame into `frame`, upright; `Ok(None)` after the last one. Returns the
    /// frame's 0-based index.
    pub fn next_frame(&mut self, frame: &mut GreyFrame) -> anyhow::Result<Option<usize>> {
        let h = &self.header;
        let k = self.next;
        let Some(&at) = h.offsets.get(k) else {
            return Ok(None);
        };
        let err = |e: std::io::Error| {
            bad_input(format!(
                "{} frame {} of {}: cannot read: {e}",
                h.path.display(),
                k + 1,
                h.offsets.len()
            ))
        };
        let mut ann = [0u8; 4];
        self.file.seek(SeekFrom::Start(at)).map_err(err)?;
        self.file.read_exact(&mut ann).map_err(err)?;
        let ann = u64::from(u32::from_le_bytes(ann));
        self.file.seek(SeekFrom::Start(at + ann)).map_err(err)?;
        self.file.read_exact(&mut self.bytes).map_err(err)?;
        let (w, rows) = (h.width, h.height);
        // the source row of output row r: bottom-up frames are turned upright
        let src = |r: usize| if h.bottom_up { rows - 1 - r } else { r };
        if h.bits == 8 {
            let data = frame.u8_pixels(w, rows);
            for (r, out) in data.chunks_exact_mut(w).enumerate() {
                out.copy_from_slice(&self.bytes[src(r) * w..(src(r) + 1) * w]);
            }
        } else {
            let data = frame.u16_pixels(w, rows);
            match h.compression {
                P10 => unpack_10_into(&self.bytes, data),
                P12L => super::photron::unpack_12_into(&self.bytes, data),
                _ => {
                    for (r, out) in data.chunks_exact_mut(w).enumerate() {
                        let row = &self.bytes[src(r) * 2 * w..(src(r) + 1) * 2 * w];
                        super::photron::unpack_16_into(row, out);
                    }
                }
            }
        }
        self.next += 1;
        Ok(Some(k))
    }
}

/// Four 10-bit codes in five bytes (a big-endian 40-bit word, most significant bit first),
/// each linearised to 12 bits ([`super::phantom_lut::LIN_LUT`]); appended to `out`.
pub fn unpack_10(bytes: &[u8], out: &mut Vec<u16>) {
    let at = out.len();
    out.resize(at + bytes.len() / 5 * 4, 0);
    unpack_10_into(bytes, &mut out[at..]);
}

/// [`unpack_10`] into `out` (`bytes.len() / 5 * 4` values).
pub fn unpack_10_into(bytes: &[u8], out: &mut [u16]) {
    let lut = &super::phantom_lut::LIN_LUT;
    for (o, b) in out.chunks_exact_mut(4).zip(bytes.chunks_exact(5)) {
        let word = u64::from(b[0]) << 32
            | u64::from(b[1]) << 24
            | u64::from(b[2]) << 16
            | u64::from(b[3]) << 8
            | u64::from(b[4]);
        o[0] = lut[(word >> 30) as usize & 0x3FF];
        o[1] = lut[(word >> 20) as usize & 0x3FF];
        o[2] = lut[(word >> 10) as usize & 0x3FF];
        o[3] = lut[word as usize & 0x3FF];
    }
}

/// Packs 10-bit codes four to five bytes (the inverse of [`unpack_10`] before the table).
pub fn pack_10(codes: &[u16]) -> Vec<u8> {
    let mut out = Vec::with_capacity(codes.len() * 5 / 4);
    for c in codes.chunks(4) {
        let word = (0..4).fold(0u64, |acc, i| {
            acc << 10 | u64::from(c.get(i).copied().unwrap_or(0) & 0x3FF)
        });
        out.extend_from_slice(&word.to_be_bytes()[3..]);
    }
    out
}

/// One frame's image bytes as a .cine stores them: packed 10-bit, or bottom row first, 8 or
/// 16 bits per pixel.
fn cine_image(
    f: &[u16],
    (width, height): (usize, usize),
    (bits, compression): (u16, u32),
) -> Vec<u8> {
    match (compression, bits) {
        (P10, _) => pack_10(f),
        (_, 8) => (0..height)
            .rev()
            .flat_map(|r| f[r * width..(r + 1) * width].iter().map(|&v| v as u8))
            .collect(),
        _ => (0..height)
            .rev()
            .flat_map(|r| {
                f[r * width..(r + 1) * width]
                    .iter()
                    .flat_map(|v| v.to_le_bytes())
            })
            .collect(),
    }
}

/// The setup block's fields a reader reads (rate, shutter, depth, black and white levels) and
/// the time block: one timestamp per frame at `fps`.
fn put_setup_and_times(
    b: &mut [u8],
    (s, setup_len): (usize, usize),
    (bits, compression): (u16, u32),
    (fps, shutter_ns): (u32, u32),
    n: usize,
) {
    let put = |b: &mut [u8], at: usize, v: &[u8]| b[at..at + v.len()].copy_from_slice(v);
    let time_block = 8 + 8 * n;
    put(b, s + 142, &(setup_len as u16).to_le_bytes());
    put(b, s + SETUP_FRAME_RATE, &fps.to_le_bytes());
    put(b, s + SETUP_SHUTTER_US, &(shutter_ns / 1000).to_le_bytes());
    // the sensor's depth, as cameras state it: 10 for packed 10-bit (Phantom's own files,
    // e.g. pycine's chart1.cine, say 10 there; the linearised values are 12-bit)
    let real: u32 = if compression == P10 {
        10
    } else {
        u32::from(bits).min(12)
    };
    put(b, s + SETUP_REAL_BPP, &real.to_le_bytes());
    put(b, s + SETUP_SHUTTER_NS, &shutter_ns.to_le_bytes());
    // BlackLevel 0, WhiteLevel full scale (pycine stretches between them: the identity)
    put(b, s + 5732, &0u32.to_le_bytes());
    put(b, s + 5736, &((1u32 << real) - 1).to_le_bytes());
    let t = s + setup_len;
    put(b, t, &(time_block as u32).to_le_bytes());
    put(b, t + 4, &1002u16.to_le_bytes());
    for k in 0..n {
        let ticks = (k as u64 * (1u64 << 32)) / u64::from(fps);
        let v = ((1000 + (ticks >> 32)) << 32) | (ticks & 0xFFFF_FFFF);
        let at = t + 8 + 8 * k;
        put(b, at, &((v & 0xFFFF_FFFF) as u32).to_le_bytes());
        put(b, at + 4, &((v >> 32) as u32).to_le_bytes());
    }
}

/// A cine file's frames as stored: `(width, height)`, the bitmap's bit count and compression
/// (0 with 8 or 16 bits; 256 with codes below 1024, packed), bottom-up rows for uncompressed
/// frames (as cameras write them), the frame rate and shutter, and a time-stamp block one frame
/// period apart. For tests and synthetic recordings; the layout is the one [`read_header`]
/// reads.
pub fn write_cine(
    path: &Path,
    (width, height): (usize, usize),
    (bits, compression): (u16, u32),
    (fps, shutter_ns): (u32, u32),
    frames: &[Vec<u16>],
) -> anyhow::Result<()> {
    let n = frames.len();
    let setup_len: usize = 13_484;
    let (off_bmi, off_setup) = (44usize, 84usize);
    let time_block = 8 + 8 * n;
    let off_offsets = off_setup + setup_len + time_block;
    let images: Vec<Vec<u8>> = frames
        .iter()
        .map(|f| cine_image(f, (width, height), (bits, compression)))
        .collect();
    let mut b = vec![0u8; off_offsets + 8 * n];
    let put = |b: &mut Vec<u8>, at: usize, v: &[u8]| b[at..at + v.len()].copy_from_slice(v);
    put(&mut b, 0, b"CI");
    put(&mut b, 2, &44u16.to_le_bytes());
    put(&mut b, 6, &1u16.to_le_bytes());
    put(&mut b, 12, &(n as u32).to_le_bytes());
    put(&mut b, 20, &(n as u32).to_le_bytes());
    put(&mut b, 24, &(off_bmi as u32).to_le_bytes());
    put(&mut b, 28, &(off_setup as u32).to_le_bytes());
    put(&mut b, 32, &(off_offsets as u32).to_le_bytes());
    put(&mut b, off_bmi, &40u32.to_le_bytes());
    put(&mut b, off_bmi + 4, &(width as i32).to_le_bytes());
    put(&mut b, off_bmi + 8, &(height as i32).to_le_bytes());
    put(&mut b, off_bmi + 12, &1u16.to_le_bytes());
    // packed frames: the bit count of the unpacked words, 16, as the cameras write it
    let stored_bits: u16 = if matches!(compression, P10 | P12L) {
        16
    } else {
        bits
    };
    put(&mut b, off_bmi + 14, &stored_bits.to_le_bytes());
    put(&mut b, off_bmi + 16, &compression.to_le_bytes());
    put(
        &mut b,
        off_bmi + 20,
        &(images[0].len() as u32).to_le_bytes(),
    );
    put_setup_and_times(
        &mut b,
        (off_setup, setup_len),
        (bits, compression),
        (fps, shutter_ns),
        n,
    );
    for (k, img) in images.iter().enumerate() {
        let at = b.len() as u64;
        put(&mut b, off_offsets + 8 * k, &at.to_le_bytes());
        b.extend_from_slice(&8u32.to_le_bytes());
        b.extend_from_slice(&(img.len() as u32).to_le_bytes());
        b.extend_from_slice(img);
    }
    std::fs::write(path, b)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packed_ten_bit_codes_are_read_most_significant_bit_first_and_linearised() {
        // codes 1, 2, 3, 1023 -> 0000000001 0000000010 0000000011 1111111111
        let packed = pack_10(&[1, 2, 3, 1023]);
        assert_eq!(packed, [0x00, 0x40, 0x20, 0x0F, 0xFF]);
        let mut out = Vec::new();
        unpack_10(&packed, &mut out);
        let lut = super::super::phantom_lut::LIN_LUT;
        assert_eq!(out, [lut[1], lut[2], lut[3], lut[1023]]);
        assert_eq!((lut[0], lut[1023]), (2, 4095));
    }

    #[test]
    fn written_files_read_back_upright() {
        let dir = tempfile::tempdir().unwrap();
        let frames: Vec<Vec<u16>> = (0..3u16)
            .map(|k| (0..12u16).map(|i| i * 10 + k).collect())
            .collect();
        for (bits, comp) in [(8u16, 0u32), (16, 0), (10, P10)] {
            let p = dir.path().join(format!("r{bits}.cine"));
            write_cine(&p, (4, 3), (bits, comp), (500, 1_000_000), &frames).unwrap();
            let mut r = CineFrames::open(&p).unwrap();
            assert_eq!(r.header().fps, Some(500.0));
            assert_eq!(r.header().shutter_s, Some(1e-3));
            assert_eq!(r.header().times.len(), 3);
            let mut f = GreyFrame::U8 {
                width: 0,
                height: 0,
                data: Vec::new(),
            };
            for (k, want) in frames.iter().enumerate() {
                assert_eq!(r.next_frame(&mut f).unwrap(), Some(k));
                let got: Vec<u16> = match &f {
                    GreyFrame::U8 { data, .. } => data.iter().map(|&v| u16::from(v)).collect(),
                    GreyFrame::U16 { data, .. } => data.clone(),
                };
                let want: Vec<u16> = match comp {
                    P10 => want
                        .iter()
                        .map(|&c| super::super::phantom_lut::LIN_LUT[c as usize])
                        .collect(),
                    _ => want.clone(),
                };
                assert_eq!(got, want, "{bits} bits frame {k}");
            }
            assert_eq!(r.next_frame(&mut f).unwrap(), None);
        }
    }
}
