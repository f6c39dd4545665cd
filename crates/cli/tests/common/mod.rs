//! Helpers shared by the CLI's test binaries: run the built `helicon` and a
//! scratch folder per test.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

use std::path::PathBuf;
use std::process::Command;

/// A fresh scratch folder for one test: named after the test binary, the
/// process and `name`, emptied if a previous run left it.
pub fn tmpdir(name: &str) -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let binary = exe.file_stem().unwrap().to_string_lossy().into_owned();
    let d = std::env::temp_dir().join(format!("helicon_{binary}_{}_{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

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
