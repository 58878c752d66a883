//! `host-harness calibrate`: fits a study's unreported imaging knobs to observed figures
//! ([`crate::calibrate`]); prints the fit and writes `parameters.csv`, `residuals.csv`,
//! `evaluations.csv` and `fitted.toml` (a study file that uses the fitted values), each atomically.

use crate::bad_input;
use crate::calibrate::{self, Free};
use crate::study::{Preset, StudyConfig};
use std::path::PathBuf;

/// Arguments of `host-harness calibrate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Observed figures: CSV `rig,mode,exposure_ms,quantity,value[,u][,unit]` (`quantity` one
    /// of mu_a, sigma_a, mu_f, ratio_to_first, chi_mu, chi_sigma; a chi row's `unit` is
    /// `percent` or `fraction`, never guessed); only the rows of the study's rig are used.
    #[arg(long, value_name = "FILE.csv")]
    pub observed: PathBuf,
    /// The study to calibrate (TOML, as `study --config`); its `[imaging]` and `[rig]` values not set free
    /// stay as they are. Default: the preset's.
    #[arg(long, value_name = "FILE.toml", conflicts_with = "preset")]
    pub config: Option<PathBuf>,
    /// The rig, when no --config is given.
    #[arg(long, default_value = "grandstand", value_parser = super::args::choice(&Preset::ALL, Preset::name))]
    pub preset: Preset,
    /// A free parameter and its range, NAME=LO:HI (repeat): target_radius_px,
    /// target_edge_sigma_px, threshold_frac, read_noise, optical_blur_sigma_px, gain,
    /// tip_rotation_lever, beam_length_m (`[rig]`; the config must set beam_orientation),
    /// epsa_images (whole numbers from 2: the sharp images averaged per exposure).
    #[arg(long = "free", value_name = "NAME=LO:HI", required = true, value_parser = calibrate::parse_free)]
    pub free: Vec<Free>,
    /// Runs per evaluation (the same runs every time: common random numbers).
    #[arg(long, default_value_t = 40, value_parser = clap::value_parser!(u64).range(2..))]
    pub runs: u64,
    /// Grid points per free parameter in the coarse search (ends included, >= 2).
    #[arg(long, default_value_t = 4, value_parser = super::args::int_range(2..=10_000))]
    pub grid: usize,
    /// Rounds of the local pattern search after the grid.
    #[arg(long, default_value_t = 8)]
    pub refine: usize,
    /// Output directory.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

/// Runs `calibrate`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let base = match &args.config {
        Some(path) => StudyConfig::from_toml_file(path)?,
        None => StudyConfig::preset(args.preset),
    };
    // --runs >= 2 and --grid >= 2 are checked by their value parsers
    let points = args.grid.checked_pow(args.free.len() as u32);
    if points.is_none_or(|p| p > 10_000) {
        return Err(bad_input(format!(
            "--grid {}: between 2 and a grid of at most 10 000 points over the {} free parameters",
            args.grid,
            args.free.len()
        )));
    }
    let mut inputs = vec![args.observed.as_path()];
    inputs.extend(args.config.as_deref());
    for f in [
        "fitted.toml",
        "parameters.csv",
        "residuals.csv",
        "evaluations.csv",
    ] {
        crate::outdir::refuse_overwriting_input(&args.out.join(f), &inputs)?;
    }
    for (i, f) in args.free.iter().enumerate() {
        if args.free[..i].iter().any(|g| g.knob == f.knob) {
            return Err(bad_input(format!(
                "--free {}: given twice; each knob is fitted once",
                f.knob.name()
            )));
        }
    }
    let summary = calibrate::run(&calibrate::Request {
        base,
        observed: args.observed.clone(),
        free: args.free.clone(),
        runs: args.runs,
        grid: args.grid,
        refine: args.refine,
        out: args.out.clone(),
    })?;
    super::stdout(&summary)
}
