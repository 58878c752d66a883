//! Files and flags as a hostile or careless user gives them: every size a header states is
//! checked before it is allocated, every bound is named, and nothing that is wrong comes out as
//! a number. Each test here failed before its fix (crash, hang or silent wrong answer).

use crate::util::{assert_exit_2, assert_ok, harness, stderr, words};
use std::path::{Path, PathBuf};

/// `n` frames of `w x h` 8-bit pixels with a bright disk of radius 4 px at `(cx, cy + k)`.
fn disk_frames(n: usize, (w, h): (usize, usize), (cx, cy): (f64, f64)) -> Vec<Vec<u16>> {
    (0..n)
        .map(|k| {
            let y0 = cy + 0.5 * (k as f64 * 0.7).sin();
            (0..w * h)
                .map(|i| {
                    let (x, y) = ((i % w) as f64, (i / w) as f64);
                    let r = ((x - cx).powi(2) + (y - y0).powi(2)).sqrt();
                    if r < 4.0 {
                        220
                    } else {
                        20
                    }
                })
                .collect()
        })
        .collect()
}

/// An 8-bit cine of `frames` (32 x 24) at 100 fps, with a time stamp per frame.
fn cine(dir: &Path, name: &str, frames: &[Vec<u16>]) -> PathBuf {
    let p = dir.join(name);
    host_harness::frames::phantom::write_cine(&p, (32, 24), (8, 0), (100, 1_000_000), frames)
        .unwrap();
    p
}

/// `track --frames FRAMES --targets 1 --threshold 100 --out OUT` and `extra`.
fn track_one(frames: &str, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = words(
        "track --frames {} --targets 1 --threshold 100 --out {}",
        &[frames, out.to_str().unwrap()],
    );
    args.extend_from_slice(extra);
    harness(&args)
}

/// Overwrites 4 bytes of `p` at `at` with `v` (little-endian).
fn patch_u32(p: &Path, at: usize, v: u32) {
    let mut b = std::fs::read(p).unwrap();
    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
    std::fs::write(p, b).unwrap();
}

#[test]
fn header_sizes_past_the_file_are_refused_before_anything_is_allocated() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = disk_frames(3, (32, 24), (16.0, 12.0));
    // the image count (byte 20 of the file header): 0xFFFFFFFF frames would be a 32 GiB offset
    // table; the process aborted allocating it
    let huge_count = cine(tmp.path(), "count.cine", &frames);
    patch_u32(&huge_count, 20, u32::MAX);
    // the bitmap header's width (byte 44 + 4): frames larger than the file
    let huge_width = cine(tmp.path(), "width.cine", &frames);
    patch_u32(&huge_width, 48, 0x7fff_ffff);
    for (p, needle) in [(&huge_count, "frames"), (&huge_width, "pixels")] {
        let name = p.to_str().unwrap();
        let o = harness(&words("centroid --threshold 100 {}", &[name]));
        assert_exit_2(&o, needle);
        assert!(stderr(&o).contains(name), "{}", stderr(&o));
        let out = tmp.path().join("out");
        let o = track_one(name, &out, &[]);
        assert_exit_2(&o, "damaged header");
        assert!(!out.exists());
    }
}

