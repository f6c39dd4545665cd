//! Helpers of the SITL tests.
#![allow(dead_code)]

pub mod client;
pub mod harness;
pub mod vehicle;
