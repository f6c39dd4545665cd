//! The command line describes itself: shell completions and a manual page
//! generated from its definition, and old option spellings kept as aliases.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;
use common::{helicon, tmpdir};

#[test]
fn completions_cover_every_subcommand() {
    for shell in ["bash", "zsh", "fish"] {
        let (ok, out, err) = helicon(&["completions", shell]);
        assert!(ok, "{shell}: {err}");
        for sub in ["demo", "sim", "ident", "servo-bench", "completions", "man"] {
            assert!(out.contains(sub), "{shell} completions lack `{sub}`");
        }
    }
    let (ok, _, err) = helicon(&["completions", "tcsh-not-a-shell"]);
    assert!(!ok && err.contains("invalid value"), "{err}");
}

#[test]
fn man_page_is_roff_of_the_cli() {
    let (ok, out, err) = helicon(&["man"]);
    assert!(ok, "{err}");
    assert!(
        out.starts_with(".ie") || out.contains(".TH helicon"),
        "{}",
        &out[..200.min(out.len())]
    );
    for sub in ["demo", "trim", "linearize", "mc", "ident"] {
        assert!(out.contains(sub), "man page lacks `{sub}`");
    }
}

#[test]
fn sensors_simulate_takes_duration_and_its_old_spelling() {
    let d = tmpdir("duration");
    for (flag, file) in [("--duration", "a.csv"), ("--duration-s", "b.csv")] {
        let out = d.join(file);
        let (ok, _, err) = helicon(&[
            "sensors",
            "simulate",
            flag,
            "0.5",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(ok, "{flag}: {err}");
    }
    assert_eq!(
        std::fs::read(d.join("a.csv")).unwrap(),
        std::fs::read(d.join("b.csv")).unwrap()
    );
}
