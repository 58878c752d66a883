//! A field record filmed by a camera that shakes, or that looks at the structure at an angle
//! (`simulate-field --render` with `--shake-px`, `--roll-deg`, `--oblique-deg` or
//! `--references`): the ground truth for removing the camera's motion with static references
//! and for the scale from the structure's plane (docs/method.md §3.14).
//!
//! The scene is a plane (mm, `y` up): the field model's points as white disks of radius
//! [`DISK_MM`] in a row [`SPACING_MM`] apart, moving along `y` by the model's displacement
//! (the point that moves most with an RMS of `rms_px` pixels at the nominal scale), and
//! `references` static disks of the same kind above and below the row (a wall behind the
//! structure, in its plane). A pinhole camera [`DISTANCE_MM`] in front of the row's centre
//! with a focal length of [`FOCAL_PX`] (a nominal 0.5 px/mm where the row crosses the optical
//! axis) sees the plane turned by `oblique_deg` about its vertical axis
//! ([`vibcam_common::geometry::plane_view`]); the camera's shake moves the image by a translation
//! (RMS `shake_px` along each axis) and a roll about the image's centre (RMS `roll_deg`), each
//! band-limited Gaussian noise with a flat spectrum over `shake_band_hz`.
//!
//! Each pixel is drawn by its centre taken back to the plane (the disk's edge blurred by a Gaussian
//! of half a pixel at the disk's local scale), averaged over [`INSTANTS`] instants spread over the
//! exposure; read noise is added before 8-bit rounding. Beside the frames:
//! `truth_motion.csv` (`frame,t_s,target,x_px,y_px,disp_mm`: each target's centre in the
//! image as the camera saw it and its displacement along the plane's `y` in mm, exposure
//! averaged), `camera_truth.csv` (`frame,t_s,dx_px,dy_px,rotation_deg`: the shake at the
//! image's centre), `points.csv` and `references.csv` (a window per disk), `world.csv` (the
//! references' centres in the image at rest and in the plane: `--world`), `truth.csv` (the
//! modes).

use super::{FrameSink, SinkCamera};
use std::fmt::Write as _;
use std::path::Path;
use vibcam_common::geometry::{plane_view, Homography};
use vibcam_model::field::{self, FieldModel, SUB};

/// Disks' radius, mm.
pub const DISK_MM: f64 = 10.0;
/// The targets' spacing along the row, mm.
pub const SPACING_MM: f64 = 80.0;
/// The camera's distance from the row's centre, mm.
pub const DISTANCE_MM: f64 = 500.0;
/// Focal length, px (0.5 px/mm at the row's centre).
pub const FOCAL_PX: f64 = 250.0;
/// The references' distance above and below the row, mm.
pub const REFERENCE_Y_MM: f64 = 110.0;
/// Instants averaged over each exposure.
pub const INSTANTS: usize = 4;
/// The disks' edges blurred by a Gaussian of this width, px (as the rigs' targets).
const EDGE_SIGMA_PX: f64 = 0.5;
/// Grey level of a disk (on black).
const LEVEL: f32 = 255.0;
/// Window of each disk in points.csv and references.csv, px.
const WINDOW: u32 = 21;
/// Margin around the scene, px.
const MARGIN: f64 = 24.0;

/// How the camera sees the field record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraView {
    /// Static reference disks (0 to 8).
    pub references: usize,
    /// RMS shake along each image axis, px.
    pub shake_px: f64,
    /// RMS roll, degrees.
    pub roll_deg: f64,
    /// The shake's band, Hz.
    pub shake_band_hz: (f64, f64),
    /// The plane turned about its vertical axis, degrees (0: square to the camera).
    pub oblique_deg: f64,
}

impl CameraView {
    /// Checks the settings against the frame rate.
    pub fn validate(&self, fps: f64) -> anyhow::Result<()> {
        let bad = vibcam_readers::bad_input;
        if self.references > 8 {
            return Err(bad(format!(
                "$references {}: 0 to 8 static disks",
                self.references
            )));
        }
        if !(self.shake_px.is_finite() && (0.0..=20.0).contains(&self.shake_px)) {
            return Err(bad(format!("$shake_px {}: 0 to 20 px", self.shake_px)));
        }
        if !(self.roll_deg.is_finite() && (0.0..=5.0).contains(&self.roll_deg)) {
            return Err(bad(format!("$roll_deg {}: 0 to 5 degrees", self.roll_deg)));
        }
        let (a, b) = self.shake_band_hz;
        if !(a.is_finite() && b.is_finite() && 0.0 < a && a < b && b < fps / 2.0) {
            return Err(bad(format!(
                "$shake_hz {a},{b}: a band 0 < A < B below the Nyquist frequency ({} Hz)",
                fps / 2.0
            )));
        }
        if !(self.oblique_deg.is_finite() && (0.0..=60.0).contains(&self.oblique_deg)) {
            return Err(bad(format!(
                "$oblique_deg {}: 0 to 60 degrees",
                self.oblique_deg
            )));
        }
        Ok(())
    }
}

