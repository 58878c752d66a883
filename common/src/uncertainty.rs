//! Uncertainty statements from Monte Carlo samples, after JCGM 101:2008 (GUM Supplement 1):
//! estimate, standard uncertainty, standard uncertainty of the mean and the two coverage
//! intervals of section 7.7, and the adaptive Monte Carlo procedure of section 7.9.
//! Pure functions, no I/O.
//!
//! # Coverage intervals (JCGM 101 7.7.2)
//!
//! From `M` values sorted into `y_(1) <= ... <= y_(M)`: `q = pM` when `pM` is an integer,
//! otherwise the integer part of `pM + 1/2`; every `[y_(r), y_(r+q)]`, `r = 1 ..= M - q`, is a
//! `100p %` coverage interval. Why `r + q` (an interval spanning `q + 1` sorted values): the
//! distribution function of the sample (7.5.1) puts `y_(r)` at probability `(r - 1/2)/M`, so
//! `[y_(r), y_(r+q)]` holds exactly `q/M ~= p` of it.
//!
//! * probabilistically symmetric: `r = (M - q)/2` when that is an integer, else the integer
//!   part of `(M - q + 1)/2`;
//! * shortest: the `r` minimising `y_(r+q) - y_(r)` (the first such `r` on ties).
//!
//! Both need `M - q >= 1`: [`min_values`] gives the smallest such `M`; fewer values are an
//! error ([`CoverageError::TooFewValues`]), never a NaN. JCGM 101 7.2 asks for `M` much larger
//! (at least `10^4 / (1 - p)` for a reliable 95 % interval): [`CoverageSummary::u_mean`] tells
//! a reader how well the mean is known.
//!
//! # Estimate and standard uncertainty (JCGM 101 7.6)
//!
//! `y` is the mean of the values and `u(y)` their standard deviation with `M - 1` in the
//! denominator. `u_mean = u(y) / sqrt(M)` is the standard uncertainty *of that mean*, the
//! Monte Carlo's own numerical uncertainty on `y` (not a property of the measurand).
//!
//! # Adaptive procedure (JCGM 101 7.9)
//!
//! Batches of `M` runs ([`default_batch_size`]: `max(ceil(100 / (1 - p)), 10^4)`, 7.9.4 b)
//! give per batch `h` the estimate `y(h)`, `u(y(h))` and the interval ends. After the second
//! batch, for each of these four `z`, `s_z` is the standard deviation **of their average**:
//! `s_z^2 = 1 / (h (h - 1)) sum_r (z(r) - zbar)^2` (7.9.4 g, h). The results are stable when
//! `2 s_z <= delta` for all four, with `delta` the numerical tolerance (7.9.2) of `u(y)`
//! formed from all `h M` values: `u(y)` written `c x 10^l` with `c` an integer of `n_dig`
//! digits, `delta = 10^l / 2` ([`numerical_tolerance`]). The final results (7.9.4 l) are then
//! computed from all `h M` values ([`final_results`]). [`AdaptiveQuantity`] keeps the batch
//! history of one output quantity; [`Stability`] is the state after a batch and estimates how
//! many more batches are needed, from `s_z` falling as `1 / sqrt(h)`.

use std::fmt;

/// The coverage probability used when none is given (JCGM 101: 95 %).
pub const DEFAULT_COVERAGE: f64 = 0.95;

/// Why a coverage statement cannot be made.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CoverageError {
    /// The coverage probability is not strictly between 0 and 1.
    #[error("coverage probability {0} must lie strictly between 0 and 1")]
    Probability(f64),
    /// Too few values for an interval of this coverage probability (`M - q < 1`) or for a
    /// standard deviation (`M < 2`).
    #[error(
        "{n} values are too few for a {p} coverage interval: at least {needed} are needed \
         (JCGM 101 7.7.2)"
    )]
    TooFewValues {
        /// Values given.
        n: usize,
        /// Coverage probability.
        p: f64,
        /// Smallest number of values that gives an interval.
        needed: usize,
    },
    /// A value is NaN or infinite.
    #[error("value {index} is not finite ({value})")]
    NotFinite {
        /// Index of the value in the input.
        index: usize,
        /// The value.
        value: f64,
    },
}

/// A coverage interval `[lo, hi]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoverageInterval {
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
}

impl CoverageInterval {
    /// `hi - lo`.
    pub fn length(&self) -> f64 {
        self.hi - self.lo
    }
}

/// Which coverage interval of JCGM 101 7.7.2.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum IntervalKind {
    /// Probabilistically symmetric: `(1 - p)/2` of the values on each side.
    #[default]
    Symmetric,
    /// Shortest interval holding the fraction `p`.
    Shortest,
}

