//! The statistical uncertainty of output-only results from the record itself, by the
//! delete-one-group jackknife (docs/method.md §3.12, "Uncertainty"): the record's Welch
//! segments (FDD, EFDD) or its time (SSI-cov) in `G` contiguous groups; each replicate is the
//! whole analysis of the mode without one group, with the settings, peak and shape of the
//! whole record's; the standard uncertainty `u = sqrt((G - 1) / G sum (x_g - mean)^2)` and the
//! 95 % interval `x +- t(0.975, G - 1) u` around the whole record's estimate.
//!
//! A replicate holds `(G - 1) / G` of the record, so it behaves like the whole record's
//! estimate (the jackknife's condition: a smooth function of averages, which the spectra and
//! correlations are); the groups are long against the correlation of neighbouring segments or
//! samples, so they are nearly independent. Where a replicate does not find the mode, no
//! interval is given (and a note says so): an interval from the replicates that did would be
//! too narrow.

use super::cluster::{self, ClusterRule, SsiMode};
use super::csd::{self, Csd};
use super::fdd::{self, Svd};
use super::modes::Peak;
use super::ssi;
use super::{Method, OmaMode, OmaSettings};
use crate::modal::{mac, normalise_shape};

/// Groups of the jackknife by default.
pub const GROUPS: usize = 10;

/// A quantity's standard uncertainty and 95 % coverage interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    /// Standard uncertainty.
    pub u: f64,
    /// Lower end of the 95 % interval.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
}

impl Interval {
    /// The half-width of the 95 % interval.
    pub fn half_width(&self) -> f64 {
        (self.hi - self.lo) / 2.0
    }

    /// The interval of a quantity that is positive (a frequency), when it stays so: `None`
    /// when its lower end reaches 0 or below (the uncertainty is as large as the quantity:
    /// no interval means anything then; the caller says so).
    pub fn of_positive(self) -> Option<Interval> {
        (self.lo > 0.0).then_some(self)
    }

    /// The interval scaled by `k > 0` (a change of unit).
    pub fn scaled(self, k: f64) -> Interval {
        Interval {
            u: self.u * k,
            lo: self.lo * k,
            hi: self.hi * k,
        }
    }
}

/// The interval of a quantity that cannot be negative (a damping ratio, a singular value)
/// with its lower end at 0 where the symmetric interval reached below (the weak mode of an
/// FDD, whose singular value scatters by as much as it is, came out at -0.007 .. 0.304).
fn non_negative(i: Interval) -> Interval {
    Interval {
        lo: i.lo.max(0.0),
        ..i
    }
}

/// What the jackknife gives one mode.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Uncertainty {
    /// Of the frequency (EFDD, SSI-cov).
    pub f_hz: Option<Interval>,
    /// Of the damping ratio (EFDD, SSI-cov).
    pub damping: Option<Interval>,
    /// Of the amplitude (FDD, EFDD: the singular value at the peak).
    pub amplitude: Option<Interval>,
    /// Of each shape component's magnitude (shape normalised, largest component 1).
    pub shape_abs: Option<Vec<f64>>,
}

/// The 97.5 % quantile of Student's t with `dof` degrees of freedom (1 to 30 tabulated, the
/// normal's 1.96 beyond).
pub fn t975(dof: usize) -> f64 {
    const T: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
        2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
        2.052, 2.048, 2.045, 2.042,
    ];
    match dof {
        0 => f64::INFINITY,
        d if d <= 30 => T[d - 1],
        _ => 1.96,
    }
}

/// The segments (or other units) of group `g` of `groups` contiguous groups of `units`: sizes
/// differ by at most one.
pub fn group(g: usize, groups: usize, units: usize) -> std::ops::Range<usize> {
    g * units / groups..(g + 1) * units / groups
}

/// The jackknife interval of `estimate` from its replicates (one per group left out).
pub fn jackknife(estimate: f64, replicates: &[f64]) -> Option<Interval> {
    let g = replicates.len();
    if g < 2 || !replicates.iter().all(|v| v.is_finite()) {
        return None;
    }
    let mean = replicates.iter().sum::<f64>() / g as f64;
    let var =
        (g - 1) as f64 / g as f64 * replicates.iter().map(|v| (v - mean).powi(2)).sum::<f64>();
    let u = var.sqrt();
    let half = t975(g - 1) * u;
    Some(Interval {
        u,
        lo: estimate - half,
        hi: estimate + half,
    })
}

