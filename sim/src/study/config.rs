//! What a study is: the preset, the run count, the exposures, the seed and the options, resolved
//! from the preset's defaults, a study file (`--config FILE.toml`) and the command line. Written
//! to `config.toml` in the study directory.

pub use crate::imaging::ImagingOptions;
use serde::{Deserialize, Serialize};
use std::path::Path;
use vibcam_readers::bad_input;

/// Which simulated measurement a study runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Preset {
    /// method.md §3.1: three-mode grandstand platform, decay test, 50 fps camera.
    Grandstand,
    /// method.md §3.2: base-excited aluminium cantilever, 120 fps camera, accelerometers.
    Cantilever,
}

impl Preset {
    /// Every preset.
    pub const ALL: [Preset; 2] = [Preset::Grandstand, Preset::Cantilever];

    /// `grandstand` or `cantilever`.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Grandstand => "grandstand",
            Preset::Cantilever => "cantilever",
        }
    }
}

/// The complete, resolved description of a study. Written to `config.toml` in the output
/// directory; a study file (`--config FILE.toml`) has the same fields, all optional except
/// `preset`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyConfig {
    /// Scenario.
    pub preset: Preset,
    /// Number of realizations (runs).
    pub runs: u64,
    /// Camera exposure times, ms.
    pub exposures_ms: Vec<f64>,
    /// Master seed: run `r` uses the stream derived from `(seed, r)`.
    pub seed: u64,
    /// Method-uncertainty variant (method.md §3.1, paper section 4.4): all modal parameter stds zero,
    /// only excitation and transducer noise vary.
    pub fixed_structure: bool,
    /// Highest frequency written to `frf_band.csv`, Hz.
    pub frf_max_hz: f64,
    /// Optional image-formation effects.
    #[serde(default)]
    pub imaging: ImagingOptions,
    /// Coverage probability of the intervals in `summary.csv` and `coverage.csv` (JCGM 101
    /// 7.7). Only the reporting depends on it: a study resumed or merged with another value
    /// reports with that one.
    #[serde(default = "default_coverage")]
    pub coverage: f64,
    /// The adaptive procedure (JCGM 101 7.9): `runs` is then the most runs it may take.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adaptive: Option<super::adaptive::AdaptiveConfig>,
    /// How the structure stands (the `[rig]` table); absent from `config.toml` when default.
    #[serde(default, skip_serializing_if = "RigOptions::is_default")]
    pub rig: RigOptions,
}

/// The `[rig]` table of a study file: how the structure stands, which the imaging cannot change.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
pub struct RigOptions {
    /// Cantilever only: how the beam stands in gravity, which decides what the tip
    /// accelerometer reads of its own tilt ([`vibcam_model::cantilever::Tilt`]); horizontal
    /// (none) when absent.
    pub beam_orientation: Option<vibcam_model::cantilever::Tilt>,
    /// Cantilever only: the beam's length, m (with an upright or hanging beam).
    pub beam_length_m: Option<f64>,
}

/// The shortest and longest beam `[rig] beam_length_m` takes, m.
pub const BEAM_LENGTH_RANGE_M: (f64, f64) = (0.02, 10.0);

impl RigOptions {
    fn is_default(&self) -> bool {
        *self == RigOptions::default()
    }

    /// The tip accelerometer's tilt gain (m/s^2 per radian) and the beam length (m) for the
    /// cantilever ([`vibcam_model::cantilever::Rig::accel_tilt_gain`]); the message names the
    /// field.
    pub fn accel_tilt(&self) -> anyhow::Result<(f64, f64)> {
        let tilt = self.beam_orientation.unwrap_or_default();
        let (lo, hi) = BEAM_LENGTH_RANGE_M;
        use vibcam_model::cantilever::Tilt;
        match (tilt, self.beam_length_m) {
            (Tilt::Horizontal, None) => Ok((0.0, 1.0)),
            (Tilt::Horizontal, Some(_)) => Err(bad_input(
                "rig.beam_length_m: only used with beam_orientation = \"upright\" or \"hanging\" \
                 (a horizontal beam's accelerometer reads no first-order tilt)",
            )),
            (_, None) => Err(bad_input(
                "rig.beam_length_m: an upright or hanging beam needs its length (m)",
            )),
            (_, Some(l)) if !(l.is_finite() && (lo..=hi).contains(&l)) => Err(bad_input(format!(
                "rig.beam_length_m: {l} m is outside {lo} .. {hi} m"
            ))),
            (t, Some(l)) => Ok((t.gain(), l)),
        }
    }
}

fn default_coverage() -> f64 {
    vibcam_common::uncertainty::DEFAULT_COVERAGE
}

