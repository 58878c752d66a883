//! What supports a tracked position: its match score, its forward-backward disagreement, and
//! the check that took it away, if one did (the tracking crate's `verify` gathers them; the
//! outputs write them).

/// Why a tracked position was taken away.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Doubt {
    /// Tracked back into the previous frame, the window did not land where the target was.
    ForwardBackward,
    /// The score fell far below the target's own over the record.
    Score,
    /// The target left its group's shared motion by more than the group's deformation allows.
    Group,
}

impl Doubt {
    /// The word written in `displacement.csv`'s `check` column and the report.
    pub fn word(self) -> &'static str {
        match self {
            Doubt::ForwardBackward => "forward-backward",
            Doubt::Score => "score",
            Doubt::Group => "group",
        }
    }
}

/// The evidence of one target's position in one frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Evidence {
    /// Match score of the position against the first frame's template (ZNCC), when the
    /// tracker has one.
    pub score: Option<f32>,
    /// Forward-backward disagreement, px, when it was measured (a tracked position with a
    /// tracked previous frame).
    pub fb_px: Option<f32>,
    /// Why the position was taken away, if it was.
    pub doubt: Option<Doubt>,
}

/// A position's evidence as `displacement.csv` writes it: `score,fb_px,check` cells (empty
/// where there is none).
pub fn cells(e: Option<&Evidence>) -> String {
    let Some(e) = e else {
        return ",,".to_string();
    };
    format!(
        "{},{},{}",
        e.score.map_or(String::new(), |s| format!("{s:.4}")),
        e.fb_px.map_or(String::new(), |f| format!("{f:.4}")),
        e.doubt.map_or("", Doubt::word)
    )
}
