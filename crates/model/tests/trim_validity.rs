//! Physical validity of trims (`Trim::validity`, `require_physical`), jumps
//! between sweep points (`discontinuities`), and linearization only at an
//! equilibrium.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_model::linearize::linearize;
use helicon_model::state::{REDUCED_OFFSET, ix};
use helicon_model::trim::{
    Allowed, JUMP_FLOOR, Trim, TrimError, TrimOptions, TrimTarget, discontinuities, sweep, trim,
};
use helicon_model::{InflowMode, Model, Params, Preset};
use nalgebra::Vector3;

fn heavy(factor: f64) -> Model {
    let mut p = Params::bergen_twin();
    p.body.mass_kg *= factor;
    Model::new(p, Preset::Physical.options())
}

fn climb_targets(values: &[f64]) -> Vec<TrimTarget> {
    values
        .iter()
        .map(|&c| TrimTarget {
            velocity_ned_m_s: Vector3::new(0.0, 0.0, -c),
            ..TrimTarget::hover()
        })
        .collect()
}

#[test]
fn hover_and_the_forward_sweep_0_to_15_are_physical_without_jumps() {
    for preset in [Preset::Physical, Preset::Thesis] {
        let model = Model::bergen_twin(preset);
        let h = trim(&model, &TrimTarget::hover(), &TrimOptions::default()).unwrap();
        assert!(h.validity(&model).is_physical(), "{preset:?}");
        assert!(h.require_physical(&model).is_ok());
    }
    let model = Model::bergen_twin(Preset::Physical);
    let targets: Vec<TrimTarget> = (0..=30)
        .map(|k| TrimTarget {
            velocity_ned_m_s: Vector3::new(0.5 * f64::from(k), 0.0, 0.0),
            ..TrimTarget::hover()
        })
        .collect();
    let results = sweep(&model, &targets, &TrimOptions::default());
    for (k, r) in results.iter().enumerate() {
        let v = r.as_ref().unwrap().validity(&model);
        assert!(v.is_physical(), "point {k}: {:?}", v.violations);
    }
    let d = discontinuities(&results);
    assert!(d.is_empty(), "{d:?}");
}

