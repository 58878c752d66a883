//! FDD, EFDD and pLSCF of several setups identified together by the spectral PreGER (as
//! pyOMA-2's `SD_PreGER` under `FDD_MS`, `EFDD_MS` and `pLSCF_MS`; docs/method.md §3.12,
//! "Several setups"): per
//! line, each setup's cross-spectral matrix `S_s` (its own records) is split at its references
//! into `B_s = S_s[ref, ref]` and `A_s = S_s[other, ref]`; the references' mean spectrum
//! `Bbar` (the setups' `B_s` averaged) is the first block of the global matrix and each
//! setup's other points follow as `A_s pinv(B_s) Bbar` (its transmissibility to the
//! references, times their mean spectrum): the global `N x R` matrix `G` of the `N` global
//! points (the numbering of [`super::setups::layout`]) against the `R` references. FDD takes
//! `G`'s singular values and left singular vectors; here `G` is made the `N x N` Hermitian
//! matrix `(G G^H)^(1/2) = U S U^H` (the same singular values and vectors), so that the peaks,
//! bells, EFDD fits and intervals are FDD's and EFDD's unchanged; pLSCF fits the half-spectra
//! of `G`'s columns, the references'. The intervals are the jackknife's with the same group of
//! Welch segments left out of every setup.

use super::csd::{self, Csd};
use super::fdd::{self, Svd};
use super::modes::{self, Peak, QuantityChoice};
use super::plscf;
use super::preger::{in_setup, scaled_setups, Record};
use super::uncertainty::{self, group};
use super::{EfddRule, OmaMode, OmaSettings};
use nalgebra::DMatrix;
use num_complex::Complex64;

/// What the spectral PreGER found: the global matrix and its decomposition, the peaks and the
/// FDD, EFDD (and pLSCF) modes with shapes on the global points (intervals included).
#[derive(Debug, Clone)]
pub struct SpectralFound {
    /// The global cross-spectral matrix `(G G^H)^(1/2)`, in the first setup's unit squared.
    pub csd: Csd,
    /// Its singular values (the references' count of them: `G`'s rank is at most that) and
    /// vectors.
    pub svd: Svd,
    /// The peaks taken.
    pub peaks: Vec<Peak>,
    /// The FDD, EFDD and pLSCF modes.
    pub modes: Vec<OmaMode>,
    /// The quantity EFDD's bells were fitted as.
    pub quantity: QuantityChoice,
    /// pLSCF's references among the global points (0-based; empty when it did not run).
    pub plscf_references: Vec<usize>,
}

/// A singular value of a setup's references' matrix under this fraction of its largest is
/// left out of the pseudo-inverse (a line where fewer modes than references move them).
const PINV_RELATIVE: f64 = 1e-12;

/// Every setup's records (scaled), cross-spectral matrices, weights and references: what
/// the global matrices and their replicates are made of.
struct Setups<'a> {
    scaled: Vec<(Vec<Vec<f64>>, f64)>,
    csds: Vec<Csd>,
    weights: Vec<f64>,
    references: Vec<&'a [usize]>,
}

