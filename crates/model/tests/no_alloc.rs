//! The derivative and the RK4 step allocate nothing on the heap (counting
//! global allocator around the calls).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_model::{Input, Model, Preset, State};
use nalgebra::Vector3;

use helicon_test_support::allocations;

#[global_allocator]
static ALLOC: helicon_test_support::Counting = helicon_test_support::Counting;

#[test]
fn derivative_and_step_do_not_allocate() {
    for preset in [Preset::Physical, Preset::Thesis] {
        let model = Model::bergen_twin(preset);
        let mut x = State::zeros();
        x[22] = 0.13;
        x[25] = 0.11;
        x[6] = 3.0;
        let u = Input::new(0.18, 0.01, -0.01, 0.16);
        let wind = Vector3::new(1.0, -2.0, 0.3);
        // warm up (lazy statics, if any)
        let _ = model.derivative(&x, &u, &wind).unwrap();
        let before = allocations();
        let mut acc = 0.0;
        for _ in 0..1000 {
            let (xd, aux) = model.derivative(&x, &u, &wind).unwrap();
            acc += xd[8] + aux.lambda_mr;
            x = model.step(&x, &u, &wind, 1.0 / 400.0).unwrap().0;
        }
        let after = allocations();
        assert!(acc.is_finite());
        assert_eq!(
            after - before,
            0,
            "{preset:?}: {} allocations",
            after - before
        );
    }
}

#[test]
fn plant_step_with_the_ground_blocks_does_not_allocate() {
    use helicon_model::drivetrain::{RotorState, Spool};
    use helicon_model::landing_gear::{Anchors, resting_state};
    use helicon_model::{Params, PlantState};
    let mut p = Params::bergen_twin();
    p.landing_gear.enabled = 1.0;
    p.ground_effect.enabled = 1.0;
    p.drivetrain.enabled = 1.0;
    let model = Model::new(p, Preset::Physical.options());
    let x = resting_state(&p.landing_gear, 14.0, 9.82, &State::zeros());
    let mut s = PlantState {
        x,
        rotor: RotorState {
            omega_rad_s: 0.0,
            governor_integral: 0.0,
        },
        anchors: Anchors::default(),
    };
    let mut spool = Spool::stopped(&p);
    spool.start(0.0);
    let u = Input::new(0.05, 0.0, 0.0, 0.1);
    let wind = Vector3::new(1.0, -2.0, 0.3);
    let _ = model
        .plant_step(&mut s, &u, &wind, &spool.command, 1.0 / 400.0)
        .unwrap();
    let before = allocations();
    for _ in 0..1000 {
        // spooling up through the aerodynamic floor, on the skids
        model
            .plant_step(&mut s, &u, &wind, &spool.command, 1.0 / 400.0)
            .unwrap();
        spool.step(1.0 / 400.0);
    }
    let after = allocations();
    assert!(s.rotor.omega_rad_s > 10.0 && s.x.iter().all(|v| v.is_finite()));
    assert_eq!(after - before, 0, "{} allocations", after - before);
}
