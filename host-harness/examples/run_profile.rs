//! Where a grandstand run's time goes, stage by stage, in CPU time of one thread (10 ms ticks):
//! the stages of `Grandstand::run` redone with the same public functions (simulation, Welch
//! H1s, renderer, imaging by either path, lost-frame filling), then `Grandstand::run` itself and
//! the checkpoint line of its record, for comparison.
//!
//! ```sh
//! cargo run --release -p host-harness --example run_profile [RUNS]
//! ```
use firmware_core::centroid::{centroid, CentroidConfig, Frame};
use firmware_core::spectrum::{scratch_capacity, WelchH1};
use host_harness::chain::displacement::fill_lost_frames;
use host_harness::chain::frf::measure as measure_system;
use host_harness::imaging::fastpath::FastDiskCamera;
use host_harness::imaging::BlurRenderer;
use host_harness::model::grandstand::{
    simulate, BANDS, FINE, FS_HZ, N, NFFT, NPERSEG, PX_PER_MM, TARGET, THRESHOLD, WELCH,
};
use host_harness::study::Grandstand;
use host_harness::study::{run_rng, Scenario, StudyConfig};

type Welch = WelchH1<NPERSEG, NFFT, { scratch_capacity(NFFT) }>;

#[derive(Default)]
struct Split {
    simulate: f64,
    welch_transducer: f64,
    renderer: f64,
    fast_setup: f64,
    imaging_ref: f64,
    imaging_fast: f64,
    fill: f64,
    welch_vision: f64,
    run_total: f64,
    checkpoint: f64,
}

fn main() {
    let runs: u64 = std::env::args()
        .nth(1)
        .map(|a| a.parse().expect("RUNS must be a number"))
        .unwrap_or(3);
    let cfg = StudyConfig::preset(host_harness::study::Preset::Grandstand);
    let scenario = Grandstand::new(&cfg).expect("preset is valid");
    let target = TARGET;
    let dt_ms = 1000.0 / (FS_HZ * FINE as f64);
    let (pad, block) = (scenario.padding(), scenario.block());
    let bands = BANDS;
    let keep = (5.0 * NFFT as f64 / FS_HZ) as usize + 1;
    let mut welch = Box::new(Welch::try_new(WELCH).expect("valid Welch settings"));
    let config = CentroidConfig::binary(THRESHOLD);
    let mut s = Split::default();
    let t = |f: &mut dyn FnMut(), acc: &mut f64| {
        let started = host_harness::testing::thread_cpu_seconds();
        f();
        *acc += host_harness::testing::thread_cpu_seconds() - started;
    };
    for run in 0..runs {
        let mut rng = run_rng(1, run);
        let mut r = None;
        t(
            &mut || r = Some(simulate(&mut rng, false, pad)),
            &mut s.simulate,
        );
        let r = r.expect("simulated");
        t(
            &mut || {
                measure_system(
                    &mut welch,
                    &r.force_meas_kn,
                    &r.disp_meas_mm,
                    &bands,
                    keep,
                    1.0,
                )
                .expect("Welch");
            },
            &mut s.welch_transducer,
        );
        let path: Vec<f64> = r
            .fine_disp_m
            .iter()
            .map(|x| -x * 1000.0 * PX_PER_MM)
            .collect();
        let mut renderer = None;
        t(
            &mut || renderer = Some(BlurRenderer::for_path(&target, &path, block)),
            &mut s.renderer,
        );
        let mut renderer = renderer.expect("renderer");
        let mut fast = None;
        t(
            &mut || fast = Some(FastDiskCamera::new(&target, &renderer, THRESHOLD)),
            &mut s.fast_setup,
        );
        let mut fast = fast.expect("fast camera");
        let (w, h) = (renderer.width(), renderer.height());
        let mut img = vec![0u8; w * h];
        let (mut disp, mut valid) = (vec![0.0f64; N], vec![false; N]);
        let rest_y = renderer.rest_y();
        for &e in &cfg.exposures_ms {
            let half = e / 2.0 / dt_ms;
            let window = |i: usize| {
                let c = (r.pad + i * FINE) as f64;
                (c - half, c + half)
            };
            t(
                &mut || {
                    for i in 0..N {
                        let (a, b) = window(i);
                        renderer.render(a, b, &mut img);
                        let c = Frame::new(&img, w, h, w)
                            .and_then(|f| centroid(&config, &f))
                            .expect("frame");
                        std::hint::black_box(c);
                    }
                },
                &mut s.imaging_ref,
            );
            t(
                &mut || {
                    for i in 0..N {
                        let (a, b) = window(i);
                        let c = fast.frame(&mut renderer, a, b).expect("frame");
                        match c.position() {
                            Some((_, cy)) => {
                                disp[i] = -(cy as f64 - rest_y) / PX_PER_MM;
                                valid[i] = true;
                            }
                            None => valid[i] = false,
                        }
                    }
                },
                &mut s.imaging_fast,
            );
            let mut d32 = Vec::new();
            t(
                &mut || {
                    fill_lost_frames(&mut disp, &valid);
                    d32 = disp.iter().map(|v| *v as f32).collect();
                },
                &mut s.fill,
            );
            t(
                &mut || {
                    measure_system(&mut welch, &r.force_meas_kn, &d32, &bands, keep, 1.0)
                        .expect("Welch");
                },
                &mut s.welch_vision,
            );
        }
        let mut rng = run_rng(1, run);
        let mut rec = None;
        t(
            &mut || rec = Some(scenario.run(run, &mut rng).expect("run")),
            &mut s.run_total,
        );
        let rec = rec.expect("record");
        t(
            &mut || {
                std::hint::black_box(serde_json::to_string(&rec).expect("json"));
            },
            &mut s.checkpoint,
        );
    }
    let frames = (runs as usize * cfg.exposures_ms.len() * N) as f64;
    let ns = |v: f64| v * 1e9 / frames;
    println!(
        "{runs} runs x {} exposures x {N} frames; ns per frame (one core):",
        cfg.exposures_ms.len()
    );
    let rows = [
        (
            "simulate (modes, excitation, ZOH response, transducer noise)",
            s.simulate,
        ),
        ("Welch H1, transducer (1 per run)", s.welch_transducer),
        (
            "BlurRenderer::for_path (column spectra, ramp blocks)",
            s.renderer,
        ),
        ("FastDiskCamera::new", s.fast_setup),
        (
            "imaging, reference (render + quantise + centroid)",
            s.imaging_ref,
        ),
        ("imaging, fast path", s.imaging_fast),
        ("lost-frame fill + f32 copy", s.fill),
        ("Welch H1, vision (1 per exposure)", s.welch_vision),
    ];
    for (name, v) in rows {
        println!("  {name:<64} {:>7.0}", ns(v));
    }
    let rest = s.simulate + s.welch_transducer + s.renderer + s.fill + s.welch_vision;
    println!(
        "  {:<64} {:>7.0}",
        "total with the reference imaging (sum of stages)",
        ns(rest + s.imaging_ref)
    );
    println!(
        "  {:<64} {:>7.0}",
        "total with the fast path (sum of stages)",
        ns(rest + s.fast_setup + s.imaging_fast)
    );
    println!(
        "  {:<64} {:>7.0}",
        "Grandstand::run as the study calls it",
        ns(s.run_total)
    );
    println!(
        "  {:<64} {:>7.1}",
        "checkpoint line (serde_json of the run record)",
        ns(s.checkpoint)
    );
}
