//! SSI-cov's stable poles grouped into modes (docs/method.md §3.12): hierarchical clustering
//! with average linkage on a distance that combines frequency and shape (Magalhaes, Cunha &
//! Caetano 2009; Reynders, Houbrechts & De Roeck 2012), one pole per model order in a cluster,
//! then rules that reject a cluster which does not behave like a mode, each with its reason.
//!
//! The distance between two poles is `|f_a - f_b| / max(f_a, f_b) + (1 - MAC_ab)`: two poles of
//! one mode differ by a fraction of a per cent in frequency and a MAC near 1, two modes by their
//! frequency or their shape. Average linkage (the mean distance between the members of two
//! clusters) does not chain: a run of poles drifting in frequency does not merge two modes, and
//! one odd pole does not split a mode's column.

use super::ssi::Pole;
use crate::modal::{mac, normalise_shape};
use num_complex::Complex64;

/// The rules of the clustering.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClusterRule {
    /// Clusters closer than this (average linkage) are merged.
    pub distance_max: f64,
    /// Fewest poles (model orders) a mode needs.
    pub min_poles: usize,
    /// Least median modal phase collinearity (MPC) of the cluster's poles.
    pub mpc_min: f64,
    /// Largest median mean phase deviation (MPD) of the cluster's poles, degrees.
    pub mpd_max_deg: f64,
}

impl Default for ClusterRule {
    /// Distance 0.03 (1 % in frequency and a MAC of 0.98 make 0.03), at least 5 poles,
    /// median MPC at least 0.5, median MPD at most 30 degrees. (No least fraction of the
    /// fullest cluster's poles, as pyOMA-2's `min_size_pctg` has: a third rejected a true mode
    /// with 6 stable poles beside a fuller one of 19 on a 10-minute record.)
    fn default() -> Self {
        ClusterRule {
            distance_max: 0.03,
            min_poles: 5,
            mpc_min: 0.5,
            mpd_max_deg: 30.0,
        }
    }
}

/// A mode: a cluster of stable poles.
#[derive(Debug, Clone, PartialEq)]
pub struct SsiMode {
    /// Median frequency of the cluster's poles, Hz.
    pub f_hz: f64,
    /// Median damping ratio.
    pub damping: f64,
    /// The mean of the poles' shapes (each scaled to its largest component first).
    pub shape: Vec<Complex64>,
    /// Poles in the cluster (one per model order).
    pub poles: usize,
    /// Standard deviation of the poles' frequencies, relative to the median.
    pub f_spread: f64,
    /// Standard deviation of the poles' damping ratios, relative to the median.
    pub damping_spread: f64,
    /// Median modal phase collinearity of the poles (1: a real shape).
    pub mpc: f64,
    /// Median mean phase deviation of the poles, degrees (0: a real shape).
    pub mpd_deg: f64,
    /// The lowest and highest model order in the cluster.
    pub orders: (usize, usize),
    /// Its poles' frequencies and orders.
    pub members: Vec<(f64, usize)>,
}

/// A cluster that is not reported as a mode, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Rejected {
    /// The cluster (its statistics as a mode would have them).
    pub cluster: SsiMode,
    /// Why it is not a mode.
    pub reason: String,
}

/// The clusters reported, each with its mode number and band: without `bands` every kept
/// cluster (each rejected one to `rejected`, named `"{name} cluster at ..."` with its reason),
/// with bands the fullest kept cluster in each (a band without one noted as `"{label}: no
/// stable mode in band ..."`).
pub fn chosen<'a>(
    (kept, dropped): (&'a [SsiMode], &[Rejected]),
    bands: &[(f64, f64)],
    (name, label): (&str, &str),
    notes: &mut Vec<String>,
    rejected: &mut Vec<String>,
) -> Vec<(usize, Option<usize>, &'a SsiMode)> {
    if bands.is_empty() {
        for r in dropped {
            rejected.push(format!(
                "{name} cluster at {:.4} Hz (damping {:.4}, {} poles, orders {}-{}): {}",
                r.cluster.f_hz,
                r.cluster.damping,
                r.cluster.poles,
                r.cluster.orders.0,
                r.cluster.orders.1,
                r.reason
            ));
        }
        return kept
            .iter()
            .enumerate()
            .map(|(n, c)| (n + 1, None, c))
            .collect();
    }
    let mut out = Vec::new();
    for (b, band) in bands.iter().enumerate() {
        match kept
            .iter()
            .filter(|c| c.f_hz >= band.0 && c.f_hz <= band.1)
            .max_by_key(|c| c.poles)
        {
            Some(c) => out.push((b + 1, Some(b), c)),
            None => notes.push(format!(
                "{label}: no stable mode in band {}-{} Hz",
                band.0, band.1
            )),
        }
    }
    out
}

