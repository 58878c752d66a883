//! `host-harness plan`: the CSV contract, the weighted centroid's rows against the
//! closed-form sinc, the longest exposure at `1 - tolerance`, the warnings, the preset, and
//! bad flags refused with exit code 2 naming the flag.

use crate::util::{harness, words};
use std::collections::HashMap;
use std::path::Path;

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// `sin(pi x) / (pi x)` in double precision (the closed form the rows are checked against).
fn sinc(x: f64) -> f64 {
    let z = std::f64::consts::PI * x;
    if z == 0.0 {
        1.0
    } else {
        z.sin() / z
    }
}

/// Runs `plan` with `args` and `--out DIR/plan.csv`; the header line and the rows by column.
fn plan_csv(dir: &Path, args: &[&str]) -> (String, Vec<HashMap<String, String>>, String) {
    let out = dir.join("plan.csv");
    let mut all = vec!["plan"];
    all.extend(args);
    all.extend(["--out", out.to_str().unwrap()]);
    let o = harness(&all);
    assert!(o.status.success(), "{all:?}: {}", text(&o.stderr));
    let body = std::fs::read_to_string(&out).unwrap();
    let header = body.lines().next().unwrap().to_string();
    let mut r = csv::Reader::from_reader(body.as_bytes());
    let names: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r
        .records()
        .map(|rec| {
            let rec = rec.unwrap();
            names
                .iter()
                .cloned()
                .zip(rec.iter().map(String::from))
                .collect()
        })
        .collect();
    (header, rows, text(&o.stdout))
}

/// Runs `host-harness` with `args`: exit code 2 and an `error:` on stderr that contains `needle`.
fn assert_refused(args: &[&str], needle: &str) {
    let o = harness(args);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert!(
        err.starts_with("error:") && err.contains(needle),
        "{args:?}: {err}"
    );
}

fn num(row: &HashMap<String, String>, col: &str) -> f64 {
    row[col]
        .parse()
        .unwrap_or_else(|_| panic!("{col}: {:?}", row[col]))
}

#[test]
fn weighted_rows_follow_the_sinc_and_the_csv_header_is_the_contract() {
    let dir = tempfile::tempdir().unwrap();
    let base = [
        "--freqs-hz",
        "2,2.5",
        "--amplitude-px",
        "4,3",
        // 5 fps: a frame period (200 ms) longer than the tolerance's exposures
        "--fps",
        "5",
        "--tolerance",
        "0.1",
        "--threshold-frac",
        "0",
        "--centroid",
        "weighted",
    ];
    let (header, rows, stdout) = plan_csv(dir.path(), &base);
    assert_eq!(
        header,
        "mode,f_hz,centroid,max_exposure_ms,e2pr,predicted_ratio,compensated_residual,\
         lost_frame_risk"
    );
    assert_eq!(rows.len(), 2, "{stdout}");
    for (row, f) in rows.iter().zip([2.0, 2.5]) {
        assert_eq!(row["centroid"], "weighted");
        assert_eq!(num(row, "f_hz"), f);
        // the longest exposure keeps the ratio at exactly 1 - tolerance (bisection to 1e-18 in
        // E2PR; the CSV's shortest round-trip digits are exact)
        let te = num(row, "max_exposure_ms") / 1000.0;
        assert!((sinc(f * te) - 0.9).abs() < 1e-9, "{row:?}");
        // evaluated there: E2PR = f Te and the ratio is the sinc of it
        assert!((num(row, "e2pr") - f * te).abs() < 1e-12, "{row:?}");
        assert!(
            (num(row, "predicted_ratio") - sinc(f * te)).abs() < 1e-12,
            "{row:?}"
        );
    }
    // the sinc depends on f Te only: 2.0 Hz gets 1.25 x the exposure of 2.5 Hz
    let ratio = num(&rows[0], "max_exposure_ms") / num(&rows[1], "max_exposure_ms");
    assert!((ratio - 1.25).abs() < 1e-12, "{ratio}");
    // at a given exposure every row is evaluated there, the ratio the closed form
    let mut fixed = base.to_vec();
    fixed.extend(["--exposure-ms", "60"]);
    let (_, rows, _) = plan_csv(dir.path(), &fixed);
    for (row, f) in rows.iter().zip([2.0, 2.5]) {
        assert!((num(row, "e2pr") - f * 0.06).abs() < 1e-15, "{row:?}");
        assert!(
            (num(row, "predicted_ratio") - sinc(f * 0.06)).abs() < 1e-12,
            "{row:?}"
        );
    }
    // the CSV was renamed into place: no temporary file is left beside it
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["plan.csv"]);
}

