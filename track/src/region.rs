//! Points from a region of the first frame: windows on a grid at a spacing inside a polygon,
//! along a line or under a brush's strokes, kept where their texture fixes the motion to be
//! measured (docs/method.md §2.12).
//!
//! A window's texture is its gradient structure tensor `S = mean([gx², gx·gy; gx·gy, gy²])`
//! (central differences over the window's pixels, grey levels per px): in every direction the
//! smaller eigenvalue `l2` (Shi & Tomasi's "good features to track", what Lucas-Kanade needs to
//! fix a position in both directions), along one direction `v` the energy `vᵀ S v` (a window
//! that only has to measure motion along `v`, such as a beam's edge across its vibration). A
//! window is kept when its texture is at least `min_texture` times the best candidate's in the
//! region (OpenCV's `qualityLevel` rule), so the threshold does not depend on the camera's
//! gain or bit depth, and when Lucas-Kanade accepts it as a template (its Hessian's smaller
//! eigenvalue at least the tracker's `min_texture`: a window textured along one direction only
//! may not be).

use vibcam_readers::frames::GreyFrame;

/// The shape points are taken from (image pixels, x to the right, y down).
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// The inside of a closed polygon (its vertices, at least three; even-odd rule).
    Polygon(Vec<(f64, f64)>),
    /// Along a line through its vertices (at least two), one point every spacing.
    Line(Vec<(f64, f64)>),
    /// Under a brush of `radius` px drawn through the vertices (at least one).
    Brush {
        /// The brush's radius, px.
        radius: f64,
        /// The stroke's vertices.
        path: Vec<(f64, f64)>,
    },
}

/// The direction the points must measure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Direction {
    /// Every direction: the structure tensor's smaller eigenvalue (Shi-Tomasi).
    Both,
    /// Along the angle (radians from +x toward +y): the gradient energy in that direction.
    Along(f64),
}

impl Direction {
    /// Parses a direction as the command line and Python give it: `both`, `x`, `y` or an
    /// angle in degrees from x toward y.
    pub fn parse(s: &str) -> Result<Direction, String> {
        match s.trim() {
            "both" => Ok(Direction::Both),
            "x" => Ok(Direction::Along(0.0)),
            "y" => Ok(Direction::Along(std::f64::consts::FRAC_PI_2)),
            d => d
                .parse::<f64>()
                .ok()
                .filter(|d| d.is_finite())
                .map(|d| Direction::Along(d.to_radians()))
                .ok_or_else(|| format!("`{d}`: both, x, y or an angle in degrees")),
        }
    }
}

/// How points are chosen in a region.
#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    /// Where.
    pub shape: Shape,
    /// The grid's (or the line's) spacing, px (> 0).
    pub spacing: f64,
    /// Each window's width and height, px (odd, at least 5).
    pub window: usize,
    /// The least texture kept, as a fraction of the region's best (0 to 1).
    pub min_texture: f64,
    /// What the texture must fix.
    pub direction: Direction,
}

/// One place considered.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// The window's centre, px (whole pixels).
    pub xy: (f64, f64),
    /// Its texture ([`texture`]), grey levels² / px²; `None` when its window (and the one
    /// pixel of margin the gradients need) leaves the frame.
    pub texture: Option<f64>,
    /// Whether it is kept.
    pub kept: bool,
    /// Textured enough by the region's rule, but refused by Lucas-Kanade in the first frame
    /// (too little texture in its weaker direction for its Hessian: it would follow the
    /// window in no frame).
    pub flat_for_lk: bool,
}

/// The points a region gives, and why the others were left out.
#[derive(Debug, Clone, PartialEq)]
pub struct RegionPoints {
    /// Every grid place in the shape, in row order (y, then x); a line's in its order.
    pub candidates: Vec<Candidate>,
    /// The best texture among them (the reference of `min_texture`).
    pub best: f64,
    /// The texture a kept point needs at least.
    pub needed: f64,
}

impl RegionPoints {
    /// The kept windows' centres.
    pub fn kept(&self) -> Vec<(f64, f64)> {
        self.candidates
            .iter()
            .filter(|c| c.kept)
            .map(|c| c.xy)
            .collect()
    }

