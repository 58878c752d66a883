//! The refinement: inverse-compositional Gauss-Newton steps from a start, the error of the
//! warped window by the spline or the convolution kernels, the unexplained-jump rule and the
//! template refresh.

use super::*;

impl<const N: usize, const W: usize> LkTracker<N, W> {
    pub(super) fn track_inner<P: Pixel>(
        &mut self,
        frame: &Frame<'_, P>,
        given: Option<(f32, f32)>,
    ) -> LkResult {
        let mut out = LkResult {
            dx: 0.0,
            dy: 0.0,
            flags: Flags::NONE,
            iterations: 0,
            score: 0.0,
            searched: false,
        };
        if !self.ready {
            out.flags = Flags::DIVERGED;
            return out;
        }
        // a new frame: the spline path's window buffer holds the last one's
        self.g_at = None;
        let sat = match self.config.saturation {
            0 => P::FULL,
            s => s,
        };
        // (a template taken from frames of another pixel type)
        self.mark_dark(sat);
        // constant-velocity prediction from the last two tracked frames (none after a loss),
        // unless the caller gives the start
        let mut start = match given {
            Some((dx, dy)) if dx.is_finite() && dy.is_finite() => {
                (dx - self.base.0, dy - self.base.1)
            }
            Some(_) => {
                out.flags = Flags::DIVERGED;
                return out;
            }
            None => (self.p.0 + self.v.0, self.p.1 + self.v.1),
        };
        let mut first = self.refine(frame, start, sat, &mut out);
        if first == Err(Flags::BORDER) && start != self.p {
            // the prediction overshoots past the frame's edge: start where the target was
            start = self.p;
            first = self.refine(frame, start, sat, &mut out);
        }
        let accepted = match first {
            Ok((p, score, settled)) if settled && score >= self.config.accept_score => {
                Some((p, score))
            }
            _ => None,
        };
        let result = match accepted {
            Some(r) => Ok(r),
            // the window at the last position reaches past the frame's edge: the target is
            // leaving; a search would find something else
            None if first == Err(Flags::BORDER) => Err(Flags::BORDER),
            None if self.config.search > 0 => {
                out.searched = true;
                match self.search(frame, start) {
                    Err(flags) => Err(flags),
                    Ok(q) => match self.refine(frame, q, sat, &mut out) {
                        Ok((p, _, true)) if self.unexplained(p, start) => Err(Flags::AMBIGUOUS),
                        Ok((p, score, true)) if score >= self.config.min_score => Ok((p, score)),
                        Ok((_, score, _)) => {
                            out.score = score;
                            Err(Flags::DIVERGED)
                        }
                        Err(f) => Err(f),
                    },
                }
            }
            None => match first {
                Ok((p, score, true)) if score >= self.config.min_score => Ok((p, score)),
                Ok((_, score, _)) => {
                    out.score = score;
                    Err(Flags::DIVERGED)
                }
                Err(f) => Err(f),
            },
        };
        match result {
            Ok((p, score)) => {
                self.v = (p.0 - self.p.0, p.1 - self.p.1);
                self.max_step = self.max_step.max(fabsf(self.v.0).max(fabsf(self.v.1)));
                self.p = p;
                out.score = score;
                let (dx, dy) = self.displacement();
                out.dx = dx;
                out.dy = dy;
                if score < self.config.refresh_below {
                    self.refresh(frame);
                }
            }
            Err(f) => {
                self.v = (0.0, 0.0);
                out.flags.insert(f);
            }
        }
        out
    }

    /// Whether a match the search found at `p` lies further from where the search started
    /// (`start`: the prediction, or the caller's start) than the motion seen so far explains:
    /// more than [`JUMP_FACTOR`] times the largest step between two tracked frames, and more
    /// than half the template's larger side (the default search range: a search within it is
    /// always explained). A look-alike neighbour found by a long search is taken for a
    /// jump of the target no more: the frame is lost ([`Flags::AMBIGUOUS`]).
    pub(super) fn unexplained(&self, p: (f32, f32), start: (f32, f32)) -> bool {
        let jump = fabsf(p.0 - start.0).max(fabsf(p.1 - start.1));
        let half = f32::from(self.config.width.max(self.config.height)) / 2.0;
        jump > half && jump > JUMP_FACTOR * self.max_step
    }

