//! The frame's window at a whole-pixel position: loaded, smoothed like the template (exact
//! integer arithmetic) and counted for clipped pixels.

use super::*;

impl<const N: usize, const W: usize> LkTracker<N, W> {
    /// The frame's window at the template's origin plus `q` into `g` (smoothed as the template
    /// was; past the frame's edge the edge pixels repeat), less the template's mean, and its
    /// own moments into `cross`; `Err` when the window leaves the frame or has more clipped
    /// pixels than the template.
    pub(super) fn load_window<P: Pixel>(
        &mut self,
        frame: &Frame<'_, P>,
        q: (i64, i64),
        sat: u16,
    ) -> Result<(), Flags> {
        let (tw, th) = (
            usize::from(self.config.width),
            usize::from(self.config.height),
        );
        let (fw, fh) = (frame.width() as i64, frame.height() as i64);
        let (x0, y0) = (
            i64::from(self.origin.0) + q.0,
            i64::from(self.origin.1) + q.1,
        );
        if x0 < 0 || y0 < 0 || x0 + tw as i64 > fw || y0 + th as i64 > fh {
            return Err(Flags::BORDER);
        }
        // one monomorphised pass per kernel length, so every inner loop has a constant length
        let at = (x0, y0, sat);
        let saturated = match self.config.smoothing {
            Smoothing::None => self.smooth_window::<P, 1>(frame, at, [1]),
            Smoothing::Binomial3 => self.smooth_window::<P, 3>(frame, at, [1, 2, 1]),
            Smoothing::Binomial5 => self.smooth_window::<P, 5>(frame, at, [1, 4, 6, 4, 1]),
        };
        if saturated > clip_limit(tw * th) {
            return Err(Flags::SATURATED);
        }
        Ok(())
    }