/// Modal phase collinearity of a shape: `((Sxx - Syy)^2 + 4 Sxy^2) / (Sxx + Syy)^2` of its
/// real and imaginary parts (Pappa, Elliott & Schenk 1993); 1 for a shape whose components
/// share one phase (or its opposite), 0 for a circle.
pub fn mpc(shape: &[Complex64]) -> f64 {
    let (sxx, syy, sxy) = moments(shape);
    let t = sxx + syy;
    if t <= 0.0 {
        return 0.0;
    }
    ((sxx - syy).powi(2) + 4.0 * sxy * sxy) / (t * t)
}

/// Mean phase deviation of a shape, degrees: the components' angles from the shape's best
/// straight line through the origin in the complex plane (its principal axis), weighted by
/// their magnitudes; 0 for a real shape, 45 on average for random phases.
pub fn mpd_deg(shape: &[Complex64]) -> f64 {
    let (sxx, syy, sxy) = moments(shape);
    let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let turn = Complex64::from_polar(1.0, -theta);
    let (mut sum, mut weight) = (0.0, 0.0);
    for v in shape {
        let r = v * turn;
        let m = r.norm();
        if m > 0.0 {
            sum += m * r.im.abs().atan2(r.re.abs());
            weight += m;
        }
    }
    if weight > 0.0 {
        (sum / weight).to_degrees()
    } else {
        90.0
    }
}

fn moments(shape: &[Complex64]) -> (f64, f64, f64) {
    shape.iter().fold((0.0, 0.0, 0.0), |(a, b, c), v| {
        (a + v.re * v.re, b + v.im * v.im, c + v.re * v.im)
    })
}

/// The distance of two poles (module documentation).
fn distance(a: &Pole, b: &Pole) -> f64 {
    (a.f_hz - b.f_hz).abs() / a.f_hz.max(b.f_hz) + (1.0 - mac(&a.shape, &b.shape))
}

/// Groups of indices into `poles` by average-linkage clustering, merged while the closest two
/// groups are within `distance_max`.
fn average_linkage(poles: &[&Pole], distance_max: f64) -> Vec<Vec<usize>> {
    let n = poles.len();
    let mut d = vec![vec![0.0f64; n]; n];
    for i in 0..n {
        for j in i + 1..n {
            let v = distance(poles[i], poles[j]);
            d[i][j] = v;
            d[j][i] = v;
        }
    }
    let mut groups: Vec<Option<Vec<usize>>> = (0..n).map(|i| Some(vec![i])).collect();
    loop {
        let mut best: Option<(usize, usize, f64)> = None;
        for i in 0..n {
            if groups[i].is_none() {
                continue;
            }
            for j in i + 1..n {
                if groups[j].is_some() && best.is_none_or(|b| d[i][j] < b.2) {
                    best = Some((i, j, d[i][j]));
                }
            }
        }
        let Some((i, j, _)) = best.filter(|b| b.2 <= distance_max) else {
            break;
        };
        let (ni, nj) = (
            groups[i].as_ref().map_or(0, Vec::len) as f64,
            groups[j].as_ref().map_or(0, Vec::len) as f64,
        );
        // Lance-Williams update of average linkage
        for k in 0..n {
            if k != i && k != j && groups[k].is_some() {
                let v = (ni * d[k][i] + nj * d[k][j]) / (ni + nj);
                d[k][i] = v;
                d[i][k] = v;
            }
        }
        let moved = groups[j].take().unwrap_or_default();
        if let Some(g) = groups[i].as_mut() {
            g.extend(moved);
        }
    }
    groups.into_iter().flatten().collect()
}

