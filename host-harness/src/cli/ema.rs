//! `host-harness ema`: experimental modal analysis of responses (a camera's displacements or a
//! DAQ's transducers) over a measured force ([`crate::analysis::ema`]).

use super::args::{parse_bands, Bands};
use crate::analysis::ema::ExpChoice;
use crate::analysis::modal::FrfForm;
use crate::jobs::{EmaInput, EmaSpec, RovingRecord, SpecError};
use std::path::PathBuf;

/// What the responses measure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum QuantityArg {
    /// Displacement (a camera's): receptance FRFs.
    Displacement,
    /// Velocity: mobility.
    Velocity,
    /// Acceleration: accelerance.
    Acceleration,
}

/// `--exp-window`: `off`, `auto` or the window's value at the block's end (its row's range).
fn parse_exp(s: &str) -> Result<ExpChoice, String> {
    match s {
        "off" => Ok(ExpChoice::Off),
        "auto" => Ok(ExpChoice::Auto),
        v => super::args::number_in(Some("ema"), "exp_window")(v).map(ExpChoice::End),
    }
}

/// `--roving POINT=FILE[,FILE]`: the hit point, then one file holding force and responses,
/// or the responses' file and the force's.
fn parse_roving(s: &str) -> Result<RovingRecord, String> {
    let (point, files) = s
        .split_once('=')
        .ok_or_else(|| format!("`{s}`: POINT=FILE or POINT=RESPONSES,FORCE (`3=hit3.lvm`)"))?;
    let point: usize = point
        .trim()
        .parse()
        .ok()
        .filter(|&p| p >= 1)
        .ok_or_else(|| format!("`{s}`: the hit point `{point}` is not a whole number from 1"))?;
    let (response, excitation) = match files.split_once(',') {
        Some((r, f)) => (PathBuf::from(r), PathBuf::from(f)),
        None => (PathBuf::from(files), PathBuf::from(files)),
    };
    if response.as_os_str().is_empty() || excitation.as_os_str().is_empty() {
        return Err(format!("`{s}`: a file name is empty"));
    }
    Ok(RovingRecord {
        point,
        response,
        excitation,
    })
}

