//! A camera that moves and a structure seen at an angle: `simulate-field --render` with a
//! shake, a roll and an oblique view writes the truth; `track`/`analyze` with `--reference`
//! take the camera's motion out, `--world` converts each target with its own scale, and bad
//! references are named.

use crate::util::assert_contains;
use crate::util::{analyze_recording, assert_exit_2, assert_ok, harness, render_cantilever, words};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// [`render`] into `rec` of a new temporary directory: (the directory, `rec`).
fn rendered(minutes: &str, extra: &[&str]) -> (tempfile::TempDir, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let rec = tmp.path().join("rec");
    render(&rec, minutes, extra);
    (tmp, rec)
}

/// Renders a field record of `minutes` into `dir` with `extra` flags.
fn render(dir: &Path, minutes: &str, extra: &[&str]) {
    let mut args = words(
        "simulate-field --render --minutes {} --out {}",
        &[minutes, dir.to_str().unwrap()],
    );
    args.extend_from_slice(extra);
    assert_ok(&harness(&args));
}

/// A CSV's rows as maps of column -> text.
fn rows(path: &Path) -> Vec<BTreeMap<String, String>> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let h: Vec<String> = r.headers().unwrap().iter().map(str::to_string).collect();
    r.records()
        .map(|rec| {
            let rec = rec.unwrap();
            h.iter()
                .cloned()
                .zip(rec.iter().map(str::to_string))
                .collect()
        })
        .collect()
}

/// Per target: a column of a per-frame, per-target file.
fn per_target(path: &Path, col: &str) -> BTreeMap<usize, Vec<f64>> {
    let mut out: BTreeMap<usize, Vec<f64>> = BTreeMap::new();
    for r in rows(path) {
        out.entry(r["target"].parse().unwrap())
            .or_default()
            .push(r[col].parse().unwrap());
    }
    out
}

