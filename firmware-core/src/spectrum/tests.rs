//! Tests of the Welch estimator against a naive f64 reference, scipy's conventions and its
//! edge cases.

use super::*;
use crate::dft::DftError;
use crate::{BufferError, Complex32};
use proptest::prelude::*;
use std::vec::Vec;

/// Capacities for every test length (an odd length n <= 128 needs at most 3n scratch).
type W = WelchH1<64, 128, 384>;

fn cfg(nperseg: usize, noverlap: usize, nfft: usize, window: Window) -> WelchConfig {
    WelchConfig {
        fs_hz: 100.0,
        nperseg,
        noverlap,
        nfft,
        window,
        detrend: Detrend::Constant,
    }
}

/// Deterministic pseudo-random samples in [-0.5, 0.5) (LCG).
fn noise(n: usize, seed: u64) -> Vec<f32> {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 40) as f32 / (1u64 << 24) as f32) - 0.5
        })
        .collect()
}

/// y = x through a resonant two-pole filter plus a little independent noise.
fn system(n: usize, seed: u64) -> (Vec<f32>, Vec<f32>) {
    let x = noise(n, seed);
    let e = noise(n, seed + 1);
    let (mut y1, mut y2) = (0.0f32, 0.0f32);
    let y = x
        .iter()
        .zip(&e)
        .map(|(&xi, &ei)| {
            let v = xi + 1.6 * y1 - 0.8 * y2;
            y2 = y1;
            y1 = v;
            v + 0.2 * ei
        })
        .collect();
    (x, y)
}

fn all_bits<const S: usize, const N: usize, const C: usize>(w: &WelchH1<S, N, C>) -> Vec<u32> {
    (0..w.accumulator().bins())
        .flat_map(|k| {
            let s = w.accumulator().sums(k).unwrap();
            [
                s.pxx.to_bits(),
                s.pyy.to_bits(),
                s.pxy.re.to_bits(),
                s.pxy.im.to_bits(),
            ]
        })
        .collect()
}

/// Naive f64 reference: direct DFT per segment, separate for x and y.
fn reference(x: &[f32], y: &[f32], c: &WelchConfig) -> Vec<(f64, f64, (f64, f64))> {
    let bins = c.nfft / 2 + 1;
    let mut acc = vec![(0.0, 0.0, (0.0, 0.0)); bins];
    let step = c.nperseg - c.noverlap;
    let mut start = 0;
    while start + c.nperseg <= x.len() {
        let seg = |s: &[f32]| -> Vec<f64> {
            let s = &s[start..start + c.nperseg];
            let m = if c.detrend == Detrend::Constant {
                s.iter().map(|&v| v as f64).sum::<f64>() / s.len() as f64
            } else {
                0.0
            };
            s.iter()
                .enumerate()
                .map(|(j, &v)| {
                    let ph = 2.0 * std::f64::consts::PI * j as f64 / c.nperseg as f64;
                    let w = match c.window {
                        Window::Hann => 0.5 - 0.5 * ph.cos(),
                        Window::Hamming => 0.54 - 0.46 * ph.cos(),
                        Window::Rect => 1.0,
                    };
                    (v as f64 - m) * w
                })
                .collect()
        };
        let (xs, ys) = (seg(x), seg(y));
        for (k, a) in acc.iter_mut().enumerate() {
            let dft = |s: &[f64]| {
                s.iter().enumerate().fold((0.0, 0.0), |(re, im), (j, &v)| {
                    let ph =
                        -2.0 * std::f64::consts::PI * ((j * k) % c.nfft) as f64 / c.nfft as f64;
                    (re + v * ph.cos(), im + v * ph.sin())
                })
            };
            let (xr, xi) = dft(&xs);
            let (yr, yi) = dft(&ys);
            a.0 += xr * xr + xi * xi;
            a.1 += yr * yr + yi * yi;
            a.2 .0 += xr * yr + xi * yi;
            a.2 .1 += xr * yi - xi * yr;
        }
        start += step;
    }
    acc
}

