//! Runs the `helicon control` subcommands as a user would.

#![allow(clippy::unwrap_used)] // test helpers outside #[test] fns

use std::path::{Path, PathBuf};
use std::process::Command;

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("helicon_control_cli_{}_{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

fn helicon(args: &[&str]) -> (bool, String, String) {
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

fn matrix(v: &serde_json::Value) -> Vec<Vec<f64>> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|r| {
            r.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect()
}

/// MATLAB `dare` documentation example: X = [4.7687 0.9438; 0.9438 3.2369] (printed digits).
#[test]
fn dare_matlab_example() {
    let d = tmpdir("dare");
    let a = write(&d, "A.csv", "-0.9,-0.3\n0.7,0.1\n");
    let b = write(&d, "B.csv", "1\n1\n");
    let q = write(&d, "Q.csv", "1,0\n0,3\n");
    let r = write(&d, "R.csv", "0.1\n");
    let (ok, out, err) = helicon(&[
        "control", "dare", "--a", &a, "--b", &b, "--q", &q, "--r", &r,
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let x = matrix(&v["X"]);
    let printed = [[4.7687, 0.9438], [0.9438, 3.2369]];
    for i in 0..2 {
        for j in 0..2 {
            assert!((x[i][j] - printed[i][j]).abs() <= 0.5e-4, "{x:?}");
        }
    }
    assert!(v["residual"].as_f64().unwrap() < 1e-13);

    let (ok, out, err) = helicon(&[
        "control", "dlqr", "--a", &a, "--b", &b, "--q", &q, "--r", &r, "--alpha", "1.2",
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(matrix(&v["K"]).len(), 1);
    for p in v["poles"].as_array().unwrap() {
        let (re, im) = (p[0].as_f64().unwrap(), p[1].as_f64().unwrap());
        assert!(re.hypot(im) < 1.0 / 1.2, "pincer pole {re} {im}");
    }
}

#[test]
fn c2d_and_kalman() {
    let d = tmpdir("c2d");
    // Double integrator with a header row and row names (reference-file layout).
    let a = write(&d, "A.csv", "row,x,v\nx,0,1\nv,0,0\n");
    let b = write(&d, "B.csv", "0\n1\n");
    let (ok, out, err) = helicon(&["control", "c2d", "--a", &a, "--b", &b, "--ts", "0.1"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let phi = matrix(&v["Phi"]);
    let gamma = matrix(&v["Gamma"]);
    // Exact: Φ = [[1, T], [0, 1]], Γ = [T²/2, T]; rounding only (1e-15).
    assert!((phi[0][1] - 0.1).abs() < 1e-15 && (phi[0][0] - 1.0).abs() < 1e-15);
    assert!((gamma[0][0] - 0.005).abs() < 1e-16 && (gamma[1][0] - 0.1).abs() < 1e-15);

    let phi_csv = write(&d, "Phi.csv", "1,0.1\n0,1\n");
    let c = write(&d, "C.csv", "1,0\n");
    let qn = write(&d, "Qn.csv", "0.01,0\n0,0.01\n");
    let rn = write(&d, "Rn.csv", "1\n");
    let (ok, out, err) = helicon(&[
        "control", "kalman", "--a", &phi_csv, "--c", &c, "--qn", &qn, "--rn", &rn,
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let l = matrix(&v["L"]);
    assert_eq!((l.len(), l[0].len()), (2, 1));
    // Estimator poles inside the unit circle.
    for p in v["poles"].as_array().unwrap() {
        assert!(p[0].as_f64().unwrap().hypot(p[1].as_f64().unwrap()) < 1.0);
    }
}

#[test]
fn bad_input_is_a_clear_error() {
    let d = tmpdir("bad");
    let a = write(&d, "A.csv", "1,2\n3,oops\n");
    let b = write(&d, "B.csv", "1\n1\n");
    let q = write(&d, "Q.csv", "1,0\n0,1\n");
    let r = write(&d, "R.csv", "1\n");
    let (ok, _, err) = helicon(&[
        "control", "dare", "--a", &a, "--b", &b, "--q", &q, "--r", &r,
    ]);
    assert!(!ok);
    assert!(err.contains("A.csv: line 2, column 2"), "{err}");
    assert!(!err.contains("panicked"), "{err}");

    let ragged = write(&d, "Ar.csv", "1,2\n3\n");
    let (ok, _, err) = helicon(&[
        "control", "dare", "--a", &ragged, "--b", &b, "--q", &q, "--r", &r,
    ]);
    assert!(!ok && err.contains("Ar.csv: line 2 has 1 columns"), "{err}");

    let nan = write(&d, "An.csv", "1,NaN\n0,1\n");
    let (ok, _, err) = helicon(&[
        "control", "dare", "--a", &nan, "--b", &b, "--q", &q, "--r", &r,
    ]);
    assert!(!ok && err.contains("non-finite"), "{err}");

    let good_a = write(&d, "Ag.csv", "1,1\n0,1\n");
    let b3 = write(&d, "B3.csv", "1\n1\n1\n");
    let (ok, _, err) = helicon(&[
        "control", "dare", "--a", &good_a, "--b", &b3, "--q", &q, "--r", &r,
    ]);
    assert!(
        !ok && err.contains("B3.csv") && err.contains("3x1, expected 2x1"),
        "{err}"
    );

    let missing = d.join("nope.csv").display().to_string();
    let (ok, _, err) = helicon(&["control", "c2d", "--a", &missing, "--b", &b, "--ts", "0.1"]);
    assert!(!ok && err.contains("nope.csv"), "{err}");

    // Not stabilizable: typed library error surfaces in the message.
    let a_unst = write(&d, "Au.csv", "2,0\n0,0.5\n");
    let b_bad = write(&d, "Bb.csv", "0\n1\n");
    let (ok, _, err) = helicon(&[
        "control", "dare", "--a", &a_unst, "--b", &b_bad, "--q", &q, "--r", &r,
    ]);
    assert!(!ok && err.contains("not stabilizable"), "{err}");
}
