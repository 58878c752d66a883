//! Output-only modal analysis from the command line: `simulate-field` writes a synthetic
//! ambient record of a five-storey shear frame with its true modes, `modal` identifies them
//! (FDD, EFDD, SSI-cov) and writes modes.csv, shapes.csv, svd.csv, shapes.uff and the figures;
//! bad records are named.

use crate::util::assert_says;
use crate::util::{assert_exit_2, assert_ok, harness, render_cantilever, words};
use std::path::Path;

/// `simulate-field --minutes M --seed S` into `dir`: its `displacement.csv`.
fn field_record(dir: &Path, minutes: u32, seed: u32) -> std::path::PathBuf {
    assert_ok(&harness(&words(
        "simulate-field --minutes {} --seed {} --out {}",
        &[
            &minutes.to_string(),
            &seed.to_string(),
            dir.to_str().unwrap(),
        ],
    )));
    dir.join("displacement.csv")
}

/// `(method, mode, f_hz, damping)` from modes.csv.
fn modes(dir: &Path) -> Vec<(String, usize, f64, f64)> {
    crate::util::modes_csv_rows(dir)
        .into_iter()
        .map(|c| {
            let l = c.join(",");
            assert_eq!(c[0], "vision");
            assert_eq!(c[1], "", "a mode belongs to all targets");
            // an interval, where given, is around its estimate, its u positive
            for (est, at) in [(5, 10), (7, 13), (6, 16)] {
                if let (Ok(x), Ok(u), Ok(lo), Ok(hi)) = (
                    c[est].parse::<f64>(),
                    c[at].parse::<f64>(),
                    c[at + 1].parse::<f64>(),
                    c[at + 2].parse::<f64>(),
                ) {
                    assert!(u > 0.0 && lo <= x && x <= hi, "{l}");
                }
            }
            (
                c[9].to_string(),
                c[2].parse().unwrap(),
                c[5].parse().unwrap(),
                c[7].parse().unwrap_or(f64::NAN),
            )
        })
        .collect()
}

/// `(mode, f_hz, damping, shape)` from truth.csv.
fn truth(dir: &Path) -> Vec<(f64, f64, Vec<f64>)> {
    let text = std::fs::read_to_string(dir.join("truth.csv")).unwrap();
    let mut out: Vec<(f64, f64, Vec<f64>)> = Vec::new();
    for l in text.lines().skip(1) {
        let c: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
        let m = c[0] as usize;
        if out.len() < m {
            out.push((c[1], c[2], Vec::new()));
        }
        out[m - 1].2.push(c[4]);
    }
    out
}

