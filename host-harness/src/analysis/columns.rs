//! The commands on CSV columns, as library calls: `frf` (H1 and coherence of two columns
//! through firmware-core's Welch estimator, and the peaks in bands) and `upsample` (one column
//! through firmware-core's Fourier upsampler). Each reads its input, checks it (errors name the
//! file, row and column), computes, and writes its `--out` atomically, never over its input.

use crate::bad_input;
use crate::chain::frf::{self, Defaults, Frf, PickedMode, WelchSettings};
use crate::csvio::read_columns;
use crate::export::{self, signals};
use std::path::PathBuf;

/// A checked `frf` request.
#[derive(Debug, Clone)]
pub struct FrfRequest {
    /// The CSV file.
    pub input: PathBuf,
    /// Column of the input channel.
    pub x: String,
    /// Column of the output channel.
    pub y: String,
    /// Sample rate, Hz.
    pub fs: f64,
    /// Welch settings as given (resolved against the record's length).
    pub welch: WelchSettings,
    /// Bands to pick a peak in, Hz.
    pub bands: Option<Vec<(f64, f64)>>,
    /// The output CSV.
    pub out: PathBuf,
}

/// What `frf` computed (its CSV is written).
#[derive(Debug)]
pub struct FrfOutcome {
    /// H1 and coherence.
    pub frf: Frf,
    /// The peak per band, with bands.
    pub picked: Option<Vec<PickedMode>>,
    /// Samples per channel.
    pub samples: usize,
}

/// Runs `frf`; see the module documentation.
pub fn frf(req: &FrfRequest) -> anyhow::Result<FrfOutcome> {
    // (a rate that is not positive is refused with the Welch settings)
    if let (Some(b), true) = (&req.bands, req.fs.is_finite() && req.fs > 0.0) {
        crate::setting::bands_below_nyquist(b, req.fs, "the record's")
            .map_err(crate::setting::SpecError::into_anyhow)?;
    }
    crate::outdir::refuse_overwriting_input(&req.out, &[&req.input])?;
    let cols = read_columns(&req.input, &[req.x.as_str(), req.y.as_str()])?;
    let (x, y) = match cols.values.as_slice() {
        [x, y] => (x, y),
        _ => anyhow::bail!("internal: expected two columns"),
    };
    let file = req.input.display();
    super::check_channel(x, &format!("{file}: column `{}` ($x)", req.x))?;
    super::check_channel(y, &format!("{file}: column `{}` ($y)", req.y))?;
    let config = req.welch.resolve(x.len(), req.fs, Defaults::Scipy)?;
    let frf = frf::estimate(x, y, config)?;
    let picked = req
        .bands
        .as_ref()
        .map(|b| frf::pick_modes(&frf, b, None))
        .transpose()?;
    export::write_atomic(&req.out, &signals::frf_csv(super::spectrum(&frf)))?;
    Ok(FrfOutcome {
        frf,
        picked,
        samples: x.len(),
    })
}

/// A checked `upsample` request.
#[derive(Debug, Clone)]
pub struct UpsampleRequest {
    /// The CSV file.
    pub input: PathBuf,
    /// The column.
    pub col: String,
    /// Its sample rate, Hz (> 0).
    pub from_hz: f64,
    /// The output rate, Hz (> 0).
    pub to_hz: f64,
    /// The output CSV (`t_s,value`).
    pub out: PathBuf,
}

/// Runs `upsample`; returns the sample counts in and out.
pub fn upsample(req: &UpsampleRequest) -> anyhow::Result<(usize, usize)> {
    crate::outdir::refuse_overwriting_input(&req.out, &[&req.input])?;
    let cols = read_columns(&req.input, &[req.col.as_str()])?;
    let raw = &cols.values[0];
    if let Some((i, v)) = raw.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(bad_input(format!(
            "{}: row {}: `{}` is {v}, not a finite number",
            req.input.display(),
            i + 2,
            req.col
        )));
    }
    let up = crate::chain::resample::upsample_column(raw, req.from_hz, req.to_hz)?;
    let bytes = signals::upsampled_csv(&up.values, up.scale, req.to_hz);
    export::write_atomic(&req.out, &bytes)?;
    Ok((raw.len(), up.values.len()))
}

#[cfg(test)]
mod tests {
    use crate::chain::frf;
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
}
