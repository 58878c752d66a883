//! Experimental modal analysis with a measured force (`ema`, docs/method.md §3.13): FRFs of the
//! responses (a camera's displacements, a DAQ's transducers) over the force, from the hits of
//! an impact test ([`impact`]) or Welch segments of a continuous one ([`spectra`]); poles by
//! LSCF with a stabilisation diagram ([`lscf`]), its stable poles grouped into modes by the
//! rules of `modal`'s SSI ([`crate::oma::cluster`]); residues and mode shapes by LSFD
//! with residual terms ([`lsfd`]); each mode's interval by the jackknife over the hits or the
//! segment groups.

pub mod excited;
pub mod impact;
pub use crate::oma::lscf;
pub mod lsfd;
pub mod mimo;
pub mod roving;
pub mod spectra;

use crate::modal::{mac, normalise_shape, FrfForm, Pole};
use crate::oma::cluster::{cluster, ClusterRule, Rejected, SsiMode};
use crate::oma::ssi;
use crate::oma::uncertainty::{jackknife_sized, Interval};
use impact::{ExpWindow, Hits, ImpactRule};
use num_complex::Complex64;
use spectra::{Frfs, Spectra};

/// Asserts that one of `notes` holds `needle` (the tests of several modules).
#[cfg(test)]
fn assert_noted(notes: &[String], needle: &str) {
    assert!(
        notes.iter().any(|n| n.contains(needle)),
        "`{needle}` in none of {notes:?}"
    );
}

/// The exponential window of an impact test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ExpChoice {
    /// None.
    Off,
    /// Applied when the responses have not decayed by their block's end (over the lines the
    /// hits excited, [`excited`], more than 5 % of the amplitude left in the block's last
    /// quarter; without such lines, the RMS of the last tenth above 5 % of the largest
    /// excursion), ending at 1 %.
    Auto,
    /// Applied, its value at the block's end this (0 < end < 1).
    End(f64),
}

/// How the structure was excited.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Excitation {
    /// Hits of a hammer.
    Impact {
        /// Hit finding.
        rule: ImpactRule,
        /// The exponential window.
        exp: ExpChoice,
    },
    /// A continuous force (shaker, random): Welch segments.
    Continuous {
        /// Samples per segment.
        nperseg: usize,
    },
}

/// What the analysis is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct EmaSettings {
    /// The excitation.
    pub excitation: Excitation,
    /// Displacement, velocity or acceleration over force.
    pub form: FrfForm,
    /// The band the poles and residues are fitted in, Hz; with `band_from_data`, the outer
    /// limits of the band chosen.
    pub band_hz: (f64, f64),
    /// Choose the band's lower and upper end inside `band_hz` from the data (each end not
    /// given): from an impact test's excited lines ([`excited::Excited::band`]), said in the
    /// notes.
    pub band_from_data: (bool, bool),
    /// One mode per band (none: every mode the stabilisation diagram shows).
    pub bands: Option<Vec<(f64, f64)>>,
    /// LSCF's orders and stability rules.
    pub lscf: lscf::LscfRule,
    /// The clustering of stable poles into modes.
    pub cluster: ClusterRule,
    /// Poles given (picked by hand on the stabilisation diagram, or an earlier `modes.csv`):
    /// exactly these modes, the structure's poles (an exponential window's damping added back
    /// before they are fitted), instead of the clusters; none: the clusters.
    pub poles: Option<Vec<Pole>>,
}

/// One mode found.
#[derive(Debug, Clone, PartialEq)]
pub struct EmaMode {
    /// Number, 1-based, ascending frequency.
    pub mode: usize,
    /// Its band (with bands).
    pub band_hz: Option<(f64, f64)>,
    /// The pole, the exponential window's damping removed.
    pub pole: Pole,
    /// The pole of the (windowed) FRFs.
    pub fitted: Pole,
    /// The shape: residues normalised (largest component 1).
    pub shape: Vec<Complex64>,
    /// Its cluster of stable poles.
    pub cluster: SsiMode,
    /// Interval of the frequency.
    pub f_interval: Option<Interval>,
    /// Interval of the damping ratio.
    pub damping_interval: Option<Interval>,
    /// Standard uncertainty of each shape component's magnitude.
    pub shape_abs_u: Option<Vec<f64>>,
}

/// How a test's FRFs stand: `outputs` responses for each of `inputs` hit points (references),
/// FRF `j * outputs + o` the response `o` over the force at hit point `j`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    /// Responses.
    pub outputs: usize,
    /// Hit points (forces): 1 but for a roving hammer ([`roving`]).
    pub inputs: usize,
}

impl Layout {
    /// The shape is given over the hit points: there are more of them than responses (a roving
    /// hammer with one fixed transducer); else over the responses.
    pub fn over_inputs(&self) -> bool {
        self.inputs > self.outputs
    }

    /// The references of the LSCF fit: the fewer of responses and hit points (one: the
    /// common denominator; several: the poly-reference model, docs/method.md §3.13).
    pub fn references(&self) -> usize {
        self.outputs.min(self.inputs)
    }

