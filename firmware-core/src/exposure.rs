//! Exposure transfer function and its compensation (method.md §2.6, §2.8).
//!
//! # The box exposure
//!
//! A camera integrates light over its exposure time `Te`. For a centroid that is linear in the
//! image (the weighted centroid with its threshold at the background level) the measured
//! position of a frame is the time average of the target's position over the exposure window,
//! a moving average of duration `Te`. A motion `x(t) = exp(i 2 pi f t)` then gives
//!
//! ```text
//! centred window  [t - Te/2, t + Te/2]:  y(t) = sinc(pi f Te) x(t)
//! start window    [t,        t + Te   ]:  y(t) = sinc(pi f Te) exp(+i pi f Te) x(t)
//! end window      [t - Te,   t        ]:  y(t) = sinc(pi f Te) exp(-i pi f Te) x(t)
//! ```
//!
//! with `sinc(z) = sin(z) / z`. The centred window ([`Alignment::Centred`], the study's and the
//! rig's convention) is real: an amplitude loss and no phase. A window that starts at the frame
//! time is the centred window of the instant `t + Te/2`: the frame's effective sampling instant
//! is *delayed* by `Te/2` against its time stamp, so against the time stamps the measured
//! motion leads by `pi f Te` rad ([`box_transfer_complex`] gives the factor in the `exp(+i
//! omega t)` convention of a forward DFT `X[k] = sum x[n] exp(-i 2 pi k n / N)`).
//!
//! `E2PR = f Te` (exposure-to-period ratio, [`e2pr`]) is the one parameter of the box
//! transfer; its first zero is at `E2PR = 1`.
//!
//! # Compensation
//!
//! Dividing the vision spectrum by the transfer removes the blur's amplitude bias. Near the
//! first zero the division amplifies noise without bound (at `E2PR = 0.8` the gain is already
//! 1 / 0.234 = 4.3), so bins with `E2PR > `[`E2PR_LIMIT`] are left uncorrected and counted
//! ([`Compensation`]). The binary centroid is not linear in the image; its transfer depends on
//! the motion amplitude against the target size and the threshold, and is given as a
//! [`CorrectionTable`] (ratio against E2PR on a uniform grid, computed on the host with the
//! imaging model) behind the same [`ExposureTransfer`] interface as the sinc ([`BoxTransfer`]).
//!
//! A centred exposure of a sinusoid gives a binary centroid signal with the symmetries of the
//! sinusoid (odd about the zero crossings, even about the extremes: the blurred image only
//! depends on how long the target spends where, not on the order), so its fundamental has no
//! phase shift either and the table is real. The binary centroid also creates odd harmonics
//! (`3 f`, `5 f`, ...) that a per-bin division cannot undo; the table corrects the fundamental.
//!
//! Entry points for the two spectrum layouts of the crate: [`compensate_dft`] for a whole
//! `n`-point DFT (bins above `n/2` are the negative frequencies, as in
//! [`upsample`](crate::upsample)), [`compensate_one_sided`] for bins `0, df, 2 df, ...` (a real
//! FFT or a Welch estimate), and [`compensate_with`] for any other frequency layout.

use crate::Complex32;
use core::f32::consts::PI;

/// Largest E2PR whose bins are divided by the transfer. At `E2PR = 0.8` the box transfer is
/// `sinc(0.8 pi) = 0.234` (a noise gain of 4.3); towards its first zero at `E2PR = 1` the
/// gain grows without bound.
pub const E2PR_LIMIT: f32 = 0.8;

/// Smallest transfer ratio a bin is divided by: the box transfer at [`E2PR_LIMIT`]
/// (`sinc(0.8 pi) = 0.2339`). A [`CorrectionTable`] whose ratio falls below it (a binary
/// centroid losing the target) leaves those bins uncorrected, like the sinc beyond the limit.
pub const RATIO_FLOOR: f32 = 0.233_872_32;

/// Exposure-to-period ratio `f * Te` of a frequency `f_hz` (Hz) and an exposure `exposure_s`
/// (s). The sign of `f` is kept (negative DFT frequencies give a negative E2PR).
pub fn e2pr(f_hz: f32, exposure_s: f32) -> f32 {
    f_hz * exposure_s
}

