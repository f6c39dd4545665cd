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
fn man_out_writes_a_page_per_subcommand() {
    let d = tmpdir("man");
    let dir = d.join("man");
    let (ok, _, err) = helicon(&["man", "--out", dir.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(err.contains("manual pages to"), "{err}");
    for page in [
        "helicon",
        "helicon-sim",
        "helicon-ident-frf",
        "helicon-control-c2d",
    ] {
        let text = std::fs::read_to_string(dir.join(format!("{page}.1"))).unwrap();
        assert!(text.contains(".TH"), "{page}: {text}");
    }
    let sim = std::fs::read_to_string(dir.join("helicon-sim.1")).unwrap();
    assert!(sim.contains("duration"), "{sim}");
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

#[test]
fn c2d_takes_dt_and_its_old_spelling() {
    let d = tmpdir("c2d-dt");
    let a = d.join("A.csv");
    let b = d.join("B.csv");
    std::fs::write(&a, "0,1\n0,0\n").unwrap();
    std::fs::write(&b, "0\n1\n").unwrap();
    let run = |flag: &str| {
        let (ok, out, err) = helicon(&[
            "control",
            "c2d",
            "--a",
            a.to_str().unwrap(),
            "--b",
            b.to_str().unwrap(),
            flag,
            "0.1",
        ]);
        assert!(ok, "{flag}: {err}");
        out
    };
    assert_eq!(run("--dt"), run("--ts"));
    // the help names the one spelling
    let (_, help, _) = helicon(&["control", "c2d", "--help"]);
    assert!(help.contains("--dt") && !help.contains("--ts"), "{help}");
}

#[test]
fn shaker_takes_duration_and_its_old_spelling() {
    let (_, help, _) = helicon(&["sensors", "shaker", "--help"]);
    assert!(
        help.contains("--duration <") && !help.contains("--duration-s"),
        "{help}"
    );
    // both spellings are the one option: a value that is not a number is
    // refused as that option's, not as an unknown argument
    for flag in ["--duration", "--duration-s"] {
        let (ok, _, err) = helicon(&["sensors", "shaker", flag, "five"]);
        assert!(
            !ok && err.contains("invalid value 'five' for '--duration"),
            "{flag}: {err}"
        );
    }
}

/// A misspelt key in a scenario, a parameter file and an on-board
/// configuration: the error names the file and the key, and the nearest
/// valid key.
#[test]
fn unknown_keys_get_the_nearest_valid_one() {
    let d = tmpdir("did-you-mean");
    let scenario = d.join("s.toml");
    std::fs::write(&scenario, "name = \"x\"\nduraton_s = 2\n").unwrap();
    let (ok, _, err) = helicon(&[
        "sim",
        scenario.to_str().unwrap(),
        "--out",
        d.join("o").to_str().unwrap(),
    ]);
    assert!(!ok, "{err}");
    assert!(
        err.contains("s.toml")
            && err.contains("unknown field `duraton_s`")
            && err.contains("did you mean `duration_s`?"),
        "{err}"
    );
    let params = d.join("p.toml");
    std::fs::write(&params, "[main_rotor]\nradus_m = 0.9\n").unwrap();
    let (ok, _, err) = helicon(&["trim", "--params", params.to_str().unwrap()]);
    assert!(!ok, "{err}");
    assert!(
        err.contains("p.toml") && err.contains("did you mean `main_rotor.radius_m`?"),
        "{err}"
    );
    // clap's own suggestions for flags are on
    let (ok, _, err) = helicon(&["trim", "--paramz", "x"]);
    assert!(
        !ok && err.contains("similar argument exists: '--params'"),
        "{err}"
    );
}
