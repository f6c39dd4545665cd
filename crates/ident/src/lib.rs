//! # helicon-ident
//!
//! Frequency-domain system identification as rotorcraft flight testing
//! practises it (thesis chapter 11, after CIFER): flight-test [`inputs`],
//! frequency responses with coherence and random error, conditioned for
//! correlated inputs and composited over several windows ([`frf`]),
//! transfer-function fits with the coherence-weighted cost, Cramér–Rao
//! bounds and time-domain verification ([`fit`]), and Welch spectra
//! ([`spectral`]). Generic: any sampled channels, SI units, ω in rad/s.

pub mod error;
pub mod fit;
pub mod frf;
pub mod inputs;
pub mod servo;
pub mod spectral;

pub use error::{IdentError, Result};
pub use rustfft::num_complex::Complex64;