/// `sin(pi x) / (pi x)` (1 at `x = 0`), the normalised sinc, in single precision.
pub fn sinc_pi(x: f32) -> f32 {
    let z = PI * x;
    if libm::fabsf(z) < 1e-3 {
        // Taylor: 1 - z^2/6 + z^4/120; the next term is below 2e-16 here.
        let z2 = z * z;
        1.0 - z2 / 6.0 + z2 * z2 / 120.0
    } else {
        libm::sinf(z) / z
    }
}

/// Amplitude transfer of a centred box exposure: `sinc(pi f Te)` for a frequency `f_hz` (Hz)
/// and an exposure `exposure_s` (s). Even in `f`; negative beyond the first zero (`E2PR` in
/// `1..2`), where the motion is seen in antiphase.
pub fn box_transfer(f_hz: f32, exposure_s: f32) -> f32 {
    sinc_pi(e2pr(f_hz, exposure_s))
}

/// Where the exposure window lies against the frame's time stamp `t`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Alignment {
    /// `[t - Te/2, t + Te/2]`: no phase (the study's and the rig's convention).
    #[default]
    Centred,
    /// `[t, t + Te]`: the effective sampling instant is delayed by `Te/2` against the stamp,
    /// so the measured motion leads the stamps by `pi f Te` rad.
    Start,
    /// `[t - Te, t]`: the effective sampling instant is `Te/2` before the stamp, so the
    /// measured motion lags by `pi f Te` rad.
    End,
}

/// Complex transfer of a box exposure with the given alignment, in the convention where a
/// motion `exp(i 2 pi f t)` is measured as `H(f) exp(i 2 pi f t)` (the forward DFT's sign, see
/// the module documentation): `sinc(pi f Te)` times `1`, `exp(+i pi f Te)` or
/// `exp(-i pi f Te)` for [`Alignment::Centred`], [`Alignment::Start`] and [`Alignment::End`].
pub fn box_transfer_complex(f_hz: f32, exposure_s: f32, alignment: Alignment) -> Complex32 {
    let x = e2pr(f_hz, exposure_s);
    let s = sinc_pi(x);
    let phase = match alignment {
        Alignment::Centred => return Complex32::new(s, 0.0),
        Alignment::Start => PI * x,
        Alignment::End => -PI * x,
    };
    Complex32::new(s * libm::cosf(phase), s * libm::sinf(phase))
}

/// A real amplitude transfer of the exposure against E2PR, usable for compensation.
pub trait ExposureTransfer {
    /// The ratio measured / true amplitude at `|E2PR| = e2pr_abs`, or `None` where the
    /// transfer is not to be divided by (beyond [`E2PR_LIMIT`], outside a table, or below
    /// [`RATIO_FLOOR`]).
    fn ratio(&self, e2pr_abs: f32) -> Option<f32>;
}

/// The box (sinc) transfer of a centred exposure, exact for the weighted centroid with its
/// threshold at the background level.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BoxTransfer;

impl ExposureTransfer for BoxTransfer {
    fn ratio(&self, e2pr_abs: f32) -> Option<f32> {
        if e2pr_abs.is_nan() || e2pr_abs > E2PR_LIMIT {
            return None;
        }
        Some(sinc_pi(e2pr_abs))
    }
}

/// Why a [`CorrectionTable`] cannot be built.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum TableError {
    /// Fewer than two nodes.
    TooFewNodes,
    /// The grid step is not a positive finite number.
    Step(f32),
    /// A ratio is not a positive finite number.
    Ratio {
        /// Node index.
        index: usize,
        /// The value.
        value: f32,
    },
}

error_display!(TableError, f, {
    TableError::TooFewNodes => write!(f, "a correction table needs at least two nodes"),
    TableError::Step(s) => write!(f, "table step {s} must be a positive finite E2PR"),
    TableError::Ratio { index, value } => write!(
        f,
        "table ratio {value} at node {index} must be a positive finite number"
    ),
});