    /// Re-takes the template at the current position (the refresh rule); a refused template
    /// keeps the old one.
    pub(super) fn refresh<P: Pixel>(&mut self, frame: &Frame<'_, P>) {
        let (rx, ry) = (floorf(self.p.0 + 0.5), floorf(self.p.1 + 0.5));
        let (x0, y0) = (self.origin.0 + rx as i32, self.origin.1 + ry as i32);
        // a refused template (flat, outside) must leave the old one whole: keep a copy
        let saved = (
            self.origin,
            self.h_inv,
            self.t_mean,
            self.t_norm,
            self.moments,
        );
        let (t, gx, gy, coef) = (self.t, self.gx, self.gy, self.coef);
        if self.take(frame, x0, y0).is_ok() {
            self.base = (self.base.0 + rx, self.base.1 + ry);
            self.p = (self.p.0 - rx, self.p.1 - ry);
        } else {
            (
                self.origin,
                self.h_inv,
                self.t_mean,
                self.t_norm,
                self.moments,
            ) = saved;
            (self.t, self.gx, self.gy, self.coef) = (t, gx, gy, coef);
            self.g_at = None;
            self.ready = true;
        }
    }

    /// The taps of one axis for a fraction `f` (interpolation, with the smoothing folded in):
    /// the weights, how many lead the whole-pixel position, and how many there are.
    pub(super) fn weights(&self, f: f32) -> ([f32; 8], i64, usize) {
        let (base, lead, n): ([f32; 4], i64, usize) = match self.config.interpolation {
            Interpolation::Bicubic | Interpolation::Spline => (cubic_weights(f), 1, 4),
            Interpolation::Bilinear => ([1.0 - f, f, 0.0, 0.0], 0, 2),
        };
        let (kernel, taps) = self.config.smoothing.kernel();
        // the smoothing kernel convolved with the interpolation taps
        let mut w = [0.0f32; 8];
        for (i, b) in base.iter().take(n).enumerate() {
            for (k, s) in kernel.iter().take(taps).enumerate() {
                if let Some(o) = w.get_mut(i + k) {
                    *o += b * s;
                }
            }
        }
        (w, lead + (taps / 2) as i64, n + taps - 1)
    }

    /// Inverse-compositional refinement from `p`: the displacement, its ZNCC and whether the
    /// last step was below 0.1 px; `Err(flags)` when the window leaves the frame or saturates.
    pub(super) fn refine<P: Pixel>(
        &mut self,
        frame: &Frame<'_, P>,
        mut p: (f32, f32),
        sat: u16,
        out: &mut LkResult,
    ) -> Result<((f32, f32), f32, bool), Flags> {
        let mut step = f32::INFINITY;
        let mut score = 0.0;
        let from = p;
        let weak = self.weak_direction();
        for _ in 0..self.config.max_iterations {
            out.iterations = out.iterations.saturating_add(1);
            let (b, s) = if self.config.interpolation == Interpolation::Spline {
                self.spline_error(frame, p, sat)?
            } else {
                self.warp_error(frame, p, sat)?
            };
            score = s;
            let dx = self.h_inv[0] * b.0 + self.h_inv[1] * b.1;
            let dy = self.h_inv[1] * b.0 + self.h_inv[2] * b.1;
            p = (p.0 - dx, p.1 - dy);
            step = match weak {
                None => sqrtf(dx * dx + dy * dy),
                // a window that measures one direction only: the step along the other scaled
                // by how weakly the window measures it ([`APERTURE`])
                Some(((wx, wy), r)) => {
                    let (along, across) = (dx * wx + dy * wy, dy * wx - dx * wy);
                    sqrtf(across * across + r * r * along * along)
                }
            };
            if !step.is_finite() {
                return Err(Flags::DIVERGED);
            }
            if step < self.config.tolerance {
                break;
            }
            // a refinement that runs away from its start (more than the window) has lost the
            // target
            if fabsf(p.0 - from.0) > f32::from(self.config.width) + f32::from(self.config.search)
                || fabsf(p.1 - from.1)
                    > f32::from(self.config.height) + f32::from(self.config.search)
            {
                return Err(Flags::DIVERGED);
            }
        }
        Ok((p, score, step < 0.1))
    }