    /// A mode's shape vector from its residues in every FRF: with one hit point, the residues;
    /// else the dominant singular vector of the residue matrix `A = phi L^T` (outputs x inputs,
    /// of rank one), over the responses or, by [`Layout::over_inputs`], over the hit points
    /// (`L`, equal to `phi` at those points when the structure is reciprocal).
    pub fn vector(&self, residues: &[Complex64]) -> Vec<Complex64> {
        if self.inputs <= 1 || residues.len() != self.outputs * self.inputs {
            return residues.to_vec();
        }
        let a = nalgebra::DMatrix::from_fn(self.outputs, self.inputs, |o, j| {
            residues[j * self.outputs + o]
        });
        let svd = a.svd(true, true);
        let best = (0..svd.singular_values.len())
            .max_by(|&x, &y| svd.singular_values[x].total_cmp(&svd.singular_values[y]))
            .unwrap_or(0);
        let sigma = svd.singular_values[best];
        if self.over_inputs() {
            // A = u s v^H: L^T is s times the row of v^H, phi's scale aside
            svd.v_t.map_or_else(Vec::new, |vt| {
                (0..self.inputs).map(|j| vt[(best, j)] * sigma).collect()
            })
        } else {
            svd.u.map_or_else(Vec::new, |u| {
                (0..self.outputs).map(|o| u[(o, best)] * sigma).collect()
            })
        }
    }

    /// FRF `k` named for a reader: "response 2", with several hit points "response 2 at
    /// hit point 3" (`points`: the hit points' numbers), with several forces at once (no
    /// points) "response 2 over force 1".
    pub fn frf_name(&self, k: usize, points: &[usize]) -> String {
        let o = k % self.outputs.max(1) + 1;
        let j = k / self.outputs.max(1);
        match points.get(j) {
            _ if self.inputs <= 1 => format!("response {o}"),
            Some(p) => format!("response {o} at hit point {p}"),
            None => format!("response {o} over force {}", j + 1),
        }
    }
}

/// What the analysis found.
#[derive(Debug, Clone)]
pub struct EmaResult {
    /// The FRFs' lines, Hz.
    pub freq_hz: Vec<f64>,
    /// H1, H2 and coherence of all units.
    pub frfs: Frfs,
    /// Every pole of the stabilisation diagram.
    pub poles: Vec<ssi::Pole>,
    /// The clusters: reported (true) or rejected.
    pub clusters: Vec<(SsiMode, bool)>,
    /// Clusters rejected, with the reason.
    pub rejected: Vec<Rejected>,
    /// The modes.
    pub modes: Vec<EmaMode>,
    /// LSFD's constants per response (residues in mode order).
    pub constants: Vec<lsfd::Constants>,
    /// The FRFs' layout (responses, hit points); the shapes are over the responses or over
    /// the hit points ([`Layout::over_inputs`]).
    pub layout: Layout,
    /// The hits (impact; a roving hammer's: those of its first record).
    pub hits: Option<Hits>,
    /// A roving hammer's hits, per record (empty for one record).
    pub roving: Vec<Hits>,
    /// The exponential window applied.
    pub exp: Option<ExpWindow>,
    /// The band fitted, Hz (`band_hz` of the settings, or the one chosen from the data).
    pub band_hz: (f64, f64),
    /// Units averaged (hits or segment groups) and their sizes.
    pub unit_sizes: Vec<usize>,
    /// What the reader should know.
    pub notes: Vec<String>,
}

impl EmaResult {
    /// The structure's pole behind a pole of the diagram (`poles`): the exponential window's
    /// damping removed, what `EmaSettings::poles` takes back.
    pub fn structure_pole(&self, p: &ssi::Pole) -> Pole {
        unwindowed(
            Pole {
                f_hz: p.f_hz,
                damping: p.damping,
            },
            self.exp,
        )
    }
}

/// The largest ratio, over responses and used hits, of the RMS of a block's last tenth to its
/// largest excursion (each less its mean before the pulse).
fn undecayed(responses: &[Vec<f64>], hits: &Hits) -> f64 {
    let n = hits.block;
    let mut worst = 0.0f64;
    for hit in hits.used() {
        let s = hits.block_start(hit);
        for x in responses {
            let b = &x[s..s + n];
            let pre = hits.pre.max(1);
            let mean = b[..pre].iter().sum::<f64>() / pre as f64;
            let peak = b.iter().fold(0.0f64, |a, v| a.max((v - mean).abs()));
            let tail = &b[n - n / 10..];
            let rms =
                (tail.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / tail.len() as f64).sqrt();
            if peak > 0.0 {
                worst = worst.max(rms / peak);
            }
        }
    }
    worst
}

/// What [`select`] finds: every pole, the modes (clusters reported), the clusters rejected,
/// and the mode of each band (every mode, without bands).
struct Selection {
    poles: Vec<ssi::Pole>,
    modes: Vec<SsiMode>,
    rejected: Vec<Rejected>,
    per_band: Vec<Option<SsiMode>>,
}

