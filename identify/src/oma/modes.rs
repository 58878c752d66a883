//! Which peaks of the singular values and which clusters of SSI-cov's poles are modes
//! (docs/method.md §3.12), with bands (one per band and method) or without (each peak and
//! each cluster checked, the rejected ones named with their reason).
//!
//! Without bands a peak of the first singular value (6 dB of prominence) is a mode when it
//! behaves like one: its singular vector holds over a bell of at least five lines (a noise
//! peak's turns from line to line), it is not a ripple on the bell of a stronger peak with the
//! same shape, and, unless it stands 10 dB or more above its surroundings, SSI-cov finds a mode
//! within its bell with a like shape. An SSI-cov mode that no peak took (a mode hidden in the
//! second singular value beside a close stronger one, or a weak mode without 6 dB of
//! prominence) gives FDD and EFDD its bell: the lines whose first or second singular vector
//! has its shape. An SSI-cov cluster rejected for its size alone is kept when it is the only
//! explanation of a strong peak ([`lone_explanations`]; docs/method.md §3.12).

use super::bell::Quantity;
use super::cluster::{self, SsiMode};
use super::fdd::{self, Svd};
use super::ssi::{self, Pole};
use super::{Method, OmaMode, OmaSettings};
use crate::modal::{mac, normalise_shape};
use num_complex::Complex64;

/// Least prominence of a peak taken without SSI-cov's support, dB.
pub const STRONG_PEAK_DB: f64 = 10.0;
/// Least MAC between a peak's vector and an SSI-cov mode's shape for the two to agree.
pub const AGREE_MAC: f64 = 0.8;

/// A peak taken as a mode.
#[derive(Debug, Clone)]
pub struct Peak {
    /// Its line (the bell's largest value).
    pub line: usize,
    /// Its band (with bands).
    pub band: Option<usize>,
    /// The mode's shape (the peak's singular vector).
    pub reference: Vec<Complex64>,
    /// The bell's value at the peak (its singular value).
    pub value: f64,
    /// How it was found, for the report.
    pub evidence: String,
}

impl Peak {
    /// The number of the FDD and EFDD modes of the peak at `index` of the peaks: its band's
    /// with bands, else its place in frequency.
    pub fn mode_number(&self, index: usize) -> usize {
        self.band.map_or(index + 1, |b| b + 1)
    }
}

/// SSI-cov's result: its modes, every pole, the clusters kept and rejected.
#[derive(Debug)]
pub struct SsiFound {
    /// The modes.
    pub modes: Vec<OmaMode>,
    /// Every pole of every order.
    pub poles: Vec<Pole>,
    /// The clusters reported (as modes) and the ones rejected, for the stabilisation plot.
    pub clusters: Vec<(SsiMode, bool)>,
    /// The frequencies of the modes kept with fewer poles than a mode needs, as the only
    /// explanation of a strong peak ([`lone_explanations`]).
    pub lone: Vec<f64>,
}

/// SSI-cov's modes: the clusters of stable poles that pass [`cluster::cluster`]'s rules
/// (without bands) or the fullest such cluster in each band; the rejected clusters go to
/// `rejected` with their reason; a stable mode below the range analysed is noted, never
/// dropped in silence.
pub fn ssi_modes(
    (channels, svd): (&[Vec<f64>], &Svd),
    s: &OmaSettings,
    notes: &mut Vec<String>,
    rejected: &mut Vec<String>,
) -> anyhow::Result<SsiFound> {
    let (poles, cut) = ssi::poles(channels, s.fs_hz, s.ssi)?;
    let kind = s.ssi.kind.label();
    let (mut kept, mut dropped) = cluster::cluster(&poles, s.cluster);
    let lone = match s.bands.is_empty() && s.poles.is_none() {
        true => keep_lone(svd, s, &mut kept, &mut dropped),
        false => Vec::new(),
    };
    for c in cluster::cluster(&cut, s.cluster).0 {
        notes.push(format!(
            "{kind}: a stable mode at {:.4} Hz (damping {:.4}, {} stable poles) lies below the \
             lowest frequency analysed, {:.4} Hz (0.5 Hz, or two spectral lines of {} samples, \
             whichever is higher; or $f_min_hz): not reported; a longer $nperseg or a lower \
             $f_min_hz takes it in",
            c.f_hz, c.damping, c.poles, s.ssi.f_range_hz.0, s.csd.nfft
        ));
    }
    if let Some(given) = &s.poles {
        return Ok(SsiFound {
            modes: given_modes(given, &poles, kind)?,
            poles,
            clusters: kept
                .into_iter()
                .map(|c| (c, true))
                .chain(dropped.into_iter().map(|r| (r.cluster, false)))
                .collect(),
            lone: Vec::new(),
        });
    }
    let modes: Vec<OmaMode> =
        cluster::chosen((&kept, &dropped), &s.bands, ("ssi", kind), notes, rejected)
            .into_iter()
            .map(|chosen| {
                let why = lone.iter().find(|l| l.0 == chosen.2.f_hz);
                let evidence = match why {
                    Some((_, why)) => format!("{}; {why}", cluster_evidence(chosen.2)),
                    None => cluster_evidence(chosen.2),
                };
                of_cluster(Method::Ssi, chosen, &s.bands, evidence)
            })
            .collect();
    let clusters = kept
        .into_iter()
        .map(|c| (c, true))
        .chain(dropped.into_iter().map(|r| (r.cluster, false)))
        .collect();
    Ok(SsiFound {
        modes,
        poles,
        clusters,
        lone: lone.into_iter().map(|l| l.0).collect(),
    })
}

