//! # helicon-python
//!
//! The Python package `helicon`: the model, trim and linearization of
//! `helicon-model`, the LTI design of `helicon-lti`, closed-loop flights and
//! Monte Carlo campaigns of `helicon-sim`, frequency responses of
//! `helicon-ident` and the flight-log reader of `helicon-ulog`, with NumPy
//! `float64` arrays in and out (SI units, the state and input orders of
//! docs/model.md).
//!
//! The crate has two layers:
//!
//! - the binding-free core ([`batch`], [`conditions`], [`frf`], [`logs`],
//!   [`mc`], [`ulog`]): plain Rust on slices and the library types, every
//!   input validated and every failure a [`Error`] carrying the library's
//!   message. It builds and is tested with the workspace (`cargo test
//!   --workspace`), no Python needed;
//! - the extension module `helicon._helicon` (behind the `python` feature,
//!   which maturin turns on): thin PyO3 wrappers that convert NumPy arrays
//!   to slices, release the GIL around the work, check for Ctrl-C between
//!   the cases of a flight and the runs of a campaign, and raise
//!   `helicon.HeliconError` (a `ValueError`) with the core's message.
//!
//! Nothing here panics on input: shapes, lengths and finiteness are checked
//! before any library call, so no input can abort the interpreter.
//!
//! See docs/python.md for the Python API.

pub mod batch;
pub mod conditions;
pub mod error;
pub mod frf;
pub mod logs;
pub mod mc;
pub mod params;
pub mod ulog;

#[cfg(feature = "python")]
mod bindings;

pub use error::Error;
