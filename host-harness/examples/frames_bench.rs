//! Speed of the frame sources and of `--points` tracking, as ratios measured in one run
//! (docs/performance.md):
//!
//! 1. tracking 5 chosen points in their windows over the 1200 frames of a 5-target recording
//!    (colour JPEG frames of `render --scene cluttered`, and the grey PNG ones) against only
//!    decoding the same frames through the same frame source;
//! 2. decoding a Photron (16-bit and 12-bit packed) and a Phantom (16-bit and packed 10-bit)
//!    recording against reading their bytes (`cat FILE > /dev/null`), page cache warm.
//!
//! ```text
//! cargo run --release -p host-harness --example frames_bench
//! ```

use host_harness::analysis::points::{read_points, track_points, PointTracker, ThresholdRule};
use host_harness::frames::{discover_frames, phantom, photron, FrameSource};
use std::path::Path;

mod common;
use std::time::Instant;

/// Best of 3 wall-clock runs of `f`, s (one thread: wall clock is CPU time here).
fn best(mut f: impl FnMut() -> anyhow::Result<()>) -> anyhow::Result<f64> {
    let mut b = f64::INFINITY;
    for _ in 0..3 {
        let t = Instant::now();
        f()?;
        b = b.min(t.elapsed().as_secs_f64());
    }
    Ok(b)
}

fn decode_all(source: &FrameSource) -> anyhow::Result<()> {
    let mut n = 0u64;
    source.for_each(120.0, |_, f| {
        n += f.dimensions().0 as u64;
        Ok(())
    })?;
    std::hint::black_box(n);
    Ok(())
}

fn render(dir: &Path, scene: &str) -> anyhow::Result<()> {
    common::render_targets(dir, &["--read-noise", "1", "--scene", scene])
}

fn main() -> anyhow::Result<()> {
    let tmp = tempfile::tempdir()?;
    println!(
        "| what | decode only, s | with blob tracking, s | ratio | with LK tracking, s | ratio | \
         LK per target-frame, us |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|");
    for scene in ["cluttered", "plain"] {
        let dir = tmp.path().join(scene);
        render(&dir, scene)?;
        let points = if scene == "cluttered" {
            read_points(&dir.join("points.csv"))?
        } else {
            let mut p = read_points(&tmp.path().join("cluttered/points.csv"))?;
            for q in &mut p {
                q.xy.1 -= host_harness::recording::cluttered::WALL_PX as f64;
            }
            p
        };
        let source = discover_frames(dir.join("frames").to_str().unwrap_or(""))?.source;
        let config = firmware_core::centroid::CentroidConfig::binary(127);
        let decode = best(|| decode_all(&source))?;
        let run = |tracker: PointTracker| {
            best(|| {
                track_points(&source, 120.0, &points, &config, tracker)?;
                Ok(())
            })
        };
        let track = run(PointTracker::Centroid(ThresholdRule::Level(127)))?;
        let lk = run(PointTracker::Lk { search_px: None })?;
        println!(
            "| 5 points x 1200 frames, {} | {decode:.3} | {track:.3} | {:.2} | {lk:.3} | {:.2} | \
             {:.1} |",
            if scene == "cluttered" {
                "colour JPEG 205 x 128"
            } else {
                "grey PNG 165 x 80"
            },
            track / decode,
            lk / decode,
            (lk - decode) / (5.0 * 1200.0) * 1e6
        );
    }
    println!();
    println!("| file | size, MB | cat > /dev/null, s | decode, s | ratio |");
    println!("|---|---:|---:|---:|---:|");
    let (w, h, n) = (640usize, 480usize, 200usize);
    let frames: Vec<Vec<u16>> = (0..n)
        .map(|k| {
            (0..w * h)
                .map(|i| ((i * 7 + k * 13) % 4096) as u16)
                .collect()
        })
        .collect();
    let cases: Vec<(String, std::path::PathBuf)> = vec![
        ("Photron 16-bit".into(), {
            let p = tmp.path().join("p16.cih");
            photron::write_recording(&p, (w, h), 16, 1000.0, 1e-4, &frames)?;
            p
        }),
        ("Photron 12-bit packed".into(), {
            let p = tmp.path().join("p12.cih");
            photron::write_recording(&p, (w, h), 12, 1000.0, 1e-4, &frames)?;
            p
        }),
        ("Phantom 16-bit".into(), {
            let p = tmp.path().join("c16.cine");
            phantom::write_cine(&p, (w, h), (16, 0), (1000, 100_000), &frames)?;
            p
        }),
        ("Phantom packed 10-bit".into(), {
            let p = tmp.path().join("c10.cine");
            let codes: Vec<Vec<u16>> = frames
                .iter()
                .map(|f| f.iter().map(|v| v & 1023).collect())
                .collect();
            phantom::write_cine(&p, (w, h), (10, 256), (1000, 100_000), &codes)?;
            p
        }),
    ];
    for (name, p) in cases {
        let data = if photron::is_header(&p) {
            p.with_extension("mraw")
        } else {
            p.clone()
        };
        let mb = std::fs::metadata(&data)?.len() as f64 / 1e6;
        let cat = best(|| {
            let ok = std::process::Command::new("sh")
                .arg("-c")
                .arg(format!("cat '{}' > /dev/null", data.display()))
                .status()?
                .success();
            anyhow::ensure!(ok, "cat failed");
            Ok(())
        })?;
        let source = discover_frames(p.to_str().unwrap_or(""))?.source;
        let decode = best(|| decode_all(&source))?;
        println!(
            "| {name}, {w} x {h} x {n} | {mb:.0} | {cat:.3} | {decode:.3} | {:.2} |",
            decode / cat
        );
    }
    Ok(())
}