    /// The template's weak direction when it measures one direction only (the smaller
    /// eigenvalue of its structure tensor below [`APERTURE`] times the larger: stripes, a
    /// straight edge): the unit eigenvector of the smaller eigenvalue and
    /// `sqrt(lambda_2 / lambda_1)`; `None` for a template textured both ways.
    pub(super) fn weak_direction(&self) -> Option<((f32, f32), f32)> {
        let [a, b, c] = self.structure();
        let half_tr = 0.5 * (a + c);
        let disc = sqrtf(0.25 * (a - c) * (a - c) + b * b);
        let (l1, l2) = (half_tr + disc, (half_tr - disc).max(0.0));
        if !(l1 > 0.0 && l1.is_finite()) || l2 >= APERTURE * l1 {
            return None;
        }
        // (H - l2 I) v = 0 by either row, the one of larger coefficients
        let (vx, vy) = if fabsf(a - l2) >= fabsf(c - l2) {
            (b, l2 - a)
        } else {
            (l2 - c, b)
        };
        let n = sqrtf(vx * vx + vy * vy);
        (n > 0.0 && n.is_finite()).then(|| ((vx / n, vy / n), sqrtf(l2 / l1)))
    }

    /// Interpolates the frame at the template's pixels shifted by `p`: returns
    /// `sum [gx e, gy e]` with `e = I(x + p) - T(x)`, and the ZNCC of the warped window and the
    /// template.
    pub(super) fn warp_error<P: Pixel>(
        &mut self,
        frame: &Frame<'_, P>,
        p: (f32, f32),
        sat: u16,
    ) -> Result<((f32, f32), f32), Flags> {
        let (ix, iy) = (floorf(p.0), floorf(p.1));
        if !(ix.is_finite() && iy.is_finite()) || fabsf(ix) > 1e6 || fabsf(iy) > 1e6 {
            return Err(Flags::DIVERGED);
        }
        let (fx, fy) = (p.0 - ix, p.1 - iy);
        let (wx, lead, taps) = self.weights(fx);
        let (wy, _, _) = self.weights(fy);
        let at = (ix as i64, iy as i64, lead);
        // one monomorphised pass per tap count, so every inner loop has a constant length
        match taps {
            2 => self.warp::<P, 2>(frame, at, (&wx, &wy), sat),
            4 => self.warp::<P, 4>(frame, at, (&wx, &wy), sat),
            6 => self.warp::<P, 6>(frame, at, (&wx, &wy), sat),
            _ => self.warp::<P, 8>(frame, at, (&wx, &wy), sat),
        }
    }

