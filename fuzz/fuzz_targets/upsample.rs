//! Fourier upsampling and the fused acceleration conversion: random lengths and values must
//! never panic; wrong buffer lengths are errors, not panics.
#![no_main]
use firmware_core::upsample::Upsampler;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if data.len() < 4 {
        return;
    }
    let (head, body) = data.split_at(4);
    let values: Vec<f32> = body
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let n = values.len().clamp(1, 128);
    let m = (n + head[0] as usize % 256).min(512);
    let Ok(mut up) = Upsampler::<512, 512>::try_new(n, m) else {
        return;
    };
    let mut input = values;
    input.resize(n, 0.0);
    let mut out = vec![0.0f32; m];
    let _ = up.process(&input, &mut out);
    let _ = up.process_acceleration(&input, &mut out, 100.0, 1e-3);
    // a mismatched output length is refused
    let mut short = vec![0.0f32; m.saturating_sub(1 + head[1] as usize % 3)];
    assert!(short.len() == m || up.process(&input, &mut short).is_err());
});
