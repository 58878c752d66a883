//! Identifying what a rig leaves unreported from observed study figures (method.md §3.5):
//! the imaging knobs of a study file's `[imaging]` table (target radius and edge,
//! threshold, read noise, optical blur, gain, the cantilever's projected tip rotation) and the
//! `[rig]` table's beam length (the tip accelerometer's tilt reading) fitted to observed values of `mu_a`, `sigma_a`,
//! `mu_f`, `ratio_to_first`, `chi_mu` and `chi_sigma`.
//!
//! Every evaluation is a small study of the same runs (the same seed: common random numbers,
//! so a parameter change is not drowned in Monte Carlo noise) computed in process through the
//! study's scenario and aggregation. The misfit is `chi2 = sum r^2` over the observations,
//! `r = (model - observed) / u`, `u = sqrt(u_obs^2 + u_model^2)` (`u_model` the Monte Carlo
//! standard uncertainty of the model's figure; `u_obs` the observation's, when given). Because
//! `u_model` depends on the parameters, chi2 alone rewards a noisier model (a smaller target,
//! more read noise: larger `u`, smaller `r`), so the search minimises the Gaussian negative
//! log-likelihood `objective = sum (r^2 + ln u^2)` instead, whose `ln u^2` term charges for the
//! spread it buys. The search: a coarse grid over the ranges, then a pattern search from the
//! best point that halves its steps when no neighbour improves. A parameter's uncertainty is
//! `sqrt(2 / c)`, `c` the curvature of the objective along its axis at the optimum (the
//! `+1` half-width of `-2 ln L`, correlations ignored).

use crate::imaging::exposure::ExposureCorrection;
use crate::study::{aggregate, run_rng, scenario_for, Preset, RunRecord, StudyConfig};
use std::collections::BTreeMap;
use std::path::Path;
use vibcam_readers::bad_input;
use vibcam_report::export::calibrate::{ParameterRow, ResidualRow};
use vibcam_report::export::study::{CoverageRow, SummaryRow, System};

/// A figure an observation gives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Quantity {
    /// Mean vision amplitude.
    MuA,
    /// Standard deviation of the vision amplitude.
    SigmaA,
    /// Mean vision frequency, Hz.
    MuF,
    /// Mean vision amplitude over its value at the shortest observed exposure of the mode.
    RatioToFirst,
    /// Mean vision amplitude over the transducer's (the rig's index).
    ChiMu,
    /// Vision amplitude standard deviation over the transducer's.
    ChiSigma,
}

impl Quantity {
    const NAMES: [(&'static str, Quantity); 6] = [
        ("mu_a", Quantity::MuA),
        ("sigma_a", Quantity::SigmaA),
        ("mu_f", Quantity::MuF),
        ("ratio_to_first", Quantity::RatioToFirst),
        ("chi_mu", Quantity::ChiMu),
        ("chi_sigma", Quantity::ChiSigma),
    ];

    /// The CSV name.
    pub fn name(self) -> &'static str {
        Self::NAMES
            .iter()
            .find(|(_, q)| *q == self)
            .map_or("", |(n, _)| n)
    }

    fn parse(s: &str) -> Option<Quantity> {
        Self::NAMES.iter().find(|(n, _)| *n == s).map(|(_, q)| *q)
    }
}

/// One observed figure (a row of the observations CSV).
#[derive(Debug, Clone, PartialEq)]
pub struct Observation {
    /// Mode, 1-based.
    pub mode: usize,
    /// Exposure, ms.
    pub exposure_ms: f64,
    /// What is observed.
    pub quantity: Quantity,
    /// Observed value (chi indices as fractions, not percent).
    pub value: f64,
    /// Its standard uncertainty, when known.
    pub u: Option<f64>,
}

