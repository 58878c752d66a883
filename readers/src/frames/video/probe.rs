//! `ffprobe`: stream properties and packet timestamps, and the timestamp checks.

use super::*;

pub(super) struct StreamProps {
    pub(super) codec: String,
    pub(super) pix_fmt: String,
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) bits: u32,
    pub(super) time_base_s: f64,
    /// Frame count from the container's header, where it has one (AVI, MP4, MOV).
    pub(super) nb_frames: Option<usize>,
    /// Duration of the video stream, or of the file when it holds only the video stream.
    pub(super) duration_s: Option<f64>,
}

fn run_probe(
    path: &Path,
    ffprobe: &str,
    entries: &str,
    format: &str,
) -> Result<String, VideoError> {
    let out = Command::new(ffprobe)
        .args([
            "-v",
            "error",
            "-select_streams",
            "v:0",
            "-show_entries",
            entries,
        ])
        .args(["-of", format])
        .arg(file_arg(path))
        .stdin(Stdio::null())
        .output()
        .map_err(|source| program_missing(ffprobe, path, source))?;
    if !out.status.success() {
        return Err(VideoError::Unreadable {
            path: path.into(),
            stderr: String::from_utf8_lossy(&out.stderr).trim().to_string(),
        });
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

pub(super) fn probe_stream(path: &Path, ffprobe: &str) -> Result<StreamProps, VideoError> {
    let text = run_probe(
        path,
        ffprobe,
        "stream=codec_name,width,height,pix_fmt,time_base,nb_frames,duration:format=duration,nb_streams",
        "json",
    )?;
    let missing = |what: &str| VideoError::NoVideoStream {
        path: path.into(),
        what: what.into(),
    };
    let json: serde_json::Value =
        serde_json::from_str(&text).map_err(|_| missing("ffprobe's answer is not JSON"))?;
    let stream = &json["streams"][0];
    if !stream.is_object() {
        return Err(missing("no video stream"));
    }
    // ffprobe gives numbers for sizes and strings for the rest; "N/A" or absent when unknown.
    let text_of = |v: &serde_json::Value| -> Option<String> {
        let s = match v {
            serde_json::Value::String(s) => s.clone(),
            serde_json::Value::Number(n) => n.to_string(),
            _ => return None,
        };
        (!s.is_empty() && s != "N/A" && s != "unknown").then_some(s)
    };
    let count = |v: &serde_json::Value| -> Option<usize> {
        text_of(v)?.parse().ok().filter(|&n: &usize| n > 0)
    };
    let seconds = |v: &serde_json::Value| -> Option<f64> {
        text_of(v)?
            .parse()
            .ok()
            .filter(|d: &f64| d.is_finite() && *d > 0.0)
    };
    let width = count(&stream["width"]).ok_or_else(|| missing("no frame width"))?;
    let height = count(&stream["height"]).ok_or_else(|| missing("no frame height"))?;
    // a decoded frame is at most 16 bits a pixel: its buffer is allocated from these sizes
    if (width as u64)
        .saturating_mul(height as u64)
        .saturating_mul(2)
        > crate::frames::MAX_FRAME_BYTES
    {
        return Err(missing(&format!(
            "frames of {width} x {height} pixels, more than {} MiB a frame",
            crate::frames::MAX_FRAME_BYTES >> 20
        )));
    }
    let pix_fmt = text_of(&stream["pix_fmt"]).ok_or_else(|| missing("no pixel format"))?;
    let time_base_s = text_of(&stream["time_base"])
        .as_deref()
        .and_then(parse_rational)
        .ok_or_else(|| missing("no time base"))?;
    let only_stream = count(&json["format"]["nb_streams"]) == Some(1);
    let duration_s = seconds(&stream["duration"]).or_else(|| {
        only_stream
            .then(|| seconds(&json["format"]["duration"]))
            .flatten()
    });
    Ok(StreamProps {
        codec: text_of(&stream["codec_name"]).unwrap_or_else(|| "unknown".into()),
        bits: component_bits(&pix_fmt),
        pix_fmt,
        width,
        height,
        time_base_s,
        nb_frames: count(&stream["nb_frames"]),
        duration_s,
    })
}

/// `"1/1000"` -> 0.001.
pub(super) fn parse_rational(s: &str) -> Option<f64> {
    let (n, d) = s.split_once('/')?;
    let (n, d): (f64, f64) = (n.trim().parse().ok()?, d.trim().parse().ok()?);
    (n > 0.0 && d > 0.0).then_some(n / d)
}

/// Bits per component of an FFmpeg pixel format, from its name: formats with a bit depth above 8
/// end in the depth and the byte order (`yuv420p10le`, `gray12le`, `p010le`; `rgb48le` and
/// `rgba64le` are 16 bits a component); all others are 8 bits or fewer (`rgb565le` too).
pub(super) fn component_bits(pix_fmt: &str) -> u32 {
    let Some(stem) = pix_fmt
        .strip_suffix("le")
        .or_else(|| pix_fmt.strip_suffix("be"))
    else {
        return 8;
    };
    let digits: String = stem
        .chars()
        .rev()
        .take_while(char::is_ascii_digit)
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
        .collect();
    match digits.parse::<u32>() {
        Ok(b @ 9..=16) => b,
        Ok(32 | 48 | 64) => 16,
        _ => 8,
    }
}

/// Packet presentation times of the video stream, sorted, relative to the first.
pub(super) fn probe_times(path: &Path, ffprobe: &str) -> Result<Vec<f64>, VideoError> {
    let mut child = spawn_reader(
        Command::new(ffprobe)
            .args(["-v", "error", "-select_streams", "v:0"])
            .args(["-show_entries", "packet=pts_time,flags", "-of", "csv=p=0"])
            .arg(file_arg(path)),
        ffprobe,
        path,
    )?;
    let stderr = child.stderr.take().map(collect_stderr);
    let stdout = child.stdout.take().expect("stdout is piped");
    let mut times = Vec::new();
    let mut bad = None;
    for line in BufReader::new(stdout).lines() {
        let Ok(line) = line else { break };
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let (pts, flags) = line.split_once(',').unwrap_or((line, ""));
        if flags.contains('D') {
            continue;
        }
        let frame = times.len();
        if bad.is_some() {
            continue;
        }
        if flags.contains('C') {
            bad = Some((frame, "the demuxer marks the packet corrupt".to_string()));
            continue;
        }
        match pts.trim().parse::<f64>() {
            Ok(t) if t.is_finite() => times.push(t),
            _ => bad = Some((frame, format!("no presentation timestamp ({pts:?})"))),
        }
    }
    let status = child.wait();
    let said = stderr.and_then(|h| h.join().ok()).unwrap_or_default();
    if !matches!(status, Ok(s) if s.success()) {
        return Err(VideoError::Unreadable {
            path: path.into(),
            stderr: said.trim().to_string(),
        });
    }
    if let Some((frame, what)) = bad {
        return Err(VideoError::BadPacket {
            path: path.into(),
            frame,
            what,
        });
    }
    if times.is_empty() {
        return Err(VideoError::NoVideoStream {
            path: path.into(),
            what: "no frames".into(),
        });
    }
    times.sort_by(f64::total_cmp);
    let t0 = times[0];
    for t in &mut times {
        *t -= t0;
    }
    Ok(times)
}

/// Tolerance on frame times: ffprobe prints microseconds (2 µs on a difference), plus one tick
/// of the time base (each timestamp is rounded to the tick, a difference of two to one) unless
/// the frame period is a whole number of ticks (AVI's 1/fps, MOV's 1/15360 at 120 fps: exact).
fn time_tolerance(period: f64, time_base_s: f64) -> f64 {
    let ticks = period / time_base_s;
    if (ticks - ticks.round()).abs() < 1e-6 * ticks.max(1.0) {
        2e-6
    } else {
        time_base_s + 2e-6
    }
}

/// Checks that the container declares no more frames than it has timestamps for: its header's
/// frame count, or its duration (the video stream's, or the file's when it holds only video).
pub(super) fn check_complete(
    path: &Path,
    times: &[f64],
    fps: f64,
    stream: &StreamProps,
) -> Result<(), VideoError> {
    let n = times.len();
    if let Some(declared) = stream.nb_frames {
        if declared != n {
            return Err(VideoError::MissingFrames {
                path: path.into(),
                frame: n.min(declared),
                what: format!("the container's header lists {declared} frames, it holds {n}"),
            });
        }
    } else if let Some(duration) = stream.duration_s {
        let period = 1.0 / fps;
        let covered = times[n - 1] + period;
        let tol = time_tolerance(period, stream.time_base_s);
        if duration - covered > 0.5 * period + tol {
            return Err(VideoError::MissingFrames {
                path: path.into(),
                frame: n,
                what: format!(
                    "the container declares {duration:.6} s (about {:.0} frames), its {n} frames cover {covered:.6} s",
                    duration * fps
                ),
            });
        }
    }
    Ok(())
}

/// Checks frame times (relative to the first) against `fps` (see the module documentation).
/// With `retime`, timestamps regular at a constant rate other than `fps` are accepted as a
/// retiming and that rate (Hz) returned (`Ok(Some(rate))`); `Ok(None)`: they agree with `fps`.
pub(super) fn check_times(
    path: &Path,
    times: &[f64],
    fps: f64,
    time_base_s: f64,
    retime: bool,
) -> Result<Option<f64>, VideoError> {
    let period = 1.0 / fps;
    let tol = time_tolerance(period, time_base_s);
    if tol >= period / 3.0 {
        return Err(VideoError::CoarseTimeBase {
            path: path.into(),
            time_base_s,
            fps,
        });
    }
    let n = times.len();
    let own = (n >= 2 && times[n - 1] > 0.0).then(|| (n - 1) as f64 / times[n - 1]);
    let own_text = own.map(rate_text).unwrap_or_default();
    // a constant rate other than --fps: named as such, never a dropped frame or a variable rate
    let mut steps: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(f64::total_cmp);
    if let Some(&median) = steps.get(steps.len() / 2) {
        // two timestamps each rounded to the time base differ by up to one tick
        let step_tol = time_base_s + 2e-6;
        let regular = steps.iter().all(|s| (s - median).abs() <= step_tol);
        if regular {
            if let Some(i) = (1..n).find(|&i| (times[i] - i as f64 * period).abs() > tol) {
                if let Some(own) = own.filter(|_| retime) {
                    return Ok(Some(own));
                }
                return Err(VideoError::IrregularTimestamps {
                    path: path.into(),
                    frame: i,
                    time_s: times[i],
                    expected_s: i as f64 * period,
                    fps,
                    what: format!(
                        "the video's frame rate is {own_text}, constant, not {fps}; give that \
                         as $fps, or add $retime if the camera recorded at {fps} fps and \
                         the file plays it at another rate (slow motion, a time lapse)"
                    ),
                });
            }
            return Ok(None);
        }
    }
    for i in 1..times.len() {
        let expected = i as f64 * period;
        let step = times[i] - times[i - 1];
        let what = if (step - period).abs() > tol {
            if step > 1.5 * period {
                format!(
                    "{:.2} frame periods after the previous frame: a dropped frame",
                    step / period
                )
            } else {
                format!(
                    "{:.3} frame periods after the previous frame: a variable frame rate",
                    step / period
                )
            }
        } else if (times[i] - expected).abs() > tol {
            format!(
                "the container's frame rate is about {:.4} fps, not {fps}",
                i as f64 / times[i]
            )
        } else {
            continue;
        };
        return Err(VideoError::IrregularTimestamps {
            path: path.into(),
            frame: i,
            time_s: times[i],
            expected_s: expected,
            fps,
            what: format!("{what} (the video's mean frame rate is {own_text})"),
        });
    }
    Ok(None)
}

/// A frame rate measured from timestamps as a message gives it: `29.9700 fps (30000/1001)`
/// when it is within 1e-4 of a whole number of frames per second or per 1.001 s (the NTSC
/// rates), else `about 47.1234 fps`.
pub fn rate_text(fps: f64) -> String {
    for (scale, den) in [(1.0, 1.0), (1000.0, 1001.0)] {
        let num = (fps * den / scale).round() * scale;
        let exact = num / den;
        if num > 0.0 && (exact - fps).abs() < 1e-4 * fps {
            return format!("{exact:.4} fps ({num}/{den})");
        }
    }
    format!("about {fps:.4} fps")
}