#[test]
fn a_junk_time_stamp_refuses_only_the_rate_and_a_frame_range_reads_the_rest() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = disk_frames(6, (32, 24), (16.0, 12.0));
    let p = cine(tmp.path(), "junk.cine", &frames);
    // the time-stamp block follows the setup (84 + 13 484 bytes): 8 bytes of block header,
    // then 8 per frame (fraction, seconds); the last frame's seconds made junk, as in the
    // camera file pycine ships
    patch_u32(&p, 84 + 13_484 + 8 + 8 * 5 + 4, 987_654);
    let name = p.to_str().unwrap();
    // a centroid needs no time stamps: every frame is measured
    let o = harness(&words("centroid --threshold 100 {}", &[name]));
    assert_ok(&o);
    let rows = String::from_utf8_lossy(&o.stdout).lines().count();
    assert_eq!(rows, 7, "header and 6 frames");
    // tracking needs the rate: refused, naming the frame and the regular range
    let out = tmp.path().join("track");
    let track = |extra: &[&str]| {
        let mut args = vec!["--force"];
        args.extend_from_slice(extra);
        track_one(name, &out, &args)
    };
    let o = track(&[]);
    assert_exit_2(&o, "frame 6 comes");
    assert!(stderr(&o).contains("--frame-range 1..5"), "{}", stderr(&o));
    // and the range the error names is read, its frames labelled as in the whole file
    assert_ok(&track(&["--frame-range", "1..5"]));
    let disp = std::fs::read_to_string(out.join("displacement.csv")).unwrap();
    assert_eq!(disp.lines().count(), 1 + 5, "{disp}");
    let o = harness(&words(
        "centroid --threshold 100 --frame-range 2..3 {}",
        &[name],
    ));
    assert_ok(&o);
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    let labels: Vec<&str> = text
        .lines()
        .skip(1)
        .filter_map(|l| l.split(',').next())
        .collect();
    assert_eq!(labels, [format!("{name}#2"), format!("{name}#3")]);
    // a range past the end, or backwards, is named
    assert_exit_2(&track(&["--frame-range", "4..9"]), "has 6 frames");
    assert_exit_2(&track(&["--frame-range", "5..2"]), "comes before");
    assert_exit_2(&track(&["--frame-range", "0..2"]), "at least 1");
}

#[test]
fn simulate_field_names_its_bounds_and_the_modes_it_cannot_sample() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("field");
    let o = out.to_str().unwrap();
    let sim = |extra: &[&str]| {
        let mut args = words("simulate-field --out {} --force", &[o]);
        args.extend_from_slice(extra);
        harness(&args)
    };
    // each of these aborted the process (a record's allocation) or ran for hours
    for (flags, needle) in [
        (&["--minutes", "1e9"][..], "20000000 sample periods"),
        (&["--fps", "1e9"][..], "20000000 sample periods"),
        (&["--minutes", "100000"][..], "20000000 sample periods"),
        (&["--render", "--minutes", "1e6"][..], "sample periods"),
        (&["--render", "--minutes", "60"][..], "200000 frames"),
        // a header-only record
        (&["--minutes", "0.00001"][..], "at least 20 periods"),
        (&["--minutes", "nan"][..], "positive number"),
    ] {
        assert_exit_2(&sim(flags), needle);
        let left: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().collect();
        assert!(left.is_empty(), "{flags:?} left {left:?}");
    }
    // every mode above the Nyquist frequency is named, with where it aliases
    let o = sim(&["--fps", "1", "--minutes", "5"]);
    assert_ok(&o);
    let report = String::from_utf8_lossy(&o.stdout).into_owned();
    let named = report.matches("above the Nyquist frequency").count();
    assert_eq!(named, 5, "{report}");
    assert!(report.contains("mode 2 (4.3785 Hz)") && report.contains("aliases to 0.3785 Hz"));
    let o = sim(&["--fps", "60", "--minutes", "1"]);
    assert!(!String::from_utf8_lossy(&o.stdout).contains("Nyquist"));
}

