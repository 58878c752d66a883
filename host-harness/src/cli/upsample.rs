//! `host-harness upsample`: one CSV column read, upsampled by [`crate::chain::resample`]
//! (firmware-core's upsampler), written as `t_s,value`.

use crate::bad_input;
use std::path::PathBuf;

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
    let up = crate::chain::resample::upsample_column(raw, args.from_hz, args.to_hz)?;
    let (n, m) = (raw.len(), up.values.len());
    let mut text = String::from("t_s,value\n");
    for (k, v) in up.values.iter().enumerate() {
        let t = k as f64 / args.to_hz;
        if up.scale == 1.0 {
            text.push_str(&format!("{t},{v}\n"));
        } else {
            text.push_str(&format!("{t},{}\n", *v as f64 * up.scale));
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