/// The modes of the poles `given` (`$poles`), in ascending frequency: each its frequency and
/// damping as given, its shape the one of the diagram's stable pole nearest it (the highest
/// order among equals) within 1 %, the stable poles there its evidence. A pole picked on the
/// diagram is one of its poles: its own shape. Refused (bad input) where no stable pole lies
/// within 1 % of one.
fn given_modes(
    given: &[crate::modal::Pole],
    poles: &[Pole],
    kind: &str,
) -> anyhow::Result<Vec<OmaMode>> {
    let mut given = given.to_vec();
    given.sort_by(|a, b| a.f_hz.total_cmp(&b.f_hz));
    given
        .iter()
        .enumerate()
        .map(|(i, g)| {
            let gap = |p: &Pole| (p.f_hz - g.f_hz).abs();
            let near: Vec<&Pole> = poles
                .iter()
                .filter(|p| p.stable && gap(p) <= 0.01 * g.f_hz)
                .collect();
            let best = near
                .iter()
                .min_by(|a, b| gap(a).total_cmp(&gap(b)).then(b.order.cmp(&a.order)))
                .ok_or_else(|| {
                    vibcam_readers::bad_input(format!(
                        "$poles: no stable {kind} pole lies within 1 % of {} Hz (the diagram's \
                         poles are in report.html's picker)",
                        g.f_hz
                    ))
                })?;
            Ok(OmaMode {
                method: Method::Ssi,
                mode: i + 1,
                band_hz: None,
                f_hz: g.f_hz,
                amplitude: None,
                damping: Some(g.damping),
                shape: normalise_shape(&best.shape),
                evidence: format!(
                    "given ($poles): the shape of the stable pole at {:.4} Hz (order {}); {} \
                     stable poles within 1 %",
                    best.f_hz,
                    best.order,
                    near.len()
                ),
                uncertainty: Default::default(),
            })
        })
        .collect()
}

/// Moves the clusters of `dropped` that [`lone_explanations`] keeps into `kept` (ascending
/// frequency); their frequencies and why each was kept.
fn keep_lone(
    svd: &Svd,
    s: &OmaSettings,
    kept: &mut Vec<SsiMode>,
    dropped: &mut Vec<cluster::Rejected>,
) -> Vec<(f64, String)> {
    let mut found = lone_explanations(svd, s, kept, dropped);
    found.sort_by_key(|x| std::cmp::Reverse(x.0));
    let mut lone = Vec::new();
    for (i, why) in found {
        let c = dropped.remove(i).cluster;
        lone.push((c.f_hz, why));
        kept.push(c);
    }
    kept.sort_by(|a, b| a.f_hz.total_cmp(&b.f_hz));
    lone
}

/// Fewest stable poles of a cluster kept as the only explanation of a strong peak
/// ([`lone_explanations`]): two model orders in a row that agree.
pub const LONE_MIN_POLES: usize = 2;

