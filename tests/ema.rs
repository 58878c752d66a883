//! Experimental modal analysis from the command line: a three-mode structure hit by a simulated
//! hammer (closed-form response, `host_harness::model::hammer`), the force recorded by a DAQ at
//! 50 kHz with noise, five points' displacements by a camera at 2 kHz from the same trigger;
//! `ema` must find the modes (frequency within 0.1 %, damping within 5 %, shapes MAC >= 0.99)
//! with and without the exponential window, and name a double hit and a clipped hit.

use crate::util::{assert_exit_2, assert_ok, harness};
use host_harness::model::hammer::{HammerMode, HammerTest, Hit};
use std::fmt::Write as _;
use std::path::Path;

const DAQ_HZ: f64 = 50_000.0;
const CAMERA_HZ: f64 = 2_000.0;
const POINTS: usize = 5;

fn structure(hits: Vec<Hit>) -> HammerTest {
    let shape = |r: usize| -> Vec<f64> {
        (0..POINTS)
            .map(|o| ((r + 1) as f64 * std::f64::consts::PI * (o as f64 + 0.7) / 6.0).sin())
            .collect()
    };
    HammerTest {
        modes: vec![
            HammerMode {
                f_hz: 23.0,
                damping: 0.015,
                shape: shape(0),
            },
            HammerMode {
                f_hz: 61.5,
                damping: 0.010,
                shape: shape(1),
            },
            HammerMode {
                f_hz: 118.0,
                damping: 0.008,
                shape: shape(2),
            },
        ],
        drive: 1,
        hits,
    }
}

fn hits(peaks: &[f64]) -> Vec<Hit> {
    peaks
        .iter()
        .enumerate()
        .map(|(i, &p)| Hit {
            t_s: 0.2 + 3.0 * i as f64,
            width_s: 0.0006,
            peak_n: p,
        })
        .collect()
}

/// A deterministic noise in [-0.5, 0.5).
fn noise(seed: u64, n: usize) -> Vec<f64> {
    host_harness::testing::uniform_noise(seed, n)
}

/// Writes `force.csv` (50 kHz, `t_s,force_n`, noise 0.3 N sd, clipped at `clip` N when given)
/// and `camera.csv` (2 kHz, `t_s,p1..p5` in mm, noise 0.5 um sd) of `test`, `seconds` long.
fn write_test(dir: &Path, test: &HammerTest, seconds: f64, clip: Option<f64>) {
    std::fs::create_dir_all(dir).unwrap();
    let n = (seconds * DAQ_HZ) as usize;
    let e = noise(1, n);
    let mut s = String::from("t_s,force_n\n");
    for (k, e) in e.iter().enumerate() {
        let t = k as f64 / DAQ_HZ;
        let mut f = test.force(t) + 0.3 * 3.46 * e;
        if let Some(c) = clip {
            f = f.min(c);
        }
        let _ = writeln!(s, "{t},{f:.5}");
    }
    std::fs::write(dir.join("force.csv"), s).unwrap();
    let m = (seconds * CAMERA_HZ) as usize;
    let e = noise(2, m * POINTS);
    let mut s = String::from("t_s");
    for o in 0..POINTS {
        let _ = write!(s, ",p{}", o + 1);
    }
    s.push('\n');
    for k in 0..m {
        let t = k as f64 / CAMERA_HZ;
        let _ = write!(s, "{t}");
        for o in 0..POINTS {
            let x_mm = 1e3 * test.displacement(o, t) + 5e-4 * 3.46 * e[k * POINTS + o];
            let _ = write!(s, ",{x_mm:.7}");
        }
        s.push('\n');
    }
    std::fs::write(dir.join("camera.csv"), s).unwrap();
}

/// `(f_hz, damping)` per mode of modes.csv, and the shapes (per mode, per point, re + i im).
fn results(dir: &Path) -> (Vec<(f64, f64)>, Vec<Vec<(f64, f64)>>) {
    let text = std::fs::read_to_string(dir.join("modes.csv")).unwrap();
    let modes: Vec<(f64, f64)> = text
        .lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            assert_eq!(c[9], "lscf", "{l}");
            (c[5].parse().unwrap(), c[7].parse().unwrap())
        })
        .collect();
    let text = std::fs::read_to_string(dir.join("shapes.csv")).unwrap();
    let mut shapes = vec![vec![(0.0, 0.0); POINTS]; modes.len()];
    for l in text.lines().skip(1) {
        let c: Vec<&str> = l.split(',').collect();
        let (m, t): (usize, usize) = (c[0].parse().unwrap(), c[1].parse().unwrap());
        shapes[m - 1][t - 1] = (c[4].parse().unwrap(), c[5].parse().unwrap());
    }
    (modes, shapes)
}