    /// [`warp_error`](Self::warp_error) with `T` taps per axis: the window's top-left source
    /// pixel at the template's origin plus `(ix, iy)` less `lead`.
    pub(super) fn warp<P: Pixel, const T: usize>(
        &mut self,
        frame: &Frame<'_, P>,
        (ix, iy, lead): (i64, i64, i64),
        (wx, wy): (&[f32; 8], &[f32; 8]),
        sat: u16,
    ) -> Result<((f32, f32), f32), Flags> {
        let (tw, th) = (
            usize::from(self.config.width),
            usize::from(self.config.height),
        );
        let (wx, wy): ([f32; T], [f32; T]) = (taps_of(wx), taps_of(wy));
        // source columns x_first .. x_first + tw + T - 1, rows likewise; the window itself must
        // be inside the frame, the interpolation's support beyond it repeats the edge pixels
        let x_first = i64::from(self.origin.0) + ix - lead;
        let y_first = i64::from(self.origin.1) + iy - lead;
        let (fw, fh) = (frame.width() as i64, frame.height() as i64);
        let (x_win, y_win) = (x_first + lead, y_first + lead);
        if x_win < 0 || y_win < 0 || x_win + tw as i64 > fw || y_win + th as i64 > fh {
            return Err(Flags::BORDER);
        }
        let span = tw + T - 1;
        let lead = lead as usize;
        let mut saturated = 0u32;
        let (bx, by, sd, sdd, sdt) = {
            let LkTracker {
                t,
                dark,
                gx,
                gy,
                ring,
                src,
                acc,
                t_mean,
                ..
            } = self;
            let m = *t_mean;
            // source row `r` to floats (edge pixels repeated), then its horizontal pass into
            // ring slot `r % 8`
            let mut fill = |ring: &mut [[f32; W]; 8], r: usize| {
                let y = (y_first + r as i64).min(fh - 1).max(0) as usize;
                let row = frame.row(y).unwrap_or(&[]);
                let Some(src) = src.get_mut(..span) else {
                    return;
                };
                let inside = x_first >= 0 && x_first + span as i64 <= fw;
                match row.get(x_first.max(0) as usize..).filter(|_| inside) {
                    Some(seg) => {
                        for (o, v) in src.iter_mut().zip(seg) {
                            *o = f32::from((*v).into());
                        }
                        if (lead..lead + th).contains(&r) {
                            let whole = seg.get(lead..lead + tw).unwrap_or(&[]);
                            let j = (r - lead) * tw;
                            let dark = dark.get(j..j + tw).unwrap_or(&[]);
                            saturated += kernels::newly_clipped(whole, dark, sat);
                        }
                    }
                    None => {
                        for (c, o) in src.iter_mut().enumerate() {
                            let x = (x_first + c as i64).min(fw - 1).max(0) as usize;
                            let v = row.get(x).map_or(0, |v| (*v).into());
                            *o = f32::from(v);
                            let in_window =
                                (lead..lead + tw).contains(&c) && (lead..lead + th).contains(&r);
                            saturated += u32::from(
                                in_window
                                    && v >= sat
                                    && dark.get((r - lead) * tw + c - lead).is_some_and(|&d| d),
                            );
                        }
                    }
                }
                let slot = &mut ring[r % 8];
                for (o, win) in slot.iter_mut().zip(src.windows(T)) {
                    let mut v = 0.0;
                    for (a, b) in wx.iter().zip(win) {
                        v += a * b;
                    }
                    *o = v;
                }
            };
            for r in 0..T - 1 {
                fill(ring, r);
            }
            let (mut bx, mut by) = (0.0f32, 0.0f32);
            let (mut sd, mut sdd, mut sdt) = (0.0f32, 0.0f32, 0.0f32);
            for j in 0..th {
                fill(ring, j + T - 1);
                let Some(acc) = acc.get_mut(..tw) else {
                    break;
                };
                // the vertical pass, the first tap's row written, the others added
                let mut first = true;
                for (k, w) in wy.iter().enumerate() {
                    let row = &ring[(j + k) % 8];
                    if first {
                        for (a, r) in acc.iter_mut().zip(row.iter()) {
                            *a = w * r;
                        }
                        first = false;
                    } else {
                        for (a, r) in acc.iter_mut().zip(row.iter()) {
                            *a += w * r;
                        }
                    }
                }
                let rows = j * tw..(j + 1) * tw;
                let (Some(t), Some(gx), Some(gy)) =
                    (t.get(rows.clone()), gx.get(rows.clone()), gy.get(rows))
                else {
                    break;
                };
                for (((&v, &t), &gx), &gy) in acc.iter().zip(t).zip(gx).zip(gy) {
                    let e = v - t;
                    bx += gx * e;
                    by += gy * e;
                    // the ZNCC's sums about the template mean (small numbers: no cancellation)
                    let d = v - m;
                    sd += d;
                    sdd += d * d;
                    sdt += d * (t - m);
                }
            }
            (bx, by, sd, sdd, sdt)
        };
        // a clipped plateau that moves with the template is tracked; more clipped pixels than
        // the template had (brighter, or a neighbour's) break brightness constancy
        if saturated > clip_limit(tw * th) {
            return Err(Flags::SATURATED);
        }
        let n = (tw * th) as f32;
        let var = sdd - sd * sd / n;
        let score = if var > 0.0 && self.t_norm > 0.0 {
            sdt / (sqrtf(var) * self.t_norm)
        } else {
            0.0
        };
        Ok(((bx, by), score))
    }

