//! End-to-end tests of `host-harness study` and `merge`: reproducibility across thread counts,
//! shards merged byte-identically, resume after an interruption, refusal to overwrite or to mix
//! runs of two model revisions.

use crate::util::{assert_exit_2, assert_ok as ok, harness, words};
use std::path::Path;

const SMALL: &[&str] = &[
    "study",
    "--runs",
    "4",
    "--exposures-ms",
    "40,180",
    "--seed",
    "11",
    "--no-plots",
];

fn study(out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args: Vec<&str> = SMALL.to_vec();
    let o = out.to_str().unwrap();
    args.extend(["--out", o]);
    args.extend(extra);
    harness(&args)
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// `host-harness study --config cfg --out out --no-plots`.
fn study_config(cfg: &Path, out: &Path) -> std::process::Output {
    harness(&words(
        "study --config {} --out {} --no-plots",
        &[cfg.to_str().unwrap(), out.to_str().unwrap()],
    ))
}

/// Writes the study file `text` into a new temporary directory and runs it into its `out`;
/// returns the directory (removed when dropped) and the output directory.
fn run_study_file(text: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("study.toml");
    std::fs::write(&cfg, text).unwrap();
    let out = dir.path().join("out");
    ok(&study_config(&cfg, &out));
    (dir, out)
}

/// Asserts that `files` are byte-identical in directories `a` and `b`.
fn assert_same_files(a: &Path, b: &Path, files: &[&str]) {
    for f in files {
        assert_eq!(
            read(&a.join(f)),
            read(&b.join(f)),
            "{f} differs in {}",
            b.display()
        );
    }
}

/// `mu_a` (column 6) of the first summary row starting with `prefix`.
fn mu_a(summary: &str, prefix: &str) -> f64 {
    summary
        .lines()
        .find(|l| l.starts_with(prefix))
        .and_then(|l| l.split(',').nth(6))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{prefix} in {summary}"))
}

/// Runs the study as shards 1/2 and 2/2 into `dir/s1` and `dir/s2`.
fn two_shards(dir: &Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let (s1, s2) = (dir.join("s1"), dir.join("s2"));
    ok(&study(&s1, &["--shard", "1/2"]));
    ok(&study(&s2, &["--shard", "2/2"]));
    (s1, s2)
}

/// `host-harness merge s1 s2 --out out --no-plots`.
fn merge(s1: &Path, s2: &Path, out: &Path) -> std::process::Output {
    harness(&words(
        "merge {} {} --out {} --no-plots",
        &[
            s1.to_str().unwrap(),
            s2.to_str().unwrap(),
            out.to_str().unwrap(),
        ],
    ))
}

#[test]
fn same_seed_same_numbers_for_any_thread_count_and_sharding() {
    let dir = tempfile::tempdir().unwrap();
    let one = dir.path().join("one");
    let two = dir.path().join("two");
    ok(&study(&one, &["--threads", "1"]));
    ok(&study(&two, &["--threads", "2"]));
    for f in ["summary.csv", "realizations.csv", "frf_band.csv"] {
        assert_eq!(read(&one.join(f)), read(&two.join(f)), "{f} differs");
    }
    // the summary has both systems, both modes and every exposure
    let summary = read(&one.join("summary.csv"));
    let mut lines = summary.lines();
    assert_eq!(
        lines.next().unwrap(),
        "system,exposure_ms,mode,runs,mu_f_hz,sigma_f_hz,mu_a,sigma_a,e2pr,\
         u_mu_a,a_lo95,a_hi95,u_mu_f,f_lo95,f_hi95"
    );
    // transducer, vision, vision_compensated x 2 modes x 2 exposures
    assert_eq!(lines.count(), 3 * 2 * 2);
    // the table is printed
    let out = String::from_utf8_lossy(&study(&dir.path().join("three"), &[]).stdout).to_string();
    assert!(out.contains("mu_a") && out.contains("vision"), "{out}");

    // two shards merged give byte-identical outputs
    let (s1, s2) = two_shards(dir.path());
    let merged = dir.path().join("merged");
    ok(&merge(&s1, &s2, &merged));
    assert_same_files(
        &one,
        &merged,
        &[
            "summary.csv",
            "realizations.csv",
            "frf_band.csv",
            "coverage.csv",
        ],
    );
    // merging an incomplete set is refused
    let bad = dir.path().join("bad");
    let out = harness(&[
        "merge",
        s1.to_str().unwrap(),
        "--out",
        bad.to_str().unwrap(),
    ]);
    assert_exit_2(&out, "missing");
}

#[test]
fn resume_after_interruption_gives_the_uninterrupted_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full");
    ok(&study(&full, &[]));
    // an interrupted study: two runs done, the third cut mid-line
    let part = dir.path().join("part");
    ok(&study(&part, &[]));
    let runs = read(&part.join("runs.jsonl"));
    let lines: Vec<&str> = runs.lines().collect();
    assert_eq!(lines.len(), 4);
    let cut = format!("{}\n{}\n{}", lines[0], lines[1], &lines[2][..40]);
    std::fs::write(part.join("runs.jsonl"), cut).unwrap();
    std::fs::remove_file(part.join("summary.csv")).unwrap();

    // without --resume the directory is not overwritten
    assert_exit_2(&study(&part, &[]), "--resume");
    // resuming with another configuration is refused
    let out = study(&part, &["--resume", "--fixed-structure"]);
    assert_eq!(out.status.code(), Some(2));

    let out = study(&part, &["--resume"]);
    ok(&out);
    for f in ["summary.csv", "realizations.csv", "frf_band.csv"] {
        assert_eq!(
            read(&full.join(f)),
            read(&part.join(f)),
            "{f} differs after resume"
        );
    }
    assert_eq!(read(&part.join("runs.jsonl")).lines().count(), 4);
}

