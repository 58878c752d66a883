//! `host-harness plan`: the exposure planner (method.md §3.4) before a test. Parses the modes,
//! target, camera and tolerance from the flags or a study preset's model
//! ([`crate::plan::preset`]), runs [`crate::plan::plan`] for the chosen centroids, prints the
//! table and the warnings, and writes the CSV atomically with `--out`.

use super::args::ModeArg;
use crate::bad_input;
use crate::imaging::DiskTarget;
use crate::plan::{self, preset, Plan, PlanInput, PlanMode};
use crate::study::{Preset, StudyConfig};
use firmware_core::centroid::Mode;
use std::path::PathBuf;

/// Arguments of `host-harness plan`. Either `--preset`/`--config` (the modes, motion
/// amplitudes, target, threshold and frame rate of a study's model) or `--freqs-hz`,
/// `--amplitude-px` and `--fps`; explicit flags override the preset's values.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Take the modes, motion amplitudes, target, threshold and frame rate from this study
    /// preset's model (only `grandstand` is supported).
    #[arg(long, conflicts_with = "config", value_parser = super::args::choice(&Preset::ALL, Preset::name))]
    pub preset: Option<Preset>,
    /// Natural frequencies of the modes, Hz, comma separated (> 0).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    pub freqs_hz: Option<Vec<f64>>,
    /// Target disk radius, px (> 0; default 12, the grandstand's).
    #[arg(long, value_name = "PX", allow_negative_numbers = true)]
    pub target_radius_px: Option<f64>,
    /// Target grey level on the 8-bit scale, in (0, 255] (default 200).
    #[arg(long, value_name = "LEVEL", allow_negative_numbers = true)]
    pub target_level: Option<f64>,
    /// Gaussian edge sigma of the target, px (> 0; default 1.5).
    #[arg(long, value_name = "PX", allow_negative_numbers = true)]
    pub edge_sigma_px: Option<f64>,
    /// Threshold as a fraction of the target level, in [0, 1) (default 0.5).
    #[arg(long, value_name = "FRAC", allow_negative_numbers = true)]
    pub threshold_frac: Option<f64>,
    /// Camera frame rate, frames per second (> 0).
    #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
    pub fps: Option<f64>,
    /// Motion amplitude of the target in each mode, px (> 0): one value per mode, or one for all.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    pub amplitude_px: Option<Vec<f64>>,
    /// Largest acceptable amplitude loss, in (0, 1): 0.1 keeps the ratio >= 0.9.
    #[arg(long, default_value_t = 0.1, allow_negative_numbers = true)]
    pub tolerance: f64,
    /// Centroid(s) to plan for: one row per mode and centroid.
    #[arg(long, value_enum, default_value_t = CentroidChoice::Both)]
    pub centroid: CentroidChoice,
    /// Evaluate every row at this exposure, ms (>= 0); default: each mode's longest exposure.
    #[arg(long, value_name = "MS", allow_negative_numbers = true)]
    pub exposure_ms: Option<f64>,
    /// Study file (TOML, as `study --config`): its preset's model, as --preset.
    #[arg(long, value_name = "FILE.toml")]
    pub config: Option<PathBuf>,
    /// Write the rows as CSV to this file (atomically: a temporary file, then renamed).
    #[arg(long, value_name = "FILE.csv")]
    pub out: Option<PathBuf>,
}

/// `--centroid`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CentroidChoice {
    /// The binary centroid only (the studies').
    Binary,
    /// The weighted centroid only.
    Weighted,
    /// Both: binary rows, then weighted rows.
    Both,
}

impl CentroidChoice {
    fn modes(self) -> Vec<Mode> {
        match self {
            CentroidChoice::Binary => vec![ModeArg::Binary.mode()],
            CentroidChoice::Weighted => vec![ModeArg::Weighted.mode()],
            CentroidChoice::Both => vec![ModeArg::Binary.mode(), ModeArg::Weighted.mode()],
        }
    }
}

/// Refuses a value that is not finite and inside `ok`, naming the flag.
fn check(flag: &str, v: f64, ok: impl Fn(f64) -> bool, want: &str) -> anyhow::Result<()> {
    if v.is_finite() && ok(v) {
        Ok(())
    } else {
        Err(bad_input(format!("{flag} {v}: must be {want}")))
    }
}

/// The preset's input (from `--preset` or the study file's preset), if any.
fn preset_input(args: &Args) -> anyhow::Result<Option<PlanInput>> {
    let config = args
        .config
        .as_ref()
        .map(|p| StudyConfig::from_toml_file(p))
        .transpose()?;
    let preset = match &config {
        Some(c) => Some(c.preset),
        None => args.preset,
    };
    match preset {
        None => Ok(None),
        Some(Preset::Grandstand) => {
            let mut input = preset::grandstand_input(args.tolerance, Mode::Binary);
            if let Some(c) = &config {
                apply_imaging(&mut input, &c.imaging)?;
            }
            Ok(Some(input))
        }
        Some(p) => Err(bad_input(format!(
            "{} {}: the planner supports only the grandstand preset; give --freqs-hz, \
             --amplitude-px and --fps instead",
            if args.config.is_some() {
                "--config: preset"
            } else {
                "--preset"
            },
            p.name()
        ))),
    }
}

