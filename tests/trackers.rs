//! The trackers of `--points` windows side by side: blob and weighted centroids and
//! Lucas-Kanade (`--tracker lk`), against the exact motion a recording's `truth.csv` states,
//! and every way Lucas-Kanade loses a target: a flag and a lost frame, never a wrong position.

use crate::util::{assert_contains, assert_says};
use crate::util::{assert_exit_2, assert_ok, harness, path_words, render_cantilever, words};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// `(frame, target) -> (x, y)` from a recording's truth.csv.
fn truth(dir: &Path) -> HashMap<(usize, usize), (f64, f64)> {
    let text = std::fs::read_to_string(dir.join("truth.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("frame,target,x_px,y_px"));
    lines
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            (
                (c[0].parse().unwrap(), c[1].parse().unwrap()),
                (c[2].parse().unwrap(), c[3].parse().unwrap()),
            )
        })
        .collect()
}

/// One row of displacement.csv: `(frame, target, cx, cy, flags, lost)` (`cx, cy` NaN when
/// empty).
type Row = (usize, usize, f64, f64, u8, bool);

fn displacement(out: &Path) -> Vec<Row> {
    let text = std::fs::read_to_string(out.join("displacement.csv")).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    // Lucas-Kanade writes each position's evidence: score, forward-backward, the check
    let evidence = header == "frame,t_s,target,cx,cy,pixels,flags,disp_mm,lost,score,fb_px,check";
    assert!(
        evidence || header == "frame,t_s,target,cx,cy,pixels,flags,disp_mm,lost",
        "{header}"
    );
    lines
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            let num = |s: &str| s.parse::<f64>().unwrap_or(f64::NAN);
            if evidence {
                // a position the checks took away is a lost frame without a position; a score
                // is a ZNCC, a forward-backward disagreement within its bound where it stands
                let (score, fb, check) = (num(c[9]), num(c[10]), c[11]);
                assert!(check.is_empty() || (c[3].is_empty() && c[8] == "1"), "{l}");
                assert!(score.is_nan() || (-1.0..=1.0).contains(&score), "{l}");
                assert!(
                    fb.is_nan() || fb <= 1.0 || check == "forward-backward",
                    "{l}"
                );
            }
            (
                c[0].parse().unwrap(),
                c[2].parse().unwrap(),
                num(c[3]),
                num(c[4]),
                c[6].parse().unwrap(),
                c[8] == "1",
            )
        })
        .collect()
}

/// Per target, the RMS of (measured y - true y) with its mean removed, px.
fn rms_errors(rows: &[Row], truth: &HashMap<(usize, usize), (f64, f64)>) -> Vec<f64> {
    let mut per: HashMap<usize, Vec<f64>> = HashMap::new();
    for &(k, t, _, cy, _, lost) in rows {
        assert!(!lost, "frame {k} target {t} lost");
        per.entry(t).or_default().push(cy - truth[&(k, t)].1);
    }
    let mut targets: Vec<usize> = per.keys().copied().collect();
    targets.sort();
    targets
        .iter()
        .map(|t| {
            let e = &per[t];
            let m = e.iter().sum::<f64>() / e.len() as f64;
            (e.iter().map(|v| (v - m).powi(2)).sum::<f64>() / e.len() as f64).sqrt()
        })
        .collect()
}

/// Renders the 5-target cantilever recording (2 ms exposure, read noise 1) of `scene` into
/// `rec`.
fn render_noisy_targets(rec: &Path, scene: &str) {
    render_cantilever(
        rec,
        &["--targets", "5", "--read-noise", "1", "--scene", scene],
    );
}

fn track(frames: &Path, points: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    harness(&path_words(
        "track --frames {} --fps 120 --points {} --out {} --no-plots",
        &[frames, points, out],
        extra,
    ))
}

