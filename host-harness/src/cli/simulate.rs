//! `host-harness simulate-field`: a synthetic field record ([`crate::model::field`]): the
//! displacements of a structure's points under a broadband random force, and the true modes.

use crate::model::field::{simulate, FieldCase};
use std::path::PathBuf;

/// Arguments of `host-harness simulate-field`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The structure: a five-storey shear frame (five modes, 1.5 to 10.1 Hz) or two modes
    /// 2 % apart and a third (2.00, 2.04, 5.00 Hz), five points each.
    #[arg(long, value_enum, default_value_t = CaseArg::ShearFrame)]
    pub case: CaseArg,
    /// Record length, minutes (> 0).
    #[arg(long, value_name = "MIN", default_value_t = 30.0)]
    pub minutes: f64,
    /// Sample rate (the camera's frame rate), Hz.
    #[arg(long, value_name = "HZ", default_value_t = 60.0)]
    pub fps: f64,
    /// Measurement noise, relative to each record's RMS.
    #[arg(long, value_name = "REL", default_value_t = 0.02)]
    pub noise: f64,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output directory (created): displacement.csv (`t_s,1,...,5`) and truth.csv
    /// (`mode,f_hz,damping,target,shape`).
    #[arg(long, value_name = "DIR", default_value = "field")]
    pub out: PathBuf,
    /// Replace --out if it is an earlier output of `simulate-field`.
    #[arg(long)]
    pub force: bool,
}

/// `--case`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CaseArg {
    /// Five-storey shear frame.
    ShearFrame,
    /// Two close modes and a third.
    CloseModes,
}

/// Runs `host-harness simulate-field`.
pub fn run(args: Args) -> anyhow::Result<()> {
    for (name, v) in [("--minutes", args.minutes), ("--fps", args.fps)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(crate::bad_input(format!(
                "{name} must be positive, got {v}"
            )));
        }
    }
    if !(args.noise.is_finite() && args.noise >= 0.0) {
        return Err(crate::bad_input(format!(
            "--noise must be >= 0, got {}",
            args.noise
        )));
    }
    let case = match args.case {
        CaseArg::ShearFrame => FieldCase::ShearFrame,
        CaseArg::CloseModes => FieldCase::CloseModes,
    };
    let model = case.model();
    let n = (args.minutes * 60.0 * args.fps).round() as usize;
    let rec = simulate(&model, args.fps, n, args.noise, args.seed);
    let report = crate::model::field::write_field(&args.out, args.force, &model, &rec, args.fps)?;
    super::stdout(&report)
}
