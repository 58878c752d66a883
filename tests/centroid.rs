//! End-to-end tests of `host-harness centroid`: grey PNG/TIFF frames written to a temporary
//! directory, centroids checked against naive sums computed here, bad files reported by name.

use crate::util::{assert_exit_2, harness, words};
use image::{ImageBuffer, Luma};
use std::path::{Path, PathBuf};

/// Writes a grey frame of `T` (`u8` or `u16`; format from the extension).
fn write_grey<T>(dir: &Path, name: &str, w: u32, h: u32, f: impl Fn(u32, u32) -> T) -> PathBuf
where
    Luma<T>: image::Pixel<Subpixel = T> + image::PixelWithColorType,
    [T]: image::EncodableLayout,
{
    let path = dir.join(name);
    ImageBuffer::<Luma<T>, Vec<T>>::from_fn(w, h, |x, y| Luma([f(x, y)]))
        .save(&path)
        .unwrap();
    path
}

/// Writes an 8-bit grey frame (format from the extension).
fn write_u8(dir: &Path, name: &str, w: u32, h: u32, f: impl Fn(u32, u32) -> u8) -> PathBuf {
    write_grey(dir, name, w, h, f)
}

/// Writes a 16-bit grey frame (format from the extension).
fn write_u16(dir: &Path, name: &str, w: u32, h: u32, f: impl Fn(u32, u32) -> u16) -> PathBuf {
    write_grey(dir, name, w, h, f)
}

/// `value` at the pixels where `on` holds, 0 elsewhere.
fn spot<T: Default + Copy>(on: impl Fn(u32, u32) -> bool, value: T) -> impl Fn(u32, u32) -> T {
    move |x, y| if on(x, y) { value } else { T::default() }
}

/// Naive centroid over the whole frame (or ROI): (cx, cy, pixels).
fn naive(
    w: u32,
    h: u32,
    f: impl Fn(u32, u32) -> u32,
    t: u32,
    weighted: bool,
    roi: Option<(u32, u32, u32, u32)>,
) -> (f64, f64, u64) {
    let (x0, y0, rw, rh) = roi.unwrap_or((0, 0, w, h));
    let (mut n, mut sw, mut sx, mut sy) = (0u64, 0f64, 0f64, 0f64);
    for y in y0..y0 + rh {
        for x in x0..x0 + rw {
            let v = f(x, y);
            if v > t {
                let wt = if weighted { f64::from(v - t) } else { 1.0 };
                n += 1;
                sw += wt;
                sx += f64::from(x) * wt;
                sy += f64::from(y) * wt;
            }
        }
    }
    (sx / sw, sy / sw, n)
}

struct Run {
    code: Option<i32>,
    /// CSV data rows split on commas (header checked and removed).
    rows: Vec<Vec<String>>,
    stderr: String,
}

/// `host-harness centroid --threshold threshold flags.. files..`.
fn run(threshold: &str, flags: &[&str], files: &[&Path]) -> Run {
    let mut args = vec!["centroid", "--threshold", threshold];
    args.extend_from_slice(flags);
    args.extend(files.iter().map(|f| f.to_str().unwrap()));
    let out = harness(&args);
    let stdout = String::from_utf8(out.stdout).unwrap();
    let mut lines = stdout.lines();
    assert_eq!(
        lines.next(),
        Some("file,cx,cy,pixels,flags"),
        "stdout: {stdout}"
    );
    Run {
        code: out.status.code(),
        rows: lines
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect(),
        stderr: String::from_utf8(out.stderr).unwrap(),
    }
}

fn num(s: &str) -> f64 {
    s.parse()
        .unwrap_or_else(|_| panic!("{s:?} is not a number"))
}

/// A soft blob (8-bit values up to 220) centred near (17.3, 9.6) in a 40 x 24 frame.
fn blob(x: u32, y: u32) -> u32 {
    let r2 = (f64::from(x) - 17.3).powi(2) + (f64::from(y) - 9.6).powi(2);
    (220.0 * (-r2 / 18.0).exp()).round() as u32
}

#[test]
fn png_and_tiff_8_and_16_bit_match_naive_sums() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (40, 24);
    let png8 = write_u8(dir.path(), "a.png", w, h, |x, y| blob(x, y) as u8);
    let tif8 = write_u8(dir.path(), "b.tif", w, h, |x, y| blob(x, y) as u8);
    let png16 = write_u16(dir.path(), "c.png", w, h, |x, y| blob(x, y) as u16 * 250);
    let tif16 = write_u16(dir.path(), "d.tiff", w, h, |x, y| blob(x, y) as u16 * 250);
    for weighted in [false, true] {
        let mode = if weighted { "weighted" } else { "binary" };
        // The 16-bit frames are the 8-bit ones times 250, so T * 250 selects the same pixels
        // and (weighted) scales every weight by 250: the same centroid.
        for (files, t) in [([&png8, &tif8], 50u32), ([&png16, &tif16], 50 * 250)] {
            let ts = t.to_string();
            let r = run(&ts, &["--mode", mode], &[files[0], files[1]]);
            assert_eq!(r.code, Some(0), "{}", r.stderr);
            assert_eq!(r.rows.len(), 2);
            let scale = if t > 255 { 250 } else { 1 };
            let (ex, ey, en) = naive(w, h, |x, y| blob(x, y) * scale, t, weighted, None);
            for (row, file) in r.rows.iter().zip(files) {
                assert_eq!(row[0], file.to_str().unwrap());
                assert!((num(&row[1]) - ex).abs() < 1e-4, "cx {} vs {ex}", row[1]);
                assert!((num(&row[2]) - ey).abs() < 1e-4, "cy {} vs {ey}", row[2]);
                assert_eq!(row[3], en.to_string());
                assert_eq!(row[4], "0");
            }
        }
    }
}

