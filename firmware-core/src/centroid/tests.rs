//! Tests of the centroiding against independent references: a naive double loop over the
//! frame, a flood-fill labelling, closed forms for symmetric frames and rendered disks.

extern crate std;

use super::*;
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::vec;
use std::vec::Vec;

/// The one-shot centroid of a strided 8- or 16-bit frame (the former `centroid_u8` and
/// `centroid_u16`).
fn centroid_strided<P: Pixel>(
    cfg: &CentroidConfig,
    px: &[P],
    w: usize,
    h: usize,
    stride: usize,
) -> Result<Centroid, FrameError> {
    Frame::new(px, w, h, stride).and_then(|f| centroid(cfg, &f))
}

/// Settings from their four values, checked (the former `CentroidConfig::try_new`).
fn config(
    threshold: u16,
    mode: Mode,
    roi: Option<Roi>,
    saturation: Option<u16>,
) -> Result<CentroidConfig, ConfigError> {
    CentroidConfig {
        threshold,
        mode,
        roi,
        saturation,
    }
    .validate()
}

/// A ROI from its corner and size.
fn roi(x: u32, y: u32, width: u32, height: u32) -> Roi {
    Roi {
        x,
        y,
        width,
        height,
    }
}

/// A centroider for valid settings.
fn centroider(cfg: CentroidConfig) -> Centroider {
    Centroider::try_new(cfg).unwrap()
}

/// The references' region `(x0, y0, x1, y1)` (end exclusive): the ROI, or the whole
/// `width x height` frame.
fn region(roi: Option<Roi>, width: usize, height: usize) -> (usize, usize, usize, usize) {
    match roi {
        Some(r) => (
            r.x as usize,
            r.y as usize,
            (r.x + r.width) as usize,
            (r.y + r.height) as usize,
        ),
        None => (0, 0, width, height),
    }
}

/// Naive reference: one double loop over the region, u128 sums, flags from their definitions.
#[allow(clippy::too_many_arguments)]
fn naive(
    px: &[u32],
    width: usize,
    height: usize,
    stride: usize,
    t: u32,
    sat: u32,
    mode: Mode,
    roi: Option<Roi>,
) -> (u128, u128, u128, u128, Flags) {
    let (rx0, ry0, rx1, ry1) = region(roi, width, height);
    let (mut n, mut w, mut sx, mut sy) = (0u128, 0u128, 0u128, 0u128);
    let mut flags = Flags::NONE;
    for y in ry0..ry1 {
        for x in rx0..rx1 {
            let v = px[y * stride + x];
            if v > t {
                let wt = match mode {
                    Mode::Binary => 1,
                    Mode::Weighted => u128::from(v - t),
                };
                n += 1;
                w += wt;
                sx += x as u128 * wt;
                sy += y as u128 * wt;
                if x == rx0 || x == rx1 - 1 || y == ry0 || y == ry1 - 1 {
                    flags |= Flags::BORDER;
                }
                if v >= sat {
                    flags |= Flags::SATURATED;
                }
            }
        }
    }
    if n == 0 {
        flags |= Flags::EMPTY;
    }
    (n, w, sx, sy, flags)
}

/// `|a - b|` within one f32 ulp of `b`.
fn within_ulp(a: f32, b: f64) -> bool {
    let b32 = b as f32;
    let ulp = f32::from_bits(b32.abs().to_bits() + 1) - b32.abs();
    (f64::from(a) - b).abs() <= f64::from(ulp)
}

fn check_against_naive(c: &Centroid, r: (u128, u128, u128, u128, Flags)) {
    let (n, w, sx, sy, flags) = r;
    assert_eq!(u128::from(c.moments.pixels), n);
    assert_eq!(u128::from(c.moments.weight), w);
    assert_eq!(u128::from(c.moments.sum_x), sx);
    assert_eq!(u128::from(c.moments.sum_y), sy);
    assert_eq!(c.flags, flags);
    if n == 0 {
        assert_eq!((c.cx, c.cy), (0.0, 0.0));
        assert!(c.position().is_none());
    } else {
        let (ex, ey) = (sx as f64 / w as f64, sy as f64 / w as f64);
        assert!(within_ulp(c.cx, ex), "cx {} vs {}", c.cx, ex);
        assert!(within_ulp(c.cy, ey), "cy {} vs {}", c.cy, ey);
    }
}

fn mode_strategy() -> impl Strategy<Value = Mode> {
    prop_oneof![Just(Mode::Binary), Just(Mode::Weighted)]
}

/// A frame of `w x h` pixels with stride `w + pad`, values in `0..=max`, biased towards a few
/// bright blobs (so that thresholds in the middle select something) and full-scale pixels.
fn frame_strategy(max: u32) -> impl Strategy<Value = (usize, usize, usize, Vec<u32>)> {
    (1usize..48, 1usize..32, 0usize..5).prop_flat_map(move |(w, h, pad)| {
        let n = (h - 1) * (w + pad) + w;
        let px = prop_oneof![
            3 => 0..=max / 4,
            2 => 0..=max,
            1 => Just(max),
        ];
        (
            Just(w),
            Just(h),
            Just(w + pad),
            proptest::collection::vec(px, n),
        )
    })
}

