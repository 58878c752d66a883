//! `host-harness modal`: output-only modal analysis (FDD, EFDD, SSI-cov or -dat) of a displacement
//! file ([`crate::analysis::oma`]): `track`'s `displacement.csv`, or a wide CSV from another
//! tool.

use super::args::{parse_bands, Bands, WelchArgs};
use crate::analysis::oma::bell::Quantity;
use crate::analysis::oma::input::PixelAxis;
use crate::analysis::oma::multi_setup::Merge;
use crate::analysis::oma::ssi::SsiKind;
use crate::jobs::{ModalInput, ModalSpec, SpecError};
use std::path::PathBuf;

/// Target numbers (1-based), as given.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Targets(pub Vec<usize>);

/// `T,...`: target numbers, each at least 1.
fn parse_targets(s: &str) -> Result<Targets, String> {
    let out: Vec<usize> = s
        .split(',')
        .map(|t| match t.trim().parse::<usize>() {
            Ok(n) if n >= 1 => Ok(n),
            _ => Err(format!("`{t}` is not a target number (1, 2, ...)")),
        })
        .collect::<Result<_, _>>()?;
    Ok(Targets(out))
}

/// `FILE:T,...`: a setup's file and its reference targets (split at the last `:`).
fn parse_setup(s: &str) -> Result<(PathBuf, Targets), String> {
    let (file, targets) = s
        .rsplit_once(':')
        .ok_or_else(|| format!("`{s}`: FILE.csv:T,... (the file, then its reference targets)"))?;
    if file.is_empty() {
        return Err(format!("`{s}`: no file before `:`"));
    }
    Ok((PathBuf::from(file), parse_targets(targets)?))
}

/// What the records measure, for EFDD.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum EfddQuantityArg {
    /// Chosen from the bells.
    Auto,
    /// Displacement.
    Displacement,
    /// Velocity.
    Velocity,
    /// Acceleration.
    Acceleration,
}

/// How several setups are merged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MergeArg {
    /// Post separate estimation re-scaling.
    Poser,
    /// Pre global estimation re-scaling (SSI).
    Preger,
}

/// Which SSI.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SsiArg {
    /// Covariance-driven.
    Cov,
    /// Data-driven.
    Dat,
}

