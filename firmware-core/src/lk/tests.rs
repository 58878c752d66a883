//! The Lucas-Kanade tracker's tests.

use super::*;
extern crate std;
use std::vec::Vec;

const FW: usize = 96;
const FH: usize = 80;

/// A speckle pattern (a few Gaussian spots of sigma 2 px) displaced by `(dx, dy)`, sampled
/// at the pixel centres, 8-bit with `gain` (values up to about `40 + gain`).
fn speckle(dx: f64, dy: f64, gain: f64) -> Vec<u8> {
    let spots = [
        (40.0, 35.0, 1.0),
        (47.0, 38.0, 0.7),
        (43.0, 44.0, 0.9),
        (52.0, 33.0, 0.6),
        (36.0, 42.0, 0.8),
        (50.0, 46.0, 0.5),
    ];
    let mut px = Vec::with_capacity(FW * FH);
    for y in 0..FH {
        for x in 0..FW {
            let mut v = 40.0;
            for (sx, sy, a) in spots {
                let (ex, ey) = (x as f64 - sx - dx, y as f64 - sy - dy);
                v += gain * a * libm::exp(-(ex * ex + ey * ey) / 8.0);
            }
            px.push(libm::round(v).clamp(0.0, 255.0) as u8);
        }
    }
    px
}

fn frame(px: &[u8]) -> Frame<'_, u8> {
    Frame::new(px, FW, FH, FW).unwrap()
}

type Lk = LkTracker<{ 39 * 39 }, 38>;

fn tracker(search: u16, interpolation: Interpolation) -> Lk {
    let mut cfg = LkConfig::new(31, 31);
    cfg.search = search;
    cfg.interpolation = interpolation;
    let mut t = Lk::try_new(cfg).unwrap();
    let reference = speckle(0.0, 0.0, 200.0);
    t.set_template(&frame(&reference), 44 - 15, 40 - 15)
        .unwrap();
    t
}

#[test]
fn sub_pixel_shifts_are_measured_to_a_few_thousandths() {
    for interpolation in [
        Interpolation::Spline,
        Interpolation::Bicubic,
        Interpolation::Bilinear,
    ] {
        let mut worst = 0.0f32;
        // (0.93, -0.93): refined on the first window, kept up to `KEEP` px
        let shifts = [
            (0.3, -0.7),
            (-0.45, 0.25),
            (0.5, 0.5),
            (1.2, -0.9),
            (0.93, -0.93),
        ];
        for &(dx, dy) in &shifts {
            let mut t = tracker(0, interpolation);
            let img = speckle(dx, dy, 200.0);
            let r = t.track(&frame(&img));
            let (mx, my) = r.displacement().expect("tracked");
            worst = worst
                .max((mx - dx as f32).abs())
                .max((my - dy as f32).abs());
            assert!(r.score > 0.99, "{r:?}");
            assert!(!r.searched);
        }
        // rounding to 8 bits alone limits it; bilinear smooths the pattern (a bias)
        let limit = match interpolation {
            Interpolation::Bicubic | Interpolation::Spline => 0.01,
            Interpolation::Bilinear => 0.05,
        };
        assert!(worst < limit, "{interpolation:?}: {worst}");
    }
}

#[test]
fn a_template_blurred_unlike_the_frame_settles_at_every_half_pixel() {
    // the template smeared over 6 px along y (a long exposure at speed), the frames sharp:
    // no shift matches exactly, and the window read at whole pixels changes at the half
    // pixels; the estimate must still settle, and move with the target smoothly
    let (w, h) = (FW, FH);
    let mut acc = std::vec![0.0f64; w * h];
    for s in 0..13 {
        let img = speckle(0.0, -3.0 + 0.5 * s as f64, 200.0);
        for (a, v) in acc.iter_mut().zip(&img) {
            *a += f64::from(*v) / 13.0;
        }
    }
    let blurred: Vec<u8> = acc.iter().map(|v| libm::round(*v) as u8).collect();
    let mut cfg = LkConfig::new(31, 31);
    cfg.search = 0;
    let mut t = Lk::try_new(cfg).unwrap();
    t.set_template(&frame(&blurred), 44 - 15, 40 - 15).unwrap();
    let mut last: Option<f32> = None;
    for k in 0..=20 {
        let dy = 2.0 + 0.05 * f64::from(k);
        let r = t.track(&frame(&speckle(0.1, dy, 200.0)));
        let (_, my) = r
            .displacement()
            .unwrap_or_else(|| panic!("lost at {dy}: {r:?}"));
        assert!((f64::from(my) - dy).abs() < 0.06, "{dy}: {my}");
        if let Some(l) = last {
            let step = my - l;
            assert!((0.03..0.07).contains(&step), "{dy}: step {step}");
        }
        last = Some(my);
    }
}