/// The clusters of `dropped` (by index, with the reason they are kept) that were rejected for
/// their size alone and are the only explanation of a strong peak: a peak of the first
/// singular value that stands [`STRONG_PEAK_DB`] or more, whose bell (its singular vector held,
/// MAC >= the EFDD rule's) holds no mode of `kept` with a like shape (MAC >= [`AGREE_MAC`]),
/// and within half a line of which one cluster alone has the peak's shape (MAC >=
/// [`AGREE_MAC`]): that cluster, when it has at least [`LONE_MIN_POLES`] poles and shares a
/// phase (the MPC and MPD rules). Several small clusters there explain nothing: none is
/// kept. A short or lightly damped record (a struck fork filmed for a second or two) gives
/// few stable orders; the peak says the mode is there, and the poles give its frequency finer
/// than the line and its damping.
pub fn lone_explanations(
    svd: &Svd,
    s: &OmaSettings,
    kept: &[SsiMode],
    dropped: &[cluster::Rejected],
) -> Vec<(usize, String)> {
    let lines = svd.freq_hz.len();
    let f = |l: usize| svd.freq_hz[l];
    let df = svd.freq_hz.get(1).copied().unwrap_or(1.0);
    let rule = s.cluster;
    let mut out: Vec<(usize, String)> = Vec::new();
    for (l, prominence) in fdd::pick_peaks(svd, s.peaks) {
        if prominence < STRONG_PEAK_DB {
            continue;
        }
        let reference = &svd.u1[l];
        let (a, values) = fdd::bell(svd, reference, l, (0, lines), s.efdd.mac_min);
        let (lo, hi) = (f(a), f(a + values.len().max(1) - 1));
        let agrees = |c: &SsiMode| mac(&c.shape, reference) >= AGREE_MAC;
        if kept
            .iter()
            .any(|c| c.f_hz >= lo && c.f_hz <= hi && agrees(c))
        {
            continue;
        }
        // the line nearest a mode's frequency is its peak: a cluster of the peak's shape within
        // half a line of it, and no other there (several small clusters are no explanation)
        let near: Vec<(usize, &cluster::Rejected)> = dropped
            .iter()
            .enumerate()
            .filter(|(_, r)| (r.cluster.f_hz - f(l)).abs() <= 0.5 * df && agrees(&r.cluster))
            .collect();
        let best = match near.as_slice() {
            [(i, r)] => {
                let c = &r.cluster;
                let fits = (LONE_MIN_POLES..rule.min_poles).contains(&c.poles)
                    && c.mpc >= rule.mpc_min
                    && c.mpd_deg <= rule.mpd_max_deg
                    && !out.iter().any(|o| o.0 == *i);
                fits.then_some((*i, *r))
            }
            _ => None,
        };
        if let Some((i, r)) = best {
            out.push((
                i,
                format!(
                    "kept with {} stable poles (a mode needs {} otherwise): the only explanation \
                     of the {prominence:.1} dB peak of the first singular value at {:.4} Hz (MAC \
                     {:.3} with its singular vector; no fuller SSI-cov mode in its bell)",
                    r.cluster.poles,
                    rule.min_poles,
                    f(l),
                    mac(&r.cluster.shape, reference)
                ),
            ));
        }
    }
    out
}

/// A cluster's size and spread, for the report.
pub fn cluster_evidence(c: &SsiMode) -> String {
    format!(
        "{} poles (orders {}-{}), spread f {:.2} % damping {:.0} %, MPC {:.3}, MPD {:.1} deg",
        c.poles,
        c.orders.0,
        c.orders.1,
        100.0 * c.f_spread,
        100.0 * c.damping_spread,
        c.mpc,
        c.mpd_deg
    )
}

/// The mode `method` found as the cluster `c`, numbered `n` (in band `band` of `bands`), with
/// `evidence` for the report; no interval yet.
pub fn of_cluster(
    method: Method,
    (n, band, c): (usize, Option<usize>, &SsiMode),
    bands: &[(f64, f64)],
    evidence: String,
) -> OmaMode {
    OmaMode {
        method,
        mode: n,
        band_hz: band.map(|b| bands[b]),
        f_hz: c.f_hz,
        amplitude: None,
        damping: Some(c.damping),
        shape: normalise_shape(&c.shape),
        evidence,
        uncertainty: Default::default(),
    }
}

