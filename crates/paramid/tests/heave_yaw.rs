//! The heave and yaw responses of the identification flights match the true
//! model (issue 15). The cost of truth-a's own linearisation on the responses
//! estimated from a flight of truth-a is the measure: at the truth only the
//! estimate's random error (and any bias) is left, so a response whose cost
//! per point stays far above the cyclic ones' is not the model's response.
//!
//! Before the fix the instrumental-variable estimates carried the multiple
//! coherence of the output on the excitations, which stays high in closed
//! loop (the law hides the disturbance from the output) while the estimate
//! of the tail and collective columns is poor (the law moves those servos to
//! cancel the disturbance); and the demo's 24 s windows hold most of one
//! sweep each, the tail sweep's last 6 s (12–30 rad/s) in none. Measured at
//! the truth on the noise-free hover flight, default windows: r/S_tr 705
//! over 40 points, w/S_col 66 (cyclic 0.5); on the shipped (turbulent,
//! sensors in the loop) hover flight with the 24/12/6 s windows: r/S_tr
//! 1335, r/S_col 479, w/S_col 283 (cyclic 2–4).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_ident::frf::{WindowSpec, conditioned, cross_spectra_grid, log_grid};
use helicon_model::Params;
use helicon_paramid::config::{IdentConfig, Spectra};
use helicon_paramid::cost::Cost;
use helicon_paramid::data::{instrumented, measure};
use helicon_paramid::demo::{DemoOptions, FLIGHTS, TRUTHS, fly_scenario, ident_toml};
use std::path::{Path, PathBuf};

fn truth_a() -> (Params, &'static str) {
    let text = TRUTHS.iter().find(|t| t.0 == "truth-a").unwrap().1;
    (Params::from_toml_str(text, "truth-a").unwrap(), text)
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "helicon-paramid-heave-yaw-{name}-{}",
        std::process::id()
    ));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The hover flight's scenario text, optionally without turbulence and
/// with ideal measurements (no sensor models, no fusion).
fn hover_text(clean: bool) -> String {
    let text = FLIGHTS.iter().find(|f| f.0 == "hover").unwrap().2;
    if !clean {
        return text.to_string();
    }
    let cut = text.find("[wind.dryden]").unwrap();
    let end = text[cut..].find("\n\n").unwrap() + cut;
    let out = format!("{}{}", &text[..cut], &text[end + 2..]);
    assert!(!out.contains("dryden"));
    out.replace("fusion = true", "fusion = false")
}

/// Per response of the single operating point: (label, points, cost at
/// the truth per point). `ident` is an IDENT.toml text whose start is the
/// truth (written to `dir/start.toml`).
fn costs_at_truth(dir: &Path, ident: &str) -> Vec<(String, usize, f64)> {
    let (_, truth_text) = truth_a();
    std::fs::write(dir.join("start.toml"), truth_text).unwrap();
    let cfg = IdentConfig::from_toml_str(ident, "heave-yaw.toml", dir).unwrap();
    let data = vec![measure(&cfg, 0).unwrap()];
    let cost = Cost::new(&cfg, &data).unwrap();
    assert!(cost.skipped.is_empty(), "skipped: {:?}", cost.skipped);
    let at: Vec<f64> = cost.parameters.iter().map(|p| p.start).collect();
    let split = cost.split(&cost.residuals(&at).unwrap());
    cost.points[0]
        .responses
        .iter()
        .zip(&split[0])
        .map(|(r, c)| {
            let n = r.omega_rad_s.len();
            println!(
                "{:14} {n:3} points, cost at the truth {c:8.2} ({:.3} per point)",
                r.label,
                c / n as f64
            );
            (r.label.clone(), n, c / n as f64)
        })
        .collect()
}

const RESPONSES: [(&str, &str); 5] = [
    ("S_lat", "meas_p"),
    ("S_lon", "meas_q"),
    ("S_col", "w"),
    ("S_col", "meas_r"),
    ("S_tr", "meas_r"),
];

/// Noise-free hover flight (no turbulence, ideal measurements, truth-a, the
/// LQI on the nominal model), instrumental-variable estimates with the
/// default 24/12/6 s windows: every heave and yaw response keeps ≥ 30 of 40
/// points and its cost at the truth per point stays below 0.5 (an rms error
/// of ~0.5 dB and ~4°; measured 0.03–0.14, cyclic 0.02–0.03; before the fix
/// 17.6 for r/S_tr and 1.65 for w/S_col).
#[test]
fn noise_free_flight_heave_and_yaw_match_the_truth() {
    let dir = scratch("clean");
    fly_scenario(
        "hover",
        &hover_text(true),
        &truth_a().0,
        None,
        &dir.join("log.csv"),
    )
    .unwrap();
    let mut ident = String::from(
        "start = \"start.toml\"\npoints = 40\n\n[[operating_point]]\nname = \"hover\"\n\
         velocity_ned_m_s = [0.0, 0.0, 0.0]\nlog = \"log.csv\"\n\
         instruments = [\"exc_col\", \"exc_lat\", \"exc_lon\", \"exc_tr\"]\n",
    );
    for (i, o) in RESPONSES {
        ident += &format!(
            "\n[[response]]\ninput = \"{i}\"\noutput = \"{o}\"\nomega_min_rad_s = 1.5\nomega_max_rad_s = 25.0\n"
        );
    }
    ident += "\n[[parameter]]\nkey = \"main_rotor.drag_coefficient\"\nmin = 0.004\nmax = 0.02\n";
    let costs = costs_at_truth(&dir, &ident);
    let _ = std::fs::remove_dir_all(&dir);
    for (label, n, c) in &costs {
        assert!(*n >= 30, "{label}: {n} coherent points");
        assert!(*c < 0.5, "{label}: cost at the truth {c:.3} per point");
    }
}