#[test]
fn negative_numbers_are_values_refused_by_their_range_and_dot_is_bad_input() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = disk_frames(3, (32, 24), (16.0, 12.0));
    let p = cine(tmp.path(), "ok.cine", &frames);
    let name = p.to_str().unwrap();
    let out = tmp.path().join("o");
    for flags in [["--fps", "-60"], ["--fps=-60", "--force"]] {
        let mut args = words("track --frames {} --targets 1 --threshold 9", &[name]);
        args.extend_from_slice(&flags);
        args.extend(["--out", out.to_str().unwrap()]);
        let o = harness(&args);
        assert_exit_2(&o, "'-60' for '--fps <HZ>': a number > 0 is needed");
        assert!(
            !stderr(&o).contains("unexpected argument"),
            "{}",
            stderr(&o)
        );
    }
    // `--out .` is the user's mistake: exit 2, as every other refused flag
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_host-harness"))
        .current_dir(tmp.path())
        .args([
            "track",
            "--frames",
            name,
            "--targets",
            "1",
            "--threshold",
            "100",
        ])
        .args(["--out", "."])
        .output()
        .unwrap();
    assert_exit_2(&o, "needs a name");
    // a camera file stating a rate of 0 is named as such
    let zero = cine(tmp.path(), "zero.cine", &frames);
    patch_u32(&zero, 84 + 768, 0);
    let o = harness(&words(
        "track --frames {} --targets 1 --threshold 100 --out {}",
        &[
            zero.to_str().unwrap(),
            tmp.path().join("z").to_str().unwrap(),
        ],
    ));
    assert_exit_2(&o, "no usable frame rate (none, or 0 fps)");
}

/// `modes.csv` of a `modal` output as `(method, mode, f_hz, damping)`.
fn modal_modes(dir: &Path) -> Vec<(String, usize, f64, Option<f64>)> {
    std::fs::read_to_string(dir.join("modes.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            (
                c[9].to_string(),
                c[2].parse().unwrap(),
                c[5].parse().unwrap(),
                c[7].parse().ok(),
            )
        })
        .collect()
}

/// A ten-minute shear-frame record (`simulate-field`), and `modal` run on `file` with `extra`.
fn field(dir: &Path) -> PathBuf {
    let out = dir.join("field");
    assert_ok(&harness(&words(
        "simulate-field --minutes 10 --seed 3 --out {}",
        &[out.to_str().unwrap()],
    )));
    out.join("displacement.csv")
}

fn modal(file: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = words(
        "modal --displacement {} --out {} --force",
        &[file.to_str().unwrap(), out.to_str().unwrap()],
    );
    args.extend_from_slice(extra);
    harness(&args)
}

/// `file`'s rows with every value column multiplied by `scale` (the time column kept).
fn scaled_copy(file: &Path, to: &Path, scale: f64) {
    let text = std::fs::read_to_string(file).unwrap();
    let mut lines = text.lines();
    let mut out = format!("{}\n", lines.next().unwrap());
    for l in lines {
        let c: Vec<String> = l
            .split(',')
            .enumerate()
            .map(|(i, v)| match i {
                0 => v.to_string(),
                _ => format!("{:e}", v.parse::<f64>().unwrap() * scale),
            })
            .collect();
        out.push_str(&c.join(","));
        out.push('\n');
    }
    std::fs::write(to, out).unwrap();
}

#[test]
fn modal_gives_the_same_modes_in_any_unit() {
    // scaled by 1e-11 the SSI's eigenvalue iteration ran for more than 300 s, by 1e-9 SSI lost
    // modes, by 1e150 it found none, all with exit 0
    let tmp = tempfile::tempdir().unwrap();
    let file = field(tmp.path());
    let base = tmp.path().join("base");
    assert_ok(&modal(&file, &base, &[]));
    let want = modal_modes(&base);
    assert_eq!(want.iter().filter(|m| m.0 == "ssi").count(), 5, "{want:?}");
    for scale in [1e-11, 1e-9, 1e150] {
        let f = tmp.path().join(format!("scaled_{scale:e}.csv"));
        scaled_copy(&file, &f, scale);
        let out = tmp.path().join(format!("m_{scale:e}"));
        assert_ok(&modal(&f, &out, &[]));
        let got = modal_modes(&out);
        assert_eq!(got.len(), want.len(), "x{scale}: {got:?}");
        for (a, b) in got.iter().zip(&want) {
            // the scaled file differs from the original by the rounding of each value (1e-16):
            // FDD does not move beyond it; EFDD's bell fit is a least-squares minimum whose cost
            // is flat in the damping (a change of 3e-5 in it moves the cost by about its
            // rounding), so its damping moves by up to 4e-5 and its frequency by 1e-8 (seen
            // here); a pole on the edge of SSI's stability criteria can flip
            // with it and move a cluster's median by 1e-5 (seen here); all far below the
            // estimates' scatter (1e-3 in frequency, 10 % in damping)
            assert_eq!((&a.0, a.1), (&b.0, b.1), "x{scale}");
            let (df, dz) = match a.0.as_str() {
                "ssi" => (1e-4, 1e-2),
                "efdd" => (1e-7, 1e-4),
                _ => (1e-9, 1e-6),
            };
            assert!((a.2 / b.2 - 1.0).abs() < df, "x{scale}: {a:?} vs {b:?}");
            if let (Some(x), Some(y)) = (a.3, b.3) {
                assert!((x / y - 1.0).abs() < dz, "x{scale}: {a:?} vs {b:?}");
            }
        }
    }
    // a record that does not move, or whose squares overflow, is named
    let f = tmp.path().join("huge.csv");
    scaled_copy(&file, &f, 1e300);
    assert_exit_2(&modal(&f, &tmp.path().join("h"), &[]), "RMS");
}