/// Points of the plane, mm.
type PlanePoints = Vec<(f64, f64)>;

/// The plane's points: the targets' rest centres and the references', mm.
fn layout(k: usize, refs: usize) -> (PlanePoints, PlanePoints) {
    let half = (k as f64 - 1.0) / 2.0;
    let targets = (0..k)
        .map(|j| ((j as f64 - half) * SPACING_MM, 0.0))
        .collect();
    // references at the row's ends and between, alternately above and below
    let span = (half + 0.5) * SPACING_MM;
    let references = (0..refs)
        .map(|i| {
            let x = if refs == 1 {
                -span
            } else {
                -span + 2.0 * span * (i / 2) as f64 / ((refs - 1) / 2).max(1) as f64
            };
            let y = if i % 2 == 0 {
                REFERENCE_Y_MM
            } else {
                -REFERENCE_Y_MM
            };
            (x, y)
        })
        .collect();
    (targets, references)
}

/// Band-limited Gaussian noise: `n` samples at `fs_hz`, a flat spectrum over `band`, RMS 1
/// (zero when the band holds no line).
fn band_noise(n: usize, fs_hz: f64, band: (f64, f64), seed: u64) -> Vec<f64> {
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let normal = Normal::new(0.0, 1.0).expect("unit normal");
    let mut planner = vibcam_fft::RealPlanner::new();
    let inv = planner.inverse(n);
    let mut spec = inv.make_input_vec();
    let df = fs_hz / n as f64;
    for (i, s) in spec.iter_mut().enumerate() {
        let f = i as f64 * df;
        if f >= band.0 && f <= band.1 && i > 0 && i < n / 2 {
            *s = num_complex::Complex64::new(normal.sample(&mut rng), normal.sample(&mut rng));
        }
    }
    let mut out = inv.make_output_vec();
    if inv.process(&mut spec, &mut out).is_err() {
        return vec![0.0; n];
    }
    let rms = (out.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    if rms > 0.0 {
        out.iter_mut().for_each(|v| *v /= rms);
    }
    out
}

/// Renders the frames and the truth into `staged` (see the module documentation); returns
/// the frame size.
pub(super) fn render(
    model: &FieldModel,
    (fps, frames, seed, exposure_ms): (f64, usize, u64, f64),
    rms_px: f64,
    view: &CameraView,
    camera: &SinkCamera,
    (staged, out): (&vibcam_report::outdir::Staged, &Path),
    mut progress: impl FnMut(usize),
) -> anyhow::Result<(usize, usize)> {
    let k = model.points;
    let (targets, refs) = layout(k, view.references);
    let (w, h, centre) = frame_size(&targets, &refs, view, rms_px);
    let base = plane_view(view.oblique_deg, DISTANCE_MM, FOCAL_PX, centre);
    // the motion, mm along the plane's y, at every fine step
    let fine = field::simulate_fine(model, fps, frames, seed);
    let scale_mm = motion_scale(&fine, frames, rms_px);
    let fine_hz = fps * SUB as f64;
    let n_fine = fine.first().map_or(0, Vec::len);
    let shake = CameraShake::new(view, (n_fine, fine_hz), seed, centre);
    let camera_at = |s: f64| shake.at(s);
    let target_at = |j: usize, s: f64| -> f64 {
        let i = (s.floor().max(0.0) as usize).min(n_fine.saturating_sub(2));
        let f = s - i as f64;
        scale_mm * (fine[j][i] * (1.0 - f) + fine[j][i + 1] * f)
    };
    let mut sink = FrameSink::open(camera, (staged.dir(), out), (w, h))?;
    let mut frame = vec![0f32; w * h];
    let mut truth = String::from("frame,t_s,target,x_px,y_px,disp_mm\n");
    let mut cam_truth = String::from("frame,t_s,dx_px,dy_px,rotation_deg\n");
    let exposure_steps = exposure_ms / 1000.0 * fine_hz;
    let disks: Vec<(f64, f64)> = targets.iter().chain(&refs).copied().collect();
    for n in 0..frames {
        frame.iter_mut().for_each(|v| *v = 0.0);
        let mid = (SUB + n * SUB) as f64;
        let mut seen = vec![(0.0, 0.0, 0.0); k];
        let mut cam = (0.0, 0.0, 0.0);
        for i in 0..INSTANTS {
            let s = if INSTANTS == 1 {
                mid
            } else {
                mid + exposure_steps * ((i as f64 + 0.5) / INSTANTS as f64 - 0.5)
            };
            let c = camera_at(s);
            let h_cam = c.after(&base);
            let Some(inv) = h_cam.inverse() else {
                continue;
            };
            let (cx, cy) = c.apply(centre);
            cam.0 += (cx - centre.0) / INSTANTS as f64;
            cam.1 += (cy - centre.1) / INSTANTS as f64;
            cam.2 += c.rotation_scale(centre).0.to_degrees() / INSTANTS as f64;
            for (d, &(x0, y0)) in disks.iter().enumerate() {
                let y = if d < k { y0 + target_at(d, s) } else { y0 };
                let p = h_cam.apply((x0, y));
                if d < k {
                    seen[d].0 += p.0 / INSTANTS as f64;
                    seen[d].1 += p.1 / INSTANTS as f64;
                    seen[d].2 += (y - y0) / INSTANTS as f64;
                }
                draw_disk(&mut frame, (w, h), (&h_cam, &inv), (x0, y), p);
            }
        }
        let t_s = n as f64 / fps;
        for (j, (x, y, d)) in seen.iter().enumerate() {
            let _ = writeln!(truth, "{n},{t_s},{},{x},{y},{d}", j + 1);
        }
        let _ = writeln!(cam_truth, "{n},{t_s},{},{},{}", cam.0, cam.1, cam.2);
        frame.iter_mut().for_each(|v| *v = v.min(LEVEL));
        sink.put(n, &frame)?;
        progress(n + 1);
    }
    sink.finish()?;
    staged.write("truth_motion.csv", truth)?;
    staged.write("camera_truth.csv", cam_truth)?;
    write_layout(staged, &base, &targets, &refs)?;
    Ok((w, h))
}

/// mm of the plane per unit of the field's motion: its largest RMS over the points at the
/// frames' instants is `rms_px` in the image.
fn motion_scale(fine: &[Vec<f64>], frames: usize, rms_px: f64) -> f64 {
    let at_frames = |f: &Vec<f64>| {
        let s: f64 = (0..frames).map(|i| f[SUB + i * SUB].powi(2)).sum();
        (s / frames as f64).sqrt()
    };
    let rms = fine.iter().map(at_frames).fold(0.0, f64::max);
    if rms > 0.0 {
        rms_px / (FOCAL_PX / DISTANCE_MM) / rms
    } else {
        0.0
    }
}

/// The camera's shake and roll: band-limited noise on the fine time base (x, y, roll), scaled
/// by the view's sizes; its map at any instant.
struct CameraShake {
    shake: Vec<Vec<f64>>,
    sizes: [f64; 3],
    n_fine: usize,
    centre: (f64, f64),
}

impl CameraShake {
    fn new(
        view: &CameraView,
        (n_fine, fine_hz): (usize, f64),
        seed: u64,
        centre: (f64, f64),
    ) -> Self {
        let shake: Vec<Vec<f64>> = (0..3)
            .map(|i| {
                band_noise(
                    n_fine,
                    fine_hz,
                    view.shake_band_hz,
                    seed ^ (0x5a4e_0000 + i),
                )
            })
            .collect();
        CameraShake {
            shake,
            sizes: [view.shake_px, view.shake_px, view.roll_deg.to_radians()],
            n_fine,
            centre,
        }
    }

    /// The camera's map at fine step `s` (linear interpolation between fine steps).
    fn at(&self, s: f64) -> Homography {
        let i = (s.floor().max(0.0) as usize).min(self.n_fine.saturating_sub(2));
        let f = s - i as f64;
        let v =
            |c: usize| self.sizes[c] * (self.shake[c][i] * (1.0 - f) + self.shake[c][i + 1] * f);
        Homography::similarity(self.centre, v(2), 1.0, (v(0), v(1)))
    }
}

/// The frame's size, odd both ways, and its centre: the plane's disks (targets and references)
/// at their largest reach, plus a margin for the camera's shake and roll.
fn frame_size(
    targets: &[(f64, f64)],
    refs: &[(f64, f64)],
    view: &CameraView,
    rms_px: f64,
) -> (usize, usize, (f64, f64)) {
    // where the plane lands with the image's centre at 0, then the frame around it
    let probe = plane_view(view.oblique_deg, DISTANCE_MM, FOCAL_PX, (0.0, 0.0));
    let reach = DISK_MM + 4.0 * rms_px / (FOCAL_PX / DISTANCE_MM);
    let corners: Vec<(f64, f64)> = targets
        .iter()
        .chain(refs)
        .flat_map(|&(x, y)| {
            [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .map(|(a, b)| probe.apply((x + a * reach, y + b * reach)))
        })
        .collect();
    let xmax = corners.iter().map(|p| p.0.abs()).fold(0.0, f64::max);
    let ymax = corners.iter().map(|p| p.1.abs()).fold(0.0, f64::max);
    let slack = MARGIN + 3.0 * view.shake_px + (view.roll_deg * 3.0).to_radians() * xmax;
    let w = (2.0 * (xmax + slack)).ceil() as usize | 1;
    let h = (2.0 * (ymax + slack)).ceil() as usize | 1;
    let centre = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    (w, h, centre)
}

/// Adds one instant's disk at plane point `(x0, y)`, seen through `h_cam` (`inv` its inverse)
/// at image point `p`, to `frame` (`w` x `h`): its edge blurred by a Gaussian of EDGE_SIGMA_PX.
fn draw_disk(
    frame: &mut [f32],
    (w, h): (usize, usize),
    (h_cam, inv): (&Homography, &Homography),
    (x0, y): (f64, f64),
    p: (f64, f64),
) {
    let jac = h_cam.jacobian((x0, y));
    let px_per_mm = (jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0]).abs().sqrt();
    let r_px = DISK_MM * px_per_mm * 1.6 + 2.0;
    let (x_lo, x_hi) = (
        (p.0 - r_px).floor().max(0.0) as usize,
        ((p.0 + r_px).ceil() as usize).min(w - 1),
    );
    let (y_lo, y_hi) = (
        (p.1 - r_px).floor().max(0.0) as usize,
        ((p.1 + r_px).ceil() as usize).min(h - 1),
    );
    for yy in y_lo..=y_hi {
        for xx in x_lo..=x_hi {
            let q = inv.apply((xx as f64, yy as f64));
            let dist = ((q.0 - x0).powi(2) + (q.1 - y).powi(2)).sqrt() - DISK_MM;
            // the edge blurred by a Gaussian of EDGE_SIGMA_PX (a lens's): no
            // staircase for the centroid to lock to
            let cover = (0.5
                * libm::erfc(dist * px_per_mm / (EDGE_SIGMA_PX * std::f64::consts::SQRT_2)))
                as f32;
            frame[yy * w + xx] += LEVEL * cover / INSTANTS as f32;
        }
    }
}

/// `points.csv` (the targets' windows), and with references `references.csv` and `world.csv`
/// (their plane coordinates).
fn write_layout(
    staged: &vibcam_report::outdir::Staged,
    base: &Homography,
    targets: &[(f64, f64)],
    refs: &[(f64, f64)],
) -> anyhow::Result<()> {
    let windows = |pts: &[(f64, f64)]| {
        let mut s = String::from("target,x,y,w,h\n");
        for (i, p) in pts.iter().enumerate() {
            let (x, y) = base.apply(*p);
            let _ = writeln!(s, "{},{x:.2},{y:.2},{WINDOW},{WINDOW}", i + 1);
        }
        s
    };
    staged.write("points.csv", windows(targets))?;
    if !refs.is_empty() {
        staged.write("references.csv", windows(refs))?;
        let mut world = String::from("x,y,x_mm,y_mm\n");
        for p in refs {
            let (x, y) = base.apply(*p);
            let _ = writeln!(world, "{x:.3},{y:.3},{},{}", p.0, p.1);
        }
        staged.write("world.csv", world)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_noise_has_unit_rms_and_no_power_outside_its_band() {
        let n = 4096;
        let v = band_noise(n, 100.0, (1.0, 5.0), 3);
        let rms = (v.iter().map(|x| x * x).sum::<f64>() / n as f64).sqrt();
        assert!((rms - 1.0).abs() < 1e-9);
        // a naive DFT line outside the band holds nothing
        let line = |f: f64| {
            let (mut re, mut im) = (0.0, 0.0);
            for (i, x) in v.iter().enumerate() {
                let a = std::f64::consts::TAU * f * i as f64 / 100.0;
                re += x * a.cos();
                im -= x * a.sin();
            }
            (re * re + im * im).sqrt()
        };
        let df = 100.0 / n as f64;
        // 9.8 Hz is outside the band, 2.4 Hz and 2.5 Hz inside it
        assert!(line(400.0 * df) < 1e-6 * line(100.0 * df).max(line(101.0 * df)));
    }

    #[test]
    fn references_surround_the_row() {
        let (t, r) = layout(5, 4);
        assert_eq!(t.len(), 5);
        assert_eq!(r.len(), 4);
        assert!(r.iter().all(|p| p.1.abs() == REFERENCE_Y_MM));
        assert!(r.iter().any(|p| p.0 < t[0].0) && r.iter().any(|p| p.0 > t[4].0));
    }
}