fn roi_strategy(w: usize, h: usize) -> impl Strategy<Value = Option<Roi>> {
    let some = (0..w, 0..h).prop_flat_map(move |(x, y)| {
        (1..=w - x, 1..=h - y)
            .prop_map(move |(rw, rh)| Some(roi(x as u32, y as u32, rw as u32, rh as u32)))
    });
    prop_oneof![Just(None), some]
}

/// A frame from [`frame_strategy`] with a ROI inside it from [`roi_strategy`].
#[allow(clippy::type_complexity)]
fn frame_roi_strategy(
    max: u32,
) -> impl Strategy<Value = (usize, usize, usize, Vec<u32>, Option<Roi>)> {
    frame_strategy(max)
        .prop_flat_map(|(w, h, s, px)| (Just(w), Just(h), Just(s), Just(px), roi_strategy(w, h)))
}

proptest! {
    #[test]
    fn whole_frame_u8_matches_naive_double_loop(
        (w, h, stride, px, roi) in frame_roi_strategy(255),
        t in 0u16..300,
        mode in mode_strategy(),
        sat in prop_oneof![Just(None), (150u16..400).prop_map(Some)],
    ) {
        let Ok(cfg) = config(t, mode, roi, sat) else {
            prop_assume!(false);
            unreachable!()
        };
        let frame: Vec<u8> = px.iter().map(|&v| v as u8).collect();
        let c = centroid_strided(&cfg, &frame, w, h, stride).unwrap();
        let sat_level = u32::from(sat.unwrap_or(255).min(255));
        let r = naive(&px, w, h, stride, u32::from(t), sat_level, mode, roi);
        check_against_naive(&c, r);
    }

    #[test]
    fn whole_frame_u16_matches_naive_double_loop(
        (w, h, stride, px, roi) in frame_roi_strategy(65535),
        t in 0u16..=65535,
        mode in mode_strategy(),
        sat in prop_oneof![Just(None), (30000u16..=65535).prop_map(Some)],
    ) {
        let Ok(cfg) = config(t, mode, roi, sat) else {
            prop_assume!(false);
            unreachable!()
        };
        let frame: Vec<u16> = px.iter().map(|&v| v as u16).collect();
        let c = centroid_strided(&cfg, &frame, w, h, stride).unwrap();
        let r = naive(&px, w, h, stride, u32::from(t), u32::from(sat.unwrap_or(65535)), mode, roi);
        check_against_naive(&c, r);
    }

    /// Row kernels over several blocks plus a tail, against a naive loop.
    #[test]
    fn row_kernels_match_naive(
        row in proptest::collection::vec(any::<u16>(), 0..9000),
        t16 in any::<u16>(),
        t8 in any::<u8>(),
    ) {
        let row8: Vec<u8> = row.iter().map(|&v| (v >> 8) as u8).collect();
        let naive_row = |vals: &[u32], t: u32, weighted: bool| {
            let mut s = (0u64, 0u64, 0u64, 0u32);
            for (x, &v) in vals.iter().enumerate() {
                if v > t {
                    let w = if weighted { u64::from(v - t) } else { 1 };
                    s.0 += 1;
                    s.1 += w;
                    s.2 += x as u64 * w;
                }
                s.3 = s.3.max(v);
            }
            RowSums { pixels: s.0 as u32, weight: s.1 as u32, sum_x: s.2, max: s.3 as u16 }
        };
        let v16: Vec<u32> = row.iter().map(|&v| u32::from(v)).collect();
        let v8: Vec<u32> = row8.iter().map(|&v| u32::from(v)).collect();
        prop_assert_eq!(row_binary_u16(&row, t16), naive_row(&v16, u32::from(t16), false));
        prop_assert_eq!(row_weighted_u16(&row, t16), naive_row(&v16, u32::from(t16), true));
        prop_assert_eq!(row_binary_u8(&row8, t8), naive_row(&v8, u32::from(t8), false));
        prop_assert_eq!(row_weighted_u8(&row8, t8), naive_row(&v8, u32::from(t8), true));
    }

    /// Streaming rows one at a time (from rows padded with bright garbage past the width)
    /// equals the whole-frame call to the last bit.
    #[test]
    fn streaming_equals_whole_frame(
        (w, h, stride, px, roi) in frame_roi_strategy(255),
        t in 0u16..255,
        mode in mode_strategy(),
    ) {
        let cfg = config(t, mode, roi, None).unwrap();
        let frame: Vec<u8> = px.iter().map(|&v| v as u8).collect();
        let whole = centroid_strided(&cfg, &frame, w, h, stride).unwrap();
        let mut c = centroider(cfg);
        for y in 0..h {
            let row: Vec<u8> = frame[y * stride..y * stride + w].to_vec();
            c.push_row(&row);
        }
        let streamed = c.result();
        prop_assert_eq!(streamed.moments, whole.moments);
        prop_assert_eq!(streamed.flags, whole.flags);
        prop_assert_eq!(streamed.cx.to_bits(), whole.cx.to_bits());
        prop_assert_eq!(streamed.cy.to_bits(), whole.cy.to_bits());
        // After a reset the same centroider gives the same result again.
        c.reset();
        for y in 0..h {
            c.push_row(&frame[y * stride..y * stride + w]);
        }
        prop_assert_eq!(c.result(), whole);
    }

    /// Moving the frame content by whole pixels moves the moments by exactly `d * weight`, so
    /// the centroid (an exact rational) moves by exactly `d`.
    #[test]
    fn integer_translation_moves_centroid_exactly(
        (w, h, _stride, px) in frame_strategy(65535),
        dx in 0usize..40,
        dy in 0usize..40,
        t in 0u16..60000,
        mode in mode_strategy(),
    ) {
        // Content surrounded by a one-pixel background margin so no flag changes either.
        let (fw, fh) = (w + 2 + 40, h + 2 + 40);
        let place = |ox: usize, oy: usize| {
            let mut f = vec![0u16; fw * fh];
            for y in 0..h {
                for x in 0..w {
                    f[(y + oy + 1) * fw + x + ox + 1] = px[y * w + x] as u16;
                }
            }
            f
        };
        let cfg = config(t, mode, None, None).unwrap();
        let a = centroid_strided(&cfg, &place(0, 0), fw, fh, fw).unwrap();
        let b = centroid_strided(&cfg, &place(dx, dy), fw, fh, fw).unwrap();
        prop_assert_eq!(a.flags, b.flags);
        prop_assert_eq!(a.moments.pixels, b.moments.pixels);
        prop_assert_eq!(a.moments.weight, b.moments.weight);
        prop_assert_eq!(b.moments.sum_x, a.moments.sum_x + dx as u64 * a.moments.weight);
        prop_assert_eq!(b.moments.sum_y, a.moments.sum_y + dy as u64 * a.moments.weight);
        if let (Some((ax, ay)), Some((bx, by))) = (a.position(), b.position()) {
            prop_assert!(within_ulp(bx, f64::from(ax) + dx as f64) || within_ulp(bx - dx as f32, f64::from(ax)));
            prop_assert!(within_ulp(by, f64::from(ay) + dy as f64) || within_ulp(by - dy as f32, f64::from(ay)));
        }
    }
}

