//! The flight controller's design and step: against the linear model it was
//! designed on, allocation-free, gains file round trip.

#![allow(clippy::unwrap_used, clippy::expect_used)]
#![allow(unsafe_code)] // the counting GlobalAlloc below

use helicon_gnc::controller::{ControllerSwitches, Feedback, FlightController, Reference};
use helicon_gnc::design::{ControllerConfig, Gains, design};
use helicon_model::linearize::linearize;
use helicon_model::trim::{TrimOptions, TrimTarget, trim};
use helicon_model::{InflowMode, Model, Preset};
use nalgebra::{DMatrix, DVector, SVector, Vector3};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;
thread_local! {
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
}
// SAFETY: forwards every call unchanged to the system allocator.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCS.with(|c| c.set(c.get() + 1));
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}
#[global_allocator]
static GLOBAL: Counting = Counting;

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
    let (phi, gamma) = lm.discretize(config.sample_time_s).unwrap();
    let gains = design(&phi, &gamma, t.x.as_slice(), t.u.as_slice(), config).unwrap();
    Setup {
        gains,
        phi,
        gamma,
        x_trim: DVector::from_column_slice(t.x.as_slice()),
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
    assert!((s.gains.alpha - 1.0023).abs() < 1e-4, "{}", s.gains.alpha);
    assert!(r < 1.0 / s.gains.alpha, "{r}");
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
    let sw = ControllerSwitches::default();
    let mut c = FlightController::new(&s.gains, [-1.0; 4], [1.0; 4], sw).unwrap();
    let mut x = s.x_trim.clone();
    x[3] += 0.5; // 0.5 m/s initial error the estimator does not know about
    let u_trim = DVector::from_column_slice(&s.gains.u_trim);
    c.reset(&SVector::<f64, 27>::from_column_slice(s.x_trim.as_slice()));
    let reference = Reference {
        velocity_ned_m_s: Vector3::new(1.0, 0.0, 0.0),
        yaw_rad: 0.0,
    };
    let mut est_err = 0.0;
    for k in 0..8000 {
        let y = SVector::<f64, 9>::from_fn(|i, _| x[i]);
        let out = c.step(Feedback::Measured(&y), &reference);
        let du = DVector::from_column_slice(out.u.as_slice()) - &u_trim;
        let dx = &x - &s.x_trim;
        x = &s.x_trim + &s.phi * dx + &s.gamma * du;
        if k == 7999 {
            est_err = (SVector::<f64, 27>::from_column_slice(x.as_slice()) - c.estimate()).amax();
        }
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
    let mut c =
        FlightController::new(&loaded, [-1.0; 4], [1.0; 4], ControllerSwitches::default()).unwrap();
    let y = SVector::<f64, 9>::from_fn(|i, _| s.x_trim[i] + 0.01);
    let r = Reference::default();
    let _ = c.step(Feedback::Measured(&y), &r);
    let before = ALLOCS.with(Cell::get);
    let mut acc = 0.0;
    for _ in 0..1000 {
        acc += c.step(Feedback::Measured(&y), &r).u[0];
    }
    assert!(acc.is_finite());
    assert_eq!(
        ALLOCS.with(Cell::get) - before,
        0,
        "FlightController::step allocated"
    );
    // a corrupted file is an error naming it, not a panic
    std::fs::write(&path, "{\"version\": 1}").unwrap();
    let e = Gains::load(&path).unwrap_err().to_string();
    assert!(e.contains("gains.json"), "{e}");
}
