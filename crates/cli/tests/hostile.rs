//! The hostile-input suite: bad files and flags for every subcommand of the
//! built `helicon` binary (`helicon control` has its own 63-case corpus in
//! `control_cli.rs` and is not repeated here).
//!
//! Every case is checked the same way: no panic, no hang (killed after
//! [`LIMIT`]), and either
//! - a failure: a non-zero exit status, an `error:` line naming the file and
//!   the field or option (the case's needles), each cause said once; or
//! - a documented success: exit 0 and no `NaN`, `inf` or `null` where a
//!   number belongs, in stdout or in any file the case lists.
//!
//! A second group of tests closes stdout early (`helicon … | head -1`): the
//! command must exit 0 quietly and still write all its files.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

use helicon_test_support::tmpdir;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Longest a single case may run.
const LIMIT: Duration = Duration::from_secs(20);

/// What a finished child did.
struct Run {
    code: Option<i32>,
    stdout: String,
    stderr: String,
    elapsed: Duration,
}

/// Wait for `child` at most [`LIMIT`] (then kill it): the output pipes are
/// drained on threads so a chatty child cannot block.
fn finish(mut child: Child) -> Run {
    let t0 = Instant::now();
    let drain = |r: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut s = Vec::new();
            if let Some(mut r) = r {
                let _ = r.read_to_end(&mut s);
            }
            String::from_utf8_lossy(&s).into_owned()
        })
    };
    let out = drain(
        child
            .stdout
            .take()
            .map(|s| Box::new(s) as Box<dyn Read + Send>),
    );
    let err = drain(
        child
            .stderr
            .take()
            .map(|s| Box::new(s) as Box<dyn Read + Send>),
    );
    let code = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status.code();
        }
        if t0.elapsed() > LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    Run {
        code,
        stdout: out.join().unwrap(),
        stderr: err.join().unwrap(),
        elapsed: t0.elapsed(),
    }
}

fn helicon(dir: &Path, args: &[String], stdin: Option<&str>) -> Run {
    let mut child = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .current_dir(dir)
        .args(args)
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    if let Some(text) = stdin {
        let mut w = child.stdin.take().unwrap();
        let _ = w.write_all(text.as_bytes());
    }
    finish(child)
}

/// Words that must not stand where a number belongs.
fn non_numbers(text: &str) -> Vec<String> {
    text.split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|w| {
            let w = w.to_ascii_lowercase();
            matches!(w.as_str(), "nan" | "inf" | "infinity" | "null")
        })
        .map(str::to_string)
        .collect()
}

/// In a JSON document: `null` anywhere but under the keys that document an
/// absent value (`reason`: no divergence; `settling_time_s`: not settled).
fn json_non_numbers(text: &str) -> Vec<String> {
    fn walk(v: &serde_json::Value, path: &str, out: &mut Vec<String>) {
        match v {
            serde_json::Value::Null => {
                let key = path.rsplit('.').next().unwrap_or("");
                if !matches!(key, "reason" | "settling_time_s") {
                    out.push(format!("null at {path}"));
                }
            }
            serde_json::Value::Array(a) => {
                for (i, x) in a.iter().enumerate() {
                    walk(x, &format!("{path}[{i}]"), out);
                }
            }
            serde_json::Value::Object(m) => {
                for (k, x) in m {
                    walk(x, &format!("{path}.{k}"), out);
                }
            }
            _ => {}
        }
    }
    let mut out = Vec::new();
    match serde_json::from_str::<serde_json::Value>(text) {
        Ok(v) => walk(&v, "", &mut out),
        Err(e) => out.push(format!("not JSON: {e}")),
    }
    out
}

/// A cause said twice in one `error:` line (a `: `-separated part of at
/// least 24 characters that occurs again in the line).
fn repeated_cause(stderr: &str) -> Option<String> {
    for line in stderr.lines().filter(|l| l.starts_with("error: ")) {
        for part in line.split(": ").filter(|p| p.len() >= 24) {
            if line.matches(part).count() > 1 {
                return Some(part.to_string());
            }
        }
    }
    None
}

/// What a case must do.
enum Want {
    /// Non-zero exit; stderr contains each needle.
    Fail(&'static [&'static str]),
    /// Exit 0; stdout and these files (relative to the corpus folder) hold
    /// no NaN/inf/null.
    Ok(&'static [&'static str]),
}

struct Case {
    /// Subcommand (for the per-subcommand counts).
    cmd: &'static str,
    /// Regression name.
    name: &'static str,
    /// Arguments, split on whitespace.
    args: &'static str,
    /// Standard input.
    stdin: Option<&'static str>,
    want: Want,
}

const fn fail(
    cmd: &'static str,
    name: &'static str,
    args: &'static str,
    needles: &'static [&'static str],
) -> Case {
    Case {
        cmd,
        name,
        args,
        stdin: None,
        want: Want::Fail(needles),
    }
}

const fn ok(
    cmd: &'static str,
    name: &'static str,
    args: &'static str,
    files: &'static [&'static str],
) -> Case {
    Case {
        cmd,
        name,
        args,
        stdin: None,
        want: Want::Ok(files),
    }
}

const fn with_stdin(mut c: Case, stdin: &'static str) -> Case {
    c.stdin = Some(stdin);
    c
}

