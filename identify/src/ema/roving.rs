//! A roving-hammer test (docs/method.md §3.13, "Several hit points"): the structure hit at
//! several points, one record each (its force and the same responses), identified together.
//!
//! Every FRF must show the same poles, so the records share what changes them: one block
//! length (the shortest any record's hit spacing allows) and one exponential window (applied to
//! every record when one needs it: its decay is the same in every FRF and taken off the poles
//! as for one record); the band fitted is the union of the records' own. The FRF matrix
//! `H[o][j]` (response `o` over the force at hit point `j`) is fitted as one set of FRFs: LSCF
//! gives the poles (poly-reference with the fewer of responses and hit points as references),
//! LSFD the residues of every FRF. A mode's residues form the
//! matrix `A_r = phi_r L_r^T` (responses x hit points), of rank one; its dominant singular
//! vectors are the shape over the responses and over the hit points (the same shape where both
//! sets hold the point and the structure is reciprocal, Maxwell-Betti). The shape reported is
//! over the larger set ([`super::Layout::over_inputs`]): the hit points for a roving hammer
//! with one fixed transducer.
//!
//! The intervals: the jackknife over `G` groups of hits, group `g` the `g`-th of `G`
//! contiguous groups of every record's hits (`G` the fewest hits of a record), so that every
//! replicate keeps every hit point.

use super::impact::{self, Hits, ImpactRule};
use super::spectra::{self, Frfs, Spectra};
use super::{identify, impact_spectra, EmaResult, EmaSettings, Excitation, Formed, Layout};
use crate::oma::uncertainty::group;
use vibcam_readers::bad_input;

/// One record of a roving-hammer test.
#[derive(Debug, Clone, Copy)]
pub struct Record<'a> {
    /// The force of the hits at its point.
    pub force: &'a [f64],
    /// The responses (the same transducers or points in every record, in one order).
    pub responses: &'a [Vec<f64>],
    /// The hit point's number (the node the shapes over hit points are given at).
    pub point: usize,
    /// The record's name in notes and errors (its file).
    pub name: &'a str,
}

/// Each record's spectra, hits and own choices of band and window.
struct Prepared {
    spectra: Vec<Spectra>,
    hits: Vec<Hits>,
}

/// The records' spectra with one block, one exponential window and one band (module
/// documentation); the choices said in `notes`. Returns the spectra, the window and the band.
fn prepare(
    records: &[Record],
    fs_hz: f64,
    s: &EmaSettings,
    notes: &mut Vec<String>,
) -> anyhow::Result<(Prepared, Option<impact::ExpWindow>, (f64, f64))> {
    let Excitation::Impact { rule, exp } = s.excitation else {
        return Err(bad_input(
            "a roving-hammer test is an impact test: its records are analysed hit by hit \
             ($impact)",
        ));
    };
    let mut block = usize::MAX;
    for r in records {
        block = block.min(impact::find(r.force, fs_hz, rule, r.name)?.block);
    }
    let rule = ImpactRule {
        block_s: Some(block as f64 / fs_hz),
        ..rule
    };
    let mut own = Vec::new();
    for r in records {
        let mut said = Vec::new();
        let p = impact_spectra(
            r.force,
            r.responses,
            fs_hz,
            (r.name, rule, exp),
            s,
            &mut said,
        )?;
        for n in said {
            let n = format!("{} (hit point {}): {n}", r.name, r.point);
            if !notes.contains(&n) {
                notes.push(n);
            }
        }
        own.push(p);
    }
    let window = own.iter().find_map(|p| p.exp);
    let band = own.iter().fold((f64::INFINITY, 0.0f64), |b, p| {
        (b.0.min(p.band_hz.0), b.1.max(p.band_hz.1))
    });
    let windowed = own.iter().filter(|p| p.exp.is_some()).count();
    notes.push(format!(
        "roving hammer: {} records, one block of {:.4} s for all (the shortest their hits \
         allow); {}; the band fitted {:.1}-{:.1} Hz, the union of the records' own",
        records.len(),
        block as f64 / fs_hz,
        match (window, windowed) {
            (None, _) => "no exponential window".to_string(),
            (Some(_), w) if w == records.len() => "the exponential window on every record".into(),
            (Some(_), w) => format!(
                "the exponential window on every record, as {w} of them need it (one window: \
                 every FRF shows the same poles)"
            ),
        },
        band.0,
        band.1
    ));
    let mut prepared = Prepared {
        spectra: Vec::new(),
        hits: Vec::new(),
    };
    for (r, p) in records.iter().zip(own) {
        let hits = p
            .hits
            .ok_or_else(|| anyhow::anyhow!("an impact test without hits"))?;
        let sp = spectra::of_hits(r.force, r.responses, fs_hz, &hits, window, band.1 * 1.05)?;
        prepared.spectra.push(sp);
        prepared.hits.push(hits);
    }
    Ok((prepared, window, band))
}

