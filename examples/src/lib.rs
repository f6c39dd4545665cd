//! The numbered examples live under `examples/NN_name/main.rs`; run one with
//! `cargo run --release -p helicon-examples --example 01_trim_and_linearize`.
//! This library is empty: the package exists to build and test them.