/// The FDD peaks with bands: the highest line of each band (a band without a line is noted).
pub fn banded_peaks(svd: &Svd, df_hz: f64, s: &OmaSettings, notes: &mut Vec<String>) -> Vec<Peak> {
    s.bands
        .iter()
        .enumerate()
        .filter_map(|(b, &band)| match fdd::peak_in_band(svd, band) {
            Some(l) => Some(Peak {
                line: l,
                band: Some(b),
                reference: svd.u1[l].clone(),
                value: svd.s[l][0],
                evidence: format!("the band's highest line, {:.4} Hz", svd.freq_hz[l]),
            }),
            None => {
                notes.push(format!(
                    "band {}-{} Hz has no spectral line (line spacing {:.4} Hz)",
                    band.0, band.1, df_hz
                ));
                None
            }
        })
        .collect()
}

/// A peak accepted, with its bell's lines (first, last).
struct Taken {
    peak: Peak,
    bell: (usize, usize),
}

/// The FDD peaks without bands (module documentation), ascending; each peak rejected goes to
/// `rejected` with its reason.
pub fn automatic_peaks(
    svd: &Svd,
    s: &OmaSettings,
    ssi: &[OmaMode],
    rejected: &mut Vec<String>,
) -> Vec<Peak> {
    let lines = svd.freq_hz.len();
    let kind = s.ssi.kind.label();
    let f = |l: usize| svd.freq_hz[l];
    let mut candidates = fdd::pick_peaks(svd, s.peaks);
    candidates.sort_by(|a, b| svd.s[b.0][0].total_cmp(&svd.s[a.0][0]));
    let mut taken: Vec<Taken> = Vec::new();
    for (l, prominence) in candidates {
        let reference = svd.u1[l].clone();
        let (a, values) = fdd::bell(svd, &reference, l, (0, lines), s.efdd.mac_min);
        let b = a + values.len().max(1) - 1;
        let name = format!("fdd peak at {:.4} Hz ({prominence:.1} dB)", f(l));
        if values.len() < s.efdd.min_lines {
            rejected.push(format!(
                "{name}: its singular vector holds (MAC >= {}) over {} lines, fewer than {} (a \
                 mode's holds over its bell; a noise peak's turns from line to line)",
                s.efdd.mac_min,
                values.len(),
                s.efdd.min_lines
            ));
            continue;
        }
        // one bell holds the other's peak, and the two have one shape (a bell also runs
        // through the lines where its mode is the second singular value, under another mode)
        if let Some(t) = taken.iter().find(|t| {
            ((t.bell.0..=t.bell.1).contains(&l) || (a..=b).contains(&t.peak.line))
                && mac(&t.peak.reference, &reference) >= s.efdd.mac_min
        }) {
            rejected.push(format!(
                "{name}: on the bell of the {:.4} Hz peak, with its shape (MAC {:.3}): a \
                 ripple of that mode",
                f(t.peak.line),
                mac(&t.peak.reference, &reference)
            ));
            continue;
        }
        let (c, d) = half_power(svd, l, (a, b));
        let agree = agreeing(ssi, &reference, (f(c), f(d)));
        if agree.is_none() && prominence < STRONG_PEAK_DB {
            rejected.push(format!(
                "{name}: no {kind} mode within its half-power band ({:.4}-{:.4} Hz, a line \
                 wider either side) with a like shape (MAC >= {AGREE_MAC}); a peak of less \
                 than {STRONG_PEAK_DB} dB is taken only with {kind}'s support",
                f(c),
                f(d)
            ));
            continue;
        }
        let evidence = peak_evidence(prominence, values.len(), agree, kind);
        taken.push(Taken {
            peak: Peak {
                line: l,
                band: None,
                value: svd.s[l][0],
                reference,
                evidence,
            },
            bell: (a, b),
        });
    }
    rescue(svd, s, ssi, &mut taken);
    let mut peaks: Vec<Peak> = taken.into_iter().map(|t| t.peak).collect();
    peaks.sort_by_key(|p| p.line);
    peaks
}

/// A peak's evidence: its prominence, its bell's lines and the SSI mode (of the kind `ssi`
/// names) that agrees.
fn peak_evidence(
    prominence: f64,
    lines: usize,
    agree: Option<(&OmaMode, f64)>,
    ssi: &str,
) -> String {
    match agree {
        Some((m, c)) => format!(
            "first singular value, {prominence:.1} dB, bell of {lines} lines; {ssi}'s {:.4} Hz \
             mode agrees (MAC {c:.3})",
            m.f_hz
        ),
        None => format!(
            "first singular value, {prominence:.1} dB, bell of {lines} lines; no {ssi} mode \
             agrees"
        ),
    }
}

