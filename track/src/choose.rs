//! `--tracker auto`, the default with chosen points: per target, the blob centroid where a
//! threshold separates the target in its first-frame window (a compact part clearly brighter
//! than the rest of the window, not touching its edge, not filling it), Lucas-Kanade otherwise;
//! each choice with its reason in words, for the report.
//!
//! A blob target is then held to what made it one: a frame where its pixels above the
//! threshold are lost, or cover less than half or more than twice what they covered in the
//! first frame (a neighbour entering the window, the target leaving it), sends the whole target
//! to Lucas-Kanade instead ([`blob_holds`]), so the choice never costs a frame Lucas-Kanade
//! would have kept.

use firmware_core::centroid::{Centroid, Roi};
use vibcam_readers::frames::GreyFrame;

/// The least separation of the two levels, in within-class standard deviations.
pub const MIN_SEPARATION_SD: f64 = 6.0;
/// The largest share of the window above the threshold.
pub const MAX_FILL: f64 = 0.5;
/// The least share of the pixels above the threshold in one connected part.
pub const MIN_ONE_PART: f64 = 0.95;
/// The least share of its bounding box the part fills (a dot 0.79, a square 1).
pub const MIN_COMPACT: f64 = 0.3;
/// The fewest pixels above the threshold.
pub const MIN_PIXELS: usize = 4;
/// The range of a frame's pixel count against the first frame's a blob target must keep.
pub const AREA_RANGE: (f64, f64) = (0.5, 2.0);

/// What the first frame's window says of a target at `threshold`: `Ok` with the reason it is
/// a blob, `Err` with the reason it is not.
pub fn separates(frame: &GreyFrame, roi: Roi, threshold: u16) -> Result<String, String> {
    let Split { above, n, s, s2 } = split(frame, roi, threshold);
    let (w, h) = (roi.width as usize, roi.height as usize);
    if n[1] < MIN_PIXELS {
        return Err(format!(
            "{} pixel(s) of the window above threshold {threshold}: no target to centre on",
            n[1]
        ));
    }
    let fill = n[1] as f64 / (w * h) as f64;
    if fill > MAX_FILL {
        return Err(format!(
            "{:.0} % of the window is above threshold {threshold}: the bright part fills it \
             (a bright tag or background, or a dark target)",
            fill * 100.0
        ));
    }
    if n[0] == 0 {
        return Err(format!("no pixel of the window at or below {threshold}"));
    }
    let mean = |c: usize| s[c] / n[c] as f64;
    let var = |c: usize| (s2[c] / n[c] as f64 - mean(c).powi(2)).max(0.0);
    let within = ((n[0] as f64 * var(0) + n[1] as f64 * var(1)) / (w * h) as f64).sqrt();
    let gap = mean(1) - mean(0);
    // a within-class spread of zero (two flat levels) separates at any gap; half a grey level
    // stands for the quantisation
    let sd = gap / within.max(0.5);
    if sd < MIN_SEPARATION_SD {
        return Err(format!(
            "the levels above and below threshold {threshold} are {sd:.1} within-class standard \
             deviations apart (a blob needs {MIN_SEPARATION_SD}): texture or noise, not a \
             target on a plain background"
        ));
    }
    let part = largest_part(&above, w, h);
    if (part.pixels as f64) < MIN_ONE_PART * n[1] as f64 {
        return Err(format!(
            "the pixels above threshold {threshold} are in several parts (the largest holds \
             {:.0} %): more than one bright thing in the window",
            100.0 * part.pixels as f64 / n[1] as f64
        ));
    }
    if part.touches_edge {
        return Err(format!(
            "the bright part above threshold {threshold} touches the window's edge: larger \
             than the window, or off its centre"
        ));
    }
    let compact = part.pixels as f64 / part.box_pixels as f64;
    if compact < MIN_COMPACT {
        return Err(format!(
            "the bright part fills {:.0} % of its bounding box (a blob needs {:.0} %): a line \
             or an edge, not a spot",
            compact * 100.0,
            MIN_COMPACT * 100.0
        ));
    }
    Ok(format!(
        "a compact spot of {} px ({:.0} % of the window) {sd:.0} standard deviations brighter \
         than its background at threshold {threshold}",
        n[1],
        fill * 100.0
    ))
}

/// A window split at a threshold: the mask of the pixels above it, and per class (0 at or
/// below, 1 above) the count, sum and sum of squares.
struct Split {
    above: Vec<bool>,
    n: [usize; 2],
    s: [f64; 2],
    s2: [f64; 2],
}

fn split(frame: &GreyFrame, roi: Roi, threshold: u16) -> Split {
    let (fw, _) = frame.dimensions();
    let (w, h) = (roi.width as usize, roi.height as usize);
    let value = |x: usize, y: usize| -> f64 {
        let i = (roi.y as usize + y) * fw + roi.x as usize + x;
        match frame {
            GreyFrame::U8 { data, .. } => f64::from(data[i]),
            GreyFrame::U16 { data, .. } => f64::from(data[i]),
        }
    };
    let t = f64::from(threshold);
    let mut out = Split {
        above: vec![false; w * h],
        n: [0; 2],
        s: [0.0; 2],
        s2: [0.0; 2],
    };
    for y in 0..h {
        for x in 0..w {
            let v = value(x, y);
            let c = usize::from(v > t);
            out.above[y * w + x] = c == 1;
            out.n[c] += 1;
            out.s[c] += v;
            out.s2[c] += v * v;
        }
    }
    out
}