/// The largest ratio, over responses and used hits, of a response's RMS before its block's
/// pulse to its largest excursion after it: a response that moves before the force hits is
/// ahead of it in time (the records are not aligned).
fn precursor(responses: &[Vec<f64>], hits: &Hits) -> f64 {
    let mut worst = 0.0f64;
    if hits.pre < 8 {
        return 0.0;
    }
    for hit in hits.used() {
        let s = hits.block_start(hit);
        for x in responses {
            let b = &x[s..s + hits.block];
            let pre = &b[..hits.pre];
            let mean = pre.iter().sum::<f64>() / pre.len() as f64;
            let rms =
                (pre.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / pre.len() as f64).sqrt();
            let peak = b[hits.pre..]
                .iter()
                .fold(0.0f64, |a, v| a.max((v - mean).abs()));
            if peak > 0.0 {
                worst = worst.max(rms / peak);
            }
        }
    }
    worst
}

/// The poles of `h1` and the modes among them: every stable cluster, or per band the fullest
/// reported cluster in it (`None` where a band has none).
fn select(
    freq_hz: &[f64],
    h1: &[Vec<Complex64>],
    layout: Layout,
    s: &EmaSettings,
) -> anyhow::Result<Selection> {
    let poles = layout_poles(freq_hz, h1, layout, s)?;
    let (modes, rejected) = cluster(&poles, s.cluster);
    let per_band = match &s.bands {
        None => modes.iter().cloned().map(Some).collect(),
        Some(bands) => bands
            .iter()
            .map(|&(lo, hi)| {
                modes
                    .iter()
                    .filter(|m| m.f_hz >= lo && m.f_hz <= hi)
                    .max_by_key(|m| m.poles)
                    .cloned()
            })
            .collect(),
    };
    Ok(Selection {
        poles,
        modes,
        rejected,
        per_band,
    })
}

/// The LSCF poles of the FRFs `h1` (input-major, as `layout` says): with one hit point or one
/// response the common denominator over every FRF, else the poly-reference LSCF with the
/// fewer of forces and responses as references (the matrix transposed when the hit points
/// are more, by reciprocity), so that the poles' shapes are over [`Layout::over_inputs`]'s
/// side (docs/method.md §3.13).
fn layout_poles(
    freq_hz: &[f64],
    h1: &[Vec<Complex64>],
    layout: Layout,
    s: &EmaSettings,
) -> anyhow::Result<Vec<ssi::Pole>> {
    let Layout { outputs, inputs } = layout;
    if layout.references() <= 1 || h1.len() != outputs * inputs {
        return lscf::poles(freq_hz, h1, s.band_hz, s.lscf);
    }
    if layout.over_inputs() {
        // h1[j * outputs + o]: rows are the hit points, the responses the references
        return lscf::poles_matrix(freq_hz, h1, outputs, s.band_hz, s.lscf);
    }
    let by_response: Vec<Vec<Complex64>> = (0..outputs * inputs)
        .map(|oj| h1[(oj % inputs) * outputs + oj / inputs].clone())
        .collect();
    lscf::poles_matrix(freq_hz, &by_response, inputs, s.band_hz, s.lscf)
}

/// One replicate of a mode: its pole and residues (`None`: not found without that unit).
type Replicate = Option<(Pole, Vec<Complex64>)>;

/// A pole from a cluster's median frequency and damping.
fn pole_of(m: &SsiMode) -> Pole {
    Pole {
        f_hz: m.f_hz,
        damping: m.damping,
    }
}

/// `p` with its real part moved by `by` (1/s): the exponential window's shift.
fn shifted(p: Pole, by: f64) -> Pole {
    let s = p.s();
    let s = Complex64::new(s.re + by, s.im);
    let wn = s.norm();
    Pole {
        f_hz: wn / (2.0 * std::f64::consts::PI),
        damping: -s.re / wn,
    }
}

/// `p` as the exponential window `exp` shows it ([`unwindowed`]'s inverse).
fn windowed(p: Pole, exp: Option<ExpWindow>) -> Pole {
    exp.map_or(p, |w| shifted(p, w.pole_shift()))
}

/// `p` with the exponential window's shift of the real part undone.
fn unwindowed(p: Pole, exp: Option<ExpWindow>) -> Pole {
    exp.map_or(p, |w| shifted(p, -w.pole_shift()))
}

/// The analysis of `force` and `responses` (one rate `fs_hz`); `force_name` names the force in
/// errors.
pub fn analyse(
    force: &[f64],
    responses: &[Vec<f64>],
    fs_hz: f64,
    force_name: &str,
    s: &EmaSettings,
) -> anyhow::Result<EmaResult> {
    let mut notes = Vec::new();
    let Prepared {
        spectra,
        hits,
        exp,
        band_hz,
    } = prepare(force, responses, fs_hz, force_name, s, &mut notes)?;
    let formed = Formed {
        freq: spectra.freq_hz.clone(),
        frfs: spectra.frfs(None),
        layout: Layout {
            outputs: responses.len(),
            inputs: 1,
        },
        points: &[],
        exp,
        band_hz,
        unit_sizes: spectra.units.iter().map(|u| u.size).collect(),
        unit: hits.as_ref().map_or("segment group", |_| "hit"),
        without: &|g| spectra.frfs(Some(g)).h1,
    };
    let mut r = identify(formed, s, notes)?;
    r.hits = hits;
    Ok(r)
}

