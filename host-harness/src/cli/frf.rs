//! `host-harness frf`: H1 frequency response and coherence of two CSV columns through
//! firmware-core's streaming Welch estimator ([`crate::chain::frf`]), and optionally the
//! resonance peaks in frequency bands.
//!
//! Output: `--out` CSV with header `freq_hz,h1_re,h1_im,h1_abs,coherence`, one row per bin
//! `0 ..= nfft/2` (values in `f32`, the firmware's precision); with `--bands`, stdout CSV
//! `band,f_hz,amplitude` (one row per band, `band` as given, `LO-HI` in Hz); a one-line summary
//! on stderr.

use super::args::{parse_bands, Bands, WelchArgs};
use crate::chain::frf::{self, Defaults, Frf, PickedMode};
use crate::csvio::read_columns;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `host-harness frf`.
#[derive(Debug, clap::Args)]
#[command(after_help = FLAGS_HELP, after_long_help = FLAGS_HELP)]
pub struct Args {
    /// Input CSV file with a header row.
    #[arg(long, value_name = "FILE.csv")]
    pub input: PathBuf,
    /// Sampling rate of both columns, in Hz (> 0).
    #[arg(long, value_name = "HZ")]
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
    /// Frequency bands LO-HI in Hz, comma separated (e.g. 1.5-2.25,2.25-2.9): prints the peak
    /// of |Im H1| in each band on stdout.
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

/// Writes the FRF CSV (`freq_hz,h1_re,h1_im,h1_abs,coherence`, H1 and coherence in `f32`).
pub fn write_frf(w: impl Write, frf: &Frf) -> anyhow::Result<()> {
    let mut out = csv::Writer::from_writer(w);
    out.write_record(["freq_hz", "h1_re", "h1_im", "h1_abs", "coherence"])?;
    for ((f, h), c) in frf.freq_hz.iter().zip(&frf.h1).zip(&frf.coherence) {
        let (re, im) = (h.re as f32, h.im as f32);
        out.write_record([
            f.to_string(),
            re.to_string(),
            im.to_string(),
            re.hypot(im).to_string(),
            (*c as f32).to_string(),
        ])?;
    }
    out.flush()?;
    Ok(())
}

/// Writes the peaks CSV (`band,f_hz,amplitude`) to `w`.
pub fn write_peaks(w: impl Write, bands: &Bands, peaks: &[PickedMode]) -> anyhow::Result<()> {
    let mut out = csv::Writer::from_writer(w);
    out.write_record(["band", "f_hz", "amplitude"])?;
    for (b, p) in bands.0.iter().zip(peaks) {
        out.write_record([
            b.label.clone(),
            (p.f_hz as f32).to_string(),
            (p.amplitude as f32).to_string(),
        ])?;
    }
    out.flush()?;
    Ok(())
}

/// Runs `host-harness frf`.
pub fn run(args: Args) -> anyhow::Result<()> {
    crate::outdir::refuse_overwriting_input(&args.out, &[&args.input])?;
    let cols = read_columns(&args.input, &[args.x.as_str(), args.y.as_str()])?;
    let (x, y) = match cols.values.as_slice() {
        [x, y] => (x, y),
        _ => anyhow::bail!("internal: expected two columns"),
    };
    let file = args.input.display();
    crate::analysis::check_channel(x, &format!("{file}: column `{}` (--x)", args.x))?;
    crate::analysis::check_channel(y, &format!("{file}: column `{}` (--y)", args.y))?;
    let config = args
        .welch
        .settings()
        .resolve(x.len(), args.fs, Defaults::Scipy)?;
    let frf = frf::estimate(x, y, config)?;
    let picked = args
        .bands
        .as_ref()
        .map(|b| frf::pick_modes(&frf, &b.pairs(), None))
        .transpose()?;
    let mut buf = Vec::new();
    write_frf(&mut buf, &frf)?;
    crate::study::checkpoint::write_atomic(&args.out, &buf)?;
    if let (Some(b), Some(p)) = (&args.bands, &picked) {
        write_peaks(std::io::stdout().lock(), b, p)?;
    }
    let c = frf.config;
    eprintln!(
        "frf: {} samples of `{}` -> `{}`, {} segment(s) averaged (nperseg {}, noverlap {}, nfft {}, {:?} window, detrend {:?}{}), df = {} Hz, {} bins -> {}",
        x.len(),
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

#[cfg(test)]
mod tests {
    use super::*;
    use firmware_core::spectrum::{Detrend, WelchConfig, Window};

    #[test]
    fn gain_and_units_do_not_matter() {
        // y = -3 x in very different units: H1 = -3 exactly up to f32 rounding, coherence 1
        let x: Vec<f64> = (0..2000)
            .map(|i| ((i as f64) * 0.37).sin() * 1e12 + ((i * i % 97) as f64) * 1e10)
            .collect();
        let y: Vec<f64> = x.iter().map(|v| -3.0 * v * 1e-20).collect();
        let config = WelchConfig {
            fs_hz: 100.0,
            nperseg: 200,
            noverlap: 100,
            nfft: 250,
            window: Window::Hamming,
            detrend: Detrend::Constant,
        };
        let frf = frf::estimate(&x, &y, config).unwrap();
        assert_eq!(frf.freq_hz.len(), 126);
        assert_eq!(frf.segments, 19);
        for (h, c) in frf.h1.iter().zip(&frf.coherence).skip(1) {
            assert!(
                (h.re / -3e-20 - 1.0).abs() < 1e-5 && h.im.abs() < 1e-5 * 3e-20,
                "{h}"
            );
            assert!((c - 1.0).abs() < 1e-5);
        }
        assert!((frf.freq_hz[25] - 10.0).abs() < 1e-12);
    }

    #[test]
    fn writers_emit_the_contract_headers() {
        let frf = Frf {
            freq_hz: vec![0.5],
            h1: vec![num_complex::Complex64::new(3.0, -4.0)],
            coherence: vec![0.25],
            config: WelchConfig {
                fs_hz: 1.0,
                nperseg: 1,
                noverlap: 0,
                nfft: 1,
                window: Window::Rect,
                detrend: Detrend::None,
            },
            segments: 1,
            skipped: 0,
        };
        let mut buf = Vec::new();
        write_frf(&mut buf, &frf).unwrap();
        assert_eq!(
            String::from_utf8(buf).unwrap(),
            "freq_hz,h1_re,h1_im,h1_abs,coherence\n0.5,3,-4,5,0.25\n"
        );
        let p = PickedMode {
            band_hz: (1.0, 2.0),
            f_hz: 1.5,
            amplitude: 2.0,
            bin: 3,
            e2pr: None,
        };
        let bands = parse_bands("1-2").unwrap();
        let mut buf = Vec::new();
        write_peaks(&mut buf, &bands, &[p]).unwrap();
        assert_eq!(
            String::from_utf8(buf).unwrap(),
            "band,f_hz,amplitude\n1-2,1.5,2\n"
        );
    }
}
