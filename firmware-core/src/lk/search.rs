//! The coarse integer search: block then pixel ZNCC over `+-search` px around a start, the best
//! match and its rival (the ambiguity rule), and the jump rule's factor.

use super::*;

impl<const N: usize, const W: usize> LkTracker<N, W> {
    /// The coarse integer search around `p` (see the module documentation): the best integer
    /// displacement, or `Err(flags)` when no offset fits in the frame, the best one is on the
    /// edge of the range, or a rival match away from it scores nearly as well (ambiguous).
    pub(super) fn search<P: Pixel>(
        &self,
        frame: &Frame<'_, P>,
        p: (f32, f32),
    ) -> Result<(f32, f32), Flags> {
        let (tw, th) = (i64::from(self.config.width), i64::from(self.config.height));
        // no window displaced further than the frame is wide lies in it: a range beyond that
        // (65535) would only cost time
        let side = frame.width().max(frame.height()) as i64;
        let r = i64::from(self.config.search).min(side);
        let b = (r / 8).min(tw.min(th) / 3).max(1);
        let (cx, cy) = (floorf(p.0 + 0.5) as i64, floorf(p.1 + 0.5) as i64);
        // a rival is a match at least half the template's larger side from the best
        let apart = (tw.max(th) / 2).max(2);
        let mut best = Ranked::default();
        let sums = self.template_sums();
        let consider = |dx: i64, dy: i64, block: i64, best: &mut Ranked| {
            if (dx - cx).abs() > r || (dy - cy).abs() > r {
                return;
            }
            let score = match block {
                1 => self.zncc_pixels(frame, dx, dy, sums),
                _ => self.zncc_at(frame, dx, dy, block),
            };
            if let Some(s) = score {
                best.offer((s, dx, dy), apart);
            }
        };
        if b > 1 {
            let steps = r / b;
            for sy in -steps..=steps {
                for sx in -steps..=steps {
                    consider(cx + sx * b, cy + sy * b, b, &mut best);
                }
            }
        }
        let (fx, fy, span) = match best.best {
            Some((_, x, y)) => (x, y, b),
            None => (cx, cy, r),
        };
        let mut fine = Ranked::default();
        for dy in fy - span..=fy + span {
            for dx in fx - span..=fx + span {
                consider(dx, dy, 1, &mut fine);
            }
        }
        let Some((score, x, y)) = fine.best else {
            return Err(Flags::BORDER);
        };
        if score < self.config.min_score {
            return Err(Flags::DIVERGED);
        }
        // the rival of the pass that saw the whole range (block sums compared with block sums)
        let whole = if b > 1 { &best } else { &fine };
        if let (Some((top, ..)), Some((rival, ..))) = (whole.best, whole.rival) {
            if self.config.ambiguity > 0.0 && rival >= top - self.config.ambiguity {
                return Err(Flags::AMBIGUOUS);
            }
        }
        if r > 0 && r < side && ((x - cx).abs() == r || (y - cy).abs() == r) {
            return Err(Flags::DIVERGED);
        }
        // saturation is judged by the refinement that follows
        Ok((x as f32, y as f32))
    }

    /// The template's own sums of a search's ZNCC, `(sum vt, sum vt^2)` with `vt = t - mean`,
    /// the same at every offset.
    pub(super) fn template_sums(&self) -> (f32, f32) {
        let n = usize::from(self.config.width) * usize::from(self.config.height);
        let m = self.t_mean;
        self.t
            .get(..n)
            .unwrap_or_default()
            .iter()
            .fold((0.0, 0.0), |(a, b), t| (a + (t - m), b + (t - m) * (t - m)))
    }