/// Reads `rig,mode,exposure_ms,quantity,value[,u][,unit]` and keeps the rows of `rig` (the others are
/// counted in the second value). A chi index states its unit (`percent` or `fraction`). Errors
/// name the file and row.
pub fn read_observations(path: &Path, rig: Preset) -> anyhow::Result<(Vec<Observation>, usize)> {
    let modes = crate::study::scenario_for(&StudyConfig::preset(rig))?
        .reporting()
        .bands
        .len();
    let file = || path.display().to_string();
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .flexible(true)
        .from_path(path)
        .map_err(|e| bad_input(format!("{}: {e}", file())))?;
    let headers = reader
        .headers()
        .map_err(|e| bad_input(format!("{}: {e}", file())))?
        .clone();
    let col = |name: &str| headers.iter().position(|h| h == name);
    let need =
        |name: &str| col(name).ok_or_else(|| bad_input(format!("{}: no column `{name}`", file())));
    let cols = ObservationColumns {
        rig: need("rig")?,
        mode: need("mode")?,
        exposure: need("exposure_ms")?,
        quantity: need("quantity")?,
        value: need("value")?,
        u: col("u"),
        unit: col("unit"),
    };
    let (mut out, mut other) = (Vec::new(), 0);
    for (i, row) in reader.records().enumerate() {
        let at = format!("{} row {}", file(), i + 2);
        let row = row.map_err(|e| bad_input(format!("{at}: {e}")))?;
        if !row
            .get(cols.rig)
            .unwrap_or("")
            .eq_ignore_ascii_case(rig.name())
        {
            other += 1;
            continue;
        }
        out.push(parse_observation(&row, &cols, (rig, modes), &at)?);
    }
    if out.is_empty() {
        return Err(bad_input(format!(
            "{}: no observation of the {} rig",
            path.display(),
            rig.name()
        )));
    }
    Ok((out, other))
}

/// Where the columns of an observations file are.
struct ObservationColumns {
    rig: usize,
    mode: usize,
    exposure: usize,
    quantity: usize,
    value: usize,
    u: Option<usize>,
    unit: Option<usize>,
}

/// One row of `rig`'s (which reports `modes` modes) as an observation; `at` names the row.
fn parse_observation(
    row: &csv::StringRecord,
    c: &ObservationColumns,
    (rig, modes): (Preset, usize),
    at: &str,
) -> anyhow::Result<Observation> {
    let cell = |i: usize| row.get(i).unwrap_or("");
    let num = |i: usize, what: &str| -> anyhow::Result<f64> {
        cell(i)
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| bad_input(format!("{at}: {what} `{}` is not a number", cell(i))))
    };
    let mode = cell(c.mode)
        .parse::<usize>()
        .ok()
        .filter(|m| (1..=modes).contains(m))
        .ok_or_else(|| {
            bad_input(format!(
                "{at}: mode `{}` must be 1 to {modes}, the modes the {} rig reports",
                cell(c.mode),
                rig.name()
            ))
        })?;
    let quantity = Quantity::parse(cell(c.quantity)).ok_or_else(|| {
        bad_input(format!(
            "{at}: quantity `{}` is not one of mu_a, sigma_a, mu_f, ratio_to_first, chi_mu, chi_sigma",
            cell(c.quantity)
        ))
    })?;
    let exposure_ms = num(c.exposure, "exposure_ms")?;
    if exposure_ms < 0.0 {
        return Err(bad_input(format!("{at}: exposure_ms must be >= 0")));
    }
    let u = match c.u.filter(|i| !cell(*i).is_empty()) {
        Some(i) if num(i, "u")? < 0.0 => {
            return Err(bad_input(format!(
                "{at}: u `{}` is negative; a standard uncertainty is >= 0",
                cell(i)
            )))
        }
        Some(i) => Some(num(i, "u")?),
        None => None,
    };
    let unit = c
        .unit
        .map(|i| cell(i).to_ascii_lowercase())
        .unwrap_or_default();
    let per = unit_divisor(quantity, &unit, at)?;
    Ok(Observation {
        mode,
        exposure_ms,
        quantity,
        value: num(c.value, "value")? / per,
        u: u.map(|u| u / per),
    })
}

/// What an observation is divided by to be in the study's units: a chi index's stated unit
/// (`percent`: 100, `fraction`: 1; never guessed from its size, 1.5 % is not 150 %); the other
/// quantities are in the study's own units and take none.
fn unit_divisor(quantity: Quantity, unit: &str, at: &str) -> anyhow::Result<f64> {
    match (
        matches!(quantity, Quantity::ChiMu | Quantity::ChiSigma),
        unit,
    ) {
        (true, "percent" | "%") => Ok(100.0),
        (true, "fraction") | (false, "") => Ok(1.0),
        (true, "") => Err(bad_input(format!(
            "{at}: {} needs its unit: a `unit` column with `percent` (95.5) or `fraction` \
             (0.955)",
            quantity.name()
        ))),
        (true, other) => Err(bad_input(format!(
            "{at}: unit `{other}`: `percent` or `fraction`"
        ))),
        (false, other) => Err(bad_input(format!(
            "{at}: unit `{other}` for {}: only chi_mu and chi_sigma take a unit (the others \
             are in the study's own units)",
            quantity.name()
        ))),
    }
}

