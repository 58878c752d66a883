//! `host-harness upsample`: Fourier upsampling of one CSV column through firmware-core's
//! upsampler (f32, method.md §2.2, the convention of `scipy.signal.resample`).

use crate::bad_input;
use anyhow::Context as _;
use firmware_core::upsample::Upsampler;
use std::path::PathBuf;

/// Largest output length this command handles (the host instantiation's capacity).
pub const MAX_OUTPUT: usize = 1 << 16;

/// Largest input magnitude taken into the f32 core as it is: its transform (sums over up to
/// 65 536 values, times the window of the output) stays far from `f32::MAX` (3.4e38).
const F32_SAFE: f64 = 1e30;

type HostUpsampler = Upsampler<MAX_OUTPUT, { 2 * MAX_OUTPUT + 256 }>;

/// Arguments of `host-harness upsample`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Input CSV file with a header row.
    #[arg(long)]
    pub input: PathBuf,
    /// Column to upsample (header name).
    #[arg(long)]
    pub col: String,
    /// Sampling rate of the input, Hz.
    #[arg(long = "from", value_name = "HZ")]
    pub from_hz: f64,
    /// Output sampling rate, Hz (`N * to / from` must be an integer number of samples).
    #[arg(long = "to", value_name = "HZ")]
    pub to_hz: f64,
    /// Output CSV file (`t_s,value`).
    #[arg(long)]
    pub out: PathBuf,
}

/// Output length `n * to / from` if it is an integer (within 1e-9 relative).
fn output_len(n: usize, from: f64, to: f64) -> Option<usize> {
    if !(from.is_finite() && to.is_finite() && from > 0.0 && to > 0.0) {
        return None;
    }
    let m = n as f64 * to / from;
    let r = m.round();
    ((m - r).abs() <= 1e-9 * m.max(1.0) && r >= 1.0).then_some(r as usize)
}

/// Runs `host-harness upsample`.
pub fn run(args: Args) -> anyhow::Result<()> {
    for (flag, hz) in [("--from", args.from_hz), ("--to", args.to_hz)] {
        if !(hz.is_finite() && hz > 0.0) {
            return Err(bad_input(format!(
                "{flag}: must be a positive sample rate in Hz, got {hz}"
            )));
        }
    }
    crate::outdir::refuse_overwriting_input(&args.out, &[&args.input])?;
    let cols = crate::csvio::read_columns(&args.input, &[args.col.as_str()])?;
    let raw = &cols.values[0];
    if let Some((i, v)) = raw.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(bad_input(format!(
            "{}: row {}: `{}` is {v}, not a finite number",
            args.input.display(),
            i + 2,
            args.col
        )));
    }
    // firmware-core computes in f32: values whose transform could overflow it are scaled by
    // a power of two (exact) into range and scaled back in f64 for the output
    let peak = raw.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let scale = if peak > F32_SAFE {
        2f64.powi(peak.log2().ceil() as i32)
    } else {
        1.0
    };
    let x: Vec<f32> = raw.iter().map(|v| (*v / scale) as f32).collect();
    let n = x.len();
    let m = output_len(n, args.from_hz, args.to_hz).ok_or_else(|| {
        bad_input(format!(
            "--from {} / --to {}: {n} samples at {} Hz do not make an integer number of samples at {} Hz",
            args.from_hz, args.to_hz, args.from_hz, args.to_hz
        ))
    })?;
    if m < n {
        return Err(bad_input(format!(
            "--to {} Hz is below --from {} Hz: this command only upsamples",
            args.to_hz, args.from_hz
        )));
    }
    if m > MAX_OUTPUT {
        return Err(bad_input(format!(
            "{m} output samples exceed this command's capacity of {MAX_OUTPUT}"
        )));
    }
    let y = std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(move || -> anyhow::Result<Vec<f32>> {
            let mut up = Box::new(
                HostUpsampler::try_new(n, m).map_err(|e| bad_input(format!("{n} -> {m}: {e}")))?,
            );
            let mut y = vec![0.0f32; m];
            up.process(&x, &mut y)
                .map_err(|e| anyhow::anyhow!("upsampling: {e}"))?;
            Ok(y)
        })
        .context("cannot start the worker thread")?
        .join()
        .map_err(|_| anyhow::anyhow!("the upsampling thread panicked"))??;
    let mut text = String::from("t_s,value\n");
    for (k, v) in y.iter().enumerate() {
        let t = k as f64 / args.to_hz;
        if scale == 1.0 {
            text.push_str(&format!("{t},{v}\n"));
        } else {
            text.push_str(&format!("{t},{}\n", *v as f64 * scale));
        }
    }
    crate::study::checkpoint::write_atomic(&args.out, text.as_bytes())?;
    eprintln!(
        "upsampled {n} samples at {} Hz to {m} samples at {} Hz -> {}",
        args.from_hz,
        args.to_hz,
        args.out.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_length_must_be_an_integer() {
        assert_eq!(output_len(1200, 120.0, 2048.0), Some(20480));
        assert_eq!(output_len(120, 120.0, 2048.0), Some(2048));
        assert_eq!(output_len(100, 120.0, 2048.0), None);
        assert_eq!(output_len(10, 0.0, 2048.0), None);
    }
}