#[test]
fn binary_rows_cross_the_tolerance_at_their_longest_exposure() {
    let dir = tempfile::tempdir().unwrap();
    let (_, rows, _) = plan_csv(
        dir.path(),
        &[
            "--freqs-hz",
            "2.5",
            "--amplitude-px",
            "5",
            "--fps",
            "5",
            "--centroid",
            "binary",
        ],
    );
    let row = &rows[0];
    assert_eq!(row["centroid"], "binary");
    // the rendered transfer, evaluated where the planner says it crosses 0.9: the same
    // interpolated curve, so the crossing is exact to rounding
    assert!((num(row, "predicted_ratio") - 0.9).abs() < 1e-9, "{row:?}");
    // the binary centroid loses less than the box filter here (method.md §2.6): the longest
    // exposure is beyond the sinc's 0.2505 / 2.5 Hz = 100.2 ms
    assert!(num(row, "max_exposure_ms") > 100.2, "{row:?}");
}

#[test]
fn aliasing_and_long_exposures_are_warned() {
    let o = harness(&words(
        "plan --freqs-hz 2,30 --amplitude-px 3 --fps 50 --centroid weighted",
        &[],
    ));
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(
        out.contains("warning: mode 2 at 30 Hz is above fps/2 = 25 Hz: it aliases"),
        "{out}"
    );
    assert!(!out.contains("mode 1 at 2 Hz is above"), "{out}");
    // the tolerance alone would allow 125 ms for mode 1, longer than the 20 ms frame: the
    // maximum is the frame period, never an exposure no camera has
    assert!(
        out.contains(
            "warning: mode 1: the tolerance alone allows 125.2 ms, longer than the frame \
             period; max_exposure_ms is the frame period, 20.000 ms"
        ),
        "{out}"
    );
    assert!(!out.contains("exposure 125.2 ms is longer"), "{out}");
    // an exposure given longer than the frame is warned as such
    let o = harness(&words(
        "plan --freqs-hz 2 --amplitude-px 3 --fps 50 --exposure-ms 60 --centroid weighted",
        &[],
    ));
    assert!(
        text(&o.stdout).contains("warning: mode 1: exposure 60.0 ms is longer than the frame"),
        "{}",
        text(&o.stdout)
    );
}

#[test]
fn the_grandstand_preset_plans_the_study_modes() {
    let dir = tempfile::tempdir().unwrap();
    let (_, rows, stdout) = plan_csv(
        dir.path(),
        &["--preset", "grandstand", "--tolerance", "0.1"],
    );
    // three modes, binary rows then weighted rows
    let got: Vec<(String, String, String)> = rows
        .iter()
        .map(|r| (r["mode"].clone(), r["f_hz"].clone(), r["centroid"].clone()))
        .collect();
    let want: Vec<(String, String, String)> = ["binary", "weighted"]
        .iter()
        .flat_map(|c| {
            [("1", "2"), ("2", "2.5"), ("3", "3.16")]
                .map(|(m, f)| (m.to_string(), f.to_string(), c.to_string()))
        })
        .collect();
    assert_eq!(got, want);
    assert!(
        stdout.contains("threshold 100 (0.5 of the level); 50 fps"),
        "{stdout}"
    );
    assert_refused(&["plan", "--preset", "cantilever"], "--preset cantilever");
}

#[test]
fn bad_flags_exit_2_naming_the_flag() {
    let ok = ["--freqs-hz", "2.5", "--amplitude-px", "3", "--fps", "50"];
    let cases: [(&[&str], &str); 10] = [
        (&["--tolerance", "1.5"], "--tolerance"),
        (&["--tolerance", "0"], "--tolerance"),
        (&["--tolerance", "-0.1"], "--tolerance"),
        (&["--fps", "NaN"], "--fps"),
        (&["--amplitude-px", "-1"], "--amplitude-px"),
        (&["--freqs-hz", "0"], "--freqs-hz"),
        (&["--threshold-frac", "1"], "--threshold-frac"),
        (&["--exposure-ms", "-5"], "--exposure-ms"),
        (&["--target-radius-px", "inf"], "--target-radius-px"),
        (&["--amplitude-px", "1,2,3"], "--amplitude-px"),
    ];
    for (extra, flag) in cases {
        // the bad value replaces the good one of the same flag
        let mut args = vec!["plan"];
        let mut i = 0;
        while i < ok.len() {
            if ok[i] != extra[0] {
                args.extend(&ok[i..i + 2]);
            }
            i += 2;
        }
        args.extend(extra);
        assert_refused(&args, flag);
    }
    assert_refused(
        &["plan", "--freqs-hz", "2.5", "--amplitude-px", "3"],
        "missing --fps",
    );
}

