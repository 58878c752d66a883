//! Streaming Welch H1 on the host: time to push one segment pair (one DFT of `x + i y` and the
//! accumulation of Pxx, Pyy, Pxy).
//!
//! `cargo bench -p firmware-core --bench welch`; the figures are quoted in the README
//! ("Signal path figures"). Each iteration pushes exactly `nperseg - noverlap` new samples of
//! both channels, i.e. completes one segment.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use firmware_core::spectrum::{scratch_capacity, Detrend, WelchConfig, WelchH1, Window};
use std::hint::black_box;

fn noise(n: usize, seed: u64) -> Vec<f32> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 40) as f32 / (1u64 << 24) as f32 - 0.5
        })
        .collect()
}

fn bench_case<const S: usize, const N: usize, const C: usize>(
    c: &mut Criterion,
    name: &str,
    config: WelchConfig,
) {
    let step = config.nperseg - config.noverlap;
    let x = noise(step, 1);
    let y = noise(step, 2);
    let mut w = Box::new(WelchH1::<S, N, C>::try_new(config).expect("valid config"));
    // fill the overlap once, so every measured push completes exactly one segment
    let pre = noise(config.noverlap, 3);
    w.push(&pre, &pre).expect("equal lengths");
    let mut g = c.benchmark_group("welch");
    g.throughput(Throughput::Elements(step as u64));
    g.bench_function(name, |b| {
        b.iter(|| {
            w.push(black_box(&x), black_box(&y)).expect("equal lengths");
        })
    });
    g.finish();
    eprintln!(
        "{name}: size_of WelchH1<{S}, {N}, {C}> = {} bytes",
        std::mem::size_of::<WelchH1<S, N, C>>()
    );
}

fn welch(c: &mut Criterion) {
    bench_case::<2048, 2048, 0>(
        c,
        "segment_2048_hann",
        WelchConfig {
            fs_hz: 2048.0,
            nperseg: 2048,
            noverlap: 0,
            nfft: 2048,
            window: Window::Hann,
            detrend: Detrend::Constant,
        },
    );
    bench_case::<1111, 5000, { scratch_capacity(5000) }>(
        c,
        "segment_grandstand_1111_555_5000_hamming",
        WelchConfig {
            fs_hz: 50.0,
            nperseg: 1111,
            noverlap: 555,
            nfft: 5000,
            window: Window::Hamming,
            detrend: Detrend::Constant,
        },
    );
    bench_case::<20480, 20480, { scratch_capacity(20480) }>(
        c,
        "segment_cantilever_20480_hann",
        WelchConfig {
            fs_hz: 2048.0,
            nperseg: 20480,
            noverlap: 0,
            nfft: 20480,
            window: Window::Hann,
            detrend: Detrend::Constant,
        },
    );
}

criterion_group!(benches, welch);
criterion_main!(benches);