/// The window read, smoothed and stored in integers equals the smoothing done in f64 at
/// every kernel, for 8- and 16-bit frames, inside the frame and at its left edge (the
/// edge pixels repeat), and its sums are the sums over those values.
fn window_matches_f64<P: Pixel>(px: &[P], smoothing: Smoothing, q: (i64, i64)) {
    let f = Frame::new(px, FW, FH, FW).unwrap();
    let mut cfg = LkConfig::new(31, 31);
    cfg.smoothing = smoothing;
    let mut t = Lk::try_new(cfg).unwrap();
    t.set_template(&f, 29, 25).unwrap();
    t.load_window(&f, q, u16::MAX).unwrap();
    let (k, half): (&[f64], i64) = match smoothing {
        Smoothing::None => (&[1.0], 0),
        Smoothing::Binomial3 => (&[1.0, 2.0, 1.0], 1),
        Smoothing::Binomial5 => (&[1.0, 4.0, 6.0, 4.0, 1.0], 2),
    };
    let total: f64 = k.iter().sum();
    let at = |x: i64, y: i64| {
        let (x, y) = (x.clamp(0, FW as i64 - 1), y.clamp(0, FH as i64 - 1));
        f64::from(px[y as usize * FW + x as usize].into())
    };
    let (x0, y0) = (29 + q.0, 25 + q.1);
    let (mut sum, mut sq, mut worst) = (0.0f64, 0.0f64, 0.0f64);
    let mut values = Vec::new();
    for j in 0..31i64 {
        for i in 0..31i64 {
            let mut v = 0.0;
            for (dy, ky) in (-half..).zip(k) {
                for (dx, kx) in (-half..).zip(k) {
                    v += ky * kx * at(x0 + i + dx, y0 + j + dy);
                }
            }
            let g = v / (total * total) - f64::from(t.t_mean);
            let stored = f64::from(t.g[j as usize * window_stride(31) + i as usize]);
            let back = f64::from(t.cross.scale) * stored + f64::from(t.cross.offset);
            worst = worst.max((back - g).abs());
            sum += g;
            values.push(g);
        }
    }
    let mean = sum / values.len() as f64;
    for g in &values {
        sq += (g - mean) * (g - mean);
    }
    let level = f64::from(P::FULL);
    assert!(worst < 1e-6 * level, "{smoothing:?} at {q:?}: {worst}");
    assert!(
        (f64::from(t.cross.sum) - sum).abs() < 1e-6 * level * 961.0,
        "{smoothing:?} at {q:?}: sum {} {sum}",
        t.cross.sum
    );
    assert!(
        (f64::from(t.cross.var) - sq).abs() < 1e-6 * sq,
        "{smoothing:?} at {q:?}: var {} {sq}",
        t.cross.var
    );
    // the row pad the cross moments' kernels run over is zero
    for j in 0..31 {
        assert_eq!(t.g[j * window_stride(31) + 31], 0.0);
    }
}

#[test]
fn the_window_is_smoothed_exactly_for_every_kernel_and_at_the_frame_edge() {
    let px8 = speckle(0.3, -0.2, 200.0);
    // 16-bit: the same scene on the whole range, and a level near the top
    let px16: Vec<u16> = px8.iter().map(|&v| u16::from(v) * 257).collect();
    for smoothing in [Smoothing::None, Smoothing::Binomial3, Smoothing::Binomial5] {
        // inside; the window's left column on the frame's first column (the kernel's
        // margin repeats it); its top row on the frame's first row
        for q in [(2, -1), (-29, 0), (0, -25)] {
            window_matches_f64(&px8, smoothing, q);
            window_matches_f64(&px16, smoothing, q);
        }
    }
}

#[test]
fn the_spline_moments_equal_the_sums_over_the_pixels() {
    // every iteration's sums come from moments formed once per template and per window:
    // check them against the sums over the shifted template's pixels, in f64
    let mut t = tracker(0, Interpolation::Spline);
    let img = speckle(0.37, -0.61, 190.0);
    let f = frame(&img);
    let (tw, th) = (31usize, 31usize);
    let pw = tw + 2 * SPLINE_MARGIN;
    let m = SPLINE_MARGIN as i64;
    for &(px, py) in &[(0.3f32, -0.7f32), (0.74, 0.1), (-0.2, -0.74), (0.0, 0.5)] {
        let (b, score) = t.spline_error(&f, (px, py), u16::MAX).unwrap();
        let (qx, qy) = t.g_at.unwrap();
        let (sx, sy) = (qx as f64 - f64::from(px), qy as f64 - f64::from(py));
        let (ax, ay) = (sx.floor(), sy.floor());
        let wts = |f: f64| bspline_weights(f as f32).map(f64::from);
        let slopes = |f: f64| bspline_slopes(f as f32).map(f64::from);
        let (wx, wy, dwx, dwy) = (wts(sx - ax), wts(sy - ay), slopes(sx - ax), slopes(sy - ay));
        let c = |i: i64, j: i64| f64::from(t.coef[((j + m) * pw as i64 + i + m) as usize]);
        let (mut bx, mut by) = (0.0f64, 0.0f64);
        let (mut g1, mut g2, mut s1, mut s2, mut gs) = (0.0f64, 0.0, 0.0, 0.0, 0.0);
        for j in 0..th as i64 {
            for i in 0..tw as i64 {
                let (mut v, mut dx, mut dy) = (0.0, 0.0, 0.0);
                for l in 0..4 {
                    for k in 0..4 {
                        let cv = c(i + ax as i64 - 1 + k, j + ay as i64 - 1 + l);
                        let (k, l) = (k as usize, l as usize);
                        v += wx[k] * wy[l] * cv;
                        dx += dwx[k] * wy[l] * cv;
                        dy += wx[k] * dwy[l] * cv;
                    }
                }
                // the window as stored (integers, rows padded to the stride) back on the
                // template's scale
                let stored = f64::from(t.g[j as usize * window_stride(tw) + i as usize]);
                let g = f64::from(t.cross.scale) * stored + f64::from(t.cross.offset);
                bx += dx * (g - v);
                by += dy * (g - v);
                g1 += g;
                g2 += g * g;
                s1 += v;
                s2 += v * v;
                gs += g * v;
            }
        }
        let n = (tw * th) as f64;
        let zncc = (gs - g1 * s1 / n) / ((g2 - g1 * g1 / n) * (s2 - s1 * s1 / n)).sqrt();
        // relative to the terms' scale (sum of |slope| |g|): f32 moments against f64 sums
        let scale = t.h_inv[0].abs().recip() as f64;
        assert!(
            (f64::from(b.0) - bx).abs() < 1e-4 * scale,
            "{px},{py}: {} {bx}",
            b.0
        );
        assert!(
            (f64::from(b.1) - by).abs() < 1e-4 * scale,
            "{px},{py}: {} {by}",
            b.1
        );
        assert!((f64::from(score) - zncc).abs() < 1e-5, "{score} {zncc}");
        assert!(
            bx.abs() > 1e-3 * scale,
            "a shift away from the optimum has an error"
        );
    }
}

