//! Two channels -> H1 and coherence -> peaks (method.md §2.4, §2.5), on firmware-core's streaming
//! Welch estimator and peak picking. Two entries, one core:
//!
//! - [`estimate`] for records in `f64` (CSV columns, recordings): each column's mean is removed
//!   in `f64` when the detrend is "constant" (every segment loses its mean anyway, so this is
//!   neutral, and a large offset costs no `f32` precision), then the column is scaled by a power
//!   of two so its largest magnitude lies in `[0.5, 1)` (exact, undone on H1): the result does not
//!   depend on the units, and values far outside the `f32` range are handled. The estimator runs
//!   at the host capacity [`MAX_NFFT`] on a large-stack thread.
//! - [`measure`] for `f32` records already in sensible units with an estimator of exactly the
//!   needed size, reused across calls (the Monte Carlo inner loop): peaks and |H1|.

use firmware_core::peaks;
use firmware_core::spectrum::{Detrend, WelchConfig, WelchH1, Window};
use firmware_core::Complex32;
use num_complex::Complex64;
use serde::{Deserialize, Serialize};
use vibcam_readers::bad_input;

/// Largest segment and transform length on the host: 65 536 samples (32 s at 2048 Hz in one
/// segment).
pub const MAX_NFFT: usize = 65_536;
/// DFT scratch for any supported length up to [`MAX_NFFT`] (Bluestein: `n + 2 l + m`,
/// `l <= 32768`, `m <= l / 2`).
pub const SCRATCH: usize =
    MAX_NFFT + 2 * firmware_core::dft::MAX_POW2 + firmware_core::dft::MAX_POW2 / 2;

/// The estimator the host entry instantiates (a few MiB: boxed, on a large-stack thread).
type HostWelch = WelchH1<MAX_NFFT, MAX_NFFT, SCRATCH>;

/// How unset Welch settings are resolved for a record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Defaults {
    /// scipy's: `nperseg = min(256, len)`, `noverlap = nperseg / 2`, `nfft = nperseg` (`frf`).
    Scipy,
    /// The rig's: one segment over the whole record, no overlap (`analyze`).
    WholeRecord,
}

/// Welch H1 settings as a user gives them; `None` fields are resolved by [`Defaults`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WelchSettings {
    /// Window of each segment (periodic).
    pub window: Window,
    /// Segment length, samples.
    pub nperseg: Option<usize>,
    /// Overlap, samples.
    pub noverlap: Option<usize>,
    /// FFT length (>= nperseg, zero padding).
    pub nfft: Option<usize>,
    /// Per-segment detrending.
    pub detrend: Detrend,
}

impl Default for WelchSettings {
    /// Periodic Hann, mean removed, sizes from the [`Defaults`].
    fn default() -> Self {
        WelchSettings {
            window: Window::Hann,
            nperseg: None,
            noverlap: None,
            nfft: None,
            detrend: Detrend::Constant,
        }
    }
}

impl WelchSettings {
    /// The estimator configuration for a record of `len` samples at `fs_hz`; errors name the flag.
    pub fn resolve(
        &self,
        len: usize,
        fs_hz: f64,
        defaults: Defaults,
    ) -> anyhow::Result<WelchConfig> {
        if !(fs_hz.is_finite() && fs_hz > 0.0 && (fs_hz as f32).is_normal()) {
            return Err(bad_input(format!(
                "$fs {fs_hz:e}: the sampling rate must be a positive number of Hz within the \
                 f32 range"
            )));
        }
        let nperseg = self.nperseg.unwrap_or(match defaults {
            Defaults::Scipy => len.min(256),
            Defaults::WholeRecord => len,
        });
        if nperseg == 0 || nperseg > len {
            return Err(bad_input(format!(
                "$nperseg {nperseg} must be between 1 and the record length ({len} samples)"
            )));
        }
        let noverlap = self.noverlap.unwrap_or(match defaults {
            Defaults::WholeRecord if nperseg == len => 0,
            _ => nperseg / 2,
        });
        if noverlap >= nperseg {
            return Err(bad_input(format!(
                "$noverlap {noverlap} must be smaller than $nperseg {nperseg}"
            )));
        }
        let nfft = self.nfft.unwrap_or(nperseg);
        if nfft < nperseg {
            return Err(bad_input(format!(
                "$nfft {nfft} must be at least $nperseg {nperseg}"
            )));
        }
        if nfft > MAX_NFFT {
            return Err(bad_input(format!(
                "$nfft {nfft} (or the record length) is above the largest supported transform, \
                 {MAX_NFFT}"
            )));
        }
        Ok(WelchConfig {
            fs_hz: fs_hz as f32,
            nperseg,
            noverlap,
            nfft,
            window: self.window,
            detrend: self.detrend,
        })
    }
}

