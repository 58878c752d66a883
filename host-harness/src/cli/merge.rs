//! `host-harness merge`: combine the directories of `study --shard K/N` runs.

use crate::bad_input;
use crate::study::{self, files, StudyConfig};
use anyhow::Context as _;
use std::path::PathBuf;

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
}

/// Runs `host-harness merge`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let mut cfg: Option<StudyConfig> = None;
    let mut revision: Option<u32> = None;
    let mut records = Vec::new();
    for dir in &args.dirs {
        // runs of two code revisions must not be mixed (see study::MODEL_REVISION)
        let rev = study::recorded_revision(dir)?;
        match revision {
            None => revision = Some(rev),
            Some(first) if first != rev => {
                return Err(bad_input(format!(
                    "{}: runs of model revision {rev}, but {} holds revision {first}; only \
                     shards computed by the same code can be merged",
                    dir.display(),
                    args.dirs[0].display()
                )))
            }
            _ => {}
        }
        let p = dir.join(files::CONFIG);
        let text = std::fs::read_to_string(&p)
            .map_err(|e| bad_input(format!("cannot read {}: {e}", p.display())))?;
        let c: StudyConfig =
            toml::from_str(&text).map_err(|e| bad_input(format!("{}: {e}", p.display())))?;
        match &cfg {
            None => cfg = Some(c),
            Some(first) if *first != c => {
                return Err(bad_input(format!(
                    "{}: configuration differs from {}; only shards of one study can be merged",
                    p.display(),
                    args.dirs[0].join(files::CONFIG).display()
                )))
            }
            _ => {}
        }
        records.extend(study::read_checkpoint(&dir.join(files::RUNS))?);
    }
    let cfg = cfg.ok_or_else(|| bad_input("no directories to merge"))?;
    records.sort_by_key(|r| r.run);
    if let Some(w) = records.windows(2).find(|w| w[0].run == w[1].run) {
        return Err(bad_input(format!(
            "run {} appears in more than one directory",
            w[0].run
        )));
    }
    let missing: Vec<u64> = (0..cfg.runs)
        .filter(|r| records.binary_search_by_key(r, |x| x.run).is_err())
        .collect();
    if !missing.is_empty() {
        return Err(bad_input(format!(
            "{} of {} runs are missing (first: run {}); finish the shards (study --resume) before merging",
            missing.len(),
            cfg.runs,
            missing[0]
        )));
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    if args.out.join(files::RUNS).exists() {
        return Err(bad_input(format!(
            "{} already holds a study; choose another --out",
            args.out.display()
        )));
    }
    std::fs::write(args.out.join(files::CONFIG), cfg.to_toml())?;
    if let Some(rev) = revision {
        std::fs::write(args.out.join(files::REVISION), format!("{rev}\n"))?;
    }
    let mut lines = String::new();
    for r in &records {
        lines.push_str(&serde_json::to_string(r)?);
        lines.push('\n');
    }
    std::fs::write(args.out.join(files::RUNS), lines)?;
    let scenario = study::scenario_for(&cfg)?;
    eprintln!(
        "merged {} runs from {} directories",
        records.len(),
        args.dirs.len()
    );
    super::study::finish(&cfg, scenario.as_ref(), &records, &args.out, !args.no_plots)
}
