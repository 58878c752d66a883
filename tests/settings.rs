//! Every setting the library names in a message is refused in the command line's words: for
//! each key of `setting::KEYS` a command that the library refuses (exit 2) for that setting,
//! its message naming `--the-flag` and no `$key` left unspelled. Python's spelling of the same
//! messages is checked by python/tests (its arguments, never a flag).

use std::path::Path;
use std::process::{Command, Output};

/// The inputs the refusals below read, written into `dir`: eight 32 x 24 frames of a bright
/// disk (`fr/`), a points file, displacement and accelerometer CSVs, a two-channel force, two
/// signals.
fn inputs(dir: &Path) {
    let fr = dir.join("fr");
    std::fs::create_dir(&fr).unwrap();
    for k in 0..8u32 {
        let img = image::GrayImage::from_fn(32, 24, |x, y| {
            let (dx, dy) = (f64::from(x) - 16.0, f64::from(y) - 12.0 - f64::from(k % 2));
            image::Luma([if dx * dx + dy * dy < 16.0 { 220 } else { 20 }])
        });
        img.save(fr.join(format!("frame_{k}.png"))).unwrap();
    }
    let rows = |n: usize, line: &dyn Fn(usize) -> String| -> String {
        (0..n).map(line).collect::<Vec<_>>().concat()
    };
    let files = [
        ("p.csv", "target,x,y,w,h\n1,16,12,9,9\n".to_string()),
        ("a.csv", "t,a\n0,1\n".to_string()),
        (
            "d.csv",
            format!(
                "t_s,target,x_px,y_px\n{}",
                rows(400, &|i| format!(
                    "{},1,{},{}\n",
                    i as f64 / 100.0,
                    i % 3,
                    (i * 7) % 5
                ))
            ),
        ),
        (
            "a2.csv",
            format!(
                "t_s,base_acc,tip_acc\n{}",
                rows(100, &|i| format!(
                    "{},{},{}\n",
                    i as f64 / 1024.0,
                    i % 5,
                    i % 7
                ))
            ),
        ),
        (
            "ac.csv",
            format!(
                "t_s,c,tip_acc,d\n{}",
                rows(200, &|i| format!("{},1,{},2\n", i as f64 / 1024.0, i % 7))
            ),
        ),
        (
            "xy.csv",
            format!("x,y\n{}", rows(400, &|i| format!("{},{}\n", i % 5, i % 7))),
        ),
        (
            "f3.csv",
            format!(
                "t,a,b\n{}",
                rows(400, &|i| format!(
                    "{},{},{}\n",
                    i as f64 / 1000.0,
                    i % 5,
                    i % 7
                ))
            ),
        ),
    ];
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    std::fs::create_dir(dir.join("empty")).unwrap();
}

/// The binary with `args`, run in `dir`.
fn run_in(dir: &Path, args: &str) -> Output {
    Command::new(env!("CARGO_BIN_EXE_host-harness"))
        .current_dir(dir)
        .args(args.split_whitespace())
        .output()
        .unwrap()
}