/// The FRFs of a test and what they were formed with: their lines, layout and hit points
/// (none for one test), the exponential window, the band, the jackknife's units (their sizes,
/// their name, and the FRFs without each).
struct Formed<'a> {
    freq: Vec<f64>,
    frfs: Frfs,
    layout: Layout,
    points: &'a [usize],
    exp: Option<ExpWindow>,
    band_hz: (f64, f64),
    unit_sizes: Vec<usize>,
    unit: &'static str,
    without: Without<'a>,
}

/// The modes of FRFs `f` formed (one test's or a roving hammer's): the poles of the
/// stabilisation diagram, the modes chosen (clusters, bands or poles given), their residues
/// and shapes, their intervals; `notes` so far, the result's (no hits: the caller's).
fn identify(f: Formed, s: &EmaSettings, mut notes: Vec<String>) -> anyhow::Result<EmaResult> {
    let s = &EmaSettings {
        band_hz: f.band_hz,
        ..s.clone()
    };
    given_in_band(s, f.exp)?;
    let Selection {
        poles,
        modes: mut all,
        mut rejected,
        per_band,
    } = select(&f.freq, &f.frfs.h1, f.layout, s)?;
    let mut chosen = s.poles.as_ref().map_or_else(
        || chosen_modes(per_band, s.bands.as_deref(), &mut notes),
        |given| given_modes(given, f.exp, &poles),
    );
    let (fitted, constants) = fit_without_twins(&f, s, &mut chosen, (&mut all, &mut rejected))?;
    let units = f.unit_sizes.len();
    let reps = if units >= 3 && !fitted.is_empty() {
        replicates((units, f.without), &f.freq, &fitted, s, f.layout)
    } else {
        no_replicates(units, &fitted, f.unit, &mut notes)
    };
    let modes = modes_of(
        chosen,
        &fitted,
        &constants,
        (&reps, &f.unit_sizes, f.unit),
        (f.exp, f.layout),
        &mut notes,
    );
    notes.extend(misfit_note(
        &f.freq,
        &f.frfs.h1,
        s,
        &fitted,
        (&constants, f.layout, f.points),
    ));
    let clusters = all
        .into_iter()
        .map(|m| (m, true))
        .chain(rejected.iter().map(|r| (r.cluster.clone(), false)))
        .collect();
    Ok(EmaResult {
        freq_hz: f.freq,
        frfs: f.frfs,
        poles,
        clusters,
        rejected,
        modes,
        constants,
        layout: f.layout,
        hits: None,
        roving: Vec::new(),
        exp: f.exp,
        band_hz: f.band_hz,
        unit_sizes: f.unit_sizes,
        notes,
    })
}

/// The chosen modes' poles and LSFD constants, each mode that is another's [`twin`] dropped
/// (to `rejected`, and out of `all`) and the rest fitted again; poles given are all kept.
fn fit_without_twins(
    f: &Formed,
    s: &EmaSettings,
    chosen: &mut Vec<(Option<(f64, f64)>, SsiMode)>,
    (all, rejected): (&mut Vec<SsiMode>, &mut Vec<Rejected>),
) -> anyhow::Result<(Vec<Pole>, Vec<lsfd::Constants>)> {
    loop {
        let fitted: Vec<Pole> = chosen.iter().map(|(_, m)| pole_of(m)).collect();
        let constants = if fitted.is_empty() {
            Vec::new()
        } else {
            lsfd::fit(&f.freq, &f.frfs.h1, s.band_hz, &fitted, s.form)?
        };
        let twin = match s.poles {
            Some(_) => None,
            None => twin(chosen, &constants, f.layout),
        };
        let Some(t) = twin else {
            return Ok((fitted, constants));
        };
        let (_, c) = chosen.remove(t.drop);
        all.retain(|m| m != &c);
        rejected.push(Rejected {
            cluster: c,
            reason: t.reason,
        });
        rejected.sort_by(|a, b| a.cluster.f_hz.total_cmp(&b.cluster.f_hz));
    }
}

/// A mode chosen that is another's second pole: which to drop, and why.
struct Twin {
    drop: usize,
    reason: String,
}

/// Of the modes `chosen` and their LSFD `constants`, one whose residues give the shape (MAC
/// at least 0.9, as [`Layout::vector`] takes it) of a fuller cluster's mode within five of its
/// half-power bandwidths: the fitted model's second pole for one mode of the structure (the
/// poly-reference model, with a matrix denominator, can place one beside a mode's own on noisy
/// FRFs; its shape across the orders is noise, so the clusters' own rule does not see it).
/// Two close modes of the structure have shapes of their own and are kept.
fn twin(
    chosen: &[(Option<(f64, f64)>, SsiMode)],
    constants: &[lsfd::Constants],
    layout: Layout,
) -> Option<Twin> {
    if constants.is_empty() {
        return None;
    }
    let shapes: Vec<Vec<Complex64>> = (0..chosen.len())
        .map(|i| layout.vector(&constants.iter().map(|c| c.residues[i]).collect::<Vec<_>>()))
        .collect();
    for i in 0..chosen.len() {
        for j in i + 1..chosen.len() {
            let (a, b) = (&chosen[i].1, &chosen[j].1);
            let (fuller, other) = if a.poles >= b.poles { (i, j) } else { (j, i) };
            let (m, c) = (&chosen[fuller].1, &chosen[other].1);
            let within = (m.f_hz - c.f_hz).abs() <= 5.0 * 2.0 * m.damping.max(c.damping) * m.f_hz;
            let same = mac(&shapes[i], &shapes[j]);
            if within && same >= 0.9 {
                return Some(Twin {
                    drop: other,
                    reason: format!(
                        "LSFD gives it the shape of the {:.4} Hz mode (MAC {same:.3}), a fuller \
                         column ({} poles) within five of its half-power bandwidths: a second \
                         pole of the fitted model for that mode",
                        m.f_hz, m.poles
                    ),
                });
            }
        }
    }
    None
}

