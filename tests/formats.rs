//! Frames as cameras and ordinary tools write them: Photron recordings (8, 12-bit packed and
//! 16-bit; the header's rate and shutter as defaults), colour PNG and JPEG frames (BT.601
//! luma), and the errors a damaged or mismatched camera file gives. The pixel-for-pixel
//! comparison with pyMRAW and PIL is `scripts/check_frames.py`, run by CI.

use crate::analyze::{disk, make_recording, position_px, Recording, FPS, H, W};
use crate::util::{assert_exit_2, assert_ok, harness, path_words, stderr, words};
use host_harness::frames::photron::write_recording;
use std::path::Path;

/// The 1 s recording's 120 frames, levels multiplied by `scale`.
fn scaled_frames(scale: u16) -> Vec<Vec<u16>> {
    (0..120)
        .map(|k| {
            disk(position_px(k as f64 / FPS), W, H)
                .into_iter()
                .map(|v| u16::from(v) * scale)
                .collect()
        })
        .collect()
}

/// The 1 s recording's frames as Photron `rec.cih` + `rec.mraw` at `bits`, levels scaled by
/// `scale` (the threshold scales with them).
fn photron(dir: &Path, bits: u32, scale: u16) -> std::path::PathBuf {
    let frames = scaled_frames(scale);
    let cih = dir.join(format!("rec{bits}.cih"));
    write_recording(&cih, (W as usize, H as usize), bits, FPS, 0.002, &frames).unwrap();
    cih
}

fn analyze(frames: &Path, accel: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    harness(&path_words(
        "analyze --frames {} --accel {} --fs 2048 --mm-per-px 0.1 --out {}",
        &[frames, accel, out],
        extra,
    ))
}

