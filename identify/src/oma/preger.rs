//! Several setups identified together by PreGER (pre-global estimation re-scaling, as
//! pyOMA-2's `MultiSetup_PreGER` with `SSI_MS`; docs/method.md §3.12, "Several setups"): each
//! setup's SSI matrix (SSI-cov's block Toeplitz matrix or SSI-dat's projection factor, of its
//! own records) gives its observability matrix of the highest order; the rows of its
//! references are mapped onto the first setup's (`T = pinv(O_ref) O_ref,1`) and its other
//! rows carried by the same map (`O_other T`); the global observability matrix interleaves,
//! per block row, the first setup's references and then every setup's other points (the
//! global numbering of [`super::setups::layout`]). Its poles, stable poles and clusters are
//! SSI's, with shapes over every point at once; the intervals from the jackknife leaving the
//! same half of the blocks out of every setup.
//!
//! The map asks the references' rows to span the model: the highest order is at most the
//! references times the block rows.

use super::cluster::{self, SsiMode};
use super::modes::{cluster_evidence, of_cluster};
use super::ssi::{self, Parts, Pole};
use super::uncertainty;
use super::{Method, OmaMode, OmaSettings};
use nalgebra::DMatrix;

/// One setup: its records (one per channel) and which channels are the references (the same
/// points in every setup, in the same order).
#[derive(Debug, Clone, Copy)]
pub struct Record<'a> {
    /// Its records, sampled at the first setup's rate.
    pub channels: &'a [Vec<f64>],
    /// Its channels (0-based) that are the references, in the common order.
    pub references: &'a [usize],
}

/// What PreGER found: the SSI modes with global shapes, every pole (the stabilisation
/// diagram), the clusters kept and rejected, and the highest order used.
#[derive(Debug, Clone)]
pub struct Found {
    /// The modes (method SSI), shapes on the global points.
    pub modes: Vec<OmaMode>,
    /// Every pole of every order of the global model.
    pub poles: Vec<Pole>,
    /// The clusters reported (true) and rejected.
    pub clusters: Vec<(SsiMode, bool)>,
    /// The highest model order, after the references' limit.
    pub max_order: usize,
}