#[test]
fn single_pixel_centroid_is_its_index() {
    let (w, h) = (37, 23);
    for (i, j) in [(0, 0), (36, 22), (5, 7), (17, 0), (0, 11)] {
        let mut f = vec![10u8; w * h];
        f[j * w + i] = 200;
        for mode in [Mode::Binary, Mode::Weighted] {
            let cfg = config(100, mode, None, None).unwrap();
            let c = centroid_strided(&cfg, &f, w, h, w).unwrap();
            assert_eq!(c.position(), Some((i as f32, j as f32)));
            assert_eq!(c.pixels(), 1);
        }
    }
}

/// Smooth-edged disk (flat level inside, edge `Phi((R - rho) / sigma)`): radially symmetric
/// and effectively band-limited, so its sampled centre of gravity is the true centre.
fn smooth_disk(w: usize, h: usize, cx: f64, cy: f64, r: f64, sigma: f64, level: f64) -> Vec<u16> {
    let mut f = vec![0u16; w * h];
    for y in 0..h {
        for x in 0..w {
            let rho = ((x as f64 - cx).powi(2) + (y as f64 - cy).powi(2)).sqrt();
            let v = level * 0.5 * libm::erfc((rho - r) / (sigma * core::f64::consts::SQRT_2));
            f[y * w + x] = v.round() as u16;
        }
    }
    f
}

#[test]
fn weighted_smooth_disk_found_within_a_thousandth_of_a_pixel() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let (w, h) = (64, 64);
    let cfg = config(0, Mode::Weighted, None, None).unwrap();
    let mut worst = 0.0f64;
    for _ in 0..50 {
        let cx = 31.0 + rng.random::<f64>();
        let cy = 30.0 + rng.random::<f64>();
        let f = smooth_disk(w, h, cx, cy, 12.0, 1.5, 60000.0);
        let c = centroid_strided(&cfg, &f, w, h, w).unwrap();
        assert_eq!(c.flags, Flags::NONE);
        worst = worst
            .max((f64::from(c.cx) - cx).abs())
            .max((f64::from(c.cy) - cy).abs());
    }
    assert!(worst < 0.001, "worst weighted error {worst} px");
}

/// Exact binary centroid of the pixel centres inside a circle, row by row from the chord
/// end points (closed form, independent of the frame loop).
fn lattice_disk_centroid(cx: f64, cy: f64, r: f64) -> (f64, f64) {
    let (mut n, mut sx, mut sy) = (0.0, 0.0, 0.0);
    for y in (cy - r).floor() as i64 - 1..=(cy + r).ceil() as i64 + 1 {
        let d = r * r - (y as f64 - cy).powi(2);
        if d < 0.0 {
            continue;
        }
        let half = d.sqrt();
        let (a, b) = ((cx - half).ceil() as i64, (cx + half).floor() as i64);
        if b < a {
            continue;
        }
        let k = (b - a + 1) as f64;
        n += k;
        sx += (a + b) as f64 * k / 2.0;
        sy += y as f64 * k;
    }
    (sx / n, sy / n)
}

