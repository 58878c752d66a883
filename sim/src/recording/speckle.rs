//! A speckle-painted beam (`simulate-field --render --scene speckle`): a full field of texture
//! whose modes and shapes are known at every pixel, for dense tracking (`pick --region`), modes
//! from many channels and motion magnification (docs/method.md §3.12, "A full field").
//!
//! A simply supported beam seen side-on: light grey, [`BEAM_TOP`] to [`BEAM_BOTTOM`] rows,
//! its supports at columns [`X0`] and [`X1`], painted with dark Gaussian dots (a jittered grid
//! of 4 px, sigma 1.2 px) in front of a dark background. It moves vertically only: pixel column
//! `x` is shifted by `v(x, t) = sum_r sin(r pi (x - X0) / (X1 - X0)) q_r(t)` (positive up),
//! the texture moving with its column (the slope's small rotation is left out). The modal
//! coordinates `q_r` come from [`vibcam_model::field`] with one unit point per mode (each mode
//! driven by a white force of its own), scaled so that the modes' RMS responses are alike and
//! the column that moves most has an RMS of `rms_px`. An exposure is the mean of the sharp
//! images at the simulation's fine steps within it (16 per frame period; at least the frame's
//! own instant), read noise added before 8-bit rounding.
//!
//! Written beside the frames: `shapes.csv` (each mode's shape at every pixel column),
//! `motion.csv` (the exposure-averaged `q_r` of every frame, px: the true displacement of any
//! pixel), `truth.csv` (the modes, their shapes at [`STATIONS`] stations), `region.txt` (the
//! beam as a `--region` polygon) and `README.txt` with the `pick` and `analyze` commands.

use super::field::FieldRecording;
use super::{FrameSink, SinkCamera};
use rand::{Rng as _, SeedableRng as _};
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::Path;
use vibcam_model::field::{self, FieldMode, FieldModel, SUB};

/// Frame width, px.
pub const WIDTH: usize = 320;
/// Frame height, px.
pub const HEIGHT: usize = 72;
/// The left support's column, px.
pub const X0: f64 = 16.0;
/// The right support's column, px.
pub const X1: f64 = 304.0;
/// The beam's upper edge at rest, px (pixel centres at whole numbers).
pub const BEAM_TOP: f64 = 23.5;
/// The beam's lower edge at rest, px.
pub const BEAM_BOTTOM: f64 = 47.5;
/// The modes: natural frequency (Hz) and damping ratio; the simply supported beam's
/// frequencies grow as `r^2`.
pub const MODES: [(f64, f64); 3] = [(2.5, 0.010), (10.0, 0.015), (22.5, 0.012)];
/// Stations along the beam at which `truth.csv` gives the shapes.
pub const STATIONS: usize = 9;

const BACKGROUND: f64 = 40.0;
const BEAM: f64 = 200.0;
const DOT_PITCH: f64 = 4.0;
const DOT_SIGMA: f64 = 1.2;

/// Mode `r`'s (1-based) shape at column `x_px`: `sin(r pi (x - X0) / (X1 - X0))`, 0 beyond
/// the supports.
pub fn shape(r: usize, x_px: f64) -> f64 {
    let xi = (x_px - X0) / (X1 - X0);
    if (0.0..=1.0).contains(&xi) {
        (r as f64 * PI * xi).sin()
    } else {
        0.0
    }
}

/// The beam as a `pick --region` polygon.
pub fn region() -> String {
    format!("{X0},{BEAM_TOP};{X1},{BEAM_TOP};{X1},{BEAM_BOTTOM};{X0},{BEAM_BOTTOM}")
}

/// The modal model whose points are the modal coordinates: one point per mode, its force
/// scaled by `(f_r / f_1)^(3/4)` so that the modes' RMS responses are alike (a white force
/// gives a response variance `1 / (zeta w^3)`).
pub fn model() -> FieldModel {
    let n = MODES.len();
    let f1 = MODES[0].0;
    FieldModel {
        points: n,
        modes: MODES
            .iter()
            .enumerate()
            .map(|(r, &(f_hz, damping))| {
                let mut shape = vec![0.0; n];
                shape[r] = (f_hz / f1).powf(0.75) * (damping / MODES[0].1).sqrt();
                FieldMode {
                    f_hz,
                    damping,
                    shape,
                }
            })
            .collect(),
    }
}

