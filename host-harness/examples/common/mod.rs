//! What several examples share: the 5-target cantilever recording they measure, rendered by
//! the `host-harness` binary built beside them.

use std::path::Path;

/// Renders `render --preset cantilever --recording DIR --targets 5 --exposure-ms 2` plus
/// `extra` (read noise, scene) into `dir`, with the `host-harness` binary of the same build.
pub fn render_targets(dir: &Path, extra: &[&str]) -> anyhow::Result<()> {
    let exe = std::env::current_exe()?;
    let bin = exe
        .parent()
        .and_then(|p| p.parent())
        .map(|p| p.join("host-harness"))
        .filter(|p| p.is_file())
        .ok_or_else(|| anyhow::anyhow!("build host-harness first (cargo build --release)"))?;
    let ok = std::process::Command::new(bin)
        .args(["render", "--preset", "cantilever", "--recording"])
        .arg(dir)
        .args(["--targets", "5", "--exposure-ms", "2"])
        .args(extra)
        .output()?
        .status
        .success();
    anyhow::ensure!(ok, "render failed");
    Ok(())
}