/// The lines of the peak at `l`'s half-power band (the contiguous lines whose first singular
/// value is at least half the peak's), a line wider either side, within its bell `(a, b)`:
/// where an SSI-cov mode must lie to agree with the peak. The bell alone was too wide a
/// net: on a real record of 16 lines of 3.1 Hz, whose every target moves alike (so every
/// shape agrees), the bell held the whole spectrum and a 43.70 Hz SSI mode "agreed" with the
/// 21.875 Hz peak.
pub fn half_power(svd: &Svd, l: usize, (a, b): (usize, usize)) -> (usize, usize) {
    let v = |i: usize| svd.s[i].first().copied().unwrap_or(0.0);
    let half = 0.5 * v(l);
    let mut lo = l;
    while lo > a && v(lo - 1) >= half {
        lo -= 1;
    }
    let mut hi = l;
    while hi < b && v(hi + 1) >= half {
        hi += 1;
    }
    (lo.saturating_sub(1).max(a), (hi + 1).min(b))
}

/// The SSI-cov mode within `(lo, hi)` Hz whose shape agrees best with `reference` (MAC at
/// least [`AGREE_MAC`]), and the MAC.
fn agreeing<'a>(
    ssi: &'a [OmaMode],
    reference: &[Complex64],
    (lo, hi): (f64, f64),
) -> Option<(&'a OmaMode, f64)> {
    ssi.iter()
        .filter(|m| m.f_hz >= lo && m.f_hz <= hi)
        .map(|m| (m, mac(&m.shape, reference)))
        .filter(|(_, c)| *c >= AGREE_MAC)
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

/// The SSI-cov modes no peak took, given their bells: near each one's frequency (two lines, or
/// twice its half-power bandwidth) the line and singular vector (first or second) of its
/// shape (MAC >= 0.9); its bell of at least `min_lines` lines, the peak at the bell's largest
/// value.
fn rescue(svd: &Svd, s: &OmaSettings, ssi: &[OmaMode], taken: &mut Vec<Taken>) {
    let lines = svd.freq_hz.len();
    let df = svd.freq_hz.get(1).copied().unwrap_or(1.0);
    for m in ssi {
        let covered = taken.iter().any(|t| {
            let (lo, hi) = (svd.freq_hz[t.bell.0], svd.freq_hz[t.bell.1]);
            m.f_hz >= lo && m.f_hz <= hi && mac(&t.peak.reference, &m.shape) >= AGREE_MAC
        });
        if covered {
            continue;
        }
        let reach = (2.0 * df).max(2.0 * 2.0 * m.damping.unwrap_or(0.0) * m.f_hz);
        let best = (0..lines)
            .filter(|&l| (svd.freq_hz[l] - m.f_hz).abs() <= reach)
            .flat_map(|l| {
                [(l, &svd.u1[l]), (l, &svd.u2[l])]
                    .into_iter()
                    .map(|(l, u)| (l, u, mac(u, &m.shape)))
            })
            .filter(|x| x.2 >= 0.9)
            .max_by(|a, b| a.2.total_cmp(&b.2));
        let Some((l, u, c)) = best else {
            continue;
        };
        let reference = u.clone();
        let (a, values) = fdd::bell(svd, &reference, l, (0, lines), s.efdd.mac_min);
        if values.len() < s.efdd.min_lines {
            continue;
        }
        let Some(top) = (0..values.len()).max_by(|&i, &j| values[i].total_cmp(&values[j])) else {
            continue;
        };
        let line = a + top;
        // a bell whose top is not at SSI-cov's mode (a free-decay record's bell reaching down
        // to the pull's quasi-static line) gives no frequency of it
        if (svd.freq_hz[line] - m.f_hz).abs() > reach {
            continue;
        }
        let b = a + values.len() - 1;
        let inside = taken.iter().any(|t| {
            (t.bell.0..=t.bell.1).contains(&line)
                && mac(&t.peak.reference, &reference) >= s.efdd.mac_min
        });
        if inside {
            continue;
        }
        // the mode's shape at its peak: the singular vector there that has it (MAC 0.99 with
        // the vector found beside SSI-cov's frequency); where the SVD mixes it with a close
        // mode of like power, the vector found
        let (m1, m2) = (
            mac(&svd.u1[line], &reference),
            mac(&svd.u2[line], &reference),
        );
        let (which, reference) = if m1.max(m2) < 0.99 {
            ("first and second", reference)
        } else if m2 > m1 {
            ("second", svd.u2[line].clone())
        } else {
            ("first", svd.u1[line].clone())
        };
        taken.push(Taken {
            peak: Peak {
                line,
                band: None,
                reference,
                value: values[top],
                evidence: format!(
                    "{which} singular value, bell of {} lines, found from {}'s {:.4} Hz mode \
                     (MAC {c:.3}): no peak of 6 dB stood for it",
                    values.len(),
                    s.ssi.kind.label(),
                    m.f_hz
                ),
            },
            bell: (a, b),
        });
    }
}

/// The lines between which peak `n`'s bell may run: the neighbouring peaks' (the spectrum's
/// ends for the first and the last; `lines` the spectrum's count).
pub fn fence(peaks: &[Peak], n: usize, lines: usize) -> (usize, usize) {
    (
        if n > 0 { peaks[n - 1].line } else { 0 },
        peaks.get(n + 1).map_or(lines, |q| q.line),
    )
}

/// The fraction by which another quantity's model must lower the RMS residual of the bells'
/// fits below the displacement's to be taken ([`choose_quantity`]): a camera measures
/// displacements, and on narrow bells the three models fit alike (their residuals then differ
/// by a few per cent either way, and any of them gives the same frequency).
pub const QUANTITY_MARGIN: f64 = 0.05;

/// The quantity EFDD's bells were fitted as, and how it was chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuantityChoice {
    /// The quantity taken.
    pub quantity: Quantity,
    /// Each quantity's RMS residual (natural log) over the bells fitted by all three, in the
    /// order of [`Quantity::ALL`]; `None` when the quantity was given or no bell was resolved.
    pub rms_log: Option<[f64; 3]>,
    /// Whether the quantity was given (not chosen from the bells).
    pub given: bool,
}

