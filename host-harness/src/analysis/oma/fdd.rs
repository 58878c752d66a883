//! Frequency domain decomposition (FDD) and its enhanced form (EFDD) (docs/method.md §3.12):
//! the singular values and first singular vector of the cross-spectral matrix per line, peaks
//! picked on the first singular value, and per peak the single-degree-of-freedom bell back to
//! a correlation function for damping and frequency.

use super::csd::Csd;
use crate::analysis::modal::mac;
use nalgebra::{DMatrix, SymmetricEigen};
use num_complex::Complex64;
use realfft::RealFftPlanner;

/// The singular values (descending) and the first singular vector of every line.
#[derive(Debug, Clone, PartialEq)]
pub struct Svd {
    /// Line frequencies, Hz.
    pub freq_hz: Vec<f64>,
    /// Per line, the K singular values, largest first.
    pub s: Vec<Vec<f64>>,
    /// Per line, the first singular vector (unit norm).
    pub u1: Vec<Vec<Complex64>>,
}

/// The decomposition of every line of `csd` (a Hermitian positive semi-definite matrix: its
/// singular values are its eigenvalues).
pub fn decompose(csd: &Csd) -> anyhow::Result<Svd> {
    let k = csd.k;
    let mut s = Vec::with_capacity(csd.g.len());
    let mut u1 = Vec::with_capacity(csd.g.len());
    for (l, m) in csd.g.iter().enumerate() {
        let a = DMatrix::from_fn(k, k, |i, j| m[i * k + j]);
        let e =
            SymmetricEigen::try_new(a, f64::EPSILON, super::MAX_ITERATIONS).ok_or_else(|| {
                anyhow::anyhow!(
                    "FDD: the cross-spectral matrix at {:.4} Hz did not decompose in {} \
                 iterations (degenerate or non-finite values)",
                    csd.freq_hz.get(l).copied().unwrap_or(f64::NAN),
                    super::MAX_ITERATIONS
                )
            })?;
        let mut order: Vec<usize> = (0..k).collect();
        order.sort_by(|&a, &b| e.eigenvalues[b].total_cmp(&e.eigenvalues[a]));
        // rounding can leave a tiny negative eigenvalue of a semi-definite matrix
        s.push(order.iter().map(|&i| e.eigenvalues[i].max(0.0)).collect());
        let first = order.first().copied().unwrap_or(0);
        u1.push(e.eigenvectors.column(first).iter().copied().collect());
    }
    Ok(Svd {
        freq_hz: csd.freq_hz.clone(),
        s,
        u1,
    })
}

/// How peaks are picked without bands.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeakRule {
    /// Lowest frequency searched, Hz.
    pub f_min_hz: f64,
    /// Highest frequency searched, Hz (exclusive; the Nyquist frequency).
    pub f_max_hz: f64,
    /// Least prominence of a peak of the first singular value over the higher of the two
    /// lowest points between it and a higher peak (or the range's end) on either side, dB.
    pub prominence_db: f64,
    /// Least height of a peak over the floor (the median of the first singular value over
    /// the range), dB.
    pub over_floor_db: f64,
}