/// One pole per model order: of several, the one nearest the cluster's medoid (the pole with
/// the least total distance to the others).
fn one_per_order<'a>(group: &[&'a Pole]) -> Vec<&'a Pole> {
    let total = |p: &Pole| group.iter().map(|q| distance(p, q)).sum::<f64>();
    let medoid = group
        .iter()
        .min_by(|a, b| total(a).total_cmp(&total(b)))
        .copied();
    let Some(medoid) = medoid else {
        return Vec::new();
    };
    let mut kept: Vec<&Pole> = Vec::new();
    for p in group {
        match kept.iter_mut().find(|k| k.order == p.order) {
            Some(k) if distance(p, medoid) < distance(k, medoid) => *k = p,
            Some(_) => {}
            None => kept.push(p),
        }
    }
    kept
}

/// The statistics of a group of poles as a mode.
fn summarise(g: &[&Pole]) -> SsiMode {
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let spread = |v: &[f64], m: f64| {
        let n = v.len() as f64;
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt() / m
    };
    let fs: Vec<f64> = g.iter().map(|p| p.f_hz).collect();
    let zs: Vec<f64> = g.iter().map(|p| p.damping).collect();
    let (f_hz, damping) = (median(fs.clone()), median(zs.clone()));
    let k = g.first().map_or(0, |p| p.shape.len());
    let mut shape = vec![Complex64::new(0.0, 0.0); k];
    // the poles' shapes aligned to the first's phase before they are averaged
    let reference = g.first().map(|p| normalise_shape(&p.shape));
    for p in g {
        let v = normalise_shape(&p.shape);
        let align = reference.as_ref().map_or(Complex64::new(1.0, 0.0), |r| {
            let dot: Complex64 = v.iter().zip(r).map(|(a, b)| a.conj() * b).sum();
            if dot.norm() > 0.0 {
                dot / dot.norm()
            } else {
                Complex64::new(1.0, 0.0)
            }
        });
        for (o, x) in shape.iter_mut().zip(v) {
            *o += x * align;
        }
    }
    SsiMode {
        f_hz,
        damping,
        shape,
        poles: g.len(),
        f_spread: spread(&fs, f_hz),
        damping_spread: spread(&zs, damping),
        mpc: median(g.iter().map(|p| mpc(&p.shape)).collect()),
        mpd_deg: median(g.iter().map(|p| mpd_deg(&p.shape)).collect()),
        orders: (
            g.iter().map(|p| p.order).min().unwrap_or(0),
            g.iter().map(|p| p.order).max().unwrap_or(0),
        ),
        members: g.iter().map(|p| (p.f_hz, p.order)).collect(),
    }
}