/// A study file: every field optional except the preset, whose defaults fill the rest.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct StudyFile {
    preset: Preset,
    runs: Option<u64>,
    exposures_ms: Option<Vec<f64>>,
    seed: Option<u64>,
    fixed_structure: Option<bool>,
    frf_max_hz: Option<f64>,
    #[serde(default)]
    imaging: ImagingOptions,
    coverage: Option<f64>,
    adaptive: Option<super::adaptive::AdaptiveConfig>,
    #[serde(default)]
    rig: RigOptions,
}

/// Most runs one study directory takes (see [`StudyConfig::validate`]).
pub const MAX_RUNS: u64 = 1_000_000;

impl StudyConfig {
    /// Defaults of a preset. The grandstand run count is what finishes in about a minute on two
    /// cores; the paper used 1000.
    pub fn preset(preset: Preset) -> StudyConfig {
        match preset {
            Preset::Grandstand => StudyConfig {
                preset,
                runs: 100,
                exposures_ms: (0..8).map(|i| 40.0 + 20.0 * i as f64).collect(),
                seed: 1,
                fixed_structure: false,
                frf_max_hz: 5.0,
                imaging: ImagingOptions::default(),
                coverage: default_coverage(),
                adaptive: None,
                rig: RigOptions::default(),
            },
            Preset::Cantilever => StudyConfig {
                preset,
                runs: 100,
                exposures_ms: vec![2.0, 4.0, 6.0],
                seed: 1,
                fixed_structure: false,
                frf_max_hz: 60.0,
                imaging: ImagingOptions::default(),
                coverage: default_coverage(),
                adaptive: None,
                rig: RigOptions::default(),
            },
        }
    }