/// An `[imaging]` (or `[rig]`) knob a calibration may turn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Knob {
    /// `target_radius_px`.
    TargetRadius,
    /// `target_edge_sigma_px`.
    EdgeSigma,
    /// `threshold_frac`.
    ThresholdFrac,
    /// `read_noise`.
    ReadNoise,
    /// `optical_blur_sigma_px`.
    OpticalBlur,
    /// `gain`.
    Gain,
    /// `tip_rotation_lever` (the cantilever's projected tip rotation).
    TipRotationLever,
    /// `beam_length_m` (`[rig]`: the cantilever's length, with an upright or hanging beam the
    /// tip accelerometer's tilt reading).
    BeamLength,
    /// `epsa_images` (an integer: the sharp images averaged per exposure; the search moves it
    /// in whole steps).
    EpsaImages,
}

impl Knob {
    const NAMES: [(&'static str, Knob); 9] = [
        ("target_radius_px", Knob::TargetRadius),
        ("target_edge_sigma_px", Knob::EdgeSigma),
        ("threshold_frac", Knob::ThresholdFrac),
        ("read_noise", Knob::ReadNoise),
        ("optical_blur_sigma_px", Knob::OpticalBlur),
        ("gain", Knob::Gain),
        ("tip_rotation_lever", Knob::TipRotationLever),
        ("beam_length_m", Knob::BeamLength),
        ("epsa_images", Knob::EpsaImages),
    ];

    /// Whether the knob takes whole numbers only (the search rounds and steps by at least 1).
    pub fn integer(self) -> bool {
        self == Knob::EpsaImages
    }

    /// The `[imaging]` (or `[rig]`) field name.
    pub fn name(self) -> &'static str {
        Self::NAMES
            .iter()
            .find(|(_, k)| *k == self)
            .map_or("", |(n, _)| n)
    }

    fn set(self, cfg: &mut StudyConfig, v: f64) {
        let o = &mut cfg.imaging;
        let field = match self {
            Knob::TargetRadius => &mut o.target_radius_px,
            Knob::EdgeSigma => &mut o.target_edge_sigma_px,
            Knob::ThresholdFrac => &mut o.threshold_frac,
            Knob::ReadNoise => &mut o.read_noise,
            Knob::OpticalBlur => &mut o.optical_blur_sigma_px,
            Knob::Gain => &mut o.gain,
            Knob::TipRotationLever => &mut o.tip_rotation_lever,
            Knob::BeamLength => &mut cfg.rig.beam_length_m,
            Knob::EpsaImages => {
                o.epsa_images = Some(v.round().max(2.0) as usize);
                return;
            }
        };
        *field = Some(v);
    }
}

/// A free parameter and its range (`--free NAME=LO:HI`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Free {
    /// The knob.
    pub knob: Knob,
    /// Smallest value.
    pub lo: f64,
    /// Largest value.
    pub hi: f64,
}

/// Parses `NAME=LO:HI` (LO < HI, both finite).
pub fn parse_free(s: &str) -> Result<Free, String> {
    let names = || Knob::NAMES.map(|(n, _)| n).join(", ");
    let (name, range) = s
        .split_once('=')
        .ok_or_else(|| format!("`{s}`: expected NAME=LO:HI with NAME one of {}", names()))?;
    let knob = Knob::NAMES
        .iter()
        .find(|(n, _)| *n == name.trim())
        .map(|(_, k)| *k)
        .ok_or_else(|| format!("`{name}` is not one of {}", names()))?;
    let (lo, hi) = range
        .split_once(':')
        .and_then(|(a, b)| Some((a.trim().parse::<f64>().ok()?, b.trim().parse::<f64>().ok()?)))
        .ok_or_else(|| format!("`{range}`: expected LO:HI, two numbers"))?;
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(format!("`{range}`: LO must be below HI, both finite"));
    }
    if knob.integer() && !(lo >= 2.0 && lo.fract() == 0.0 && hi.fract() == 0.0) {
        return Err(format!(
            "`{range}`: {} takes whole numbers from 2 (LO and HI integers)",
            knob.name()
        ));
    }
    Ok(Free { knob, lo, hi })
}

/// One observation against the model.
#[derive(Debug, Clone, PartialEq)]
pub struct Residual {
    /// The observation.
    pub observed: Observation,
    /// The model's figure (NaN when the model has none, e.g. every run lost the target).
    pub model: f64,
    /// Its Monte Carlo standard uncertainty.
    pub u_model: f64,
    /// `(model - observed) / sqrt(u_obs^2 + u_model^2)`.
    pub r: f64,
}

