//! # helicon-ident
//!
//! Frequency-domain system identification as rotorcraft flight testing
//! practises it (thesis chapter 11, after CIFER): flight-test [`inputs`],
//! the check that the input was excited ([`excitation`]),
//! frequency responses with coherence and random error, conditioned for
//! correlated inputs and composited over several windows ([`frf`]),
//! transfer-function fits with the coherence-weighted cost, Cramér–Rao
//! bounds and time-domain verification ([`fit`]), linear state-space fits
//! with chosen free entries to one or several responses ([`ssfit`]), the
//! shared cost and accuracy ([`cost`]), and Welch spectra
//! ([`spectral`]). Generic: any sampled channels, SI units, ω in rad/s.

pub mod cost;
pub mod error;
pub mod excitation;
pub mod fit;
pub mod frf;
/// The flight-test input programs (`helicon-setup`: the on-board program flies them too).
pub use helicon_setup::inputs;
pub mod servo;
pub mod spectral;
pub mod ssfit;

pub use error::{IdentError, Result};
pub use rustfft::num_complex::Complex64;
