//! Every file the tool writes, in one room: one module per family of outputs, each a pure
//! function from typed rows to bytes (testable without the disk), and [`write_atomic`], the one
//! way a single file reaches the disk. A directory of outputs is staged and moved into place by
//! [`crate::outdir::Staged`], which writes these bytes.
//!
//! Changing the columns of an output file touches one module here:
//!
//! | file(s) | module |
//! |---|---|
//! | study: `summary.csv`, `coverage.csv`, `realizations.csv`, `frf_band.csv`, `lost_frames.csv`, `adaptive.csv`, the printed table | [`study`] |
//! | `analyze`: `frf.csv`, `modes.csv`, `displacement.csv`, `compensation.csv` (one target) | [`analysis`] |
//! | `analyze --targets`: `frf.csv`, `modes.csv`, `displacement.csv`, `shapes.csv`, `mac.csv`, `compensation.csv` | [`targets`] |
//! | `frf.uff` (dataset 58) | [`uff`] |
//! | `frf --out`, its peaks, `upsample --out`, `centroid`'s rows | [`signals`] |
//! | `plan --out` | [`plan`] |
//! | `calibrate`: `parameters.csv`, `residuals.csv`, `evaluations.csv` | [`calibrate`] |
//! | `recording.toml`, a recording's `accel.csv` | [`recording`] |
//!
//! Numbers are written with Rust's shortest round-trip formatting (`Display`), so that a file
//! is exact and identical for identical numbers.
//!
//! Why not `#[derive(Serialize)]` rows: every float needs the same formatter (shortest
//! round-trip, an undefined value as an empty cell, never `NaN`), and some files keep `f32`
//! text; a header and the cells of its row side by side in one function ([`csv_bytes`]) keep a
//! column change to one place as well, without a `serialize_with` on every field. Files that
//! are read back (`recording.toml`, the study's `config.toml`) are serde types.

pub mod analysis;
pub mod calibrate;
pub mod ema;
pub mod field;
pub mod html;
pub mod labels;
pub mod oma;
pub mod pick;
pub mod picker;
pub mod plan;
pub mod recording;
pub mod scrub;
pub mod signals;
pub mod study;
pub mod targets;
pub mod uff;
pub mod wire;

use std::path::Path;

/// Formats a float for CSV: shortest representation that round-trips (Rust's `Display`). An
/// undefined value (a standard deviation of one run, a mean of none) is an empty cell, never
/// `NaN`.
pub fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        String::new()
    }
}

/// An optional value: its `Display`, or an empty cell.
pub fn opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map(|v| v.to_string()).unwrap_or_default()
}

/// CSV bytes: the `header` line, then the `cells` of each row joined by commas.
pub fn csv_bytes<T, const N: usize>(
    header: &str,
    rows: impl IntoIterator<Item = T>,
    cells: impl Fn(T) -> [String; N],
) -> Vec<u8> {
    let mut s = String::from(header);
    s.push('\n');
    for r in rows {
        s.push_str(&cells(r).join(","));
        s.push('\n');
    }
    s.into_bytes()
}

/// Writes `bytes` to `path` atomically: a temporary file in the same directory, synced, renamed
/// over `path`, and the directory synced, so that a reader (or a crash) sees the old file or the
/// new one, never a part.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    use std::io::Write as _;
    let dir = path.parent().unwrap_or(Path::new("."));
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("out");
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let write = || -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        vibcam_common::failpoint::hit("atomic-synced");
        std::fs::rename(&tmp, path)?;
        vibcam_common::failpoint::hit("atomic-renamed");
        if let Ok(d) = std::fs::File::open(dir) {
            d.sync_all().ok();
        }
        Ok(())
    };
    write().map_err(|e| {
        std::fs::remove_file(&tmp).ok();
        anyhow::Error::new(e).context(format!("cannot write {}", path.display()))
    })
}

/// The columns `modes.csv` of `modal` and `analyze` add to their own: each
/// estimate's standard uncertainty and 95 % interval.
pub const INTERVAL_COLUMNS: &str = "f_hz_u,f_hz_lo,f_hz_hi,damping_u,damping_lo,damping_hi,\
                                    amplitude_u,amplitude_lo,amplitude_hi";

/// The cells of [`INTERVAL_COLUMNS`], each after a comma (empty where not estimated).
pub(crate) fn push_intervals(s: &mut String, intervals: &[Option<(f64, f64, f64)>; 3]) {
    for i in intervals {
        let (u, lo, hi) = i.map_or((None, None, None), |(u, lo, hi)| {
            (Some(u), Some(lo), Some(hi))
        });
        s.push_str(&format!(",{},{},{}", opt(u), opt(lo), opt(hi)));
    }
}
