//! The firmware centroid's row pushes: random widths, rows, thresholds, modes, ROI and
//! saturation, 8- and 16-bit, must never panic, and the streamed result must equal the
//! whole-frame result.
#![no_main]
use firmware_core::centroid::{centroid, CentroidConfig, Centroider, Frame, Mode, Roi};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if data.len() < 12 {
        return;
    }
    let (head, pixels) = data.split_at(12);
    let width = 1 + head[0] as usize % 96;
    let threshold = u16::from_le_bytes([head[1], head[2]]);
    let mode = if head[3] & 1 == 0 {
        Mode::Binary
    } else {
        Mode::Weighted
    };
    let roi = (head[3] & 2 != 0).then(|| Roi {
        x: head[4] as u32 % 64,
        y: head[5] as u32 % 64,
        width: 1 + head[6] as u32 % 64,
        height: 1 + head[7] as u32 % 64,
    });
    let saturation = (head[3] & 4 != 0).then(|| u16::from_le_bytes([head[8], head[9]]));
    let config = CentroidConfig {
        threshold,
        mode,
        roi,
        saturation,
    };
    let Ok(config) = config.validate() else {
        return;
    };
    let height = pixels.len() / width;
    if height == 0 {
        return;
    }
    let rows8 = &pixels[..width * height];
    // 8-bit: stream row by row, then the whole frame where the ROI fits
    let Ok(mut c) = Centroider::try_new(config) else {
        return;
    };
    for row in rows8.chunks(width) {
        c.push_row(row);
    }
    let streamed = c.result();
    if let Ok(frame) = Frame::new(rows8, width, height, width) {
        if let Ok(whole) = centroid(&config, &frame) {
            assert_eq!(streamed, whole);
        }
    }
    // 16-bit from pairs of bytes
    let wide: Vec<u16> = pixels
        .chunks_exact(2)
        .map(|p| u16::from_le_bytes([p[0], p[1]]))
        .collect();
    let h16 = wide.len() / width;
    let Ok(mut c) = Centroider::try_new(config) else {
        return;
    };
    for row in wide[..width * h16].chunks(width) {
        c.push_row(row);
    }
    let _ = c.result();
});
