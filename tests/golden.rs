//! Golden outputs: what each job wrote before the restructuring into crates, and
//! the comparison that holds every later change to them: every cell of every CSV equal, or
//! within 1e-12 relative for numbers. A change that moves a number on purpose regenerates them
//! (`VIBCAM_BLESS=1 cargo test -p host-harness --test e2e golden`) and says why in its commit.
//!
//! The jobs: a small `study`, `simulate-hammer` and `ema`, `render --recording` and `analyze`
//! with and without an accelerometer (five targets), `simulate-field` and `modal`,
//! `simulate-field --render` and `track` by Lucas-Kanade with references. Large files are kept
//! as every k-th row (at most [`MAX_ROWS`]), the same rows compared.

use crate::util::{assert_ok, harness};
use std::path::{Path, PathBuf};

/// The most data rows a golden file keeps.
const MAX_ROWS: usize = 600;

/// The golden files' folder.
fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/golden")
}

/// `text`'s header and every k-th data row (k so that at most [`MAX_ROWS`] are kept).
fn sampled(text: &str) -> String {
    let mut lines = text.lines();
    let Some(header) = lines.next() else {
        return String::new();
    };
    let rows: Vec<&str> = lines.collect();
    let k = rows.len().div_ceil(MAX_ROWS).max(1);
    let mut out = format!("{header}\n");
    for (i, r) in rows.iter().enumerate() {
        if i % k == 0 {
            out.push_str(r);
            out.push('\n');
        }
    }
    out
}

/// Whether two cells agree: equal text, or numbers within 1e-12 relative (1e-300 absolute).
fn same_cell(a: &str, b: &str) -> bool {
    if a == b {
        return true;
    }
    match (a.parse::<f64>(), b.parse::<f64>()) {
        (Ok(x), Ok(y)) => (x - y).abs() <= 1e-12 * x.abs().max(y.abs()) || (x - y).abs() <= 1e-300,
        _ => false,
    }
}