/// One evaluated parameter point.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    /// Parameter values, in the order of the free parameters.
    pub x: Vec<f64>,
    /// Sum of squared residuals (a large penalty per figure the model cannot give).
    pub chi2: f64,
    /// What the search minimises: `chi2 + sum ln u^2` (the Gaussian negative log-likelihood
    /// up to a constant, see the module documentation).
    pub objective: f64,
    /// Per observation.
    pub residuals: Vec<Residual>,
}

/// Penalty of a figure the model cannot give (all runs failed, an undefined index).
const MISSING: f64 = 1e6;

/// The study configuration of a parameter point: `base` with the free knobs set and the
/// observed exposures (ascending).
pub fn config_at(base: &StudyConfig, free: &[Free], x: &[f64], obs: &[Observation]) -> StudyConfig {
    let mut cfg = base.clone();
    for (f, v) in free.iter().zip(x) {
        f.knob.set(&mut cfg, *v);
    }
    let mut exposures: Vec<f64> = obs.iter().map(|o| o.exposure_ms).collect();
    exposures.sort_by(f64::total_cmp);
    exposures.dedup();
    cfg.exposures_ms = exposures;
    cfg
}

/// Runs the small study of a parameter point (in parallel, the same runs for every point) and
/// compares it with the observations.
pub fn evaluate(
    base: &StudyConfig,
    free: &[Free],
    x: &[f64],
    obs: &[Observation],
) -> anyhow::Result<Evaluation> {
    use rayon::prelude::*;
    let cfg = config_at(base, free, x, obs);
    let scenario = scenario_for(&cfg)?;
    // worker threads with the study runner's stack (the estimators' fixed buffers)
    let pool = rayon::ThreadPoolBuilder::new()
        .stack_size(64 << 20)
        .build()
        .map_err(|e| anyhow::anyhow!("cannot start the worker threads: {e}"))?;
    let records: Vec<RunRecord> = pool.install(|| {
        (0..cfg.runs)
            .into_par_iter()
            .map(|r| scenario.run(r, &mut run_rng(cfg.seed, r)))
            .collect::<anyhow::Result<_>>()
    })?;
    // the correction only feeds the vision_compensated rows, which a calibration ignores
    let out =
        aggregate::aggregate_with(&cfg, scenario.as_ref(), &records, &ExposureCorrection::Sinc)?;
    let residuals: Vec<Residual> = obs
        .iter()
        .map(|o| {
            let (model, u_model) = model_figure(&out.summary, &out.coverage, &cfg, o);
            if model.is_finite() && !u_model.is_finite() {
                // a residual over an unknown uncertainty would be a number without meaning
                return Err(bad_input(format!(
                    "the model's uncertainty of {} (mode {}, {} ms) is undefined with {} runs \
                     per evaluation; raise $runs",
                    o.quantity.name(),
                    o.mode,
                    o.exposure_ms,
                    cfg.runs
                )));
            }
            let u = combined_u(o, u_model);
            Ok(Residual {
                observed: o.clone(),
                model,
                u_model,
                r: (model - o.value) / u,
            })
        })
        .collect::<anyhow::Result<_>>()?;
    let chi2 = residuals
        .iter()
        .map(|r| if r.r.is_finite() { r.r * r.r } else { MISSING })
        .sum();
    Ok(Evaluation {
        x: x.to_vec(),
        chi2,
        objective: objective(&residuals),
        residuals,
    })
}

/// The standard uncertainty a residual is divided by: the observation's and the model's
/// combined (floored at a millionth of the observed value).
fn combined_u(o: &Observation, u_model: f64) -> f64 {
    let u = (o.u.unwrap_or(0.0).powi(2) + u_model.powi(2)).sqrt();
    u.max(1e-6 * o.value.abs().max(1e-12))
}

/// `sum (r^2 + ln u^2)` over the residuals; a figure the model cannot give costs a large penalty (1e6).
pub fn objective(residuals: &[Residual]) -> f64 {
    residuals
        .iter()
        .map(|r| {
            let u = combined_u(&r.observed, r.u_model);
            if r.r.is_finite() && u.is_finite() {
                r.r * r.r + (u * u).ln()
            } else {
                MISSING
            }
        })
        .sum()
}

