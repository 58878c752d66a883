//! The defects found attacking `ema`, the DAQ readers, `pick`, camera motion and frame ranges
//! as hostile and careless new users would: each was a lost file, a crash or a silently wrong
//! number on the command line, each now an error naming its cause, a named warning or a right
//! answer. (Readers' and parsers' own cases are unit tests beside them: `daq::tdms`, `daq::lvm`,
//! `daq::npy`, `daq::uff`, `analysis::ema::impact`, `outdir`, `setting`.)

use crate::analyze::{make_recording, Recording};
use crate::util::assert_says;
use crate::util::{
    analyze_recording, assert_exit_2, assert_ok, harness, render_cantilever, stderr,
};
use crate::util::{path_words, words};
use std::path::{Path, PathBuf};

/// `simulate-hammer` into `dir` (a short record: two hits).
fn hammer(dir: &Path) {
    assert_ok(&harness(&words(
        "simulate-hammer --out {} --seconds 6.2 --peaks-n 150,120",
        &[dir.to_str().unwrap()],
    )));
}

/// `ema` of `response` over `excitation` (column `force_n` unless `extra` names one) into
/// `out`, an impact test below 200 Hz.
fn ema(response: &Path, excitation: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = path_words(
        "ema --response {} --excitation {} --impact --out {} --force",
        &[response, excitation, out],
        &[],
    );
    if !extra.contains(&"--exp-window") {
        args.extend_from_slice(&["--exp-window", "off"]);
    }
    if !extra.contains(&"--excitation-col") {
        args.extend_from_slice(&["--excitation-col", "force_n"]);
    }
    if !extra.contains(&"--f-max-hz") {
        args.extend_from_slice(&["--f-max-hz", "200"]);
    }
    args.extend_from_slice(extra);
    harness(&args)
}

/// The rows of a CSV file as its cells.
fn cells(path: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

/// A little NumPy `.npy` (version 1) of little-endian f8 `values` with `shape`, its `descr`
/// given.
fn npy(path: &Path, descr: &str, shape: &str, values: &[f64]) {
    let h = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(path, vibcam_readers::daq::npy::encode_v1(&h, &data)).unwrap();
}

/// `pick --frames FRAMES --out OUT --force`: a page asked to replace `out`.
fn pick_over(frames: &str, out: &str) -> std::process::Output {
    harness(&words("pick --frames {} --out {} --force", &[frames, out]))
}

#[test]
fn pick_never_writes_over_its_inputs_and_its_page_holds_any_file_name_and_large_frames() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = tmp.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    // a name that once kept the page's data block from closing (its script never ran)
    for k in 0..3 {
        let img = image::GrayImage::from_fn(3000, 2400, |x, y| {
            image::Luma([((x / 50 + y / 50 + k) % 2 * 200) as u8])
        });
        img.save(frames.join(format!("f<!--<script>_{k:05}.png")))
            .unwrap();
    }
    let points = tmp.path().join("points.csv");
    std::fs::write(&points, "target,x,y,w,h\n1,100,100,21,21\n").unwrap();
    let before = std::fs::read(&points).unwrap();
    let f = frames.to_str().unwrap();
    let o = harness(&words(
        "pick --frames {} --points {} --out {} --force",
        &[f, points.to_str().unwrap(), points.to_str().unwrap()],
    ));
    assert_exit_2(&o, "is the input");
    assert_eq!(std::fs::read(&points).unwrap(), before);
    let frame = frames.join("f<!--<script>_00001.png");
    let frame_bytes = std::fs::read(&frame).unwrap();
    let o = pick_over(f, frame.to_str().unwrap());
    assert_exit_2(&o, "an input of this run");
    assert_eq!(std::fs::read(&frame).unwrap(), frame_bytes);
    // anyone's file elsewhere (a camera's raw data beside its header): only a page `pick`
    // wrote is replaced
    let raw = tmp.path().join("rec.mraw");
    std::fs::write(&raw, [7u8; 64]).unwrap();
    let o = pick_over(f, raw.to_str().unwrap());
    assert_exit_2(&o, "is not a page `pick` wrote");
    assert_eq!(std::fs::read(&raw).unwrap(), [7u8; 64]);
    // the page: its data block closes (no `<` inside it), the frames shown at most 2048 px
    // wide, the clicks' coordinates the frame's own (3000 x 2400)
    let page = tmp.path().join("pick.html");
    assert_ok(&harness(&words(
        "pick --frames {} --out {}",
        &[f, page.to_str().unwrap()],
    )));
    let html = std::fs::read_to_string(&page).unwrap();
    let start = html.find("id=\"pick-data\">").unwrap() + "id=\"pick-data\">".len();
    let data = &html[start..start + html[start..].find("</script>").unwrap()];
    assert!(!data.contains('<'), "the data block holds a `<`");
    let json: serde_json::Value = serde_json::from_str(data).unwrap();
    assert_eq!(
        (json["width"].as_u64(), json["height"].as_u64()),
        (Some(3000), Some(2400))
    );
    assert!(json["frames"][0]["label"]
        .as_str()
        .unwrap()
        .contains("<!--"));
    let png = json["frames"][0]["png"].as_str().unwrap();
    let shown = image::load_from_memory(&decode_base64(png)).unwrap();
    assert_eq!((shown.width(), shown.height()), (2048, 1638));
}