/// The FRFs of every record, one after the other, each without its hits of jackknife group `g`
/// of `groups` (none: every hit).
fn frfs(spectra: &[Spectra], left_out: Option<(usize, usize)>) -> Frfs {
    let mut all = Frfs {
        h1: Vec::new(),
        h2: Vec::new(),
        coherence: Vec::new(),
    };
    for sp in spectra {
        let range = left_out.map_or(0..0, |(g, groups)| group(g, groups, sp.units.len()));
        all.extend(sp.frfs_without(range));
    }
    all
}

/// The analysis of a roving-hammer test (module documentation): `records` at one rate
/// `fs_hz`, each with the same responses.
pub fn analyse(records: &[Record], fs_hz: f64, s: &EmaSettings) -> anyhow::Result<EmaResult> {
    let Some(first) = records.first() else {
        return Err(bad_input("a roving-hammer test needs at least one record"));
    };
    let outputs = first.responses.len();
    if let Some(r) = records.iter().find(|r| r.responses.len() != outputs) {
        return Err(bad_input(format!(
            "{}: {} responses where {} has {outputs}: every record of a roving-hammer test holds \
             the same responses",
            r.name,
            r.responses.len(),
            first.name
        )));
    }
    let mut points: Vec<usize> = records.iter().map(|r| r.point).collect();
    points.sort_unstable();
    if let Some(w) = points.windows(2).find(|w| w[0] == w[1]) {
        return Err(bad_input(format!(
            "hit point {} is given twice: one record per hit point",
            w[0]
        )));
    }
    let points: Vec<usize> = records.iter().map(|r| r.point).collect();
    let mut notes = Vec::new();
    let (prepared, exp, band_hz) = prepare(records, fs_hz, s, &mut notes)?;
    let groups = prepared
        .spectra
        .iter()
        .map(|sp| sp.units.len())
        .min()
        .unwrap_or(0);
    let formed = Formed {
        freq: prepared.spectra[0].freq_hz.clone(),
        frfs: frfs(&prepared.spectra, None),
        layout: Layout {
            outputs,
            inputs: records.len(),
        },
        points: &points,
        exp,
        band_hz,
        unit_sizes: (0..groups)
            .map(|g| {
                let per = |sp: &Spectra| group(g, groups, sp.units.len()).len();
                prepared.spectra.iter().map(per).sum()
            })
            .collect(),
        unit: "group of hits",
        without: &|g| frfs(&prepared.spectra, Some((g, groups))).h1,
    };
    let mut r = identify(formed, s, notes)?;
    r.hits = prepared.hits.first().cloned();
    r.roving = prepared.hits;
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::modal::{mac, FrfForm};
    use crate::oma::cluster::ClusterRule;
    use crate::oma::lscf::LscfRule;
    use num_complex::Complex64;
    use rand::SeedableRng as _;
    use rand_distr::{Distribution as _, Normal};
    use vibcam_model::hammer::{HammerTest, Hit, THREE_MODE_POINTS};

    const FS: f64 = 2000.0;

    /// The closed-form test hit at `drive` (0-based) three times, 3 s apart, its force and
    /// the displacements (mm) of `outputs`, with a little noise.
    fn record(drive: usize, outputs: &[usize], seed: u64) -> (Vec<f64>, Vec<Vec<f64>>) {
        let hits = Hit::every_3_s(&[150.0, 120.0, 180.0]);
        let test = HammerTest {
            drive,
            ..HammerTest::three_modes(hits)
        };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let noise = Normal::new(0.0, 1.0).unwrap();
        let n = (9.2 * FS) as usize;
        // the force sampled at the camera's rate, its pulse as a DAQ averaging over a sample
        let force: Vec<f64> = (0..n)
            .map(|k| {
                let t = k as f64 / FS;
                (0..20)
                    .map(|q| test.force(t + q as f64 / (20.0 * FS)))
                    .sum::<f64>()
                    / 20.0
                    + 0.05 * noise.sample(&mut rng)
            })
            .collect();
        let responses = outputs
            .iter()
            .map(|&o| {
                (0..n)
                    .map(|k| {
                        1e3 * test.displacement(o, k as f64 / FS) + 2e-5 * noise.sample(&mut rng)
                    })
                    .collect()
            })
            .collect();
        (force, responses)
    }

    fn settings() -> EmaSettings {
        EmaSettings {
            excitation: Excitation::Impact {
                rule: ImpactRule::default(),
                exp: super::super::ExpChoice::Auto,
            },
            form: FrfForm::Receptance,
            band_hz: (0.0, 0.4 * FS),
            band_from_data: (true, true),
            bands: None,
            lscf: LscfRule::default(),
            cluster: ClusterRule::default(),
            poles: None,
        }
    }

    fn check(outputs: &[usize], over_hit_points: bool) {
        let truth = HammerTest::three_modes(Vec::new());
        let recs: Vec<(Vec<f64>, Vec<Vec<f64>>)> = (0..THREE_MODE_POINTS)
            .map(|d| record(d, outputs, d as u64 + 1))
            .collect();
        let names: Vec<String> = (0..THREE_MODE_POINTS)
            .map(|d| format!("hit{}.csv", d + 1))
            .collect();
        let records: Vec<Record> = recs
            .iter()
            .zip(&names)
            .enumerate()
            .map(|(d, ((f, x), name))| Record {
                force: f,
                responses: x,
                point: d + 1,
                name,
            })
            .collect();
        let r = analyse(&records, FS, &settings()).unwrap();
        assert_eq!(r.layout.over_inputs(), over_hit_points);
        assert_eq!(r.roving.len(), THREE_MODE_POINTS);
        assert_eq!(r.frfs.h1.len(), outputs.len() * THREE_MODE_POINTS);
        assert_eq!(r.modes.len(), 3, "{:?} {:?}", r.modes, r.notes);
        for (m, t) in r.modes.iter().zip(&truth.modes) {
            let df = (m.pole.f_hz - t.f_hz).abs() / t.f_hz;
            let dz = (m.pole.damping - t.damping).abs() / t.damping;
            assert!(df < 0.002, "{} against {}", m.pole.f_hz, t.f_hz);
            assert!(dz < 0.1, "{} against {}", m.pole.damping, t.damping);
            // the shape over the hit points (or the responses): the true shape there
            let at: Vec<Complex64> = if over_hit_points {
                t.shape.iter().map(|&v| Complex64::new(v, 0.0)).collect()
            } else {
                outputs
                    .iter()
                    .map(|&o| Complex64::new(t.shape[o], 0.0))
                    .collect()
            };
            let mac = mac(&m.shape, &at);
            assert!(mac > 0.999, "mode {} MAC {mac}", m.mode);
            let fi = m.f_interval.expect("an interval from three groups of hits");
            assert!(fi.lo <= m.pole.f_hz && m.pole.f_hz <= fi.hi);
        }
        super::super::assert_noted(&r.notes, "roving hammer: 5 records");
    }

    #[test]
    fn a_roving_hammer_with_one_transducer_gives_the_shapes_over_the_hit_points() {
        check(&[3], true);
    }

    #[test]
    fn a_roving_hammer_filmed_at_every_point_gives_the_shapes_over_the_points() {
        check(&[0, 1, 2, 3, 4], false);
    }

    #[test]
    fn records_with_other_responses_or_a_point_twice_are_refused() {
        let (f, x) = record(0, &[3], 1);
        let (g, y) = record(1, &[2, 3], 2);
        let a = Record {
            force: &f,
            responses: &x,
            point: 1,
            name: "a.csv",
        };
        let b = Record {
            force: &g,
            responses: &y,
            point: 2,
            name: "b.csv",
        };
        let e = analyse(&[a, b], FS, &settings()).unwrap_err().to_string();
        assert!(e.contains("b.csv: 2 responses where a.csv has 1"), "{e}");
        let e = analyse(&[a, Record { point: 1, ..a }], FS, &settings())
            .unwrap_err()
            .to_string();
        assert!(e.contains("hit point 1 is given twice"), "{e}");
    }
}
