//! What every tracker returns ([`Tracks`]: each target's centroid per frame), and the K blobs of
//! the whole frame followed (`--targets K`): firmware-core's
//! multi-target centroider on every frame, targets numbered left to right (then top to bottom)
//! in the first frame, each followed by its nearest detection within a gate; a target with no
//! detection in the gate, whose detection is also the nearest of another target (two targets
//! merging), whose detection touches the frame border (leaving the frame: its centroid would
//! be biased), or whose detection is implausible for its history ([`History`]: a pixel count
//! far from its recent ones, as when two blobs merge or stray light joins it, or a jump far
//! beyond what its motion so far predicts) is a lost frame of that target only.

use firmware_core::centroid::{Centroid, CentroidConfig, Flags, Frame, Moments, MultiCentroider};
use vibcam_readers::bad_input;
use vibcam_readers::frames::{FrameSource, GreyFrame};

/// Widest frame the multi-target labelling buffer holds, px.
const MAX_WIDTH: usize = 8192;
/// Most components labelled at once per frame (targets plus clutter, plus the provisional
/// parts of ragged components that join further down).
const MAX_DETECTIONS: usize = 512;

/// Each target's centroid per frame (an empty centroid where it was lost) and where it was
/// first seen.
#[derive(Debug, Clone)]
pub struct Tracks {
    /// `centroids[t][k]`: target `t`, frame `k`.
    pub centroids: Vec<Vec<Centroid>>,
    /// Position in the first frame, px.
    pub first: Vec<(f64, f64)>,
    /// Per target, the detections refused as implausible ([`History::plausible`]), counted among
    /// its lost frames.
    pub refused: Vec<usize>,
    /// The frames' bit depth and largest value.
    pub depth: vibcam_readers::frames::FrameDepth,
    /// `evidence[t][k]`: what supports target `t`'s position in frame `k`
    /// (`verify`); empty for a tracker that gathers none (the centroids).
    pub evidence: Vec<Vec<vibcam_common::evidence::Evidence>>,
}

/// Pixel counts of a target's accepted detections this many frames back are its reference.
const PIXEL_HISTORY: usize = 15;
/// A detection whose pixel count is more than this factor above or below the median of the
/// target's recent ones is not the target alone (two blobs merged: 2x) or not all of it.
const PIXEL_FACTOR: f64 = 1.5;
/// A detection this far (px) from the constant-velocity prediction is always plausible: the
/// floor of the jump check, above the quantisation and noise of a centroid.
const JUMP_FLOOR_PX: f64 = 3.0;
/// Beyond the floor, a detection may be this many RMS prediction residuals of the target's
/// history from the prediction.
const JUMP_SIGMAS: f64 = 6.0;
/// Residuals needed before the history's RMS is trusted (until then: the gate only).
const JUMP_WARMUP: usize = 10;

/// What a target's accepted detections so far allow of the next one.
#[derive(Debug, Clone, Default)]
pub struct History {
    /// Pixel counts of the last accepted detections (at most [`PIXEL_HISTORY`]).
    pixels: std::collections::VecDeque<u64>,
    /// The last accepted position and, if the frame before it was accepted too, the one before.
    last: Option<(f64, f64)>,
    before: Option<(f64, f64)>,
    /// Sum of squared constant-velocity prediction residuals, and their count.
    residual_sq: f64,
    residuals: usize,
}

