//! The motion shared by targets that move together (`group` column of `--points`, docs/
//! method.md §2.11): when a jump between two frames is larger than the distance between
//! look-alike targets (identical tags on a structure that is pulled and released), a search
//! around one target cannot tell its tag from the neighbour's; a person looks at the whole
//! storey. Here every target of a group shares one coarse offset from where it was last seen:
//! the one that maximises the sum of the members' zero-normalised cross-correlations (ZNCC)
//! of `b x b` block sums (`b` = [`BLOCK`]) over a grid of offsets `STEP` px apart within the
//! search range, then at every pixel within `STEP` of the best. A wrong offset that puts
//! one target on its neighbour puts the group's end target on the wall, and the tags' spacing
//! is never quite regular, so the sum is largest at the true motion.

use vibcam_readers::frames::GreyFrame;

/// Side of the blocks whose sums are correlated, px.
pub const BLOCK: usize = 4;
/// Spacing of the first grid of offsets, px.
const STEP: i64 = 4;

/// A target's template as block sums, zero-mean and unit-norm.
#[derive(Debug, Clone)]
pub struct BlockTemplate {
    /// Top-left pixel of the window in the first frame.
    origin: (i64, i64),
    /// Blocks across and down.
    blocks: (usize, usize),
    /// The normalised block sums, row-major; empty when the window is flat.
    t: Vec<f64>,
}

/// Summed-area table of a frame: the sum of any rectangle in four reads.
#[derive(Debug, Clone)]
pub struct Integral {
    w: usize,
    h: usize,
    s: Vec<f64>,
}

impl Integral {
    /// The table of `frame`.
    pub fn of(frame: &GreyFrame) -> Integral {
        let (w, h) = frame.dimensions();
        let mut s = vec![0.0f64; (w + 1) * (h + 1)];
        for y in 0..h {
            let mut row = 0.0;
            for x in 0..w {
                row += match frame {
                    GreyFrame::U8 { data, .. } => f64::from(data[y * w + x]),
                    GreyFrame::U16 { data, .. } => f64::from(data[y * w + x]),
                };
                s[(y + 1) * (w + 1) + x + 1] = s[y * (w + 1) + x + 1] + row;
            }
        }
        Integral { w, h, s }
    }

    /// Sum of the `b x b` block whose top-left pixel is `(x, y)` (inside the frame).
    fn block(&self, x: usize, y: usize, b: usize) -> f64 {
        let w1 = self.w + 1;
        self.s[(y + b) * w1 + x + b] - self.s[y * w1 + x + b] - self.s[(y + b) * w1 + x]
            + self.s[y * w1 + x]
    }
}

impl BlockTemplate {
    /// The window of `size` px whose top-left pixel is `origin` in the first frame.
    pub fn new(first: &Integral, origin: (i64, i64), size: (u32, u32)) -> BlockTemplate {
        let blocks = (size.0 as usize / BLOCK, size.1 as usize / BLOCK);
        let mut t = Vec::with_capacity(blocks.0 * blocks.1);
        let inside = origin.0 >= 0
            && origin.1 >= 0
            && origin.0 as usize + blocks.0 * BLOCK <= first.w
            && origin.1 as usize + blocks.1 * BLOCK <= first.h;
        if inside {
            for j in 0..blocks.1 {
                for i in 0..blocks.0 {
                    t.push(first.block(
                        origin.0 as usize + i * BLOCK,
                        origin.1 as usize + j * BLOCK,
                        BLOCK,
                    ));
                }
            }
        }
        let n = t.len().max(1) as f64;
        let mean = t.iter().sum::<f64>() / n;
        let norm = t.iter().map(|v| (v - mean).powi(2)).sum::<f64>().sqrt();
        if norm > 1e-9 {
            for v in &mut t {
                *v = (*v - mean) / norm;
            }
        } else {
            t.clear();
        }
        BlockTemplate { origin, blocks, t }
    }

    /// ZNCC of the template and the frame's window displaced by `d` px from the first frame
    /// (`None` when the window leaves the frame or either is flat).
    fn score(&self, frame: &Integral, d: (i64, i64)) -> Option<f64> {
        if self.t.is_empty() {
            return None;
        }
        let (x0, y0) = (self.origin.0 + d.0, self.origin.1 + d.1);
        let (bw, bh) = self.blocks;
        if x0 < 0
            || y0 < 0
            || x0 as usize + bw * BLOCK > frame.w
            || y0 as usize + bh * BLOCK > frame.h
        {
            return None;
        }
        let (x0, y0) = (x0 as usize, y0 as usize);
        let (mut sf, mut sff, mut stf) = (0.0, 0.0, 0.0);
        for j in 0..bh {
            for i in 0..bw {
                let f = frame.block(x0 + i * BLOCK, y0 + j * BLOCK, BLOCK);
                sf += f;
                sff += f * f;
                stf += self.t[j * bw + i] * f;
            }
        }
        let n = (bw * bh) as f64;
        let var = sff - sf * sf / n;
        (var > 1e-9).then(|| stf / var.sqrt())
    }
}

/// The offset (px, added to every member's last displacement) within `+-range` that maximises
/// the members' summed ZNCC, and the mean ZNCC there (a member whose window leaves the frame
/// counts 0). `members`: each target's template and its last displacement, rounded.
pub fn shared_offset(
    frame: &Integral,
    members: &[(&BlockTemplate, (i64, i64))],
    range: i64,
) -> Option<((i64, i64), f64)> {
    let total = |d: (i64, i64)| -> f64 {
        members
            .iter()
            .map(|(t, last)| t.score(frame, (last.0 + d.0, last.1 + d.1)).unwrap_or(0.0))
            .sum()
    };
    let mut best: Option<((i64, i64), f64)> = None;
    let consider = |d: (i64, i64), best: &mut Option<((i64, i64), f64)>| {
        let s = total(d);
        if best.is_none_or(|(_, b)| s > b) {
            *best = Some((d, s));
        }
    };
    let mut dy = -range;
    while dy <= range {
        let mut dx = -range;
        while dx <= range {
            consider((dx, dy), &mut best);
            dx += STEP;
        }
        dy += STEP;
    }
    let (c, _) = best?;
    for dy in c.1 - STEP + 1..c.1 + STEP {
        for dx in c.0 - STEP + 1..c.0 + STEP {
            if dx.abs() <= range && dy.abs() <= range {
                consider((dx, dy), &mut best);
            }
        }
    }
    best.map(|(d, s)| (d, s / members.len().max(1) as f64))
}
