//! Run outputs: the files of a run folder, the `log.csv` layout and
//! decimation, the `summary.json` keys, and the gains round trip (flying the
//! saved gains reproduces the run bit for bit).
#![allow(clippy::too_many_lines, clippy::panic, clippy::cast_possible_wrap)] // tests: long scenarios, panics are failures
#![allow(clippy::unwrap_used, missing_docs)] // tests: a failed unwrap is a failed test

use helicon_core::frames::wrap_pi;
use helicon_gnc::design::Gains;
use helicon_model::state::{INPUT_NAMES, STATE_NAMES, ix};
use helicon_sim::closed_loop::{Outcome, fly, prepare};
use helicon_sim::output::{LOG_COLUMNS, MEASURED_NAMES, log_header, write_run};
use helicon_sim::scenario::Scenario;
use helicon_test_support::tmpdir;
use std::path::PathBuf;

/// A short flight with a step, wind and a decimated log.
const SHORT: &str = r#"
name = "short"
preset = "physical"
duration_s = 1.0
[initial]
psi = 0.2
[[reference]]
t_s = 0.2
output = "vn"
value = 1.0
[wind]
seed = 3
[wind.steady]
wind_ned_m_s = [1.0, 0.5, 0.0]
[log]
decimation = 3
"#;

fn csv_rows(path: &std::path::Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse::<f64>().unwrap()).collect())
        .collect();
    (header, rows)
}

