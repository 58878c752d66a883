//! The Welch cross-spectral density matrix of K channels (docs/method.md §3.12): per frequency
//! line the K x K Hermitian matrix `G[i][j] = E[conj(X_i) X_j]`, one-sided, as
//! `scipy.signal.csd(x_i, x_j)` with the same window, segments, overlap, transform length and
//! per-segment detrending (density scaling: `1 / (fs sum w^2)`, doubled except at 0 and at the
//! Nyquist line of an even transform).

use firmware_core::spectrum::{Detrend, Window};
use num_complex::Complex64;
use vibcam_readers::bad_input;

/// Welch settings of the cross-spectral matrix (resolved: every length known).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CsdConfig {
    /// Window of each segment (periodic).
    pub window: Window,
    /// Samples per segment.
    pub nperseg: usize,
    /// Samples shared by consecutive segments (< nperseg).
    pub noverlap: usize,
    /// Transform length (>= nperseg).
    pub nfft: usize,
    /// Per-segment detrending.
    pub detrend: Detrend,
}

impl From<firmware_core::spectrum::WelchConfig> for CsdConfig {
    /// The lengths, window and detrending of a resolved Welch H1 setting.
    fn from(c: firmware_core::spectrum::WelchConfig) -> Self {
        CsdConfig {
            window: c.window,
            nperseg: c.nperseg,
            noverlap: c.noverlap,
            nfft: c.nfft,
            detrend: c.detrend,
        }
    }
}

/// The cross-spectral density matrices of K channels.
#[derive(Debug, Clone, PartialEq)]
pub struct Csd {
    /// Line frequencies, Hz (`k fs / nfft`, `k = 0..=nfft/2`).
    pub freq_hz: Vec<f64>,
    /// Channels.
    pub k: usize,
    /// Per line, the K x K matrix row-major (`g[line][i * k + j] = G_ij`).
    pub g: Vec<Vec<Complex64>>,
    /// Segments averaged.
    pub segments: usize,
}

impl Csd {
    /// Line spacing, Hz.
    pub fn df_hz(&self) -> f64 {
        self.freq_hz.get(1).copied().unwrap_or(0.0)
    }
}

/// The cross-spectral matrix of `channels` (equal lengths, sampled at `fs_hz`). Errors when
/// the record is shorter than one segment or a sample is not finite (naming the channel).
pub fn csd_matrix(channels: &[Vec<f64>], fs_hz: f64, c: CsdConfig) -> anyhow::Result<Csd> {
    let segments = check(channels, c)?;
    of_segments(channels, fs_hz, c, 0..segments)
}

/// The cross-spectral matrix of the segments `range` of checked channels ([`check`]).
pub fn of_segments(
    channels: &[Vec<f64>],
    fs_hz: f64,
    c: CsdConfig,
    range: std::ops::Range<usize>,
) -> anyhow::Result<Csd> {
    let segments = range.len();
    let raw = raw_sum(channels, c, range)?;
    Ok(finish(raw, channels.len(), segments, fs_hz, c))
}

impl Csd {
    /// The matrix of this one's segments without those of `part` (the matrix of some of
    /// them, same settings): the two averages weighted by their segments, one taken from the
    /// other.
    pub fn without(&self, part: &Csd) -> Csd {
        let (all, some) = (self.segments as f64, part.segments as f64);
        let rest = (all - some).max(1.0);
        Csd {
            freq_hz: self.freq_hz.clone(),
            k: self.k,
            g: self
                .g
                .iter()
                .zip(&part.g)
                .map(|(a, b)| {
                    a.iter()
                        .zip(b)
                        .map(|(x, y)| (x * all - y * some) / rest)
                        .collect()
                })
                .collect(),
            segments: self.segments.saturating_sub(part.segments),
        }
    }
}