/// Compares (or with `VIBCAM_BLESS` writes) the golden copies of `files` of `dir` under
/// `case`.
fn check(case: &str, dir: &Path, files: &[&str]) {
    let gdir = golden_dir().join(case);
    let bless = std::env::var_os("VIBCAM_BLESS").is_some();
    let mut problems = Vec::new();
    for f in files {
        let text = std::fs::read_to_string(dir.join(f))
            .unwrap_or_else(|e| panic!("{case}: {f} was not written: {e}"));
        let got = sampled(&text);
        let gpath = gdir.join(f);
        if bless {
            std::fs::create_dir_all(gpath.parent().unwrap()).unwrap();
            std::fs::write(&gpath, &got).unwrap();
            continue;
        }
        let want = std::fs::read_to_string(&gpath)
            .unwrap_or_else(|e| panic!("{case}: no golden {}: {e}", gpath.display()));
        let (w, g): (Vec<&str>, Vec<&str>) = (want.lines().collect(), got.lines().collect());
        if w.len() != g.len() {
            problems.push(format!("{case}/{f}: {} rows, golden {}", g.len(), w.len()));
            continue;
        }
        for (row, (a, b)) in w.iter().zip(&g).enumerate() {
            let (ca, cb): (Vec<&str>, Vec<&str>) = (a.split(',').collect(), b.split(',').collect());
            if ca.len() != cb.len() || ca.iter().zip(&cb).any(|(x, y)| !same_cell(x, y)) {
                problems.push(format!("{case}/{f} row {row}:\n  golden {a}\n  now    {b}"));
                break;
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

fn run(args: &[&str]) {
    assert_ok(&harness(args));
}

#[test]
fn a_small_study_writes_what_it_wrote() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("s");
    run(&[
        "study",
        "--runs",
        "4",
        "--exposures-ms",
        "40,180",
        "--no-plots",
        "--threads",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    check(
        "study",
        &out,
        &[
            "summary.csv",
            "realizations.csv",
            "frf_band.csv",
            "lost_frames.csv",
            "coverage.csv",
        ],
    );
}

#[test]
fn a_hammer_test_and_its_ema_write_what_they_wrote() {
    let tmp = tempfile::tempdir().unwrap();
    let h = tmp.path().join("h");
    run(&["simulate-hammer", "--out", h.to_str().unwrap()]);
    check(
        "simulate-hammer",
        &h,
        &["force.csv", "camera.csv", "truth.csv"],
    );
    let e = tmp.path().join("e");
    run(&[
        "ema",
        "--response",
        h.join("camera.csv").to_str().unwrap(),
        "--excitation",
        h.join("force.csv").to_str().unwrap(),
        "--excitation-col",
        "force_n",
        "--impact",
        "--exp-window",
        "off",
        "--f-max-hz",
        "200",
        "--no-plots",
        "--out",
        e.to_str().unwrap(),
    ]);
    check("ema", &e, &["modes.csv", "shapes.csv", "frf.csv"]);
}

#[test]
fn a_rendered_recording_analysed_with_and_without_its_accelerometer_writes_what_it_wrote() {
    let tmp = tempfile::tempdir().unwrap();
    let rec = tmp.path().join("rec");
    run(&[
        "render",
        "--preset",
        "cantilever",
        "--recording",
        rec.to_str().unwrap(),
        "--targets",
        "5",
        "--exposure-ms",
        "2",
    ]);
    let frames = rec.join("frames");
    let common = [
        "--frames",
        frames.to_str().unwrap(),
        "--fps",
        "120",
        "--threshold",
        "127",
        "--mm-per-px",
        "0.1266",
        "--targets",
        "5",
    ];
    let with = tmp.path().join("with");
    let accel = rec.join("accel.csv");
    let mut args = vec!["analyze"];
    args.extend_from_slice(&common);
    args.extend_from_slice(&[
        "--accel",
        accel.to_str().unwrap(),
        "--fs",
        "2048",
        "--time-col",
        "t_s",
        "--exposure-ms",
        "2",
        "--window",
        "rect",
        "--out",
        with.to_str().unwrap(),
    ]);
    run(&args);
    check(
        "analyze-accel",
        &with,
        &["modes.csv", "frf.csv", "displacement.csv", "shapes.csv"],
    );
    let without = tmp.path().join("without");
    let mut args = vec!["analyze"];
    args.extend_from_slice(&common);
    args.extend_from_slice(&["--out", without.to_str().unwrap()]);
    run(&args);
    check(
        "analyze-oma",
        &without,
        &["modes.csv", "shapes.csv", "displacement.csv"],
    );
}

#[test]
fn a_field_record_and_its_modal_analysis_write_what_they_wrote() {
    let tmp = tempfile::tempdir().unwrap();
    let f = tmp.path().join("f");
    run(&[
        "simulate-field",
        "--minutes",
        "2",
        "--seed",
        "4",
        "--out",
        f.to_str().unwrap(),
    ]);
    check("simulate-field", &f, &["displacement.csv", "truth.csv"]);
    let m = tmp.path().join("m");
    run(&[
        "modal",
        "--displacement",
        f.join("displacement.csv").to_str().unwrap(),
        "--no-plots",
        "--out",
        m.to_str().unwrap(),
    ]);
    check("modal", &m, &["modes.csv", "shapes.csv"]);
}

#[test]
fn a_shaken_scene_tracked_by_lucas_kanade_with_references_writes_what_it_wrote() {
    let tmp = tempfile::tempdir().unwrap();
    let rec = tmp.path().join("rec");
    run(&[
        "simulate-field",
        "--render",
        "--minutes",
        "0.25",
        "--references",
        "4",
        "--shake-px",
        "0.5",
        "--roll-deg",
        "0.2",
        "--out",
        rec.to_str().unwrap(),
    ]);
    let out = tmp.path().join("t");
    run(&[
        "track",
        "--frames",
        rec.join("frames").to_str().unwrap(),
        "--fps",
        "60",
        "--points",
        rec.join("points.csv").to_str().unwrap(),
        "--tracker",
        "lk",
        "--mm-per-px",
        "2",
        "--reference",
        rec.join("references.csv").to_str().unwrap(),
        "--no-plots",
        "--out",
        out.to_str().unwrap(),
    ]);
    check(
        "track-lk-reference",
        &out,
        &["displacement.csv", "camera_motion.csv"],
    );
}
