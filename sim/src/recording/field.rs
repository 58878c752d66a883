//! Rendered field recordings (`simulate-field --render`): the ambient motion of
//! [`vibcam_model::field`]'s points filmed by the studies' camera, so that the output-only
//! analysis can be run through the whole chain (frames, `analyze --targets K` without
//! `--accel`) on motion whose modes are known.
//!
//! Point `j` of `K` is a white disk (the cantilever rig's target) in its own column strip of
//! the frame, left to right, moving vertically (up for a positive displacement, the `--axis y`
//! convention of `analyze`) by the model's displacement at the point, scaled so that the point
//! that moves most has an RMS displacement of `rms_px`. The motion is simulated 16 steps per
//! frame and integrated exactly over each exposure (centred on the frame's instant) by the EPSA
//! renderer; read noise is added before 8-bit rounding.
//!
//! Written beside the frames: `displacement.csv` (the exact exposure-averaged displacement of
//! every target, px, positive up: what a perfect tracker would measure, for `modal`),
//! `truth.csv` (the modes), `points.csv` (a window per target for `--points`) and `README.txt`
//! with the `analyze` command.

use super::{FrameSink, SinkCamera};
use crate::imaging::{BlurRenderer, TargetPath};
use std::path::Path;
use vibcam_model::cantilever;
use vibcam_model::field::{self, FieldModel, SUB};
use vibcam_report::export::field::{self as export, TrueMode};

/// A rendered field recording.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldRecording {
    /// The structure and its points (one target per point).
    pub model: FieldModel,
    /// Frame rate, fps.
    pub fps: f64,
    /// Number of frames.
    pub frames: usize,
    /// Seed of the forces (and, on a stream of its own, of the read noise).
    pub seed: u64,
    /// Exposure, ms (centred on the frame's instant), `0 <= exposure < 1000 / fps`.
    pub exposure_ms: f64,
    /// Read noise, grey levels.
    pub read_noise: f64,
    /// RMS displacement of the point that moves most, px.
    pub rms_px: f64,
    /// Also write `frames.mkv` (FFV1, lossless).
    pub video: bool,
    /// A camera that shakes or looks at an angle, with static references
    /// ([`super::camera_view`]); `None`: each target in its own strip, square to the camera.
    pub view: Option<super::camera_view::CameraView>,
}

impl FieldRecording {
    /// `N frames at F fps, exposure E ms, read noise R grey levels, seed S` (the READMEs').
    pub fn camera_words(&self) -> String {
        format!(
            "{} frames at {} fps, exposure {} ms, read noise {} grey levels, seed {}",
            self.frames, self.fps, self.exposure_ms, self.read_noise, self.seed
        )
    }

    /// Refuses an exposure of a frame period or more, an RMS motion outside (0, 20] px, read
    /// noise outside 0-64 grey levels and fewer than 2 frames, naming the setting.
    pub fn validate(&self) -> anyhow::Result<()> {
        let period_ms = 1000.0 / self.fps;
        if !(self.exposure_ms >= 0.0 && self.exposure_ms < period_ms) {
            return Err(vibcam_readers::bad_input(format!(
                "$exposure_ms {}: must be >= 0 and shorter than the frame period ({period_ms} \
                 ms)",
                self.exposure_ms
            )));
        }
        if !(self.rms_px.is_finite() && self.rms_px > 0.0 && self.rms_px <= 20.0) {
            return Err(vibcam_readers::bad_input(format!(
                "$rms_px {}: must be in (0, 20]",
                self.rms_px
            )));
        }
        if !(self.read_noise.is_finite() && (0.0..=64.0).contains(&self.read_noise)) {
            return Err(vibcam_readers::bad_input(format!(
                "$read_noise {}: must be between 0 and 64 grey levels",
                self.read_noise
            )));
        }
        if self.frames < 2 {
            return Err(vibcam_readers::bad_input(format!(
                "{} frames: a recording needs at least 2",
                self.frames
            )));
        }
        Ok(())
    }
}