/// A study file's `[imaging]` table in the plan: its target and threshold replace the rig's;
/// the effects the planner does not model are named on stderr, never silently dropped.
fn apply_imaging(
    input: &mut PlanInput,
    imaging: &crate::imaging::ImagingOptions,
) -> anyhow::Result<()> {
    let (target, threshold) = imaging.target_and_threshold(input.target, input.threshold())?;
    input.target = target;
    input.threshold_frac = f64::from(threshold) / target.level;
    let ignored: Vec<&str> = [
        ("gain", imaging.gain.is_some()),
        ("distortion_k1", imaging.distortion_k1.is_some()),
        ("distortion_k2", imaging.distortion_k2.is_some()),
        (
            "optical_blur_sigma_px",
            imaging.optical_blur_sigma_px.is_some(),
        ),
        ("read_noise", imaging.read_noise.is_some()),
        (
            "shot_noise_e_per_level",
            imaging.shot_noise_e_per_level.is_some(),
        ),
        ("bits", imaging.bits.is_some()),
        ("exposure_alignment", imaging.exposure_alignment.is_some()),
        ("threshold_rule", imaging.threshold_rule.is_some()),
    ]
    .into_iter()
    .filter_map(|(name, set)| set.then_some(name))
    .collect();
    if !ignored.is_empty() {
        eprintln!(
            "note: the planner models the target, threshold and centroid of [imaging]; not: {}",
            ignored.join(", ")
        );
    }
    Ok(())
}

fn missing(flag: &str) -> anyhow::Error {
    bad_input(format!("missing {flag} (or give --preset)"))
}

/// The modes from `--freqs-hz` and `--amplitude-px`, else the preset's; errors name the flag.
fn resolve_modes(args: &Args, base: Option<&PlanInput>) -> anyhow::Result<Vec<PlanMode>> {
    let freqs = match (&args.freqs_hz, base) {
        (Some(f), _) => f.clone(),
        (None, Some(b)) => b.modes.iter().map(|m| m.f_hz).collect(),
        (None, None) => return Err(missing("--freqs-hz")),
    };
    let amps = match (&args.amplitude_px, base) {
        (Some(a), _) => a.clone(),
        // the preset's amplitudes belong to its own modes only
        (None, Some(b)) if args.freqs_hz.is_none() => {
            b.modes.iter().map(|m| m.amplitude_px).collect()
        }
        _ => return Err(missing("--amplitude-px")),
    };
    for &f in &freqs {
        check("--freqs-hz", f, |v| v > 0.0, "a positive frequency")?;
    }
    for &a in &amps {
        check("--amplitude-px", a, |v| v > 0.0, "a positive amplitude")?;
    }
    if amps.len() != 1 && amps.len() != freqs.len() {
        return Err(bad_input(format!(
            "--amplitude-px: {} values for {} modes (give one per mode, or one for all)",
            amps.len(),
            freqs.len()
        )));
    }
    Ok(freqs
        .iter()
        .enumerate()
        .map(|(i, &f_hz)| PlanMode {
            mode: i + 1,
            f_hz,
            amplitude_px: amps[i.min(amps.len() - 1)],
        })
        .collect())
}

/// The target from the flags, else the preset's, else the grandstand's defaults.
fn resolve_target(args: &Args, base: Option<&PlanInput>) -> anyhow::Result<DiskTarget> {
    let bt = base.map(|b| b.target);
    let target = DiskTarget {
        radius_px: args
            .target_radius_px
            .or(bt.map(|t| t.radius_px))
            .unwrap_or(12.0),
        level: args.target_level.or(bt.map(|t| t.level)).unwrap_or(200.0),
        edge_sigma_px: args
            .edge_sigma_px
            .or(bt.map(|t| t.edge_sigma_px))
            .unwrap_or(1.5),
        texture: crate::model::Texture::Plain,
    };
    check("--target-radius-px", target.radius_px, |v| v > 0.0, "> 0")?;
    let level_ok = |v: f64| v > 0.0 && v <= 255.0;
    check("--target-level", target.level, level_ok, "in (0, 255]")?;
    check("--edge-sigma-px", target.edge_sigma_px, |v| v > 0.0, "> 0")?;
    Ok(target)
}

