//! Runs the `helicon control` subcommands as a user would.

#![allow(clippy::unwrap_used)] // test helpers outside #[test] fns

mod common;
use common::{helicon, tmpdir};
use std::path::Path;
use std::process::{Command, Stdio};

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
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
    let (ok, out, err) = helicon(&["control", "c2d", "--a", &a, "--b", &b, "--dt", "0.1"]);
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
    let (ok, _, err) = helicon(&["control", "c2d", "--a", &missing, "--b", &b, "--dt", "0.1"]);
    assert!(!ok && err.contains("nope.csv"), "{err}");

    // Not stabilizable: typed library error surfaces in the message.
    let a_unst = write(&d, "Au.csv", "2,0\n0,0.5\n");
    let b_bad = write(&d, "Bb.csv", "0\n1\n");
    let (ok, _, err) = helicon(&[
        "control", "dare", "--a", &a_unst, "--b", &b_bad, "--q", &q, "--r", &r,
    ]);
    assert!(!ok && err.contains("not stabilizable"), "{err}");
}

/// Every matrix file of the hostile corpus, by name (written once into one directory).
const FILES: &[(&str, &str)] = &[
    // Good data: the MATLAB `dare` example and a double-integrator Kalman problem.
    ("A.csv", "-0.9,-0.3\n0.7,0.1\n"),
    ("B.csv", "1\n1\n"),
    ("Q.csv", "1,0\n0,3\n"),
    ("R.csv", "0.1\n"),
    ("Phi.csv", "1,0.1\n0,1\n"),
    ("C.csv", "1,0\n"),
    ("Qn.csv", "0.01,0\n0,0.01\n"),
    ("Rn.csv", "1\n"),
    ("G.csv", "0\n1\n"),
    ("Qn1.csv", "1\n"),
    // Malformed CSV.
    ("oops.csv", "1,2\n3,oops\n"),
    ("ragged.csv", "1,2\n3\n"),
    ("nan.csv", "1,NaN\n0,1\n"),
    ("inf.csv", "1,0\n-inf,1\n"),
    ("e400.csv", "1,0\n0,1e400\n"),
    ("empty.csv", "\n\n# nothing\n"),
    ("header.csv", "x,y\n"),
    ("semicolon.csv", "1;2\n3;4\n"),
    ("hex.csv", "0x10,0\n0,1\n"),
    // Wrong shapes.
    ("B3.csv", "1\n1\n1\n"),
    ("A23.csv", "1,0,0\n0,1,0\n"),
    ("Q3.csv", "1,0,0\n0,1,0\n0,0,1\n"),
    ("R2.csv", "1,0\n0,1\n"),
    ("N3.csv", "0\n0\n0\n"),
    ("C3.csv", "1,0,0\n"),
    ("G3.csv", "0\n0\n1\n"),
    // Hostile numbers (all finite, so they pass the parser and reach the library).
    ("A1e308.csv", "row,x,v\nx,1e308,0\nv,0,1\n"),
    ("B1e200.csv", "1\n1e200\n"),
    ("Q1e300.csv", "1e300,0\n0,1\n"),
    ("R1e300.csv", "1e300\n"),
    ("Rzero.csv", "0\n"),
    ("Rneg.csv", "-1\n"),
    ("Qasym.csv", "1,2\n0,1\n"),
    ("Qindef.csv", "1,0\n0,-1\n"),
    ("Ckill.csv", "0,1\n"),
    ("Czero.csv", "0,0\n"),
    ("Gzero.csv", "0\n0\n"),
    ("Qnneg.csv", "-0.01,0\n0,0.01\n"),
    ("Qnasym.csv", "0.01,1\n0,0.01\n"),
    ("Aunst.csv", "2,0\n0,0.5\n"),
    ("Bdead.csv", "0\n1\n"),
    ("Qdead.csv", "0,0\n0,1\n"),
    ("B2.csv", "1,0\n0,1\n"),
    ("R22.csv", "1,0\n0,1\n"),
    ("Nbig.csv", "5\n0\n"),
    ("Aexp.csv", "1,0\n0,-2\n"),
    ("Bexp.csv", "1\n1\n"),
    ("Aneg308.csv", "-1e308,0\n0,-1\n"),
    // JSON inputs.
    ("null.json", "[[1, 2], [3, null]]"),
    ("syntax.json", "[[1, 2],\n [3, 4]"),
    ("ragged.json", "[[1, 2], [3]]"),
    ("e400.json", "[[1, 0], [0, 1e400]]"),
    ("string.json", "[[1, \"x\"], [0, 1]]"),
    ("flat.json", "[1, 2]"),
    (
        "sys.json",
        "{\"Phi\": [[1, 0.1], [0, 1]], \"Gamma\": [[0.005], [0.1]]}",
    ),
];

