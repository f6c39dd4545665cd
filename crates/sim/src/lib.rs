//! # helicon-sim
//!
//! The world around the helicopter: sensor models, wind and turbulence, plots.
