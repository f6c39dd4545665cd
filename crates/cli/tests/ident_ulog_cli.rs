//! The flight computer's ULog as an identification data source, proved on
//! one SITL identification flight (`scenarios/ident/hover.toml`, lock-step:
//! the on-board runtime writes `flight.ulg`, the simulator `log.csv`):
//! the columns read from the ULog equal log.csv's (servo commands up to the
//! servo link's quantisation), `helicon ident frf` and `helicon ident fit`
//! give the same responses and the same identified parameter from either.
//! And a ULog's bad requests name the file and the column.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;
use common::{helicon, tmpdir};
use std::path::Path;

fn scenario() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/ident/hover.toml")
        .display()
        .to_string()
}

/// Rows of a frf.csv: (output, ω, H, γ², ε).
fn frf_rows(path: &Path) -> Vec<(String, f64, helicon_ident::Complex64, f64, f64)> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            let v: Vec<f64> = c[1..].iter().map(|x| x.parse().unwrap()).collect();
            let h =
                helicon_ident::Complex64::from_polar(10f64.powf(v[1] / 20.0), v[2].to_radians());
            (c[0].to_string(), v[0], h, v[3], v[4])
        })
        .collect()
}

/// The IDENT.toml of the proof; `start`: the verification's start and wind
/// lines (empty: the defaults).
fn ident_toml(log: &str, start: &str) -> String {
    format!(
        "start = \"start.toml\"\npreset = \"physical\"\npoints = 20\nwindows_s = [24.0, 12.0, 6.0]\nauto_fix = false\n\n\
         [[operating_point]]\nname = \"hover\"\nvelocity_ned_m_s = [0.0, 0.0, 0.0]\nlog = \"{log}\"\n\
         instruments = [\"exc_col\", \"exc_lat\", \"exc_lon\", \"exc_tr\"]\n\n\
         [[response]]\ninput = \"S_lat\"\noutput = \"meas_p\"\nomega_min_rad_s = 1.5\nomega_max_rad_s = 25.0\n\n\
         [[response]]\ninput = \"S_lon\"\noutput = \"meas_q\"\nomega_min_rad_s = 1.5\nomega_max_rad_s = 25.0\n\n\
         [[parameter]]\nkey = \"main_rotor.lift_slope_per_rad\"\nmin = 3.0\nmax = 12.0\n\n\
         [[verification]]\noperating_point = \"hover\"\nlog = \"{log}\"\noutputs = [\"meas_p\", \"meas_q\"]\n\
         t_start_s = 30.0\nt_end_s = 33.0\n{start}"
    )
}