/// The segments of `channels` under `c`, after the checks of [`csd_matrix`].
pub fn check(channels: &[Vec<f64>], c: CsdConfig) -> anyhow::Result<usize> {
    let k = channels.len();
    let n = channels.first().map_or(0, Vec::len);
    if k == 0 {
        return Err(bad_input("no channel to analyse"));
    }
    if channels.iter().any(|ch| ch.len() != n) {
        return Err(bad_input("the channels have different lengths"));
    }
    for (i, ch) in channels.iter().enumerate() {
        if let Some(at) = ch.iter().position(|v| !v.is_finite()) {
            return Err(bad_input(format!(
                "channel {}: sample {at} is not a finite number",
                i + 1
            )));
        }
    }
    if c.nperseg == 0 || c.noverlap >= c.nperseg || c.nfft < c.nperseg {
        return Err(bad_input(format!(
            "invalid Welch settings: nperseg {}, noverlap {}, nfft {}",
            c.nperseg, c.noverlap, c.nfft
        )));
    }
    if n < c.nperseg {
        return Err(bad_input(format!(
            "the record has {n} samples, fewer than one segment ($nperseg {}): record longer \
             or choose a shorter segment",
            c.nperseg
        )));
    }
    Ok((n - c.nperseg) / (c.nperseg - c.noverlap) + 1)
}

/// The unscaled sums `sum conj(X_i) X_j` (upper triangle, `i <= j`, row-major K x K per line)
/// over the segments `range` of checked channels.
fn raw_sum(
    channels: &[Vec<f64>],
    c: CsdConfig,
    range: std::ops::Range<usize>,
) -> anyhow::Result<Vec<Vec<Complex64>>> {
    let k = channels.len();
    let step = c.nperseg - c.noverlap;
    let w: Vec<f64> = (0..c.nperseg)
        .map(|i| f64::from(c.window.value(i, c.nperseg)))
        .collect();
    let lines = c.nfft / 2 + 1;
    let mut planner = vibcam_fft::RealPlanner::new();
    let fft = planner.forward(c.nfft);
    let mut input = fft.make_input_vec();
    let mut spectra = vec![vec![Complex64::new(0.0, 0.0); lines]; k];
    let mut g = vec![vec![Complex64::new(0.0, 0.0); k * k]; lines];
    for s in range {
        let start = s * step;
        for (ch, out) in channels.iter().zip(spectra.iter_mut()) {
            segment_spectrum(
                &ch[start..start + c.nperseg],
                (&w, c.detrend),
                &fft,
                &mut input,
                out,
            )?;
        }
        for (line, m) in g.iter_mut().enumerate() {
            for i in 0..k {
                let xi = spectra[i][line].conj();
                for j in i..k {
                    m[i * k + j] += xi * spectra[j][line];
                }
            }
        }
    }
    Ok(g)
}

/// The spectrum of one segment into `out`: its mean removed (constant detrending), windowed by
/// `w`, zero-padded to the transform's length in `input`.
pub(crate) fn segment_spectrum(
    seg: &[f64],
    (w, detrend): (&[f64], Detrend),
    fft: &std::sync::Arc<dyn vibcam_fft::RealToComplex<f64>>,
    input: &mut [f64],
    out: &mut [Complex64],
) -> anyhow::Result<()> {
    let mean = match detrend {
        Detrend::Constant => seg.iter().sum::<f64>() / seg.len().max(1) as f64,
        _ => 0.0,
    };
    input.iter_mut().for_each(|v| *v = 0.0);
    for ((o, v), wv) in input.iter_mut().zip(seg).zip(w) {
        *o = (v - mean) * wv;
    }
    fft.process(input, out)
        .map_err(|e| anyhow::anyhow!("internal: {e}"))
}

