//! `host-harness ema`: experimental modal analysis of responses (a camera's displacements or a
//! DAQ's transducers) over a measured force ([`crate::analysis::ema`]).

use super::args::{parse_bands, Bands};
use crate::analysis::ema::ExpChoice;
use crate::analysis::modal::FrfForm;
use crate::jobs::{EmaInput, EmaSpec, SpecError};
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

/// `--exp-window`: `off`, `auto` or the window's value at the block's end.
fn parse_exp(s: &str) -> Result<ExpChoice, String> {
    match s {
        "off" => Ok(ExpChoice::Off),
        "auto" => Ok(ExpChoice::Auto),
        v => v
            .parse::<f64>()
            .ok()
            .filter(|e| *e > 0.0 && *e < 1.0)
            .map(ExpChoice::End)
            .ok_or_else(|| format!("`{v}`: off, auto, or the value at the block's end (0 to 1)")),
    }
}

/// Arguments of `host-harness ema`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Responses: `displacement.csv` of `track`/`analyze`, a wide CSV (a time column `t_s`,
    /// `time` or `t`, one column per response), a pyidi `.npy`, or a DAQ file (`.lvm`,
    /// `.tdms`, `.uff`/`.unv`).
    #[arg(long, value_name = "FILE")]
    pub response: PathBuf,
    /// A response channel by name (repeat for several; default: every channel, a pyidi
    /// `.npy`'s coordinate that moves more; in a `displacement.csv`, `target N` or `N`).
    #[arg(long = "response-col", value_name = "NAME")]
    pub response_col: Vec<String>,
    /// The responses' sample rate, Hz, when the file states none.
    #[arg(long, value_name = "HZ", value_parser = super::args::parse_rate)]
    pub response_fs: Option<f64>,
    /// The force: a DAQ file or CSV.
    #[arg(long, value_name = "FILE")]
    pub excitation: PathBuf,
    /// The force's channel (default: the file's only channel).
    #[arg(long, value_name = "NAME")]
    pub excitation_col: Option<String>,
    /// The force's sample rate, Hz, when the file states none.
    #[arg(long, value_name = "HZ", value_parser = super::args::parse_rate)]
    pub excitation_fs: Option<f64>,
    /// An impact test: hits found in the force, double hits and clipped hits left out and
    /// named, the rest averaged (default: a continuous force, Welch segments).
    #[arg(long)]
    pub impact: bool,
    /// Impact: the exponential window (`off`, `auto`: when a response has not decayed by the
    /// block's end, or its value at the block's end, e.g. 0.01); its damping is removed.
    #[arg(long, value_name = "off|auto|END", default_value = "auto", value_parser = parse_exp)]
    pub exp_window: ExpChoice,
    /// Impact: the longest block after a hit, s (default: the hits' spacing).
    #[arg(long, value_name = "S")]
    pub block_s: Option<f64>,
    /// The responses' first sample came this long after the force's, s (negative: before).
    #[arg(long, value_name = "S", default_value_t = 0.0)]
    pub delay_s: f64,
    /// What the responses measure (sets the FRF's residual terms).
    #[arg(long, value_enum, default_value_t = QuantityArg::Displacement)]
    pub response_quantity: QuantityArg,
    /// Frequency bands, Hz: one mode per band (default: every mode the stabilisation
    /// diagram shows between --f-min-hz and --f-max-hz).
    #[arg(long, value_name = "LO-HI,...", value_parser = parse_bands)]
    pub bands: Option<Bands>,
    /// Lowest frequency fitted, Hz (default: the bands', else 1 % of the top, at least 0.5).
    #[arg(long, value_name = "HZ")]
    pub f_min_hz: Option<f64>,
    /// Highest frequency fitted, Hz (default: the bands', else 0.8 x the slower record's
    /// Nyquist frequency).
    #[arg(long, value_name = "HZ")]
    pub f_max_hz: Option<f64>,
    /// LSCF's highest model order.
    #[arg(long, value_name = "N", default_value_t = 48)]
    pub max_order: usize,
    /// Continuous force: samples per Welch segment (default: the largest power of two with
    /// at least 8 half-overlapping segments, up to 65536).
    #[arg(long, value_name = "N")]
    pub nperseg: Option<usize>,
    /// Output directory (created).
    #[arg(long, value_name = "DIR", default_value = "ema")]
    pub out: PathBuf,
    /// Replace --out if it is an earlier output of `ema` (as a whole).
    #[arg(long)]
    pub force: bool,
    /// Do not write the figures.
    #[arg(long)]
    pub no_plots: bool,
}

/// Runs `host-harness ema`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let out = args.out.clone();
    let spec = EmaSpec::new(EmaInput {
        response: args.response,
        response_cols: args.response_col,
        response_fs: args.response_fs,
        excitation: args.excitation,
        excitation_col: args.excitation_col,
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
        f_min_hz: args.f_min_hz,
        f_max_hz: args.f_max_hz,
        max_order: args.max_order,
        nperseg: args.nperseg,
        out: args.out,
        force: args.force,
        plots: !args.no_plots,
    })
    .map_err(SpecError::into_anyhow)?;
    let outcome = spec.run()?;
    super::stdout(&outcome.report)?;
    if outcome.result.is_ok() {
        super::outputs_in(&out)?;
    }
    outcome.result
}