#[test]
fn modal_refuses_a_rate_against_its_time_column_duplicates_and_short_segments() {
    let tmp = tempfile::tempdir().unwrap();
    let file = field(tmp.path());
    let out = tmp.path().join("m");
    // the file's time column is 60 Hz: --fps 30 would halve every frequency
    assert_exit_2(
        &modal(&file, &out, &["--fps", "30"]),
        "contradicts the time column",
    );
    assert_ok(&modal(&file, &out, &["--fps", "60"]));
    // a 0.5 s gap in the time column stays an error, and its message does not advise --fps
    let text = std::fs::read_to_string(&file).unwrap();
    let gap: String = text
        .lines()
        .enumerate()
        .filter(|(i, _)| !(1000..1030).contains(i))
        .map(|(_, l)| format!("{l}\n"))
        .collect();
    let gapped = tmp.path().join("gap.csv");
    std::fs::write(&gapped, gap).unwrap();
    for extra in [&[][..], &["--fps", "60"][..]] {
        let o = modal(&gapped, &out, extra);
        assert_exit_2(&o, "must be regular");
        assert!(!stderr(&o).contains("give --fps"), "{}", stderr(&o));
    }
    // --nperseg below the shortest segment is refused; a mode the line rule leaves out is named
    assert_exit_2(&modal(&file, &out, &["--nperseg", "2"]), "at least 64");
    assert_exit_2(&modal(&file, &out, &["--nperseg", "63"]), "at least 64");
    let o = modal(&file, &out, &["--nperseg", "64"]);
    assert_ok(&o);
    let report = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        report.contains("a stable mode at 1.4") && report.contains("below the lowest frequency"),
        "{report}"
    );
    // duplicate (frame, target) rows of a long file: the same values are one row, different
    // ones are refused naming both rows
    let long = tmp.path().join("long.csv");
    let mut rows = String::from("frame,t_s,target,cx,cy\n");
    for (f, l) in text.lines().skip(1).take(2000).enumerate() {
        let c: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
        for t in 1..=5 {
            rows.push_str(&format!("{f},{},{t},10,{}\n", c[0], c[t]));
        }
    }
    std::fs::write(&long, &rows).unwrap();
    assert_ok(&modal(&long, &out, &[]));
    let mut lines: Vec<&str> = rows.lines().collect();
    let copy = lines[7].to_string();
    lines.push(&copy);
    std::fs::write(&long, lines.join("\n")).unwrap();
    assert_ok(&modal(&long, &out, &[]));
    let changed = copy.replace(",10,", ",11,");
    lines.pop();
    lines.push(&changed);
    std::fs::write(&long, lines.join("\n")).unwrap();
    let o = modal(&long, &out, &[]);
    assert_exit_2(&o, "rows 8 and 10002 both give frame 1 of target 2");
    // a frame number no file of this size can have (an allocation of that many frames)
    lines.pop();
    lines.push("99999999999,0,1,10,1");
    std::fs::write(&long, lines.join("\n")).unwrap();
    assert_exit_2(&modal(&long, &out, &[]), "a whole number from 0 to");
}