    /// [`warp_error`](Self::warp_error) for [`Interpolation::Spline`]: the frame's window at
    /// the whole-pixel part `q` of `p` against the template's spline shifted by `q - p`;
    /// returns `sum [gx e, gy e]` with `e = I(x + q) - T(x - (p - q))` and the ZNCC.
    ///
    /// `q` is the nearest whole pixel, except that within a frame the window already read is
    /// kept while `p` stays within [`KEEP`] px of it (hysteresis): when the template does not
    /// match the frame exactly (a blur that changes from frame to frame), the error measured on
    /// two neighbouring windows differs slightly, and with the plain nearest pixel an optimum
    /// near a half pixel made the iteration jump between the two windows without settling.
    pub(super) fn spline_error<P: Pixel>(
        &mut self,
        frame: &Frame<'_, P>,
        p: (f32, f32),
        sat: u16,
    ) -> Result<((f32, f32), f32), Flags> {
        let (qx, qy) = match self.g_at {
            Some((x, y)) if fabsf(p.0 - x as f32) <= KEEP && fabsf(p.1 - y as f32) <= KEEP => {
                (x as f32, y as f32)
            }
            _ => (floorf(p.0 + 0.5), floorf(p.1 + 0.5)),
        };
        if !(qx.is_finite() && qy.is_finite()) || fabsf(qx) > 1e6 || fabsf(qy) > 1e6 {
            return Err(Flags::DIVERGED);
        }
        let (tw, th) = (
            usize::from(self.config.width),
            usize::from(self.config.height),
        );
        let q = (qx as i64, qy as i64);
        if self.g_at != Some(q) {
            self.load_window(frame, q, sat)?;
            self.g_at = Some(q);
        }
        // the template's pixels shifted by s = q - p, |s| <= KEEP < 1: taps at a - 1 .. a + 2,
        // among the lags -2 ..= 2
        let (sx, sy) = (qx - p.0, qy - p.1);
        let (ax, ay) = (floorf(sx), floorf(sy));
        if !(-1.0..=0.0).contains(&ax) || !(-1.0..=0.0).contains(&ay) {
            return Err(Flags::DIVERGED);
        }
        let (wx, wy) = (bspline_weights(sx - ax), bspline_weights(sy - ay));
        let (dwx, dwy) = (bspline_slopes(sx - ax), bspline_slopes(sy - ay));
        // the first tap's lag index: a - 1 + 2
        let (lx, ly) = ((ax + 1.0) as usize, (ay + 1.0) as usize);
        let LkTracker {
            g,
            coef,
            cross,
            moments,
            ..
        } = self;
        // the lags of the taps with a weight: at a whole-pixel shift the fourth tap's weights
        // (the spline's and its slope's) are zero, and its lags are not formed
        let used = |l: usize, w: &[f32; 4], dw: &[f32; 4]| {
            l..l + if w[3] == 0.0 && dw[3] == 0.0 { 3 } else { 4 }
        };
        let data = (&g[..], &coef[..], &moments.s);
        cross.need(used(lx, &wx, &dwx), used(ly, &wy, &dwy), data, (tw, th));
        // the weights of the shifted template (u), of its x and y slopes (vx, vy), at the
        // lags `at`
        let mut at = [0usize; 16];
        let (mut u, mut vx, mut vy) = ([0.0f32; 16], [0.0f32; 16], [0.0f32; 16]);
        for (l, (&wyl, &dwyl)) in wy.iter().zip(&dwy).enumerate() {
            for (k, (&wxk, &dwxk)) in wx.iter().zip(&dwx).enumerate() {
                let n = l * 4 + k;
                if let (Some(a), Some(u), Some(vx), Some(vy)) =
                    (at.get_mut(n), u.get_mut(n), vx.get_mut(n), vy.get_mut(n))
                {
                    *a = (ly + l) * LAGS + lx + k;
                    *u = wxk * wyl;
                    *vx = dwxk * wyl;
                    *vy = wxk * dwyl;
                }
            }
        }
        // sums with the window: sum g' T_s', sum g' d/dx T_s, sum g' d/dy T_s, sum T_s'
        let (mut sdt, mut gdx, mut gdy, mut ss) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        // the template's quadratic forms: sum T_s'^2, sum T_s' d/dx T_s, sum T_s' d/dy T_s
        let (mut sss, mut tdx, mut tdy) = (0.0f32, 0.0f32, 0.0f32);
        #[cfg(not(target_arch = "arm"))]
        let forms = kernels::tap_forms(&moments.c, LAGS, (lx, ly), wx, wy);
        for (n, &i) in at.iter().enumerate() {
            let (a, sm) = (
                cross.a.get(i).copied().unwrap_or(0.0),
                moments.s.get(i).copied().unwrap_or(0.0),
            );
            let (un, vxn, vyn) = (
                u.get(n).copied().unwrap_or(0.0),
                vx.get(n).copied().unwrap_or(0.0),
                vy.get(n).copied().unwrap_or(0.0),
            );
            sdt += un * a;
            gdx += vxn * a;
            gdy += vyn * a;
            ss += un * sm;
            // sum over the taps of c[i][tap] u[tap], u separable: the four lags of a
            // vertical tap are neighbours in the row of c (on hosts formed above, four lags
            // at a time, the same operations in each lane)
            #[cfg(not(target_arch = "arm"))]
            let cu = forms.get(n).copied().unwrap_or(0.0);
            #[cfg(target_arch = "arm")]
            let cu = {
                let row = moments.c.get(i * LAGS * LAGS..).unwrap_or(&[]);
                let mut cu = 0.0f32;
                for (l, &wyl) in wy.iter().enumerate() {
                    let at = (ly + l) * LAGS + lx;
                    if let Some(&[c0, c1, c2, c3]) = row.get(at..at + 4) {
                        let [w0, w1, w2, w3] = wx;
                        cu += wyl * (c0 * w0 + c1 * w1 + c2 * w2 + c3 * w3);
                    }
                }
                cu
            };
            sss += un * cu;
            tdx += vxn * cu;
            tdy += vyn * cu;
        }
        // the error e = I(x + q) - T(x - s) weighted by the shifted template's slopes (not
        // the reference's): the update is then the gradient of the squared error itself,
        // whose zero does not depend on the whole-pixel window when the frame differs from
        // the template (blur)
        let (bx, by) = (gdx - tdx, gdy - tdy);
        let n = (tw * th) as f32;
        let (sd, var_g) = (cross.sum, cross.var);
        let var_s = sss - ss * ss / n;
        let score = if var_g > 0.0 && var_s > 0.0 {
            (sdt - sd * ss / n) / sqrtf(var_g * var_s)
        } else {
            0.0
        };
        Ok(((bx, by), score))
    }
}
