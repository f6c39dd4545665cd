//! Outputs (placeholder, filled below).
