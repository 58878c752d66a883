//! Synthetic recordings (being written).