/// The 5-target recording with read noise (disks of radius 10 px with 0.5 px edges, 2 ms
/// exposure): Lucas-Kanade's RMS error against the exact exposure-averaged motion is below the
/// weighted centroid's on average and about two thousandths of a pixel on every target, the
/// binary centroid's about 0.07 px; every frame of every target followed.
#[test]
fn lucas_kanade_follows_the_rendered_targets_closer_than_the_centroids() {
    let tmp = tempfile::tempdir().unwrap();
    let rec = tmp.path().join("rec");
    render_noisy_targets(&rec, "plain");
    let truth = truth(&rec);
    let (frames, points) = (rec.join("frames"), rec.join("points.csv"));
    let mut rms = HashMap::new();
    for (name, extra) in [
        ("blob", vec!["--threshold", "127"]),
        ("weighted", words("--tracker weighted --threshold 127", &[])),
        ("lk", vec!["--tracker", "lk"]),
    ] {
        let out = tmp.path().join(name);
        assert_ok(&track(&frames, &points, &out, &extra));
        let rows = displacement(&out);
        assert_eq!(rows.len(), 5 * 1200);
        rms.insert(name, rms_errors(&rows, &truth));
    }
    let mean = |v: &Vec<f64>| v.iter().sum::<f64>() / v.len() as f64;
    // measured: blob 0.068-0.069, weighted 0.0047-0.0053, lk 0.0018-0.0022 px (pyidi's
    // LucasKanade on these frames: 0.0019-0.0022, scripts/peer_trackers.py)
    for (t, e) in rms["lk"].iter().enumerate() {
        assert!(*e < 0.003, "target {}: LK RMS error {e}", t + 1);
    }
    assert!(mean(&rms["lk"]) < mean(&rms["weighted"]), "{rms:?}");
    assert!(rms["blob"].iter().all(|e| *e > 0.03), "{rms:?}");
}

/// Writes `frames` 8-bit PNG frames of 200 x 64 px into `dir/frames` with `paint(k, x, y)`
/// the value of pixel `(x, y)` in frame `k`.
fn frames(dir: &Path, n: usize, paint: impl Fn(usize, f64, f64) -> f64) {
    let d = dir.join("frames");
    std::fs::create_dir_all(&d).unwrap();
    for k in 0..n {
        let mut img = image::GrayImage::new(200, 64);
        for (x, y, p) in img.enumerate_pixels_mut() {
            p.0[0] = paint(k, f64::from(x), f64::from(y))
                .round()
                .clamp(0.0, 255.0) as u8;
        }
        img.save(d.join(format!("f_{k:03}.png"))).unwrap();
    }
}

/// A speckle patch (Gaussian spots of sigma 2 px) centred at `(cx, cy)`, scaled by `gain`.
fn speckle(x: f64, y: f64, (cx, cy): (f64, f64), gain: f64) -> f64 {
    const SPOTS: [(f64, f64, f64); 5] = [
        (-4.0, -3.0, 1.0),
        (3.0, -1.0, 0.7),
        (-1.0, 4.0, 0.9),
        (5.0, 5.0, 0.6),
        (-6.0, 3.0, 0.8),
    ];
    SPOTS
        .iter()
        .map(|&(sx, sy, a)| {
            let (ex, ey) = (x - cx - sx, y - cy - sy);
            gain * a * (-(ex * ex + ey * ey) / 8.0).exp()
        })
        .sum()
}