/// The record's quantity as EFDD's bells tell it, when it was not given: each peak's bell
/// fitted as a displacement's, a velocity's and an acceleration's spectrum
/// ([`super::bell::Quantity`]); the quantity whose fits leave the least squared residual over
/// the bells that all three fit with a half-power band of [`super::bell::RESOLVED_LINES`] or
/// more, the displacement unless another's RMS residual is lower by [`QUANTITY_MARGIN`]. A
/// velocity's bell fitted as a displacement's is tilted: its frequency came out 0.2-0.6 % high,
/// its damping up to 37 % low.
pub fn choose_quantity(svd: &Svd, peaks: &[Peak], s: &OmaSettings) -> QuantityChoice {
    if let Some(quantity) = s.efdd.quantity {
        return QuantityChoice {
            quantity,
            rms_log: None,
            given: true,
        };
    }
    let lines = svd.freq_hz.len();
    let lag = fdd::lag_window(s.csd.window, s.csd.nperseg);
    let df = s.fs_hz / s.csd.nfft as f64;
    let (mut cost, mut count) = ([0.0f64; 3], 0usize);
    for (n, p) in peaks.iter().enumerate() {
        let fence = fence(peaks, n, lines);
        let fits: Vec<fdd::Efdd> = Quantity::ALL
            .iter()
            .filter_map(|q| {
                // the tilt held: free, it would carry a velocity's bell as a displacement's
                let rule = fdd::EfddRule {
                    quantity: Some(*q),
                    tilt: false,
                    ..s.efdd
                };
                let at = (&p.reference[..], p.line);
                fdd::efdd(svd, at, fence, (s.csd.nfft, s.fs_hz), (&lag, None), rule).ok()
            })
            .collect();
        // a bell of the spectral window (a half-power band of a line or two) is alike in
        // every quantity's model: its residuals only say how badly the window fits (on a
        // short rendered record of 8 segments they chose accelerations for displacements)
        let resolved = |e: &fdd::Efdd| super::bell::resolved(e.f_hz, e.damping, df);
        if fits.len() == 3 && fits.iter().all(resolved) {
            for (c, e) in cost.iter_mut().zip(&fits) {
                *c += e.rms_log * e.rms_log * e.lines as f64;
            }
            count += fits[0].lines;
        }
    }
    if count == 0 {
        return QuantityChoice {
            quantity: Quantity::Displacement,
            rms_log: None,
            given: false,
        };
    }
    let best = (1..3)
        .min_by(|&i, &j| cost[i].total_cmp(&cost[j]))
        .filter(|&i| cost[i] < (1.0 - QUANTITY_MARGIN).powi(2) * cost[0])
        .unwrap_or(0);
    QuantityChoice {
        quantity: Quantity::ALL[best],
        rms_log: Some(cost.map(|c| (c / count as f64).sqrt())),
        given: false,
    }
}

