//! Fourier (zero-padding) upsampling of camera-rate displacement to the ADC rate (method.md §2.2),
//! optionally fused with the displacement-to-acceleration conversion of [`crate::convert`].
//!
//! A record of `n` samples becomes `m >= n` samples spanning the same time: `X = DFT_n(x)`;
//! `Y` has `m` bins with `Y[k] = X[k]` for the positive and negative frequencies below `n/2`,
//! zeros in between, and for even `n` the Nyquist bin `X[n/2]` split in half between `+n/2`
//! and `-n/2`; `y = IDFT_m(Y) * m / n` (with the unnormalised inverse of [`crate::dft`] that is
//! `sum / n`). This is `scipy.signal.resample`'s convention. `m == n` returns the input.
//!
//! The state owns its buffers, sized by const generics: `M >= m` complex work values and
//! `SCRATCH >= max(scratch_len(n), scratch_len(m))` ([`scratch_capacity`]). 1200 -> 20480
//! (10 s at 120 fps to 2048 Hz) needs `Upsampler<20480, { scratch_capacity(1200, 20480) }>`;
//! 120 -> 2048 needs `Upsampler<2048, { scratch_capacity(120, 2048) }>` (about 17 KiB).
//!
//! ```
//! use firmware_core::upsample::{scratch_capacity, Upsampler};
//! // one second at 12 fps to 64 Hz, built in place in a `static` on an MCU:
//! // `static mut UP: Up = Up::new();` then `configure`
//! type Up = Upsampler<64, { scratch_capacity(12, 64) }>;
//! let mut up = Up::try_new(12, 64).unwrap();
//! let x: [f32; 12] = core::array::from_fn(|j| libm::sinf(2.0 * core::f32::consts::PI * j as f32 / 12.0));
//! let mut y = [0.0f32; 64];
//! up.process(&x, &mut y).unwrap();
//! // the sinusoid at the new rate
//! assert!((y[16] - 1.0).abs() < 1e-5);
//! ```

use crate::dft::{scratch_len, Dft, DftError, Direction};
use crate::exposure::{self, BoxTransfer, Compensation};
use crate::{BufferError, Complex32};
use core::f32::consts::PI;

/// Why an upsampling plan or an [`Upsampler`] cannot be built (checked once; running a plan
/// can only fail on a caller buffer of the wrong length, [`BufferError`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ConfigError {
    /// `n` is zero or `m < n` (this type only upsamples).
    Lengths {
        /// Input length.
        n: usize,
        /// Output length.
        m: usize,
    },
    /// `m` exceeds the work capacity `M`.
    Capacity {
        /// Output length asked for.
        m: usize,
        /// Capacity `M`.
        capacity: usize,
    },
    /// The DFT scratch capacity is too small (see [`scratch_capacity`]).
    Scratch {
        /// Scratch values needed.
        needed: usize,
        /// Capacity `SCRATCH`.
        capacity: usize,
    },
    /// A transform length is not supported by [`crate::dft`].
    Dft(DftError),
    /// The output rate is not an integer multiple of the input rate times `n`: `n * to / from`
    /// is not an integer.
    RateRatio,
}

error_display!(ConfigError, f, {
    ConfigError::Lengths { n, m } => {
        write!(f, "cannot upsample {n} samples to {m}: need 1 <= n <= m")
    }
    ConfigError::Capacity { m, capacity } => {
        write!(f, "output length {m} exceeds the capacity {capacity}")
    }
    ConfigError::Scratch { needed, capacity } => write!(
        f,
        "DFT scratch needs {needed} values, the capacity is {capacity}"
    ),
    ConfigError::Dft(e) => write!(f, "{e}"),
    ConfigError::RateRatio => write!(
        f,
        "the record length times the rate ratio is not an integer number of samples"
    ),
});

impl From<DftError> for ConfigError {
    fn from(e: DftError) -> Self {
        ConfigError::Dft(e)
    }
}

/// Scratch capacity for upsampling `n -> m` (0 if a length is unsupported; `try_new` then
/// rejects it). Usable in const context.
pub const fn scratch_capacity(n: usize, m: usize) -> usize {
    let a = match scratch_len(n) {
        Some(v) => v,
        None => 0,
    };
    let b = match scratch_len(m) {
        Some(v) => v,
        None => 0,
    };
    if a > b {
        a
    } else {
        b
    }
}

/// `n * to / from` when it is an integer (rates in Hz as integers or exact ratios).
pub const fn output_len(n: usize, from_hz: u32, to_hz: u32) -> Option<usize> {
    if from_hz == 0 {
        return None;
    }
    let num = n as u64 * to_hz as u64;
    if num % from_hz as u64 != 0 {
        return None;
    }
    Some((num / from_hz as u64) as usize)
}