/// The JCGM 101 7.6/7.7 summary of a Monte Carlo sample of one output quantity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoverageSummary {
    /// Number of values `M`.
    pub n: usize,
    /// Coverage probability `p`.
    pub p: f64,
    /// Estimate `y`: the mean of the values.
    pub mean: f64,
    /// Standard uncertainty `u(y)`: the standard deviation of the values (`M - 1`).
    pub std: f64,
    /// Standard uncertainty of the mean, `u(y) / sqrt(M)`.
    pub u_mean: f64,
    /// Lower end of the probabilistically symmetric interval.
    pub sym_lo: f64,
    /// Upper end of the probabilistically symmetric interval.
    pub sym_hi: f64,
    /// Lower end of the shortest interval.
    pub short_lo: f64,
    /// Upper end of the shortest interval.
    pub short_hi: f64,
}

impl CoverageSummary {
    /// The interval of the given kind.
    pub fn interval(&self, kind: IntervalKind) -> CoverageInterval {
        match kind {
            IntervalKind::Symmetric => CoverageInterval {
                lo: self.sym_lo,
                hi: self.sym_hi,
            },
            IntervalKind::Shortest => CoverageInterval {
                lo: self.short_lo,
                hi: self.short_hi,
            },
        }
    }
}

fn check_p(p: f64) -> Result<(), CoverageError> {
    if p > 0.0 && p < 1.0 {
        Ok(())
    } else {
        Err(CoverageError::Probability(p))
    }
}

/// `q` of JCGM 101 7.7.2 for `m` values and probability `p`: `pM` when it is an integer,
/// otherwise the integer part of `pM + 1/2`.
pub fn coverage_count(m: usize, p: f64) -> usize {
    let pm = p * m as f64;
    if pm == pm.floor() {
        pm as usize
    } else {
        (pm + 0.5).floor() as usize
    }
}

/// Smallest number of values that gives a `p` coverage interval (`M >= 2` and `M - q >= 1`).
/// `None` when `p` is not in `(0, 1)`.
pub fn min_values(p: f64) -> Option<usize> {
    check_p(p).ok()?;
    // M - q grows about as (1 - p) M, so this ends near 1 / (1 - p)
    (2usize..).find(|&m| m > coverage_count(m, p))
}

/// Checks a sorted sample's size for probability `p`; returns `q`.
fn check_len(n: usize, p: f64) -> Result<usize, CoverageError> {
    check_p(p)?;
    let q = coverage_count(n, p);
    if n < 2 || n <= q {
        return Err(CoverageError::TooFewValues {
            n,
            p,
            needed: min_values(p).unwrap_or(usize::MAX),
        });
    }
    Ok(q)
}

/// The probabilistically symmetric `p` coverage interval of **sorted** values (JCGM 101
/// 7.7.2, see the module documentation for the index rule).
pub fn symmetric_interval(sorted: &[f64], p: f64) -> Result<CoverageInterval, CoverageError> {
    let m = sorted.len();
    let q = check_len(m, p)?;
    let d = m - q;
    // 1-based r; d >= 1 so r >= 1 and r + q <= M
    // (M - q)/2 when it is an integer, else the integer part of (M - q + 1)/2
    let r = if d.is_multiple_of(2) {
        d / 2
    } else {
        d.div_ceil(2)
    };
    Ok(CoverageInterval {
        lo: sorted[r - 1],
        hi: sorted[r + q - 1],
    })
}

/// The shortest `p` coverage interval of **sorted** values (JCGM 101 7.7.2): the shortest of
/// `[y_(r), y_(r+q)]`, `r = 1 ..= M - q`, the first one on ties.
pub fn shortest_interval(sorted: &[f64], p: f64) -> Result<CoverageInterval, CoverageError> {
    let m = sorted.len();
    let q = check_len(m, p)?;
    let mut best = 0usize; // 0-based r - 1
    let mut len = f64::INFINITY;
    for i in 0..m - q {
        let l = sorted[i + q] - sorted[i];
        if l < len {
            len = l;
            best = i;
        }
    }
    Ok(CoverageInterval {
        lo: sorted[best],
        hi: sorted[best + q],
    })
}

/// Mean and standard deviation (`n - 1`) of at least two values, two-pass.
fn mean_std(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let ss: f64 = v.iter().map(|x| (x - mean) * (x - mean)).sum();
    (mean, (ss / (n - 1.0)).sqrt())
}

