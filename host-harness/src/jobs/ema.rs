//! `ema`: experimental modal analysis of responses over a measured force.

use super::{SpecError, SpecResult};
use crate::analysis::ema::excited::{self, onset_lag_s};
use crate::analysis::ema::impact;
use crate::analysis::ema::impact::ImpactRule;
use crate::analysis::ema::input::{
    align, choose_axis, rate_text, read_force, read_poles, read_responses, Aligned, Series,
};
use crate::analysis::ema::lscf::LscfRule;
use crate::analysis::ema::run::{EmaRequest, RovingRead};
use crate::analysis::ema::{EmaSettings, Excitation, ExpChoice};
use crate::analysis::modal::FrfForm;
use crate::analysis::oma::cluster::ClusterRule;
use crate::setting::table;
use std::path::{Path, PathBuf};

/// `ema`'s settings as given.
#[derive(Debug, Clone, PartialEq)]
pub struct EmaInput {
    /// The responses' file.
    pub response: PathBuf,
    /// `$response_col`: the responses by name (empty: every channel).
    pub response_cols: Vec<String>,
    /// `$response_fs`, Hz, when the file states no rate.
    pub response_fs: Option<f64>,
    /// The force's file.
    pub excitation: PathBuf,
    /// `$roving`: a roving-hammer test's records, one per hit point (empty: the one test of
    /// `response` and `excitation`, which are then the first record's).
    pub roving: Vec<RovingRecord>,
    /// `$excitation_col`: the force's channel (none: the file's only channel), or several
    /// forces at once (shakers), each a channel of the excitation's file.
    pub excitation_cols: Vec<String>,
    /// `$excitation_fs`, Hz, when the file states no rate.
    pub excitation_fs: Option<f64>,
    /// `$impact`: hits of a hammer (else a continuous force).
    pub impact: bool,
    /// `$exp_window`.
    pub exp_window: ExpChoice,
    /// `$block_s`: longest block of a hit, s.
    pub block_s: Option<f64>,
    /// `$delay_s`: the responses' first sample after the force's, s (none: as the files
    /// state, else estimated from an impact test's onset, else 0).
    pub delay_s: Option<f64>,
    /// `$response_quantity`: displacement (receptance), velocity or acceleration.
    pub form: FrfForm,
    /// `$bands`, Hz (none: every mode the diagram shows).
    pub bands: Option<Vec<(f64, f64)>>,
    /// `$f_min_hz`.
    pub f_min_hz: Option<f64>,
    /// `$f_max_hz`.
    pub f_max_hz: Option<f64>,
    /// `$poles`: a CSV of the poles to give as modes (`f_hz`, `damping`; none: the
    /// stabilisation diagram's clusters).
    pub poles: Option<PathBuf>,
    /// `$max_order`: LSCF's highest order.
    pub max_order: usize,
    /// `$nperseg`: a continuous test's Welch segment.
    pub nperseg: Option<usize>,
    /// Output directory.
    pub out: PathBuf,
    /// Replace an earlier `ema` output there.
    pub force: bool,
    /// Draw the figures.
    pub plots: bool,
    /// Also print `report.pdf` (headless Chromium).
    pub pdf: bool,
    /// `$geometry`: the structure's nodes and lines the page draws the shapes on.
    pub geometry: Option<PathBuf>,
}

/// One record of a roving-hammer test: the point hit, the responses' file and the force's
/// (the same file when it holds both).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RovingRecord {
    /// The hit point's number.
    pub point: usize,
    /// The responses' file.
    pub response: PathBuf,
    /// The force's file.
    pub excitation: PathBuf,
}

/// The responses without the force's own channel when both come from one file (`files`: the
/// responses' and the force's): taken among every channel it is left out (said so); named as a
/// response it is refused (the FRF of the force over itself is 1, and would be fitted as a
/// mode).
fn without_the_force(
    mut response: Series,
    force: &Series,
    files: (&Path, &Path),
    input: &EmaInput,
) -> SpecResult<Series> {
    let same_file = match (
        std::fs::canonicalize(files.0),
        std::fs::canonicalize(files.1),
    ) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if !same_file {
        return Ok(response);
    }
    let Some(i) = response.names.iter().position(|n| *n == force.names[0]) else {
        return Ok(response);
    };
    if !input.response_cols.is_empty() {
        return Err(SpecError::setting(format!(
            "$response_col {}: the force's own channel (of the same file) is no response: its \
             FRF over itself is 1",
            force.names[0]
        )));
    }
    response.names.remove(i);
    response.channels.remove(i);
    if response.names.is_empty() {
        return Err(SpecError::setting(format!(
            "{}: its only channel is the force: give the responses' file",
            files.0.display()
        )));
    }
    response.notes.push(format!(
        "the force's channel `{}` left out of the responses (the same file holds both)",
        force.names[0]
    ));
    Ok(response)
}