    /// One line for the report: how many places, kept, left out and why.
    pub fn describe(&self, sel: &Selection) -> String {
        let outside = self
            .candidates
            .iter()
            .filter(|c| c.texture.is_none())
            .count();
        let kept = self.candidates.iter().filter(|c| c.kept).count();
        let flat = self.candidates.iter().filter(|c| c.flat_for_lk).count();
        let weak = self.candidates.len() - outside - kept - flat;
        let what = match sel.direction {
            Direction::Both => "the smaller eigenvalue of the structure tensor".to_string(),
            Direction::Along(a) => format!(
                "the gradient energy along {:.0} deg",
                a.to_degrees().rem_euclid(360.0)
            ),
        };
        format!(
            "{} places every {} px in the region: {kept} kept, {weak} with less texture than {} \
             of the best ({what} >= {:.4e} of {:.4e}), {flat} that Lucas-Kanade finds flat (too \
             little texture in their weaker direction), {outside} whose {w} x {w} window leaves \
             the frame",
            self.candidates.len(),
            sel.spacing,
            sel.min_texture,
            self.needed,
            self.best,
            w = sel.window
        )
    }
}

impl Shape {
    /// Parses a region as the command line gives it: `X,Y;X,Y;...` (a polygon), `line:X,Y;X,Y;..`
    /// or `brush:R:X,Y;X,Y;...`.
    pub fn parse(s: &str) -> Result<Shape, String> {
        let s = s.trim();
        let (kind, rest) = match s.split_once(':') {
            Some((k @ ("polygon" | "line" | "brush"), r)) => (k, r),
            Some((k, _)) => {
                return Err(format!(
                    "`{k}`: a region is `X,Y;X,Y;...` (a polygon), `line:X,Y;...` or \
                     `brush:R:X,Y;...`"
                ))
            }
            None => ("polygon", s),
        };
        let (radius, rest) = match kind {
            "brush" => {
                let (r, rest) = rest
                    .split_once(':')
                    .ok_or("a brush is `brush:R:X,Y;X,Y;...` (R its radius in px)")?;
                let r: f64 = r
                    .trim()
                    .parse()
                    .ok()
                    .filter(|r: &f64| r.is_finite() && *r > 0.0)
                    .ok_or_else(|| format!("brush radius `{r}`: a number of px > 0"))?;
                (r, rest)
            }
            _ => (0.0, rest),
        };
        let mut pts = Vec::new();
        for (i, p) in rest.split(';').filter(|p| !p.trim().is_empty()).enumerate() {
            let xy: Vec<Option<f64>> = p
                .split(',')
                .map(|v| v.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
                .collect();
            match xy.as_slice() {
                [Some(x), Some(y)] => pts.push((*x, *y)),
                _ => return Err(format!("vertex {} `{}`: give X,Y in px", i + 1, p.trim())),
            }
        }
        let least = match kind {
            "polygon" => 3,
            "line" => 2,
            _ => 1,
        };
        if pts.len() < least {
            return Err(format!(
                "a {kind} needs at least {least} vertices X,Y separated by `;`, got {}",
                pts.len()
            ));
        }
        Ok(match kind {
            "polygon" => Shape::Polygon(pts),
            "line" => Shape::Line(pts),
            _ => Shape::Brush { radius, path: pts },
        })
    }

    /// The grid places (whole pixels) in the shape, `spacing` px apart: a polygon's and a
    /// brush's on the grid of multiples of `spacing` (rounded) inside a `frame` (width, height)
    /// frame, in row order; a line's along it from its first vertex, duplicates left out. More
    /// than [`MAX_PLACES`] is refused (the message names the count), so that a region far
    /// larger than the frame or a tiny spacing cannot run for hours.
    pub fn places(&self, spacing: f64, frame: (usize, usize)) -> Result<Vec<(f64, f64)>, String> {
        let too_many = |n: f64| {
            format!(
                "$region: {n:.0} places every {spacing} px, at most {MAX_PLACES} (a larger \
                 $spacing, or a smaller region)"
            )
        };
        match self {
            Shape::Line(path) => {
                let length: f64 = path
                    .windows(2)
                    .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
                    .sum();
                match length / spacing + 1.0 {
                    n if n > MAX_PLACES as f64 => Err(too_many(n)),
                    _ => Ok(along(path, spacing)),
                }
            }
            Shape::Polygon(poly) => {
                grid(poly, 0.0, (spacing, frame), |p| inside(poly, p)).map_err(too_many)
            }
            Shape::Brush { radius, path } => grid(path, *radius, (spacing, frame), |p| {
                distance_to_path(path, p) <= *radius
            })
            .map_err(too_many),
        }
    }
}

/// The most places a region may have (a 6000 x 6000 frame at 14 px).
pub const MAX_PLACES: usize = 200_000;

/// The grid places within the bounding box of `pts` grown by `margin` and within the `(width,
/// height)` frame, kept by `keep`; `Err(count)` when the box holds more than [`MAX_PLACES`].
fn grid(
    pts: &[(f64, f64)],
    margin: f64,
    (spacing, (width, height)): (f64, (usize, usize)),
    keep: impl Fn((f64, f64)) -> bool,
) -> Result<Vec<(f64, f64)>, f64> {
    let lo = |f: fn(&(f64, f64)) -> f64| pts.iter().map(f).fold(f64::INFINITY, f64::min) - margin;
    let hi =
        |f: fn(&(f64, f64)) -> f64| pts.iter().map(f).fold(f64::NEG_INFINITY, f64::max) + margin;
    let (x0, x1) = (lo(|p| p.0).max(0.0), hi(|p| p.0).min(width as f64 - 1.0));
    let (y0, y1) = (lo(|p| p.1).max(0.0), hi(|p| p.1).min(height as f64 - 1.0));
    let mut out = Vec::new();
    let (i0, i1) = ((x0 / spacing).ceil() as i64, (x1 / spacing).floor() as i64);
    let (j0, j1) = ((y0 / spacing).ceil() as i64, (y1 / spacing).floor() as i64);
    let count = ((i1 - i0 + 1).max(0) as f64) * ((j1 - j0 + 1).max(0) as f64);
    if count > MAX_PLACES as f64 {
        return Err(count);
    }
    for j in j0..=j1 {
        for i in i0..=i1 {
            let p = ((i as f64 * spacing).round(), (j as f64 * spacing).round());
            if keep(p) && out.last() != Some(&p) {
                out.push(p);
            }
        }
    }
    Ok(out)
}

/// Places every `spacing` px along the polyline `path` (rounded to whole pixels).
fn along(path: &[(f64, f64)], spacing: f64) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    let mut push = |p: (f64, f64)| {
        let p = (p.0.round(), p.1.round());
        if seen.insert((p.0 as i64, p.1 as i64)) {
            out.push(p);
        }
    };
    // the distance along the line to the next place
    let mut next = 0.0;
    let mut walked = 0.0;
    for w in path.windows(2) {
        let (a, b) = (w[0], w[1]);
        let len = (b.0 - a.0).hypot(b.1 - a.1);
        while next <= walked + len {
            let t = if len > 0.0 {
                (next - walked) / len
            } else {
                0.0
            };
            push((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)));
            next += spacing;
        }
        walked += len;
    }
    out
}

