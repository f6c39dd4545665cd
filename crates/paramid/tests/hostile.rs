//! Hostile IDENT.toml inputs: every mistake is refused with the file and
//! the field named, never a panic.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_paramid::config::IdentConfig;
use std::path::Path;

const GOOD: &str = r#"
[[operating_point]]
name = "hover"
log = "log.csv"
[[response]]
input = "S_lon"
output = "meas_q"
omega_min_rad_s = 1.5
omega_max_rad_s = 25.0
[[parameter]]
key = "body.iyy_kg_m2"
min = 0.3
max = 1.2
"#;

fn err(text: &str) -> String {
    IdentConfig::from_toml_str(text, "bad.toml", Path::new("."))
        .unwrap_err()
        .to_string()
}

#[test]
fn the_good_file_loads() {
    let c = IdentConfig::from_toml_str(GOOD, "good.toml", Path::new("/data")).unwrap();
    assert_eq!(c.operating_points[0].log, Path::new("/data/log.csv"));
    assert_eq!(c.operating_points[0].conditioned_on.len(), 4);
    assert_eq!(c.parameters[0].start, 0.62);
    assert_eq!(c.min_coherence, 0.6);
}

#[test]
fn hostile_files_name_the_file_and_field() {
    let cases: Vec<(String, &str)> = vec![
        (GOOD.replace("min = 0.3", "min = nan"), "parameter[0].min"),
        (GOOD.replace("max = 1.2", "max = 0.5"), "parameter[0].min"),
        (GOOD.replace("min = 0.3", "min = 0.7"), "parameter[0].min"),
        (
            GOOD.replace("body.iyy_kg_m2", "body.iyy"),
            "parameter[0].key",
        ),
        (
            GOOD.replace("body.iyy_kg_m2", "main_rotor.blades"),
            "parameter[0].key",
        ),
        (GOOD.replace("max = 1.2", "max = 1e300"), "parameter[0].max"),
        (GOOD.replace("\"S_lon\"", "\"S_yaw\""), "response[0].input"),
        (
            GOOD.replace("\"meas_q\"", "\"meas_x\""),
            "response[0].output",
        ),
        (
            GOOD.replace("omega_min_rad_s = 1.5", "omega_min_rad_s = -1.5"),
            "response[0].omega_min_rad_s",
        ),
        (
            GOOD.replace("omega_max_rad_s = 25.0", "omega_max_rad_s = 1.0"),
            "response[0].omega_max_rad_s",
        ),
        (
            GOOD.replace("omega_max_rad_s = 25.0", "omega_max_rad_s = inf"),
            "response[0].omega_max_rad_s",
        ),
        (format!("min_coherence = 1.0\n{GOOD}"), "min_coherence"),
        (format!("w_chi = -1.0\n{GOOD}"), "w_chi"),
        (format!("w_kappa = 0.0\nw_chi = 0.0\n{GOOD}"), "w_kappa"),
        (format!("points = 1\n{GOOD}"), "points"),
        (format!("min_points = 0\n{GOOD}"), "min_points"),
        (format!("max_iterations = 0\n{GOOD}"), "max_iterations"),
        (format!("windows_s = []\n{GOOD}"), "windows_s"),
        (format!("spectra = \"fft\"\n{GOOD}"), "spectra"),
        (
            format!("spectra = \"sweeps\"\n{GOOD}"),
            "operating_point[0].instruments",
        ),
        (format!("sweep_pad_s = -1.0\n{GOOD}"), "sweep_pad_s"),
        (format!("sweep_pad_s = nan\n{GOOD}"), "sweep_pad_s"),
        (format!("sweep_pad_s = 1e9\n{GOOD}"), "sweep_pad_s"),
        (format!("sweep_taper_s = 3.0\n{GOOD}"), "sweep_taper_s"),
        (format!("sweep_taper_s = -0.5\n{GOOD}"), "sweep_taper_s"),
        (format!("windows_s = [24.0, -6.0]\n{GOOD}"), "windows_s[1]"),
        (format!("preset = \"fast\"\n{GOOD}"), "preset"),
        (format!("cost = \"l1\"\n{GOOD}"), "cost"),
        (format!("optimiser = \"genetic\"\n{GOOD}"), "optimiser"),
        (format!("colour = 1\n{GOOD}"), "colour"),
        (
            GOOD.replace(
                "name = \"hover\"",
                "name = \"hover\"\nvelocity_ned_m_s = [1e9, 0.0, 0.0]",
            ),
            "operating_point[0].velocity_ned_m_s[0]",
        ),
        (
            GOOD.replace(
                "name = \"hover\"",
                "name = \"hover\"\nconditioned_on = [\"S_col\", \"S_col\"]",
            ),
            "operating_point[0].conditioned_on[1]",
        ),
        (
            GOOD.replace(
                "name = \"hover\"",
                "name = \"hover\"\nconditioned_on = [\"S_col\"]",
            ),
            "response[0].input",
        ),
        (
            GOOD.replace(
                "name = \"hover\"",
                "name = \"hover\"\nt_start_s = 5.0\nt_end_s = 2.0",
            ),
            "operating_point[0].t_start_s",
        ),
        (
            GOOD.replace("name = \"hover\"", "name = \"\""),
            "operating_point[0].name",
        ),
        (
            format!("{GOOD}\n[[operating_point]]\nname = \"hover\"\nlog = \"b.csv\"\n"),
            "operating_point[1].name",
        ),
        (
            format!("{GOOD}\n[[parameter]]\nkey = \"body.iyy_kg_m2\"\nmin = 0.3\nmax = 1.2\n"),
            "parameter[1].key",
        ),
        (
            GOOD.replace(
                "[[parameter]]\nkey = \"body.iyy_kg_m2\"\nmin = 0.3\nmax = 1.2\n",
                "",
            ),
            "parameter",
        ),
        (
            GOOD.replace(
                "[[operating_point]]\nname = \"hover\"\nlog = \"log.csv\"\n",
                "",
            ),
            "operating_point",
        ),
        (
            format!("{GOOD}\n[[verification]]\noperating_point = \"cruise\"\nlog = \"d.csv\"\n"),
            "verification[0].operating_point",
        ),
        (
            format!(
                "{GOOD}\n[[verification]]\noperating_point = \"hover\"\nlog = \"d.csv\"\noutputs = [\"speed\"]\n"
            ),
            "verification[0].outputs[0]",
        ),
        (
            format!("start = \"/nonexistent/params.toml\"\n{GOOD}"),
            "start",
        ),
        ("[[operating_point]\n".to_string(), "bad.toml"),
    ];
    for (text, field) in cases {
        let e = err(&text);
        assert!(e.contains("bad.toml") && e.contains(field), "{field}: {e}");
    }
}