#[test]
fn runs_of_another_model_revision_are_never_mixed() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a");
    ok(&study(&a, &[]));
    let rev = host_harness::study::MODEL_REVISION;
    assert_eq!(read(&a.join("model_revision.txt")).trim(), rev.to_string());
    // a directory written by other code (here: before revisions were recorded) is not resumed
    std::fs::remove_file(a.join("model_revision.txt")).unwrap();
    let out = study(&a, &["--resume"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("model revision 1") && err.contains(&format!("revision {rev}")),
        "{err}"
    );
    // nor merged with shards of this revision
    let (s1, s2) = two_shards(dir.path());
    std::fs::write(s2.join("model_revision.txt"), format!("{}\n", rev + 1)).unwrap();
    assert_exit_2(&merge(&s1, &s2, &dir.path().join("merged")), "same code");
}

#[test]
fn bad_arguments_exit_2_and_name_the_field() {
    let dir = tempfile::tempdir().unwrap();
    assert_exit_2(
        &study(&dir.path().join("x"), &["--shard", "3/2"]),
        "--shard",
    );
    let y = dir.path().join("y");
    let out = harness(&words("study --runs 0 --out {}", &[y.to_str().unwrap()]));
    assert_exit_2(&out, "runs");
    let cfg = dir.path().join("s.toml");
    std::fs::write(&cfg, "preset = \"grandstand\"\nrunz = 3\n").unwrap();
    let out = harness(&["study", "--config", cfg.to_str().unwrap()]);
    assert_exit_2(&out, "s.toml");
    assert_exit_2(&out, "runz");
}

