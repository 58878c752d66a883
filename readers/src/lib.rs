//! The files people measure with, read (the bottom layer of the host side, above
//! firmware-core only): camera frames ([`frames`]: PNG/TIFF/JPEG folders and patterns,
//! multi-page TIFF, Photron and Phantom files, videos through FFmpeg) and DAQ records
//! ([`daq`]: LabVIEW, TDMS, universal file 58, NumPy, CSV), CSV columns ([`csvio`]) and a structure's geometry ([`geometry`]). Every
//! error a file's content causes is a [`BadInput`] naming the file, and the row, frame, page
//! or channel; nothing here knows of studies, analyses or outputs.

pub mod csvio;
pub mod daq;
pub mod frames;
pub mod geometry;

/// An error caused by the user's input (a file, a field, a flag value). The binary exits with
/// code 2 when the error chain contains one; other failures exit with 1.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct BadInput(pub String);

/// Shorthand to build an [`anyhow::Error`] carrying [`BadInput`].
pub fn bad_input(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(BadInput(msg.into()))
}