/// Amplitude ratio (measured / true) against E2PR on the uniform grid `0, step, 2 step, ...,
/// (N - 1) step`, linearly interpolated: a binary centroid's exposure transfer for one target,
/// threshold and motion amplitude, computed on the host (`host_harness::compensation`).
/// `N` nodes of `f32`: 17 nodes (step 0.05 up to E2PR 0.8) take 72 bytes.
///
/// Outside `0 ..= (N - 1) step` (or beyond [`E2PR_LIMIT`]) and where the interpolated ratio is
/// below [`RATIO_FLOOR`] there is no ratio: those bins are left uncorrected.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CorrectionTable<const N: usize> {
    step: f32,
    ratios: [f32; N],
}

impl<const N: usize> CorrectionTable<N> {
    /// Validates a table: `N >= 2`, `step` positive and finite (E2PR units), every ratio
    /// positive and finite.
    pub fn try_new(step: f32, ratios: [f32; N]) -> Result<Self, TableError> {
        if N < 2 {
            return Err(TableError::TooFewNodes);
        }
        if !(step.is_finite() && step > 0.0) {
            return Err(TableError::Step(step));
        }
        for (index, &value) in ratios.iter().enumerate() {
            if !(value.is_finite() && value > 0.0) {
                return Err(TableError::Ratio { index, value });
            }
        }
        Ok(CorrectionTable { step, ratios })
    }

    /// Grid step (E2PR).
    pub const fn step(&self) -> f32 {
        self.step
    }

    /// The ratios at the nodes `0, step, ...`.
    pub const fn ratios(&self) -> &[f32; N] {
        &self.ratios
    }

    /// Largest E2PR the table covers, `(N - 1) step`.
    pub fn max_e2pr(&self) -> f32 {
        self.step * (N - 1) as f32
    }

    /// The linearly interpolated ratio at `e2pr_abs` (in `0 ..= max_e2pr`), without the
    /// [`E2PR_LIMIT`] and [`RATIO_FLOOR`] checks of [`ExposureTransfer::ratio`].
    pub fn interpolate(&self, e2pr_abs: f32) -> Option<f32> {
        let u = e2pr_abs / self.step;
        // also rejects NaN
        if !(0.0..=(N - 1) as f32).contains(&u) {
            return None;
        }
        // u in [0, N - 1]: the cast truncates towards zero, then clamp to the last interval
        let i = (u as usize).min(N - 2);
        let frac = u - i as f32;
        let (a, b) = (self.ratios[i], self.ratios[i + 1]);
        Some(a + (b - a) * frac)
    }
}

impl<const N: usize> ExposureTransfer for CorrectionTable<N> {
    fn ratio(&self, e2pr_abs: f32) -> Option<f32> {
        if e2pr_abs.is_nan() || e2pr_abs > E2PR_LIMIT {
            return None;
        }
        self.interpolate(e2pr_abs).filter(|r| *r >= RATIO_FLOOR)
    }
}

impl<T: ExposureTransfer + ?Sized> ExposureTransfer for &T {
    fn ratio(&self, e2pr_abs: f32) -> Option<f32> {
        (**self).ratio(e2pr_abs)
    }
}

/// What a compensation did to a spectrum.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Compensation {
    /// Bins divided by the transfer.
    pub corrected: usize,
    /// Bins left as they were (no ratio at their E2PR: beyond [`E2PR_LIMIT`], outside the
    /// table or below [`RATIO_FLOOR`]).
    pub uncorrected: usize,
    /// Index of the first uncorrected bin, if any.
    pub first_uncorrected: Option<usize>,
}

/// Divides every bin `k` by the transfer at `|E2PR| = |freq_hz(k)| * exposure_s`; bins
/// without a ratio are left unchanged and counted. `exposure_s` is the exposure (s) and
/// `freq_hz(k)` the frequency (Hz, any sign) of bin `k`.
pub fn compensate_with(
    transfer: &impl ExposureTransfer,
    bins: &mut [Complex32],
    exposure_s: f32,
    freq_hz: impl Fn(usize) -> f32,
) -> Compensation {
    each_ratio(transfer, bins.len(), exposure_s, freq_hz, |k, r| {
        if let Some(bin) = bins.get_mut(k) {
            *bin /= r;
        }
    })
}