#[test]
fn render_writes_sharp_and_blurred_frames() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("frames");
    let o = harness(&words(
        "render --exposure-ms 180 --times 33.4 --out {}",
        &[out.to_str().unwrap()],
    ));
    ok(&o);
    let sharp = image::open(out.join("frame_t33.4_sharp.png"))
        .unwrap()
        .to_luma8();
    let blurred = image::open(out.join("frame_t33.4_exp180ms.png"))
        .unwrap()
        .to_luma8();
    assert_eq!(sharp.dimensions(), blurred.dimensions());
    // the sharp disk reaches its level 200; 180 ms of motion smear it below that
    let max = |im: &image::GrayImage| im.pixels().map(|p| p.0[0]).max().unwrap();
    assert_eq!(max(&sharp), 200);
    assert!(max(&blurred) < 200, "blurred max {}", max(&blurred));
    // the same total light: the blur redistributes it (sums within 1 %)
    let sum = |im: &image::GrayImage| im.pixels().map(|p| p.0[0] as f64).sum::<f64>();
    assert!((sum(&sharp) / sum(&blurred) - 1.0).abs() < 0.01);
    // a second render into the same directory is refused without --force
    let again = harness(&words(
        "render --times 33.4 --out {}",
        &[out.to_str().unwrap()],
    ));
    assert_exit_2(&again, "--force");
    let o = harness(&words(
        "render --times 1e6 --out {} --force",
        &[out.to_str().unwrap()],
    ));
    assert_exit_2(&o, "--times");
}

#[test]
fn imaging_effects_from_a_study_file() {
    let (dir, out) = run_study_file(
        "preset = \"grandstand\"\nruns = 2\nexposures_ms = [40.0]\n\n[imaging]\nbits = 12\nread_noise = 1.0\nshot_noise_e_per_level = 20.0\noptical_blur_sigma_px = 0.7\ngain = 1.1\n",
    );
    let written = read(&out.join("config.toml"));
    assert!(written.contains("bits = 12"), "{written}");
    // vision rows are present and the amplitude stays near the transducer's at 40 ms
    let s = read(&out.join("summary.csv"));
    let (vis, tr) = (mu_a(&s, "vision,40,1,"), mu_a(&s, "transducer,40,1,"));
    assert!((vis / tr - 1.0).abs() < 0.1, "{s}");
    // an invalid option is refused with the field named
    let cfg = dir.path().join("bad.toml");
    std::fs::write(&cfg, "preset = \"grandstand\"\n[imaging]\nbits = 10\n").unwrap();
    assert_exit_2(&study_config(&cfg, &dir.path().join("p")), "imaging.bits");
}

#[test]
fn imaging_effects_in_the_cantilever_study() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("c.toml");
    let base = "preset = \"cantilever\"\nruns = 3\nexposures_ms = [2.0]\n";
    std::fs::write(
        &cfg,
        format!("{base}\n[imaging]\nbits = 12\nread_noise = 2.0\noptical_blur_sigma_px = 0.5\n"),
    )
    .unwrap();
    let run = |name: &str, file: &Path| {
        let out = dir.path().join(name);
        ok(&study_config(file, &out));
        out
    };
    let noisy = run("noisy", &cfg);
    let plain_cfg = dir.path().join("p.toml");
    std::fs::write(&plain_cfg, base).unwrap();
    let plain = run("plain", &plain_cfg);
    // the effects reach the frames: the vision realizations differ from the plain camera's,
    // the accelerometer ones do not
    let rows = |d: &Path, sys: &str| -> Vec<String> {
        read(&d.join("realizations.csv"))
            .lines()
            .filter(|l| l.contains(&format!(",{sys},")))
            .map(String::from)
            .collect()
    };
    assert_eq!(rows(&noisy, "transducer").len(), 6);
    assert_eq!(rows(&noisy, "transducer"), rows(&plain, "transducer"));
    assert_ne!(rows(&noisy, "vision"), rows(&plain, "vision"));
    // and mode 1 still follows the accelerometer at 2 ms (sinc = 0.9997)
    let s = read(&noisy.join("summary.csv"));
    let chi = mu_a(&s, "vision,2,1,") / mu_a(&s, "transducer,2,1,");
    assert!((chi - 1.0).abs() < 0.02, "chi {chi}\n{s}");
}

