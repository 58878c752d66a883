//! `host-harness simulate-hammer`: a synthetic impact hammer test
//! ([`crate::recording::hammer`]) to try `ema` on: the force at a DAQ's rate, five points'
//! displacements at a camera's, the true modes.

use crate::recording::hammer::{write_hammer_recording, HammerRecording};
use std::path::PathBuf;

/// Arguments of `host-harness simulate-hammer`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Record length, s (the hits come every 3 s from 0.2 s).
    #[arg(long, value_name = "S", default_value_t = 9.2)]
    pub seconds: f64,
    /// The force's rate (a DAQ), Hz.
    #[arg(long, value_name = "HZ", default_value_t = 50_000.0)]
    pub daq_hz: f64,
    /// The displacements' rate (a camera), Hz.
    #[arg(long, value_name = "HZ", default_value_t = 2_000.0)]
    pub camera_hz: f64,
    /// The hits' peak forces, N (one hit each, 3 s apart).
    #[arg(
        long,
        value_name = "N,...",
        value_delimiter = ',',
        default_value = "150,120,180"
    )]
    pub peaks_n: Vec<f64>,
    /// A rebound 4 ms after the second hit (a double hit).
    #[arg(long)]
    pub double_hit: bool,
    /// Clip the force channel at this level, N (a saturated transducer).
    #[arg(long, value_name = "N")]
    pub clip_n: Option<f64>,
    /// The force's noise, N (standard deviation).
    #[arg(long, value_name = "N", default_value_t = 0.3)]
    pub force_noise_n: f64,
    /// The displacements' noise, mm (standard deviation).
    #[arg(long, value_name = "MM", default_value_t = 0.0005)]
    pub camera_noise_mm: f64,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// A roving hammer: the points hit (of 1-5), one record each (`force_P.csv`,
    /// `camera_P.csv`), every one with the same hits (default: one record, hit at point 2).
    #[arg(long, value_name = "P,...", value_delimiter = ',')]
    pub hit_points: Vec<usize>,
    /// Output directory (created).
    #[arg(long, value_name = "DIR", default_value = "hammer")]
    pub out: PathBuf,
    /// Replace --out if it is an earlier output of `simulate-hammer`.
    #[arg(long)]
    pub force: bool,
}

/// The flags checked ([`hits_held`] too); the notes on what the record will hold.
fn check(a: &Args) -> anyhow::Result<Vec<String>> {
    let positive = |v: f64, flag: &str| -> anyhow::Result<()> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(crate::bad_input(format!(
                "{flag} must be positive, got {v}"
            )))
        }
    };
    positive(a.seconds, "--seconds")?;
    positive(a.daq_hz, "--daq-hz")?;
    positive(a.camera_hz, "--camera-hz")?;
    if a.seconds * a.daq_hz.max(a.camera_hz) > 2e7 {
        return Err(crate::bad_input(format!(
            "--seconds {} at {} Hz: more than 20 million samples",
            a.seconds,
            a.daq_hz.max(a.camera_hz)
        )));
    }
    let mut points = a.hit_points.clone();
    points.sort_unstable();
    if let Some(p) = points.iter().find(|&&p| !(1..=5).contains(&p)) {
        return Err(crate::bad_input(format!(
            "--hit-points: point {p} is not one of the structure's five (1-5)"
        )));
    }
    if let Some(w) = points.windows(2).find(|w| w[0] == w[1]) {
        return Err(crate::bad_input(format!(
            "--hit-points: point {} is given twice",
            w[0]
        )));
    }
    if a.peaks_n.is_empty() || a.peaks_n.iter().any(|p| !(p.is_finite() && *p > 0.0)) {
        return Err(crate::bad_input(
            "--peaks-n: positive forces, N".to_string(),
        ));
    }
    for (v, flag) in [
        (a.force_noise_n, "--force-noise-n"),
        (a.camera_noise_mm, "--camera-noise-mm"),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(crate::bad_input(format!("{flag} must be >= 0, got {v}")));
        }
    }
    hits_held(a)
}

/// The hits the record can hold, checked against the pulses' width and the record's length;
/// the notes on what it will hold.
fn hits_held(a: &Args) -> anyhow::Result<Vec<String>> {
    // the pulses are 0.6 ms wide: a DAQ must sample each several times or `ema` finds none
    const WIDTH_S: f64 = 0.0006;
    if a.daq_hz * WIDTH_S < 5.0 {
        return Err(crate::bad_input(format!(
            "--daq-hz {}: the hammer's pulses are {} ms wide, {:.2} samples at that rate; at \
             least 5 samples across a pulse need {} Hz or more",
            a.daq_hz,
            WIDTH_S * 1e3,
            a.daq_hz * WIDTH_S,
            (5.0 / WIDTH_S).ceil()
        )));
    }
    if let Some(c) = a.clip_n {
        if !(c.is_finite() && c > 0.0) {
            return Err(crate::bad_input(format!(
                "--clip-n must be a positive force, N, got {c}"
            )));
        }
    }
    if a.double_hit && a.peaks_n.len() < 2 {
        return Err(crate::bad_input(
            "--double-hit: the rebound follows the second hit; give two peaks or more \
             (--peaks-n)"
                .to_string(),
        ));
    }
    // hits every 3 s from 0.2 s; one needs the 0.5 s after it that `ema` takes as its block
    let hits_held = a
        .peaks_n
        .iter()
        .enumerate()
        .filter(|(i, _)| 0.2 + 3.0 * *i as f64 + 0.5 <= a.seconds)
        .count();
    if hits_held == 0 {
        return Err(crate::bad_input(format!(
            "--seconds {}: the first hit comes at 0.2 s and needs 0.5 s of response after it; \
             give --seconds 0.7 or more",
            a.seconds
        )));
    }
    let mut notes = Vec::new();
    if hits_held < a.peaks_n.len() {
        notes.push(format!(
            "note: the record holds {hits_held} of the {} hits (one every 3 s from 0.2 s, each \
             with 0.5 s after it)",
            a.peaks_n.len()
        ));
    }
    if let Some(c) = a.clip_n {
        let max = a.peaks_n.iter().copied().fold(0.0, f64::max);
        if c >= max {
            notes.push(format!(
                "note: --clip-n {c} N is above every hit's peak ({max} N): nothing is clipped"
            ));
        }
    }
    Ok(notes)
}

/// Runs `host-harness simulate-hammer`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let notes = check(&a)?;
    write_hammer_recording(
        &a.out,
        a.force,
        &HammerRecording {
            seconds: a.seconds,
            daq_hz: a.daq_hz,
            camera_hz: a.camera_hz,
            peaks_n: a.peaks_n,
            double_hit: a.double_hit,
            clip_n: a.clip_n,
            force_noise_n: a.force_noise_n,
            camera_noise_mm: a.camera_noise_mm,
            seed: a.seed,
            hit_points: a.hit_points.clone(),
        },
    )?;
    let mut text = String::new();
    for n in &notes {
        text.push_str(n);
        text.push('\n');
    }
    let records = if a.hit_points.is_empty() {
        "force.csv, camera.csv".to_string()
    } else {
        let p: Vec<String> = a.hit_points.iter().map(usize::to_string).collect();
        format!("force_P.csv and camera_P.csv for P = {}", p.join(", "))
    };
    text.push_str(&format!(
        "wrote {}: {records}, truth.csv, README.txt\n",
        a.out.display()
    ));
    super::stdout(&text)?;
    super::outputs_in(&a.out)
}
