//! Taking a template: the window of the reference frame, its cubic B-spline coefficients
//! (Unser's prefilter), gradients, Hessian and moments, and the mask of dark pixels the
//! saturation rule reads; the interpolation weights the template and the iteration share.

use super::*;

/// Row `y` of the frame smoothed along x by the first `taps` of `kernel` (centred), at
/// `x_first + i` into `out[i]`: the taps summed in order. Coordinates are offset by 8 (so they
/// stay unsigned past the top-left edge); past the frame's edges the edge pixels repeat.
fn smooth_x<P: Pixel>(
    frame: &Frame<'_, P>,
    (kernel, taps): ([f32; 5], usize),
    (x_first, y): (usize, usize),
    out: &mut [f32],
) {
    let (fw, fh) = (frame.width() as i64, frame.height() as i64);
    let row = frame
        .row((y as i64 - 8).min(fh - 1).max(0) as usize)
        .unwrap_or(&[]);
    let half = taps / 2;
    let lo = x_first as i64 - half as i64 - 8;
    let span = out.len() + taps.max(1) - 1;
    // inside the frame: the row's pixels themselves (most windows)
    if let Some(src) = usize::try_from(lo)
        .ok()
        .and_then(|lo| row.get(lo..lo + span))
    {
        for (o, win) in out.iter_mut().zip(src.windows(taps.max(1))) {
            let mut v = 0.0;
            for (w, p) in kernel.iter().zip(win) {
                v += w * f32::from((*p).into());
            }
            *o = v;
        }
        return;
    }
    let raw = |x: i64| {
        row.get((x - 8).min(fw - 1).max(0) as usize)
            .map_or(0.0, |&v| f32::from(v.into()))
    };
    for (i, o) in out.iter_mut().enumerate() {
        let mut v = 0.0;
        for (k, w) in kernel.iter().take(taps).enumerate() {
            v += w * raw((x_first + i + k) as i64 - half as i64);
        }
        *o = v;
    }
}

/// Cubic B-spline interpolation coefficients of the `w x h` image in `c` (row-major), in place:
/// the causal and anticausal recursive filters of Unser (1999) along the rows, then the
/// columns, pole `sqrt(3) - 2`, mirror-symmetric ends (the causal start summed over the first
/// 12 samples: `0.268^12 < 1e-6`).
pub(super) fn prefilter(c: &mut [f32], w: usize, h: usize) {
    fn line(c: &mut [f32], start: usize, step: usize, n: usize) {
        const Z: f32 = -0.267_949_2; // sqrt(3) - 2
        if n < 2 {
            return;
        }
        let at = |k: usize| start + k * step;
        for k in 0..n {
            if let Some(v) = c.get_mut(at(k)) {
                *v *= 6.0;
            }
        }
        let get = |c: &[f32], k: usize| c.get(at(k)).copied().unwrap_or(0.0);
        // causal: c+[0] from the mirrored start, then c+[k] = c[k] + z c+[k-1]
        let mut zk = 1.0f32;
        let mut first = 0.0f32;
        for k in 0..n.min(12) {
            first += zk * get(c, k);
            zk *= Z;
        }
        if let Some(v) = c.get_mut(at(0)) {
            *v = first;
        }
        for k in 1..n {
            let prev = get(c, k - 1);
            if let Some(v) = c.get_mut(at(k)) {
                *v += Z * prev;
            }
        }
        // anticausal: c[n-1] = z / (z^2 - 1) (c+[n-1] + z c+[n-2]), c[k] = z (c[k+1] - c+[k])
        let last = Z / (Z * Z - 1.0) * (get(c, n - 1) + Z * get(c, n - 2));
        if let Some(v) = c.get_mut(at(n - 1)) {
            *v = last;
        }
        for k in (0..n - 1).rev() {
            let next = get(c, k + 1);
            if let Some(v) = c.get_mut(at(k)) {
                *v = Z * (next - *v);
            }
        }
    }
    for j in 0..h {
        line(c, j * w, 1, w);
    }
    for i in 0..w {
        line(c, i, w, h);
    }
}

/// The derivatives of [`bspline_weights`] with respect to `f`: the spline's slope at `f`.
pub(super) fn bspline_slopes(f: f32) -> [f32; 4] {
    let g = 1.0 - f;
    [
        -0.5 * g * g,
        (3.0 * f * f - 4.0 * f) / 2.0,
        (-3.0 * f * f + 2.0 * f + 1.0) / 2.0,
        0.5 * f * f,
    ]
}