#[test]
fn matches_naive_f64_reference() {
    let (x, y) = system(700, 3);
    for (c, shift) in [
        (cfg(64, 32, 64, Window::Hann), 0.0),
        (cfg(50, 10, 96, Window::Hamming), 3.0),
        (cfg(37, 0, 37, Window::Rect), 0.0),
        (
            WelchConfig {
                detrend: Detrend::None,
                ..cfg(60, 45, 75, Window::Hann)
            },
            0.25,
        ),
    ] {
        let xo: Vec<f32> = x.iter().map(|v| v + shift).collect();
        let mut w = W::try_new(c).unwrap();
        w.push(&xo, &y).unwrap();
        let want = reference(&xo, &y, &c);
        assert_eq!(w.accumulator().segments() as usize, c.segments_in(x.len()));
        let maxx = want.iter().map(|a| a.0).fold(0.0, f64::max);
        let maxy = want.iter().map(|a| a.1).fold(0.0, f64::max);
        for (k, r) in want.iter().enumerate() {
            let s = w.accumulator().sums(k).unwrap();
            // errors relative to the largest bin (DFT rounding is relative to the energy)
            assert!((s.pxx as f64 - r.0).abs() < 1e-5 * maxx, "{c:?} bin {k}");
            assert!((s.pyy as f64 - r.1).abs() < 1e-5 * maxy, "{c:?} bin {k}");
            let m = (maxx * maxy).sqrt();
            assert!((s.pxy.re as f64 - r.2 .0).abs() < 1e-5 * m, "{c:?} bin {k}");
            assert!((s.pxy.im as f64 - r.2 .1).abs() < 1e-5 * m, "{c:?} bin {k}");
            let h = w.accumulator().h1(k).unwrap();
            let hr = (r.2 .0 / r.0, r.2 .1 / r.0);
            let habs = (hr.0 * hr.0 + hr.1 * hr.1).sqrt();
            let coh = (r.2 .0 * r.2 .0 + r.2 .1 * r.2 .1) / (r.0 * r.1);
            if coh > 0.1 {
                let e = ((h.re as f64 - hr.0).powi(2) + (h.im as f64 - hr.1).powi(2)).sqrt();
                assert!(e < 1e-4 * habs, "{c:?} bin {k}: {h} vs {hr:?}");
                assert!((w.accumulator().coherence(k).unwrap() as f64 - coh).abs() < 1e-4);
            }
        }
    }
}

#[test]
fn identity_and_gain() {
    let (x, _) = system(1000, 9);
    for window in [Window::Hann, Window::Hamming, Window::Rect] {
        for gain in [1.0f32, 2.0, -0.5] {
            let y: Vec<f32> = x.iter().map(|v| gain * v).collect();
            let mut w = W::try_new(cfg(64, 16, 96, window)).unwrap();
            w.push(&x, &y).unwrap();
            for k in 0..w.accumulator().bins() {
                let h = w.accumulator().h1(k).unwrap();
                assert!(
                    (h.re - gain).abs() <= 4.0 * f32::EPSILON * gain.abs()
                        && h.im.abs() <= 4.0 * f32::EPSILON,
                    "{window:?} gain {gain} bin {k}: {h}"
                );
                let c = w.accumulator().coherence(k).unwrap();
                assert!((c - 1.0).abs() <= 4.0 * f32::EPSILON, "bin {k}: {c}");
            }
        }
    }
}

#[test]
fn very_different_channel_scales() {
    // force in newtons, displacement in metres: the shared transform must not drown y
    let (x, y) = system(700, 5);
    let xs: Vec<f32> = x.iter().map(|v| v * 1000.0).collect();
    let ys: Vec<f32> = y.iter().map(|v| v * 1e-6).collect();
    let c = cfg(64, 32, 64, Window::Hann);
    let mut a = W::try_new(c).unwrap();
    let mut b = W::try_new(c).unwrap();
    a.push(&x, &y).unwrap();
    b.push(&xs, &ys).unwrap();
    for k in 0..a.accumulator().bins() {
        let (ha, hb) = (
            a.accumulator().h1(k).unwrap(),
            b.accumulator().h1(k).unwrap() * 1e9,
        );
        assert!(
            (ha - hb).norm_sqr() <= 1e-10 * ha.norm_sqr(),
            "bin {k}: {ha} {hb}"
        );
    }
}