fn centred(v: &[f64]) -> Vec<f64> {
    let m = v.iter().sum::<f64>() / v.len() as f64;
    v.iter().map(|x| x - m).collect()
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

/// Per target: the RMS error of the measured displacement (mm, about its mean) against the
/// truth's, and the gain (least-squares slope of measured on true).
fn errors(dir: &Path, out: &Path) -> Vec<(f64, f64)> {
    let truth = per_target(&dir.join("truth_motion.csv"), "disp_mm");
    let got = per_target(&out.join("displacement.csv"), "disp_mm");
    truth
        .iter()
        .map(|(t, x)| {
            let (x, y) = (centred(x), centred(&got[t]));
            let diff: Vec<f64> = x.iter().zip(&y).map(|(a, b)| b - a).collect();
            let gain = x.iter().zip(&y).map(|(a, b)| a * b).sum::<f64>()
                / x.iter().map(|a| a * a).sum::<f64>();
            (rms(&diff), gain)
        })
        .collect()
}

/// `track` of the record in `dir` with its own `points.csv`.
pub(crate) fn track(dir: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    track_points(dir, &dir.join("points.csv"), out, extra)
}

/// `track` of the record in `dir` with the windows of `points`.
fn track_points(dir: &Path, points: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args: Vec<String> = vec![
        "track".into(),
        "--frames".into(),
        dir.join("frames").to_str().unwrap().to_owned(),
        "--fps".into(),
        "60".into(),
        "--points".into(),
        points.to_str().unwrap().to_owned(),
        "--threshold".into(),
        "127".into(),
        "--tracker".into(),
        "weighted".into(),
        "--out".into(),
        out.to_str().unwrap().to_owned(),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    harness(&args)
}

#[test]
fn the_cameras_shake_is_taken_out_by_static_references() {
    let tmp = tempfile::tempdir().unwrap();
    let (still, shaken) = (tmp.path().join("still"), tmp.path().join("shaken"));
    render(&still, "1", &["--references", "4"]);
    // 0.5 px RMS along each axis over 1-5 Hz and a roll of 0.2 deg RMS
    let shake = "--references 4 --shake-px 0.5 --roll-deg 0.2";
    render(&shaken, "1", &shake.split(' ').collect::<Vec<_>>());
    let scale = ["--mm-per-px", "2"];
    let base = tmp.path().join("base");
    assert_ok(&track(&still, &base, &scale));
    let raw = tmp.path().join("raw");
    assert_ok(&track(&shaken, &raw, &scale));
    let comp = tmp.path().join("comp");
    let refs = shaken.join("references.csv");
    let o = track(
        &shaken,
        &comp,
        &[&scale[..], &["--reference", refs.to_str().unwrap()]].concat(),
    );
    assert_ok(&o);
    let (e0, e_raw, e_comp) = (
        errors(&still, &base),
        errors(&shaken, &raw),
        errors(&shaken, &comp),
    );
    for t in 0..e0.len() {
        // the bar: within 1.5x of the same scene without shake
        assert!(
            e_comp[t].0 <= 1.5 * e0[t].0,
            "target {}: {:.4} mm compensated, {:.4} mm without shake",
            t + 1,
            e_comp[t].0,
            e0[t].0
        );
        assert!(
            e_raw[t].0 > 10.0 * e0[t].0,
            "the shake shows without references"
        );
    }
    // the estimate against the truth, both about their means
    let got = rows(&comp.join("camera_motion.csv"));
    let truth = rows(&shaken.join("camera_truth.csv"));
    for (col, tol) in [("dx_px", 0.02), ("dy_px", 0.02), ("rotation_deg", 0.005)] {
        let a: Vec<f64> = got.iter().map(|r| r[col].parse().unwrap()).collect();
        let b: Vec<f64> = truth.iter().map(|r| r[col].parse().unwrap()).collect();
        let d: Vec<f64> = centred(&a)
            .iter()
            .zip(centred(&b))
            .map(|(x, y)| x - y)
            .collect();
        assert!(rms(&d) < tol, "{col}: {} off", rms(&d));
        assert!(rms(&centred(&b)) > 0.15, "{col}: the truth moves");
    }
    // displacement.csv keeps the raw position beside the compensated one
    let d = rows(&comp.join("displacement.csv"));
    assert!(d[0].contains_key("cx_raw") && d[0].contains_key("cy_raw"));
    let report = std::fs::read_to_string(comp.join("report.txt")).unwrap();
    assert_contains(
        &report,
        &[
            "camera motion: similarity from 4 reference(s)",
            "of its raw motion's RMS",
        ],
    );
    assert!(comp.join("camera_motion.png").exists());
}

/// The modes of `analyze`'s modes.csv: (method, f_hz).
fn modes(out: &Path) -> Vec<(String, f64)> {
    rows(&out.join("modes.csv"))
        .iter()
        .map(|r| (r["method"].clone(), r["f_hz"].parse().unwrap()))
        .collect()
}

#[test]
fn a_shake_that_looks_like_a_mode_is_named_and_gone_with_references() {
    // a tripod's sway at 2.8-3.2 Hz (inside the 1-5 Hz), between the shear frame's
    // first two modes (1.50 and 4.38 Hz)
    let shake = "--references 4 --shake-px 0.5 --roll-deg 0.2 --shake-hz 2.8,3.2";
    let (tmp, rec) = rendered("1", &shake.split(' ').collect::<Vec<_>>());
    let analyze = |out: &Path, refs: bool| {
        let mut args = vec![
            "analyze".to_string(),
            "--frames".into(),
            rec.join("frames").to_str().unwrap().into(),
            "--fps".into(),
            "60".into(),
            "--points".into(),
            rec.join("points.csv").to_str().unwrap().into(),
            "--threshold".into(),
            "127".into(),
            "--tracker".into(),
            "weighted".into(),
            "--out".into(),
            out.to_str().unwrap().into(),
        ];
        if refs {
            args.push("--reference".into());
            args.push(rec.join("references.csv").to_str().unwrap().into());
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        assert_ok(&harness(&args));
        let report = std::fs::read_to_string(out.join("report.txt")).unwrap();
        (modes(out), report)
    };
    let (without, report) = analyze(&tmp.path().join("a"), false);
    let spurious = |m: &[(String, f64)]| m.iter().filter(|(_, f)| (2.6..3.4).contains(f)).count();
    assert!(spurious(&without) > 0, "{without:?}");
    assert!(report.contains("moves every target alike"), "{report}");
    let (with, report) = analyze(&tmp.path().join("b"), true);
    assert_eq!(spurious(&with), 0, "{with:?}");
    assert!(!report.contains("moves every target alike"), "{report}");
    // and the structure's five modes are still there (SSI within 1 %)
    let truth: Vec<f64> = rows(&rec.join("truth.csv"))
        .iter()
        .filter(|r| r["target"] == "1")
        .map(|r| r["f_hz"].parse().unwrap())
        .collect();
    assert_eq!(truth.len(), 5);
    for f in truth {
        assert!(
            with.iter()
                .any(|(m, g)| m == "ssi" && (g - f).abs() < 0.01 * f),
            "{f} Hz: {with:?}"
        );
    }
}

#[test]
fn an_oblique_view_is_measured_in_millimetres_through_the_planes_points() {
    // 2 px RMS: the motion well above the centroid's noise, so that the scale is what is seen
    let (tmp, rec) = rendered(
        "1",
        &["--references", "4", "--oblique-deg", "30", "--rms-px", "2"],
    );
    let world = tmp.path().join("world");
    let o = track(
        &rec,
        &world,
        &["--world", rec.join("world.csv").to_str().unwrap()],
    );
    assert_ok(&o);
    for (t, (_, gain)) in errors(&rec, &world).iter().enumerate() {
        assert!((gain - 1.0).abs() < 0.01, "target {}: gain {gain}", t + 1);
    }
    let report = std::fs::read_to_string(world.join("report.txt")).unwrap();
    assert!(report.contains("would be off by"), "{report}");
    // the output-only analysis in mm through the plane: the scale's uncertainty is in the
    // amplitudes' intervals, which are wider than the record's statistics alone
    let a = tmp.path().join("analyze");
    let wfile = rec.join("world.csv");
    let run = |out: &Path, scale: &[&str]| {
        let mut args = words(
            "analyze --frames {} --fps 60 --points {} --threshold 127 --tracker weighted --out {}",
            &[
                rec.join("frames").to_str().unwrap(),
                rec.join("points.csv").to_str().unwrap(),
                out.to_str().unwrap(),
            ],
        )
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>();
        args.extend(scale.iter().map(|s| s.to_string()));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        assert_ok(&harness(&args));
        rows(&out.join("modes.csv"))
    };
    // the same plane with its points' image positions taken as exact, then as 3 px uncertain:
    // the same homography, the same records, only the scale's uncertainty differs
    let with_u = |u: &str, name: &str| {
        let text = std::fs::read_to_string(&wfile).unwrap();
        let mut lines = text.lines();
        let mut out = format!("{},u_px\n", lines.next().unwrap());
        for l in lines {
            out.push_str(&format!("{l},{u}\n"));
        }
        let f = tmp.path().join(name);
        std::fs::write(&f, out).unwrap();
        f
    };
    let (exact, loose) = (with_u("0", "exact.csv"), with_u("3", "loose.csv"));
    let plain = run(
        &tmp.path().join("exact"),
        &["--world", exact.to_str().unwrap()],
    );
    let report = std::fs::read_to_string(tmp.path().join("exact/report.txt")).unwrap();
    assert!(!report.contains("is folded into the"), "{report}");
    let with = run(&a, &["--world", loose.to_str().unwrap()]);
    let report = std::fs::read_to_string(a.join("report.txt")).unwrap();
    assert!(report.contains("is folded into the"), "{report}");
    let rel = |r: &BTreeMap<String, String>| -> Option<f64> {
        Some(r["amplitude_u"].parse::<f64>().ok()? / r["amplitude"].parse::<f64>().ok()?)
    };
    let mut compared = 0;
    for (w, p) in with.iter().zip(&plain) {
        if let (Some(a), Some(b)) = (rel(w), rel(p)) {
            assert!(
                a > b,
                "{}: {a} with the plane's scale, {b} without",
                w["f_hz"]
            );
            compared += 1;
        }
    }
    assert!(compared > 0, "no amplitude intervals: {with:?}");
    // one scale for the frame (the true one at the row's centre) is off at the ends
    let one = tmp.path().join("one");
    assert_ok(&track(&rec, &one, &["--mm-per-px", "2"]));
    let g = errors(&rec, &one);
    assert!(
        (g[0].1 - 1.0).abs() > 0.1 && (g[4].1 - 1.0).abs() > 0.1,
        "{g:?}"
    );
    // the scale between two points: the references r1 and r3 are 400 mm apart in the plane
    let between = tmp.path().join("between");
    let refs = rec.join("references.csv");
    assert_ok(&track(
        &rec,
        &between,
        &[
            "--reference",
            refs.to_str().unwrap(),
            "--scale",
            "r1,r3,400",
        ],
    ));
    let report = std::fs::read_to_string(between.join("report.txt")).unwrap();
    assert!(
        report.contains("400 mm between reference r1 and reference r3"),
        "{report}"
    );
}

#[test]
fn bad_references_are_named_never_silently_used() {
    let (tmp, rec) = rendered("0.5", &["--references", "4", "--shake-px", "0.5"]);
    let refs = std::fs::read_to_string(rec.join("references.csv")).unwrap();
    let points = std::fs::read_to_string(rec.join("points.csv")).unwrap();
    // a fifth "reference" on the top target (it moves) and a sixth on black (lost)
    let top = points.lines().last().unwrap().split_once(',').unwrap().1;
    let bad = format!("{refs}5,{top}\n6,3,3,5,5\n").replace("\n\n", "\n");
    let bad_file = tmp.path().join("bad.csv");
    std::fs::write(&bad_file, bad).unwrap();
    // placed on a target's window it is refused at once: the target's own motion would be
    // taken for the camera's
    let o = track(
        &rec,
        &tmp.path().join("on"),
        &["--reference", bad_file.to_str().unwrap()],
    );
    assert_exit_2(&o, "r5 at");
    assert_exit_2(&o, "overlaps target 5's window");
    // on a moving part that is not a target (the top storey, not followed here): found moving
    // and left out, named
    let four = tmp.path().join("four.csv");
    let kept: Vec<&str> = points.lines().take(points.lines().count() - 1).collect();
    std::fs::write(&four, kept.join("\n") + "\n").unwrap();
    let track4 = |out: &Path, extra: &[&str]| track_points(&rec, &four, out, extra);
    let out = tmp.path().join("out");
    let o = track4(&out, &["--reference", bad_file.to_str().unwrap()]);
    assert_ok(&o);
    let report = std::fs::read_to_string(out.join("report.txt")).unwrap();
    assert_contains(
        &report,
        &[
            "reference r5 left out: moves against the others",
            "reference r6 left out: lost in",
            "from 4 reference(s) (r1, r2, r3, r4)",
        ],
    );
    // too few for the model asked
    let three = tmp.path().join("three.csv");
    std::fs::write(&three, refs.lines().take(4).collect::<Vec<_>>().join("\n")).unwrap();
    let o = track(
        &rec,
        &tmp.path().join("x"),
        &[
            "--reference",
            three.to_str().unwrap(),
            "--camera-model",
            "homography",
        ],
    );
    assert_exit_2(
        &o,
        "--camera-model homography: needs 4 references or more; --reference has 3",
    );
    // two that disagree: which one moves cannot be told
    let two = tmp.path().join("two.csv");
    std::fs::write(
        &two,
        format!(
            "target,x,y,w,h\n1,{}\n2,{top}\n",
            refs.lines().nth(1).unwrap().split_once(',').unwrap().1
        ),
    )
    .unwrap();
    let o = track4(
        &tmp.path().join("y"),
        &[
            "--reference",
            two.to_str().unwrap(),
            "--camera-model",
            "translation",
        ],
    );
    assert_exit_2(&o, "cannot be told");
}

#[test]
fn references_with_an_accelerometer_follow_the_same_rules() {
    let tmp = tempfile::tempdir().unwrap();
    let rec = tmp.path().join("rec");
    render_cantilever(&rec, &["--targets", "5"]);
    // a reference on the black background: nothing to follow
    let refs = tmp.path().join("refs.csv");
    std::fs::write(&refs, "target,x,y,w,h\n1,4,4,7,7\n").unwrap();
    let out = tmp.path().join("out");
    let analyze = |extra: &[&str]| {
        let mut args = vec!["--out", out.to_str().unwrap()];
        args.extend_from_slice(extra);
        analyze_recording(&rec, "frames", &args)
    };
    let r = refs.to_str().unwrap();
    let o = analyze(&["--targets", "5", "--reference", r]);
    assert_exit_2(&o, "needs 1 reference(s) that stay; 0 of 1 remain");
    assert!(
        crate::util::stderr(&o).contains("r1 lost in"),
        "{}",
        crate::util::stderr(&o)
    );
    assert_exit_2(&analyze(&["--reference", r]), "--reference with --accel");
    assert_exit_2(
        &analyze(&["--targets", "5", "--target-size-mm", "10"]),
        "with --accel give --mm-per-px",
    );
}