/// Every way Lucas-Kanade loses a target is a flag (the `flags` column) and a lost frame of
/// that target, counted, with an empty position: a jump beyond the search range (`diverged`,
/// 64), a flat window (`flat`, 32), a target that turns brighter and clips (`saturated`, 4),
/// a window that leaves the frame (`border`, 2); each with `empty` (1, no position). The
/// frames around a loss are followed.
#[test]
fn lucas_kanade_losses_are_flags_and_lost_frames_never_wrong_positions() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    // target 1 at x 30: jumps 40 px in frame 4 (beyond --search-px 6), back in frame 5
    // target 2 at x 80: a flat grey window
    // target 3 at x 120: twice as bright from frame 6 on (clipped at 255)
    // target 4 at x 170: moves right 4 px per frame and leaves the frame
    let pos1 = |k: usize| if k == 4 { 70.0 } else { 30.0 + 0.3 * k as f64 };
    let pos4 = |k: usize| 170.0 + 4.0 * k as f64;
    frames(dir, 10, |k, x, y| {
        let gain3 = if k >= 6 { 400.0 } else { 180.0 };
        20.0 + speckle(x, y, (pos1(k), 32.0), 180.0)
            + if (70.0..90.0).contains(&x) { 60.0 } else { 0.0 }
            + speckle(x, y, (120.0, 32.0), gain3)
            + speckle(x, y, (pos4(k), 32.0), 180.0)
    });
    let points = dir.join("points.csv");
    std::fs::write(
        &points,
        "target,x,y,w,h\n1,30,32,21,21\n2,80,32,15,15\n3,120,32,21,21\n4,170,32,21,21\n",
    )
    .unwrap();
    let out = dir.join("out");
    let o = track(
        &dir.join("frames"),
        &points,
        &out,
        &["--tracker", "lk", "--search-px", "6"],
    );
    assert_ok(&o);
    let rows = displacement(&out);
    let row = |k: usize, t: usize| *rows.iter().find(|r| r.0 == k && r.1 == t).unwrap();
    let lost_flags = |k: usize, t: usize, flag: u8| {
        let r = row(k, t);
        assert!(r.5, "frame {k} target {t} not lost: {r:?}");
        assert!(
            r.2.is_nan() && r.3.is_nan(),
            "a lost frame has no position: {r:?}"
        );
        assert_eq!(r.4, flag | 1, "frame {k} target {t}: {r:?}");
    };
    // target 1: followed, lost at the jump, followed again
    for k in [0, 1, 2, 3, 5, 6, 9] {
        let r = row(k, 1);
        assert!(!r.5 && (r.2 - pos1(k)).abs() < 0.05, "frame {k}: {r:?}");
    }
    lost_flags(4, 1, 64);
    // target 2: every frame, flat
    for k in 0..10 {
        lost_flags(k, 2, 32);
    }
    // target 3: followed while its brightness holds, then saturated
    assert!(!row(5, 3).5 && (row(5, 3).2 - 120.0).abs() < 0.05);
    for k in 6..10 {
        lost_flags(k, 3, 4);
    }
    // target 4: followed until its window reaches the frame's edge (frame 5: 190 + 10 px),
    // then lost at the border; its centre past the frame's edge from frame 8, where nothing
    // matches any more
    for k in 0..5 {
        let r = row(k, 4);
        assert!(!r.5 && (r.2 - pos4(k)).abs() < 0.05, "{r:?}");
    }
    for k in 5..8 {
        lost_flags(k, 4, 2);
    }
    for k in 8..10 {
        assert!(row(k, 4).5 && row(k, 4).3.is_nan(), "{:?}", row(k, 4));
    }
    // the report counts them
    let report = std::fs::read_to_string(out.join("report.txt")).unwrap();
    assert_contains(
        &report,
        &[
            "target 1: window 21x21 px",
            "1 of 10 frames lost",
            "10 of 10 frames lost",
        ],
    );
}

/// `--tracker lk` needs `--points`; `--search-px` belongs to it.
#[test]
fn lucas_kanade_flags_are_checked() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    frames(dir, 2, |_, x, y| 20.0 + speckle(x, y, (30.0, 32.0), 180.0));
    let out = dir.join("out").to_string_lossy().into_owned();
    let f = dir.join("frames").to_string_lossy().into_owned();
    let o = harness(&words(
        "track --frames {} --fps 120 --targets 1 --tracker lk --out {}",
        &[&f, &out],
    ));
    assert_exit_2(&o, "--tracker lk follows the windows of --points");
    std::fs::write(dir.join("p.csv"), "target,x,y,w,h\n1,30,32,21,21\n").unwrap();
    let o = track(
        &dir.join("frames"),
        &dir.join("p.csv"),
        &dir.join("o2"),
        &[
            "--threshold",
            "100",
            "--search-px",
            "9",
            "--tracker",
            "blob",
        ],
    );
    assert_exit_2(&o, "--search-px: the coarse search of --tracker lk");
    let o = track(
        &dir.join("frames"),
        &dir.join("p.csv"),
        &dir.join("o3"),
        &["--tracker", "blob"],
    );
    assert_exit_2(&o, "--threshold T");
}