#[test]
fn not_available_before_first_segment_and_zero_input() {
    let c = cfg(64, 32, 64, Window::Hann);
    let mut w = W::try_new(c).unwrap();
    assert_eq!(w.accumulator().h1(0), None);
    assert_eq!(w.accumulator().coherence(3), None);
    let mut out = [Complex32::new(9.0, 9.0); 40];
    assert_eq!(
        w.accumulator().fill_h1(&mut out),
        Err(WelchError::NoSegments)
    );
    w.push(&[1.0; 63], &[1.0; 63]).unwrap();
    assert_eq!((w.accumulator().segments(), w.pending()), (0, 63));
    assert_eq!(w.accumulator().h1(1), None);
    // a constant removed by the detrend leaves Pxx == 0 everywhere: H1 = 0, coherence 0
    w.push(&[1.0], &[1.0]).unwrap();
    assert_eq!((w.accumulator().segments(), w.pending()), (1, 32));
    for k in 0..w.accumulator().bins() {
        assert_eq!(w.accumulator().h1(k), Some(Complex32::new(0.0, 0.0)));
        assert_eq!(w.accumulator().coherence(k), Some(0.0));
    }
    assert_eq!(w.accumulator().h1(w.accumulator().bins()), None);
    assert_eq!(w.accumulator().fill_h1(&mut out), Ok(33));
    assert!(out[..33].iter().all(|v| *v == Complex32::new(0.0, 0.0)));
    assert_eq!(out[33], Complex32::new(9.0, 9.0));
    let mut coh = [5.0f32; 10];
    assert_eq!(w.accumulator().fill_coherence(&mut coh), Ok(10));
    assert!(coh.iter().all(|v| *v == 0.0));
    let dbg = std::format!("{w:?}");
    assert!(dbg.starts_with("WelchH1 {") && dbg.contains("segments: 1") && dbg.len() < 400);
    w.reset();
    assert_eq!(
        (
            w.accumulator().segments(),
            w.pending(),
            w.accumulator().h1(0)
        ),
        (0, 0, None)
    );
}

#[test]
fn non_finite_and_huge_segments_are_skipped() {
    let (x, y) = system(64 * 4, 2);
    let c = cfg(64, 0, 64, Window::Hann);
    let mut clean = W::try_new(c).unwrap();
    clean.push(&x[..64], &y[..64]).unwrap();
    clean.push(&x[192..], &y[192..]).unwrap();
    let mut w = W::try_new(c).unwrap();
    let mut xb = x.clone();
    let mut yb = y.clone();
    xb[70] = f32::NAN;
    yb[150] = 2.0e9;
    w.push(&xb, &yb).unwrap();
    assert_eq!(
        (
            w.accumulator().segments(),
            w.accumulator().skipped_segments()
        ),
        (2, 2)
    );
    assert_eq!(all_bits(&w), all_bits(&clean));
    for k in 0..w.accumulator().bins() {
        assert!(
            w.accumulator().h1(k).unwrap().re.is_finite()
                && w.accumulator().coherence(k).unwrap().is_finite()
        );
    }
}