/// The FDD mode at each peak and its EFDD refinement (frequency and damping from the bell
/// fitted; a bell too narrow or a fit that fails is noted).
pub fn fdd_modes(
    svd: &Svd,
    peaks: &[Peak],
    s: &OmaSettings,
    notes: &mut Vec<String>,
) -> Vec<OmaMode> {
    let mut modes = Vec::new();
    let lines = svd.freq_hz.len();
    let lag = fdd::lag_window(s.csd.window, s.csd.nperseg);
    for (n, p) in peaks.iter().enumerate() {
        let mode = p.mode_number(n);
        let band_hz = p.band.map(|b| s.bands[b]);
        let shape = normalise_shape(&p.reference);
        modes.push(OmaMode {
            method: Method::Fdd,
            mode,
            band_hz,
            f_hz: svd.freq_hz[p.line],
            amplitude: Some(p.value),
            damping: None,
            shape: shape.clone(),
            evidence: p.evidence.clone(),
            uncertainty: Default::default(),
        });
        // the bell stops at the neighbouring peaks
        let fence = fence(peaks, n, lines);
        match fdd::efdd(
            svd,
            (&p.reference, p.line),
            fence,
            (s.csd.nfft, s.fs_hz),
            (&lag, None),
            s.efdd,
        ) {
            Ok(e) => {
                let df = s.fs_hz / s.csd.nfft as f64;
                modes.push(efdd_mode(
                    &e,
                    (mode, band_hz, p.value),
                    shape,
                    (svd, df),
                    notes,
                ));
            }
            Err(why) => notes.push(format!(
                "EFDD of mode {mode} ({:.4} Hz) not reported: {why}",
                svd.freq_hz[p.line]
            )),
        }
    }
    modes
}

/// The narrowest half-power band, in lines, whose width an EFDD fit determines: a bell
/// narrower than half a line is the estimate's spectral window, whatever the damping under
/// it (a struck fork's 0.001 came out 0.00003 from a slowly decaying record, 0.0028 from
/// one with two strikes).
const MIN_BAND_LINES: f64 = 0.5;

/// EFDD's damping when the fitted half-power band `2 zeta f` is at least
/// [`MIN_BAND_LINES`] of the line spacing `df` (and the fit's damping is not at its least).
fn resolved_damping(e: &fdd::Efdd, df: f64) -> Option<f64> {
    let floor = e.damping <= 1.0001 * super::bell::ZETA_MIN;
    (!floor && 2.0 * e.damping * e.f_hz >= MIN_BAND_LINES * df).then_some(e.damping)
}