/// The painted dots: a jittered grid over the beam, in the beam's own coordinates.
struct Speckle {
    cols: usize,
    rows: usize,
    y0: f64,
    /// Per cell: centre x, centre y, depth (0-1).
    dots: Vec<(f64, f64, f64)>,
}

impl Speckle {
    fn new(seed: u64) -> Speckle {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(0x7370_6563_6b6c);
        let y0 = BEAM_TOP - DOT_PITCH;
        let cols = (WIDTH as f64 / DOT_PITCH).ceil() as usize + 2;
        let rows = ((BEAM_BOTTOM - BEAM_TOP) / DOT_PITCH).ceil() as usize + 3;
        let mut dots = Vec::with_capacity(cols * rows);
        for j in 0..rows {
            for i in 0..cols {
                let x = (i as f64 - 1.0 + 0.5) * DOT_PITCH + rng.random_range(-1.2..1.2);
                let y = y0 + (j as f64 + 0.5) * DOT_PITCH + rng.random_range(-1.2..1.2);
                dots.push((x, y, rng.random_range(0.5..0.9)));
            }
        }
        Speckle {
            cols,
            rows,
            y0,
            dots,
        }
    }

    /// The grey level at pixel `(x, y)` of a beam at rest (`y` in the beam's coordinates).
    fn grey(&self, x: f64, y: f64) -> f64 {
        // the pixel's area inside the beam (edges exact for a box pixel)
        let cover = |a: f64, b: f64, p: f64| ((p + 0.5).min(b) - (p - 0.5).max(a)).max(0.0);
        let inside = cover(BEAM_TOP, BEAM_BOTTOM, y) * cover(X0 - 8.0, X1 + 8.0, x);
        if inside <= 0.0 {
            return BACKGROUND;
        }
        let (ci, cj) = (
            (x / DOT_PITCH + 1.0).floor() as isize,
            ((y - self.y0) / DOT_PITCH).floor() as isize,
        );
        let mut dark = 0.0;
        for j in cj - 1..=cj + 1 {
            for i in ci - 1..=ci + 1 {
                if i < 0 || j < 0 || i as usize >= self.cols || j as usize >= self.rows {
                    continue;
                }
                let (dx, dy, a) = self.dots[j as usize * self.cols + i as usize];
                let r2 = (x - dx).powi(2) + (y - dy).powi(2);
                dark += a * (-r2 / (2.0 * DOT_SIGMA * DOT_SIGMA)).exp();
            }
        }
        BACKGROUND + (BEAM - BACKGROUND) * inside * (1.0 - dark.min(1.0))
    }

    /// The sharp image of the beam with column `x` moved up by `v[x]` px, added into `img`
    /// with weight `w`.
    fn add(&self, v: &[f64], w: f32, img: &mut [f32]) {
        let rows = (BEAM_TOP - 12.0).max(0.0) as usize..((BEAM_BOTTOM + 13.0) as usize).min(HEIGHT);
        for (x, &d) in v.iter().enumerate() {
            for y in 0..HEIGHT {
                let g = if rows.contains(&y) {
                    // up by d: the pixel at y sees the beam's point y + d
                    self.grey(x as f64, y as f64 + d)
                } else {
                    BACKGROUND
                };
                img[y * WIDTH + x] += w * g as f32;
            }
        }
    }
}

/// The modal coordinates at the simulation's fine steps, scaled (px) so that the column moving
/// most has an RMS of `rec.rms_px` at the frames' instants.
fn scaled_coordinates(rec: &FieldRecording) -> Vec<Vec<f64>> {
    let mut q = field::simulate_fine(&model(), rec.fps, rec.frames, rec.seed);
    let rms = (0..WIDTH)
        .map(|x| {
            let s: f64 = (0..rec.frames)
                .map(|k| {
                    let v: f64 = (0..q.len())
                        .map(|r| shape(r + 1, x as f64) * q[r][SUB + k * SUB])
                        .sum();
                    v * v
                })
                .sum();
            (s / rec.frames as f64).sqrt()
        })
        .fold(0.0, f64::max);
    let scale = if rms > 0.0 { rec.rms_px / rms } else { 0.0 };
    for c in &mut q {
        c.iter_mut().for_each(|v| *v *= scale);
    }
    q
}