/// An H1 frequency response with its coherence.
#[derive(Debug, Clone, PartialEq)]
pub struct Frf {
    /// Bin frequencies, Hz (`k fs / nfft`, `k = 0..=nfft/2`).
    pub freq_hz: Vec<f64>,
    /// H1 = Pxy / Pxx per bin, output units per input unit (0 where the input has no energy).
    pub h1: Vec<Complex64>,
    /// |Pxy|^2 / (Pxx Pyy) per bin, 0..=1.
    pub coherence: Vec<f64>,
    /// The settings used.
    pub config: WelchConfig,
    /// Segments averaged.
    pub segments: u32,
    /// Segments skipped because a sample was out of the firmware's range (never for finite
    /// input after the power-of-two scaling).
    pub skipped: u32,
}

impl Frf {
    /// Bin spacing, Hz.
    pub fn df_hz(&self) -> f64 {
        self.freq_hz.get(1).copied().unwrap_or(0.0)
    }
}

/// Power of two `2^e` with `max |v| / 2^e` in `[0.5, 1)` (1 for an all-zero column).
pub(crate) fn pow2_scale(v: &[f64]) -> f64 {
    let m = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if m > 0.0 && m.is_finite() {
        2f64.powi(m.log2().floor() as i32 + 1)
    } else {
        1.0
    }
}

/// H1 of `y` against `x` (equal lengths, `f64`) with firmware-core's estimator (see the module
/// documentation for the centring and scaling). Errors when no complete segment was averaged.
pub fn estimate(x: &[f64], y: &[f64], config: WelchConfig) -> anyhow::Result<Frf> {
    if x.len() != y.len() {
        return Err(bad_input(format!(
            "the channels have different lengths ({} and {})",
            x.len(),
            y.len()
        )));
    }
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
    let job = move || -> anyhow::Result<Frf> {
        let mut welch = Box::new(HostWelch::try_new(config).map_err(|e| {
            bad_input(format!(
                "invalid Welch settings ($nperseg/$noverlap/$nfft/$fs): {e}"
            ))
        })?);
        welch
            .push(&xs, &ys)
            .map_err(|e| anyhow::anyhow!("internal: {e}"))?;
        if welch.accumulator().segments() == 0 {
            return Err(bad_input(format!(
                "no usable segment: {} samples, nperseg {}; {} segment(s) skipped because a \
                 sample is not finite or beyond the f32 range",
                xs.len(),
                config.nperseg,
                welch.accumulator().skipped_segments()
            )));
        }
        let gain = ay / ax;
        let bins = welch.accumulator().bins();
        Ok(Frf {
            freq_hz: (0..bins)
                .map(|k| k as f64 * config.fs_hz as f64 / config.nfft as f64)
                .collect(),
            h1: (0..bins)
                .map(|k| {
                    let h = welch.accumulator().h1(k).unwrap_or_default();
                    Complex64::new(h.re as f64 * gain, h.im as f64 * gain)
                })
                .collect(),
            coherence: (0..bins)
                .map(|k| f64::from(welch.accumulator().coherence(k).unwrap_or(0.0)))
                .collect(),
            config,
            segments: welch.accumulator().segments(),
            skipped: welch.accumulator().skipped_segments(),
        })
    };
    super::on_large_stack("Welch", job)?
}

