//! Streaming Welch H1: random configurations, chunk sizes and values (NaN, infinities, huge
//! values included) must never panic; every estimate is finite or absent.
#![no_main]
use firmware_core::spectrum::{Detrend, WelchConfig, WelchH1, Window};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if data.len() < 8 {
        return;
    }
    let (head, body) = data.split_at(8);
    let nperseg = 1 + head[0] as usize % 64;
    let noverlap = head[1] as usize % nperseg;
    let nfft = nperseg + head[2] as usize % (65 - nperseg);
    let window = [Window::Hann, Window::Hamming, Window::Rect][head[3] as usize % 3];
    let detrend = if head[4] & 1 == 0 {
        Detrend::Constant
    } else {
        Detrend::None
    };
    let config = WelchConfig {
        fs_hz: 100.0,
        nperseg,
        noverlap,
        nfft,
        window,
        detrend,
    };
    let Ok(mut welch) = WelchH1::<64, 64, 0>::try_new(config) else {
        return;
    };
    let values: Vec<f32> = body
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let half = values.len() / 2;
    let (x, y) = values.split_at(half);
    let chunk = 1 + head[5] as usize % 17;
    for (cx, cy) in x.chunks(chunk).zip(y[..half].chunks(chunk)) {
        let _ = welch.push(cx, cy);
    }
    for k in 0..=nfft / 2 {
        if let Some(h) = welch.accumulator().h1(k) {
            assert!(h.re.is_finite() && h.im.is_finite(), "bin {k}: {h:?}");
        }
    }
});