/// The JCGM 101 7.6/7.7 summary of `values` (any order; they are copied and sorted) for
/// coverage probability `p`. Errors instead of NaN: `p` outside `(0, 1)`, a non-finite value,
/// or fewer values than [`min_values`].
pub fn coverage_summary(values: &[f64], p: f64) -> Result<CoverageSummary, CoverageError> {
    if let Some((index, &value)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(CoverageError::NotFinite { index, value });
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    summary_of_sorted(&sorted, p)
}

/// [`coverage_summary`] of values already sorted ascending and finite (not checked again).
pub fn summary_of_sorted(sorted: &[f64], p: f64) -> Result<CoverageSummary, CoverageError> {
    debug_assert!(sorted.windows(2).all(|w| w[0] <= w[1]));
    let sym = symmetric_interval(sorted, p)?;
    let short = shortest_interval(sorted, p)?;
    let (mean, std) = mean_std(sorted);
    Ok(CoverageSummary {
        n: sorted.len(),
        p,
        mean,
        std,
        u_mean: std / (sorted.len() as f64).sqrt(),
        sym_lo: sym.lo,
        sym_hi: sym.hi,
        short_lo: short.lo,
        short_hi: short.hi,
    })
}

/// Resamples drawn by [`bootstrap_chi`].
pub const BOOTSTRAP_RESAMPLES: usize = 2000;

/// Bootstrap statements of the two rig indices `chi_mu = mean(v) / mean(t)` and
/// `chi_sigma = std(v) / std(t)` over paired runs `(t, v)` (`v` `None` where the run's vision
/// pick failed: such runs count in the transducer's statistics only, as in the point
/// estimates). [`BOOTSTRAP_RESAMPLES`] resamples of the runs with replacement, drawn from a
/// stream seeded by `seed` (deterministic). Each summary's `mean` is the estimate from the
/// runs themselves, `std` and `u_mean` the bootstrap standard deviation of the statistic (its
/// standard uncertainty), and the intervals the bootstrap distribution's (percentile)
/// intervals. Errors when fewer runs than [`min_values`] or a statistic is undefined.
pub fn bootstrap_chi(
    pairs: &[(f64, Option<f64>)],
    p: f64,
    seed: u64,
) -> Result<(CoverageSummary, CoverageSummary), CoverageError> {
    use rand::{Rng, SeedableRng};
    let stats = |idx: &mut dyn Iterator<Item = usize>| -> Option<(f64, f64)> {
        let (mut t, mut v) = (Vec::new(), Vec::new());
        for i in idx {
            let (ti, vi) = pairs[i];
            t.push(ti);
            v.extend(vi);
        }
        let (mt, st) = (crate::stats::mean(&t)?, crate::stats::std_dev(&t)?);
        let (mv, sv) = (crate::stats::mean(&v)?, crate::stats::std_dev(&v)?);
        let (mu, sigma) = (mv / mt, sv / st);
        (mu.is_finite() && sigma.is_finite()).then_some((mu, sigma))
    };
    let n = pairs.len();
    let needed = min_values(p).ok_or(CoverageError::Probability(p))?;
    let undefined = CoverageError::TooFewValues { n, p, needed };
    if n < needed {
        return Err(undefined);
    }
    let (mu, sigma) = stats(&mut (0..n)).ok_or(undefined)?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let (mut mus, mut sigmas) = (Vec::new(), Vec::new());
    for _ in 0..BOOTSTRAP_RESAMPLES {
        let mut draw = (0..n).map(|_| rng.random_range(0..n));
        if let Some((m, s)) = stats(&mut draw) {
            mus.push(m);
            sigmas.push(s);
        }
    }
    let state = |estimate: f64, draws: Vec<f64>| {
        let s = coverage_summary(&draws, p)?;
        Ok(CoverageSummary {
            n,
            mean: estimate,
            u_mean: s.std,
            ..s
        })
    };
    Ok((state(mu, mus)?, state(sigma, sigmas)?))
}

/// The final results of the adaptive procedure (JCGM 101 7.9.4 l): the summary of all the
/// `h M` values of the batches.
pub fn final_results(batches: &[&[f64]], p: f64) -> Result<CoverageSummary, CoverageError> {
    let all: Vec<f64> = batches.iter().flat_map(|b| b.iter().copied()).collect();
    coverage_summary(&all, p)
}

/// Default batch size of the adaptive procedure (JCGM 101 7.9.4 b): `max(J, 10^4)` with `J`
/// the smallest integer `>= 100 / (1 - p)`. `None` when `p` is not in `(0, 1)`.
pub fn default_batch_size(p: f64) -> Option<usize> {
    check_p(p).ok()?;
    let j = (100.0 / (1.0 - p)).ceil();
    // 100 / (1 - p) rounds up to the next integer; guard the float noise of e.g. p = 0.99
    let j = if (100.0 / (1.0 - p) - (j - 1.0)).abs() < 1e-9 {
        j - 1.0
    } else {
        j
    };
    Some((j as usize).max(10_000))
}

/// Numerical tolerance of a value `z` known to `digits` significant decimal digits (JCGM 101
/// 7.9.2): `z = c x 10^l` with `c` an integer of `digits` digits, `delta = 10^l / 2`. `None`
/// for `digits == 0` or a `z` that is zero or not finite.
pub fn numerical_tolerance(z: f64, digits: u32) -> Option<f64> {
    if digits == 0 || !z.is_finite() || z == 0.0 {
        return None;
    }
    let z = z.abs();
    let mut l = z.log10().floor() as i32 - digits as i32 + 1;
    // rounding c may carry into one more digit (0.0996 to 1 digit is 1 x 10^-1, not 10 x 10^-2)
    let c = (z / 10f64.powi(l)).round();
    if c >= 10f64.powi(digits as i32) {
        l += 1;
    }
    Some(0.5 * 10f64.powi(l))
}

/// The results of one batch of runs for one output quantity (JCGM 101 7.9.4 e).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BatchResult {
    /// Runs in the batch (`M`).
    pub runs: usize,
    /// Estimate `y(h)` (mean of the batch).
    pub estimate: f64,
    /// Standard uncertainty `u(y(h))` (standard deviation of the batch).
    pub std_uncertainty: f64,
    /// Lower end of the batch's coverage interval.
    pub lo: f64,
    /// Upper end of the batch's coverage interval.
    pub hi: f64,
}

