//! The README's "A short tour" block runs as written: every line, in order,
//! in one scratch folder holding copies of `scenarios/`, `campaigns/`,
//! `examples/` and `params/` (what a fresh clone has), through `sh -c` with
//! the built `helicon` first on `PATH`. A README edit that breaks a command
//! (a missing input file, a renamed option, a folder an earlier line no
//! longer writes) fails here.
//!
//! Every PNG the tour writes is checked to be a rendered picture.
//!
//! The exceptions are the ones the README states below the block: `mc` runs
//! `--runs 10` instead of 1000, `onboard` (real serial devices), `gcs`
//! (waits for a vehicle until stopped), `sitl --ardupilot-json` and `sitl
//! --px4` (wait for the autopilot) are not run.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The tour block's lines, without their `#` comments; comment-only
/// continuation lines are dropped.
fn tour_commands(readme: &str) -> Vec<String> {
    let start = readme
        .find("## A short tour")
        .expect("the README has a tour section");
    let rest = &readme[start..];
    let open = rest.find("```\n").expect("the tour has a code block") + 4;
    let close = open + rest[open..].find("```").expect("the tour block is closed");
    rest[open..close]
        .lines()
        .map(strip_comment)
        .filter(|l| !l.is_empty())
        .collect()
}

/// A line without its shell comment: from the first `#` that starts a word
/// outside quotes.
fn strip_comment(line: &str) -> String {
    let mut quote: Option<char> = None;
    let mut prev = ' ';
    for (i, c) in line.char_indices() {
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => {}
            None if c == '\'' || c == '"' => quote = Some(c),
            None if c == '#' && prev.is_whitespace() => return line[..i].trim().to_string(),
            None => {}
        }
        prev = c;
    }
    line.trim().to_string()
}

/// What the test does with one tour line: run it as written, run it with a
/// smaller workload, or not run it, each with the reason the README gives.
enum Plan {
    AsWritten(String),
    Shortened(String),
    NotRun(&'static str),
}

fn plan(line: &str) -> Plan {
    if line.starts_with("helicon gcs") {
        return Plan::NotRun("waits for a vehicle until stopped");
    }
    if line.contains("--ardupilot-json") {
        return Plan::NotRun("waits for ArduPilot's SITL until stopped");
    }
    if line.contains("--px4") {
        return Plan::NotRun("waits for PX4's SITL until stopped");
    }
    if line.starts_with("helicon onboard") {
        return Plan::NotRun("needs the helicopter's serial devices");
    }
    if line.starts_with("helicon mc ") && line.contains("--slurm") {
        // no cluster here: the scripts are written and nothing is submitted
        // (tools/slurm/one-node.sh submits to a real one-node Slurm)
        return Plan::Shortened(format!("{line} --dry-run"));
    }
    if line.starts_with("helicon mc ") && line.contains("--runs 1000") {
        return Plan::Shortened(line.replace("--runs 1000", "--runs 10"));
    }
    Plan::AsWritten(line.to_string())
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), &target).unwrap();
        }
    }
}

/// Every `--out X` / `--csv X` folder or file a command names exists after it.
fn named_outputs(cmd: &str) -> Vec<String> {
    let words: Vec<&str> = cmd.split_whitespace().collect();
    words
        .windows(2)
        .filter(|w| w[0] == "--out" || w[0] == "--csv")
        .map(|w| w[1].to_string())
        .collect()
}

#[test]
fn strip_comment_keeps_quoted_hashes() {
    assert_eq!(strip_comment("helicon demo   # the demo"), "helicon demo");
    assert_eq!(strip_comment("echo '# not' | x  # yes"), "echo '# not' | x");
    assert_eq!(strip_comment("   # only a comment"), "");
    assert_eq!(strip_comment("a#b"), "a#b");
}

#[test]
fn readme_tour_runs_as_written() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let lines = tour_commands(&readme);
    assert!(lines.len() >= 25, "the tour has {} lines", lines.len());
    let dir = helicon_test_support::tmpdir("tour");
    for sub in ["scenarios", "campaigns", "examples", "params"] {
        copy_dir(&root().join(sub), &dir.join(sub));
    }
    let bin = Path::new(env!("CARGO_BIN_EXE_helicon")).parent().unwrap();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let (mut ran, mut skipped) = (0, Vec::new());
    for line in &lines {
        assert!(
            line.starts_with("helicon ") || line.starts_with("echo "),
            "a tour line that is not a helicon command: `{line}`"
        );
        let cmd = match plan(line) {
            Plan::AsWritten(c) | Plan::Shortened(c) => c,
            Plan::NotRun(why) => {
                skipped.push(format!("{line}: {why}"));
                continue;
            }
        };
        let out = Command::new("sh")
            .arg("-c")
            .arg(&cmd)
            .current_dir(&dir)
            .env("PATH", &path)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            out.status.success(),
            "README tour line failed: `{cmd}`\n{stderr}"
        );
        assert!(
            !stderr.contains("error"),
            "README tour line `{cmd}` printed an error: {stderr}"
        );
        for f in named_outputs(&cmd) {
            assert!(dir.join(&f).exists(), "`{cmd}` did not write {f}");
        }
        ran += 1;
    }
    // the two not run are the two the README names
    assert_eq!(skipped.len(), 4, "{skipped:?}");
    assert!(ran >= 25, "{ran} tour lines ran");
    // every plot the tour makes was rendered: a PNG with a picture in it
    let mut pngs = Vec::new();
    collect_pngs(&dir.join("out"), &mut pngs);
    collect_pngs(&dir.join("gains"), &mut pngs);
    assert!(pngs.len() >= 60, "{} plots", pngs.len());
    for p in &pngs {
        let bytes = std::fs::read(p).unwrap();
        assert!(
            bytes.starts_with(b"\x89PNG\r\n\x1a\n") && bytes.len() > 8_000,
            "{}: not a rendered PNG ({} bytes)",
            p.display(),
            bytes.len()
        );
    }
}

fn collect_pngs(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            collect_pngs(&p, out);
        } else if p.extension().is_some_and(|x| x == "png") {
            out.push(p);
        }
    }
}