/// The model's figure for an observation and its Monte Carlo standard uncertainty.
fn model_figure(
    summary: &[SummaryRow],
    coverage: &[CoverageRow],
    cfg: &StudyConfig,
    o: &Observation,
) -> (f64, f64) {
    let row = |e: f64| {
        summary
            .iter()
            .find(|r| r.system == System::Vision && r.mode == o.mode && r.exposure_ms == e)
    };
    let chi_u = |q: &str| {
        coverage
            .iter()
            .find(|c| {
                c.system == System::Vision
                    && c.mode == o.mode
                    && c.exposure_ms == o.exposure_ms
                    && c.quantity == q
            })
            .map_or(f64::NAN, |c| c.coverage.u_mean)
    };
    let nan = (f64::NAN, f64::NAN);
    let Some(r) = row(o.exposure_ms) else {
        return nan;
    };
    let n = r.runs as f64;
    match o.quantity {
        Quantity::MuA => (r.mu_a, r.sigma_a / n.sqrt()),
        Quantity::SigmaA => (r.sigma_a, r.sigma_a / (2.0 * (n - 1.0)).sqrt()),
        Quantity::MuF => (r.mu_f_hz, r.sigma_f_hz / n.sqrt()),
        Quantity::ChiMu => (r.chi_mu.unwrap_or(f64::NAN), chi_u("chi_mu")),
        Quantity::ChiSigma => (r.chi_sigma.unwrap_or(f64::NAN), chi_u("chi_sigma")),
        Quantity::RatioToFirst => {
            let Some(first) = cfg.exposures_ms.first().and_then(|e| row(*e)) else {
                return nan;
            };
            let ratio = r.mu_a / first.mu_a;
            // the two means come from the same runs, so this overstates the uncertainty
            let rel = |r: &SummaryRow| r.sigma_a / (r.runs as f64).sqrt() / r.mu_a;
            (ratio, ratio * (rel(r).powi(2) + rel(first).powi(2)).sqrt())
        }
    }
}

/// The result of a search.
#[derive(Debug, Clone, PartialEq)]
pub struct Fit {
    /// The best point.
    pub best: Evaluation,
    /// Standard uncertainty of each parameter (`None`: the objective not convex along that axis).
    pub u: Vec<Option<f64>>,
    /// Every evaluation, in the order made.
    pub evaluations: Vec<Evaluation>,
}

/// Coarse grid (`grid` points per parameter, ends included) then pattern search for `refine`
/// rounds; `progress` hears about each evaluation.
pub fn search(
    base: &StudyConfig,
    free: &[Free],
    obs: &[Observation],
    (grid, refine): (usize, usize),
    progress: impl FnMut(&Evaluation),
) -> anyhow::Result<Fit> {
    let grid = grid.max(2);
    let mut ev = Evaluations {
        base,
        free,
        obs,
        progress,
        cache: BTreeMap::new(),
        order: Vec::new(),
    };
    let mut best = grid_search(&mut ev, grid)?;
    let mut step: Vec<f64> = free
        .iter()
        .map(|f| {
            let s = (f.hi - f.lo) / (grid - 1) as f64 / 2.0;
            if f.knob.integer() {
                s.round().max(1.0)
            } else {
                s
            }
        })
        .collect();
    for _ in 0..refine {
        if !pattern_step(&mut ev, &mut best, &step)? {
            for (s, f) in step.iter_mut().zip(free) {
                *s = if f.knob.integer() {
                    (*s / 2.0).round().max(1.0)
                } else {
                    *s / 2.0
                };
            }
        }
    }
    let u = curvature_u(&mut ev, &best, &step)?;
    Ok(Fit {
        best,
        u,
        evaluations: ev.order,
    })
}

/// The evaluations of a search: each point evaluated once (cached), in the order evaluated,
/// each reported to `progress`.
struct Evaluations<'a, P: FnMut(&Evaluation)> {
    base: &'a StudyConfig,
    free: &'a [Free],
    obs: &'a [Observation],
    progress: P,
    cache: BTreeMap<Vec<u64>, Evaluation>,
    order: Vec<Evaluation>,
}

impl<P: FnMut(&Evaluation)> Evaluations<'_, P> {
    fn eval(&mut self, x: &[f64]) -> anyhow::Result<Evaluation> {
        let key: Vec<u64> = x.iter().map(|v| v.to_bits()).collect();
        if let Some(e) = self.cache.get(&key) {
            return Ok(e.clone());
        }
        let e = evaluate(self.base, self.free, x, self.obs)?;
        (self.progress)(&e);
        self.order.push(e.clone());
        self.cache.insert(key, e.clone());
        Ok(e)
    }
}

/// A value of knob `f`, rounded when the knob is an integer.
fn whole(f: &Free, v: f64) -> f64 {
    if f.knob.integer() {
        v.round()
    } else {
        v
    }
}

