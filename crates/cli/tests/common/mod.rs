//! Helpers shared by the CLI's test binaries: run the built `helicon` and a
//! scratch folder per test.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

use std::process::Command;

pub use helicon_test_support::tmpdir;

/// Run `helicon` with `args`: (success, stdout, stderr).
pub fn helicon(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}
