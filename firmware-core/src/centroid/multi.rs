//! Several targets per frame: streaming connected-component labelling (8-connectivity) with a
//! label buffer of one row and a fixed capacity of targets.
//!
//! Each pixel above the threshold takes the label of an already labelled neighbour (left,
//! up-left, up, up-right) or a new one; when two labels meet (a `U` whose arms join further
//! down) their components are merged (union-find on the slots, the moments are added). At the
//! end of every row the row's labels are replaced by their roots and slots merged away are
//! freed. A component whose first pixel finds no free slot is dropped (its pixels are counted,
//! [`Flags::CAPACITY`] is set on the frame and on every target, since a dropped component
//! might have joined one of them) and labelling goes on.

use super::{
    Centroid, CentroidConfig, ConfigError, Flags, Frame, FrameError, Moments, Pixel, MAX_DIM,
};

/// Smallest rectangle holding every pixel of a target (inclusive, full-frame pixels).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BoundingBox {
    /// Leftmost column.
    pub x_min: u32,
    /// Topmost row.
    pub y_min: u32,
    /// Rightmost column.
    pub x_max: u32,
    /// Bottom row.
    pub y_max: u32,
}

/// One connected component: centroid, moments, bounding box and flags.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Target {
    /// Centroid, exact moments (`moments.pixels` is the pixel count) and flags.
    pub centroid: Centroid,
    /// Bounding box.
    pub bbox: BoundingBox,
}

/// Accumulators of one slot.
#[derive(Debug, Clone, Copy)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
struct Slot {
    /// Parent slot (union-find); the slot itself for a root.
    parent: u16,
    used: bool,
    moments: Moments,
    bbox: BoundingBox,
    flags: Flags,
}

impl Slot {
    const FREE: Slot = Slot {
        parent: 0,
        used: false,
        moments: Moments {
            pixels: 0,
            weight: 0,
            sum_x: 0,
            sum_y: 0,
        },
        bbox: BoundingBox {
            x_min: u32::MAX,
            y_min: u32::MAX,
            x_max: 0,
            y_max: 0,
        },
        flags: Flags::NONE,
    };
}

/// Streaming multi-target centroider: rows of at most `W` pixels in the region, at most `N`
/// targets per frame. Memory: `W` 16-bit labels plus `N` slots of about 64 bytes.
///
/// Push rows top to bottom, read [`targets`](Self::targets) and [`flags`](Self::flags),
/// [`reset`](Self::reset) for the next frame. Targets come in slot order (not sorted).
/// Without ROI, columns past `W` are ignored and flagged [`Flags::CLIPPED`].
#[derive(Debug, Clone)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MultiCentroider<const W: usize, const N: usize> {
    config: CentroidConfig,
    /// Labels of the previous region row: 0 = background, `k` = slot `k - 1`.
    labels: [u16; W],
    slots: [Slot; N],
    next_y: u32,
    /// Region row processed last, if any.
    last_y: Option<u32>,
    /// Frame-level flags (CAPACITY, CLIPPED).
    flags: Flags,
    dropped: u64,
    /// Labels `filled..W` are all 0 (the longest row since the last reset was shorter).
    filled: usize,
}

impl<const W: usize, const N: usize> MultiCentroider<W, N> {
    const CHECK: () = {
        assert!(W >= 1 && W <= MAX_DIM, "W must be in 1..=MAX_DIM");
        assert!(N >= 1 && N < u16::MAX as usize, "N must be in 1..65535");
    };

    /// A multi-target centroider with the settings [`CentroidConfig::binary`]`(0)` (valid, but
    /// rarely what a firmware wants): a `static` built in place, then
    /// [`configure`](Self::configure)d.
    pub const fn new() -> Self {
        Self::empty(CentroidConfig::binary(0))
    }

    /// A multi-target centroider; fails on invalid settings
    /// ([`CentroidConfig::validate`]) or a ROI wider than `W`. `W` (1..=65 536) and `N`
    /// (1..65 535) are checked at compile time. `const`: a `static` initialiser builds it in
    /// place (the label buffer is `2 W` bytes), checked at compile time.
    pub const fn try_new(config: CentroidConfig) -> Result<Self, ConfigError> {
        Ok(Self::empty(const_try!(Self::check(config))))
    }