/// The cluttered scene (colour JPEG frames, tags as bright as the wall, clipped at 255, read
/// noise 1): Lucas-Kanade in the windows of its points.csv follows every tag through every
/// frame, a few thousandths of a pixel from the exact motion (measured 0.0018-0.0030 px; the
/// clipped plateau moves with the template and is not a loss).
#[test]
fn lucas_kanade_follows_the_clipped_tags_of_the_cluttered_scene() {
    let tmp = tempfile::tempdir().unwrap();
    let rec = tmp.path().join("rec");
    render_noisy_targets(&rec, "cluttered");
    let out = tmp.path().join("lk");
    assert_ok(&track(
        &rec.join("frames"),
        &rec.join("points.csv"),
        &out,
        &["--tracker", "lk"],
    ));
    let rows = displacement(&out);
    assert_eq!(rows.len(), 5 * 1200);
    for (t, e) in rms_errors(&rows, &truth(&rec)).iter().enumerate() {
        assert!(*e < 0.004, "target {}: LK RMS error {e}", t + 1);
    }
}

/// The largest error against truth.csv (px, either axis) and the lost frames of a `track`.
fn worst_and_lost(rows: &[Row], truth: &HashMap<(usize, usize), (f64, f64)>) -> (f64, usize) {
    rows.iter()
        .fold((0.0f64, 0usize), |(w, l), &(k, t, cx, cy, _, lost)| {
            if lost {
                (w, l + 1)
            } else {
                let (tx, ty) = truth[&(k, t)];
                (w.max((cx - tx).abs()).max((cy - ty).abs()), l)
            }
        })
}

/// A recording's truth: `(frame, target) -> (x, y)` px.
type Truth = HashMap<(usize, usize), (f64, f64)>;

/// The pull-and-release recording of the cluttered scene (28 alike tags on four storeys in
/// front of a white brick wall, 184 HD frames at 23 fps, jumps up to 120 px between frames, tags
/// 150-170 px apart), rendered once for the three tests that track it (so they can run in
/// parallel), under Cargo's temporary directory for tests (a static's guard would never remove
/// it).
fn release() -> &'static Release {
    static REC: std::sync::OnceLock<Release> = std::sync::OnceLock::new();
    REC.get_or_init(|| {
        let rec = Path::new(env!("CARGO_TARGET_TMPDIR")).join("release-rec");
        let _ = std::fs::remove_dir_all(&rec);
        assert_ok(&harness(&words(
            "render --recording {} --scene cluttered --motion release",
            &[rec.to_str().unwrap()],
        )));
        Release {
            frames: format!("{}/frames", rec.display()),
            truth: truth(&rec),
            rec,
        }
    })
}

/// The rendered pull and release: its directory, its frames (a `--frames` argument) and its
/// truth.
struct Release {
    rec: PathBuf,
    frames: String,
    truth: Truth,
}

/// The release's points file without its groups column, as a new user writes it, in `dir`.
fn release_alone(rec: &Path, dir: &Path) -> (String, PathBuf) {
    let text = std::fs::read_to_string(rec.join("points.csv")).unwrap();
    let alone: String = text
        .lines()
        .map(|l| l.rsplit_once(',').map_or(l, |(head, _)| head).to_string() + "\n")
        .collect();
    assert!(alone.starts_with("target,x,y,w,h\n"), "{alone}");
    let alone_csv = dir.join("alone.csv");
    std::fs::write(&alone_csv, &alone).unwrap();
    (alone, alone_csv)
}