/// The displacement-to-acceleration conversion fused with the upsampling: the spectrum times
/// `-(2 pi f)^2 * scale` (DC zeroed), as [`Upsampler::process_acceleration`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Accel {
    /// The input's sample rate, Hz (the bins are at `k fs_in_hz / n`).
    pub fs_in_hz: f32,
    /// The unit conversion: input unit times s^-2 to the output unit (`1e-3` for mm in, m/s^2
    /// out).
    pub scale: f32,
}

/// What a run of an [`UpsamplePlan`] does besides upsampling: the options of
/// [`UpsamplePlan::process`] and [`Upsampler::process_options`]. The default is plain
/// upsampling.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct UpsampleOptions {
    /// `Some(_)`: convert displacement to acceleration ([`Accel`]).
    pub accel: Option<Accel>,
    /// `Some(next)`: end matching of a streamed block (see [`UpsamplePlan::process`]).
    pub end_match: Option<f32>,
    /// `Some(_)`: divide the input spectrum by the exposure transfer (see
    /// [`ExposureCompensation`]).
    pub exposure: Option<ExposureCompensation>,
}

/// Exposure compensation in the upsampling (method.md §2.6): every bin of the input's
/// `n`-point spectrum is divided by the box transfer `sinc(pi f Te)` of a centred exposure
/// ([`exposure::BoxTransfer`], exact for the weighted centroid), except the bins with
/// `E2PR = |f| Te >` [`exposure::E2PR_LIMIT`] (0.8, a noise gain of 4.3 and growing without
/// bound towards the first zero at 1): those are left unchanged and counted in the
/// [`Compensation`] the run returns. It is done on the `n` input bins before the zero padding
/// (the padded bins are zero, and only the input's bins are reported), in the same spectral
/// pass as the acceleration conversion; the end-matching line is not divided (a box average
/// leaves a straight line unchanged).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ExposureCompensation {
    /// Input (camera) sampling rate, Hz: bin `k` of the input spectrum is at `k fs_in / n`.
    pub fs_in_hz: f32,
    /// Exposure time `Te`, s (`>= 0`; 0 is no blur and changes nothing).
    pub exposure_s: f32,
}

impl ExposureCompensation {
    /// What the compensation does to the spectrum of `n` input samples (without running it):
    /// [`exposure::dft_compensation`] with the box transfer.
    pub fn bins(&self, n: usize) -> Compensation {
        exposure::dft_compensation(&BoxTransfer, n, self.fs_in_hz, self.exposure_s)
    }
}

/// The plan of an `n -> m` Fourier upsampling (lengths and the two DFT plans), with no
/// buffers: [`process`](Self::process) runs it in caller buffers, so a firmware can
/// lend it the work buffer of another stage (the Welch estimate's, see [`crate::pipeline`]).
/// [`Upsampler`] is the same with owned buffers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UpsamplePlan {
    n: usize,
    m: usize,
    fwd: Dft,
    inv: Dft,
}

impl UpsamplePlan {
    /// The plan of nothing (`0 -> 0`): the placeholder of an unconfigured [`Upsampler`] or
    /// pipeline (all zero bytes).
    pub(crate) const NONE: UpsamplePlan = UpsamplePlan {
        n: 0,
        m: 0,
        fwd: Dft::NONE,
        inv: Dft::NONE,
    };

    /// Plans `n -> m` (`1 <= n <= m`, both lengths supported by [`crate::dft`]).
    pub const fn try_new(n: usize, m: usize) -> Result<Self, ConfigError> {
        if n == 0 || m < n {
            return Err(ConfigError::Lengths { n, m });
        }
        let fwd = match Dft::try_new(n) {
            Ok(d) => d,
            Err(e) => return Err(ConfigError::Dft(e)),
        };
        let inv = match Dft::try_new(m) {
            Ok(d) => d,
            Err(e) => return Err(ConfigError::Dft(e)),
        };
        Ok(UpsamplePlan { n, m, fwd, inv })
    }

    /// Plans the upsampling of `n` samples at `from_hz` to `to_hz` (integer rates; the output
    /// length `n * to / from` must be an integer).
    pub const fn from_rates(n: usize, from_hz: u32, to_hz: u32) -> Result<Self, ConfigError> {
        match output_len(n, from_hz, to_hz) {
            Some(m) => Self::try_new(n, m),
            None => Err(ConfigError::RateRatio),
        }
    }

    /// Input length.
    pub const fn input_len(&self) -> usize {
        self.n
    }

    /// Output length.
    pub const fn output_len(&self) -> usize {
        self.m
    }

    /// Scratch values [`process`](Self::process) needs (the larger of the two
    /// transforms' [`crate::dft::scratch_len`]).
    pub const fn scratch_len(&self) -> usize {
        let (a, b) = (self.fwd.scratch_len(), self.inv.scratch_len());
        if a > b {
            a
        } else {
            b
        }
    }

