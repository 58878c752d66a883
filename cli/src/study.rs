//! `host-harness study` and `vibcam-study`: run a Monte Carlo study and write its outputs.

use std::path::PathBuf;
use vibcam_sim::study::{self, Execution, Preset, Shard, StudyConfig};

/// Arguments of `host-harness study`. Without arguments: the grandstand preset at a run count
/// that finishes in about a minute on two cores.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scenario preset (ignored fields come from it).
    #[arg(long, conflicts_with = "config", value_parser = crate::flags::choice(&Preset::ALL, Preset::name))]
    pub preset: Option<Preset>,
    /// Study file (TOML) with the fields of the resolved `config.toml`; flags override it.
    #[arg(long, value_name = "FILE.toml")]
    pub config: Option<PathBuf>,
    /// Number of Monte Carlo runs [default: 100, both presets; the paper used 1000]. With
    /// --adaptive: the most runs the procedure may take.
    #[arg(long)]
    pub runs: Option<u64>,
    /// Exposure times in ms, comma separated [default: grandstand 40,60,...,180; cantilever
    /// 2,4,6].
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub exposures_ms: Option<Vec<f64>>,
    /// Master seed [default: 1]; the same seed gives identical numbers whatever the thread
    /// count or sharding.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Method-uncertainty variant: modal parameters fixed at their means, only excitation and
    /// transducer noise vary (paper section 4.4).
    #[arg(long)]
    pub fixed_structure: bool,
    /// `$threads`.
    #[arg(long, default_value = crate::flags::given("threads"), value_parser = crate::flags::whole::<usize>("threads"), help = crate::flags::help("threads"))]
    pub threads: usize,
    /// Output directory. Default: `out/<preset>-<config hash>`, resumed automatically when
    /// it exists (running the same command twice re-reports the finished study).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Continue an interrupted study in --out: runs already in its runs.jsonl are kept (implied
    /// when --out is not given).
    #[arg(long)]
    pub resume: bool,
    /// Compute only shard K of N (runs r with r mod N = K-1); combine with `host-harness merge`.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// Do not write the PNG/SVG figures.
    #[arg(long)]
    pub no_plots: bool,
    /// Coverage probability of the intervals (JCGM 101 7.7) in summary.csv and coverage.csv;
    /// the column names keep "95" (default 0.95).
    #[arg(long, value_name = "P", value_parser = crate::flags::parse_coverage)]
    pub coverage: Option<f64>,
    /// Adaptive Monte Carlo (JCGM 101 7.9): batches of runs until every reported quantity
    /// (or the --adaptive-on one) is stable to --digits; --runs is then the cap.
    #[arg(long, requires = "digits")]
    pub adaptive: bool,
    /// Significant digits wanted in the standard uncertainties (with --adaptive).
    #[arg(long, value_name = "ND", requires = "adaptive")]
    pub digits: Option<u32>,
    /// Runs per batch (with --adaptive; default max(100/(1-p), 10^4) as JCGM 101 7.9.4 b).
    #[arg(long, value_name = "M", requires = "adaptive")]
    pub batch: Option<u64>,
    /// The one quantity that decides, SYSTEM:MODE:a|f (e.g. vision:2:a; every exposure).
    #[arg(long, value_name = "SYSTEM:MODE:Q", requires = "adaptive")]
    pub adaptive_on: Option<String>,
}

/// Resolves the configuration from preset, study file and flags.
pub fn resolve(args: &Args) -> anyhow::Result<StudyConfig> {
    let mut cfg = match &args.config {
        Some(p) => StudyConfig::from_toml_file(p)?,
        None => StudyConfig::preset(args.preset.unwrap_or(Preset::Grandstand)),
    };
    if let Some(r) = args.runs {
        cfg.runs = r;
    }
    if let Some(e) = &args.exposures_ms {
        cfg.exposures_ms = e.clone();
    }
    if let Some(s) = args.seed {
        cfg.seed = s;
    }
    if args.fixed_structure {
        cfg.fixed_structure = true;
    }
    if let Some(p) = args.coverage {
        cfg.coverage = p;
    }
    if args.adaptive {
        set_adaptive(args, &mut cfg)?;
    }
    cfg.validate()?;
    Ok(cfg)
}

