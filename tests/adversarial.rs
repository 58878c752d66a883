//! Adversarial end-to-end cases of the recording commands: each was once a lost file or a
//! silently wrong number (exit 0); each now gives a clear error or a correct answer, and no
//! file the user did not ask to replace is touched.

use crate::analyze::{disk, make_recording, position_px, Recording, FPS, H, W};
use crate::util::{assert_exit_2, assert_ok, harness, render_cantilever, stderr, words};
use std::path::Path;

/// `analyze` of a hand-made recording (1 s, two modes at 8 and 30 Hz) into `out`, with `extra`.
fn analyze_into(rec: &Recording, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = words("--threshold 100 --out {}", &[out.to_str().unwrap()]);
    args.extend_from_slice(extra);
    crate::analyze::analyze_hand(rec, &rec.frames, &args)
}

/// Every entry below `dir`, relative, sorted.
fn tree(dir: &Path) -> Vec<String> {
    fn walk(d: &Path, pre: &str, v: &mut Vec<String>) {
        for e in std::fs::read_dir(d).unwrap().flatten() {
            let n = format!("{pre}{}", e.file_name().to_string_lossy());
            if e.path().is_dir() {
                walk(&e.path(), &format!("{n}/"), v);
            }
            v.push(n);
        }
    }
    let mut v = Vec::new();
    walk(dir, "", &mut v);
    v.sort();
    v
}

#[test]
fn force_never_deletes_a_folder_holding_the_inputs_or_files_of_someone_else() {
    let (_tmp, rec) = make_recording(120, 2048);
    // the recording's own folder, with a report.txt of the user's beside the frames
    std::fs::write(rec.dir.join("report.txt"), "my notes").unwrap();
    let before = tree(&rec.dir);
    let o = analyze_into(&rec, &rec.dir, &["--force"]);
    assert_exit_2(&o, "not replaced even with --force");
    assert!(
        stderr(&o).contains("an input of this run"),
        "{}",
        stderr(&o)
    );
    assert_eq!(tree(&rec.dir), before);
    // a folder with a report.txt, a thesis and raw data, holding no input: still refused
    let lab = rec.dir.join("lab");
    std::fs::create_dir_all(lab.join("data")).unwrap();
    for f in ["report.txt", "thesis.docx", "data/raw.bin"] {
        std::fs::write(lab.join(f), f).unwrap();
    }
    let before = tree(&lab);
    let o = analyze_into(&rec, &lab, &["--force"]);
    assert_exit_2(&o, "not replaced even with --force");
    assert_eq!(tree(&lab), before);
    // an analysis the user added a file to is someone's too
    let out = rec.dir.join("out");
    assert_ok(&analyze_into(&rec, &out, &[]));
    std::fs::write(out.join("my-plot.py"), "").unwrap();
    assert_exit_2(&analyze_into(&rec, &out, &["--force"]), "my-plot.py");
    assert!(out.join("my-plot.py").exists() && out.join("modes.csv").exists());
    // the same analysis, untouched, is replaced
    std::fs::remove_file(out.join("my-plot.py")).unwrap();
    assert_ok(&analyze_into(&rec, &out, &["--force"]));
}