    /// The centroider with checked settings `config` and no frame seen (the capacities are
    /// checked at compile time here).
    const fn empty(config: CentroidConfig) -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::CHECK;
        MultiCentroider {
            config,
            labels: [0; W],
            slots: [Slot::FREE; N],
            next_y: 0,
            last_y: None,
            flags: Flags::NONE,
            dropped: 0,
            filled: 0,
        }
    }

    /// Replaces the settings in place (checked as in [`try_new`](Self::try_new)) and forgets
    /// the current frame. On error nothing changes.
    pub fn configure(&mut self, config: CentroidConfig) -> Result<(), ConfigError> {
        self.config = Self::check(config)?;
        self.reset();
        Ok(())
    }

    const fn check(config: CentroidConfig) -> Result<CentroidConfig, ConfigError> {
        let config = const_try!(config.validate());
        if let Some(r) = config.roi {
            if r.width as usize > W {
                return Err(ConfigError::RoiTooWide {
                    width: r.width,
                    max: W,
                });
            }
        }
        Ok(config)
    }

    /// The settings.
    pub const fn config(&self) -> &CentroidConfig {
        &self.config
    }

    /// Forgets the current frame; the next pushed row is row 0.
    pub fn reset(&mut self) {
        self.labels = [0; W];
        self.slots = [Slot::FREE; N];
        self.next_y = 0;
        self.last_y = None;
        self.flags = Flags::NONE;
        self.dropped = 0;
        self.filled = 0;
    }

    /// Pixels above the threshold that were dropped because the capacity was exceeded.
    pub const fn dropped_pixels(&self) -> u64 {
        self.dropped
    }

    /// Pushes the next row of the frame (8- or 16-bit pixels, column 0 first). Infallible:
    /// components past the capacity are dropped and flagged [`Flags::CAPACITY`].
    pub fn push_row<P: Pixel>(&mut self, row: &[P]) {
        let t = P::threshold(self.config.threshold);
        let sat = self.config.saturation_for(P::FULL);
        self.push(row, t, sat);
    }

    /// Resets, then processes a whole frame. Fails (before touching the state) when the ROI
    /// does not lie inside the frame or the region is wider than `W`.
    pub fn process<P: Pixel>(&mut self, frame: &Frame<'_, P>) -> Result<(), FrameError> {
        self.config.check_region(frame, W)?;
        self.reset();
        for row in frame.rows() {
            self.push_row(row);
        }
        Ok(())
    }

    fn slot(&self, label: u16) -> Option<&Slot> {
        self.slots.get(usize::from(label).wrapping_sub(1))
    }

    fn slot_mut(&mut self, label: u16) -> Option<&mut Slot> {
        self.slots.get_mut(usize::from(label).wrapping_sub(1))
    }

    /// Root label of `label` (path halving). 0 stays 0.
    fn find(&mut self, mut label: u16) -> u16 {
        loop {
            let Some(parent) = self.slot(label).map(|s| s.parent) else {
                return 0;
            };
            if parent == label {
                return label;
            }
            let grand = self.slot(parent).map_or(parent, |s| s.parent);
            if let Some(s) = self.slot_mut(label) {
                s.parent = grand;
            }
            label = grand;
        }
    }

    /// Merges the components of `a` and `b`; returns the root (the smaller label).
    fn union(&mut self, a: u16, b: u16) -> u16 {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb || ra == 0 || rb == 0 {
            return ra.max(rb);
        }
        let (keep, gone) = (ra.min(rb), ra.max(rb));
        let Some(g) = self.slot(gone).copied() else {
            return keep;
        };
        if let Some(k) = self.slot_mut(keep) {
            k.moments.merge(&g.moments);
            k.bbox.x_min = k.bbox.x_min.min(g.bbox.x_min);
            k.bbox.y_min = k.bbox.y_min.min(g.bbox.y_min);
            k.bbox.x_max = k.bbox.x_max.max(g.bbox.x_max);
            k.bbox.y_max = k.bbox.y_max.max(g.bbox.y_max);
            k.flags |= g.flags;
        }
        if let Some(g) = self.slot_mut(gone) {
            g.parent = keep;
        }
        keep
    }

    /// A fresh root slot, or 0 when every slot is in use.
    fn alloc(&mut self) -> u16 {
        for (label, s) in (1u16..).zip(self.slots.iter_mut()) {
            if !s.used {
                *s = Slot {
                    parent: label,
                    used: true,
                    ..Slot::FREE
                };
                return label;
            }
        }
        0
    }

    fn push<P: Pixel>(&mut self, row: &[P], t: P, sat: u16) {
        let Some((y, y0)) = self.config.enter_row(&mut self.next_y, &mut self.flags) else {
            return;
        };
        let (x0, x1) = self.config.cols();
        let end = x1.min(x0 + W).min(row.len());
        self.flags
            .set_if(Flags::CLIPPED, row.len() > x0 + W && x1 > x0 + W);
        let seg = row.get(x0..end).unwrap_or(&[]);
        let len = seg.len();
        let top = y == y0;
        let binary = self.config.mode == super::Mode::Binary;

        let mut up_left = 0u16;
        let mut left = 0u16;
        for (i, &p) in seg.iter().enumerate() {
            let up = self.labels.get(i).copied().unwrap_or(0);
            let up_right = self.labels.get(i + 1).copied().unwrap_or(0);
            let mut label = 0;
            if p > t {
                label = if left != 0 {
                    if up_right != 0 {
                        self.union(left, up_right)
                    } else {
                        left
                    }
                } else if up != 0 {
                    up
                } else if up_left != 0 {
                    if up_right != 0 {
                        self.union(up_left, up_right)
                    } else {
                        up_left
                    }
                } else if up_right != 0 {
                    up_right
                } else {
                    self.alloc()
                };
                label = self.find(label);
                let x = (x0 + i) as u32;
                let w = if binary { 1 } else { u64::from(p.excess(t)) };
                let edge = top || i == 0 || i + 1 == len;
                let saturated = p.into() >= sat;
                match self.slot_mut(label) {
                    Some(s) => {
                        s.moments.pixels += 1;
                        s.moments.weight += w;
                        s.moments.sum_x += u64::from(x) * w;
                        s.moments.sum_y += u64::from(y) * w;
                        s.bbox.x_min = s.bbox.x_min.min(x);
                        s.bbox.x_max = s.bbox.x_max.max(x);
                        s.bbox.y_min = s.bbox.y_min.min(y);
                        s.bbox.y_max = s.bbox.y_max.max(y);
                        s.flags.set_if(Flags::BORDER, edge);
                        s.flags.set_if(Flags::SATURATED, saturated);
                    }
                    None => {
                        self.dropped += 1;
                        self.flags.insert(Flags::CAPACITY);
                    }
                }
            }
            if let Some(l) = self.labels.get_mut(i) {
                *l = label;
            }
            up_left = up;
            left = label;
        }
        // End of row: labels to roots, stale labels past this row (a longer row before) cleared,
        // merged slots freed. Only the labels a row has written are visited: a narrow frame in
        // a wide capacity costs its own width, not `W`.
        for i in 0..len.max(self.filled) {
            let l = self.labels.get(i).copied().unwrap_or(0);
            let r = if i < len { self.find(l) } else { 0 };
            if let Some(d) = self.labels.get_mut(i) {
                *d = r;
            }
        }
        self.filled = len;
        for (label, s) in (1u16..).zip(self.slots.iter_mut()) {
            if s.used && s.parent != label {
                *s = Slot::FREE;
            }
        }
        self.last_y = Some(y);
    }

    /// Targets found so far (every connected component, in slot order), at most `N`. A target
    /// whose bottom row is the last region row pushed gets [`Flags::BORDER`].
    pub fn targets(&self) -> heapless::Vec<Target, N> {
        let mut out = heapless::Vec::new();
        for t in self.iter_targets() {
            // at most N roots: never refused
            if out.push(t).is_err() {
                break;
            }
        }
        out
    }

    /// The targets without collecting them.
    fn iter_targets(&self) -> impl Iterator<Item = Target> + '_ {
        let frame = self.flags;
        let last_y = self.last_y;
        (1u16..)
            .zip(self.slots.iter())
            .filter(|(label, s)| s.used && s.parent == *label)
            .map(move |(_, s)| {
                let mut flags = s.flags | frame;
                flags.set_if(Flags::BORDER, Some(s.bbox.y_max) == last_y);
                Target {
                    centroid: Centroid::from_moments(s.moments, flags),
                    bbox: s.bbox,
                }
            })
    }

    /// Number of targets found so far.
    pub fn count(&self) -> usize {
        self.iter_targets().count()
    }

    /// Frame-level flags: [`Flags::EMPTY`] when there is no target, [`Flags::CAPACITY`],
    /// [`Flags::CLIPPED`], and the union of the targets' flags.
    pub fn flags(&self) -> Flags {
        let mut f = self.flags;
        let mut any = false;
        for t in self.iter_targets() {
            f |= t.centroid.flags;
            any = true;
        }
        f.set_if(Flags::EMPTY, !any);
        f
    }
}

impl<const W: usize, const N: usize> Default for MultiCentroider<W, N> {
    fn default() -> Self {
        Self::new()
    }
}
