//! Motion magnification: a mode's motion, known at the tracked points, spread over the image as
//! a displacement field and applied to the recording's reference frame, magnified so that the
//! point that moves most moves a stated number of pixels (docs/method.md §2.13).
//!
//! The field at pixel `p` is the points' displacements averaged with Gaussian weights
//! `w_j = exp(-|p - p_j|^2 / (2 s^2))` (`s` from the points' spacing, [`spread_px`]), held
//! within `h = A + 2 s` of the nearest point (`A` the largest motion shown) and faded linearly
//! to zero at `2 h`: the structure moves, the background beyond it stays. Frame `n` of `N` over
//! one period shows the reference frame warped backwards, `out(p) = ref(p - A Re(D(p) e^(i 2
//! pi n / N)) u)` with `u` the motion's image direction and bilinear interpolation. That moves
//! the picture by the field where the field is constant over the motion: so the hold, which
//! carries a structure's edge (just beyond its outermost points) the whole way, however far it
//! moves.

use num_complex::Complex64;

/// Frames in one period of a magnified mode.
pub const FRAMES_PER_PERIOD: usize = 48;

/// The most points whose nearest neighbour [`spread_px`] measures.
pub const SPREAD_SAMPLE: usize = 1024;

/// The Gaussian weights' width for points at `points`: 0.75 of the median distance from a point
/// to its nearest neighbour (over at most [`SPREAD_SAMPLE`] of the points, evenly taken, each
/// against all: bounded for a field of many thousands), at least 2 px (a lone point: 20 px).
pub fn spread_px(points: &[(f64, f64)]) -> f64 {
    if points.len() < 2 {
        return 20.0;
    }
    let step = points.len().div_ceil(SPREAD_SAMPLE);
    let mut nearest: Vec<f64> = points
        .iter()
        .enumerate()
        .step_by(step)
        .map(|(i, a)| {
            points
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, b)| (a.0 - b.0).hypot(a.1 - b.1))
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    nearest.sort_by(f64::total_cmp);
    (0.75 * nearest[nearest.len() / 2]).max(2.0)
}

/// A mode's displacement field over a `width x height` image: per pixel, the complex
/// displacement along the motion's direction (the shape's unit).
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Per pixel, row 0 first.
    pub d: Vec<Complex64>,
}

/// The field of `shape` (one value per point) at `points` (image px, pixel centres at whole
/// numbers) over a `width x height` image, with Gaussian weights of width `spread` px, held
/// within `hold` px of the nearest point and faded to zero at twice that.
pub fn field(
    (width, height): (usize, usize),
    points: &[(f64, f64)],
    shape: &[Complex64],
    (spread, hold): (f64, f64),
) -> Field {
    let reach = 2.0 * hold.max(spread);
    let cell = reach.max(1.0);
    let (cw, ch) = (
        (width as f64 / cell).ceil() as usize + 1,
        (height as f64 / cell).ceil() as usize + 1,
    );
    // the points binned in cells of the weights' reach
    let mut bins: Vec<Vec<usize>> = vec![Vec::new(); cw * ch];
    for (j, p) in points.iter().enumerate() {
        let (cx, cy) = ((p.0 / cell).floor(), (p.1 / cell).floor());
        if cx >= 0.0 && cy >= 0.0 && (cx as usize) < cw && (cy as usize) < ch {
            bins[cy as usize * cw + cx as usize].push(j);
        }
    }
    let mut d = vec![Complex64::new(0.0, 0.0); width * height];
    let k = -1.0 / (2.0 * spread * spread);
    for y in 0..height {
        for x in 0..width {
            let (cx, cy) = (
                (x as f64 / cell).floor() as isize,
                (y as f64 / cell).floor() as isize,
            );
            let (mut sum, mut wsum, mut nearest) = (Complex64::new(0.0, 0.0), 0.0, f64::MAX);
            for by in cy - 1..=cy + 1 {
                for bx in cx - 1..=cx + 1 {
                    if bx < 0 || by < 0 || bx as usize >= cw || by as usize >= ch {
                        continue;
                    }
                    for &j in &bins[by as usize * cw + bx as usize] {
                        let p = points[j];
                        let r2 = (x as f64 - p.0).powi(2) + (y as f64 - p.1).powi(2);
                        if r2 <= reach * reach {
                            // relative to the nearest point's weight: no underflow far out
                            let w = (k * r2).exp().max(f64::MIN_POSITIVE);
                            sum += shape[j] * w;
                            wsum += w;
                            nearest = nearest.min(r2);
                        }
                    }
                }
            }
            if wsum > 0.0 {
                let fade = (2.0 - nearest.sqrt() / hold.max(spread)).clamp(0.0, 1.0);
                d[y * width + x] = sum / wsum * fade;
            }
        }
    }
    Field { width, height, d }
}

