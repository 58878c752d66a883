//! `host-harness frf`: H1 frequency response and coherence of two CSV columns through
//! firmware-core's streaming Welch estimator ([`firmware_core::spectrum`]), and optionally the
//! resonance peaks in frequency bands ([`firmware_core::peaks`]).
//!
//! The columns are read as `f64` and converted to the `f32` the firmware uses. Before the
//! conversion each column is scaled by a power of two so that its largest magnitude lies in
//! `[0.5, 1)` (exact, and undone on H1 afterwards): the result does not depend on the units of
//! the columns, and values far outside the `f32` range (or below its normal range) are handled.
//! With `--detrend constant` the column means are also removed in `f64` first: each segment
//! loses its mean anyway, so this is neutral, and a large offset costs no `f32` precision.
//!
//! Output: `--out` CSV with header `freq_hz,h1_re,h1_im,h1_abs,coherence`, one row per bin
//! `0 ..= nfft/2`; with `--bands`, stdout CSV `band,f_hz,amplitude` (one row per band, `band`
//! as given, `LO-HI` in Hz); a one-line summary on stderr.

use crate::bad_input;
use crate::csvio::read_columns;
use firmware_core::peaks;
use firmware_core::spectrum::{scratch_capacity, Detrend, WelchConfig, WelchH1, Window};
use firmware_core::Complex32;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Largest `nperseg` and `nfft` of this build (the capacities of the firmware estimator the
/// command instantiates).
pub const MAX_LEN: usize = 32768;

/// Scratch for any supported transform length up to [`MAX_LEN`]: the length plus a Bluestein
/// convolution of at most `2 * 32768` values.
const MAX_SCRATCH: usize = MAX_LEN + 2 * 32768;

/// The estimator the command runs (about 1.7 MB; boxed, built on a large-stack thread).
type HostWelch = WelchH1<MAX_LEN, MAX_LEN, MAX_SCRATCH>;

// every power of two and the lengths of the studies fit
const _: () = assert!(scratch_capacity(20480) <= MAX_SCRATCH);
const _: () = assert!(scratch_capacity(5000) <= MAX_SCRATCH);

/// Segment window (periodic, as scipy's default).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum WindowArg {
    /// Periodic Hann.
    Hann,
    /// Periodic Hamming.
    Hamming,
    /// Rectangular (scipy's `boxcar`).
    Rect,
}

/// `--detrend` (shared with the other subcommands that run Welch).
pub use super::args::DetrendArg;

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
    /// Segment window.
    #[arg(long, value_enum, default_value_t = WindowArg::Hann)]
    pub window: WindowArg,
    /// Samples per segment, 1..=32768 [default: min(256, record length), as scipy].
    #[arg(long, value_name = "N")]
    pub nperseg: Option<usize>,
    /// Samples shared by consecutive segments, < nperseg [default: nperseg / 2].
    #[arg(long, value_name = "N")]
    pub noverlap: Option<usize>,
    /// Transform length (zero padding), nperseg..=32768 [default: nperseg].
    #[arg(long, value_name = "N")]
    pub nfft: Option<usize>,
    /// Segment detrending.
    #[arg(long, value_enum, default_value_t = DetrendArg::Constant)]
    pub detrend: DetrendArg,
    /// Frequency bands LO-HI in Hz, comma separated (e.g. 1.5-2.25,2.25-2.9): prints the peak
    /// of |Im H1| in each band on stdout.
    #[arg(long, value_name = "LO-HI,...")]
    pub bands: Option<String>,
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

/// One band of `--bands`, with its text as given.
#[derive(Debug, Clone, PartialEq)]
pub struct Band {
    /// The band as the user wrote it (trimmed), used as its label in the output.
    pub label: String,
    /// Lower edge, Hz.
    pub lo_hz: f64,
    /// Upper edge, Hz.
    pub hi_hz: f64,
}

