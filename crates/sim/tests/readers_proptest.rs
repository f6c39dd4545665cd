//! Property tests of the file readers a user feeds: scenario and campaign
//! TOML, sensor logs and `log.csv`. Random and extreme values (0, ±1e-300,
//! ±1e300, NaN, inf, text, truncated numbers) in random fields must give
//! either a valid result whose numbers are finite or a typed error — never a
//! panic. Each reader is also checked to accept the unmodified file, so the
//! properties exercise the checks rather than a parse failure.

use helicon_sim::log_csv::read_log_csv;
use helicon_sim::mc::Campaign;
use helicon_sim::scenario::Scenario;
use helicon_sim::sensor_log::read_sensor_log;
use proptest::prelude::*;

/// Values a hostile user types into a numeric field.
fn hostile_value() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("0".to_string()),
        Just("-0.0".to_string()),
        Just("1e-300".to_string()),
        Just("-1e-300".to_string()),
        Just("1e300".to_string()),
        Just("-1e300".to_string()),
        Just("nan".to_string()),
        Just("inf".to_string()),
        Just("-inf".to_string()),
        Just("\"text\"".to_string()),
        Just("[1.0, 2.0]".to_string()),
        Just("true".to_string()),
        Just("1000000000".to_string()),
        (-1e6f64..1e6).prop_map(|v| format!("{v:?}")),
    ]
}

const SCENARIO_KEYS: [&str; 14] = [
    "duration_s",
    "trim.velocity_ned_m_s",
    "trim.yaw_rad",
    "plant.substeps",
    "plant.inflow_iterations",
    "plant.max_attitude_rad",
    "plant.max_rate_rad_s",
    "log.decimation",
    "wind.seed",
    "wind.steady.wind_ned_m_s",
    "wind.dryden.w20_m_s",
    "sensors.gps.rate_hz",
    "navigation.accel_sigma_m_s2",
    "controller.rho",
];

/// A scenario with `key = value` set (dotted keys become a table).
fn scenario_with(key: &str, value: &str) -> String {
    let reference = "[[reference]]\nt_s = 1.0\noutput = \"vn\"\nvalue = 1.0\n";
    match key.rsplit_once('.') {
        None => format!("name = \"p\"\n{key} = {value}\n{reference}"),
        Some((table, k)) => {
            format!("name = \"p\"\nduration_s = 1.0\n{reference}[{table}]\n{k} = {value}\n")
        }
    }
}

#[test]
fn the_unmodified_files_are_accepted() {
    Scenario::from_toml_str(&scenario_with("duration_s", "2.0"), "s.toml").unwrap();
    Scenario::from_toml_str(&scenario_with("plant.substeps", "2"), "s.toml").unwrap();
    Campaign::from_toml_str(&campaign_with("0.05"), "c.toml", None).unwrap();
}

fn campaign_with(sigma: &str) -> String {
    format!(
        "name = \"c\"\nruns = 3\nseed = 1\n[scenario]\nduration_s = 1.0\n\
         [[dispersion]]\nparam = \"body.mass_kg\"\ndistribution = \"normal\"\n\
         kind = \"relative\"\nsigma = {sigma}\n"
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn scenario_fields_never_panic(k in 0..SCENARIO_KEYS.len(), v in hostile_value()) {
        let text = scenario_with(SCENARIO_KEYS[k], &v);
        match Scenario::from_toml_str(&text, "s.toml") {
            Ok(s) => {
                prop_assert!(s.duration_s.is_finite() && s.duration_s > 0.0);
                prop_assert!(s.plant.substeps >= 1 && s.plant.substeps <= 1000);
            }
            Err(e) => prop_assert!(e.to_string().starts_with("s.toml"), "{e}"),
        }
    }

    #[test]
    fn campaign_dispersions_never_panic(v in hostile_value()) {
        match Campaign::from_toml_str(&campaign_with(&v), "c.toml", None) {
            Ok(c) => prop_assert!(c.runs >= 1),
            Err(e) => prop_assert!(e.to_string().contains("c.toml"), "{e}"),
        }
    }

    #[test]
    fn sensor_log_cells_never_panic(row in 0usize..5, col in 0usize..13, v in hostile_value()) {
        let dir = std::env::temp_dir().join(format!("helicon-prop-sl-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("log.csv");
        let mut text = String::from(
            "t_s,fx_m_s2,fy_m_s2,fz_m_s2,p_rad_s,q_rad_s,r_rad_s,mx,my,mz,gps_n_m,gps_e_m,gps_d_m\n",
        );
        for r in 0..5 {
            let mut cells: Vec<String> = vec![
                format!("{}", r as f64 * 0.01), "0.1".into(), "0".into(), "-9.8".into(),
                "0".into(), "0".into(), "0.01".into(), "0.15".into(), "0".into(), "-0.44".into(),
                "1".into(), "2".into(), "-3".into(),
            ];
            if r == row {
                cells[col] = v.replace('"', "");
            }
            text.push_str(&cells.join(","));
            text.push('\n');
        }
        std::fs::write(&path, text).unwrap();
        match read_sensor_log(&path) {
            Ok(log) => {
                for r in &log.rows {
                    prop_assert!(r.frame.first_non_finite().is_none());
                }
            }
            Err(e) => prop_assert!(e.to_string().contains("log.csv"), "{e}"),
        }
    }

    #[test]
    fn log_csv_cells_never_panic(col in 0usize..83, v in hostile_value()) {
        let dir = std::env::temp_dir().join(format!("helicon-prop-lc-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("log.csv");
        let header = helicon_sim::output::log_header().join(",");
        let n = header.split(',').count();
        let mut text = format!("{header}\n");
        for r in 0..3 {
            let mut cells: Vec<String> = (0..n).map(|j| format!("{}", j as f64 * 0.5)).collect();
            cells[0] = format!("{}", r as f64 * 0.01);
            if r == 1 {
                cells[col % n] = v.replace('"', "");
            }
            text.push_str(&cells.join(","));
            text.push('\n');
        }
        std::fs::write(&path, text).unwrap();
        match read_log_csv(&path) {
            Ok(t) => prop_assert!(t.time_s().iter().all(|v| v.is_finite())),
            Err(e) => prop_assert!(e.to_string().contains("log.csv"), "{e}"),
        }
    }
}
