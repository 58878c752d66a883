//! Coverage of `analyze`'s H1 intervals (docs/validation.md §3): rendered cantilever recordings
//! (the rig's nominal modes, the study's EPSA camera, 8-bit frames, optional read noise; the
//! first half of a run periodic over twice the span, so not itself periodic), each
//! analysed by the library's `analyze` chain with Welch segments, with and without the exposure
//! compensation; the truth is the rig's closed-form FRF at the picked line (times the box
//! exposure's transfer `sinc(pi f Te)` for the uncompensated vision system) and its modes'
//! damping ratios and frequencies.
//!
//! ```text
//! cargo run --release -p host-harness --example h1_coverage -- RUNS SECONDS NPERSEG EXPOSURE_MS \
//!     [weighted|binary] [READ_NOISE] [FIRST_SEED]
//! ```
//!
//! Prints, per system, mode and quantity: the fraction of 95 % intervals holding the truth, the
//! mean interval width over `2 x 1.96 x` the estimates' real spread (1 = as wide as needed), the
//! mean error of the interval's centre and the runs that gave an interval.

use host_harness::analysis::compensate::compensate;
use host_harness::analysis::frf_uncertainty::{of_analysis, FrfModeUncertainty};
use host_harness::analysis::{self, Axis, Settings, WelchSettings, Window};
use host_harness::chain::displacement::{displacement_mm, DisplacementSettings};
use host_harness::model;
use host_harness::recording::{camera_path, RecordingSpec};
use rand::SeedableRng as _;
use rand_distr::{Distribution as _, Normal};

/// One quantity's results over the runs: (estimate - truth, covered, interval width).
#[derive(Default)]
struct Tally {
    rows: Vec<(f64, bool, f64)>,
    missing: usize,
}

impl Tally {
    fn push(&mut self, est: Option<(f64, f64, f64)>, truth: f64) {
        match est {
            Some((x, lo, hi)) => self
                .rows
                .push((x - truth, lo <= truth && truth <= hi, hi - lo)),
            None => self.missing += 1,
        }
    }