/// Hard-edged 8-bit disk: 200 where the pixel centre is within `r` of the centre, else 0.
fn hard_disk(w: usize, h: usize, cx: f64, cy: f64, r: f64) -> Vec<u8> {
    crate::test_support::disk(w, h, (cx, cy), r, 0, 200)
}

/// Binary mode on a disk: a hard threshold keeps the pixel centres inside a circle, whose
/// centroid differs from the true centre by a lattice error (up to about 0.1 px at R = 12,
/// still about 0.02 px at R = 1000). So: (1) the binary centroid equals the closed-form
/// lattice centroid; (2) at centres where the lattice is symmetric (integer or half-integer)
/// it is within 0.01 px of the true centre; (3) averaged over random sub-pixel centres it is
/// unbiased to 0.01 px.
#[test]
fn binary_disk_matches_lattice_reference_and_true_centre() {
    let (w, h) = (64, 64);
    let r = 12.0;
    let cfg = config(100, Mode::Binary, None, None).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let (mut bias_x, mut bias_y) = (0.0, 0.0);
    let runs = 400;
    for _ in 0..runs {
        let cx = 31.0 + rng.random::<f64>();
        let cy = 30.0 + rng.random::<f64>();
        let f = hard_disk(w, h, cx, cy, r);
        let c = centroid_strided(&cfg, &f, w, h, w).unwrap();
        let (lx, ly) = lattice_disk_centroid(cx, cy, r);
        assert!((f64::from(c.cx) - lx).abs() < 1e-5, "{} vs {lx}", c.cx);
        assert!((f64::from(c.cy) - ly).abs() < 1e-5, "{} vs {ly}", c.cy);
        bias_x += f64::from(c.cx) - cx;
        bias_y += f64::from(c.cy) - cy;
    }
    assert!(
        (bias_x / runs as f64).abs() < 0.01,
        "mean x error {}",
        bias_x / runs as f64
    );
    assert!(
        (bias_y / runs as f64).abs() < 0.01,
        "mean y error {}",
        bias_y / runs as f64
    );
    for (cx, cy) in [(31.0, 30.0), (31.5, 30.0), (31.5, 30.5), (31.0, 30.5)] {
        let f = hard_disk(w, h, cx, cy, r + 0.3);
        let c = centroid_strided(&cfg, &f, w, h, w).unwrap();
        assert!((f64::from(c.cx) - cx).abs() < 0.01 && (f64::from(c.cy) - cy).abs() < 0.01);
    }
}

#[test]
fn full_scale_4096_square_16_bit_frame_gives_exact_centre() {
    let n = 4096usize;
    let f = vec![u16::MAX; n * n];
    for (mode, t) in [
        (Mode::Binary, 0u16),
        (Mode::Weighted, 0),
        (Mode::Weighted, 1000),
    ] {
        let cfg = config(t, mode, None, None).unwrap();
        let c = centroid_strided(&cfg, &f, n, n, n).unwrap();
        let w = match mode {
            Mode::Binary => 1u128,
            Mode::Weighted => u128::from(u16::MAX - t),
        };
        let count = (n * n) as u128;
        // sum over the frame of x * w = n * (n (n - 1) / 2) * w.
        let s = n as u128 * (n as u128 * (n as u128 - 1) / 2) * w;
        assert_eq!(u128::from(c.moments.pixels), count);
        assert_eq!(u128::from(c.moments.weight), count * w);
        assert_eq!(u128::from(c.moments.sum_x), s);
        assert_eq!(u128::from(c.moments.sum_y), s);
        assert_eq!(c.position(), Some((2047.5, 2047.5)));
        assert_eq!(c.flags, Flags::BORDER | Flags::SATURATED);
    }
}

/// The accumulator bound of the module docs at its limit: 65 536 rows of 65 536 full-scale
/// weighted pixels (row sums from the closed form) do not overflow (overflow checks are on in
/// tests) and give the exact centre.
#[test]
fn accumulators_hold_the_largest_frame() {
    let n = MAX_DIM as u64;
    let row = RowSums {
        pixels: n as u32,
        weight: (n * 65535) as u32,
        sum_x: 65535 * n * (n - 1) / 2,
        max: 65535,
    };
    // The row kernel agrees with that closed form on a full row.
    let full = vec![u16::MAX; MAX_DIM];
    assert_eq!(row_weighted_u16(&full, 0), row);
    let full8 = vec![u8::MAX; MAX_DIM];
    let n32 = n as u32;
    let binary = RowSums {
        pixels: n32,
        weight: n32,
        sum_x: n * (n - 1) / 2,
        max: 255,
    };
    assert_eq!(row_binary_u8(&full8, 0), binary);
    assert_eq!(
        row_binary_u16(&full, 0),
        RowSums {
            max: 65535,
            ..binary
        }
    );
    assert_eq!(
        row_weighted_u8(&full8, 0),
        RowSums {
            weight: n32 * 255,
            sum_x: 255 * n * (n - 1) / 2,
            ..binary
        }
    );
    let mut m = Moments::default();
    for y in 0..n {
        m.add_row(&row, 0, y);
    }
    assert_eq!(m.pixels, n * n);
    assert_eq!(
        u128::from(m.sum_x),
        65535 * u128::from(n) * u128::from(n) * u128::from(n - 1) / 2
    );
    assert_eq!(m.position(), Some((32767.5, 32767.5)));
}

