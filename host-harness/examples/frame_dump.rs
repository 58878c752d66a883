//! Decodes a frame source exactly as `analyze` and `centroid` do and writes the grey frames as
//! raw little-endian samples, for comparisons with other readers (`scripts/check_frames.py`:
//! pyMRAW for Photron files, PIL for JPEG and colour images).
//!
//! ```text
//! cargo run --release --example frame_dump -- FRAMES OUT.bin [FPS]
//! ```
//! prints `width height bits frames` (bits 8 or 16: the sample size in OUT.bin); FPS (default
//! 1) is only used to check a video's timestamps.

use host_harness::frames::{discover_frames, GreyFrame};
use std::io::Write as _;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(frames), Some(out)) = (args.first(), args.get(1)) else {
        anyhow::bail!("usage: frame_dump FRAMES OUT.bin [FPS]");
    };
    let fps: f64 = args.get(2).map_or(Ok(1.0), |s| s.parse())?;
    let source = discover_frames(frames)?.source;
    let mut file = std::io::BufWriter::new(std::fs::File::create(out)?);
    let (mut shape, mut count) = (None, 0usize);
    source.for_each(fps, |_, frame| {
        let (w, h) = frame.dimensions();
        let bits = match frame {
            GreyFrame::U8 { data, .. } => {
                file.write_all(data)?;
                8
            }
            GreyFrame::U16 { data, .. } => {
                for v in data {
                    file.write_all(&v.to_le_bytes())?;
                }
                16
            }
        };
        shape.get_or_insert((w, h, bits));
        count += 1;
        Ok(())
    })?;
    file.flush()?;
    let (w, h, bits) = shape.unwrap_or((0, 0, 8));
    println!("{w} {h} {bits} {count}");
    Ok(())
}