/// `analyze --compensate-exposure` on a synthetic cantilever recording filmed with an 8 ms
/// exposure (E2PR 0.26 for mode 2 at 32.4 Hz: the blur costs about 11 %), weighted centroid
/// with the threshold at the black background (the case where the sinc is exact).
#[test]
fn compensation_brings_the_weighted_vision_amplitude_back_to_the_accelerometer() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rec");
    let rec_s = rec.to_str().unwrap();
    let o = harness(&words(
        "render --preset cantilever --recording {} --exposure-ms 8",
        &[rec_s],
    ));
    assert!(o.status.success(), "{}", text(&o.stderr));
    let analyze = |out: &str, extra: &[&str]| {
        let frames = rec.join("frames");
        let accel = rec.join("accel.csv");
        let out = dir.path().join(out);
        // the recording's README.txt command, with the weighted centroid at threshold 0
        let mut args: Vec<&str> = "analyze --fps 120 --fs 2048 --time-col t_s --threshold 0 \
                                   --mode weighted --mm-per-px 0.1266 --exposure-ms 8"
            .split_whitespace()
            .collect();
        let paths = [("--frames", &frames), ("--accel", &accel), ("--out", &out)];
        for (flag, p) in &paths {
            args.extend([*flag, p.to_str().unwrap()]);
        }
        args.extend(extra);
        let o = harness(&args);
        assert!(o.status.success(), "{}", text(&o.stderr));
        let modes = std::fs::read_to_string(out.join("modes.csv")).unwrap();
        // (system, mode) -> (f_hz, amplitude)
        let rows: HashMap<(String, String), (f64, f64)> = modes
            .lines()
            .skip(1)
            .map(|l| {
                let c: Vec<&str> = l.split(',').collect();
                (
                    (c[0].to_string(), c[1].to_string()),
                    (c[4].parse().unwrap(), c[5].parse().unwrap()),
                )
            })
            .collect();
        (rows, text(&o.stdout), out)
    };
    let (raw, _, raw_dir) = analyze("raw", &[]);
    let (comp, report, comp_dir) = analyze("comp", &["--compensate-exposure"]);
    assert!(!raw_dir.join("compensation.csv").exists());
    assert!(comp_dir.join("compensation.csv").exists());
    for mode in ["1", "2"] {
        let key = |s: &str| (s.to_string(), mode.to_string());
        let acc = raw[&key("accelerometer")].1;
        assert_eq!(
            acc,
            comp[&key("accelerometer")].1,
            "the accelerometer is not touched"
        );
        let ((f_raw, a_raw), (f_comp, a_comp)) = (raw[&key("vision")], comp[&key("vision")]);
        eprintln!(
            "mode {mode}: vision / accelerometer {:.4} raw, {:.4} compensated",
            a_raw / acc,
            a_comp / acc
        );
        // the same bin is picked, divided by the closed-form sinc there (the firmware's f32
        // sinc: 1e-6 relative)
        assert_eq!(f_raw, f_comp);
        let want = a_raw / sinc(f_raw * 0.008);
        assert!(
            (a_comp / want - 1.0).abs() < 1e-5,
            "mode {mode}: {a_comp} vs {want}"
        );
        assert!(
            (a_comp / acc - 1.0).abs() < (a_raw / acc - 1.0).abs(),
            "mode {mode}: compensated {a_comp}, raw {a_raw}, accelerometer {acc}"
        );
        assert!(report.contains(&format!("mode {mode}: ")), "{report}");
    }
    assert!(report.contains("exposure compensation (8 ms"), "{report}");
}

#[test]
fn a_study_files_imaging_table_reaches_the_plan() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("big-target.toml");
    std::fs::write(
        &cfg,
        "preset = \"grandstand\"\n[imaging]\ntarget_radius_px = 24.0\nread_noise = 1.0\n",
    )
    .unwrap();
    let fixed = ["--centroid", "weighted", "--exposure-ms", "100"];
    let (_, preset, _) = plan_csv(
        dir.path(),
        &[&["--preset", "grandstand"][..], &fixed].concat(),
    );
    let o = harness(&[&["plan", "--config", cfg.to_str().unwrap()][..], &fixed].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    // the effects it does not model are named, not dropped in silence
    assert!(
        text(&o.stderr).contains("not: read_noise"),
        "{}",
        text(&o.stderr)
    );
    let (_, with_cfg, _) = plan_csv(
        dir.path(),
        &[&["--config", cfg.to_str().unwrap()][..], &fixed].concat(),
    );
    // the lost-frame risk is the swept path over the target's diameter: twice the radius,
    // half the risk
    for (a, b) in preset.iter().zip(&with_cfg) {
        let ratio = num(b, "lost_frame_risk") / num(a, "lost_frame_risk");
        assert!((ratio - 0.5).abs() < 1e-9, "{ratio}: {a:?} {b:?}");
    }
}