/// Frame `n` of `frames` over one period: `reference` (grey, `width * height`) warped by the
/// field times `amplitude` along the image direction `u` (a unit vector; y down), rounded to
/// 8 bits.
pub fn frame(
    reference: &[f32],
    f: &Field,
    (amplitude, u): (f64, (f64, f64)),
    (n, frames): (usize, usize),
) -> Vec<u8> {
    use rayon::prelude::*;
    let turn = Complex64::from_polar(1.0, 2.0 * std::f64::consts::PI * n as f64 / frames as f64);
    let (w, h) = (f.width, f.height);
    let mut out = vec![0u8; w * h];
    // rows spread over the cores (an HD frame is a million pixels, a video 48 of them)
    out.par_chunks_mut(w.max(1))
        .zip(f.d.par_chunks(w.max(1)))
        .enumerate()
        .for_each(|(y, (row, d))| {
            for (x, (o, d)) in row.iter_mut().zip(d).enumerate() {
                let s = amplitude * (d * turn).re;
                let v = bilinear(reference, (w, h), (x as f64 - s * u.0, y as f64 - s * u.1));
                *o = (v + 0.5).clamp(0.0, 255.0) as u8;
            }
        });
    out
}

/// `img` at `(x, y)` by bilinear interpolation, the edge pixels repeated beyond the image.
fn bilinear(img: &[f32], (w, h): (usize, usize), (x, y): (f64, f64)) -> f64 {
    let x = x.clamp(0.0, (w - 1) as f64);
    let y = y.clamp(0.0, (h - 1) as f64);
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = (x - x0 as f64, y - y0 as f64);
    let at = |xx: usize, yy: usize| f64::from(img[yy * w + xx]);
    (at(x0, y0) * (1.0 - fx) + at(x1, y0) * fx) * (1.0 - fy)
        + (at(x0, y1) * (1.0 - fx) + at(x1, y1) * fx) * fy
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_field_is_the_points_own_value_among_equal_points_and_fades_away() {
        let points: Vec<(f64, f64)> = (0..10)
            .flat_map(|i| (0..4).map(move |j| (20.0 + 4.0 * i as f64, 20.0 + 4.0 * j as f64)))
            .collect();
        let shape = vec![Complex64::new(0.5, -0.25); points.len()];
        let s = spread_px(&points);
        assert_eq!(s, 3.0);
        let f = field((100, 60), &points, &shape, (s, 5.0));
        // inside the grid and within the hold: the common value; beyond twice it: nothing
        assert!((f.d[26 * 100 + 30] - shape[0]).norm() < 1e-12);
        assert!((f.d[(32 + 5) * 100 + 32] - shape[0]).norm() < 1e-12);
        assert!((f.d[(32 + 8) * 100 + 32] - shape[0] * 0.4).norm() < 1e-12);
        assert_eq!(f.d[55 * 100 + 95], Complex64::new(0.0, 0.0));
    }

    #[test]
    fn a_uniform_field_moves_a_ramp_by_the_amplitude() {
        // a ramp along y: a shift by s along y changes every inner value by -s times its slope
        let (w, h) = (30, 30);
        let img: Vec<f32> = (0..w * h).map(|i| (i / w) as f32 * 4.0).collect();
        let f = Field {
            width: w,
            height: h,
            d: vec![Complex64::new(1.0, 0.0); w * h],
        };
        // y up is (0, -1): the picture moves up by 2.5 px, each pixel shows the one below
        let top = frame(&img, &f, (2.5, (0.0, -1.0)), (0, 4));
        assert_eq!(top[10 * w + 5], ((10.0 + 2.5) * 4.0_f64).round() as u8);
        // a quarter period later the real part is 0: the reference itself
        let quarter = frame(&img, &f, (2.5, (0.0, -1.0)), (1, 4));
        assert_eq!(quarter[10 * w + 5], 40);
    }
}