/// The fine steps frame `k`'s exposure averages.
fn exposure_steps(rec: &FieldRecording, k: usize) -> std::ops::RangeInclusive<usize> {
    let half = (rec.exposure_ms / 1000.0 / 2.0 * rec.fps * SUB as f64).floor() as usize;
    let half = half.min(SUB / 2);
    let c = SUB + k * SUB;
    c - half..=c + half
}

/// Refuses what [`FieldRecording::validate`] refuses, and an RMS motion above 5 px (the
/// beam's edges are 23 px from the frame's).
fn validate(rec: &FieldRecording) -> anyhow::Result<()> {
    rec.validate()?;
    if rec.rms_px > 5.0 {
        return Err(vibcam_readers::bad_input(format!(
            "$rms_px {}: at most 5 for the speckle beam (its edges are {} px from the frame's)",
            rec.rms_px, BEAM_TOP as usize
        )));
    }
    Ok(())
}

/// Writes the recording into `out` (staged: complete or absent; `force` replaces an earlier
/// output of `simulate-field`), reporting progress to `progress(frames done)`; returns a short
/// report naming the commands.
/// The model is always [`model`]'s (`rec.model` and `rec.view` play no part).
pub fn write_speckle_beam(
    rec: &FieldRecording,
    out: &Path,
    force: bool,
    mut progress: impl FnMut(usize),
) -> anyhow::Result<String> {
    validate(rec)?;
    let staged = vibcam_report::outdir::Staged::new(out, force, "simulate-field", &[])?;
    let q = scaled_coordinates(rec);
    let speckle = Speckle::new(rec.seed);
    let camera = SinkCamera {
        fps: rec.fps,
        video: rec.video,
        read_noise: rec.read_noise,
        seed: rec.seed,
        cluttered: false,
    };
    let mut sink = FrameSink::open(&camera, (staged.dir(), out), (WIDTH, HEIGHT))?;
    let shapes: Vec<Vec<f64>> = (1..=q.len())
        .map(|r| (0..WIDTH).map(|x| shape(r, x as f64)).collect())
        .collect();
    let mut img = vec![0f32; WIDTH * HEIGHT];
    let mut v = vec![0.0; WIDTH];
    let mut motion = String::from("frame,t_s");
    for r in 1..=q.len() {
        let _ = write!(motion, ",q_{r}");
    }
    motion.push('\n');
    for k in 0..rec.frames {
        img.iter_mut().for_each(|p| *p = 0.0);
        let steps = exposure_steps(rec, k);
        let w = 1.0 / steps.clone().count() as f32;
        let mut mean_q = vec![0.0; q.len()];
        for s in steps {
            for (x, vx) in v.iter_mut().enumerate() {
                *vx = shapes.iter().zip(&q).map(|(sh, c)| sh[x] * c[s]).sum();
            }
            for (m, c) in mean_q.iter_mut().zip(&q) {
                *m += w as f64 * c[s];
            }
            speckle.add(&v, w, &mut img);
        }
        let _ = write!(motion, "{k},{}", k as f64 / rec.fps);
        for m in &mean_q {
            let _ = write!(motion, ",{m}");
        }
        motion.push('\n');
        sink.put(k, &img)?;
        progress(k + 1);
    }
    sink.finish()?;
    staged.write("motion.csv", motion)?;
    staged.write("shapes.csv", shapes_csv(&shapes))?;
    staged.write("truth.csv", truth_csv())?;
    staged.write("region.txt", format!("{}\n", region()))?;
    let (readme, commands) = readme(rec, out);
    staged.write("README.txt", readme)?;
    staged.commit()?;
    Ok(format!(
        "a speckle-painted beam, {} frames of {WIDTH}x{HEIGHT} px at {} fps, modes: {}\nwritten \
         to {}\nchoose the points and analyse with:\n{commands}",
        rec.frames,
        rec.fps,
        field::modes_line(&model()),
        out.display()
    ))
}