/// Arguments of `host-harness modal`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Displacements: `displacement.csv` of `track` or `analyze` (its `disp_mm` when every
    /// target has it, else the pixel coordinate along --axis), or a wide CSV: a time column
    /// (`t_s`, `time` or `t`) and one column per target, an empty cell a lost sample.
    #[arg(long, value_name = "FILE.csv")]
    pub displacement: PathBuf,
    /// Sample rate, Hz (default: from the time column, which must be regular).
    #[arg(long, value_name = "HZ", value_parser = super::args::parse_rate)]
    pub fps: Option<f64>,
    /// Image axis of the motion in a `displacement.csv` without millimetres (`y`: positive
    /// up in the image; `x`: positive right).
    #[arg(long, value_enum, default_value_t = super::analyze::AxisArg::Y)]
    pub axis: super::analyze::AxisArg,
    /// Welch settings of the cross-spectral matrix (default: Hann segments of the largest
    /// power of two up to 4096 with at least 8 half-overlapping segments).
    #[command(flatten)]
    pub welch: WelchArgs,
    /// Frequency bands, Hz: one mode per band and method (default: peaks picked
    /// automatically, see --prominence-db).
    #[arg(long, value_name = "LO-HI,...", value_parser = parse_bands)]
    pub bands: Option<Bands>,
    /// `$prominence_db`.
    #[arg(long, value_name = "DB", allow_negative_numbers = true, default_value = super::args::given("prominence_db"), value_parser = super::args::number("prominence_db"), help = super::args::help("prominence_db"))]
    pub prominence_db: f64,
    /// Lowest frequency analysed, Hz (default: 0.5 Hz or two spectral lines, the higher).
    #[arg(long, value_name = "HZ")]
    pub f_min_hz: Option<f64>,
    /// `$efdd_quantity`.
    #[arg(long, value_enum, default_value = super::args::given("efdd_quantity"), help = super::args::help("efdd_quantity"))]
    pub efdd_quantity: EfddQuantityArg,
    /// `$plscf`.
    #[arg(long, help = super::args::help("plscf"))]
    pub plscf: bool,
    /// SSI's modes exactly these poles: a CSV with `f_hz` and `damping` columns (poles picked
    /// on report.html's stabilisation diagram, or an earlier `modes.csv`); each one's shape
    /// from the diagram's stable pole nearest it (default: the diagram's clusters).
    #[arg(long, value_name = "FILE")]
    pub poles: Option<std::path::PathBuf>,
    /// `$ssi`.
    #[arg(long, value_enum, default_value = super::args::given("ssi"), help = super::args::help("ssi"))]
    pub ssi: SsiArg,
    /// `$ssi_block_rows`.
    #[arg(long, value_name = "N", value_parser = super::args::whole::<usize>("ssi_block_rows"), help = super::args::help("ssi_block_rows"))]
    pub ssi_block_rows: Option<usize>,
    /// `$ssi_max_order`.
    #[arg(long, value_name = "N", value_parser = super::args::whole::<usize>("ssi_max_order"), help = super::args::help("ssi_max_order"))]
    pub ssi_max_order: Option<usize>,
    /// Several setups: the targets of --displacement that every setup shares (the
    /// references), in a common order, e.g. `1,2`.
    #[arg(long, value_name = "T,...", value_parser = parse_targets)]
    pub references: Option<Targets>,
    /// Another setup of the same structure: its displacement file and its reference targets
    /// in --references' order (`FILE.csv:T,...`); repeat for each. The modes are merged into
    /// global shapes as --merge says (outputs on the global points, `setups.csv` each setup's
    /// part in the modes PoSER merged).
    #[arg(long, value_name = "FILE.csv:T,...", value_parser = parse_setup)]
    pub setup: Vec<(PathBuf, Targets)>,
    /// `$merge`.
    #[arg(long, value_enum, default_value = super::args::given("merge"), help = super::args::help("merge"))]
    pub merge: MergeArg,
    /// Output directory (created).
    #[arg(long, value_name = "DIR", default_value = "modal")]
    pub out: PathBuf,
    /// Replace --out if it is an earlier output of `modal` (as a whole).
    #[arg(long)]
    pub force: bool,
    /// `--pdf` and `--geometry`: what the page is printed to and drawn on.
    #[command(flatten)]
    pub page: super::args::PageArgs,
    /// Do not write the figures.
    #[arg(long)]
    pub no_plots: bool,
}

/// Runs `host-harness modal`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let out = args.out.clone();
    let spec = ModalSpec::new(ModalInput {
        displacement: args.displacement,
        fps: args.fps,
        axis: match args.axis {
            super::analyze::AxisArg::X => PixelAxis::X,
            super::analyze::AxisArg::Y => PixelAxis::Y,
        },
        welch: args.welch.settings(),
        bands: args.bands.as_ref().map(Bands::pairs),
        prominence_db: args.prominence_db,
        f_min_hz: args.f_min_hz,
        ssi: match args.ssi {
            SsiArg::Cov => SsiKind::Cov,
            SsiArg::Dat => SsiKind::Dat,
        },
        efdd_quantity: match args.efdd_quantity {
            EfddQuantityArg::Auto => None,
            EfddQuantityArg::Displacement => Some(Quantity::Displacement),
            EfddQuantityArg::Velocity => Some(Quantity::Velocity),
            EfddQuantityArg::Acceleration => Some(Quantity::Acceleration),
        },
        plscf: args.plscf,
        poles: args.poles,
        ssi_block_rows: args.ssi_block_rows,
        ssi_max_order: args.ssi_max_order,
        references: args.references.map(|t| t.0),
        setups: args.setup.into_iter().map(|(p, t)| (p, t.0)).collect(),
        merge: match args.merge {
            MergeArg::Poser => Merge::Poser,
            MergeArg::Preger => Merge::Preger,
        },
        out: args.out,
        force: args.force,
        pdf: args.page.pdf,
        plots: !args.no_plots,
        geometry: args.page.geometry.clone(),
    })
    .map_err(SpecError::into_anyhow)?;
    super::finish(spec.run()?, &out)
}