/// The line indices of the peaks of the first singular value (see [`PeakRule`]), ascending.
pub fn pick_peaks(svd: &Svd, rule: PeakRule) -> Vec<usize> {
    let s1: Vec<f64> = svd
        .s
        .iter()
        .map(|s| s.first().copied().unwrap_or(0.0))
        .collect();
    let range: Vec<usize> = (0..s1.len())
        .filter(|&l| svd.freq_hz[l] >= rule.f_min_hz && svd.freq_hz[l] < rule.f_max_hz)
        .collect();
    let (Some(&lo), Some(&hi)) = (range.first(), range.last()) else {
        return Vec::new();
    };
    let mut sorted: Vec<f64> = s1[lo..=hi].to_vec();
    sorted.sort_by(f64::total_cmp);
    let floor = sorted[sorted.len() / 2];
    let db = |a: f64, b: f64| 10.0 * (a / b).log10();
    let mut peaks = Vec::new();
    for l in lo..=hi {
        let left = if l > lo { s1[l - 1] } else { f64::NEG_INFINITY };
        let right = if l < hi { s1[l + 1] } else { f64::NEG_INFINITY };
        if !(s1[l] > left && s1[l] >= right) || s1[l] <= 0.0 {
            continue;
        }
        // the lowest point on each side before a higher value (or the range's end)
        let base = |it: &mut dyn Iterator<Item = usize>| {
            let mut m = s1[l];
            for i in it {
                if s1[i] > s1[l] {
                    break;
                }
                m = m.min(s1[i]);
            }
            m
        };
        let lb = base(&mut (lo..l).rev());
        let rb = base(&mut (l + 1..=hi));
        let prominence = db(s1[l], lb.max(rb).max(f64::MIN_POSITIVE));
        if prominence >= rule.prominence_db
            && db(s1[l], floor.max(f64::MIN_POSITIVE)) >= rule.over_floor_db
        {
            peaks.push(l);
        }
    }
    peaks
}

/// The line of the largest first singular value within `[lo, hi]` Hz, if the band has a line.
pub fn peak_in_band(svd: &Svd, (lo, hi): (f64, f64)) -> Option<usize> {
    (0..svd.freq_hz.len())
        .filter(|&l| svd.freq_hz[l] >= lo && svd.freq_hz[l] <= hi)
        .max_by(|&a, &b| svd.s[a][0].total_cmp(&svd.s[b][0]))
}

/// Settings of EFDD.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EfddRule {
    /// Lines around a peak whose first singular vector has at least this MAC with the peak's
    /// belong to its bell.
    pub mac_min: f64,
    /// Extrema of the correlation function skipped at its start (the bell's truncation
    /// distorts the first cycles).
    pub skip: usize,
    /// Most extrema used after them.
    pub max_extrema: usize,
}

impl Default for EfddRule {
    /// MAC 0.85, skip 3, up to 20 extrema (pyOMA-2's defaults for EFDD).
    fn default() -> Self {
        EfddRule {
            mac_min: 0.85,
            skip: 3,
            max_extrema: 20,
        }
    }
}

/// One EFDD estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Efdd {
    /// Undamped natural frequency, Hz.
    pub f_hz: f64,
    /// Damping ratio.
    pub damping: f64,
    /// Lines in the bell.
    pub lines: usize,
    /// Extrema used.
    pub extrema: usize,
}

/// The lag window of a Welch estimate with `window` segments of `nperseg`: the inverse
/// transform of the averaged spectrum is the correlation function times
/// `w_c(t) = sum_n w[n] w[n + t] / sum_n w[n]^2` (a Hann segment's `w_c` falls to 0.5 at about
/// a fifth of the segment), which adds an apparent damping unless divided out. Returned for
/// the lags `0 .. nperseg / 3`, where the circular transform's negative lags (weighted by
/// `w_c(nfft - t)`) stay small.
pub fn lag_window(window: firmware_core::spectrum::Window, nperseg: usize) -> Vec<f64> {
    let w: Vec<f64> = (0..nperseg)
        .map(|i| f64::from(window.value(i, nperseg)))
        .collect();
    let s2: f64 = w.iter().map(|v| v * v).sum();
    (0..nperseg / 3)
        .map(|t| {
            w[..nperseg - t]
                .iter()
                .zip(&w[t..])
                .map(|(a, b)| a * b)
                .sum::<f64>()
                / s2
        })
        .collect()
}