/// Cubic B-spline weights of the four coefficients at `-1, 0, 1, 2` for a fraction `f`.
pub(super) fn bspline_weights(f: f32) -> [f32; 4] {
    let g = 1.0 - f;
    [
        g * g * g / 6.0,
        (3.0 * f * f * f - 6.0 * f * f + 4.0) / 6.0,
        (-3.0 * f * f * f + 3.0 * f * f + 3.0 * f + 1.0) / 6.0,
        f * f * f / 6.0,
    ]
}

/// A frame pixel at or above the saturation level where the template (and its neighbours) is
/// below this fraction of it was clipped by a change (a brighter target, a neighbour's highlight), not by a plateau
/// that moves with the template.
pub(super) const CLIP_FRACTION: f32 = 0.75;

/// Whether the template is below [`CLIP_FRACTION`] of `sat` at pixel `(i, j)` and its eight
/// neighbours (the frame's window may sit up to a pixel off the template's grid): the
/// definition [`LkTracker::mark_dark`] computes for every pixel at once.
#[cfg(test)]
pub(super) fn dark_near(
    t: &[f32],
    (tw, th): (usize, usize),
    (i, j): (usize, usize),
    sat: u16,
) -> bool {
    let level = CLIP_FRACTION * f32::from(sat);
    for y in j.saturating_sub(1)..(j + 2).min(th) {
        for x in i.saturating_sub(1)..(i + 2).min(tw) {
            if t.get(y * tw + x).is_some_and(|&v| v >= level) {
                return false;
            }
        }
    }
    true
}

/// The `n` flags of `d` at `start`, `start + step`, ...: each one and its two neighbours
/// along the line (fewer at its ends), in place (a carry holds the flag before).
fn erode_line(d: &mut [bool], start: usize, step: usize, n: usize) {
    let mut before = true;
    for k in 0..n {
        let at = start + k * step;
        let next = k + 1 >= n || d.get(at + step).copied().unwrap_or(true);
        if let Some(v) = d.get_mut(at) {
            let now = *v;
            *v = before && now && next;
            before = now;
        }
    }
}

/// Stores the smoothed values `v` (integers) as `v - mean` into `out`; returns their sum and
/// sum of squares, exact (a value is below 2^24 in magnitude: the sum is formed in `i32` over
/// at most 127 values at a time, the squares in `i64`, which holds a row of up to 2^15).
#[inline(always)]
pub(super) fn emit(out: &mut [f32], mut v: impl Iterator<Item = u32>, mean: i32) -> (i64, i64) {
    let (mut sum, mut sq) = (0i64, 0i64);
    for seg in out.chunks_mut(127) {
        let mut rs = 0i32;
        for (o, v) in seg.iter_mut().zip(&mut v) {
            let d = v as i32 - mean;
            *o = d as f32;
            rs += d;
            sq += i64::from(d) * i64::from(d);
        }
        sum += i64::from(rs);
    }
    (sum, sq)
}

/// More newly clipped pixels than this in a window of `n` pixels lose the frame: two, and 2 %.
pub(super) fn clip_limit(n: usize) -> u32 {
    2 + (n / 50) as u32
}

/// The first `T` of eight weights.
pub(super) fn taps_of<const T: usize>(w: &[f32; 8]) -> [f32; T] {
    let mut out = [0.0; T];
    for (o, v) in out.iter_mut().zip(w) {
        *o = *v;
    }
    out
}

/// Keys' cubic convolution weights of the four taps at `-1, 0, 1, 2` for a fraction `f`.
pub(super) fn cubic_weights(f: f32) -> [f32; 4] {
    const A: f32 = -0.5;
    let near = |t: f32| ((A + 2.0) * t - (A + 3.0)) * t * t + 1.0;
    let far = |t: f32| ((A * t - 5.0 * A) * t + 8.0 * A) * t - 4.0 * A;
    [far(1.0 + f), near(f), near(1.0 - f), far(2.0 - f)]
}

impl<const N: usize, const W: usize> LkTracker<N, W> {
    /// The template's dark pixels ([`LkTracker::dark`]) for the saturation level `sat`,
    /// unless marked for it already.
    pub(super) fn mark_dark(&mut self, sat: u16) {
        if self.dark_sat == sat {
            return;
        }
        let (tw, th) = (
            usize::from(self.config.width),
            usize::from(self.config.height),
        );
        // below the level at the pixel (a NaN is below), then at its row neighbours, then at
        // its column neighbours: separably, what `dark_near` says of each pixel
        let level = CLIP_FRACTION * f32::from(sat);
        for (d, &v) in self.dark.iter_mut().zip(&self.t).take(tw * th) {
            *d = v.partial_cmp(&level).is_none_or(|o| o.is_lt());
        }
        for j in 0..th {
            erode_line(&mut self.dark, j * tw, 1, tw);
        }
        for i in 0..tw {
            erode_line(&mut self.dark, i, tw, th);
        }
        self.dark_sat = sat;
    }