#[test]
fn a_start_given_far_from_the_last_position_is_refined_there() {
    // what a caller that knows the shared motion of several targets does: the target
    // jumped 20.4 px, further than the refinement reaches and with no search of its own
    let mut t = tracker(0, Interpolation::Spline);
    let img = speckle(20.4, -12.3, 200.0);
    assert!(t.track(&frame(&img)).displacement().is_none());
    let r = t.track_from(&frame(&img), Some((19.0, -11.0)), 3);
    let (x, y) = r.displacement().expect("tracked from the given start");
    assert!((x - 20.4).abs() < 0.01 && (y + 12.3).abs() < 0.01, "{r:?}");
    // the configured search is back
    assert_eq!(t.config().search, 0);
    assert!(t
        .track_from(&frame(&img), Some((f32::NAN, 0.0)), 3)
        .displacement()
        .is_none());
}

#[test]
fn the_coarse_search_catches_motions_of_many_pixels_and_its_edge_is_a_loss() {
    let mut t = tracker(24, Interpolation::Bicubic);
    // from rest, a jump of 20 px is more than the motion so far explains (and than half
    // the template): lost, whatever the search found (a look-alike or the target)
    let img = speckle(20.4, -12.3, 200.0);
    let r = t.track(&frame(&img));
    assert!(r.searched);
    assert!(r.flags.contains(Flags::AMBIGUOUS), "{r:?}");
    assert_eq!(t.displacement(), (0.0, 0.0));
    // a target seen moving 7.3 px a frame: the search finds it 21.4 px from the
    // prediction (within three of its steps)
    for dx in [7.3, 14.6] {
        let r = t.track(&frame(&speckle(dx, 0.0, 200.0)));
        assert!((r.dx - dx as f32).abs() < 0.01, "{r:?}");
    }
    let r = t.track(&frame(&speckle(0.5, -1.0, 200.0)));
    assert!(r.searched, "{r:?}");
    let (mx, my) = r.displacement().expect("found by the search");
    assert!((mx - 0.5).abs() < 0.01 && (my + 1.0).abs() < 0.01, "{r:?}");
    // and the next frame at a small step from there, its prediction 14 px off (the last
    // step's velocity): a search within half the template, explained
    let img = speckle(1.0, -0.7, 200.0);
    let r = t.track(&frame(&img));
    assert!((r.dx - 1.0).abs() < 0.01 && r.flags.is_clear(), "{r:?}");
    // 22.5 px from the prediction of the same target: more than three of its steps
    let mut t = tracker(24, Interpolation::Bicubic);
    for dx in [7.3, 14.6] {
        t.track(&frame(&speckle(dx, 0.0, 200.0)));
    }
    let r = t.track(&frame(&speckle(-0.6, 0.0, 200.0)));
    assert!(r.flags.contains(Flags::AMBIGUOUS), "{r:?}");
    // a jump beyond the range (and beyond where the refinement alone converges): lost,
    // flagged, and the state kept
    let mut t = tracker(6, Interpolation::Bicubic);
    let img = speckle(25.0, 0.0, 200.0);
    let r = t.track(&frame(&img));
    assert_eq!(r.displacement(), None, "{r:?}");
    assert!(r.flags.contains(Flags::DIVERGED), "{r:?}");
    assert_eq!(t.displacement(), (0.0, 0.0));
}

#[test]
fn a_search_that_sees_two_look_alikes_is_ambiguous_not_a_jump_onto_one() {
    // the target gone from where it was, and two copies of it 12 px either side (within
    // half the template of the start: a jump the search range explains): the search
    // cannot tell which is the target (a tag among tags of a structure)
    let (left, right) = (speckle(-12.0, 0.0, 200.0), speckle(12.0, 0.0, 200.0));
    let img: Vec<u8> = left
        .iter()
        .zip(&right)
        .map(|(&a, &b)| (u16::from(a) + u16::from(b) - 40).min(255) as u8)
        .collect();
    let mut t = tracker(24, Interpolation::Bicubic);
    let r = t.track(&frame(&img));
    assert!(r.searched, "{r:?}");
    assert_eq!(r.displacement(), None, "{r:?}");
    assert!(r.flags.contains(Flags::AMBIGUOUS), "{r:?}");
    assert_eq!(t.displacement(), (0.0, 0.0));
    // without the check the search takes one of them: the silent jump this flag prevents
    let mut cfg = *t.config();
    cfg.ambiguity = 0.0;
    let mut t = Lk::try_new(cfg).unwrap();
    t.set_template(&frame(&speckle(0.0, 0.0, 200.0)), 44 - 15, 40 - 15)
        .unwrap();
    let (dx, _) = t.track(&frame(&img)).displacement().expect("a jump");
    assert!((dx.abs() - 12.0).abs() < 0.5, "{dx}");
    // one copy alone, as far: found, not ambiguous
    let mut t = tracker(24, Interpolation::Bicubic);
    let r = t.track(&frame(&right));
    assert!((r.dx - 12.0).abs() < 0.01 && r.flags.is_clear(), "{r:?}");
    // the setting is checked
    cfg.ambiguity = 1.5;
    assert_eq!(cfg.validate(39 * 39, 38), Err(LkError::Setting));
}