/// Standard base64 decoded (the page's inline PNGs).
fn decode_base64(s: &str) -> Vec<u8> {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = Vec::new();
    let (mut acc, mut bits) = (0u32, 0);
    for c in s.bytes().filter(|c| *c != b'=') {
        let v = T.iter().position(|t| *t == c).unwrap() as u32;
        acc = (acc << 6) | v;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    out
}

#[test]
fn a_folder_that_only_bears_a_staging_name_is_never_removed() {
    let tmp = tempfile::tempdir().unwrap();
    let notes = tmp.path().join(".res.old-2023");
    std::fs::create_dir(&notes).unwrap();
    std::fs::write(notes.join("n.txt"), "notes").unwrap();
    hammer(&tmp.path().join("res"));
    assert_eq!(
        std::fs::read_to_string(notes.join("n.txt")).unwrap(),
        "notes"
    );
}

#[test]
fn hammer_files_as_careless_users_give_them_are_refused_named_or_read() {
    let tmp = tempfile::tempdir().unwrap();
    let h = tmp.path().join("h");
    hammer(&h);
    let (camera, force) = (h.join("camera.csv"), h.join("force.csv"));
    let out = tmp.path().join("e");
    // the reference run
    let o = ema(&camera, &force, &out, &[]);
    assert_ok(&o);
    assert!(stderr(&o).contains("outputs in"), "{}", stderr(&o));
    let modes = cells(&out.join("modes.csv"));
    assert_eq!(modes.len(), 4, "{modes:?}");

    // a block shorter than the samples kept before a pulse (a panic)
    assert_exit_2(
        &ema(&camera, &force, &out, &["--block-s", "0.01"]),
        "--block-s 0.01",
    );
    // overlapping bands, an exponential window that damps every mode away, bands outside
    // the band analysed
    assert_exit_2(
        &ema(&camera, &force, &out, &["--bands", "15-70,50-130"]),
        "overlap",
    );
    assert_exit_2(
        &ema(&camera, &force, &out, &["--exp-window", "1e-300"]),
        "'1e-300' for '--exp-window",
    );
    assert_exit_2(
        &ema(
            &camera,
            &force,
            &out,
            &["--bands", "20-30", "--f-min-hz", "50"],
        ),
        "reaches outside the band analysed",
    );
    // one response named twice would be two identical responses
    assert_exit_2(
        &ema(
            &camera,
            &force,
            &out,
            &["--response-col", "p1", "--response-col", "p1"],
        ),
        "--response-col p1 is given twice",
    );

    // a force and responses without time columns at rates 10^6 apart (an abort allocating
    // 74 GB, or "capacity overflow")
    let text = std::fs::read_to_string(&force).unwrap();
    let bare: String = text
        .lines()
        .map(|l| l.split(',').nth(1).unwrap().to_string() + "\n")
        .collect();
    let bare_force = tmp.path().join("bare_force.csv");
    std::fs::write(&bare_force, &bare).unwrap();
    let o = ema(
        &camera,
        &bare_force,
        &out,
        &["--excitation-fs", "1e9", "--response-fs", "2000"],
    );
    assert_exit_2(&o, "at most");
    // a time column in microseconds read as seconds: the same bound, named
    let us: String = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 0 {
                format!("{l}\n")
            } else {
                let (t, f) = l.split_once(',').unwrap();
                format!("{},{f}\n", t.parse::<f64>().unwrap() * 1e6)
            }
        })
        .collect();
    let us_force = tmp.path().join("us.csv");
    std::fs::write(&us_force, us).unwrap();
    let o = ema(&camera, &us_force, &out, &[]);
    assert_exit_2(&o, "a time column in ms or us read as seconds");

    // a UTF-8 byte-order mark (Excel's "CSV UTF-8") and quoted names: the time column found
    let quoted = format!(
        "\u{feff}{}",
        text.replacen("t_s,force_n", "\"t_s\",\"force_n\"", 1)
    );
    let bom_force = tmp.path().join("bom.csv");
    std::fs::write(&bom_force, quoted).unwrap();
    let o = ema(&camera, &bom_force, &tmp.path().join("bom"), &[]);
    assert_ok(&o);
    assert_eq!(cells(&tmp.path().join("bom/modes.csv")), modes);

    // times rounded to fewer digits than the rate needs: read, and a rate given exactly wins
    let h3 = tmp.path().join("h3");
    assert_ok(&harness(&words(
        "simulate-hammer --out {} --seconds 3.7 --peaks-n 150 --camera-hz 3000",
        &[h3.to_str().unwrap()],
    )));
    let rounded: String = std::fs::read_to_string(h3.join("camera.csv"))
        .unwrap()
        .lines()
        .enumerate()
        .map(|(i, l)| match (i, l.split_once(',')) {
            (0, _) | (_, None) => format!("{l}\n"),
            (_, Some((t, rest))) => format!("{:.5},{rest}\n", t.parse::<f64>().unwrap()),
        })
        .collect();
    let rounded_file = tmp.path().join("rounded.csv");
    std::fs::write(&rounded_file, rounded).unwrap();
    let o = ema(
        &rounded_file,
        &h3.join("force.csv"),
        &tmp.path().join("r"),
        &["--response-fs", "3000"],
    );
    assert_ok(&o);
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("the rate given, 3000 Hz, used"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );

    // two channels of one name: refused, naming it (response 2 was a copy of response 1)
    let cam = std::fs::read_to_string(&camera).unwrap();
    let dup = cam.replacen("p2", "p1", 1);
    let dup_file = tmp.path().join("dup.csv");
    std::fs::write(&dup_file, dup).unwrap();
    assert_exit_2(
        &ema(&dup_file, &force, &out, &[]),
        "two channels are named `p1`",
    );

    // the force's channel among the responses: left out when every channel is taken, refused
    // when named
    let both = tmp.path().join("both.csv");
    let mut rows = String::new();
    let cam_rows: Vec<&str> = cam.lines().collect();
    for (i, l) in text.lines().enumerate() {
        // the force's rows at 50 kHz, each beside the camera's row of its time (held)
        let c = cam_rows[if i == 0 {
            0
        } else {
            (1 + (i - 1) / 25).min(cam_rows.len() - 1)
        }];
        rows.push_str(&format!("{l},{}\n", c.split_once(',').unwrap().1));
    }
    std::fs::write(&both, rows).unwrap();
    // the force's file as the responses too: its only channel is the force
    assert_exit_2(
        &ema(&force, &force, &out, &[]),
        "its only channel is the force",
    );
    let o = ema(&both, &both, &tmp.path().join("both"), &[]);
    assert_says(&o, &["the force's channel `force_n` left out"]);
    assert_exit_2(
        &ema(&both, &both, &out, &["--response-col", "force_n"]),
        "the force's own channel",
    );

    // a non-finite response and an empty one, in .npy files
    let n = cam.lines().count() - 1;
    let mut v: Vec<f64> = (0..2 * n).map(|k| (k as f64 * 0.01).sin()).collect();
    v[n + 7] = f64::NAN;
    let nan = tmp.path().join("nan.npy");
    npy(&nan, "<f8", &format!("(2, {n})"), &v);
    assert_exit_2(
        &ema(&nan, &force, &out, &["--response-fs", "2000"]),
        "response channel `point 2`, sample 8: not a finite number",
    );
    let empty = tmp.path().join("empty.npy");
    npy(&empty, "<f8", "(5, 0, 2)", &[]);
    assert_exit_2(
        &ema(&empty, &force, &out, &["--response-fs", "2000"]),
        "holds no samples",
    );
    let accented = tmp.path().join("accented.npy");
    npy(&accented, "<fé", "(2,)", &[0.0, 0.0]);
    assert_exit_2(
        &ema(&accented, &force, &out, &["--response-fs", "2000"]),
        "data type",
    );

    // a response rate given ten times too low: the records' lengths disagree, named
    let bare_cam: String = cam
        .lines()
        .map(|l| l.split_once(',').unwrap().1.to_string() + "\n")
        .collect();
    let bare_camera = tmp.path().join("bare_camera.csv");
    std::fs::write(&bare_camera, bare_cam).unwrap();
    let o = ema(
        &bare_camera,
        &force,
        &tmp.path().join("slow"),
        &["--response-fs", "1000", "--f-max-hz", "150"],
    );
    let report = String::from_utf8_lossy(&o.stdout);
    assert!(
        report.contains("warning: the responses last 12.4") && report.contains("the force 6.2"),
        "{report}{}",
        stderr(&o)
    );
}