/// One record read: the responses, the force, both aligned.
type Read = (Series, Series, Aligned);

/// The record of `files` (the responses' and the force's) read and aligned: the force's channel
/// out of the responses, an impact test's delay estimated when the files state none, a pyidi
/// `.npy`'s axis chosen.
fn read_record(input: &EmaInput, files: (&Path, &Path)) -> SpecResult<Read> {
    let response = read_responses(files.0, &input.response_cols, input.response_fs)
        .map_err(SpecError::Input)?;
    let force = read_force(
        files.1,
        input.excitation_cols.first().map_or("", String::as_str),
        input.excitation_fs,
    )
    .map_err(SpecError::Input)?;
    let mut response = without_the_force(response, &force, files, input)?;
    let mut aligned =
        align(&response, &force, input.delay_s.unwrap_or(0.0)).map_err(SpecError::Input)?;
    let nyq = aligned.nyquist_hz;
    if let Some(b) = &input.bands {
        super::bands_below_nyquist(b, 2.0 * nyq, "the slower record's")?;
    }
    let (f_min, f_max) = band_analysed(input, aligned.nyquist_hz)?;
    let rule = match excitation(input, &aligned)? {
        Excitation::Impact { rule, .. } => Some(rule),
        Excitation::Continuous { .. } => None,
    };
    if let (Some(rule), None, false) = (rule, input.delay_s, stated_starts(&response, &force)) {
        if let Some(a) = estimated_delay(&response, &force, &aligned, rule)? {
            aligned = a;
        }
    }
    choose_axis(&mut response, &mut aligned, rule, (f_min, f_max));
    Ok((response, force, aligned))
}

/// The forces after the first (`$excitation_col` repeated: shakers at once), each read from the
/// excitation's file and aligned with the responses as the first was.
fn more_forces(input: &EmaInput, response: &Series) -> SpecResult<Vec<(Series, Vec<f64>)>> {
    let mut out = Vec::new();
    for col in input.excitation_cols.iter().skip(1) {
        let force =
            read_force(&input.excitation, col, input.excitation_fs).map_err(SpecError::Input)?;
        let a = align(response, &force, input.delay_s.unwrap_or(0.0)).map_err(SpecError::Input)?;
        out.push((force, a.force));
    }
    Ok(out)
}

/// A roving-hammer test's other records (after the first, `first`), read as the first: the same
/// responses at the same rate, or refused naming the file.
fn read_roving(input: &EmaInput, first: &Read) -> SpecResult<Vec<RovingRead>> {
    let mut out = Vec::new();
    for r in input.roving.iter().skip(1) {
        let (response, force, aligned) = read_record(input, (&r.response, &r.excitation))?;
        let name = r.response.display();
        if response.names != first.0.names {
            return Err(SpecError::Input(vibcam_readers::bad_input(format!(
                "{name}: its responses ({}) are not the first record's ({}): every record of a \
                 roving-hammer test holds the same responses",
                response.names.join(", "),
                first.0.names.join(", ")
            ))));
        }
        if (aligned.fs_hz - first.2.fs_hz).abs() > 1e-9 * first.2.fs_hz {
            return Err(SpecError::Input(vibcam_readers::bad_input(format!(
                "{name}: its records are analysed at {} Hz, the first record's at {} Hz: a \
                 roving-hammer test's records share one rate",
                rate_text(aligned.fs_hz),
                rate_text(first.2.fs_hz)
            ))));
        }
        out.push(RovingRead {
            point: r.point,
            name: name.to_string(),
            notes: response.notes.into_iter().chain(force.notes).collect(),
            aligned,
        });
    }
    Ok(out)
}

/// A checked `ema` job: its records read and aligned.
#[derive(Debug, Clone)]
pub struct EmaSpec {
    request: EmaRequest,
}