/// `shapes.csv`: `x_px,mode_1,...` at every pixel column.
fn shapes_csv(shapes: &[Vec<f64>]) -> String {
    let mut t = String::from("x_px");
    for r in 1..=shapes.len() {
        let _ = write!(t, ",mode_{r}");
    }
    t.push('\n');
    for x in 0..WIDTH {
        let _ = write!(t, "{x}");
        for s in shapes {
            let _ = write!(t, ",{}", s[x]);
        }
        t.push('\n');
    }
    t
}

/// `truth.csv`: the modes with their shapes at [`STATIONS`] evenly spaced stations between the
/// supports (the first and last a station inside them).
fn truth_csv() -> String {
    let stations: Vec<Vec<f64>> = (1..=MODES.len())
        .map(|r| {
            (1..=STATIONS)
                .map(|j| shape(r, X0 + (X1 - X0) * j as f64 / (STATIONS + 1) as f64))
                .collect()
        })
        .collect();
    let modes: Vec<vibcam_report::export::field::TrueMode<'_>> = MODES
        .iter()
        .zip(&stations)
        .map(
            |(&(f_hz, damping), s)| vibcam_report::export::field::TrueMode {
                f_hz,
                damping,
                shape: s,
            },
        )
        .collect();
    vibcam_report::export::field::truth_csv(&modes)
}

/// The README and the commands that choose the points and analyse the frames.
fn readme(rec: &FieldRecording, out: &Path) -> (String, String) {
    let d = out.display();
    let commands = format!(
        "  host-harness pick --frames {d}/frames --region '{}' --spacing 3 --window-px 15 \
         --direction y --points-out {d}/points.csv --out {d}/pick.html\n  host-harness analyze \
         --frames {d}/frames --fps {} --points {d}/points.csv --tracker lk --out {d}/analysis\n",
        region(),
        rec.fps
    );
    let readme = format!(
        "Synthetic full field: a simply supported beam painted with speckle, seen side-on in \
         frames of {WIDTH}x{HEIGHT} px: {}; the column that moves most has an RMS \
         displacement of {} px.\nModes: \
         {}\nEvery pixel column x moves vertically (up positive) by sum_r shape_r(x) q_r(t): \
         shape_r in shapes.csv (sin(r pi (x - {X0}) / {})), q_r per frame in motion.csv (px, \
         averaged over the exposure). truth.csv: the modes and their shapes at {STATIONS} \
         stations. region.txt: the beam as a polygon.\n\nChoose points over the beam and \
         analyse them (output-only) with:\n\n{commands}",
        rec.camera_words(),
        rec.rms_px,
        field::modes_line(&model()),
        X1 - X0,
    );
    (readme, commands)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_are_the_simply_supported_beams() {
        assert_eq!(shape(1, X0), 0.0);
        assert!((shape(1, (X0 + X1) / 2.0) - 1.0).abs() < 1e-12);
        assert!(shape(2, (X0 + X1) / 2.0).abs() < 1e-12);
        assert!((shape(3, X0 + (X1 - X0) / 6.0) - 1.0).abs() < 1e-12);
        assert_eq!(shape(2, X1 + 1.0), 0.0);
    }

    #[test]
    fn a_shifted_beam_is_the_same_picture_moved() {
        // a whole-pixel shift of every column moves the picture by whole rows
        let s = Speckle::new(3);
        let (mut a, mut b) = (vec![0f32; WIDTH * HEIGHT], vec![0f32; WIDTH * HEIGHT]);
        s.add(&vec![0.0; WIDTH], 1.0, &mut a);
        s.add(&vec![2.0; WIDTH], 1.0, &mut b);
        for y in 14..60 {
            for x in 0..WIDTH {
                assert!(
                    (b[(y - 2) * WIDTH + x] - a[y * WIDTH + x]).abs() < 1e-3,
                    "{x},{y}"
                );
            }
        }
        // textured: the beam's rows are not flat
        let row: Vec<f32> = a[35 * WIDTH..36 * WIDTH].to_vec();
        let (lo, hi) = row
            .iter()
            .fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
        assert!(hi - lo > 80.0, "{lo}..{hi}");
    }
}