/// The largest 8-connected part of a mask.
struct Part {
    pixels: usize,
    box_pixels: usize,
    touches_edge: bool,
}

fn largest_part(mask: &[bool], w: usize, h: usize) -> Part {
    let mut seen = vec![false; mask.len()];
    let mut best = Part {
        pixels: 0,
        box_pixels: 1,
        touches_edge: false,
    };
    let mut stack = Vec::new();
    for start in 0..mask.len() {
        if !mask[start] || seen[start] {
            continue;
        }
        seen[start] = true;
        stack.push(start);
        let (mut count, mut x0, mut x1, mut y0, mut y1) = (0usize, w, 0usize, h, 0usize);
        while let Some(i) = stack.pop() {
            let (x, y) = (i % w, i / w);
            count += 1;
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            for dy in -1i64..=1 {
                for dx in -1i64..=1 {
                    let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                    if nx < 0 || ny < 0 || nx >= w as i64 || ny >= h as i64 {
                        continue;
                    }
                    let j = ny as usize * w + nx as usize;
                    if mask[j] && !seen[j] {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
        }
        if count > best.pixels {
            best = Part {
                pixels: count,
                box_pixels: (x1 - x0 + 1) * (y1 - y0 + 1),
                touches_edge: x0 == 0 || y0 == 0 || x1 + 1 == w || y1 + 1 == h,
            };
        }
    }
    best
}

/// Whether a blob target's centroids held through the record: `Ok` when every frame was
/// measured with between half and twice the first frame's pixels, `Err` naming the first
/// frame (1-based) that was not and why.
pub fn blob_holds(centroids: &[Centroid]) -> Result<(), String> {
    let Some(first) = centroids.first().filter(|c| c.position().is_some()) else {
        return Err("lost in the first frame".to_string());
    };
    let n0 = first.moments.pixels as f64;
    for (f, c) in centroids.iter().enumerate() {
        if c.position().is_none() {
            return Err(format!("lost in frame {}", f + 1));
        }
        let r = c.moments.pixels as f64 / n0;
        if r < AREA_RANGE.0 || r > AREA_RANGE.1 {
            return Err(format!(
                "in frame {} its pixels above the threshold were {:.0} % of the first frame's \
                 (a neighbour in the window, or the target leaving it)",
                f + 1,
                r * 100.0
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn window(w: usize, h: usize, f: impl Fn(usize, usize) -> u8) -> (GreyFrame, Roi) {
        let data = (0..w * h).map(|i| f(i % w, i / w)).collect();
        (
            GreyFrame::U8 {
                width: w,
                height: h,
                data,
            },
            Roi {
                x: 0,
                y: 0,
                width: w as u32,
                height: h as u32,
            },
        )
    }

    #[test]
    fn a_bright_dot_on_a_plain_background_is_a_blob() {
        let (f, roi) = window(21, 21, |x, y| {
            let r2 = (x as f64 - 10.0).powi(2) + (y as f64 - 10.0).powi(2);
            if r2 <= 16.0 {
                220
            } else {
                20 + ((x * 7 + y * 3) % 5) as u8
            }
        });
        let why = separates(&f, roi, 120).unwrap();
        assert!(why.contains("compact spot"), "{why}");
    }

    #[test]
    fn a_white_tag_filling_the_window_a_dark_dot_two_spots_and_texture_are_not() {
        // a white tag with a black dot: the bright part fills the window
        let (f, roi) = window(21, 21, |x, y| {
            let r2 = (x as f64 - 10.0).powi(2) + (y as f64 - 10.0).powi(2);
            if r2 <= 9.0 {
                10
            } else {
                230
            }
        });
        assert!(separates(&f, roi, 120).unwrap_err().contains("fills it"));
        // two spots
        let (f, roi) = window(21, 21, |x, y| {
            if (3..6).contains(&x) && (3..6).contains(&y)
                || (14..18).contains(&x) && (14..18).contains(&y)
            {
                220
            } else {
                20
            }
        });
        assert!(separates(&f, roi, 120)
            .unwrap_err()
            .contains("several parts"));
        // a bright bar across the window touches its edge
        let (f, roi) = window(21, 21, |_, y| if (9..12).contains(&y) { 220 } else { 20 });
        assert!(separates(&f, roi, 120).unwrap_err().contains("edge"));
        // speckle: two levels mixed pixel by pixel, no clean gap
        let (f, roi) = window(21, 21, |x, y| ((x * 37 + y * 91) % 97) as u8 * 2);
        assert!(separates(&f, roi, 96).is_err());
    }

    #[test]
    fn a_blob_that_loses_or_doubles_its_pixels_does_not_hold() {
        let c = |pixels: u64| Centroid {
            cx: 5.0,
            cy: 5.0,
            moments: firmware_core::centroid::Moments {
                pixels,
                weight: pixels,
                sum_x: 5 * pixels,
                sum_y: 5 * pixels,
            },
            flags: Default::default(),
        };
        assert!(blob_holds(&[c(40), c(30), c(70)]).is_ok());
        assert!(blob_holds(&[c(40), c(30), c(90)])
            .unwrap_err()
            .contains("frame 3"));
        assert!(blob_holds(&[c(40), c(19)]).unwrap_err().contains("frame 2"));
    }
}
