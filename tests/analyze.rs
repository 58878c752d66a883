//! End-to-end tests of `analyze` (under construction).