#[test]
fn lk_follows_alike_tags_through_a_pull_and_release_by_their_storeys_shared_motion() {
    // every tag through every frame within 1 px of the truth with the storeys as groups
    let Release { rec, frames, truth } = release();
    let tmp = tempfile::tempdir().unwrap();
    // tracked and analysed in one run (`analyze` without an accelerometer: `track`'s
    // displacement.csv and `modal`'s outputs, one tracking of the 184 HD frames, not two)
    let grouped = tmp.path().join("grouped");
    let o = harness(&words(
        "analyze --frames {} --fps 23 --points {} --tracker lk --search-px 130 --axis x --out {}",
        &[
            frames,
            rec.join("points.csv").to_str().unwrap(),
            grouped.to_str().unwrap(),
        ],
    ));
    let report = assert_says(&o, &["regime: 2 free decay(s)"]);
    let rows = displacement(&grouped);
    assert_eq!(rows.len(), 184 * 28);
    let (worst, lost) = worst_and_lost(&rows, truth);
    assert_eq!(lost, 0);
    // measured 0.063 px (the JPEG, the blur, the wall in the windows' margins)
    assert!(worst < 1.0, "worst {worst} px");
    // the free decays of that track give the structure's mode by default (3.6 Hz, damping
    // 10 %; before the decay method, no mode): measured 3.6000 Hz, 0.1000
    let decay: Vec<Vec<String>> = crate::util::modes_csv_rows(&grouped)
        .into_iter()
        .filter(|c| c[9] == "decay")
        .collect();
    assert_eq!(decay.len(), 1, "{report}");
    let (f, z): (f64, f64) = (decay[0][5].parse().unwrap(), decay[0][7].parse().unwrap());
    assert!(
        (f - 3.6).abs() < 0.01 * 3.6 && (z - 0.1).abs() < 0.01,
        "{f} Hz, {z}"
    );
    // no FDD line far from the mode (the pull's quasi-static line is no mode)
    for c in crate::util::modes_csv_rows(&grouped) {
        let f: f64 = c[5].parse().unwrap();
        assert!((f - 3.6).abs() < 0.5, "{} at {f} Hz: {report}", c[9]);
    }
    // the shapes are drawn storey by storey (the points file's groups, each joined in order:
    // 4 x 6 lines), not zig-zagging from one storey to the next
    let page = std::fs::read_to_string(grouped.join("report.html")).unwrap();
    let shapes = page.matches("<svg class=\"mode-shape\"").count();
    assert!(shapes >= 1, "no shape drawn");
    assert_eq!(page.matches("<line class=\"wire\"").count(), 24 * shapes);
    assert!(
        page.contains("Lines join the targets of each group tracking followed together (4 groups)")
    );
    assert!(
        !page.contains("data-a=\"6\" data-b=\"7\""),
        "a line from storey 1 to 2"
    );
}

#[test]
fn lk_finds_the_storeys_of_a_pull_and_release_from_the_first_frames_motion() {
    let Release { rec, frames, truth } = release();
    let tmp = tempfile::tempdir().unwrap();
    // the same windows without the storeys, as a new user writes them: the groups are found
    // from the first frames' motion, and every tag is followed through every frame (before,
    // 7 tags took their neighbours), with the default search and with a search of the whole
    // frame (65535 px: a top tag was reported on one two storeys down, flags 0)
    let (_, alone_csv) = release_alone(rec, tmp.path());
    for search in [None, Some("65535")] {
        let out = tmp
            .path()
            .join(format!("alone_{}", search.unwrap_or("default")));
        let mut args = words("track --frames {} --fps 23 --tracker lk", &[frames]);
        args.extend(["--points", alone_csv.to_str().unwrap()]);
        args.extend(["--out", out.to_str().unwrap()]);
        if let Some(s) = search {
            args.extend(["--search-px", s]);
        }
        let o = harness(&args);
        assert_ok(&o);
        let report = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(
            report.contains("groups found from the motion of the first")
                && report.contains("[1 2 3 4 5 6 7], [8 9 10 11 12 13 14]")
                && !report.contains("WARNING"),
            "{report}"
        );
        let (worst, lost) = worst_and_lost(&displacement(&out), truth);
        assert_eq!(lost, 0, "{search:?}");
        assert!(worst < 1.0, "{search:?}: worst {worst} px");
    }
}