/// One picked mode: the bin of largest |Im H1| in a band (method.md §2.5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PickedMode {
    /// Band searched, Hz.
    pub band_hz: (f64, f64),
    /// Resonance frequency, Hz.
    pub f_hz: f64,
    /// |H1| at that bin.
    pub amplitude: f64,
    /// Bin index in the FRF.
    pub bin: usize,
    /// Exposure-to-period ratio (exposure x `f_hz`), when the exposure is known.
    pub e2pr: Option<f64>,
}

/// Picks one mode per band with firmware-core's [`peaks::pick`] (no sub-bin refinement, the
/// paper's method); `exposure_s` gives the E2PR. A band with no bin is an error naming it.
pub fn pick_modes(
    frf: &Frf,
    bands: &[(f64, f64)],
    exposure_s: Option<f64>,
) -> anyhow::Result<Vec<PickedMode>> {
    let h: Vec<Complex32> = frf
        .h1
        .iter()
        .map(|v| Complex32::new(v.re as f32, v.im as f32))
        .collect();
    let df = frf.config.df_hz();
    bands
        .iter()
        .map(|&(lo, hi)| {
            let p = peaks::pick(&h, df, (lo as f32, hi as f32), false).ok_or_else(|| {
                bad_input(format!(
                    "band {lo}-{hi} Hz contains no bin of the spectrum (0 to {} Hz in steps of \
                     {df} Hz)",
                    frf.freq_hz.last().copied().unwrap_or(0.0)
                ))
            })?;
            let f_hz = frf.freq_hz.get(p.bin).copied().unwrap_or(f64::from(p.f_hz));
            Ok(PickedMode {
                band_hz: (lo, hi),
                f_hz,
                amplitude: frf
                    .h1
                    .get(p.bin)
                    .map_or(f64::from(p.amplitude), |v| v.norm()),
                bin: p.bin,
                e2pr: exposure_s.map(|e| e * f_hz),
            })
        })
        .collect()
}

/// Peak picked in one mode band: frequency (Hz) and amplitude.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PeakRecord {
    /// Resonance frequency, Hz.
    pub f_hz: f64,
    /// Resonant amplitude (study units).
    pub a: f64,
}

/// What one system measured: a peak per band and |H1| on the first bins.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SystemRecord {
    /// One entry per mode band; `None` when the band held no usable bin.
    pub peaks: Vec<Option<PeakRecord>>,
    /// |H1| at the first bins (the study's output bins).
    pub frf_abs: Vec<f32>,
}

/// Streams `x` (input) and `y` (output) through `welch` (reset first), picks the peaks of `bands`
/// with firmware-core's peak picking and keeps |H1| of the first `keep_bins` bins. `scale`
/// multiplies H1 (unit conversion).
pub fn measure<const SEG: usize, const NFFT: usize, const SCR: usize>(
    welch: &mut WelchH1<SEG, NFFT, SCR>,
    x: &[f32],
    y: &[f32],
    bands: &[(f64, f64)],
    keep_bins: usize,
    scale: f64,
) -> anyhow::Result<SystemRecord> {
    welch.reset();
    welch
        .push(x, y)
        .map_err(|e| anyhow::anyhow!("Welch estimator: {e}"))?;
    let peaks = bands
        .iter()
        .map(|&(lo, hi)| {
            peaks::pick_with(
                welch.accumulator().bins(),
                welch.accumulator().df_hz(),
                (lo as f32, hi as f32),
                false,
                |k| welch.accumulator().h1(k),
            )
            .map(|p| PeakRecord {
                f_hz: p.f_hz as f64,
                a: p.amplitude as f64 * scale,
            })
        })
        .collect();
    let frf_abs = (0..keep_bins.min(welch.accumulator().bins()))
        .map(|k| {
            welch
                .accumulator()
                .h1(k)
                .map_or(f32::NAN, |h| (h.norm() as f64 * scale) as f32)
        })
        .collect();
    Ok(SystemRecord { peaks, frf_abs })
}

