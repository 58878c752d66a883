//! Synthetic field records for output-only modal analysis (docs/method.md §3.12): the
//! displacements of a structure's measured points under a broadband random force, simulated
//! directly (no frames rendered) by modal superposition, with the modes as the truth.
//!
//! Each mode `r` (natural frequency `f_r`, damping ratio `zeta_r`, shape `phi_r` at the
//! measured points, mass-normalised) has the modal coordinate
//! `q'' + 2 zeta w q' + w^2 q = sum_j phi_r[j] F_j(t)`, with `F_j` independent white noise
//! forces at the points, held constant over each step of a simulation 16 times faster than
//! the camera (exact discrete-time solution of the held input), read every 16th step. The
//! displacement at point `j` is `sum_r phi_r[j] q_r`, plus white measurement noise.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::f64::consts::PI;

/// One mode of a field model.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldMode {
    /// Undamped natural frequency, Hz.
    pub f_hz: f64,
    /// Damping ratio.
    pub damping: f64,
    /// Shape at the measured points (mass-normalised for a model built from masses).
    pub shape: Vec<f64>,
}

/// A structure seen at `points` measured points.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldModel {
    /// Its modes.
    pub modes: Vec<FieldMode>,
    /// Measured points.
    pub points: usize,
}

/// The cases the `simulate` command and the tests use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FieldCase {
    /// A five-storey shear frame (equal masses and storey stiffnesses), one point per floor:
    /// five modes from 1.5 to 10.1 Hz, damping 1 to 2 %.
    ShearFrame,
    /// Two modes 2 % apart (2.00 and 2.04 Hz, 1 % damping, orthogonal shapes over five
    /// points) and a third at 5 Hz: where FDD's peak picking sees one peak and SSI two.
    CloseModes,
    /// Four modes of a six-storey shear frame (1.95, 5.79, 9.57, 13.08 Hz; damping 1.0, 1.5,
    /// 0.8 and 1.2 %) at six points, the fourth weak: its shape scaled by a half, so its
    /// response is a sixteenth of the others' beside them (the displacement already falls as
    /// `1 / f^4`), near the noise floor of a 3 % measurement noise.
    WeakHighMode,
}

impl FieldCase {
    /// The model of the case.
    pub fn model(self) -> FieldModel {
        match self {
            FieldCase::ShearFrame => shear_frame(5, 1.5, &[0.01, 0.012, 0.015, 0.018, 0.02]),
            FieldCase::CloseModes => FieldModel {
                points: 5,
                modes: vec![
                    FieldMode {
                        f_hz: 2.0,
                        damping: 0.01,
                        shape: vec![1.0, 0.5, 0.0, -0.5, -1.0],
                    },
                    FieldMode {
                        f_hz: 2.04,
                        damping: 0.01,
                        shape: vec![0.5, 1.0, 1.0, 1.0, 0.5],
                    },
                    FieldMode {
                        f_hz: 5.0,
                        damping: 0.015,
                        shape: vec![1.0, -1.0, 1.0, -1.0, 1.0],
                    },
                ],
            },
            FieldCase::WeakHighMode => {
                let mut m = shear_frame(6, 1.95, &[0.01, 0.015, 0.008, 0.012]);
                m.modes.truncate(4);
                for v in &mut m.modes[3].shape {
                    *v *= 0.5;
                }
                m
            }
        }
    }
}

impl FieldModel {
    /// How near an estimate must be to mode `i` to count as it, Hz, on a spectrum of line
    /// spacing `df_hz`: `max(3 lines, 3 zeta f)`, and nearer than half the distance to another
    /// mode (how the examples count a method's modes against the truth).
    pub fn match_window(&self, i: usize, df_hz: f64) -> f64 {
        let m = &self.modes[i];
        let gap = self
            .modes
            .iter()
            .filter(|o| o.f_hz != m.f_hz)
            .map(|o| (o.f_hz - m.f_hz).abs() / 2.0)
            .fold(f64::INFINITY, f64::min);
        (3.0 * df_hz).max(3.0 * m.damping * m.f_hz).min(gap)
    }
}

