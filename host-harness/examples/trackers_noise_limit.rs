//! Each `--points` tracker's RMS position error on the 5-target cantilever recording with read
//! noise, against the exact exposure-averaged motion (`truth.csv`), beside the Cramér-Rao lower
//! bound of a translation estimate for that target and noise (docs/method.md §2.11).
//!
//! RMS error as users compute it: per target, the estimated `y` minus the true one, its mean
//! removed (a constant offset is not an error of a displacement), over all 1200 frames.
//!
//! The bound: `sigma^2 / sum (dI/dy)^2` over the target's pixels, with `sigma^2` the read noise
//! variance plus the 8-bit quantisation's `1/12`, and `dI/dy` the renderer's own image
//! derivative (central difference of two renderings 0.01 px apart) of the unblurred target.
//! Motion blur lowers the gradients of a frame, so this static bound is the lowest of the
//! per-frame bounds.
//!
//! ```text
//! cargo build --release -p host-harness
//! cargo run --release -p host-harness --example trackers_noise_limit [speckle] [READ_NOISE ...]
//! ```
//!
//! `speckle`: the targets painted with speckle (`render --texture speckle`), the bound for that
//! image.

use host_harness::analysis::points::{read_points, track_points, PointTracker, ThresholdRule};
use host_harness::frames::discover_frames;
use host_harness::imaging::BlurRenderer;
use std::collections::HashMap;
use std::path::Path;

mod common;

fn render(dir: &Path, noise: f64, texture: &str) -> anyhow::Result<()> {
    common::render_targets(
        dir,
        &["--read-noise", &noise.to_string(), "--texture", texture],
    )
}

/// The Cramér-Rao bound (px) of the target's `y` for noise `sigma` (grey levels).
fn crlb_y(sigma: f64, texture: host_harness::model::Texture) -> f64 {
    let target = host_harness::model::DiskTarget {
        texture,
        ..host_harness::model::cantilever::TARGET
    };
    let d = 0.01;
    let image = |shift: f64| {
        let mut r = BlurRenderer::for_path(&target, &[shift, shift], 1);
        let mut out = vec![0f32; r.width() * r.height()];
        r.render_float(0.0, 1.0, &mut out);
        out
    };
    let (a, b) = (image(-d), image(d));
    let fisher: f64 = a
        .iter()
        .zip(&b)
        .map(|(x, y)| {
            let g = (f64::from(*y) - f64::from(*x)) / (2.0 * d);
            g * g
        })
        .sum();
    ((sigma * sigma + 1.0 / 12.0) / fisher).sqrt()
}

fn main() -> anyhow::Result<()> {
    let speckle = std::env::args().any(|a| a == "speckle");
    let (texture, name) = if speckle {
        (host_harness::model::Texture::Speckle, "speckle")
    } else {
        (host_harness::model::Texture::Plain, "plain")
    };
    let noises: Vec<f64> = std::env::args()
        .skip(1)
        .filter(|a| a != "speckle")
        .map(|a| a.parse())
        .collect::<Result<_, _>>()?;
    let noises = if noises.is_empty() { vec![1.0] } else { noises };
    println!(
        "| read noise | target | tracker | RMS error per target, px | mean | Cramér-Rao bound, px | mean / bound |"
    );
    println!("|---:|---|---|---|---:|---:|---:|");
    for noise in noises {
        let tmp = tempfile::tempdir()?;
        let dir = tmp.path().join("rec");
        render(&dir, noise, name)?;
        let truth: HashMap<(usize, usize), f64> = std::fs::read_to_string(dir.join("truth.csv"))?
            .lines()
            .skip(1)
            .map(|l| {
                let c: Vec<&str> = l.split(',').collect();
                Ok(((c[0].parse()?, c[1].parse()?), c[3].parse()?))
            })
            .collect::<anyhow::Result<_>>()?;
        let points = read_points(&dir.join("points.csv"))?;
        let source = discover_frames(dir.join("frames").to_str().unwrap_or(""))?.source;
        let bound = crlb_y(noise, texture);
        for (name, tracker, mode) in [
            (
                "blob",
                PointTracker::Centroid(ThresholdRule::Level(127)),
                firmware_core::centroid::Mode::Binary,
            ),
            (
                "weighted",
                PointTracker::Centroid(ThresholdRule::Level(127)),
                firmware_core::centroid::Mode::Weighted,
            ),
            (
                "lk",
                PointTracker::Lk { search_px: None },
                firmware_core::centroid::Mode::Binary,
            ),
        ] {
            let config = firmware_core::centroid::CentroidConfig {
                mode,
                ..firmware_core::centroid::CentroidConfig::binary(127)
            };
            let (tracks, _) = track_points(&source, 120.0, &points, &config, tracker)?;
            let rms: Vec<f64> = tracks
                .centroids
                .iter()
                .enumerate()
                .map(|(t, cs)| {
                    let e: Vec<f64> = cs
                        .iter()
                        .enumerate()
                        .filter_map(|(k, c)| {
                            c.position().map(|(_, y)| f64::from(y) - truth[&(k, t + 1)])
                        })
                        .collect();
                    let m = e.iter().sum::<f64>() / e.len() as f64;
                    (e.iter().map(|v| (v - m).powi(2)).sum::<f64>() / e.len() as f64).sqrt()
                })
                .collect();
            let mean = rms.iter().sum::<f64>() / rms.len() as f64;
            println!(
                "| {noise} | {texture:?} | {name} | {} | {mean:.4} | {bound:.4} | {:.2} |",
                rms.iter()
                    .map(|v| format!("{v:.4}"))
                    .collect::<Vec<_>>()
                    .join(" "),
                mean / bound
            );
        }
    }
    Ok(())
}
