//! `host-harness calibrate`: fits a study's unreported imaging knobs to observed figures
//! ([`crate::calibrate`]); prints the fit and writes `parameters.csv`, `residuals.csv`,
//! `evaluations.csv` and `fitted.toml` (a study file that uses the fitted values), each atomically.

use crate::bad_input;
use crate::calibrate::{self, Free, Quantity};
use crate::study::checkpoint::write_atomic;
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
    #[arg(long, value_enum, default_value_t = Preset::Grandstand)]
    pub preset: Preset,
    /// A free parameter and its range, NAME=LO:HI (repeat): target_radius_px,
    /// target_edge_sigma_px, threshold_frac, read_noise, optical_blur_sigma_px, gain,
    /// tip_rotation_lever, beam_length_m (`[rig]`; the config must set beam_orientation).
    #[arg(long = "free", value_name = "NAME=LO:HI", required = true, value_parser = calibrate::parse_free)]
    pub free: Vec<Free>,
    /// Runs per evaluation (the same runs every time: common random numbers).
    #[arg(long, default_value_t = 40)]
    pub runs: u64,
    /// Grid points per free parameter in the coarse search (ends included, >= 2).
    #[arg(long, default_value_t = 4)]
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
    if args.runs < 2 {
        return Err(bad_input(format!(
            "--runs {}: at least 2 runs per evaluation",
            args.runs
        )));
    }
    if args.grid < 2 || args.grid.pow(args.free.len() as u32) > 10_000 {
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
    let (obs, other) = calibrate::read_observations(&args.observed, base.preset)?;
    let chi = obs
        .iter()
        .any(|o| matches!(o.quantity, Quantity::ChiMu | Quantity::ChiSigma));
    let needed = crate::uncertainty::min_values(base.coverage).unwrap_or(2) as u64;
    if chi && args.runs < needed {
        return Err(bad_input(format!(
            "--runs {}: the chi_mu/chi_sigma observations need the model's bootstrap \
             uncertainty, which needs at least {needed} runs per evaluation (coverage {})",
            args.runs, base.coverage
        )));
    }
    if other > 0 {
        eprintln!(
            "{}: {other} rows of another rig left out",
            args.observed.display()
        );
    }
    let mut small = base.clone();
    small.runs = args.runs;
    small.adaptive = None;
    eprintln!(
        "calibrate {}: {} observations, {} free parameters, {} runs per evaluation (seed {}), grid {} then {} refinement rounds",
        base.preset.name(),
        obs.len(),
        args.free.len(),
        args.runs,
        base.seed,
        args.grid,
        args.refine
    );
    let started = std::time::Instant::now();
    let mut count = 0;
    let fit = calibrate::search(&small, &args.free, &obs, (args.grid, args.refine), |e| {
        count += 1;
        let at: Vec<String> = args
            .free
            .iter()
            .zip(&e.x)
            .map(|(f, v)| format!("{}={v:.4}", f.knob.name()))
            .collect();
        eprintln!(
            "  evaluation {count}: {} -> chi2 {:.3}, objective {:.3} ({:.0} s)",
            at.join(" "),
            e.chi2,
            e.objective,
            started.elapsed().as_secs_f64()
        );
    })?;
    std::fs::create_dir_all(&args.out)
        .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", args.out.display()))?;
    let mut fitted = base.clone();
    for (f, v) in args.free.iter().zip(&fit.best.x) {
        let one = calibrate::config_at(&fitted, std::slice::from_ref(f), &[*v], &obs);
        (fitted.imaging, fitted.rig) = (one.imaging, one.rig);
    }
    let header = format!(
        "# fitted by `host-harness calibrate` to {} ({} observations, {} runs per evaluation)\n",
        args.observed.display(),
        obs.len(),
        args.runs
    );
    write_atomic(
        &args.out.join("fitted.toml"),
        (header + &fitted.to_toml()).as_bytes(),
    )?;
    write_atomic(
        &args.out.join("parameters.csv"),
        &calibrate::parameters_csv(&args.free, &fit),
    )?;
    write_atomic(
        &args.out.join("residuals.csv"),
        &calibrate::residuals_csv(&fit.best),
    )?;
    write_atomic(
        &args.out.join("evaluations.csv"),
        &calibrate::evaluations_csv(&args.free, &fit.evaluations),
    )?;
    println!(
        "fitted (chi2 {:.3}, objective {:.3}, over {} observations):",
        fit.best.chi2,
        fit.best.objective,
        obs.len()
    );
    for ((f, v), u) in args.free.iter().zip(&fit.best.x).zip(&fit.u) {
        let u = u.map_or("not determined (objective not convex there)".into(), |u| {
            format!("+/- {u:.4}")
        });
        println!(
            "  {:<22} {v:.4} {u}   (range {} .. {})",
            f.knob.name(),
            f.lo,
            f.hi
        );
    }
    println!("mode | exposure_ms | quantity       |   observed |      model | residual");
    for r in &fit.best.residuals {
        let o = &r.observed;
        println!(
            "{:>4} | {:>11} | {:<14} | {:>10.4} | {:>10.4} | {:>8.2}",
            o.mode,
            o.exposure_ms,
            o.quantity.name(),
            o.value,
            r.model,
            r.r
        );
    }
    println!(
        "wrote parameters.csv, residuals.csv, evaluations.csv and fitted.toml in {} ({} evaluations, {:.0} s)",
        args.out.display(),
        fit.evaluations.len(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
