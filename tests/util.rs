//! Helpers shared by the end-to-end tests.

use std::path::Path;
use std::process::{Command, Output};

/// Runs the `host-harness` binary built for this test run with `args`.
pub fn harness(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_host-harness"))
        .args(args)
        .output()
        .expect("host-harness runs")
}

/// The words of a command line written as one would type it: `line` split at whitespace, each
/// `{}` taking the next of `slots` whole (a path with spaces stays one word).
pub fn words<'a>(line: &'a str, slots: &[&'a str]) -> Vec<&'a str> {
    let mut slots = slots.iter();
    let words: Vec<&str> = line
        .split_whitespace()
        .map(|w| {
            if w == "{}" {
                slots.next().expect("a slot for every {}")
            } else {
                w
            }
        })
        .collect();
    assert!(slots.next().is_none(), "more slots than {{}} in `{line}`");
    words
}

/// The words of `line` with each `{}` taking the next of `paths` (as text), then `extra`.
pub fn path_words<'a>(line: &'a str, paths: &[&'a Path], extra: &[&'a str]) -> Vec<&'a str> {
    let slots: Vec<&str> = paths.iter().map(|p| p.to_str().unwrap()).collect();
    let mut w = words(line, &slots);
    w.extend_from_slice(extra);
    w
}

/// MAC of a complex shape (`(re, im)` per point) with a real one.
pub fn mac(a: &[(f64, f64)], b: &[f64]) -> f64 {
    let (re, im) = a
        .iter()
        .zip(b)
        .fold((0.0, 0.0), |(r, i), (x, y)| (r + x.0 * y, i + x.1 * y));
    let aa: f64 = a.iter().map(|x| x.0 * x.0 + x.1 * x.1).sum();
    let bb: f64 = b.iter().map(|y| y * y).sum();
    (re * re + im * im) / (aa * bb)
}

/// The process's standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Asserts that the process succeeded, showing its exit code and both outputs if not.
pub fn assert_ok(o: &Output) {
    assert!(
        o.status.success(),
        "exit {:?}\nstdout:\n{}\nstderr:\n{}",
        o.status.code(),
        String::from_utf8_lossy(&o.stdout),
        stderr(o)
    );
}

/// Asserts that the process succeeded and that its standard output contains every one of
/// `needles`; gives that output back.
pub fn assert_says(o: &Output, needles: &[&str]) -> String {
    assert_ok(o);
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    assert_contains(&out, needles);
    out
}

/// Asserts that `text` contains every one of `needles`, naming the first missing one.
pub fn assert_contains(text: &str, needles: &[&str]) {
    for needle in needles {
        assert!(text.contains(needle), "`{needle}` not in {text}");
    }
}

/// Asserts exit code 2 (bad input) and that standard error contains `needle`.
pub fn assert_exit_2(o: &Output, needle: &str) {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains(needle), "`{needle}` not in {e}");
}

/// `render --preset cantilever --recording REC --exposure-ms 2` and `extra`, asserted to
/// succeed: the rendered cantilever most end-to-end tests read.
pub fn render_cantilever(rec: &Path, extra: &[&str]) {
    let mut args = words(
        "render --preset cantilever --recording {} --exposure-ms 2",
        &[rec.to_str().unwrap()],
    );
    args.extend_from_slice(extra);
    assert_ok(&harness(&args));
}

/// `analyze` of the frames `frames` (a name inside `rec`, or a whole path) of a recording
/// `render` wrote in `rec`, with its accelerometer: 120 fps, 2048 Hz by the `t_s` column,
/// threshold 127, 0.1266 mm/px, then `extra` (`--out` among them).
pub fn analyze_recording(rec: &Path, frames: &str, extra: &[&str]) -> Output {
    let (frames, accel) = (rec.join(frames), rec.join("accel.csv"));
    let mut args = words("analyze --frames {} --fps 120 --accel {} --fs 2048 --time-col t_s --threshold 127 --mm-per-px 0.1266", &[frames.to_str().unwrap(), accel.to_str().unwrap()]);
    args.extend_from_slice(extra);
    harness(&args)
}

/// The rows of `modes.csv` in `dir`, each a row of cells, its header checked to be the
/// multi-target one with the interval columns.
pub fn modes_csv_rows(dir: &std::path::Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(dir.join("modes.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "system,target,mode,band_lo_hz,band_hi_hz,f_hz,amplitude,damping,e2pr,method,\
         f_hz_u,f_hz_lo,f_hz_hi,damping_u,damping_lo,damping_hi,amplitude_u,amplitude_lo,\
         amplitude_hi"
    );
    lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

/// The poles of `report.html`'s picker (frequency, damping, order), and the indices of those
/// drawn as members of a mode's cluster.
pub fn page_poles(dir: &std::path::Path) -> (Vec<(f64, f64, u64)>, Vec<usize>) {
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    let tag = "id=\"pole-data\">";
    let start = html.find(tag).expect("a pole picker") + tag.len();
    let end = start + html[start..].find("</script>").unwrap();
    let data: serde_json::Value = serde_json::from_str(&html[start..end]).unwrap();
    let poles = data["poles"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            (
                p[0].as_f64().unwrap(),
                p[1].as_f64().unwrap(),
                p[2].as_u64().unwrap(),
            )
        })
        .collect();
    let circle = "<circle class=\"pole mode\" data-i=\"";
    let in_modes = html
        .match_indices(circle)
        .map(|(i, _)| {
            let rest = &html[i + circle.len()..];
            rest[..rest.find('"').unwrap()].parse().unwrap()
        })
        .collect();
    (poles, in_modes)
}
