//! `host-harness merge`: combine the directories of `study --shard K/N` runs.

use std::path::PathBuf;
use vibcam_sim::study;

/// Arguments of `host-harness merge`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Shard output directories (each written by `study --shard K/N --out DIR`).
    #[arg(required = true, value_name = "DIR")]
    pub dirs: Vec<PathBuf>,
    /// Output directory of the merged study.
    #[arg(long)]
    pub out: PathBuf,
    /// Do not write the PNG/SVG figures.
    #[arg(long)]
    pub no_plots: bool,
    /// Coverage probability of the intervals (default: the shards' one).
    #[arg(long, value_name = "P", value_parser = crate::flags::parse_coverage)]
    pub coverage: Option<f64>,
}

/// Runs `host-harness merge`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let mut merged = study::merge::read_shards(&args.dirs)?;
    if let Some(p) = args.coverage {
        merged.config.coverage = p;
    }
    study::merge::write_merged(&args.out, &merged)?;
    let scenario = study::scenario_for(&merged.config)?;
    eprintln!(
        "merged {} runs from {} directories",
        merged.records.len(),
        args.dirs.len()
    );
    let text = study::finish(
        &merged.config,
        scenario.as_ref(),
        &merged.records,
        &args.out,
        !args.no_plots,
    )?;
    crate::process::stdout(&text)
}