impl EmaSpec {
    /// Reads the files and checks the settings against them.
    pub fn new(input: EmaInput) -> SpecResult<Self> {
        check_alone(&input)?;
        let first = read_record(&input, (&input.response, &input.excitation))?;
        let others = read_roving(&input, &first)?;
        let more = more_forces(&input, &first.0)?;
        let (response, force, aligned) = first;
        let (f_min, f_max) = band_analysed(&input, aligned.nyquist_hz)?;
        let excitation = excitation(&input, &aligned)?;
        let settings = EmaSettings {
            excitation,
            form: input.form,
            band_hz: (f_min, f_max),
            band_from_data: (
                input.f_min_hz.is_none() && input.bands.is_none(),
                input.f_max_hz.is_none() && input.bands.is_none(),
            ),
            bands: input.bands.clone(),
            lscf: LscfRule {
                max_order: input.max_order,
                ..LscfRule::default()
            },
            cluster: ClusterRule::default(),
            poles: match &input.poles {
                Some(p) => Some(read_poles(p).map_err(SpecError::Input)?),
                None => None,
            },
        };
        let geometry = super::read_geometry(input.geometry.as_deref())?;
        // the shapes are over the hit points when they outnumber the responses
        let (points, what): (Vec<usize>, _) = if input.roving.len() > aligned.responses.len() {
            (input.roving.iter().map(|r| r.point).collect(), "hit point")
        } else {
            ((1..=aligned.responses.len()).collect(), "response")
        };
        let wire = crate::export::wire::Wire::on(geometry.as_ref(), &points, what, None)
            .map_err(SpecError::Input)?;
        let roving = match input.roving.first() {
            Some(r) => std::iter::once(RovingRead {
                point: r.point,
                name: r.response.display().to_string(),
                notes: Vec::new(),
                aligned: aligned.clone(),
            })
            .chain(others)
            .collect(),
            None => Vec::new(),
        };
        let files = input
            .roving
            .iter()
            .skip(1)
            .flat_map(|r| [&r.response, &r.excitation]);
        Ok(EmaSpec {
            request: EmaRequest {
                response,
                force,
                aligned,
                roving,
                more_forces: more,
                settings,
                inputs: [&input.response, &input.excitation]
                    .into_iter()
                    .chain(files)
                    .chain(&input.poles)
                    .chain(&input.geometry)
                    .cloned()
                    .collect(),
                out: input.out.clone(),
                force_out: input.force,
                pdf: input.pdf,
                plots: input.plots,
                wire,
            },
        })
    }

    /// The request: records and settings.
    pub fn request(&self) -> &EmaRequest {
        &self.request
    }

    /// The analysis and its report, nothing written (Python without an output directory).
    pub fn compute(&self) -> anyhow::Result<(crate::analysis::ema::EmaResult, String)> {
        crate::analysis::ema::run::compute(&self.request)
    }

    /// Runs the job: the report, and whether it succeeded.
    pub fn run(&self) -> anyhow::Result<crate::analysis::request::Outcome> {
        crate::analysis::ema::run::run(&self.request)
    }
}

/// Both files state when their first sample was taken (their delay is theirs).
fn stated_starts(response: &Series, force: &Series) -> bool {
    response.start_time.is_some() && force.start_time.is_some()
}

/// The records aligned again when an impact test's responses start to move well after the
/// force's pulse ([`onset_lag_s`]: more than twice the pulse and three samples of the slower
/// record): their record began that much before the force's. The estimate is said in the
/// notes; `None` when there is no such lag.
fn estimated_delay(
    response: &Series,
    force: &Series,
    aligned: &Aligned,
    rule: ImpactRule,
) -> SpecResult<Option<Aligned>> {
    let fs = aligned.fs_hz;
    let Ok(hits) = impact::find(&aligned.force, fs, rule, &force.names[0]) else {
        return Ok(None);
    };
    let Some(lag) = onset_lag_s(&aligned.responses, &hits, fs) else {
        return Ok(None);
    };
    let pulse = hits
        .used()
        .map(|h| (h.pulse().end - h.pulse().start) as f64 / fs)
        .fold(0.0f64, f64::max);
    if lag <= (2.0 * pulse).max(3.0 / (2.0 * aligned.nyquist_hz)) {
        return Ok(None);
    }
    let mut a = align(response, force, -lag).map_err(SpecError::Input)?;
    a.notes.push(format!(
        "the responses start to move {:.2} ms after the force's pulse (the median over \
         responses and hits of when each leaves its noise by {} standard deviations): their \
         record began that much before the force's, and they are aligned by it ($delay_s gives \
         the delay instead)",
        1e3 * lag,
        excited::ONSET_SIGMAS
    ));
    Ok(Some(a))
}

