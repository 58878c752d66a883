//! `host-harness analyze` (under construction).

/// Arguments of `host-harness analyze`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `host-harness analyze`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`analyze` is not implemented yet")
}