#[cfg(test)]
mod tests {
    use super::*;
    use vibcam_common::testing::uniform_noise;

    fn window_coeffs(w: Window, n: usize) -> Vec<f64> {
        let two_pi = 2.0 * std::f64::consts::PI;
        (0..n)
            .map(|i| {
                let c = (two_pi * i as f64 / n as f64).cos();
                match w {
                    Window::Hann => 0.5 - 0.5 * c,
                    Window::Hamming => 0.54 - 0.46 * c,
                    Window::Rect => 1.0,
                }
            })
            .collect()
    }

    /// Reference Welch H1 (rustfft, f64, written from method.md §2.4).
    fn reference_h1(x: &[f64], y: &[f64], c: &WelchConfig) -> (Vec<Complex64>, Vec<f64>) {
        let (nperseg, noverlap, nfft) = (c.nperseg, c.noverlap, c.nfft);
        let win = window_coeffs(c.window, nperseg);
        let fft = vibcam_fft::Planner::new().forward(nfft);
        let bins = nfft / 2 + 1;
        let mut pxx = vec![0.0; bins];
        let mut pyy = vec![0.0; bins];
        let mut pxy = vec![Complex64::new(0.0, 0.0); bins];
        let step = nperseg - noverlap;
        let mut start = 0;
        while start + nperseg <= x.len().min(y.len()) {
            let seg = |s: &[f64]| {
                let s = &s[start..start + nperseg];
                let mean = if c.detrend == Detrend::Constant {
                    s.iter().sum::<f64>() / nperseg as f64
                } else {
                    0.0
                };
                let mut buf = vec![Complex64::new(0.0, 0.0); nfft];
                for ((b, v), c) in buf.iter_mut().zip(s).zip(&win) {
                    *b = Complex64::new((v - mean) * c, 0.0);
                }
                fft.process(&mut buf);
                buf
            };
            let (fx, fy) = (seg(x), seg(y));
            for k in 0..bins {
                pxx[k] += fx[k].norm_sqr();
                pyy[k] += fy[k].norm_sqr();
                pxy[k] += fx[k].conj() * fy[k];
            }
            start += step;
        }
        let h1 = pxy
            .iter()
            .zip(&pxx)
            .map(|(c, &p)| {
                if p > 0.0 {
                    c / p
                } else {
                    Complex64::new(0.0, 0.0)
                }
            })
            .collect();
        let coherence = pxy
            .iter()
            .zip(pxx.iter().zip(&pyy))
            .map(|(c, (&a, &b))| {
                if a * b > 0.0 {
                    c.norm_sqr() / (a * b)
                } else {
                    0.0
                }
            })
            .collect();
        (h1, coherence)
    }

    /// H1 of a system y = 2 x (delayed by a whole number of samples on a periodic record) is
    /// 2 exp(-i omega d), coherence 1; peaks pick the band maxima of |Im H1|.
    #[test]
    fn settings_resolve_with_either_defaults_and_name_the_flag() {
        let s = WelchSettings::default();
        let c = s.resolve(1000, 50.0, Defaults::Scipy).unwrap();
        assert_eq!((c.nperseg, c.noverlap, c.nfft), (256, 128, 256));
        let c = s.resolve(1000, 50.0, Defaults::WholeRecord).unwrap();
        assert_eq!((c.nperseg, c.noverlap, c.nfft), (1000, 0, 1000));
        let bad = |s: WelchSettings, fs: f64, flag: &str| {
            let e = s
                .resolve(1000, fs, Defaults::Scipy)
                .unwrap_err()
                .to_string();
            assert!(e.contains(flag), "{e}");
        };
        bad(
            WelchSettings {
                nperseg: Some(2000),
                ..s
            },
            50.0,
            "$nperseg",
        );
        bad(
            WelchSettings {
                nperseg: Some(100),
                noverlap: Some(100),
                ..s
            },
            50.0,
            "$noverlap",
        );
        bad(
            WelchSettings {
                nperseg: Some(100),
                nfft: Some(99),
                ..s
            },
            50.0,
            "$nfft",
        );
        bad(s, 1e308, "$fs 1e308");
        bad(s, 0.0, "$fs");
    }