#[test]
fn rejects_invalid_configs() {
    let ok = cfg(64, 32, 96, Window::Hann);
    assert!(W::try_new(ok).is_ok());
    for fs in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        let e = W::try_new(WelchConfig { fs_hz: fs, ..ok }).unwrap_err();
        assert_eq!(e, ConfigError::SampleRate);
    }
    // the capacities of `W`: 64-sample segments, 128-point transforms
    let segment = |nperseg| ConfigError::SegmentLength {
        nperseg,
        capacity: 64,
    };
    let overlap = ConfigError::Overlap {
        noverlap: 64,
        nperseg: 64,
    };
    let fft = ConfigError::FftLength {
        nfft: 63,
        nperseg: 64,
        capacity: 128,
    };
    for (bad, want) in [
        (WelchConfig { nperseg: 0, ..ok }, segment(0)),
        (WelchConfig { nperseg: 65, ..ok }, segment(65)),
        (WelchConfig { noverlap: 64, ..ok }, overlap),
        (WelchConfig { nfft: 63, ..ok }, fft),
    ] {
        assert_eq!(W::try_new(bad).unwrap_err(), want, "{bad:?}");
    }
    let e = W::try_new(WelchConfig { nfft: 129, ..ok }).unwrap_err();
    assert!(matches!(e, ConfigError::FftLength { nfft: 129, .. }));
    // 120 = 8 * 15 needs more scratch than scratch_capacity(96) = 96 + 2 * 3 = 102
    let e = WelchH1::<64, 128, { scratch_capacity(96) }>::try_new(WelchConfig { nfft: 120, ..ok })
        .unwrap_err();
    assert_eq!(
        e,
        ConfigError::Scratch {
            needed: 150,
            capacity: 102
        }
    );
    assert!(WelchH1::<64, 128, { scratch_capacity(96) }>::try_new(ok).is_ok());
    // a large prime is not supported by the DFT
    let e = WelchH1::<4, 40000, 0>::try_new(WelchConfig {
        nperseg: 4,
        noverlap: 0,
        nfft: 32771,
        ..ok
    })
    .unwrap_err();
    assert_eq!(e, ConfigError::Dft(DftError::Unsupported { len: 32771 }));
    // configure rejects without touching the state
    let mut w = W::try_new(ok).unwrap();
    w.push(&[0.5; 70], &[0.25; 70]).unwrap();
    assert!(w.configure(WelchConfig { noverlap: 99, ..ok }).is_err());
    assert_eq!(
        (w.accumulator().config(), w.accumulator().segments()),
        (&ok, 1)
    );
    let new = cfg(32, 0, 32, Window::Rect);
    w.configure(new).unwrap();
    assert_eq!(
        (
            w.accumulator().config(),
            w.accumulator().segments(),
            w.accumulator().bins()
        ),
        (&new, 0, 17)
    );
    // unequal chunks consume nothing
    assert_eq!(
        w.push(&[1.0; 3], &[1.0; 2]),
        Err(WelchError::ChunkLengths { x: 3, y: 2 })
    );
    assert_eq!(w.pending(), 0);
    // every error has a message
    assert!(std::format!("{e}").contains("32771"));
}

#[test]
fn windows_are_periodic_like_scipy() {
    // scipy.signal.get_window('hann', 4) = [0, 0.5, 1, 0.5]; ('hamming', 4) = [0.08, 0.54, 1, 0.54]
    let h: Vec<f32> = (0..4).map(|n| Window::Hann.value(n, 4)).collect();
    assert_eq!(h, [0.0, 0.5, 1.0, 0.5]);
    let h: Vec<f32> = (0..4).map(|n| Window::Hamming.value(n, 4)).collect();
    let want = [0.08f32, 0.54, 1.0, 0.54];
    for (a, b) in h.iter().zip(want) {
        assert!((a - b).abs() < 1e-7);
    }
    assert_eq!(Window::Rect.value(3, 4), 1.0);
}

