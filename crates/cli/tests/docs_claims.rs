//! Claims of the documentation that must hold, checked against the built
//! binary: the project stands alone (no citation of files outside the
//! repository), `--params` where the README says, the demo printout of
//! docs/closed-loop.md, the plot files docs/sensors.md names, the
//! divergence time in the Appendix F scenario's comment, the Figure 14.5
//! figures of docs/closed-loop-results.md.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

use helicon_test_support::tmpdir;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

fn helicon(dir: &Path, args: &[&str]) -> Output {
    let o = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "helicon {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// README, the model, closed-loop and sensors pages and the scenarios cite
/// no file outside the repository (the specification notes the project was
/// written from are not shipped).
#[test]
fn docs_cite_no_file_outside_the_repository() {
    let mut files = vec![
        "README.md".to_string(),
        "docs/model.md".to_string(),
        "docs/closed-loop.md".to_string(),
        "docs/sensors.md".to_string(),
    ];
    for e in std::fs::read_dir(root().join("scenarios")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            files.push(format!(
                "scenarios/{}",
                p.file_name().unwrap().to_string_lossy()
            ));
        }
    }
    for f in &files {
        let text = read(f);
        for needle in ["shared/", "MODEL.md", "DESIGN.md", "../shared"] {
            assert!(!text.contains(needle), "{f} cites `{needle}`");
        }
    }
}

/// The README lists the subcommands that take `--params`, and that
/// `helicon sim` takes `--params`, `--seed` and `--duration`: each `--help`
/// must say so.
#[test]
fn readme_params_list_holds() {
    let readme = read("README.md");
    let marker = "--params my_heli.toml: ";
    let start = readme
        .find(marker)
        .expect("README lists the --params subcommands")
        + marker.len();
    let list = &readme[start..start + readme[start..].find(')').unwrap()];
    let cmds: Vec<&str> = list.split(", ").collect();
    assert!(cmds.len() >= 8, "{cmds:?}");
    let d = tmpdir("params");
    for cmd in cmds {
        let mut args: Vec<&str> = cmd.split_whitespace().collect();
        args.push("--help");
        let help = String::from_utf8(helicon(&d, &args).stdout).unwrap();
        assert!(
            help.contains("--params"),
            "`helicon {cmd} --help` lacks --params"
        );
    }
    assert!(readme.contains("`helicon sim` takes `--params FILE`, `--seed N`"));
    let help = String::from_utf8(helicon(&d, &["sim", "--help"]).stdout).unwrap();
    for opt in ["--params <FILE>", "--seed <SEED>", "--duration <S>"] {
        assert!(help.contains(opt), "sim --help lacks {opt}");
    }
}

/// Mask the wall times of a demo printout (they vary run to run).
fn mask_times(line: &str) -> String {
    if line.starts_with("  times:") || line.starts_with("demo done in") {
        return "<times>".to_string();
    }
    // "... Kalman predictor |z|max = 0.95802 (0.00 s)": the design time
    match line.rfind(" (") {
        Some(i) if line.starts_with("3. designed") && line.ends_with(" s)") => {
            format!("{} (<time>)", &line[..i])
        }
        _ => line.to_string(),
    }
}

