//! The cantilever scenario (being written).

use super::{RunRecord, Scenario, StudyConfig};
use rand_chacha::ChaCha8Rng;

/// The cantilever scenario.
#[derive(Debug)]
pub struct Cantilever {}

impl Cantilever {
    /// Builds the scenario from a resolved configuration.
    pub fn new(_cfg: &StudyConfig) -> anyhow::Result<Self> {
        anyhow::bail!("the cantilever scenario is not implemented yet")
    }
}

impl Scenario for Cantilever {
    fn name(&self) -> &'static str {
        "cantilever"
    }
    fn amplitude_unit(&self) -> &'static str {
        ""
    }
    fn bands(&self) -> Vec<(f64, f64)> {
        Vec::new()
    }
    fn frf_freqs(&self) -> Vec<f64> {
        Vec::new()
    }
    fn run(&self, _run: u64, _rng: &mut ChaCha8Rng) -> anyhow::Result<RunRecord> {
        anyhow::bail!("not implemented")
    }
}