impl History {
    /// Whether detection `c` is plausible for this target: its pixel count within a factor 1.5
    /// of the median of its last 15, and (once the history has 10 residuals) its distance from
    /// the constant-velocity prediction within max(3 px, 6 RMS residuals). Runs per target and
    /// frame: no allocation.
    pub fn plausible(&self, c: &Centroid) -> bool {
        let mut recent = [0u64; PIXEL_HISTORY];
        let n = self.pixels.len();
        for (r, p) in recent.iter_mut().zip(&self.pixels) {
            *r = *p;
        }
        recent[..n].sort_unstable();
        if let Some(&median) = recent[..n].get(n / 2) {
            let (p, m) = (c.moments.pixels as f64, median as f64);
            if p > m * PIXEL_FACTOR || p * PIXEL_FACTOR < m {
                return false;
            }
        }
        if let (Some(last), Some(before)) = (self.last, self.before) {
            if self.residuals >= JUMP_WARMUP {
                let r = self.residual(last, before, c);
                let rms = (self.residual_sq / self.residuals as f64).sqrt();
                if r > JUMP_FLOOR_PX.max(JUMP_SIGMAS * rms) {
                    return false;
                }
            }
        }
        true
    }

    fn residual(&self, last: (f64, f64), before: (f64, f64), c: &Centroid) -> f64 {
        let predicted = (2.0 * last.0 - before.0, 2.0 * last.1 - before.1);
        (f64::from(c.cx) - predicted.0).hypot(f64::from(c.cy) - predicted.1)
    }

    /// Takes an accepted detection into the history.
    pub fn accept(&mut self, c: &Centroid) {
        if let (Some(last), Some(before)) = (self.last, self.before) {
            let r = self.residual(last, before, c);
            self.residual_sq += r * r;
            self.residuals += 1;
        }
        self.before = self.last;
        self.last = Some((f64::from(c.cx), f64::from(c.cy)));
        if self.pixels.len() == PIXEL_HISTORY {
            self.pixels.pop_front();
        }
        self.pixels.push_back(c.moments.pixels);
    }

    /// A frame without an accepted detection: the velocity is unknown until two consecutive
    /// frames are accepted again.
    pub fn miss(&mut self) {
        self.before = None;
    }
}

/// A centroid standing for a lost frame.
pub(crate) fn lost() -> Centroid {
    Centroid {
        cx: 0.0,
        cy: 0.0,
        moments: Moments {
            pixels: 0,
            weight: 0,
            sum_x: 0,
            sum_y: 0,
        },
        flags: Flags::EMPTY,
    }
}

/// Follows `k` targets through the frames of `source` (see the module documentation).
pub fn track(
    source: &FrameSource,
    fps: f64,
    config: &CentroidConfig,
    k: usize,
    gate_px: f64,
) -> anyhow::Result<Tracks> {
    let mut mc = Box::new(
        MultiCentroider::<MAX_WIDTH, MAX_DETECTIONS>::try_new(*config)
            .map_err(|e| bad_input(format!("centroid settings: {e}")))?,
    );
    let mut tracks = Tracks {
        centroids: vec![Vec::new(); k],
        first: Vec::new(),
        refused: vec![0; k],
        depth: Default::default(),
        evidence: Vec::new(),
    };
    let mut history = vec![History::default(); k];
    let mut last: Vec<(f64, f64)> = Vec::new();
    let mut frame_no = 0usize;
    let mut one = |label: String, frame: &GreyFrame| -> anyhow::Result<()> {
        frame_no += 1;
        tracks.depth.add(frame);
        let found = detect(&mut mc, frame, &label)?;
        if frame_no == 1 {
            let order = first_frame(found, k, &label)?;
            last = order.iter().map(|c| (c.cx as f64, c.cy as f64)).collect();
            tracks.first = last.clone();
            for (t, c) in order.into_iter().enumerate() {
                history[t].accept(&c);
                tracks.centroids[t].push(c);
            }
            return Ok(());
        }
        let nearest = nearest_in_gate(&last, &found, gate_px);
        for t in 0..k {
            let claimed =
                nearest[t].filter(|j| nearest.iter().filter(|n| **n == Some(*j)).count() == 1);
            match claimed {
                // touching the frame (or ROI) border: partly outside, its centroid is biased
                Some(j) if found[j].flags.contains(Flags::BORDER) => {
                    history[t].miss();
                    tracks.centroids[t].push(lost())
                }
                Some(j) if !history[t].plausible(&found[j]) => {
                    history[t].miss();
                    tracks.refused[t] += 1;
                    tracks.centroids[t].push(lost())
                }
                Some(j) => {
                    let c = found[j];
                    history[t].accept(&c);
                    last[t] = (c.cx as f64, c.cy as f64);
                    tracks.centroids[t].push(c);
                }
                None => {
                    history[t].miss();
                    tracks.centroids[t].push(lost())
                }
            }
        }
        Ok(())
    };
    source.for_each(fps, &mut one)?;
    Ok(tracks)
}

