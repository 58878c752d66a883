//! firmware-core's Lucas-Kanade tracker at the host's capacities: what the simulated camera's
//! firmware and the tracking of real recordings both run.

/// The host's capacities of a Lucas-Kanade window: pixels (136 x 136, windows up to 128 px
/// wide with the spline's margin).
pub const LK_PIXELS: usize = 136 * 136;
/// The host's longest Lucas-Kanade window row, with the spline's margin.
pub const LK_ROW: usize = 128 + 7;
/// The host's Lucas-Kanade tracker (windows up to 128 px wide, with the spline's margin).
pub type HostLk = firmware_core::lk::LkTracker<LK_PIXELS, LK_ROW>;