/// Files of the corpus (name, text). More are generated in [`corpus`]:
/// `g/gains.json` (a real design) and its edits, `log.csv` (a simulated
/// sensor log) and its edits.
const FILES: &[(&str, &str)] = &[
    ("heavy.toml", "[body]\nmass_kg = 1e308\n"),
    ("mass100.toml", "[body]\nmass_kg = 1400.0\n"),
    ("light.toml", "[body]\nmass_kg = 13.0\n"),
    ("unknown_key.toml", "[body]\nmas_kg = 14.0\n"),
    ("nan_param.toml", "[body]\n\nmass_kg = nan\n"),
    ("string_param.toml", "[body]\nmass_kg = \"heavy\"\n"),
    ("syntax.toml", "[body\nmass_kg = 14.0\n"),
    ("empty.toml", ""),
    ("ok.toml", "name = \"ok\"\nduration_s = 0.2\n"),
    (
        "substeps_1e9.toml",
        "duration_s = 1.0\n[plant]\nsubsteps = 1000000000\n",
    ),
    (
        "work_day.toml",
        "duration_s = 86400.0\n[plant]\nsubsteps = 1000\n",
    ),
    (
        "inflow0.toml",
        "duration_s = 1.0\n[plant]\ninflow = \"thesis-iteration\"\ninflow_iterations = 0\n",
    ),
    (
        "ref1e300.toml",
        "duration_s = 0.5\n[[reference]]\nt_s = 0.1\noutput = \"vn\"\nvalue = 1e300\n",
    ),
    (
        "psi_ref.toml",
        "duration_s = 0.5\n[[reference]]\nt_s = 0.1\noutput = \"psi\"\nvalue = -1e6\n",
    ),
    (
        "ref_t_nan.toml",
        "duration_s = 0.5\n[[reference]]\nt_s = nan\noutput = \"vd\"\nvalue = 1.0\n",
    ),
    (
        "wind_neg.toml",
        "duration_s = 1.0\n[wind.dryden]\nw20_m_s = -1.0\n",
    ),
    (
        "sensors_rate.toml",
        "duration_s = 1.0\n[sensors.imu]\nrate_hz = 0.0\n",
    ),
    (
        "nav_sigma.toml",
        "duration_s = 1.0\n[navigation]\naccel_sigma_m_s2 = -1.0\n",
    ),
    (
        "controller_rho.toml",
        "duration_s = 1.0\n[controller]\nrho = 0.0\n",
    ),
    (
        "trim_speed.toml",
        "duration_s = 1.0\n[trim]\nvelocity_ned_m_s = [1e9, 0.0, 0.0]\n",
    ),
    (
        "initial_big.toml",
        "duration_s = 1.0\n[initial]\np = 1e200\n",
    ),
    ("duration_tiny.toml", "duration_s = 1e-300\n"),
    ("duration_long.toml", "duration_s = 86401.0\n"),
    (
        "case_bad.toml",
        "name = \"c\"\nduration_s = 0.2\n[[case]]\nname = \"a\"\n[[case]]\nname = \"b\"\nplant = { substeps = 0 }\n",
    ),
    (
        "params_heavy.toml",
        "duration_s = 0.2\nparams = \"heavy.toml\"\n",
    ),
    (
        "gains_alpha.toml",
        "duration_s = 0.2\n[controller]\ngains_file = \"gains_alpha.json\"\n",
    ),
    (
        "gains_ts.toml",
        "duration_s = 0.2\n[controller]\ngains_file = \"gains_ts.json\"\n",
    ),
    (
        "gains_dup.toml",
        "duration_s = 0.2\n[controller]\ngains_file = \"gains_dup.json\"\n",
    ),
    (
        "gains_ok.toml",
        "duration_s = 0.2\n[controller]\ngains_file = \"g/gains.json\"\n",
    ),
    ("sensors_bad.toml", "[imu]\nrate_hz = 0.0\n"),
    ("sensors_unknown.toml", "[imu]\nrat_hz = 400.0\n"),
    (
        "att_text.csv",
        "w1,b1x,b1y,b1z,r1x,r1y,r1z\n1,abc,0,0,0,1,0\n",
    ),
    (
        "att_huge.csv",
        "w1,b1x,b1y,b1z,r1x,r1y,r1z,w2,b2x,b2y,b2z,r2x,r2y,r2z\n1,1e308,0,0,1,0,0,1,0,1,0,0,1,0\n",
    ),
    (
        "att_nan.csv",
        "w1,b1x,b1y,b1z,r1x,r1y,r1z,w2,b2x,b2y,b2z,r2x,r2y,r2z\n1,NaN,0,0,1,0,0,1,0,1,0,0,1,0\n",
    ),
    ("att_empty.csv", ""),
    (
        "att_ok.csv",
        "w1,b1x,b1y,b1z,r1x,r1y,r1z,w2,b2x,b2y,b2z,r2x,r2y,r2z\n1,0,1,0,1,0,0,1,-1,0,0,0,1,0\n",
    ),
    ("campaign_syntax.toml", "name = \"x\"\nruns = \n"),
    (
        "campaign.toml",
        "name = \"hostile\"\nruns = 2\nseed = 1\n[scenario]\nduration_s = 0.2\n",
    ),
    (
        "campaign_disp.toml",
        "name = \"hostile\"\nruns = 2\nseed = 1\n[scenario]\nduration_s = 0.2\n\
         [[dispersion]]\nparam = \"body.mass_kg\"\ndistribution = \"normal\"\nkind = \"relative\"\nsigma = -0.1\n",
    ),
    (
        "campaign_work.toml",
        "name = \"hostile\"\nruns = 1\nseed = 1\n[scenario]\nduration_s = 1.0\n[scenario.plant]\nsubsteps = 1000000000\n",
    ),
];

const EVAL_HOVER_ZEROS: &str =
    "{\"x\":[0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0],\"u\":[0,0,0,0]}\n";