#[test]
fn run_folder_files_csv_and_json() {
    let s = Scenario::from_toml_str(SHORT, "short.toml").unwrap();
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    assert_eq!(f.summary.outcome, Outcome::Completed);
    let n = f.log.len();
    // 1 s at 400 Hz is 401 samples; the flight keeps every 3rd (k = 0, 3, …,
    // 399: 134) and the last one (k = 400): 135
    assert_eq!(n, 135, "decimated flight log");
    assert_eq!(f.log.last().unwrap().t_s, 1.0);
    assert!((f.log[1].t_s - 3.0 / 400.0).abs() < 1e-15);
    let dir = tmpdir("files");
    let files = write_run(&dir, &s, &p, &f).unwrap();
    for path in [
        &files.log,
        &files.summary,
        &files.gains,
        &files.scenario,
        &files.report,
    ] {
        assert!(std::fs::metadata(path).unwrap().len() > 0, "{path:?}");
    }
    // plots: each PNG has its SVG; the wind plot is there because there is wind
    let names: Vec<String> = files
        .plots
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    for stem in ["outputs", "servos", "estimator", "wind", "inflow"] {
        for ext in ["png", "svg"] {
            let name = format!("{stem}.{ext}");
            assert!(names.contains(&name), "{name} missing from {names:?}");
            assert!(dir.join(&name).exists());
        }
    }
    let png = std::fs::read(dir.join("outputs.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let report = std::fs::read_to_string(&files.report).unwrap();
    assert!(report.contains("completed"));
    assert!(report.contains("(outputs.png)"));
    assert!(report.contains("| vn |"));

    // log.csv: header, 83 columns, every 3rd sample from t = 0, exact values
    let (header, rows) = csv_rows(&files.log);
    assert_eq!(header, log_header());
    assert_eq!(header.len(), LOG_COLUMNS);
    assert_eq!(LOG_COLUMNS, 83);
    assert_eq!(header[0], "t_s");
    assert_eq!(&header[1..31], &STATE_NAMES.map(str::to_string)[..]);
    assert_eq!(&header[31..35], &INPUT_NAMES.map(str::to_string)[..]);
    for name in [
        "ref_vn",
        "ref_psi",
        "vn",
        "vd",
        "est_phi",
        "err_psi",
        "meas_r",
        "wind_n",
        "wind_d",
        "lambda_mr",
        "lambda_tr",
        "thrust_mr_n",
        "force_tr_y_n",
    ] {
        assert!(header.iter().any(|h| h == name), "{name}");
    }
    assert_eq!(rows.len(), n);
    assert_eq!(files.log_rows, rows.len());
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row.len(), LOG_COLUMNS);
        let r = &f.log[k];
        // the shortest round-trip text reads back to the same f64
        assert_eq!(row[0].to_bits(), r.t_s.to_bits());
        assert_eq!(row[col("psi")].to_bits(), r.x[ix::PSI].to_bits());
        assert_eq!(row[col("S_tr")].to_bits(), r.u[3].to_bits());
        assert_eq!(row[col("ref_vn")], r.reference[0]);
        assert_eq!(row[col("vn")], r.output[0]);
        assert_eq!(row[col("est_q")], r.estimate9[7]);
        assert_eq!(row[col("meas_theta")], r.measured9[1]);
        assert_eq!(row[col("wind_e")], 0.5);
        assert_eq!(row[col("lambda_mr")], r.lambda[0]);
        assert_eq!(row[col("force_tr_y_n")], r.thrust[1]);
        for (i, m) in MEASURED_NAMES.iter().enumerate() {
            let mut d = r.x[i + 3] - r.estimate9[i];
            if i == 2 {
                d = wrap_pi(d);
            }
            assert_eq!(row[col(&format!("err_{m}"))], d, "err_{m}");
        }
    }
    assert!((rows[1][0] - 3.0 * 0.0025).abs() < 1e-15);
    // the step at 0.2 s is in the reference column
    assert_eq!(rows[0][col("ref_vn")], 0.0);
    assert_eq!(rows.last().unwrap()[col("ref_vn")], 1.0);

    // summary.json
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&files.summary).unwrap()).unwrap();
    assert_eq!(v["outcome"], "completed");
    assert!(v["reason"].is_null());
    assert_eq!(v["t_end_s"].as_f64().unwrap(), f.summary.t_end_s);
    assert_eq!(v["scenario"], "short");
    for out in ["vn", "ve", "vd", "psi"] {
        let m = &v["metrics"][out];
        for key in [
            "settling_time_s",
            "overshoot_pct",
            "rms_error",
            "max_abs_error",
        ] {
            assert!(m.get(key).is_some(), "metrics.{out}.{key}");
        }
        assert!(m["rms_error"].as_f64().unwrap() >= 0.0);
    }
    // 1 s is too short for the 1 m/s step to settle to 1 %: null
    assert!(v["metrics"]["vn"]["settling_time_s"].is_null());
    let max_vn = v["metrics"]["vn"]["max_abs_error"].as_f64().unwrap();
    assert!(max_vn > 0.9 && max_vn <= 1.0, "{max_vn}");
    for key in [
        "control_effort_rms",
        "saturation_time_s",
        "estimator_error_rms",
    ] {
        assert!(v[key].is_array(), "{key}");
    }
    assert_eq!(v["estimator_error_rms"].as_array().unwrap().len(), 9);
    assert_eq!(v["wind_seed"], 3);
    assert!(v["sensor_seed"].is_u64());
    assert_eq!(v["parameter_hash"].as_str().unwrap().len(), 16);
    assert_eq!(v["version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(v["preset"], "physical");

    // scenario.toml reads back to the scenario flown
    let back = Scenario::from_file(&files.scenario).unwrap();
    let mut expected = s.clone();
    expected.base_dir = back.base_dir.clone();
    assert_eq!(back, expected);
}

#[test]
fn flying_the_saved_gains_reproduces_the_run_bit_for_bit() {
    // thesis wind (random) and fusion off; the estimator in the loop
    let text = SHORT.replace(
        "[wind.steady]\nwind_ned_m_s = [1.0, 0.5, 0.0]",
        "[wind.thesis]",
    );
    let s = Scenario::from_toml_str(&text, "gains.toml").unwrap();
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    let dir = tmpdir("gains");
    let files = write_run(&dir, &s, &p, &f).unwrap();
    let loaded = Gains::load(&files.gains).unwrap();
    assert_eq!(loaded, p.gains, "gains.json is an exact copy");

    // the run folder's scenario.toml with gains_file = "gains.json"
    let mut s2 = Scenario::from_file(&files.scenario).unwrap();
    assert!(s2.controller.gains_file.is_none());
    s2.controller.gains_file = Some(PathBuf::from("gains.json"));
    let p2 = prepare(&s2).unwrap();
    assert_eq!(p2.gains, p.gains);
    let f2 = fly(&s2, &p2, None).unwrap();
    assert_eq!(f2.summary, f.summary);
    assert_eq!(f2.log, f.log);
    let j1 = serde_json::to_string(&f.summary).unwrap();
    let j2 = serde_json::to_string(&f2.summary).unwrap();
    assert_eq!(j1, j2);

    // and the copy written for that run points at the absolute gains file
    let dir2 = tmpdir("gains2");
    let files2 = write_run(&dir2, &s2, &p2, &f2).unwrap();
    let s3 = Scenario::from_file(&files2.scenario).unwrap();
    let g = s3.controller.gains_file.unwrap();
    assert!(g.is_absolute(), "{g:?}");
    assert_eq!(
        std::fs::read_to_string(&files2.gains).unwrap(),
        std::fs::read_to_string(&files.gains).unwrap()
    );
}

#[test]
fn a_diverged_run_is_written_with_its_reason() {
    // open loop from a tilted start with a tight attitude limit
    let text = r#"
name = "falls"
duration_s = 2.0
[initial]
vn = 6.0
[controller]
feedback = false
[plant]
max_attitude_rad = 0.1
"#;
    let s = Scenario::from_toml_str(text, "falls.toml").unwrap();
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    assert_eq!(f.summary.outcome, Outcome::Diverged);
    let dir = tmpdir("diverged");
    let files = write_run(&dir, &s, &p, &f).unwrap();
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&files.summary).unwrap()).unwrap();
    assert_eq!(v["outcome"], "diverged");
    let reason = v["reason"].as_str().unwrap();
    assert!(reason.contains("attitude"), "{reason}");
    assert!(v["t_end_s"].as_f64().unwrap() < 2.0);
    let (_, rows) = csv_rows(&files.log);
    assert_eq!(rows.len(), f.log.len());
    assert!(rows.len() > 1);
    let report = std::fs::read_to_string(&files.report).unwrap();
    assert!(report.contains("diverged"), "{report}");
    // no wind: no wind plot
    assert!(!dir.join("wind.png").exists());
}