#[test]
fn lk_flags_a_pull_and_release_tag_followed_alone_ambiguous_never_a_jump_onto_its_neighbour() {
    let Release { rec, frames, .. } = release();
    let tmp = tempfile::tempdir().unwrap();
    let (alone, _) = release_alone(rec, tmp.path());
    // each tag in a group of its own: the look-alikes are named in the report, and a search
    // that reaches a neighbour nearly as good a match, or a jump the motion so far does not
    // explain, is a lost frame flagged ambiguous (128), never a clean jump onto the neighbour
    let single: String = alone
        .lines()
        .enumerate()
        .map(|(i, l)| match i {
            0 => format!("{l},group\n"),
            _ => format!("{l},{i}\n"),
        })
        .collect();
    let single_csv = tmp.path().join("single.csv");
    std::fs::write(&single_csv, single).unwrap();
    let out = tmp.path().join("single");
    let o = harness(&words(
        "track --frames {} --fps 23 --tracker lk --search-px 130 --points {} --out {}",
        &[frames, single_csv.to_str().unwrap(), out.to_str().unwrap()],
    ));
    assert_ok(&o);
    let report = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        report.contains("WARNING: targets 1 2 3") && report.contains("followed alone"),
        "{report}"
    );
    let flagged = std::fs::read_to_string(out.join("displacement.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .filter(|l| {
            l.split(',')
                .nth(6)
                .and_then(|f| f.parse::<u8>().ok())
                .is_some_and(|f| f & 128 != 0)
        })
        .count();
    assert!(flagged > 100, "{flagged} ambiguous tag-frames");
}

/// `(frame, target) -> (dx, dy)` px of a corpus recording's `pyidi_lk.csv`.
fn pyidi_reference(dir: &Path) -> HashMap<(usize, usize), (f64, f64)> {
    let text = std::fs::read_to_string(dir.join("pyidi_lk.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let c: Vec<f64> = l.split(',').map(|s| s.parse().unwrap()).collect();
            ((c[0] as usize, c[1] as usize), (c[2], c[3]))
        })
        .collect()
}

/// A real recording made by others (tests/data/real/pyidi-showcase: pyidi's Photron showcase,
/// MIT, 75 frames of a striped beam at 15 kHz moving by a tenth of a pixel): the default
/// tracker, and `--tracker lk`, follow every window across the stripes' edges (y) within
/// 0.05 px of pyidi 1.4's Lucas-Kanade in every frame (measured: median 0.001 px, largest
/// 0.009 px), take no position away (the forward-backward check weighs the disagreement by
/// the window's texture), and say that x, along the edges, is not measured (pyidi and ours
/// wander apart there by up to 3.3 px: the aperture).
#[test]
fn a_real_high_speed_recording_tracks_across_its_edges_as_pyidi_does() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/real/pyidi-showcase");
    let reference = pyidi_reference(&data);
    let tmp = tempfile::tempdir().unwrap();
    for tracker in ["auto", "lk"] {
        let out = tmp.path().join(tracker);
        let o = harness(&words(
            "track --frames {} --points {} --tracker {} --out {} --no-plots",
            &[
                data.join("data_showcase.cih").to_str().unwrap(),
                data.join("points.csv").to_str().unwrap(),
                tracker,
                out.to_str().unwrap(),
            ],
        ));
        assert_ok(&o);
        let rows = displacement(&out);
        assert_eq!(rows.len(), 75 * 15);
        let first: HashMap<usize, f64> = rows
            .iter()
            .filter(|r| r.0 == 0)
            .map(|r| (r.1, r.3))
            .collect();
        let mut worst = 0.0f64;
        for r in &rows {
            assert!(!r.5 && r.4 == 0, "{tracker}: a position taken away: {r:?}");
            let dy = r.3 - first[&r.1];
            worst = worst.max((dy - reference[&(r.0, r.1)].1).abs());
        }
        assert!(
            worst < 0.05,
            "{tracker}: y differs from pyidi by {worst} px"
        );
        let report = std::fs::read_to_string(out.join("report.txt")).unwrap();
        assert!(
            report.contains("edges along x only")
                && report.contains("its x position is not measured"),
            "{report}"
        );
    }
}