impl BatchResult {
    /// The batch values of a batch's [`CoverageSummary`], with the interval of `kind`.
    pub fn from_summary(s: &CoverageSummary, kind: IntervalKind) -> BatchResult {
        let i = s.interval(kind);
        BatchResult {
            runs: s.n,
            estimate: s.mean,
            std_uncertainty: s.std,
            lo: i.lo,
            hi: i.hi,
        }
    }
}

/// Why an adaptive procedure cannot be set up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum AdaptiveError {
    /// The number of significant digits must be at least 1.
    #[error("the number of significant digits must be at least 1")]
    Digits,
}

/// The batch history of one output quantity in the adaptive procedure (JCGM 101 7.9.4).
#[derive(Debug, Clone, PartialEq)]
pub struct AdaptiveQuantity {
    digits: u32,
    batches: Vec<BatchResult>,
}

/// Twice the standard deviation of the average of each batch value (`2 s_z`, 7.9.4 g, h).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwiceStd {
    /// `2 s_y` of the estimate.
    pub estimate: f64,
    /// `2 s_u(y)` of the standard uncertainty.
    pub std_uncertainty: f64,
    /// `2 s_ylow` of the lower interval end.
    pub lo: f64,
    /// `2 s_yhigh` of the upper interval end.
    pub hi: f64,
}

impl TwiceStd {
    /// The largest of the four.
    pub fn max(&self) -> f64 {
        self.estimate
            .max(self.std_uncertainty)
            .max(self.lo)
            .max(self.hi)
    }
}

/// The state of the adaptive procedure for one quantity after `batches >= 2` batches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stability {
    /// Batches so far (`h`).
    pub batches: usize,
    /// Runs so far (sum of the batch sizes).
    pub runs: usize,
    /// Estimate from all runs.
    pub estimate: f64,
    /// Standard uncertainty `u(y)` from all runs (7.9.4 i).
    pub std_uncertainty: f64,
    /// Numerical tolerance of `u(y)` (7.9.2, 7.9.4 j).
    pub delta: f64,
    /// `2 s_z` of the four batch values.
    pub twice_std: TwiceStd,
}

impl Stability {
    /// Whether every `2 s_z <= delta` (7.9.4 k): the results are stabilised.
    pub fn is_stable(&self) -> bool {
        self.twice_std.max() <= self.delta
    }

    /// How many more batches are expected to be needed: `s_z` of an average of `h` batch
    /// values falls as `1 / sqrt(h)`, so the criterion is expected to hold at
    /// `H = h (2 s_z / delta)^2` batches (the largest over the four values). 0 when stable,
    /// at least 1 otherwise. An estimate: `s_z` itself is uncertain with few batches.
    pub fn more_batches_needed(&self) -> usize {
        if self.is_stable() {
            return 0;
        }
        let ratio = self.twice_std.max() / self.delta;
        let total = (self.batches as f64 * ratio * ratio).ceil();
        let more = total - self.batches as f64;
        if more.is_finite() {
            (more as usize).max(1)
        } else {
            usize::MAX
        }
    }
}

impl AdaptiveQuantity {
    /// An empty history for a quantity whose `u(y)` is wanted to `digits` significant digits
    /// (`n_dig`, usually 1 or 2).
    pub fn new(digits: u32) -> Result<AdaptiveQuantity, AdaptiveError> {
        if digits == 0 {
            return Err(AdaptiveError::Digits);
        }
        Ok(AdaptiveQuantity {
            digits,
            batches: Vec::new(),
        })
    }

    /// Significant digits `n_dig`.
    pub fn digits(&self) -> u32 {
        self.digits
    }

    /// Adds the results of the next batch.
    pub fn push(&mut self, batch: BatchResult) {
        self.batches.push(batch);
    }

    /// The batches so far.
    pub fn batches(&self) -> &[BatchResult] {
        &self.batches
    }

    /// Runs so far.
    pub fn runs(&self) -> usize {
        self.batches.iter().map(|b| b.runs).sum()
    }

    /// Mean and standard deviation (`N - 1`) of all the runs so far, pooled exactly from the
    /// batch means and standard deviations (no values kept). `None` below two runs.
    pub fn pooled(&self) -> Option<(f64, f64)> {
        let n = self.runs();
        if n < 2 {
            return None;
        }
        let mean = self
            .batches
            .iter()
            .map(|b| b.runs as f64 * b.estimate)
            .sum::<f64>()
            / n as f64;
        let ss: f64 = self
            .batches
            .iter()
            .map(|b| {
                let within = if b.runs > 1 {
                    (b.runs - 1) as f64 * b.std_uncertainty * b.std_uncertainty
                } else {
                    0.0
                };
                within + b.runs as f64 * (b.estimate - mean) * (b.estimate - mean)
            })
            .sum();
        Some((mean, (ss / (n - 1) as f64).sqrt()))
    }

