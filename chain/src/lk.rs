//! firmware-core's Lucas-Kanade tracker at the host's capacities: what the simulated camera's
//! firmware and the tracking of real recordings both run.

use firmware_core::centroid::{Frame, Pixel};
use firmware_core::lk::{LkConfig, LkError, LkResult};

/// The host's capacities of a Lucas-Kanade window: pixels (136 x 136, windows up to 128 px
/// wide with the spline's margin).
pub const LK_PIXELS: usize = 136 * 136;
/// The host's longest Lucas-Kanade window row, with the spline's margin.
pub const LK_ROW: usize = 128 + 7;
/// The host's Lucas-Kanade tracker (windows up to 128 px wide, with the spline's margin).
pub type HostLk = firmware_core::lk::LkTracker<LK_PIXELS, LK_ROW>;

/// A tracker for windows up to 32 px (40 x 40 pixels with the spline's margin): a dense
/// field's windows. Its buffers are a twelfth of [`HostLk`]'s (about 38 kB against 440 kB), which
/// for hundreds of targets, each with a backward tracker, is the difference between tens of
/// MB and most of a GB, touched page by page.
pub type SmallLk = firmware_core::lk::LkTracker<{ 40 * 40 }, 39>;

/// A host Lucas-Kanade tracker of the smallest capacity its window fits: [`SmallLk`] or
/// [`HostLk`]. The same results either way (the capacity only bounds the window).
#[derive(Debug, Clone)]
pub enum AnyLk {
    /// Windows up to 32 px.
    Small(Box<SmallLk>),
    /// Windows up to 128 px.
    Host(Box<HostLk>),
}

impl AnyLk {
    /// The tracker of `cfg`, of the smallest capacity that holds its window; the error
    /// [`HostLk`]'s when neither does.
    pub fn try_new(cfg: LkConfig) -> Result<AnyLk, LkError> {
        match SmallLk::try_new(cfg) {
            Ok(t) => Ok(AnyLk::Small(Box::new(t))),
            Err(_) => HostLk::try_new(cfg).map(|t| AnyLk::Host(Box::new(t))),
        }
    }

    /// [`firmware_core::lk::LkTracker::config`].
    pub fn config(&self) -> &LkConfig {
        match self {
            AnyLk::Small(t) => t.config(),
            AnyLk::Host(t) => t.config(),
        }
    }

    /// [`firmware_core::lk::LkTracker::set_template`].
    pub fn set_template<P: Pixel>(
        &mut self,
        frame: &Frame<'_, P>,
        x0: i32,
        y0: i32,
    ) -> Result<(), LkError> {
        match self {
            AnyLk::Small(t) => t.set_template(frame, x0, y0),
            AnyLk::Host(t) => t.set_template(frame, x0, y0),
        }
    }

    /// [`firmware_core::lk::LkTracker::structure`].
    pub fn structure(&self) -> [f32; 3] {
        match self {
            AnyLk::Small(t) => t.structure(),
            AnyLk::Host(t) => t.structure(),
        }
    }

    /// [`firmware_core::lk::LkTracker::displacement`].
    pub fn displacement(&self) -> (f32, f32) {
        match self {
            AnyLk::Small(t) => t.displacement(),
            AnyLk::Host(t) => t.displacement(),
        }
    }

    /// [`firmware_core::lk::LkTracker::track_from`].
    pub fn track_from<P: Pixel>(
        &mut self,
        frame: &Frame<'_, P>,
        start: Option<(f32, f32)>,
        search: u16,
    ) -> LkResult {
        match self {
            AnyLk::Small(t) => t.track_from(frame, start, search),
            AnyLk::Host(t) => t.track_from(frame, start, search),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth random-looking 8-bit pattern shifted by `(dx, dy)`.
    fn pattern(w: usize, h: usize, (dx, dy): (f64, f64)) -> Vec<u8> {
        (0..w * h)
            .map(|k| {
                let (x, y) = ((k % w) as f64 - dx, (k / w) as f64 - dy);
                let v = 120.0
                    + 50.0 * (0.31 * x + 0.17 * y).sin()
                    + 40.0 * (0.23 * x - 0.29 * y).cos()
                    + 25.0 * (0.11 * x * 0.7 + 0.41 * y).sin();
                v.round().clamp(0.0, 255.0) as u8
            })
            .collect()
    }

    #[test]
    fn the_small_tracker_is_chosen_for_small_windows_and_tracks_as_the_host_one() {
        let (w, h) = (120, 100);
        let (a, b) = (pattern(w, h, (0.0, 0.0)), pattern(w, h, (0.37, -1.21)));
        let (fa, fb) = (
            Frame::new(&a, w, h, w).unwrap(),
            Frame::new(&b, w, h, w).unwrap(),
        );
        for (side, small) in [(21u16, true), (32, true), (33, false), (61, false)] {
            let cfg = LkConfig::new(side, side);
            let mut any = AnyLk::try_new(cfg).unwrap();
            assert_eq!(matches!(any, AnyLk::Small(_)), small, "{side}");
            let mut host = HostLk::try_new(cfg).unwrap();
            any.set_template(&fa, 30, 20).unwrap();
            host.set_template(&fa, 30, 20).unwrap();
            let (r1, r2) = (any.track_from(&fb, None, 4), host.track_from(&fb, None, 4));
            assert_eq!((r1.dx, r1.dy, r1.score), (r2.dx, r2.dy, r2.score), "{side}");
            assert!(
                (r1.dx - 0.37).abs() < 0.02 && (r1.dy + 1.21).abs() < 0.02,
                "{r1:?}"
            );
            assert_eq!(any.structure(), host.structure());
        }
        // too wide for either: the host tracker's error
        let cfg = LkConfig::new(200, 20);
        assert_eq!(AnyLk::try_new(cfg).err(), HostLk::try_new(cfg).err());
    }
}
