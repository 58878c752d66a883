//! `host-harness render`: what the camera saw. PNG frames of the simulated target at chosen
//! times, sharp and blurred, or (`--recording DIR`) a complete synthetic recording (frames +
//! accelerometer CSV) that `host-harness analyze` can read.

use crate::bad_input;
use crate::study::render::{BlurRenderer, DiskTarget};
use crate::study::{grandstand, run_rng, Preset};
use anyhow::Context as _;
use std::path::{Path, PathBuf};

/// Arguments of `host-harness render`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scenario whose camera is rendered.
    #[arg(long, value_enum, default_value = "grandstand")]
    pub preset: Preset,
    /// Seed of the simulated run (the study's run 0 of this seed).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Exposure time of the blurred frames, ms (centred on the frame time).
    #[arg(long, default_value_t = 100.0)]
    pub exposure_ms: f64,
    /// Frame times in seconds, comma separated (default: a few instants of the response).
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub times: Option<Vec<f64>>,
    /// Output directory of the PNG frames.
    #[arg(long, default_value = "out/render")]
    pub out: PathBuf,
    /// Instead of single frames, write a complete synthetic recording (frames/, accel.csv,
    /// recording.toml, README.txt with the `analyze` command) into this directory.
    #[arg(long, value_name = "DIR")]
    pub recording: Option<PathBuf>,
}

/// Runs `host-harness render`.
pub fn run(args: Args) -> anyhow::Result<()> {
    if !(args.exposure_ms.is_finite() && args.exposure_ms >= 0.0) {
        return Err(bad_input(format!(
            "--exposure-ms {}: must be a non-negative number",
            args.exposure_ms
        )));
    }
    if let Some(dir) = &args.recording {
        let files = crate::recording::write_synthetic_recording(
            args.preset,
            args.seed,
            args.exposure_ms,
            dir,
        )?;
        println!(
            "wrote a synthetic {} recording in {} ({files:?}); see {}",
            match args.preset {
                Preset::Grandstand => "grandstand",
                Preset::Cantilever => "cantilever",
            },
            dir.display(),
            dir.join("README.txt").display()
        );
        return Ok(());
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let scene = match args.preset {
        Preset::Grandstand => grandstand_scene(&args),
        Preset::Cantilever => cantilever_scene(&args)?,
    };
    let written = write_frames(&args.out, &scene, args.exposure_ms)?;
    for p in &written {
        println!("{}", p.display());
    }
    eprintln!("wrote {} frames in {}", written.len(), args.out.display());
    Ok(())
}

/// What the camera of a preset looks at.
#[derive(Debug)]
struct Scene {
    /// The target.
    target: DiskTarget,
    /// Displacement path, px (positive down), on the fine time base of rate `fine_hz` whose
    /// index 0 is at time `-pad / fine_hz`.
    path_px: Vec<f64>,
    /// Fine steps of path before t = 0 (and at least as many after the record).
    pad: usize,
    /// Rate of the fine time base, Hz.
    fine_hz: f64,
    /// Frame times, s: `--times` or the preset's default instants.
    times: Vec<f64>,
}

/// Fine steps of path needed either side of a frame for the exposure window, plus a margin.
fn pad_for(exposure_ms: f64, fine_hz: f64) -> usize {
    (exposure_ms / 2000.0 * fine_hz).ceil() as usize + 2
}

/// Writes the sharp and the blurred frame at each time of `scene.times`.
fn write_frames(out: &Path, scene: &Scene, exposure_ms: f64) -> anyhow::Result<Vec<PathBuf>> {
    let Scene {
        target,
        path_px,
        pad,
        fine_hz,
        times,
    } = scene;
    let (pad, fine_hz) = (*pad, *fine_hz);
    let mut r = BlurRenderer::for_path(target, path_px, 1);
    let (w, h) = (r.width(), r.height());
    let mut frame = vec![0u8; w * h];
    let half = exposure_ms / 2000.0 * fine_hz;
    let span = path_px.len() as f64 / fine_hz;
    let mut written = Vec::new();
    for &t in times {
        let c = pad as f64 + t * fine_hz;
        if !(t.is_finite() && c - half >= 0.0 && c + half <= (path_px.len() - 1) as f64) {
            return Err(bad_input(format!(
                "--times: {t} s is outside the simulated record (0 .. {:.1} s) with this exposure",
                span - 2.0 * pad as f64 / fine_hz
            )));
        }
        for (label, a, b) in [
            ("sharp".to_string(), c, c),
            (format!("exp{exposure_ms}ms"), c - half, c + half),
        ] {
            r.render(a, b, &mut frame);
            let p = out.join(format!("frame_t{t}_{label}.png"));
            image::GrayImage::from_raw(w as u32, h as u32, frame.clone())
                .context("frame buffer size")?
                .save(&p)
                .with_context(|| format!("cannot write {}", p.display()))?;
            written.push(p);
        }
    }
    Ok(written)
}

fn grandstand_scene(args: &Args) -> Scene {
    let fine_hz = grandstand::FS_HZ * grandstand::FINE as f64;
    let pad = pad_for(args.exposure_ms, fine_hz);
    let mut rng = run_rng(args.seed, 0);
    let sim = grandstand::simulate(&mut rng, false, pad);
    Scene {
        target: DiskTarget {
            radius_px: 12.0,
            level: 200.0,
            edge_sigma_px: 1.5,
        },
        path_px: sim
            .fine_disp_m
            .iter()
            .map(|x| -x * 1000.0 * grandstand::PX_PER_MM)
            .collect(),
        pad,
        fine_hz,
        times: args
            .times
            .clone()
            .unwrap_or_else(|| vec![33.2, 33.4, 33.6, 34.0]),
    }
}

fn cantilever_scene(args: &Args) -> anyhow::Result<Scene> {
    let spec = crate::recording::RecordingSpec::cantilever(args.seed, 0.0);
    let sim = crate::recording::simulate(&spec)?;
    let fine_hz = spec.fps * sim.fine_per_frame as f64;
    let pad = pad_for(args.exposure_ms, fine_hz);
    let n = sim.tip_mm.len();
    Ok(Scene {
        target: DiskTarget {
            radius_px: 10.0,
            level: 255.0,
            edge_sigma_px: 0.5,
        },
        path_px: (0..n + 2 * pad)
            .map(|i| -sim.tip_mm[(i + n - pad) % n] / spec.mm_per_px)
            .collect(),
        pad,
        fine_hz,
        times: args.times.clone().unwrap_or_else(|| vec![1.0, 1.01, 1.02]),
    })
}