/// The best point of a `grid`-point grid over every free knob's range.
fn grid_search<P: FnMut(&Evaluation)>(
    ev: &mut Evaluations<'_, P>,
    grid: usize,
) -> anyhow::Result<Evaluation> {
    let free = ev.free;
    let at = |f: &Free, i: usize| whole(f, f.lo + (f.hi - f.lo) * i as f64 / (grid - 1) as f64);
    let mut best: Option<Evaluation> = None;
    for flat in 0..grid.pow(free.len() as u32) {
        let x: Vec<f64> = (0..free.len())
            .map(|j| at(&free[j], flat / grid.pow(j as u32) % grid))
            .collect();
        let e = ev.eval(&x)?;
        if best.as_ref().is_none_or(|b| e.objective < b.objective) {
            best = Some(e);
        }
    }
    best.ok_or_else(|| bad_input("calibrate: no free parameter ($free)"))
}

/// One pattern-search step: each knob moved by its step either way; whether `best` improved.
fn pattern_step<P: FnMut(&Evaluation)>(
    ev: &mut Evaluations<'_, P>,
    best: &mut Evaluation,
    step: &[f64],
) -> anyhow::Result<bool> {
    let free = ev.free;
    let mut improved = false;
    for j in 0..free.len() {
        for sign in [-1.0, 1.0] {
            let mut x = best.x.clone();
            x[j] = whole(
                &free[j],
                (x[j] + sign * step[j]).clamp(free[j].lo, free[j].hi),
            );
            let e = ev.eval(&x)?;
            if e.objective < best.objective {
                *best = e;
                improved = true;
            }
        }
    }
    Ok(improved)
}

/// Each knob's standard uncertainty from the objective's curvature at `best` over its last
/// step (none for an integer knob, or where the curvature is not positive or a side is out of
/// range).
fn curvature_u<P: FnMut(&Evaluation)>(
    ev: &mut Evaluations<'_, P>,
    best: &Evaluation,
    step: &[f64],
) -> anyhow::Result<Vec<Option<f64>>> {
    let free = ev.free;
    let mut u = Vec::with_capacity(free.len());
    for j in 0..free.len() {
        let h = step[j];
        let mut side = |sign: f64| -> anyhow::Result<Option<f64>> {
            let mut x = best.x.clone();
            x[j] += sign * h;
            if x[j] < free[j].lo || x[j] > free[j].hi {
                return Ok(None);
            }
            Ok(Some(ev.eval(&x)?.objective))
        };
        let curvature = match (side(-1.0)?, side(1.0)?) {
            (Some(a), Some(b)) => Some((a - 2.0 * best.objective + b) / (h * h)),
            _ => None,
        };
        // an integer knob's curvature over whole steps is no standard uncertainty
        let integer = free[j].knob.integer();
        u.push(
            curvature
                .filter(|c| *c > 0.0 && !integer)
                .map(|c| (2.0 / c).sqrt()),
        );
    }
    Ok(u)
}

/// The rows of `residuals.csv` of evaluation `e`.
pub fn residual_rows(e: &Evaluation) -> Vec<ResidualRow> {
    e.residuals
        .iter()
        .map(|r| {
            let o = &r.observed;
            ResidualRow {
                mode: o.mode,
                exposure_ms: o.exposure_ms,
                quantity: o.quantity.name(),
                observed: o.value,
                u_observed: o.u,
                model: r.model,
                u_model: r.u_model,
                residual: r.r,
            }
        })
        .collect()
}

/// The rows of `parameters.csv`: the fitted value of each free knob.
pub fn parameter_rows(free: &[Free], fit: &Fit) -> Vec<ParameterRow> {
    free.iter()
        .zip(&fit.best.x)
        .zip(&fit.u)
        .map(|((f, &value), &u)| ParameterRow {
            name: f.knob.name(),
            value,
            u,
            range: (f.lo, f.hi),
        })
        .collect()
}

/// A checked `calibrate` request (what `cli::calibrate` builds from its flags).
#[derive(Debug, Clone)]
pub struct Request {
    /// The study whose knobs are fitted (the file's, or the preset's).
    pub base: StudyConfig,
    /// The observed figures (`read_observations`).
    pub observed: std::path::PathBuf,
    /// The free knobs and their ranges, each once.
    pub free: Vec<Free>,
    /// Runs per evaluation, >= 2.
    pub runs: u64,
    /// Grid points per free knob, >= 2.
    pub grid: usize,
    /// Rounds of the local search.
    pub refine: usize,
    /// Output directory (created).
    pub out: std::path::PathBuf,
}