/// The `modes.csv` cells `f_hz,amplitude` of every row.
fn modes(out: &Path) -> Vec<String> {
    std::fs::read_to_string(out.join("modes.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').skip(4).take(2).collect::<Vec<_>>().join(","))
        .collect()
}

/// The 120-frame recording and the modes of its PNG frames at 120 fps, threshold 100, and
/// `extra`: what a camera file of the same frames must give.
fn png_modes(extra: &[&str]) -> (tempfile::TempDir, Recording, Vec<String>) {
    let (tmp, rec) = make_recording(120, 2048);
    let png_out = rec.dir.join("png");
    let mut args = vec!["--fps", "120", "--threshold", "100"];
    args.extend_from_slice(extra);
    assert_ok(&analyze(&rec.frames, &rec.accel, &png_out, &args));
    let want = modes(&png_out);
    (tmp, rec, want)
}

#[test]
fn a_photron_recording_gives_the_modes_of_its_png_frames_at_the_header_rate() {
    let (_tmp, rec, want) = png_modes(&["--exposure-ms", "2"]);
    for (bits, scale, threshold) in [(8, 1, "100"), (12, 16, "1600"), (16, 256, "25600")] {
        let cih = photron(&rec.dir, bits, scale);
        let out = rec.dir.join(format!("ph{bits}"));
        // no --fps, no --exposure-ms: the header's 120 fps and 1/500 s
        header_gives_the_modes(&cih, &rec, &out, threshold, &want, bits);
    }
    // --fps overrides the header's rate, and the report says so
    let cih = rec.dir.join("rec8.cih");
    let out = rec.dir.join("override");
    let o = analyze(
        &cih,
        &rec.accel,
        &out,
        &["--threshold", "100", "--fps", "240"],
    );
    assert_ok(&o);
    let report = std::fs::read_to_string(out.join("report.txt")).unwrap();
    assert!(
        report.contains("--fps 240 overrides the 120 fps that"),
        "{report}"
    );
    // image files state no rate: --fps is needed
    let nofps = rec.dir.join("nofps");
    let o = analyze(&rec.frames, &rec.accel, &nofps, &["--threshold", "100"]);
    assert_exit_2(&o, "--fps is needed");
}

#[test]
fn centroid_reads_every_frame_of_a_photron_recording() {
    let (_tmp, rec) = make_recording(2, 64);
    let cih = photron(&rec.dir, 12, 16);
    let o = harness(&words(
        "centroid --threshold 1600 {}",
        &[cih.to_str().unwrap()],
    ));
    assert_ok(&o);
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    let rows: Vec<&str> = out.lines().skip(1).collect();
    assert_eq!(rows.len(), 120, "{out}");
    let c = cih.to_str().unwrap();
    assert!(rows[0].starts_with(&format!("{c}#1,12,")), "{}", rows[0]);
    assert!(rows[119].starts_with(&format!("{c}#120,")), "{}", rows[119]);
}

#[test]
fn damaged_or_mismatched_photron_files_are_named() {
    let (_tmp, rec) = make_recording(2, 64);
    let cih = photron(&rec.dir, 16, 256);
    let mraw = cih.with_extension("mraw");
    let args = |f: &Path| {
        harness(&words(
            "analyze --frames {} --accel {} --fs 2048 --threshold 100 --mm-per-px 0.1 --out {}",
            &[
                f.to_str().unwrap(),
                rec.accel.to_str().unwrap(),
                rec.dir.join("out").to_str().unwrap(),
            ],
        ))
    };
    // the frames file named instead of the header
    assert_exit_2(&args(&mraw), "named by its header: give");
    // truncated
    let bytes = std::fs::read(&mraw).unwrap();
    std::fs::write(&mraw, &bytes[..bytes.len() - 100]).unwrap();
    let o = args(&cih);
    assert_exit_2(&o, "truncated");
    assert!(stderr(&o).contains("rec16.mraw"), "{}", stderr(&o));
    // a header whose frame count disagrees with the data
    std::fs::write(&mraw, &bytes).unwrap();
    let text = std::fs::read_to_string(&cih).unwrap();
    std::fs::write(&cih, text.replace("Total Frame : 120", "Total Frame : 100")).unwrap();
    assert_exit_2(&args(&cih), "states 100 frames");
    // an unsupported bit depth, and a compressed format
    std::fs::write(&cih, text.replace("Color Bit : 16", "Color Bit : 10")).unwrap();
    assert_exit_2(&args(&cih), "10 bits per pixel");
    std::fs::write(
        &cih,
        text.replace("File Format : MRaw", "File Format : AVI"),
    )
    .unwrap();
    assert_exit_2(&args(&cih), "only MRaw");
    // not a header at all
    std::fs::write(&cih, "hello\n").unwrap();
    assert_exit_2(&args(&cih), "no `File Format`");
}

#[test]
fn colour_png_and_jpeg_frames_are_read_as_their_luma() {
    let dir = tempfile::tempdir().unwrap();
    // a colour spot (200, 100, 50): luma 0.299*200 + 0.587*100 + 0.114*50 = 124.2 -> 124
    let mut img = image::RgbImage::new(16, 12);
    for (x, y) in [(5, 4), (6, 4), (5, 5), (6, 5)] {
        img.put_pixel(x, y, image::Rgb([200, 100, 50]));
    }
    let png = dir.path().join("spot.png");
    img.save(&png).unwrap();
    let at = |t: &str, f: &Path| {
        let o = harness(&["centroid", "--threshold", t, f.to_str().unwrap()]);
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .nth(1)
            .unwrap_or("")
            .to_string()
    };
    let p = png.to_str().unwrap();
    assert_eq!(at("123", &png), format!("{p},5.5,4.5,4,0"));
    // 124 is not above 124: the luma is exactly 124
    assert_eq!(at("124", &png), format!("{p},,,0,1"));
    // the same scene as a JPEG (lossy: the centroid within 0.05 px, the level within a few)
    let jpg = dir.path().join("spot.jpg");
    let mut big = image::RgbImage::new(64, 48);
    for y in 16..28 {
        for x in 20..36 {
            big.put_pixel(x, y, image::Rgb([200, 100, 50]));
        }
    }
    image::DynamicImage::ImageRgb8(big)
        .save_with_format(&jpg, image::ImageFormat::Jpeg)
        .unwrap();
    let row = at("60", &jpg);
    let cells: Vec<f64> = row
        .split(',')
        .skip(1)
        .take(2)
        .map(|v| v.parse().unwrap())
        .collect();
    assert!(
        (cells[0] - 27.5).abs() < 0.05 && (cells[1] - 21.5).abs() < 0.05,
        "{row}"
    );
    // a file named .jpg that is not one
    let bad = dir.path().join("bad.jpg");
    std::fs::write(&bad, b"GIF89a not a jpeg").unwrap();
    let o = harness(&words(
        "centroid --threshold 60 {}",
        &[bad.to_str().unwrap()],
    ));
    assert_exit_2(&o, "bad.jpg");
}

/// The 1 s recording's frames as a Phantom cine (`bits`, `compression`), levels scaled.
fn cine(dir: &Path, bits: u16, compression: u32, scale: u16) -> std::path::PathBuf {
    let frames = scaled_frames(scale);
    let p = dir.join(format!("rec{bits}_{compression}.cine"));
    host_harness::frames::phantom::write_cine(
        &p,
        (W as usize, H as usize),
        (bits, compression),
        (120, 2_000_000),
        &frames,
    )
    .unwrap();
    p
}

#[test]
fn a_phantom_cine_gives_the_modes_of_its_png_frames_at_its_own_rate() {
    let (_tmp, rec, want) = png_modes(&[]);
    // 8 and 16 bits (stored bottom-up), and packed 10-bit codes 4 v (through the monotonic
    // 10-to-12-bit table, LIN_LUT[400] = 623 < LIN_LUT[401] = 626: a pixel is above 623 exactly
    // when v is above 100, the same binary mask as the PNG frames at 100)
    for (bits, comp, scale, threshold) in
        [(8, 0, 1, "100"), (16, 0, 16, "1600"), (10, 256, 4, "623")]
    {
        let p = cine(&rec.dir, bits, comp, scale);
        let out = rec.dir.join(format!("cine{bits}"));
        header_gives_the_modes(&p, &rec, &out, threshold, &want, bits.into());
    }
    let p = rec.dir.join("rec8_0.cine");
    let o = harness(&words(
        "centroid --threshold 100 {}",
        &[p.to_str().unwrap()],
    ));
    assert_ok(&o);
    assert_eq!(String::from_utf8_lossy(&o.stdout).lines().count(), 121);
}

#[test]
fn damaged_phantom_files_are_named() {
    let (_tmp, rec) = make_recording(2, 64);
    let p = cine(&rec.dir, 16, 0, 1);
    let centroid = |f: &Path| {
        harness(&words(
            "centroid --threshold 100 {}",
            &[f.to_str().unwrap()],
        ))
    };
    let bytes = std::fs::read(&p).unwrap();
    // truncated: the last frame beyond the end
    std::fs::write(&p, &bytes[..bytes.len() - 10]).unwrap();
    assert_exit_2(
        &centroid(&p),
        "frame 120 of 120 lies beyond the end of the file",
    );
    // a dropped frame: frame 51's time stamp two periods after frame 50's
    let mut b = bytes.clone();
    let setup = u32::from_le_bytes(b[28..32].try_into().unwrap()) as usize;
    let stamps = setup + 13_484 + 8;
    for k in 50..120 {
        let at = stamps + 8 * k;
        let frac = u32::from_le_bytes(b[at..at + 4].try_into().unwrap());
        let v = (u64::from(u32::from_le_bytes(b[at + 4..at + 8].try_into().unwrap())) << 32
            | u64::from(frac))
            + (1u64 << 32) / 120;
        b[at..at + 4].copy_from_slice(&(v as u32).to_le_bytes());
        b[at + 4..at + 8].copy_from_slice(&((v >> 32) as u32).to_le_bytes());
    }
    std::fs::write(&p, &b).unwrap();
    // what needs the rate names the frame and the regular frames (1..50 and 51..120: the
    // longer); a centroid of each frame needs none
    let out = rec.dir.join("track");
    let o = harness(&words(
        "track --frames {} --targets 1 --threshold 100 --out {}",
        &[p.to_str().unwrap(), out.to_str().unwrap()],
    ));
    assert_exit_2(&o, "frame 51 comes 16.667 ms after frame 50");
    assert!(
        stderr(&o).contains("--frame-range 51..120"),
        "{}",
        stderr(&o)
    );
    assert_ok(&centroid(&p));
    // not a cine, and an unsupported compression
    std::fs::write(&p, [b"RIFF".as_slice(), &[0u8; 60]].concat()).unwrap();
    assert_exit_2(&centroid(&p), "not a Phantom cine file");
    let mut b = bytes;
    b[44 + 16..44 + 20].copy_from_slice(&2u32.to_le_bytes());
    std::fs::write(&p, &b).unwrap();
    assert_exit_2(&centroid(&p), "compression 2");
}

#[test]
fn centroid_reads_a_video_at_its_rate_and_needs_one() {
    let (_tmp, rec) = make_recording(6, 128);
    let video = rec.dir.join("v.mkv");
    use host_harness::frames::video::{Ffv1Writer, Pixels};
    let mut w = Ffv1Writer::create(&video, W as usize, H as usize, FPS, Pixels::Grey8).unwrap();
    for k in 0..6 {
        w.write_frame(&disk(position_px(k as f64 / FPS), W, H))
            .unwrap();
    }
    w.finish().unwrap();
    let v = video.to_str().unwrap();
    let o = harness(&words("centroid --threshold 100 --fps 120 {}", &[v]));
    assert_ok(&o);
    let rows: Vec<String> = String::from_utf8_lossy(&o.stdout)
        .lines()
        .skip(1)
        .map(str::to_string)
        .collect();
    assert_eq!(rows.len(), 6);
    // the same pixels as the PNG frames (FFV1 is lossless): the same centroids
    for (k, row) in rows.iter().enumerate() {
        let png = rec.frames.join(format!("frame_{k}.png"));
        let p = harness(&words(
            "centroid --threshold 100 {}",
            &[png.to_str().unwrap()],
        ));
        let want = String::from_utf8_lossy(&p.stdout)
            .lines()
            .nth(1)
            .unwrap()
            .to_string();
        let strip = |r: &str| r.split_once(',').unwrap().1.to_string();
        assert!(row.starts_with(&format!("{v}#{},", k + 1)), "{row}");
        assert_eq!(strip(row), strip(&want));
    }
    assert_exit_2(
        &harness(&words("centroid --threshold 100 {}", &[v])),
        "a video needs --fps",
    );
}

/// `analyze` of the camera file `frames` with no `--fps` or `--exposure-ms` gives the modes
/// `want` and reports the header's 120 fps and 2 ms.
fn header_gives_the_modes(
    frames: &Path,
    rec: &Recording,
    out: &Path,
    threshold: &str,
    want: &[String],
    bits: u32,
) {
    let o = analyze(frames, &rec.accel, out, &["--threshold", threshold]);
    assert_ok(&o);
    assert_eq!(modes(out), want, "{bits} bits");
    let report = std::fs::read_to_string(out.join("report.txt")).unwrap();
    assert!(
        report.contains("frame rate 120 fps, as") && report.contains("exposure 2 ms, as"),
        "{report}"
    );
}
