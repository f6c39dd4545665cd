//! `helicon eval`, `params`, `trim` and `linearize` end to end.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::io::Write;
use std::process::{Command, Stdio};

fn helicon() -> Command {
    Command::new(env!("CARGO_BIN_EXE_helicon"))
}

fn run_with_stdin(args: &[&str], stdin: &str) -> std::process::Output {
    let mut child = helicon()
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(stdin.as_bytes())
        .unwrap();
    child.wait_with_output().unwrap()
}

#[test]
fn eval_reads_json_lines_and_names_bad_lines() {
    let mut x = vec![0.0; 30];
    x[3] = 0.0573;
    x[12] = 0.016;
    x[22] = 0.1295;
    x[25] = 0.1114;
    let good = format!("{{\"x\": {:?}, \"u\": [0.185, 0.0003, -0.0008, 0.159]}}", x);
    let out = run_with_stdin(
        &["eval", "--preset", "thesis"],
        &format!("{good}\n{good}\n"),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 2);
    let v: serde_json::Value = serde_json::from_str(lines[0]).unwrap();
    assert!(v["xdot"]["w"].as_f64().unwrap().abs() < 0.2);
    let lam = v["lambda_mr"].as_f64().unwrap();
    assert!((lam + 0.0415).abs() < 0.001, "{lam}");
    assert!(v["force_mr_hub_n"].as_array().unwrap().len() == 3);

    // a bad second line: stop with an error naming line 2 and the field
    let bad = "{\"x\": [1, 2], \"u\": [0, 0, 0, 0]}";
    let out = run_with_stdin(&["eval"], &format!("{good}\n{bad}\n"));
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("line 2") && err.contains("`x`"), "{err}");
    // --keep-going: one output line per input line, the bad one as an error object
    let out = run_with_stdin(&["eval", "--keep-going"], &format!("{bad}\n{good}\n"));
    assert!(!out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let first: serde_json::Value = serde_json::from_str(text.lines().next().unwrap()).unwrap();
    assert_eq!(first["line"], 1);
    assert_eq!(text.lines().count(), 2);
}

#[test]
fn params_prints_a_loadable_file_and_rejects_bad_ones() {
    let out = helicon().arg("params").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("mass_kg = 14.0"));
    let dir = std::env::temp_dir().join(format!("helicon-params-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("p.toml");
    std::fs::write(&f, text.replace("mass_kg = 14.0", "mass_kg = 12.5")).unwrap();
    let out = helicon()
        .args(["params", "--params", f.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        String::from_utf8(out.stdout)
            .unwrap()
            .contains("mass_kg = 12.5")
    );
    std::fs::write(&f, "[body]\nmass_kg = 0\n").unwrap();
    let out = helicon()
        .args(["trim", "--params", f.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("p.toml") && err.contains("body.mass_kg") && err.contains("> 0"),
        "{err}"
    );
}

#[test]
fn trim_json_and_linearize_files() {
    let out = helicon()
        .args(["trim", "--preset", "thesis", "--json"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["state"].as_object().unwrap().len(), 27);
    assert_eq!(v["input"].as_object().unwrap().len(), 4);
    assert!((v["input"]["S_col"].as_f64().unwrap() - 0.184975).abs() < 1e-6);
    assert!(v["residual_norm"].as_f64().unwrap() < 1e-9);

    let dir = std::env::temp_dir().join(format!("helicon-lin-{}", std::process::id()));
    let out = helicon()
        .args([
            "linearize",
            "--preset",
            "thesis",
            "--thesis-inflow",
            "--discrete",
            "0.0025",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in [
        "A.csv",
        "B.csv",
        "poles.csv",
        "summary.json",
        "Phi.csv",
        "Gamma.csv",
    ] {
        assert!(dir.join(f).exists(), "{f}");
    }
    let a = std::fs::read_to_string(dir.join("A.csv")).unwrap();
    let header = a.lines().next().unwrap();
    assert!(header.starts_with("row,phi,theta,psi,u,v,w"));
    assert_eq!(a.lines().count(), 28);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["controllability_rank"], 27);
    assert_eq!(s["observability_rank"], 27);
    assert_eq!(s["unstable_poles"], 2);

    let out = helicon()
        .args(["trim", "--velocity-ned", "1,x,0"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("velocity-ned"));
}