/// A shear frame of `n` storeys with equal masses and stiffnesses, its first frequency `f1_hz`,
/// the damping ratios of its modes (the last repeated if fewer are given). Closed form: with
/// unit masses the modes of the fixed-free chain are `w_r = 2 sqrt(k) sin((2r - 1) pi /
/// (2 (2n + 1)))`, `phi_r[j] = sqrt(4 / (2n + 1)) sin((2r - 1) (j + 1) pi / (2n + 1))`
/// (floor `j` = 0 the lowest).
pub fn shear_frame(n: usize, f1_hz: f64, damping: &[f64]) -> FieldModel {
    let m = (2 * n + 1) as f64;
    let theta = |r: usize| (2 * r - 1) as f64 * PI / (2.0 * m);
    let modes = (1..=n)
        .map(|r| FieldMode {
            f_hz: f1_hz * theta(r).sin() / theta(1).sin(),
            damping: damping
                .get(r - 1)
                .or(damping.last())
                .copied()
                .unwrap_or(0.01),
            shape: (0..n)
                .map(|j| (4.0 / m).sqrt() * ((2 * r - 1) as f64 * (j + 1) as f64 * PI / m).sin())
                .collect(),
        })
        .collect();
    FieldModel { modes, points: n }
}

/// The most sample periods a record and its settling run may take together (the simulation
/// steps 16 times per sample period): about 3 minutes of computing on one core.
pub const MAX_SIMULATED_PERIODS: u64 = 20_000_000;
/// The most frames a rendered record may have (each one a PNG file written).
pub const MAX_RENDERED_FRAMES: u64 = 200_000;
/// The fewest periods of the structure's lowest mode a record must span (a modal analysis of
/// fewer has no spectral line or correlation lag to resolve the mode).
pub const MIN_PERIODS: f64 = 20.0;

/// A record of the model's points `minutes` long at `fs_hz`, checked: its sample count, with
/// warnings for modes at or above the Nyquist frequency (they alias); a record shorter than
/// [`MIN_PERIODS`] of the lowest mode, or longer than the simulation's or the renderer's
/// bound (with `render`), is an error naming the flag and the bound.
pub fn record_length(
    model: &FieldModel,
    minutes: f64,
    fs_hz: f64,
    render: bool,
) -> anyhow::Result<(usize, Vec<String>)> {
    for (name, v) in [("$minutes", minutes), ("$fps", fs_hz)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(vibcam_readers::bad_input(format!(
                "{name} must be a positive number, got {v}"
            )));
        }
    }
    let f1 = model
        .modes
        .iter()
        .map(|m| m.f_hz)
        .fold(f64::INFINITY, f64::min);
    let seconds = minutes * 60.0;
    let samples = (seconds * fs_hz).round();
    let shortest = MIN_PERIODS / f1;
    if seconds < shortest || samples < 2.0 {
        return Err(vibcam_readers::bad_input(format!(
            "$minutes {minutes} at $fps {fs_hz}: {samples} samples over {seconds:.3} s; the \
             record must span at least {MIN_PERIODS} periods of the lowest mode ({f1} Hz): \
             $minutes {:.3} or more",
            shortest / 60.0
        )));
    }
    let settle = settling_periods(model, fs_hz);
    if samples + settle > MAX_SIMULATED_PERIODS as f64 {
        return Err(vibcam_readers::bad_input(format!(
            "$minutes {minutes} at $fps {fs_hz}: {samples} samples and {settle} of settling \
             (ten decay times of the slowest mode) exceed the {MAX_SIMULATED_PERIODS} sample \
             periods simulated at most; shorten the record or lower the rate"
        )));
    }
    if render && samples > MAX_RENDERED_FRAMES as f64 {
        return Err(vibcam_readers::bad_input(format!(
            "$render $minutes {minutes} at $fps {fs_hz}: {samples} frames, more than the \
             {MAX_RENDERED_FRAMES} frames (PNG files) rendered at most"
        )));
    }
    let nyquist = fs_hz / 2.0;
    let warnings = model
        .modes
        .iter()
        .enumerate()
        .filter(|(_, m)| m.f_hz >= nyquist)
        .map(|(i, m)| {
            format!(
                "mode {} ({:.4} Hz) is at or above the Nyquist frequency ({nyquist} Hz at \
                 $fps {fs_hz}): it aliases to {:.4} Hz in the record, and no analysis of it \
                 can find it where it is",
                i + 1,
                m.f_hz,
                alias_hz(m.f_hz, fs_hz)
            )
        })
        .collect();
    Ok((samples as usize, warnings))
}