/// [`jackknife`] for groups of unequal sizes (Busing, Meijer & van der Leeden, *Sociological
/// Methodology* 29, 1999): group `g` holds `sizes[g]` of the `n = sum sizes` units and
/// `replicates[g]` is the estimate without it; with `h_g = n / sizes[g]` the pseudo-values
/// `h_g x - (h_g - 1) x_g`, their weighted mean `x_J`, and `u^2 = (1/G) sum (pseudo_g - x_J)^2 /
/// (h_g - 1)`. Equal sizes give [`jackknife`]'s `u`.
pub fn jackknife_sized(estimate: f64, replicates: &[f64], sizes: &[usize]) -> Option<Interval> {
    let g = replicates.len();
    let n: usize = sizes.iter().sum();
    if g < 2 || sizes.len() != g || sizes.contains(&0) || !replicates.iter().all(|v| v.is_finite())
    {
        return None;
    }
    let h: Vec<f64> = sizes.iter().map(|&m| n as f64 / m as f64).collect();
    let x_j: f64 = replicates
        .iter()
        .zip(sizes)
        .map(|(x, &m)| (estimate - x) + m as f64 / n as f64 * x)
        .sum();
    let var = replicates
        .iter()
        .zip(&h)
        .map(|(x, h)| (h * estimate - (h - 1.0) * x - x_j).powi(2) / (h - 1.0))
        .sum::<f64>()
        / g as f64;
    let u = var.sqrt();
    let half = t975(g - 1) * u;
    Some(Interval {
        u,
        lo: estimate - half,
        hi: estimate + half,
    })
}

/// Replicates of SSI's delete-half jackknife by default ([`half_samples`]).
pub const HALF_SAMPLES: usize = 20;

/// The replicates of the delete-half jackknife over `groups` groups: each the groups it leaves
/// out, `groups / 2` of them. Every such choice when there are at most `count`; otherwise
/// `count` of them in complementary pairs (each group left out equally often), drawn by a fixed
/// generator so that a record always gets the same intervals.
pub fn half_samples(groups: usize, d: usize, count: usize) -> Vec<Vec<usize>> {
    // C(groups, d), saturating (only its comparison with `count` matters)
    let all = (0..d).fold(1usize, |c, i| c.saturating_mul(groups - i) / (i + 1));
    if all <= count {
        return (0..1usize << groups)
            .filter(|m| m.count_ones() as usize == d)
            .map(|m| (0..groups).filter(|g| m >> g & 1 == 1).collect())
            .collect();
    }
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        // splitmix64
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    let mut out: Vec<Vec<usize>> = Vec::with_capacity(count);
    while out.len() < count {
        let mut order: Vec<usize> = (0..groups).collect();
        for i in (1..groups).rev() {
            order.swap(i, (next() % (i as u64 + 1)) as usize);
        }
        let mut left: Vec<usize> = order[..d].to_vec();
        left.sort_unstable();
        if out.contains(&left) {
            continue;
        }
        let mut other: Vec<usize> = order[d..].to_vec();
        other.sort_unstable();
        out.push(left);
        if groups == 2 * d && out.len() < count {
            out.push(other);
        }
    }
    out
}

/// The delete-half jackknife interval of `estimate` from its replicates, each without `d` of
/// the `groups` groups (Shao & Wu, *Annals of Statistics* 17, 1989): `u^2 = (G - d) / (d R)
/// sum (x_r - mean)^2` over the `R` replicates, Student's t with `G - 1` degrees of freedom.
/// Unlike the delete-one jackknife it holds for estimates that are not smooth in the data
/// (a median, a pole chosen among several): a jump of one replicate enters its variance once
/// instead of about `G - 1` times.
pub fn jackknife_half(
    estimate: f64,
    replicates: &[f64],
    (groups, d): (usize, usize),
) -> Option<Interval> {
    let r = replicates.len();
    if r < 2 || d == 0 || d >= groups || !replicates.iter().all(|v| v.is_finite()) {
        return None;
    }
    let mean = replicates.iter().sum::<f64>() / r as f64;
    let var = (groups - d) as f64 / (d * r) as f64
        * replicates.iter().map(|v| (v - mean).powi(2)).sum::<f64>();
    let u = var.sqrt();
    let half = t975(groups - 1) * u;
    Some(Interval {
        u,
        lo: estimate - half,
        hi: estimate + half,
    })
}

/// How a mode's replicates were made, which says how their spread gives a variance.
#[derive(Debug, Clone, Copy)]
enum Scheme<'a> {
    /// One of equal groups left out per replicate ([`jackknife`]).
    Plain,
    /// One group left out per replicate, the groups of these sizes ([`jackknife_sized`]).
    Sized(&'a [usize]),
    /// `d` of `groups` groups left out per replicate ([`jackknife_half`]).
    Half(usize, usize),
}

impl Scheme<'_> {
    fn interval(self, estimate: f64, replicates: &[f64]) -> Option<Interval> {
        match self {
            Scheme::Plain => jackknife(estimate, replicates),
            Scheme::Sized(sizes) => jackknife_sized(estimate, replicates, sizes),
            Scheme::Half(groups, d) => jackknife_half(estimate, replicates, (groups, d)),
        }
    }
}

/// Per mode of `modes` (in their order), its uncertainty by the jackknife over `groups`
/// groups; `peaks` are the FDD peaks the FDD and EFDD modes came from (in mode order), the
/// records, their cross-spectral matrix (`whole`) and the settings those of the analysis;
/// `lone` the frequencies of the SSI modes kept with fewer poles than a mode needs (their
/// replicates are sought among clusters as small). Notes name the modes left without an
/// interval.
pub fn of_modes(
    (channels, whole): (&[Vec<f64>], &Csd),
    s: &OmaSettings,
    (modes, lone): (&[OmaMode], &[f64]),
    peaks: &[Peak],
    groups: usize,
    notes: &mut Vec<String>,
) -> anyhow::Result<Vec<Uncertainty>> {
    if groups < 3 {
        return Ok(vec![Uncertainty::default(); modes.len()]);
    }
    let replicate = of_record(channels, whole, s);
    let starts = efdd_starts(modes, peaks);
    let spectral = spectral_replicates((whole.segments, &replicate), s, (peaks, &starts), groups)?;
    let ssi = ssi_replicates(channels, s, (modes, lone), groups, notes)?;
    Ok(intervals(
        modes,
        peaks,
        (spectral.as_ref(), ssi.as_ref()),
        notes,
    ))
}