#[test]
fn sitl_flight_ulog_identifies_as_its_log_csv() {
    let d = tmpdir("sitl");
    let run = d.join("sitl");
    let (ok, stdout, stderr) = helicon(&["sitl", &scenario(), "--out", run.to_str().unwrap()]);
    assert!(ok, "{stdout}\n{stderr}");
    let (ulg, csv) = (run.join("flight.ulg"), run.join("log.csv"));

    // 1. the columns: the estimate, the measurements and the excitation
    // equal log.csv's bit for bit; the servo commands differ by the servo
    // link's quantisation (counts of 1e-4: log.csv has the plant's input,
    // the ULog the law's command)
    let names = [
        "S_col", "S_lat", "S_lon", "S_tr", "meas_p", "meas_q", "meas_r", "est_p", "est_phi",
        "exc_lat", "exc_lon",
    ];
    let u = helicon_ulog::columns::read_ulog_columns(&ulg, &names, Some(0.0025)).unwrap();
    let c = helicon_sim::log_csv::read_log_csv_with(&csv, &names).unwrap();
    assert_eq!(u.columns[0].len(), c.rows());
    assert!(u.filled.is_empty() && u.skipped_start == 0 && u.max_jitter_s < 1e-9);
    for (a, b) in u.columns[0].iter().zip(c.time_s()) {
        assert!((a - b).abs() < 1e-9, "{a} {b}");
    }
    for n in names {
        let (a, b) = (u.get(n).unwrap(), c.column(n).unwrap());
        let worst = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        let tol = if n.starts_with("S_") {
            0.5e-4 + 1e-12
        } else {
            0.0
        };
        assert!(worst <= tol, "{n}: {worst}");
    }

    // 2. ident frf on each: the same grid; the responses agree to a small
    // fraction of their random error (the quantisation above is the only
    // difference in the data)
    let mut out = Vec::new();
    for (tag, log) in [("ulg", &ulg), ("csv", &csv)] {
        let o = d.join(format!("frf_{tag}"));
        let (ok, stdout, stderr) = helicon(&[
            "ident",
            "frf",
            log.to_str().unwrap(),
            "--input",
            "S_lat",
            "--output",
            "meas_p,meas_q",
            "--conditioned-on",
            "S_col,S_lon,S_tr",
            "--out",
            o.to_str().unwrap(),
        ]);
        assert!(ok, "{stdout}\n{stderr}");
        out.push(frf_rows(&o.join("frf.csv")));
    }
    assert_eq!(out[0].len(), out[1].len());
    let mut z = Vec::new();
    for (a, b) in out[0].iter().zip(&out[1]) {
        assert_eq!(a.0, b.0);
        assert!((a.1 - b.1).abs() < 1e-12 * a.1);
        if a.3.min(b.3) > 0.6 {
            z.push((a.2 - b.2).norm() / b.2.norm() / b.4);
        }
    }
    z.sort_by(f64::total_cmp);
    assert!(z.len() > 200, "{}", z.len());
    // measured: median 0.012, largest 0.66 random errors
    assert!(
        z[z.len() / 2] < 0.05 && z[z.len() - 1] < 1.0,
        "median {} max {}",
        z[z.len() / 2],
        z[z.len() - 1]
    );

    // 3. ident fit on each (instrumental variables): the same lift slope,
    // to a small fraction of its Cramér–Rao bound, and the true one (the
    // Bergen Twin's 6.0) within three bounds
    std::fs::write(
        d.join("start.toml"),
        "[main_rotor]\nlift_slope_per_rad = 4.5\n",
    )
    .unwrap();
    let mut fits = Vec::new();
    // the verification (3 s of the S_lat sweep, replayed open loop): the
    // flight log's default start is the estimate in still air; log.csv is
    // told the same
    let csv_start = "initial_state = \"estimate\"\nwind = \"still\"\n";
    let mut theil = Vec::new();
    for (tag, log, start) in [
        ("ulg", "sitl/flight.ulg", ""),
        ("csv", "sitl/log.csv", csv_start),
    ] {
        let file = d.join(format!("ident_{tag}.toml"));
        std::fs::write(&file, ident_toml(log, start)).unwrap();
        let o = d.join(format!("fit_{tag}"));
        let (ok, stdout, stderr) = helicon(&[
            "ident",
            "fit",
            file.to_str().unwrap(),
            "--out",
            o.to_str().unwrap(),
        ]);
        assert!(ok, "{stdout}\n{stderr}");
        let r: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(o.join("report.json")).unwrap()).unwrap();
        let v = &r["verification"][0];
        assert_eq!(v["initial_state"], "estimate", "{v}");
        assert_eq!(v["wind"], "still", "{v}");
        for o in v["outputs"].as_array().unwrap() {
            theil.push(o["theil_identified"].as_f64().unwrap());
        }
        let p = &r["parameters"][0];
        fits.push((
            p["identified"].as_f64().unwrap(),
            p["cramer_rao_pct"].as_f64().unwrap(),
        ));
    }
    let (a, b) = (fits[0], fits[1]);
    let cr = a.0 * a.1 / 100.0;
    // measured: 5.99821 (ULog) and 5.99852 (log.csv), CR 1.31 %
    assert!((a.0 - b.0).abs() < 0.05 * cr, "{a:?} {b:?}");
    assert!((a.0 - 6.0).abs() < 3.0 * cr, "{a:?}");
    // measured: Theil 0.2082/0.2634 (ULog), 0.2082/0.2633 (log.csv)
    for j in 0..2 {
        assert!((theil[j] - theil[2 + j]).abs() < 0.01, "{theil:?}");
    }
    // a flight log has no true state: "logged" is refused naming the field
    let file = d.join("ident_logged.toml");
    std::fs::write(
        &file,
        ident_toml("sitl/flight.ulg", "initial_state = \"logged\"\n"),
    )
    .unwrap();
    let (ok, _, stderr) = helicon(&[
        "ident",
        "fit",
        file.to_str().unwrap(),
        "--out",
        d.join("fit_bad").to_str().unwrap(),
    ]);
    assert!(
        !ok && stderr.contains("ident_logged.toml")
            && stderr.contains("verification[0].initial_state")
            && stderr.contains("flight.ulg has no column x"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn ulog_requests_name_the_file_and_column() {
    let d = tmpdir("bad");
    // a short flight without excitation: 2 s of the demo hover
    let run = d.join("sitl");
    let scen = d.join("short.toml");
    std::fs::write(&scen, "name = \"short\"\npreset = \"physical\"\nduration_s = 2.0\n[trim]\nvelocity_ned_m_s = [0.0, 0.0, 0.0]\n").unwrap();
    let (ok, stdout, stderr) = helicon(&[
        "sitl",
        scen.to_str().unwrap(),
        "--out",
        run.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    let ulg = run.join("flight.ulg");
    let o = d.join("o");
    let frf = |extra: &[&str]| {
        let mut args = vec![
            "ident",
            "frf",
            ulg.to_str().unwrap(),
            "--out",
            o.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        helicon(&args)
    };
    // no excitation topic in this flight
    let (ok, _, stderr) = frf(&["--input", "exc_lat", "--output", "meas_p"]);
    assert!(
        !ok && stderr.contains("flight.ulg")
            && stderr.contains("`excitation`")
            && stderr.contains("[[excitation]]"),
        "{stderr}"
    );
    // a name a flight log does not give (the truth)
    let (ok, _, stderr) = frf(&["--input", "S_lat", "--output", "p"]);
    assert!(
        !ok && stderr.contains("flight.ulg")
            && stderr.contains("no column `p`")
            && stderr.contains("meas_p"),
        "{stderr}"
    );
    // another time column
    let (ok, _, stderr) = frf(&[
        "--input",
        "S_lat",
        "--output",
        "meas_p",
        "--time",
        "timestamp",
    ]);
    assert!(!ok && stderr.contains("`t_s`"), "{stderr}");
    // the columns that exist work
    let (ok, stdout, stderr) = frf(&["--input", "S_lat", "--output", "meas_p", "--windows", "3"]);
    assert!(ok, "{stdout}\n{stderr}");
    assert!(
        stderr.contains("flight log read on its control grid"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&d);
}
