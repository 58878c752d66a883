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
    let (n, m) = crate::analysis::columns::upsample(&crate::analysis::columns::UpsampleRequest {
        input: args.input.clone(),
        col: args.col.clone(),
        from_hz: args.from_hz,
        to_hz: args.to_hz,
        out: args.out.clone(),
    })?;
    eprintln!(
        "upsampled {n} samples at {} Hz to {m} samples at {} Hz -> {}",
        args.from_hz,
        args.to_hz,
        args.out.display()
    );
    Ok(())
}