/// The corpus. Names are the regressions of the reliability issue.
const CORPUS: &[Case] = &[
    // --- demo
    fail(
        "demo",
        "demo duration 0",
        "demo --duration 0 --out o/demo",
        &["--duration", "duration_s", "> 0"],
    ),
    fail(
        "demo",
        "demo duration NaN",
        "demo --duration nan --out o/demo",
        &["duration_s", "NaN"],
    ),
    fail(
        "demo",
        "demo duration below one sample",
        "demo --duration 1e-5 --out o/demo",
        &["duration_s", "1e-5", "one controller sample"],
    ),
    fail(
        "demo",
        "demo duration beyond a day",
        "demo --duration 86401 --out o/demo",
        &["duration_s", "86400"],
    ),
    fail(
        "demo",
        "demo params missing",
        "demo --params missing.toml --out o/demo",
        &["missing.toml", "cannot read"],
    ),
    fail(
        "demo",
        "demo params mass x100 (trim saturates)",
        "demo --params mass100.toml --out o/demo",
        &["mass100.toml", "trim is not physical", "S_col"],
    ),
    fail(
        "demo",
        "demo seed not a number",
        "demo --seed x",
        &["--seed"],
    ),
    ok(
        "demo",
        "demo short flight",
        "demo --duration 0.3 --seed 3 --out o/demo",
        &["o/demo/summary.json", "o/demo/log.csv"],
    ),
    // --- eval
    with_stdin(
        fail(
            "eval",
            "eval --params mass_kg = 1e308",
            "eval --params heavy.toml",
            &["heavy.toml:2", "body.mass_kg", "1e308"],
        ),
        EVAL_HOVER_ZEROS,
    ),
    with_stdin(
        fail(
            "eval",
            "eval not JSON",
            "eval",
            &["<stdin>: line 1", "not valid JSON"],
        ),
        "{x\n",
    ),
    with_stdin(
        fail("eval", "eval x too short", "eval", &["line 1", "`x`", "30"]),
        "{\"x\":[0,0],\"u\":[0,0,0,0]}\n",
    ),
    with_stdin(
        fail(
            "eval",
            "eval number beyond f64",
            "eval",
            &["line 1", "out of range"],
        ),
        "{\"x\":[1e999],\"u\":[0,0,0,0]}\n",
    ),
    with_stdin(
        fail(
            "eval",
            "eval unknown field",
            "eval",
            &["line 2", "unknown field `v`"],
        ),
        "\n{\"v\":1}\n",
    ),
    fail(
        "eval",
        "eval input missing",
        "eval --input missing.json",
        &["missing.json"],
    ),
    with_stdin(
        fail(
            "eval",
            "eval keep-going reports and fails",
            "eval --keep-going",
            &["1 line(s) failed"],
        ),
        "{\"u\":[0,0,0,0]}\n",
    ),
    with_stdin(ok("eval", "eval zeros", "eval", &[]), EVAL_HOVER_ZEROS),
    // --- params
    fail(
        "params",
        "params mass_kg = 1e308",
        "params --params heavy.toml",
        &["heavy.toml:2", "body.mass_kg"],
    ),
    fail(
        "params",
        "params unknown key",
        "params --params unknown_key.toml",
        &["unknown_key.toml:2", "body.mas_kg"],
    ),
    fail(
        "params",
        "params NaN",
        "params --params nan_param.toml",
        &["nan_param.toml:3", "body.mass_kg"],
    ),
    fail(
        "params",
        "params wrong type",
        "params --params string_param.toml",
        &["string_param.toml", "body.mass_kg"],
    ),
    fail(
        "params",
        "params TOML syntax",
        "params --params syntax.toml",
        &["syntax.toml", "TOML"],
    ),
    fail(
        "params",
        "params missing",
        "params --params missing.toml",
        &["missing.toml", "cannot read"],
    ),
    ok("params", "params defaults", "params", &[]),
    ok(
        "params",
        "params empty file",
        "params --params empty.toml",
        &[],
    ),
    // --- trim
    fail(
        "trim",
        "trim mass x100",
        "trim --params mass100.toml",
        &["not physical", "S_col"],
    ),
    fail(
        "trim",
        "trim velocity NaN",
        "trim --velocity-ned nan,0,0",
        &["--velocity-ned"],
    ),
    fail("trim", "trim yaw inf", "trim --yaw inf", &["--yaw"]),
    fail(
        "trim",
        "trim wind 1e308",
        "trim --wind-ned 1e308,0,0",
        &["--wind-ned"],
    ),
    fail(
        "trim",
        "trim sweep of 1e18 points",
        "trim --sweep forward --from 0 --to 1e9 --step 1e-9 --out o/sw",
        &["sweep points", "100000"],
    ),
    fail(
        "trim",
        "trim params missing",
        "trim --params missing.toml",
        &["missing.toml"],
    ),
    ok("trim", "trim json", "trim --json", &[]),
    // --- linearize
    fail(
        "linearize",
        "linearize discrete 0",
        "linearize --discrete 0 --out o/lin",
        &["--discrete"],
    ),
    fail(
        "linearize",
        "linearize discrete NaN",
        "linearize --discrete nan --out o/lin",
        &["--discrete"],
    ),
    fail(
        "linearize",
        "linearize mass x100",
        "linearize --params mass100.toml --out o/lin",
        &["not physical"],
    ),
    fail(
        "linearize",
        "linearize velocity 1e6",
        "linearize --velocity-ned 1e6,0,0 --out o/lin",
        &["--velocity-ned"],
    ),
    ok(
        "linearize",
        "linearize discrete",
        "linearize --discrete 0.0025 --out o/lin",
        &[
            "o/lin/A.csv",
            "o/lin/Phi.csv",
            "o/lin/summary.json",
            "o/lin/poles.csv",
        ],
    ),
    // --- attitude
    fail(
        "attitude",
        "attitude input missing",
        "attitude --input missing.csv",
        &["missing.csv"],
    ),
    fail(
        "attitude",
        "attitude text cell",
        "attitude --input att_text.csv",
        &["att_text.csv", "row 1"],
    ),
    fail(
        "attitude",
        "attitude 1e308 cell",
        "attitude --input att_huge.csv",
        &["att_huge.csv", "row 1"],
    ),
    fail(
        "attitude",
        "attitude NaN cell",
        "attitude --input att_nan.csv",
        &["att_nan.csv", "row 1"],
    ),
    fail(
        "attitude",
        "attitude empty file",
        "attitude --input att_empty.csv",
        &["att_empty.csv"],
    ),
    ok(
        "attitude",
        "attitude two vectors",
        "attitude --input att_ok.csv --out o/att.csv",
        &["o/att.csv"],
    ),
    // --- sensors
    fail(
        "sensors",
        "simulate duration 0",
        "sensors simulate --duration-s 0",
        &["--duration 0 "],
    ),
    fail(
        "sensors",
        "simulate duration 1e300 (printed short)",
        "sensors simulate --duration-s 1e300",
        &["--duration 1e300 ", "86400"],
    ),
    fail(
        "sensors",
        "simulate config rate 0",
        "sensors simulate --config sensors_bad.toml --duration-s 1",
        &["sensors_bad.toml", "imu.rate_hz"],
    ),
    fail(
        "sensors",
        "simulate config unknown key",
        "sensors simulate --config sensors_unknown.toml --duration-s 1",
        &["sensors_unknown.toml", "rat_hz"],
    ),
    fail(
        "sensors",
        "simulate config missing",
        "sensors simulate --config missing.toml --duration-s 1",
        &["missing.toml"],
    ),
    fail(
        "sensors",
        "simulate params mass_kg = 1e308",
        "sensors simulate --params heavy.toml --duration-s 1",
        &["heavy.toml:2", "body.mass_kg"],
    ),
    fail(
        "sensors",
        "config takes no argument",
        "sensors config extra",
        &["extra"],
    ),
    ok(
        "sensors",
        "simulate short",
        "sensors simulate --duration-s 0.5 --seed 2 --out o/s.csv",
        &["o/s.csv"],
    ),
    ok("sensors", "config", "sensors config", &[]),
    fail(
        "sensors",
        "shaker frequency 0",
        "sensors shaker --freq-hz 0 --amplitude-g 1 --out o/sh",
        &["freq_hz"],
    ),
    fail(
        "sensors",
        "shaker amplitude 1e300",
        "sensors shaker --freq-hz 200 --amplitude-g 1e300 --out o/sh",
        &["amplitude"],
    ),
    fail(
        "sensors",
        "shaker config rate 0",
        "sensors shaker --freq-hz 200 --amplitude-g 1 --config sensors_bad.toml --out o/sh",
        &["sensors_bad.toml", "imu.rate_hz"],
    ),
    ok(
        "sensors",
        "shaker short",
        "sensors shaker --freq-hz 200 --amplitude-g 2 --duration-s 1 --no-sweep --out o/sh",
        &["o/sh/summary.json", "o/sh/shaker.csv"],
    ),
    // --- fuse
    fail(
        "fuse",
        "fuse --mag-field-ned nan 0 0",
        "fuse log.csv --out o/f --mag-field-ned nan 0 0",
        &["--mag-field-ned"],
    ),
    fail(
        "fuse",
        "fuse text cell",
        "fuse log_text.csv --out o/f",
        &["log_text.csv", "fx_m_s2"],
    ),
    fail(
        "fuse",
        "fuse 1e308 cell",
        "fuse log_huge.csv --out o/f",
        &["log_huge.csv", "`fx_m_s2` = 1e308: beyond"],
    ),
    fail(
        "fuse",
        "fuse time 0. repeated",
        "fuse log_zero.csv --out o/f",
        &["log_zero.csv", "t_s"],
    ),
    fail(
        "fuse",
        "fuse log missing",
        "fuse missing.csv --out o/f",
        &["missing.csv"],
    ),
    fail(
        "fuse",
        "fuse sensors config bad",
        "fuse log.csv --out o/f --sensors sensors_bad.toml",
        &["sensors_bad.toml", "imu.rate_hz"],
    ),
    fail(
        "fuse",
        "fuse accel sigma negative",
        "fuse log.csv --out o/f --accel-sigma-m-s2=-1",
        &["accel"],
    ),
    ok(
        "fuse",
        "fuse simulated log",
        "fuse log.csv --out o/f",
        &["o/f/fused.csv", "o/f/summary.json"],
    ),
    // --- sim
    fail(
        "sim",
        "sim substeps 1e9",
        "sim substeps_1e9.toml --out o/x",
        &[
            "substeps_1e9.toml",
            "plant.substeps",
            "1000000000",
            "1..=1000",
        ],
    ),
    fail(
        "sim",
        "sim a day at 1000 substeps (total work)",
        "sim work_day.toml --out o/x",
        &["work_day.toml", "duration_s", "plant steps", "1e8"],
    ),
    fail(
        "sim",
        "sim inflow_iterations = 0",
        "sim inflow0.toml --out o/x",
        &["inflow0.toml", "plant.inflow_iterations"],
    ),
    fail(
        "sim",
        "sim [[reference]] value = 1e300",
        "sim ref1e300.toml --out o/x",
        &["ref1e300.toml", "reference[0].value", "1e300", "100 m/s"],
    ),
    fail(
        "sim",
        "sim psi reference -1e6",
        "sim psi_ref.toml --out o/x",
        &["psi_ref.toml", "reference[0].value", "100 rad"],
    ),
    fail(
        "sim",
        "sim reference t_s NaN",
        "sim ref_t_nan.toml --out o/x",
        &["ref_t_nan.toml", "reference[0].t_s"],
    ),
    fail(
        "sim",
        "sim wind.dryden.w20_m_s = -1 (nested, said once)",
        "sim wind_neg.toml --out o/x",
        &["wind_neg.toml: `wind.dryden.w20_m_s` = -1: allowed: >= 0"],
    ),
    fail(
        "sim",
        "sim sensors.imu.rate_hz = 0",
        "sim sensors_rate.toml --out o/x",
        &["sensors_rate.toml: `sensors.imu.rate_hz` = 0"],
    ),
    fail(
        "sim",
        "sim navigation sigma",
        "sim nav_sigma.toml --out o/x",
        &["nav_sigma.toml: `navigation.accel_sigma_m_s2` = -1"],
    ),
    fail(
        "sim",
        "sim controller rho 0",
        "sim controller_rho.toml --out o/x",
        &["controller_rho.toml: `controller.rho` = 0"],
    ),
    fail(
        "sim",
        "sim trim speed 1e9",
        "sim trim_speed.toml --out o/x",
        &["trim_speed.toml", "trim.velocity_ned_m_s[0]", "1000000000"],
    ),
    fail(
        "sim",
        "sim initial rate 1e200",
        "sim initial_big.toml --out o/x",
        &["initial_big.toml", "initial.p", "1e200"],
    ),
    fail(
        "sim",
        "sim duration 1e-300 (printed short)",
        "sim duration_tiny.toml --out o/x",
        &[
            "duration_tiny.toml",
            "`duration_s` = 1e-300",
            "one controller sample",
        ],
    ),
    fail(
        "sim",
        "sim duration beyond a day",
        "sim duration_long.toml --out o/x",
        &["duration_long.toml", "duration_s", "86400"],
    ),
    fail(
        "sim",
        "sim a bad case",
        "sim case_bad.toml --out o/x",
        &["case_bad.toml", "case `b`", "plant.substeps"],
    ),
    fail(
        "sim",
        "sim scenario params mass_kg = 1e308",
        "sim params_heavy.toml --out o/x",
        &["heavy.toml:2", "body.mass_kg"],
    ),
    fail(
        "sim",
        "sim --params mass x100 (trim saturates, said once)",
        "sim ok.toml --params mass100.toml --out o/x",
        &["mass100.toml", "trim is not physical", "S_col"],
    ),
    fail(
        "sim",
        "sim --params missing",
        "sim ok.toml --params missing.toml --out o/x",
        &["missing.toml", "cannot read"],
    ),
    fail(
        "sim",
        "sim --duration NaN",
        "sim ok.toml --duration nan --out o/x",
        &["ok.toml", "--duration", "duration_s", "NaN"],
    ),
    fail(
        "sim",
        "sim --duration 0",
        "sim ok.toml --duration 0 --out o/x",
        &["duration_s", "> 0"],
    ),
    fail(
        "sim",
        "sim --seed negative",
        "sim ok.toml --seed -1 --out o/x",
        &["--seed"],
    ),
    fail(
        "sim",
        "sim gains file alpha edited",
        "sim gains_alpha.toml --out o/x",
        &["gains_alpha.json", "`alpha`", "edited"],
    ),
    fail(
        "sim",
        "sim gains file sample_time_s edited",
        "sim gains_ts.toml --out o/x",
        &["gains_ts.json", "`sample_time_s` = 0.005"],
    ),
    fail(
        "sim",
        "sim gains file duplicated key",
        "sim gains_dup.toml --out o/x",
        &["gains_dup.json", "duplicate key `config.rho`"],
    ),
    fail(
        "sim",
        "sim gains file missing",
        "sim gains_alpha.toml --out o/x --params missing.toml",
        &["missing.toml"],
    ),
    fail(
        "sim",
        "sim scenario missing",
        "sim missing.toml",
        &["missing.toml", "cannot read"],
    ),
    fail(
        "sim",
        "sim scenario TOML syntax",
        "sim syntax.toml",
        &["syntax.toml"],
    ),
    ok(
        "sim",
        "sim --params --seed --duration",
        "sim ok.toml --params light.toml --seed 7 --duration 0.1 --out o/sim",
        &["o/sim/summary.json", "o/sim/log.csv"],
    ),
    ok(
        "sim",
        "sim unedited gains file",
        "sim gains_ok.toml --out o/sim_gains",
        &["o/sim_gains/summary.json"],
    ),
    // --- mc
    fail(
        "mc",
        "mc campaign missing",
        "mc missing.toml",
        &["missing.toml"],
    ),
    fail(
        "mc",
        "mc campaign syntax",
        "mc campaign_syntax.toml",
        &["campaign_syntax.toml"],
    ),
    fail(
        "mc",
        "mc negative sigma",
        "mc campaign_disp.toml --out o/mc",
        &["campaign_disp.toml", "sigma"],
    ),
    fail("mc", "mc runs 0", "mc campaign.toml --runs 0", &["--runs"]),
    fail(
        "mc",
        "mc threads 0",
        "mc campaign.toml --threads 0",
        &["--threads"],
    ),
    fail(
        "mc",
        "mc duration NaN",
        "mc campaign.toml --duration nan --out o/mc",
        &["duration_s"],
    ),
    fail(
        "mc",
        "mc params mass_kg = 1e308",
        "mc campaign.toml --params heavy.toml --out o/mc",
        &["heavy.toml:2", "body.mass_kg"],
    ),
    fail(
        "mc",
        "mc shard 3/2",
        "mc campaign.toml --shard 3/2",
        &["--shard"],
    ),
    fail(
        "mc",
        "mc scenario substeps 1e9",
        "mc campaign_work.toml --out o/mc",
        &["plant.substeps"],
    ),
    fail(
        "mc",
        "mc merge nothing",
        "mc merge missing_dir --out o/merged",
        &["missing_dir"],
    ),
    ok(
        "mc",
        "mc two runs",
        "mc campaign.toml --out o/mc_ok --threads 1",
        &["o/mc_ok/stats.json", "o/mc_ok/runs.csv"],
    ),
    // --- bench
    fail("bench", "bench unknown flag", "bench --fast", &["--fast"]),
    ok("bench", "bench json", "bench --json", &[]),
];