/// Whether `p` is inside the polygon (even-odd rule).
fn inside(poly: &[(f64, f64)], p: (f64, f64)) -> bool {
    let mut c = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + n - 1) % n]);
        if (a.1 > p.1) != (b.1 > p.1) && p.0 < (b.0 - a.0) * (p.1 - a.1) / (b.1 - a.1) + a.0 {
            c = !c;
        }
    }
    c
}

/// The distance from `p` to the polyline `path` (to its one point when it has one).
fn distance_to_path(path: &[(f64, f64)], p: (f64, f64)) -> f64 {
    let seg = |a: (f64, f64), b: (f64, f64)| {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let l2 = dx * dx + dy * dy;
        let t = if l2 > 0.0 {
            (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (a.0 + t * dx - p.0).hypot(a.1 + t * dy - p.1)
    };
    match path {
        [one] => seg(*one, *one),
        _ => path
            .windows(2)
            .map(|w| seg(w[0], w[1]))
            .fold(f64::INFINITY, f64::min),
    }
}

/// The structure tensor `[sxx, sxy, syy]` of the `window` x `window` window centred on the
/// whole pixel `xy`: the mean over its pixels of the products of the central-difference
/// gradients; `None` when the window and its one pixel of margin leave the frame.
pub fn structure(frame: &GreyFrame, xy: (f64, f64), window: usize) -> Option<[f64; 3]> {
    let (width, height) = frame.dimensions();
    let half = (window as i64 - 1) / 2;
    let (cx, cy) = (xy.0 as i64, xy.1 as i64);
    if cx - half < 1 || cy - half < 1 {
        return None;
    }
    if cx + half + 1 >= width as i64 || cy + half + 1 >= height as i64 {
        return None;
    }
    let at = |x: i64, y: i64| -> f64 {
        let i = y as usize * width + x as usize;
        match frame {
            GreyFrame::U8 { data, .. } => f64::from(data[i]),
            GreyFrame::U16 { data, .. } => f64::from(data[i]),
        }
    };
    let mut s = [0.0f64; 3];
    for y in cy - half..=cy + half {
        for x in cx - half..=cx + half {
            let gx = 0.5 * (at(x + 1, y) - at(x - 1, y));
            let gy = 0.5 * (at(x, y + 1) - at(x, y - 1));
            s[0] += gx * gx;
            s[1] += gx * gy;
            s[2] += gy * gy;
        }
    }
    let n = (window * window) as f64;
    Some(s.map(|v| v / n))
}

/// A window's texture for `direction` ([`Direction`]) from its structure tensor.
pub fn texture(s: [f64; 3], direction: Direction) -> f64 {
    match direction {
        Direction::Both => {
            let half_tr = 0.5 * (s[0] + s[2]);
            let disc = (0.25 * (s[0] - s[2]).powi(2) + s[1] * s[1]).sqrt();
            (half_tr - disc).max(0.0)
        }
        Direction::Along(a) => {
            let (c, sn) = (a.cos(), a.sin());
            (c * c * s[0] + 2.0 * c * sn * s[1] + sn * sn * s[2]).max(0.0)
        }
    }
}

/// The points of `sel` in `frame` (its first frame): every place of the shape, its texture,
/// and the ones kept. Errors name the setting (`$spacing`, `$window_px`, `$min_texture`,
/// `$region`).
pub fn select(frame: &GreyFrame, sel: &Selection) -> anyhow::Result<RegionPoints> {
    use vibcam_readers::bad_input;
    if !(sel.spacing.is_finite() && sel.spacing >= 1.0) {
        return Err(bad_input(format!(
            "$spacing {}: at least 1 px",
            sel.spacing
        )));
    }
    if sel.window < 5 || sel.window.is_multiple_of(2) || sel.window > 255 {
        return Err(bad_input(format!(
            "$window_px {}: an odd number of px from 5 to 255",
            sel.window
        )));
    }
    if !(0.0..=1.0).contains(&sel.min_texture) {
        return Err(bad_input(format!(
            "$min_texture {}: a fraction of the region's best texture, 0 to 1",
            sel.min_texture
        )));
    }
    let places = sel
        .shape
        .places(sel.spacing, frame.dimensions())
        .map_err(bad_input)?;
    if places.is_empty() {
        return Err(bad_input(format!(
            "$region: no place of the {} px grid inside it (a smaller $spacing, or a larger \
             region)",
            sel.spacing
        )));
    }
    let mut candidates: Vec<Candidate> = places
        .iter()
        .map(|&xy| Candidate {
            xy,
            texture: structure(frame, xy, sel.window).map(|s| texture(s, sel.direction)),
            kept: false,
            flat_for_lk: false,
        })
        .collect();
    let best = candidates
        .iter()
        .filter_map(|c| c.texture)
        .fold(0.0f64, f64::max);
    let needed = sel.min_texture * best;
    for c in &mut candidates {
        // a flat window (no texture at all) never fixes a position
        c.kept = c.texture.is_some_and(|t| t > 0.0 && t >= needed);
    }
    // what Lucas-Kanade itself would refuse: a window textured along one direction only may
    // still leave its Hessian too weak in the other
    let kept: Vec<usize> = (0..candidates.len())
        .filter(|&i| candidates[i].kept)
        .collect();
    let side = u32::try_from(sel.window).unwrap_or(u32::MAX);
    let points: Vec<crate::points::Point> = kept
        .iter()
        .enumerate()
        .map(|(k, &i)| crate::points::Point {
            target: k + 1,
            xy: candidates[i].xy,
            size: (side, side),
            threshold: None,
            group: None,
        })
        .collect();
    for (&i, refused) in kept.iter().zip(crate::points::lk_refusals(&points, frame)?) {
        if refused.is_some() {
            candidates[i].kept = false;
            candidates[i].flat_for_lk = true;
        }
    }
    Ok(RegionPoints {
        candidates,
        best,
        needed,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(width: usize, height: usize, f: impl Fn(usize, usize) -> u8) -> GreyFrame {
        let data = (0..width * height)
            .map(|i| f(i % width, i / width))
            .collect();
        GreyFrame::U8 {
            width,
            height,
            data,
        }
    }

    #[test]
    fn regions_parse_and_bad_ones_are_named() {
        assert_eq!(
            Shape::parse("0,0; 10,0; 10,10").unwrap(),
            Shape::Polygon(vec![(0.0, 0.0), (10.0, 0.0), (10.0, 10.0)])
        );
        assert_eq!(
            Shape::parse("line:0,0;5,5").unwrap(),
            Shape::Line(vec![(0.0, 0.0), (5.0, 5.0)])
        );
        assert_eq!(
            Shape::parse("brush:4:1,2").unwrap(),
            Shape::Brush {
                radius: 4.0,
                path: vec![(1.0, 2.0)]
            }
        );
        assert!(Shape::parse("0,0;1,1").unwrap_err().contains("at least 3"));
        assert!(Shape::parse("0,0;x,1;2,2")
            .unwrap_err()
            .contains("vertex 2"));
        assert!(Shape::parse("circle:1,1").unwrap_err().contains("circle"));
        assert!(Shape::parse("brush:-1:1,1").unwrap_err().contains("radius"));
    }

    #[test]
    fn a_rectangle_holds_its_grid_and_a_triangle_half_of_it() {
        let rect = Shape::Polygon(vec![
            (-0.5, -0.5),
            (100.5, -0.5),
            (100.5, 50.5),
            (-0.5, 50.5),
        ]);
        let p = rect.places(10.0, (1000, 1000)).unwrap();
        // 0, 10, ..., 100 across and 0, ..., 50 down
        assert_eq!(p.len(), 11 * 6);
        assert_eq!(p[0], (0.0, 0.0));
        assert_eq!(p[12], (10.0, 10.0));
        // a right triangle below the diagonal of a 100 x 100 square: about half the places
        let tri = Shape::Polygon(vec![(0.0, 0.0), (100.0, 100.0), (0.0, 100.0)]);
        let t = tri.places(5.0, (1000, 1000)).unwrap();
        assert!(t.iter().all(|&(x, y)| x <= y), "{t:?}");
        // between the strict inside (x > 0, x < y, y < 100: 171 places) and the closed
        // triangle (21 * 22 / 2 = 231): the even-odd rule takes some of the edges' places
        assert!((171..=231).contains(&t.len()), "{}", t.len());
    }

    #[test]
    fn a_line_gives_points_at_the_spacing_and_a_brush_its_neighbourhood() {
        let line = Shape::Line(vec![(0.0, 0.0), (30.0, 0.0), (30.0, 20.0)]);
        assert_eq!(
            line.places(10.0, (1000, 1000)).unwrap(),
            vec![
                (0.0, 0.0),
                (10.0, 0.0),
                (20.0, 0.0),
                (30.0, 0.0),
                (30.0, 10.0),
                (30.0, 20.0)
            ]
        );
        let brush = Shape::Brush {
            radius: 10.0,
            path: vec![(50.0, 50.0)],
        };
        let b = brush.places(5.0, (1000, 1000)).unwrap();
        // a region far larger than the frame is cut to it; one too fine to finish is refused
        let huge = Shape::Polygon(vec![(-1e12, -1e12), (1e12, -1e12), (1e12, 1e12)]);
        let cut = huge.places(10.0, (100, 50)).unwrap();
        // the places with x > y (35) up to those with x >= y (40), all in the frame
        assert!((35..=40).contains(&cut.len()), "{}", cut.len());
        assert!(cut.iter().all(|&(x, y)| x <= 99.0 && y <= 49.0 && x >= y));
        let far = Shape::Line(vec![(0.0, 0.0), (1e12, 0.0)]);
        assert!(far.places(1.0, (100, 50)).unwrap_err().contains("at most"));
        // the places of the 5 px grid within 10 px of (50, 50): the centre, 4 at 5 px, 4 at
        // 7.07 px, 4 at 10 px
        assert_eq!(b.len(), 13);
        assert!(b.iter().all(|&(x, y)| (x - 50.0).hypot(y - 50.0) <= 10.0));
    }

    #[test]
    fn the_structure_tensor_is_the_closed_form_of_a_ramp_and_of_stripes() {
        // a ramp of 3 grey levels per px along x: gx = 3 everywhere, gy = 0
        let ramp = frame(40, 40, |x, _| (3 * x) as u8);
        let s = structure(&ramp, (20.0, 20.0), 7).unwrap();
        assert_eq!(s, [9.0, 0.0, 0.0]);
        // an edge in one direction fixes nothing along it: Shi-Tomasi 0, along x 9
        assert_eq!(texture(s, Direction::Both), 0.0);
        assert!((texture(s, Direction::Along(0.0)) - 9.0).abs() < 1e-12);
        assert!(texture(s, Direction::Along(std::f64::consts::FRAC_PI_2)) < 1e-12);
        // at 60 deg: cos² 60 * 9
        let a = texture(s, Direction::Along(60f64.to_radians()));
        assert!((a - 0.25 * 9.0).abs() < 1e-9, "{a}");
        // a window touching the frame's edge has no tensor (its gradients need a margin)
        assert!(structure(&ramp, (3.0, 20.0), 7).is_none());
        assert!(structure(&ramp, (4.0, 20.0), 7).is_some());
        assert!(structure(&ramp, (35.0, 20.0), 7).is_some());
        assert!(structure(&ramp, (36.0, 20.0), 7).is_none());
    }

    #[test]
    fn stripes_measure_one_direction_but_lucas_kanade_needs_both() {
        // horizontal stripes 4 px high: all their texture is along y
        let f = frame(80, 80, |_, y| if (y / 4) % 2 == 0 { 50 } else { 200 });
        let sel = Selection {
            shape: Shape::Polygon(vec![(0.0, 0.0), (79.0, 0.0), (79.0, 79.0), (0.0, 79.0)]),
            spacing: 10.0,
            window: 11,
            min_texture: 0.1,
            direction: Direction::Along(std::f64::consts::FRAC_PI_2),
        };
        let r = select(&f, &sel).unwrap();
        let inside: Vec<&Candidate> = r
            .candidates
            .iter()
            .filter(|c| c.texture.is_some())
            .collect();
        assert!(!inside.is_empty());
        // textured enough along y everywhere, but the tracker's Hessian is singular: none kept
        assert!(
            inside.iter().all(|c| c.flat_for_lk && !c.kept),
            "{inside:?}"
        );
        assert!(r.describe(&sel).contains("Lucas-Kanade finds flat"));
        // and in every direction the stripes have no texture at all
        let both = select(
            &f,
            &Selection {
                direction: Direction::Both,
                ..sel
            },
        )
        .unwrap();
        assert!(both.kept().is_empty() && both.candidates.iter().all(|c| !c.flat_for_lk));
    }

    #[test]
    fn texture_keeps_the_checkerboard_and_leaves_the_flat_half() {
        // left half flat, right half a checkerboard of 4 px squares
        let f = frame(120, 60, |x, y| {
            if x < 60 {
                100
            } else if ((x / 4) + (y / 4)) % 2 == 0 {
                40
            } else {
                200
            }
        });
        let sel = Selection {
            shape: Shape::Polygon(vec![(0.0, 0.0), (119.0, 0.0), (119.0, 59.0), (0.0, 59.0)]),
            spacing: 10.0,
            window: 11,
            min_texture: 0.1,
            direction: Direction::Both,
        };
        let r = select(&f, &sel).unwrap();
        let kept = r.kept();
        // every window wholly on the checkerboard is kept, none wholly on the flat half
        // (the gradients' margin included)
        for c in r.candidates.iter().filter(|c| c.texture.is_some()) {
            let x = c.xy.0;
            if x - 5.0 >= 60.0 {
                assert!(c.kept, "{c:?}");
            }
            if x + 6.0 < 60.0 {
                assert!(!c.kept, "{c:?}");
            }
        }
        assert!(kept.len() >= 25, "{kept:?}");
        assert!(r.describe(&sel).contains("kept"), "{}", r.describe(&sel));
        let bad = Selection {
            spacing: 0.0,
            ..sel.clone()
        };
        assert!(select(&f, &bad)
            .unwrap_err()
            .to_string()
            .contains("$spacing"));
        let bad = Selection { window: 4, ..sel };
        assert!(select(&f, &bad)
            .unwrap_err()
            .to_string()
            .contains("$window_px"));
    }
}