/// The shipped hover flight (turbulence, sensors in the loop, seed 3) with
/// the demo's own IDENT.toml (its responses), estimated with the overlapped
/// Hann windows and with one window per sweep: every response is kept, and
/// the heave (w/S_col) and yaw (meas_r/S_tr) costs at the truth per point
/// are within 4× the worst cyclic one; with the Hann windows also below 1.5
/// (measured: yaw 0.40, heave 0.62, cyclic 0.08–0.26; before the fix, with
/// these windows, 17.7 on the yaw). The sweep windows' estimate is noisier
/// (its window holds the whole sweep's turbulence, while the sweep passes
/// each frequency in a few seconds), so its costs at the truth are larger:
/// yaw 2.14 per point, cyclic 0.33–0.75 (asserted yaw < 4× cyclic). Its
/// heave estimate is poor at hover: 9 coherent points at 8.0 per point
/// (asserted only kept, ≥ 5 points); this is why the demo flags the
/// collective servo's bandwidth insensitive (docs/paramid.md).
#[test]
fn shipped_hover_flight_heave_and_yaw_at_the_cyclic_level() {
    let dir = scratch("hover");
    let log = dir.join("flights").join("hover").join("log.csv");
    fly_scenario("hover", &hover_text(false), &truth_a().0, Some(3), &log).unwrap();
    for spectra in [Spectra::Welch, Spectra::Sweeps] {
        let opts = DemoOptions {
            flights: vec!["hover".into()],
            verify: false,
            spectra,
            ..DemoOptions::default()
        };
        let costs = costs_at_truth(&dir, &ident_toml(&opts));
        let cyclic = costs
            .iter()
            .filter(|c| c.0.ends_with("/S_lat") || c.0.ends_with("/S_lon"))
            .map(|c| c.2)
            .fold(0.0, f64::max);
        let heave_yaw: Vec<_> = costs
            .iter()
            .filter(|c| c.0.ends_with("/S_col") || c.0.ends_with("/S_tr"))
            .collect();
        assert_eq!(heave_yaw.len(), 2);
        for (label, n, c) in heave_yaw {
            if spectra == Spectra::Sweeps && label == "w/S_col" {
                // kept, but poor: see the doc comment
                assert!(*n >= 5, "{spectra:?} {label}: {n} coherent points");
                continue;
            }
            assert!(*n >= 10, "{spectra:?} {label}: {n} coherent points");
            assert!(
                *c < 4.0 * cyclic && (spectra == Spectra::Sweeps || *c < 1.5),
                "{spectra:?} {label}: cost at the truth {c:.3} per point (cyclic up to {cyclic:.3})"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// With the excitation as its own instrument (open loop, e = u) the
/// instrumented estimate and its coherence are the ordinary ones: the same
/// H and γ² as the single-input conditioned estimate, to round-off.
#[test]
fn instrumented_coherence_is_the_ordinary_one_in_open_loop() {
    // xorshift noise: u white, y = first-order lag of u plus independent noise
    let mut s: u64 = 0x2545_f491_4f6c_dd1d;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let n = 8000;
    let dt = 0.01;
    let u: Vec<f64> = (0..n).map(|_| rnd()).collect();
    let mut y = vec![0.0; n];
    for k in 1..n {
        y[k] = 0.9 * y[k - 1] + 0.1 * u[k - 1];
    }
    let y: Vec<f64> = y.iter().map(|v| v + 0.1 * rnd()).collect();
    let grid = log_grid(0.5, 100.0, 30).unwrap();
    let cs = cross_spectra_grid(&[&u, &u, &y], dt, WindowSpec::half_overlap(500), &grid).unwrap();
    let iv = instrumented(&cs, &[1], &[0], 2, 0).unwrap();
    let (cond, _) = conditioned(&cs, &[0], 2).unwrap();
    assert_eq!(iv.omega_rad_s, cond[0].omega_rad_s);
    let mut lowest: f64 = 1.0;
    for k in 0..iv.omega_rad_s.len() {
        assert!((iv.h[k] - cond[0].h[k]).norm() < 1e-9 * cond[0].h[k].norm());
        assert!((iv.coherence[k] - cond[0].coherence[k]).abs() < 1e-9);
        assert!((iv.random_error[k] - cond[0].random_error[k]).abs() < 1e-9);
        lowest = lowest.min(iv.coherence[k]);
    }
    // the noise shows at the high frequencies, where the lag has rolled off
    assert!(lowest < 0.9, "lowest γ² {lowest}");
}
