//! Adversarial end-to-end cases: each fixed defect stays fixed. A study directory is
//! locked, its checkpoint is never emptied or double counted, sizes are bounded, undefined
//! statistics are empty cells.

use crate::util::assert_contains;
use crate::util::{assert_exit_2, assert_ok, harness, stderr, words};
use std::path::Path;
use std::process::{Command, Stdio};

/// `host-harness study --runs runs --exposures-ms 40 --no-plots --out out` and `extra`.
fn study_of(runs: &str, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = words("study --runs {} --exposures-ms 40 --no-plots", &[runs]);
    args.extend(["--out", out.to_str().unwrap()]);
    args.extend(extra);
    harness(&args)
}

/// Three runs of seed 5.
fn study(out: &Path, extra: &[&str]) -> std::process::Output {
    study_of("3", out, &[&["--seed", "5"], extra].concat())
}

/// A study of 40 runs on one thread: many seconds, long enough to still be running when a
/// second process starts on the same directory.
const LONG: &[&str] = &["study", "--runs", "40", "--threads", "1", "--no-plots"];

#[test]
fn a_second_process_on_a_running_study_is_refused_with_the_holders_pid() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s");
    // a study long enough to still be running when the second one starts
    let mut first = Command::new(env!("CARGO_BIN_EXE_host-harness"))
        .args(LONG)
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let lock = out.join(".lock");
    let t0 = std::time::Instant::now();
    while std::fs::read_to_string(&lock).map_or(true, |s| s.trim().is_empty()) {
        assert!(
            t0.elapsed().as_secs() < 60,
            "the first study never took its lock"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let second = harness(&[LONG, &["--resume", "--out", out.to_str().unwrap()]].concat());
    let still_running = first.try_wait().unwrap().is_none();
    first.kill().ok();
    first.wait().ok();
    // 40 runs on one thread take many seconds: the first must still hold the lock
    assert!(
        still_running,
        "the first study ended before the second started"
    );
    assert_exit_2(&second, "in use by another host-harness process");
    assert_exit_2(&second, &first.id().to_string());
}

#[test]
fn duplicated_and_torn_checkpoint_lines_are_neither_counted_twice_nor_fatal() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    assert_ok(&study(&a, &[]));
    assert_ok(&study(&b, &[]));
    let runs = std::fs::read_to_string(b.join("runs.jsonl")).unwrap();
    let first = runs.lines().next().unwrap();
    // one identical duplicate and a torn last line
    let tampered = format!("{runs}{first}\n{}", &first[..30]);
    std::fs::write(b.join("runs.jsonl"), tampered).unwrap();
    let o = study(&b, &["--resume"]);
    assert_ok(&o);
    let e = stderr(&o);
    assert_contains(&e, &["recorded more than once", "cut short"]);
    let read = |d: &Path| std::fs::read_to_string(d.join("summary.csv")).unwrap();
    assert_eq!(read(&a), read(&b), "the duplicate was counted");
    // the torn line is gone, the file was cut back, not emptied
    let after = std::fs::read_to_string(b.join("runs.jsonl")).unwrap();
    assert!(
        after.ends_with('\n') && after.lines().count() == 4,
        "{after}"
    );
    // a run recorded twice with different results is refused
    let changed = first.replace("\"natural_f_hz\":[", "\"natural_f_hz\":[9.5,");
    assert_ne!(changed, first);
    std::fs::write(b.join("runs.jsonl"), format!("{after}{changed}\n")).unwrap();
    assert_exit_2(
        &study(&b, &["--resume"]),
        "recorded twice with different results",
    );
}

#[test]
fn sizes_from_one_flag_are_bounded_and_the_bound_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x");
    for (args, needle) in [
        (&["--runs", "1000000000000"][..], "1000000"),
        (
            &["--exposures-ms", "1e9"][..],
            "longer than the simulated record",
        ),
    ] {
        let mut a = words("study --no-plots --out {}", &[out.to_str().unwrap()]);
        a.extend(args);
        assert_exit_2(&harness(&a), needle);
    }
    let o = harness(&words(
        "render --exposure-ms 1e9 --out {}",
        &[out.to_str().unwrap()],
    ));
    assert_exit_2(&o, "longer than the simulated record");
    // an absurd thread count is capped with a warning, and the study runs
    let o = study(&dir.path().join("t"), &["--threads", "100000"]);
    assert_ok(&o);
    assert!(stderr(&o).contains("capped"), "{}", stderr(&o));
}