/// The cross-spectral matrix from the raw sums of `segments` segments ([`raw_sum`]): the
/// one-sided density, the lower triangle the conjugate of the upper.
fn finish(mut g: Vec<Vec<Complex64>>, k: usize, segments: usize, fs_hz: f64, c: CsdConfig) -> Csd {
    let s2: f64 = (0..c.nperseg)
        .map(|i| f64::from(c.window.value(i, c.nperseg)).powi(2))
        .sum();
    let lines = g.len();
    let scale = 1.0 / (fs_hz * s2 * segments as f64);
    for (line, m) in g.iter_mut().enumerate() {
        let one_sided = if line == 0 || (c.nfft.is_multiple_of(2) && line == lines - 1) {
            1.0
        } else {
            2.0
        };
        for i in 0..k {
            for j in i..k {
                let v = m[i * k + j] * (scale * one_sided);
                m[i * k + j] = v;
                m[j * k + i] = v.conj();
            }
            // the diagonal is real (a power spectral density)
            m[i * k + i].im = 0.0;
        }
    }
    Csd {
        freq_hz: (0..lines)
            .map(|l| l as f64 * fs_hz / c.nfft as f64)
            .collect(),
        k,
        g,
        segments,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The naive DFT of one windowed segment.
    fn dft(seg: &[f64], nfft: usize) -> Vec<Complex64> {
        (0..=nfft / 2)
            .map(|l| {
                seg.iter()
                    .enumerate()
                    .map(|(t, v)| {
                        let a = -2.0 * std::f64::consts::PI * (l * t) as f64 / nfft as f64;
                        Complex64::new(a.cos(), a.sin()) * v
                    })
                    .sum()
            })
            .collect()
    }

    #[test]
    fn the_matrix_equals_naive_sums_over_the_segments() {
        let n = 300;
        let x: Vec<f64> = (0..n)
            .map(|i| (i as f64 * 0.37).sin() + 0.1 * i as f64)
            .collect();
        let y: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos() * 2.0).collect();
        let c = CsdConfig {
            window: Window::Hann,
            nperseg: 64,
            noverlap: 32,
            nfft: 80,
            detrend: Detrend::Constant,
        };
        let fs = 50.0;
        let got = csd_matrix(&[x.clone(), y.clone()], fs, c).unwrap();
        assert_eq!(got.segments, (n - 64) / 32 + 1);
        let w: Vec<f64> = (0..64)
            .map(|i| f64::from(Window::Hann.value(i, 64)))
            .collect();
        let s2: f64 = w.iter().map(|v| v * v).sum();
        let mut want = vec![Complex64::new(0.0, 0.0); 41];
        for s in 0..got.segments {
            let seg = |v: &[f64]| -> Vec<f64> {
                let part = &v[s * 32..s * 32 + 64];
                let m = part.iter().sum::<f64>() / 64.0;
                part.iter().zip(&w).map(|(a, b)| (a - m) * b).collect()
            };
            let (fx, fy) = (dft(&seg(&x), 80), dft(&seg(&y), 80));
            for ((w, a), b) in want.iter_mut().zip(&fx).zip(&fy) {
                *w += a.conj() * b;
            }
        }
        for (l, want) in want.iter().enumerate() {
            let d = if l == 0 || l == 40 { 1.0 } else { 2.0 };
            let w = want * d / (fs * s2 * got.segments as f64);
            let g = got.g[l][1];
            assert!((g - w).norm() <= 1e-9 * (1.0 + w.norm()), "{l}: {g} {w}");
            assert!((got.g[l][2] - w.conj()).norm() <= 1e-9 * (1.0 + w.norm()));
        }
    }

    #[test]
    fn short_records_and_bad_samples_are_refused() {
        let c = CsdConfig {
            window: Window::Hann,
            nperseg: 64,
            noverlap: 32,
            nfft: 64,
            detrend: Detrend::Constant,
        };
        let e = csd_matrix(&[vec![0.0; 10]], 10.0, c)
            .unwrap_err()
            .to_string();
        assert!(e.contains("fewer than one segment"), "{e}");
        let mut v = vec![0.0; 100];
        v[7] = f64::NAN;
        let e = csd_matrix(&[vec![0.0; 100], v], 10.0, c)
            .unwrap_err()
            .to_string();
        assert!(e.contains("channel 2: sample 7"), "{e}");
    }
}
