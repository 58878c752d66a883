//! End-to-end tests of `signal` (under construction).