/// MAC of a complex shape with a real one.
fn mac(a: &[(f64, f64)], b: &[f64]) -> f64 {
    let (re, im) = a
        .iter()
        .zip(b)
        .fold((0.0, 0.0), |(r, i), (x, y)| (r + x.0 * y, i + x.1 * y));
    let aa: f64 = a.iter().map(|x| x.0 * x.0 + x.1 * x.1).sum();
    let bb: f64 = b.iter().map(|y| y * y).sum();
    (re * re + im * im) / (aa * bb)
}

fn check_modes(dir: &Path, test: &HammerTest, what: &str) {
    let (modes, shapes) = results(dir);
    assert_eq!(modes.len(), 3, "{what}: {modes:?}");
    for (i, m) in test.modes.iter().enumerate() {
        let (f, z) = modes[i];
        assert!(
            (f - m.f_hz).abs() < 1e-3 * m.f_hz,
            "{what}: mode {}: {f} Hz vs {}",
            i + 1,
            m.f_hz
        );
        assert!(
            (z - m.damping).abs() < 0.05 * m.damping,
            "{what}: mode {}: damping {z} vs {}",
            i + 1,
            m.damping
        );
        let c = mac(&shapes[i], &m.shape);
        assert!(c >= 0.99, "{what}: mode {}: MAC {c}", i + 1);
    }
}

fn ema(dir: &Path, out: &str, extra: &[&str]) -> std::process::Output {
    let (r, f, o) = (
        dir.join("camera.csv"),
        dir.join("force.csv"),
        dir.join(out),
    );
    let mut args = vec![
        "ema",
        "--response",
        r.to_str().unwrap(),
        "--excitation",
        f.to_str().unwrap(),
        "--excitation-col",
        "force_n",
        "--impact",
        "--f-max-hz",
        "200",
        "--out",
        o.to_str().unwrap(),
        "--force",
        "--no-plots",
    ];
    args.extend_from_slice(extra);
    harness(&args)
}

#[test]
fn a_hammer_test_at_two_rates_gives_the_modes_with_and_without_the_exponential_window() {
    let dir = std::env::temp_dir().join(format!("vibcam-ema-{}", std::process::id()));
    let test = structure(hits(&[150.0, 120.0, 180.0]));
    write_test(&dir, &test, 9.2, None);
    let plain = ema(&dir, "plain", &["--exp-window", "off"]);
    assert_ok(&plain);
    let report = String::from_utf8_lossy(&plain.stdout);
    assert!(report.contains("3 hits found, 3 used"), "{report}");
    assert!(report.contains("upsampled"), "{report}");
    check_modes(&dir.join("plain"), &test, "no window");
    // the exponential window adds 0.3 to 1.4 % damping here: removed again
    let windowed = ema(&dir, "windowed", &["--exp-window", "0.01"]);
    assert_ok(&windowed);
    check_modes(&dir.join("windowed"), &test, "exponential window");
    let frf = std::fs::read_to_string(dir.join("plain/frf.csv")).unwrap();
    assert!(frf.starts_with("freq_hz,target,re,im,abs,coherence\n"));
    let uff = std::fs::read_to_string(dir.join("plain/frf.uff")).unwrap();
    assert_eq!(uff.matches("    -1\n    58\n").count(), POINTS);
    if std::env::var_os("VIBCAM_KEEP").is_none() {
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[test]
fn a_double_hit_and_a_clipped_hit_are_named_and_left_out() {
    let dir = std::env::temp_dir().join(format!("vibcam-ema-bad-{}", std::process::id()));
    let mut h = hits(&[80.0, 70.0, 100.0]);
    // a rebound 4 ms after the second hit; the third clipped at 90 N
    h.push(Hit {
        t_s: 3.204,
        width_s: 0.0006,
        peak_n: 40.0,
    });
    let test = structure(h);
    write_test(&dir, &test, 9.2, Some(90.0));
    let out = ema(&dir, "bad", &[]);
    assert_ok(&out);
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(report.contains("3 hits found, 1 used"), "{report}");
    assert!(report.contains("hit 2 at 3.2000 s: a double hit"), "{report}");
    assert!(report.contains("hit 3 at 6.2000 s: the force is clipped"), "{report}");
    // all hits bad: refused, each named
    let all_bad = structure(vec![
        Hit {
            t_s: 0.2,
            width_s: 0.0006,
            peak_n: 150.0,
        },
        Hit {
            t_s: 0.205,
            width_s: 0.0006,
            peak_n: 60.0,
        },
    ]);
    write_test(&dir, &all_bad, 3.0, None);
    let out = ema(&dir, "worse", &[]);
    assert_exit_2(&out, "no hit can be used: hit 1 at 0.2000 s: a double hit");
    let _ = std::fs::remove_dir_all(&dir);
}
