//! Host throughput of the single-target centroiding (Mpixel/s = criterion's Melem/s).
//!
//! `cargo bench -p firmware-core --bench centroid`
//!
//! * a 640 x 480 8-bit frame with one bright disk (radius 40 px, level 200 on background 10,
//!   threshold 100), whole-frame path, binary and weighted;
//! * the binary 8-bit row kernel alone on the same frame's rows;
//! * the Monte Carlo study's frame size (40 x 200, 8-bit), whole-frame binary;
//! * a 640 x 480 16-bit frame, binary and weighted;
//! * the multi-target labeller on the 640 x 480 frame (for comparison; scalar code).

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use firmware_core::centroid::{
    centroid, row_binary_u8, CentroidConfig, Frame, Mode, MultiCentroider,
};

#[path = "../src/test_support.rs"]
mod test_support;

/// The benchmark disk: level 200 on a background of 10.
fn disk(w: usize, h: usize, cx: f64, cy: f64, r: f64) -> Vec<u8> {
    test_support::disk(w, h, (cx, cy), r, 10, 200)
}

fn bench(c: &mut Criterion) {
    let (w, h) = (640, 480);
    let frame = disk(w, h, 321.3, 239.7, 40.0);
    let frame16: Vec<u16> = frame.iter().map(|&v| u16::from(v) * 257).collect();
    let mut g = c.benchmark_group("centroid_640x480");
    g.throughput(Throughput::Elements((w * h) as u64));
    let view = Frame::new(&frame, w, h, w).unwrap();
    let view16 = Frame::new(&frame16, w, h, w).unwrap();
    for mode in [Mode::Binary, Mode::Weighted] {
        let cfg = CentroidConfig {
            mode,
            ..CentroidConfig::binary(100)
        };
        g.bench_function(format!("u8_{mode:?}").to_lowercase(), |b| {
            b.iter(|| centroid(black_box(&cfg), black_box(&view)))
        });
        let cfg16 = CentroidConfig {
            mode,
            ..CentroidConfig::binary(100 * 257)
        };
        g.bench_function(format!("u16_{mode:?}").to_lowercase(), |b| {
            b.iter(|| centroid(black_box(&cfg16), black_box(&view16)))
        });
    }
    g.bench_function("row_binary_u8_kernel", |b| {
        b.iter(|| {
            let mut n = 0u32;
            for row in black_box(&frame).chunks_exact(w) {
                n = n.wrapping_add(row_binary_u8(row, black_box(100)).pixels);
            }
            n
        })
    });
    g.bench_function("multi_target_u8_binary", |b| {
        let mut m = MultiCentroider::<640, 16>::try_new(CentroidConfig::binary(100)).unwrap();
        b.iter(|| {
            m.process(black_box(&view)).unwrap();
            m.count()
        })
    });
    g.finish();

    let (w, h) = (40, 200);
    let small = disk(w, h, 19.6, 101.2, 12.0);
    let mut g = c.benchmark_group("centroid_40x200");
    g.throughput(Throughput::Elements((w * h) as u64));
    let cfg = CentroidConfig::binary(100);
    let small = Frame::new(&small, w, h, w).unwrap();
    g.bench_function("u8_binary", |b| {
        b.iter(|| centroid(black_box(&cfg), black_box(&small)))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