/// The adaptive settings from the flags: the standard's batch size unless `--batch` (a smaller
/// one is said), the run cap `--runs` or a thousand batches (at most `MAX_RUNS`).
fn set_adaptive(args: &Args, cfg: &mut StudyConfig) -> anyhow::Result<()> {
    let standard =
        vibcam_common::uncertainty::default_batch_size(cfg.coverage).unwrap_or(10_000) as u64;
    let batch = args.batch.unwrap_or(standard);
    if batch < standard {
        eprintln!(
            "note: --batch {batch} is smaller than JCGM 101 7.9.4 b's {standard} runs per batch \
             (allowed; the batch values scatter more, so the criterion is checked more often)"
        );
    }
    if batch == 0 {
        return Err(vibcam_readers::bad_input("--batch: must be at least 1"));
    }
    if args.runs.is_none() {
        cfg.runs = (study::config::MAX_RUNS / batch).min(1000) * batch;
    }
    cfg.adaptive = Some(study::adaptive::AdaptiveConfig {
        digits: args.digits.unwrap_or(1),
        batch,
        on: args.adaptive_on.clone(),
    });
    Ok(())
}

/// `out/<preset>-<hash of the resolved configuration and the model revision>[-shard-K-of-N]`.
pub fn default_out(cfg: &StudyConfig, shard: Shard) -> PathBuf {
    // FNV-1a 64 of the resolved configuration's TOML and the model revision: stable across
    // runs and platforms; a new code revision starts a new directory instead of resuming
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    // the run count too: studies of other lengths get directories of their own
    let key = study::StudyConfig {
        runs: cfg.runs,
        ..cfg.runs_key()
    };
    let text = format!(
        "{}model_revision = {}\n",
        key.to_toml(),
        study::MODEL_REVISION
    );
    for b in text.bytes() {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    let preset = match cfg.preset {
        Preset::Grandstand => "grandstand",
        Preset::Cantilever => "cantilever",
    };
    let mut name = format!("{preset}-{:08x}", h >> 32);
    if shard != Shard::ALL {
        name.push_str(&format!("-shard-{}-of-{}", shard.index, shard.count));
    }
    PathBuf::from("out").join(name)
}

/// Runs `host-harness study`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let cfg = resolve(&args)?;
    let shard = match &args.shard {
        Some(s) => Shard::parse(s)?,
        None => Shard::ALL,
    };
    // Without --out, the directory is named after the configuration, so running the same
    // command again resumes (or just re-reports) that study instead of refusing to overwrite,
    // and a different configuration never mixes with it.
    let (out, resume) = match &args.out {
        Some(o) => (o.clone(), args.resume),
        None => (default_out(&cfg, shard), true),
    };
    let scenario = study::scenario_for(&cfg)?;
    eprintln!(
        "{} study: {}{} runs x {} exposures ({} ms), seed {}{}{} -> {}",
        scenario.name(),
        match &cfg.adaptive {
            Some(a) => format!("adaptive in batches of {}, at most ", a.batch),
            None => String::new(),
        },
        cfg.runs,
        cfg.exposures_ms.len(),
        cfg.exposures_ms
            .iter()
            .map(|e| e.to_string())
            .collect::<Vec<_>>()
            .join(","),
        cfg.seed,
        if cfg.fixed_structure {
            ", fixed structure"
        } else {
            ""
        },
        if shard == Shard::ALL {
            String::new()
        } else {
            format!(", shard {}/{}", shard.index, shard.count)
        },
        out.display()
    );
    let started = std::time::Instant::now();
    let exec = Execution {
        out: out.clone(),
        resume,
        threads: args.threads,
        shard,
        progress: true,
    };
    let done = study::execute(&cfg, scenario.as_ref(), &exec)?;
    let elapsed = started.elapsed();
    let text = study::finish(&cfg, scenario.as_ref(), &done.records, &out, !args.no_plots)?;
    crate::process::stdout(&text)?;
    eprintln!(
        "{} runs computed in {:.1} s ({} in the study)",
        done.computed,
        elapsed.as_secs_f64(),
        done.records.len()
    );
    if shard != Shard::ALL {
        eprintln!(
            "this is shard {}/{}: combine all shard directories with `host-harness merge DIR... --out DIR`",
            shard.index, shard.count
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_directory_is_named_after_the_configuration() {
        let a = StudyConfig::preset(Preset::Grandstand);
        let mut b = a.clone();
        b.runs += 1;
        assert_eq!(
            default_out(&a, Shard::ALL),
            default_out(&a.clone(), Shard::ALL)
        );
        assert_ne!(default_out(&a, Shard::ALL), default_out(&b, Shard::ALL));
        let s = Shard { index: 2, count: 3 };
        assert!(default_out(&a, s)
            .to_string_lossy()
            .ends_with("-shard-2-of-3"));
        assert!(default_out(&a, Shard::ALL)
            .to_string_lossy()
            .starts_with("out/grandstand-"));
    }
}