/// Writes `frames` (8-bit, `w x h`) as `dir/f_NNN.EXT`.
fn write_frames(dir: &Path, frames: &[Vec<u16>], (w, h): (u32, u32), ext: &str) {
    std::fs::create_dir_all(dir).unwrap();
    for (k, f) in frames.iter().enumerate() {
        let img = image::GrayImage::from_raw(w, h, f.iter().map(|&v| v as u8).collect()).unwrap();
        img.save(dir.join(format!("f_{k:03}.{ext}"))).unwrap();
    }
}

fn track_into(frames: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = words(
        "track --frames {} --fps 60 --out {} --force",
        &[frames.to_str().unwrap(), out.to_str().unwrap()],
    );
    args.extend_from_slice(extra);
    harness(&args)
}

#[test]
fn a_truncated_jpeg_or_a_frame_of_another_depth_is_named_not_measured() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = disk_frames(6, (64, 48), (32.0, 24.0));
    let dir = tmp.path().join("jpg");
    write_frames(&dir, &frames, (64, 48), "jpg");
    let out = tmp.path().join("t");
    let flags = ["--targets", "1", "--threshold", "100"];
    assert_ok(&track_into(&dir, &out, &flags));
    // frame 3 cut short: the decoder filled it with grey and gave a centroid 6 px off, flag 0
    let cut = dir.join("f_003.jpg");
    let bytes = std::fs::read(&cut).unwrap();
    std::fs::write(&cut, &bytes[..bytes.len() * 3 / 4]).unwrap();
    let o = track_into(&dir, &out, &flags);
    assert_exit_2(&o, "f_003.jpg: a JPEG frame that is not whole");
    let o = harness(&words(
        "centroid --threshold 100 {}",
        &[cut.to_str().unwrap()],
    ));
    assert_exit_2(&o, "truncated");
    // a 16-bit PNG among 8-bit ones was a silent lost frame, and the report called the
    // sequence 16-bit
    let png = tmp.path().join("png");
    write_frames(&png, &frames, (64, 48), "png");
    let wide: Vec<u16> = frames[4].iter().map(|&v| v * 257).collect();
    image::ImageBuffer::<image::Luma<u16>, _>::from_raw(64, 48, wide)
        .unwrap()
        .save(png.join("f_004.png"))
        .unwrap();
    let o = track_into(&png, &out, &flags);
    assert_exit_2(&o, "f_004.png: a 16-bit frame, but");
}