/// Write the corpus folder; generate a real gains file and sensor log and
/// their edits.
fn corpus() -> helicon_test_support::Scratch {
    let d = tmpdir("corpus");
    for (name, text) in FILES {
        std::fs::write(d.join(name), text).unwrap();
    }
    // a real design, then edited copies
    let r = helicon(
        &d,
        &["sim".into(), "ok.toml".into(), "--out".into(), "g".into()],
        None,
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let gains = std::fs::read_to_string(d.join("g/gains.json")).unwrap();
    let edit = |from: &str, to: &str, file: &str| {
        assert!(gains.contains(from), "{from} not in gains.json");
        std::fs::write(d.join(file), gains.replacen(from, to, 1)).unwrap();
    };
    let alpha = gains
        .lines()
        .find(|l| l.trim_start().starts_with("\"alpha\""))
        .unwrap()
        .to_string();
    edit(&alpha, "  \"alpha\": 1.01,", "gains_alpha.json");
    edit(
        "\"sample_time_s\": 0.0025",
        "\"sample_time_s\": 0.005",
        "gains_ts.json",
    );
    edit(
        "\"rho\": 10.0,",
        "\"rho\": 10.0, \"rho\": 1.0,",
        "gains_dup.json",
    );
    // a simulated sensor log, then edited copies (row 5's fx cell / its time)
    let r = helicon(
        &d,
        &[
            "sensors".into(),
            "simulate".into(),
            "--duration-s".into(),
            "1".into(),
            "--out".into(),
            "log.csv".into(),
        ],
        None,
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let log = std::fs::read_to_string(d.join("log.csv")).unwrap();
    let edit_cell = |col: usize, to: &str, file: &str| {
        let mut rows = 0;
        let text: Vec<String> = log
            .lines()
            .map(|l| {
                if l.starts_with('#') || l.starts_with("t_s") {
                    return l.to_string();
                }
                rows += 1;
                if rows != 5 {
                    return l.to_string();
                }
                let mut cells: Vec<&str> = l.split(',').collect();
                cells[col] = to;
                cells.join(",")
            })
            .collect();
        std::fs::write(d.join(file), text.join("\n") + "\n").unwrap();
    };
    edit_cell(1, "abc", "log_text.csv");
    edit_cell(1, "1e308", "log_huge.csv");
    edit_cell(0, "0.", "log_zero.csv");
    d
}

fn expand(args: &str) -> Vec<String> {
    args.split_whitespace().map(str::to_string).collect()
}

/// Run one case: its failure, the case, its problems and its stderr in one
/// message (`None` when it passes).
fn check(d: &Path, c: &Case) -> (Option<String>, Run) {
    let r = helicon(d, &expand(c.args), c.stdin);
    let mut problems = Vec::new();
    if r.stderr.contains("panicked") {
        problems.push("panicked".to_string());
    }
    if r.code.is_none() {
        problems.push(format!("killed after {LIMIT:?} (hang?)"));
    }
    match c.want {
        Want::Fail(needles) => {
            if r.code == Some(0) || r.code.is_none() {
                problems.push(format!("exit {:?}, expected a failure", r.code));
            }
            if !r.stderr.contains("error:") {
                problems.push("no `error:` line".to_string());
            }
            for n in needles {
                if !r.stderr.contains(n) {
                    problems.push(format!("stderr lacks {n:?}"));
                }
            }
            if let Some(p) = repeated_cause(&r.stderr) {
                problems.push(format!("said twice: {p:?}"));
            }
        }
        Want::Ok(files) => {
            if r.code != Some(0) {
                problems.push(format!("exit {:?}, expected success", r.code));
            }
            let bad = non_numbers(&r.stdout);
            if !bad.is_empty() {
                problems.push(format!("stdout holds {bad:?}"));
            }
            for f in files {
                match std::fs::read_to_string(d.join(f)) {
                    Ok(text) => {
                        let bad = if f.ends_with(".json") {
                            json_non_numbers(&text)
                        } else {
                            non_numbers(&text)
                        };
                        if !bad.is_empty() {
                            problems.push(format!("{f} holds {bad:?}"));
                        }
                    }
                    Err(e) => problems.push(format!("{f}: {e}")),
                }
            }
        }
    }
    let failure = (!problems.is_empty()).then(|| {
        format!(
            "[{}] helicon {}: {}\n  stderr: {}",
            c.name,
            c.args,
            problems.join("; "),
            r.stderr.trim()
        )
    });
    (failure, r)
}

/// Every case of the corpus, all failures collected before reporting; the
/// corpus size per subcommand is printed (`cargo test -- --nocapture`).
#[test]
fn hostile_corpus_every_subcommand() {
    let d = corpus();
    let t0 = Instant::now();
    let mut failures = Vec::new();
    let mut counts: std::collections::BTreeMap<&str, usize> = Default::default();
    let mut slowest = (Duration::ZERO, "");
    for c in CORPUS {
        *counts.entry(c.cmd).or_default() += 1;
        let (failure, r) = check(&d, c);
        if r.elapsed > slowest.0 {
            slowest = (r.elapsed, c.name);
        }
        failures.extend(failure);
        if r.elapsed > UNBOUNDED_WALL {
            failures.push(format!(
                "{} {}: took {:.2} s, more than {UNBOUNDED_WALL:?}",
                c.cmd,
                c.name,
                r.elapsed.as_secs_f64()
            ));
        }
    }
    println!(
        "hostile corpus: {} cases ({counts:?}) in {:.1} s, slowest {:.2} s ({}); {} failed",
        CORPUS.len(),
        t0.elapsed().as_secs_f64(),
        slowest.0.as_secs_f64(),
        slowest.1,
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `--seed` overrides both the wind and the sensor seed; `--duration` the
/// flight time; both shown in summary.json.
#[test]
fn sim_overrides_seed_and_duration() {
    let d = tmpdir("overrides");
    std::fs::write(
        d.join("s.toml"),
        "duration_s = 5.0\n[wind]\nseed = 1\n[sensors]\nseed = 2\n",
    )
    .unwrap();
    let args = expand("sim s.toml --seed 42 --duration 0.25 --out r");
    let r = helicon(&d, &args, None);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("r/summary.json")).unwrap()).unwrap();
    assert_eq!(v["wind_seed"], 42, "{v}");
    assert_eq!(v["sensor_seed"], 42, "{v}");
    let t_end = v["t_end_s"].as_f64().unwrap();
    assert!((t_end - 0.25).abs() < 0.003, "{t_end}");
    // --help documents the three options
    let r = helicon(&d, &expand("sim --help"), None);
    for opt in ["--params <FILE>", "--seed <SEED>", "--duration <S>"] {
        assert!(r.stdout.contains(opt), "{opt} not in sim --help");
    }
}

/// Spawn `helicon args` with stdout piped; read `lines` lines, then close
/// the pipe; the process must end with status 0, no panic, nothing on stderr
/// but its progress.
fn closed_pipe(d: &Path, args: &str, lines: usize) -> Run {
    let mut child = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .current_dir(d)
        .args(expand(args))
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let mut reader = BufReader::new(stdout);
    for _ in 0..lines {
        let mut l = String::new();
        let _ = reader.read_line(&mut l);
    }
    drop(reader); // the reader goes away, like `head -1`
    finish(child)
}

/// `helicon sim <multi-case> | head -1`: every case is flown and written,
/// the index too, and the exit is a quiet 0 (not a panic).
#[test]
fn sim_multi_case_with_closed_stdout_flies_every_case() {
    let d = tmpdir("pipe_sim");
    std::fs::write(
        d.join("three.toml"),
        "name = \"three\"\nduration_s = 0.3\n[[case]]\nname = \"a\"\ninitial = { psi = 0.1 }\n\
         [[case]]\nname = \"b\"\ninitial = { vn = 0.3 }\n[[case]]\nname = \"c\"\ninitial = { vd = 0.2 }\n",
    )
    .unwrap();
    let r = closed_pipe(&d, "sim three.toml --out o", 1);
    assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    for case in ["a", "b", "c"] {
        for f in ["summary.json", "log.csv", "report.md"] {
            assert!(d.join("o").join(case).join(f).exists(), "{case}/{f}");
        }
    }
    assert!(d.join("o/summary.json").exists() && d.join("o/report.md").exists());
}

/// Every subcommand that writes to stdout ends quietly with status 0 when
/// its reader has gone before the first byte, and still writes its files.
#[test]
fn closed_stdout_is_a_quiet_exit_everywhere() {
    let d = tmpdir("pipe_all");
    std::fs::write(d.join("ok.toml"), "duration_s = 0.2\n").unwrap();
    std::fs::write(
        d.join("att.csv"),
        "w1,b1x,b1y,b1z,r1x,r1y,r1z,w2,b2x,b2y,b2z,r2x,r2y,r2z\n1,0,1,0,1,0,0,1,-1,0,0,0,1,0\n",
    )
    .unwrap();
    std::fs::write(d.join("a.csv"), "0\n").unwrap();
    std::fs::write(d.join("b.csv"), "1\n").unwrap();
    for (args, file) in [
        ("params", None),
        ("sensors config", None),
        ("trim", None),
        ("trim --json", None),
        ("linearize --out lin", Some("lin/summary.json")),
        ("demo --duration 0.2 --out demo", Some("demo/summary.json")),
        ("sim ok.toml --out sim", Some("sim/summary.json")),
        ("attitude --input att.csv", None),
        ("sensors simulate --duration-s 0.2", None),
        ("control c2d --a a.csv --b b.csv --ts 0.1", None),
    ] {
        let r = closed_pipe(&d, args, 0);
        assert!(!r.stderr.contains("panicked"), "{args}: {}", r.stderr);
        assert_eq!(r.code, Some(0), "{args}: {}", r.stderr);
        assert!(!r.stderr.contains("error"), "{args}: {}", r.stderr);
        if let Some(f) = file {
            assert!(d.join(f).exists(), "{args}: {f} not written");
        }
    }
}

/// `helicon … 2>&1 | head -1` with both pipes gone: notes and the error line
/// on stderr are dropped, never a panic (exit status 101): an error still
/// exits 1, a run 0 with its files written.
#[test]
fn closed_stderr_is_not_a_panic() {
    let d = tmpdir("pipe_err");
    std::fs::write(d.join("mass100.toml"), "[body]\nmass_kg = 1400.0\n").unwrap();
    std::fs::write(
        d.join("c.toml"),
        "name = \"c\"\nruns = 2\nseed = 1\n[scenario]\nduration_s = 0.2\n",
    )
    .unwrap();
    for (args, code, file) in [
        ("trim --params mass100.toml", 1, None),
        ("sim missing.toml", 1, None),
        ("mc c.toml --out mc --threads 1", 0, Some("mc/stats.json")),
        ("params", 0, None),
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_helicon"))
            .current_dir(&d)
            .args(expand(args))
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        drop(child.stderr.take());
        let r = finish(child);
        assert_eq!(r.code, Some(code), "{args}");
        if let Some(f) = file {
            assert!(d.join(f).exists(), "{args}: {f}");
        }
    }
}

/// Hostile inputs to the features of the ULog identification, the
/// stabilizer-bar ground experiment and the silent receiver: a short SITL
/// flight gives a real `flight.ulg`, then each case as in the corpus.
const TODAY: &[Case] = &[
    fail(
        "sitl",
        "rc silent after the flight",
        "sitl fly.toml --out o/s1 --rc-silent-at 10",
        &["--rc-silent-at 10", "after the flight's end", "fly.toml"],
    ),
    fail(
        "sitl",
        "rc silent back before it goes",
        "sitl fly.toml --out o/s2 --rc-silent-at 2 --rc-silent-until 1",
        &["--rc-silent-until 1", "after --rc-silent-at 2"],
    ),
    fail(
        "sitl",
        "manual until = at",
        "sitl fly.toml --out o/s3 --manual-at 3 --manual-until 3",
        &["--manual-until 3", "--manual-at 3"],
    ),
    fail(
        "sitl",
        "gps loss after the flight",
        "sitl fly.toml --out o/s4 --gps-loss-at 1e300",
        &["--gps-loss-at", "after the flight's end"],
    ),
    ok(
        "sitl",
        "rc silent for a second",
        "sitl fly.toml --out o/s5 --rc-silent-at 1 --rc-silent-until 2",
        &["o/s5/summary.json"],
    ),
    fail(
        "ident",
        "frf omega max above Nyquist on a flight log",
        "ident frf f/flight.ulg --input S_lat --output meas_p --out o/f1 --omega-max 1e6",
        &["--omega-max", "flight.ulg", "Nyquist"],
    ),
    fail(
        "ident",
        "frf on a cut flight log",
        "ident frf cut.ulg --input S_lat --output meas_p --out o/f2",
        &["cut.ulg", "control"],
    ),
    fail(
        "ident",
        "frf on a log of the magic bytes only",
        "ident frf magic.ulg --input S_lat --output meas_p --out o/f3",
        &["magic.ulg"],
    ),
    fail(
        "ident",
        "stabilizer lift slope in degrees",
        "ident ground stabilizer-lift-slope deg.csv --out o/g1",
        &["deg.csv", "line 2", "`pitch_rad`", "degrees"],
    ),
    fail(
        "ident",
        "stabilizer lift slope zero thrust",
        "ident ground stabilizer-lift-slope zero.csv --out o/g2",
        &["zero.csv", "thrust_n"],
    ),
    ok(
        "ident",
        "stabilizer lift slope negative pitch",
        "ident ground stabilizer-lift-slope neg.csv --out o/g3",
        &[],
    ),
];

#[test]
fn todays_features_refuse_hostile_inputs() {
    let d = tmpdir("today");
    std::fs::write(d.join("fly.toml"), "name = \"fly\"\nduration_s = 8.0\n").unwrap();
    let r = helicon(&d, &expand("sitl fly.toml --out f"), None);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let ulg = std::fs::read(d.join("f/flight.ulg")).unwrap();
    std::fs::write(d.join("cut.ulg"), &ulg[..3000]).unwrap();
    std::fs::write(d.join("magic.ulg"), &ulg[..7]).unwrap();
    std::fs::write(
        d.join("deg.csv"),
        "pitch_rad,thrust_n\n3,3.67\n6,9.28\n9,15.47\n",
    )
    .unwrap();
    std::fs::write(d.join("zero.csv"), "pitch_rad,thrust_n\n0.05,0\n0.1,0\n").unwrap();
    std::fs::write(
        d.join("neg.csv"),
        "pitch_rad,thrust_n\n-0.05,-3.67\n-0.1,-9.28\n-0.15,-15.47\n",
    )
    .unwrap();
    let failures: Vec<String> = TODAY.iter().filter_map(|c| check(&d, c).0).collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // the result file (its optional fields are null by design): no NaN/inf
    let g = std::fs::read_to_string(d.join("o/g3/ground_stabilizer_lift_slope.json")).unwrap();
    let bad: Vec<String> = non_numbers(&g)
        .into_iter()
        .filter(|w| w != "null")
        .collect();
    assert!(bad.is_empty(), "{bad:?}");
    let _ = std::fs::remove_dir_all(&d);
}

/// Readers that a small file could stall: every command that takes a file
/// refuses a character device that never ends (`/dev/zero`) and a FIFO
/// nobody writes (an open of it blocks) before reading; the ULog bombs are
/// refused naming the limit; an endless CSV header is refused naming the
/// line. Each case as in the corpus (killed after [`LIMIT`]), and each
/// refused or read within [`UNBOUNDED_WALL`]; the slowest is printed.
const UNBOUNDED: &[Case] = &[
    fail(
        "ident",
        "frf /dev/zero",
        "ident frf /dev/zero --input S_col --output p --out o/z1",
        &["/dev/zero", "not a regular file"],
    ),
    fail(
        "ident",
        "frf fifo",
        "ident frf fifo --input S_col --output p --out o/z1",
        &["fifo", "not a regular file (a FIFO)"],
    ),
    fail(
        "ident",
        "tf /dev/zero",
        "ident tf /dev/zero --output p --num 1 --den 2 --out o/z2",
        &["/dev/zero", "not a regular file"],
    ),
    fail(
        "ident",
        "tf fifo",
        "ident tf fifo --output p --num 1 --den 2 --out o/z2",
        &["fifo", "not a regular file"],
    ),
    fail(
        "ident",
        "servo /dev/zero",
        "ident servo /dev/zero --command S_col --position p --out o/z3",
        &["/dev/zero", "not a regular file"],
    ),
    fail(
        "ident",
        "servo fifo",
        "ident servo fifo --command S_col --position p --out o/z3",
        &["fifo", "not a regular file"],
    ),
    fail(
        "ident",
        "input /dev/zero",
        "ident input /dev/zero --out o/z4.csv",
        &["/dev/zero", "not a regular file"],
    ),
    fail(
        "ident",
        "ground /dev/zero",
        "ident ground rotor-drag /dev/zero --out o/z5",
        &["/dev/zero", "not a regular file"],
    ),
    fail(
        "ident",
        "fit /dev/zero",
        "ident fit /dev/zero --out o/z6",
        &["/dev/zero", "not a regular file"],
    ),
    fail(
        "ident",
        "ss /dev/zero",
        "ident ss /dev/zero --out o/z7",
        &["/dev/zero", "not a regular file"],
    ),
    fail(
        "onboard",
        "config /dev/zero",
        "onboard --config /dev/zero",
        &["/dev/zero", "not a regular file"],
    ),
    fail(
        "onboard",
        "config fifo",
        "onboard --config fifo",
        &["fifo", "not a regular file (a FIFO)"],
    ),
    fail(
        "log",
        "info /dev/zero",
        "log info /dev/zero",
        &["/dev/zero", "not a regular file"],
    ),
    fail(
        "log",
        "info fifo",
        "log info fifo",
        &["fifo", "not a regular file"],
    ),
    fail(
        "log",
        "export /dev/zero",
        "log export /dev/zero --csv o/z8",
        &["/dev/zero", "not a regular file"],
    ),
    fail(
        "log",
        "export fifo",
        "log export fifo --csv o/z8",
        &["fifo", "not a regular file (a FIFO)"],
    ),
    fail(
        "sim",
        "scenario /dev/zero",
        "sim /dev/zero --out o/z9",
        &["/dev/zero", "not a regular file"],
    ),
    fail(
        "sim",
        "scenario fifo",
        "sim fifo --out o/z9",
        &["fifo", "not a regular file"],
    ),
    fail(
        "sim",
        "params /dev/zero",
        "trim --params /dev/zero",
        &["/dev/zero", "not a regular file"],
    ),
    fail(
        "sim",
        "params fifo",
        "trim --params fifo",
        &["fifo", "not a regular file (a FIFO)"],
    ),
    fail(
        "sitl",
        "scenario /dev/zero",
        "sitl /dev/zero --out o/z10",
        &["/dev/zero", "not a regular file"],
    ),
    fail(
        "mc",
        "campaign /dev/zero",
        "mc /dev/zero --out o/z11",
        &["/dev/zero", "not a regular file"],
    ),
    fail(
        "mc",
        "campaign fifo",
        "mc fifo --out o/z11",
        &["fifo", "not a regular file (a FIFO)"],
    ),
    // `helicon gcs` reads its commands from stdin: the mission file named
    // there is read before any vehicle is heard (port 0: any free one)
    with_stdin(
        fail(
            "gcs",
            "mission upload /dev/zero",
            "gcs udpin:127.0.0.1:0 --timeout 1",
            &["/dev/zero:0: not a regular file", "1 command(s) failed"],
        ),
        "mission upload /dev/zero\n",
    ),
    with_stdin(
        fail(
            "gcs",
            "mission upload fifo",
            "gcs udpin:127.0.0.1:0 --timeout 1",
            &["fifo:0: not a regular file (a FIFO)", "1 command(s) failed"],
        ),
        "mission upload fifo\n",
    ),
    fail(
        "eval",
        "input /dev/zero",
        "eval --input /dev/zero",
        &["/dev/zero", "not a regular file"],
    ),
    fail(
        "attitude",
        "input /dev/zero",
        "attitude --input /dev/zero",
        &["/dev/zero", "not a regular file"],
    ),
    fail(
        "control",
        "matrix /dev/zero",
        "control c2d --a /dev/zero --b /dev/zero --ts 0.01",
        &["/dev/zero", "not a regular file"],
    ),
    // the ULog bombs: refused naming the file and the limit, or read
    fail(
        "log",
        "info 65,500 columns x 50,000 subscriptions",
        "log info bomb.ulg",
        &["bomb.ulg", "more than 4096 subscriptions"],
    ),
    fail(
        "log",
        "export 65,500 columns x 50,000 subscriptions",
        "log export bomb.ulg --csv o/b1",
        &["bomb.ulg", "more than 4096 subscriptions"],
    ),
    fail(
        "ident",
        "frf 65,500 columns x 50,000 subscriptions",
        "ident frf bomb.ulg --input S_col --output est_p --out o/b2",
        &["bomb.ulg", "more than 4096 subscriptions"],
    ),
    ok(
        "log",
        "info 65,500 columns x 1,000 subscriptions",
        "log info wide.ulg",
        &[],
    ),
    ok(
        "log",
        "info of 100 INFO_MULTIPLE parts",
        "log info multi.ulg",
        &[],
    ),
    // an endless header: refused at its line
    fail(
        "ident",
        "frf CSV header of 2 MiB",
        "ident frf long.csv --input S_col --output p --out o/l1",
        &["long.csv", "line 1 is longer than 1048576 bytes"],
    ),
    fail(
        "ident",
        "tf CSV header of 2 MiB",
        "ident tf long.csv --output p --num 1 --den 2 --out o/l2",
        &["long.csv", "line 1 is longer"],
    ),
];

/// A ULog file of raw messages (`(type, payload)`).
fn raw_ulog(messages: &[(u8, Vec<u8>)]) -> Vec<u8> {
    let mut b = vec![0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35, 1];
    b.extend_from_slice(&0u64.to_le_bytes());
    for (kind, p) in messages {
        b.extend_from_slice(&u16::try_from(p.len()).unwrap().to_le_bytes());
        b.push(*kind);
        b.extend_from_slice(p);
    }
    b
}

/// A format of 65,500 columns subscribed `n` times.
fn wide_ulog(n: usize) -> Vec<u8> {
    let mut m = vec![(b'F', b"t:uint64_t timestamp;uint8_t[65500] x;".to_vec())];
    for i in 0..n {
        let mut p = vec![0u8];
        p.extend_from_slice(&u16::try_from(i % 65_535).unwrap().to_le_bytes());
        p.push(b't');
        m.push((b'A', p));
    }
    raw_ulog(&m)
}

/// An INFO or INFO_MULTIPLE payload.
fn key_value(prefix: &[u8], key: &str, value: &[u8]) -> Vec<u8> {
    let mut p = prefix.to_vec();
    p.push(u8::try_from(key.len()).unwrap());
    p.extend_from_slice(key.as_bytes());
    p.extend_from_slice(value);
    p
}

/// The wall time each [`UNBOUNDED`] case may take (the issue: "`/dev/zero`
/// is an error within a second"). A refusal is a `stat` and an open,
/// 5–8 ms measured for the whole process on an idle machine; the bound
/// leaves room for starting the process on a loaded 2-core machine (tests
/// run in parallel) and for the ULog-bomb cases, which read a 450 kB
/// file up to its limit. A reader that reads `/dev/zero` until memory runs
/// out, or blocks on a FIFO, takes far longer than this (until [`LIMIT`]).
const UNBOUNDED_WALL: Duration = Duration::from_secs(2);

#[test]
fn readers_a_small_file_could_stall_are_bounded() {
    let d = tmpdir("unbounded");
    let fifo = d.join("fifo");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    std::fs::write(d.join("bomb.ulg"), wide_ulog(50_000)).unwrap();
    std::fs::write(d.join("wide.ulg"), wide_ulog(1000)).unwrap();
    let parts: Vec<(u8, Vec<u8>)> = (0..100u8)
        .map(|i| {
            (
                b'M',
                key_value(&[u8::from(i > 0)], "uint8_t[65000] blob", &vec![i; 65_000]),
            )
        })
        .collect();
    std::fs::write(d.join("multi.ulg"), raw_ulog(&parts)).unwrap();
    std::fs::write(d.join("long.csv"), "x".repeat(2 << 20)).unwrap();
    let mut failures = Vec::new();
    let mut slowest = (Duration::ZERO, "");
    for c in UNBOUNDED {
        let (failure, r) = check(&d, c);
        if r.elapsed > slowest.0 {
            slowest = (r.elapsed, c.name);
        }
        failures.extend(failure);
        if r.elapsed > UNBOUNDED_WALL {
            failures.push(format!(
                "{} {}: took {:.2} s, more than {UNBOUNDED_WALL:?}",
                c.cmd,
                c.name,
                r.elapsed.as_secs_f64()
            ));
        }
    }
    println!(
        "unbounded readers: {} cases, slowest {:.2} s ({})",
        UNBOUNDED.len(),
        slowest.0.as_secs_f64(),
        slowest.1
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let r = helicon(&d, &expand("log info multi.ulg"), None);
    assert!(
        r.stdout
            .contains("info blob: (6500000 bytes in several parts)"),
        "{}",
        r.stdout
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// Text from a file reaches the terminal and the exported files with its
/// control characters escaped, and an exported CSV's header cells cannot
/// start a formula.
#[test]
fn file_text_is_printed_escaped_and_csv_cells_cannot_start_a_formula() {
    let d = tmpdir("text");
    let esc_key = "char[6] sys_\u{1b}]0;x";
    let mut m = vec![
        (b'I', key_value(&[], esc_key, b"a\nb\x1b[2J")),
        (b'I', key_value(&[], "char[3] ver_hw", b"\xe2\x80\xae")),
        (
            b'F',
            b"=HYPERLINK:uint64_t timestamp;float =cmd;float -x;float ok;".to_vec(),
        ),
        (
            b'A',
            vec![
                0, 0, 0, b'=', b'H', b'Y', b'P', b'E', b'R', b'L', b'I', b'N', b'K',
            ],
        ),
    ];
    let mut rec = vec![0u8, 0];
    rec.extend_from_slice(&1000u64.to_le_bytes());
    for v in [1.5f32, -2.0, 3.0] {
        rec.extend_from_slice(&v.to_le_bytes());
    }
    m.push((b'D', rec));
    let mut log = vec![6u8]; // level 6: info
    log.extend_from_slice(&1000u64.to_le_bytes());
    log.extend_from_slice(b"line\r\nforged\x07");
    m.push((b'L', log));
    std::fs::write(d.join("text.ulg"), raw_ulog(&m)).unwrap();
    let r = helicon(&d, &expand("log info text.ulg"), None);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    for c in ['\u{1b}', '\u{7}', '\r', '\u{202e}'] {
        assert!(!r.stdout.contains(c), "{c:?} printed raw: {:?}", r.stdout);
    }
    assert!(
        r.stdout.contains("info sys_\\u{1b}]0;x: a\\nb\\u{1b}[2J"),
        "{}",
        r.stdout
    );
    assert!(r.stdout.contains("info ver_hw: \\u{202e}"), "{}", r.stdout);
    let r = helicon(&d, &expand("log export text.ulg --csv o"), None);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(!r.stdout.contains('\u{1b}'), "{}", r.stdout);
    let info = std::fs::read_to_string(d.join("o/text_info.txt")).unwrap();
    assert!(
        info.contains("sys_\\u{1b}]0;x: a\\nb\\u{1b}[2J\n"),
        "{info}"
    );
    let msgs = std::fs::read_to_string(d.join("o/text_messages.txt")).unwrap();
    assert_eq!(msgs, "1000 info line\\r\\nforged\\u{7}\n");
    let csv = std::fs::read_to_string(d.join("o/text__HYPERLINK_0.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("timestamp,'=cmd,'-x,ok"));
    // numbers are left as they are
    assert_eq!(lines.next(), Some("1000,1.5,-2,3"));
    let _ = std::fs::remove_dir_all(&d);
}