/// The adaptive procedure (JCGM 101 7.9): one process stops at a whole number of batches and
/// says so; the same batches computed as three shards and merged give identical outputs.
#[test]
fn adaptive_batches_stop_and_three_shards_merge_identically() {
    let dir = tempfile::tempdir().unwrap();
    let base: Vec<&str> = "study --adaptive --digits 1 --batch 20 --runs 60 --exposures-ms 40 \
                           --seed 5 --adaptive-on transducer:1:f --no-plots"
        .split_whitespace()
        .collect();
    let run = |out: &Path, extra: &[&str]| {
        let mut a = base.clone();
        a.extend(["--out", out.to_str().unwrap()]);
        a.extend(extra);
        harness(&a)
    };
    let one = dir.path().join("one");
    let o = run(&one, &[]);
    ok(&o);
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(text.contains("adaptive (JCGM 101 7.9, 1 significant digit(s), batches of 20)"));
    assert!(crate::util::stderr(&o).contains("smaller than JCGM 101"));
    // whole batches only, at least two
    let runs = read(&one.join("runs.jsonl")).lines().count();
    assert!(runs == 40 || runs == 60, "{runs} runs");
    let adaptive = read(&one.join("adaptive.csv"));
    let row = adaptive.lines().nth(1).unwrap();
    assert!(row.starts_with("transducer,40,1,f_hz,"), "{adaptive}");
    assert_eq!(row.split(',').nth(5), Some(runs.to_string().as_str()));
    assert!(text.contains(&format!("{} runs", runs)), "{text}");

    let shards: Vec<_> = (1..=3)
        .map(|k| {
            let d = dir.path().join(format!("s{k}"));
            ok(&run(&d, &["--shard", &format!("{k}/3")]));
            // a shard holds whole batches: batch k - 1 of the three
            assert_eq!(read(&d.join("runs.jsonl")).lines().count(), 20);
            d
        })
        .collect();
    let merged = dir.path().join("merged");
    let mut args = vec!["merge"];
    args.extend(shards.iter().map(|d| d.to_str().unwrap()));
    args.extend(["--out", merged.to_str().unwrap(), "--no-plots"]);
    ok(&harness(&args));
    let all = [
        "summary.csv",
        "realizations.csv",
        "frf_band.csv",
        "coverage.csv",
    ];
    assert_same_files(&one, &merged, &all);
    assert_same_files(&one, &merged, &["adaptive.csv"]);
    // a bad selection names the flag
    assert_exit_2(
        &run(&dir.path().join("bad"), &["--adaptive-on", "vision:9:a"]),
        "--adaptive-on",
    );
}

/// `vision_compensated`: with the weighted centroid at 180 ms, mode 2 (E2PR 0.45) loses about
/// 30 % of its amplitude; divided by the centroid's transfer it is back within 3 % of the
/// transducer (mean of the paired per-run ratios over 12 runs: enough for a 95 % interval).
#[test]
fn weighted_centroid_amplitudes_compensated_for_the_exposure() {
    let (_dir, out) = run_study_file(
        "preset = \"grandstand\"\nruns = 12\nexposures_ms = [180.0]\n[imaging]\ncentroid = \"weighted\"\n",
    );
    let cov = read(&out.join("coverage.csv"));
    let rows: Vec<(String, Vec<f64>)> = read(&out.join("realizations.csv"))
        .lines()
        .skip(1)
        .filter(|l| l.contains(",2,"))
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            (
                c[2].to_string(),
                vec![c[0].parse().unwrap(), c[5].parse().unwrap()],
            )
        })
        .collect();
    let amp = |system: &str, run: f64| {
        rows.iter()
            .find(|(s, v)| s == system && v[0] == run)
            .map(|(_, v)| v[1])
            .unwrap()
    };
    let mean_ratio = |system: &str| {
        (0..12)
            .map(|run| amp(system, run as f64) / amp("transducer", run as f64))
            .sum::<f64>()
            / 12.0
    };
    let (v, c) = (mean_ratio("vision"), mean_ratio("vision_compensated"));
    assert!(v < 0.8, "vision/transducer {v}");
    // one run's ratio scatters by about 3 % (std), the mean of 12 by about 1 %
    assert!((c - 1.0).abs() < 0.03, "compensated/transducer {c}");
    // the coverage file states the ratio of every vision system
    assert!(
        cov.contains("vision_compensated,180,2,ratio,12,0.95,"),
        "{cov}"
    );
}
