//! The target a rig's camera looks at: a physical object of the rig (its size and contrast are
//! the rig's constants, `model::cantilever::TARGET`), drawn by the simulation's `imaging`.

use serde::{Deserialize, Serialize};

/// What is painted on the disk (`[imaging] target_texture`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Texture {
    /// A uniform disk (the paper's target; the default).
    #[default]
    Plain,
    /// Painted speckle: dark Gaussian dots of sigma [`DOT_SIGMA_PX`] on the disk, one
    /// per cell of a [`DOT_PITCH_PX`] grid, jittered by up to a fifth of the pitch (dots at
    /// least two sigmas apart, so the paint never clips to black and stays band-limited), each
    /// darkening the paint by up to [`DOT_DEPTH`] (a fixed pattern: the same physical
    /// target in every run). What a gradient tracker needs and a threshold cannot use.
    Speckle,
}

/// Sigma of a speckle dot, px: wide enough that the pattern stays band-limited (its spectrum
/// is 1.5e-5 of the DC at the Nyquist frequency), as the renderer's phase shift needs.
pub const DOT_SIGMA_PX: f64 = 1.5;
/// Spacing of the speckle grid, px.
pub const DOT_PITCH_PX: f64 = 5.0;
/// How much a dot's centre darkens the paint (fraction of the level).
pub const DOT_DEPTH: f64 = 0.7;

/// A bright disk with a Gaussian-smoothed edge on a black background, optionally speckled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiskTarget {
    /// Disk radius, px.
    pub radius_px: f64,
    /// Grey level of the disk (8-bit scale).
    pub level: f64,
    /// Gaussian sigma of the edge, px.
    pub edge_sigma_px: f64,
    /// What is painted on it.
    pub texture: Texture,
}

impl Texture {
    /// `plain` or `speckle`.
    pub fn name(self) -> &'static str {
        match self {
            Texture::Plain => "plain",
            Texture::Speckle => "speckle",
        }
    }
}

impl DiskTarget {
    /// Grey level at distance `r` (px) from the centre of the plain disk.
    pub fn profile(&self, r: f64) -> f64 {
        self.level * 0.5 * libm::erfc((r - self.radius_px) / (self.edge_sigma_px * 2f64.sqrt()))
    }

    /// Grey level at `(dx, dy)` px from the centre (right, down): the disk's profile, darkened
    /// by the speckle dots when textured.
    pub fn value(&self, dx: f64, dy: f64) -> f64 {
        let disk = self.profile((dx * dx + dy * dy).sqrt());
        match self.texture {
            Texture::Plain => disk,
            Texture::Speckle => {
                let s2 = 2.0 * DOT_SIGMA_PX * DOT_SIGMA_PX;
                let reach = 6.0 * DOT_SIGMA_PX;
                let dots: f64 = self
                    .speckle_dots()
                    .filter(|(x, y)| (x - dx).abs() < reach && (y - dy).abs() < reach)
                    .map(|(x, y)| (-((x - dx).powi(2) + (y - dy).powi(2)) / s2).exp())
                    .sum();
                disk * (1.0 - DOT_DEPTH * dots).max(0.0)
            }
        }
    }

    /// Whether the image is symmetric about the centre column (a plain disk).
    pub fn is_symmetric(&self) -> bool {
        self.texture == Texture::Plain
    }

    /// Centres of the speckle dots, px from the disk's centre: one per grid cell inside the
    /// disk, jittered by a fixed pseudo-random sequence (a hash of the cell, so the pattern
    /// does not depend on the order of evaluation).
    pub fn speckle_dots(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        let n = (self.radius_px / DOT_PITCH_PX).ceil() as i64;
        (-n..=n).flat_map(move |i| {
            (-n..=n).filter_map(move |j| {
                let jitter = |salt: u64| {
                    // splitmix64 of the cell: a uniform value in [-1, 1)
                    let mut z = (i as u64)
                        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
                        .wrapping_add((j as u64).wrapping_mul(0xBF58_476D_1CE4_E5B9))
                        .wrapping_add(salt);
                    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
                    z ^= z >> 31;
                    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
                };
                let x = (i as f64 + jitter(1) / 5.0) * DOT_PITCH_PX;
                let y = (j as f64 + jitter(2) / 5.0) * DOT_PITCH_PX;
                (x * x + y * y < (self.radius_px - 1.0).powi(2)).then_some((x, y))
            })
        })
    }

    /// Half-extent (px) beyond which the profile is below 1e-6 of the level.
    pub fn extent(&self) -> f64 {
        self.radius_px + 7.0 * self.edge_sigma_px
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speckle_darkens_the_disk_at_its_dots_and_nowhere_else() {
        let t = DiskTarget {
            radius_px: 12.0,
            level: 200.0,
            edge_sigma_px: 1.0,
            texture: Texture::Speckle,
        };
        let dots: Vec<(f64, f64)> = t.speckle_dots().collect();
        // a 12 px disk on a 5 px grid: about pi 11^2 / 25 = 15 dots
        assert!((10..=22).contains(&dots.len()), "{} dots", dots.len());
        for (x, y) in &dots {
            assert!(t.value(*x, *y) < 0.4 * 200.0, "dot at {x},{y}");
        }
        // outside the disk the speckle changes nothing
        let plain = DiskTarget {
            texture: Texture::Plain,
            ..t
        };
        assert_eq!(t.value(20.0, 3.0), plain.value(20.0, 3.0));
        assert!(!t.is_symmetric() && plain.is_symmetric());
    }
}