/// Runs a calibration: reads the observations, searches, writes `fitted.toml`,
/// `parameters.csv`, `residuals.csv` and `evaluations.csv` atomically into `req.out`, and
/// returns the summary to print (progress goes to stderr as it happens).
pub fn run(req: &Request) -> anyhow::Result<String> {
    let obs = checked_observations(req)?;
    let mut small = req.base.clone();
    small.runs = req.runs;
    small.adaptive = None;
    eprintln!(
        "calibrate {}: {} observations, {} free parameters, {} runs per evaluation (seed {}), grid {} then {} refinement rounds",
        req.base.preset.name(),
        obs.len(),
        req.free.len(),
        req.runs,
        req.base.seed,
        req.grid,
        req.refine
    );
    let started = std::time::Instant::now();
    let mut count = 0;
    let fit = search(&small, &req.free, &obs, (req.grid, req.refine), |e| {
        count += 1;
        let at: Vec<String> = req
            .free
            .iter()
            .zip(&e.x)
            .map(|(f, v)| format!("{}={v:.4}", f.knob.name()))
            .collect();
        eprintln!(
            "  evaluation {count}: {} -> chi2 {:.3}, objective {:.3} ({:.0} s)",
            at.join(" "),
            e.chi2,
            e.objective,
            started.elapsed().as_secs_f64()
        );
    })?;
    write_outputs(req, &obs, &fit)?;
    let mut summary = summary_text(req, obs.len(), &fit);
    summary.push_str(&format!(
        "wrote parameters.csv, residuals.csv, evaluations.csv and fitted.toml in {} ({} evaluations, {:.0} s)\n",
        req.out.display(),
        fit.evaluations.len(),
        started.elapsed().as_secs_f64()
    ));
    Ok(summary)
}

/// The observations of the request's rig, refused when the run count cannot give the model's
/// uncertainty of a chi index (a bootstrap of at least `min_values` runs).
fn checked_observations(req: &Request) -> anyhow::Result<Vec<Observation>> {
    let (obs, other) = read_observations(&req.observed, req.base.preset)?;
    let chi = obs
        .iter()
        .any(|o| matches!(o.quantity, Quantity::ChiMu | Quantity::ChiSigma));
    let needed = vibcam_common::uncertainty::min_values(req.base.coverage).unwrap_or(2) as u64;
    if chi && req.runs < needed {
        return Err(bad_input(format!(
            "$runs {}: the chi_mu/chi_sigma observations need the model's bootstrap \
             uncertainty, which needs at least {needed} runs per evaluation (coverage {})",
            req.runs, req.base.coverage
        )));
    }
    if other > 0 {
        eprintln!(
            "{}: {other} rows of another rig left out",
            req.observed.display()
        );
    }
    Ok(obs)
}

/// `fitted.toml` (the study file with the fitted values), `parameters.csv`, `residuals.csv`
/// and `evaluations.csv`, each written atomically.
fn write_outputs(req: &Request, obs: &[Observation], fit: &Fit) -> anyhow::Result<()> {
    use vibcam_report::export::calibrate::{evaluations_csv, parameters_csv, residuals_csv};
    use vibcam_report::export::write_atomic;
    std::fs::create_dir_all(&req.out)
        .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", req.out.display()))?;
    let mut fitted = req.base.clone();
    for (f, v) in req.free.iter().zip(&fit.best.x) {
        let one = config_at(&fitted, std::slice::from_ref(f), &[*v], obs);
        (fitted.imaging, fitted.rig) = (one.imaging, one.rig);
    }
    let header = format!(
        "# fitted by `host-harness calibrate` to {} ({} observations, {} runs per evaluation)\n",
        req.observed.display(),
        obs.len(),
        req.runs
    );
    let out = |name: &str| req.out.join(name);
    write_atomic(&out("fitted.toml"), (header + &fitted.to_toml()).as_bytes())?;
    let rows = parameter_rows(&req.free, fit);
    write_atomic(&out("parameters.csv"), &parameters_csv(&rows))?;
    write_atomic(
        &out("residuals.csv"),
        &residuals_csv(&residual_rows(&fit.best)),
    )?;
    let names: Vec<&str> = req.free.iter().map(|f| f.knob.name()).collect();
    let evals = fit
        .evaluations
        .iter()
        .map(|e| (e.x.as_slice(), e.chi2, e.objective));
    write_atomic(&out("evaluations.csv"), &evaluations_csv(&names, evals))?;
    Ok(())
}

