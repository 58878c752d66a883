//! `render` without `--recording`: what the camera of a preset sees at chosen instants, sharp
//! and blurred, as PNG frames.

use super::{camera_path, save_grey_png, RecordingSpec};
use crate::imaging::{BlurRenderer, DiskTarget, TargetPath};
use crate::study::{run_rng, Preset};
use std::path::{Path, PathBuf};
use vibcam_model::{self as model, grandstand};
use vibcam_readers::bad_input;
use vibcam_report::outdir::Staged;

/// What the camera of a preset looks at: the target and its path.
#[derive(Debug)]
pub struct Scene {
    /// The target.
    target: DiskTarget,
    /// Its motion; fine step `pad` is t = 0.
    path: TargetPath,
    /// Frame times, s: `--times` or the preset's default instants.
    times: Vec<f64>,
}

impl Scene {
    /// The scene of `preset`'s run 0 of `seed` at `times` (s; default: a few instants of the
    /// response).
    pub fn of(
        preset: Preset,
        seed: u64,
        times: Option<Vec<f64>>,
        exposure_ms: f64,
    ) -> anyhow::Result<Scene> {
        match preset {
            Preset::Grandstand => Ok(grandstand_scene(seed, times, exposure_ms)),
            Preset::Cantilever => cantilever_scene(seed, times, exposure_ms),
        }
    }

    /// Writes the sharp and the blurred frame at each time into the new directory `out`
    /// (`frame_tT_sharp.png`, `frame_tT_expEms.png`; staged and moved into place, `force`
    /// replacing an earlier `render` output there); returns their final paths.
    pub fn write_frames(
        &self,
        out: &Path,
        force: bool,
        exposure_ms: f64,
    ) -> anyhow::Result<Vec<PathBuf>> {
        let staged = Staged::new(out, force, "render", &[])?;
        let written = write_frames(staged.dir(), self, exposure_ms)?;
        staged.commit()?;
        Ok(written
            .iter()
            .map(|p| out.join(p.file_name().unwrap_or_default()))
            .collect())
    }
}

/// See [`Scene::write_frames`].
fn write_frames(out: &Path, scene: &Scene, exposure_ms: f64) -> anyhow::Result<Vec<PathBuf>> {
    let Scene {
        target,
        path,
        times,
    } = scene;
    let mut r = BlurRenderer::for_path(target, &path.path_px, 1);
    let (w, h) = (r.width(), r.height());
    let mut frame = vec![0u8; w * h];
    let n = path.path_px.len();
    let span = (n - 2 * path.pad) as f64 / path.fine_hz;
    let mut written = Vec::new();
    for &t in times {
        let c = path.pad as f64 + t * path.fine_hz;
        let (a, b) = path.window(c, exposure_ms);
        if !(t.is_finite() && a >= 0.0 && b <= (n - 1) as f64) {
            return Err(bad_input(format!(
                "$times: {t} s is outside the simulated record (0 .. {span:.1} s) with this \
                 exposure"
            )));
        }
        for (label, a, b) in [
            ("sharp".to_string(), c, c),
            (format!("exp{exposure_ms}ms"), a, b),
        ] {
            r.render(a, b, &mut frame);
            let p = out.join(format!("frame_t{t}_{label}.png"));
            save_grey_png(&p, (w, h), &frame)?;
            written.push(p);
        }
    }
    Ok(written)
}

/// The grandstand of run 0 of `--seed`, as the study simulates it.
fn grandstand_scene(seed: u64, times: Option<Vec<f64>>, exposure_ms: f64) -> Scene {
    let fine_hz = grandstand::FS_HZ * grandstand::FINE as f64;
    let pad = TargetPath::pad_for(exposure_ms, fine_hz);
    let mut rng = run_rng(seed, 0);
    let sim = grandstand::simulate(&mut rng, false, pad);
    Scene {
        target: grandstand::TARGET,
        path: TargetPath {
            path_px: sim
                .fine_disp_m
                .iter()
                .map(|x| -x * 1000.0 * grandstand::PX_PER_MM)
                .collect(),
            pad,
            fine_per_frame: grandstand::FINE,
            fine_hz,
        },
        times: times.unwrap_or_else(|| vec![33.2, 33.4, 33.6, 34.0]),
    }
}

/// The nominal cantilever, as a synthetic recording simulates it.
fn cantilever_scene(seed: u64, times: Option<Vec<f64>>, exposure_ms: f64) -> anyhow::Result<Scene> {
    let spec = RecordingSpec::cantilever(seed, exposure_ms);
    let sim = model::simulate(&spec.rig, &spec.acquisition, spec.seed)?;
    let (path, _) = camera_path(&spec, &sim);
    Ok(Scene {
        target: spec.target,
        path,
        times: times.unwrap_or_else(|| vec![1.0, 1.01, 1.02]),
    })
}