#[test]
fn flat_windows_edges_and_saturation_are_refused_or_lost() {
    let mut t = Lk::try_new(LkConfig::new(31, 31)).unwrap();
    let flat = [77u8; FW * FH];
    assert_eq!(t.set_template(&frame(&flat), 10, 10), Err(LkError::Flat));
    // a straight edge moving along itself has no texture across one axis
    let edge: Vec<u8> = (0..FW * FH)
        .map(|i| if i % FW < 48 { 30 } else { 200 })
        .collect();
    assert_eq!(t.set_template(&frame(&edge), 30, 20), Err(LkError::Flat));
    // the template must be inside the frame (at its edge the edge pixels repeat)
    let img = speckle(0.0, 0.0, 200.0);
    assert_eq!(t.set_template(&frame(&img), -1, 10), Err(LkError::Outside));
    assert_eq!(t.set_template(&frame(&img), 66, 10), Err(LkError::Outside));
    let texture: Vec<u8> = (0..FW * FH).map(|i| (i * 37 % 251) as u8).collect();
    assert_eq!(t.set_template(&frame(&texture), 65, 49), Ok(()));
    // followed to the frame's edge, then further: the window would leave the frame
    let mut t = tracker(0, Interpolation::Bicubic);
    for dx in [-7.0, -14.0, -21.0, -27.5] {
        let img = speckle(dx, 0.0, 200.0);
        let r = t.track(&frame(&img));
        assert!((r.dx - dx as f32).abs() < 0.02, "{dx}: {r:?}");
    }
    let img = speckle(-30.5, 0.0, 200.0);
    let r = t.track(&frame(&img));
    assert_eq!(r.displacement(), None, "{r:?}");
    assert!(r.flags.contains(Flags::BORDER), "{r:?}");
    // brighter and clipped at 255: the clipped pixels do not move with the template
    let mut t = tracker(4, Interpolation::Bicubic);
    let img = speckle(0.2, 0.1, 400.0);
    let r = t.track(&frame(&img));
    assert!(r.flags.contains(Flags::SATURATED), "{r:?}");
    assert_eq!(r.displacement(), None);
    // the same clipped frame against a template taken again, from a dim frame, after one
    // taken from a clipped frame (where those pixels were bright): the new template's
    // mask decides, on both paths
    for interpolation in [Interpolation::Bicubic, Interpolation::Spline] {
        let mut t = tracker(4, interpolation);
        let bright = speckle(0.0, 0.0, 400.0);
        t.set_template(&frame(&bright), 29, 25).unwrap();
        let r = t.track(&frame(&speckle(0.2, 0.1, 400.0)));
        assert!(
            !r.flags.contains(Flags::SATURATED),
            "{interpolation:?} {r:?}"
        );
        let dim = speckle(0.0, 0.0, 100.0);
        t.set_template(&frame(&dim), 29, 25).unwrap();
        let r = t.track(&frame(&speckle(0.2, 0.1, 400.0)));
        assert!(
            r.flags.contains(Flags::SATURATED),
            "{interpolation:?} {r:?}"
        );
    }
    // a tracker without a template reports no displacement
    let mut t = Lk::try_new(LkConfig::new(31, 31)).unwrap();
    assert_eq!(t.track(&frame(&img)).displacement(), None);
}

#[test]
fn settings_are_checked_against_the_capacities() {
    assert_eq!(
        Lk::try_new(LkConfig::new(2, 31)).err(),
        Some(LkError::WindowTooSmall)
    );
    assert!(matches!(
        Lk::try_new(LkConfig::new(32, 29)).err(),
        Some(LkError::WindowTooLarge { .. })
    ));
    let mut c = LkConfig::new(31, 31);
    c.tolerance = 0.0;
    assert_eq!(Lk::try_new(c).err(), Some(LkError::Setting));
    let mut c = LkConfig::new(31, 31);
    c.accept_score = 0.2;
    assert_eq!(Lk::try_new(c).err(), Some(LkError::Setting));
}

#[test]
fn sixteen_bit_frames_track_as_eight_bit_ones() {
    let img8 = speckle(0.35, -0.6, 200.0);
    let img16: Vec<u16> = img8.iter().map(|&v| u16::from(v) * 16).collect();
    let mut t = LkTracker::<{ 39 * 39 }, 38>::try_new(LkConfig::new(31, 31)).unwrap();
    let reference: Vec<u16> = speckle(0.0, 0.0, 200.0)
        .iter()
        .map(|&v| u16::from(v) * 16)
        .collect();
    fn f16(p: &[u16]) -> Frame<'_, u16> {
        Frame::new(p, FW, FH, FW).unwrap()
    }
    t.set_template(&f16(&reference), 29, 25).unwrap();
    let a = t.track(&f16(&img16)).displacement().unwrap();
    let b = tracker(15, Interpolation::Spline)
        .track(&frame(&img8))
        .displacement()
        .unwrap();
    assert!(
        (a.0 - b.0).abs() < 1e-3 && (a.1 - b.1).abs() < 1e-3,
        "{a:?} {b:?}"
    );
}

