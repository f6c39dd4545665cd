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
    // The child may refuse its arguments and exit before reading stdin: a
    // broken pipe here is the child's choice, not a test failure.
    if let Err(e) = child.stdin.take().unwrap().write_all(stdin.as_bytes()) {
        assert_eq!(e.kind(), std::io::ErrorKind::BrokenPipe, "{e}");
    }
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

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("helicon-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn trim_of_mass_x100_is_refused_naming_each_violation_unless_allowed() {
    // Regression: mass x100 "trimmed" with theta0 = 6.0 rad, S_col = 8.6, exit 0.
    let dir = temp_dir("heavy");
    let f = dir.join("heavy.toml");
    std::fs::write(&f, "[body]\nmass_kg = 1400.0\n").unwrap();
    let out = helicon()
        .args(["trim", "--params", f.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("unphysical: S_col = 8.6161 not [-0.1, 0.3]")
            && err.contains("alpha75_mr")
            && err.contains("a0 = 1.1883 not [-0.2, 0.2]")
            && err.contains("--allow-unphysical"),
        "{err}"
    );
    let out = helicon()
        .args(["trim", "--json", "--allow-unphysical", "--params"])
        .arg(&f)
        .output()
        .unwrap();
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["validity"]["physical"], false);
    assert_eq!(v["validity"]["violations"][0]["quantity"], "S_col");
    assert_eq!(v["validity"]["violations"][0]["allowed"]["max"], 0.3);
    // mass x2: only S_col
    std::fs::write(&f, "[body]\nmass_kg = 28.0\n").unwrap();
    let out = helicon()
        .args(["trim", "--params"])
        .arg(&f)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.matches("unphysical:").count(), 1, "{err}");
    assert!(err.contains("S_col = 0.3180"), "{err}");
    // the nominal hover is physical
    let out = helicon().args(["trim", "--json"]).output().unwrap();
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["validity"]["physical"], true);
}