/// Writes the recording into `out` (staged: complete or absent; `force` replaces an earlier
/// output of `simulate-field`), reporting progress to `progress(frames done)`; returns a short
/// report naming the `analyze` command.
pub fn write_field_recording(
    rec: &FieldRecording,
    out: &Path,
    force: bool,
    mut progress: impl FnMut(usize),
) -> anyhow::Result<String> {
    rec.validate()?;
    if let Some(v) = &rec.view {
        v.validate(rec.fps)?;
    }
    let staged = vibcam_report::outdir::Staged::new(out, force, "simulate-field", &[])?;
    if let Some(v) = &rec.view {
        return write_view(rec, v, staged, out, progress);
    }
    let paths = scaled_paths(rec);
    let target = cantilever::TARGET;
    let mut renderers = strip_renderers(&paths, &target);
    let k = paths.len();
    let (sw, h) = (renderers[0].width(), renderers[0].height());
    let w = sw * k;
    let camera = camera_of(rec);
    let mut sink = FrameSink::open(&camera, (staged.dir(), out), (w, h))?;
    let (mut strip, mut frame) = (vec![0f32; sw * h], vec![0f32; w * h]);
    let mut seen = vec![Vec::with_capacity(rec.frames); k];
    let mut first = Vec::new();
    for n in 0..rec.frames {
        for (t, (r, p)) in renderers.iter_mut().zip(&paths).enumerate() {
            let (a, b) = p.frame_window(n, rec.exposure_ms);
            seen[t].push(-p.mean_px((a, b)));
            r.render_float(a, b, &mut strip);
            for (row, src) in frame.chunks_exact_mut(w).zip(strip.chunks_exact(sw)) {
                row[t * sw..(t + 1) * sw].copy_from_slice(src);
            }
        }
        if n == 0 {
            let half = target.level as f32 / 2.0;
            first = (0..k)
                .map(|t| super::targets::strip_centroid(&frame, w, (t * sw, sw), half))
                .collect();
        }
        sink.put(n, &frame)?;
        progress(n + 1);
    }
    sink.finish()?;
    staged.write("displacement.csv", export::displacement_csv(&seen, rec.fps))?;
    staged.write("truth.csv", export::truth_csv(&true_modes(&rec.model)))?;
    let window = ((sw - 2) | 1, (h - 2).min(31) | 1);
    staged.write("points.csv", export::points_csv(&first, window))?;
    let (readme, command) = readme(rec, k, out);
    staged.write("README.txt", readme)?;
    staged.commit()?;
    Ok(format!(
        "{k} targets, {} frames of {w}x{h} px at {} fps ({:.1} min), modes: {}\nwritten to \
         {}\nanalyse with:\n  {command}\n",
        rec.frames,
        rec.fps,
        rec.frames as f64 / rec.fps / 60.0,
        field::modes_line(&rec.model),
        out.display()
    ))
}

/// One renderer per target's strip, all over the same span of the paths' motion.
fn strip_renderers(paths: &[TargetPath], target: &crate::imaging::DiskTarget) -> Vec<BlurRenderer> {
    let (lo, hi) = paths
        .iter()
        .flat_map(|p| p.path_px.iter())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    paths
        .iter()
        .map(|p| {
            let mut r = BlurRenderer::new(target, lo, hi);
            // no precomputed blocks: an exposure spans a few fine steps
            r.set_path(&p.path_px, p.path_px.len() + 1);
            r
        })
        .collect()
}

/// [`write_field_recording`] through [`super::camera_view`].
fn write_view(
    rec: &FieldRecording,
    v: &super::camera_view::CameraView,
    staged: vibcam_report::outdir::Staged,
    out: &Path,
    progress: impl FnMut(usize),
) -> anyhow::Result<String> {
    let camera = camera_of(rec);
    let (w, h) = super::camera_view::render(
        &rec.model,
        (rec.fps, rec.frames, rec.seed, rec.exposure_ms),
        rec.rms_px,
        v,
        &camera,
        (&staged, out),
        progress,
    )?;
    staged.write("truth.csv", export::truth_csv(&true_modes(&rec.model)))?;
    let d = out.display();
    let refs = if v.references > 0 {
        format!(" --reference {d}/references.csv")
    } else {
        String::new()
    };
    let command = format!(
        "host-harness analyze --frames {d}/frames --fps {} --points {d}/points.csv --threshold \
         {} --tracker weighted{refs} --out {d}/analysis",
        rec.fps,
        cantilever::THRESHOLD
    );
    let readme = format!(
        "Synthetic field recording seen by a camera that moves or looks at an angle: {} \
         targets, {}; the point that moves most has an RMS displacement of {} px at the nominal 0.5 px/mm.\n\
         Camera: shake {} px RMS per axis and roll {} deg RMS over {}-{} Hz, the plane turned \
         by {} deg, {} static reference disks.\nModes: {}\nTruth: truth.csv (modes), \
         truth_motion.csv (each target's image centre and its displacement along the plane's y \
         in mm), camera_truth.csv (the shake). points.csv and references.csv: a window per \
         disk; world.csv: the references' centres in the image and in the plane (mm), for \
         `analyze --world`.\n\nAnalyse the frames (output-only) with:\n\n  {command}\n",
        rec.model.points,
        rec.camera_words(),
        rec.rms_px,
        v.shake_px,
        v.roll_deg,
        v.shake_band_hz.0,
        v.shake_band_hz.1,
        v.oblique_deg,
        v.references,
        field::modes_line(&rec.model)
    );
    staged.write("README.txt", readme)?;
    staged.commit()?;
    Ok(format!(
        "{} targets and {} references, {} frames of {w}x{h} px at {} fps, modes: {}\nwritten \
         to {}\nanalyse with:\n  {command}\n",
        rec.model.points,
        v.references,
        rec.frames,
        rec.fps,
        field::modes_line(&rec.model),
        out.display()
    ))
}