#[test]
fn mass_x100_converges_but_is_unphysical_naming_each_quantity() {
    // Today's regression: mass x100 "trimmed" with theta0 = 6.0 rad and S_col = 8.6.
    let model = heavy(100.0);
    let t = trim(&model, &TrimTarget::hover(), &TrimOptions::default()).unwrap();
    assert!(t.residual_norm < 1e-9);
    let v = t.validity(&model);
    let names: Vec<&str> = v.violations.iter().map(|v| v.quantity).collect();
    for q in [
        "S_col",
        "S_tr",
        "alpha75_mr",
        "alpha75_tr",
        "a0",
        "a1",
        "a1sb",
    ] {
        assert!(names.contains(&q), "{q} missing from {names:?}");
    }
    let s_col = &v.violations[0];
    assert_eq!(s_col.quantity, "S_col");
    assert!((s_col.value - 8.616).abs() < 1e-3, "{}", s_col.value);
    assert_eq!(
        s_col.allowed,
        Allowed::Within {
            min: -0.1,
            max: 0.3
        }
    );
    match t.require_physical(&model) {
        Err(e @ TrimError::Unphysical { .. }) => {
            let s = e.to_string();
            assert!(
                s.contains("S_col = 8.6") && s.contains("[-0.1, 0.3]"),
                "{s}"
            );
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn mass_x2_hover_only_needs_s_col_beyond_its_range() {
    let model = heavy(2.0);
    let t = trim(&model, &TrimTarget::hover(), &TrimOptions::default()).unwrap();
    let v = t.validity(&model);
    assert_eq!(v.violations.len(), 1, "{:?}", v.violations);
    assert_eq!(v.violations[0].quantity, "S_col");
    assert!(v.violations[0].value > 0.3 && v.violations[0].value < 0.33);
}

#[test]
fn climb_sweep_flags_servo_range_vortex_ring_and_the_branch_jump() {
    // helicon trim --sweep climb --from -20 --to 20: today "all converged", no warning.
    let model = Model::bergen_twin(Preset::Physical);
    let values: Vec<f64> = (0..=80).map(|k| -20.0 + 0.5 * f64::from(k)).collect();
    let results = sweep(&model, &climb_targets(&values), &TrimOptions::default());
    let o = REDUCED_OFFSET;
    for (c, r) in values.iter().zip(&results) {
        let t = r.as_ref().unwrap();
        let names: Vec<&str> = t
            .validity(&model)
            .violations
            .iter()
            .map(|v| v.quantity)
            .collect();
        // S_col beyond [-0.1, 0.3]: fast climbs and fast descents
        let s_col = t.u[0];
        assert_eq!(
            names.contains(&"S_col"),
            !(-0.1..=0.3).contains(&s_col),
            "{c}: {names:?}"
        );
        assert_eq!(names.contains(&"S_col"), *c >= 7.5 || *c <= -11.0, "{c}");
        // vortex-ring region of the main rotor: descents 1.5..8 m/s (the (7.33)
        // root with lambda < 0 in descent always has 0 < d < 2, see the unit test)
        assert_eq!(
            names.contains(&"descent_ratio_mr"),
            (-8.0..=-1.5).contains(c),
            "{c}: {names:?}"
        );
        // windmill brake beyond: flow up through the disc
        assert_eq!(t.aux.lambda_mr > 0.0, *c <= -8.5, "{c}");
        assert!(t.x[ix::A0 - o].abs() < 0.2);
    }
    // one jump: from the windmill-brake root at -8.5 to the vortex-ring root at -8
    let d = discontinuities(&results);
    assert_eq!(d.len(), 1, "{d:?}");
    assert_eq!(values[d[0].index], -8.0);
    let jumped: Vec<&str> = d[0].quantities.iter().map(|q| q.0).collect();
    for q in ["S_col", "S_tr", "theta0", "lambda_mr"] {
        assert!(jumped.contains(&q), "{q}: {jumped:?}");
    }
    // the same jump at a coarser step
    let coarse: Vec<f64> = (0..=20).map(|k| -20.0 + 2.0 * f64::from(k)).collect();
    let results = sweep(&model, &climb_targets(&coarse), &TrimOptions::default());
    let d = discontinuities(&results);
    assert_eq!(d.len(), 1, "{d:?}");
    assert_eq!(coarse[d[0].index], -8.0);
}

#[test]
fn discontinuity_rule_on_synthetic_sweeps() {
    // The rule: |d_k| > 3 max(|d_k-1|, |d_k+1|), > 5 % of the excursion, > 1e-6.
    let model = Model::bergen_twin(Preset::Physical);
    let base = trim(&model, &TrimTarget::hover(), &TrimOptions::default()).unwrap();
    let with = |f: &dyn Fn(usize) -> f64| -> Vec<Result<Trim, TrimError>> {
        (0..10)
            .map(|k| {
                let mut t = base.clone();
                t.u[0] = f(k);
                Ok(t)
            })
            .collect()
    };
    // smooth, even strongly curved: no jump
    assert!(discontinuities(&with(&|k| 0.01 * (k * k) as f64)).is_empty());
    // an extremum just before the end of the sweep: the last step (−2) is
    // far more than 3x its only neighbour (0), but 3.6 % of the excursion
    // (56): no jump
    let flat_end = |k: usize| -> f64 {
        let x = k as f64 - 7.5;
        -(x * x)
    };
    assert!(discontinuities(&with(&flat_end)).is_empty());
    // a step of 0.05 on a ramp of 0.01 per point, between points 4 and 5
    let d = discontinuities(&with(&|k| {
        0.01 * k as f64 + if k >= 5 { 0.05 } else { 0.0 }
    }));
    assert_eq!(d.len(), 1);
    assert_eq!(d[0].index, 5);
    assert_eq!(d[0].quantities.len(), 1);
    assert_eq!(d[0].quantities[0].0, "S_col");
    assert!((d[0].quantities[0].1 - 0.06).abs() < 1e-12);
    // a jump below the floor on a flat line is not one
    assert!(discontinuities(&with(&|k| if k >= 5 { 0.5 * JUMP_FLOOR } else { 0.0 })).is_empty());
    // a failed point breaks the neighbourhood: no step across it
    let mut r = with(&|k| if k >= 5 { 1.0 } else { 0.0 });
    r[5] = Err(TrimError::BadTarget);
    assert!(discontinuities(&r).is_empty());
}

#[test]
fn linearize_sees_a_clipped_trim_is_not_an_equilibrium() {
    // mass x100: the trim (saturation lifted) needs S_col = 8.6; the model
    // clips it to 0.3, so the point is far from an equilibrium (affine residual ~1e2).
    let model = heavy(100.0);
    let t = trim(&model, &TrimTarget::hover(), &TrimOptions::default()).unwrap();
    let lm = linearize(&model, &t.x, &t.u, &Vector3::zeros(), InflowMode::Converged).unwrap();
    assert!(!lm.is_equilibrium());
    let (name, value) = lm.worst_residual();
    assert!(value.abs() > 1.0, "{name} = {value}");
    // a hover of the nominal model is one
    let model = Model::bergen_twin(Preset::Physical);
    let t = trim(&model, &TrimTarget::hover(), &TrimOptions::default()).unwrap();
    let lm = linearize(&model, &t.x, &t.u, &Vector3::zeros(), InflowMode::Converged).unwrap();
    assert!(lm.is_equilibrium(), "{:?}", lm.worst_residual());
}
