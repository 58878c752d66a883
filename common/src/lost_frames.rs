//! Lost frames: a frame without a centroid (no pixel above the threshold, a target leaving the
//! frame, a detection refused) has no position, and the chain needs one value per frame. The one
//! policy of the toolkit for what such a frame's value becomes, and when a record has too many
//! of them; used by the synthetic camera's studies and by recordings alike (method.md "Lost
//! frames").

/// Largest fraction of lost frames (no centroid) a measurement accepts: 5 %.
pub const MAX_LOST_FRACTION: f64 = 0.05;

/// What a lost frame's value becomes (`[imaging] lost_frame_policy`, `analyze --lost-frames`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LostFramePolicy {
    /// Linear interpolation between the neighbouring valid frames ([`fill_lost_frames`]).
    #[default]
    Interpolate,
    /// The last valid frame's value (the first valid one's before it): a zero-order hold.
    Hold,
}

impl LostFramePolicy {
    /// Every policy, the default first.
    pub const ALL: [LostFramePolicy; 2] = [LostFramePolicy::Interpolate, LostFramePolicy::Hold];

    /// `interpolate` or `hold` (as a study file and the command line spell it).
    pub fn name(self) -> &'static str {
        match self {
            LostFramePolicy::Interpolate => "interpolate",
            LostFramePolicy::Hold => "hold",
        }
    }
}

/// [`fill_lost_frames`] with a policy: interpolation, or a hold of the last valid value.
/// Returns the number of lost frames.
pub fn fill_lost_frames_with(values: &mut [f64], valid: &[bool], policy: LostFramePolicy) -> usize {
    match policy {
        LostFramePolicy::Interpolate => fill_lost_frames(values, valid),
        LostFramePolicy::Hold => {
            let n = values.len().min(valid.len());
            let lost = valid[..n].iter().filter(|v| !**v).count();
            let Some(first) = valid[..n].iter().position(|v| *v) else {
                return lost;
            };
            let mut last = values[first];
            for i in 0..n {
                if valid[i] {
                    last = values[i];
                } else {
                    values[i] = last;
                }
            }
            lost
        }
    }
}

/// Fills the values of lost frames (`valid[i] == false`) by linear interpolation between the
/// neighbouring valid frames; lost frames before the first or after the last valid one take its
/// value. Returns the number of lost frames; with no valid frame at all, nothing is changed and
/// the count equals the length.
pub fn fill_lost_frames(values: &mut [f64], valid: &[bool]) -> usize {
    let n = values.len().min(valid.len());
    let lost = valid[..n].iter().filter(|v| !**v).count();
    let Some(first) = valid[..n].iter().position(|v| *v) else {
        return lost;
    };
    let mut prev = first;
    for i in 0..first {
        values[i] = values[first];
    }
    for i in first + 1..n {
        if valid[i] {
            let gap = i - prev;
            for j in prev + 1..i {
                let w = (j - prev) as f64 / gap as f64;
                values[j] = values[prev] * (1.0 - w) + values[i] * w;
            }
            prev = i;
        }
    }
    for i in prev + 1..n {
        values[i] = values[prev];
    }
    lost
}

/// Whether `lost` of `frames` lost frames exceed [`MAX_LOST_FRACTION`].
pub fn too_many_lost(lost: usize, frames: usize) -> bool {
    lost as f64 > MAX_LOST_FRACTION * frames as f64
}

impl LostFramePolicy {
    /// How a report says what the policy did to the lost frames.
    pub fn describe(self) -> &'static str {
        match self {
            LostFramePolicy::Interpolate => "filled by linear interpolation",
            LostFramePolicy::Hold => "held at the last valid value",
        }
    }
}
