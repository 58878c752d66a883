//! `host-harness modal`: output-only modal analysis (FDD, EFDD, SSI-cov) of a displacement
//! file ([`crate::analysis::oma`]): `track`'s `displacement.csv`, or a wide CSV from another
//! tool.

use super::args::{parse_bands, Bands, WelchArgs};
use crate::analysis::oma::input::{self, PixelAxis};
use crate::analysis::oma::run::Output;
use crate::analysis::oma::OmaSettings;
use crate::bad_input;
use std::path::PathBuf;

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
    /// Without --bands: least prominence of a peak of the first singular value, dB.
    #[arg(long, value_name = "DB", default_value_t = 6.0)]
    pub prominence_db: f64,
    /// Lowest frequency analysed, Hz (default: 0.5 Hz or two spectral lines, the higher).
    #[arg(long, value_name = "HZ")]
    pub f_min_hz: Option<f64>,
    /// SSI-cov: block rows of the Toeplitz matrix (default 30, fewer for short records).
    #[arg(long, value_name = "N", value_parser = super::args::int_range(2..=500))]
    pub ssi_block_rows: Option<usize>,
    /// SSI-cov: highest model order (even; default 40).
    #[arg(long, value_name = "N", value_parser = super::args::int_range(2..=400))]
    pub ssi_max_order: Option<usize>,
    /// Output directory (created).
    #[arg(long, value_name = "DIR", default_value = "modal")]
    pub out: PathBuf,
    /// Replace --out if it is an earlier output of `modal` (as a whole).
    #[arg(long)]
    pub force: bool,
    /// Do not write the figures.
    #[arg(long)]
    pub no_plots: bool,
}

/// Runs `host-harness modal`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let axis = match args.axis {
        super::analyze::AxisArg::X => PixelAxis::X,
        super::analyze::AxisArg::Y => PixelAxis::Y,
    };
    let records = input::read(&args.displacement, axis, args.fps)?;
    let settings = settings(&args.welch, records.fs_hz, &records, &args)?;
    let preamble = format!("input: {}\n", args.displacement.display());
    let outcome = crate::analysis::oma::run::run(
        &records,
        &settings,
        &Output {
            out: &args.out,
            force: args.force,
            command: "modal",
            inputs: vec![args.displacement.clone()],
            plots: !args.no_plots,
            along_x: axis == PixelAxis::X,
            preamble,
            extra: Vec::new(),
        },
    )?;
    super::stdout(&outcome.report)?;
    outcome.result
}

use crate::analysis::oma::MIN_SEGMENT;

/// The analysis settings the flags describe, checked against the record.
fn settings(
    welch: &WelchArgs,
    fs_hz: f64,
    records: &input::Records,
    args: &Args,
) -> anyhow::Result<OmaSettings> {
    let n = records.channels.first().map_or(0, Vec::len);
    let mut s = OmaSettings::with_welch(fs_hz, n, &welch.settings());
    crate::analysis::oma::check_segment(welch.nperseg)?;
    if s.csd.nperseg > n {
        return Err(bad_input(format!(
            "--nperseg {}: the record has only {n} samples, fewer than one segment",
            s.csd.nperseg
        )));
    }
    if n < MIN_SEGMENT {
        return Err(bad_input(format!(
            "{}: the record has {n} samples, fewer than one segment of {MIN_SEGMENT} (the \
             shortest analysed)",
            args.displacement.display()
        )));
    }
    if s.csd.noverlap >= s.csd.nperseg {
        return Err(bad_input(format!(
            "--noverlap {} must be smaller than --nperseg {}",
            s.csd.noverlap, s.csd.nperseg
        )));
    }
    if s.csd.nfft < s.csd.nperseg {
        return Err(bad_input(format!(
            "--nfft {} must be at least --nperseg {}",
            s.csd.nfft, s.csd.nperseg
        )));
    }
    let df = fs_hz / s.csd.nfft as f64;
    if let Some(f) = args.f_min_hz {
        if !(f.is_finite() && f >= 0.0 && f < fs_hz / 2.0) {
            return Err(bad_input(format!(
                "--f-min-hz {f} must be between 0 and the Nyquist frequency ({} Hz)",
                fs_hz / 2.0
            )));
        }
        s.peaks.f_min_hz = f.max(df);
        s.ssi.f_range_hz.0 = f;
    }
    if !(args.prominence_db.is_finite() && args.prominence_db >= 0.0) {
        return Err(bad_input(format!(
            "--prominence-db must be >= 0, got {}",
            args.prominence_db
        )));
    }
    s.peaks.prominence_db = args.prominence_db;
    if let Some(b) = &args.bands {
        for &(lo, hi) in &b.pairs() {
            if hi > fs_hz / 2.0 {
                return Err(bad_input(format!(
                    "--bands {lo}-{hi}: reaches above the Nyquist frequency ({} Hz)",
                    fs_hz / 2.0
                )));
            }
        }
        s.bands = b.pairs();
    }
    if let Some(i) = args.ssi_block_rows {
        s.ssi.block_rows = i;
    }
    if let Some(m) = args.ssi_max_order {
        s.ssi.max_order = m;
    }
    if n < 4 * s.ssi.block_rows {
        return Err(bad_input(format!(
            "--ssi-block-rows {}: the record has {n} samples, at least {} are needed",
            s.ssi.block_rows,
            4 * s.ssi.block_rows
        )));
    }
    Ok(s)
}