#[test]
fn the_shear_frame_is_identified_without_an_accelerometer() {
    let tmp = tempfile::tempdir().unwrap();
    let (field, out) = (tmp.path().join("field"), tmp.path().join("modal"));
    assert_ok(&harness(&words(
        "simulate-field --minutes 60 --seed 3 --out {}",
        &[field.to_str().unwrap()],
    )));
    let o = harness(&words(
        "modal --displacement {} --nperseg 2048 --out {}",
        &[
            field.join("displacement.csv").to_str().unwrap(),
            out.to_str().unwrap(),
        ],
    ));
    assert_ok(&o);
    for f in [
        "modes.csv",
        "shapes.csv",
        "svd.csv",
        "shapes.uff",
        "svd.png",
        "svd.svg",
        "stabilisation.png",
        "stabilisation.svg",
        "report.txt",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    let truth = truth(&field);
    let found = modes(&out);
    let df = 60.0 / 2048.0;
    for method in ["fdd", "efdd", "ssi"] {
        let of: Vec<_> = found.iter().filter(|m| m.0 == method).collect();
        assert_eq!(of.len(), 5, "{method}: {of:?}");
        for (m, (f, z, _)) in of.iter().zip(&truth) {
            // SSI within a line; EFDD two; FDD's peak line within half the half-power band
            let tol = match method {
                "ssi" => df,
                "efdd" => 2.0 * df,
                _ => z * f,
            };
            assert!((m.2 - f).abs() <= tol, "{method} {}: {} vs {f}", m.1, m.2);
            if method == "ssi" {
                assert!(
                    (m.3 / z - 1.0).abs() <= 0.25,
                    "{method} {}: {} vs {z}",
                    m.1,
                    m.3
                );
            }
        }
    }
    // the shapes: one row per mode, method and target, MAC >= 0.99 against the truth
    let text = std::fs::read_to_string(out.join("shapes.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "mode,target,x_px,y_px,re,im,abs,method,abs_u"
    );
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(rows.len(), 3 * 5 * 5);
    for method in ["fdd", "efdd", "ssi"] {
        for (m, (_, _, shape)) in truth.iter().enumerate() {
            let got: Vec<f64> = rows
                .iter()
                .filter(|r| r[7] == method && r[0] == (m + 1).to_string())
                .map(|r| r[4].parse().unwrap())
                .collect();
            let ab: f64 = got.iter().zip(shape).map(|(a, b)| a * b).sum();
            let mac = ab * ab
                / (got.iter().map(|a| a * a).sum::<f64>()
                    * shape.iter().map(|b| b * b).sum::<f64>());
            assert!(mac >= 0.99, "{method} mode {}: MAC {mac}", m + 1);
        }
    }
    let svd = std::fs::read_to_string(out.join("svd.csv")).unwrap();
    assert!(svd.starts_with("freq_hz,s1,s2,s3,s4,s5\n"));
    assert_eq!(svd.lines().count(), 1 + 1025);
    // the UFF: one dataset 55 per mode and method
    let uff = std::fs::read_to_string(out.join("shapes.uff")).unwrap();
    assert_eq!(uff.matches("\n    55").count(), 15);
    // SSI-dat and pLSCF on the same record: the same five modes, within a line (pLSCF two)
    // and 25 % in damping
    let dat = tmp.path().join("dat");
    assert_ok(&harness(&words(
        "modal --displacement {} --nperseg 2048 --ssi dat --plscf --efdd-quantity displacement \
         --no-plots --out {}",
        &[
            field.join("displacement.csv").to_str().unwrap(),
            dat.to_str().unwrap(),
        ],
    )));
    let found: Vec<_> = modes(&dat).into_iter().filter(|m| m.0 == "ssi").collect();
    assert_eq!(found.len(), 5, "{found:?}");
    for (m, (f, z, _)) in found.iter().zip(&truth) {
        assert!((m.2 - f).abs() <= df, "ssi-dat {}: {} vs {f}", m.1, m.2);
        assert!(
            (m.3 / z - 1.0).abs() <= 0.25,
            "ssi-dat {}: {} vs {z}",
            m.1,
            m.3
        );
    }
    let found: Vec<_> = modes(&dat).into_iter().filter(|m| m.0 == "plscf").collect();
    assert_eq!(found.len(), 5, "{found:?}");
    for (m, (f, z, _)) in found.iter().zip(&truth) {
        assert!((m.2 - f).abs() <= 2.0 * df, "plscf {}: {} vs {f}", m.1, m.2);
        assert!(
            (m.3 / z - 1.0).abs() <= 0.25,
            "plscf {}: {} vs {z}",
            m.1,
            m.3
        );
    }
    let report = std::fs::read_to_string(dat.join("report.txt")).unwrap();
    assert!(report.contains("SSI-dat: 30 block rows"), "{report}");
    assert!(
        report.contains("pLSCF: poly-reference LSCF (4 x 4 matrix coefficients, orders 1 to 20"),
        "{report}"
    );
}

#[test]
fn bad_records_are_named_and_bad_targets_left_out() {
    let tmp = tempfile::tempdir().unwrap();
    let write = |name: &str, rows: &dyn Fn(usize) -> String, n: usize, header: &str| {
        let p = tmp.path().join(name);
        let mut s = String::from(header);
        for i in 0..n {
            s.push_str(&rows(i));
        }
        std::fs::write(&p, s).unwrap();
        p
    };
    let run = |p: &Path, out: &str| {
        harness(&words(
            "modal --displacement {} --out {}",
            &[p.to_str().unwrap(), tmp.path().join(out).to_str().unwrap()],
        ))
    };
    let wave = |i: usize, f: f64| (2.0 * std::f64::consts::PI * f * i as f64 / 50.0).sin();
    // fewer samples than one segment
    let p = write(
        "short.csv",
        &|i| format!("{},{}\n", i as f64 / 50.0, wave(i, 3.0)),
        10,
        "t_s,a\n",
    );
    assert_exit_2(&run(&p, "o1"), "10 samples, fewer than one segment");
    let p = write(
        "short2.csv",
        &|i| format!("{},{}\n", i as f64 / 50.0, wave(i, 3.0)),
        1000,
        "t_s,a\n",
    );
    let o = harness(&words(
        "modal --displacement {} --nperseg 2048 --out {}",
        &[
            p.to_str().unwrap(),
            tmp.path().join("o1b").to_str().unwrap(),
        ],
    ));
    assert_exit_2(&o, "--nperseg 2048: the record has only 1000 samples");
    // NaN in a cell
    let p = write(
        "nan.csv",
        &|i| {
            let v = if i == 7 {
                "NaN".to_string()
            } else {
                wave(i, 3.0).to_string()
            };
            format!("{},{v},{}\n", i as f64 / 50.0, wave(i, 5.0))
        },
        3000,
        "t_s,a,b\n",
    );
    assert_exit_2(&run(&p, "o2"), "row 9: column a");
    // a dead (constant) target and one lost for long stretches: left out and named
    let p = write(
        "bad.csv",
        &|i| {
            let lost = if (500..1500).contains(&i) {
                String::new()
            } else {
                wave(i, 4.0).to_string()
            };
            format!(
                "{},{},{},1.5,{lost}\n",
                i as f64 / 50.0,
                wave(i, 3.0) + 0.3 * wave(i, 7.0),
                wave(i, 3.0) - 0.2 * wave(i, 7.0),
            )
        },
        6000,
        "t_s,a,b,c,d\n",
    );
    let o = run(&p, "o3");
    assert_says(
        &o,
        &[
            "target 3 left out: constant",
            "target 4 left out: 1000 of 6000 samples lost",
            "output-only modal analysis: 2 targets",
        ],
    );
    // an irregular time column
    let p = write(
        "irregular.csv",
        &|i| {
            format!(
                "{},{}\n",
                i as f64 / 50.0 + if i == 100 { 0.005 } else { 0.0 },
                wave(i, 3.0)
            )
        },
        3000,
        "t_s,a\n",
    );
    assert_exit_2(&run(&p, "o4"), "sample 100");
}

#[test]
fn the_cantilever_recording_without_its_accelerometer_gives_the_modes_of_h1() {
    // the frames alone (`analyze` without --accel) against the same frames with the
    // accelerometer (H1): the same two modes, within two lines of the H1 bins
    let tmp = tempfile::tempdir().unwrap();
    let rec = tmp.path().join("rec");
    let r = rec.to_str().unwrap();
    render_cantilever(Path::new(r), &["--targets", "5", "--read-noise", "2"]);
    let frames = format!("{r}/frames");
    let (h1, oma) = (rec.join("h1"), rec.join("oma"));
    let accel = format!("{r}/accel.csv");
    let base = [
        "analyze",
        "--frames",
        &frames,
        "--fps",
        "120",
        "--targets",
        "5",
        "--threshold",
        "127",
        "--mm-per-px",
        "0.1",
    ];
    let mut with: Vec<&str> = base.to_vec();
    with.extend([
        "--accel",
        &accel,
        "--fs",
        "2048",
        "--time-col",
        "t_s",
        "--out",
        h1.to_str().unwrap(),
    ]);
    assert_ok(&harness(&with));
    let mut without: Vec<&str> = base.to_vec();
    without.extend(["--out", oma.to_str().unwrap()]);
    let o = harness(&without);
    assert_ok(&o);
    assert!(oma.join("displacement.csv").exists());
    let h1_modes: Vec<f64> = std::fs::read_to_string(h1.join("modes.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .filter(|l| l.starts_with("accelerometer"))
        .map(|l| l.split(',').nth(5).unwrap().parse().unwrap())
        .collect();
    assert_eq!(h1_modes.len(), 2);
    let found = modes(&oma);
    let df = 120.0 / 256.0;
    for method in ["fdd", "efdd", "ssi"] {
        for f in &h1_modes {
            assert!(
                found
                    .iter()
                    .any(|m| m.0 == method && (m.2 - f).abs() <= 2.0 * df),
                "{method}: no mode near {f} Hz in {found:?}"
            );
        }
    }
    // flags that need the accelerometer are refused without it
    let mut bad = without.clone();
    bad.push("--compensate-exposure");
    bad.extend(["--exposure-ms", "2"]);
    assert_exit_2(&harness(&bad), "--compensate-exposure needs --accel");
}

#[test]
fn a_rendered_field_recording_gives_the_modes_through_the_whole_chain() {
    // ambient motion of the shear frame filmed (5 disks, 60 fps, 5 ms exposure, read noise 1),
    // tracked and analysed output-only: with a linear tracker the modes of the exact motion
    let tmp = tempfile::tempdir().unwrap();
    let rec = tmp.path().join("rec");
    let r = rec.to_str().unwrap();
    let o = harness(&words("simulate-field --render --minutes 3 --out {}", &[r]));
    assert_ok(&o);
    for f in ["displacement.csv", "truth.csv", "points.csv", "README.txt"] {
        assert!(rec.join(f).exists(), "{f}");
    }
    assert_eq!(
        std::fs::read_dir(rec.join("frames")).unwrap().count(),
        10_800
    );
    let readme = std::fs::read_to_string(rec.join("README.txt")).unwrap();
    // the command the README gives is the linear tracker's, which the analysis below shows
    // finds exactly the five modes
    assert!(
        readme.contains("analyze --frames") && readme.contains("--tracker weighted"),
        "{readme}"
    );
    let exact = rec.join("exact");
    assert_ok(&harness(&words(
        "modal --displacement {} --out {}",
        &[&format!("{r}/displacement.csv"), exact.to_str().unwrap()],
    )));
    let frames = format!("{r}/frames");
    let analyze = |tracker: &str| {
        let out = rec.join(tracker);
        let o = harness(&words(
            "analyze --frames {} --fps 60 --targets 5 --threshold 127 --tracker {} --out {}",
            &[&frames, tracker, out.to_str().unwrap()],
        ));
        assert_ok(&o);
        (out, String::from_utf8_lossy(&o.stdout).to_string())
    };
    let (weighted, report) = analyze("weighted");
    assert!(!report.contains("harmonic"), "{report}");
    let truth = truth(&rec);
    let df = 60.0 / 2048.0;
    let (found, reference) = (modes(&weighted), modes(&exact));
    let ssi: Vec<_> = found.iter().filter(|m| m.0 == "ssi").collect();
    assert_eq!(ssi.len(), 5, "{ssi:?}");
    for (m, (f, _, _)) in ssi.iter().zip(&truth) {
        assert!((m.2 - f).abs() <= df, "ssi {}: {} vs {f}", m.1, m.2);
    }
    // the chain adds little to the exact motion's analysis: the same modes per method
    assert_eq!(found.len(), reference.len());
    for (a, b) in found.iter().zip(&reference) {
        assert_eq!((&a.0, a.1), (&b.0, b.1));
        assert!((a.2 - b.2).abs() <= 0.25 * df, "{a:?} vs {b:?}");
    }
    // shapes: MAC >= 0.99 against the truth, >= 0.999 against the exact motion's
    let shape_of = |dir: &Path, method: &str, mode: usize| -> Vec<f64> {
        std::fs::read_to_string(dir.join("shapes.csv"))
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(str::to_string).collect::<Vec<_>>())
            .filter(|c| c[7] == method && c[0] == mode.to_string())
            .map(|c| c[4].parse().unwrap())
            .collect()
    };
    let mac = |a: &[f64], b: &[f64]| {
        let ab: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
        ab * ab / (a.iter().map(|x| x * x).sum::<f64>() * b.iter().map(|y| y * y).sum::<f64>())
    };
    for method in ["fdd", "efdd", "ssi"] {
        for (m, (_, _, shape)) in truth.iter().enumerate() {
            let got = shape_of(&weighted, method, m + 1);
            let to_truth = mac(&got, shape);
            assert!(to_truth >= 0.99, "{method} mode {}: MAC {to_truth}", m + 1);
            let to_exact = mac(&got, &shape_of(&exact, method, m + 1));
            assert!(to_exact >= 0.999, "{method} mode {}: MAC {to_exact}", m + 1);
        }
    }
    // the binary centroid's pixel locking makes a harmonic of mode 1 that SSI takes for a
    // mode: it is named in the report
    let (_, report) = analyze("blob");
    assert!(report.contains("5 x mode 1"), "{report}");
    // the displacement record's noise is not the camera's
    let o = harness(&words("simulate-field --render --noise 0.1 --out {}", &[r]));
    assert_exit_2(&o, "--read-noise");
}

/// The host's FDD (`modal`: f64, realfft, nalgebra's SVD) and the camera's (firmware-core's
/// `CrossSpectra` with the C ABI's `vc_fdd4_t` settings: 4 targets, Hann segments of 512, half
/// overlap, 30 power iterations, the same peak rule) on one record: the same first singular
/// value up to f32 rounding, the same peaks, the same shapes. The two compute the spectra
/// separately; this is what says they agree.
#[test]
fn the_hosts_fdd_and_the_cameras_agree_on_one_record() {
    use firmware_core::spectrum::cross::{pick_peaks, CrossSpectra};
    use host_harness::analysis::modal::mac;
    use host_harness::analysis::oma::{analyze, Method, OmaSettings};
    use host_harness::model::field::{shear_frame, simulate};
    use num_complex::Complex64;
    // the C ABI's capacities (firmware-core-ffi: VC_FDD4_TARGETS, _SEGMENT, _LINES)
    const K: usize = 4;
    const SEG: usize = 512;
    const LINES: usize = SEG / 2 + 1;
    let fs = 60.0;
    let n = 5 * 60 * 60; // five minutes
    let model = shear_frame(K, 1.5, &[0.01, 0.012, 0.015, 0.02]);
    let rec = simulate(&model, fs, n, 0.02, 7);
    let host = analyze(&rec, &OmaSettings::new(fs, n, Some(SEG))).unwrap();

    let mut cam = CrossSpectra::<K, SEG, LINES, { K * (K + 1) / 2 }, 0>::try_new(fs as f32)
        .expect("the C ABI's capacities");
    // frame i: every target's sample i
    (0..n).for_each(|i| cam.push(&core::array::from_fn(|t| rec[t][i] as f32)));
    assert_eq!(cam.segments(), host.csd.segments as u32);
    let lines: Vec<(f32, [num_complex::Complex32; K])> =
        (0..LINES).map(|l| cam.first_singular(l, 30)).collect();
    // the first singular value, line by line, above the record's floor: f32 and 30 power
    // iterations against f64 and an SVD. Where one singular value dominates (s2/s1 < 0.8,
    // every peak) they agree to f32's rounding (measured: 4e-6 at worst); where the first two
    // are close the power iteration converges as (s2/s1)^60 and stays below the true value (a
    // Rayleigh quotient), 0.4 % at s2/s1 = 0.92 between two modes of this record
    let s1_host: Vec<f64> = host.svd.s.iter().map(|s| s[0]).collect();
    let mut sorted = s1_host.clone();
    sorted.sort_by(f64::total_cmp);
    let floor = sorted[LINES / 2];
    let (mut worst, mut compared) = (0.0f64, 0);
    for (l, (s, _)) in lines.iter().enumerate().skip(2) {
        let e = f64::from(*s) / s1_host[l] - 1.0;
        assert!(
            e < 1e-5,
            "line {l}: the camera's s1 above the host's by {e:.2e}"
        );
        if s1_host[l] > floor && host.svd.s[l][1] / s1_host[l] < 0.8 {
            worst = worst.max(e.abs());
            compared += 1;
        }
    }
    assert!(compared > 20, "only {compared} lines compared");
    assert!(worst < 1e-5, "first singular values differ by {worst:.2e}");
    // the peaks: the host's FDD modes at the camera's picked lines, the shapes alike
    let s1: Vec<f32> = lines.iter().map(|(s, _)| *s).collect();
    let df = fs / SEG as f64;
    // the host's lowest frequency searched: 0.5 Hz or two lines
    let lo = (0.5f64.max(2.0 * df) / df).ceil();
    let (mut sorted32, mut out) = ([0.0f32; LINES], [0usize; LINES]);
    let found = pick_peaks(
        &s1,
        (lo as usize, LINES - 1),
        (6.0, 10.0),
        &mut sorted32,
        &mut out,
    );
    let cam_f: Vec<f64> = out[..found].iter().map(|&l| l as f64 * df).collect();
    let fdd: Vec<_> = host
        .modes
        .iter()
        .filter(|m| m.method == Method::Fdd)
        .collect();
    assert_eq!(fdd.len(), K, "the host's FDD finds the four modes: {fdd:?}");
    let host_f: Vec<f64> = fdd.iter().map(|m| m.f_hz).collect();
    assert_eq!(cam_f, host_f, "peaks: camera {cam_f:?}, host {host_f:?}");
    for m in &fdd {
        let l = (m.f_hz / df).round() as usize;
        let v: Vec<Complex64> = lines[l]
            .1
            .iter()
            .map(|c| Complex64::new(f64::from(c.re), f64::from(c.im)))
            .collect();
        let mac = mac(&v, &m.shape);
        assert!(mac > 0.99999, "mode at {} Hz: MAC {mac}", m.f_hz);
    }
}

/// Two setups of the shear frame (two records of other seeds): setup 1 sees storeys 1-3,
/// setup 2 storeys 4, 1 and 5 (storey 1, its second column, the reference): merged by PoSER,
/// the five storeys' shapes are the true ones and the setups' parts are in `setups.csv`; a
/// setup without references, a reference that is not in its file and a setup with another
/// count of references are refused naming the flag.
#[test]
fn two_setups_sharing_a_reference_give_the_global_shapes() {
    let tmp = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    for (seed, keep) in [(21, [1, 2, 3]), (22, [4, 1, 5])] {
        let rec = tmp.path().join(format!("r{seed}"));
        assert_ok(&harness(&words(
            "simulate-field --minutes 5 --seed {} --out {}",
            &[&seed.to_string(), rec.to_str().unwrap()],
        )));
        let text = std::fs::read_to_string(rec.join("displacement.csv")).unwrap();
        let mut out = String::from("t_s,1,2,3\n");
        for l in text.lines().skip(1) {
            let c: Vec<&str> = l.split(',').collect();
            out.push_str(&format!(
                "{},{},{},{}\n",
                c[0], c[keep[0]], c[keep[1]], c[keep[2]]
            ));
        }
        let f = tmp.path().join(format!("s{seed}.csv"));
        std::fs::write(&f, out).unwrap();
        files.push(f);
    }
    let (s1, s2) = (files[0].to_str().unwrap(), files[1].to_str().unwrap());
    let out = tmp.path().join("m");
    let setup2 = format!("{s2}:2");
    assert_ok(&harness(&words(
        "modal --displacement {} --references 1 --setup {} --no-plots --out {}",
        &[s1, &setup2, out.to_str().unwrap()],
    )));
    let report = std::fs::read_to_string(out.join("report.txt")).unwrap();
    assert!(report.contains("2 setups merged by PoSER"), "{report}");
    assert!(
        report.contains("4 = setup 2 target 1; 5 = setup 2 target 3"),
        "{report}"
    );
    let truth = truth(&tmp.path().join("r21"));
    let modes_are_the_truth = |out: &Path, method: &str, mac_min: f64| {
        let found: Vec<_> = modes(out).into_iter().filter(|m| m.0 == method).collect();
        assert_eq!(found.len(), 5, "{found:?}");
        let shapes = std::fs::read_to_string(out.join("shapes.csv")).unwrap();
        for (m, (f, _, shape)) in found.iter().zip(&truth) {
            assert!((m.2 - f).abs() < 0.005 * f, "mode {}: {} vs {f}", m.1, m.2);
            let got: Vec<f64> = shapes
                .lines()
                .map(|l| l.split(',').collect::<Vec<_>>())
                .filter(|c| c[7] == method && c[0] == m.1.to_string())
                .map(|c| c[4].parse().unwrap())
                .collect();
            assert_eq!(got.len(), 5);
            let ab: f64 = got.iter().zip(shape).map(|(a, b)| a * b).sum();
            let mac = ab * ab
                / (got.iter().map(|a| a * a).sum::<f64>()
                    * shape.iter().map(|b| b * b).sum::<f64>());
            assert!(mac >= mac_min, "{method} mode {}: MAC {mac}", m.1);
        }
    };
    modes_are_the_truth(&out, "ssi", 0.99);
    let parts = std::fs::read_to_string(out.join("setups.csv")).unwrap();
    assert!(parts.starts_with("method,mode,setup,f_hz,damping,scale_re,scale_im,reference_mac\n"));
    assert_eq!(parts.lines().filter(|l| l.starts_with("ssi,")).count(), 10);
    // the same setups with SSI's modes by PreGER: one model of both records (60 block rows, so
    // that the one reference's rows are 1.5 times the highest order, 40), and FDD's and EFDD's
    // (and pLSCF's) by the spectral PreGER (one global cross-spectral matrix): no parts per
    // setup
    let pre = tmp.path().join("p");
    assert_ok(&harness(&words(
        "modal --displacement {} --references 1 --setup {} --merge preger --plscf --no-plots \
         --out {}",
        &[s1, &setup2, pre.to_str().unwrap()],
    )));
    let report = std::fs::read_to_string(pre.join("report.txt")).unwrap();
    assert!(
        report.contains("2 setups: SSI's modes by PreGER"),
        "{report}"
    );
    assert!(report.contains("PreGER: 60 block rows"), "{report}");
    assert!(
        report.contains("FDD's, EFDD's and pLSCF's by the spectral PreGER"),
        "{report}"
    );
    modes_are_the_truth(&pre, "ssi", 0.99);
    // with one reference the spectral PreGER's shape at a line is each point's transmissibility
    // to it there, which the tail of a stronger neighbouring mode enters (pyOMA-2's
    // `SD_PreGER` as well): on these 5-minute records the weakest mode's global shape has
    // MAC 0.976 (PoSER's FDD 0.987, which loses EFDD's second mode); 0.99 and more on every
    // mode of 10-minute setups with two references (docs/validation.md §10)
    modes_are_the_truth(&pre, "efdd", 0.97);
    // pLSCF on the global matrix's reference column
    modes_are_the_truth(&pre, "plscf", 0.99);
    assert!(
        report.contains("on the half-spectra of references 1 "),
        "{report}"
    );
    let parts = std::fs::read_to_string(pre.join("setups.csv")).unwrap();
    for method in ["ssi,", "fdd,", "efdd,", "plscf,"] {
        assert!(!parts.lines().any(|l| l.starts_with(method)), "{parts}");
    }
    // refusals
    let o = harness(&words(
        "modal --displacement {} --setup {} --out {}",
        &[s1, &setup2, tmp.path().join("x1").to_str().unwrap()],
    ));
    assert_exit_2(&o, "--setup needs --references");
    let o = harness(&words(
        "modal --displacement {} --references 7 --setup {} --out {}",
        &[s1, &setup2, tmp.path().join("x2").to_str().unwrap()],
    ));
    assert_exit_2(&o, "--references: target 7 of");
    let two = format!("{s2}:2,1");
    let o = harness(&words(
        "modal --displacement {} --references 1 --setup {} --out {}",
        &[s1, &two, tmp.path().join("x3").to_str().unwrap()],
    ));
    assert_exit_2(&o, "2 reference targets, --references has 1");
}

#[test]
fn poles_picked_on_the_page_are_exactly_the_ssi_modes() {
    let tmp = tempfile::tempdir().unwrap();
    let disp = field_record(&tmp.path().join("field"), 20, 5);
    let run = |name: &str, extra: &[&str]| {
        let out = tmp.path().join(name);
        let mut args = words(
            "modal --displacement {} --nperseg 1024 --no-plots --out {}",
            &[disp.to_str().unwrap(), out.to_str().unwrap()],
        );
        args.extend_from_slice(extra);
        harness(&args)
    };
    assert_ok(&run("all", &[]));
    let ssi: Vec<_> = modes(&tmp.path().join("all"))
        .into_iter()
        .filter(|m| m.0 == "ssi")
        .collect();
    assert!(ssi.len() >= 3, "{ssi:?}");
    // per SSI mode but the second, the highest-order pole of its cluster, as a user clicks it
    let (poles, in_modes) = crate::util::page_poles(&tmp.path().join("all"));
    let picked: Vec<(f64, f64, u64)> = ssi
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != 1)
        .map(|(_, m)| {
            in_modes
                .iter()
                .map(|&i| poles[i])
                .filter(|p| (p.0 - m.2).abs() < 0.01 * m.2)
                .max_by_key(|p| p.2)
                .unwrap_or_else(|| panic!("no pole of the mode at {} Hz on the page", m.2))
        })
        .collect();
    let file = tmp.path().join("poles.csv");
    let rows: Vec<String> = picked.iter().map(|p| format!("{},{}", p.0, p.1)).collect();
    std::fs::write(&file, format!("f_hz,damping\n{}\n", rows.join("\n"))).unwrap();
    let o = run("picked", &["--poles", file.to_str().unwrap()]);
    assert_says(&o, &["given (--poles): the shape of the stable pole at"]);
    let got: Vec<_> = modes(&tmp.path().join("picked"))
        .into_iter()
        .filter(|m| m.0 == "ssi")
        .collect();
    assert_eq!(got.len(), picked.len(), "{got:?}");
    for (g, p) in got.iter().zip(&picked) {
        assert_eq!((g.2, g.3), (p.0, p.1));
    }
    // a pole beyond the Nyquist frequency, one where the diagram has no stable pole, and poles
    // with bands are refused
    let far = tmp.path().join("far.csv");
    std::fs::write(&far, "f_hz,damping\n500,0.01\n").unwrap();
    assert_exit_2(
        &run("far", &["--poles", far.to_str().unwrap()]),
        "lies outside the frequencies analysed",
    );
    let lone = tmp.path().join("lone.csv");
    let gap = 0.5 * (ssi[0].2 + ssi[1].2);
    std::fs::write(&lone, format!("f_hz,damping\n{gap},0.01\n")).unwrap();
    assert_exit_2(
        &run("lone", &["--poles", lone.to_str().unwrap()]),
        "no stable SSI-cov pole lies within 1 %",
    );
    assert_exit_2(
        &run(
            "both",
            &["--poles", file.to_str().unwrap(), "--bands", "1-2"],
        ),
        "--poles with --setup or --bands",
    );
}

/// SHA-256 of `path` by coreutils' `sha256sum`, an implementation independent of ours.
fn sha256sum(path: &Path) -> String {
    let o = std::process::Command::new("sha256sum")
        .arg(path)
        .output()
        .expect("sha256sum runs");
    String::from_utf8(o.stdout).unwrap()[..64].to_string()
}

#[test]
fn a_report_opens_with_who_what_and_when() {
    let tmp = tempfile::tempdir().unwrap();
    // a folder with a space and a quote: the command line quotes it as a shell reads it back
    let disp = field_record(&tmp.path().join("lab's field"), 5, 4);
    let run = |out: &Path| {
        std::process::Command::new(env!("CARGO_BIN_EXE_host-harness"))
            .args(["modal", "--displacement", disp.to_str().unwrap()])
            .args(["--nperseg", "512", "--out", out.to_str().unwrap()])
            .env("SOURCE_DATE_EPOCH", "1000000000")
            .output()
            .unwrap()
    };
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    assert_ok(&run(&a));
    assert_ok(&run(&b));
    let report = std::fs::read_to_string(a.join("report.txt")).unwrap();
    let head: Vec<&str> = report.lines().take_while(|l| !l.is_empty()).collect();
    assert_eq!(head[0], "date: 2001-09-09T01:46:40Z", "{report}");
    assert!(
        head[1].starts_with("version: vibcam 0.1.0 (commit "),
        "{report}"
    );
    let quoted = disp.to_str().unwrap().replace('\'', "'\\''");
    let typed = format!(
        "command: host-harness modal --displacement '{quoted}' --nperseg 512 --out {}",
        a.display()
    );
    assert!(head.contains(&typed.as_str()), "{typed}\n{report}");
    let bytes = std::fs::metadata(&disp).unwrap().len();
    let input = format!(
        "input: {}, {bytes} bytes, sha256 {}",
        disp.display(),
        sha256sum(&disp)
    );
    assert!(head.contains(&input.as_str()), "{input}\n{report}");
    // the settings: the one given, and the defaults marked
    assert!(head.contains(&"  --nperseg = 512"), "{report}");
    assert!(
        head.contains(&"  --prominence-db = 6 (default)"),
        "{report}"
    );
    assert!(head.contains(&"  --fps = (none) (default)"), "{report}");
    // then the analysis, as before
    assert!(report.contains("\n\ninput: "), "{report}");
    // the page holds the same block; the same run at the same stated date writes the same
    let page = std::fs::read_to_string(a.join("report.html")).unwrap();
    assert!(page.contains("<section id=\"provenance\">"));
    assert!(page.contains(&format!("data-sha256=\"{}\"", sha256sum(&disp))));
    let other = std::fs::read_to_string(b.join("report.txt")).unwrap();
    assert_eq!(
        other,
        report.replace(a.to_str().unwrap(), b.to_str().unwrap())
    );
}

#[test]
fn pdf_is_printed_by_chromium_or_its_absence_is_said() {
    let tmp = tempfile::tempdir().unwrap();
    let disp = field_record(&tmp.path().join("field"), 5, 4);
    let run = |out: &Path, browser: Option<&str>| {
        let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_host-harness"));
        c.args(["modal", "--displacement", disp.to_str().unwrap(), "--pdf"])
            .args(["--out", out.to_str().unwrap(), "--force"]);
        if let Some(b) = browser {
            c.env("VIBCAM_CHROMIUM", b);
        }
        c.output().unwrap()
    };
    // a browser that cannot run: said, and every other output written
    let none = tmp.path().join("none");
    let o = run(&none, Some("/no/such/chromium"));
    assert_ok(&o);
    let warned = crate::util::stderr(&o);
    crate::util::assert_contains(&warned, &["warning: no report.pdf", "/no/such/chromium"]);
    assert!(none.join("report.html").is_file() && !none.join("report.pdf").exists());
    // with a Chromium on this machine: the page as a PDF, listed as an output (so that --force
    // replaces it), no scratch file left
    let found = ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .any(|b| {
            std::process::Command::new(b)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        });
    if found {
        let out = tmp.path().join("pdf");
        for _ in 0..2 {
            assert_ok(&run(&out, None));
        }
        let pdf = std::fs::read(out.join("report.pdf")).unwrap();
        // the page printed, not an error page: a page per section (the print stylesheet)
        let pages = pdf.windows(11).filter(|w| w == b"/Type /Page").count()
            - pdf.windows(12).filter(|w| w == b"/Type /Pages").count();
        assert!(pdf.starts_with(b"%PDF") && pages >= 3, "{pages} pages");
        assert!(!out.join(".report.pdf.partial").exists());
    }
}

#[test]
fn shapes_are_drawn_on_the_geometry_given_and_a_wrong_one_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let disp = field_record(&tmp.path().join("field"), 5, 4);
    let disp = disp.to_str().unwrap();
    // the five storeys one above the other, 3 m apart, joined floor to floor
    let geometry = tmp.path().join("frame.csv");
    let nodes: String = (1..=5).map(|i| format!("{i},0,{}\n", 3000 * i)).collect();
    let lines: String = (1..5).map(|i| format!("{i},{}\n", i + 1)).collect();
    std::fs::write(
        &geometry,
        format!("# shear frame\nnode,x_mm,y_mm\n{nodes}from,to\n{lines}"),
    )
    .unwrap();
    let g = geometry.to_str().unwrap();
    let out = tmp.path().join("m");
    assert_ok(&harness(&words(
        "modal --displacement {} --nperseg 512 --geometry {} --out {}",
        &[disp, g, out.to_str().unwrap()],
    )));
    let page = std::fs::read_to_string(out.join("report.html")).unwrap();
    let shapes = page.matches("<svg class=\"mode-shape\"").count();
    assert!(shapes >= 3, "{shapes} shapes");
    // every shape is the geometry's four lines, drawn where its nodes are (y up: storey 5 on top)
    assert_eq!(page.matches("<line class=\"wire\"").count(), 4 * shapes);
    assert!(
        page.contains("data-a=\"3\" data-b=\"4\" x1=\"0\" y1=\"-12000\" x2=\"0\" y2=\"-15000\"")
    );
    assert!(page.contains(&format!(
        "Lines of the geometry {g} (4 lines; its nodes in millimetres"
    )));
    let report = std::fs::read_to_string(out.join("report.txt")).unwrap();
    assert!(report.contains(&format!("input: {g}, ")), "{report}");
    // without it: the targets in number order, said so
    let plain = tmp.path().join("p");
    assert_ok(&harness(&words(
        "modal --displacement {} --nperseg 512 --out {}",
        &[disp, plain.to_str().unwrap()],
    )));
    let page = std::fs::read_to_string(plain.join("report.html")).unwrap();
    assert!(page.contains("Lines join the points in number order"));
    assert_eq!(page.matches("<line class=\"wire\"").count(), 4 * shapes);
    // a sixth target left out of the analysis (constant): its node is no error, its lines go
    let text = std::fs::read_to_string(disp).unwrap();
    let six: String = text
        .lines()
        .enumerate()
        .map(|(i, l)| format!("{l},{}\n", if i == 0 { "6" } else { "0" }))
        .collect();
    let six_csv = tmp.path().join("six.csv");
    std::fs::write(&six_csv, six).unwrap();
    std::fs::write(
        &geometry,
        format!("node,x_mm,y_mm\n{nodes}6,0,18000\nfrom,to\n{lines}5,6\n"),
    )
    .unwrap();
    let left = tmp.path().join("left");
    assert_ok(&harness(&words(
        "modal --displacement {} --nperseg 512 --geometry {} --out {}",
        &[six_csv.to_str().unwrap(), g, left.to_str().unwrap()],
    )));
    let page = std::fs::read_to_string(left.join("report.html")).unwrap();
    let n = page.matches("<svg class=\"mode-shape\"").count();
    assert_eq!(page.matches("<line class=\"wire\"").count(), 4 * n);
    // a node that is no target, and a row that is no node: refused before any work, named
    let refuse = |text: &str, needle: &str| {
        std::fs::write(&geometry, text).unwrap();
        let o = harness(&words(
            "modal --displacement {} --geometry {} --out {}",
            &[disp, g, tmp.path().join("x").to_str().unwrap()],
        ));
        assert_exit_2(&o, needle);
        assert!(!tmp.path().join("x").exists());
    };
    refuse(
        &format!("node,x_mm,y_mm\n{nodes}6,0,0\n"),
        "node 6 is not a target of the input (its targets are 1, 2, 3, 4, 5)",
    );
    refuse(
        "from,to\n1,2\n2,x\n",
        &format!("{g}: row 3: `x` is not a node number"),
    );
    refuse(
        &format!("node,x_mm,y_mm\n{}", &nodes[..nodes.len() - 10]),
        "target 5 has no node",
    );
}