// ---------------------------------------------------------------------------------------------
// Flags

fn frame_with(w: usize, h: usize, pixels: &[(usize, usize, u8)]) -> Vec<u8> {
    let mut f = vec![0u8; w * h];
    for &(x, y, v) in pixels {
        f[y * w + x] = v;
    }
    f
}

#[test]
fn flag_empty_when_nothing_above_threshold() {
    let f = frame_with(10, 8, &[(3, 3, 100)]);
    let cfg = config(100, Mode::Binary, None, None).unwrap();
    let c = centroid_strided(&cfg, &f, 10, 8, 10).unwrap();
    assert_eq!(c.flags, Flags::EMPTY);
    assert_eq!((c.cx, c.cy, c.position()), (0.0, 0.0, None));
    // 8-bit frame with a threshold at or above 255 selects nothing, even full-scale pixels.
    let f = vec![255u8; 80];
    let cfg = config(255, Mode::Weighted, None, None).unwrap();
    assert_eq!(
        centroid_strided(&cfg, &f, 10, 8, 10).unwrap().flags,
        Flags::EMPTY
    );
    let cfg = config(300, Mode::Binary, None, None).unwrap();
    assert_eq!(
        centroid_strided(&cfg, &f, 10, 8, 10).unwrap().flags,
        Flags::EMPTY
    );
    // 16-bit.
    let f = vec![65535u16; 80];
    let cfg = config(65535, Mode::Binary, None, None).unwrap();
    assert_eq!(
        centroid_strided(&cfg, &f, 10, 8, 10).unwrap().flags,
        Flags::EMPTY
    );
    // A fresh streaming centroider has no centroid either.
    assert_eq!(centroider(cfg).result().flags, Flags::EMPTY);
}

#[test]
fn flag_border_on_each_frame_and_roi_edge() {
    let (w, h) = (12, 9);
    let cfg = CentroidConfig::binary(50);
    let at = |x, y| centroid_strided(&cfg, &frame_with(w, h, &[(x, y, 200)]), w, h, w).unwrap();
    assert_eq!(at(5, 4).flags, Flags::NONE);
    for (x, y) in [(0, 4), (11, 4), (5, 0), (5, 8), (0, 0), (11, 8)] {
        assert_eq!(at(x, y).flags, Flags::BORDER, "pixel at ({x}, {y})");
    }
    // ROI columns 2..=8, rows 1..=6: its edges count, pixels outside it do not.
    let cfg = config(50, Mode::Binary, Some(roi(2, 1, 7, 6)), None).unwrap();
    let at = |x, y| centroid_strided(&cfg, &frame_with(w, h, &[(x, y, 200)]), w, h, w).unwrap();
    assert_eq!(at(5, 4).flags, Flags::NONE);
    for (x, y) in [(2, 4), (8, 4), (5, 1), (5, 6)] {
        let c = at(x, y);
        assert_eq!(c.flags, Flags::BORDER, "pixel at ({x}, {y})");
        assert_eq!(c.position(), Some((x as f32, y as f32)));
    }
    for (x, y) in [(1, 4), (9, 4), (5, 0), (5, 7)] {
        assert_eq!(
            at(x, y).flags,
            Flags::EMPTY,
            "pixel at ({x}, {y}) outside the ROI"
        );
    }
    // Streaming: a frame that ends before the ROI does makes its last row the border.
    let cfg = config(50, Mode::Binary, Some(roi(0, 0, 12, 100)), None).unwrap();
    let mut c = centroider(cfg);
    let f = frame_with(w, h, &[(5, 8, 200)]);
    for row in f.chunks(w) {
        c.push_row(row);
    }
    assert_eq!(c.result().flags, Flags::BORDER);
    // A row shorter than the ROI: its last pixel is that row's right border.
    let mut c = centroider(cfg);
    c.push_row(&[0u8; 12]);
    c.push_row(&[0u8, 0, 0, 200]);
    c.push_row(&[0u8; 12]);
    assert_eq!(c.result().flags, Flags::BORDER);
}

#[test]
fn flag_saturated_at_full_scale_or_configured_level() {
    let (w, h) = (8, 8);
    let full_scale = CentroidConfig::binary(50);
    // A 12-bit camera in a 16-bit container saturates at 4095.
    let twelve_bit = config(50, Mode::Weighted, None, Some(4095)).unwrap();
    // Configured 8-bit level.
    let level_200 = config(50, Mode::Binary, None, Some(200)).unwrap();
    // A saturated pixel outside the ROI does not count.
    let in_roi = config(50, Mode::Binary, Some(roi(0, 0, 3, 8)), None).unwrap();
    for (cfg, pixels, want) in [
        (full_scale, &[(3, 3, 254), (4, 3, 200)][..], Flags::NONE),
        (full_scale, &[(3, 3, 255), (4, 3, 200)], Flags::SATURATED),
        (level_200, &[(3, 3, 199)], Flags::NONE),
        (level_200, &[(3, 3, 200)], Flags::SATURATED),
        (in_roi, &[(1, 3, 100), (5, 3, 255)], Flags::NONE),
    ] {
        let f = frame_with(w, h, pixels);
        let got = centroid_strided(&cfg, &f, w, h, w).unwrap().flags;
        assert_eq!(got, want, "{cfg:?}, 8-bit pixels {pixels:?}");
    }
    for (cfg, level, want) in [
        (full_scale, 65534, Flags::NONE),
        (full_scale, 65535, Flags::SATURATED),
        (twelve_bit, 4094, Flags::NONE),
        (twelve_bit, 4095, Flags::SATURATED),
    ] {
        let mut f16 = vec![0u16; 64];
        f16[27] = level;
        let got = centroid_strided(&cfg, &f16, w, h, w).unwrap().flags;
        assert_eq!(got, want, "{cfg:?}, 16-bit pixel {level}");
    }
}

