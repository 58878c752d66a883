//! Fourier upsampling on the host: 1200 -> 20480 (10 s at 120 fps to 2048 Hz, the cantilever
//! record) and 120 -> 2048 (one second), plain and fused with -omega^2. Also prints the state
//! sizes (`core::mem::size_of`) quoted in the README.
//!
//! `cargo bench -p firmware-core --bench upsample`

use criterion::{criterion_group, criterion_main, Criterion};
use firmware_core::upsample::{scratch_capacity, Upsampler};
use std::hint::black_box;

fn signal(n: usize) -> Vec<f32> {
    (0..n)
        .map(|i| (0.05 * i as f32).sin() + 0.3 * (0.71 * i as f32).cos())
        .collect()
}

fn case<const M: usize, const S: usize>(c: &mut Criterion, n: usize, m: usize) {
    println!(
        "size_of Upsampler<{M}, {S}> ({n} -> {m}): {} bytes",
        core::mem::size_of::<Upsampler<M, S>>()
    );
    let x = signal(n);
    let mut y = vec![0.0f32; m];
    let mut up = Box::new(Upsampler::<M, S>::try_new(n, m).expect("valid lengths"));
    let mut g = c.benchmark_group("upsample");
    g.bench_function(format!("{n}->{m}"), |b| {
        b.iter(|| up.process(black_box(&x), &mut y).expect("lengths"))
    });
    g.bench_function(format!("{n}->{m} fused -omega^2"), |b| {
        b.iter(|| {
            up.process_acceleration(black_box(&x), &mut y, 120.0, 1e-3)
                .expect("lengths")
        })
    });
    g.finish();
}

fn benches(c: &mut Criterion) {
    case::<20480, { scratch_capacity(1200, 20480) }>(c, 1200, 20480);
    case::<2048, { scratch_capacity(120, 2048) }>(c, 120, 2048);
}

criterion_group!(upsample, benches);
criterion_main!(upsample);