/// The printed result: the fitted values with their uncertainty, and the residuals.
fn summary_text(req: &Request, observations: usize, fit: &Fit) -> String {
    use std::fmt::Write as _;
    let mut summary = format!(
        "fitted (chi2 {:.3}, objective {:.3}, over {observations} observations):\n",
        fit.best.chi2, fit.best.objective,
    );
    for ((f, v), u) in req.free.iter().zip(&fit.best.x).zip(&fit.u) {
        let u = u.map_or("not determined (objective not convex there)".into(), |u| {
            format!("+/- {u:.4}")
        });
        let _ = writeln!(
            summary,
            "  {:<22} {v:.4} {u}   (range {} .. {})",
            f.knob.name(),
            f.lo,
            f.hi
        );
    }
    summary.push_str("mode | exposure_ms | quantity       |   observed |      model | residual\n");
    for r in &fit.best.residuals {
        let o = &r.observed;
        let _ = writeln!(
            summary,
            "{:>4} | {:>11} | {:<14} | {:>10.4} | {:>10.4} | {:>8.2}",
            o.mode,
            o.exposure_ms,
            o.quantity.name(),
            o.value,
            r.model,
            r.r
        );
    }
    summary
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn free_parameters_parse_and_name_what_is_wrong() {
        let f = parse_free("threshold_frac=0.1:0.9").unwrap();
        assert_eq!((f.knob, f.lo, f.hi), (Knob::ThresholdFrac, 0.1, 0.9));
        assert!(parse_free("radius=1:2")
            .unwrap_err()
            .contains("target_radius_px"));
        assert!(parse_free("gain=2:1")
            .unwrap_err()
            .contains("LO must be below HI"));
        assert!(parse_free("gain").unwrap_err().contains("NAME=LO:HI"));
        let f = parse_free("epsa_images=2:8").unwrap();
        assert!(f.knob.integer() && (f.lo, f.hi) == (2.0, 8.0));
        assert!(parse_free("epsa_images=1:8")
            .unwrap_err()
            .contains("whole numbers from 2"));
        assert!(parse_free("epsa_images=2:7.5")
            .unwrap_err()
            .contains("whole numbers"));
    }

    #[test]
    fn calibration_recovers_a_known_threshold() {
        // observations made by the model itself with the threshold at 0.3 of the target level
        // (off the grid): the search over 0.15..0.75 must come back to it. Grandstand, fixed
        // structure, the same 4 runs every time (common random numbers); the longest exposure's
        // amplitude falls smoothly as the threshold drops (binary centroid of the blurred disk).
        let mut base = StudyConfig::preset(Preset::Grandstand);
        base.runs = 4;
        base.fixed_structure = true;
        let free = [Free {
            knob: Knob::ThresholdFrac,
            lo: 0.15,
            hi: 0.75,
        }];
        let template: Vec<Observation> = [
            (40.0, Quantity::MuA),
            (180.0, Quantity::MuA),
            (180.0, Quantity::RatioToFirst),
        ]
        .iter()
        .map(|&(exposure_ms, quantity)| Observation {
            mode: 1,
            exposure_ms,
            quantity,
            value: 1.0,
            u: None,
        })
        .collect();
        let truth = evaluate(&base, &free, &[0.3], &template).unwrap();
        let obs: Vec<Observation> = truth
            .residuals
            .iter()
            .map(|r| Observation {
                value: r.model,
                ..r.observed.clone()
            })
            .collect();
        let fit = search(&base, &free, &obs, (4, 5), |_| {}).unwrap();
        assert!(
            (fit.best.x[0] - 0.3).abs() < 0.02,
            "fitted {}",
            fit.best.x[0]
        );
        assert!(fit.best.chi2 < 1.0, "chi2 {}", fit.best.chi2);
        let u = fit.u[0].expect("convex at the optimum");
        assert!(u > 0.0 && u < 0.2, "u {u}");
    }

    #[test]
    fn the_objective_charges_for_the_spread_a_noisier_model_buys() {
        // one observation 100 +/- 0 against two models: 101 with u 0.5 (r = 2) and a noisier
        // 103 with u 3 (r = 1). chi2 prefers the noisy one; the likelihood does not
        let obs = Observation {
            mode: 2,
            exposure_ms: 2.0,
            quantity: Quantity::ChiMu,
            value: 100.0,
            u: None,
        };
        let at = |model: f64, u_model: f64| Residual {
            observed: obs.clone(),
            model,
            u_model,
            r: (model - obs.value) / u_model,
        };
        let (tight, noisy) = ([at(101.0, 0.5)], [at(103.0, 3.0)]);
        assert!(noisy[0].r.powi(2) < tight[0].r.powi(2));
        let (a, b) = (objective(&tight), objective(&noisy));
        assert!((a - (4.0 + 0.25f64.ln())).abs() < 1e-12, "{a}");
        assert!((b - (1.0 + 9.0f64.ln())).abs() < 1e-12, "{b}");
        assert!(a < b);
        // a figure the model cannot give costs the penalty
        assert_eq!(objective(&[at(f64::NAN, 1.0)]), MISSING);
    }
}