/// Parses `LO-HI,LO-HI,...` (non-negative, finite, `LO <= HI`).
pub fn parse_bands(s: &str) -> anyhow::Result<Vec<Band>> {
    let mut out = Vec::new();
    for part in s.split(',') {
        let label = part.trim();
        let bad = |why: &str| bad_input(format!("--bands: band `{label}`: {why}"));
        let (lo, hi) = label
            .split_once('-')
            .ok_or_else(|| bad("expected LO-HI in Hz, e.g. 1.5-2.25"))?;
        let num = |v: &str| -> anyhow::Result<f64> {
            let x: f64 = v
                .trim()
                .parse()
                .map_err(|_| bad(&format!("`{}` is not a number", v.trim())))?;
            if !x.is_finite() || x < 0.0 {
                return Err(bad(&format!(
                    "`{}` is not a finite frequency >= 0",
                    v.trim()
                )));
            }
            Ok(x)
        };
        let (lo_hz, hi_hz) = (num(lo)?, num(hi)?);
        if lo_hz > hi_hz {
            return Err(bad("LO is above HI"));
        }
        out.push(Band {
            label: label.to_string(),
            lo_hz,
            hi_hz,
        });
    }
    Ok(out)
}

/// One output row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrfRow {
    /// Bin frequency, Hz.
    pub freq_hz: f64,
    /// H1 in y units per x unit.
    pub h1: Complex32,
    /// Magnitude-squared coherence, 0..=1.
    pub coherence: f32,
}

/// The spectrum of a record: rows, the settings used and the segment counts.
#[derive(Debug, Clone)]
pub struct Frf {
    /// One row per bin, `0 ..= nfft/2`.
    pub rows: Vec<FrfRow>,
    /// Settings used.
    pub config: WelchConfig,
    /// Segments averaged.
    pub segments: u32,
    /// Segments skipped (a sample out of the firmware's range; never for finite CSV input).
    pub skipped: u32,
}

/// Resolves the scipy-like defaults for a record of `len` samples.
pub fn resolve_config(args: &Args, len: usize) -> anyhow::Result<WelchConfig> {
    let nperseg = args.nperseg.unwrap_or(len.min(256));
    let config = WelchConfig {
        fs_hz: args.fs as f32,
        nperseg,
        noverlap: args.noverlap.unwrap_or(nperseg / 2),
        nfft: args.nfft.unwrap_or(nperseg),
        window: match args.window {
            WindowArg::Hann => Window::Hann,
            WindowArg::Hamming => Window::Hamming,
            WindowArg::Rect => Window::Rect,
        },
        detrend: match args.detrend {
            DetrendArg::Constant => Detrend::Constant,
            DetrendArg::None => Detrend::None,
        },
    };
    if !(args.fs.is_finite() && args.fs > 0.0 && config.fs_hz.is_normal()) {
        return Err(bad_input(format!(
            "--fs {}: the sampling rate must be a finite number > 0",
            args.fs
        )));
    }
    if nperseg > len {
        return Err(bad_input(format!(
            "--nperseg {nperseg} is longer than the record ({len} samples): no complete segment"
        )));
    }
    Ok(config)
}

/// Power of two `2^e` with `max |v| / 2^e` in `[0.5, 1)` (1 for an all-zero column).
fn pow2_scale(v: &[f64]) -> f64 {
    let m = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if m > 0.0 && m.is_finite() {
        2f64.powi(m.log2().floor() as i32 + 1)
    } else {
        1.0
    }
}