    /// Upsamples `input` (`n` values) into the output samples `first .. first + output.len()`
    /// (`first + output.len() <= m`; `first = 0` and `m` values for a whole record), using
    /// `work` (at least `m` values) and `scratch` (at least [`scratch_len`](Self::scratch_len)),
    /// both overwritten, with the [`UpsampleOptions`]; returns what the exposure compensation
    /// did ([`Compensation::default`] without one). The one entry point of the plan.
    ///
    /// With `options.end_match = Some(next)`, `next` being the sample that follows the block,
    /// the straight line through the first input sample (at position 0) and `next` (at position
    /// `n`) is subtracted before the transform and added back to the output (its second
    /// derivative is zero, so nothing is added with `accel`). The subtraction removes the jump
    /// that the transform's periodic extension of a block would otherwise see between its last
    /// and first samples (Gibbs ringing, amplified by `omega^2` in the acceleration); a block
    /// that already holds whole periods has `next == input[0]` and is left as it is.
    ///
    /// Errors (nothing written to `output`): [`BufferError`] for a wrong `input` length, a
    /// range past `m` (`expected = m - first`), too short a `work` or too small a `scratch`.
    pub fn process(
        &self,
        input: &[f32],
        output: &mut [f32],
        first: usize,
        options: UpsampleOptions,
        work: &mut [Complex32],
        scratch: &mut [Complex32],
    ) -> Result<Compensation, BufferError> {
        let (n, m) = (self.n, self.m);
        if input.len() != n {
            return Err(BufferError {
                expected: n,
                got: input.len(),
            });
        }
        if first > m || output.len() > m - first {
            return Err(BufferError {
                expected: m.saturating_sub(first),
                got: output.len(),
            });
        }
        if work.len() < m {
            return Err(BufferError {
                expected: m,
                got: work.len(),
            });
        }
        if scratch.len() < self.scratch_len() {
            return Err(BufferError {
                expected: self.scratch_len(),
                got: scratch.len(),
            });
        }
        Ok(self.run_part((input, output, first), options, (work, scratch)))
    }

    /// [`process`](Self::process) for the crate's own callers, whose buffers follow
    /// from a validated configuration: infallible (a buffer of the wrong length, impossible
    /// there, leaves `output` untouched and reports no compensation). The arguments are
    /// `process`'s, grouped as what is read and written and the transform's buffers.
    pub(crate) fn run_part(
        &self,
        (input, output, first): (&[f32], &mut [f32], usize),
        options: UpsampleOptions,
        (work, scratch): (&mut [Complex32], &mut [Complex32]),
    ) -> Compensation {
        let none = Compensation::default();
        let UpsampleOptions {
            accel,
            end_match,
            exposure,
        } = options;
        let (n, m) = (self.n, self.m);
        if n == 0 || input.len() != n || first > m || output.len() > m - first {
            return none;
        }
        // the line a + slope * i through the first sample and the next block's (i in input
        // samples)
        let (a, slope) = match (end_match, input.first()) {
            (Some(next), Some(&a)) => (a, (next - a) / n as f32),
            _ => (0.0, 0.0),
        };
        let Some(work) = work.get_mut(..m) else {
            return none;
        };
        if scratch.len() < self.scratch_len() {
            return none;
        }
        for (i, (w, x)) in work.iter_mut().zip(input).enumerate() {
            *w = Complex32::new(*x - (a + slope * i as f32), 0.0);
        }
        let Some(head) = work.get_mut(..n) else {
            return none;
        };
        self.fwd.run(head, scratch, Direction::Forward);
        let compensation = match exposure {
            Some(e) => exposure::compensate_dft(&BoxTransfer, head, e.fs_in_hz, e.exposure_s),
            None => none,
        };
        // bins kept on each side: positive 0 ..= pos - 1, negative 1 ..= neg
        let even = n % 2 == 0;
        let pos = if even { n / 2 } else { n.div_ceil(2) };
        let neg = if even { n / 2 - 1 } else { (n - 1) / 2 };
        let nyq = if even {
            work.get(n / 2).map(|v| *v * 0.5)
        } else {
            None
        };
        if m > n {
            // move the negative frequencies to the top; in ascending j no source is
            // overwritten before it is moved (targets m - j lie above sources n - j' for j' > j)
            for j in 1..=neg {
                if let Some(v) = work.get(n - j).copied() {
                    if let Some(d) = work.get_mut(m - j) {
                        *d = v;
                    }
                }
            }
            if let Some(mid) = work.get_mut(pos..m - neg) {
                for w in mid.iter_mut() {
                    *w = Complex32::new(0.0, 0.0);
                }
            }
            if let Some(v) = nyq {
                for i in [n / 2, m - n / 2] {
                    if let Some(d) = work.get_mut(i) {
                        *d = v;
                    }
                }
            }
        }
        if let Some(Accel {
            fs_in_hz: fs,
            scale,
        }) = accel
        {
            let df = fs / n as f32;
            if let Some(w0) = work.first_mut() {
                *w0 = Complex32::new(0.0, 0.0);
            }
            for (k, w) in work.iter_mut().enumerate().skip(1) {
                // signed frequency of bin k of the m-point spectrum (same bins as the input)
                let kk = if k <= m / 2 {
                    k as f32
                } else {
                    k as f32 - m as f32
                };
                let om = 2.0 * PI * kk * df;
                *w *= -om * om * scale;
            }
        }
        self.inv.run(work, scratch, Direction::Inverse);
        let s = 1.0 / n as f32;
        // the line on the output grid (output sample j is at input position j n / m)
        let (a, slope) = if accel.is_some() {
            (0.0, 0.0)
        } else {
            (a, slope * n as f32 / m as f32)
        };
        let kept = work.iter().skip(first);
        for (j, (o, w)) in output.iter_mut().zip(kept).enumerate() {
            *o = w.re * s + (a + slope * (first + j) as f32);
        }
        compensation
    }
}