/// Calls `divide(k, ratio)` for every bin `k < len` that has a ratio at its E2PR and counts
/// the bins that have none: the one loop behind [`compensate_with`] and
/// [`dft_compensation`].
fn each_ratio(
    transfer: &impl ExposureTransfer,
    len: usize,
    exposure_s: f32,
    freq_hz: impl Fn(usize) -> f32,
    mut divide: impl FnMut(usize, f32),
) -> Compensation {
    let mut out = Compensation::default();
    for k in 0..len {
        match transfer.ratio(libm::fabsf(e2pr(freq_hz(k), exposure_s))) {
            Some(r) => {
                divide(k, r);
                out.corrected += 1;
            }
            None => {
                out.uncorrected += 1;
                if out.first_uncorrected.is_none() {
                    out.first_uncorrected = Some(k);
                }
            }
        }
    }
    out
}

/// [`compensate_with`] for bins at `0, bin_hz, 2 bin_hz, ...` (a real FFT's or a Welch
/// estimate's one-sided bins; `bin_hz = fs / nfft`).
pub fn compensate_one_sided(
    transfer: &impl ExposureTransfer,
    bins: &mut [Complex32],
    bin_hz: f32,
    exposure_s: f32,
) -> Compensation {
    compensate_with(transfer, bins, exposure_s, |k| k as f32 * bin_hz)
}

/// The signed frequency (Hz) of bin `k` of an `n`-point DFT at `sample_rate_hz`: `k fs / n`
/// for `k <= n/2`, `(k - n) fs / n` above.
fn dft_bin_hz(n: usize, sample_rate_hz: f32) -> impl Fn(usize) -> f32 {
    let df = if n == 0 {
        0.0
    } else {
        sample_rate_hz / n as f32
    };
    move |k| {
        if 2 * k <= n {
            k as f32 * df
        } else {
            (k as f32 - n as f32) * df
        }
    }
}

/// [`compensate_with`] for a whole `n`-point DFT (`n = bins.len()`) of a signal sampled at
/// `sample_rate_hz`: bin `k` is at `k fs / n` for `k <= n/2` and at `(k - n) fs / n` above
/// (the layout [`upsample`](crate::upsample) works on). The transfer is even in `f`, so the
/// corrected spectrum stays Hermitian and its inverse real.
pub fn compensate_dft(
    transfer: &impl ExposureTransfer,
    bins: &mut [Complex32],
    sample_rate_hz: f32,
    exposure_s: f32,
) -> Compensation {
    let n = bins.len();
    compensate_with(transfer, bins, exposure_s, dft_bin_hz(n, sample_rate_hz))
}