// ------------------------------------------------------------ log.csv

use helicon_model::{Input, State};
use helicon_sim::closed_loop::LogRow;
use helicon_sim::log_csv::{
    CellProblem, LOG_FORMAT_VERSION, LOG_SCHEMA, LogCsvError, LogReader, LogWriter, log_unit,
    read_log_csv_with,
};
use helicon_sim::output::{
    FigureOptions, OutputError, check_summary, finish_run, read_log_csv, start_run, write_figures,
    write_summary,
};
use std::path::Path;

fn row(t: f64) -> LogRow {
    LogRow {
        t_s: t,
        x: State::zeros(),
        u: Input::zeros(),
        reference: [0.0; 4],
        output: [0.0; 4],
        estimate9: [0.0; 9],
        measured9: [0.0; 9],
        wind_ned: [0.0; 3],
        lambda: [0.0; 2],
        thrust: [0.0; 2],
        inflow_residual: [0.0; 2],
        imu_health: [0.0; 3],
        excitation: [0.0; 4],
    }
}

fn short_flight() -> (
    Scenario,
    helicon_sim::closed_loop::Prepared,
    helicon_sim::closed_loop::Flight,
) {
    let s = Scenario::from_toml_str(SHORT, "short.toml").unwrap();
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    (s, p, f)
}

#[test]
fn log_csv_round_trips_every_column_bit_for_bit() {
    let (s, p, f) = short_flight();
    let dir = tmpdir("roundtrip");
    let files = write_run(&dir, &s, &p, &f).unwrap();
    let table = read_log_csv(&files.log).unwrap();
    assert_eq!(table.rows(), f.log.len());
    assert_eq!(table.names(), &log_header()[..]);
    assert_eq!(LOG_FORMAT_VERSION, 3);
    for c in &LOG_SCHEMA {
        let col = table.column(c.name).unwrap();
        assert_eq!(table.unit(c.name), Some(c.unit));
        for (k, r) in f.log.iter().enumerate() {
            assert_eq!(
                col[k].to_bits(),
                c.value(r).to_bits(),
                "{} row {k}: {} != {}",
                c.name,
                col[k],
                c.value(r)
            );
        }
    }
    // independent of the schema: a few columns straight from the rows
    let t: Vec<f64> = f.log.iter().map(|r| r.t_s).collect();
    assert_eq!(table.time_s(), &t[..]);
    let psi: Vec<u64> = f.log.iter().map(|r| r.x[ix::PSI].to_bits()).collect();
    let psi_read: Vec<u64> = table
        .column("psi")
        .unwrap()
        .iter()
        .map(|v| v.to_bits())
        .collect();
    assert_eq!(psi_read, psi);
    assert_eq!(table.unit("psi"), Some("rad"));
    assert_eq!(table.unit("thrust_mr_n"), Some("N"));
    assert_eq!(table.unit("S_col"), Some("1"));
    assert_eq!(log_unit("nope"), None);
    // an absent column is an error naming the file
    let e = table.column("nope").unwrap_err().to_string();
    assert!(e.contains("log.csv") && e.contains("nope"), "{e}");
}