/// Where a frequency `f_hz` appears in a record sampled at `fs_hz` (folded into 0..fs/2).
pub fn alias_hz(f_hz: f64, fs_hz: f64) -> f64 {
    let r = f_hz.rem_euclid(fs_hz);
    r.min(fs_hz - r)
}

/// Sample periods of the settling run at `fs_hz` (ten of the slowest mode's decay times).
fn settling_periods(model: &FieldModel, fs_hz: f64) -> f64 {
    let slowest = model
        .modes
        .iter()
        .map(|m| 1.0 / (2.0 * PI * m.f_hz * m.damping))
        .fold(0.0, f64::max);
    (10.0 * slowest * fs_hz).ceil().max(1.0)
}

/// Simulates `samples` samples at `fs_hz` of the model's points under unit-variance white
/// forces (per simulation step) at every point, plus measurement noise of standard deviation
/// `noise` relative to the record's RMS, seeded. Returns one record per point.
pub fn simulate(
    model: &FieldModel,
    fs_hz: f64,
    samples: usize,
    noise: f64,
    seed: u64,
) -> Vec<Vec<f64>> {
    let k = model.points;
    let mut out = vec![Vec::with_capacity(samples); k];
    let mut rng = run(model, fs_hz, samples, seed, SUB, |s, disp| {
        if s > 0 {
            for (o, &v) in out.iter_mut().zip(disp) {
                o.push(v);
            }
        }
    });
    if noise > 0.0 {
        let normal = Normal::new(0.0, 1.0).expect("unit normal");
        for o in out.iter_mut() {
            let rms = (o.iter().map(|v| v * v).sum::<f64>() / o.len().max(1) as f64).sqrt();
            for v in o.iter_mut() {
                *v += noise * rms * normal.sample(&mut rng);
            }
        }
    }
    out
}

/// Simulation steps per sample: the force is held over a step of `1 / (16 fs)`.
pub const SUB: usize = 16;

/// The motion at every simulation step (`SUB` per sample), for a camera that integrates over
/// its exposure: one record per point, `(samples + 1) * SUB + 1` steps long, where sample `k`
/// of [`simulate`] (same model, rate and seed, no noise) is step `SUB + k * SUB`: one sample
/// period of motion either side of the samples. The same forces as [`simulate`] up to its last
/// sample.
pub fn simulate_fine(model: &FieldModel, fs_hz: f64, samples: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut out = vec![Vec::with_capacity((samples + 1) * SUB + 1); model.points];
    run(model, fs_hz, samples + 1, seed, 1, |_, disp| {
        for (o, &v) in out.iter_mut().zip(disp) {
            o.push(v);
        }
    });
    out
}