#[test]
fn one_run_gives_empty_cells_not_nan() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("one");
    assert_ok(&study_of("1", &out, &[]));
    let s = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    assert!(!s.contains("NaN"), "{s}");
    // sigma of one run is undefined: an empty cell
    assert!(s.lines().nth(1).unwrap().contains(",,"), "{s}");
    // a shard that gets no run: every statistic empty, in every file
    let empty = dir.path().join("empty");
    assert_ok(&study_of("1", &empty, &["--shard", "2/2"]));
    for f in [
        "summary.csv",
        "coverage.csv",
        "frf_band.csv",
        "realizations.csv",
    ] {
        let s = std::fs::read_to_string(empty.join(f)).unwrap();
        assert!(!s.to_lowercase().contains("nan"), "{f}: {s}");
    }
    let s = std::fs::read_to_string(empty.join("summary.csv")).unwrap();
    assert!(
        s.lines().nth(1).unwrap().starts_with("transducer,40,1,0,,"),
        "{s}"
    );
    // merged with the shard that has the run: the one-process study's files, byte for byte
    let first = dir.path().join("first");
    assert_ok(&study_of("1", &first, &["--shard", "1/2"]));
    let merged = dir.path().join("merged");
    assert_ok(&harness(&words(
        "merge {} {} --out {} --no-plots",
        &[
            first.to_str().unwrap(),
            empty.to_str().unwrap(),
            merged.to_str().unwrap(),
        ],
    )));
    for f in [
        "summary.csv",
        "coverage.csv",
        "frf_band.csv",
        "realizations.csv",
    ] {
        assert_eq!(
            std::fs::read_to_string(merged.join(f)).unwrap(),
            std::fs::read_to_string(out.join(f)).unwrap(),
            "{f}: merge of a full and an empty shard differs from the one-process study"
        );
    }
}

/// `study --help` states the defaults of --runs and --seed and the units of the outputs
/// (it stated neither).
#[test]
fn study_help_states_defaults_and_units() {
    let o = harness(&["study", "--help"]);
    let text = String::from_utf8_lossy(&o.stdout);
    let needles = [
        "[default: 100",
        "[default: 1]",
        "mm/kN",
        "frequencies in Hz",
    ];
    for needle in needles {
        assert!(text.contains(needle), "`{needle}` not in\n{text}");
    }
}

/// Shards of two layouts (1/2 and 1/3) overlap; `merge` says so instead of "run 0 appears in
/// more than one directory".
#[test]
fn merging_shards_of_two_layouts_names_the_layouts() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    assert_ok(&study(&a, &["--shard", "1/2"]));
    assert_ok(&study(&b, &["--shard", "1/3"]));
    let merged = dir.path().join("m");
    let o = harness(&[
        "merge",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert_exit_2(&o, "is shard 1/3, but");
    assert!(stderr(&o).contains("same N"), "{}", stderr(&o));
}

/// A 16 x 16 8-bit grey frame with a bright 4 x 4 square at (`x`, 6).
fn square(x: u32) -> Vec<u8> {
    (0..16 * 16)
        .map(|i| {
            if (x..x + 4).contains(&(i % 16)) && (6..10).contains(&(i / 16)) {
                200
            } else {
                0
            }
        })
        .collect()
}

/// `DIR/f.png`: the 8-bit frame of [`square`] at x = 4.
fn square_png(dir: &Path) -> std::path::PathBuf {
    let frame = dir.join("f.png");
    image::GrayImage::from_raw(16, 16, square(4))
        .unwrap()
        .save(&frame)
        .unwrap();
    frame
}

#[test]
fn centroid_measures_every_page_of_a_multi_page_tiff_and_names_a_bad_one() {
    use tiff::encoder::{colortype, TiffEncoder};
    let dir = tempfile::tempdir().unwrap();
    let (good, bad) = (dir.path().join("three.tif"), dir.path().join("bad.tif"));
    {
        let mut enc = TiffEncoder::new(std::fs::File::create(&good).unwrap()).unwrap();
        for x in [2, 5, 9] {
            enc.write_image::<colortype::Gray8>(16, 16, &square(x))
                .unwrap();
        }
        let mut enc = TiffEncoder::new(std::fs::File::create(&bad).unwrap()).unwrap();
        enc.write_image::<colortype::Gray8>(16, 16, &square(2))
            .unwrap();
        enc.write_image::<colortype::Gray8>(8, 8, &[0u8; 64])
            .unwrap();
        enc.write_image::<colortype::Gray32Float>(16, 16, &[0f32; 256])
            .unwrap();
    }
    let o = harness(&words(
        "centroid --threshold 100 {}",
        &[good.to_str().unwrap()],
    ));
    assert_ok(&o);
    let rows: Vec<String> = String::from_utf8_lossy(&o.stdout)
        .lines()
        .skip(1)
        .map(|l| l.split(',').take(2).collect::<Vec<_>>().join(","))
        .collect();
    let g = good.to_str().unwrap();
    assert_eq!(
        rows,
        [
            format!("{g}#1,3.5"),
            format!("{g}#2,6.5"),
            format!("{g}#3,10.5")
        ]
    );
    // page 2 (another size, no target) is measured on its own; page 3 is colour: named
    let o = harness(&words(
        "centroid --threshold 100 {}",
        &[bad.to_str().unwrap()],
    ));
    assert_exit_2(&o, "bad.tif page 3: unsupported colour type");
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        out.contains("bad.tif#1,3.5") && out.contains("bad.tif#2,,"),
        "{out}"
    );
    // a truncated TIFF: the page that cannot be read is named
    let bytes = std::fs::read(&good).unwrap();
    std::fs::write(&bad, &bytes[..bytes.len() / 2]).unwrap();
    let o = harness(&words(
        "centroid --threshold 100 {}",
        &[bad.to_str().unwrap()],
    ));
    assert_exit_2(&o, "bad.tif page");
}