#[test]
fn bins_and_frequencies() {
    let c = WelchConfig {
        fs_hz: 50.0,
        ..cfg(1111, 555, 5000, Window::Hamming)
    };
    assert_eq!(c.bins(), 2501);
    // 100 s at 50 Hz: scipy averages 7 complete segments (the 8th would end at sample 5003)
    assert_eq!(c.segments_in(5000), 7);
    assert_eq!(c.segments_in(1110), 0);
    let w = WelchH1::<1111, 5000, { scratch_capacity(5000) }>::try_new(c).unwrap();
    assert!((w.accumulator().freq(200) - 2.0).abs() < 1e-6);
    assert!((w.accumulator().freq(2500) - 25.0).abs() < 1e-5);
    let odd = cfg(5, 2, 7, Window::Hann);
    assert_eq!(odd.bins(), 4);
    let d = WelchConfig::scipy_default(10.0, 100);
    assert_eq!((d.nperseg, d.noverlap, d.nfft), (100, 50, 100));
    let d = WelchConfig::scipy_default(10.0, 1000);
    assert_eq!((d.nperseg, d.noverlap, d.nfft), (256, 128, 256));
}

#[test]
fn odd_nfft_and_tiny_lengths() {
    // odd nfft (no Nyquist bin) and nfft 1 and 2 against the naive reference
    let (x, y) = system(60, 4);
    for c in [
        cfg(5, 2, 7, Window::Hann),
        cfg(1, 0, 1, Window::Rect),
        cfg(2, 1, 2, Window::Rect),
        WelchConfig {
            detrend: Detrend::None,
            ..cfg(1, 0, 2, Window::Rect)
        },
    ] {
        let mut w = W::try_new(c).unwrap();
        w.push(&x, &y).unwrap();
        let want = reference(&x, &y, &c);
        assert_eq!(want.len(), w.accumulator().bins());
        for (k, r) in want.iter().enumerate() {
            let s = w.accumulator().sums(k).unwrap();
            let tol = 1e-5 * (1.0 + r.0 + r.1);
            assert!((s.pxx as f64 - r.0).abs() < tol, "{c:?} {k}");
            assert!((s.pyy as f64 - r.1).abs() < tol, "{c:?} {k}");
            assert!((s.pxy.re as f64 - r.2 .0).abs() < tol, "{c:?} {k}");
            assert!((s.pxy.im as f64 - r.2 .1).abs() < tol, "{c:?} {k}");
        }
    }
}

#[test]
fn accumulator_with_caller_buffers_matches_the_streaming_estimator_bit_for_bit() {
    let c = cfg(100, 40, 128, Window::Hann);
    let (x, y) = system(700, 3);
    let mut w = WelchH1::<100, 128, 0>::try_new(c).unwrap();
    w.push(&x, &y).unwrap();
    let mut acc = WelchAccumulator::<128>::try_new(c).unwrap();
    let mut work = vec![Complex32::new(0.0, 0.0); 200];
    let mut start = 0;
    while start + 100 <= x.len() {
        let seg = start..start + 100;
        let ok = acc.add_segment(&x[seg.clone()], &y[seg], &mut work, &mut []);
        assert_eq!(ok, Ok(true));
        start += 60;
    }
    assert_eq!(acc.segments(), w.accumulator().segments());
    assert_eq!(all_bits(&w), {
        let mut v = Vec::new();
        for k in 0..acc.bins() {
            let s = acc.sums(k).unwrap();
            v.extend([
                s.pxx.to_bits(),
                s.pyy.to_bits(),
                s.pxy.re.to_bits(),
                s.pxy.im.to_bits(),
            ]);
        }
        v
    });
    // wrong buffers are errors and accumulate nothing
    let before = acc.segments();
    assert_eq!(
        acc.add_segment(&x[..99], &y[..100], &mut work, &mut []),
        Err(WelchError::Buffer(BufferError {
            expected: 100,
            got: 99
        }))
    );
    assert_eq!(
        acc.add_segment(&x[..100], &y[..100], &mut work[..127], &mut []),
        Err(WelchError::Buffer(BufferError {
            expected: 128,
            got: 127
        }))
    );
    let mut odd = WelchAccumulator::<120>::try_new(cfg(100, 40, 120, Window::Hann)).unwrap();
    assert!(odd.scratch_len() > 0);
    assert!(matches!(
        odd.add_segment(&x[..100], &y[..100], &mut work, &mut []),
        Err(WelchError::Buffer(BufferError { .. }))
    ));
    let mut scratch = vec![Complex32::new(0.0, 0.0); odd.scratch_len()];
    assert_eq!(
        odd.add_segment(&x[..100], &y[..100], &mut work, &mut scratch),
        Ok(true)
    );
    // a non-finite sample skips the segment
    let mut bad = x[..100].to_vec();
    bad[7] = f32::NAN;
    assert_eq!(
        acc.add_segment(&bad, &y[..100], &mut work, &mut []),
        Ok(false)
    );
    assert_eq!((acc.segments(), acc.skipped_segments()), (before, 1));
}