/// What [`compensate_dft`] does to an `n`-point spectrum, without one: the bins it divides
/// and the bins it leaves (for a report of a compensation whose spectrum is gone, e.g. the
/// blocks of [`VisionH1`](crate::pipeline::VisionH1), which all have the same bins).
pub fn dft_compensation(
    transfer: &impl ExposureTransfer,
    n: usize,
    sample_rate_hz: f32,
    exposure_s: f32,
) -> Compensation {
    each_ratio(
        transfer,
        n,
        exposure_s,
        dft_bin_hz(n, sample_rate_hz),
        |_, _| {},
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn abs(c: Complex32) -> f32 {
        libm::sqrtf(c.norm_sqr())
    }

    /// Naive forward DFT in f64 (reference).
    fn dft(x: &[f64]) -> Vec<Complex32> {
        let n = x.len();
        (0..n)
            .map(|k| {
                let (mut re, mut im) = (0.0f64, 0.0f64);
                for (j, v) in x.iter().enumerate() {
                    let a = -core::f64::consts::TAU * (k * j) as f64 / n as f64;
                    re += v * a.cos();
                    im += v * a.sin();
                }
                Complex32::new(re as f32, im as f32)
            })
            .collect()
    }

    #[test]
    fn sinc_matches_the_closed_form_and_its_zeros() {
        for x in [1e-6f32, 1e-4, 2e-3, 0.1, 0.5, 0.8, 1.3, 2.5] {
            let want =
                (core::f64::consts::PI * x as f64).sin() / (core::f64::consts::PI * x as f64);
            // f32 evaluation of sin(pi x)/(pi x): a few ulp of the argument near the zeros
            assert!((sinc_pi(x) as f64 - want).abs() < 2e-7, "{x}");
        }
        assert_eq!(sinc_pi(0.0), 1.0);
        assert!(sinc_pi(1.0).abs() < 1e-7 && sinc_pi(2.0).abs() < 1e-7);
        // f32 argument pi * 0.8 is within 2.4e-7 of the true one: 1e-7 on the ratio
        assert!((sinc_pi(E2PR_LIMIT) - RATIO_FLOOR).abs() < 2e-7);
        assert_eq!(box_transfer(-3.0, 0.1), box_transfer(3.0, 0.1));
    }

    /// The box average of `exp(i w s)` over the window of each alignment, by the midpoint
    /// rule with 20 000 steps (an independent numerical reference), against the closed form.
    #[test]
    fn complex_transfer_is_the_window_average_of_a_phasor() {
        let (f, te, t) = (3.7f64, 0.11f64, 0.25f64);
        let w = core::f64::consts::TAU * f;
        for (al, start) in [
            (Alignment::Centred, t - te / 2.0),
            (Alignment::Start, t),
            (Alignment::End, t - te),
        ] {
            let steps = 20_000;
            let (mut re, mut im) = (0.0f64, 0.0f64);
            for j in 0..steps {
                let s = start + (j as f64 + 0.5) * te / steps as f64;
                re += (w * s).cos();
                im += (w * s).sin();
            }
            let avg = (re / steps as f64, im / steps as f64);
            // measured / exp(i w t)
            let (c, sn) = ((w * t).cos(), (w * t).sin());
            let h = (avg.0 * c + avg.1 * sn, avg.1 * c - avg.0 * sn);
            let got = box_transfer_complex(f as f32, te as f32, al);
            // midpoint rule error ~ (w te / steps)^2 / 24 ~ 1e-12; f32 arithmetic ~ 1e-7
            assert!(
                (got.re as f64 - h.0).abs() < 1e-6 && (got.im as f64 - h.1).abs() < 1e-6,
                "{al:?}: {got} vs {h:?}"
            );
        }
    }

    /// A sinusoid blurred analytically by a centred exposure (`A sinc(pi f Te)`), one whole
    /// DFT, compensated: the amplitude comes back, and the bins beyond the limit are counted.
    #[test]
    fn compensating_an_analytically_blurred_sinusoid_restores_its_amplitude() {
        let (n, fs) = (64usize, 50.0f64);
        let te = 0.12f64;
        let (amp, cycles) = (3.0f64, 5usize); // f = 5 fs / n = 3.906 Hz, E2PR 0.47
        let f = cycles as f64 * fs / n as f64;
        let blur = (core::f64::consts::PI * f * te).sin() / (core::f64::consts::PI * f * te);
        let x: Vec<f64> = (0..n)
            .map(|j| amp * blur * (core::f64::consts::TAU * f * j as f64 / fs + 0.3).sin())
            .collect();
        let mut bins = dft(&x);
        let report = compensate_dft(&BoxTransfer, &mut bins, fs as f32, te as f32);
        for k in [cycles, n - cycles] {
            let a = 2.0 * abs(bins[k]) as f64 / n as f64;
            // f32 DFT and sinc: 1e-5 relative
            assert!((a / amp - 1.0).abs() < 1e-5, "bin {k}: {a}");
        }
        // bins with |f| te > 0.8: |k| > 0.8 n / (fs te) = 8.53, i.e. k = 9 ..= 55
        let kmax = (E2PR_LIMIT as f64 * n as f64 / (fs * te)).floor() as usize;
        assert_eq!(report.uncorrected, n - (2 * kmax + 1));
        assert_eq!(report.corrected, 2 * kmax + 1);
        assert_eq!(report.first_uncorrected, Some(kmax + 1));
    }

    #[test]
    fn one_sided_bins_use_k_df_and_stop_at_the_limit() {
        let mut bins = [Complex32::new(1.0, 1.0); 11];
        // df = 1 Hz, Te = 0.1 s: E2PR = k / 10, bins 0..=8 corrected
        let r = compensate_one_sided(&BoxTransfer, &mut bins, 1.0, 0.1);
        assert_eq!(
            (r.corrected, r.uncorrected, r.first_uncorrected),
            (9, 2, Some(9))
        );
        for (k, b) in bins.iter().enumerate().take(9) {
            let want = 1.0 / sinc_pi(k as f32 / 10.0);
            assert!((b.re - want).abs() < 1e-6 * want && b.re == b.im, "{k}");
        }
        assert_eq!(bins[9], Complex32::new(1.0, 1.0));
    }

    #[test]
    fn table_interpolation_is_exact_at_nodes_and_linear_between() {
        let nodes = [1.0f32, 0.96, 0.85, 0.7, 0.5];
        let t = CorrectionTable::try_new(0.2, nodes).unwrap();
        for (i, r) in nodes.iter().enumerate() {
            assert_eq!(t.interpolate(i as f32 * 0.2), Some(*r), "node {i}");
        }
        // midpoints: the mean of the neighbours (f32 rounding of the grid position)
        for i in 0..4 {
            let mid = t.interpolate((i as f32 + 0.5) * 0.2).unwrap();
            assert!((mid - 0.5 * (nodes[i] + nodes[i + 1])).abs() < 1e-6, "{i}");
        }
        assert_eq!(t.interpolate(0.8000001), None);
        assert_eq!(t.interpolate(-0.01), None);
        assert_eq!(t.interpolate(f32::NAN), None);
        assert_eq!(t.max_e2pr(), 0.8);
        // through the transfer interface: the floor applies (0.5 > floor, so all kept)
        assert_eq!(t.ratio(0.8), Some(0.5));
        let low = CorrectionTable::try_new(0.4, [1.0, 0.5, 0.1]).unwrap();
        assert_eq!(low.ratio(0.8), None, "0.1 is below the ratio floor");
    }

    #[test]
    fn a_table_of_the_sinc_compensates_like_the_sinc() {
        let mut nodes = [0.0f32; 33];
        for (i, r) in nodes.iter_mut().enumerate() {
            *r = sinc_pi(i as f32 * 0.025);
        }
        let t = CorrectionTable::try_new(0.025, nodes).unwrap();
        let mut a = [Complex32::new(2.0, -1.0); 40];
        let mut b = a;
        let ra = compensate_one_sided(&t, &mut a, 0.5, 0.07);
        let rb = compensate_one_sided(&BoxTransfer, &mut b, 0.5, 0.07);
        assert_eq!(ra, rb);
        for (x, y) in a.iter().zip(&b) {
            // linear interpolation error of sinc(pi x) on a 0.025 grid: h^2 max|f''| / 8
            // = 0.025^2 * pi^2 / 3 / 8 = 2.6e-4 of the ratio
            assert!(abs(x - y) / abs(*y) < 3e-4, "{x} {y}");
        }
    }

    #[test]
    fn invalid_tables_are_rejected() {
        assert_eq!(
            CorrectionTable::try_new(0.1, [1.0]),
            Err(TableError::TooFewNodes)
        );
        assert_eq!(
            CorrectionTable::try_new(0.0, [1.0, 0.9]),
            Err(TableError::Step(0.0))
        );
        assert!(matches!(
            CorrectionTable::try_new(0.1, [1.0, f32::NAN]),
            Err(TableError::Ratio { index: 1, .. })
        ));
        assert!(matches!(
            CorrectionTable::try_new(0.1, [1.0, -0.2]),
            Err(TableError::Ratio { index: 1, .. })
        ));
    }
}