/// Runs the model after its settling run (ten of the slowest mode's decay times, discarded)
/// for `samples` sample periods, calling `keep(s, disp)` with the displacement at every
/// point at every `every`-th step `s = 0 ..= samples * SUB` counted from the settling run's
/// last sample (`s % SUB == 0` at the samples). Returns the random stream (for the
/// measurement noise).
fn run(
    model: &FieldModel,
    fs_hz: f64,
    samples: usize,
    seed: u64,
    every: usize,
    mut keep: impl FnMut(usize, &[f64]),
) -> ChaCha8Rng {
    let dt = 1.0 / (fs_hz * SUB as f64);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let normal = Normal::new(0.0, 1.0).expect("unit normal");
    let k = model.points;
    // per mode the exact step of the held input: x+ = A x + B u, x = (q, q')
    let steps: Vec<([f64; 4], [f64; 2])> = model
        .modes
        .iter()
        .map(|m| {
            let w = 2.0 * PI * m.f_hz;
            let z = m.damping;
            let wd = w * (1.0 - z * z).sqrt();
            let e = (-z * w * dt).exp();
            let (c, s) = ((wd * dt).cos(), (wd * dt).sin());
            let a = [
                e * (c + z * w / wd * s),
                e * s / wd,
                -e * w * w / wd * s,
                e * (c - z * w / wd * s),
            ];
            // B = A_c^-1 (A - I) (0, 1): q = (1 - a00) / w^2, q' = a10 / -w^2 ... from
            // A_c^-1 = [[-2 z / w, -1 / w^2], [1, 0]]
            let (a01, a11) = (a[1], a[3] - 1.0);
            let b = [-2.0 * z / w * a01 - a11 / (w * w), a01];
            (a, b)
        })
        .collect();
    let mut state = vec![[0.0f64; 2]; model.modes.len()];
    let mut force = vec![0.0; k];
    let mut disp = vec![0.0; k];
    let settle = settling_periods(model, fs_hz) as usize;
    let start = settle * SUB;
    for n in 0..settle + samples {
        for sub in 0..SUB {
            force.iter_mut().for_each(|f| *f = normal.sample(&mut rng));
            for ((x, (a, b)), m) in state.iter_mut().zip(&steps).zip(&model.modes) {
                let u: f64 = m.shape.iter().zip(&force).map(|(p, f)| p * f).sum();
                *x = [
                    a[0] * x[0] + a[1] * x[1] + b[0] * u,
                    a[2] * x[0] + a[3] * x[1] + b[1] * u,
                ];
            }
            let g = n * SUB + sub + 1;
            if g >= start && (g - start).is_multiple_of(every) {
                for (j, d) in disp.iter_mut().enumerate() {
                    *d = model
                        .modes
                        .iter()
                        .zip(&state)
                        .map(|(m, x)| m.shape[j] * x[0])
                        .sum();
                }
                keep(g - start, &disp);
            }
        }
    }
    rng
}

/// One line per mode: `1.5000 Hz (1.0 %), ...`.
pub fn modes_line(model: &FieldModel) -> String {
    model
        .modes
        .iter()
        .map(|m| format!("{:.4} Hz ({:.1} %)", m.f_hz, 100.0 * m.damping))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shear_frame_modes_solve_its_eigenproblem() {
        // K phi = w^2 phi for the fixed-free chain with unit masses and stiffness k
        let model = shear_frame(5, 1.5, &[0.01]);
        let w1 = 2.0 * PI * 1.5;
        let theta1 = PI / 22.0;
        let k = (w1 / (2.0 * theta1.sin())).powi(2);
        for m in &model.modes {
            let p = &m.shape;
            let w2 = (2.0 * PI * m.f_hz).powi(2);
            for j in 0..5 {
                let below = if j == 0 { 0.0 } else { p[j - 1] };
                let above = if j == 4 { p[j] } else { p[j + 1] };
                let kp = k * (2.0 * p[j] - below - above);
                assert!((kp - w2 * p[j]).abs() < 1e-9 * k, "{j}: {kp} {}", w2 * p[j]);
            }
            let norm: f64 = p.iter().map(|v| v * v).sum();
            assert!((norm - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn the_fine_motion_passes_through_the_samples() {
        let model = FieldCase::CloseModes.model();
        let coarse = simulate(&model, 30.0, 200, 0.0, 3);
        let fine = simulate_fine(&model, 30.0, 200, 3);
        for (c, f) in coarse.iter().zip(&fine) {
            assert_eq!(f.len(), 201 * SUB + 1);
            for (k, v) in c.iter().enumerate() {
                assert_eq!(*v, f[SUB + k * SUB], "sample {k}");
            }
            // and moves in between (not a held copy of the samples)
            assert_ne!(f[SUB + 1], f[SUB]);
        }
    }

    #[test]
    fn one_mode_decays_as_its_damping_says() {
        // the held-input step against the closed-form free decay of an SDOF
        let model = FieldModel {
            points: 1,
            modes: vec![FieldMode {
                f_hz: 3.0,
                damping: 0.02,
                shape: vec![1.0],
            }],
        };
        let r = simulate(&model, 50.0, 20_000, 0.0, 7);
        // the variance of the response to white force: 1 / (4 zeta w^3) per unit force
        // spectral density (force variance 1 per step of dt: density dt)
        let dt = 1.0 / (50.0 * 16.0);
        let w = 2.0 * PI * 3.0;
        let want = dt / (4.0 * 0.02 * w.powi(3));
        let got = r[0].iter().map(|v| v * v).sum::<f64>() / r[0].len() as f64;
        assert!((got / want - 1.0).abs() < 0.15, "{got} {want}");
    }
}