impl<'a> Setups<'a> {
    fn of(setups: &[Record<'a>], s: &OmaSettings) -> anyhow::Result<Setups<'a>> {
        let scaled = scaled_setups(setups)?;
        let csds: Vec<Csd> = scaled
            .iter()
            .enumerate()
            .map(|(i, (c, _))| csd::csd_matrix(c, s.fs_hz, s.csd).map_err(|e| in_setup(i, e)))
            .collect::<anyhow::Result<_>>()?;
        let weights = scaled
            .iter()
            .map(|(_, scale)| (scale / scaled[0].1).powi(2))
            .collect();
        Ok(Setups {
            scaled,
            csds,
            weights,
            references: setups.iter().map(|r| r.references).collect(),
        })
    }

    /// The global matrices ([`combine`]).
    fn global(&self) -> (Csd, Csd) {
        combine(&self.csds, &self.references, &self.weights)
    }

    /// The global matrices without group `g` of `groups` of every setup's Welch segments, and
    /// the segments left out.
    fn without(
        &self,
        g: usize,
        groups: usize,
        s: &OmaSettings,
    ) -> anyhow::Result<((Csd, Csd), usize)> {
        let mut size = 0;
        let parts: Vec<Csd> = self
            .scaled
            .iter()
            .zip(&self.csds)
            .map(|((c, _), whole)| {
                let range = group(g, groups, whole.segments);
                size += range.len();
                Ok(whole.without(&csd::of_segments(c, s.fs_hz, s.csd, range)?))
            })
            .collect::<anyhow::Result<_>>()?;
        Ok((combine(&parts, &self.references, &self.weights), size))
    }

    /// The least number of segments of a setup.
    fn segments(&self) -> usize {
        self.csds.iter().map(|c| c.segments).min().unwrap_or(0)
    }
}

/// FDD, EFDD (and pLSCF with `s.plscf`) of every setup's records together, with the settings
/// `s` (the first setup's) and `ssi` the SSI modes that support weak peaks (PreGER's, on the
/// global points).
pub fn identify(
    setups: &[Record<'_>],
    s: &OmaSettings,
    ssi: &[OmaMode],
    notes: &mut Vec<String>,
    rejected: &mut Vec<String>,
) -> anyhow::Result<SpectralFound> {
    let all = Setups::of(setups, s)?;
    let (global, columns) = all.global();
    let mut svd = fdd::decompose(&global)?;
    // G has as many columns as references: the other singular values are rounding
    let rank = all.references.first().map_or(0, |r| r.len()).max(1);
    for line in &mut svd.s {
        line.truncate(rank);
    }
    let peaks = if s.bands.is_empty() {
        modes::automatic_peaks(&svd, s, ssi, rejected)
    } else {
        modes::banded_peaks(&svd, global.df_hz(), s, notes)
    };
    let quantity = modes::choose_quantity(&svd, &peaks, s);
    let s = &OmaSettings {
        efdd: EfddRule {
            quantity: Some(quantity.quantity),
            ..s.efdd
        },
        ..s.clone()
    };
    let mut found = modes::fdd_modes(&svd, &peaks, s, notes);
    let replicate = |g: usize, groups: usize| -> anyhow::Result<(Csd, usize)> {
        all.without(g, groups, s)
            .map(|((square, _), n)| (square, n))
    };
    let intervals =
        uncertainty::of_spectral_modes((all.segments(), &replicate), s, &found, &peaks, notes)?;
    for (m, u) in found.iter_mut().zip(intervals) {
        m.uncertainty = u;
    }
    let (plscf, plscf_references) =
        plscf_of(&all, (&columns, rank), s, (&found, ssi), (notes, rejected))?;
    found.extend(plscf);
    for m in &mut found {
        m.evidence = format!(
            "{}; spectral PreGER over {} setups",
            m.evidence,
            setups.len()
        );
    }
    Ok(unscaled(
        SpectralFound {
            csd: global,
            svd,
            peaks,
            modes: found,
            quantity,
            plscf_references,
        },
        all.scaled[0].1.powi(2),
    ))
}

/// pLSCF on the global matrix's reference columns (`columns`, the first `refs` of them; at
/// most [`plscf::MAX_REFERENCES`], those of most power), its band from the modes found by FDD,
/// EFDD and SSI: its modes and the references used.
fn plscf_of(
    all: &Setups<'_>,
    (columns, refs): (&Csd, usize),
    s: &OmaSettings,
    (fdd, ssi): (&[OmaMode], &[OmaMode]),
    (notes, rejected): (&mut Vec<String>, &mut Vec<String>),
) -> anyhow::Result<(Vec<OmaMode>, Vec<usize>)> {
    if s.plscf.is_none() {
        return Ok((Vec::new(), Vec::new()));
    }
    let chosen = plscf::references_among(columns, refs);
    let replicate = |g: usize, groups: usize| -> anyhow::Result<(Csd, usize)> {
        all.without(g, groups, s).map(|((_, cols), n)| (cols, n))
    };
    let others: Vec<OmaMode> = fdd.iter().chain(ssi).cloned().collect();
    let found = plscf::plscf_of((columns, &chosen, &replicate), s, &others, notes, rejected)?;
    Ok((found, chosen))
}

/// `f` (found on records divided by a scale) back in the first setup's unit: times `power`,
/// the scale squared ([`super::scale_back`], and the peaks' values).
fn unscaled(mut f: SpectralFound, power: f64) -> SpectralFound {
    super::scale_back((&mut f.csd, &mut f.svd, &mut f.modes), power);
    for p in &mut f.peaks {
        p.value *= power;
    }
    f
}

/// The global matrices of the setups' matrices `csds` (same lines), their `references` (the
/// same points, in the same order) and `weights` (each setup's unit squared over the
/// first's), line by line (`global_line`): `(G G^H)^(1/2)`, and `G` itself as the first `R`
/// columns of an `N x N` matrix (the others zero: the references' columns, which pLSCF's
/// half-spectra read); segments the least of the setups'.
pub fn combine(csds: &[Csd], references: &[&[usize]], weights: &[f64]) -> (Csd, Csd) {
    let lines = csds.first().map_or(0, |c| c.g.len());
    let mut k = 0;
    let (square, columns): (Vec<_>, Vec<_>) = (0..lines)
        .map(|l| {
            let (g, h) = global_line(
                csds.iter()
                    .zip(references)
                    .zip(weights)
                    .map(|((c, &r), &w)| (c.k, c.g[l].as_slice(), r, w)),
            );
            k = h.nrows();
            // row-major: the transposes' column-major storage
            let cols = g
                .resize_horizontally(k, Complex64::new(0.0, 0.0))
                .transpose();
            (
                h.transpose().iter().copied().collect(),
                cols.iter().copied().collect(),
            )
        })
        .unzip();
    let of = |g| Csd {
        freq_hz: csds.first().map_or_else(Vec::new, |c| c.freq_hz.clone()),
        k,
        g,
        segments: csds.iter().map(|c| c.segments).min().unwrap_or(0),
    };
    (of(square), of(columns))
}

/// One line of the global matrices: from each setup `(channels, its matrix row-major, its
/// references, its weight)`, the `N x R` matrix `G` (the module's) and `(G G^H)^(1/2)`.
fn global_line<'a>(
    setups: impl Iterator<Item = (usize, &'a [Complex64], &'a [usize], f64)> + Clone,
) -> (DMatrix<Complex64>, DMatrix<Complex64>) {
    let parts: Vec<_> = setups
        .map(|(k, m, refs, w)| {
            let s = DMatrix::from_fn(k, k, |i, j| m[i * k + j]);
            let others: Vec<usize> = (0..k).filter(|c| !refs.contains(c)).collect();
            let b = s.select_rows(refs).select_columns(refs);
            let a = s.select_rows(&others).select_columns(refs);
            (a, b, w)
        })
        .collect();
    let r = parts.first().map_or(0, |p| p.1.nrows());
    let mut mean = DMatrix::<Complex64>::zeros(r, r);
    for (_, b, w) in &parts {
        mean += b * Complex64::new(*w / parts.len() as f64, 0.0);
    }
    let mut blocks = vec![mean.clone()];
    for (a, b, _) in &parts {
        let svd = b.clone().svd(true, true);
        let largest = svd.singular_values.max();
        let pinv = svd
            .pseudo_inverse(largest * PINV_RELATIVE)
            .unwrap_or_else(|_| DMatrix::zeros(r, r));
        blocks.push(a * pinv * &mean);
    }
    let n: usize = blocks.iter().map(|b| b.nrows()).sum();
    let mut g = DMatrix::<Complex64>::zeros(n, r);
    let mut row = 0;
    for b in &blocks {
        g.rows_mut(row, b.nrows()).copy_from(b);
        row += b.nrows();
    }
    let h = square_root_of_gram(g.clone());
    (g, h)
}

/// `(G G^H)^(1/2)` of `g`: `U S U^H` from its thin singular value decomposition, made exactly
/// Hermitian.
fn square_root_of_gram(g: DMatrix<Complex64>) -> DMatrix<Complex64> {
    let n = g.nrows();
    let svd = g.svd(true, false);
    let (Some(u), s) = (svd.u, svd.singular_values) else {
        return DMatrix::zeros(n, n);
    };
    let us = DMatrix::from_fn(n, s.len(), |i, j| u[(i, j)] * s[j]);
    let h = us * u.adjoint();
    (&h + h.adjoint()) * Complex64::new(0.5, 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Hermitian rank-`modes` matrix `sum_m c_m phi_m phi_m^H` on the rows `points`.
    fn spectral(phis: &[Vec<Complex64>], c: &[f64], points: &[usize]) -> Vec<Complex64> {
        let k = points.len();
        let mut g = vec![Complex64::new(0.0, 0.0); k * k];
        for (phi, &c) in phis.iter().zip(c) {
            for (i, &p) in points.iter().enumerate() {
                for (j, &q) in points.iter().enumerate() {
                    g[i * k + j] += phi[p] * phi[q].conj() * c;
                }
            }
        }
        g
    }

    fn csd_of(g: Vec<Complex64>, k: usize) -> Csd {
        Csd {
            freq_hz: vec![1.0],
            k,
            g: vec![g],
            segments: 10,
        }
    }

    #[test]
    fn one_mode_in_two_setups_gives_the_global_shape_as_the_first_singular_vector() {
        // five global points: references 0 and 1; setup 1 also has 2, setup 2 has 3 and 4
        // (its references in other columns); setup 2 excited 3 times as strongly
        let phi = vec![
            Complex64::new(1.0, 0.0),
            Complex64::new(-0.5, 0.1),
            Complex64::new(0.8, 0.0),
            Complex64::new(0.3, -0.2),
            Complex64::new(-0.9, 0.0),
        ];
        let other = vec![
            Complex64::new(0.2, 0.0),
            Complex64::new(1.0, 0.0),
            Complex64::new(-0.4, 0.0),
            Complex64::new(0.5, 0.0),
            Complex64::new(0.1, 0.0),
        ];
        let phis = [phi.clone(), other];
        let s1 = csd_of(spectral(&phis, &[5.0, 0.01], &[0, 1, 2]), 3);
        // setup 2's columns: point 3, reference 1, point 4, reference 0
        let s2 = csd_of(spectral(&phis, &[15.0, 0.03], &[3, 1, 4, 0]), 4);
        let (g, columns) = combine(&[s1, s2], &[&[0, 1], &[3, 1]], &[1.0, 1.0]);
        assert_eq!((g.k, columns.k), (5, 5));
        // G's columns are the references' (the others zero), near 10 phi phi_ref^H
        for i in 0..5 {
            for j in 0..5 {
                let v = columns.g[0][i * 5 + j];
                let want = match j < 2 {
                    true => phi[i] * phi[j].conj() * 10.0,
                    false => Complex64::new(0.0, 0.0),
                };
                assert!((v - want).norm() < 0.05, "{i} {j}: {v} {want}");
            }
        }
        let svd = fdd::decompose(&g).unwrap();
        let u = &svd.u1[0];
        assert!(crate::modal::mac(u, &phi) > 0.9999, "{u:?}");
        // the setups' references' spectra are 5 and 15 times the mode's: their mean is 10,
        // so G is 10 phi phi_ref^H and its largest singular value 10 |phi| |phi_ref|
        let norm = |v: &[Complex64]| v.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt();
        let expected = 10.0 * norm(&phi) * norm(&phi[..2]);
        assert!(
            (svd.s[0][0] / expected - 1.0).abs() < 0.02,
            "{} {expected}",
            svd.s[0][0]
        );
    }

    /// The modes of `method` of the pair of [`crate::oma::test_records::two_setups`] (seeds
    /// `seeds`) by the spectral PreGER, and PoSER's of the same records (settings `s`).
    fn of_pair(
        seeds: (u64, u64),
        s: &OmaSettings,
        method: super::super::Method,
    ) -> (Vec<OmaMode>, Vec<OmaMode>) {
        let [one, two] = crate::oma::test_records::two_setups(seeds);
        let (ssi, merged) = crate::oma::preger::tests::both([&one, &two], s, &mut Vec::new());
        let records = [
            Record {
                channels: &one,
                references: &[0, 1],
            },
            Record {
                channels: &two,
                references: &[3, 1],
            },
        ];
        let found = identify(&records, s, &ssi.modes, &mut Vec::new(), &mut Vec::new()).unwrap();
        let of = |m: &[OmaMode]| -> Vec<OmaMode> {
            m.iter().filter(|m| m.method == method).cloned().collect()
        };
        (of(&found.modes), of(&merged.modes))
    }

    /// EFDD's modes of a pair of setups ([`of_pair`]) with the default settings.
    fn efdd_of_pair(seeds: (u64, u64)) -> (Vec<OmaMode>, Vec<OmaMode>) {
        let s = OmaSettings::new(50.0, 30_000, None);
        of_pair(seeds, &s, super::super::Method::Efdd)
    }

    /// pLSCF on the global matrix's reference columns (the poly-reference model of the two
    /// references): both modes at their frequencies with intervals holding them, the shapes
    /// over all six points (MAC > 0.995), PoSER's pLSCF of the same records agreeing.
    #[test]
    fn two_setups_give_plscf_modes_with_global_shapes() {
        let mut s = OmaSettings::new(50.0, 30_000, None);
        s.plscf = Some(crate::oma::lscf::LscfRule {
            max_order: 20,
            ..Default::default()
        });
        let (found, poser) = of_pair((100, 200), &s, super::super::Method::Plscf);
        let truth = crate::oma::test_records::SIX_POINTS;
        assert_eq!(found.len(), truth.len(), "{found:?}");
        for ((f, z, shape), m) in truth.iter().zip(&found) {
            let want: Vec<Complex64> = shape.iter().map(|&v| Complex64::new(v, 0.0)).collect();
            assert!((m.f_hz - f).abs() < 0.005 * f, "{m:?}");
            assert!((m.damping.unwrap() - z).abs() < 0.3 * z, "{m:?}");
            let c = crate::modal::mac(&m.shape, &want);
            assert!(c > 0.995, "{f} Hz: MAC {c} {:?}", m.shape);
            let i = m.uncertainty.f_hz.expect("an interval");
            assert!(i.lo <= *f && *f <= i.hi, "{f} Hz: {i:?}");
            assert!(m.evidence.contains("references 1, 2"), "{}", m.evidence);
            let p = poser
                .iter()
                .find(|p| (p.f_hz - f).abs() < 0.01 * f)
                .unwrap();
            assert!(crate::modal::mac(&p.shape, &m.shape) > 0.99, "{p:?} {m:?}");
        }
    }

    /// Six points, two modes, two setups (setup 2's records 2.5 times larger, its references
    /// in other channels): EFDD of the global spectra gives each true frequency within its
    /// interval, the damping within 30 % and the shape over all six points (MAC > 0.995);
    /// PoSER's EFDD of the same records agrees.
    #[test]
    fn two_setups_give_efdd_modes_with_global_shapes() {
        let (found, poser) = efdd_of_pair((100, 200));
        let truth = crate::oma::test_records::SIX_POINTS;
        assert_eq!(found.len(), truth.len(), "{found:?}");
        for ((f, z, shape), m) in truth.iter().zip(&found) {
            let want: Vec<Complex64> = shape.iter().map(|&v| Complex64::new(v, 0.0)).collect();
            assert_eq!(m.shape.len(), 6);
            let c = crate::modal::mac(&m.shape, &want);
            assert!(c > 0.995, "{f} Hz: MAC {c} {:?}", m.shape);
            assert!((m.damping.unwrap() - z).abs() < 0.3 * z, "{m:?}");
            let i = m.uncertainty.f_hz.expect("an interval");
            assert!(i.lo <= *f && *f <= i.hi, "{f} Hz: {i:?}");
            assert!(
                m.evidence.contains("spectral PreGER over 2 setups"),
                "{}",
                m.evidence
            );
            let p = poser
                .iter()
                .find(|p| (p.f_hz - f).abs() < 0.01 * f)
                .unwrap();
            assert!((p.f_hz - m.f_hz).abs() < 0.005 * f, "{p:?} {m:?}");
            assert!(crate::modal::mac(&p.shape, &m.shape) > 0.99, "{p:?} {m:?}");
        }
    }

    /// Sixteen pairs of setups: EFDD of the global spectra beside PoSER's EFDD of the same
    /// records: frequencies unbiased (the mean within three standard errors of the truth),
    /// the spread within 1.5 times PoSER's and the standard uncertainties not narrower than
    /// 0.8 of the spread. Printed: the table of docs/validation.md §10. Run with
    /// `cargo test --release -p vibcam-identify --lib preger_spectral -- --ignored --nocapture`.
    #[test]
    #[ignore = "a Monte Carlo of 16 x 2 setups, about 30 s"]
    fn spectral_preger_beside_poser_over_sixteen_pairs_of_setups() {
        let truth = crate::oma::test_records::SIX_POINTS;
        // per mode, per method: (f, u of f, damping, MAC with the truth)
        let mut got = vec![[Vec::new(), Vec::new()]; truth.len()];
        for seed in 0..16u64 {
            let (found, poser) = efdd_of_pair((1000 + seed, 2000 + seed));
            for ((f, _, shape), g) in truth.iter().zip(got.iter_mut()) {
                let want: Vec<Complex64> = shape.iter().map(|&v| Complex64::new(v, 0.0)).collect();
                let near = |m: &&OmaMode| (m.f_hz - f).abs() < 0.02 * f;
                for (list, m) in g
                    .iter_mut()
                    .zip([found.iter().find(near), poser.iter().find(near)])
                {
                    let m = m.unwrap_or_else(|| panic!("seed {seed}: no mode at {f} Hz"));
                    let u = m.uncertainty.f_hz.map_or(f64::NAN, |i| i.u);
                    let c = crate::modal::mac(&m.shape, &want);
                    list.push([m.f_hz, u, m.damping.unwrap_or(f64::NAN), c]);
                }
            }
        }
        let stats =
            |v: &[[f64; 4]], k: usize| crate::oma::test_records::mean_sd(v.iter().map(|r| r[k]));
        println!("| mode | truth f, damping | EFDD by | mean f | sd f | mean u(f) | mean damping | sd damping | least MAC |");
        println!("|---:|---|---|---:|---:|---:|---:|---:|---:|");
        for (mode, ((f, z, _), g)) in truth.iter().zip(&got).enumerate() {
            for (name, v) in ["PreGER", "PoSER"].iter().zip(g) {
                let ((mf, sf), (mu, _), (mz, sz)) = (stats(v, 0), stats(v, 1), stats(v, 2));
                let least = v.iter().map(|r| r[3]).fold(1.0, f64::min);
                println!(
                    "| {} | {f}, {z} | {name} | {mf:.4} | {sf:.4} | {mu:.4} | {mz:.4} | {sz:.4} | {least:.4} |",
                    mode + 1
                );
            }
            let ((mf, sf), (mu, _), (_, sp)) = (stats(&g[0], 0), stats(&g[0], 1), stats(&g[1], 0));
            assert!(
                (mf - f).abs() < 3.0 * sf / 4.0,
                "{f} Hz: mean {mf}, sd {sf}"
            );
            assert!(sf < 1.5 * sp, "{f} Hz: PreGER sd {sf}, PoSER {sp}");
            assert!(mu > 0.8 * sf, "{f} Hz: mean u {mu}, sd {sf}");
        }
    }

    #[test]
    fn one_setup_alone_gives_its_own_singular_values_and_vectors() {
        // with one setup whose every point is a reference, G = S and (S S^H)^(1/2) = S
        let phis = [
            vec![
                Complex64::new(1.0, 0.0),
                Complex64::new(0.5, 0.3),
                Complex64::new(-0.2, 0.0),
            ],
            vec![
                Complex64::new(0.1, 0.0),
                Complex64::new(-0.7, 0.0),
                Complex64::new(1.0, 0.2),
            ],
        ];
        let g = spectral(&phis, &[2.0, 0.7], &[0, 1, 2]);
        let mut with_noise = g.clone();
        for (i, v) in with_noise.iter_mut().enumerate() {
            if i % 4 == 0 {
                *v += 0.01;
            }
        }
        let (one, columns) = combine(&[csd_of(with_noise.clone(), 3)], &[&[0, 1, 2]], &[1.0]);
        for (a, b) in one.g[0].iter().zip(&with_noise) {
            assert!((a - b).norm() < 1e-9, "{a} {b}");
        }
        // and G itself is the matrix: every column a reference's
        for (a, b) in columns.g[0].iter().zip(&with_noise) {
            assert!((a - b).norm() < 1e-12, "{a} {b}");
        }
    }
}
