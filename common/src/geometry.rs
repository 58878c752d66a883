//! Plane geometry of the image: homographies (a plane seen by a pinhole camera, a camera that
//! moves), fitted to point pairs by least squares: a translation, a similarity (rotation,
//! scale, translation) or a projective homography (Hartley's normalised DLT). Used by the
//! camera's motion from static references, the scale from the scene's known points, and the
//! oblique and shaken views of the synthetic recordings.

use nalgebra::{DMatrix, Matrix3, Vector3};

/// A plane-to-plane projective map `p' ~ H p` in homogeneous coordinates (row-major,
/// normalised so that `h[8] = 1` where possible).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Homography(pub [f64; 9]);

impl Homography {
    /// The identity.
    pub const IDENTITY: Homography = Homography([1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);

    fn matrix(&self) -> Matrix3<f64> {
        Matrix3::from_row_slice(&self.0)
    }

    fn of(m: Matrix3<f64>) -> Homography {
        let s = if m[(2, 2)].abs() > 1e-300 {
            m[(2, 2)]
        } else {
            1.0
        };
        let m = m / s;
        let mut h = [0.0; 9];
        for r in 0..3 {
            for c in 0..3 {
                h[3 * r + c] = m[(r, c)];
            }
        }
        Homography(h)
    }

    /// The map of `p`; non-finite where `p` maps to infinity.
    pub fn apply(&self, (x, y): (f64, f64)) -> (f64, f64) {
        let h = &self.0;
        let w = h[6] * x + h[7] * y + h[8];
        (
            (h[0] * x + h[1] * y + h[2]) / w,
            (h[3] * x + h[4] * y + h[5]) / w,
        )
    }

    /// The inverse map (`None` when singular).
    pub fn inverse(&self) -> Option<Homography> {
        self.matrix().try_inverse().map(Homography::of)
    }

    /// `self` after `first`: `p -> self(first(p))`.
    pub fn after(&self, first: &Homography) -> Homography {
        Homography::of(self.matrix() * first.matrix())
    }

    /// The map's Jacobian at `p`: `[[dx'/dx, dx'/dy], [dy'/dx, dy'/dy]]`.
    pub fn jacobian(&self, (x, y): (f64, f64)) -> [[f64; 2]; 2] {
        let h = &self.0;
        let w = h[6] * x + h[7] * y + h[8];
        let (u, v) = self.apply((x, y));
        [
            [(h[0] - u * h[6]) / w, (h[1] - u * h[7]) / w],
            [(h[3] - v * h[6]) / w, (h[4] - v * h[7]) / w],
        ]
    }

    /// A similarity: rotation by `angle` (radians, counter-clockwise in x-right y-up axes,
    /// clockwise on an image whose y grows down) and scaling by `scale` about `centre`, then a
    /// shift by `shift`.
    pub fn similarity(centre: (f64, f64), angle: f64, scale: f64, shift: (f64, f64)) -> Homography {
        let (s, c) = angle.sin_cos();
        let (a, b) = (scale * c, scale * s);
        let (cx, cy) = centre;
        Homography([
            a,
            -b,
            cx - a * cx + b * cy + shift.0,
            b,
            a,
            cy - b * cx - a * cy + shift.1,
            0.0,
            0.0,
            1.0,
        ])
    }

    /// The rotation (radians) and scale of the map's Jacobian at `p` (its closest similarity).
    pub fn rotation_scale(&self, p: (f64, f64)) -> (f64, f64) {
        let j = self.jacobian(p);
        let a = 0.5 * (j[0][0] + j[1][1]);
        let b = 0.5 * (j[1][0] - j[0][1]);
        (
            b.atan2(a),
            (j[0][0] * j[1][1] - j[0][1] * j[1][0]).abs().sqrt(),
        )
    }
}

/// A plane seen by a pinhole camera: the plane's point `(X, Y)` (mm, `Y` up) at `distance_mm`
/// along the optical axis at the plane's origin, the plane turned by `tilt_deg` about its
/// vertical axis (0: square to the camera), imaged with a focal length of `focal_px` pixels
/// onto an image whose centre is `centre` (x right, y down).
pub fn plane_view(
    tilt_deg: f64,
    distance_mm: f64,
    focal_px: f64,
    centre: (f64, f64),
) -> Homography {
    let (s, c) = tilt_deg.to_radians().sin_cos();
    // camera coordinates: Xc = X cos, Yc = -Y (image y down), Zc = D + X sin
    let (f, (cx, cy)) = (focal_px, centre);
    Homography::of(Matrix3::new(
        f * c + cx * s,
        0.0,
        cx * distance_mm,
        cy * s,
        -f,
        cy * distance_mm,
        s,
        0.0,
        distance_mm,
    ))
}

/// Which map a fit estimates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Model {
    /// A shift (one point pair or more).
    Translation,
    /// Rotation, scale and shift (two or more).
    Similarity,
    /// A projective homography (four or more, not three on a line).
    Homography,
}

