//! Frequency domain decomposition (FDD) and its enhanced form (EFDD) (docs/method.md §3.12):
//! the singular values and first singular vector of the cross-spectral matrix per line, peaks
//! picked on the first singular value, and per peak the single-degree-of-freedom bell back to
//! a correlation function for damping and frequency.

use super::bell::Quantity;
use super::csd::Csd;
use crate::modal::mac;
use nalgebra::{DMatrix, SymmetricEigen};
use num_complex::Complex64;

/// The singular values (descending) and the first singular vector of every line.
#[derive(Debug, Clone, PartialEq)]
pub struct Svd {
    /// Line frequencies, Hz.
    pub freq_hz: Vec<f64>,
    /// Per line, the K singular values, largest first.
    pub s: Vec<Vec<f64>>,
    /// Per line, the first singular vector (unit norm).
    pub u1: Vec<Vec<Complex64>>,
    /// Per line, the second singular vector (unit norm; zeros with one channel): where two
    /// modes share lines, the weaker one's shape.
    pub u2: Vec<Vec<Complex64>>,
}

/// The decomposition of every line of `csd` (a Hermitian positive semi-definite matrix: its
/// singular values are its eigenvalues).
pub fn decompose(csd: &Csd) -> anyhow::Result<Svd> {
    let k = csd.k;
    let mut s = Vec::with_capacity(csd.g.len());
    let mut u1 = Vec::with_capacity(csd.g.len());
    let mut u2 = Vec::with_capacity(csd.g.len());
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
        u2.push(match order.get(1) {
            Some(&second) => e.eigenvectors.column(second).iter().copied().collect(),
            None => vec![Complex64::new(0.0, 0.0); k],
        });
    }
    Ok(Svd {
        freq_hz: csd.freq_hz.clone(),
        s,
        u1,
        u2,
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
    /// the range), dB; none by default: a displacement spectrum falls as `1 / f^4` above its
    /// modes, and its high modes stand below the median of the whole range.
    pub over_floor_db: Option<f64>,
}

/// The peaks of the first singular value (see [`PeakRule`]), ascending: each line and its
/// prominence, dB.
pub fn pick_peaks(svd: &Svd, rule: PeakRule) -> Vec<(usize, f64)> {
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
            && rule
                .over_floor_db
                .is_none_or(|o| db(s1[l], floor.max(f64::MIN_POSITIVE)) >= o)
        {
            peaks.push((l, prominence));
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
    /// Fewest lines a bell must have to be fitted.
    pub min_lines: usize,
    /// What the records measure (the bell's model, [`super::bell::Quantity`]); `None`: the
    /// quantity whose model fits the bells best ([`super::modes::choose_quantity`]).
    pub quantity: Option<Quantity>,
    /// Whether a bell's tilt beyond the quantity's is fitted ([`super::bell::TILT_WEIGHT`]).
    pub tilt: bool,
}

impl Default for EfddRule {
    /// MAC 0.85 (pyOMA-2's default for EFDD), at least 5 lines, the quantity from the bells,
    /// the tilt fitted.
    fn default() -> Self {
        EfddRule {
            mac_min: 0.85,
            min_lines: 5,
            quantity: None,
            tilt: true,
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
    /// The lines (first, last) of the bell.
    pub range: (usize, usize),
    /// The fitted floor under the bell, relative to the bell's peak.
    pub floor: f64,
    /// RMS of the fit's residuals, natural log of the singular value (about
    /// `1 / sqrt(segments)` for a fit that describes the bell).
    pub rms_log: f64,
    /// The fitted tilt beyond the quantity's ([`super::bell::BellFit::tilt`]).
    pub tilt: f64,
}

/// The lag window of a Welch estimate with `window` segments of `nperseg` at every lag
/// `0 .. nperseg`: the averaged spectrum is the transform of the correlation function times
/// `w_c(t) = sum_n w[n] w[n + t] / sum_n w[n]^2` (a Hann segment's `w_c` falls to 0.5 at about
/// a fifth of the segment), which broadens every peak by the window's kernel.
pub fn lag_window(window: firmware_core::spectrum::Window, nperseg: usize) -> Vec<f64> {
    let w: Vec<f64> = (0..nperseg)
        .map(|i| f64::from(window.value(i, nperseg)))
        .collect();
    let s2: f64 = w.iter().map(|v| v * v).sum();
    (0..nperseg)
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

/// A mode's bell: around `peak`, the contiguous lines strictly between `fence.0` and
/// `fence.1` where the first or the second singular vector has a MAC of at least `mac_min`
/// with `reference` (the mode's shape) (with one or two channels, down to the first valley
/// below half the peak on either side), each line's value the singular value of the vector
/// that matches (where two modes share lines, the SVD gives each its own singular value); on
/// a line where neither matches but the plane of the two holds the shape (their MACs add up
/// to `mac_min`: two modes of like power, mixed by the SVD), the spectrum projected on the
/// shape, `s1 MAC1 + s2 MAC2`. Returns the first line and the values; empty when `peak` itself does not match.
pub fn bell(
    svd: &Svd,
    reference: &[Complex64],
    peak: usize,
    fence: (usize, usize),
    mac_min: f64,
) -> (usize, Vec<f64>) {
    let lines = svd.freq_hz.len();
    let value = |l: usize| -> Option<f64> {
        let (m1, m2) = (mac(&svd.u1[l], reference), mac(&svd.u2[l], reference));
        let s = |j: usize| svd.s[l].get(j).copied().unwrap_or(0.0);
        let v = if m1 >= mac_min {
            s(0)
        } else if m2 >= mac_min {
            s(1)
        } else if reference.len() > 2 && m1 + m2 >= mac_min {
            // two modes of like power on this line: the SVD mixes them, but the shape still
            // lies in the plane of the first two vectors; the spectrum projected on it (with
            // two channels that plane is all there is: any shape lies in it, and the bell
            // would never end)
            s(0) * m1 + s(1) * m2
        } else {
            return None;
        };
        (v > 0.0).then_some(v)
    };
    if peak >= lines || value(peak).is_none() {
        return (peak, Vec::new());
    }
    let top = value(peak).unwrap_or(0.0);
    // the next line outward belongs to the bell when its vector matches; with one or two
    // channels also only while it does not rise from a line already below half the peak (a
    // bell falls from its peak to the valley where the floor or another mode takes over):
    // one channel matches any shape, and of two, one of the two singular vectors nearly
    // always does, so the shape alone would carry the bell through the floor to the fences
    // (a struck fork's 32 Hz came out 0.6 % low from a bell of the whole spectrum). With
    // more channels the shape ends the bell, and a valley in the noisy estimate is no end.
    let few = reference.len() <= 2;
    let next = |from: usize, to: usize| -> bool {
        match (value(from), value(to)) {
            (Some(here), Some(there)) => !few || here >= 0.5 * top || there <= here,
            _ => false,
        }
    };
    let mut a = peak;
    while a > fence.0 + 1 && next(a, a - 1) {
        a -= 1;
    }
    let mut b = peak;
    while b + 1 < fence.1.min(lines) && next(b, b + 1) {
        b += 1;
    }
    (a, (a..=b).filter_map(value).collect())
}

/// The largest residual (natural log) of a fit at the least damping
/// ([`super::bell::ZETA_MIN`]) whose frequency EFDD keeps: such a fit says the bell is the
/// spectral window's, which holds only when the window's shape describes it (a fit that does
/// scatters by about `1 / sqrt(segments)`, 0.27 for 14). Struck forks: 0.02-0.12; the real
/// pyidi-cine record's bell over the whole spectrum: 0.69 (a frequency of no mode, refused).
pub const NARROW_RMS_MAX: f64 = 0.3;

/// The largest floor under a bell, relative to its peak, with which EFDD reports a damping:
/// over a floor of more than a tenth (the mode less than 10 dB above what lies under it) the
/// fit trades the floor against the bell's width, and the damping came out 30-90 % low on a
/// weak mode under 10 % measurement noise.
pub const FLOOR_MAX: f64 = 0.1;

/// EFDD of the mode of shape `reference` peaking at line `peak`: its bell ([`bell`], MAC
/// `rule.mac_min`, between the neighbouring peaks `fence`) fitted by the spectrum a single
/// mode makes in this estimate ([`super::bell`]): `nfft` the transform length, `fs_hz` the
/// sample rate, `lag` the estimate's lag window ([`lag_window`]), `start` where the fit starts
/// ([`super::bell::fit`]). An error saying why when the
/// bell has fewer than `rule.min_lines` lines, the fit does not settle on a damped mode inside
/// it, or the floor it finds under the bell is more than [`FLOOR_MAX`] of its peak.
pub fn efdd(
    svd: &Svd,
    (reference, peak): (&[Complex64], usize),
    fence: (usize, usize),
    (nfft, fs_hz): (usize, f64),
    (lag, start): (&[f64], Option<(f64, f64)>),
    rule: EfddRule,
) -> Result<Efdd, String> {
    let (a, y) = bell(svd, reference, peak, fence, rule.mac_min);
    let count = y.len();
    if count < rule.min_lines {
        return Err(format!(
            "its bell has {count} lines, fewer than {} (a longer segment, $nperseg, gives it \
             more)",
            rule.min_lines
        ));
    }
    let top = (0..count)
        .max_by(|&i, &j| y[i].total_cmp(&y[j]))
        .unwrap_or(0);
    let quantity = rule.quantity.unwrap_or(Quantity::Displacement);
    let fit = super::bell::fit(
        &y,
        (a, a + top),
        (nfft, fs_hz),
        (lag, quantity, rule.tilt),
        start,
    )
    .ok_or_else(|| {
        format!("the fit of its bell ({count} lines) did not settle on a damped mode inside it")
    })?;
    if fit.damping <= 1.0001 * super::bell::ZETA_MIN && fit.rms_log > NARROW_RMS_MAX {
        return Err(format!(
            "the fit sits at its least damping and does not describe the bell (residual {:.2} \
             (ln), more than {NARROW_RMS_MAX}): no mode narrower than the lines there",
            fit.rms_log
        ));
    }
    if fit.floor > FLOOR_MAX {
        return Err(format!(
            "the floor under its bell is {:.0} % of its peak (more than {:.0} %: noise or other \
             modes): the bell's width, and so the damping, is not determined",
            100.0 * fit.floor,
            100.0 * FLOOR_MAX
        ));
    }
    Ok(Efdd {
        f_hz: fit.f_hz,
        damping: fit.damping,
        lines: count,
        range: (a, a + count - 1),
        floor: fit.floor,
        rms_log: fit.rms_log,
        tilt: fit.tilt,
    })
}