#[test]
fn a_force_in_g_and_a_labview_file_cut_short_are_named() {
    let tmp = tempfile::tempdir().unwrap();
    let h = tmp.path().join("h");
    hammer(&h);
    let force = std::fs::read_to_string(h.join("force.csv")).unwrap();
    // the force as a LabVIEW file whose channel states `g`
    let mut lvm = String::from(
        "LabVIEW Measurement\t\nWriter_Version\t2\nSeparator\tTab\nDecimal_Separator\t.\n\
         Multi_Headings\tYes\nX_Columns\tNo\n***End_of_Header***\t\n\t\nChannels\t1\t\n",
    );
    let n = force.lines().count() - 1;
    lvm.push_str(&format!(
        "Samples\t{n}\t\nY_Unit_Label\tg\t\nX0\t0\t\nDelta_X\t2E-5\t\n***End_of_Header***\t\t\n\
         X_Value\tforce_n\tComment\n"
    ));
    for l in force.lines().skip(1) {
        lvm.push_str(&format!("\t{}\n", l.split(',').nth(1).unwrap()));
    }
    let g = tmp.path().join("force_g.lvm");
    std::fs::write(&g, &lvm).unwrap();
    let out = tmp.path().join("e");
    assert_exit_2(
        &ema(&h.join("camera.csv"), &g, &out, &[]),
        "a unit of acceleration, not of a force",
    );
    // `head -c`: the last value cut inside its digits
    let cut = tmp.path().join("cut.lvm");
    std::fs::write(
        &cut,
        &lvm.replace("Y_Unit_Label\tg", "Y_Unit_Label\tN")[..lvm.len() - 3],
    )
    .unwrap();
    assert_exit_2(
        &ema(&h.join("camera.csv"), &cut, &out, &[]),
        "ends inside a line",
    );
}

