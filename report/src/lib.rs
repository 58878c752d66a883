//! Results to bytes, and bytes to disk complete or not at all: every output file's columns
//! ([`export`]: typed rows -> CSV, UFF, TOML, HTML; `write_atomic`), the figures ([`plots`]:
//! PNG and SVG), output directories that are complete or absent ([`outdir`]: staged, synced,
//! moved into place, with their manifest), and the block opening every report ([`provenance`]:
//! date, version, command, inputs with their SHA-256, settings, machine); [`pdf`] prints a
//! page through a headless Chromium. Nothing here computes a measurement.

pub mod export;
pub mod outdir;
pub mod pdf;
pub mod plots;
pub mod provenance;