/// Both backends' cross-moment kernels against the sums in f64, for every lag count, on
/// a window whose rows are padded with zeros (as `LkTracker::g` is).
#[test]
fn both_backends_form_the_cross_moments_of_every_lag_count() {
    fn check<const K: usize>(tw: usize, th: usize) {
        let (gs, pw) = (window_stride(tw), tw + 2 * SPLINE_MARGIN);
        let mut g = std::vec![0.0f32; gs * th];
        for (k, v) in g.iter_mut().enumerate() {
            if k % gs < tw {
                *v = ((k * 7919) % 513) as f32 - 256.0;
            }
        }
        let c: Vec<f32> = (0..pw * (th + 4))
            .map(|k| (((k * 104729) % 1001) as f32 - 500.0) / 37.0)
            .collect();
        let (mut lag, mut col, mut scale) = ([0.0f64; K], [0.0f64; K], [0.0f64; K]);
        for j in 0..th {
            for i in 0..gs {
                let gv = f64::from(g[j * gs + i]);
                for k in 0..K {
                    let (a, b) = (f64::from(c[j * pw + i + k]), f64::from(c[(j + k) * pw + i]));
                    lag[k] += gv * a;
                    col[k] += gv * b;
                    scale[k] += (gv * a).abs() + (gv * b).abs();
                }
            }
        }
        let got = [
            (m4::lag_sums::<K>(&g, gs, &c, pw, th), lag),
            (lanes::lag_sums::<K>(&g, gs, &c, pw, th), lag),
            (m4::column_sums::<K>(&g, gs, &c, pw, th), col),
            (lanes::column_sums::<K>(&g, gs, &c, pw, th), col),
        ];
        for (n, (sums, want)) in got.iter().enumerate() {
            for k in 0..K {
                let err = (f64::from(sums[k]) - want[k]).abs();
                assert!(
                    err <= 1e-6 * scale[k],
                    "kernel {n}, {K} lags, {tw} x {th}, lag {k}: {} against {}",
                    sums[k],
                    want[k]
                );
            }
        }
    }
    for (tw, th) in [(3, 3), (4, 5), (9, 7), (31, 31), (37, 12), (64, 3)] {
        check::<1>(tw, th);
        check::<2>(tw, th);
        check::<3>(tw, th);
        check::<4>(tw, th);
    }
}

/// Both backends' `[1 2 1]` row smoothing against the integer sums, exactly (8- and
/// 16-bit pixels, rows shorter and longer than a block, the longest row), and their
/// refusals; both backends' count of newly clipped pixels against the mask read per pixel.
#[test]
fn both_backends_smooth_a_row_exactly_and_count_clipped_pixels_alike() {
    fn check<P: Pixel + Copy>(px: &[P], n: usize, mean: i32) {
        let v = |k: usize| i64::from(px[k].into());
        let rows = [
            &px[..n + 2],
            &px[n + 2..2 * n + 4],
            &px[2 * n + 4..3 * n + 6],
        ];
        let (mut sum, mut sq, mut top) = (0i64, 0i64, 0u16);
        let mut want = std::vec![0.0f32; n];
        let col = |i: usize| v(i) + 2 * v(n + 2 + i) + v(2 * n + 4 + i);
        for (i, w) in want.iter_mut().enumerate() {
            let d = col(i) + 2 * col(i + 1) + col(i + 2) - i64::from(mean);
            *w = d as f32;
            sum += d;
            sq += d * d;
        }
        for &b in rows[1] {
            top = top.max(b.into());
        }
        for backend in 0..2 {
            let mut out = std::vec![f32::NAN; n];
            let r = match backend {
                0 => m4::smooth_row3(rows[0], rows[1], rows[2], &mut out, mean),
                _ => lanes::smooth_row3(rows[0], rows[1], rows[2], &mut out, mean),
            };
            assert_eq!(r, Some((sum, sq, top)), "backend {backend}, {n} pixels");
            assert_eq!(out, want, "backend {backend}, {n} pixels");
            // rows of the wrong length, or too long a row: refused, nothing stored
            let mut short = std::vec![f32::NAN; n + 1];
            let r = match backend {
                0 => m4::smooth_row3(rows[0], rows[1], rows[2], &mut short, mean),
                _ => lanes::smooth_row3(rows[0], rows[1], rows[2], &mut short, mean),
            };
            assert_eq!(r, None);
            assert!(short.iter().all(|v| v.is_nan()));
        }
    }
    let noise = |k: usize, top: u64| ((k as u64 * 2654435761) % (top + 1)) as u32;
    for n in [1, 3, 4, 31, 63, 64, 65, 130, 2047] {
        let p8: Vec<u8> = (0..3 * n + 6).map(|k| noise(k, 255) as u8).collect();
        check(&p8, n, 2040);
        check(&p8, n, 0);
        // the extremes of 8-bit values against the mean (the largest squares: the 16-bit
        // lanes' sums must not overflow), and a mean beyond 8-bit values (a template
        // taken from 16-bit frames)
        check(&std::vec![255u8; 3 * n + 6], n, 0);
        check(&std::vec![0u8; 3 * n + 6], n, 16 * 255);
        check(&p8, n, 1 << 19);
        let p16: Vec<u16> = (0..3 * n + 6).map(|k| noise(k, 65535) as u16).collect();
        check(&p16, n, 1 << 19);
    }
    // longer than 2047 pixels: refused by both
    let long = std::vec![7u8; 2050];
    let mut out = std::vec![0.0f32; 2048];
    assert_eq!(m4::smooth_row3(&long, &long, &long, &mut out, 0), None);
    assert_eq!(lanes::smooth_row3(&long, &long, &long, &mut out, 0), None);

    let row: Vec<u16> = (0..70).map(|k| [65535, 3, 65000, 65535][k % 4]).collect();
    let dark: Vec<bool> = (0..70).map(|k| k % 3 != 0).collect();
    let want = (0..70).filter(|&k| row[k] >= 65000 && dark[k]).count() as u32;
    assert!(want > 0);
    assert_eq!(m4::newly_clipped(&row, &dark, 65000), want);
    assert_eq!(lanes::newly_clipped(&row, &dark, 65000), want);
    // a mask shorter than the row: the pixels past it are not counted
    let want = (0..10).filter(|&k| row[k] >= 65000 && dark[k]).count() as u32;
    assert_eq!(m4::newly_clipped(&row, &dark[..10], 65000), want);
    assert_eq!(lanes::newly_clipped(&row, &dark[..10], 65000), want);
}

