//! A cluttered scene around the targets of a synthetic recording, as a phone or an ordinary
//! camera sees a test: the rendered frame (the tags on the dark structure) framed by a
//! textured warm-white wall as bright as the tags above and below it, and a phone (a bright
//! rectangle) beside it, written as colour JPEG frames (and, with `--video`, the same colour
//! frames losslessly in `frames.mkv`). A global threshold that finds the
//! tags finds the wall and the phone too; a window around each tag (`--points`) sees only the
//! structure and its tag.

use image::{Rgb, RgbImage};

/// Rows of wall above and below the structure, px.
pub const WALL_PX: usize = 24;
/// Columns beside the structure holding the phone, px.
pub const SIDE_PX: usize = 40;
/// JPEG quality of the frames.
const QUALITY: u8 = 92;

/// The static wall texture and the layout of the composed frames.
#[derive(Debug, Clone)]
pub struct Clutter {
    /// The structure's frame size (the rendered frame), px.
    inner: (usize, usize),
    /// The wall's grey level per pixel of the composed frame (row-major).
    wall: Vec<f32>,
}

impl Clutter {
    /// The clutter around frames of `inner` size (width, height); the wall's texture comes
    /// from `seed`.
    pub fn new(inner: (usize, usize), seed: u64) -> Clutter {
        use rand::{Rng as _, SeedableRng as _};
        let (w, h) = Self::outer_of(inner);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x7761_6c6c);
        // a plaster-like texture: smooth blotches plus fine grain, 200 .. 250 grey levels
        let blotch: Vec<(f64, f64, f64)> = (0..12)
            .map(|_| {
                (
                    rng.random_range(0.0..w as f64),
                    rng.random_range(0.0..h as f64),
                    rng.random_range(-12.0..12.0),
                )
            })
            .collect();
        let wall = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x as f64, y as f64)))
            .map(|(x, y)| {
                let b: f64 = blotch
                    .iter()
                    .map(|&(bx, by, a)| a * (-((x - bx).powi(2) + (y - by).powi(2)) / 200.0).exp())
                    .sum();
                (225.0 + b + rng.random_range(-8.0..8.0)) as f32
            })
            .collect();
        Clutter { inner, wall }
    }

    fn outer_of((w, h): (usize, usize)) -> (usize, usize) {
        (w + SIDE_PX, h + 2 * WALL_PX)
    }

    /// Width and height of the composed frames.
    pub fn outer(&self) -> (usize, usize) {
        Self::outer_of(self.inner)
    }

    /// The composed colour frame of the rendered grey frame `px` (the structure: dark, tags
    /// bright): the wall warm white (R, G, B = 1, 0.95, 0.85 of its level), the structure grey
    /// (lifted by 20 levels: a dark grey beam, not black), the phone bright.
    pub fn compose(&self, px: &[u8]) -> RgbImage {
        let (iw, ih) = self.inner;
        let (w, h) = self.outer();
        let mut img = RgbImage::new(w as u32, h as u32);
        for y in 0..h {
            for x in 0..w {
                let inside = x < iw && (WALL_PX..WALL_PX + ih).contains(&y);
                let phone = x >= iw + 8
                    && x < iw + SIDE_PX - 8
                    && (WALL_PX + 10..WALL_PX + ih.saturating_sub(10)).contains(&y);
                let c = if inside {
                    let v = f32::from(px[(y - WALL_PX) * iw + x]).max(20.0);
                    [v, v, v]
                } else if phone {
                    [250.0, 250.0, 252.0]
                } else {
                    let v = self.wall[y * w + x];
                    [v, v * 0.95, v * 0.85]
                };
                img.put_pixel(
                    x as u32,
                    y as u32,
                    Rgb(c.map(|v| (v + 0.5).clamp(0.0, 255.0) as u8)),
                );
            }
        }
        img
    }
}

/// Writes a composed frame ([`Clutter::compose`]) as a JPEG at `path`.
pub fn write_jpeg(img: &RgbImage, path: &std::path::Path) -> anyhow::Result<()> {
    use anyhow::Context as _;
    let file =
        std::fs::File::create(path).with_context(|| format!("cannot write {}", path.display()))?;
    let mut enc =
        image::codecs::jpeg::JpegEncoder::new_with_quality(std::io::BufWriter::new(file), QUALITY);
    enc.encode_image(img)
        .with_context(|| format!("cannot write {}", path.display()))
}
