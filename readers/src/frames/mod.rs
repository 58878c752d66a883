//! Frames as they come from a camera or a file: the decoded grey frame, files (PNG/TIFF
//! directories, patterns, multi-page TIFF) and videos (through FFmpeg). Every frame source of the
//! toolkit lives here; what is done with a frame (centroid, tracking, analysis) lives above it.

pub mod files;
pub mod phantom;
pub mod phantom_lut;
pub mod photron;
mod rates;
pub mod video;

pub use files::{
    centroid_source, centroid_source_seen, discover_frames, for_each_tiff_page, ignored_note,
    load_frame, open_frames, Discovered, FrameDepth, FrameRange, FrameSource,
};
pub use rates::{resolve_rates, Rates};

use crate::bad_input;
use firmware_core::centroid::{self, Centroid, CentroidConfig};

/// A grey frame as a PNG, for a page: its own size in pixels (the PNG may be scaled down:
/// [`GreyFrame::to_image_within`]).
#[derive(Debug, Clone, PartialEq)]
pub struct FrameImage {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// The frame as PNG bytes.
    pub png: Vec<u8>,
}

/// The most bytes one stored or decoded frame may take (a 16-bit frame of 16 384 x 16 384
/// pixels): a header that states a larger frame is refused before anything is allocated.
pub const MAX_FRAME_BYTES: u64 = 1 << 29;

/// The most frames a camera file's header may state (a Phantom's offset table is 8 bytes a
/// frame, read whole): a larger count is refused before anything is allocated.
pub const MAX_FRAMES: u64 = 50_000_000;

/// The bytes of one frame of `width x height` pixels at `bits` bits per pixel, as a header
/// states them: refused (naming `name`, the file) when the product overflows or exceeds
/// [`MAX_FRAME_BYTES`], so that no size taken from a header allocates more than that.
pub fn checked_frame_bytes(name: &str, width: u64, height: u64, bits: u64) -> anyhow::Result<u64> {
    let bytes = width
        .checked_mul(height)
        .and_then(|p| p.checked_mul(bits))
        .map(|b| b.div_ceil(8));
    match bytes {
        Some(b) if b <= MAX_FRAME_BYTES => Ok(b),
        _ => Err(bad_input(format!(
            "{name}: its header states frames of {width} x {height} pixels at {bits} bits, \
             more than {} MiB a frame: a damaged header, or a frame too large to read",
            MAX_FRAME_BYTES >> 20
        ))),
    }
}

/// Refuses a frame count taken from a header (of `name`) above [`MAX_FRAMES`].
pub fn checked_frame_count(name: &str, frames: u64) -> anyhow::Result<usize> {
    if frames > MAX_FRAMES {
        return Err(bad_input(format!(
            "{name}: its header states {frames} frames, more than {MAX_FRAMES}: a damaged \
             header, or a recording too long to read whole (split it)"
        )));
    }
    usize::try_from(frames).map_err(|_| bad_input(format!("{name}: {frames} frames")))
}

/// A grey frame in memory, 8 or 16 bits per pixel, row-major without padding.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum GreyFrame {
    /// 8-bit pixels.
    U8 {
        /// Columns.
        width: usize,
        /// Rows.
        height: usize,
        /// `width * height` pixels, row 0 first.
        data: Vec<u8>,
    },
    /// 16-bit pixels.
    U16 {
        /// Columns.
        width: usize,
        /// Rows.
        height: usize,
        /// `width * height` pixels, row 0 first.
        data: Vec<u16>,
    },
}

impl GreyFrame {
    /// The frame for a page (`report.html`, `pick.html`): an 8-bit grey PNG (a 16-bit frame
    /// scaled so its largest value is 255).
    pub fn to_image(&self) -> anyhow::Result<FrameImage> {
        self.to_image_within(u32::MAX)
    }

