//! End-to-end tests of `study` (under construction).