impl<const M: usize, const SCRATCH: usize> Default for Upsampler<M, SCRATCH> {
    fn default() -> Self {
        Self::new()
    }
}

/// Fourier upsampler from `n` to `m` samples with owned buffers (`M` work values, `SCRATCH`
/// DFT scratch values): an [`UpsamplePlan`] and its buffers.
#[derive(Debug, Clone)]
pub struct Upsampler<const M: usize, const SCRATCH: usize> {
    plan: UpsamplePlan,
    work: [Complex32; M],
    scratch: [Complex32; SCRATCH],
}

impl<const M: usize, const SCRATCH: usize> Upsampler<M, SCRATCH> {
    /// An unconfigured upsampler (plan `0 -> 0`: `process` accepts only empty slices) to
    /// build in place in a `static` (all zero bytes: `.bss`), then
    /// [`configure`](Self::configure).
    pub const fn new() -> Self {
        Upsampler {
            plan: UpsamplePlan::NONE,
            work: [Complex32::new(0.0, 0.0); M],
            scratch: [Complex32::new(0.0, 0.0); SCRATCH],
        }
    }

    /// Plans `n -> m` (`1 <= n <= m <= M`). `const`: a `static` initialiser builds it in
    /// place, checked at compile time.
    pub const fn try_new(n: usize, m: usize) -> Result<Self, ConfigError> {
        match UpsamplePlan::try_new(n, m) {
            Ok(plan) => Self::with_plan(plan),
            Err(e) => Err(e),
        }
    }

    /// Plans the upsampling of `n` samples at `from_hz` to `to_hz` (integer rates; the output
    /// length `n * to / from` must be an integer).
    pub const fn from_rates(n: usize, from_hz: u32, to_hz: u32) -> Result<Self, ConfigError> {
        match UpsamplePlan::from_rates(n, from_hz, to_hz) {
            Ok(plan) => Self::with_plan(plan),
            Err(e) => Err(e),
        }
    }

    /// Re-plans in place for `plan` (checked against the capacities as in
    /// [`try_new`](Self::try_new)); on error nothing changes.
    pub fn configure(&mut self, plan: UpsamplePlan) -> Result<(), ConfigError> {
        Self::check(&plan)?;
        self.plan = plan;
        Ok(())
    }

    const fn check(plan: &UpsamplePlan) -> Result<(), ConfigError> {
        if plan.m > M {
            return Err(ConfigError::Capacity {
                m: plan.m,
                capacity: M,
            });
        }
        if plan.scratch_len() > SCRATCH {
            return Err(ConfigError::Scratch {
                needed: plan.scratch_len(),
                capacity: SCRATCH,
            });
        }
        Ok(())
    }

    const fn with_plan(plan: UpsamplePlan) -> Result<Self, ConfigError> {
        if let Err(e) = Self::check(&plan) {
            return Err(e);
        }
        Ok(Upsampler {
            plan,
            work: [Complex32::new(0.0, 0.0); M],
            scratch: [Complex32::new(0.0, 0.0); SCRATCH],
        })
    }

    /// The plan (lengths and transforms).
    pub fn plan(&self) -> &UpsamplePlan {
        &self.plan
    }

    /// Input length.
    pub fn input_len(&self) -> usize {
        self.plan.n
    }

    /// Output length.
    pub fn output_len(&self) -> usize {
        self.plan.m
    }

    /// Upsamples `input` (`n` values) into `output` (`m` values).
    pub fn process(&mut self, input: &[f32], output: &mut [f32]) -> Result<(), BufferError> {
        self.process_options(input, output, UpsampleOptions::default())
            .map(|_| ())
    }

