//! Synthetic recordings with several targets along the cantilever (
//! `render --recording --targets K`): target `k` of `K` sits at `xi = k / K` of the beam (the
//! last at the tip), moves with the model's mode shapes there (`model::simulate_at`), and is
//! drawn in its own column strip of the frame, left to right; `recording.toml` gets the true
//! shapes.

use super::{RecordingFiles, RecordingSpec};
use crate::imaging::{BlurRenderer, TargetPath};
use anyhow::Context as _;
use std::path::Path;
use vibcam_model::{self as model, cantilever, Rig};

/// Positions `xi = k / K`, `k = 1..=K`, along the beam.
pub fn positions(k: usize) -> Vec<f64> {
    (1..=k).map(|i| i as f64 / k as f64).collect()
}

/// The true mode shapes at `positions` (per mode, the shape relative to the tip, normalised to
/// unit largest modulus: the modal residues of the absolute-acceleration FRFs are proportional
/// to it).
pub fn true_shapes(modes: usize, positions: &[f64]) -> Vec<Vec<f64>> {
    (0..modes)
        .map(|i| {
            let v: Vec<f64> = positions
                .iter()
                .map(|&xi| cantilever::mode_shape(i, xi) / cantilever::mode_shape(i, 1.0))
                .collect();
            let big = v
                .iter()
                .copied()
                .fold(0.0f64, |a, b| if b.abs() > a.abs() { b } else { a });
            v.iter().map(|x| x / big).collect()
        })
        .collect()
}

/// Writes a `targets`-target recording of `spec` (the cantilever) into `write_to` for the
/// directory `dir` it will be moved to (see [`super::write_recording_into`]).
pub fn write_targets_recording(
    spec: &RecordingSpec,
    targets: usize,
    (write_to, dir): (&Path, &Path),
) -> anyhow::Result<RecordingFiles> {
    spec.validate()?;
    if !(2..=16).contains(&targets) {
        return Err(vibcam_readers::bad_input(format!(
            "$targets {targets}: between 2 and 16 targets"
        )));
    }
    let Rig::Cantilever(beam) = &spec.rig else {
        return Err(vibcam_readers::bad_input(
            "$targets: only the cantilever has targets along it",
        ));
    };
    let xis = positions(targets);
    let (run, at_mm) = model::simulate_at(&spec.rig, &spec.acquisition, spec.seed, &xis)?;
    let (sink, renderers, (sw, w, h), first, truth) =
        render_strips(spec, &run, &at_mm, targets, (write_to, dir))?;
    std::fs::write(
        write_to.join("truth.csv"),
        vibcam_report::export::recording::truth_csv(&truth),
    )
    .with_context(|| format!("cannot write {}", dir.join("truth.csv").display()))?;
    let (frames_dir, video) = sink.finish()?;
    let wall = if spec.cluttered {
        super::cluttered::WALL_PX as f64
    } else {
        0.0
    };
    write_points(&first, sw, h, wall, (write_to, dir))?;
    let (w, h) = if spec.cluttered {
        super::cluttered::Clutter::new((w, h), spec.seed).outer()
    } else {
        (w, h)
    };
    let x_px: Vec<f64> = (0..targets)
        .map(|t| (t * sw) as f64 + renderers[t].rest_x())
        .collect();
    let shapes = true_shapes(beam.modes.len(), &xis);
    let args = write_texts(
        spec,
        &run,
        TargetsLayout {
            xi: xis,
            x_px,
            shapes,
            frame_size: (w, h),
        },
        video.as_deref(),
        (write_to, dir),
    )?;
    Ok(RecordingFiles {
        frames_dir,
        video,
        accel_csv: dir.join("accel.csv"),
        toml: dir.join("recording.toml"),
        readme: dir.join("README.txt"),
        analyze_args: args,
        frame_size: (w, h),
        frame_count: spec.acquisition.frames,
    })
}

/// Where the targets of a recording are and how they move: the true shapes and geometry
/// `recording.toml` states.
struct TargetsLayout {
    /// Positions along the beam, `x / L`, left to right.
    xi: Vec<f64>,
    /// Their columns in the frame, px.
    x_px: Vec<f64>,
    /// Per mode, the true shape across the targets.
    shapes: Vec<Vec<f64>>,
    /// Frame width and height, px.
    frame_size: (usize, usize),
}

/// `points.csv` of a recording with targets: each target's centroid in the first frame (in the
/// written frame's pixels: a cluttered scene's wall rows `wall` above the structure) and a window that holds the tag and its motion between two frames
/// but not the wall or a neighbour: the strip's width less 2 (odd), 31 rows.
fn write_points(
    first: &[(f64, f64)],
    strip_w: usize,
    inner_h: usize,
    wall: f64,
    (write_to, dir): (&Path, &Path),
) -> anyhow::Result<()> {
    let w = (strip_w - 2) | 1;
    let h = 31.min(inner_h.saturating_sub(2)) | 1;
    let mut csv = String::from("target,x,y,w,h\n");
    for (t, &(x, y)) in first.iter().enumerate() {
        csv.push_str(&format!("{},{x},{},{w},{h}\n", t + 1, y + wall));
    }
    std::fs::write(write_to.join("points.csv"), csv)
        .with_context(|| format!("cannot write {}", dir.join("points.csv").display()))
}

/// The centroid of the pixels above half the target's level in columns `x0..x0 + sw` of the
/// float frame `img` (`w` wide): a target's position in the first frame.
pub(super) fn strip_centroid(
    img: &[f32],
    w: usize,
    (x0, sw): (usize, usize),
    half: f32,
) -> (f64, f64) {
    let (mut n, mut sx, mut sy) = (0.0f64, 0.0f64, 0.0f64);
    for (y, row) in img.chunks_exact(w).enumerate() {
        for (x, &v) in row.iter().enumerate().skip(x0).take(sw) {
            if v > half {
                n += 1.0;
                sx += x as f64;
                sy += y as f64;
            }
        }
    }
    (sx / n.max(1.0), sy / n.max(1.0))
}