#[test]
fn flag_clipped_for_rows_longer_than_supported() {
    let mut c = centroider(CentroidConfig::binary(10));
    let mut row = vec![0u8; MAX_DIM + 5];
    row[100] = 200;
    row[MAX_DIM + 2] = 200; // ignored
    c.push_row(&[0u8; 4]);
    c.push_row(&row);
    c.push_row(&[0u8; 4]);
    let r = c.result();
    assert_eq!(r.flags, Flags::CLIPPED);
    assert_eq!(r.position(), Some((100.0, 1.0)));
    // Multi-target: a row wider than the label buffer.
    let mut m = MultiCentroider::<8, 4>::try_new(CentroidConfig::binary(10)).unwrap();
    m.push_row(&[0u8; 8]);
    m.push_row(&[0u8, 200, 0, 0, 0, 0, 0, 0, 0, 200]);
    m.push_row(&[0u8; 8]);
    assert_eq!(m.count(), 1);
    assert!(m.flags().contains(Flags::CLIPPED));
}

#[test]
fn flags_display_and_bits() {
    assert_eq!(std::format!("{}", Flags::NONE), "none");
    assert_eq!(
        std::format!("{}", Flags::BORDER | Flags::SATURATED),
        "border|saturated"
    );
    assert_eq!(u8::from(Flags::EMPTY | Flags::CAPACITY), 9);
    assert_eq!(Flags::from_bits_truncate(0xff).bits(), 127);
}

// ---------------------------------------------------------------------------------------------
// Configuration and frame errors

#[test]
fn invalid_settings_and_frames_are_rejected() {
    let roi = |x, y, width, height| {
        Some(Roi {
            x,
            y,
            width,
            height,
        })
    };
    assert_eq!(
        config(10, Mode::Binary, roi(0, 0, 0, 5), None),
        Err(ConfigError::EmptyRoi)
    );
    assert_eq!(
        config(10, Mode::Binary, roi(65000, 0, 600, 5), None),
        Err(ConfigError::RoiTooLarge)
    );
    assert_eq!(
        config(10, Mode::Binary, roi(u32::MAX, 0, 600, 5), None),
        Err(ConfigError::RoiTooLarge)
    );
    assert!(matches!(
        config(100, Mode::Binary, None, Some(100)),
        Err(ConfigError::SaturationNotAboveThreshold { .. })
    ));
    let cfg = config(10, Mode::Binary, roi(0, 0, 20, 5), None).unwrap();
    assert!(matches!(
        MultiCentroider::<16, 4>::try_new(cfg),
        Err(ConfigError::RoiTooWide { width: 20, max: 16 })
    ));
    let f = [0u8; 100];
    let c = CentroidConfig::binary(10);
    assert_eq!(centroid_strided(&c, &f, 0, 5, 10), Err(FrameError::Empty));
    assert_eq!(
        centroid_strided(&c, &f, 10, 5, 9),
        Err(FrameError::Stride {
            stride: 9,
            width: 10
        })
    );
    assert_eq!(
        centroid_strided(&c, &f, 10, 11, 10),
        Err(FrameError::BufferTooShort {
            needed: 110,
            got: 100
        })
    );
    assert!(centroid_strided(&c, &f, 10, 10, 10).is_ok());
    assert!(matches!(
        centroid_strided(&c, &f, MAX_DIM + 1, 1, MAX_DIM + 1),
        Err(FrameError::TooLarge { .. })
    ));
    assert_eq!(
        centroid_strided(&c, &f, 10, usize::MAX, usize::MAX),
        Err(FrameError::TooLarge {
            width: 10,
            height: usize::MAX
        })
    );
    let c = config(10, Mode::Binary, roi(5, 0, 6, 5), None).unwrap();
    assert_eq!(
        centroid_strided(&c, &f, 10, 10, 10),
        Err(FrameError::RoiOutsideFrame)
    );
}

// ---------------------------------------------------------------------------------------------
// Multi-target