    /// Upsamples and converts displacement to acceleration in one pass (method.md §2.3 fused with
    /// 2.2): the spectrum is multiplied by `-(2 pi f)^2 * scale` (DC zeroed) before the inverse
    /// transform. `fs_in_hz` is the input sampling rate (the bins are at `k fs_in / n`);
    /// `scale` converts the input unit times s^-2 to the output unit (e.g. `1e-3` for mm in,
    /// m/s^2 out).
    pub fn process_acceleration(
        &mut self,
        input: &[f32],
        output: &mut [f32],
        fs_in_hz: f32,
        scale: f32,
    ) -> Result<(), BufferError> {
        let options = UpsampleOptions {
            accel: Some(Accel { fs_in_hz, scale }),
            ..UpsampleOptions::default()
        };
        self.process_options(input, output, options).map(|_| ())
    }

    /// Upsamples `input` (`n` values) into `output` (`m` values) with the [`UpsampleOptions`]
    /// (acceleration, end matching, exposure compensation: see
    /// [`UpsamplePlan::process`]); returns what the exposure compensation did.
    ///
    /// ```
    /// use firmware_core::upsample::{scratch_capacity, ExposureCompensation, UpsampleOptions, Upsampler};
    /// // 12 fps, 40 ms exposure: a 3 Hz tone is seen at sinc(pi 3 0.04) = 0.94 of its amplitude
    /// type Up = Upsampler<64, { scratch_capacity(12, 64) }>;
    /// let mut up = Up::try_new(12, 64).unwrap();
    /// let (f, te) = (3.0, 0.04);
    /// let seen = firmware_core::exposure::box_transfer(f, te);
    /// let x: [f32; 12] = core::array::from_fn(|j| {
    ///     seen * libm::sinf(2.0 * core::f32::consts::PI * f * j as f32 / 12.0)
    /// });
    /// let exposure = Some(ExposureCompensation { fs_in_hz: 12.0, exposure_s: te });
    /// let options = UpsampleOptions { exposure, ..UpsampleOptions::default() };
    /// let mut y = [0.0f32; 64];
    /// let c = up.process_options(&x, &mut y, options).unwrap();
    /// // 64 / 12 output samples per frame: y[16] is at t = 0.25 s, sin(2 pi 3 0.25) = -1
    /// assert!((y[16] + 1.0).abs() < 1e-4);
    /// // E2PR = |f| 0.04 <= 0.8 for every bin up to the 6 Hz Nyquist: all 12 corrected
    /// assert_eq!((c.corrected, c.uncorrected), (12, 0));
    /// ```
    pub fn process_options(
        &mut self,
        input: &[f32],
        output: &mut [f32],
        options: UpsampleOptions,
    ) -> Result<Compensation, BufferError> {
        if output.len() != self.plan.m {
            return Err(BufferError {
                expected: self.plan.m,
                got: output.len(),
            });
        }
        let (work, scratch) = (&mut self.work, &mut self.scratch);
        self.plan.process(input, output, 0, options, work, scratch)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec;
    use std::vec::Vec;

    /// f64 reference: direct DFT, method.md §2.2 bin mapping, direct inverse.
    fn reference(x: &[f32], m: usize) -> Vec<f64> {
        let n = x.len();
        let tau = std::f64::consts::TAU;
        let big: Vec<(f64, f64)> = (0..n)
            .map(|k| {
                x.iter().enumerate().fold((0.0, 0.0), |(re, im), (j, v)| {
                    let a = -tau * ((j * k) % n) as f64 / n as f64;
                    (re + *v as f64 * a.cos(), im + *v as f64 * a.sin())
                })
            })
            .collect();
        let mut y = vec![(0.0, 0.0); m];
        for k in 0..n {
            let (re, im) = big[k];
            if n % 2 == 0 && k == n / 2 {
                y[n / 2].0 += re / 2.0;
                y[n / 2].1 += im / 2.0;
                y[m - n / 2].0 += re / 2.0;
                y[m - n / 2].1 += im / 2.0;
            } else if 2 * k < n {
                y[k] = (re, im);
            } else {
                y[m - (n - k)] = (re, im);
            }
        }
        (0..m)
            .map(|t| {
                y.iter().enumerate().fold(0.0, |acc, (k, (re, im))| {
                    let a = tau * ((k * t) % m) as f64 / m as f64;
                    acc + re * a.cos() - im * a.sin()
                }) / n as f64
            })
            .collect()
    }

    fn signal(n: usize) -> Vec<f32> {
        (0..n)
            .map(|i| {
                let t = i as f32;
                (0.37 * t).sin() + 0.5 * (1.3 * t + 0.2).cos() + 0.01 * t
            })
            .collect()
    }

    fn check<const M: usize, const S: usize>(n: usize, m: usize) {
        let x = signal(n);
        let want = reference(&x, m);
        let mut up = Upsampler::<M, S>::try_new(n, m).unwrap();
        let mut y = vec![0.0f32; m];
        up.process(&x, &mut y).unwrap();
        let (err, rms) = crate::test_support::max_error_and_rms(&y, &want);
        assert!(err / rms < 1e-5, "{n} -> {m}: max error {err} vs rms {rms}");
    }

    #[test]
    fn matches_the_direct_reference_for_odd_and_even_lengths() {
        check::<256, { scratch_capacity(15, 256) }>(15, 256);
        check::<256, { scratch_capacity(16, 256) }>(16, 256);
        check::<363, { scratch_capacity(121, 363) }>(121, 363);
        check::<128, { scratch_capacity(75, 128) }>(75, 128);
        check::<2048, { scratch_capacity(120, 2048) }>(120, 2048);
        check::<101, { scratch_capacity(100, 101) }>(100, 101);
        check::<100, { scratch_capacity(100, 100) }>(100, 100);
    }

    #[test]
    fn band_limited_sinusoid_upsamples_to_its_analytic_values() {
        // 7 cycles in 120 samples, upsampled to 2048: exact samples of the same sinusoid
        let (n, m) = (120, 2048);
        let x: Vec<f32> = (0..n)
            .map(|i| (2.0 * PI * 7.0 * i as f32 / n as f32 + 0.3).sin())
            .collect();
        let mut up =
            Upsampler::<2048, { scratch_capacity(120, 2048) }>::from_rates(n, 120, 2048).unwrap();
        let mut y = vec![0.0f32; m];
        up.process(&x, &mut y).unwrap();
        for (i, v) in y.iter().enumerate() {
            let want = libm::sinf(2.0 * PI * 7.0 * i as f32 / m as f32 + 0.3);
            assert!((v - want).abs() < 2e-5, "sample {i}: {v} vs {want}");
        }
        // and the fused conversion gives -omega^2 times it (fs = 120 Hz -> f = 7 Hz)
        let mut a = vec![0.0f32; m];
        up.process_acceleration(&x, &mut a, 120.0, 1.0).unwrap();
        let om = 2.0 * PI * 7.0;
        for (i, v) in a.iter().enumerate() {
            let want = -om * om * libm::sinf(2.0 * PI * 7.0 * i as f32 / m as f32 + 0.3);
            // f32 rounding amplified by omega^2: 1e-4 of the peak
            assert!(
                (v - want).abs() < 1e-4 * om * om,
                "sample {i}: {v} vs {want}"
            );
        }
    }

    #[test]
    fn decimating_the_output_returns_the_input() {
        // 1200 -> 20480 is not an integer ratio; 15 -> 256 neither; use 60 -> 240 (x4)
        let x = signal(60);
        let mut up = Upsampler::<240, { scratch_capacity(60, 240) }>::try_new(60, 240).unwrap();
        let mut y = vec![0.0f32; 240];
        up.process(&x, &mut y).unwrap();
        for (i, v) in x.iter().enumerate() {
            assert!((y[4 * i] - v).abs() < 1e-5, "sample {i}");
        }
    }

    #[test]
    fn parts_and_end_matching() {
        let (n, m) = (60, 256);
        let plan = UpsamplePlan::try_new(n, m).unwrap();
        let mut work = vec![Complex32::new(0.0, 0.0); m];
        let mut scratch = vec![Complex32::new(0.0, 0.0); plan.scratch_len()];
        let x = signal(n);
        let mut full = vec![0.0f32; m];
        let plain = UpsampleOptions::default();
        plan.process(&x, &mut full, 0, plain, &mut work, &mut scratch)
            .unwrap();
        // a part is the same samples as the whole output
        let mut part = vec![0.0f32; 100];
        plan.process(&x, &mut part, 64, plain, &mut work, &mut scratch)
            .unwrap();
        assert_eq!(part[..], full[64..164]);
        assert_eq!(
            plan.process(&x, &mut part, 157, plain, &mut work, &mut scratch),
            Err(BufferError {
                expected: 99,
                got: 100
            })
        );
        // end matching: a ramp (whose periodic extension jumps) comes back exactly, and its
        // acceleration is zero; without it the jump rings through the whole block
        let ramp: Vec<f32> = (0..n).map(|i| 0.5 + 0.1 * i as f32).collect();
        let want = |j: usize| 0.5 + 0.1 * (j * n) as f32 / m as f32;
        let matched = UpsampleOptions {
            end_match: Some(0.5 + 0.1 * n as f32),
            ..plain
        };
        plan.process(&ramp, &mut full, 0, matched, &mut work, &mut scratch)
            .unwrap();
        for (j, v) in full.iter().enumerate() {
            assert!((v - want(j)).abs() < 1e-5, "sample {j}: {v} vs {}", want(j));
        }
        let accel = Some(Accel {
            fs_in_hz: 60.0,
            scale: 1.0,
        });
        plan.process(
            &ramp,
            &mut full,
            0,
            UpsampleOptions { accel, ..matched },
            &mut work,
            &mut scratch,
        )
        .unwrap();
        assert!(full.iter().all(|v| v.abs() < 1e-2), "{:?}", &full[..4]);
        plan.process(&ramp, &mut full, 0, plain, &mut work, &mut scratch)
            .unwrap();
        let worst = (0..m)
            .map(|j| (full[j] - want(j)).abs())
            .fold(0.0, f32::max);
        assert!(worst > 0.5, "without end matching: {worst}");
    }

    #[test]
    fn rejects_bad_settings_and_buffers() {
        type U = Upsampler<256, { scratch_capacity(15, 256) }>;
        assert!(matches!(
            U::try_new(0, 10),
            Err(ConfigError::Lengths { .. })
        ));
        assert!(matches!(
            U::try_new(20, 10),
            Err(ConfigError::Lengths { .. })
        ));
        assert!(matches!(
            U::try_new(15, 300),
            Err(ConfigError::Capacity { .. })
        ));
        assert!(matches!(
            Upsampler::<256, 0>::try_new(15, 256),
            Err(ConfigError::Scratch { .. })
        ));
        assert_eq!(
            U::from_rates(15, 120, 2047).err(),
            Some(ConfigError::RateRatio)
        );
        let mut u = U::try_new(15, 256).unwrap();
        let mut out = [0.0f32; 255];
        assert!(matches!(
            u.process(&[0.0; 15], &mut out),
            Err(BufferError { .. })
        ));
    }

    /// One second at 120 fps of `sin(2 pi f t + 0.4)` seen through a centred box exposure of
    /// `te` s: the exact box average, `sinc(pi f te) sin(2 pi f t + 0.4)` (closed form, f64).
    fn box_averaged(f: f64, te: f64) -> Vec<f32> {
        let z = std::f64::consts::PI * f * te;
        let sinc = if z == 0.0 { 1.0 } else { z.sin() / z };
        (0..120)
            .map(|j| (sinc * (std::f64::consts::TAU * f * j as f64 / 120.0 + 0.4).sin()) as f32)
            .collect()
    }

    /// Largest `|y[j] - want(t_j)|` over an output at 480 Hz.
    fn max_error(y: &[f32], want: impl Fn(f64) -> f64) -> f64 {
        y.iter()
            .enumerate()
            .map(|(j, v)| (*v as f64 - want(j as f64 / 480.0)).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn exposure_compensation_recovers_a_box_averaged_sinusoid() {
        type Up = Upsampler<480, { scratch_capacity(120, 480) }>;
        let mut up = Up::try_new(120, 480).unwrap();
        let (f, te) = (17.0, 0.03); // E2PR 0.51: seen at sinc(0.51 pi) = 0.614
        let sinc = crate::exposure::box_transfer(f as f32, te as f32) as f64;
        let x = box_averaged(f, te);
        let true_x = |t: f64| (std::f64::consts::TAU * f * t + 0.4).sin();
        let compensation = ExposureCompensation {
            fs_in_hz: 120.0,
            exposure_s: te as f32,
        };
        let exposure = Some(compensation);
        let mut y = vec![0.0f32; 480];
        // uncompensated: the motion times the sinc factor (f32 DFT rounding, amplitude 1)
        up.process(&x, &mut y).unwrap();
        assert!(max_error(&y, |t| sinc * true_x(t)) < 1e-4);
        // 1 - sinc = 0.386 at the peaks; the 480 Hz grid comes within 1 % of them
        assert!(max_error(&y, true_x) > 0.99 * (1.0 - sinc));
        // compensated: the motion itself (f32 rounding of the frames and transforms)
        let options = UpsampleOptions {
            exposure,
            ..UpsampleOptions::default()
        };
        let c = up.process_options(&x, &mut y, options).unwrap();
        let err = max_error(&y, true_x);
        assert!(err < 1e-3, "max error {err}");
        // E2PR = |k| 0.03 <= 0.8 for |k| <= 26 Hz: 53 of the 120 bins corrected
        assert_eq!(
            c,
            Compensation {
                corrected: 53,
                uncorrected: 67,
                first_uncorrected: Some(27),
            }
        );
        assert_eq!(compensation.bins(120), c);
        // fused with -omega^2 in the same pass: -(2 pi f)^2 sin, scaled to amplitude 1
        let w2 = (std::f64::consts::TAU * f).powi(2);
        let options = UpsampleOptions {
            accel: Some(Accel {
                fs_in_hz: 120.0,
                scale: (1.0 / w2) as f32,
            }),
            exposure,
            end_match: None,
        };
        up.process_options(&x, &mut y, options).unwrap();
        let err = max_error(&y, |t| -true_x(t));
        assert!(err < 1e-3, "acceleration: max error {err}");
    }

    #[test]
    fn bins_beyond_the_e2pr_limit_are_left_and_counted() {
        type Up = Upsampler<48, { scratch_capacity(12, 48) }>;
        let mut up = Up::try_new(12, 48).unwrap();
        // 12 fps, 0.45 s exposure: E2PR 0 and 0.45 for 0 and 1 Hz (corrected), 0.9 for 2 Hz
        // (beyond the limit, where the transfer is only 0.109), more above
        let exposure = ExposureCompensation {
            fs_in_hz: 12.0,
            exposure_s: 0.45,
        };
        let options = UpsampleOptions {
            exposure: Some(exposure),
            ..UpsampleOptions::default()
        };
        let want = Compensation {
            corrected: 3, // bins 0, 1 and 11 (-1 Hz)
            uncorrected: 9,
            first_uncorrected: Some(2),
        };
        assert_eq!(exposure.bins(12), want);
        // DC plus 2 Hz: the 2 Hz bins are left (divided, they would be 9.2 times larger), DC
        // is divided by exactly 1; what changes is the f32 rounding noise of the +-1 Hz bins,
        // amplified by 1 / sinc(0.45 pi) = 1.4
        let x: Vec<f32> = (0..12)
            .map(|j| 0.25 + libm::cosf(2.0 * PI * 2.0 * j as f32 / 12.0 + 0.3))
            .collect();
        let (mut plain, mut comp) = (vec![0.0f32; 48], vec![0.0f32; 48]);
        up.process(&x, &mut plain).unwrap();
        assert_eq!(up.process_options(&x, &mut comp, options), Ok(want));
        for (j, (c, p)) in comp.iter().zip(&plain).enumerate() {
            assert!((c - p).abs() < 1e-6, "sample {j}: {c} vs {p}");
        }
        // a 1 Hz tone (E2PR 0.45) is divided by its transfer, the 2 Hz one is not
        let gain = 1.0 / crate::exposure::box_transfer(1.0, 0.45);
        let tone = |j: usize| libm::sinf(2.0 * PI * j as f32 / 12.0);
        let x2: Vec<f32> = x.iter().enumerate().map(|(j, v)| v + tone(j)).collect();
        up.process_options(&x2, &mut comp, options).unwrap();
        for (j, (c, p)) in comp.iter().zip(&plain).enumerate() {
            let added = libm::sinf(2.0 * PI * j as f32 / 48.0) * gain;
            assert!(
                (c - p - added).abs() < 1e-5,
                "sample {j}: {c} - {p} vs {added}"
            );
        }
    }

    #[test]
    fn without_exposure_compensation_the_output_is_bit_identical() {
        type Up = Upsampler<363, { scratch_capacity(121, 363) }>;
        let mut up = Up::try_new(121, 363).unwrap();
        let x = signal(121);
        let a = Accel {
            fs_in_hz: 120.0,
            scale: 1e-3,
        };
        for accel in [None, Some(a)] {
            let mut want = vec![0.0f32; 363];
            match accel {
                None => up.process(&x, &mut want).unwrap(),
                Some(a) => up
                    .process_acceleration(&x, &mut want, a.fs_in_hz, a.scale)
                    .unwrap(),
            }
            let mut y = vec![0.0f32; 363];
            let options = UpsampleOptions {
                accel,
                ..UpsampleOptions::default()
            };
            let c = up.process_options(&x, &mut y, options).unwrap();
            assert_eq!((c, y), (Compensation::default(), want));
        }
    }

    #[test]
    fn state_sizes() {
        // RAM an MCU needs (listed in the README)
        assert!(
            core::mem::size_of::<Upsampler<2048, { scratch_capacity(120, 2048) }>>() < 20 * 1024
        );
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// Upsampling by an integer factor L then keeping every L-th sample returns the input,
        /// for any signal and any n (odd or even: the split Nyquist halves recombine there).
        #[test]
        fn decimation_returns_any_input(
            n in 1usize..=64,
            factor in 1usize..=8,
            seed in proptest::collection::vec(-1.0f32..1.0, 64),
        ) {
            let m = n * factor;
            let x = &seed[..n];
            let mut up = Upsampler::<512, 8192>::try_new(n, m).unwrap();
            let mut y = vec![0.0f32; m];
            up.process(x, &mut y).unwrap();
            for (i, v) in x.iter().enumerate() {
                // f32 DFT rounding on inputs of magnitude <= 1
                proptest::prop_assert!((y[factor * i] - v).abs() < 1e-4, "n {} L {} sample {}: {} vs {}", n, factor, i, y[factor * i], v);
            }
        }
    }
}