/// A note when the fitted model leaves over a fifth of an FRF unexplained, with the cause the
/// residual points to: spread over the band as a noise floor is, or gathered at a mode.
fn misfit_note(
    freq: &[f64],
    h1: &[Vec<Complex64>],
    s: &EmaSettings,
    poles: &[Pole],
    (constants, layout, points): (&[lsfd::Constants], Layout, &[usize]),
) -> Option<String> {
    if constants.is_empty() {
        return None;
    }
    let r = &lsfd::residual(freq, h1, s.band_hz, poles, s.form, constants);
    let (worst, misfit) = r.worst;
    if misfit <= 0.2 {
        return None;
    }
    let cause = match r.at_pole.map(|p| poles[p].f_hz) {
        _ if r.below.0 >= 0.5 => format!(
            "{:.0} % of the residual lies below the lowest mode's peak ({:.0} Hz): a rigid-body \
             or suspension motion there, or a mode below it, that the lower residual term does \
             not follow; $f_min_hz above it fits the modes alone",
            100.0 * r.below.0,
            r.below.1
        ),
        Some(f) if r.near_over_far >= 3.0 => format!(
            "the residual gathers at the modes (per line {:.0} times elsewhere, most at {f:.1} \
             Hz): the model misses there: a delay between the records ($delay_s), a mode not \
             found or split, or the band cutting a mode ($f_min_hz, $f_max_hz, $bands)",
            r.near_over_far
        ),
        _ => format!(
            "the residual is spread over the band as a noise floor is (per line near the modes \
             {:.1} times elsewhere), not gathered at the modes: the FRFs are noisy between their \
             peaks; more hits averaged or a narrower band ($f_min_hz, $f_max_hz, $bands) lower \
             it",
            r.near_over_far
        ),
    };
    Some(format!(
        "the fitted model leaves {:.0} % of {}'s FRF unexplained (LSFD misfit \
         {misfit:.3}; {:.0} % over all responses): {cause}; the numbers above are doubtful",
        100.0 * misfit,
        layout.frf_name(worst, points),
        100.0 * r.overall
    ))
}

/// No replicates (noted when there are modes): `units` (hits or segment groups) are fewer than
/// the jackknife's 3.
fn no_replicates(
    units: usize,
    fitted: &[Pole],
    unit: &str,
    notes: &mut Vec<String>,
) -> Vec<Vec<Replicate>> {
    if !fitted.is_empty() {
        notes.push(format!(
            "no intervals: {units} {unit}s averaged, the jackknife needs at least 3"
        ));
    }
    vec![Vec::new(); fitted.len()]
}

/// The modes chosen: one per band (a band without one noted), or every cluster per band found.
fn chosen_modes(
    per_band: Vec<Option<SsiMode>>,
    bands: Option<&[(f64, f64)]>,
    notes: &mut Vec<String>,
) -> Vec<(Option<(f64, f64)>, SsiMode)> {
    if let Some(bands) = bands {
        for (b, m) in bands.iter().zip(&per_band) {
            if m.is_none() {
                notes.push(format!(
                    "band {}-{} Hz: no mode (no cluster of stable poles there)",
                    b.0, b.1
                ));
            }
        }
    }
    match bands {
        None => per_band.into_iter().flatten().map(|m| (None, m)).collect(),
        Some(bands) => bands
            .iter()
            .zip(per_band)
            .filter_map(|(b, m)| m.map(|m| (Some(*b), m)))
            .collect(),
    }
}

/// The poles given lie in the band fitted (`s.band_hz`), as the window `exp` moves them.
fn given_in_band(s: &EmaSettings, exp: Option<ExpWindow>) -> anyhow::Result<()> {
    if let Some(p) = s.poles.iter().flatten().find(|p| {
        let f = windowed(**p, exp).f_hz;
        f < s.band_hz.0 || f > s.band_hz.1
    }) {
        return Err(vibcam_readers::bad_input(format!(
            "$poles: the pole at {} Hz lies outside the band fitted, {:.1}-{:.1} Hz ($f_min_hz, \
             $f_max_hz)",
            p.f_hz, s.band_hz.0, s.band_hz.1
        )));
    }
    Ok(())
}