/// Points from a region of the same real recording (`pick --region`, docs/method.md §2.12):
/// the whole frame at a 4 px spacing keeps 760 of the 775 21 px windows that fit when the
/// texture must fix y, the beam's motion (15 that Lucas-Kanade would refuse as flat left out),
/// and only a few when it must fix every direction (the stripes fix no x: Shi-Tomasi);
/// Lucas-Kanade follows all of them, and the ones at the
/// places of the hand-chosen windows give pyidi's y there (measured: within 0.031 px in every
/// frame; windows that straddle the beam's edge lose some frames to the ambiguity check,
/// never a wrong position).
#[test]
fn a_region_of_the_real_beam_gives_hundreds_of_points_that_track_as_pyidi_does() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/real/pyidi-showcase");
    let reference = pyidi_reference(&data);
    let tmp = tempfile::tempdir().unwrap();
    let cih = data.join("data_showcase.cih");
    let pick = |direction: &str| {
        let points = tmp.path().join(format!("{direction}.csv"));
        let o = harness(&words(
            "pick --frames {} --region 0,0;640,0;640,40;0,40 --spacing 4 --direction {} \
             --points-out {} --out {}",
            &[
                cih.to_str().unwrap(),
                direction,
                points.to_str().unwrap(),
                tmp.path()
                    .join(format!("{direction}.html"))
                    .to_str()
                    .unwrap(),
            ],
        ));
        assert_ok(&o);
        let text = std::fs::read_to_string(&points).unwrap();
        let rows: Vec<(usize, f64, f64)> = text
            .lines()
            .skip(1)
            .map(|l| {
                let c: Vec<&str> = l.split(',').collect();
                assert_eq!(&c[3..5], ["21", "21"], "{l}");
                (
                    c[0].parse().unwrap(),
                    c[1].parse().unwrap(),
                    c[2].parse().unwrap(),
                )
            })
            .collect();
        // every window and the pixel its gradients need inside the 640 x 40 frame
        for &(t, x, y) in &rows {
            assert!(
                (11.0..=628.0).contains(&x) && (11.0..=28.0).contains(&y),
                "{t}: {x},{y}"
            );
        }
        (points, rows)
    };
    let (points, across) = pick("y");
    assert!(across.len() >= 500, "{} points", across.len());
    let (_, both) = pick("both");
    assert!(
        both.len() * 10 < across.len(),
        "{} in both directions",
        both.len()
    );
    let out = tmp.path().join("track");
    // (the helper's --fps 120 stands for the file's 15 kHz: positions in px do not depend on it)
    assert_ok(&track(&cih, &points, &out, &["--tracker", "lk"]));
    let rows = displacement(&out);
    assert_eq!(rows.len(), 75 * across.len());
    // the stripes measure no x: an iteration that counted its steps along them whole wandered
    // to its cap and lost 4.7 % of the positions; measured 2.6 % since
    let lost = rows.iter().filter(|r| r.5).count();
    assert!(
        (lost as f64) < 0.035 * rows.len() as f64,
        "{lost} of {} positions lost",
        rows.len()
    );
    let first: HashMap<usize, f64> = rows
        .iter()
        .filter(|r| r.0 == 0 && !r.5)
        .map(|r| (r.1, r.3))
        .collect();
    // the hand-chosen windows are at x = 40, 80, ..., y = 22: the region's at y = 20 and 24
    let at: HashMap<usize, usize> = across
        .iter()
        .filter(|p| p.1 % 40.0 == 0.0 && p.1 <= 600.0 && (p.2 == 20.0 || p.2 == 24.0))
        .map(|p| (p.0, (p.1 / 40.0) as usize))
        .collect();
    assert_eq!(at.len(), 30);
    let mut compared = 0;
    for r in rows.iter().filter(|r| at.contains_key(&r.1) && !r.5) {
        let Some(y0) = first.get(&r.1) else { continue };
        let dy = r.3 - y0;
        let want = reference[&(r.0, at[&r.1])].1;
        assert!((dy - want).abs() < 0.05, "{r:?}: {dy} px, pyidi {want} px");
        compared += 1;
    }
    assert!(compared > 30 * 70, "{compared} positions compared");
    // pyidi's Phantom file, whose last time stamp is damaged: `pick` names the way out and
    // takes it, as `track` does
    let cine = data.join("../pyidi-cine/data_small_cine.cine");
    let pick_cine = |range: &[&str]| {
        let (points, page) = (tmp.path().join("cine.csv"), tmp.path().join("cine.html"));
        let mut args = words(
            "pick --frames {} --region 0,0;255,0;255,31;0,31 --points-out {} --out {} --force",
            &[
                cine.to_str().unwrap(),
                points.to_str().unwrap(),
                page.to_str().unwrap(),
            ],
        );
        args.extend(range);
        harness(&args)
    };
    assert_exit_2(&pick_cine(&[]), "--frame-range 1..234");
    assert_ok(&pick_cine(&["--frame-range", "1..234"]));
}