/// docs/closed-loop-results.md's Figure 14.5 figures are what
/// `helicon sim scenarios/thesis-fig14-5.toml` computes: each case's
/// settling time and overshoot of the stepped output, the coupled outputs'
/// settling times (case (a)'s horizontal velocities, the largest of the
/// others) and the vertical dip of the half turn.
#[test]
fn closed_loop_results_fig14_5_figures_are_computed() {
    let doc = read("docs/closed-loop-results.md");
    let section = &doc[doc.find("## Figure 14.5").expect("the Figure 14.5 section")..];
    let section = &section[..section[3..].find("\n## ").map_or(section.len(), |i| i + 3)];
    let d = tmpdir("fig14-5");
    helicon(
        &d,
        &[
            "sim",
            root()
                .join("scenarios/thesis-fig14-5.toml")
                .to_str()
                .unwrap(),
            "--out",
            "o",
        ],
    );
    let metrics = |case: &str| -> serde_json::Value {
        let text = std::fs::read_to_string(d.join("o").join(case).join("summary.json")).unwrap();
        serde_json::from_str::<serde_json::Value>(&text).unwrap()["metrics"].clone()
    };
    let outputs = ["vn", "ve", "vd", "psi"];
    let mut coupled_other: f64 = 0.0;
    for (case, stepped, label) in [
        ("a", "psi", "| (a) ψ = π | ψ |"),
        ("b", "vn", "| (b) vn = 2 m/s | vn |"),
        ("c", "ve", "| (c) ve = 2 m/s | ve |"),
        ("d", "vd", "| (d) vd = 2 m/s | vd |"),
    ] {
        let m = metrics(case);
        let row = format!(
            "{label} {:.2} s | {:.1} % |",
            m[stepped]["settling_time_s"].as_f64().unwrap(),
            m[stepped]["overshoot_pct"].as_f64().unwrap()
        );
        assert!(
            section.contains(&row),
            "docs/closed-loop-results.md lacks the row `{row}`"
        );
        if case != "a" {
            for o in outputs.iter().filter(|o| **o != stepped) {
                coupled_other = coupled_other.max(m[*o]["settling_time_s"].as_f64().unwrap());
            }
        }
    }
    let a = metrics("a");
    let settle = |o: &str| a[o]["settling_time_s"].as_f64().unwrap();
    let (lo, hi) = (
        settle("vn").min(settle("ve")),
        settle("vn").max(settle("ve")),
    );
    assert!(
        settle("vd") <= hi,
        "case (a): vd settles after the horizontal velocities"
    );
    let claim = format!(
        "The coupled outputs settle within {:.1} s: the horizontal velocities of case (a) at {:.1}–{:.1} s,\nevery other within {:.2} s; the largest coupling is the {:.3} m/s vertical dip",
        hi.max(coupled_other),
        lo,
        hi,
        coupled_other.max(settle("vd")),
        a["vd"]["max_abs_error"].as_f64().unwrap()
    );
    assert!(
        section.contains(&claim),
        "docs/closed-loop-results.md: the coupled outputs' sentence should read:\n{claim}"
    );
}

/// The demo printout quoted in docs/closed-loop.md is what
/// `helicon demo --out out/demo` prints today (wall times masked).
#[test]
fn closed_loop_doc_demo_printout_is_current() {
    let doc = read("docs/closed-loop.md");
    let start = doc
        .find("```\nhelicon demo: ")
        .expect("docs/closed-loop.md quotes the demo printout")
        + 4;
    let quoted = &doc[start..start + doc[start..].find("```").unwrap()];
    let d = tmpdir("demo");
    let out = helicon(&d, &["demo", "--out", "out/demo"]).stdout;
    let printed = String::from_utf8(out).unwrap();
    let a: Vec<String> = quoted.lines().map(mask_times).collect();
    let b: Vec<String> = printed.lines().map(mask_times).collect();
    assert_eq!(
        a, b,
        "docs/closed-loop.md's demo printout is stale: regenerate it with `cargo run --release -- demo`"
    );
}

/// Every figure docs/sensors.md shows exists, and the files it says
/// `helicon fuse` writes are written.
#[test]
fn sensors_doc_names_files_that_exist() {
    let doc = read("docs/sensors.md");
    let mut shown = 0;
    for part in doc.split("](sensors/").skip(1) {
        let name = &part[..part.find(')').unwrap()];
        assert!(
            root().join("docs/sensors").join(name).exists(),
            "docs/sensors/{name} is shown but missing"
        );
        shown += 1;
    }
    assert!(shown >= 9, "{shown}");
    // the fuse comment names run/<file> entries
    let line = doc
        .lines()
        .find(|l| l.starts_with("helicon fuse log.csv --out run"))
        .expect("the fuse command line");
    let named: Vec<&str> = line
        .split_whitespace()
        .filter_map(|w| w.trim_end_matches(',').strip_prefix("run/"))
        .collect();
    assert!(named.len() >= 2, "{line}");
    let d = tmpdir("fuse");
    helicon(
        &d,
        &[
            "sensors",
            "simulate",
            "--duration-s",
            "2",
            "--out",
            "log.csv",
        ],
    );
    helicon(&d, &["fuse", "log.csv", "--out", "run"]);
    for f in named {
        assert!(d.join("run").join(f).exists(), "fuse did not write run/{f}");
    }
    assert!(d.join("run/fused.csv").exists() && d.join("run/summary.json").exists());
}

