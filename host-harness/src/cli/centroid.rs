//! `host-harness centroid` (under construction).

/// Arguments of `host-harness centroid`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `host-harness centroid`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`centroid` is not implemented yet")
}