#[test]
fn windows_filled_above_the_threshold_say_so_and_file_thresholds_need_no_flag() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = disk_frames(30, (64, 48), (32.0, 24.0));
    let dir = tmp.path().join("png");
    write_frames(&dir, &frames, (64, 48), "png");
    let out = tmp.path().join("t");
    let points = tmp.path().join("p.csv");
    std::fs::write(&points, "target,x,y,w,h\n1,32,24,15,15\n").unwrap();
    let p = points.to_str().unwrap();
    // a threshold below the background fills the window: the target is "at its edge", as
    // `centroid` says, not "no pixel above the threshold"; and nothing measured is exit 2,
    // for `track` as for `analyze`
    let o = track_into(
        &dir,
        &out,
        &["--points", p, "--threshold", "10", "--tracker", "blob"],
    );
    assert_exit_2(&o, "at the edge of its window");
    assert!(!stderr(&o).contains("no pixel above"), "{}", stderr(&o));
    // the default tracker sees the filled window and follows it by Lucas-Kanade, saying why
    assert_ok(&track_into(
        &dir,
        &out,
        &["--points", p, "--threshold", "10"],
    ));
    let report = std::fs::read_to_string(out.join("report.txt")).unwrap();
    assert!(
        report.contains("tracker (auto): Lucas-Kanade:") && report.contains("fills it"),
        "{report}"
    );
    let analyze = |extra: &[&str]| {
        let out = tmp.path().join("a");
        let mut args = words("analyze --frames {} --fps 60", &[dir.to_str().unwrap()]);
        args.extend(["--points", p, "--out", out.to_str().unwrap()]);
        args.extend_from_slice(extra);
        harness(&args)
    };
    assert_exit_2(
        &analyze(&["--threshold", "10", "--tracker", "blob"]),
        "at the edge of its window",
    );
    let c = harness(&words(
        "centroid --threshold 10 --roi 25,17,15,15 {}",
        &[dir.join("f_000.png").to_str().unwrap()],
    ));
    assert_ok(&c);
    assert!(String::from_utf8_lossy(&c.stdout).ends_with(",2\n"));
    // the file's threshold column is each window's threshold: no --threshold needed
    std::fs::write(&points, "target,x,y,w,h,threshold\n1,32,24,15,15,100\n").unwrap();
    assert_ok(&track_into(&dir, &out, &["--points", p]));
    let report = std::fs::read_to_string(out.join("report.txt")).unwrap();
    assert!(
        report.contains("threshold 100, 0 of 30 frames lost"),
        "{report}"
    );
    // a row without one, and no flag: named (the default tracker takes Otsu's there)
    std::fs::write(
        &points,
        "target,x,y,w,h,threshold\n1,32,24,15,15,100\n2,10,10,7,7,\n",
    )
    .unwrap();
    assert_exit_2(
        &track_into(&dir, &out, &["--points", p, "--tracker", "blob"]),
        "target 2: no threshold",
    );
    // Lucas-Kanade has no threshold, and a window does not take a blob's gate
    std::fs::write(&points, "target,x,y,w,h\n1,32,24,15,15\n").unwrap();
    let o = track_into(
        &dir,
        &out,
        &["--points", p, "--tracker", "lk", "--threshold", "9"],
    );
    assert_exit_2(&o, "uses no threshold");
    let o = track_into(&dir, &out, &["--points", p, "--tracker", "lk"]);
    assert_ok(&o);
    let report = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(report.contains("Lucas-Kanade, 0 of 30") && !report.contains("threshold 0"));
    let o = track_into(
        &dir,
        &out,
        &["--points", p, "--tracker", "lk", "--gate-px", "5"],
    );
    assert_exit_2(&o, "leave --gate-px out");
    let a = analyze(&["--tracker", "lk", "--gate-px", "5"]);
    assert_exit_2(&a, "leave --gate-px out");
}

#[test]
fn a_frame_range_of_a_camera_file_reads_the_frames_the_whole_file_has_there() {
    // the readers start at the range's first frame (the cine by its offset table, the .mraw
    // by seeking): the rows must be those of the whole file at the same frame numbers
    let tmp = tempfile::tempdir().unwrap();
    let frames = disk_frames(7, (32, 24), (16.0, 12.0));
    let cih = tmp.path().join("rec.cih");
    host_harness::frames::photron::write_recording(&cih, (32, 24), 8, 100.0, 0.001, &frames)
        .unwrap();
    let cine = cine(tmp.path(), "rec.cine", &frames);
    for p in [cih, cine] {
        let name = p.to_str().unwrap();
        let rows = |extra: &[&str]| {
            let mut args = vec!["centroid", "--threshold", "100"];
            args.extend_from_slice(extra);
            args.push(name);
            let o = harness(&args);
            assert_ok(&o);
            String::from_utf8_lossy(&o.stdout)
                .lines()
                .skip(1)
                .map(str::to_string)
                .collect::<Vec<_>>()
        };
        let whole = rows(&[]);
        assert_eq!(whole.len(), 7);
        assert_eq!(
            rows(&["--frame-range", "3..5"]),
            whole[2..5].to_vec(),
            "{name}"
        );
        assert_eq!(
            rows(&["--frame-range", "6.."]),
            whole[5..].to_vec(),
            "{name}"
        );
    }
}