impl Model {
    /// The fewest point pairs that determine it.
    pub fn minimum(self) -> usize {
        match self {
            Model::Translation => 1,
            Model::Similarity => 2,
            Model::Homography => 4,
        }
    }

    /// Its name as the options spell it.
    pub fn name(self) -> &'static str {
        match self {
            Model::Translation => "translation",
            Model::Similarity => "similarity",
            Model::Homography => "homography",
        }
    }
}

/// The least-squares map of `model` taking `src[i]` to `dst[i]` (`None`: too few pairs or a
/// degenerate configuration).
pub fn fit(model: Model, src: &[(f64, f64)], dst: &[(f64, f64)]) -> Option<Homography> {
    let n = src.len().min(dst.len());
    if n < model.minimum() {
        return None;
    }
    match model {
        Model::Translation => {
            let (mut dx, mut dy) = (0.0, 0.0);
            for (s, d) in src.iter().zip(dst) {
                dx += d.0 - s.0;
                dy += d.1 - s.1;
            }
            let k = n as f64;
            Some(Homography([
                1.0,
                0.0,
                dx / k,
                0.0,
                1.0,
                dy / k,
                0.0,
                0.0,
                1.0,
            ]))
        }
        Model::Similarity => fit_similarity(&src[..n], &dst[..n]),
        Model::Homography => fit_homography(&src[..n], &dst[..n]),
    }
}

/// `x' = a x - b y + tx, y' = b x + a y + ty` by least squares (closed form about the
/// centroids).
fn fit_similarity(src: &[(f64, f64)], dst: &[(f64, f64)]) -> Option<Homography> {
    let k = src.len() as f64;
    let mean = |p: &[(f64, f64)]| {
        let (sx, sy) = p.iter().fold((0.0, 0.0), |a, q| (a.0 + q.0, a.1 + q.1));
        (sx / k, sy / k)
    };
    let (ms, md) = (mean(src), mean(dst));
    let (mut num_a, mut num_b, mut den) = (0.0, 0.0, 0.0);
    for (s, d) in src.iter().zip(dst) {
        let (x, y) = (s.0 - ms.0, s.1 - ms.1);
        let (u, v) = (d.0 - md.0, d.1 - md.1);
        num_a += x * u + y * v;
        num_b += x * v - y * u;
        den += x * x + y * y;
    }
    if den <= 1e-12 {
        return None;
    }
    let (a, b) = (num_a / den, num_b / den);
    Some(Homography([
        a,
        -b,
        md.0 - a * ms.0 + b * ms.1,
        b,
        a,
        md.1 - b * ms.0 - a * ms.1,
        0.0,
        0.0,
        1.0,
    ]))
}