#[test]
fn a_failed_analysis_never_replaces_a_good_one() {
    let (_tmp, rec) = make_recording(120, 2048);
    let out = rec.dir.join("out");
    assert_ok(&analyze_into(&rec, &out, &[]));
    let good = tree(&out);
    let modes = std::fs::read(out.join("modes.csv")).unwrap();
    // 10 of 120 frames blank: 8.3 % lost, the analysis fails (exit 2)
    let blank = image::GrayImage::new(W, H);
    for k in (0..10).map(|i| 5 + 11 * i) {
        blank
            .save(rec.frames.join(format!("frame_{k}.png")))
            .unwrap();
    }
    let o = analyze_into(&rec, &out, &["--force"]);
    assert_exit_2(&o, "more than the 5 %");
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("left as it was"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert_eq!(tree(&out), good);
    assert_eq!(std::fs::read(out.join("modes.csv")).unwrap(), modes);
    // nothing of the failed run beside it
    assert!(
        !tree(&rec.dir).iter().any(|n| n.starts_with(".out.")),
        "{:?}",
        tree(&rec.dir)
    );
    // the frames restored, the next forced run replaces it again
    for k in (0..10).map(|i| 5 + 11 * i) {
        image::GrayImage::from_raw(W, H, disk(position_px(k as f64 / FPS), W, H))
            .unwrap()
            .save(rec.frames.join(format!("frame_{k}.png")))
            .unwrap();
    }
    assert_ok(&analyze_into(&rec, &out, &["--force"]));
}

#[test]
fn no_command_writes_over_its_own_input() {
    let (_tmp, rec) = make_recording(4, 2048);
    let accel = rec.accel.to_str().unwrap();
    let before = std::fs::read(&rec.accel).unwrap();
    // the same file by another name, too
    let other_name = format!("{}/./accel.csv", rec.dir.display());
    for out in [accel, other_name.as_str()] {
        let o = harness(&words(
            "frf --input {} --fs 2048 --x base_acc --y tip_acc --out {}",
            &[accel, out],
        ));
        assert_exit_2(&o, "is the input");
        let o = harness(&words(
            "upsample --input {} --col tip_acc --from 2048 --to 4096 --out {}",
            &[accel, out],
        ));
        assert_exit_2(&o, "is the input");
    }
    assert_eq!(std::fs::read(&rec.accel).unwrap(), before);
}

#[test]
fn a_stray_image_beside_the_frames_is_ignored_and_named() {
    let (_tmp, rec) = make_recording(120, 2048);
    let clean = rec.dir.join("clean");
    assert_ok(&analyze_into(&rec, &clean, &[]));
    // a white background.png sorts before frame_0.png
    image::GrayImage::from_pixel(W, H, image::Luma([255]))
        .save(rec.frames.join("background.png"))
        .unwrap();
    let out = rec.dir.join("out");
    let o = analyze_into(&rec, &out, &[]);
    assert_ok(&o);
    assert!(stderr(&o).contains("background.png"), "{}", stderr(&o));
    let report = std::fs::read_to_string(out.join("report.txt")).unwrap();
    assert!(
        report.contains("background.png") && report.contains("ignored"),
        "{report}"
    );
    assert!(report.contains("lost frames: 0 of 120"), "{report}");
    assert_eq!(
        std::fs::read(out.join("modes.csv")).unwrap(),
        std::fs::read(clean.join("modes.csv")).unwrap()
    );
    // two numbered sequences of one length: which one is meant is asked, not guessed
    for k in 0..120 {
        std::fs::copy(
            rec.frames.join(format!("frame_{k}.png")),
            rec.frames.join(format!("other_{k}.png")),
        )
        .unwrap();
    }
    assert_exit_2(&analyze_into(&rec, &rec.dir.join("o2"), &[]), "pattern");
}

/// Rewrites the recording's accelerometer CSV with `f(row, base, tip) -> (base, tip)`.
fn rewrite_accel(rec: &Recording, f: impl Fn(usize, &str, &str) -> (String, String)) {
    let text = std::fs::read_to_string(&rec.accel).unwrap();
    let mut out = String::new();
    for (i, line) in text.lines().enumerate() {
        if i == 0 {
            out.push_str(line);
        } else {
            let c: Vec<&str> = line.split(',').collect();
            let (b, t) = f(i, c[1], c[2]);
            out.push_str(&format!("{},{b},{t}", c[0]));
        }
        out.push('\n');
    }
    std::fs::write(&rec.accel, out).unwrap();
}

#[test]
fn dead_constant_or_vanishing_accelerometer_channels_are_refused() {
    type Edit = fn(usize, &str, &str) -> (String, String);
    let cases: [(Edit, &str); 4] = [
        (|_, _, t| ("0".into(), t.into()), "`base_acc`"),
        (|_, _, t| ("0.05".into(), t.into()), "no variation"),
        (|_, b, _| (b.into(), "0".into()), "`tip_acc`"),
        (
            |_, b, t| {
                let tiny = |v: &str| format!("{:e}", v.parse::<f64>().unwrap() * 1e-300);
                (tiny(b), tiny(t))
            },
            "far below the range",
        ),
    ];
    for (edit, needle) in cases {
        let (_tmp, rec) = make_recording(120, 2048);
        rewrite_accel(&rec, edit);
        let o = analyze_into(&rec, &rec.dir.join("out"), &[]);
        assert_exit_2(&o, needle);
        assert!(!rec.dir.join("out").exists());
        let o = harness(&words(
            "frf --input {} --fs 2048 --x base_acc --y tip_acc --out {}",
            &[
                rec.accel.to_str().unwrap(),
                rec.dir.join("frf.csv").to_str().unwrap(),
            ],
        ));
        assert_exit_2(&o, needle);
    }
}

#[test]
fn an_exposure_longer_than_the_frame_period_is_named() {
    let (_tmp, rec) = make_recording(120, 2048);
    // 20 ms at 120 fps (8.33 ms frames): a warning in analyze, never a compensation
    let o = analyze_into(&rec, &rec.dir.join("a"), &["--exposure-ms", "20"]);
    assert_ok(&o);
    assert!(
        stderr(&o).contains("longer than the frame period (8.333 ms"),
        "{}",
        stderr(&o)
    );
    let o = analyze_into(
        &rec,
        &rec.dir.join("b"),
        &["--exposure-ms", "20", "--compensate-exposure"],
    );
    assert_exit_2(&o, "--compensate-exposure refused");
    // a recording is never rendered with one unless asked, nor with a silent default
    let r = rec.dir.join("r");
    let render = |extra: &[&str]| {
        let mut a = words(
            "render --preset cantilever --recording {}",
            &[r.to_str().unwrap()],
        );
        a.extend_from_slice(extra);
        harness(&a)
    };
    assert_exit_2(&render(&[]), "needs --exposure-ms");
    assert_exit_2(
        &render(&["--exposure-ms", "100"]),
        "longer than the frame period",
    );
    assert!(!r.exists());
}

#[test]
fn gate_and_lost_frame_flags_are_checked_and_reported_as_used() {
    let (_tmp, rec) = make_recording(120, 2048);
    let out = rec.dir.join("out");
    for (gate, needle) in [
        ("0", "'0' for '--gate-px"),
        ("NaN", "'NaN' for '--gate-px"),
        ("-1", "'-1' for '--gate-px"),
    ] {
        let o = analyze_into(&rec, &out, &["--targets", "2", "--gate-px", gate]);
        assert_exit_2(&o, needle);
    }
    // --gate-px means nothing without --targets: refused, not ignored
    let o = analyze_into(&rec, &out, &["--gate-px", "5"]);
    assert_exit_2(&o, "--targets");
    // three blank frames held, and the report says so
    let blank = image::GrayImage::new(W, H);
    for k in [10, 50, 90] {
        blank
            .save(rec.frames.join(format!("frame_{k}.png")))
            .unwrap();
    }
    assert_ok(&analyze_into(&rec, &out, &["--lost-frames", "hold"]));
    let report = std::fs::read_to_string(out.join("report.txt")).unwrap();
    assert!(
        report.contains("lost frames: 3 of 120") && report.contains("held at the last valid"),
        "{report}"
    );
}

#[test]
fn a_threshold_for_8_bit_frames_on_16_bit_ones_and_bands_above_nyquist_are_named() {
    let (_tmp, rec) = make_recording(120, 2048);
    let out = rec.dir.join("out");
    assert_exit_2(
        &analyze_into(&rec, &out, &["--bands", "5-15,55-70"]),
        "Nyquist frequency (60 Hz",
    );
    // the same frames as 16-bit PNGs (x257), analysed with the 8-bit threshold
    for k in 0..120 {
        let p = rec.frames.join(format!("frame_{k}.png"));
        let img = image::open(&p).unwrap().to_luma8();
        let wide: image::ImageBuffer<image::Luma<u16>, Vec<u16>> =
            image::ImageBuffer::from_fn(img.width(), img.height(), |x, y| {
                image::Luma([u16::from(img.get_pixel(x, y).0[0]) * 257])
            });
        wide.save(&p).unwrap();
    }
    let o = analyze_into(&rec, &out, &[]);
    assert!(
        stderr(&o).contains("--threshold 100 on 16-bit frames whose values reach 51400"),
        "{}",
        stderr(&o)
    );
    let report = std::fs::read_to_string(out.join("report.txt")).unwrap();
    assert!(report.contains("16-bit, largest value 51400"), "{report}");
}

#[test]
fn calibrate_refuses_observations_and_settings_it_cannot_honour() {
    let tmp = tempfile::tempdir().unwrap();
    let obs = tmp.path().join("observed.csv");
    let out = tmp.path().join("fit");
    let calibrate = |rows: &str, extra: &[&str]| {
        std::fs::write(
            &obs,
            format!("rig,mode,exposure_ms,quantity,value,u,unit\n{rows}"),
        )
        .unwrap();
        let mut a = words(
            "calibrate --preset cantilever --observed {} --free target_radius_px=5:20 --out {}",
            &[obs.to_str().unwrap(), out.to_str().unwrap()],
        );
        a.extend_from_slice(extra);
        harness(&a)
    };
    let chi = "cantilever,1,2,chi_mu,95.5,,percent\n";
    // too few runs for the model's uncertainty of a chi index: refused before any run
    assert_exit_2(
        &calibrate(chi, &["--runs", "5"]),
        "--runs 5: the chi_mu/chi_sigma observations need",
    );
    // a mode the rig does not report, a negative uncertainty, a knob freed twice
    assert_exit_2(
        &calibrate("cantilever,3,2,chi_mu,95.5,,percent\n", &[]),
        "row 2: mode `3` must be 1 to 2",
    );
    assert_exit_2(
        &calibrate("cantilever,1,2,chi_mu,95.5,-1,percent\n", &[]),
        "row 2: u `-1` is negative",
    );
    assert_exit_2(
        &calibrate(chi, &["--free", "target_radius_px=6:9"]),
        "--free target_radius_px: given twice",
    );
    // a chi without its unit is not guessed from its size
    assert_exit_2(
        &calibrate("cantilever,1,2,chi_mu,1.5,\n", &[]),
        "chi_mu needs its unit",
    );
    assert!(!out.exists());
}

/// Encodes `rec/frames/frame_%05d.png` at `rate` with `codec` into `rec/name`.
fn encode(rec: &Path, rate: &str, codec: &[&str], name: &str) {
    let status = std::process::Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-framerate", rate, "-i"])
        .arg(rec.join("frames/frame_%05d.png"))
        .args(codec)
        .arg(rec.join(name))
        .status()
        .expect("ffmpeg (Debian: apt-get install ffmpeg)");
    assert!(status.success());
}

#[test]
fn videos_as_cameras_write_them_are_read_or_their_rate_is_named() {
    let tmp = tempfile::tempdir().unwrap();
    let rec = tmp.path().join("rec");
    render_cantilever(&rec, &[]);
    let analyze_with = |frames: &str, fps: &str, out: &str, extra: &[&str]| {
        // one band below the Nyquist frequency of the slowest rate here (15 Hz at 30 fps)
        let bands = if fps.starts_with('3') {
            "5-14"
        } else {
            "5-15,25-45"
        };
        std::process::Command::new(env!("CARGO_BIN_EXE_host-harness"))
            .current_dir(&rec)
            .args([
                "analyze",
                &format!("--frames={frames}"),
                "--fps",
                fps,
                "--accel",
                "accel.csv",
                "--fs",
                "2048",
                "--time-col",
                "t_s",
                "--threshold",
                "127",
                "--mm-per-px",
                "0.1266",
                "--bands",
                bands,
                "--out",
                out,
            ])
            .args(extra)
            .output()
            .unwrap()
    };
    let analyze = |frames: &str, fps: &str, out: &str| analyze_with(frames, fps, out, &[]);
    // an MJPEG AVI of 33 px wide frames: FFmpeg notes "EOI missing" on every frame, which is
    // not damage
    encode(&rec, "120", &["-c:v", "mjpeg", "-q:v", "2"], "mjpeg.avi");
    assert_ok(&analyze("mjpeg.avi", "120", "a1"));
    // a file whose name starts with '-' is a file, not an FFmpeg option
    encode(&rec, "120", &["-c:v", "ffv1"], "-y.mkv");
    assert_ok(&analyze("-y.mkv", "120", "a2"));
    // a constant 60 fps video read as 120, and an NTSC 29.97 fps one read as 30: the video's
    // own rate is named, never "a dropped frame" or "a variable frame rate"
    encode(&rec, "60", &["-c:v", "ffv1"], "v60.mkv");
    let o = analyze("v60.mkv", "120", "a3");
    assert_exit_2(&o, "frame rate is 60.0000 fps (60/1), constant, not 120");
    assert_exit_2(&o, "or add --retime");
    // said to be slow motion (--retime), the same frames read 1/120 s apart: the analysis of
    // the 120 fps file, with a note naming both rates
    assert_ok(&analyze_with("v60.mkv", "120", "a6", &["--retime"]));
    for f in ["modes.csv", "displacement.csv"] {
        let (a, b) = (rec.join("a2").join(f), rec.join("a6").join(f));
        assert_eq!(
            std::fs::read(&a).unwrap(),
            std::fs::read(&b).unwrap(),
            "{f}: retimed 60 fps file differs from the 120 fps one"
        );
    }
    let report = std::fs::read_to_string(rec.join("a6/report.txt")).unwrap();
    assert!(
        report.contains("--fps 120 retimes v60.mkv, whose container plays at 60.0000 fps"),
        "{report}"
    );
    // --retime is for videos: with image files it is refused, naming the flag
    let o = analyze_with("frames", "120", "a7", &["--retime"]);
    assert_exit_2(&o, "--retime applies to a video file");
    let png = rec.join("frames/frame_00000.png");
    let o = harness(&words(
        "centroid --threshold 127 --fps 120 --retime {}",
        &[png.to_str().unwrap()],
    ));
    assert_exit_2(&o, "--retime applies to a video file");
    encode(&rec, "30000/1001", &["-c:v", "ffv1"], "ntsc.mkv");
    let o = analyze("ntsc.mkv", "30", "a4");
    assert_exit_2(&o, "29.9700 fps (30000/1001), constant");
    // the rate written as the container writes it is accepted; 1200 frames at 30000/1001 fps
    // span no whole number of 2048 Hz samples (that needs a multiple of 1875 frames): said so
    let o = analyze("ntsc.mkv", "30000/1001", "a5");
    assert_exit_2(&o, "no record of up to 1200 frames spans a whole number");
}

#[test]
fn a_study_resumed_with_more_runs_keeps_its_runs_and_equals_a_fresh_one() {
    let tmp = tempfile::tempdir().unwrap();
    let study = |out: &Path, runs: &str, extra: &[&str]| {
        let mut a = words(
            "study --runs {} --exposures-ms 40 --seed 5 --no-plots --out {}",
            &[runs, out.to_str().unwrap()],
        );
        a.extend_from_slice(extra);
        harness(&a)
    };
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    assert_ok(&study(&a, "3", &[]));
    // what an adaptive study's "raise runs to at least N" asks for: the runs done are kept
    assert_ok(&study(&a, "5", &["--resume"]));
    let lines = std::fs::read_to_string(a.join("runs.jsonl")).unwrap();
    assert_eq!(lines.lines().count(), 5);
    assert_ok(&study(&b, "5", &[]));
    assert_eq!(
        std::fs::read(a.join("summary.csv")).unwrap(),
        std::fs::read(b.join("summary.csv")).unwrap()
    );
    // lowering is refused, naming both counts
    assert_exit_2(&study(&a, "4", &["--resume"]), "--runs 4 is below the 5");
}

#[test]
fn thirty_three_blobs_are_counted_not_called_a_capacity_overflow() {
    let (_tmp, rec) = make_recording(120, 2048);
    // 33 ragged blobs (V-shaped: two labels each until the arms join) in a row: 66 labels at
    // once, more than the 64 slots the tracker once had
    let (w, h) = (400u32, 16u32);
    let mut img = image::GrayImage::new(w, h);
    for b in 0..33 {
        let (cx, cy) = (6 + 12 * b, 8);
        // a V whose two arms start on the top row and meet at the bottom
        for d in 0..=3 {
            img.put_pixel(cx - 3 + d, cy - 3 + d, image::Luma([250]));
            img.put_pixel(cx + 3 - d, cy - 3 + d, image::Luma([250]));
        }
    }
    for k in 0..120 {
        img.save(rec.frames.join(format!("frame_{k}.png"))).unwrap();
    }
    let o = analyze_into(&rec, &rec.dir.join("out"), &["--targets", "2"]);
    assert_exit_2(
        &o,
        "33 targets above the threshold in the first frame, --targets 2 expected",
    );
}

#[test]
fn a_new_study_never_writes_into_a_folder_of_someone_elses() {
    let tmp = tempfile::tempdir().unwrap();
    let mine = tmp.path().join("mine");
    std::fs::create_dir(&mine).unwrap();
    std::fs::write(mine.join("summary.csv"), "my own table").unwrap();
    let o = harness(&words(
        "study --runs 2 --exposures-ms 40 --no-plots --out {}",
        &[mine.to_str().unwrap()],
    ));
    assert_exit_2(&o, "holds summary.csv, which is not a study's");
    assert_eq!(
        std::fs::read_to_string(mine.join("summary.csv")).unwrap(),
        "my own table"
    );
}