/// The settings checked on their own, before any file is read.
fn check_alone(input: &EmaInput) -> SpecResult<()> {
    let cols = &input.excitation_cols;
    if let Some((_, c)) = cols
        .iter()
        .enumerate()
        .find(|(i, c)| cols[..*i].contains(c))
    {
        return Err(SpecError::setting(format!(
            "$excitation_col {c} is given twice: each force once"
        )));
    }
    if cols.len() > 1 && (input.impact || !input.roving.is_empty()) {
        return Err(SpecError::setting(
            "$excitation_col given more than once: several forces at once are a continuous \
             test (shakers), not $impact nor $roving"
                .to_string(),
        ));
    }
    let mut points: Vec<usize> = input.roving.iter().map(|r| r.point).collect();
    points.sort_unstable();
    if let Some(w) = points.windows(2).find(|w| w[0] == w[1]) {
        return Err(SpecError::setting(format!(
            "$roving: hit point {} is given twice: one record per hit point",
            w[0]
        )));
    }
    if !input.roving.is_empty() && !input.impact {
        return Err(SpecError::setting(
            "$roving: a roving-hammer test is an impact test, analysed hit by hit ($impact)"
                .to_string(),
        ));
    }
    if let Some(b) = &input.bands {
        super::bands_ordered(b)?;
    }
    if input.bands.is_some() && input.poles.is_some() {
        return Err(SpecError::setting(
            "$bands and $poles: the poles given are the modes; bands choose among clusters"
                .to_string(),
        ));
    }
    if let Some((_, c)) = input
        .response_cols
        .iter()
        .enumerate()
        .find(|(i, c)| input.response_cols[..*i].contains(c))
    {
        return Err(SpecError::setting(format!(
            "$response_col {c} is given twice: each response once"
        )));
    }
    if let Some(d) = input.delay_s.filter(|d| !d.is_finite()) {
        return Err(SpecError::setting(format!(
            "$delay_s must be a finite number of seconds, got {d}"
        )));
    }
    if let ExpChoice::End(e) = input.exp_window {
        table::number("ema", "exp_window", e)?;
    }
    table::whole("ema", "max_order", input.max_order as u64)?;
    if let Some(b) = input.block_s {
        super::positive("$block_s", b, "seconds")?;
    }
    if !input.impact && input.exp_window != ExpChoice::Auto {
        return Err(SpecError::setting(
            "$exp_window is for an impact test ($impact)".to_string(),
        ));
    }
    for fs in [input.response_fs, input.excitation_fs]
        .into_iter()
        .flatten()
    {
        if !(fs.is_finite() && fs > 0.0) {
            return Err(SpecError::setting(format!(
                "$response_fs and $excitation_fs must be positive, got {fs}"
            )));
        }
    }
    Ok(())
}

/// The band analysed, `(f_min, f_max)`: given, else the bands' extent, else 1 % to 80 % of the
/// slower record's Nyquist frequency `nyq`; every band inside it.
fn band_analysed(input: &EmaInput, nyq: f64) -> SpecResult<(f64, f64)> {
    let f_max = match input.f_max_hz {
        Some(f) if !(f.is_finite() && f > 0.0 && f <= nyq) => {
            return Err(SpecError::setting(format!(
                "$f_max_hz {f}: between 0 and the slower record's Nyquist frequency ({} Hz)",
                rate_text(nyq)
            )))
        }
        Some(f) => f,
        None => match &input.bands {
            Some(b) => b.iter().map(|x| x.1).fold(0.0, f64::max),
            None => 0.8 * nyq,
        },
    };
    let f_min = match input.f_min_hz {
        Some(f) if !(f.is_finite() && f >= 0.0 && f < f_max) => {
            return Err(SpecError::setting(format!(
                "$f_min_hz {f}: between 0 and the band's top ({f_max} Hz)"
            )))
        }
        Some(f) => f,
        None => match &input.bands {
            Some(b) => b.iter().map(|x| x.0).fold(f64::INFINITY, f64::min),
            None => (f_max / 100.0).max(0.5),
        },
    };
    if let Some(b) = input.bands.as_ref().and_then(|b| {
        b.iter()
            .find(|(lo, hi)| *lo < f_min || *hi > f_max)
            .copied()
    }) {
        return Err(SpecError::setting(format!(
            "$bands {}-{} reaches outside the band analysed, {f_min}-{f_max} Hz \
             ($f_min_hz, $f_max_hz): nothing is fitted there",
            b.0, b.1
        )));
    }
    Ok((f_min, f_max))
}

/// The excitation: an impact's rule and window, or a continuous excitation's Welch segments
/// (given, else the longest power of two with at least 9 half-overlapping segments).
fn excitation(
    input: &EmaInput,
    aligned: &crate::analysis::ema::input::Aligned,
) -> SpecResult<Excitation> {
    let n = aligned.force.len();
    let excitation = if input.impact {
        Excitation::Impact {
            rule: ImpactRule {
                block_s: input.block_s,
                ..ImpactRule::default()
            },
            exp: input.exp_window,
        }
    } else {
        let nperseg = match input.nperseg {
            Some(p) if !(64..=1 << 20).contains(&p) || 2 * p > n => {
                return Err(SpecError::setting(format!(
                    "$nperseg {p}: 64 to 2^20 samples and at most half the record ({n})"
                )))
            }
            Some(p) => p,
            None => {
                let mut p = 1usize << 16;
                while p > 64 && 9 * p > 2 * n {
                    p /= 2;
                }
                if 2 * p > n {
                    return Err(SpecError::setting(format!(
                        "the record has {n} samples at {} Hz: too short for Welch segments",
                        aligned.fs_hz
                    )));
                }
                p
            }
        };
        Excitation::Continuous { nperseg }
    };
    Ok(excitation)
}