/// Hartley's normalisation: shift to the centroid, scale to a mean distance of sqrt 2.
fn normalising(p: &[(f64, f64)]) -> Option<Matrix3<f64>> {
    let k = p.len() as f64;
    let (sx, sy) = p.iter().fold((0.0, 0.0), |a, q| (a.0 + q.0, a.1 + q.1));
    let (mx, my) = (sx / k, sy / k);
    let d = p
        .iter()
        .map(|q| ((q.0 - mx).powi(2) + (q.1 - my).powi(2)).sqrt())
        .sum::<f64>()
        / k;
    if !(d > 1e-12 && d.is_finite()) {
        return None;
    }
    let s = std::f64::consts::SQRT_2 / d;
    Some(Matrix3::new(
        s,
        0.0,
        -s * mx,
        0.0,
        s,
        -s * my,
        0.0,
        0.0,
        1.0,
    ))
}

/// The normalised DLT: the right singular vector of the smallest singular value.
fn fit_homography(src: &[(f64, f64)], dst: &[(f64, f64)]) -> Option<Homography> {
    let (ts, td) = (normalising(src)?, normalising(dst)?);
    let n = src.len();
    // at least 9 rows (zeros past the pairs): a thin SVD then gives all 9 right singular
    // vectors, the null one of four pairs among them
    let mut a = DMatrix::<f64>::zeros(2 * n.max(5), 9);
    for (i, (s, d)) in src.iter().zip(dst).enumerate() {
        let p = ts * Vector3::new(s.0, s.1, 1.0);
        let q = td * Vector3::new(d.0, d.1, 1.0);
        let (x, y) = (p[0] / p[2], p[1] / p[2]);
        let (u, v) = (q[0] / q[2], q[1] / q[2]);
        let rows = [
            [-x, -y, -1.0, 0.0, 0.0, 0.0, u * x, u * y, u],
            [0.0, 0.0, 0.0, -x, -y, -1.0, v * x, v * y, v],
        ];
        for (r, row) in rows.iter().enumerate() {
            for (c, val) in row.iter().enumerate() {
                a[(2 * i + r, c)] = *val;
            }
        }
    }
    let svd = a.svd(false, true);
    let vt = svd.v_t?;
    let (imin, smin) =
        svd.singular_values
            .iter()
            .enumerate()
            .fold(
                (0, f64::INFINITY),
                |m, (i, &s)| if s < m.1 { (i, s) } else { m },
            );
    // a second (near-)zero singular value: the points do not determine the map (three on a
    // line)
    let mut sorted: Vec<f64> = svd.singular_values.iter().copied().collect();
    sorted.sort_by(f64::total_cmp);
    if !(smin.is_finite()) || sorted[1] <= 1e-9 * sorted[8].max(1e-300) {
        return None;
    }
    let h = vt.row(imin);
    let hn = Matrix3::new(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]);
    let m = td.try_inverse()? * hn * ts;
    let out = Homography::of(m);
    out.0.iter().all(|v| v.is_finite()).then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: (f64, f64), b: (f64, f64), tol: f64) -> bool {
        (a.0 - b.0).abs() < tol && (a.1 - b.1).abs() < tol
    }

    #[test]
    fn a_homography_is_recovered_from_four_and_from_many_points() {
        let h = plane_view(30.0, 400.0, 800.0, (320.0, 240.0));
        let world = [
            (-100.0, -60.0),
            (100.0, -60.0),
            (100.0, 60.0),
            (-100.0, 60.0),
            (10.0, 5.0),
            (-40.0, 30.0),
        ];
        let img: Vec<(f64, f64)> = world.iter().map(|&p| h.apply(p)).collect();
        for n in [4, 6] {
            let back = fit(Model::Homography, &img[..n], &world[..n]).unwrap();
            for (p, w) in img.iter().zip(&world) {
                assert!(close(back.apply(*p), *w, 1e-7), "{n}: {p:?}");
            }
        }
        // three on a line and a fourth: no homography
        let line = [(0.0, 0.0), (1.0, 1.0), (2.0, 2.0), (3.0, 3.0)];
        assert!(fit(Model::Homography, &line, &world[..4]).is_none());
    }

    #[test]
    fn the_view_foreshortens_as_a_pinhole_camera_does() {
        // a point of the plane at X: depth D + X sin(tilt), image x = cx + f X cos / depth
        let h = plane_view(30.0, 400.0, 800.0, (320.0, 240.0));
        let (x, y) = h.apply((100.0, 20.0));
        let depth = 400.0 + 100.0 * 0.5;
        assert!((x - (320.0 + 800.0 * 100.0 * 3f64.sqrt() / 2.0 / depth)).abs() < 1e-9);
        assert!((y - (240.0 - 800.0 * 20.0 / depth)).abs() < 1e-9);
    }

    #[test]
    fn a_similarity_is_recovered_and_composes_with_its_inverse() {
        let s = Homography::similarity((100.0, 50.0), 0.01, 1.002, (0.3, -0.7));
        let src = [(10.0, 20.0), (200.0, 30.0), (120.0, 90.0)];
        let dst: Vec<(f64, f64)> = src.iter().map(|&p| s.apply(p)).collect();
        let f = fit(Model::Similarity, &src, &dst).unwrap();
        for (a, b) in f.0.iter().zip(s.0) {
            assert!((a - b).abs() < 1e-9);
        }
        let (angle, scale) = f.rotation_scale((0.0, 0.0));
        assert!((angle - 0.01).abs() < 1e-12 && (scale - 1.002).abs() < 1e-12);
        let id = f.inverse().unwrap().after(&f);
        assert!(close(id.apply((5.0, 7.0)), (5.0, 7.0), 1e-9));
        let t = fit(Model::Translation, &src, &dst[..1]).unwrap();
        assert!(close(t.apply(src[0]), dst[0], 1e-12));
    }

    /// The fits against OpenCV's on noisy pairs (tests/data/geometry/opencv.json, written by
    /// scripts/gen_geometry_fixtures.py): the similarity is the same least-squares solution;
    /// the homography here minimises the normalised algebraic error where OpenCV refines the
    /// reprojection error, so the two agree to second order in the noise (0.05 px): the mapped
    /// points within 0.01 px.
    #[test]
    fn the_fits_agree_with_opencvs() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../tests/data/geometry/opencv.json");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        let pts = |v: &serde_json::Value| -> Vec<(f64, f64)> {
            v.as_array()
                .unwrap()
                .iter()
                .map(|p| (p[0].as_f64().unwrap(), p[1].as_f64().unwrap()))
                .collect()
        };
        let cases = v["cases"].as_array().unwrap();
        assert_eq!(cases.len(), 11);
        for (i, c) in cases.iter().enumerate() {
            let (src, dst) = (pts(&c["src"]), pts(&c["dst"]));
            let mut h = [0.0; 9];
            for (k, x) in c["h"].as_array().unwrap().iter().enumerate() {
                h[k] = x.as_f64().unwrap();
            }
            let theirs = Homography(h);
            let (model, tol) = match c["model"].as_str().unwrap() {
                // OpenCV's refinement stops at its own tolerance (about 1e-5 px here)
                "similarity" => (Model::Similarity, 1e-4),
                _ => (Model::Homography, 1e-2),
            };
            let ours = fit(model, &src, &dst).unwrap();
            for p in &src {
                let (a, b) = (ours.apply(*p), theirs.apply(*p));
                assert!(close(a, b, tol), "case {i}: {p:?}: {a:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn the_jacobian_is_the_maps_derivative() {
        let h = plane_view(25.0, 300.0, 700.0, (200.0, 100.0));
        let p = (30.0, -12.0);
        let j = h.jacobian(p);
        let e = 1e-5;
        let (a, b) = (h.apply((p.0 + e, p.1)), h.apply((p.0 - e, p.1)));
        assert!(((a.0 - b.0) / (2.0 * e) - j[0][0]).abs() < 1e-6);
        assert!(((a.1 - b.1) / (2.0 * e) - j[1][0]).abs() < 1e-6);
    }
}