#[test]
fn the_hosts_whole_window_pass_equals_the_rows_and_counts_clipped_pixels_alike() {
    let noise = |k: usize, top: u64| ((k as u64 * 2654435761 + 12345) % (top + 1)) as u8;
    for (tw, th) in [
        (8, 1),
        (9, 3),
        (15, 7),
        (16, 16),
        (31, 31),
        (33, 40),
        (40, 100),
    ] {
        let stride = tw + 2 + 5;
        for (mean, px) in [
            (
                2040,
                (0..(th + 2) * stride)
                    .map(|k| noise(k, 255))
                    .collect::<Vec<u8>>(),
            ),
            (0, std::vec![255u8; (th + 2) * stride]),
            (16 * 255, std::vec![0u8; (th + 2) * stride]),
        ] {
            // the rows' smoothing (the M4's, tested above against the sums themselves)
            let gs = window_stride(tw) + 4;
            let mut want = std::vec![0.0f32; th * gs];
            let (mut sum, mut sq, mut top) = (0i64, 0i64, 0u16);
            for j in 0..th {
                let row = |r: usize| &px[r * stride..r * stride + tw + 2];
                let out = &mut want[j * gs..j * gs + tw];
                let (s, q, _) = m4::smooth_row3(row(j), row(j + 1), row(j + 2), out, mean)
                    .expect("rows of the right length");
                (sum, sq) = (sum + s, sq + q);
                let window_row = &row(j + 1)[1..tw + 1];
                top = top.max(window_row.iter().map(|&v| u16::from(v)).max().unwrap_or(0));
            }
            let mut g = std::vec![f32::NAN; th * gs];
            let r = lanes::smooth_window3_bytes(&px, stride, (tw, th), (&mut g, gs), mean);
            assert_eq!(r, Some((sum, sq, top)), "{tw} x {th}, mean {mean}");
            assert_eq!(g, want, "{tw} x {th}, mean {mean}");
            // the whole window's clip count, against the rows' (masks and levels varied)
            let dark: Vec<bool> = (0..tw * th).map(|k| (k * 7) % 5 != 0).collect();
            let win = &px[stride + 1..];
            for sat in [0u16, 1, 128, 255, 256] {
                let rows: u32 = (0..th)
                    .map(|j| {
                        let row = &win[j * stride..j * stride + tw];
                        m4::newly_clipped(row, &dark[j * tw..j * tw + tw], sat)
                    })
                    .sum();
                let whole = lanes::clipped_window_bytes(win, stride, (tw, th), &dark, sat);
                assert_eq!(whole, (tw >= 16).then_some(rows), "{tw} x {th}, sat {sat}");
            }
        }
    }
    // refused, nothing stored: too narrow a window, a mean off the 8-bit scale, too short
    // a source or buffer
    let px = std::vec![9u8; 40 * 40];
    let mut g = std::vec![f32::NAN; 40 * 40];
    assert_eq!(
        lanes::smooth_window3_bytes(&px, 40, (7, 5), (&mut g, 8), 0),
        None
    );
    assert_eq!(
        lanes::smooth_window3_bytes(&px, 40, (8, 5), (&mut g, 8), -1),
        None
    );
    assert_eq!(
        lanes::smooth_window3_bytes(&px, 40, (8, 5), (&mut g, 8), 4081),
        None
    );
    assert_eq!(
        lanes::smooth_window3_bytes(&px[..200], 40, (8, 5), (&mut g, 8), 0),
        None
    );
    assert_eq!(
        lanes::smooth_window3_bytes(&px, 40, (8, 5), (&mut g[..39], 8), 0),
        None
    );
    // rows closer than the source is wide (a stride of 0 among them)
    for stride in [0, 9] {
        let r = lanes::smooth_window3_bytes(&px, stride, (8, 5), (&mut g, 8), 0);
        assert_eq!(r, None);
    }
    assert!(g.iter().all(|v| v.is_nan()));
    assert_eq!(
        m4::smooth_window3_bytes(&px, 40, (8, 5), (&mut g, 8), 0),
        None
    );
    let dark = std::vec![true; 40 * 40];
    assert_eq!(
        lanes::clipped_window_bytes(&px, 40, (16, 40), &dark[..100], 0),
        None
    );
    assert_eq!(
        lanes::clipped_window_bytes(&px[..100], 40, (16, 40), &dark, 0),
        None
    );
    assert_eq!(
        lanes::clipped_window_bytes(&px, 40, (16, 40), &dark, 0),
        Some(16 * 40)
    );
    assert_eq!(m4::clipped_window_bytes(&px, 40, (16, 40), &dark, 0), None);
}