    /// The state after the batches so far; `None` before the second batch (7.9.4 f), or when
    /// `u(y)` is zero (no tolerance can be formed).
    pub fn status(&self) -> Option<Stability> {
        let h = self.batches.len();
        if h < 2 {
            return None;
        }
        let (estimate, u) = self.pooled()?;
        let delta = numerical_tolerance(u, self.digits)?;
        let twice = |f: fn(&BatchResult) -> f64| {
            let zbar = self.batches.iter().map(f).sum::<f64>() / h as f64;
            let ss: f64 = self.batches.iter().map(|b| (f(b) - zbar).powi(2)).sum();
            2.0 * (ss / (h * (h - 1)) as f64).sqrt()
        };
        Some(Stability {
            batches: h,
            runs: self.runs(),
            estimate,
            std_uncertainty: u,
            delta,
            twice_std: TwiceStd {
                estimate: twice(|b| b.estimate),
                std_uncertainty: twice(|b| b.std_uncertainty),
                lo: twice(|b| b.lo),
                hi: twice(|b| b.hi),
            },
        })
    }
}

/// Whether every quantity is stabilised (false while any has fewer than two batches).
pub fn all_stable(quantities: &[AdaptiveQuantity]) -> bool {
    quantities
        .iter()
        .all(|q| q.status().is_some_and(|s| s.is_stable()))
}

/// How many more batches the set of quantities is expected to need: the largest
/// [`Stability::more_batches_needed`], and `2 - h` for a quantity with `h < 2` batches.
pub fn more_batches_needed(quantities: &[AdaptiveQuantity]) -> usize {
    quantities
        .iter()
        .map(|q| match q.status() {
            Some(s) => s.more_batches_needed(),
            None => 2usize.saturating_sub(q.batches().len()).max(1),
        })
        .max()
        .unwrap_or(0)
}