    fn line(&self, what: &str, scale: f64) -> String {
        let n = self.rows.len();
        if n < 2 {
            return format!("{what:<34} no intervals ({} missing)", self.missing);
        }
        let cover = self.rows.iter().filter(|r| r.1).count() as f64 / n as f64;
        let mean = self.rows.iter().map(|r| r.0).sum::<f64>() / n as f64;
        let sd =
            (self.rows.iter().map(|r| (r.0 - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
        let width = self.rows.iter().map(|r| r.2).sum::<f64>() / n as f64;
        format!(
            "{what:<34} {:>5.1} %  width/needed {:>5.2}  mean error {:>+9.2e} ({:+.2} %)  n {n} (missing {})",
            100.0 * cover,
            width / (2.0 * 1.96 * sd),
            mean,
            100.0 * mean / scale,
            self.missing
        )
    }
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, d: &str| args.get(i).cloned().unwrap_or_else(|| d.to_string());
    let runs: u64 = arg(0, "20").parse()?;
    let seconds: usize = arg(1, "60").parse()?;
    let nperseg: usize = arg(2, "4096").parse()?;
    let exposure_ms: f64 = arg(3, "4").parse()?;
    let weighted = arg(4, "weighted") == "weighted";
    let read_noise: f64 = arg(5, "0").parse()?;
    let first: u64 = arg(6, "1").parse()?;
    let bands = vec![(5.0, 15.0), (25.0, 45.0)];
    // per system (acc, vis, vis compensated), mode, quantity (f, damping, amplitude)
    let mut t: Vec<Vec<[Tally; 3]>> = (0..3)
        .map(|_| (0..2).map(|_| Default::default()).collect())
        .collect();
    let mut segments = 0;
    // per mode, |H1| at the picked line over the closed form smoothed by the window's kernel
    let mut smoothed_ratio = [Vec::new(), Vec::new()];
    let kernel = host_harness::analysis::modal::Smoothing::welch(Window::Hann, nperseg, 2048.0);
    for seed in first..first + runs {
        let mut spec = RecordingSpec::cantilever(seed, exposure_ms);
        // a record periodic over twice the analysed span, of which the first half is analysed:
        // a periodic record's segments that tile its period average out much of the estimate's
        // random error, which a real record's do not
        spec.acquisition.frames = 2 * 120 * seconds;
        let run = model::simulate(&spec.rig, &spec.acquisition, seed)?;
        spec.acquisition.frames = 120 * seconds;
        let (path, mut renderer) = camera_path(&spec, &run);
        let (w, h) = (renderer.width(), renderer.height());
        let mut img = vec![0f32; w * h];
        let mut px = vec![0u8; w * h];
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
        let noise = Normal::new(0.0, read_noise.max(1e-12))?;
        let config = firmware_core::centroid::CentroidConfig {
            mode: if weighted {
                firmware_core::centroid::Mode::Weighted
            } else {
                firmware_core::centroid::Mode::Binary
            },
            ..firmware_core::centroid::CentroidConfig::binary(spec.threshold)
        };
        let mut centroids = Vec::with_capacity(spec.acquisition.frames);
        for k in 0..spec.acquisition.frames {
            let (a, b) = path.frame_window(k, spec.exposure_ms);
            renderer.render_float(a, b, &mut img);
            for (p, v) in px.iter_mut().zip(&img) {
                let n = if read_noise > 0.0 {
                    noise.sample(&mut rng)
                } else {
                    0.0
                };
                *p = (f64::from(*v) + n).round().clamp(0.0, 255.0) as u8;
            }
            let frame = firmware_core::centroid::Frame::new(&px, w, h, w)
                .map_err(|e| anyhow::anyhow!("{e:?}"))?;
            centroids.push(
                firmware_core::centroid::centroid(&config, &frame)
                    .map_err(|e| anyhow::anyhow!("{e:?}"))?,
            );
        }
        let disp = displacement_mm(
            &centroids,
            &DisplacementSettings {
                mm_per_px: spec.mm_per_px,
                axis: Axis::Y,
                invert: false,
                lost_frames: Default::default(),
            },
        )?;
        let settings = Settings {
            frame_rate_hz: spec.acquisition.fps,
            accel_rate_hz: spec.acquisition.fs,
            time_offset_s: 0.0,
            welch: WelchSettings {
                window: Window::Hann,
                nperseg: Some(nperseg),
                noverlap: std::env::var("NOVERLAP").ok().and_then(|v| v.parse().ok()),
                nfft: None,
                detrend: Default::default(),
            },
            bands: bands.clone(),
            exposure_s: Some(exposure_ms / 1000.0),
            end_match: false,
        };
        let samples = spec.acquisition.samples();
        let records = (&run.input[..samples], &run.tip_acc[..samples]);
        let a = analysis::analyze(&disp, records.0, records.1, &settings)?;
        let plain = of_analysis(&a, records, None, 10)?;
        let mut ac = a.clone();
        compensate(&mut ac, exposure_ms / 1000.0, &bands, !weighted)?;
        let comp = of_analysis(&ac, records, Some(exposure_ms / 1000.0), 10)?;
        segments = plain.segments;
        let te = exposure_ms / 1000.0;
        let sinc = |f: f64| {
            let x = std::f64::consts::PI * f * te;
            if x == 0.0 {
                1.0
            } else {
                x.sin() / x
            }
        };
        let freqs = spec.natural_frequencies();
        let damping: Vec<f64> = match &spec.rig {
            model::Rig::Cantilever(r) => r.modes.iter().map(|m| m.zeta).collect(),
            model::Rig::Grandstand(_) => unreachable!(),
        };
        let systems: [(&[analysis::PickedMode], &[FrfModeUncertainty], bool); 3] = [
            (&a.acc_modes, &plain.acc, false),
            (&a.vis_modes, &plain.vis, true),
            (&ac.vis_modes, &comp.vis, false),
        ];
        for (i, m) in a.acc_modes.iter().enumerate() {
            let expected = kernel.apply(|f| spec.frf(f), m.f_hz).norm();
            smoothed_ratio[i].push(m.amplitude / expected);
        }
        for (s, (modes, unc, blurred)) in systems.iter().enumerate() {
            for (i, (m, u)) in modes.iter().zip(unc.iter()).enumerate() {
                let cell =
                    |x: f64, i: Option<host_harness::analysis::oma::uncertainty::Interval>| {
                        i.map(|i| (x, i.lo, i.hi))
                    };
                let truth_a = spec.frf(m.f_hz).norm() * if *blurred { sinc(m.f_hz) } else { 1.0 };
                t[s][i][0].push(cell(m.f_hz, u.f_hz), freqs[i]);
                t[s][i][1].push(u.damping_fit.and_then(|z| cell(z, u.damping)), damping[i]);
                // the amplitude's interval is centred on the fit's FRF at the line
                t[s][i][2].push(
                    u.amplitude.map(|a| ((a.lo + a.hi) / 2.0, a.lo, a.hi)),
                    truth_a,
                );
            }
        }
        eprint!("\rrun {}/{runs}", seed - first + 1);
    }
    eprintln!();
    println!(
        "{runs} rendered cantilever records of {seconds} s, {} centroid, exposure {exposure_ms} \
         ms, read noise {read_noise}, Hann nperseg {nperseg} ({segments} segments), 10 groups",
        if weighted { "weighted" } else { "binary" }
    );
    for (i, r) in smoothed_ratio.iter().enumerate() {
        let n = r.len() as f64;
        let mean = r.iter().sum::<f64>() / n;
        let sd = (r.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        println!(
            "accelerometer mode {}: |H1| / |K * T| at the picked line {mean:.4} +- {:.4} (sd {sd:.4})",
            i + 1,
            sd / n.sqrt()
        );
    }
    let names = ["accelerometer", "vision", "vision compensated"];
    let scales = [[7.1, 0.0115, 68.0], [32.4, 0.011, 39.4]];
    for (s, name) in names.iter().enumerate() {
        for i in 0..2 {
            for (q, what) in ["f", "damping", "|FRF|"].iter().enumerate() {
                println!(
                    "{}",
                    t[s][i][q].line(&format!("{name} mode {} {what}", i + 1), scales[i][q])
                );
            }
        }
    }
    Ok(())
}