#[test]
fn the_hosts_tap_forms_equal_the_scalar_forms() {
    // a symmetric matrix of moments (as `Moments::of` makes them) with values of many
    // magnitudes, and weights of a spline's shifts
    let n = LAGS * LAGS;
    let mut c = std::vec![0.0f32; n * n];
    for i in 0..n {
        for j in i..n {
            let v = ((i * 31 + j * 17) % 23) as f32 * 1.37e3 - 9.1e3 + (i * j) as f32 * 0.013;
            c[i * n + j] = v;
            c[j * n + i] = v;
        }
    }
    for (fx, fy) in [(0.0, 0.0), (0.3, 0.9), (0.999, 0.5), (0.125, 0.0)] {
        let (wx, wy) = (bspline_weights(fx), bspline_weights(fy));
        for (lx, ly) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let forms = lanes::tap_forms(&c, LAGS, (lx, ly), wx, wy);
            for (m, &got) in forms.iter().enumerate() {
                let (l, k) = (m / 4, m % 4);
                let i = (ly + l) * LAGS + lx + k;
                let mut cu = 0.0f32;
                for (l2, &wyl) in wy.iter().enumerate() {
                    let at = i * n + (ly + l2) * LAGS + lx;
                    let [c0, c1, c2, c3] = [c[at], c[at + 1], c[at + 2], c[at + 3]];
                    let [w0, w1, w2, w3] = wx;
                    cu += wyl * (c0 * w0 + c1 * w1 + c2 * w2 + c3 * w3);
                }
                assert_eq!(got.to_bits(), cu.to_bits(), "lag {i} at ({lx}, {ly})");
            }
        }
    }
}

proptest::proptest! {
    #[test]
    fn nothing_panics_on_any_frame_or_setting(
        seed in proptest::collection::vec(0u8..=255, FW * FH),
        x0 in -5i32..100,
        y0 in -5i32..90,
        w in 0u16..40,
        h in 0u16..40,
        search in 0u16..40,
        bilinear in proptest::bool::ANY,
    ) {
        let mut cfg = LkConfig::new(w, h);
        cfg.search = search;
        if bilinear {
            cfg.interpolation = Interpolation::Bilinear;
        }
        if let Ok(mut t) = LkTracker::<{ 39 * 39 }, 38>::try_new(cfg) {
            let f = frame(&seed);
            let _ = t.set_template(&f, x0, y0);
            let r = t.track(&f);
            if let Some((dx, dy)) = r.displacement() {
                proptest::prop_assert!(dx.is_finite() && dy.is_finite());
            }
        }
    }
}

#[test]
fn the_separable_dark_mask_is_the_definition_at_every_pixel() {
    let noise = |k: usize| ((k as u64 * 2654435761 + 977) % 1000) as f32;
    for (tw, th) in [(3, 3), (5, 9), (21, 21), (31, 4), (3, 7), (7, 3)] {
        for sparse in [1usize, 7, 40, 1000] {
            let mut lk = Lk::try_new(LkConfig::new(tw as u16, th as u16)).unwrap();
            for (k, v) in lk.t.iter_mut().take(tw * th).enumerate() {
                // bright pixels (at or above 3/4 of 255) one in `sparse`, a NaN now and then
                *v = match (k % sparse, k % 11) {
                    (0, _) => 191.25 + noise(k) / 10.0,
                    (_, 5) => f32::NAN,
                    _ => noise(k) / 6.0,
                };
            }
            lk.dark_sat = 0;
            lk.mark_dark(255);
            for j in 0..th {
                for i in 0..tw {
                    assert_eq!(
                        lk.dark[j * tw + i],
                        dark_near(&lk.t, (tw, th), (i, j), 255),
                        "{tw} x {th}, one bright in {sparse}: pixel ({i}, {j})"
                    );
                }
            }
        }
    }
}

/// Horizontal stripes (period 7 px, 120 grey levels) with a faint texture along them (period 37
/// px, 16 levels), displaced by `(dx, dy)`, 8-bit, with pseudo-random noise of up to `noise`
/// grey levels (seeded by `seed`).
fn stripes(dx: f64, dy: f64, (noise, seed): (f64, u64)) -> Vec<u8> {
    let tau = 2.0 * core::f64::consts::PI;
    let mut px = Vec::with_capacity(FW * FH);
    for y in 0..FH {
        for x in 0..FW {
            // (the displaced frame's stripes turned by `noise / 300` rad: a bending beam)
            let (u, v) = (
                x as f64 - dx,
                y as f64 - dy - noise / 300.0 * (x as f64 - 40.0),
            );
            let k = (y * FW + x) as u64 + seed * 7919;
            let e = noise * (((k * 2654435761 + 12345) % 2001) as f64 / 1000.0 - 1.0);
            let g = 128.0 + 60.0 * libm::sin(tau * v / 7.0) + 8.0 * libm::sin(tau * u / 37.0) + e;
            px.push(libm::round(g).clamp(0.0, 255.0) as u8);
        }
    }
    px
}