/// The modes of the poles `given` (the structure's): each as a cluster of its own, the pole of
/// the windowed FRFs (`exp`'s decay added back), its count the diagram's stable poles within
/// 1 % of it; MPC and MPD follow from its LSFD shape ([`modes_of`]).
fn given_modes(
    given: &[Pole],
    exp: Option<ExpWindow>,
    diagram: &[ssi::Pole],
) -> Vec<(Option<(f64, f64)>, SsiMode)> {
    given
        .iter()
        .map(|p| {
            let w = windowed(*p, exp);
            let near = diagram
                .iter()
                .filter(|q| q.stable && (q.f_hz - w.f_hz).abs() <= 0.01 * w.f_hz)
                .count();
            let mode = SsiMode {
                f_hz: w.f_hz,
                damping: w.damping,
                shape: Vec::new(),
                poles: near,
                f_spread: 0.0,
                damping_spread: 0.0,
                mpc: f64::NAN,
                mpd_deg: f64::NAN,
                orders: (0, 0),
                members: Vec::new(),
            };
            (None, mode)
        })
        .collect()
}

/// Each chosen mode with its pole (the exponential window's damping removed), its shape from
/// the LSFD residues (by `layout`, [`Layout::vector`]) and its intervals from the replicates
/// (`unit`: what one replicate leaves out; their shapes already by `layout`).
fn modes_of(
    chosen: Vec<(Option<(f64, f64)>, SsiMode)>,
    fitted: &[Pole],
    constants: &[lsfd::Constants],
    (reps, unit_sizes, unit): (&[Vec<Replicate>], &[usize], &str),
    (exp, layout): (Option<ExpWindow>, Layout),
    notes: &mut Vec<String>,
) -> Vec<EmaMode> {
    let mut modes = Vec::new();
    for (i, ((band, cl), p)) in chosen.into_iter().zip(fitted).enumerate() {
        let residues = layout.vector(&constants.iter().map(|c| c.residues[i]).collect::<Vec<_>>());
        let shape = normalise_shape(&residues);
        let pole = unwindowed(*p, exp);
        let (fi, di, su) = match intervals(pole, (&residues, &shape), &reps[i], exp, unit_sizes) {
            Some(v) => v,
            None => {
                notes.push(format!(
                    "mode {} ({:.4} Hz): no interval, it was not found with every {} left out",
                    i + 1,
                    pole.f_hz,
                    unit
                ));
                (None, None, None)
            }
        };
        let mut cl = cl;
        if cl.mpc.is_nan() {
            // a pole given: its shape is LSFD's
            cl.mpc = crate::oma::cluster::mpc(&shape);
            cl.mpd_deg = crate::oma::cluster::mpd_deg(&shape);
        }
        modes.push(EmaMode {
            mode: i + 1,
            band_hz: band,
            pole,
            fitted: *p,
            shape,
            cluster: cl,
            f_interval: fi,
            damping_interval: di,
            shape_abs_u: su,
        });
    }
    modes
}

/// The spectra a test's FRFs are formed from, and what was decided on the way.
struct Prepared {
    spectra: Spectra,
    hits: Option<Hits>,
    exp: Option<ExpWindow>,
    band_hz: (f64, f64),
}

/// The spectra of the test `s` describes, an impact's or a continuous force's.
fn prepare(
    force: &[f64],
    responses: &[Vec<f64>],
    fs_hz: f64,
    force_name: &str,
    s: &EmaSettings,
    notes: &mut Vec<String>,
) -> anyhow::Result<Prepared> {
    match s.excitation {
        Excitation::Impact { rule, exp } => {
            impact_spectra(force, responses, fs_hz, (force_name, rule, exp), s, notes)
        }
        Excitation::Continuous { nperseg } => {
            continuous_spectra(force, responses, fs_hz, nperseg, s, notes)
        }
    }
}

/// The spectra of an impact test, hit by hit: the hits found, the band (from what they excited
/// when `s.band_from_data`) and the exponential window chosen; notes say both, and when the
/// responses have not decayed or move before the pulses.
fn impact_spectra(
    force: &[f64],
    responses: &[Vec<f64>],
    fs_hz: f64,
    (force_name, rule, exp): (&str, ImpactRule, ExpChoice),
    s: &EmaSettings,
    notes: &mut Vec<String>,
) -> anyhow::Result<Prepared> {
    let hits = impact::find(force, fs_hz, rule, force_name)?;
    let block_s = hits.block as f64 / fs_hz;
    let ex = excited::excited(responses, &hits, fs_hz, s.band_hz);
    let band_hz = match &ex {
        Some(e) if s.band_from_data.0 || s.band_from_data.1 => {
            band_note(e, s.band_hz, s.band_from_data, notes)
        }
        _ => s.band_hz,
    };
    let (ratio, why) = match &ex {
        Some(e) if e.lines > 0 => (
            e.undecayed,
            format!(
                "{:.0} % of the excited lines' amplitude is left in the block's last quarter{}",
                100.0 * e.undecayed,
                e.undecayed_at_hz
                    .map(|f| format!(", most at {f:.0} Hz"))
                    .unwrap_or_default()
            ),
        ),
        _ => {
            let r = undecayed(responses, &hits);
            let why = format!(
                "the last tenth's RMS is {:.0} % of the largest excursion",
                100.0 * r
            );
            (r, why)
        }
    };
    let window = match exp {
        ExpChoice::Off => None,
        ExpChoice::End(e) => Some(ExpWindow::ending_at(e, block_s)),
        ExpChoice::Auto if ratio > 0.05 => Some(ExpWindow::ending_at(0.01, block_s)),
        ExpChoice::Auto => None,
    };
    match (window.is_some(), ratio > 0.05, exp) {
        (false, true, _) => notes.push(format!(
            "the responses have not decayed by the blocks' end ({why}) and no exponential \
             window was applied: leakage widens the peaks and raises the damping"
        )),
        (true, true, ExpChoice::Auto) => notes.push(format!(
            "exponential window applied: the responses have not decayed by the blocks' end \
             ({why}); $exp_window off to leave it out"
        )),
        (false, false, ExpChoice::Auto) => notes.push(format!(
            "no exponential window: the responses decayed within the blocks ({why})"
        )),
        _ => {}
    }
    let ahead = precursor(responses, &hits);
    if ahead > 0.1 {
        notes.push(format!(
            "the responses move before the force's pulses (their RMS before a pulse is \
             {:.0} % of their largest excursion after it): the records are not aligned; \
             give the delay between their starts ($delay_s, delay_s in Python)",
            100.0 * ahead
        ));
    }
    let sp = spectra::of_hits(force, responses, fs_hz, &hits, window, band_hz.1 * 1.05)?;
    Ok(Prepared {
        spectra: sp,
        hits: Some(hits),
        exp: window,
        band_hz,
    })
}