/// The camera that films `rec` (plain frames).
fn camera_of(rec: &FieldRecording) -> SinkCamera {
    SinkCamera {
        fps: rec.fps,
        video: rec.video,
        read_noise: rec.read_noise,
        seed: rec.seed,
        cluttered: false,
    }
}

/// Each point's motion at the simulation's fine steps as an image path, px: scaled so that the
/// point moving most has an RMS of `rec.rms_px` at the frames' instants; image `y` grows
/// downwards, so a positive displacement moves the disk up.
fn scaled_paths(rec: &FieldRecording) -> Vec<TargetPath> {
    let fine = field::simulate_fine(&rec.model, rec.fps, rec.frames, rec.seed);
    // the scale: the largest RMS over the points at the frames' instants
    let rms = fine
        .iter()
        .map(|f| {
            let s: f64 = (0..rec.frames).map(|k| f[SUB + k * SUB].powi(2)).sum();
            (s / rec.frames as f64).sqrt()
        })
        .fold(0.0, f64::max);
    let scale = if rms > 0.0 { rec.rms_px / rms } else { 0.0 };
    let fine_hz = rec.fps * SUB as f64;
    // image y grows downwards: a positive displacement moves the disk up
    let paths: Vec<TargetPath> = fine
        .iter()
        .map(|f| TargetPath {
            path_px: f.iter().map(|v| -v * scale).collect(),
            pad: SUB,
            fine_per_frame: SUB,
            fine_hz,
        })
        .collect();
    paths
}

/// The recording's README and the command that analyses its frames.
fn readme(rec: &FieldRecording, k: usize, out: &Path) -> (String, String) {
    // the weighted centroid: linear in the motion, so no harmonics of pixel locking (the binary
    // centroid's staircase turns the strong first mode into modes at 3 and 5 times it)
    let command = format!(
        "host-harness analyze --frames {d}/frames --fps {} --targets {k} --threshold {} \
         --tracker weighted --out {d}/analysis",
        rec.fps,
        cantilever::THRESHOLD,
        d = out.display()
    );
    let readme = format!(
        "Synthetic field recording: {k} targets on a structure under broadband random force, \
         {} frames at {} fps ({:.1} min), exposure {} ms, read noise {} grey levels, seed {}; \
         the point that moves most has an RMS displacement of {} px.\nModes: {}\nTrue modes \
         in truth.csv; the exact exposure-averaged displacements (px, positive up) in \
         displacement.csv (`host-harness modal --displacement` reads it).\n\nAnalyse the \
         frames (output-only, no accelerometer) with:\n\n  {command}\n",
        rec.frames,
        rec.fps,
        rec.frames as f64 / rec.fps / 60.0,
        rec.exposure_ms,
        rec.read_noise,
        rec.seed,
        rec.rms_px,
        field::modes_line(&rec.model),
    );
    (readme, command)
}

/// The model's modes as `truth.csv` lists them.
fn true_modes(model: &FieldModel) -> Vec<TrueMode<'_>> {
    model
        .modes
        .iter()
        .map(|m| TrueMode {
            f_hz: m.f_hz,
            damping: m.damping,
            shape: &m.shape,
        })
        .collect()
}

/// Writes a field record without frames: `displacement.csv` (`t_s,1,...,K`: a wide file
/// `modal` reads) and `truth.csv` (`mode,f_hz,damping,target,shape`) into `out` (staged:
/// complete or absent; `force` replaces an earlier output of `simulate-field`); returns a short
/// report.
pub fn write_field(
    out: &Path,
    force: bool,
    model: &FieldModel,
    rec: &[Vec<f64>],
    fs_hz: f64,
) -> anyhow::Result<String> {
    let staged = vibcam_report::outdir::Staged::new(out, force, "simulate-field", &[])?;
    let n = rec.first().map_or(0, Vec::len);
    staged.write("displacement.csv", export::displacement_csv(rec, fs_hz))?;
    staged.write("truth.csv", export::truth_csv(&true_modes(model)))?;
    staged.commit()?;
    Ok(format!(
        "{} points, {n} samples at {fs_hz} Hz ({:.1} min), {} modes: {}\nwritten to {}\n",
        model.points,
        n as f64 / fs_hz / 60.0,
        model.modes.len(),
        field::modes_line(model),
        out.display()
    ))
}