/// Runs the firmware estimator over the two columns (must have equal lengths).
pub fn compute(x: &[f64], y: &[f64], config: WelchConfig) -> anyhow::Result<Frf> {
    if x.len() != y.len() {
        return Err(bad_input(format!(
            "the columns have different lengths ({} and {})",
            x.len(),
            y.len()
        )));
    }
    // With the constant detrend every segment loses its mean anyway, so removing the column
    // mean here (in f64) changes nothing mathematically but keeps a large offset (a centroid
    // in pixels, a sensor bias) from eating the f32 precision of the small vibration.
    let centre = |v: &[f64]| -> Vec<f64> {
        let m = match config.detrend {
            Detrend::Constant if !v.is_empty() => v.iter().sum::<f64>() / v.len() as f64,
            _ => 0.0,
        };
        v.iter().map(|a| a - m).collect()
    };
    let (x, y) = (centre(x), centre(y));
    let (ax, ay) = (pow2_scale(&x), pow2_scale(&y));
    let xs: Vec<f32> = x.iter().map(|v| (v / ax) as f32).collect();
    let ys: Vec<f32> = y.iter().map(|v| (v / ay) as f32).collect();
    // ~1.7 MB of state: build it on a thread with room for it rather than on the caller's stack
    let job = move || -> anyhow::Result<Frf> {
        let mut welch = Box::new(HostWelch::try_new(config).map_err(|e| {
            bad_input(format!(
                "invalid Welch settings (--nperseg/--noverlap/--nfft/--fs): {e}"
            ))
        })?);
        welch
            .push(&xs, &ys)
            .map_err(|e| anyhow::anyhow!("internal: {e}"))?;
        if welch.segments() == 0 {
            return Err(bad_input(format!(
                "no usable segment: {} samples, nperseg {}, {} segment(s) skipped",
                xs.len(),
                config.nperseg,
                welch.skipped_segments()
            )));
        }
        let gain = ay / ax;
        let rows = (0..welch.bins())
            .map(|k| {
                let h = welch.h1(k).unwrap_or_default();
                FrfRow {
                    freq_hz: k as f64 * config.fs_hz as f64 / config.nfft as f64,
                    h1: Complex32::new((h.re as f64 * gain) as f32, (h.im as f64 * gain) as f32),
                    coherence: welch.coherence(k).unwrap_or(0.0),
                }
            })
            .collect();
        Ok(Frf {
            rows,
            config,
            segments: welch.segments(),
            skipped: welch.skipped_segments(),
        })
    };
    std::thread::Builder::new()
        .name("frf".into())
        .stack_size(64 << 20)
        .spawn(job)
        .map_err(|e| anyhow::anyhow!("cannot start the FRF thread: {e}"))?
        .join()
        .map_err(|_| anyhow::anyhow!("the FRF thread panicked"))?
}

/// Picks the peak of each band on the rows of `frf` (firmware-core's [`peaks::pick`], no
/// refinement). A band with no bin is an error naming it.
pub fn pick_peaks(frf: &Frf, bands: &[Band]) -> anyhow::Result<Vec<(String, peaks::Peak)>> {
    let h1: Vec<Complex32> = frf.rows.iter().map(|r| r.h1).collect();
    let df = frf.config.df_hz();
    bands
        .iter()
        .map(|b| {
            peaks::pick(&h1, df, (b.lo_hz as f32, b.hi_hz as f32), false)
                .map(|p| (b.label.clone(), p))
                .ok_or_else(|| {
                    bad_input(format!(
                        "--bands: band `{}` Hz contains no bin of the spectrum (0 to {} Hz in steps of {} Hz)",
                        b.label,
                        frf.rows.last().map_or(0.0, |r| r.freq_hz),
                        df
                    ))
                })
        })
        .collect()
}

/// Writes the FRF CSV (`freq_hz,h1_re,h1_im,h1_abs,coherence`) to `w`.
pub fn write_frf(w: impl Write, rows: &[FrfRow]) -> anyhow::Result<()> {
    let mut out = csv::Writer::from_writer(w);
    out.write_record(["freq_hz", "h1_re", "h1_im", "h1_abs", "coherence"])?;
    for r in rows {
        out.write_record([
            r.freq_hz.to_string(),
            r.h1.re.to_string(),
            r.h1.im.to_string(),
            r.h1.re.hypot(r.h1.im).to_string(),
            r.coherence.to_string(),
        ])?;
    }
    out.flush()?;
    Ok(())
}

