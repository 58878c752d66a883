//! The target a rig's camera looks at: a physical object of the rig (its size and contrast are
//! the rig's constants, `model::cantilever::TARGET`), drawn by [`crate::imaging`].

/// A bright disk with a Gaussian-smoothed edge on a black background.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiskTarget {
    /// Disk radius, px.
    pub radius_px: f64,
    /// Grey level of the disk (8-bit scale).
    pub level: f64,
    /// Gaussian sigma of the edge, px.
    pub edge_sigma_px: f64,
}

impl DiskTarget {
    /// Grey level at distance `r` (px) from the centre.
    pub fn profile(&self, r: f64) -> f64 {
        self.level * 0.5 * libm::erfc((r - self.radius_px) / (self.edge_sigma_px * 2f64.sqrt()))
    }

    /// Half-extent (px) beyond which the profile is below 1e-6 of the level.
    pub fn extent(&self) -> f64 {
        self.radius_px + 7.0 * self.edge_sigma_px
    }
}
