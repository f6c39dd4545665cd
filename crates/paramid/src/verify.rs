//! Time-domain verification (placeholder, filled below).