#[test]
fn roi_selects_one_of_two_targets_in_full_frame_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    // Two 3 x 2 blocks: columns 5..=7 rows 4..=5, and columns 30..=32 rows 12..=13.
    let f = |x: u32, y: u32| {
        let a = (5..=7).contains(&x) && (4..=5).contains(&y);
        let b = (30..=32).contains(&x) && (12..=13).contains(&y);
        a || b
    };
    let p = write_u16(dir.path(), "two.tif", 40, 20, spot(f, 1000));
    for (flags, want) in [
        (&[][..], ["18.5", "8.5", "12", "0"]),
        (&["--roi", "20,0,20,20"][..], ["31", "12.5", "6", "0"]),
        // A ROI whose edge cuts the target: border flag (2).
        (&["--roi", "0,0,6,20"][..], ["5", "4.5", "2", "2"]),
    ] {
        let r = run("10", flags, &[&p]);
        assert_eq!(r.code, Some(0), "{flags:?}: {}", r.stderr);
        assert_eq!(r.rows[0][1..], want, "{flags:?}");
    }
}

#[test]
fn flags_empty_border_and_saturated() {
    let dir = tempfile::tempdir().unwrap();
    let dark = write_u8(dir.path(), "dark.png", 10, 10, |_, _| 20);
    let edge = spot(|x, y| x == 0 && y == 4, 255);
    let edge = write_u8(dir.path(), "edge.png", 10, 10, edge);
    let sat16 = spot(|x, y| (4..=5).contains(&x) && y == 5, 4095);
    let sat16 = write_u16(dir.path(), "sat.png", 10, 10, sat16);
    let r = run("100", &[], &[&dark, &edge, &sat16]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert_eq!(r.rows[0][1..], ["", "", "0", "1"]);
    assert_eq!(r.rows[1][1..], ["0", "4", "1", "6"]);
    assert_eq!(r.rows[2][1..], ["4.5", "5", "2", "0"]);
    // A 12-bit camera: saturation level 4095.
    let r = run("100", &["--saturation", "4095"], &[&sat16]);
    assert_eq!(r.rows[0][1..], ["4.5", "5", "2", "4"]);
}

#[test]
fn bad_files_are_named_and_the_others_still_processed() {
    let dir = tempfile::tempdir().unwrap();
    let good1 = write_u8(
        dir.path(),
        "good1.png",
        8,
        8,
        spot(|x, y| (x, y) == (3, 2), 200),
    );
    // 32-bit float pixels: neither grey nor colour of 8 or 16 bits
    let rgb = dir.path().join("float.tif");
    {
        use tiff::encoder::{colortype, TiffEncoder};
        let mut enc = TiffEncoder::new(std::fs::File::create(&rgb).unwrap()).unwrap();
        enc.write_image::<colortype::Gray32Float>(8, 8, &[0f32; 64])
            .unwrap();
    }
    let junk = dir.path().join("junk.png");
    std::fs::write(&junk, b"not an image at all").unwrap();
    let missing = dir.path().join("missing.tif");
    let small = write_u8(dir.path(), "small.png", 4, 4, |_, _| 0);
    let good2 = spot(|x, y| (x, y) == (6, 5), 60000);
    let good2 = write_u16(dir.path(), "good2.tif", 8, 8, good2);
    let files: [&Path; 6] = [&good1, &rgb, &junk, &missing, &small, &good2];
    let r = run("100", &["--roi", "1,1,6,6"], &files);
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert_eq!(r.rows.len(), 2);
    assert_eq!(r.rows[0], [good1.to_str().unwrap(), "3", "2", "1", "0"]);
    // (6, 5) is on the ROI's last column.
    assert_eq!(r.rows[1], [good2.to_str().unwrap(), "6", "5", "1", "2"]);
    for bad in [&rgb, &junk, &missing, &small] {
        let name = bad.to_str().unwrap();
        assert!(
            r.stderr.lines().any(|l| l.contains(name)),
            "stderr does not name {name}: {}",
            r.stderr
        );
    }
    assert!(r.stderr.contains("float.tif"), "{}", r.stderr);
    assert!(r.stderr.contains("4 of 6"), "{}", r.stderr);
}

#[test]
fn invalid_settings_exit_with_code_2() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_u8(dir.path(), "a.png", 4, 4, |_, _| 0);
    let p = p.to_str().unwrap();
    let out = harness(&words("centroid --threshold 100 --saturation 90 {}", &[p]));
    assert_exit_2(&out, "saturation");
    let out = harness(&words("centroid --threshold 1 --roi 0,0,0,3 {}", &[p]));
    assert_eq!(out.status.code(), Some(2));
    let out = harness(&["centroid", "--threshold", "1"]);
    assert_eq!(out.status.code(), Some(2), "files are required");
}

#[test]
fn help_documents_the_output_and_flag_bits() {
    let out = harness(&["centroid", "--help"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for s in [
        "--threshold",
        "--mode",
        "--roi",
        "--saturation",
        "file,cx,cy,pixels,flags",
        "empty",
        "border",
        "saturated",
        "capacity",
    ] {
        assert!(text.contains(s), "--help does not mention {s}");
    }
}