/// The refusals, by the key each names: the command's arguments (in the inputs' folder).
const REFUSALS: &[(&str, &str)] = &[
    ("accel", "analyze --frames fr --fps 120 --accel a.csv --threshold 100 --out o"),
    ("accel_target", "analyze --frames fr --fps 120 --targets 2 --accel-target 5 --threshold 100 --out o"),
    ("adaptive_on", "study --adaptive-on zz --out o"),
    ("axis", "ema --response d.csv --excitation a.csv --axis x --out o"),
    ("bands", "modal --displacement d.csv --fps 100 --bands 30-60"),
    ("block_s", "ema --response a.csv --excitation a.csv --impact --block-s -1 --out o"),
    ("camera_model", "track --frames fr --fps 120 --targets 1 --threshold 100 --camera-model homography --out o"),
    ("compensate_exposure", "analyze --frames fr --fps 120 --accel a.csv --fs 100 --mm-per-px 0.1 --threshold 100 --compensate-exposure --out o"),
    ("detrend", "frf --input xy.csv --x x --y y --fs 100 --detrend linear --out f.csv"),
    ("delay_s", "ema --response a.csv --excitation a.csv --delay-s inf --out o"),
    ("excitation_col", "ema --response f3.csv --excitation f3.csv --out o"),
    ("poles", "ema --response a.csv --excitation a.csv --bands 1-2 --poles a.csv --out o"),
    ("excitation_fs", "ema --response a.csv --excitation a.csv --excitation-fs -1 --out o"),
    ("exp_window", "ema --response a.csv --excitation a.csv --exp-window 0.5 --out o"),
    ("exposure_ms", "analyze --frames fr --fps 120 --accel a2.csv --fs 1024 --mm-per-px 0.1 --threshold 100 --exposure-ms 20 --out o"),
    ("f_max_hz", "modal --displacement a.csv --fps 100 --f-max-hz 80"),
    ("f_min_hz", "modal --displacement d.csv --fps 100 --f-min-hz 80"),
    ("force", "track --frames fr --fps 120 --targets 1 --threshold 100 --out fr --force"),
    ("fps", "track --frames fr --targets 1 --threshold 100 --out o"),
    ("frame_range", "track --frames fr --fps 120 --targets 1 --threshold 100 --frame-range 5..20 --out o"),
    ("frames", "track --frames nowhere --fps 120 --targets 1 --threshold 100 --out o"),
    ("frames_shown", "pick --frames fr --fps 120 --frames-shown 99 --out o.html"),
    ("region", "pick --frames fr --fps 120 --region 1,1;2,1;2,2 --out o.html"),
    ("magnify_px", "analyze --frames fr --fps 120 --threshold 100 --magnify-px 101 --out o"),
    ("spacing", "pick --frames fr --fps 120 --region 0,0;40,0;40,40 --spacing 0.5 --out o.html"),
    ("window_px", "pick --frames fr --fps 120 --region 0,0;40,0;40,40 --window-px 4 --out o.html"),
    ("min_texture", "pick --frames fr --fps 120 --region 0,0;40,0;40,40 --min-texture 2 --out o.html"),
    ("points_out", "pick --frames fr --fps 120 --region 0,0;40,0;40,40 --points-out o.html --out o.html"),
    ("free", "calibrate --observed a.csv --out o"),
    ("from", "upsample --input a.csv --col a --from 10 --to 5 --out o.csv"),
    ("fs", "analyze --frames fr --fps 120 --accel a.csv --threshold 100 --out o"),
    ("roving", "ema --roving 1=a.csv --roving 1=a.csv --impact --out o"),
    ("geometry", "analyze --frames fr --fps 120 --threshold 100 --geometry a.csv --out o"),
    ("gate_px", "track --frames fr --fps 120 --points p.csv --gate-px 3 --threshold 10 --out o"),
    ("impact", "ema --response a.csv --excitation a.csv --exp-window 0.5 --out o"),
    ("input_col", "analyze --frames fr --fps 120 --accel ac.csv --fs 1024 --mm-per-px 0.1 --threshold 100 --input-col c --out o"),
    ("lost_frames", "track --frames fr --fps 120 --targets 1 --threshold 100 --lost-frames drop --out o"),
    ("max_order", "ema --response a.csv --excitation a.csv --max-order 500 --out o"),
    ("minutes", "simulate-field --minutes 0 --out o"),
    ("mm_per_px", "analyze --frames fr --fps 120 --accel a.csv --fs 100 --threshold 100 --out o"),
    (
        "nfft",
        "frf --input xy.csv --x x --y y --fs 100 --nperseg 64 --nfft 32 --out f.csv",
    ),
    (
        "noverlap",
        "frf --input xy.csv --x x --y y --fs 100 --nperseg 64 --noverlap 64 --out f.csv",
    ),
    ("nperseg", "modal --displacement d.csv --fps 100 --nperseg 8"),
    ("oblique_deg", "simulate-field --render --minutes 0.25 --oblique-deg 80 --out o"),
    ("out", "track --frames fr --fps 120 --targets 1 --threshold 100 --out fr"),
    ("output_col", "analyze --frames fr --fps 120 --accel ac.csv --fs 1024 --mm-per-px 0.1 --threshold 100 --input-col tip_acc --output-col d --out o"),
    ("points", "track --frames fr --fps 120 --points p.csv --gate-px 3 --threshold 10 --out o"),
    ("prominence_db", "modal --displacement d.csv --fps 100 --prominence-db -1"),
    ("read_noise", "simulate-field --render --minutes 0.25 --read-noise 100 --out o"),
    ("reference", "analyze --frames fr --fps 120 --accel a.csv --fs 100 --mm-per-px 0.1 --threshold 100 --reference p.csv --out o"),
    ("references", "simulate-field --render --minutes 0.25 --references 20 --out o"),
    ("render", "simulate-field --render --minutes 100 --out o"),
    ("response_col", "ema --response a.csv --excitation a.csv --response-col a --response-col a --out o"),
    ("response_fs", "ema --response a.csv --excitation a.csv --response-fs -1 --out o"),
    ("response_quantity", "ema --response a.csv --excitation a.csv --response-quantity zz --out o"),
    ("retime", "track --frames fr --fps 120 --retime --targets 1 --threshold 100 --out o"),
    ("rms_px", "simulate-field --render --minutes 0.25 --rms-px 100 --out o"),
    ("roi", "track --frames fr --fps 120 --points p.csv --roi 0,0,4,4 --threshold 10 --out o"),
    ("roll_deg", "simulate-field --render --minutes 0.25 --roll-deg 20 --out o"),
    ("runs", "calibrate --observed a.csv --free gain=1:2 --runs 1 --out o"),
    ("saturation", "centroid --threshold 100 --saturation 1000 fr/frame_0.png"),
    ("scale", "track --frames fr --fps 120 --targets 1 --threshold 10 --scale 1,1 --out o"),
    ("search_px", "track --frames fr --fps 120 --targets 1 --threshold 10 --search-px 20 --out o"),
    ("shake_hz", "simulate-field --render --minutes 0.25 --shake-hz 5,2 --out o"),
    ("shake_px", "simulate-field --render --minutes 0.25 --shake-px 50 --out o"),
    ("shape_reference", "analyze --frames fr --fps 120 --shape-reference a.csv --threshold 100 --out o"),
    ("shard", "study --shard 3/2 --out o"),
    ("ssi", "modal --displacement a.csv --fps 100 --ssi ref"),
    ("efdd_quantity", "modal --displacement a.csv --fps 100 --efdd-quantity jerk"),
    ("plscf", "modal --displacement d.csv --fps 100 --nperseg 64 --f-min-hz 48 --plscf --out m"),
    ("setup", "modal --displacement a.csv --fps 100 --setup a.csv:1 --out m"),
    ("merge", "modal --displacement a.csv --fps 100 --merge preger --out m"),
    ("ssi_block_rows", "modal --displacement a.csv --fps 100 --ssi-block-rows 1000"),
    ("ssi_max_order", "modal --displacement a.csv --fps 100 --ssi-max-order 1000"),
    ("target_size_mm", "analyze --frames fr --fps 120 --accel a.csv --fs 100 --mm-per-px 0.1 --threshold 100 --target-size-mm 3 --out o"),
    ("targets", "track --frames fr --fps 120 --targets 40 --threshold 1 --out o"),
    ("threshold", "track --frames fr --fps 120 --targets 1 --out o"),
    ("tick_hz", "analyze --frames fr --fps 120 --accel a.csv --fs 100 --mm-per-px 0.1 --threshold 100 --tick-hz -1 --out o"),
    ("tick_offset", "analyze --frames fr --fps 120 --accel a.csv --fs 100 --mm-per-px 0.1 --threshold 100 --tick-offset 5 --out o"),
    ("time_offset_s", "analyze --frames fr --fps 120 --accel a.csv --fs 100 --mm-per-px 0.1 --threshold 100 --time-offset-s nan --out o"),
    ("times", "render --times 99999 --out o"),
    ("to", "upsample --input a.csv --col a --from 10 --to 15 --out o.csv"),
    ("tracker", "track --frames fr --fps 120 --targets 2 --tracker lk --out o"),
    ("twin", "analyze --frames fr --fps 120 --targets 2 --threshold 100 --twin 3 --out o"),
    ("window", "frf --input xy.csv --x x --y y --fs 100 --window tukey --out f.csv"),
    ("world", "analyze --frames fr --fps 120 --accel a.csv --fs 100 --mm-per-px 0.1 --threshold 100 --world a.csv --out o"),
    ("x", "centroid --threshold 100 fr/frame_0.png --x zz"),
    ("y", "centroid --threshold 100 fr/frame_0.png --y zz"),
];