#[test]
fn a_missing_or_bad_log_names_the_log() {
    let dir = std::env::temp_dir().join(format!("helicon-paramid-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cfg = IdentConfig::from_toml_str(GOOD, "bad.toml", &dir).unwrap();
    let e = helicon_paramid::report::run(&cfg).unwrap_err().to_string();
    assert!(e.contains("log.csv"), "{e}");
    // a log without the output column
    std::fs::write(
        dir.join("log.csv"),
        "t_s,S_col,S_lat,S_lon,S_tr\n0,0,0,0,0\n0.0025,0,0,0,0\n",
    )
    .unwrap();
    let e = helicon_paramid::report::run(&cfg).unwrap_err().to_string();
    assert!(e.contains("log.csv") && e.contains("meas_q"), "{e}");
    // a log too short, with a NaN, with the wrong step
    let mut text = String::from("t_s,S_col,S_lat,S_lon,S_tr,meas_q\n");
    for k in 0..100 {
        text.push_str(&format!("{},0,0,0,0,0\n", k as f64 * 0.01));
    }
    std::fs::write(dir.join("log.csv"), &text).unwrap();
    let e = helicon_paramid::report::run(&cfg).unwrap_err().to_string();
    assert!(
        e.contains("operating_point[0].log") && e.contains("control period"),
        "{e}"
    );
    std::fs::write(
        dir.join("log.csv"),
        text.replace("0.5,0,0,0,0,0", "0.5,0,0,0,0,nan"),
    )
    .unwrap();
    let e = helicon_paramid::report::run(&cfg).unwrap_err().to_string();
    assert!(e.contains("log.csv"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A prior measurement (`prior`, `prior_std`) is checked like the bounds:
/// both or neither, finite, inside the bounds, a positive standard error
/// below the bounds' span.
#[test]
fn hostile_priors_name_the_field() {
    let with = |extra: &str| GOOD.replace("max = 1.2\n", &format!("max = 1.2\n{extra}\n"));
    let good = IdentConfig::from_toml_str(
        &with("prior = 0.7\nprior_std = 0.02"),
        "good.toml",
        Path::new("."),
    )
    .unwrap();
    assert_eq!(good.parameters[0].prior, Some((0.7, 0.02)));
    for (text, field) in [
        (with("prior = 0.7"), "parameter[0].prior_std"),
        (with("prior_std = 0.02"), "parameter[0].prior"),
        (with("prior = nan\nprior_std = 0.02"), "parameter[0].prior"),
        (with("prior = 1.5\nprior_std = 0.02"), "parameter[0].prior"),
        (
            with("prior = 0.7\nprior_std = 0.0"),
            "parameter[0].prior_std",
        ),
        (
            with("prior = 0.7\nprior_std = -0.1"),
            "parameter[0].prior_std",
        ),
        (
            with("prior = 0.7\nprior_std = inf"),
            "parameter[0].prior_std",
        ),
        (
            with("prior = 0.7\nprior_std = 5.0"),
            "parameter[0].prior_std",
        ),
    ] {
        let e = err(&text);
        assert!(e.contains("bad.toml") && e.contains(field), "{field}: {e}");
    }
}

/// A spectral window shorter than a few samples is refused naming the
/// IDENT file and `windows_s[i]` (before: the spectra's own error, naming
/// the log and `window.len` but not the field to change).
#[test]
fn a_window_of_a_few_samples_names_the_field() {
    let dir = std::env::temp_dir().join(format!("helicon-paramid-window-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut text = String::from("t_s,S_col,S_lat,S_lon,S_tr,meas_q\n");
    for k in 0..4000 {
        let t = f64::from(k) * 0.0025;
        let s = |f: f64| (f * t).sin();
        text.push_str(&format!(
            "{t},{},{},{},{},{}\n",
            s(1.0),
            s(2.3),
            s(3.7),
            s(5.1),
            s(0.9)
        ));
    }
    std::fs::write(dir.join("log.csv"), &text).unwrap();
    for w in ["1e-6", "0.0125"] {
        let cfg =
            IdentConfig::from_toml_str(&format!("windows_s = [{w}]\n{GOOD}"), "bad.toml", &dir)
                .unwrap();
        let e = helicon_paramid::report::run(&cfg).unwrap_err().to_string();
        assert!(
            e.contains("bad.toml")
                && e.contains("`windows_s[0]`")
                && e.contains("at least 8 samples"),
            "{w}: {e}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `spectra = "sweeps"` on a log where an excitation never moves, or moves
/// for too few samples for its window, is refused naming the IDENT file,
/// `operating_point[0].instruments[j]`, the log and the column.
#[test]
fn sweep_windows_need_each_excitation_in_the_log() {
    let dir = std::env::temp_dir().join(format!("helicon-paramid-sweeps-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let ident = format!(
        "spectra = \"sweeps\"\nwindows_s = [2.0]\n{}",
        GOOD.replace(
            "log = \"log.csv\"\n",
            "log = \"log.csv\"\ninstruments = [\"exc_col\", \"exc_lat\", \"exc_lon\", \"exc_tr\"]\n",
        )
    );
    let cfg = IdentConfig::from_toml_str(&ident, "bad.toml", &dir).unwrap();
    // exc_lon never moves
    let log = |tr_len: usize| {
        let mut text =
            String::from("t_s,S_col,S_lat,S_lon,S_tr,meas_q,exc_col,exc_lat,exc_lon,exc_tr\n");
        for k in 0..4000usize {
            let t = k as f64 * 0.0025;
            let s = |f: f64| (f * t).sin();
            let on = |a: usize, b: usize| if (a..b).contains(&k) { s(4.0) } else { 0.0 };
            text.push_str(&format!(
                "{t},{},{},{},{},{},{},{},{},{}\n",
                s(1.0),
                s(2.3),
                s(3.7),
                s(5.1),
                s(0.9),
                on(0, 1000),
                on(1000, 2000),
                0.0,
                on(3000, 3000 + tr_len)
            ));
        }
        text
    };
    std::fs::write(dir.join("log.csv"), log(1000)).unwrap();
    let e = helicon_paramid::report::run(&cfg).unwrap_err().to_string();
    assert!(
        e.contains("bad.toml")
            && e.contains("operating_point[0].instruments[2]")
            && e.contains("log.csv")
            && e.contains("exc_lon"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