/// A replicate of a cross-spectral matrix: the matrix without group `g` of `groups` of its
/// segments, and the segments left out.
pub type ReplicateOf<'a> = dyn Fn(usize, usize) -> anyhow::Result<(Csd, usize)> + 'a;

/// The replicates ([`ReplicateOf`]) of one record's matrix `whole` of `channels` (settings
/// `s`): the segments of the group left out transformed again and taken off `whole`.
pub fn of_record<'a>(
    channels: &'a [Vec<f64>],
    whole: &'a Csd,
    s: &'a OmaSettings,
) -> impl Fn(usize, usize) -> anyhow::Result<(Csd, usize)> + 'a {
    move |g, groups| {
        let range = group(g, groups, whole.segments);
        let n = range.len();
        let part = csd::of_segments(channels, s.fs_hz, s.csd, range)?;
        Ok((whole.without(&part), n))
    }
}

/// The intervals of FDD and EFDD modes found on a cross-spectral matrix that is not one
/// record's ([`super::preger_spectral`]): `segments` its least number of
/// segments, `replicate` each group's replicate; the rest as [`of_modes`].
pub fn of_spectral_modes(
    (segments, replicate): (usize, &ReplicateOf<'_>),
    s: &OmaSettings,
    modes: &[OmaMode],
    peaks: &[Peak],
    notes: &mut Vec<String>,
) -> anyhow::Result<Vec<Uncertainty>> {
    if s.groups < 3 {
        return Ok(vec![Uncertainty::default(); modes.len()]);
    }
    let starts = efdd_starts(modes, peaks);
    let spectral = spectral_replicates((segments, replicate), s, (peaks, &starts), s.groups)?;
    Ok(intervals(modes, peaks, (spectral.as_ref(), None), notes))
}

/// Each peak's EFDD estimate of the whole record: where its replicates' fits start.
fn efdd_starts(modes: &[OmaMode], peaks: &[Peak]) -> Vec<Start> {
    peaks
        .iter()
        .enumerate()
        .map(|(i, p)| {
            modes
                .iter()
                .find(|m| m.method == Method::Efdd && m.mode == p.mode_number(i))
                .and_then(|m| m.damping.map(|z| (m.f_hz, z)))
        })
        .collect()
}

/// Every mode's intervals from the replicates made.
fn intervals(
    modes: &[OmaMode],
    peaks: &[Peak],
    (spectral, ssi): (Option<&SpectralReplicates>, Option<&SsiReplicates>),
    notes: &mut Vec<String>,
) -> Vec<Uncertainty> {
    let mut out = vec![Uncertainty::default(); modes.len()];
    for (m, u) in modes.iter().zip(out.iter_mut()) {
        if let Some((reps, scheme)) = mode_replicates(m, modes, peaks, (spectral, ssi)) {
            *u = mode_intervals(m, &reps, scheme, notes);
        }
    }
    out
}

/// A mode's intervals from its replicates (made as `scheme` says): FDD's amplitude and shape;
/// EFDD's and SSI's frequency, damping and shape (EFDD's amplitude too).
fn mode_intervals(
    m: &OmaMode,
    reps: &[Replicate],
    scheme: Scheme<'_>,
    notes: &mut Vec<String>,
) -> Uncertainty {
    let mut u = Uncertainty::default();
    let jackknife = |a: f64, v: &[f64]| scheme.interval(a, v);
    let pick = |f: &dyn Fn(&Replicate) -> Option<f64>| -> Option<Vec<f64>> {
        reps.iter().map(f).collect()
    };
    let missing = |what: &str| {
        format!(
            "{} mode {} ({:.4} Hz): no interval of its {what}: a replicate without a tenth \
             of the record did not find the mode",
            m.method.name(),
            m.mode,
            m.f_hz
        )
    };
    match m.method {
        Method::Fdd => {
            u.amplitude = m
                .amplitude
                .and_then(|a| pick(&|r| r.amplitude).and_then(|v| jackknife(a, &v)))
                .map(non_negative);
            u.shape_abs = shape_u(&m.shape, reps, scheme);
        }
        Method::Efdd | Method::Ssi => {
            match pick(&|r| r.efdd_or_ssi.map(|x| x.0)) {
                Some(v) => {
                    u.f_hz = jackknife(m.f_hz, &v).and_then(|i| {
                        let kept = i.of_positive();
                        if kept.is_none() {
                            notes.push(format!(
                                "{} mode {} ({:.4} Hz): the 95 % interval of its frequency \
                                 reaches 0 Hz: its frequency is not determined, no interval",
                                m.method.name(),
                                m.mode,
                                m.f_hz
                            ));
                        }
                        kept
                    })
                }
                None => notes.push(missing("frequency and damping")),
            }
            if let (Some(z), Some(v)) = (m.damping, pick(&|r| r.efdd_or_ssi.map(|x| x.1))) {
                u.damping = jackknife(z, &v).map(non_negative);
            }
            if m.method == Method::Efdd {
                u.amplitude = m
                    .amplitude
                    .and_then(|a| pick(&|r| r.amplitude).and_then(|v| jackknife(a, &v)))
                    .map(non_negative);
            }
            u.shape_abs = shape_u(&m.shape, reps, scheme);
        }
        // the jackknife over the decays (`decay::decay_modes`), over segments
        // (`plscf::plscf_modes`), computed with them
        Method::Decay | Method::Plscf => {}
    }
    u
}

/// One mode's replicates and how they were made (the spectral ones each without a group of
/// Welch segments, of these sizes; SSI's without half of the blocks of samples); `None` when
/// there are none.
#[allow(clippy::type_complexity)]
fn mode_replicates<'a>(
    m: &OmaMode,
    modes: &[OmaMode],
    peaks: &[Peak],
    (spectral, ssi): (
        Option<&'a (Vec<Vec<Replicate>>, Vec<usize>)>,
        Option<&'a SsiReplicates>,
    ),
) -> Option<(Vec<Replicate>, Scheme<'a>)> {
    match m.method {
        Method::Fdd | Method::Efdd => {
            let p = peaks
                .iter()
                .enumerate()
                .position(|(i, p)| p.mode_number(i) == m.mode);
            p.and_then(|p| {
                spectral.map(|(r, sizes)| {
                    (
                        r.iter().map(|g| g[p].clone()).collect(),
                        Scheme::Sized(sizes.as_slice()),
                    )
                })
            })
        }
        Method::Ssi => ssi.and_then(|r| {
            let i = modes
                .iter()
                .filter(|x| x.method == Method::Ssi)
                .position(|x| x.mode == m.mode)?;
            r.get(i).cloned()
        }),
        Method::Decay | Method::Plscf => None,
    }
}

