//! A full field: the speckle-painted beam (`simulate-field --render --scene speckle`), hundreds of
//! points picked from one region, their modes (on reference channels, shapes carried to every
//! point), and each mode's magnified video tracked back by our own tracker.

use crate::util::{assert_ok, harness, mac, words};
use std::collections::HashMap;
use std::f64::consts::PI;
use std::path::Path;

/// The beam's supports (the scene's `X0`, `X1`).
const SUPPORTS: (f64, f64) = (16.0, 304.0);

/// `shapes.csv` of `dir`: per (method, mode), per target, `(x_px, shape)`.
#[allow(clippy::type_complexity)]
fn shapes(dir: &Path) -> HashMap<(String, usize), Vec<(usize, f64, (f64, f64))>> {
    let text = std::fs::read_to_string(dir.join("shapes.csv")).unwrap();
    let mut out: HashMap<(String, usize), Vec<(usize, f64, (f64, f64))>> = HashMap::new();
    for l in text.lines().skip(1) {
        // mode,target,x_px,y_px,re,im,abs,method,abs_u
        let c: Vec<&str> = l.split(',').collect();
        out.entry((c[7].to_string(), c[0].parse().unwrap()))
            .or_default()
            .push((
                c[1].parse().unwrap(),
                c[2].parse().unwrap(),
                (c[4].parse().unwrap(), c[5].parse().unwrap()),
            ));
    }
    out
}

#[test]
fn a_speckled_beam_gives_its_modes_at_hundreds_of_points_and_videos_that_track_back() {
    let tmp = tempfile::tempdir().unwrap();
    let rec = tmp.path().join("beam");
    let r = rec.to_str().unwrap();
    // 20 periods of the first mode (2.5 Hz) at 50 fps: 400 frames of 320 x 72 px
    assert_ok(&harness(&words(
        "simulate-field --render --scene speckle --minutes 0.134 --fps 50 --exposure-ms 1 \
         --out {}",
        &[r],
    )));
    let region = std::fs::read_to_string(rec.join("region.txt")).unwrap();
    let points = rec.join("points.csv");
    let frames = rec.join("frames");
    let frames = frames.to_str().unwrap();
    let page = rec.join("pick.html");
    assert_ok(&harness(&words(
        "pick --frames {} --region {} --spacing 3 --window-px 11 --direction y \
         --points-out {} --out {}",
        &[
            frames,
            region.trim(),
            points.to_str().unwrap(),
            page.to_str().unwrap(),
        ],
    )));
    let picked = std::fs::read_to_string(&points).unwrap().lines().count() - 1;
    assert!(picked >= 500, "{picked} points");
    let out = rec.join("analysis");
    let o = harness(&words(
        "analyze --frames {} --fps 50 --points {} --tracker lk --out {}",
        &[frames, points.to_str().unwrap(), out.to_str().unwrap()],
    ));
    assert_ok(&o);
    let report = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(report.contains("reference channels"), "{report}");
    // every true mode found by SSI, its shape at every point within MAC 0.99 of the truth
    let found = shapes(&out);
    let truth =
        |r: usize, x: f64| (r as f64 * PI * (x - SUPPORTS.0) / (SUPPORTS.1 - SUPPORTS.0)).sin();
    for r in 1..=3 {
        let s = &found[&("ssi".to_string(), r)];
        assert_eq!(s.len(), picked);
        let t: Vec<f64> = s.iter().map(|p| truth(r, p.1)).collect();
        let v: Vec<(f64, f64)> = s.iter().map(|p| p.2).collect();
        let m = mac(&v, &t);
        assert!(m >= 0.99, "mode {r}: MAC {m}");
    }
    // each mode's video, tracked back: the stated 4 px times the shape, within 5 %
    let page = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert_eq!(page.matches("<video class=\"magnified\"").count(), 3);
    // beside each, the mode's displacement field with its arrows
    assert_eq!(page.matches("<svg class=\"field\"").count(), 3);
    assert!(page.matches("marker-end=\"url(#head)\"").count() >= 3 * 20);
    let s = &found[&("ssi".to_string(), 1)];
    let video = out.join("magnified_ssi_1.webm");
    let back = tmp.path().join("back");
    assert_ok(&harness(&words(
        "track --frames {} --fps 24 --points {} --tracker lk --out {}",
        &[
            video.to_str().unwrap(),
            points.to_str().unwrap(),
            back.to_str().unwrap(),
        ],
    )));
    // per target, the complex amplitude of its y over the period (48 frames, y down)
    let text = std::fs::read_to_string(back.join("displacement.csv")).unwrap();
    // (lost frames left out: the least-squares fit of y = m + p cos a + q sin a)
    let mut fit: HashMap<usize, ([[f64; 3]; 3], [f64; 3])> = HashMap::new();
    for l in text.lines().skip(1) {
        // frame,t_s,target,cx,cy,...
        let c: Vec<&str> = l.split(',').collect();
        let Ok(y) = c[4].parse::<f64>() else { continue };
        let (n, t): (f64, usize) = (c[0].parse().unwrap(), c[2].parse().unwrap());
        let a = 2.0 * PI * n / 48.0;
        let b = [1.0, a.cos(), a.sin()];
        let (g, r) = fit.entry(t).or_default();
        for i in 0..3 {
            for j in 0..3 {
                g[i][j] += b[i] * b[j];
            }
            r[i] += b[i] * y;
        }
    }
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    // Cramer's rule: column k of the Gram matrix replaced by the right-hand side
    let solve = |(g, r): ([[f64; 3]; 3], [f64; 3]), k: usize| {
        let mut m = g;
        for i in 0..3 {
            m[i][k] = r[i];
        }
        det(m) / det(g)
    };
    let (mut err, mut norm) = (0.0, 0.0);
    for &(t, _, (re, im)) in s {
        let (p, q) = (solve(fit[&t], 1), solve(fit[&t], 2));
        // y = -A Re(phi e^(i a)) = -A (re cos a - im sin a)
        let want = (-4.0 * re, 4.0 * im);
        err += (p - want.0).powi(2) + (q - want.1).powi(2);
        norm += want.0.powi(2) + want.1.powi(2);
    }
    let rel = (err / norm).sqrt();
    assert!(
        rel <= 0.05,
        "the video's motion departs by {rel} from 4 px times the shape"
    );
}