/// scenarios/thesis-appendix-f.toml says when its thesis-inflow cases spin
/// away: `helicon sim` must agree (to the printed 0.01 s).
#[test]
fn appendix_f_comment_states_the_divergence_time() {
    let text = read("scenarios/thesis-appendix-f.toml");
    let d = tmpdir("appf");
    let scenario = root().join("scenarios/thesis-appendix-f.toml");
    helicon(
        &d,
        &[
            "sim",
            scenario.to_str().unwrap(),
            "--duration",
            "1.5",
            "--out",
            "o",
        ],
    );
    for case in ["thesis-inflow", "aggressive-thesis-inflow"] {
        let v: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(d.join("o").join(case).join("summary.json")).unwrap(),
        )
        .unwrap();
        assert_eq!(v["outcome"], "diverged", "{case}");
        let t = format!("t = {:.2} s", v["t_end_s"].as_f64().unwrap());
        assert!(
            text.contains(&t),
            "the scenario comment should say `{t}` for {case}"
        );
    }
}

/// The thesis hover-trim table of docs/trim-linearize.md: the printed
/// values the trim does not match to 3 significant digits (rounded or
/// truncated) are exactly the ones the text lists, computed from
/// `helicon trim --preset thesis --json`; and the README says the same.
#[test]
fn trim_doc_lists_the_values_that_miss_the_printed_digits() {
    let doc = read("docs/trim-linearize.md");
    let d = tmpdir("trimdoc");
    let out = helicon(&d, &["trim", "--preset", "thesis", "--json"]).stdout;
    let v: serde_json::Value = serde_json::from_slice(&out).unwrap();
    let value = |name: &str| -> f64 {
        let key = match name {
            "φ" => "phi",
            "θ" => "theta",
            "θ0" => "theta0",
            "θtr" => "theta_tr",
            "λmr" => "lambda_mr",
            "λtr" => "lambda_tr",
            n => n,
        };
        v["input"][key]
            .as_f64()
            .or_else(|| v["state"][key].as_f64())
            .or_else(|| v[key].as_f64())
            .unwrap_or_else(|| panic!("no `{key}` in the trim JSON"))
    };
    // `x` shown with 3 significant digits, rounded or truncated, reads `printed`
    let matches = |x: f64, printed: f64| {
        let e = printed.abs().log10().floor() - 2.0;
        let unit = 10f64.powf(e);
        let (r, t) = ((x / unit).round(), (x / unit).trunc());
        let p = (printed / unit).round();
        r == p || t == p
    };
    let start = doc
        .find("| quantity | (12.10)/(12.11) |")
        .expect("the trim table");
    let mut missed = Vec::new();
    let mut rows = 0;
    for line in doc[start..].lines().skip(2) {
        if !line.starts_with('|') {
            break;
        }
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let names: Vec<&str> = cells[1].split(", ").collect();
        let printed: Vec<f64> = cells[2]
            .split(", ")
            .map(|p| p.replace('−', "-").parse().unwrap())
            .collect();
        assert_eq!(names.len(), printed.len(), "{line}");
        for (n, p) in names.iter().zip(printed) {
            rows += 1;
            if !matches(value(n), p) {
                missed.push(n.to_string());
            }
        }
    }
    assert!(rows >= 17, "{rows} values in the table");
    let said = doc
        .split("Every printed value but ")
        .nth(1)
        .and_then(|t| t.split(" is matched").next())
        .expect("the sentence naming the exceptions");
    let mut said: Vec<String> = said
        .replace(" and ", ", ")
        .split(", ")
        .map(str::to_string)
        .collect();
    said.sort();
    missed.sort();
    assert_eq!(
        said, missed,
        "docs/trim-linearize.md names the wrong exceptions"
    );
    let readme = read("README.md");
    for n in &missed {
        assert!(
            readme.contains("all but b1") && readme.contains(n.as_str()),
            "README does not name {n}"
        );
    }
}