/// Where a peak's EFDD fit starts in the replicates: the whole record's frequency and
/// damping.
type Start = Option<(f64, f64)>;

/// One replicate's estimates of one mode.
#[derive(Debug, Clone, Default)]
struct Replicate {
    /// Frequency and damping (EFDD, SSI).
    efdd_or_ssi: Option<(f64, f64)>,
    /// The singular value at the peak (FDD, EFDD).
    amplitude: Option<f64>,
    /// The shape (normalised).
    shape: Option<Vec<num_complex::Complex64>>,
}

/// The jackknife uncertainty of each shape component's magnitude.
fn shape_u(
    shape: &[num_complex::Complex64],
    reps: &[Replicate],
    scheme: Scheme<'_>,
) -> Option<Vec<f64>> {
    let shapes: Option<Vec<&Vec<num_complex::Complex64>>> =
        reps.iter().map(|r| r.shape.as_ref()).collect();
    let shapes = shapes?;
    Some(
        (0..shape.len())
            .map(|j| {
                let v: Vec<f64> = shapes
                    .iter()
                    .map(|s| s.get(j).map_or(0.0, |c| c.norm()))
                    .collect();
                scheme
                    .interval(shape[j].norm(), &v)
                    .map_or(f64::NAN, |i| i.u)
            })
            .collect(),
    )
}

/// Per group left out its replicates (one per peak), and the segments of each group.
type SpectralReplicates = (Vec<Vec<Replicate>>, Vec<usize>);

