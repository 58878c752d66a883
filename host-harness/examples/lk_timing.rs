//! Time per target-frame of firmware-core's Lucas-Kanade tracker on a recording's `--points`
//! windows, the frames preloaded (decoding excluded), as `scripts/peer_trackers.py` times its
//! peers: the same windows, the same defaults as `track --tracker lk` (no search needed on
//! this motion, but configured as the CLI does). Prints the time per target-frame, the mean
//! iterations, the frames lost and the frames searched (the coarse search ran: the first
//! refinement was not accepted). `LK_SEARCH=R` sets the search range instead of the default
//! half window (0: none), to see what the searches cost.
//!
//! ```text
//! cargo run --release -p host-harness --example lk_timing REC [REPEATS]
//! ```

use firmware_core::centroid::Frame;
use firmware_core::lk::{LkConfig, LkTracker};
use host_harness::analysis::points::{read_points, window};
use host_harness::frames::{load_frame, GreyFrame};
use std::path::PathBuf;
use std::time::Instant;

/// The CLI's capacity for a `--points` window (its `LK_PIXELS`, `LK_ROW`).
type Lk = LkTracker<{ 136 * 136 }, 135>;

fn view(d: &[u8], (w, h): (usize, usize)) -> anyhow::Result<Frame<'_, u8>> {
    Frame::new(d, w, h, w).map_err(|e| anyhow::anyhow!("{e:?}"))
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let rec = PathBuf::from(
        args.next()
            .ok_or_else(|| anyhow::anyhow!("usage: lk_timing REC"))?,
    );
    let repeats: usize = args.next().map_or(Ok(3), |s| s.parse())?;
    let points = read_points(&rec.join("points.csv"))?;
    let mut files: Vec<PathBuf> = std::fs::read_dir(rec.join("frames"))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    files.sort();
    let frames: Vec<(usize, usize, Vec<u8>)> = files
        .iter()
        .map(|p| match load_frame(p)? {
            GreyFrame::U8 {
                width,
                height,
                data,
            } => Ok((width, height, data)),
            GreyFrame::U16 { .. } => Err(anyhow::anyhow!("{}: 8-bit frames only", p.display())),
        })
        .collect::<anyhow::Result<_>>()?;
    let (w, h, _) = frames
        .first()
        .ok_or_else(|| anyhow::anyhow!("no frames in {}", rec.display()))?;
    let (w, h) = (*w, *h);
    let mut best = f64::INFINITY;
    let (mut iterations, mut lost, mut searched) = (0u64, 0u64, 0u64);
    for _ in 0..repeats {
        let mut trackers: Vec<Box<Lk>> = Vec::new();
        let first = view(&frames[0].2, (w, h))?;
        for p in &points {
            let mut cfg = LkConfig::new(p.size.0 as u16, p.size.1 as u16);
            cfg.saturation = 0;
            if let Ok(s) = std::env::var("LK_SEARCH") {
                cfg.search = s.parse()?;
            }
            let mut t = Box::new(Lk::try_new(cfg).map_err(|e| anyhow::anyhow!("{e}"))?);
            let roi = window(p.xy, p.size, (w, h)).ok_or_else(|| {
                anyhow::anyhow!("target {}: the window leaves the frame", p.target)
            })?;
            t.set_template(&first, roi.x as i32, roi.y as i32)
                .map_err(|e| anyhow::anyhow!("target {}: {e}", p.target))?;
            trackers.push(t);
        }
        (iterations, lost, searched) = (0, 0, 0);
        let t0 = Instant::now();
        for (_, _, d) in &frames[1..] {
            let f = view(d, (w, h))?;
            for t in trackers.iter_mut() {
                let r = t.track(&f);
                iterations += u64::from(r.iterations);
                lost += u64::from(r.displacement().is_none());
                searched += u64::from(r.searched);
            }
        }
        best = best.min(t0.elapsed().as_secs_f64());
    }
    let n = ((frames.len() - 1) * points.len()) as f64;
    println!(
        "lk: {:.2} us per target-frame ({} targets, {} frames, best of {repeats}), {:.2} \
         iterations per target-frame, {lost} lost, {searched} searched",
        best / n * 1e6,
        points.len(),
        frames.len() - 1,
        iterations as f64 / n
    );
    Ok(())
}
