//! `host-harness study` (under construction).

/// Arguments of `host-harness study`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `host-harness study`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`study` is not implemented yet")
}
