//! `host-harness render` (under construction).

/// Arguments of `host-harness render`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `host-harness render`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`render` is not implemented yet")
}
