//! `host-harness merge` (under construction).

/// Arguments of `host-harness merge`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `host-harness merge`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`merge` is not implemented yet")
}