    /// The template at `(x0, y0)`, its gradients and inverse Hessian.
    pub(super) fn take<P: Pixel>(
        &mut self,
        frame: &Frame<'_, P>,
        x0: i32,
        y0: i32,
    ) -> Result<(), LkError> {
        let (tw, th) = (
            usize::from(self.config.width),
            usize::from(self.config.height),
        );
        let (fw, fh) = (frame.width() as i64, frame.height() as i64);
        let (x0l, y0l) = (i64::from(x0), i64::from(y0));
        if x0l < 0 || y0l < 0 || x0l + tw as i64 > fw || y0l + th as i64 > fh {
            return Err(LkError::Outside);
        }
        // the gradients read one pixel around the window, the smoothing up to two more, the
        // spline's padding four: past the frame's edge the edge pixels repeat (coordinates
        // offset by 8 so they stay unsigned; see `smooth_x`)
        let (x0u, y0u) = (x0 as usize + 8, y0 as usize + 8);
        let (kernel, taps) = self.config.smoothing.kernel();
        let half = taps / 2;
        let spline = self.config.interpolation == Interpolation::Spline;
        let (pw, ph) = (tw + 2 * SPLINE_MARGIN, th + 2 * SPLINE_MARGIN);
        if spline {
            // the smoothed frame over the padded window, separably: each source row smoothed
            // along x once into a ring of `taps` rows (in `g`, which a new template
            // invalidates anyway), then the rows combined along y
            let (x_first, y_first) = (x0u - SPLINE_MARGIN, y0u - SPLINE_MARGIN);
            let ring = &mut self.g;
            let slot = |y: usize| (y % taps) * pw;
            // the next source row not yet in the ring
            let mut next = y_first - half;
            for j in 0..ph {
                let y = y_first + j;
                while next <= y + half {
                    if let Some(r) = ring.get_mut(slot(next)..slot(next) + pw) {
                        smooth_x(frame, (kernel, taps), (x_first, next), r);
                    }
                    next += 1;
                }
                // the taps' rows, once per row: each pixel their weighted sum, in order
                let mut rows: [&[f32]; 5] = [&[]; 5];
                for (k, r) in rows.iter_mut().enumerate().take(taps) {
                    let at = slot(y + k - half);
                    *r = ring.get(at..at + pw).unwrap_or(&[]);
                }
                let out = self.coef.get_mut(j * pw..j * pw + pw).unwrap_or(&mut []);
                for (i, c) in out.iter_mut().enumerate() {
                    let mut v = 0.0;
                    for (w, r) in kernel.iter().zip(&rows).take(taps) {
                        v += w * r.get(i).copied().unwrap_or(0.0);
                    }
                    *c = v;
                }
            }
            // the template is the smoothed frame over the window: the padded window's inside,
            // before the prefilter turns it into coefficients
            for j in 0..th {
                let from = (j + SPLINE_MARGIN) * pw + SPLINE_MARGIN;
                if let (Some(t), Some(c)) = (
                    self.t.get_mut(j * tw..j * tw + tw),
                    self.coef.get(from..from + tw),
                ) {
                    t.iter_mut().zip(c).for_each(|(t, c)| *t = *c);
                }
            }
            prefilter(&mut self.coef, pw, ph);
        }
        // the interpolant's derivative at whole pixels: [1 4 1] / 6 across, [-1 0 1] / 2 along
        let coef = &self.coef;
        // coefficient of template pixel (i, j), which may be up to the margin outside it
        let c = |i: i64, j: i64| {
            let m = SPLINE_MARGIN as i64;
            coef.get(((j + m) * pw as i64 + i + m) as usize)
                .copied()
                .unwrap_or(0.0)
        };
        let spline_grad = |i: i64, j: i64| -> (f32, f32) {
            let dx = |j: i64| 0.5 * (c(i + 1, j) - c(i - 1, j));
            let dy = |i: i64| 0.5 * (c(i, j + 1) - c(i, j - 1));
            (
                (dx(j - 1) + 4.0 * dx(j) + dx(j + 1)) / 6.0,
                (dy(i - 1) + 4.0 * dy(i) + dy(i + 1)) / 6.0,
            )
        };
        let (mut sxx, mut sxy, mut syy, mut sum) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        if spline {
            // the template taken above, the spline's slopes
            let at = self
                .t
                .iter()
                .zip(self.gx.iter_mut().zip(self.gy.iter_mut()))
                .take(tw * th);
            let (mut i, mut j) = (0i64, 0i64);
            for (&v, (a, b)) in at {
                let (gx, gy) = spline_grad(i, j);
                i += 1;
                if i == tw as i64 {
                    (i, j) = (0, j + 1);
                }
                *a = gx;
                *b = gy;
                sum += v;
                sxx += gx * gx;
                sxy += gx * gy;
                syy += gy * gy;
            }
        }
        // without the spline: the smoothed frame over the window and one pixel around it, a
        // row at a time: the frame's rows smoothed along x once each (a ring of `taps` rows),
        // combined along y into a ring of three smoothed rows; central differences
        let (h_ring, s_ring) = self.ring.split_at_mut(5);
        let (x_first, width) = (x0u - 1, tw + 2);
        let mut h_next = y0u - 1 - half;
        let mut s_next = y0u - 1;
        for j in (0..th).filter(|_| !spline) {
            let y = y0u + j;
            while s_next <= y + 1 {
                while h_next <= s_next + half {
                    if let Some(r) = h_ring
                        .get_mut(h_next % taps)
                        .and_then(|r| r.get_mut(..width))
                    {
                        smooth_x(frame, (kernel, taps), (x_first, h_next), r);
                    }
                    h_next += 1;
                }
                if let Some(r) = s_ring.get_mut(s_next % 3) {
                    // the taps' rows summed in order into each pixel (a row at a time)
                    let out = r.get_mut(..width).unwrap_or(&mut []);
                    out.fill(0.0);
                    for (k, w) in kernel.iter().take(taps).enumerate() {
                        let h = h_ring.get((s_next + k - half) % taps);
                        for (o, v) in out.iter_mut().zip(h.map_or(&[][..], |h| &h[..])) {
                            *o += w * v;
                        }
                    }
                }
                s_next += 1;
            }
            // the smoothed rows at y - 1, y, y + 1, from x0u - 1 (the window and a pixel around)
            let rows = |e: usize| s_ring.get((y + e - 1) % 3).map_or(&[][..], |r| &r[..]);
            let (up, mid, down) = (rows(0), rows(1), rows(2));
            fn cut(a: &mut [f32], (j, tw): (usize, usize)) -> &mut [f32] {
                a.get_mut(j * tw..j * tw + tw).unwrap_or(&mut [])
            }
            let (t, gxs, gys) = (
                cut(&mut self.t, (j, tw)),
                cut(&mut self.gx, (j, tw)),
                cut(&mut self.gy, (j, tw)),
            );
            let at = mid
                .windows(3)
                .zip(up.iter().skip(1).zip(down.iter().skip(1)));
            for ((m, (u, d)), (t, (a, b))) in
                at.zip(t.iter_mut().zip(gxs.iter_mut().zip(gys.iter_mut())))
            {
                let (gx, gy) = (0.5 * (m[2] - m[0]), 0.5 * (d - u));
                let v = m[1];
                *t = v;
                *a = gx;
                *b = gy;
                sum += v;
                sxx += gx * gx;
                sxy += gx * gy;
                syy += gy * gy;
            }
        }
        let n = (tw * th) as f32;
        // smaller eigenvalue of [[sxx, sxy], [sxy, syy]], per pixel
        let half_tr = 0.5 * (sxx + syy);
        let det = sxx * syy - sxy * sxy;
        let disc = sqrtf((half_tr * half_tr - det).max(0.0));
        let lambda_min = half_tr - disc;
        // written so that a NaN (no texture at all) is flat too
        let textured = lambda_min / n >= self.config.min_texture && det > 0.0;
        if !textured {
            return Err(LkError::Flat);
        }
        self.h_inv = [syy / det, -sxy / det, sxx / det];
        let mean = sum / n;
        let mut ss = 0.0f32;
        for v in self.t.iter().take(tw * th) {
            ss += (v - mean) * (v - mean);
        }
        self.t_mean = mean;
        self.t_norm = sqrtf(ss);
        // a new template: its own mask
        self.dark_sat = 0;
        self.mark_dark(match self.config.saturation {
            0 => P::FULL,
            s => s,
        });
        if spline {
            // the spline's weights sum to one: the mean comes off the coefficients
            for c in self.coef.iter_mut().take(pw * ph) {
                *c -= mean;
            }
            self.moments = Moments::of(&self.coef, (tw, th));
        }
        self.origin = (x0, y0);
        self.g_at = None;
        self.ready = true;
        Ok(())
    }
}
