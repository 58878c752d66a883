//! Nanoseconds per frame of the two imaging paths on the grandstand study's own frames:
//!
//! * reference: EPSA render (`BlurRenderer::render`, 8-bit) + `firmware_core` binary centroid;
//! * fast: `host_harness::imaging::fastpath::FastDiskCamera::frame` (only the rows the centroid needs).
//!
//! Times are CPU time of the thread (10 ms ticks). Both see the same runs (seed 1, runs 0, 1, ...), the study's 8 exposures (40 ... 180 ms)
//! and 5000 frames each, and every centroid is compared.
//!
//! ```sh
//! cargo run --release -p host-harness --example imaging_paths [RUNS] [misaligned]
//! ```
use firmware_core::centroid::{centroid, CentroidConfig, Frame};
use host_harness::imaging::fastpath::FastDiskCamera;
use host_harness::imaging::{BlurRenderer, DiskTarget};
use host_harness::model::grandstand::{simulate, FINE, FS_HZ, N, PX_PER_MM, THRESHOLD};
use host_harness::study::{run_rng, Grandstand, Preset, StudyConfig};

fn main() {
    let runs: u64 = std::env::args()
        .nth(1)
        .map(|a| a.parse().expect("RUNS must be a number"))
        .unwrap_or(2);
    // the study's target and exposures (Grandstand::new, method.md §3.1)
    let target = DiskTarget {
        radius_px: 12.0,
        level: 200.0,
        edge_sigma_px: 1.5,
        texture: host_harness::model::Texture::Plain,
    };
    let exposures_ms: Vec<f64> = (0..8).map(|i| 40.0 + 20.0 * i as f64).collect();
    // the study's ramp block and rest padding before t = 0 (a whole number of blocks, so every
    // exposure window covers whole blocks); with `misaligned`, the padding before model
    // revision 5 (half the longest exposure and one step: windows start and end mid-block)
    let scenario = Grandstand::new(&StudyConfig::preset(Preset::Grandstand)).expect("preset");
    let (mut pad, block) = (scenario.padding(), scenario.block());
    let dt_ms = 1000.0 / (FS_HZ * FINE as f64);
    if std::env::args().nth(2).as_deref() == Some("misaligned") {
        pad = (180.0 / 2.0 / dt_ms) as usize + 1;
    }
    let config = CentroidConfig::binary(THRESHOLD);

    let (mut t_ref, mut t_fast, mut t_ramp) = (0.0f64, 0.0f64, 0.0f64);
    let (mut frames, mut identical, mut worst) = (0u64, 0u64, 0.0f32);
    let (mut evaluated, mut rendered, mut columns) = (0u64, 0u64, 0u64);
    for run in 0..runs {
        let mut rng = run_rng(1, run);
        let r = simulate(&mut rng, false, pad);
        let path: Vec<f64> = r
            .fine_disp_m
            .iter()
            .map(|x| -x * 1000.0 * PX_PER_MM)
            .collect();
        let mut renderer = BlurRenderer::for_path(&target, &path, block);
        let (w, h) = (renderer.width(), renderer.height());
        let started = std::time::Instant::now();
        let mut fast = FastDiskCamera::new(&target, &renderer, THRESHOLD);
        let setup = started.elapsed().as_secs_f64();
        t_fast += setup;
        let mut img = vec![0u8; w * h];
        let mut want = vec![Default::default(); N];
        let mut got = vec![Default::default(); N];
        for &e in &exposures_ms {
            let half = e / 2.0 / dt_ms;
            let window = |i: usize| {
                let c = (r.pad + i * FINE) as f64;
                (c - half, c + half)
            };
            let started = host_harness::testing::thread_cpu_seconds();
            for (i, out) in want.iter_mut().enumerate() {
                let (a, b) = window(i);
                renderer.render(a, b, &mut img);
                *out = Frame::new(&img, w, h, w)
                    .and_then(|f| centroid(&config, &f))
                    .expect("frame shape");
            }
            t_ref += host_harness::testing::thread_cpu_seconds() - started;
            let started = host_harness::testing::thread_cpu_seconds();
            for (i, out) in got.iter_mut().enumerate() {
                let (a, b) = window(i);
                *out = fast.frame(&mut renderer, a, b).expect("frame shape");
            }
            t_fast += host_harness::testing::thread_cpu_seconds() - started;
            // the part of the fast path spent in the renderer's averaged ramp and path range
            let started = host_harness::testing::thread_cpu_seconds();
            for i in 0..N {
                let (a, b) = window(i);
                std::hint::black_box(renderer.path_range(a, b));
                std::hint::black_box(renderer.exposure_ramp(a, b));
            }
            t_ramp += host_harness::testing::thread_cpu_seconds() - started;
            for (g, w) in got.iter().zip(&want) {
                frames += 1;
                if g == w {
                    identical += 1;
                }
                worst = worst.max((g.cy - w.cy).abs());
            }
        }
        evaluated += fast.stats().evaluated;
        rendered += fast.stats().rendered;
        columns += fast.stats().columns_fft;
        println!(
            "run {run}: frame {w} x {h} px, path range {:.1} px, fast-path setup {:.0} us",
            path.iter().cloned().fold(f64::MIN, f64::max)
                - path.iter().cloned().fold(f64::MAX, f64::min),
            setup * 1e6
        );
    }
    let ns = |t: f64| t * 1e9 / frames as f64;
    println!(
        "{frames} frames ({runs} runs x {} exposures x {N}), pad {pad} fine steps",
        exposures_ms.len()
    );
    println!(
        "reference (EPSA render + quantise + centroid): {:>7.0} ns/frame",
        ns(t_ref)
    );
    println!(
        "fast path (FastDiskCamera::frame)            : {:>7.0} ns/frame",
        ns(t_fast)
    );
    println!(
        "  of which averaged ramp + path range         : {:>7.0} ns/frame",
        ns(t_ramp)
    );
    println!(
        "speed-up {:.1}x; identical centroids in {identical} of {frames} frames, largest |d cy| {worst:e} px",
        t_ref / t_fast
    );
    println!(
        "per frame: {:.2} rows evaluated one by one, {:.3} columns by inverse FFT; {rendered} frames rendered (outside the domain)",
        evaluated as f64 / frames as f64,
        columns as f64 / frames as f64
    );
}