#[test]
fn climb_sweep_reports_validity_per_point_and_the_jump() {
    // Regression: "41 converged, 0 failed", S_col from -0.35 to 0.56 beyond
    // [-0.1, 0.3], no warning, the jump at -8.5 m/s unflagged.
    let dir = temp_dir("climb-sweep");
    let out = helicon()
        .args([
            "trim", "--sweep", "climb", "--from", "-20", "--to", "20", "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("81 converged, 0 failed, 59 unphysical: S_col beyond [-0.1, 0.3] at -20..-11 and 7.5..20 m/s; descent_ratio_mr not <= 0.25 or >= 2 at -8..-1.5 m/s"),
        "{text}"
    );
    assert!(text.contains("1 jump(s), -8.5 -> -8 m/s (S_col"), "{text}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("59 sweep point(s) are not physical"), "{err}");
    // CSV: one row per point, the validity and the jump per row
    let csv = std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert_eq!(
        &header[header.len() - 3..],
        ["physical", "violations", "jump_from_previous"]
    );
    for line in csv.lines().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells.len(), header.len(), "{line}");
        let climb: f64 = cells[0].parse().unwrap();
        let physical = cells[cells.len() - 3] == "true";
        assert_eq!(
            physical,
            climb > -11.0 && climb < 7.5 && !(-8.0..=-1.5).contains(&climb),
            "{line}"
        );
        assert_eq!(
            cells[cells.len() - 1].contains("lambda_mr"),
            climb == -8.0,
            "{line}"
        );
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(json["points"].as_array().unwrap().len(), 81);
    assert_eq!(json["points"][0]["validity"]["physical"], false);
    assert_eq!(json["jumps"][0]["from"], -8.5);
    // --allow-unphysical: same files, exit 0
    let out = helicon()
        .args([
            "trim",
            "--sweep",
            "climb",
            "--from",
            "-20",
            "--to",
            "20",
            "--allow-unphysical",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success());
    // an envelope inside the limits passes
    let out = helicon()
        .args([
            "trim", "--sweep", "forward", "--from", "0", "--to", "10", "--step", "1", "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        String::from_utf8_lossy(&out.stdout)
            .contains("11 converged, 0 failed, 0 unphysical; 0 jump(s)")
    );
}

#[test]
fn linearize_refuses_unphysical_points_and_non_equilibria_unless_allowed() {
    // Regression: exit 0 with "affine residual 1e2..1e5" at a clipped trim.
    let dir = temp_dir("lin-heavy");
    let f = dir.join("heavy.toml");
    std::fs::write(&f, "[body]\nmass_kg = 1400.0\n").unwrap();
    let out = helicon()
        .args(["linearize", "--params", f.to_str().unwrap(), "--out"])
        .arg(dir.join("lin"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("refusing to linearize: the trim is not physical"),
        "{err}"
    );
    assert!(!dir.join("lin").join("A.csv").exists());
    let out = helicon()
        .args([
            "linearize",
            "--allow-unphysical",
            "--params",
            f.to_str().unwrap(),
            "--out",
        ])
        .arg(dir.join("lin"))
        .output()
        .unwrap();
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("warning: the operating point is not an equilibrium"),
        "{err}"
    );
    let s: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("lin").join("summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(s["equilibrium"], false);
    assert!(s["affine_residual_norm"].as_f64().unwrap() > 1.0);
}

#[test]
fn absurd_parameters_and_non_finite_outputs_are_errors_not_null() {
    // Regression: `helicon eval --params` with mass_kg = 1e308 printed null
    // derivatives with exit 0.
    let dir = temp_dir("absurd");
    let f = dir.join("big.toml");
    std::fs::write(&f, "# absurd\n[body]\nmass_kg = 1e308\n").unwrap();
    let line = format!(
        "{{\"x\": {:?}, \"u\": [0.185, 0, 0, 0.159]}}",
        vec![0.0; 30]
    );
    let out = run_with_stdin(&["eval", "--params", f.to_str().unwrap()], &line);
    assert!(!out.status.success());
    assert!(out.stdout.is_empty());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!(
            "{}:3: key `body.mass_kg` = 1e308 is invalid: must be within +-1e6",
            f.display()
        )),
        "{err}"
    );
    // a state whose derivative overflows: the error names the line and the quantity
    let mut x = vec![0.0; 30];
    x[16] = 1e160; // a1
    let bad = format!("{{\"x\": {x:?}, \"u\": [0.185, 0, 0, 0.159]}}");
    let out = run_with_stdin(&["eval"], &format!("{line}\n{bad}\n"));
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("line 2") && err.contains("non-finite derivative of `u`"),
        "{err}"
    );
    assert!(!String::from_utf8_lossy(&out.stdout).contains("null"));
    let out = run_with_stdin(&["eval", "--keep-going"], &format!("{bad}\n{line}\n"));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(!text.contains("null"), "{text}");
    let first: serde_json::Value = serde_json::from_str(text.lines().next().unwrap()).unwrap();
    assert!(first["error"].as_str().unwrap().contains("non-finite"));
}

#[test]
fn parameter_file_errors_name_file_line_and_key() {
    let dir = temp_dir("param-line");
    let f = dir.join("p.toml");
    std::fs::write(
        &f,
        "[body]\nmass_kg = 12.0\n\n[main_rotor]\nradius_m = -1\n",
    )
    .unwrap();
    let lin = dir.join("lin");
    for extra in [
        &["trim"][..],
        &["eval"],
        &["linearize", "--out", lin.to_str().unwrap()],
    ] {
        let cmd = extra[0];
        let mut args = extra.to_vec();
        args.extend(["--params", f.to_str().unwrap()]);
        let out = run_with_stdin(&args, "");
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains(&format!(
                "{}:5: key `main_rotor.radius_m` = -1.0 is invalid: must be > 0",
                f.display()
            )),
            "{cmd}: {err}"
        );
    }
}
