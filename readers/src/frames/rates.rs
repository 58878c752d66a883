//! The rate a recording was taken at, and its exposure: as the user gives them, else as a camera
//! file's header states them, with notes saying which.

use super::FrameRange;

/// The frame rate and exposure a job runs at, with notes for the report on where they came
/// from.
#[derive(Debug, Clone, PartialEq)]
pub struct Rates {
    /// Frames per second.
    pub fps: f64,
    /// Exposure, ms, when known.
    pub exposure_ms: Option<f64>,
    /// Notes for the report.
    pub notes: Vec<String>,
}

/// The frame rate (Hz) and exposure (ms): as given, else as the recording's own header states
/// them (a camera file); with notes for the report on where they came from, and when a given
/// rate overrides the file's. Image files and videos state no rate: `--fps` is then needed;
/// with `retime` (a video only) it may retime the container's constant rate, a note naming both.
pub fn resolve_rates(
    frames: &str,
    fps: Option<f64>,
    exposure_ms: Option<f64>,
    retime: bool,
    range: Option<FrameRange>,
) -> anyhow::Result<Rates> {
    let source = super::open_frames(frames, retime, range)?.source;
    let recorded = source.recorded_rate()?;
    let mut notes = Vec::new();
    let fps = match (fps, recorded) {
        (Some(f), Some((r, _))) => {
            if (f - r).abs() > 1e-9 * r {
                notes.push(format!(
                    "$fps {f} overrides the {r} fps that {frames} states"
                ));
            }
            f
        }
        (Some(f), None) => f,
        (None, Some((r, _))) => {
            notes.push(format!("frame rate {r} fps, as {frames} states"));
            r
        }
        (None, None) if source.inner().is_camera_file() => {
            return Err(crate::bad_input(format!(
                "$fps is needed: the header of {frames} states no usable frame rate (none, \
                 or 0 fps)"
            )))
        }
        (None, None) => {
            return Err(crate::bad_input(format!(
                "$fps is needed: {frames} does not state the rate the camera recorded at \
                 (image files and videos; a video container's rate is often not the capture \
                 rate)"
            )))
        }
    };
    if let super::FrameSource::Video { path, .. } = source.inner() {
        if let Some(rate) =
            super::video::check_rate(path, fps, retime).map_err(|e| e.into_anyhow())?
        {
            notes.push(format!(
                "$fps {fps} retimes {frames}, whose container plays at {}: frames \
                 are 1/{fps} s apart (a slow-motion or time-lapse file; the timestamps were \
                 checked regular at the container's rate)",
                super::video::rate_text(rate)
            ));
        }
    }
    let exposure_ms = match (exposure_ms, recorded.and_then(|r| r.1)) {
        (Some(e), _) => Some(e),
        (None, Some(s)) => {
            notes.push(format!("exposure {} ms, as {frames} states", s * 1000.0));
            Some(s * 1000.0)
        }
        (None, None) => None,
    };
    Ok(Rates {
        fps,
        exposure_ms,
        notes,
    })
}