#[test]
fn f32_window_values_agree_with_the_f64_ones() {
    for len in [1usize, 2, 7, 100, 1111, 2048, 4096] {
        for n in 0..len {
            for w in [Window::Hann, Window::Hamming, Window::Rect] {
                let (a, b) = (w.value(n, len), w.value_f32(n, len));
                assert!((a - b).abs() < 2e-7, "{w:?} {n}/{len}: {a} vs {b}");
            }
        }
    }
}

#[test]
fn state_size_is_the_documented_budget() {
    // 2 SEG f32 (two segments; the window is computed, not stored) + NFFT complex (work)
    // + 2 NFFT f32 (accumulators) + SCRATCH complex + a few words of settings and
    // counters. This is the RAM an MCU needs for the estimator (README "Signal path
    // figures").
    fn check<const S: usize, const N: usize, const C: usize>() -> usize {
        let size = core::mem::size_of::<WelchH1<S, N, C>>();
        let buffers = 8 * S + 16 * N + 8 * C;
        assert!(
            size >= buffers && size <= buffers + 128,
            "WelchH1<{S}, {N}, {C}>: {size} bytes, buffers {buffers}"
        );
        std::println!("size_of WelchH1<{S}, {N}, {C}> = {size} bytes");
        size
    }
    assert!(check::<2048, 2048, 0>() < 49 * 1024);
    assert!(check::<4096, 4096, 0>() < 97 * 1024);
    // the accumulator alone: 2 NFFT f32
    let acc = core::mem::size_of::<WelchAccumulator<2048>>();
    assert!((8 * 2048..8 * 2048 + 128).contains(&acc), "{acc}");
    check::<1111, 5000, { scratch_capacity(5000) }>();
    check::<20480, 20480, { scratch_capacity(20480) }>();
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn chunking_does_not_change_a_bit(
        seed in 0u64..1000,
        len in 0usize..400,
        nperseg in 1usize..=64,
        ov in 0.0f64..1.0,
        pad in 0usize..=32,
        cuts in proptest::collection::vec(0usize..80, 0..20),
    ) {
        let noverlap = ((nperseg as f64 * ov) as usize).min(nperseg - 1);
        let c = cfg(nperseg, noverlap, nperseg + pad, Window::Hamming);
        prop_assume!(W::try_new(c).is_ok());
        let (x, y) = system(len, seed);
        let mut once = W::try_new(c).unwrap();
        once.push(&x, &y).unwrap();
        let mut single = W::try_new(c).unwrap();
        for i in 0..len {
            single.push(&x[i..i + 1], &y[i..i + 1]).unwrap();
        }
        let mut chunked = W::try_new(c).unwrap();
        let mut at = 0usize;
        for cut in cuts.iter().chain(std::iter::once(&usize::MAX)) {
            let end = at.saturating_add(*cut).min(len);
            chunked.push(&x[at..end], &y[at..end]).unwrap();
            at = end;
        }
        prop_assert_eq!(once.accumulator().segments() as usize, c.segments_in(len));
        prop_assert_eq!(single.accumulator().segments(), once.accumulator().segments());
        prop_assert_eq!(chunked.accumulator().segments(), once.accumulator().segments());
        prop_assert_eq!(all_bits(&single), all_bits(&once));
        prop_assert_eq!(all_bits(&chunked), all_bits(&once));
    }
}