#[test]
fn a_striped_window_is_aperture_limited_and_measured_across_its_stripes() {
    // a speckle window is textured both ways: its steps count whole
    assert_eq!(tracker(0, Interpolation::Spline).weak_direction(), None);
    let mut cfg = LkConfig::new(21, 21);
    cfg.search = 0;
    let mut t = Lk::try_new(cfg).unwrap();
    t.set_template(&frame(&stripes(0.0, 0.0, (0.0, 0))), 30, 30)
        .unwrap();
    // the weak direction is along the stripes (x), measured about 1000 times more weakly
    let ((wx, wy), r) = t.weak_direction().expect("an aperture-limited window");
    assert!(wx.abs() > 0.999 && wy.abs() < 0.05, "({wx}, {wy})");
    assert!(r * r < APERTURE, "{r}");
    for &(dx, dy) in &[(0.3, 0.4), (-0.6, -0.25), (1.4, 0.8)] {
        let mut t = Lk::try_new(cfg).unwrap();
        t.set_template(&frame(&stripes(0.0, 0.0, (0.0, 0))), 30, 30)
            .unwrap();
        let r = t.track(&frame(&stripes(dx, dy, (3.0, 1))));
        let (_, my) = r.displacement().expect("tracked");
        assert!((my - dy as f32).abs() < 0.01, "({dx}, {dy}): y {my}");
        // measured: 3 iterations (as many with every step counted whole: a clean translation
        // settles along the stripes too; the real beam's windows, which wandered, are checked
        // by the host's tests)
        assert!(
            r.iterations <= 6,
            "({dx}, {dy}): {} iterations",
            r.iterations
        );
    }
}

#[test]
fn the_searchs_pixel_zncc_is_the_block_zncc_of_blocks_of_one() {
    // the lanes' sums against the plain per-pixel loop, at offsets all over the range,
    // 8-bit and 16-bit frames, and none outside the frame
    let t = tracker(8, Interpolation::Bicubic);
    let img = speckle(0.7, -2.2, 200.0);
    let sums = t.template_sums();
    // 16 bits: a template of 16-bit frames
    let to16 = |px: &[u8]| -> Vec<u16> { px.iter().map(|&v| u16::from(v) * 97 + 3).collect() };
    let (reference, wide) = (to16(&speckle(0.0, 0.0, 200.0)), to16(&img));
    let f16 = Frame::new(&wide, FW, FH, FW).unwrap();
    let mut t16 = t.clone();
    t16.set_template(
        &Frame::new(&reference, FW, FH, FW).unwrap(),
        44 - 15,
        40 - 15,
    )
    .unwrap();
    let sums16 = t16.template_sums();
    let mut seen = 0;
    for dy in -12i64..=12 {
        for dx in -12i64..=12 {
            let (a, b) = (
                t.zncc_pixels(&frame(&img), dx, dy, sums),
                t.zncc_at(&frame(&img), dx, dy, 1),
            );
            assert_eq!(a.is_some(), b.is_some(), "{dx},{dy}");
            if let (Some(a), Some(b)) = (a, b) {
                assert!((a - b).abs() < 2e-5, "{dx},{dy}: {a} {b}");
                seen += 1;
            }
            let (c, d) = (
                t16.zncc_pixels(&f16, dx, dy, sums16),
                t16.zncc_at(&f16, dx, dy, 1),
            );
            assert_eq!(c.is_some(), d.is_some());
            if let (Some(c), Some(d)) = (c, d) {
                assert!((c - d).abs() < 2e-5, "{dx},{dy}: {c} {d}");
            }
        }
    }
    // the window (31 px at 29, 25 in a 96 x 80 frame) fits at every offset up to 12 px
    assert_eq!(seen, 25 * 25);
    // at the true whole-pixel shift the match is near perfect
    assert!(t.zncc_pixels(&frame(&img), 1, -2, sums).unwrap() > 0.95);
    assert_eq!(t.zncc_pixels(&frame(&img), -40, 0, sums), None);
    assert_eq!(t.zncc_pixels(&frame(&img), 0, 60, sums), None);
}

#[test]
fn both_backends_sum_a_search_offset_as_f64_does() {
    // windows 5 to 21 px wide (remainders of the four lanes 0 to 3), 8-bit frame rows
    for tw in [5usize, 8, 13, 21] {
        let th = 7;
        let t: Vec<f32> = (0..tw * th)
            .map(|k| ((k * 37) % 251) as f32 * 0.9)
            .collect();
        let f: Vec<u8> = (0..tw * th).map(|k| ((k * 53 + 11) % 256) as u8).collect();
        let m = 101.5f32;
        let (mut a, mut b, mut c) = (0.0f64, 0.0f64, 0.0f64);
        for (t, f) in t.iter().zip(&f) {
            let (vt, vf) = (f64::from(*t) - f64::from(m), f64::from(*f) - f64::from(m));
            a += vf;
            b += vf * vf;
            c += vf * vt;
        }
        for got in [
            m4::zncc_sums(&t, tw, f.chunks_exact(tw), m),
            lanes::zncc_sums(&t, tw, f.chunks_exact(tw), m),
        ] {
            for (g, want) in got.iter().zip([a, b, c]) {
                assert!(
                    (f64::from(*g) - want).abs() <= 1e-6 * want.abs().max(1e3),
                    "{tw}: {got:?} {a} {b} {c}"
                );
            }
        }
    }
}