    /// [`load_window`](Self::load_window) with the `T`-tap binomial kernel `k` (its sum a
    /// power of two), in integers: per window row, the `T` source rows summed down each
    /// column, then along the row; the smoothed value `v` (the template's scale times the
    /// kernel's total squared) is stored as `v - M`, `M` the nearest integer to the template's
    /// mean on that scale, exact in `f32` (the cross moments and the window's sums are formed
    /// from these, see [`Cross::window`]). Returns the count of newly clipped pixels.
    pub(super) fn smooth_window<P: Pixel, const T: usize>(
        &mut self,
        frame: &Frame<'_, P>,
        (x0, y0, sat): (i64, i64, u16),
        k: [u32; T],
    ) -> u32 {
        let (tw, th) = (
            usize::from(self.config.width),
            usize::from(self.config.height),
        );
        let (fw, fh) = (frame.width() as i64, frame.height() as i64);
        let half = (T / 2) as i64;
        let total: u32 = k.iter().sum();
        let scale = 1.0 / (total * total) as f32;
        // the template's mean on the integer scale (at most 2^24: a u16 pixel times 256)
        let mean = (self.t_mean / scale + 0.5).max(0.0) as i32;
        let gs = window_stride(tw);
        let inside = x0 - half >= 0 && x0 + tw as i64 + half <= fw;
        let LkTracker {
            g,
            dark,
            t_mean,
            cross,
            ..
        } = self;
        let n = (tw * th) as f32;
        // 8-bit frames with the whole source inside: the backend's whole-window pass, if it
        // has one (the same exact integers as the rows below)
        let stride = frame.stride();
        let whole = (T == 3 && inside && y0 >= half && y0 + th as i64 + half <= fh)
            .then(|| P::bytes(frame.pixels()))
            .flatten()
            .and_then(|px| {
                let at = (y0 - half) as usize * stride + (x0 - half) as usize;
                let src = px.get(at..)?;
                let (s, q, top) =
                    kernels::smooth_window3_bytes(src, stride, (tw, th), (&mut g[..], gs), mean)?;
                Some((s, q, top, src.get(stride + 1..).unwrap_or(&[])))
            });
        if let Some((s, q, top, win)) = whole {
            let mut saturated = 0;
            if top >= sat {
                saturated = match kernels::clipped_window_bytes(win, stride, (tw, th), dark, sat) {
                    Some(c) => c,
                    None => (0..th)
                        .map(|j| {
                            let row = win.get(j * stride..j * stride + tw).unwrap_or(&[]);
                            kernels::newly_clipped(row, dark.get(j * tw..).unwrap_or(&[]), sat)
                        })
                        .sum(),
                };
            }
            *cross = Cross::window(s, i128::from(q), mean, scale, *t_mean, n);
            return saturated;
        }
        // the window's sum and sum of squares: rows' sums in i64, the total of the squares in
        // i128 (any window size)
        let (mut sum, mut sq) = (0i64, 0i128);
        let mut saturated = 0u32;
        // source row `r` (frame row y0 - half + r), repeated at the frame's top and bottom
        let source = |r: usize| {
            let y = (y0 - half + r as i64).min(fh - 1).max(0) as usize;
            frame.row(y).unwrap_or(&[])
        };
        // the T source rows of window row j, slid down one row per window row
        let mut rows: [&[P]; T] = [&[]; T];
        for (n, r) in rows.iter_mut().enumerate().skip(1) {
            *r = source(n - 1);
        }
        let start = (x0 - half).max(0) as usize;
        for (j, row) in g.chunks_exact_mut(gs.max(4)).take(th).enumerate() {
            rows.rotate_left(1);
            if let Some(last) = rows.last_mut() {
                *last = source(j + T - 1);
            }
            let (out, pad) = row.split_at_mut(tw.min(row.len()));
            pad.fill(0.0);
            let segs = rows.map(|r| r.get(start..start + tw + T - 1).filter(|_| inside));
            // the brightest pixel of the centre row (the window's row and its margin), on the way
            let mut top = 0u16;
            let fast = match (T, segs.as_slice()) {
                (1, [Some(a)]) => {
                    let v = a.iter().map(|&a| {
                        let a = a.into();
                        top = top.max(a);
                        u32::from(a)
                    });
                    let (rs, rq) = emit(out, v, mean);
                    sum += rs;
                    sq += i128::from(rq);
                    true
                }
                (3, [Some(a), Some(b), Some(c)]) => {
                    match kernels::smooth_row3(a, b, c, out, mean) {
                        Some((rs, rq, rt)) => {
                            top = rt;
                            sum += rs;
                            sq += i128::from(rq);
                            true
                        }
                        None => false,
                    }
                }
                (5, [Some(a), Some(b), Some(c), Some(d), Some(e)]) => {
                    let mut cols = a
                        .iter()
                        .zip(b.iter())
                        .zip(c.iter())
                        .zip(d.iter())
                        .zip(e.iter())
                        .map(|((((&a, &b), &c), &d), &e)| {
                            let w = |p: P| u32::from(p.into());
                            let c = c.into();
                            top = top.max(c);
                            w(a) + 4 * w(b) + 6 * u32::from(c) + 4 * w(d) + w(e)
                        });
                    let mut p = [0u32; 4];
                    for v in p.iter_mut() {
                        *v = cols.next().unwrap_or(0);
                    }
                    let v = cols.map(|c4| {
                        let [p0, p1, p2, p3] = p;
                        p = [p1, p2, p3, c4];
                        p0 + 4 * p1 + 6 * p2 + 4 * p3 + c4
                    });
                    let (rs, rq) = emit(out, v, mean);
                    sum += rs;
                    sq += i128::from(rq);
                    true
                }
                _ => false,
            };
            if fast {
                // the common case: nothing at the saturation level in the row
                if top >= sat {
                    let centre = match segs.get(T / 2) {
                        Some(Some(c)) => c.get(T / 2..T / 2 + tw).unwrap_or(&[]),
                        _ => &[],
                    };
                    let dark = dark.get(j * tw..j * tw + tw).unwrap_or(&[]);
                    saturated += kernels::newly_clipped(centre, dark, sat);
                }
                continue;
            }
            // at the frame's left or right edge: the edge pixels repeat
            let px = |r: &[P], x: i64| -> u32 {
                let x = x.min(fw - 1).max(0) as usize;
                r.get(x).map_or(0, |p| u32::from((*p).into()))
            };
            for (i, o) in out.iter_mut().enumerate() {
                let x = x0 + i as i64;
                let mut v = 0u32;
                for (kx, dx) in k.iter().zip(-half..) {
                    for (ky, r) in k.iter().zip(&rows) {
                        v += kx * ky * px(r, x + dx);
                    }
                }
                let (rs, rq) = emit(core::slice::from_mut(o), [v].into_iter(), mean);
                sum += rs;
                sq += i128::from(rq);
                let raw = rows.get(T / 2).map_or(0, |r| px(r, x)) as u16;
                let dark = dark.get(j * tw + i).is_some_and(|&d| d);
                saturated += u32::from(raw >= sat && dark);
            }
        }
        *cross = Cross::window(sum, sq, mean, scale, *t_mean, n);
        saturated
    }
}