impl fmt::Display for Stability {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} batches ({} runs): u = {:.4e}, delta = {:.1e}, 2s: y {:.2e}, u {:.2e}, lo {:.2e}, \
             hi {:.2e} ({})",
            self.batches,
            self.runs,
            self.std_uncertainty,
            self.delta,
            self.twice_std.estimate,
            self.twice_std.std_uncertainty,
            self.twice_std.lo,
            self.twice_std.hi,
            if self.is_stable() {
                "stable"
            } else {
                "not stable"
            }
        )
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn bootstrap_chi_agrees_with_the_delta_method() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        // independent t ~ N(10, 1), v ~ N(9, 1), 400 runs: first-order (delta method)
        // u(chi_mu) = chi sqrt(u(mean v)^2 / mean v^2 + u(mean t)^2 / mean t^2) and, for normal
        // samples, u(chi_sigma) = chi_sigma sqrt(1 / (2 (n - 1)) * 2)
        let n = 400;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (nt, nv) = (
            Normal::new(10.0, 1.0).unwrap(),
            Normal::new(9.0, 1.0).unwrap(),
        );
        let pairs: Vec<(f64, Option<f64>)> = (0..n)
            .map(|_| (nt.sample(&mut rng), Some(nv.sample(&mut rng))))
            .collect();
        let (mu, sigma) = bootstrap_chi(&pairs, 0.95, 1).unwrap();
        let (t, v): (Vec<f64>, Vec<f64>) = pairs.iter().map(|(t, v)| (*t, v.unwrap())).unzip();
        let (mt, st) = mean_std(&t);
        let (mv, sv) = mean_std(&v);
        assert!((mu.mean - mv / mt).abs() < 1e-12 && (sigma.mean - sv / st).abs() < 1e-12);
        let nn = n as f64;
        let u_mu = mv / mt * ((sv / mv).powi(2) / nn + (st / mt).powi(2) / nn).sqrt();
        let u_sigma = sv / st * (1.0 / (nn - 1.0)).sqrt();
        assert!((mu.std / u_mu - 1.0).abs() < 0.15, "{} vs {u_mu}", mu.std);
        assert!(
            (sigma.std / u_sigma - 1.0).abs() < 0.2,
            "{} vs {u_sigma}",
            sigma.std
        );
        assert!(mu.short_lo < mu.mean && mu.mean < mu.short_hi);
        assert!((mu.sym_hi - mu.sym_lo) / (2.0 * 1.96 * u_mu) - 1.0 < 0.2);
        // a vision exactly proportional to the transducer: chi_mu is 0.9 in every resample
        let exact: Vec<(f64, Option<f64>)> = t.iter().map(|t| (*t, Some(0.9 * t))).collect();
        let (mu, sigma) = bootstrap_chi(&exact, 0.95, 1).unwrap();
        assert!(
            mu.std < 1e-12 && (mu.short_lo - 0.9).abs() < 1e-12 && (sigma.mean - 0.9).abs() < 1e-12
        );
        // too few runs: an error, not NaN
        assert!(bootstrap_chi(&exact[..5], 0.95, 1).is_err());
    }

    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Exp, StandardNormal};

    /// Standard normal quantile by bisection on erfc (independent of the code under test).
    fn norm_quantile(p: f64) -> f64 {
        let cdf = |x: f64| 0.5 * libm::erfc(-x / 2f64.sqrt());
        let (mut lo, mut hi) = (-10.0, 10.0);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if cdf(mid) < p {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    fn phi(x: f64) -> f64 {
        (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt()
    }

    fn normals(n: usize, mean: f64, sd: f64, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|_| {
                let z: f64 = StandardNormal.sample(&mut rng);
                mean + sd * z
            })
            .collect()
    }

    #[test]
    fn index_rule_follows_jcgm_101_7_7_2() {
        // M = 20, p = 0.9: pM = 18 integer, q = 18, M - q = 2 even, r = 1: [y1, y19]
        let v: Vec<f64> = (1..=20).map(|i| i as f64).collect();
        let s = symmetric_interval(&v, 0.9).unwrap();
        assert_eq!((s.lo, s.hi), (1.0, 19.0));
        // M = 30, p = 0.9: q = 27, M - q = 3 odd, r = int(4/2) = 2: [y2, y29]
        let v: Vec<f64> = (1..=30).map(|i| i as f64).collect();
        let s = symmetric_interval(&v, 0.9).unwrap();
        assert_eq!((s.lo, s.hi), (2.0, 29.0));
        // M = 21, p = 0.9: pM = 18.9, q = int(19.4) = 19, M - q = 2, r = 1: [y1, y20]
        let v: Vec<f64> = (1..=21).map(|i| i as f64).collect();
        assert_eq!(coverage_count(21, 0.9), 19);
        let s = symmetric_interval(&v, 0.9).unwrap();
        assert_eq!((s.lo, s.hi), (1.0, 20.0));
        // M = 24, p = 0.95: pM = 22.8, q = int(23.3) = 23
        assert_eq!(coverage_count(24, 0.95), 23);
        // pM = 22.5 exactly: integer part of 23.0
        assert_eq!(coverage_count(25, 0.9), 23);
    }

    #[test]
    fn shortest_interval_equals_a_brute_force_search() {
        // skewed sample: brute force over every pair i < j with j - i = q (the definition)
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for m in [11usize, 40, 97, 500] {
            let mut v: Vec<f64> = (0..m).map(|_| rng.random::<f64>().powi(3)).collect();
            v.sort_by(f64::total_cmp);
            for p in [0.5, 0.9, 0.95] {
                let Ok(got) = shortest_interval(&v, p) else {
                    assert!(m <= coverage_count(m, p));
                    continue;
                };
                let q = coverage_count(m, p);
                let mut best = (f64::INFINITY, 0.0, 0.0);
                for i in 0..m {
                    for j in i + 1..m {
                        if j - i == q && v[j] - v[i] < best.0 {
                            best = (v[j] - v[i], v[i], v[j]);
                        }
                    }
                }
                assert_eq!((got.lo, got.hi), (best.1, best.2), "M {m}, p {p}");
            }
        }
    }

    #[test]
    fn too_few_values_and_bad_inputs_are_errors_not_nan() {
        // p = 0.95: M = 10 gives q = int(10.0) = 10 = M; M = 11 gives q = int(10.95) = 10
        assert_eq!(min_values(0.95), Some(11));
        let v: Vec<f64> = (0..10).map(|i| i as f64).collect();
        assert_eq!(
            coverage_summary(&v, 0.95),
            Err(CoverageError::TooFewValues {
                n: 10,
                p: 0.95,
                needed: 11
            })
        );
        let v: Vec<f64> = (0..11).map(|i| i as f64).collect();
        let s = coverage_summary(&v, 0.95).unwrap();
        assert!(s.sym_lo.is_finite() && s.short_hi.is_finite());
        assert!(matches!(
            coverage_summary(&[1.0], 0.5),
            Err(CoverageError::TooFewValues { .. })
        ));
        assert_eq!(
            coverage_summary(&v, 1.0),
            Err(CoverageError::Probability(1.0))
        );
        assert!(matches!(
            coverage_summary(&[1.0, f64::NAN, 2.0], 0.5),
            Err(CoverageError::NotFinite { index: 1, .. })
        ));
        assert!(min_values(0.0).is_none());
    }

    /// A normal sample of 10^6 values: the shortest and the symmetric 95 % intervals are both
    /// mean +/- 1.95996 sigma.
    #[test]
    fn normal_sample_intervals_are_mean_plus_minus_1_96_sigma() {
        let (m, mu, sd) = (1_000_000usize, 3.0, 0.5);
        let s = coverage_summary(&normals(m, mu, sd, 11), 0.95).unwrap();
        let z = norm_quantile(0.975);
        assert!((z - 1.959964).abs() < 1e-6);
        // sample quantile standard error: sqrt(p (1-p) / M) sigma / phi(z) = 0.0027 sigma
        let se_q = (0.025f64 * 0.975 / m as f64).sqrt() / phi(z) * sd;
        assert!((s.sym_lo - (mu - z * sd)).abs() < 4.0 * se_q, "{s:?}");
        assert!((s.sym_hi - (mu + z * sd)).abs() < 4.0 * se_q, "{s:?}");
        // the shortest interval's length is as well determined as the quantiles; its position
        // is not (the length is flat at the optimum: the shorth converges as M^(-1/3), Kim &
        // Pollard 1990): at M = 10^6, (10^6)^(-1/3) sigma = 0.01 sigma, allowed twice that
        let len = s.short_hi - s.short_lo;
        assert!(
            (len - 2.0 * z * sd).abs() < 4.0 * se_q * 2f64.sqrt(),
            "{s:?}"
        );
        let centre = 0.5 * (s.short_hi + s.short_lo);
        eprintln!(
            "normal: symmetric ({:.5}, {:.5}), shortest ({:.5}, {:.5}), want +/- {:.5}",
            (s.sym_lo - mu) / sd,
            (s.sym_hi - mu) / sd,
            (s.short_lo - mu) / sd,
            (s.short_hi - mu) / sd,
            z
        );
        assert!((centre - mu).abs() < 0.02 * sd, "{s:?}");
        // mean and its standard uncertainty
        assert!((s.u_mean - sd / (m as f64).sqrt()).abs() < 0.01 * s.u_mean);
        assert!((s.mean - mu).abs() < 4.0 * s.u_mean);
        // standard deviation: relative standard error 1 / sqrt(2 (M - 1)) = 7e-4
        assert!((s.std / sd - 1.0).abs() < 4.0 * 7.1e-4);
    }

    /// Exponential sample (rate lambda): the shortest 95 % interval is [0, -ln(0.05) / lambda]
    /// (the density falls monotonically from 0), the symmetric one
    /// [-ln(0.975) / lambda, -ln(0.025) / lambda].
    #[test]
    fn exponential_sample_intervals_match_the_analytic_ones() {
        let (m, lambda) = (1_000_000usize, 2.0);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let exp = Exp::new(lambda).unwrap();
        let v: Vec<f64> = (0..m).map(|_| exp.sample(&mut rng)).collect();
        let s = coverage_summary(&v, 0.95).unwrap();
        // standard error of the sample quantile at probability a: sqrt(a (1-a) / M) / f(x_a),
        // f(x_a) = lambda (1 - a)
        let se = |a: f64| (a * (1.0 - a) / m as f64).sqrt() / (lambda * (1.0 - a));
        // shortest: lower end is the sample minimum (mean 1 / (lambda M) = 5e-7)
        assert!(
            s.short_lo >= 0.0 && s.short_lo < 20.0 / (lambda * m as f64),
            "{s:?}"
        );
        let hi = -(0.05f64).ln() / lambda;
        assert!(
            (s.short_hi - hi).abs() < 4.0 * se(0.95),
            "{} vs {hi}",
            s.short_hi
        );
        let (lo, hi) = (-(0.975f64).ln() / lambda, -(0.025f64).ln() / lambda);
        assert!(
            (s.sym_lo - lo).abs() < 4.0 * se(0.025),
            "{} vs {lo}",
            s.sym_lo
        );
        assert!(
            (s.sym_hi - hi).abs() < 4.0 * se(0.975),
            "{} vs {hi}",
            s.sym_hi
        );
        // and the shortest is shorter than the symmetric one for a skewed sample
        assert!(s.short_hi - s.short_lo < s.sym_hi - s.sym_lo);
    }

    #[test]
    fn numerical_tolerance_follows_7_9_2() {
        // (z, n_dig, delta), worked by hand: z = c x 10^l, delta = 10^l / 2
        let cases = [
            (0.028_571, 2, 0.000_5), // 29 x 10^-3
            (1.5, 1, 0.5),           // 2 x 10^0
            (1.732, 2, 0.05),        // 17 x 10^-1
            (0.0949, 1, 0.005),      // 9 x 10^-2
            (0.0996, 1, 0.05),       // 10 x 10^-2 has two digits: 1 x 10^-1
            (123.4, 3, 0.5),         // 123 x 10^0
            (-2.0, 2, 0.05),         // 20 x 10^-1
        ];
        for (z, d, want) in cases {
            let got = numerical_tolerance(z, d).unwrap();
            assert!((got / want - 1.0).abs() < 1e-12, "{z} {d}: {got}");
        }
        assert_eq!(numerical_tolerance(0.0, 2), None);
        assert_eq!(numerical_tolerance(1.0, 0), None);
    }

    #[test]
    fn default_batch_size_is_max_of_100_over_1_minus_p_and_10_000() {
        assert_eq!(default_batch_size(0.95), Some(10_000)); // J = 2000
        assert_eq!(default_batch_size(0.99), Some(10_000)); // J = 10 000
        assert_eq!(default_batch_size(0.995), Some(20_000));
        assert_eq!(default_batch_size(0.999), Some(100_000));
        assert_eq!(default_batch_size(1.0), None);
    }

    #[test]
    fn batch_spread_is_the_standard_deviation_of_the_average() {
        // estimates 1, 2, 3, 4: sum of squares 5, s^2 = 5 / (4 * 3), 2 s = 2 sqrt(5/12)
        let mut q = AdaptiveQuantity::new(1).unwrap();
        assert!(q.status().is_none());
        for (i, y) in [1.0, 2.0, 3.0, 4.0].into_iter().enumerate() {
            q.push(BatchResult {
                runs: 10,
                estimate: y,
                std_uncertainty: 1.0,
                lo: 0.0,
                hi: 5.0 + i as f64 * 0.0,
            });
        }
        let s = q.status().unwrap();
        assert!((s.twice_std.estimate - 2.0 * (5.0f64 / 12.0).sqrt()).abs() < 1e-12);
        assert_eq!((s.twice_std.std_uncertainty, s.twice_std.lo), (0.0, 0.0));
        assert_eq!(s.runs, 40);
        assert!(!s.is_stable());
    }

    #[test]
    fn pooled_uncertainty_equals_that_of_all_values() {
        let mut q = AdaptiveQuantity::new(2).unwrap();
        let mut all = Vec::new();
        for (k, n) in [50usize, 80, 13].into_iter().enumerate() {
            let v = normals(n, k as f64 * 0.3, 1.0 + k as f64, 100 + k as u64);
            let s = coverage_summary(&v, 0.9).unwrap();
            q.push(BatchResult::from_summary(&s, IntervalKind::Shortest));
            all.extend(v);
        }
        let (mean, u) = q.pooled().unwrap();
        let direct = coverage_summary(&all, 0.9).unwrap();
        assert!((mean - direct.mean).abs() < 1e-12 && (u - direct.std).abs() < 1e-12);
        let slices: Vec<&[f64]> = vec![&all[..50], &all[50..130], &all[130..]];
        assert_eq!(final_results(&slices, 0.9).unwrap(), direct);
    }

    /// JCGM 101 9.2.2: the additive model Y = X1 + X2 + X3 + X4 with Xi ~ N(0, 1), so Y ~
    /// N(0, 4) and u(y) = 2. With n_dig = 2, u = 20 x 10^-1 and delta = 0.05.
    ///
    /// Expected run count: per batch of M runs the four batch values have standard deviations
    /// (large-sample theory, sigma = 2)
    ///   estimate             sigma / sqrt(M)
    ///   std uncertainty      sigma / sqrt(2 (M - 1))
    ///   interval ends        sqrt(a (1 - a) / M) sigma / phi(z_a), a = 0.025: 2.67 sigma / sqrt(M)
    /// so the interval ends set the pace: 2 s_z = 2 * 2.67 sigma / sqrt(h M) <= delta at
    /// h M = (2 * 2.67 * sigma / delta)^2 = 45 700 runs.
    #[test]
    fn adaptive_procedure_stops_near_the_run_count_the_variance_implies() {
        let (sigma, p, digits, m) = (2.0f64, 0.95f64, 2, 1000usize);
        let delta = numerical_tolerance(sigma, digits).unwrap();
        assert_eq!(delta, 0.05);
        let a: f64 = (1.0 - p) / 2.0;
        let k_end = (a * (1.0 - a)).sqrt() / phi(norm_quantile(1.0 - a));
        let expected = (2.0 * k_end * sigma / delta).powi(2);
        assert!((expected - 45_700.0).abs() < 200.0, "{expected}");
        // five independent streams: the stopping point is random (s_z is itself estimated
        // from the batch values), each must land within the factor of two
        for seed in 2026..2031 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let mut q = AdaptiveQuantity::new(digits).unwrap();
            let mut prediction_at_10 = 0;
            let stop = loop {
                let v: Vec<f64> = (0..m)
                    .map(|_| {
                        (0..4)
                            .map(|_| -> f64 { StandardNormal.sample(&mut rng) })
                            .sum::<f64>()
                    })
                    .collect();
                let s = coverage_summary(&v, p).unwrap();
                q.push(BatchResult::from_summary(&s, IntervalKind::Symmetric));
                if let Some(st) = q.status() {
                    if st.batches == 10 {
                        prediction_at_10 = st.batches + st.more_batches_needed();
                    }
                    if st.is_stable() {
                        break st;
                    }
                    assert!(st.batches < 400, "no stop: {st}");
                }
            };
            let runs = stop.runs as f64;
            assert!(
                runs > expected / 2.0 && runs < expected * 2.0,
                "seed {seed}: stopped after {runs} runs, expected about {expected}: {stop}"
            );
            // u(y) from all runs is 2 within delta
            assert!((stop.std_uncertainty - sigma).abs() < delta, "{stop}");
            eprintln!(
                "seed {seed}: {stop}; predicted at 10 batches: {} runs",
                prediction_at_10 * m
            );
        }
    }
}
