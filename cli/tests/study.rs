//! `vibcam-study`, the README's main job, is `host-harness study`: the same flags give the same
//! files as the study's golden outputs (`tests/golden/study`, written by `host-harness study`
//! and held by the end-to-end tests), and a refused flag is named with exit code 2.

use std::path::Path;
use std::process::{Command, Output};

fn vibcam_study(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vibcam-study"))
        .args(args)
        .output()
        .expect("vibcam-study runs")
}

#[test]
fn the_study_binary_writes_what_host_harness_study_wrote() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("s");
    // the arguments of tests/golden.rs's small study
    let mut args: Vec<&str> = "--runs 4 --exposures-ms 40,180 --no-plots --threads 2"
        .split(' ')
        .collect();
    args.extend(["--out", out.to_str().unwrap()]);
    let o = vibcam_study(&args);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        text.contains("180"),
        "the table names the exposures: {text}"
    );
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/golden/study");
    // these files are short enough to be kept whole in the golden folder
    for f in ["summary.csv", "coverage.csv", "lost_frames.csv"] {
        let want = std::fs::read_to_string(golden.join(f)).unwrap();
        let got = std::fs::read_to_string(out.join(f)).unwrap();
        assert_eq!(got, want, "{f} differs from host-harness study's");
    }
}

#[test]
fn a_refused_flag_is_named_with_exit_code_2() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("s");
    let o = vibcam_study(&["--runs", "0", "--no-plots", "--out", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("runs"), "{err}");
    assert!(!out.exists(), "a refused study wrote {}", out.display());
}