/// The frames: each target rendered in its own strip of the frame by its own renderer, all on
/// one intensity scale; returns the sink (to finish), the renderers, (strip width, frame
/// width, height) and each target's position in the first frame.
#[allow(clippy::type_complexity)]
fn render_strips(
    spec: &RecordingSpec,
    run: &model::SyntheticRun,
    at_mm: &[Vec<f64>],
    targets: usize,
    (write_to, dir): (&Path, &Path),
) -> anyhow::Result<(
    super::FrameSink,
    Vec<BlurRenderer>,
    (usize, usize, usize),
    Vec<(f64, f64)>,
    Vec<Vec<(f64, f64)>>,
)> {
    let fine_hz = spec.acquisition.fps * run.fine_per_frame as f64;
    let pad = TargetPath::pad_for(spec.exposure_ms, fine_hz);
    let paths: Vec<TargetPath> = at_mm
        .iter()
        .map(|mm| {
            let px: Vec<f64> = mm.iter().map(|v| -v / spec.mm_per_px).collect();
            TargetPath::periodic(&px, pad, run.fine_per_frame, fine_hz)
        })
        .collect();
    let (lo, hi) = paths
        .iter()
        .flat_map(|p| p.path_px.iter())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let mut renderers: Vec<BlurRenderer> = paths
        .iter()
        .map(|p| {
            let mut r = BlurRenderer::new(&spec.target, lo, hi);
            r.set_path(&p.path_px, 1);
            r
        })
        .collect();
    let (sw, h) = (renderers[0].width(), renderers[0].height());
    let w = sw * targets;
    let mut sink = super::FrameSink::create(spec, (write_to, dir), (w, h))?;
    let (mut strip, mut frame) = (vec![0f32; sw * h], vec![0f32; w * h]);
    let mut first = Vec::new();
    // the exact exposure-averaged centres, in the written frame's pixels
    let wall = if spec.cluttered {
        super::cluttered::WALL_PX as f64
    } else {
        0.0
    };
    let mut truth = Vec::with_capacity(spec.acquisition.frames);
    for k in 0..spec.acquisition.frames {
        let mut at = Vec::with_capacity(targets);
        for (t, (r, p)) in renderers.iter_mut().zip(&paths).enumerate() {
            let (a, b) = p.frame_window(k, spec.exposure_ms);
            at.push((
                (t * sw) as f64 + r.rest_x(),
                wall + r.rest_y() + p.mean_px((a, b)),
            ));
            r.render_float(a, b, &mut strip);
            for y in 0..h {
                frame[y * w + t * sw..y * w + (t + 1) * sw]
                    .copy_from_slice(&strip[y * sw..(y + 1) * sw]);
            }
        }
        if k == 0 {
            let half = spec.target.level as f32 / 2.0;
            first = (0..targets)
                .map(|t| strip_centroid(&frame, w, (t * sw, sw), half))
                .collect();
        }
        sink.put(k, &frame)?;
        truth.push(at);
    }
    Ok((sink, renderers, (sw, w, h), first, truth))
}

/// `accel.csv`, `recording.toml` and `README.txt` (the `analyze --targets` command, returned);
/// `video` the lossless video when one was written.
fn write_texts(
    spec: &RecordingSpec,
    run: &model::SyntheticRun,
    layout: TargetsLayout,
    video: Option<&Path>,
    (write_to, dir): (&Path, &Path),
) -> anyhow::Result<Vec<String>> {
    let csv = vibcam_report::export::recording::accel_csv(
        spec.rig.input_col(),
        (&run.input, &run.tip_acc),
        spec.acquisition.fs,
    );
    std::fs::write(write_to.join("accel.csv"), csv)
        .with_context(|| format!("cannot write {}", dir.join("accel.csv").display()))?;
    let targets = layout.xi.len();
    let mut toml = super::toml_of(spec, layout.frame_size);
    toml.targets = Some(targets);
    toml.target_xi = Some(layout.xi);
    toml.target_x_px = Some(layout.x_px);
    toml.target_shapes = layout
        .shapes
        .into_iter()
        .enumerate()
        .map(|(i, shape)| super::TargetShape { mode: i + 1, shape })
        .collect();
    let toml = toml.to_text()?;
    std::fs::write(write_to.join("recording.toml"), toml)
        .with_context(|| format!("cannot write {}", dir.join("recording.toml").display()))?;
    let mut args = super::analyze_args(spec, dir);
    let at = args.iter().position(|a| a == "--out").unwrap_or(args.len());
    if spec.cluttered {
        args.insert(at, dir.join("points.csv").display().to_string());
        args.insert(at, "--points".into());
    } else {
        args.insert(at, targets.to_string());
        args.insert(at, "--targets".into());
    }
    let mut readme = format!(
        "Synthetic cantilever recording with {targets} targets along the beam ({} frames at {} \
         fps, exposure {} ms, seed {}); true mode shapes in recording.toml.\n\nAnalyse it with:\n\n  \
         host-harness {}\n",
        spec.acquisition.frames,
        spec.acquisition.fps,
        spec.exposure_ms,
        spec.seed,
        args.join(" ")
    );
    readme.push_str(&super::video_readme(video, spec.cluttered));
    std::fs::write(write_to.join("README.txt"), readme)
        .with_context(|| format!("cannot write {}", dir.join("README.txt").display()))?;
    Ok(args)
}