/// Naive connected components (8-connectivity) by flood fill over the whole region.
fn naive_components(
    px: &[u8],
    w: usize,
    h: usize,
    t: u8,
    mode: Mode,
    roi: Option<Roi>,
) -> Vec<(Moments, BoundingBox, Flags)> {
    let (rx0, ry0, rx1, ry1) = region(roi, w, h);
    let mut seen = vec![false; w * h];
    let mut out = Vec::new();
    for y0 in ry0..ry1 {
        for x0 in rx0..rx1 {
            if seen[y0 * w + x0] || px[y0 * w + x0] <= t {
                continue;
            }
            let mut m = Moments::default();
            let mut bb = BoundingBox {
                x_min: u32::MAX,
                y_min: u32::MAX,
                x_max: 0,
                y_max: 0,
            };
            let mut flags = Flags::NONE;
            let mut stack = vec![(x0, y0)];
            seen[y0 * w + x0] = true;
            while let Some((x, y)) = stack.pop() {
                let v = px[y * w + x];
                let wt = if mode == Mode::Binary {
                    1
                } else {
                    u64::from(v - t)
                };
                m.pixels += 1;
                m.weight += wt;
                m.sum_x += x as u64 * wt;
                m.sum_y += y as u64 * wt;
                bb.x_min = bb.x_min.min(x as u32);
                bb.x_max = bb.x_max.max(x as u32);
                bb.y_min = bb.y_min.min(y as u32);
                bb.y_max = bb.y_max.max(y as u32);
                if x == rx0 || x == rx1 - 1 || y == ry0 || y == ry1 - 1 {
                    flags |= Flags::BORDER;
                }
                if v == 255 {
                    flags |= Flags::SATURATED;
                }
                for ny in y.saturating_sub(1)..=(y + 1).min(ry1 - 1) {
                    for nx in x.saturating_sub(1)..=(x + 1).min(rx1 - 1) {
                        if ny >= ry0 && nx >= rx0 && !seen[ny * w + nx] && px[ny * w + nx] > t {
                            seen[ny * w + nx] = true;
                            stack.push((nx, ny));
                        }
                    }
                }
            }
            out.push((m, bb, flags));
        }
    }
    out.sort_by_key(|c| (c.1.y_min, c.1.x_min, c.0.sum_x));
    out
}

proptest! {
    #[test]
    fn multi_target_matches_flood_fill(
        (w, h, _s, px, roi) in frame_roi_strategy(255),
        t in 100u8..255,
        mode in mode_strategy(),
    ) {
        // frame_strategy's stride padding is dropped: use the first w * h values.
        let mut px: Vec<u8> = px.iter().map(|&v| v as u8).collect();
        px.resize(w * h, 0);
        let cfg = config(u16::from(t), mode, roi, None).unwrap();
        let mut m = MultiCentroider::<48, 1024>::try_new(cfg).unwrap();
        m.process(&Frame::new(&px, w, h, w).unwrap()).unwrap();
        let mut got: Vec<_> = m.targets().into_iter().map(|t| (t.centroid.moments, t.bbox, t.centroid.flags)).collect();
        got.sort_by_key(|c| (c.1.y_min, c.1.x_min, c.0.sum_x));
        let want = naive_components(&px, w, h, t, mode, roi);
        prop_assert_eq!(&got, &want);
        prop_assert_eq!(m.flags().contains(Flags::EMPTY), want.is_empty());
        for tg in m.targets() {
            let (cx, cy) = tg.centroid.position().unwrap();
            prop_assert!(within_ulp(cx, tg.centroid.moments.sum_x as f64 / tg.centroid.moments.weight as f64));
            prop_assert!(within_ulp(cy, tg.centroid.moments.sum_y as f64 / tg.centroid.moments.weight as f64));
        }
    }
}

#[test]
fn multi_target_merges_components_that_join_lower_down() {
    // A "W" whose three arms only join on the bottom row, plus a separate dot.
    let rows = [
        "#...#...#....",
        "#...#...#....",
        ".#..#..#...#.",
        "..#.#.#......",
        "...###.......",
        ".............",
    ];
    let (w, h) = (rows[0].len(), rows.len());
    let px: Vec<u8> = rows
        .iter()
        .flat_map(|r| r.bytes().map(|b| if b == b'#' { 200 } else { 0 }))
        .collect();
    let mut m = MultiCentroider::<16, 8>::try_new(CentroidConfig::binary(100)).unwrap();
    m.process(&Frame::new(&px, w, h, w).unwrap()).unwrap();
    let mut t: Vec<Target> = m.targets().into_iter().collect();
    t.sort_by_key(|t| t.bbox.x_min);
    assert_eq!(t.len(), 2);
    let arms = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| px[y * w + x] > 0 && (x, y) != (11, 2));
    let (n, sx, sy) = arms.fold((0, 0, 0), |(n, sx, sy), (x, y)| (n + 1, sx + x, sy + y));
    assert_eq!(t[0].centroid.moments.pixels, n as u64);
    assert_eq!(t[0].centroid.moments.sum_x, sx as u64);
    assert_eq!(t[0].centroid.moments.sum_y, sy as u64);
    assert_eq!(
        t[0].bbox,
        BoundingBox {
            x_min: 0,
            y_min: 0,
            x_max: 8,
            y_max: 4
        }
    );
    assert_eq!(t[0].centroid.flags, Flags::BORDER);
    assert_eq!(t[1].centroid.position(), Some((11.0, 2.0)));
    assert_eq!(t[1].centroid.flags, Flags::NONE);
    assert_eq!(m.flags(), Flags::BORDER);
}