/// The targets of the first frame, numbered left to right (then top to bottom): exactly `k`
/// detections, none touching the border, else an error naming the frame.
fn first_frame(found: Vec<Centroid>, k: usize, label: &str) -> anyhow::Result<Vec<Centroid>> {
    if found.len() != k {
        return Err(bad_input(format!(
            "{label}: {} targets above the threshold in the first frame, $targets {k} \
             expected; in a scene with other bright things, choose the targets with $points \
             FILE.csv (a window per target)",
            found.len()
        )));
    }
    if let Some(c) = found.iter().find(|c| c.flags.contains(Flags::BORDER)) {
        return Err(bad_input(format!(
            "{label}: the target at ({:.1}, {:.1}) px touches the frame border in the \
             first frame (its centroid would be biased): every target must be wholly \
             inside the frame (or $roi) in the first frame",
            c.cx, c.cy
        )));
    }
    let mut order = found;
    order.sort_by(|a, b| a.cx.total_cmp(&b.cx).then(a.cy.total_cmp(&b.cy)));
    Ok(order)
}

/// For each target's last position, the nearest detection within `gate_px`; `None` when there
/// is none, or when two are equally near (ambiguous).
fn nearest_in_gate(last: &[(f64, f64)], found: &[Centroid], gate_px: f64) -> Vec<Option<usize>> {
    last.iter()
        .map(|&(x, y)| {
            let d = |c: &Centroid| ((c.cx as f64 - x).powi(2) + (c.cy as f64 - y).powi(2)).sqrt();
            let mut inside: Vec<usize> = (0..found.len())
                .filter(|&j| d(&found[j]) <= gate_px)
                .collect();
            inside.sort_by(|&a, &b| d(&found[a]).total_cmp(&d(&found[b])));
            match inside.as_slice() {
                [] => None,
                [j] => Some(*j),
                [j, n, ..] if d(&found[*n]) - d(&found[*j]) > 1e-3 => Some(*j),
                _ => None,
            }
        })
        .collect()
}

/// The detections of one frame.
fn detect(
    mc: &mut MultiCentroider<MAX_WIDTH, MAX_DETECTIONS>,
    frame: &GreyFrame,
    label: &str,
) -> anyhow::Result<Vec<Centroid>> {
    let (w, h) = frame.dimensions();
    if w > MAX_WIDTH {
        return Err(bad_input(format!(
            "{label}: {w} px wide; $targets handles frames up to {MAX_WIDTH} px"
        )));
    }
    let r = match frame {
        GreyFrame::U8 { data, .. } => Frame::new(data, w, h, w).and_then(|f| mc.process(&f)),
        GreyFrame::U16 { data, .. } => Frame::new(data, w, h, w).and_then(|f| mc.process(&f)),
    };
    r.map_err(|e| bad_input(format!("{label}: cannot centroid the frame: {e}")))?;
    if mc.flags().contains(Flags::CAPACITY) {
        return Err(bad_input(format!(
            "{label}: more than {MAX_DETECTIONS} components above the threshold at once while \
             labelling the frame ({} kept; a ragged component, e.g. noise near the threshold, \
             holds several until its parts join): raise $threshold or narrow $roi",
            mc.targets().len()
        )));
    }
    Ok(mc.targets().iter().map(|t| t.centroid).collect())
}