    #[test]
    fn h1_of_a_scaled_copy_and_peak_picking() {
        let n = 2048;
        let x = uniform_noise(12345, n);
        let y: Vec<f64> = x.iter().map(|v| 2.0 * v).collect();
        let c = WelchSettings::default()
            .resolve(n, 2048.0, Defaults::WholeRecord)
            .unwrap();
        assert_eq!((c.nperseg, c.noverlap, c.nfft), (n, 0, n));
        let frf = estimate(&x, &y, c).unwrap();
        for (h, c) in frf.h1.iter().zip(&frf.coherence).skip(1) {
            assert!((h - Complex64::new(2.0, 0.0)).norm() < 1e-6);
            assert!((c - 1.0).abs() < 1e-6);
        }
        let mut fake = frf.clone();
        fake.h1[10] = Complex64::new(0.5, -3.0);
        fake.h1[30] = Complex64::new(0.0, 5.0);
        let m = pick_modes(&fake, &[(5.0, 15.0), (25.0, 35.0)], Some(0.002)).unwrap();
        assert_eq!((m[0].bin, m[1].bin), (10, 30));
        assert!((m[0].amplitude - (0.25f64 + 9.0).sqrt()).abs() < 1e-12);
        assert!((m[1].e2pr.unwrap() - 0.002 * 30.0).abs() < 1e-12);
        assert!(pick_modes(&fake, &[(0.1, 0.2)], None).is_err());
    }

    /// The firmware Welch estimator agrees with the f64 reference on a noisy two-channel record
    /// (Hamming, overlapping segments, zero padding to a non-power-of-two nfft).
    #[test]
    fn firmware_h1_matches_the_reference() {
        let n = 4096;
        let x = uniform_noise(99, n);
        let noise = uniform_noise(100, n);
        // y: a 3-tap filter of x plus independent noise
        let y: Vec<f64> = (0..n)
            .map(|i| {
                let a = x[i];
                let b = if i > 0 { x[i - 1] } else { 0.0 };
                let c = if i > 1 { x[i - 2] } else { 0.0 };
                0.5 * a - 0.8 * b + 0.3 * c + 0.2 * noise[i]
            })
            .collect();
        let c = WelchSettings {
            window: Window::Hamming,
            nperseg: Some(512),
            noverlap: Some(256),
            nfft: Some(600),
            detrend: Detrend::Constant,
        }
        .resolve(n, 1000.0, Defaults::Scipy)
        .unwrap();
        let got = estimate(&x, &y, c).unwrap();
        let (want_h1, want_coh) = reference_h1(&x, &y, &c);
        assert_eq!(got.h1.len(), 301);
        assert!((got.freq_hz[300] - 500.0).abs() < 1e-9);
        // f32 core against the f64 reference: 1e-4 of |H1| (single-precision accumulation)
        for k in 1..got.h1.len() {
            let e = (got.h1[k] - want_h1[k]).norm();
            assert!(
                e < 1e-4 * (1.0 + want_h1[k].norm()),
                "bin {k}: {} vs {}",
                got.h1[k],
                want_h1[k]
            );
            assert!((got.coherence[k] - want_coh[k]).abs() < 1e-4, "bin {k}");
        }
    }
}