/// The highest order PreGER can use: SSI's, at most the references times the block rows, and
/// at most the global model's (`(i - 1)` block rows of every point).
pub fn max_order(setups: &[Record<'_>], s: &OmaSettings) -> usize {
    let refs = setups.first().map_or(0, |r| r.references.len());
    let points = points(setups);
    let i = s.ssi.block_rows;
    s.ssi
        .max_order
        .min(refs * i)
        .min(points * i.saturating_sub(1))
        & !1
}

/// The references' rows must outnumber the highest order by this factor for PreGER's block
/// rows by default ([`block_rows`]).
pub const REFERENCE_ROWS_OVER_ORDER: f64 = 1.5;

/// PreGER's block rows by default: SSI's `block_rows`, raised so that the `refs` references'
/// rows are [`REFERENCE_ROWS_OVER_ORDER`] times the highest order `max_order`, but at most an
/// eighth of the shortest setup's `samples` (as SSI's default). With one reference and 30
/// block rows the map of order 30 is square, and the shear frame's first mode lost its
/// stability (4 stable poles of 5) on two five-minute setups; with 45 or 60 it had 6 to 13.
pub fn block_rows(refs: usize, max_order: usize, block_rows: usize, samples: usize) -> usize {
    let wanted = (REFERENCE_ROWS_OVER_ORDER * max_order as f64 / refs.max(1) as f64).ceil();
    block_rows.max((wanted as usize).min(samples / 8))
}

/// The number of global points: the references once, every setup's others.
fn points(setups: &[Record<'_>]) -> usize {
    let refs = setups.first().map_or(0, |r| r.references.len());
    refs + setups
        .iter()
        .map(|r| r.channels.len() - r.references.len())
        .sum::<usize>()
}

/// Each setup's observability matrix of order `n` (without the blocks `left_out`), split into the
/// rows of its references and of its other points, with its other points' count.
type Split = (DMatrix<f64>, DMatrix<f64>, usize);

/// The setups' observability matrices of order `n` from their SSI matrices (`parts`, without
/// the blocks `left_out`), each split at its references ([`Split`]).
fn observabilities(
    setups: &[Record<'_>],
    parts: &[Parts],
    (left_out, n): (&[usize], usize),
    s: &OmaSettings,
) -> anyhow::Result<Vec<Split>> {
    let i = s.ssi.block_rows;
    let rows_of = |k: usize, channels: &[usize]| -> Vec<usize> {
        (0..i)
            .flat_map(|b| channels.iter().map(move |c| b * k + c))
            .collect()
    };
    setups
        .iter()
        .zip(parts)
        .map(|(r, p)| {
            let (t, k) = p.matrix(left_out, s.ssi)?;
            let o = ssi::observability(t, n)?;
            let others: Vec<usize> = (0..k).filter(|c| !r.references.contains(c)).collect();
            Ok((
                o.select_rows(&rows_of(k, r.references)),
                o.select_rows(&rows_of(k, &others)),
                others.len(),
            ))
        })
        .collect()
}

/// The global observability matrix of order `ord` from the setups' ([`observabilities`]):
/// each setup's first `ord` columns mapped onto the first setup's at the references, as the
/// module documentation builds it.
fn global_observability(
    split: &[Split],
    refs: usize,
    ord: usize,
    block_rows: usize,
) -> anyhow::Result<DMatrix<f64>> {
    let o1 = split[0].0.columns(0, ord);
    let dof = refs + split.iter().map(|x| x.2).sum::<usize>();
    let mut o = DMatrix::<f64>::zeros(block_rows * dof, ord);
    let mut carried = Vec::with_capacity(split.len());
    for (j, (at_refs, at_others, _)) in split.iter().enumerate() {
        let mine = at_others.columns(0, ord).into_owned();
        carried.push(match j {
            0 => mine,
            _ => {
                let pinv = at_refs
                    .columns(0, ord)
                    .into_owned()
                    .pseudo_inverse(1e-12)
                    .map_err(|e| anyhow::anyhow!("PreGER: the references' map: {e}"))?;
                mine * (pinv * o1)
            }
        });
    }
    for b in 0..block_rows {
        let mut row = b * dof;
        o.rows_mut(row, refs).copy_from(&o1.rows(b * refs, refs));
        row += refs;
        for (m, (_, _, others)) in carried.iter().zip(split) {
            o.rows_mut(row, *others)
                .copy_from(&m.rows(b * others, *others));
            row += others;
        }
    }
    Ok(o)
}

/// The poles of every order of the setups together (without the blocks `left_out` of each).
fn poles(
    setups: &[Record<'_>],
    parts: &[Parts],
    left_out: &[usize],
    s: &OmaSettings,
) -> anyhow::Result<Vec<Pole>> {
    let n = max_order(setups, s);
    let split = observabilities(setups, parts, (left_out, n), s)?;
    let refs = setups[0].references.len();
    let i = s.ssi.block_rows;
    let o_of = |ord: usize| global_observability(&split, refs, ord, i);
    Ok(ssi::poles_of_orders(points(setups), n, s.fs_hz, s.ssi, o_of)?.0)
}

/// `e` with setup `i` (0-based) named, still the user's to fix when it was.
pub(super) fn in_setup(i: usize, e: anyhow::Error) -> anyhow::Error {
    let msg = format!("setup {}: {e}", i + 1);
    match e.chain().any(|c| c.is::<vibcam_readers::BadInput>()) {
        true => vibcam_readers::bad_input(msg),
        false => anyhow::anyhow!(msg),
    }
}

/// Each setup's records divided by its own power of two ([`super::scaled_record`]), with it.
pub(super) fn scaled_setups(setups: &[Record<'_>]) -> anyhow::Result<Vec<(Vec<Vec<f64>>, f64)>> {
    if setups.is_empty() {
        return Err(vibcam_readers::bad_input("PreGER: no setup to analyse"));
    }
    setups
        .iter()
        .enumerate()
        .map(|(i, r)| super::scaled_record(r.channels).map_err(|e| in_setup(i, e)))
        .collect()
}

/// PreGER over `setups` (at least one, each of at least one reference and the same count)
/// with the first setup's settings `s`: SSI's modes on the global points, their clusters
/// (rejected ones to `rejected`, bands as SSI's), intervals by the jackknife over `s.groups`
/// blocks; notes for the report.
pub fn identify(
    setups: &[Record<'_>],
    s: &OmaSettings,
    notes: &mut Vec<String>,
    rejected: &mut Vec<String>,
) -> anyhow::Result<Found> {
    // each setup by its own power of two (a factor common to a setup's channels cancels in
    // its map)
    let scaled = scaled_setups(setups)?;
    let setups: Vec<Record<'_>> = setups
        .iter()
        .zip(&scaled)
        .map(|(r, (c, _))| Record {
            channels: c,
            references: r.references,
        })
        .collect();
    let groups = if s.groups >= 3 { s.groups } else { 1 };
    let parts: Vec<Parts> = setups
        .iter()
        .map(|r| Parts::of(r.channels, s.ssi, groups))
        .collect::<anyhow::Result<_>>()?;
    let max_order = max_order(&setups, s);
    if max_order < s.ssi.max_order & !1 {
        notes.push(format!(
            "PreGER: highest model order {max_order} (the references' {} rows per block row \
             times {} block rows bound it; SSI's is {})",
            setups[0].references.len(),
            s.ssi.block_rows,
            s.ssi.max_order
        ));
    }
    let all = poles(&setups, &parts, &[], s)?;
    let (kept, dropped) = cluster::cluster(&all, s.cluster);
    let label = format!("{} by PreGER", s.ssi.kind.label());
    let mut modes: Vec<OmaMode> = cluster::chosen(
        (&kept, &dropped),
        &s.bands,
        ("ssi", &label),
        notes,
        rejected,
    )
    .into_iter()
    .map(|chosen| {
        let evidence = format!(
            "{}; PreGER over {} setups",
            cluster_evidence(chosen.2),
            setups.len()
        );
        of_cluster(Method::Ssi, chosen, &s.bands, evidence)
    })
    .collect();
    if groups >= 3 {
        let without = |g: &[usize]| poles(&setups, &parts, g, s);
        let intervals = uncertainty::of_ssi_modes(&modes, s.cluster, groups, without, notes)?;
        for (m, u) in modes.iter_mut().zip(intervals) {
            m.uncertainty = u;
        }
    }
    let clusters = kept
        .into_iter()
        .map(|c| (c, true))
        .chain(dropped.into_iter().map(|r| (r.cluster, false)))
        .collect();
    Ok(Found {
        modes,
        poles: all,
        clusters,
        max_order,
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::modal::mac;
    use crate::oma::setups::{layout, poser, Setup};
    use crate::oma::{analyze, OmaSettings};
    use num_complex::Complex64;

    /// The pair of [`crate::oma::test_records::two_setups`] (references: setup 1's channels
    /// 1 and 2, setup 2's 4 and 2) by PreGER and by PoSER, the two numbering the points
    /// alike.
    pub(crate) fn both(
        [one, two]: [&[Vec<f64>]; 2],
        s: &OmaSettings,
        rejected: &mut Vec<String>,
    ) -> (Found, crate::oma::setups::Merged) {
        let refs: [&[usize]; 2] = [&[0, 1], &[3, 1]];
        let records = [(one, refs[0]), (two, refs[1])].map(|(channels, references)| Record {
            channels,
            references,
        });
        let found = identify(&records, s, &mut Vec::new(), rejected).unwrap();
        let results = [one, two].map(|r| analyze(r, s).unwrap());
        let setups: Vec<Setup> = results
            .iter()
            .zip(refs)
            .map(|(result, references)| Setup {
                result,
                references,
                channels: 4,
            })
            .collect();
        // the global numbering is PoSER's
        assert_eq!(layout(&setups).len(), points(&records));
        (found, poser(&setups))
    }

    /// Six points, two modes, two setups sharing points 1 and 2 (setup 2 lists them as its
    /// channels 3 and 1; its records 2.5 times larger): the global modes are the true
    /// frequencies and shapes over all six points, each within its interval, and PoSER's on
    /// the same records agree.
    #[test]
    fn two_setups_identified_together_give_the_global_shapes() {
        let (fs, n) = (50.0, 30_000);
        let truth = crate::oma::test_records::SIX_POINTS;
        let [one, two] = crate::oma::test_records::two_setups((100, 200));
        let s = OmaSettings::new(fs, n, None);
        let mut rejected = Vec::new();
        let (found, merged) = both([&one, &two], &s, &mut rejected);
        assert_eq!(found.max_order, s.ssi.max_order.min(2 * s.ssi.block_rows));
        for (f, z, shape) in truth {
            let want: Vec<Complex64> = shape.iter().map(|&v| Complex64::new(v, 0.0)).collect();
            let m = found
                .modes
                .iter()
                .find(|m| (m.f_hz - f).abs() < 0.01 * f)
                .unwrap_or_else(|| panic!("{f} Hz: {:?} {rejected:?}", found.modes));
            assert_eq!(m.shape.len(), 6);
            let c = mac(&m.shape, &want);
            assert!(c > 0.995, "{f} Hz: MAC {c} {:?}", m.shape);
            assert!((m.damping.unwrap() - z).abs() < 0.3 * z, "{m:?}");
            let i = m.uncertainty.f_hz.expect("an interval");
            // the truth within the interval, and the interval narrower than 2 % either side
            assert!(i.lo <= f && f <= i.hi && i.half_width() < 0.02 * f, "{i:?}");
            let p = merged
                .modes
                .iter()
                .find(|p| p.method == Method::Ssi && (p.f_hz - f).abs() < 0.01 * f)
                .unwrap();
            assert!(mac(&p.shape, &m.shape) > 0.99, "{p:?} {m:?}");
            assert!((p.f_hz - m.f_hz).abs() < 0.005 * f, "{p:?} {m:?}");
        }
    }

    /// A setup's record the user must fix is named and stays the user's to fix (exit 2); an
    /// internal error stays internal.
    #[test]
    fn a_setups_errors_name_it_and_keep_their_class() {
        let flat = vec![vec![0.0; 100]; 2];
        let records = [Record {
            channels: &flat,
            references: &[0],
        }];
        let e = scaled_setups(&records).unwrap_err();
        assert!(
            e.to_string().starts_with("setup 1: the records' RMS"),
            "{e}"
        );
        assert!(e.chain().any(|c| c.is::<vibcam_readers::BadInput>()));
        let e = in_setup(2, anyhow::anyhow!("internal"));
        assert_eq!(e.to_string(), "setup 3: internal");
        assert!(!e.chain().any(|c| c.is::<vibcam_readers::BadInput>()));
    }

    /// One setup alone: PreGER is SSI of that setup (the same poles, order for order, up to
    /// the references' limit).
    #[test]
    fn one_setup_is_plain_ssi() {
        let (fs, n) = (40.0, 8_000);
        let of: [(f64, f64, &[f64]); 1] = [(3.1, 0.02, &[1.0, -0.5, 0.7])];
        let channels = crate::oma::test_records::oscillators(fs, n, &of, (7, 0.2));
        let mut s = OmaSettings::new(fs, n, None);
        s.groups = 1;
        let setups = [Record {
            channels: &channels,
            references: &[0, 1, 2],
        }];
        let parts: Vec<Parts> = vec![Parts::of(&channels, s.ssi, 1).unwrap()];
        let ours = poles(&setups, &parts, &[], &s).unwrap();
        let plain = ssi::poles(&channels, fs, s.ssi).unwrap().0;
        assert_eq!(ours.len(), plain.len());
        for (a, b) in ours.iter().zip(&plain) {
            assert_eq!(a.order, b.order);
            assert!((a.f_hz - b.f_hz).abs() < 1e-9 * b.f_hz, "{a:?} {b:?}");
        }
    }

    /// Sixteen pairs of setups as above (other seeds): PreGER's frequencies unbiased (the
    /// mean within three standard errors of the truth), their spread within 1.5 times
    /// PoSER's on the same records, and their standard uncertainties not narrower than 0.8
    /// of the spread. Printed: the table of docs/validation.md §10 ("PreGER"). Run with
    /// `cargo test --release -p vibcam-identify --lib preger -- --ignored --nocapture`.
    #[test]
    #[ignore = "a Monte Carlo of 16 x 2 setups, about 20 s"]
    fn preger_beside_poser_over_sixteen_pairs_of_setups() {
        let (fs, n) = (50.0, 30_000);
        let truth = crate::oma::test_records::SIX_POINTS;
        let s = OmaSettings::new(fs, n, None);
        // per mode, per method (PreGER, PoSER): (f, u of f, damping) of each pair
        let mut got = vec![[Vec::new(), Vec::new()]; truth.len()];
        for seed in 0..16u64 {
            let [one, two] = crate::oma::test_records::two_setups((1000 + seed, 2000 + seed));
            let (found, merged) = both([&one, &two], &s, &mut Vec::new());
            for ((f, _, _), g) in truth.iter().zip(got.iter_mut()) {
                let near = |m: &&OmaMode| m.method == Method::Ssi && (m.f_hz - f).abs() < 0.02 * f;
                for (list, m) in g.iter_mut().zip([
                    found.modes.iter().find(near),
                    merged.modes.iter().find(near),
                ]) {
                    let m = m.unwrap_or_else(|| panic!("seed {seed}: no mode at {f} Hz"));
                    let u = m.uncertainty.f_hz.map_or(f64::NAN, |i| i.u);
                    list.push((m.f_hz, u, m.damping.unwrap_or(f64::NAN)));
                }
            }
        }
        let stats = |v: &[(f64, f64, f64)], pick: fn(&(f64, f64, f64)) -> f64| {
            crate::oma::test_records::mean_sd(v.iter().map(pick))
        };
        println!("| mode | truth f, damping | method | mean f | sd f | mean u(f) | mean damping | sd damping |");
        println!("|---:|---|---|---:|---:|---:|---:|---:|");
        for (mode, ((f, z, _), g)) in truth.iter().zip(&got).enumerate() {
            for (name, v) in ["PreGER", "PoSER"].iter().zip(g) {
                let (mf, sf) = stats(v, |r| r.0);
                let (mu, _) = stats(v, |r| r.1);
                let (mz, sz) = stats(v, |r| r.2);
                println!(
                    "| {} | {f}, {z} | {name} | {mf:.4} | {sf:.4} | {mu:.4} | {mz:.4} | {sz:.4} |",
                    mode + 1
                );
            }
            let (mf, sf) = stats(&g[0], |r| r.0);
            let (_, sp) = stats(&g[1], |r| r.0);
            let (mu, _) = stats(&g[0], |r| r.1);
            assert!(
                (mf - f).abs() < 3.0 * sf / 4.0,
                "{f} Hz: mean {mf}, sd {sf}"
            );
            assert!(sf < 1.5 * sp, "{f} Hz: PreGER sd {sf}, PoSER {sp}");
            assert!(mu > 0.8 * sf, "{f} Hz: mean u {mu}, sd {sf}");
        }
    }
}