/// The EFDD mode of the fit `e` (mode number, band and FDD's amplitude as given; `df` the line
/// spacing of `svd`), its damping withheld with a note when the bell cannot give it
/// ([`resolved_damping`]).
fn efdd_mode(
    e: &fdd::Efdd,
    (mode, band_hz, amplitude): (usize, Option<(f64, f64)>, f64),
    shape: Vec<Complex64>,
    (svd, df): (&Svd, f64),
    notes: &mut Vec<String>,
) -> OmaMode {
    let damping = resolved_damping(e, df);
    let why = if damping.is_none() {
        notes.push(format!(
            "efdd mode {mode} ({:.4} Hz): no damping (its bell is narrower than the lines: a \
             longer segment, $nperseg, resolves it)",
            e.f_hz
        ));
        format!(
            "; no damping: the fitted half-power band ({:.4} Hz) is narrower than half a line \
             ({df:.4} Hz), so the bell is the spectral window's",
            2.0 * e.damping * e.f_hz
        )
    } else {
        String::new()
    };
    OmaMode {
        method: Method::Efdd,
        mode,
        band_hz,
        f_hz: e.f_hz,
        amplitude: Some(amplitude),
        damping,
        shape,
        evidence: format!(
            "bell of {} lines ({:.4}-{:.4} Hz) fitted, residual {:.2} (ln), floor {:.1} % of the \
             peak, tilt f^{:+.2}{why}",
            e.lines,
            svd.freq_hz[e.range.0],
            svd.freq_hz[e.range.1],
            e.rms_log,
            100.0 * e.floor,
            e.tilt,
        ),
        uncertainty: Default::default(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 64 lines of 1 Hz, two channels: a peak of 30 dB at line 20 with the shape (1, 0.6)
    /// over a floor of the other shape.
    fn svd() -> Svd {
        let norm = (1.0f64 + 0.36).sqrt();
        let a = vec![
            Complex64::new(1.0 / norm, 0.0),
            Complex64::new(0.6 / norm, 0.0),
        ];
        let b = vec![
            Complex64::new(-0.6 / norm, 0.0),
            Complex64::new(1.0 / norm, 0.0),
        ];
        let lines = 64;
        let s1 = |l: usize| 1.0 + 1000.0 / (1.0 + ((l as f64 - 20.0) / 1.5).powi(2));
        Svd {
            freq_hz: (0..lines).map(|l| l as f64).collect(),
            s: (0..lines).map(|l| vec![s1(l), 0.5]).collect(),
            u1: (0..lines)
                .map(|l| {
                    if (l as f64 - 20.0).abs() <= 6.0 {
                        a.clone()
                    } else {
                        b.clone()
                    }
                })
                .collect(),
            u2: (0..lines).map(|_| b.clone()).collect(),
        }
    }

    fn cluster_at(f_hz: f64, poles: usize, shape: &[f64]) -> SsiMode {
        SsiMode {
            f_hz,
            damping: 0.002,
            shape: shape.iter().map(|&x| Complex64::new(x, 0.0)).collect(),
            poles,
            f_spread: 0.0,
            damping_spread: 0.0,
            mpc: 1.0,
            mpd_deg: 0.0,
            orders: (10, 10 + 2 * poles),
            members: Vec::new(),
        }
    }

    fn dropped(clusters: &[SsiMode]) -> Vec<cluster::Rejected> {
        clusters
            .iter()
            .map(|c| cluster::Rejected {
                cluster: c.clone(),
                reason: "few poles".into(),
            })
            .collect()
    }

    #[test]
    fn a_small_cluster_is_kept_only_as_the_one_explanation_of_a_strong_peak() {
        let (svd, s) = (svd(), OmaSettings::new(128.0, 8192, Some(128)));
        let shape = [1.0, 0.6];
        // one cluster of 3 poles within half a line of the 30 dB peak: kept, and said why
        let one = dropped(&[cluster_at(20.3, 3, &shape), cluster_at(40.0, 3, &shape)]);
        let got = lone_explanations(&svd, &s, &[], &one);
        assert_eq!(got.len(), 1, "{got:?}");
        assert_eq!(got[0].0, 0);
        assert!(
            got[0].1.contains("kept with 3 stable poles") && got[0].1.contains("at 20.0000 Hz"),
            "{}",
            got[0].1
        );
        // a single pole, another shape, or one line and a half away: nothing
        for c in [
            cluster_at(20.3, 1, &shape),
            cluster_at(20.3, 3, &[-0.6, 1.0]),
            cluster_at(21.5, 3, &shape),
        ] {
            assert!(
                lone_explanations(&svd, &s, &[], &dropped(std::slice::from_ref(&c))).is_empty(),
                "{c:?}"
            );
        }
        // two small clusters beside the peak explain nothing (the true one is not known)
        let two = dropped(&[cluster_at(19.7, 3, &shape), cluster_at(20.4, 2, &shape)]);
        assert!(lone_explanations(&svd, &s, &[], &two).is_empty());
        // a full mode in the peak's bell already explains it
        let kept = [cluster_at(20.1, 12, &shape)];
        assert!(lone_explanations(&svd, &s, &kept, &one).is_empty());
        // a peak of less than 10 dB is no strong peak
        let mut weak = svd.clone();
        for v in &mut weak.s {
            v[0] = 1.0 + (v[0] - 1.0) * 0.005;
        }
        assert!(lone_explanations(&weak, &s, &[], &one).is_empty());
    }
}