/// EFDD of the peak at line `peak`, its bell limited to the lines strictly between `fence.0`
/// and `fence.1` (the neighbouring peaks); `nfft` the transform length of the spectrum,
/// `fs_hz` the sample rate and `lag` the estimate's lag window ([`lag_window`], divided out;
/// its length limits the lags used). `None` when the correlation function has too few
/// extrema.
pub fn efdd(
    svd: &Svd,
    peak: usize,
    fence: (usize, usize),
    (nfft, fs_hz): (usize, f64),
    lag: &[f64],
    rule: EfddRule,
) -> Option<Efdd> {
    let lines = svd.freq_hz.len();
    let up = &svd.u1[peak];
    let mut bell = vec![Complex64::new(0.0, 0.0); lines];
    let mut count = 0;
    let mut take = |l: usize, bell: &mut [Complex64]| -> bool {
        if mac(&svd.u1[l], up) < rule.mac_min {
            return false;
        }
        bell[l] = Complex64::new(svd.s[l][0], 0.0);
        count += 1;
        true
    };
    take(peak, &mut bell);
    for l in (fence.0 + 1..peak).rev() {
        if !take(l, &mut bell) {
            break;
        }
    }
    for l in peak + 1..fence.1.min(lines) {
        if !take(l, &mut bell) {
            break;
        }
    }
    // no imaginary part at 0 and at the Nyquist line of an even transform
    bell[0].im = 0.0;
    if let Some(last) = bell.last_mut() {
        last.im = 0.0;
    }
    let mut planner = RealFftPlanner::<f64>::new();
    let inverse = planner.plan_fft_inverse(nfft);
    let mut r = inverse.make_output_vec();
    inverse.process(&mut bell, &mut r).ok()?;
    let r0 = r[0];
    if r0 <= 0.0 {
        return None;
    }
    let half: Vec<f64> = r
        .iter()
        .zip(lag)
        .take(nfft / 2)
        .map(|(v, w)| v / w)
        .collect();
    // zero crossings (interpolated, in samples) and the extremum between consecutive ones
    let mut crossings = Vec::new();
    for t in 0..half.len().saturating_sub(1) {
        let (a, b) = (half[t], half[t + 1]);
        if a == 0.0 || a * b < 0.0 {
            crossings.push(t as f64 + a / (a - b));
        }
    }
    let mut extrema: Vec<f64> = Vec::new();
    for w in crossings.windows(2) {
        let (from, to) = (w[0].ceil() as usize, w[1].floor() as usize);
        let m = (from..=to.max(from))
            .filter_map(|t| half.get(t))
            .map(|v| (v / r0).abs())
            .fold(0.0, f64::max);
        extrema.push(m);
    }
    let end = (rule.skip + rule.max_extrema).min(extrema.len());
    if end < rule.skip + 3 {
        return None;
    }
    let used = &extrema[rule.skip..end];
    // stop at the noise: an extremum that is no longer decreasing on average
    let used: Vec<f64> = used.iter().copied().take_while(|&v| v > 1e-3).collect();
    if used.len() < 3 {
        return None;
    }
    // ln|r_k| = c - k delta / 2 (extrema half a period apart)
    let slope = |ys: &[f64]| -> f64 {
        let n = ys.len() as f64;
        let mx = (n - 1.0) / 2.0;
        let my = ys.iter().sum::<f64>() / n;
        let (mut sxy, mut sxx) = (0.0, 0.0);
        for (i, y) in ys.iter().enumerate() {
            sxy += (i as f64 - mx) * (y - my);
            sxx += (i as f64 - mx) * (i as f64 - mx);
        }
        sxy / sxx
    };
    let logs: Vec<f64> = used.iter().map(|v| v.ln()).collect();
    let delta = -2.0 * slope(&logs);
    let damping = delta / (4.0 * std::f64::consts::PI.powi(2) + delta * delta).sqrt();
    // the crossings that bound the extrema used: half a period apart
    let cross = &crossings[rule.skip..rule.skip + used.len() + 1];
    let half_period = slope(cross);
    let fd = fs_hz / (2.0 * half_period);
    let f_hz = fd / (1.0 - damping * damping).max(1e-12).sqrt();
    (damping.is_finite() && f_hz.is_finite() && damping > 0.0).then_some(Efdd {
        f_hz,
        damping,
        lines: count,
        extrema: used.len(),
    })
}