#[test]
fn an_8_bit_saturation_above_255_and_a_1_bit_png_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let frame = square_png(dir.path());
    let f = frame.to_str().unwrap();
    let o = harness(&words(
        "centroid --threshold 100 --saturation 1000 {}",
        &[f],
    ));
    assert_exit_2(&o, "--saturation 1000 is above 255");
    assert_ok(&harness(&words(
        "centroid --threshold 100 --saturation 250 {}",
        &[f],
    )));
    // a 1-bit grey PNG (one byte holds 8 pixels)
    let one_bit = dir.path().join("bits.png");
    {
        let file = std::fs::File::create(&one_bit).unwrap();
        let mut enc = png::Encoder::new(file, 16, 16);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::One);
        let mut w = enc.write_header().unwrap();
        w.write_image_data(&[0x0f; 32]).unwrap();
    }
    let o = harness(&words(
        "centroid --threshold 0 {}",
        &[one_bit.to_str().unwrap()],
    ));
    assert_exit_2(&o, "a 1-bit grey PNG; 8- or 16-bit grey images are needed");
}

#[test]
fn a_full_standard_output_is_an_error_naming_it_not_a_crash() {
    let dir = tempfile::tempdir().unwrap();
    let frame = square_png(dir.path());
    let full = || {
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap()
    };
    for args in [
        words("plan --preset grandstand --tolerance 0.1", &[]),
        words("centroid --threshold 100 {}", &[frame.to_str().unwrap()]),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_host-harness"))
            .args(&args)
            .stdout(full())
            .output()
            .unwrap();
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
        assert!(
            e.contains("cannot write to standard output"),
            "{args:?}: {e}"
        );
        assert!(!e.contains("panicked"), "{args:?}: {e}");
    }
}

/// `study` of 4 runs (seed 5, one thread) into `out` with `extra`, with `VIBCAM_FAILPOINT`
/// set to `failpoint` when given.
fn study_killed_at(out: &Path, extra: &[&str], failpoint: Option<&str>) -> std::process::Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_host-harness"));
    cmd.args(["study", "--runs", "4", "--exposures-ms", "40", "--no-plots"])
        .args([
            "--seed",
            "5",
            "--threads",
            "1",
            "--out",
            out.to_str().unwrap(),
        ])
        .args(extra);
    match failpoint {
        Some(f) => cmd.env("VIBCAM_FAILPOINT", f),
        None => cmd.env_remove("VIBCAM_FAILPOINT"),
    };
    cmd.output().unwrap()
}