/// The planner's input from the preset and the flags; errors name the flag at fault.
pub fn resolve(args: &Args) -> anyhow::Result<PlanInput> {
    let tolerance_ok = |v: f64| v > 0.0 && v < 1.0;
    check("--tolerance", args.tolerance, tolerance_ok, "in (0, 1)")?;
    let base = preset_input(args)?;
    let modes = resolve_modes(args, base.as_ref())?;
    let target = resolve_target(args, base.as_ref())?;
    let base_frac = base.as_ref().map(|b| b.threshold_frac);
    let threshold_frac = args.threshold_frac.or(base_frac).unwrap_or(0.5);
    let frac_ok = |v: f64| (0.0..1.0).contains(&v);
    check("--threshold-frac", threshold_frac, frac_ok, "in [0, 1)")?;
    let fps = match args.fps.or(base.as_ref().map(|b| b.fps)) {
        Some(f) => f,
        None => return Err(missing("--fps")),
    };
    check("--fps", fps, |v| v > 0.0, "a positive frame rate")?;
    if let Some(e) = args.exposure_ms {
        check("--exposure-ms", e, |v| v >= 0.0, ">= 0")?;
        let f_max = modes.iter().map(|m| m.f_hz).fold(0.0, f64::max);
        // the rendered transfer covers E2PR up to 4 (compensation::TransferSetup)
        let within = |v: f64| v * f_max / 1000.0 <= 4.0;
        check(
            "--exposure-ms",
            e,
            within,
            "at most 4 periods of the highest mode",
        )?;
    }
    Ok(PlanInput {
        modes,
        target,
        threshold_frac,
        fps,
        tolerance: args.tolerance,
        centroid: Mode::Binary,
        exposure_ms: args.exposure_ms,
        // the preset's record-wide motion, unless the flags describe another motion or camera
        motion: match (
            &args.amplitude_px,
            args.target_radius_px,
            args.threshold_frac,
        ) {
            (None, None, None) => base.and_then(|b| b.motion),
            _ => None,
        },
    })
}

/// The printed table of the plans (one per centroid) and their warnings.
pub fn table(input: &PlanInput, plans: &[Plan]) -> String {
    let t = &input.target;
    let mut s = format!(
        "plan: target radius {} px, level {}, edge sigma {} px; threshold {} ({} of the level); \
         {} fps (frame period {:.1} ms); tolerance {}\n",
        t.radius_px,
        t.level,
        t.edge_sigma_px,
        input.threshold(),
        input.threshold_frac,
        input.fps,
        1000.0 / input.fps,
        input.tolerance
    );
    s += &format!(
        "rows at {}\n\n",
        match input.exposure_ms {
            Some(e) => format!("the exposure {e} ms"),
            None => "each mode's longest exposure (max_exposure_ms)".to_string(),
        }
    );
    s += &format!(
        "{:>4} {:>7} {:>8} {:>8} {:>15} {:>6} {:>15} {:>20} {:>15}\n",
        "mode",
        "f_hz",
        "amp_px",
        "centroid",
        "max_exposure_ms",
        "e2pr",
        "predicted_ratio",
        "compensated_residual",
        "lost_frame_risk"
    );
    let mut warnings: Vec<String> = Vec::new();
    for p in plans {
        for (r, m) in p.rows.iter().zip(&input.modes) {
            let c = r.csv_record();
            s += &format!(
                "{:>4} {:>7.3} {:>8.3} {:>8} {:>15} {:>6.3} {:>15.4} {:>20.4} {:>15.3}\n",
                r.mode,
                r.f_hz,
                m.amplitude_px,
                c[2],
                r.max_exposure_ms
                    .map_or("-".to_string(), |e| format!("{e:.1}")),
                r.e2pr,
                r.predicted_ratio,
                r.compensated_residual,
                r.lost_frame_risk
            );
        }
        for w in &p.warnings {
            let line = format!("warning: {w}");
            if !warnings.contains(&line) {
                warnings.push(line);
            }
        }
    }
    for w in &warnings {
        s += &format!("\n{w}");
    }
    if !warnings.is_empty() {
        s.push('\n');
    }
    s
}

/// Runs `host-harness plan`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let input = resolve(&args)?;
    let mut plans = Vec::new();
    for centroid in args.centroid.modes() {
        let one = PlanInput {
            centroid,
            ..input.clone()
        };
        plans.push(plan::plan(&one).map_err(|e| bad_input(format!("plan: {e}")))?);
    }
    let mut text = table(&input, &plans);
    if args.preset.is_some() || args.config.is_some() {
        text.push_str(
            "transfer: averaged over the Welch segments of a nominal record, weighted by their \
             input energy, as the study's vision_compensated rows; lost-frame risk: peak of each \
             mode's response to the mean decay pulse (method.md §3.4)\n",
        );
    }
    super::stdout(&text)?;
    if let Some(path) = &args.out {
        let config: Vec<&std::path::Path> = args.config.iter().map(|p| p.as_path()).collect();
        plan::write_csv(path, &plans, &config)?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}
