//! The complete vision channel on the host (`pipeline::VisionH1<121, 2816, 2048, 150>`, the
//! mcu-demo's configuration): one second of data, 120 frames and 2048 ADC samples pushed
//! interleaved as they arrive, i.e. two overlapped blocks upsampled to acceleration and two
//! 2048-point segments accumulated in steady state. Also prints the state size quoted in the
//! README.
//!
//! `cargo bench -p firmware-core --bench pipeline`

use criterion::{criterion_group, criterion_main, Criterion};
use firmware_core::pipeline::{scratch_capacity, PipelineConfig, VisionH1};
use std::hint::black_box;

const SC: usize = scratch_capacity(120, 2048, 2048);
type Demo = VisionH1<121, 2816, 2048, SC>;

/// One second of frames (mm) and ADC samples (m/s^2), two tones.
fn second() -> (Vec<f32>, Vec<f32>) {
    let tau = std::f32::consts::TAU;
    let frames = (0..120)
        .map(|j| (tau * 7.0 * j as f32 / 120.0).sin())
        .collect();
    let adc = (0..2048)
        .map(|i| -1e-3 * (tau * 7.0).powi(2) * (tau * 7.0 * i as f32 / 2048.0).sin())
        .collect();
    (frames, adc)
}

fn push_second(p: &mut Demo, frames: &[f32], adc: &[f32]) {
    let mut next = 0;
    for (j, v) in frames.iter().enumerate() {
        p.push_frame(*v).expect("frame accepted");
        let until = (j + 1) * 2048 / 120;
        p.push_adc(&adc[next..until])
            .expect("ADC within the headroom");
        next = until;
    }
}

fn benches(c: &mut Criterion) {
    println!(
        "size_of VisionH1<121, 2816, 2048, {SC}>: {} bytes",
        core::mem::size_of::<Demo>()
    );
    let (frames, adc) = second();
    let mut p = Box::new(
        Demo::try_new(PipelineConfig::one_second_blocks(120, 2048, Some(1e-3)))
            .expect("valid settings"),
    );
    // steady state: two seconds in, so every further second cuts two segments
    push_second(&mut p, &frames, &adc);
    push_second(&mut p, &frames, &adc);
    c.bench_function("pipeline/one second (120 frames + 2048 ADC samples)", |b| {
        b.iter(|| push_second(&mut p, black_box(&frames), black_box(&adc)))
    });
}

criterion_group!(pipeline, benches);
criterion_main!(pipeline);
