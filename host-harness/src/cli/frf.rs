//! `host-harness frf`: H1 frequency response and coherence of two CSV columns through
//! firmware-core's streaming Welch estimator ([`crate::chain::frf`]), and optionally the
//! resonance peaks in frequency bands.
//!
//! Output: `--out` CSV with header `freq_hz,h1_re,h1_im,h1_abs,coherence`, one row per bin
//! `0 ..= nfft/2` (values in `f32`, the firmware's precision); with `--bands`, stdout CSV
//! `band,f_hz,amplitude` (one row per band, `band` as given, `LO-HI` in Hz); a one-line summary
//! on stderr.

use super::args::{parse_bands, Bands, WelchArgs};
use crate::analysis::columns;
use crate::export::signals;
use std::path::PathBuf;

/// Arguments of `host-harness frf`.
#[derive(Debug, clap::Args)]
#[command(after_help = FLAGS_HELP, after_long_help = FLAGS_HELP)]
pub struct Args {
    /// Input CSV file with a header row.
    #[arg(long, value_name = "FILE.csv")]
    pub input: PathBuf,
    /// `$fs`: both columns' sampling rate.
    #[arg(long, value_name = "HZ", value_parser = super::args::number_in(Some("frf"), "fs"), help = super::args::help_in("frf", "fs"))]
    pub fs: f64,
    /// Header name of the input (excitation) column.
    #[arg(long, value_name = "COL")]
    pub x: String,
    /// Header name of the output (response) column.
    #[arg(long, value_name = "COL")]
    pub y: String,
    /// Welch estimator settings.
    #[command(flatten)]
    pub welch: WelchArgs,
    /// Frequency bands LO-HI in Hz, comma separated (e.g. 1.5-2.25,2.25-2.9), each below the
    /// Nyquist frequency --fs / 2: prints the peak of |Im H1| in each band on stdout.
    #[arg(long, value_name = "LO-HI,...", value_parser = parse_bands)]
    pub bands: Option<Bands>,
    /// Output CSV file.
    #[arg(long, value_name = "FILE.csv")]
    pub out: PathBuf,
}

const FLAGS_HELP: &str = "\
H1 = Pxy / Pxx and coherence = |Pxy|^2 / (Pxx Pyy) by Welch averaging, as scipy.signal.csd
with the same window, nperseg, noverlap, nfft and detrend (only complete segments are used).
Output (--out): CSV freq_hz,h1_re,h1_im,h1_abs,coherence, bins 0..=nfft/2 at k fs / nfft;
  H1 is in y units per x unit; a bin where x has no energy gets H1 = 0 and coherence 0.
Peaks (stdout, with --bands): CSV band,f_hz,amplitude: the bin with the largest |Im H1| in
  each band (inclusive) and |H1| there.
A bad CSV (missing column, non-numeric, empty or non-finite cell, short row) is reported with
its row and column and the exit code is 2.";

/// Runs `host-harness frf`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let req = columns::FrfRequest {
        input: args.input.clone(),
        x: args.x.clone(),
        y: args.y.clone(),
        fs: args.fs,
        welch: args.welch.settings(),
        bands: args.bands.as_ref().map(|b| b.pairs()),
        out: args.out.clone(),
    };
    let columns::FrfOutcome {
        frf,
        picked,
        samples,
    } = columns::frf(&req)?;
    if let (Some(b), Some(p)) = (&args.bands, &picked) {
        let rows =
            b.0.iter()
                .zip(p)
                .map(|(b, p)| (b.label.as_str(), p.f_hz, p.amplitude));
        let text = String::from_utf8_lossy(&signals::peaks_csv(rows)).into_owned();
        super::stdout(&text)?;
    }
    let c = frf.config;
    eprintln!(
        "frf: {} samples of `{}` -> `{}`, {} segment(s) averaged (nperseg {}, noverlap {}, nfft {}, {:?} window, detrend {:?}{}), df = {} Hz, {} bins -> {}",
        samples,
        args.x,
        args.y,
        frf.segments,
        c.nperseg,
        c.noverlap,
        c.nfft,
        c.window,
        c.detrend,
        if frf.skipped > 0 {
            format!(
                ", {} skipped: a sample beyond the f32 range after scaling",
                frf.skipped
            )
        } else {
            String::new()
        },
        c.df_hz(),
        frf.freq_hz.len(),
        args.out.display()
    );
    Ok(())
}
