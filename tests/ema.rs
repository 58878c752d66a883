//! Experimental modal analysis from the command line: a three-mode structure hit by a simulated
//! hammer (closed-form response, `host_harness::model::hammer`), the force recorded by a DAQ at
//! 50 kHz with noise, five points' displacements by a camera at 2 kHz from the same trigger;
//! `ema` must find the modes (frequency within 0.1 %, damping within 5 %, shapes MAC >= 0.99)
//! with and without the exponential window, and name a double hit and a clipped hit.

use crate::util::assert_says;
use crate::util::{assert_exit_2, assert_ok, harness, mac, words};
use host_harness::model::hammer::HammerTest;
use host_harness::recording::hammer::HammerRecording;
use std::path::Path;

const POINTS: usize = 5;

/// `simulate-hammer` into `dir` with `extra` flags; the test it wrote.
fn write_test(dir: &Path, extra: &[&str]) -> HammerTest {
    let d = dir.to_str().unwrap();
    let mut args = words("simulate-hammer --out {} --force", &[d]);
    args.extend_from_slice(extra);
    assert_ok(&harness(&args));
    // the same structure as the command's (its own truth.csv is checked below)
    let peaks: Vec<f64> = extra
        .iter()
        .position(|a| *a == "--peaks-n")
        .map(|i| {
            extra[i + 1]
                .split(',')
                .map(|v| v.parse().unwrap())
                .collect()
        })
        .unwrap_or(vec![150.0, 120.0, 180.0]);
    HammerRecording {
        seconds: 9.2,
        daq_hz: 50_000.0,
        camera_hz: 2_000.0,
        peaks_n: peaks,
        double_hit: false,
        clip_n: None,
        force_noise_n: 0.3,
        camera_noise_mm: 0.0005,
        hit_points: Vec::new(),
        seed: 1,
    }
    .test()
}

/// `(f_hz, damping)` per mode of modes.csv, and the shapes (per mode, per point, re + i im).
/// A complex number as `(re, im)`.
type C = (f64, f64);

