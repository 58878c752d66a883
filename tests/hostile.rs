//! Files and flags as a hostile or careless user gives them: every size a header states is
//! checked before it is allocated, every bound is named, and nothing that is wrong comes out as
//! a number. Each test here failed before its fix (crash, hang or silent wrong answer).

use crate::util::{assert_exit_2, assert_ok, harness, stderr};
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
        let o = harness(&["centroid", "--threshold", "100", name]);
        assert_exit_2(&o, needle);
        assert!(stderr(&o).contains(name), "{}", stderr(&o));
        let out = tmp.path().join("out");
        let o = harness(&[
            "track",
            "--frames",
            name,
            "--targets",
            "1",
            "--threshold",
            "100",
            "--out",
            out.to_str().unwrap(),
        ]);
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
    let o = harness(&["centroid", "--threshold", "100", name]);
    assert_ok(&o);
    let rows = String::from_utf8_lossy(&o.stdout).lines().count();
    assert_eq!(rows, 7, "header and 6 frames");
    // tracking needs the rate: refused, naming the frame and the regular range
    let out = tmp.path().join("track");
    let track = |extra: &[&str]| {
        let mut args = vec![
            "track",
            "--frames",
            name,
            "--targets",
            "1",
            "--threshold",
            "100",
            "--out",
            out.to_str().unwrap(),
            "--force",
        ];
        args.extend_from_slice(extra);
        harness(&args)
    };
    let o = track(&[]);
    assert_exit_2(&o, "frame 6 comes");
    assert!(stderr(&o).contains("--frame-range 1..5"), "{}", stderr(&o));
    // and the range the error names is read, its frames labelled as in the whole file
    assert_ok(&track(&["--frame-range", "1..5"]));
    let disp = std::fs::read_to_string(out.join("displacement.csv")).unwrap();
    assert_eq!(disp.lines().count(), 1 + 5, "{disp}");
    let o = harness(&[
        "centroid",
        "--threshold",
        "100",
        "--frame-range",
        "2..3",
        name,
    ]);
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
        let mut args = vec!["simulate-field", "--out", o, "--force"];
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
        let mut args = vec![
            "track",
            "--frames",
            name,
            "--targets",
            "1",
            "--threshold",
            "9",
        ];
        args.extend_from_slice(&flags);
        args.extend(["--out", out.to_str().unwrap()]);
        let o = harness(&args);
        assert_exit_2(&o, "positive rate");
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
    let o = harness(&[
        "track",
        "--frames",
        zero.to_str().unwrap(),
        "--targets",
        "1",
        "--threshold",
        "100",
        "--out",
        tmp.path().join("z").to_str().unwrap(),
    ]);
    assert_exit_2(&o, "no usable frame rate (none, or 0 fps)");
}