/// Arguments of `host-harness ema`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Responses: `displacement.csv` of `track`/`analyze`, a wide CSV (a time column `t_s`,
    /// `time` or `t`, one column per response), a pyidi `.npy`, or a DAQ file (`.lvm`,
    /// `.tdms`, `.uff`/`.unv`).
    #[arg(
        long,
        value_name = "FILE",
        required_unless_present = "roving",
        conflicts_with = "roving"
    )]
    pub response: Option<PathBuf>,
    /// A response channel by name (repeat for several; default: every channel, a pyidi
    /// `.npy`'s coordinate that moves more; in a `displacement.csv`, `target N` or `N`).
    #[arg(long = "response-col", value_name = "NAME")]
    pub response_col: Vec<String>,
    /// `$response_fs`.
    #[arg(long, value_name = "HZ", value_parser = super::args::number("response_fs"), help = super::args::help("response_fs"))]
    pub response_fs: Option<f64>,
    /// The force: a DAQ file or CSV.
    #[arg(
        long,
        value_name = "FILE",
        required_unless_present = "roving",
        conflicts_with = "roving"
    )]
    pub excitation: Option<PathBuf>,
    /// A roving-hammer test's record (repeat, one per hit point): the point hit, then the
    /// file holding its force and responses, or the responses' file and the force's
    /// (`3=hit3.lvm`, `3=camera3.csv,force3.csv`); instead of --response and --excitation.
    /// The responses are the same in every record; the shapes are over the hit points when
    /// they outnumber the responses.
    #[arg(long, value_name = "POINT=FILE[,FILE]", value_parser = parse_roving)]
    pub roving: Vec<RovingRecord>,
    /// `$excitation_col`.
    #[arg(long, value_name = "NAME", help = super::args::help("excitation_col"))]
    pub excitation_col: Vec<String>,
    /// `$excitation_fs`.
    #[arg(long, value_name = "HZ", value_parser = super::args::number("excitation_fs"), help = super::args::help("excitation_fs"))]
    pub excitation_fs: Option<f64>,
    /// `$impact`.
    #[arg(long, help = super::args::help("impact"))]
    pub impact: bool,
    /// `$exp_window`.
    #[arg(long, value_name = "off|auto|END", default_value = super::args::given("exp_window"), value_parser = parse_exp, help = super::args::help("exp_window"))]
    pub exp_window: ExpChoice,
    /// `$block_s`.
    #[arg(long, value_name = "S", value_parser = super::args::number("block_s"), help = super::args::help("block_s"))]
    pub block_s: Option<f64>,
    /// `$delay_s`.
    #[arg(long, value_name = "S", allow_negative_numbers = true, value_parser = super::args::number("delay_s"), help = super::args::help("delay_s"))]
    pub delay_s: Option<f64>,
    /// `$response_quantity`.
    #[arg(long, value_enum, default_value = super::args::given("response_quantity"), help = super::args::help("response_quantity"))]
    pub response_quantity: QuantityArg,
    /// Frequency bands, Hz: one mode per band (default: every mode the stabilisation
    /// diagram shows between --f-min-hz and --f-max-hz).
    #[arg(long, value_name = "LO-HI,...", value_parser = parse_bands)]
    pub bands: Option<Bands>,
    /// Poles to give as the modes: a CSV with `f_hz` and `damping` columns (an earlier
    /// `modes.csv`, its rows kept or edited, or poles picked on the stabilisation diagram);
    /// their shapes by LSFD (default: every cluster the diagram shows).
    #[arg(long, value_name = "FILE")]
    pub poles: Option<std::path::PathBuf>,
    /// `$f_min_hz`.
    #[arg(long, value_name = "HZ", value_parser = super::args::number_in(Some("ema"), "f_min_hz"), help = super::args::help_in("ema", "f_min_hz"))]
    pub f_min_hz: Option<f64>,
    /// `$f_max_hz`.
    #[arg(long, value_name = "HZ", value_parser = super::args::number("f_max_hz"), help = super::args::help("f_max_hz"))]
    pub f_max_hz: Option<f64>,
    /// `$max_order`.
    #[arg(long, value_name = "N", default_value = super::args::given("max_order"), value_parser = super::args::whole::<usize>("max_order"), help = super::args::help("max_order"))]
    pub max_order: usize,
    /// `$nperseg`: a continuous force's Welch segment.
    #[arg(long, value_name = "N", value_parser = super::args::whole_in::<usize>(Some("ema"), "nperseg"), help = super::args::help_in("ema", "nperseg"))]
    pub nperseg: Option<usize>,
    /// Output directory (created).
    #[arg(long, value_name = "DIR", default_value = "ema")]
    pub out: PathBuf,
    /// Replace --out if it is an earlier output of `ema` (as a whole).
    #[arg(long)]
    pub force: bool,
    /// `--pdf` and `--geometry`: what the page is printed to and drawn on.
    #[command(flatten)]
    pub page: super::args::PageArgs,
    /// Do not write the figures.
    #[arg(long)]
    pub no_plots: bool,
}

/// Runs `host-harness ema`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let out = args.out.clone();
    // clap asks for both files, or --roving instead
    let first = args.roving.first();
    let spec = EmaSpec::new(EmaInput {
        response: args
            .response
            .or_else(|| first.map(|r| r.response.clone()))
            .unwrap_or_default(),
        response_cols: args.response_col,
        response_fs: args.response_fs,
        excitation: args
            .excitation
            .or_else(|| first.map(|r| r.excitation.clone()))
            .unwrap_or_default(),
        roving: args.roving,
        excitation_cols: args.excitation_col,
        excitation_fs: args.excitation_fs,
        impact: args.impact,
        exp_window: args.exp_window,
        block_s: args.block_s,
        delay_s: args.delay_s,
        form: match args.response_quantity {
            QuantityArg::Displacement => FrfForm::Receptance,
            QuantityArg::Velocity => FrfForm::Mobility,
            QuantityArg::Acceleration => FrfForm::Accelerance,
        },
        bands: args.bands.as_ref().map(Bands::pairs),
        poles: args.poles.clone(),
        f_min_hz: args.f_min_hz,
        f_max_hz: args.f_max_hz,
        max_order: args.max_order,
        nperseg: args.nperseg,
        out: args.out,
        force: args.force,
        pdf: args.page.pdf,
        geometry: args.page.geometry.clone(),
        plots: !args.no_plots,
    })
    .map_err(SpecError::into_anyhow)?;
    super::finish(spec.run()?, &out)
}