/// Each end of a band: `chosen`'s where `free` (not given), `outer`'s where given.
fn free_ends(free: (bool, bool), chosen: (f64, f64), outer: (f64, f64)) -> (f64, f64) {
    (
        if free.0 { chosen.0 } else { outer.0 },
        if free.1 { chosen.1 } else { outer.1 },
    )
}

/// The band fitted: each end `free` chosen from what the hits excited inside `outer`, the
/// others `outer`'s (said in `notes`); `outer` when nothing stands out.
fn band_note(
    e: &excited::Excited,
    outer: (f64, f64),
    free: (bool, bool),
    notes: &mut Vec<String>,
) -> (f64, f64) {
    match (e.span_hz, e.band(outer)) {
        (Some((lo, hi)), Some(b)) => {
            let band = free_ends(free, b, outer);
            notes.push(format!(
                "band fitted {:.0}-{:.0} Hz, its ends not given chosen from the data: the \
                 responses stand {} dB above their noise after the hits and decay at \
                 {lo:.0}-{hi:.0} Hz ({} lines, the strongest {:.0} dB above the noise), widened \
                 by {}; $f_min_hz, $f_max_hz or $bands to choose",
                band.0,
                band.1,
                excited::ABOVE_FLOOR_DB,
                e.lines,
                e.peak_snr_db,
                excited::MARGIN
            ));
            band
        }
        _ => {
            notes.push(format!(
                "no line of the responses stands {} dB above their noise after the hits and \
                 decays: the whole band {:.0}-{:.0} Hz fitted; are the responses those of the \
                 structure hit?",
                excited::ABOVE_FLOOR_DB,
                outer.0,
                outer.1
            ));
            outer
        }
    }
}

/// The spectra of a continuous excitation over Welch segments in groups; a note when the force
/// looks like hammer hits.
fn continuous_spectra(
    force: &[f64],
    responses: &[Vec<f64>],
    fs_hz: f64,
    nperseg: usize,
    s: &EmaSettings,
    notes: &mut Vec<String>,
) -> anyhow::Result<Prepared> {
    let mean = force.iter().sum::<f64>() / force.len().max(1) as f64;
    let rms =
        (force.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / force.len().max(1) as f64).sqrt();
    let peak = force.iter().fold(0.0f64, |a, v| a.max((v - mean).abs()));
    if rms > 0.0 && peak > 10.0 * rms {
        notes.push(format!(
            "the force's peak is {:.0} times its RMS: it looks like hammer hits, not a \
             continuous force; an impact test is analysed hit by hit ($impact, \
             impact=True in Python)",
            peak / rms
        ));
    }
    let sp = spectra::of_segments(
        force,
        responses,
        fs_hz,
        nperseg,
        crate::oma::uncertainty::GROUPS,
        s.band_hz.1 * 1.05,
    )?;
    let band_hz = match s.band_from_data {
        (false, false) => s.band_hz,
        free => {
            let segments = sp.units.iter().map(|u| u.size).sum();
            coherent_band(
                (segments, &sp.freq_hz, &sp.frfs(None)),
                s.band_hz,
                free,
                notes,
            )
        }
    };
    Ok(Prepared {
        spectra: sp,
        hits: None,
        exp: None,
        band_hz,
    })
}

