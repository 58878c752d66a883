//! Several targets along the cantilever (issue 14): a synthetic 5-target recording (2 ms
//! exposure, read noise on) analysed with `analyze --targets` from its PNG frames and from its
//! lossless video, with identical results: frequencies within one bin, damping within 10 % of
//! the model, mode shapes with MAC >= 0.99 against the model's, lost frames per target, bad
//! target counts named.

use crate::util::{assert_exit_2, assert_ok, harness};
use std::path::Path;

/// `(system, target, mode) -> (f_hz, damping)` from modes.csv.
fn modes(dir: &Path) -> Vec<(String, usize, usize, f64, f64)> {
    let text = std::fs::read_to_string(dir.join("modes.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "system,target,mode,band_lo_hz,band_hi_hz,f_hz,amplitude,damping,e2pr"
    );
    lines
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            let num = |i: usize| c[i].parse::<f64>().unwrap_or(f64::NAN);
            (
                c[0].to_string(),
                c[1].parse().unwrap(),
                c[2].parse().unwrap(),
                num(5),
                num(7),
            )
        })
        .collect()
}

/// MAC of two real shapes.
fn mac(a: &[f64], b: &[f64]) -> f64 {
    let ab: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    ab * ab / (a.iter().map(|x| x * x).sum::<f64>() * b.iter().map(|x| x * x).sum::<f64>())
}

#[test]
fn five_targets_give_the_model_frequencies_damping_and_shapes() {
    let tmp = tempfile::tempdir().unwrap();
    let rec = tmp.path().join("rec");
    let r = rec.to_str().unwrap();
    assert_ok(&harness(&[
        "render",
        "--preset",
        "cantilever",
        "--recording",
        r,
        "--targets",
        "5",
        "--exposure-ms",
        "2",
        // sensor read noise on (2 grey levels rms), and the same frames as a lossless video
        "--read-noise",
        "2",
        "--video",
    ]));
    let out = rec.join("analysis");
    let analyze_from = |frames: &str, out: &Path, k: &str| {
        let accel = format!("{r}/accel.csv");
        harness(&[
            "analyze",
            "--frames",
            frames,
            "--fps",
            "120",
            "--accel",
            &accel,
            "--fs",
            "2048",
            "--time-col",
            "t_s",
            "--threshold",
            "127",
            "--mm-per-px",
            "0.1266",
            "--exposure-ms",
            "2",
            "--targets",
            k,
            "--out",
            out.to_str().unwrap(),
            // the synthetic record is periodic: a rectangular window has no leakage, so the
            // fitted damping is the model's (a Hann segment widens the peak)
            "--window",
            "rect",
        ])
    };
    let png_frames = format!("{r}/frames");
    let analyze = |k: &str| analyze_from(&png_frames, &out, k);
    assert_ok(&analyze("5"));
    // the video gives the same results, file for file
    let from_video = rec.join("analysis-video");
    assert_ok(&analyze_from(&format!("{r}/frames.mkv"), &from_video, "5"));
    for f in ["modes.csv", "shapes.csv", "frf.uff"] {
        assert!(
            std::fs::read(out.join(f)).unwrap() == std::fs::read(from_video.join(f)).unwrap(),
            "{f} differs between the PNG frames and the video"
        );
    }
    let recording: toml::Value =
        toml::from_str(&std::fs::read_to_string(rec.join("recording.toml")).unwrap()).unwrap();
    let model = recording["modes"].as_array().unwrap();
    let found = modes(&out);
    assert_eq!(found.len(), 2 * 6, "{found:?}");
    for (mode, m) in model.iter().enumerate() {
        let (f, zeta) = (m["f_hz"].as_float().unwrap(), m["zeta"].as_float().unwrap());
        // the accelerometer and the tip target (co-located)
        for (system, target) in [("accelerometer", 0), ("vision", 5)] {
            let (_, _, _, fit_f, fit_zeta) = found
                .iter()
                .find(|r| r.0 == system && r.1 == target && r.2 == mode + 1)
                .unwrap()
                .clone();
            assert!(
                (fit_f - f).abs() < 0.1,
                "{system} mode {}: {fit_f} Hz, model {f}",
                mode + 1
            );
            assert!(
                (fit_zeta / zeta - 1.0).abs() < 0.10,
                "{system} mode {}: damping {fit_zeta}, model {zeta}",
                mode + 1
            );
        }
    }
    // shapes against the model's
    let shapes = std::fs::read_to_string(out.join("shapes.csv")).unwrap();
    for (mode, truth) in recording["target_shapes"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
    {
        let truth: Vec<f64> = truth["shape"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_float().unwrap())
            .collect();
        let fitted: Vec<f64> = shapes
            .lines()
            .skip(1)
            .filter(|l| l.starts_with(&format!("{},", mode + 1)))
            .map(|l| l.split(',').nth(4).unwrap().parse().unwrap())
            .collect();
        let m = mac(&truth, &fitted);
        assert!(
            m >= 0.99,
            "mode {}: MAC {m}, {fitted:?} vs {truth:?}",
            mode + 1
        );
    }
    // a wrong target count is named with the frame
    assert_exit_2(
        &analyze("4"),
        "5 targets above the threshold in the first frame",
    );
}