/// Keys no single command refuses from small inputs, and why; each is checked where it is.
const NOT_WALKED: &[(&str, &str)] = &[
    // a warning on standard error (the study runs with fewer threads), not a refusal
    ("threads", "sim/src/study/runner.rs worker_threads"),
];

#[test]
fn every_setting_the_library_names_is_refused_in_the_command_lines_words() {
    use host_harness::setting::KEYS;
    let tmp = tempfile::tempdir().unwrap();
    inputs(tmp.path());
    // `--resume` needs a study to resume: a two-run one
    let s = run_in(tmp.path(), "study --runs 2 --out s");
    assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
    let resume = ("resume", "study --resume --runs 1 --out s");
    let mut missing = Vec::new();
    for key in KEYS {
        if !REFUSALS.iter().chain([&resume]).any(|(k, _)| k == key)
            && !NOT_WALKED.iter().any(|(k, _)| k == key)
        {
            missing.push(*key);
        }
    }
    assert!(missing.is_empty(), "no refusal walked for {missing:?}");
    let mut wrong = Vec::new();
    for (key, args) in REFUSALS.iter().chain([&resume]) {
        let o = run_in(tmp.path(), args);
        let e = String::from_utf8_lossy(&o.stderr);
        let flag = format!("--{}", key.replace('_', "-"));
        let unspelled = e.contains(&format!("${key}"))
            || e.match_indices('$')
                .any(|(i, _)| e[i + 1..].starts_with(|c: char| c.is_ascii_lowercase()));
        if o.status.code() != Some(2) || !e.contains(&flag) || unspelled {
            wrong.push(format!("{key}: `{args}`: exit {:?}: {e}", o.status.code()));
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// The settings table declares each shared setting once; every flag of a command that the
/// table has a row for takes its help, its default and its range from that row (a flag
/// declared by hand beside the table fails here): clap's help is the row's, its default the
/// row's `Given`, its choices the row's, and a value just past either end of the row's range
/// is refused while the ends themselves (where closed) are taken.
#[test]
fn every_flag_the_settings_table_declares_takes_its_row() {
    use clap::CommandFactory as _;
    use host_harness::setting::table::{self, Bound, DefaultValue, Values};
    use host_harness::setting::Naming;
    let cli = host_harness::cli::Cli::command();
    let mut checked = 0;
    let mut wrong = Vec::new();
    for sub in cli.get_subcommands() {
        for arg in sub.get_arguments() {
            let Some(long) = arg.get_long() else { continue };
            let names: Vec<String> = std::iter::once(long.to_string())
                .chain(
                    arg.get_all_aliases()
                        .unwrap_or_default()
                        .into_iter()
                        .map(str::to_string),
                )
                .collect();
            let Some(row) = names
                .iter()
                .find_map(|n| table::find(sub.get_name(), &n.replace('-', "_")))
            else {
                continue;
            };
            let at = format!("{} --{long}", sub.get_name());
            let help = arg.get_help().map(|h| h.to_string()).unwrap_or_default();
            if help != row.help_for(Naming::Cli) {
                wrong.push(format!("{at}: help is not its row's: {help}"));
            }
            let defaults: Vec<String> = arg
                .get_default_values()
                .iter()
                .map(|d| d.to_string_lossy().into_owned())
                .collect();
            let want: Vec<String> = match row.default {
                DefaultValue::Given(d) => vec![d.to_string()],
                _ => vec![],
            };
            if defaults != want {
                wrong.push(format!("{at}: default {defaults:?}, the row says {want:?}"));
            }
            if let Values::Choice(choices) = row.values {
                let got: Vec<String> = arg
                    .get_possible_values()
                    .iter()
                    .map(|p| p.get_name().to_string())
                    .collect();
                if got != choices {
                    wrong.push(format!("{at}: choices {got:?}, the row says {choices:?}"));
                }
            }
            // the range: ends taken, just past them refused (clap's own value check)
            let parse = |v: String| {
                cli.clone()
                    .try_get_matches_from([
                        "host-harness",
                        sub.get_name(),
                        &format!("--{long}={v}"),
                    ])
                    .map_err(|e| e.kind())
            };
            let refused =
                |v: String| parse(v).err() == Some(clap::error::ErrorKind::ValueValidation);
            let mut ends: Vec<(f64, bool)> = Vec::new();
            match row.values {
                Values::Whole { min, max } => {
                    ends.extend([(min as f64, true), (max as f64, true)]);
                    if min > 0 {
                        ends.push((min as f64 - 1.0, false));
                    }
                    ends.push((max as f64 + 1.0, false));
                }
                Values::Number { min, max } => {
                    for (b, step) in [(min, -1e-9), (max, 1e-9)] {
                        match b {
                            Bound::Closed(x) => {
                                ends.extend([(x, true), (x + step * x.abs().max(1.0), false)])
                            }
                            Bound::Open(x) => ends.push((x, false)),
                            Bound::Free => {}
                        }
                    }
                    ends.push((f64::NAN, false));
                }
                _ => {}
            }
            for (v, taken) in ends {
                if refused(format!("{v}")) == taken {
                    wrong.push(format!(
                        "{at}={v}: {} (row: {})",
                        if taken { "refused" } else { "taken" },
                        row.range()
                    ));
                }
            }
            checked += 1;
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    assert!(checked >= 50, "only {checked} flags checked");
}

/// docs/settings.md is the settings table written out (`VIBCAM_BLESS=1` writes it).
#[test]
fn docs_settings_md_is_the_settings_table() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/settings.md");
    let want = host_harness::setting::table::markdown();
    if std::env::var_os("VIBCAM_BLESS").is_some() {
        std::fs::write(&path, &want).unwrap();
    }
    let got = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        got == want,
        "docs/settings.md is not the settings table: VIBCAM_BLESS=1 cargo test --test settings"
    );
}