#[test]
fn multi_target_forgets_labels_past_a_shorter_row() {
    // rows pushed one by one, the middle one shorter: the pixel below the short row's end
    // must not join the one above it (the labels past a row are cleared), and a narrow frame
    // in a wide capacity visits only its own columns
    let mut m = MultiCentroider::<64, 4>::try_new(CentroidConfig::binary(100)).unwrap();
    let mut long = [0u8; 10];
    long[8] = 200;
    m.push_row(&long[..]);
    m.push_row(&[0u8; 5][..]);
    m.push_row(&long[..]);
    let t = m.targets();
    assert_eq!(t.len(), 2, "{t:?}");
    assert!(t.iter().all(|t| t.centroid.moments.pixels == 1));
    // two adjacent rows of full width do join
    m.reset();
    m.push_row(&long[..]);
    m.push_row(&long[..]);
    assert_eq!(m.targets().len(), 1);
}

#[test]
fn multi_target_capacity_exceeded_is_flagged_and_goes_on() {
    // Four separate dots, capacity 2: two are kept, the others are dropped and counted.
    let f = frame_with(
        12,
        5,
        &[
            (1, 1, 200),
            (4, 1, 200),
            (7, 1, 200),
            (10, 3, 200),
            (10, 2, 200),
        ],
    );
    let mut m = MultiCentroider::<12, 2>::try_new(CentroidConfig::binary(100)).unwrap();
    m.process(&Frame::new(&f, 12, 5, 12).unwrap()).unwrap();
    assert_eq!(m.count(), 2);
    assert_eq!(m.dropped_pixels(), 3);
    assert!(m.flags().contains(Flags::CAPACITY));
    for t in m.targets() {
        assert!(t.centroid.flags.contains(Flags::CAPACITY));
    }
    // Enough capacity: no flag, every dot found; the same object is reused after process.
    let mut m = MultiCentroider::<12, 4>::try_new(CentroidConfig::binary(100)).unwrap();
    m.process(&Frame::new(&f, 12, 5, 12).unwrap()).unwrap();
    m.process(&Frame::new(&f, 12, 5, 12).unwrap()).unwrap();
    assert_eq!(m.count(), 4);
    assert_eq!(m.flags(), Flags::NONE);
    // Empty frame.
    m.process(&Frame::new(&[0u8; 60], 12, 5, 12).unwrap())
        .unwrap();
    assert_eq!(m.flags(), Flags::EMPTY);
}

/// Random frames with many components: the streaming labeller never panics and, when the
/// capacity suffices, finds as many components as the flood fill.
#[test]
fn multi_target_random_blobs_count() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..50 {
        let (w, h) = (64, 48);
        let px: Vec<u8> = (0..w * h)
            .map(|_| if rng.random::<f32>() < 0.3 { 200 } else { 0 })
            .collect();
        let want = naive_components(&px, w, h, 100, Mode::Binary, None).len();
        let mut big = MultiCentroider::<64, 2048>::try_new(CentroidConfig::binary(100)).unwrap();
        big.process(&Frame::new(&px, w, h, w).unwrap()).unwrap();
        assert_eq!(big.count(), want);
        let mut small = MultiCentroider::<64, 8>::try_new(CentroidConfig::binary(100)).unwrap();
        small.process(&Frame::new(&px, w, h, w).unwrap()).unwrap();
        assert!(small.count() <= 8);
        assert_eq!(
            small.flags().contains(Flags::CAPACITY),
            small.dropped_pixels() > 0
        );
    }
}

#[test]
fn streaming_state_is_constant_size() {
    // O(1) memory for one target: a few words, whatever the frame size.
    assert!(core::mem::size_of::<Centroider>() <= 96);
}

#[test]
fn multi_target_16_bit_streaming_equals_whole_frame() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let (w, h) = (50, 30);
    let px: Vec<u16> = (0..w * h)
        .map(|_| {
            if rng.random::<f32>() < 0.25 {
                rng.random_range(1000..=65535)
            } else {
                0
            }
        })
        .collect();
    let cfg = config(999, Mode::Weighted, Some(roi(3, 2, 40, 25)), Some(60000)).unwrap();
    let mut whole = MultiCentroider::<40, 512>::try_new(cfg).unwrap();
    whole.process(&Frame::new(&px, w, h, w).unwrap()).unwrap();
    let mut streamed = MultiCentroider::<40, 512>::try_new(cfg).unwrap();
    for row in px.chunks(w) {
        streamed.push_row(row);
    }
    let a: Vec<Target> = whole.targets().into_iter().collect();
    let b: Vec<Target> = streamed.targets().into_iter().collect();
    assert!(!a.is_empty());
    assert_eq!(a, b);
    // The components partition the pixels above the threshold: their moments add up to the
    // single-target moments of the same region.
    let single = centroid_strided(&cfg, &px, w, h, w).unwrap();
    let mut total = Moments::default();
    for t in &a {
        total.merge(&t.centroid.moments);
    }
    assert_eq!(total, single.moments);
    let any_sat = a
        .iter()
        .any(|t| t.centroid.flags.contains(Flags::SATURATED));
    assert_eq!(any_sat, single.flags.contains(Flags::SATURATED));
}