/// Writes the peaks CSV (`band,f_hz,amplitude`) to `w`.
pub fn write_peaks(w: impl Write, peaks: &[(String, peaks::Peak)]) -> anyhow::Result<()> {
    let mut out = csv::Writer::from_writer(w);
    out.write_record(["band", "f_hz", "amplitude"])?;
    for (label, p) in peaks {
        out.write_record([label.clone(), p.f_hz.to_string(), p.amplitude.to_string()])?;
    }
    out.flush()?;
    Ok(())
}

fn write_file(path: &Path, rows: &[FrfRow]) -> anyhow::Result<()> {
    let mut buf = Vec::new();
    write_frf(&mut buf, rows)?;
    std::fs::write(path, buf)
        .map_err(|e| anyhow::Error::new(e).context(format!("cannot write {}", path.display())))
}

/// Runs `host-harness frf`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let bands = args.bands.as_deref().map(parse_bands).transpose()?;
    let cols = read_columns(&args.input, &[args.x.as_str(), args.y.as_str()])?;
    let (x, y) = match cols.values.as_slice() {
        [x, y] => (x, y),
        _ => anyhow::bail!("internal: expected two columns"),
    };
    let config = resolve_config(&args, x.len())?;
    let frf = compute(x, y, config)?;
    let picked = bands.as_deref().map(|b| pick_peaks(&frf, b)).transpose()?;
    write_file(&args.out, &frf.rows)?;
    if let Some(p) = &picked {
        write_peaks(std::io::stdout().lock(), p)?;
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
            format!(", {} skipped", frf.skipped)
        } else {
            String::new()
        },
        c.df_hz(),
        frf.rows.len(),
        args.out.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_parse_and_reject() {
        let b = parse_bands("1.5-2.25, 2.25-2.9").unwrap();
        assert_eq!(b.len(), 2);
        assert_eq!(
            (b[0].lo_hz, b[0].hi_hz, b[0].label.as_str()),
            (1.5, 2.25, "1.5-2.25")
        );
        assert_eq!((b[1].lo_hz, b[1].hi_hz), (2.25, 2.9));
        for bad in ["1.5", "a-2", "3-2", "1-inf", "", "1-2,"] {
            let e = parse_bands(bad).unwrap_err();
            assert!(e.is::<crate::BadInput>(), "{bad}");
            assert!(format!("{e}").contains("--bands"), "{bad}: {e}");
        }
    }

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
        let frf = compute(&x, &y, config).unwrap();
        assert_eq!(frf.rows.len(), 126);
        assert_eq!(frf.segments, 19);
        for r in &frf.rows[1..] {
            assert!(
                (r.h1.re as f64 / -3e-20 - 1.0).abs() < 1e-5
                    && (r.h1.im as f64).abs() < 1e-5 * 3e-20,
                "{r:?}"
            );
            assert!((r.coherence - 1.0).abs() < 1e-5);
        }
        assert!((frf.rows[25].freq_hz - 10.0).abs() < 1e-12);
    }

    #[test]
    fn writers_emit_the_contract_headers() {
        let rows = [FrfRow {
            freq_hz: 0.5,
            h1: Complex32::new(3.0, -4.0),
            coherence: 0.25,
        }];
        let mut buf = Vec::new();
        write_frf(&mut buf, &rows).unwrap();
        assert_eq!(
            String::from_utf8(buf).unwrap(),
            "freq_hz,h1_re,h1_im,h1_abs,coherence\n0.5,3,-4,5,0.25\n"
        );
        let p = peaks::Peak {
            bin: 3,
            f_hz: 1.5,
            amplitude: 2.0,
        };
        let mut buf = Vec::new();
        write_peaks(&mut buf, &[("1-2".to_string(), p)]).unwrap();
        assert_eq!(
            String::from_utf8(buf).unwrap(),
            "band,f_hz,amplitude\n1-2,1.5,2\n"
        );
    }
}
