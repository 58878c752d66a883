//! A synthetic recording's own files: `recording.toml` (serde, `toml::to_string`) and
//! `accel.csv` (the transducer record the frames go with).

use anyhow::Context as _;
use std::fmt::Write as _;

/// One mode of the simulated structure in `recording.toml` (`[[modes]]`): the cantilever's
/// participation `g_phi` or the grandstand's modal mass, whichever the rig has.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ModeRow {
    /// Natural frequency, Hz.
    pub f_hz: f64,
    /// Damping ratio.
    pub zeta: f64,
    /// Cantilever: participation times tip shape.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub g_phi: Option<f64>,
    /// Grandstand: modal mass, kg.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mass_kg: Option<f64>,
}

/// The true shape of one mode across the targets (`[[target_shapes]]`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct TargetShape {
    /// Mode number, from 1.
    pub mode: usize,
    /// Per target, relative to the tip, unit largest modulus.
    pub shape: Vec<f64>,
}

/// Everything `recording.toml` states: the run's parameters, the rig's, the targets' (when
/// several) and the modes; written by `toml::to_string` (keys before tables).
#[derive(Debug, Clone, serde::Serialize)]
pub struct RecordingToml {
    /// `cantilever` or `grandstand`.
    pub preset: &'static str,
    /// Seed of the run.
    pub seed: u64,
    /// Exposure, ms.
    pub exposure_ms: f64,
    /// Frame rate, Hz.
    pub fps: f64,
    /// Transducer rate, Hz.
    pub fs: f64,
    /// Frames.
    pub frames: usize,
    /// Transducer samples.
    pub samples: usize,
    /// Scale, mm per pixel.
    pub mm_per_px: f64,
    /// Target radius, px.
    pub radius_px: f64,
    /// Target grey level.
    pub level: f64,
    /// Target edge sigma, px.
    pub edge_sigma_px: f64,
    /// What is painted on the target (`plain` or `speckle`).
    pub texture: &'static str,
    /// Threshold of the `README.txt` command.
    pub threshold: u16,
    /// Frame width and height, px.
    pub frame_size: [usize; 2],
    /// Read noise, grey levels.
    pub read_noise: f64,
    /// Cantilever: excitation band, Hz.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub band_hz: Option<[f64; 2]>,
    /// Cantilever: tip motion, mm peak to peak.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tip_pp_mm: Option<f64>,
    /// Cantilever: accelerometer noise, g RMS.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub accel_noise_g: Option<f64>,
    /// Cantilever standing upright: the tip accelerometer's tilt gain.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub accel_tilt_gain: Option<f64>,
    /// Cantilever standing upright: its length, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beam_length_m: Option<f64>,
    /// Grandstand: force peak, N.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub f0_n: Option<f64>,
    /// Grandstand: pulse rate, 1/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha: Option<f64>,
    /// Grandstand: pulse start, s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub t0_s: Option<f64>,
    /// Grandstand: process noise, N.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub process_noise_n: Option<f64>,
    /// Grandstand: load cell SNR.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub force_snr: Option<f64>,
    /// Grandstand: accelerometer SNR.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub accel_snr: Option<f64>,
    /// Several targets: how many.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub targets: Option<usize>,
    /// Several targets: their positions along the beam, `x / L`, left to right.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_xi: Option<Vec<f64>>,
    /// Several targets: their columns in the frame, px.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_x_px: Option<Vec<f64>>,
    /// The modes of the structure.
    pub modes: Vec<ModeRow>,
    /// Several targets: the true shapes.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub target_shapes: Vec<TargetShape>,
}

impl RecordingToml {
    /// The file's text: a comment line, then `toml::to_string`.
    pub fn to_text(&self) -> anyhow::Result<String> {
        let body = toml::to_string(self).context("cannot write recording.toml")?;
        Ok(format!(
            "# synthetic recording written by host-harness render --recording\n{body}"
        ))
    }
}

/// `accel.csv`: `t_s,INPUT,tip_acc` (`INPUT` `base_acc` or `force_n`, the rig's input column),
/// one row per sample of `(input, tip)` at `fs` Hz.
pub fn accel_csv(input_col: &str, (input, tip): (&[f64], &[f64]), fs: f64) -> String {
    let mut csv = format!("t_s,{input_col},tip_acc\n");
    for (j, (b, t)) in input.iter().zip(tip).enumerate() {
        let _ = writeln!(csv, "{},{b},{t}", j as f64 / fs);
    }
    csv
}

/// `truth.csv` of a recording with targets: per frame and target, the exact exposure-averaged
/// position of the target's centre, px (origin at the centre of the top-left pixel, x right,
/// y down): `truth[k][t] = (x, y)`.
pub fn truth_csv(truth: &[Vec<(f64, f64)>]) -> String {
    let mut csv = String::from("frame,target,x_px,y_px\n");
    for (k, row) in truth.iter().enumerate() {
        for (t, (x, y)) in row.iter().enumerate() {
            let _ = writeln!(csv, "{k},{},{x},{y}", t + 1);
        }
    }
    csv
}