#[test]
fn log_csv_round_trips_extreme_numbers_bit_for_bit() {
    let values = [
        0.1 + 0.2,
        -0.0,
        5e-324,
        2.2250738585072014e-308,
        1.7976931348623157e308,
        -1e-300,
        123_456_789_012.0,
        1e9,
        999_999_999.999_999_9,
        1e-4,
        9.999_999_999_999_999e-5,
        std::f64::consts::PI,
        -1.0 / 3.0,
    ];
    let dir = tmpdir("extreme");
    let path = dir.join("log.csv");
    let mut w = LogWriter::create(&path).unwrap();
    for (k, v) in values.iter().enumerate() {
        let mut r = row(k as f64 * 0.5);
        r.x[ix::PSI] = *v;
        r.thrust[1] = -*v;
        r.u[2] = *v;
        w.write(&r).unwrap();
    }
    assert_eq!(w.finish().unwrap(), values.len());
    let table = read_log_csv(&path).unwrap();
    for (k, v) in values.iter().enumerate() {
        assert_eq!(
            table.column("psi").unwrap()[k].to_bits(),
            v.to_bits(),
            "{v:e}"
        );
        assert_eq!(
            table.column("force_tr_y_n").unwrap()[k].to_bits(),
            (-v).to_bits()
        );
        assert_eq!(table.column("S_lon").unwrap()[k].to_bits(), v.to_bits());
    }
}

/// A file written in a test's own scratch folder; the folder goes when
/// the value does. It dereferences to the file's path.
struct BadFile {
    _dir: helicon_test_support::Scratch,
    path: PathBuf,
}

