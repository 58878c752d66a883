//! Several setups of one structure (docs/method.md §3.12, "Several setups"): records taken one
//! after another, each of some points, all of a few **reference** points that stay put, merged
//! into one set of modes with one global shape by PoSER (post separate estimation re-scaling,
//! as pyOMA-2's `MultiSetup_PoSER`): each setup is identified alone; a mode of the first setup
//! is matched in every other by method, frequency and (with two references or more) the shape
//! at the references; each setup's shape is scaled onto the first's at the references (the
//! complex least-squares factor); the global shape is the references' scaled mean, then each
//! setup's other points scaled. The global numbering: the references first (in the order
//! given), then each setup's other points in its order.

use super::uncertainty::{Interval, Uncertainty};
use super::{Method, OmaMode, OmaResult};
use crate::modal::mac;
use num_complex::Complex64;

/// One setup: what its analysis found, and which of its channels are the references (the
/// same points in every setup, in the same order).
#[derive(Debug, Clone, Copy)]
pub struct Setup<'a> {
    /// Its analysis.
    pub result: &'a OmaResult,
    /// Its channels (0-based) that are the references, in the common order.
    pub references: &'a [usize],
    /// Its number of channels.
    pub channels: usize,
}

/// Where a global point comes from: `(setup, channel)`, both 0-based (the references from the
/// first setup).
pub fn layout(setups: &[Setup<'_>]) -> Vec<(usize, usize)> {
    let mut out: Vec<(usize, usize)> = setups
        .first()
        .map(|s| s.references.iter().map(|&c| (0, c)).collect())
        .unwrap_or_default();
    for (i, s) in setups.iter().enumerate() {
        out.extend(
            (0..s.channels)
                .filter(|c| !s.references.contains(c))
                .map(|c| (i, c)),
        );
    }
    out
}

/// A merged mode's part from one setup.
#[derive(Debug, Clone, PartialEq)]
pub struct Part {
    /// The method.
    pub method: Method,
    /// The merged mode's number.
    pub mode: usize,
    /// The setup, 0-based.
    pub setup: usize,
    /// This setup's frequency, Hz.
    pub f_hz: f64,
    /// This setup's damping ratio, if its method gives one.
    pub damping: Option<f64>,
    /// The factor its shape was scaled by onto the first setup's at the references.
    pub scale: Complex64,
    /// MAC of its shape at the references with the first setup's (two references or more).
    pub reference_mac: Option<f64>,
}

/// The merge: the global modes, each setup's part of each, and notes (modes of the first
/// setup not found in every other).
#[derive(Debug, Clone, Default)]
pub struct Merged {
    /// The modes with global shapes (on [`layout`]'s points).
    pub modes: Vec<OmaMode>,
    /// Per mode and setup.
    pub parts: Vec<Part>,
    /// Why a mode was not merged.
    pub notes: Vec<String>,
}

/// Least MAC at the references of a setup's mode with the first setup's (two references or
/// more): below it the two are not taken for one mode.
pub const REFERENCE_MAC: f64 = 0.8;

/// PoSER (module documentation) over `setups` (at least one; references at least one per
/// setup, the same count in each).
pub fn poser(setups: &[Setup<'_>]) -> Merged {
    let mut merged = Merged::default();
    let Some(first) = setups.first() else {
        return merged;
    };
    let at_refs = |m: &OmaMode, s: &Setup<'_>| -> Vec<Complex64> {
        s.references.iter().map(|&c| m.shape[c]).collect()
    };
    let points = layout(setups);
    let mut numbers: Vec<(Method, usize)> = Vec::new();
    for m0 in &first.result.modes {
        let r0 = at_refs(m0, first);
        let mut found = vec![(m0, Complex64::new(1.0, 0.0), None)];
        for (i, s) in setups.iter().enumerate().skip(1) {
            let z = m0.damping.unwrap_or(0.01);
            let reach = (3.0 * 2.0 * z * m0.f_hz).max(0.01 * m0.f_hz);
            let best = s
                .result
                .modes
                .iter()
                .filter(|m| m.method == m0.method && (m.f_hz - m0.f_hz).abs() <= reach)
                .map(|m| (m, (r0.len() >= 2).then(|| mac(&at_refs(m, s), &r0))))
                .filter(|(_, c)| c.is_none_or(|c| c >= REFERENCE_MAC))
                .min_by(|a, b| {
                    (a.0.f_hz - m0.f_hz)
                        .abs()
                        .total_cmp(&(b.0.f_hz - m0.f_hz).abs())
                });
            match best {
                Some((m, c)) => found.push((m, scale_onto(&at_refs(m, s), &r0), c)),
                None => {
                    merged.notes.push(format!(
                        "{} mode {} ({:.4} Hz) of setup 1 has no match in setup {} (same method, \
                         within {:.4} Hz{}): not merged",
                        m0.method.name(),
                        m0.mode,
                        m0.f_hz,
                        i + 1,
                        reach,
                        if r0.len() >= 2 {
                            format!(", MAC >= {REFERENCE_MAC} at the references")
                        } else {
                            String::new()
                        }
                    ));
                    break;
                }
            }
        }
        if found.len() < setups.len() {
            continue;
        }
        let n = numbers.iter().filter(|(m, _)| *m == m0.method).count() + 1;
        numbers.push((m0.method, n));
        let shape = global_shape(setups, &found, &points);
        merged
            .parts
            .extend(found.iter().enumerate().map(|(i, (m, a, c))| Part {
                method: m0.method,
                mode: n,
                setup: i,
                f_hz: m.f_hz,
                damping: m.damping,
                scale: *a,
                reference_mac: *c,
            }));
        merged.modes.push(merged_mode(m0, n, &found, shape));
    }
    merged
}

/// The complex factor `a` minimising `|a x - y|^2` (x scaled onto y).
fn scale_onto(x: &[Complex64], y: &[Complex64]) -> Complex64 {
    let xy: Complex64 = x.iter().zip(y).map(|(a, b)| a.conj() * b).sum();
    let xx: f64 = x.iter().map(|a| a.norm_sqr()).sum();
    if xx > 0.0 {
        xy / xx
    } else {
        Complex64::new(1.0, 0.0)
    }
}

/// The global shape on `points` from each setup's mode scaled by its factor: the references'
/// mean over the setups, each other point from its setup; largest component 1.
fn global_shape(
    setups: &[Setup<'_>],
    found: &[(&OmaMode, Complex64, Option<f64>)],
    points: &[(usize, usize)],
) -> Vec<Complex64> {
    let refs = setups[0].references.len();
    let mut shape: Vec<Complex64> = points
        .iter()
        .enumerate()
        .map(|(g, &(s, c))| {
            if g < refs {
                let sum: Complex64 = found
                    .iter()
                    .zip(setups)
                    .map(|((m, a, _), su)| m.shape[su.references[g]] * a)
                    .sum();
                sum / found.len() as f64
            } else {
                found[s].0.shape[c] * found[s].1
            }
        })
        .collect();
    let top = shape
        .iter()
        .copied()
        .max_by(|a, b| a.norm().total_cmp(&b.norm()))
        .unwrap_or_default();
    if top.norm() > 0.0 {
        shape.iter_mut().for_each(|v| *v /= top);
    }
    shape
}

/// The merged mode: the setups' mean frequency and damping, their intervals from the setups'
/// own (independent records: the mean's standard uncertainty the root sum of squares over
/// the count) or from the setups' spread when that is larger.
fn merged_mode(
    m0: &OmaMode,
    n: usize,
    found: &[(&OmaMode, Complex64, Option<f64>)],
    shape: Vec<Complex64>,
) -> OmaMode {
    let fs: Vec<f64> = found.iter().map(|(m, _, _)| m.f_hz).collect();
    let zs: Vec<f64> = found.iter().filter_map(|(m, _, _)| m.damping).collect();
    let f_hz = fs.iter().sum::<f64>() / fs.len() as f64;
    let damping = (zs.len() == found.len()).then(|| zs.iter().sum::<f64>() / zs.len() as f64);
    let f_u: Vec<Option<&Interval>> = found
        .iter()
        .map(|(m, _, _)| m.uncertainty.f_hz.as_ref())
        .collect();
    let z_u: Vec<Option<&Interval>> = found
        .iter()
        .map(|(m, _, _)| m.uncertainty.damping.as_ref())
        .collect();
    let evidence = format!(
        "PoSER over {} setups: {}; setup 1's: {}",
        found.len(),
        found
            .iter()
            .enumerate()
            .map(|(i, (m, a, _))| format!("setup {} {:.4} Hz x {:.3}", i + 1, m.f_hz, a.norm()))
            .collect::<Vec<_>>()
            .join(", "),
        m0.evidence
    );
    OmaMode {
        method: m0.method,
        mode: n,
        band_hz: m0.band_hz,
        f_hz,
        amplitude: None,
        damping,
        shape,
        evidence,
        uncertainty: Uncertainty {
            f_hz: pooled(f_hz, &fs, &f_u),
            damping: damping.and_then(|z| pooled(z, &zs, &z_u)),
            amplitude: None,
            shape_abs: None,
        },
    }
}

/// The 95 % interval of the mean `mean` of the setups' `values`, each with its own interval
/// (all needed): the standard uncertainty the larger of `sqrt(sum u_i^2) / S` and the
/// standard error of the values' mean (`S` >= 2), the interval `mean +- 1.96 u`.
fn pooled(mean: f64, values: &[f64], intervals: &[Option<&Interval>]) -> Option<Interval> {
    let s = values.len() as f64;
    let own: Option<f64> = intervals
        .iter()
        .map(|i| i.map(|i| i.u * i.u))
        .sum::<Option<f64>>()
        .map(|v| v.sqrt() / s);
    let own = own?;
    let spread = match values.len() {
        0 | 1 => 0.0,
        _ => {
            let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (s - 1.0);
            (var / s).sqrt()
        }
    };
    let u = own.max(spread);
    Some(Interval {
        u,
        lo: mean - 1.96 * u,
        hi: mean + 1.96 * u,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::oma::{analyze, OmaSettings};

    /// A structure of six points with two modes, recorded in two setups that share points 1
    /// and 2 (setup 1 also sees 3 and 4, setup 2 sees 5 and 6; independent excitations and
    /// noise, and each setup's amplitude its own): the merged shapes are the true ones over
    /// all six points.
    #[test]
    fn two_setups_sharing_two_references_give_the_global_shapes() {
        let (fs, n) = (50.0, 30_000);
        let truth = crate::oma::test_records::SIX_POINTS;
        // setup 2 lists its references in another place and order: channels 3 and 1
        let [one, two] = crate::oma::test_records::two_setups((100, 200));
        let r1 = analyze(&one, &OmaSettings::new(fs, n, None)).unwrap();
        let r2 = analyze(&two, &OmaSettings::new(fs, n, None)).unwrap();
        let setups = [
            Setup {
                result: &r1,
                references: &[0, 1],
                channels: 4,
            },
            Setup {
                result: &r2,
                references: &[3, 1],
                channels: 4,
            },
        ];
        assert_eq!(
            layout(&setups),
            vec![(0, 0), (0, 1), (0, 2), (0, 3), (1, 0), (1, 2)]
        );
        let merged = poser(&setups);
        // global order: 1, 2, 3, 4, then setup 2's 5 and 6
        for (f, _, shape) in truth {
            let want: Vec<Complex64> = shape.iter().map(|&v| Complex64::new(v, 0.0)).collect();
            let m = merged
                .modes
                .iter()
                .find(|m| m.method == Method::Ssi && (m.f_hz - f).abs() < 0.01 * f)
                .unwrap_or_else(|| panic!("{f} Hz: {:?}", merged.notes));
            assert_eq!(m.shape.len(), 6);
            let c = mac(&m.shape, &want);
            assert!(c > 0.995, "{f} Hz: MAC {c} {:?}", m.shape);
            assert!(m
                .uncertainty
                .f_hz
                .is_some_and(|i| i.lo <= m.f_hz && m.f_hz <= i.hi));
            // setup 2's part: matched at the references
            let part = merged
                .parts
                .iter()
                .find(|p| p.setup == 1 && p.method == Method::Ssi && p.mode == m.mode)
                .unwrap();
            assert!(part.reference_mac.is_some_and(|c| c > 0.99), "{part:?}");
        }
    }
}