/// One hostile case: arguments after `helicon control` (`@name` = path of a corpus file)
/// and substrings that must all appear in stderr.
struct Case {
    args: &'static str,
    expect: &'static [&'static str],
}

const fn case(args: &'static str, expect: &'static [&'static str]) -> Case {
    Case { args, expect }
}

/// The hostile corpus of the control subcommand. Each case must exit non-zero, name the
/// file (with line/column or JSON row/column where there is one) or the option in the
/// message, print nothing on stdout (so no NaN/null/inf), and never panic.
const CORPUS: &[Case] = &[
    // --- malformed files ---
    case(
        "dare --a @oops.csv --b @B.csv --q @Q.csv --r @R.csv",
        &["oops.csv: line 2, column 2", "cannot parse \"oops\""],
    ),
    case(
        "dare --a @ragged.csv --b @B.csv --q @Q.csv --r @R.csv",
        &["ragged.csv: line 2 has 1 columns, expected 2"],
    ),
    case(
        "dare --a @nan.csv --b @B.csv --q @Q.csv --r @R.csv",
        &["nan.csv: line 1, column 2: non-finite"],
    ),
    case(
        "dare --a @inf.csv --b @B.csv --q @Q.csv --r @R.csv",
        &["inf.csv: line 2, column 1: non-finite"],
    ),
    case(
        "dare --a @e400.csv --b @B.csv --q @Q.csv --r @R.csv",
        &["e400.csv: line 2, column 2: non-finite"],
    ),
    case(
        "dare --a @empty.csv --b @B.csv --q @Q.csv --r @R.csv",
        &["empty.csv: no matrix rows"],
    ),
    case(
        "dare --a @header.csv --b @B.csv --q @Q.csv --r @R.csv",
        &["header.csv: only a header row"],
    ),
    case(
        "dare --a @nope.csv --b @B.csv --q @Q.csv --r @R.csv",
        &["cannot read matrix file", "nope.csv"],
    ),
    case(
        "dare --a @. --b @B.csv --q @Q.csv --r @R.csv",
        &["cannot read matrix file"],
    ),
    case(
        "c2d --a @semicolon.csv --b @B.csv --dt 0.1",
        &["semicolon.csv: line 2, column 1: cannot parse \"3;4\""],
    ),
    case(
        "c2d --a @hex.csv --b @B.csv --dt 0.1",
        &["hex.csv: line 1, column 1: cannot parse \"0x10\""],
    ),
    case(
        "kalman --a @Phi.csv --c @notutf8.csv --qn @Qn.csv --rn @Rn.csv",
        &["cannot read matrix file", "notutf8.csv", "UTF-8"],
    ),
    // --- wrong shapes ---
    case(
        "dare --a @A.csv --b @B3.csv --q @Q.csv --r @R.csv",
        &["B3.csv", "3x1, expected 2x1"],
    ),
    case(
        "dare --a @A23.csv --b @B.csv --q @Q.csv --r @R.csv",
        &["A23.csv", "must be square", "2x3"],
    ),
    case(
        "dare --a @A.csv --b @B.csv --q @Q3.csv --r @R.csv",
        &["Q3.csv", "3x3, expected 2x2"],
    ),
    case(
        "dare --a @A.csv --b @B.csv --q @Q.csv --r @R2.csv",
        &["R2.csv", "2x2, expected 1x1"],
    ),
    case(
        "dlqr --a @A.csv --b @B.csv --q @Q.csv --r @R.csv --n @N3.csv",
        &["N3.csv", "3x1, expected 2x1"],
    ),
    case(
        "kalman --a @Phi.csv --c @C3.csv --qn @Qn.csv --rn @Rn.csv",
        &["C3.csv", "1x3, expected 1x2"],
    ),
    case(
        "kalman --a @Phi.csv --c @C.csv --qn @Qn.csv --rn @R2.csv",
        &["R2.csv", "Rn is 2x2, expected 1x1"],
    ),
    case(
        "kalman --a @Phi.csv --c @C.csv --qn @Qn1.csv --rn @Rn.csv --g @G3.csv",
        &["G3.csv", "3x1, expected 2x1"],
    ),
    case(
        "kalman --a @Phi.csv --c @C.csv --qn @Qn.csv --rn @Rn.csv --g @G.csv",
        &["Qn.csv", "Qn is 2x2, expected 1x1"],
    ),
    case(
        "c2d --a @A.csv --b @B3.csv --dt 0.1",
        &["B3.csv", "3x1, expected 2x1"],
    ),
    // --- hostile numbers reaching the library: the file, line and column are named ---
    case(
        "dare --a @A1e308.csv --b @B.csv --q @Q.csv --r @R.csv",
        &["A1e308.csv: line 2, column 2", "at most 1e100"],
    ),
    case(
        "dare --a @A.csv --b @B1e200.csv --q @Q.csv --r @R.csv",
        &["B1e200.csv: line 2, column 1", "at most 1e100"],
    ),
    case(
        "dare --a @A.csv --b @B.csv --q @Q1e300.csv --r @R.csv",
        &["Q1e300.csv: line 1, column 1", "at most 1e100"],
    ),
    case(
        "dare --a @A.csv --b @B.csv --q @Q.csv --r @R1e300.csv",
        &["R1e300.csv: line 1, column 1", "at most 1e100"],
    ),
    case(
        "dlqr --a @A1e308.csv --b @B.csv --q @Q.csv --r @R.csv",
        &["A1e308.csv: line 2, column 2"],
    ),
    case(
        "dlqr --a @Aneg308.csv --b @B.csv --q @Q.csv --r @R.csv --alpha 1.1",
        &["Aneg308.csv: line 1, column 1"],
    ),
    case(
        "kalman --a @A1e308.csv --c @C.csv --qn @Qn.csv --rn @Rn.csv",
        &["A1e308.csv: line 2, column 2"],
    ),
    case(
        "c2d --a @A1e308.csv --b @B.csv --dt 0.1",
        &["A1e308.csv: line 2, column 2"],
    ),
    case(
        "c2d --a @A.csv --b @B1e200.csv --dt 0.1",
        &["B1e200.csv: line 2, column 1"],
    ),
    // --- options ---
    case(
        "dlqr --a @A.csv --b @B.csv --q @Q.csv --r @R.csv --alpha 1e300",
        &["--alpha", "1e300", "at most 1.000e100"],
    ),
    case(
        "dlqr --a @A.csv --b @B.csv --q @Q.csv --r @R.csv --alpha 0.5",
        &["--alpha", ">= 1"],
    ),
    case(
        "dlqr --a @A.csv --b @B.csv --q @Q.csv --r @R.csv --alpha NaN",
        &["--alpha", "NaN"],
    ),
    case(
        "dlqr --a @A.csv --b @B.csv --q @Q.csv --r @R.csv --alpha inf",
        &["--alpha", "inf"],
    ),
    case(
        "c2d --a @Aexp.csv --b @Bexp.csv --dt 1e6",
        &["--dt", "below about 7.098e2 s"],
    ),
    case("c2d --a @A.csv --b @B.csv --dt 0", &["--dt", "> 0"]),
    case("c2d --a @A.csv --b @B.csv --dt=-1", &["--dt", "> 0"]),
    case("c2d --a @A.csv --b @B.csv --dt -1", &["'-1'"]),
    case("c2d --a @A.csv --b @B.csv --dt NaN", &["--dt", "NaN"]),
    case("c2d --a @A.csv --b @B.csv --dt inf", &["--dt", "inf"]),
    case("c2d --a @A.csv --b @B.csv --dt 1e200", &["--dt", "at most"]),
    case("c2d --a @A.csv --b @B.csv --dt abc", &["--dt", "abc"]),
    // --- weights and structure: the matrix file (or the files of the pair) is named ---
    case(
        "dare --a @A.csv --b @B.csv --q @Q.csv --r @Rzero.csv",
        &["Rzero.csv", "R is not positive definite"],
    ),
    case(
        "dare --a @A.csv --b @B.csv --q @Q.csv --r @Rneg.csv",
        &["Rneg.csv", "R is not positive definite"],
    ),
    case(
        "dare --a @A.csv --b @B.csv --q @Qasym.csv --r @R.csv",
        &["Qasym.csv", "Q is not symmetric"],
    ),
    case(
        "dare --a @A.csv --b @B.csv --q @Qindef.csv --r @R.csv",
        &["Qindef.csv", "Q is not positive semidefinite"],
    ),
    case(
        "dare --a @Aunst.csv --b @Bdead.csv --q @Q.csv --r @R.csv",
        &[
            "A from ",
            "Aunst.csv",
            "B from ",
            "Bdead.csv",
            "(A, B) is not stabilizable",
        ],
    ),
    case(
        "dare --a @Aunst.csv --b @B2.csv --q @Qdead.csv --r @R22.csv",
        &["Qdead.csv", "(Q, A) is not detectable"],
    ),
    case(
        "dare --a @A.csv --b @B.csv --q @Q.csv --r @R.csv --n @Nbig.csv",
        &["Q - N R^-1 N^T", "not positive semidefinite"],
    ),
    case(
        "kalman --a @Phi.csv --c @Ckill.csv --qn @Qn.csv --rn @Rn.csv",
        &["C from ", "Ckill.csv", "(A, C) is not detectable"],
    ),
    case(
        "kalman --a @Phi.csv --c @Czero.csv --qn @Qn.csv --rn @Rn.csv",
        &["Czero.csv", "(A, C) is not detectable"],
    ),
    case(
        "kalman --a @Phi.csv --c @C.csv --qn @Qn1.csv --rn @Rn.csv --g @Gzero.csv",
        &["G from ", "Gzero.csv", "(A, G Qn^1/2) is not stabilizable"],
    ),
    case(
        "kalman --a @Phi.csv --c @C.csv --qn @Qn.csv --rn @Rzero.csv",
        &["Rzero.csv", "Rn is not positive definite"],
    ),
    case(
        "kalman --a @Phi.csv --c @C.csv --qn @Qnneg.csv --rn @Rn.csv",
        &["Qnneg.csv", "Qn is not positive semidefinite"],
    ),
    case(
        "kalman --a @Phi.csv --c @C.csv --qn @Qnasym.csv --rn @Rn.csv",
        &["Qnasym.csv", "Qn is not symmetric"],
    ),
    // --- JSON inputs ---
    case(
        "dare --a @null.json --b @B.csv --q @Q.csv --r @R.csv",
        &["null.json: row 2, column 2: expected a finite number, found null"],
    ),
    case(
        "dare --a @syntax.json --b @B.csv --q @Q.csv --r @R.csv",
        &["syntax.json: line 2", "not valid JSON"],
    ),
    case(
        "dare --a @ragged.json --b @B.csv --q @Q.csv --r @R.csv",
        &["ragged.json: row 2 has 1 columns"],
    ),
    case(
        "dare --a @e400.json --b @B.csv --q @Q.csv --r @R.csv",
        &["e400.json: line 1"],
    ),
    case(
        "dare --a @string.json --b @B.csv --q @Q.csv --r @R.csv",
        &["string.json: row 1, column 2", "found \"x\""],
    ),
    case(
        "dare --a @flat.json --b @B.csv --q @Q.csv --r @R.csv",
        &["flat.json: row 1: expected a list of numbers"],
    ),
    case(
        "dlqr --a @sys.json#Phi --b @sys.json#Gam --q @Q.csv --r @R.csv",
        &["sys.json#Gam: no field \"Gam\"", "Gamma"],
    ),
];

/// The corpus files in a folder of their own for each test (`name`): the
/// tests run in parallel and a fresh folder is emptied first.
fn corpus_dir(name: &str) -> helicon_test_support::Scratch {
    let d = tmpdir(name);
    for (name, text) in FILES {
        write(&d, name, text);
    }
    // Latin-1 bytes, not UTF-8.
    std::fs::write(d.join("notutf8.csv"), b"1,\xb5\n").unwrap();
    d
}

fn expand(dir: &Path, args: &str) -> Vec<String> {
    args.split_whitespace()
        .map(|a| match a.strip_prefix('@') {
            Some(f) => dir.join(f).display().to_string(),
            None => a.to_string(),
        })
        .collect()
}

/// Runs `helicon control <args>`: (exit code, stdout, stderr).
fn control(args: &[String]) -> (Option<i32>, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .arg("control")
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The hostile corpus (see [`CORPUS`]): non-zero exit, a message naming the file/line or
/// option, empty stdout, no panic. Collects all failures before reporting.
#[test]
fn hostile_corpus() {
    let d = corpus_dir("corpus");
    let mut failures = Vec::new();
    for c in CORPUS {
        let (code, out, err) = control(&expand(&d, c.args));
        let mut problems = Vec::new();
        if code == Some(0) || code.is_none() {
            problems.push(format!("exit {code:?}"));
        }
        if err.contains("panicked") {
            problems.push("panicked".to_string());
        }
        if !out.is_empty() {
            problems.push(format!("stdout not empty: {out}"));
        }
        for e in c.expect {
            if !err.contains(e) {
                problems.push(format!("stderr lacks {e:?}"));
            }
        }
        if !problems.is_empty() {
            failures.push(format!(
                "{}: {}\n  stderr: {}",
                c.args,
                problems.join("; "),
                err.trim()
            ));
        }
    }
    println!(
        "hostile corpus: {} cases, {} failed",
        CORPUS.len(),
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Legal but extreme inputs succeed with finite numbers only (no NaN/null/inf in stdout).
#[test]
fn extreme_but_legal_inputs_print_finite_json() {
    let d = corpus_dir("extreme");
    // Tiny weights (1e-300), a stable system sampled at Ts = 1e6 s (Φ underflows to 0),
    // the MATLAB example in units scaled by 1e±45, and the c2d output read back as JSON.
    write(&d, "Qtiny.csv", "1e-300,0\n0,1e-300\n");
    write(&d, "Astable.csv", "-1,0\n0,-2\n");
    // x = T z, T = diag(1e45, 1e-45): A_z = T⁻¹AT, B_z = T⁻¹B, Q_z = TᵀQT.
    write(&d, "As.csv", "-0.9,-0.3e-90\n0.7e90,0.1\n");
    write(&d, "Bs.csv", "1e-45\n1e45\n");
    write(&d, "Qs.csv", "1e90,0\n0,3e-90\n");
    let runs = [
        "dare --a @A.csv --b @B.csv --q @Qtiny.csv --r @R.csv",
        "c2d --a @Astable.csv --b @B.csv --dt 1e6",
        "dlqr --a @As.csv --b @Bs.csv --q @Qs.csv --r @R.csv",
        "dlqr --a @sys.json#Phi --b @sys.json#Gamma --q @Q.csv --r @R.csv --alpha 1.01",
        "kalman --a @Phi.csv --c @C.csv --qn @Qn1.csv --rn @Rn.csv --g @G.csv",
    ];
    for args in runs {
        let (code, out, err) = control(&expand(&d, args));
        assert_eq!(code, Some(0), "{args}: {err}");
        let lower = out.to_ascii_lowercase();
        assert!(
            !lower.contains("null") && !lower.contains("nan") && !lower.contains("inf"),
            "{args}: {out}"
        );
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert!(v.is_object(), "{args}");
    }
    // The scaled problem has the same gain in original units: K_z = K T.
    let (_, out, _) = control(&expand(
        &d,
        "dlqr --a @A.csv --b @B.csv --q @Q.csv --r @R.csv",
    ));
    let k: serde_json::Value = serde_json::from_str(&out).unwrap();
    let (_, out, _) = control(&expand(
        &d,
        "dlqr --a @As.csv --b @Bs.csv --q @Qs.csv --r @R.csv",
    ));
    let ks: serde_json::Value = serde_json::from_str(&out).unwrap();
    let (k, ks) = (matrix(&k["K"]), matrix(&ks["K"]));
    // Rounding of the 1e±45 factors only (SDA commutes with a diagonal similarity).
    assert!(
        (ks[0][0] / 1e45 / k[0][0] - 1.0).abs() < 1e-12,
        "{k:?} {ks:?}"
    );
    assert!(
        (ks[0][1] * 1e45 / k[0][1] - 1.0).abs() < 1e-12,
        "{k:?} {ks:?}"
    );
}

/// `helicon control c2d … | true` panicked "failed printing to stdout: Broken pipe". The
/// output here (Φ of a 120-state system, ≈ 0.7 MB) is larger than a pipe buffer, so the
/// write must hit the closed pipe however the processes are scheduled.
#[test]
fn regress_closed_stdout_pipe_is_quiet() {
    let d = tmpdir("pipe");
    let n = 120;
    let a: String = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    if i == j {
                        "-1.25".to_string()
                    } else {
                        format!("{}", 0.001 * ((i * 7 + j * 3) % 11) as f64)
                    }
                })
                .collect::<Vec<_>>()
                .join(",")
                + "\n"
        })
        .collect();
    let a = write(&d, "A.csv", &a);
    let b = write(&d, "B.csv", &"1\n".repeat(n));
    let mut child = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .args(["control", "c2d", "--a", &a, "--b", &b, "--dt", "0.01"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take()); // the reader goes away without reading
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert!(!err.contains("Broken pipe"), "{err}");
    // A closed pipe is not an error of the user's (main.rs maps BrokenPipe to exit 0).
    assert!(out.status.success(), "{:?} {err}", out.status);
}