fn results(dir: &Path) -> (Vec<(f64, f64)>, Vec<Vec<C>>) {
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

/// `ema` of the impact test in `dir` (camera.csv, force.csv) into `dir/out`, replacing it.
fn ema(dir: &Path, out: &str, extra: &[&str]) -> std::process::Output {
    let (r, f, o) = (dir.join("camera.csv"), dir.join("force.csv"), dir.join(out));
    let mut args = vec!["--force"];
    args.extend_from_slice(extra);
    ema_of((&r, &f, "force_n"), &o, &args)
}

/// `ema --impact --f-max-hz 200 --no-plots` of the `response` to the force channel `col` of
/// `force`, into `out`, with `extra`.
fn ema_of(
    (response, force, col): (&Path, &Path, &str),
    out: &Path,
    extra: &[&str],
) -> std::process::Output {
    let mut args = words("ema --response {} --excitation {} --excitation-col {} --impact --f-max-hz 200 --out {} --no-plots", &[response.to_str().unwrap(), force.to_str().unwrap(), col, out.to_str().unwrap()]);
    args.extend_from_slice(extra);
    harness(&args)
}

#[test]
fn a_hammer_test_at_two_rates_gives_the_modes_with_and_without_the_exponential_window() {
    let dir = std::env::temp_dir().join(format!("vibcam-ema-{}", std::process::id()));
    let test = write_test(&dir, &[]);
    let truth = std::fs::read_to_string(dir.join("truth.csv")).unwrap();
    assert!(
        truth.starts_with("mode,f_hz,damping,point,shape\n1,23,0.015,1,"),
        "{truth}"
    );
    let plain = ema(&dir, "plain", &["--exp-window", "off"]);
    assert_says(&plain, &["3 hits found, 3 used", "upsampled"]);
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
    write_test(
        &dir,
        &["--peaks-n", "80,70,100", "--double-hit", "--clip-n", "90"],
    );
    let out = ema(&dir, "bad", &[]);
    assert_says(
        &out,
        &[
            "3 hits found, 1 used",
            "hit 2 at 3.2000 s: a double hit",
            "hit 3 at 6.2000 s: the force is clipped",
        ],
    );
    // all hits bad: refused, each named
    let short = dir.join("short");
    write_test(
        &short,
        &["--seconds", "3", "--peaks-n", "150", "--clip-n", "100"],
    );
    let out = ema(&short, "worse", &[]);
    assert_exit_2(
        &out,
        "no hit can be used: hit 1 at 0.2000 s: the force is clipped",
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `force.csv` (`t_s,force_n`) of `dir` rewritten as a LabVIEW measurement file with decimal
/// commas (the channel `Excitation (Trigger)`, newtons, `Delta_X` the CSV's step).
fn force_as_lvm(dir: &Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(dir.join("force.csv")).unwrap();
    let values: Vec<&str> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap())
        .collect();
    let comma = |v: &str| v.replace('.', ",");
    let mut s = String::from(
        "LabVIEW Measurement\t\nWriter_Version\t2\nReader_Version\t2\nSeparator\tTab\n\
         Decimal_Separator\t,\nMulti_Headings\tYes\nX_Columns\tNo\nTime_Pref\tAbsolute\n\
         ***End_of_Header***\t\n\t\nChannels\t1\t\n",
    );
    s.push_str(&format!("Samples\t{}\t\n", values.len()));
    s.push_str(
        "Y_Unit_Label\tNewtons\t\nX_Dimension\tTime\t\nX0\t0,0000000000000000E+0\t\n\
         Delta_X\t2,000000E-5\t\n***End_of_Header***\t\t\nX_Value\tExcitation (Trigger)\tComment\n",
    );
    for v in values {
        s.push('\t');
        s.push_str(&comma(v));
        s.push('\n');
    }
    let path = dir.join("force.lvm");
    std::fs::write(&path, s).unwrap();
    path
}

#[test]
fn a_labview_force_and_a_camera_started_late_are_aligned_by_the_delay() {
    let dir = std::env::temp_dir().join(format!("vibcam-ema-lvm-{}", std::process::id()));
    let test = write_test(&dir, &[]);
    let lvm = force_as_lvm(&dir);
    // the camera started 0.1 s after the DAQ: its first 200 frames (2 kHz) were never taken
    let cam = std::fs::read_to_string(dir.join("camera.csv")).unwrap();
    let mut lines = cam.lines();
    let mut late = format!("{}\n", lines.next().unwrap());
    for l in lines.skip(200) {
        late.push_str(l);
        late.push('\n');
    }
    let late_path = dir.join("late.csv");
    std::fs::write(&late_path, late).unwrap();
    let out = dir.join("lvm");
    let o = ema_of(
        (&late_path, &lvm, "Excitation (Trigger)"),
        &out,
        &["--delay-s", "0.1"],
    );
    let report = assert_says(
        &o,
        &[
            "(Newtons, 50000 Hz)",
            "a delay of 0.1 s: the first 5000 samples of the force dropped",
        ],
    );
    check_modes(&out, &test, "LabVIEW force, late camera");
    // the band's lower end and the window are said (notes), but nothing is doubted
    for warning in ["doubtful", "move before", "not decayed", "start to move"] {
        assert!(!report.contains(warning), "{report}");
    }
    // without the delay the camera's record is 0.1 s ahead of the force: the responses move
    // before the pulses and the model cannot describe the FRFs; both said, not a silent number
    let wrong = dir.join("wrong");
    let o = ema_of((&late_path, &lvm, "Excitation (Trigger)"), &wrong, &[]);
    assert_says(
        &o,
        &[
            "the responses move before the force's pulses",
            "the numbers above are doubtful",
        ],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A random-force test in `dir`: a periodic random force at 1 kHz (2^17 samples), its
/// spectrum kept within `band` Hz when given (a shaker's), and the exact periodic response of
/// the three modes through their receptance, displacement noise 0.1 % of its RMS
/// (`force.csv`, `camera.csv`).
fn write_random_test(dir: &Path, band: Option<(f64, f64)>) -> HammerTest {
    use vibcam_fft::Complex;
    std::fs::create_dir_all(dir).unwrap();
    let test = HammerRecording {
        seconds: 1.0,
        daq_hz: 1000.0,
        camera_hz: 1000.0,
        peaks_n: vec![1.0],
        double_hit: false,
        clip_n: None,
        force_noise_n: 0.0,
        camera_noise_mm: 0.0,
        hit_points: Vec::new(),
        seed: 1,
    }
    .test();
    let (fs, n) = (1000.0, 1usize << 17);
    let mut force = host_harness::testing::uniform_noise(11, n);
    let mut planner = vibcam_fft::Planner::new();
    let mut spec: Vec<Complex<f64>> = force.iter().map(|v| Complex::new(*v, 0.0)).collect();
    planner.forward(n).process(&mut spec);
    let freq = |k: usize| (if k <= n / 2 { k } else { n - k }) as f64 * fs / n as f64;
    if let Some((lo, hi)) = band {
        for (k, c) in spec.iter_mut().enumerate() {
            if freq(k) < lo || freq(k) > hi {
                *c = Complex::new(0.0, 0.0);
            }
        }
        let mut back = spec.clone();
        planner.inverse(n).process(&mut back);
        force = back.iter().map(|c| c.re / n as f64).collect();
    }
    write_driven(dir, fs, &[("force_n", force, spec, test.drive)], 20);
    test
}

#[test]
fn a_random_force_gives_the_modes_through_welch_segments() {
    let dir = std::env::temp_dir().join(format!("vibcam-ema-random-{}", std::process::id()));
    let test = write_random_test(&dir, None);
    let out = dir.join("out");
    let o = harness(&words("ema --response {} --excitation {} --excitation-col force_n --f-max-hz 200 --out {} --no-plots", &[dir.join("camera.csv").to_str().unwrap(), dir.join("force.csv").to_str().unwrap(), out.to_str().unwrap()]));
    assert_says(
        &o,
        &["continuous excitation: Welch H1, Hann segments of 16384"],
    );
    // measured: 23.0082 Hz (+0.036 %), damping 0.01512 (+0.8 %) and closer for the others
    check_modes(&out, &test, "random force");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_shakers_band_is_found_from_the_coherence() {
    // the force within 10-150 Hz only: without a band given, the one fitted is where the
    // responses follow the force, not up to 0.8 x Nyquist
    let dir = tempfile::tempdir().unwrap();
    let test = write_random_test(dir.path(), Some((10.0, 150.0)));
    let out = dir.path().join("out");
    let o = harness(&words(
        "ema --response {} --excitation {} --excitation-col force_n --out {} --no-plots",
        &[
            dir.path().join("camera.csv").to_str().unwrap(),
            dir.path().join("force.csv").to_str().unwrap(),
            out.to_str().unwrap(),
        ],
    ));
    assert_says(&o, &["coherence with the force"]);
    let report = String::from_utf8_lossy(&o.stdout).to_string();
    let line = report
        .lines()
        .find(|l| l.starts_with("fit: "))
        .expect("the fit's line");
    let band: Vec<f64> = line[5..]
        .split(" Hz")
        .next()
        .unwrap()
        .split('-')
        .map(|v| v.parse().unwrap())
        .collect();
    assert!(
        (band[0] - 10.0).abs() < 1.0 && (band[1] - 150.0).abs() < 1.0,
        "{line}"
    );
    check_modes(&out, &test, "a shaker's band");
}

#[test]
fn a_displacement_csv_of_track_is_a_response_file() {
    // the camera's record as `track` writes it: one row per frame and target, a lost frame
    let dir = std::env::temp_dir().join(format!("vibcam-ema-track-{}", std::process::id()));
    let test = write_test(&dir, &[]);
    let cam = std::fs::read_to_string(dir.join("camera.csv")).unwrap();
    let mut s = String::from("frame,t_s,target,cx,cy,disp_mm,lost\n");
    for (k, l) in cam.lines().skip(1).enumerate() {
        let c: Vec<&str> = l.split(',').collect();
        for (o, v) in c[1..].iter().enumerate() {
            if k == 5000 && o == 2 {
                s.push_str(&format!("{k},{},{},,,,1\n", c[0], o + 1));
            } else {
                s.push_str(&format!("{k},{},{},{},100,{v},0\n", c[0], o + 1, 50 * o));
            }
        }
    }
    let path = dir.join("displacement.csv");
    std::fs::write(&path, s).unwrap();
    let out = dir.join("out");
    let o = ema_of((&path, &dir.join("force.csv"), "force_n"), &out, &[]);
    assert_says(
        &o,
        &[
            "(5 channels, mm, 2000 Hz, a camera's)",
            "target 3: 1 lost samples filled",
        ],
    );
    check_modes(&out, &test, "displacement.csv");
    let modes = std::fs::read_to_string(out.join("modes.csv")).unwrap();
    assert!(
        modes.lines().nth(1).unwrap().starts_with("vision,,1,"),
        "{modes}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bands_give_one_mode_each_and_an_empty_band_is_named() {
    let dir = std::env::temp_dir().join(format!("vibcam-ema-bands-{}", std::process::id()));
    let test = write_test(&dir, &[]);
    let out = ema(&dir, "bands", &["--bands", "15-30,50-70,100-130,150-160"]);
    assert_says(
        &out,
        &["band 150-160 Hz: no mode (no cluster of stable poles there)"],
    );
    check_modes(&dir.join("bands"), &test, "bands");
    let modes = std::fs::read_to_string(dir.join("bands/modes.csv")).unwrap();
    let bands: Vec<(String, String)> = modes
        .lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            (c[3].to_string(), c[4].to_string())
        })
        .collect();
    assert_eq!(
        bands,
        [("15", "30"), ("50", "70"), ("100", "130")]
            .iter()
            .map(|(a, b)| (a.to_string(), b.to_string()))
            .collect::<Vec<_>>()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// LADISK's free beam (tests/data/real/ladisk-ema-beam, MIT): a real impact test others made.
fn ladisk(file: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/real/ladisk-ema-beam")
        .join(file)
}

/// The modes of `modes.csv` in `dir`: frequency and damping.
fn modes_of(dir: &Path) -> Vec<(f64, f64)> {
    std::fs::read_to_string(dir.join("modes.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            (c[5].parse().unwrap(), c[7].parse().unwrap())
        })
        .collect()
}

/// Each of `want` (Hz) has a mode of `got` within `tol` of it.
fn has_modes(got: &[(f64, f64)], want: &[f64], tol: f64, what: &str) {
    for w in want {
        assert!(
            got.iter().any(|(f, _)| (f - w).abs() <= tol * w),
            "{what}: no mode within {} % of {w} Hz: {got:?}",
            100.0 * tol
        );
    }
}

#[test]
fn a_real_camera_impact_test_gives_both_modes_by_default() {
    // the camera's pyidi displacements over the DAQ's force, nothing but the rate given: the
    // axis, the band, the window and the delay between the records come from the data
    let out = tempfile::tempdir().unwrap();
    let o = ladisk_camera_ema(&out.path().join("e"), &[]);
    assert_says(
        &o,
        &["y coordinate", "start to move", "chosen from the data"],
    );
    let modes = modes_of(&out.path().join("e"));
    // sdypy-EMA on the same displacements (tests/data/real/ladisk-ema-beam/README.md)
    has_modes(&modes, &[695.91, 1898.64], 0.005, "camera vs sdypy-EMA");
    // and the accelerometer's modes of the same beam
    has_modes(&modes, &[695.76, 1898.09], 0.005, "camera vs accelerometer");
    assert!(modes.len() <= 3, "{modes:?}");
    // the page's picker: per mode the highest-order pole of its cluster, fed back as a user
    // clicks and saves them, gives those two modes; the damping it shows is the structure's
    // (the exponential window's removed), near the mode's, not the windowed FRF's
    let (poles, in_modes) = crate::util::page_poles(&out.path().join("e"));
    let mut picked = Vec::new();
    for (f, d) in modes.iter().filter(|m| m.0 < 2500.0) {
        let best = in_modes
            .iter()
            .map(|&i| poles[i])
            .filter(|p| (p.0 - f).abs() < 0.01 * f)
            .max_by_key(|p| p.2)
            .unwrap_or_else(|| panic!("no pole of the mode at {f} Hz on the page"));
        assert!((best.1 - d).abs() < 0.5 * d, "{best:?} vs the mode's {d}");
        picked.push(best);
    }
    let file = out.path().join("poles.csv");
    let rows: Vec<String> = picked.iter().map(|p| format!("{},{}", p.0, p.1)).collect();
    std::fs::write(&file, format!("f_hz,damping\n{}\n", rows.join("\n"))).unwrap();
    let o = ladisk_camera_ema(&out.path().join("p"), &["--poles", file.to_str().unwrap()]);
    assert_ok(&o);
    let again = modes_of(&out.path().join("p"));
    assert_eq!(again.len(), picked.len(), "{again:?}");
    for (got, want) in again.iter().zip(&picked) {
        assert!(
            (got.0 - want.0).abs() < 1e-9 * want.0,
            "{got:?} vs {want:?}"
        );
        assert!(
            (got.1 - want.1).abs() < 1e-9 * want.1,
            "{got:?} vs {want:?}"
        );
    }
}

/// `ema` of the real beam's camera displacements over the DAQ's force, nothing but the
/// camera's rate given, into `out`, with `extra`.
fn ladisk_camera_ema(out: &Path, extra: &[&str]) -> std::process::Output {
    let (r, f) = (ladisk("displacements_lk.npy"), ladisk("camera.lvm"));
    let mut args = vec![
        "ema",
        "--response",
        r.to_str().unwrap(),
        "--response-fs",
        "15000",
        "--excitation",
        f.to_str().unwrap(),
        "--excitation-col",
        "Force (Trigger)",
        "--impact",
        "--no-plots",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    harness(&args)
}

#[test]
fn a_real_accelerometer_impact_test_gives_its_four_modes_by_default() {
    let out = tempfile::tempdir().unwrap();
    let f = ladisk("acceleration.lvm");
    let o = harness(&[
        "ema",
        "--response",
        f.to_str().unwrap(),
        "--response-col",
        "Acceleration (Trigger)",
        "--excitation",
        f.to_str().unwrap(),
        "--excitation-col",
        "Force (Trigger)",
        "--impact",
        "--response-quantity",
        "acceleration",
        "--no-plots",
        "--out",
        out.path().join("e").to_str().unwrap(),
    ]);
    assert_ok(&o);
    let modes = modes_of(&out.path().join("e"));
    // sdypy-EMA's four modes below 4 kHz (README.md there), within 0.1 %
    has_modes(
        &modes,
        &[695.76, 1898.09, 2777.91, 3671.09],
        0.001,
        "accelerometer",
    );
}

#[test]
fn a_page_without_a_mode_says_so_and_why() {
    let dir = tempfile::tempdir().unwrap();
    write_test(dir.path(), &[]);
    // no mode lies in 40-50 Hz: the page's banner says so, with the band's note
    assert_ok(&ema(dir.path(), "none", &["--bands", "40-50"]));
    let page = std::fs::read_to_string(dir.path().join("none/report.html")).unwrap();
    assert!(page.contains("<div id=\"banner\"><strong>No mode was found."));
    assert!(page.contains("<li>band 40-50 Hz: no mode"), "{page}");
    // and a page with modes has none
    assert_ok(&ema(dir.path(), "all", &[]));
    let page = std::fs::read_to_string(dir.path().join("all/report.html")).unwrap();
    assert!(!page.contains("id=\"banner\""));
}

#[test]
fn poles_given_are_exactly_the_modes_and_an_earlier_modes_csv_is_a_poles_file() {
    let dir = tempfile::tempdir().unwrap();
    let test = write_test(dir.path(), &[]);
    let o = ema(dir.path(), "all", &[]);
    assert_ok(&o);
    let all = modes_of(&dir.path().join("all"));
    assert_eq!(all.len(), 3, "{all:?}");
    // modes 1 and 3 kept, as a user deletes a row of modes.csv (or picks two poles)
    let text = std::fs::read_to_string(dir.path().join("all/modes.csv")).unwrap();
    let kept: Vec<&str> = text
        .lines()
        .enumerate()
        .filter(|(i, _)| *i != 2)
        .map(|(_, l)| l)
        .collect();
    let poles = dir.path().join("poles.csv");
    std::fs::write(&poles, kept.join("\n")).unwrap();
    let p = poles.to_str().unwrap();
    let o = ema(dir.path(), "picked", &["--poles", p]);
    assert_ok(&o);
    let picked = modes_of(&dir.path().join("picked"));
    assert_eq!(picked.len(), 2, "{picked:?}");
    for (got, want) in picked.iter().zip([all[0], all[2]]) {
        assert!(
            (got.0 - want.0).abs() < 1e-9 * want.0,
            "{got:?} vs {want:?}"
        );
        assert!((got.1 - want.1).abs() < 1e-9, "{got:?} vs {want:?}");
    }
    // the whole modes.csv fed back: the same modes, their shapes by LSFD as the closed form's
    // (a subset's shapes are not: a mode left out of LSFD leaves its peak to the others)
    let whole = dir.path().join("all/modes.csv");
    let o = ema(dir.path(), "again", &["--poles", whole.to_str().unwrap()]);
    assert_ok(&o);
    let (again, shapes) = results(&dir.path().join("again"));
    assert_eq!(again.len(), 3);
    for (s, m) in shapes.iter().zip(&test.modes) {
        let c = mac(s, &m.shape);
        assert!(c >= 0.99, "MAC {c}");
    }
    // a pole outside the band, a file without the columns, and poles with bands are refused
    let far = dir.path().join("far.csv");
    std::fs::write(&far, "f_hz,damping\n900,0.01\n").unwrap();
    assert_exit_2(
        &ema(dir.path(), "far", &["--poles", far.to_str().unwrap()]),
        "the pole at 900 Hz lies outside the band",
    );
    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, "freq,zeta\n23,0.01\n").unwrap();
    assert_exit_2(
        &ema(dir.path(), "bad", &["--poles", bad.to_str().unwrap()]),
        "no column `f_hz`",
    );
    assert_exit_2(
        &ema(dir.path(), "both", &["--poles", p, "--bands", "20-30"]),
        "--bands and --poles",
    );
}

/// `ema --roving P=camera_P.csv,force_P.csv` for each point of `points` in `dir`, into `out`,
/// with `extra`.
fn ema_roving(dir: &Path, points: &[usize], out: &Path, extra: &[&str]) -> std::process::Output {
    let records: Vec<String> = points
        .iter()
        .map(|p| {
            let (c, f) = (
                dir.join(format!("camera_{p}.csv")),
                dir.join(format!("force_{p}.csv")),
            );
            format!("{p}={},{}", c.display(), f.display())
        })
        .collect();
    let mut args = vec!["ema"];
    for r in &records {
        args.extend(["--roving", r.as_str()]);
    }
    args.extend(words(
        "--excitation-col force_n --f-max-hz 200 --no-plots --force --out {}",
        &[out.to_str().unwrap()],
    ));
    args.extend_from_slice(extra);
    harness(&args)
}

#[test]
fn a_roving_hammer_gives_the_modes_and_the_shapes_over_the_hit_points() {
    let dir = std::env::temp_dir().join(format!("vibcam-roving-{}", std::process::id()));
    // a DAQ at 10 kHz still samples the 0.6 ms pulses 6 times
    let o = harness(&words(
        "simulate-hammer --hit-points 1,2,3,4,5 --daq-hz 10000 --out {} --force",
        &[dir.join("h").to_str().unwrap()],
    ));
    assert_says(&o, &["force_P.csv and camera_P.csv for P = 1, 2, 3, 4, 5"]);
    let h = dir.join("h");
    let all = [1, 2, 3, 4, 5];
    // one fixed transducer (point 4) and the hammer at every point: the shapes over the hit
    // points, by reciprocity the structure's at all five
    let out = dir.join("one");
    let o = ema_roving(&h, &all, &out, &["--impact", "--response-col", "p4"]);
    assert_ok(&o);
    check_modes(
        &out,
        &HammerTest::three_modes(Vec::new()),
        "roving, one response",
    );
    let frf = std::fs::read_to_string(out.join("frf.csv")).unwrap();
    let mut lines = frf.lines();
    assert_eq!(
        lines.next(),
        Some("freq_hz,target,hit_point,re,im,abs,coherence")
    );
    let first: Vec<(String, String)> = lines
        .take(5)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            (c[1].to_string(), c[2].to_string())
        })
        .collect();
    let want: Vec<(String, String)> = all.iter().map(|p| ("1".into(), p.to_string())).collect();
    assert_eq!(first, want, "one FRF per hit point at each line");
    let report = std::fs::read_to_string(out.join("report.txt")).unwrap();
    for needle in [
        "roving hammer: 5 records, one per hit point",
        "hit points (the `hit_point` of frf.csv, the `target` of shapes.csv)",
        "jackknife over the groups of every record's hits",
        "s for all (the shortest their hits allow)",
    ] {
        assert!(report.contains(needle), "`{needle}` not in {report}");
    }
    // the modes have intervals holding the truth
    let modes = std::fs::read_to_string(out.join("modes.csv")).unwrap();
    for (l, m) in modes
        .lines()
        .skip(1)
        .zip(&HammerTest::three_modes(Vec::new()).modes)
    {
        let c: Vec<&str> = l.split(',').collect();
        let (f, lo, hi): (f64, f64, f64) = (
            c[5].parse().unwrap(),
            c[11].parse().unwrap(),
            c[12].parse().unwrap(),
        );
        assert!(lo < f && f < hi && (hi - lo) < 0.01 * m.f_hz, "{l}");
    }
    // what a roving test cannot be
    let o = ema_roving(&h, &[1, 2, 2], &dir.join("twice"), &["--impact"]);
    assert_exit_2(&o, "--roving: hit point 2 is given twice");
    let o = ema_roving(&h, &[1, 2], &dir.join("cont"), &[]);
    assert_exit_2(&o, "--roving: a roving-hammer test is an impact test");
    assert!(!dir.join("twice").exists() && !dir.join("cont").exists());
    // a record whose force another DAQ took at another rate
    let o = harness(&words(
        "simulate-hammer --hit-points 3 --daq-hz 20000 --out {} --force",
        &[dir.join("other").to_str().unwrap()],
    ));
    assert_ok(&o);
    std::fs::copy(dir.join("other/force_3.csv"), h.join("force_3.csv")).unwrap();
    let o = ema_roving(&h, &[1, 2, 3], &dir.join("rates"), &["--impact"]);
    assert_exit_2(
        &o,
        "its records are analysed at 20000 Hz, the first record's at 10000 Hz",
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A force driving the structure: its column's name, samples, spectrum (a full complex
/// transform) and the point it drives (0-based).
type Driven<'a> = (&'a str, Vec<f64>, Vec<vibcam_fft::Complex<f64>>, usize);

/// Writes `force.csv` (`t_s` and a column per force) and `camera.csv` (`t_s,p1..p5`): the five
/// points' exact periodic displacements (mm) under `forces` through the receptances of the
/// three-mode structure, each with uniform noise of 0.1 % of its RMS (seeds from `seed`).
fn write_driven(dir: &Path, fs: f64, forces: &[Driven], seed: u64) {
    use vibcam_fft::Complex;
    let n = forces[0].1.len();
    let mut planner = vibcam_fft::Planner::new();
    let freq = |k: usize| (if k <= n / 2 { k } else { n - k }) as f64 * fs / n as f64;
    let mut responses = Vec::new();
    for o in 0..POINTS {
        let mut x: Vec<Complex<f64>> = (0..n)
            .map(|k| {
                forces
                    .iter()
                    .map(|(_, _, sp, d)| {
                        let test = HammerTest {
                            drive: *d,
                            ..HammerTest::three_modes(Vec::new())
                        };
                        let h = test.receptance(o, freq(k));
                        let h = if k > n / 2 { h.conj() } else { h };
                        sp[k] * Complex::new(h.re, h.im) * 1e3 / n as f64
                    })
                    .sum()
            })
            .collect();
        planner.inverse(n).process(&mut x);
        let re: Vec<f64> = x.iter().map(|c| c.re).collect();
        let rms = (re.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
        let e = host_harness::testing::uniform_noise(seed + o as u64, n);
        responses.push(
            re.iter()
                .zip(&e)
                .map(|(v, e)| v + 1e-3 * rms * 3.46 * e)
                .collect::<Vec<f64>>(),
        );
    }
    let names: Vec<&str> = forces.iter().map(|f| f.0).collect();
    let mut f = format!("t_s,{}\n", names.join(","));
    let mut r = String::from("t_s,p1,p2,p3,p4,p5\n");
    for k in 0..n {
        let t = k as f64 / fs;
        f.push_str(&format!("{t}"));
        for force in forces {
            f.push_str(&format!(",{}", force.1[k]));
        }
        f.push('\n');
        r.push_str(&format!("{t}"));
        for x in &responses {
            r.push_str(&format!(",{}", x[k]));
        }
        r.push('\n');
    }
    std::fs::write(dir.join("force.csv"), f).unwrap();
    std::fs::write(dir.join("camera.csv"), r).unwrap();
}

/// Two shakers' white forces at points 2 and 4 (`force.csv`: `t_s,shaker_a,shaker_b`) and the
/// five points' exact periodic displacements through the receptances (`camera.csv`), 2^16
/// samples at 1 kHz, 0.1 % noise.
fn write_shakers_test(dir: &Path) {
    use vibcam_fft::Complex;
    std::fs::create_dir_all(dir).unwrap();
    let (fs, n) = (1000.0, 1usize << 16);
    let mut planner = vibcam_fft::Planner::new();
    let forces: Vec<Vec<f64>> = (0..2)
        .map(|i| host_harness::testing::uniform_noise(31 + i, n))
        .collect();
    let spectra: Vec<Vec<Complex<f64>>> = forces
        .iter()
        .map(|f| {
            let mut s: Vec<Complex<f64>> = f.iter().map(|v| Complex::new(*v, 0.0)).collect();
            planner.forward(n).process(&mut s);
            s
        })
        .collect();
    let driven: Vec<Driven> = ["shaker_a", "shaker_b"]
        .into_iter()
        .zip(forces)
        .zip(spectra)
        .zip([1, 3])
        .map(|(((name, f), sp), d)| (name, f, sp, d))
        .collect();
    write_driven(dir, fs, &driven, 40);
}

#[test]
fn two_shakers_at_once_give_the_frf_matrix_and_the_modes() {
    let dir = std::env::temp_dir().join(format!("vibcam-shakers-{}", std::process::id()));
    write_shakers_test(&dir);
    let (r, f, out) = (
        dir.join("camera.csv"),
        dir.join("force.csv"),
        dir.join("out"),
    );
    let o = harness(&words(
        "ema --response {} --excitation {} --excitation-col shaker_a --excitation-col shaker_b --f-min-hz 5 --f-max-hz 200 --no-plots --out {}",
        &[r.to_str().unwrap(), f.to_str().unwrap(), out.to_str().unwrap()],
    ));
    assert_says(
        &o,
        &[
            "force 2: ",
            "2 forces at once: the FRF matrix by the multiple-input H1",
            "2 forces: the median conditioning of their cross-spectral matrix",
            "each one's mean multiple coherence with the forces in the band",
        ],
    );
    check_modes(&out, &HammerTest::three_modes(Vec::new()), "two shakers");
    let frf = std::fs::read_to_string(out.join("frf.csv")).unwrap();
    assert!(frf.starts_with("freq_hz,target,force,re,im,abs,coherence\n"));
    assert_eq!(frf.lines().nth(10).unwrap().split(',').nth(2), Some("2"));
    assert_eq!(frf.lines().filter(|l| l.starts_with("0,")).count(), 10);
    // one force named twice, and several forces with hits, are refused
    let o = ema_of(
        (&r, &f, "shaker_a"),
        &dir.join("x"),
        &["--excitation-col", "shaker_a"],
    );
    assert_exit_2(&o, "--excitation-col shaker_a is given twice");
    let o = ema_of(
        (&r, &f, "shaker_a"),
        &dir.join("x"),
        &["--excitation-col", "shaker_b"],
    );
    assert_exit_2(
        &o,
        "several forces at once are a continuous test (shakers), not --impact",
    );
    std::fs::remove_dir_all(&dir).ok();
}
