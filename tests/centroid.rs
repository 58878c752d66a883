//! End-to-end tests of `centroid` (under construction).