/// A TDMS file of one segment: a float64 channel `force_n` at 50 kHz with `wf_start_time`, a
/// unit longer than a universal file's field, and a timestamp property on the root.
fn tdms_force(path: &Path, values: &[f64], unit: &str) {
    let stamp = |secs: i64| {
        let mut v = 0u64.to_le_bytes().to_vec();
        v.extend(secs.to_le_bytes());
        v
    };
    let mut unit_bytes = (unit.len() as u32).to_le_bytes().to_vec();
    unit_bytes.extend(unit.as_bytes());
    let objects = [
        ("/", None, vec![("DateTime", 0x44, stamp(3_800_000_000))]),
        (
            "/'Untitled'/'force_n'",
            Some((10, values.len() as u64)),
            vec![
                ("wf_increment", 10, 2e-5f64.to_le_bytes().to_vec()),
                ("wf_start_time", 0x44, stamp(3_800_000_000)),
                ("unit_string", 0x20, unit_bytes),
            ],
        ),
    ];
    let raw: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(path, vibcam_readers::daq::tdms::encode_le(&objects, &raw)).unwrap();
}

#[test]
fn an_ni_waveform_with_timestamps_and_a_long_unit_is_analysed() {
    let tmp = tempfile::tempdir().unwrap();
    let h = tmp.path().join("h");
    hammer(&h);
    let force: Vec<f64> = std::fs::read_to_string(h.join("force.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
        .collect();
    let tdms = tmp.path().join("force.tdms");
    tdms_force(&tdms, &force, "N (load cell 208C02, calibrated)");
    let out = tmp.path().join("e");
    let o = ema(&h.join("camera.csv"), &tdms, &out, &[]);
    assert_says(&o, &["is cut to its first 20 characters in frf.uff"]);
    let uff = std::fs::read_to_string(out.join("frf.uff")).unwrap();
    assert!(
        uff.contains("N (load cell 208C02,"),
        "the unit cut to its field"
    );
    assert_eq!(cells(&out.join("modes.csv")).len(), 4);
    // an empty universal file as the force
    let empty = tmp.path().join("empty.uff");
    std::fs::write(&empty, "    -1\n    -1\n").unwrap();
    assert_exit_2(
        &ema(
            &h.join("camera.csv"),
            &empty,
            &out,
            &["--excitation-col", ""],
        ),
        "holds no channel that can be read as a force",
    );
}

#[test]
fn simulate_hammer_refuses_what_would_give_no_usable_record() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("h");
    let o = out.to_str().unwrap();
    for (flags, needle) in [
        (vec!["--clip-n", "0"], "--clip-n must be a positive force"),
        (vec!["--clip-n=-5"], "--clip-n must be a positive force"),
        (vec!["--clip-n", "NaN"], "--clip-n must be a positive force"),
        (vec!["--daq-hz", "1000"], "--daq-hz 1000"),
        (vec!["--seconds", "0.001"], "--seconds 0.001"),
        (
            vec!["--double-hit", "--peaks-n", "100"],
            "give two peaks or more",
        ),
    ] {
        let mut args = vec!["simulate-hammer", "--out", o];
        args.extend(flags);
        assert_exit_2(&harness(&args), needle);
        assert!(!out.exists());
    }
}

/// `analyze` of `rec` with an accelerometer into `out`, frames `range`.
fn analyze_range(rec: &Recording, out: &Path, range: &str) -> std::process::Output {
    crate::analyze::analyze_hand(
        rec,
        &rec.frames,
        &[
            "--threshold",
            "0",
            "--mode",
            "weighted",
            "--window",
            "rect",
            "--no-end-match",
            "--bands",
            "6-10,27-33",
            "--frame-range",
            range,
            "--out",
            out.to_str().unwrap(),
        ],
    )
}

#[test]
fn a_frame_range_keeps_the_recordings_own_times() {
    // 2 s of frames and samples; frames 121..240 are the second second
    let (_tmp, rec) = make_recording(240, 4096);
    let out = rec.dir.join("second");
    let o = analyze_range(&rec, &out, "121..240");
    assert_ok(&o);
    let report = std::fs::read_to_string(out.join("report.txt")).unwrap();
    assert!(
        report.contains("first frame analysed (frame 121 of the recording) at 1 s after"),
        "{report}"
    );
    // the vision modes agree with the accelerometer's (frame 121 paired with t = 1 s, not 0)
    let m = cells(&out.join("modes.csv"));
    let col = |name: &str| m[0].iter().position(|c| c == name).unwrap();
    let (sys, f, a) = (col("system"), col("f_hz"), col("amplitude"));
    for mode in 1..=2 {
        let acc = &m[mode];
        let vis = &m[mode + 2];
        assert_eq!(
            (acc[sys].as_str(), vis[sys].as_str()),
            ("accelerometer", "vision")
        );
        assert_eq!(acc[f], vis[f]);
        let (x, y): (f64, f64) = (acc[a].parse().unwrap(), vis[a].parse().unwrap());
        assert!((y / x - 1.0).abs() < 0.02, "mode {mode}: vision {y} vs {x}");
    }
    // track: t_s of the range's first frame is its time in the recording
    let t = rec.dir.join("t");
    assert_ok(&harness(&words(
        "track --frames {} --fps 120 --threshold 100 --frame-range 61..120 --targets 1 --out {}",
        &[rec.frames.to_str().unwrap(), t.to_str().unwrap()],
    )));
    let d = cells(&t.join("displacement.csv"));
    assert_eq!(d[1][1].parse::<f64>().unwrap(), 0.5);
    assert_eq!(d.len(), 61);
}

#[test]
fn stray_files_are_named_and_a_point_lost_in_every_frame_is_an_error() {
    let (_tmp, rec) = make_recording(30, 512);
    for stray in ["notes.txt", "Thumbs.db", "frame_3 (copy).png"] {
        std::fs::write(rec.frames.join(stray), "x").unwrap();
    }
    let points = rec.dir.join("points.csv");
    // target 2's window on black: no blob there in any frame
    std::fs::write(&points, "target,x,y,w,h\n1,12,24,21,41\n2,3,3,5,5\n").unwrap();
    let out = rec.dir.join("t");
    let track = |extra: &[&str]| {
        let mut args = words(
            "track --frames {} --fps 120 --threshold 100 --out {} --force",
            &[rec.frames.to_str().unwrap(), out.to_str().unwrap()],
        );
        args.extend_from_slice(extra);
        harness(&args)
    };
    let p = points.to_str().unwrap();
    // a threshold names what tracks a window it cannot separate
    let o = track(&["--points", p, "--tracker", "blob"]);
    assert_exit_2(&o, "target(s) 2 of 2 lost in every one of the 30 frames");
    assert!(stderr(&o).contains("--tracker lk"), "{}", stderr(&o));
    // the default hands the window to Lucas-Kanade, which finds it flat: named, exit 2
    let o = track(&["--points", p]);
    assert_exit_2(&o, "target(s) 2 of 2 lost in every one of the 30 frames");
    assert!(
        stderr(&o).contains("(flat)") && stderr(&o).contains("Lucas-Kanade"),
        "{}",
        stderr(&o)
    );
    for stray in ["notes.txt", "Thumbs.db", "frame_3 (copy).png"] {
        assert!(
            stderr(&o).contains(stray),
            "{stray} not named: {}",
            stderr(&o)
        );
    }
    // without a scale, --axis x is the axis the report follows
    let o = track(&["--targets", "1", "--axis", "x"]);
    assert_ok(&o);
    assert!(
        stderr(&o).contains(&format!("outputs in {}", out.display())),
        "{}",
        stderr(&o)
    );
}

#[test]
fn references_and_plane_points_the_camera_model_cannot_use_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let rec = tmp.path().join("rec");
    assert_ok(&harness(&words(
        "simulate-field --render --minutes 0.25 --references 4 --oblique-deg 30 --out {}",
        &[rec.to_str().unwrap()],
    )));
    let out = tmp.path().join("out");
    let track = |extra: &[&str]| crate::view::track(&rec, &out, extra);
    let write = |name: &str, text: String| -> PathBuf {
        let p = tmp.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let refs: Vec<String> = std::fs::read_to_string(rec.join("references.csv"))
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect();
    let row = |i: usize| refs[i].split_once(',').unwrap().1.to_string();
    // four on one line for a homography, and nearly so: the fourth 2 px off the others' line
    for (y4, needle) in [(10, "lie on one line"), (12, "no four of them stand apart")] {
        let refs = write(
            "line.csv",
            format!("target,x,y,w,h\n1,40,10,9,9\n2,80,10,9,9\n3,120,10,9,9\n4,160,{y4},9,9\n"),
        );
        let o = track(&[
            "--reference",
            refs.to_str().unwrap(),
            "--camera-model",
            "homography",
        ]);
        assert_exit_2(&o, needle);
    }
    // two windows on the same spot, and one 1 px beside another
    let twice = write(
        "twice.csv",
        format!("target,x,y,w,h\n1,{}\n2,{}\n", row(1), row(1)),
    );
    assert_exit_2(
        &track(&["--reference", twice.to_str().unwrap()]),
        "overlapping windows",
    );
    // a reference on a target's window
    let target = std::fs::read_to_string(rec.join("points.csv")).unwrap();
    let on = target
        .lines()
        .nth(2)
        .unwrap()
        .split_once(',')
        .unwrap()
        .1
        .to_string();
    let on_target = write("on.csv", format!("target,x,y,w,h\n1,{}\n2,{on}\n", row(1)));
    assert_exit_2(
        &track(&["--reference", on_target.to_str().unwrap()]),
        "overlaps target 2's window",
    );
    // plane points: one listed twice with other plane coordinates, one measured on an image
    // of another resolution, an uncertainty larger than their spacing
    let world: Vec<String> = std::fs::read_to_string(rec.join("world.csv"))
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect();
    let header = &world[0];
    let p: Vec<Vec<f64>> = world[1..]
        .iter()
        .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
        .collect();
    let rows = |ps: &[Vec<f64>]| -> String {
        let mut s = format!("{header}\n");
        for q in ps {
            s.push_str(
                &q.iter()
                    .map(|v| v.to_string())
                    .collect::<Vec<_>>()
                    .join(","),
            );
            s.push('\n');
        }
        s
    };
    let mut twice = p.clone();
    let mut again = p[0].clone();
    again[2] += 300.0;
    again[0] += 0.2;
    twice.push(again);
    let o = track(&["--world", write("w1.csv", rows(&twice)).to_str().unwrap()]);
    assert_exit_2(&o, "a point listed twice");
    let mut far = p.clone();
    far.push(vec![1e6, 1e6, p[0][2] + 1.0, p[0][3] + 1.0]);
    let far: Vec<Vec<f64>> = far
        .into_iter()
        .map(|mut q| {
            q.truncate(4);
            q
        })
        .collect();
    let far_header = header.split(',').take(4).collect::<Vec<_>>().join(",");
    let mut s = format!("{far_header}\n");
    for q in &far {
        s.push_str(
            &q.iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(","),
        );
        s.push('\n');
    }
    let o = track(&["--world", write("w2.csv", s).to_str().unwrap()]);
    assert_exit_2(&o, "outside the");
    let mut s = String::from("x,y,x_mm,y_mm,u_px\n");
    for q in &p {
        s.push_str(&format!("{},{},{},{},1000000\n", q[0], q[1], q[2], q[3]));
    }
    let o = track(&["--world", write("w3.csv", s).to_str().unwrap()]);
    assert_exit_2(&o, "u_px 1000000");
}

#[test]
fn an_interval_never_leaves_its_quantitys_domain() {
    // short Welch segments: 2 Hz lines cannot place the 7.1 Hz mode; its symmetric frequency
    // interval reached -0.75 Hz
    let tmp = tempfile::tempdir().unwrap();
    let rec = tmp.path().join("rec");
    render_cantilever(&rec, &[]);
    let out = tmp.path().join("a");
    let o = analyze_recording(
        &rec,
        "frames",
        &["--nperseg", "1024", "--out", out.to_str().unwrap()],
    );
    assert_ok(&o);
    let m = cells(&out.join("modes.csv"));
    for name in ["f_hz_lo", "damping_lo", "amplitude_lo"] {
        let c = m[0].iter().position(|h| h == name).unwrap();
        for row in &m[1..] {
            if let Ok(v) = row[c].parse::<f64>() {
                assert!(v >= 0.0, "{name} {v} in {row:?}");
            }
        }
    }
    let report = String::from_utf8_lossy(&o.stdout);
    assert!(
        report.contains("the 95 % interval of its frequency reaches 0 Hz"),
        "{report}"
    );
}
