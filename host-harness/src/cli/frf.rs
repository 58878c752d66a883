//! `host-harness frf` (under construction).

/// Arguments of `host-harness frf`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `host-harness frf`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`frf` is not implemented yet")
}