    /// Reads a study file (TOML); missing fields come from the preset's defaults.
    pub fn from_toml_file(path: &Path) -> anyhow::Result<StudyConfig> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| bad_input(format!("cannot read {}: {e}", path.display())))?;
        Self::from_toml_str(&text).map_err(|e| bad_input(format!("{}: {e:#}", path.display())))
    }

    /// Parses a study file from text.
    pub fn from_toml_str(text: &str) -> anyhow::Result<StudyConfig> {
        let f: StudyFile = toml::from_str(text)?;
        let d = StudyConfig::preset(f.preset);
        Ok(StudyConfig {
            preset: f.preset,
            runs: f.runs.unwrap_or(d.runs),
            exposures_ms: f.exposures_ms.unwrap_or(d.exposures_ms),
            seed: f.seed.unwrap_or(d.seed),
            fixed_structure: f.fixed_structure.unwrap_or(d.fixed_structure),
            frf_max_hz: f.frf_max_hz.unwrap_or(d.frf_max_hz),
            imaging: f.imaging,
            coverage: f.coverage.unwrap_or(d.coverage),
            adaptive: f.adaptive,
            rig: f.rig,
        })
    }

    /// Length of one simulated record of the preset, ms: the longest exposure that means
    /// anything (and bounds the path a frame integrates).
    pub fn record_ms(&self) -> f64 {
        match self.preset {
            Preset::Grandstand => vibcam_model::grandstand::DURATION_S * 1000.0,
            Preset::Cantilever => {
                1000.0 * vibcam_model::cantilever::FRAMES as f64 / vibcam_model::cantilever::FPS
            }
        }
    }

    /// Checks the values; the message names the field and the bound.
    pub fn validate(&self) -> anyhow::Result<()> {
        if self.runs == 0 {
            return Err(bad_input("runs: must be at least 1"));
        }
        if self.runs > MAX_RUNS {
            return Err(bad_input(format!(
                "runs: {} is more than one study directory holds ({MAX_RUNS}): every run keeps \
                 about 10 kB in memory for the aggregation and 25 kB in runs.jsonl; split larger \
                 studies into shards ($shard K/N) and merge them",
                self.runs
            )));
        }
        if let Some(e) = self.exposures_ms.iter().find(|e| **e > self.record_ms()) {
            return Err(bad_input(format!(
                "exposures_ms: {e} ms is longer than the simulated record ({} ms)",
                self.record_ms()
            )));
        }
        if self.exposures_ms.is_empty() {
            return Err(bad_input("exposures_ms: at least one exposure is needed"));
        }
        for e in &self.exposures_ms {
            if !(e.is_finite() && *e >= 0.0) {
                return Err(bad_input(format!(
                    "exposures_ms: {e} is not a non-negative number of milliseconds"
                )));
            }
        }
        let mut sorted = self.exposures_ms.clone();
        sorted.sort_by(f64::total_cmp);
        sorted.dedup();
        if sorted.len() != self.exposures_ms.len() {
            return Err(bad_input("exposures_ms: exposures must be distinct"));
        }
        if !(self.coverage > 0.0 && self.coverage < 1.0) {
            return Err(bad_input(format!(
                "coverage: {} must lie strictly between 0 and 1 (0.95 for 95 %)",
                self.coverage
            )));
        }
        if let Some(a) = &self.adaptive {
            a.validate(self.runs, self.coverage)?;
        }
        if !(self.frf_max_hz.is_finite() && self.frf_max_hz > 0.0) {
            return Err(bad_input("frf_max_hz: must be a positive number of Hz"));
        }
        match self.preset {
            Preset::Cantilever => {
                self.rig.accel_tilt()?;
            }
            Preset::Grandstand if !self.rig.is_default() => {
                return Err(bad_input(
                    "rig: beam_orientation and beam_length_m describe the cantilever; the \
                     grandstand has none",
                ));
            }
            Preset::Grandstand => {}
        }
        Ok(())
    }

    /// The configuration with the reporting-only fields (the coverage probability) at their
    /// defaults: two studies with the same key hold the same runs.
    pub fn runs_key(&self) -> StudyConfig {
        StudyConfig {
            coverage: default_coverage(),
            // every run has its own stream (seed, run index): the run count (an adaptive
            // study's cap) can be raised on resume without changing the runs already done
            runs: 0,
            ..self.clone()
        }
    }

    /// The resolved configuration as TOML text (written to `config.toml`).
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn study_file_fills_defaults_and_rejects_unknown_fields() {
        let c = StudyConfig::from_toml_str("preset = \"grandstand\"\nruns = 7\n").unwrap();
        assert_eq!(c.runs, 7);
        assert_eq!(
            c.exposures_ms,
            StudyConfig::preset(Preset::Grandstand).exposures_ms
        );
        assert!(StudyConfig::from_toml_str("preset = \"grandstand\"\nrunz = 7\n").is_err());
        // the resolved config round-trips through its TOML
        let back: StudyConfig = toml::from_str(&c.to_toml()).unwrap();
        assert_eq!(back, c);
    }

    #[test]
    fn validation_names_the_field() {
        let mut c = StudyConfig::preset(Preset::Grandstand);
        c.runs = 0;
        assert!(format!("{}", c.validate().unwrap_err()).starts_with("runs"));
        let mut c = StudyConfig::preset(Preset::Grandstand);
        c.exposures_ms = vec![40.0, 40.0];
        assert!(format!("{}", c.validate().unwrap_err()).starts_with("exposures_ms"));
    }

    #[test]
    fn the_rig_table_names_what_is_wrong() {
        let err = |text: &str| {
            let c = StudyConfig::from_toml_str(text).unwrap();
            format!("{:#}", c.validate().unwrap_err())
        };
        let e = err("preset = \"cantilever\"\n[rig]\nbeam_orientation = \"upright\"\n");
        assert!(
            e.contains("rig.beam_length_m") && e.contains("needs its length"),
            "{e}"
        );
        let e = err("preset = \"cantilever\"\n[rig]\nbeam_length_m = 0.2\n");
        assert!(e.contains("only used with beam_orientation"), "{e}");
        let e = err("preset = \"cantilever\"\n[rig]\nbeam_orientation = \"hanging\"\nbeam_length_m = 0.001\n");
        assert!(e.contains("outside 0.02 .. 10 m"), "{e}");
        let e = err(
            "preset = \"grandstand\"\n[rig]\nbeam_orientation = \"upright\"\nbeam_length_m = 0.2\n",
        );
        assert!(e.contains("the grandstand has none"), "{e}");
        assert!(StudyConfig::from_toml_str(
            "preset = \"cantilever\"\n[rig]\norientation = \"upright\"\n"
        )
        .is_err());
        // a valid table round-trips through config.toml; a default one is not written
        let c = StudyConfig::from_toml_str(
            "preset = \"cantilever\"\n[rig]\nbeam_orientation = \"upright\"\nbeam_length_m = 0.145\n",
        )
        .unwrap();
        c.validate().unwrap();
        assert_eq!(StudyConfig::from_toml_str(&c.to_toml()).unwrap(), c);
        assert!(!StudyConfig::preset(Preset::Cantilever)
            .to_toml()
            .contains("[rig]"));
    }

    #[test]
    fn every_committed_study_file_reads_and_validates() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../studies");
        let mut n = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml") {
                let c = StudyConfig::from_toml_file(&path).unwrap();
                c.validate()
                    .unwrap_or_else(|e| panic!("{}: {e:#}", path.display()));
                n += 1;
            }
        }
        assert!(n >= 4, "{n} study files in {}", dir.display());
    }
}
