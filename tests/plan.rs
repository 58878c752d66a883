//! `host-harness plan` (issue 12): the CSV contract, the weighted centroid's rows against the
//! closed-form sinc, the longest exposure at `1 - tolerance`, the warnings, the preset, and
//! bad flags refused with exit code 2 naming the flag.

use crate::util::harness;
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
        "--fps",
        "50",
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
            "50",
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
    let o = harness(&[
        "plan",
        "--freqs-hz",
        "2,30",
        "--amplitude-px",
        "3",
        "--fps",
        "50",
        "--centroid",
        "weighted",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(
        out.contains("warning: mode 2 at 30 Hz is above fps/2 = 25 Hz: it aliases"),
        "{out}"
    );
    assert!(!out.contains("mode 1 at 2 Hz is above"), "{out}");
    // 125 ms for mode 1 is longer than the 20 ms frame
    assert!(
        out.contains("warning: mode 1: exposure 125.2 ms is longer than the frame period"),
        "{out}"
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