/// Complete lines of a checkpoint.
fn complete_runs(dir: &Path) -> usize {
    let text = std::fs::read_to_string(dir.join("runs.jsonl")).unwrap_or_default();
    text.matches('\n').count()
}

#[test]
fn a_kill_at_any_write_of_a_resume_loses_no_finished_run() {
    let tmp = tempfile::tempdir().unwrap();
    let clean = tmp.path().join("clean");
    assert_ok(&study_killed_at(&clean, &[], None));
    let outputs = [
        "summary.csv",
        "realizations.csv",
        "frf_band.csv",
        "coverage.csv",
    ];
    let mut killed = 0;
    for point in [
        "checkpoint-cut",
        "checkpoint-torn",
        "checkpoint-appended",
        "atomic-synced",
        "atomic-renamed",
    ] {
        for n in 1..=3 {
            // an interrupted study: two runs done, the third cut mid-line, no outputs yet
            let dir = tmp.path().join(format!("{point}-{n}"));
            std::fs::create_dir(&dir).unwrap();
            for f in ["runs.jsonl", "config.toml", "model_revision.txt"] {
                std::fs::copy(clean.join(f), dir.join(f)).unwrap();
            }
            let runs = std::fs::read_to_string(clean.join("runs.jsonl")).unwrap();
            let lines: Vec<&str> = runs.lines().collect();
            let cut = format!("{}\n{}\n{}", lines[0], lines[1], &lines[2][..40]);
            std::fs::write(dir.join("runs.jsonl"), cut).unwrap();
            // the resume, killed at the n-th time it reaches the point (if it does)
            let o = study_killed_at(&dir, &["--resume"], Some(&format!("{point}:{n}")));
            if !o.status.success() {
                killed += 1;
                assert!(
                    stderr(&o).contains("failpoint"),
                    "{point}:{n}: {}",
                    stderr(&o)
                );
            }
            assert!(complete_runs(&dir) >= 2, "{point}:{n}: finished runs lost");
            // the next resume finishes the study with the clean run's outputs
            assert_ok(&study_killed_at(&dir, &["--resume"], None));
            for f in outputs {
                assert_eq!(
                    std::fs::read(clean.join(f)).unwrap(),
                    std::fs::read(dir.join(f)).unwrap(),
                    "{point}:{n}: {f} differs"
                );
            }
            assert_eq!(complete_runs(&dir), 4, "{point}:{n}");
        }
    }
    // every point was reached at least once (else the test would prove nothing)
    assert!(killed >= 5 + 4, "only {killed} kills");
}

