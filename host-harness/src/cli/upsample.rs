//! `host-harness upsample` (under construction).

/// Arguments of `host-harness upsample`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `host-harness upsample`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`upsample` is not implemented yet")
}