/// The band of a continuous test (`segments` averaged into the FRFs `frfs` at lines `freq`):
/// each end `free` chosen from where the responses follow the force
/// ([`excited::coherent_span`]) inside `outer`, the others `outer`'s (said in `notes`); `outer`
/// with too few segments or no coherent line.
fn coherent_band(
    (segments, freq, frfs): (usize, &[f64], &Frfs),
    outer: (f64, f64),
    free: (bool, bool),
    notes: &mut Vec<String>,
) -> (f64, f64) {
    if segments < excited::COHERENCE_SEGMENTS {
        notes.push(format!(
            "{segments} Welch segments: too few for the coherence to say where the responses \
             follow the force ({} at least); the whole band {:.1}-{:.1} Hz fitted",
            excited::COHERENCE_SEGMENTS,
            outer.0,
            outer.1
        ));
        return outer;
    }
    let Some((lo, hi, lines)) = excited::coherent_span(freq, &frfs.coherence, outer) else {
        notes.push(format!(
            "no line's coherence with the force reaches {} (the median over the responses): \
             the whole band {:.1}-{:.1} Hz fitted; are the responses those of the structure \
             driven?",
            excited::COHERENT,
            outer.0,
            outer.1
        ));
        return outer;
    };
    // not widened: a line beyond is one the force did not drive (its H1 is noise over
    // nothing)
    let band = free_ends(free, (lo, hi), outer);
    notes.push(format!(
        "band fitted {:.1}-{:.1} Hz, its ends not given chosen from the data: the responses' \
         coherence with the force (their median, over 5 lines) is at least {} at \
         {lo:.1}-{hi:.1} Hz ({lines} lines); $f_min_hz, $f_max_hz or $bands to choose",
        band.0,
        band.1,
        excited::COHERENT,
    ));
    band
}

/// The FRFs (H1) without one unit of the jackknife, by the unit's index.
type Without<'a> = &'a dyn Fn(usize) -> Vec<Vec<Complex64>>;

/// The jackknife's replicates: with every one of `units` units (hit, segment group, or a group
/// of hits of every record) left out in turn (`without` its FRFs), each fitted mode's pole
/// found again (within 2 %) and its LSFD residues as `layout` gives a shape's vector
/// ([`Layout::vector`]), or `None`.
fn replicates(
    (units, without): (usize, Without),
    freq: &[f64],
    fitted: &[Pole],
    s: &EmaSettings,
    layout: Layout,
) -> Vec<Vec<Replicate>> {
    let mut reps: Vec<Vec<Replicate>> = vec![Vec::new(); fitted.len()];
    for g in 0..units {
        let h1 = without(g);
        let got = select(freq, &h1, layout, s).ok();
        let matched: Vec<Option<Pole>> = fitted
            .iter()
            .map(|p| {
                got.as_ref().and_then(|sel| {
                    sel.modes
                        .iter()
                        .filter(|m| (m.f_hz - p.f_hz).abs() <= 0.02 * p.f_hz)
                        .min_by(|a, b| (a.f_hz - p.f_hz).abs().total_cmp(&(b.f_hz - p.f_hz).abs()))
                        .map(pole_of)
                })
            })
            .collect();
        let rep_poles: Vec<Pole> = matched
            .iter()
            .zip(fitted)
            .map(|(m, p)| m.unwrap_or(*p))
            .collect();
        let rep_shapes = lsfd::fit(freq, &h1, s.band_hz, &rep_poles, s.form).ok();
        for (r, m) in matched.iter().enumerate() {
            let shape = rep_shapes
                .as_ref()
                .map(|c| layout.vector(&c.iter().map(|k| k.residues[r]).collect::<Vec<_>>()));
            reps[r].push(m.and_then(|p| shape.map(|sh| (p, sh))));
        }
    }
    reps
}

/// A mode's 95 % intervals of frequency and damping and its shape's standard uncertainties from
/// its replicates `r`; `None` when a replicate lacks it (no replicates: no intervals).
#[allow(clippy::type_complexity)]
fn intervals(
    pole: Pole,
    (residues, shape): (&[Complex64], &[Complex64]),
    r: &[Replicate],
    exp: Option<ExpWindow>,
    unit_sizes: &[usize],
) -> Option<(Option<Interval>, Option<Interval>, Option<Vec<f64>>)> {
    if r.is_empty() {
        return Some((None, None, None));
    }
    if !r.iter().all(Option::is_some) {
        return None;
    }
    let reps: Vec<(Pole, Vec<Complex64>)> = r.iter().flatten().cloned().collect();
    let fs: Vec<f64> = reps.iter().map(|(q, _)| unwindowed(*q, exp).f_hz).collect();
    let ds: Vec<f64> = reps
        .iter()
        .map(|(q, _)| unwindowed(*q, exp).damping)
        .collect();
    // a frequency is positive: an interval reaching 0 Hz determines nothing
    let fi = jackknife_sized(pole.f_hz, &fs, unit_sizes).and_then(Interval::of_positive);
    // a damping ratio is not negative: the interval's lower end at 0 at least
    let di = jackknife_sized(pole.damping, &ds, unit_sizes).map(|i| Interval {
        lo: i.lo.max(0.0),
        ..i
    });
    let reference = residues
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.norm().total_cmp(&b.1.norm()))
        .map_or(0, |(k, _)| k);
    let su = Some(
        (0..residues.len())
            .map(|k| {
                let a: Vec<f64> = reps
                    .iter()
                    .map(|(_, sh)| (sh[k] / sh[reference]).norm())
                    .collect();
                jackknife_sized(shape[k].norm(), &a, unit_sizes).map_or(f64::NAN, |v| v.u)
            })
            .collect(),
    );
    Some((fi, di, su))
}