/// The names in a directory, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn outputs_are_complete_or_absent_and_never_mixed_with_an_earlier_run() {
    let tmp = tempfile::tempdir().unwrap();
    let rec = tmp.path().join("rec");
    let r = rec.to_str().unwrap();
    let render = |extra: &[&str]| {
        harness(
            &[
                &[
                    "render",
                    "--preset",
                    "cantilever",
                    "--exposure-ms",
                    "2",
                    "--recording",
                    r,
                ],
                extra,
            ]
            .concat(),
        )
    };
    assert_ok(&render(&[]));
    // into an existing recording: refused without --force, the recording untouched
    std::fs::write(
        rec.join("frames/frame_99999.png"),
        "an extra frame of an older recording",
    )
    .unwrap();
    assert_exit_2(&render(&[]), "--force");
    assert!(rec.join("frames/frame_99999.png").exists());
    // nor with --force: a file the recording did not write is someone's, named in the error
    assert_exit_2(&render(&["--force"]), "frames/frame_99999.png");
    assert!(rec.join("frames/frame_99999.png").exists());
    std::fs::remove_file(rec.join("frames/frame_99999.png")).unwrap();
    std::fs::remove_file(rec.join("frames/frame_00007.png")).unwrap();
    // with --force the recording is replaced as a whole (a frame deleted by hand comes back)
    assert_ok(&render(&["--force"]));
    assert!(rec.join("frames/frame_00007.png").exists());
    assert_eq!(names(&rec.join("frames")).len(), 1200);
    // a directory that is not a recording is never replaced
    let other = tmp.path().join("thesis");
    std::fs::create_dir(&other).unwrap();
    std::fs::write(other.join("chapter1.tex"), "").unwrap();
    let o = harness(&words(
        "render --preset cantilever --exposure-ms 2 --recording {} --force",
        &[other.to_str().unwrap()],
    ));
    assert_exit_2(&o, "not only an earlier output");
    assert_eq!(names(&other), ["chapter1.tex"]);

    let out = rec.join("analysis");
    let analyze = |threshold: &str, extra: &[&str]| {
        let args = [
            "analyze",
            "--frames",
            &format!("{r}/frames"),
            "--fps",
            "120",
            "--accel",
            &format!("{r}/accel.csv"),
            "--fs",
            "2048",
            "--time-col",
            "t_s",
            "--mm-per-px",
            "0.1266",
            "--threshold",
            threshold,
            "--out",
            out.to_str().unwrap(),
        ]
        .map(str::to_string);
        let mut v: Vec<&str> = args.iter().map(String::as_str).collect();
        v.extend(extra);
        harness(&v)
    };
    assert_ok(&analyze("127", &[]));
    let first = names(&out);
    assert!(first.contains(&"modes.csv".to_string()), "{first:?}");
    let report = std::fs::read(out.join("report.txt")).unwrap();
    assert_exit_2(&analyze("127", &[]), "--force");
    // a failing analysis (no pixel is above 255: every frame lost) leaves the earlier one as it was
    let o = analyze("255", &["--force"]);
    assert!(!o.status.success(), "{}", stderr(&o));
    assert_eq!(names(&out), first);
    assert_eq!(std::fs::read(out.join("report.txt")).unwrap(), report);
    // and nothing of the failed run is left beside it
    assert_eq!(
        names(&rec),
        [
            ".vibcam-manifest.toml",
            "README.txt",
            "accel.csv",
            "analysis",
            "frames",
            "recording.toml"
        ]
    );
    assert_ok(&analyze("127", &["--force"]));
    assert_eq!(names(&out), first);
    // the recording now holds an analysis it did not write: render --force refuses to wipe it
    assert_exit_2(&render(&["--force"]), "analysis/");
    assert!(out.join("modes.csv").exists());
}

/// Every vision run failing (a target too dark for the threshold: all frames lost) leaves the
/// vision rows with runs = 0 and empty statistics, in the files and in the printed table, never
/// `NaN`; the transducer rows are computed.
#[test]
fn all_failed_vision_rows_are_empty_not_nan() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("dark.toml");
    std::fs::write(
        &config,
        "preset = \"grandstand\"\nruns = 2\nexposures_ms = [40]\n[imaging]\ngain = 0.3\n",
    )
    .unwrap();
    let out = dir.path().join("dark");
    let o = harness(&words(
        "study --config {} --no-plots --out {}",
        &[config.to_str().unwrap(), out.to_str().unwrap()],
    ));
    assert_ok(&o);
    let printed = String::from_utf8_lossy(&o.stdout);
    assert!(!printed.contains("NaN"), "{printed}");
    assert!(printed.contains("runs 0:"), "{printed}");
    for f in [
        "summary.csv",
        "coverage.csv",
        "frf_band.csv",
        "realizations.csv",
    ] {
        let s = std::fs::read_to_string(out.join(f)).unwrap();
        assert!(!s.to_lowercase().contains("nan"), "{f}: {s}");
    }
    let s = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    assert_contains(&s, &["\nvision,40,1,0,,,,,", "\ntransducer,40,1,2,"]);
}

/// A reader that stops early (`host-harness centroid ... | head -1`) closes the pipe: the
/// command ends quietly with success, as ripgrep does, instead of an error about a write.
#[test]
fn a_closed_pipe_ends_the_output_quietly() {
    use std::io::Read as _;
    let dir = tempfile::tempdir().unwrap();
    let frame = square_png(dir.path());
    let f = frame.to_str().unwrap();
    // about 3000 rows of ~40 bytes: more than a pipe buffer holds
    let mut args = vec!["centroid", "--threshold", "100"];
    args.extend(std::iter::repeat_n(f, 3000));
    let mut child = Command::new(env!("CARGO_BIN_EXE_host-harness"))
        .args(&args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = [0u8; 16];
    child.stdout.take().unwrap().read_exact(&mut first).unwrap();
    // the read end is dropped here: the next write fails with EPIPE
    let o = child.wait_with_output().unwrap();
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{e}");
    assert!(!e.contains("error") && !e.contains("panicked"), "{e}");
}