/// A second real recording (tests/data/real/pyidi-cine: pyidi's 16-bit Phantom file, MIT,
/// a striped beam with a round object, moving by hundredths of a pixel): its last frame's
/// damaged time stamp is named, not measured; frames 1-234 tracked by the default tracker
/// agree with pyidi 1.4 within 0.005 px in y on the stripes (measured 0.0014) and 0.05 px in
/// x and y on the round object (measured 0.024), and only the stripes' windows are said not
/// to measure x.
#[test]
fn a_real_phantom_recording_tracks_as_pyidi_does_and_its_damaged_time_stamp_is_named() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/real/pyidi-cine");
    let reference = pyidi_reference(&data);
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("t");
    let line = "track --frames {} --points {} --out {} --no-plots";
    let paths = [
        data.join("data_small_cine.cine")
            .to_str()
            .unwrap()
            .to_owned(),
        data.join("points.csv").to_str().unwrap().to_owned(),
        out.to_str().unwrap().to_owned(),
    ];
    let paths: Vec<&str> = paths.iter().map(String::as_str).collect();
    assert_exit_2(&harness(&words(line, &paths)), "frame 235 comes");
    let mut args = words(line, &paths);
    args.extend(["--frame-range", "1..234"]);
    assert_ok(&harness(&args));
    let rows = displacement(&out);
    assert_eq!(rows.len(), 234 * 4);
    let first: HashMap<usize, (f64, f64)> = rows
        .iter()
        .filter(|r| r.0 == 0)
        .map(|r| (r.1, (r.2, r.3)))
        .collect();
    for r in &rows {
        assert!(!r.5 && r.4 == 0, "a position taken away: {r:?}");
        let (rx, ry) = reference[&(r.0, r.1)];
        let (dx, dy) = (r.2 - first[&r.1].0, r.3 - first[&r.1].1);
        let (ex, ey) = ((dx - rx).abs(), (dy - ry).abs());
        if r.1 == 3 {
            assert!(
                ex < 0.05 && ey < 0.05,
                "the round object: {r:?} vs ({rx}, {ry})"
            );
        } else {
            assert!(ey < 0.005, "a stripe's y: {r:?} vs {ry}");
        }
    }
    let report = std::fs::read_to_string(out.join("report.txt")).unwrap();
    assert!(
        report.contains("targets 1 2 4: the window's texture is edges along x only"),
        "{report}"
    );
}