    /// As [`to_image`](Self::to_image), the PNG scaled down (area-averaged) so that its longer
    /// side is at most `max_side` pixels; `width` and `height` stay the frame's own, so that a
    /// page drawing the PNG over them keeps full-resolution pixel coordinates.
    pub fn to_image_within(&self, max_side: u32) -> anyhow::Result<FrameImage> {
        let (w, h) = self.dimensions();
        let bytes: Vec<u8> = match self {
            GreyFrame::U8 { data, .. } => data.clone(),
            GreyFrame::U16 { data, .. } => {
                let top = f64::from(data.iter().copied().max().unwrap_or(0).max(1));
                data.iter()
                    .map(|v| (f64::from(*v) * 255.0 / top).round() as u8)
                    .collect()
            }
        };
        let img = image::GrayImage::from_raw(w as u32, h as u32, bytes)
            .ok_or_else(|| anyhow::anyhow!("a {w} x {h} frame of the wrong length"))?;
        let long = w.max(h) as f64;
        let img = if long > f64::from(max_side) {
            let k = f64::from(max_side) / long;
            let (sw, sh) = (
                ((w as f64 * k).round() as u32).max(1),
                ((h as f64 * k).round() as u32).max(1),
            );
            image::imageops::resize(&img, sw, sh, image::imageops::FilterType::Triangle)
        } else {
            img
        };
        let mut png = std::io::Cursor::new(Vec::new());
        img.write_to(&mut png, image::ImageFormat::Png)
            .map_err(|e| anyhow::anyhow!("PNG of a {w} x {h} frame: {e}"))?;
        Ok(FrameImage {
            width: w as u32,
            height: h as u32,
            png: png.into_inner(),
        })
    }

    /// `(width, height)` in pixels.
    pub fn dimensions(&self) -> (usize, usize) {
        match self {
            GreyFrame::U8 { width, height, .. } | GreyFrame::U16 { width, height, .. } => {
                (*width, *height)
            }
        }
    }

    /// The frame made an 8-bit `width x height` one, its buffer reused (resized, contents
    /// unspecified): the pixels to fill, row 0 first.
    pub fn u8_pixels(&mut self, width: usize, height: usize) -> &mut [u8] {
        self.pixels(width, height)
    }

    /// [`u8_pixels`](Self::u8_pixels) for a 16-bit frame.
    pub fn u16_pixels(&mut self, width: usize, height: usize) -> &mut [u16] {
        self.pixels(width, height)
    }

    /// The frame made a `width x height` one of depth `P`, its buffer reused when it had that
    /// depth.
    fn pixels<P: Depth>(&mut self, width: usize, height: usize) -> &mut [P] {
        if P::buffer(self).is_none() {
            *self = P::frame(width, height, Vec::new());
        }
        match P::buffer(self) {
            Some((w, h, data)) => {
                (*w, *h) = (width, height);
                data.resize(width * height, P::default());
                data
            }
            None => &mut [],
        }
    }

    /// Centroid with the firmware-core single-target centroider. `label` names the frame (file,
    /// page) in the error when its shape is inconsistent.
    pub fn centroid(&self, config: &CentroidConfig, label: &str) -> anyhow::Result<Centroid> {
        fn of<P: centroid::Pixel>(
            config: &CentroidConfig,
            data: &[P],
            (width, height): (usize, usize),
        ) -> Result<Centroid, centroid::FrameError> {
            centroid::Frame::new(data, width, height, width)
                .and_then(|f| centroid::centroid(config, &f))
        }
        if let (GreyFrame::U8 { .. }, Some(s)) = (self, config.saturation) {
            if s > 255 {
                return Err(bad_input(format!(
                    "{label}: $saturation {s} is above 255, the largest level of an 8-bit \
                     frame: no pixel could ever be flagged saturated"
                )));
            }
        }
        let r = match self {
            GreyFrame::U8 { data, .. } => of(config, data, self.dimensions()),
            GreyFrame::U16 { data, .. } => of(config, data, self.dimensions()),
        };
        r.map_err(|e| bad_input(format!("{label}: cannot centroid the frame: {e}")))
    }
}

/// A grey depth a [`GreyFrame`] holds: its variant made and opened.
trait Depth: Copy + Default {
    /// A frame of this depth.
    fn frame(width: usize, height: usize, data: Vec<Self>) -> GreyFrame;
    /// The frame's size and buffer if it has this depth.
    fn buffer(f: &mut GreyFrame) -> Option<(&mut usize, &mut usize, &mut Vec<Self>)>;
}

/// [`Depth`] for the pixel type `$T` of the variant `$Variant` (`$Other` the other one).
macro_rules! depth {
    ($T:ty, $Variant:ident, $Other:ident) => {
        impl Depth for $T {
            fn frame(width: usize, height: usize, data: Vec<$T>) -> GreyFrame {
                GreyFrame::$Variant {
                    width,
                    height,
                    data,
                }
            }
            fn buffer(f: &mut GreyFrame) -> Option<(&mut usize, &mut usize, &mut Vec<$T>)> {
                match f {
                    GreyFrame::$Variant {
                        width,
                        height,
                        data,
                    } => Some((width, height, data)),
                    GreyFrame::$Other { .. } => None,
                }
            }
        }
    };
}
depth!(u8, U8, U16);
depth!(u16, U16, U8);