    /// [`Self::zncc_at`] with blocks of one pixel, the template's sums given
    /// ([`Self::template_sums`]): the frame's sums in the backend's lanes
    /// (`kernels::zncc_sums`), so that a search costs a few operations per pixel and offset
    /// instead of a bounds-checked loop's tens. The same ZNCC to `f32` rounding (summed in
    /// another order).
    pub(super) fn zncc_pixels<P: Pixel>(
        &self,
        frame: &Frame<'_, P>,
        dx: i64,
        dy: i64,
        (st, stt): (f32, f32),
    ) -> Option<f32> {
        let (tw, th) = (
            usize::from(self.config.width),
            usize::from(self.config.height),
        );
        let (x0, y0) = (i64::from(self.origin.0) + dx, i64::from(self.origin.1) + dy);
        if x0 < 0 || y0 < 0 {
            return None;
        }
        let (x0, y0) = (x0 as usize, y0 as usize);
        if x0 + tw > frame.width() || y0 + th > frame.height() {
            return None;
        }
        let t = self.t.get(..tw * th)?;
        let rows = (y0..y0 + th).map_while(|y| frame.row(y)?.get(x0..x0 + tw));
        let [sf, sff, sft] = kernels::zncc_sums(t, tw, rows, self.t_mean);
        Some(zncc((st, stt), (sf, sff, sft), (tw * th) as f32))
    }

    /// ZNCC of `block x block` sums of the template and of the frame window displaced by
    /// `(dx, dy)` whole pixels; `None` when the window leaves the frame.
    pub(super) fn zncc_at<P: Pixel>(
        &self,
        frame: &Frame<'_, P>,
        dx: i64,
        dy: i64,
        block: i64,
    ) -> Option<f32> {
        let (tw, th) = (i64::from(self.config.width), i64::from(self.config.height));
        let (x0, y0) = (i64::from(self.origin.0) + dx, i64::from(self.origin.1) + dy);
        if x0 < 0 || y0 < 0 || x0 + tw > frame.width() as i64 || y0 + th > frame.height() as i64 {
            return None;
        }
        let (bw, bh) = (tw / block, th / block);
        let m = self.t_mean;
        let (mut st, mut stt, mut sf, mut sff, mut sft) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for by in 0..bh {
            for bx in 0..bw {
                let (mut vt, mut vf) = (0.0f32, 0.0f32);
                for j in by * block..(by + 1) * block {
                    let row = frame.row((y0 + j) as usize)?;
                    for i in bx * block..(bx + 1) * block {
                        let k = (j * tw + i) as usize;
                        vt += self.t.get(k).copied().unwrap_or(0.0) - m;
                        vf += f32::from(row.get((x0 + i) as usize).copied()?.into()) - m;
                    }
                }
                st += vt;
                stt += vt * vt;
                sf += vf;
                sff += vf * vf;
                sft += vf * vt;
            }
        }
        Some(zncc((st, stt), (sf, sff, sft), (bw * bh) as f32))
    }
}

/// The ZNCC of `n` pairs from their sums: the template's `(sum t, sum t^2)` and the frame's
/// `(sum f, sum f^2, sum f t)` (both offset by the same constant); 0 when either is flat.
#[inline]
fn zncc((st, stt): (f32, f32), (sf, sff, sft): (f32, f32, f32), n: f32) -> f32 {
    let (vt, vf) = (stt - st * st / n, sff - sf * sf / n);
    if vt > 0.0 && vf > 0.0 {
        (sft - st * sf / n) / sqrtf(vt * vf)
    } else {
        0.0
    }
}

/// A search's match further from its start than this many times the largest step seen so
/// far (and than half the template) is a jump the motion does not explain
/// ([`LkTracker::track`]).
pub const JUMP_FACTOR: f32 = 3.0;

/// The best match of a search and its best rival: the best-scoring offset at least `apart`
/// px (in either axis) from the best.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Ranked {
    pub(super) best: Option<(f32, i64, i64)>,
    pub(super) rival: Option<(f32, i64, i64)>,
}

impl Ranked {
    /// Takes a scored offset into account: a new best keeps the old one as the rival if it is
    /// apart from it (else the rival stays, if it is apart from the new best).
    pub(super) fn offer(&mut self, c: (f32, i64, i64), apart: i64) {
        let far = |a: (f32, i64, i64), b: (f32, i64, i64)| {
            (a.1 - b.1).abs() >= apart || (a.2 - b.2).abs() >= apart
        };
        match self.best {
            None => self.best = Some(c),
            Some(b) if c.0 > b.0 => {
                // the old best outranks every rival
                self.rival = match far(b, c) {
                    true => Some(b),
                    false => self.rival.filter(|&r| far(r, c)),
                };
                self.best = Some(c);
            }
            Some(b) => {
                if far(c, b) && self.rival.is_none_or(|r| c.0 > r.0) {
                    self.rival = Some(c);
                }
            }
        }
    }
}