impl std::ops::Deref for BadFile {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for BadFile {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

/// Write `text` to `bad.csv` in a folder of this test's own.
fn bad_file(test: &str, text: &str) -> BadFile {
    let dir = tmpdir(test);
    let path = dir.join("bad.csv");
    std::fs::write(&path, text).unwrap();
    BadFile { _dir: dir, path }
}

fn read_err(path: &Path) -> LogCsvError {
    read_log_csv_with(path, &["a"]).unwrap_err()
}

fn assert_cell(e: &LogCsvError, line: usize, column: usize, name: &str, problem: CellProblem) {
    match e {
        LogCsvError::BadCell {
            path,
            line: l,
            column: c,
            name: n,
            problem: p,
            ..
        } => {
            assert!(path.ends_with("bad.csv"), "{path}");
            assert_eq!(
                (*l, *c, n.as_str(), *p),
                (line, column, name, problem),
                "{e}"
            );
        }
        other => panic!("expected a bad cell, got {other:?}"),
    }
    let msg = e.to_string();
    assert!(msg.contains(&format!("bad.csv:{line}:")), "{msg}");
    assert!(
        msg.contains(&format!("column {column} (`{name}`)")),
        "{msg}"
    );
}

#[test]
fn reader_rejects_a_truncated_number() {
    for cut in ["0.", "1e", "1e-", "-", "2.5E+"] {
        let p = bad_file("trunc", &format!("t_s,a,b\n0,1,2\n0.5,3,{cut}\n"));
        let e = read_err(&p);
        assert_cell(&e, 3, 3, "b", CellProblem::Truncated);
        assert!(e.to_string().contains("truncated number"), "{e}");
    }
}

#[test]
fn reader_rejects_non_finite_cells() {
    for bad in ["inf", "NaN", "-infinity", "+Inf", "1e999", "-2e400"] {
        let p = bad_file("nonfinite", &format!("t_s,a\n0,1\n1,{bad}\n"));
        assert_cell(&read_err(&p), 3, 2, "a", CellProblem::NonFinite);
    }
    // also in the time column
    let p = bad_file("nonfinite_t", "t_s,a\nnan,1\n");
    assert_cell(&read_err(&p), 2, 1, "t_s", CellProblem::NonFinite);
}

#[test]
fn reader_rejects_an_empty_cell() {
    let p = bad_file("emptycell", "t_s,a,b\n0,,2\n");
    assert_cell(&read_err(&p), 2, 2, "a", CellProblem::Empty);
}

#[test]
fn reader_rejects_text_in_a_cell() {
    for bad in [".5", "1.5.2", "0x10", "abc", "1 2", "1e5.5", "--1", "1_000"] {
        let p = bad_file("text", &format!("t_s,a\n0,{bad}\n"));
        let e = read_err(&p);
        assert_cell(&e, 2, 2, "a", CellProblem::NotANumber);
    }
}

#[test]
fn reader_rejects_a_duplicated_column() {
    let p = bad_file("dup", "t_s,a,b,a\n0,1,2,3\n");
    let e = read_err(&p);
    assert!(
        matches!(&e, LogCsvError::DuplicateColumn { name, first: 2, second: 4, .. } if name == "a"),
        "{e:?}"
    );
    let msg = e.to_string();
    assert!(
        msg.contains("bad.csv:1") && msg.contains("`a` appears twice"),
        "{msg}"
    );
}

#[test]
fn reader_reports_missing_required_columns() {
    let p = bad_file("missing", "time,a\n0,1\n");
    let e = read_log_csv_with(&p, &["a", "vn", "vd"]).unwrap_err();
    match &e {
        LogCsvError::MissingColumns { names, .. } => assert_eq!(names, &["t_s", "vn", "vd"]),
        other => panic!("{other:?}"),
    }
    assert!(
        e.to_string()
            .contains("bad.csv: missing column(s) t_s, vn, vd"),
        "{e}"
    );
    // a helicon log needs every column of the schema
    let p = bad_file("missing_schema", "t_s,vn\n0,1\n");
    let e = read_log_csv(&p).unwrap_err().to_string();
    assert!(e.contains("psi") && e.contains("force_tr_y_n"), "{e}");
}

#[test]
fn reader_rejects_a_row_with_missing_or_extra_cells() {
    let p = bad_file("short", "t_s,a,b\n0,1,2\n1,2\n");
    let e = read_err(&p);
    assert_eq!(
        e,
        LogCsvError::RowLength {
            path: p.display().to_string(),
            line: 3,
            found: 2,
            expected: 3
        }
    );
    assert!(
        e.to_string()
            .contains("bad.csv:3: 2 cells, the header has 3"),
        "{e}"
    );
    let p = bad_file("row_too_long", "t_s,a\n0,1,2\n");
    assert!(matches!(
        read_err(&p),
        LogCsvError::RowLength {
            line: 2,
            found: 3,
            ..
        }
    ));
}

#[test]
fn reader_rejects_a_file_cut_off_mid_line() {
    // the writer ends every line; a last line without it was cut off
    let p = bad_file("cut", "t_s,a\n0,1\n1,0.0123");
    let e = read_err(&p);
    assert!(matches!(e, LogCsvError::Truncated { line: 3, .. }), "{e:?}");
    assert!(e.to_string().contains("bad.csv:3") && e.to_string().contains("truncated"));
    // a real log cut in the middle of a row
    let (s, p_, f) = short_flight();
    let dir = tmpdir("cut_real");
    let files = write_run(&dir, &s, &p_, &f).unwrap();
    let text = std::fs::read_to_string(&files.log).unwrap();
    let cut = bad_file("cut_real2", &text[..text.len() / 2]);
    let e = read_log_csv(&cut).unwrap_err();
    assert!(
        matches!(
            e,
            LogCsvError::Truncated { .. }
                | LogCsvError::RowLength { .. }
                | LogCsvError::BadCell { .. }
        ),
        "{e:?}"
    );
}

#[test]
fn reader_rejects_time_that_does_not_increase() {
    let p = bad_file("time", "t_s,a\n0,1\n0.5,1\n0.5,2\n");
    let e = read_err(&p);
    assert!(
        matches!(e, LogCsvError::TimeNotIncreasing { line: 4, t_s, previous_s, .. } if t_s == 0.5 && previous_s == 0.5),
        "{e:?}"
    );
    assert!(
        e.to_string()
            .contains("bad.csv:4: t_s = 0.5 s does not increase"),
        "{e}"
    );
}

#[test]
fn reader_rejects_an_empty_file_and_an_empty_line() {
    let p = bad_file("empty", "");
    assert!(matches!(read_err(&p), LogCsvError::Empty { .. }));
    assert!(read_err(&p).to_string().contains("bad.csv: empty file"));
    let p = bad_file("emptyline", "t_s,a\n0,1\n\n1,2\n");
    assert!(matches!(
        read_err(&p),
        LogCsvError::EmptyLine { line: 3, .. }
    ));
    let p = bad_file("emptyname", "t_s,,a\n0,1,2\n");
    assert!(matches!(
        read_err(&p),
        LogCsvError::EmptyName { column: 2, .. }
    ));
}

#[test]
fn reader_names_a_file_it_cannot_open() {
    let dir = tmpdir("noopen");
    let e = read_log_csv(&dir.join("absent.csv")).unwrap_err();
    assert!(matches!(e, LogCsvError::Io { .. }));
    assert!(e.to_string().contains("absent.csv"), "{e}");
}

#[test]
fn reader_takes_extra_columns_any_order_crlf_spaces_and_no_rows() {
    let p = bad_file(
        "lenient",
        "\u{feff}b, t_s ,a,extra\r\n2,0,1,9\r\n-4, 1e-3 ,+3,9\r\n",
    );
    let t = read_log_csv_with(&p, &["a", "b"]).unwrap();
    assert_eq!(t.rows(), 2);
    assert_eq!(t.time_s(), &[0.0, 1e-3]);
    assert_eq!(t.column("a").unwrap(), &[1.0, 3.0]);
    assert_eq!(t.column("b").unwrap(), &[2.0, -4.0]);
    assert_eq!(t.column("extra").unwrap(), &[9.0, 9.0]);
    assert_eq!(t.unit("extra"), None);
    let p = bad_file("norows", "t_s,a\n");
    assert_eq!(read_log_csv_with(&p, &["a"]).unwrap().rows(), 0);
    // the streaming reader parses only what it selects (and t_s)
    let p = bad_file("stream", "t_s,a,b\n0,1,x\n");
    let mut r = LogReader::open(&p, &["a"]).unwrap();
    assert_eq!(r.next_row().unwrap(), Some(&[1.0][..]));
    assert_eq!(r.next_row().unwrap(), None);
}

#[test]
fn log_writer_fails_before_flying_when_the_folder_cannot_be_written() {
    let dir = tmpdir("unwritable");
    let e = LogWriter::create(&dir.join("absent").join("log.csv")).unwrap_err();
    assert!(e.to_string().contains("absent/log.csv"), "{e}");
    // a run folder below a file
    std::fs::write(dir.join("file"), "x").unwrap();
    let e = start_run(&dir.join("file").join("run")).unwrap_err();
    assert!(e.to_string().contains("file/run"), "{e}");
}

#[test]
fn log_writer_rejects_non_finite_values_naming_the_column() {
    let dir = tmpdir("writer_nan");
    let path = dir.join("log.csv");
    let mut w = LogWriter::create(&path).unwrap();
    w.write(&row(0.0)).unwrap();
    let mut r = row(0.0025);
    r.estimate9[1] = f64::NAN;
    let e = w.write(&r).unwrap_err();
    // est_theta, and err_theta derived from it: the first in column order
    match &e {
        LogCsvError::NonFiniteValue {
            line, name, t_s, ..
        } => {
            assert_eq!((*line, name.as_str(), *t_s), (3, "est_theta", 0.0025));
        }
        other => panic!("{other:?}"),
    }
    assert!(
        e.to_string()
            .contains("log.csv:3: column `est_theta` is NaN"),
        "{e}"
    );
    let mut r = row(0.005);
    r.wind_ned[2] = f64::INFINITY;
    assert!(
        w.write(&r)
            .unwrap_err()
            .to_string()
            .contains("`wind_d` is inf")
    );
    assert_eq!(w.finish().unwrap(), 1);
    // nothing of the bad rows reached the file: it reads back
    assert_eq!(read_log_csv(&path).unwrap().rows(), 1);
}

#[test]
fn log_writer_rejects_time_that_does_not_increase() {
    let dir = tmpdir("writer_time");
    let mut w = LogWriter::create(&dir.join("log.csv")).unwrap();
    w.write(&row(1.0)).unwrap();
    let e = w.write(&row(1.0)).unwrap_err();
    assert!(
        matches!(e, LogCsvError::TimeNotIncreasing { line: 3, .. }),
        "{e:?}"
    );
}

#[test]
fn streaming_a_run_folder_writes_the_same_files_as_write_run() {
    let (s, p, f) = short_flight();
    let a = tmpdir("stream_a");
    let fa = write_run(&a, &s, &p, &f).unwrap();
    let b = tmpdir("stream_b");
    let mut w = start_run(&b).unwrap();
    for r in &f.log {
        w.write(r).unwrap();
    }
    let rows = w.finish().unwrap();
    let fb = finish_run(&b, &s, &p, &f.summary, rows).unwrap();
    assert_eq!(fb.log_rows, fa.log_rows);
    for name in ["log.csv", "summary.json", "gains.json", "report.md"] {
        assert_eq!(
            std::fs::read(a.join(name)).unwrap(),
            std::fs::read(b.join(name)).unwrap(),
            "{name}"
        );
    }
    let names = |files: &[PathBuf]| -> Vec<String> {
        files
            .iter()
            .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
            .collect()
    };
    assert_eq!(names(&fa.plots), names(&fb.plots));
}

#[test]
fn a_non_finite_summary_number_is_an_error_naming_the_field() {
    let (s, p, f) = short_flight();
    let dir = tmpdir("nonfinite_summary");
    let path = dir.join("summary.json");
    // the documented nulls are fine: not settled, no reason
    assert!(f.summary.metrics["vn"].settling_time_s.is_none());
    check_summary(&path, &f.summary).unwrap();

    let mut bad = f.summary.clone();
    bad.metrics.get_mut("vd").unwrap().rms_error = f64::NAN;
    let e = write_summary(&path, &bad).unwrap_err();
    assert!(
        matches!(&e, OutputError::NonFinite { field, .. } if field == "metrics.vd.rms_error"),
        "{e:?}"
    );
    assert!(
        e.to_string()
            .contains("summary.json: `metrics.vd.rms_error` is not a finite number")
    );
    assert!(!path.exists(), "nothing written");

    let mut bad = f.summary.clone();
    bad.control_effort_rms[2] = f64::INFINITY;
    let e = check_summary(&path, &bad).unwrap_err();
    assert!(matches!(&e, OutputError::NonFinite { field, .. } if field == "control_effort_rms[2]"));

    let mut bad = f.summary.clone();
    bad.metrics.get_mut("psi").unwrap().settling_time_s = Some(f64::NEG_INFINITY);
    let e = check_summary(&path, &bad).unwrap_err();
    assert!(
        matches!(&e, OutputError::NonFinite { field, .. } if field == "metrics.psi.settling_time_s")
    );

    // write_run refuses before writing anything
    let mut flight = f.clone();
    flight.summary.design_alpha = f64::NAN;
    let run = dir.join("run");
    let e = write_run(&run, &s, &p, &flight).unwrap_err();
    assert!(e.to_string().contains("design_alpha"), "{e}");
    assert!(!run.join("log.csv").exists());
}

/// The `<polyline>` elements of an SVG with this stroke colour and more
/// than two points (not legend samples): their number of points.
fn polylines(svg: &str, stroke: &str) -> Vec<usize> {
    svg.split("<polyline")
        .skip(1)
        .filter(|e| e.contains(&format!("stroke=\"{stroke}\"")))
        .map(|e| {
            let pts = e.split("points=\"").nth(1).unwrap();
            pts[..pts.find('"').unwrap()].split_whitespace().count()
        })
        .filter(|n| *n > 2)
        .collect()
}

#[test]
fn figures_are_written_and_non_trivial() {
    let (s, p, f) = short_flight();
    let dir = tmpdir("figures");
    let files = write_run(&dir, &s, &p, &f).unwrap();
    assert_eq!(files.plots.len(), 10);
    // PNG: signature and the layout's size (1200 wide; title, 4 panels of 210 px, time axis)
    let png = std::fs::read(dir.join("outputs.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    assert_eq!(
        (be(&png[16..20]), be(&png[20..24])),
        (1200, 44 + 4 * 210 + 48)
    );
    assert!(png.len() > 50_000, "{} bytes", png.len());
    for stem in ["servos", "estimator", "wind", "inflow"] {
        let n = std::fs::metadata(dir.join(format!("{stem}.png")))
            .unwrap()
            .len();
        assert!(n > 30_000, "{stem}.png: {n} bytes");
    }
    // SVG: every output drawn over the whole log (one solid polyline per
    // panel with a point per row), the references dashed, labels with units
    let svg = std::fs::read_to_string(dir.join("outputs.svg")).unwrap();
    let blue = polylines(&svg, "#1F77B4");
    assert_eq!(blue, vec![f.log.len(); 4], "one line per output, every row");
    // dashes: 2 px black strokes (the axes and ticks are 1 px)
    let dashes = svg.matches("stroke=\"#000000\" stroke-width=\"2\"").count();
    assert!(dashes > 100, "dashed references: {dashes}");
    for label in [
        "vn [m/s]",
        "ve [m/s]",
        "vd [m/s]",
        "ψ [rad]",
        "time [s]",
        "vn reference",
    ] {
        assert!(svg.contains(label), "{label}");
    }
    assert!(svg.contains("short: outputs and references"));
    let svg = std::fs::read_to_string(dir.join("servos.svg")).unwrap();
    for label in ["S_col [-]", "S_tr [-]", "off scale"] {
        assert!(svg.contains(label), "{label}");
    }
    let svg = std::fs::read_to_string(dir.join("estimator.svg")).unwrap();
    for label in [
        "attitude error [rad]",
        "velocity error [m/s]",
        "rate error [rad/s]",
    ] {
        assert!(svg.contains(label), "{label}");
    }
    // the report shows the figures it has
    let report = std::fs::read_to_string(&files.report).unwrap();
    for stem in ["outputs", "servos", "estimator", "wind", "inflow"] {
        assert!(report.contains(&format!("({stem}.png)")), "{stem}");
    }
}

#[test]
fn figures_of_a_long_log_have_a_bounded_number_of_points() {
    let dir = tmpdir("long_log_figures");
    let path = dir.join("log.csv");
    let mut w = LogWriter::create(&path).unwrap();
    let n = 60_000;
    for k in 0..n {
        let t = k as f64 * 0.0025;
        let mut r = row(t);
        r.output[0] = (t * 0.3).sin();
        r.reference[0] = if t > 10.0 { 1.0 } else { 0.0 };
        r.u[1] = 0.74 * (t * 0.1).sin();
        r.wind_ned[0] = (t * 2.0).cos();
        if k == 31_337 {
            r.output[0] = 5.0;
        }
        w.write(&r).unwrap();
    }
    w.finish().unwrap();
    let opts = FigureOptions {
        name: "long".into(),
        note: None,
        servo_limits: Some([[-0.1, 0.3], [-0.75, 0.75], [-0.75, 0.75], [-0.37, 0.62]]),
        max_buckets: 300,
    };
    let (figs, files) = write_figures(&dir, &path, &opts).unwrap();
    let stems: Vec<&str> = figs.iter().map(|f| f.stem).collect();
    assert_eq!(stems, ["outputs", "servos", "estimator", "wind", "inflow"]);
    assert_eq!(files.len(), 10);
    let svg = std::fs::read_to_string(dir.join("outputs.svg")).unwrap();
    let lines = polylines(&svg, "#1F77B4");
    assert_eq!(lines.len(), 4);
    for pts in lines {
        assert!(pts <= 2 * 300 + 2, "{pts} points");
    }
    // the lateral servo comes close to its limits: they are drawn
    let svg = std::fs::read_to_string(dir.join("servos.svg")).unwrap();
    assert!(svg.contains("max 0.75") && svg.contains("min -0.75"));
    assert!(svg.contains("max 0.3 (off scale)"));
}

#[test]
fn streaming_flight_gives_the_same_summary_and_log_as_in_memory() {
    use helicon_sim::closed_loop::{fly, fly_to, prepare};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/demo.toml");
    let mut s = helicon_sim::scenario::Scenario::from_file(&path).unwrap();
    s.duration_s = 3.0;
    let p = prepare(&s).unwrap();
    let mem = fly(&s, &p, None).unwrap();
    let dir = std::env::temp_dir().join(format!("helicon-stream-{}", std::process::id()));
    let mut w = helicon_sim::output::start_run(&dir).unwrap();
    let streamed = fly_to(&s, &p, &mut w, None).unwrap();
    let rows = w.finish().unwrap();
    assert!(streamed.log.is_empty());
    assert_eq!(rows, mem.log.len());
    assert_eq!(streamed.summary, mem.summary);
    assert_eq!(mem.summary.metrics_stride, 1);
    let back = helicon_sim::log_csv::read_log_csv(&dir.join("log.csv")).unwrap();
    assert_eq!(
        back.time_s(),
        mem.log.iter().map(|r| r.t_s).collect::<Vec<_>>()
    );
}