/// The modes among the stable poles of `poles` (ascending frequency) and the clusters
/// rejected, each with its reason: fewer than `rule.min_poles` poles; a median MPC below `rule.mpc_min` or MPD
/// above `rule.mpd_max_deg` (a shape whose components do not share a phase: noise, not a
/// mode of a structure with light damping); the same shape (MAC >= 0.9) as a fuller cluster
/// within five of its half-power bandwidths (a mode's column split in two).
pub fn cluster(poles: &[Pole], rule: ClusterRule) -> (Vec<SsiMode>, Vec<Rejected>) {
    let stable: Vec<&Pole> = poles.iter().filter(|p| p.stable).collect();
    let mut groups: Vec<Vec<&Pole>> = average_linkage(&stable, rule.distance_max)
        .into_iter()
        .map(|g| one_per_order(&g.iter().map(|&i| stable[i]).collect::<Vec<_>>()))
        .collect();
    groups.sort_by_key(|g| std::cmp::Reverse(g.len()));
    let (mut modes, mut rejected): (Vec<SsiMode>, Vec<Rejected>) = (Vec::new(), Vec::new());
    for g in &groups {
        let c = summarise(g);
        let twin = modes.iter().find(|m| {
            (m.f_hz - c.f_hz).abs() <= 5.0 * 2.0 * m.damping.max(c.damping) * m.f_hz
                && mac(&m.shape, &c.shape) >= 0.9
        });
        let reason = if c.poles < rule.min_poles {
            Some(format!(
                "{} stable poles, fewer than {}",
                c.poles, rule.min_poles
            ))
        } else if c.mpc < rule.mpc_min || c.mpd_deg > rule.mpd_max_deg {
            Some(format!(
                "its shape's components do not share a phase (MPC {:.2}, MPD {:.0} deg; a mode \
                 needs MPC >= {} and MPD <= {} deg)",
                c.mpc, c.mpd_deg, rule.mpc_min, rule.mpd_max_deg
            ))
        } else {
            twin.map(|m| {
                format!(
                    "the shape of the {:.4} Hz mode (MAC {:.3}) and a fuller column ({} poles): a \
                     split of that mode's column",
                    m.f_hz,
                    mac(&m.shape, &c.shape),
                    m.poles
                )
            })
        };
        match reason {
            Some(reason) => rejected.push(Rejected { cluster: c, reason }),
            None => modes.push(c),
        }
    }
    modes.sort_by(|a, b| a.f_hz.total_cmp(&b.f_hz));
    rejected.sort_by(|a, b| a.cluster.f_hz.total_cmp(&b.cluster.f_hz));
    (modes, rejected)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(re: f64, im: f64) -> Complex64 {
        Complex64::new(re, im)
    }

    #[test]
    fn collinearity_and_phase_deviation_of_known_shapes() {
        // a real shape turned by any phase: collinear, no deviation
        let turn = Complex64::from_polar(1.0, 0.7);
        let real: Vec<Complex64> = [1.0, -0.5, 0.3, 0.8].iter().map(|v| turn * v).collect();
        assert!((mpc(&real) - 1.0).abs() < 1e-12);
        assert!(mpd_deg(&real) < 1e-9);
        // two components in quadrature of equal size: a circle
        let circle = [c(1.0, 0.0), c(0.0, 1.0)];
        assert!(mpc(&circle) < 1e-12);
        // (1, 0) and (1, 1): MPC by hand: Sxx 2, Syy 1, Sxy 1 -> (1 + 4) / 9
        let two = [c(1.0, 0.0), c(1.0, 1.0)];
        assert!((mpc(&two) - 5.0 / 9.0).abs() < 1e-12);
        // the principal axis of (1, 0) and (1, 1) is at 0.5 atan2(2, 1) = 31.7 deg: the
        // deviations are 31.7 and 13.3 deg, weighted by 1 and sqrt 2
        let axis = 0.5 * 2f64.atan2(1.0);
        let want =
            (axis + 2f64.sqrt() * (std::f64::consts::FRAC_PI_4 - axis)) / (1.0 + 2f64.sqrt());
        assert!((mpd_deg(&two) - want.to_degrees()).abs() < 1e-9);
    }

    fn pole(order: usize, f_hz: f64, shape: &[f64]) -> Pole {
        Pole {
            order,
            f_hz,
            damping: 0.01,
            shape: shape.iter().map(|&v| c(v, 0.0)).collect(),
            stable: true,
        }
    }

    #[test]
    fn a_split_column_is_one_mode_and_close_modes_of_other_shapes_are_two() {
        let a = [1.0, 0.5, 0.0, -0.5, -1.0];
        let b = [0.5, 1.0, 1.0, 1.0, 0.5];
        let mut poles = Vec::new();
        for o in (2..=40).step_by(2) {
            // two modes 2 % apart with orthogonal shapes
            poles.push(pole(o, 2.0 * (1.0 + 1e-4 * o as f64), &a));
            poles.push(pole(o, 2.04, &b));
        }
        // a column of 6 poles 1.5 % above the 2.04 Hz mode, of its shape
        for o in (30..=40).step_by(2) {
            poles.push(pole(o, 2.04 * 1.015, &b));
        }
        // and 3 poles of noise
        for o in [10, 12, 14] {
            poles.push(pole(o, 7.0, &[1.0, 0.0, 0.0, 0.0, 0.0]));
        }
        let (modes, rejected) = cluster(&poles, ClusterRule::default());
        assert_eq!(modes.len(), 2, "{modes:?}");
        assert!((modes[0].f_hz - 2.0).abs() < 0.01 && modes[0].poles == 20);
        assert!((modes[1].f_hz - 2.04).abs() < 1e-9 && modes[1].poles == 20);
        // the split column merged into its mode (average linkage at 1.5 %) or, where it
        // stands apart, named as a split; the noise named for its size
        assert!(
            rejected
                .iter()
                .all(|r| r.reason.contains("split") || r.reason.contains("stable poles, fewer")),
            "{rejected:?}"
        );
        assert!(rejected.iter().any(|r| (r.cluster.f_hz - 7.0).abs() < 1e-9));
    }
}
