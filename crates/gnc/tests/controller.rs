//! The flight controller's design and step: against the linear model it was
//! designed on, allocation-free, gains file round trip.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_core::{
    Estimator, FlightComputer, KalmanPredictor, Lqi, Reference, ServoLimits, StateMeasurement,
};
use helicon_gnc::design::{ControllerConfig, Gains, design};
use helicon_model::linearize::linearize;
use helicon_model::trim::{TrimOptions, TrimTarget, trim};
use helicon_model::{InflowMode, Model, Preset};
use nalgebra::{DMatrix, DVector, SVector, Vector3};

use helicon_test_support::allocations;

#[global_allocator]
static ALLOC: helicon_test_support::Counting = helicon_test_support::Counting;

struct Setup {
    gains: Gains,
    phi: DMatrix<f64>,
    gamma: DMatrix<f64>,
    x_trim: DVector<f64>,
}

fn setup(config: &ControllerConfig) -> Setup {
    let model = Model::bergen_twin(Preset::Thesis);
    let t = trim(&model, &TrimTarget::hover(), &TrimOptions::default()).unwrap();
    let lm = linearize(&model, &t.x, &t.u, &Vector3::zeros(), InflowMode::Converged).unwrap();
    let ts = model.params().control.sample_time_s;
    let (phi, gamma) = lm.discretize(ts).unwrap();
    let gains = design(&phi, &gamma, &t.x, &t.u, ts, config).unwrap();
    Setup {
        gains,
        phi,
        gamma,
        x_trim: DVector::from_column_slice(t.x.as_slice()),
    }
}

fn computer(g: &Gains) -> FlightComputer<KalmanPredictor, Lqi> {
    let limits = ServoLimits {
        min: SVector::repeat(-1.0),
        max: SVector::repeat(1.0),
    };
    let est = KalmanPredictor::new(&g.set, &g.set.x_trim).unwrap();
    FlightComputer::new(est, Lqi::new(&g.set, limits, true).unwrap())
}

fn measure(k: usize, x: &DVector<f64>) -> <KalmanPredictor as Estimator>::Measurement {
    StateMeasurement {
        t_s: k as f64 * 0.0025,
        measured: SVector::<f64, 9>::from_fn(|i, _| x[i]),
    }
}

#[test]
fn design_meets_the_pincer_radius() {
    // (14.18)–(14.22): every closed-loop pole inside |z| < 1/α; estimator poles stable.
    let s = setup(&ControllerConfig::default());
    let r = s
        .gains
        .closed_loop_poles
        .iter()
        .map(|z| (z[0] * z[0] + z[1] * z[1]).sqrt())
        .fold(0.0, f64::max);
    assert!(
        (s.gains.set.alpha - 1.0023).abs() < 1e-4,
        "{}",
        s.gains.set.alpha
    );
    assert!(r < 1.0 / s.gains.set.alpha, "{r}");
    assert_eq!(r, s.gains.spectral_radius());
    let re = s
        .gains
        .estimator_poles
        .iter()
        .map(|z| (z[0] * z[0] + z[1] * z[1]).sqrt())
        .fold(0.0, f64::max);
    assert!(re < 1.0, "{re}");
}

#[test]
fn linear_closed_loop_with_estimator_tracks_and_converges() {
    // Fly the controller on the *linear* discrete model it was designed on,
    // with only the nine measured states: the estimate converges to the truth
    // and a 1 m/s north reference is tracked with zero steady-state error
    // (integral action), the separation principle at work.
    let s = setup(&ControllerConfig::default());
    let mut c = computer(&s.gains);
    let mut x = s.x_trim.clone();
    x[3] += 0.5; // 0.5 m/s initial error the estimator does not know about
    let u_trim = DVector::from_column_slice(s.gains.set.u_trim.as_slice());
    let reference = Reference {
        velocity_ned_m_s: Vector3::new(1.0, 0.0, 0.0),
        yaw_rad: 0.0,
    };
    let mut est_err = 0.0;
    for k in 0..8000 {
        let y = measure(k, &x);
        let out = c.step(&y, &reference).unwrap();
        if k == 7999 {
            // x̂(k|k−1) against x(k)
            est_err = (SVector::<f64, 27>::from_column_slice(x.as_slice()) - out.estimate).amax();
        }
        let du = DVector::from_column_slice(out.command.as_slice()) - &u_trim;
        let dx = &x - &s.x_trim;
        x = &s.x_trim + &s.phi * dx + &s.gamma * du;
    }
    // earth north velocity ≈ body u at ψ = 0 (small roll/pitch)
    let vn = x[3] * x[1].cos();
    assert!((vn - 1.0).abs() < 0.01, "vn = {vn}");
    assert!(est_err < 1e-3, "estimate error {est_err}");
}

#[test]
fn step_does_not_allocate_and_gains_round_trip() {
    let s = setup(&ControllerConfig::default());
    let dir = std::env::temp_dir().join(format!("helicon-gains-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("gains.json");
    s.gains.save(&path).unwrap();
    let loaded = Gains::load(&path).unwrap();
    assert_eq!(loaded, s.gains);
    let mut c = computer(&loaded);
    let xt = s.x_trim.map(|v| v + 0.01);
    let r = Reference::default();
    let _ = c.step(&measure(0, &xt), &r).unwrap();
    let before = allocations();
    let mut acc = 0.0;
    for k in 1..1000 {
        acc += c.step(&measure(k, &xt), &r).unwrap().command[0];
    }
    assert!(acc.is_finite());
    assert_eq!(allocations() - before, 0, "FlightComputer::step allocated");
    // a corrupted file is an error naming it, not a panic
    std::fs::write(&path, "{\"version\": 1}").unwrap();
    let e = Gains::load(&path).unwrap_err().to_string();
    assert!(e.contains("gains.json"), "{e}");
    // an edited sample time (α no longer matches it) is refused
    let text = s
        .gains
        .to_json()
        .unwrap()
        .replace("\"sample_time_s\": 0.0025", "\"sample_time_s\": 0.005");
    assert!(text.contains("0.005"));
    let e = Gains::from_json(&text).unwrap_err().to_string();
    assert!(e.contains("alpha"), "{e}");
    // an edited alpha is refused
    let v: serde_json::Value = serde_json::from_str(&s.gains.to_json().unwrap()).unwrap();
    let mut v = v;
    v["alpha"] = serde_json::json!(1.5);
    let e = Gains::from_json(&v.to_string()).unwrap_err().to_string();
    assert!(e.contains("alpha") && e.contains("edited"), "{e}");
}