/// Per group left out, per peak: the FDD amplitude and shape at the peak's line, and EFDD's
/// fit of the replicate's bell (same reference, line and fences); and the segments in each
/// group left out (14 segments in 10 groups: four of two). `None` with fewer Welch segments
/// than groups.
fn spectral_replicates(
    (segments, replicate_of): (usize, &ReplicateOf<'_>),
    s: &OmaSettings,
    (peaks, starts): (&[Peak], &[Start]),
    groups: usize,
) -> anyhow::Result<Option<SpectralReplicates>> {
    // as many groups as segments on a short record (overlapping segments share samples, so
    // a group of one is not quite independent of its neighbours), and none under four
    let groups = groups.min(segments);
    if groups < 4 || peaks.is_empty() {
        return Ok(None);
    }
    let lag = fdd::lag_window(s.csd.window, s.csd.nperseg);
    let mut out = Vec::with_capacity(groups);
    let mut sizes = Vec::with_capacity(groups);
    for g in 0..groups {
        let (replicate, size) = replicate_of(g, groups)?;
        sizes.push(size);
        let svd: Svd = fdd::decompose(&replicate)?;
        let lines = svd.freq_hz.len();
        let reps = peaks
            .iter()
            .enumerate()
            .map(|(n, p)| {
                let (_, at) = fdd::bell(
                    &svd,
                    &p.reference,
                    p.line,
                    (p.line.saturating_sub(1), p.line + 1),
                    0.0,
                );
                let fence = super::modes::fence(peaks, n, lines);
                let e = fdd::efdd(
                    &svd,
                    (&p.reference, p.line),
                    fence,
                    (s.csd.nfft, s.fs_hz),
                    (&lag, starts[n]),
                    s.efdd,
                )
                .ok();
                let u = if mac(&svd.u2[p.line], &p.reference) > mac(&svd.u1[p.line], &p.reference) {
                    &svd.u2[p.line]
                } else {
                    &svd.u1[p.line]
                };
                Replicate {
                    efdd_or_ssi: e.map(|e| (e.f_hz, e.damping)),
                    amplitude: at.first().copied(),
                    shape: Some(normalise_shape(u)),
                }
            })
            .collect();
        out.push(reps);
    }
    Ok(Some((out, sizes)))
}

/// SSI's replicates: per SSI mode (in their order), its replicates and how they were made.
type SsiReplicates = Vec<(Vec<Replicate>, Scheme<'static>)>;

/// Per SSI mode of `modes` (in their order) its replicates ([`ssi_mode_replicates`]) from
/// `groups` blocks of the record.
fn ssi_replicates(
    channels: &[Vec<f64>],
    s: &OmaSettings,
    (modes, lone): (&[OmaMode], &[f64]),
    groups: usize,
    notes: &mut Vec<String>,
) -> anyhow::Result<Option<SsiReplicates>> {
    if !modes.iter().any(|m| m.method == Method::Ssi) {
        return Ok(None);
    }
    let parts = ssi::Parts::of(channels, s.ssi, groups)?;
    let poles = |g: &[usize]| Ok(parts.poles(g, s.fs_hz, s.ssi)?.0);
    ssi_mode_replicates((modes, lone), s.cluster, groups, poles, notes).map(Some)
}

/// Per SSI mode of `modes` (in their order) its replicates, `poles(left_out)` the poles of
/// every order without the groups `left_out` of `groups`: those of the delete-half jackknife
/// ([`half_samples`], [`HALF_SAMPLES`] of them), because SSI's estimate of a mode is not smooth
/// in the data (the cluster's median over model orders, each order's pole a choice among
/// several) and a replicate's own jump enters the delete-one jackknife's variance about
/// `groups - 1` times (docs/validation.md §3). A mode that a replicate with half of the record
/// does not find (a short record, a weak mode) takes the delete-one jackknife's replicates
/// instead, and a note says so.
fn ssi_mode_replicates(
    (modes, lone): (&[OmaMode], &[f64]),
    rule: ClusterRule,
    groups: usize,
    poles: impl Fn(&[usize]) -> anyhow::Result<Vec<ssi::Pole>>,
    notes: &mut Vec<String>,
) -> anyhow::Result<SsiReplicates> {
    let ssi: Vec<&OmaMode> = modes.iter().filter(|m| m.method == Method::Ssi).collect();
    let column = |reps: &[Vec<Replicate>], i: usize| -> Vec<Replicate> {
        reps.iter().map(|r| r[i].clone()).collect()
    };
    let d = groups / 2;
    let half = replicates_from_poles(
        (modes, lone),
        rule,
        &half_samples(groups, d, HALF_SAMPLES),
        &poles,
    )?;
    let missed = |i: usize| half.iter().filter(|r| r[i].efdd_or_ssi.is_none()).count();
    let mut one: Option<Vec<Vec<Replicate>>> = None;
    let mut out = Vec::with_capacity(ssi.len());
    for (i, m) in ssi.iter().enumerate() {
        let k = missed(i);
        if k == 0 {
            out.push((column(&half, i), Scheme::Half(groups, d)));
            continue;
        }
        if one.is_none() {
            let design: Vec<Vec<usize>> = (0..groups).map(|g| vec![g]).collect();
            one = Some(replicates_from_poles((modes, lone), rule, &design, &poles)?);
        }
        notes.push(format!(
            "{} mode {} ({:.4} Hz): its intervals from the delete-one jackknife (each replicate \
             without a tenth of the record): {k} of {} replicates without half of the record \
             did not find the mode",
            m.method.name(),
            m.mode,
            m.f_hz,
            half.len()
        ));
        out.push((column(one.as_deref().unwrap_or_default(), i), Scheme::Plain));
    }
    Ok(out)
}

/// Per replicate of `design` (each the groups it leaves out; `poles(left_out)`: the poles of
/// every order without them), per SSI mode of `modes` (in their order): the replicate's mode
/// nearest it (within three half-power bandwidths or 1 %, whichever is wider, and a MAC of
/// 0.8 or more with its shape), `None` fields where there is none. It is sought among the
/// replicate's clusters that make a mode, then (for a mode of `lone`, kept with fewer poles
/// than a mode needs: only) among those of at least [`super::modes::LONE_MIN_POLES`] poles:
/// the whole record decided that the mode is there, a replicate with half of it re-estimates
/// the mode even where it would not have decided so.
fn replicates_from_poles(
    (modes, lone): (&[OmaMode], &[f64]),
    rule: ClusterRule,
    design: &[Vec<usize>],
    poles: &impl Fn(&[usize]) -> anyhow::Result<Vec<ssi::Pole>>,
) -> anyhow::Result<Vec<Vec<Replicate>>> {
    let ssi: Vec<&OmaMode> = modes.iter().filter(|m| m.method == Method::Ssi).collect();
    let small_rule = ClusterRule {
        min_poles: super::modes::LONE_MIN_POLES,
        ..rule
    };
    let mut out = Vec::with_capacity(design.len());
    for left_out in design {
        let poles = poles(left_out)?;
        let (kept, _) = cluster::cluster(&poles, rule);
        let small = std::cell::OnceCell::new();
        let nearest = |clusters: &[SsiMode], m: &OmaMode| {
            let z = m.damping.unwrap_or(0.01);
            let reach = (3.0 * 2.0 * z * m.f_hz).max(0.01 * m.f_hz);
            clusters
                .iter()
                .filter(|c| (c.f_hz - m.f_hz).abs() <= reach && mac(&c.shape, &m.shape) >= 0.8)
                .min_by(|a, b| (a.f_hz - m.f_hz).abs().total_cmp(&(b.f_hz - m.f_hz).abs()))
                .map(|c| Replicate {
                    efdd_or_ssi: Some((c.f_hz, c.damping)),
                    amplitude: None,
                    shape: Some(normalise_shape(&c.shape)),
                })
        };
        let reps = ssi
            .iter()
            .map(|m| {
                let found = match lone.contains(&m.f_hz) {
                    true => None,
                    false => nearest(&kept, m),
                };
                found
                    .or_else(|| {
                        let small = small.get_or_init(|| cluster::cluster(&poles, small_rule).0);
                        nearest(small, m)
                    })
                    .unwrap_or_default()
            })
            .collect();
        out.push(reps);
    }
    Ok(out)
}

/// Per mode of `modes` (an SSI mode's; the others' left empty), its uncertainty by the
/// delete-half jackknife over `groups` groups, `poles(left_out)` the poles of every order
/// without the groups `left_out` (how several setups identified together give their intervals
/// so). Notes name the modes left without an interval.
pub fn of_ssi_modes(
    modes: &[OmaMode],
    rule: ClusterRule,
    groups: usize,
    poles: impl Fn(&[usize]) -> anyhow::Result<Vec<ssi::Pole>>,
    notes: &mut Vec<String>,
) -> anyhow::Result<Vec<Uncertainty>> {
    let mut out = vec![Uncertainty::default(); modes.len()];
    if groups < 3 || modes.is_empty() {
        return Ok(out);
    }
    let reps = ssi_mode_replicates((modes, &[]), rule, groups, poles, notes)?;
    let ssi = modes.iter().zip(out.iter_mut());
    for ((m, u), (mine, scheme)) in ssi.filter(|(m, _)| m.method == Method::Ssi).zip(reps) {
        *u = mode_intervals(m, &mine, scheme, notes);
    }
    Ok(out)
}

/// Folds the scale's relative standard uncertainty per channel (`u_rel[c]`, from the scale
/// each target's displacement was converted with) into the modes' amplitude and shape-magnitude
/// intervals where they were estimated: the scale errors taken as fully correlated between the
/// targets (exact for one scale for the frame, an upper bound otherwise), the amplitude (a
/// power: the singular value at the peak) gets `2 sum_c w_c u_rel[c]` relative, `w_c` the
/// shape's share `|phi_c|^2 / sum |phi|^2`; each shape component `|phi_c| u_rel[c]`; each added
/// in quadrature to the statistical standard uncertainty and 95 % half-width (the scale's
/// taken as normal). Returns whether anything changed.
pub fn fold_scale(modes: &mut [super::OmaMode], u_rel: &[f64]) -> bool {
    // below 1e-9 relative: rounding, not an uncertainty
    if !u_rel.iter().any(|u| u.is_finite() && *u > 1e-9) {
        return false;
    }
    let mut changed = false;
    for m in modes.iter_mut() {
        if m.shape.len() != u_rel.len() {
            continue;
        }
        let norm: f64 = m.shape.iter().map(|c| c.norm_sqr()).sum();
        if norm <= 0.0 || norm.is_nan() {
            continue;
        }
        let rel: f64 = 2.0
            * m.shape
                .iter()
                .zip(u_rel)
                .map(|(c, u)| c.norm_sqr() / norm * u.max(0.0))
                .sum::<f64>();
        if let (Some(i), Some(a)) = (m.uncertainty.amplitude.as_mut(), m.amplitude) {
            let extra = a.abs() * rel;
            let centre = 0.5 * (i.lo + i.hi);
            let half = (i.half_width().powi(2) + (1.96 * extra).powi(2)).sqrt();
            *i = Interval {
                u: (i.u * i.u + extra * extra).sqrt(),
                lo: centre - half,
                hi: centre + half,
            };
            changed = true;
        }
        if let Some(s) = m.uncertainty.shape_abs.as_mut() {
            let big = m.shape.iter().map(|c| c.norm()).fold(0.0, f64::max);
            for ((u, c), r) in s.iter_mut().zip(&m.shape).zip(u_rel) {
                let extra = if big > 0.0 {
                    c.norm() / big * r.max(0.0)
                } else {
                    0.0
                };
                *u = (*u * *u + extra * extra).sqrt();
            }
            changed = true;
        }
    }
    changed
}

#[cfg(test)]
mod fold_tests {
    use super::*;
    use num_complex::Complex64;

    #[test]
    fn a_scales_uncertainty_widens_amplitude_and_shape_intervals_in_quadrature() {
        let mut m = vec![crate::oma::OmaMode {
            method: crate::oma::Method::Fdd,
            mode: 1,
            band_hz: None,
            f_hz: 2.0,
            amplitude: Some(10.0),
            damping: None,
            shape: vec![Complex64::new(1.0, 0.0), Complex64::new(1.0, 0.0)],
            evidence: String::new(),
            uncertainty: Uncertainty {
                amplitude: Some(Interval {
                    u: 0.3,
                    lo: 9.4,
                    hi: 10.6,
                }),
                shape_abs: Some(vec![0.0, 0.04]),
                ..Uncertainty::default()
            },
        }];
        // one scale for the frame, 2 % uncertain: the power 4 % of 10 = 0.4, with 0.3: 0.5
        assert!(fold_scale(&mut m, &[0.02, 0.02]));
        let a = m[0].uncertainty.amplitude.unwrap();
        assert!((a.u - 0.5).abs() < 1e-12, "{a:?}");
        let half = (0.6f64.powi(2) + (1.96f64 * 0.4).powi(2)).sqrt();
        assert!((a.lo - (10.0 - half)).abs() < 1e-12 && (a.hi - (10.0 + half)).abs() < 1e-12);
        let s = m[0].uncertainty.shape_abs.clone().unwrap();
        assert!((s[0] - 0.02).abs() < 1e-12 && (s[1] - 0.02f64.hypot(0.04)).abs() < 1e-12);
        // no scale uncertainty: nothing changes
        assert!(!fold_scale(&mut m, &[0.0, 0.0]));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::oma::{analyze, OmaSettings};
    use vibcam_model::field::{simulate, FieldCase};

    #[test]
    fn the_jackknife_by_hand() {
        // replicates 1, 2, 3, 4: mean 2.5, (G - 1) / G sum of squares = 3 / 4 * 5 = 3.75
        let i = jackknife(10.0, &[1.0, 2.0, 3.0, 4.0]).unwrap();
        assert!((i.u - 3.75f64.sqrt()).abs() < 1e-12);
        assert!((i.hi - 10.0 - 3.182 * 3.75f64.sqrt()).abs() < 1e-12);
        assert!((i.lo + i.hi - 20.0).abs() < 1e-12);
        // Student's t: 12.706 at one degree of freedom, 2.262 at nine, 1.96 beyond thirty
        assert_eq!((t975(1), t975(9), t975(40)), (12.706, 2.262, 1.96));
        assert!(jackknife(1.0, &[1.0]).is_none());
        assert!(jackknife(1.0, &[1.0, f64::NAN]).is_none());
    }

    #[test]
    fn half_samples_leave_out_half_and_each_group_equally_often() {
        let d = half_samples(10, 5, HALF_SAMPLES);
        assert_eq!(d.len(), HALF_SAMPLES);
        let mut times = [0usize; 10];
        for (i, s) in d.iter().enumerate() {
            assert_eq!(s.len(), 5);
            assert!(s.windows(2).all(|w| w[0] < w[1]), "sorted and distinct");
            assert!(!d[..i].contains(s), "no replicate twice");
            s.iter().for_each(|&g| times[g] += 1);
        }
        // complementary pairs: every group left out by half of the replicates
        assert_eq!(times, [HALF_SAMPLES / 2; 10]);
        assert_eq!(
            d,
            half_samples(10, 5, HALF_SAMPLES),
            "the same design every time"
        );
        // few groups: every choice, C(6, 3) = 20
        let all = half_samples(6, 3, 40);
        assert_eq!(all.len(), 20);
        assert!(all.iter().all(|s| s.len() == 3));
    }

    #[test]
    fn the_delete_half_jackknife_of_a_mean_is_the_variance_of_the_mean() {
        // the mean of six groups: over every half left out, the delete-half variance is
        // s^2 / n exactly (sampling without replacement), as the delete-one jackknife's is
        let x = [0.3, -1.2, 2.5, 0.7, 1.9, -0.4];
        let n = x.len() as f64;
        let mean = x.iter().sum::<f64>() / n;
        let s2 = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let design = half_samples(6, 3, 100);
        let reps: Vec<f64> = design
            .iter()
            .map(|out| {
                let kept: Vec<f64> = (0..6).filter(|g| !out.contains(g)).map(|g| x[g]).collect();
                kept.iter().sum::<f64>() / kept.len() as f64
            })
            .collect();
        let half = jackknife_half(mean, &reps, (6, 3)).unwrap();
        assert!(
            (half.u.powi(2) - s2 / n).abs() < 1e-12,
            "{} {}",
            half.u.powi(2),
            s2 / n
        );
        let ones: Vec<f64> = (0..6)
            .map(|g| (x.iter().sum::<f64>() - x[g]) / (n - 1.0))
            .collect();
        assert!((jackknife(mean, &ones).unwrap().u - half.u).abs() < 1e-12);
        assert!((half.hi - mean - t975(5) * half.u).abs() < 1e-12);
        assert!(jackknife_half(1.0, &[1.0], (6, 3)).is_none());
        assert!(jackknife_half(1.0, &[1.0, 2.0], (6, 0)).is_none());
    }

    #[test]
    fn a_jump_of_one_replicate_counts_once_in_the_delete_half_jackknife() {
        // an estimate that jumps by +-e with the data it is given (a pole chosen among
        // several), over a constant: its own variance is e^2; the delete-one jackknife sees
        // about (G - 1)^2 / G e^2, the delete-half one about e^2
        let e = 1.0;
        let jump = |out: &[usize]| {
            let h = out
                .iter()
                .fold(17u64, |h, &g| h.wrapping_mul(31).wrapping_add(g as u64));
            if h.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 63 == 1 {
                e
            } else {
                -e
            }
        };
        let (mut one, mut half) = (0.0, 0.0);
        let trials = 200;
        for t in 0..trials {
            // a different record: the groups relabelled
            let shift = |g: usize| (g + t) % 10 + 10 * (t / 10);
            let ones: Vec<f64> = (0..10).map(|g| jump(&[shift(g), 1000])).collect();
            let halves: Vec<f64> = half_samples(10, 5, HALF_SAMPLES)
                .iter()
                .map(|s| jump(&s.iter().map(|&g| shift(g)).collect::<Vec<_>>()))
                .collect();
            one += jackknife(0.0, &ones).unwrap().u.powi(2) / trials as f64;
            half += jackknife_half(0.0, &halves, (10, 5)).unwrap().u.powi(2) / trials as f64;
        }
        assert!(one > 6.0 * e * e, "delete-one: {one}");
        assert!((0.7..1.3).contains(&half), "delete-half: {half}");
    }

    #[test]
    fn the_intervals_hold_on_records_whose_truth_is_known() {
        // 16 three-minute records of the shear frame (2 % noise): of the 95 % intervals of
        // the frequency and damping of its five modes by EFDD and SSI-cov, at least 85 %
        // hold (95.3 % over 540 records of three cases, lengths and noise levels:
        // examples/oma_coverage.rs, docs/validation.md); too narrow by half they would
        // hold about 70 % of the time
        let model = FieldCase::ShearFrame.model();
        let fs = 60.0;
        let n = (fs * 180.0) as usize;
        use rayon::prelude::*;
        // (held, counted) per record, the records analysed side by side
        let (held, counted) = (0..16u64)
            .into_par_iter()
            .map(|seed| {
                let rec = simulate(&model, fs, n, 0.02, 700 + seed);
                let r = analyze(&rec, &OmaSettings::new(fs, n, None)).unwrap();
                let (mut held, mut counted) = (0usize, 0usize);
                for m in r.modes.iter().filter(|m| m.method != Method::Fdd) {
                    let Some(t) = model
                        .modes
                        .iter()
                        .find(|t| (t.f_hz - m.f_hz).abs() < 3.0 * t.damping * t.f_hz)
                    else {
                        continue;
                    };
                    for (i, truth) in [
                        (m.uncertainty.f_hz, t.f_hz),
                        (m.uncertainty.damping, t.damping),
                    ] {
                        let i = i.unwrap_or_else(|| panic!("no interval: {m:?}"));
                        held += usize::from(i.lo <= truth && truth <= i.hi);
                        counted += 1;
                    }
                }
                (held, counted)
            })
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        assert!(counted >= 16 * 5 * 2 * 2 - 8, "{counted} intervals");
        assert!(
            held as f64 >= 0.85 * counted as f64,
            "{held} of {counted} intervals hold"
        );
    }

    #[test]
    fn the_sized_jackknife_is_the_plain_one_for_equal_groups_and_weighs_unequal_ones() {
        let reps = [1.0, 1.3, 0.8, 1.1, 0.95];
        let a = jackknife(1.02, &reps).unwrap();
        let b = jackknife_sized(1.02, &reps, &[3; 5]).unwrap();
        assert!(
            (a.u - b.u).abs() < 1e-12 && (a.lo - b.lo).abs() < 1e-12,
            "{a:?} {b:?}"
        );
        // the mean of n values in groups of 1 and 2: the exact variance of the mean, s^2 / n
        let x = [2.0, 5.0, 3.0, 4.0, 7.0, 1.0, 6.0];
        let groups: [&[f64]; 4] = [&x[0..2], &x[2..3], &x[3..5], &x[5..7]];
        let n = x.len() as f64;
        let mean = x.iter().sum::<f64>() / n;
        let reps: Vec<f64> = groups
            .iter()
            .map(|g| (mean * n - g.iter().sum::<f64>()) / (n - g.len() as f64))
            .collect();
        let sizes: Vec<usize> = groups.iter().map(|g| g.len()).collect();
        let u = jackknife_sized(mean, &reps, &sizes).unwrap().u;
        let s2 = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
        // a grouped jackknife estimates s^2 / n from G groups: close, not equal
        assert!(
            (u * u / (s2 / n) - 1.0).abs() < 0.6,
            "{u} {}",
            (s2 / n).sqrt()
        );
    }
}
