//! The qualitative verification of thesis chapter 10 (Tables 4.1, 10.1, 10.2,
//! 10.3) and the model's invariants.
//!
//! Flapping responses are compared at *quasi-steady flapping*: all other
//! states are frozen and the flapping states (main rotor and stabilizer bar)
//! are integrated until they settle (time constants ≤ 0.1 s; 1 s is enough).
#![allow(clippy::too_many_lines, clippy::panic, clippy::cast_possible_wrap)] // tests: long scenarios, panics are failures
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use helicon_model::integrate::rk4;
use helicon_model::state::{State, ix};
use helicon_model::{Input, Model, Params, Preset};
use nalgebra::Vector3;

const FLAP: [usize; 10] = [
    ix::A0,
    ix::A1,
    ix::B1,
    ix::A0_DOT,
    ix::A1_DOT,
    ix::B1_DOT,
    ix::A1SB,
    ix::B1SB,
    ix::A1SB_DOT,
    ix::B1SB_DOT,
];

/// Integrate only the flapping states (others frozen) to steady state.
fn flap_steady(model: &Model, x: &State, u: &Input) -> State {
    let mut s = *x;
    let f = |y: &State| -> Result<State, helicon_model::ModelError> {
        let (d, _) = model.derivative(y, u, &Vector3::zeros())?;
        let mut out = State::zeros();
        for i in FLAP {
            out[i] = d[i];
        }
        Ok(out)
    };
    for _ in 0..4000 {
        s = rk4(&s, 2.5e-4, f).unwrap();
    }
    s
}

fn hover() -> (State, Input) {
    let (x, u, _, _) = common::six_digit_hover_trim();
    (x, u)
}

fn model(preset: Preset) -> Model {
    Model::bergen_twin(preset)
}

/// Steady flapping change when `edit` is applied to the state.
fn delta(model: &Model, x: &State, u: &Input, edit: impl Fn(&mut State)) -> (State, State) {
    let base = flap_steady(model, x, u);
    let mut xp = *x;
    edit(&mut xp);
    let pert = flap_steady(model, &xp, u);
    (base, pert)
}

#[test]
fn table_4_1_cyclic_inputs_flapping_and_translation() {
    // A1 > 0 → b1 < 0 → v̇ < 0 ; B1 > 0 → a1 < 0 → u̇ > 0 (hover); and the mirror.
    for preset in [Preset::Thesis, Preset::Physical] {
        let m = model(preset);
        let (x, u) = hover();
        for sign in [1.0, -1.0] {
            let (b, p) = delta(&m, &x, &u, |s| s[ix::A1_SWASH] += sign * 0.01);
            assert!(sign * (p[ix::B1] - b[ix::B1]) < 0.0, "{preset:?} A1 {sign}");
            let vb = m.derivative(&b, &u, &Vector3::zeros()).unwrap().0[ix::V];
            let vp = m.derivative(&p, &u, &Vector3::zeros()).unwrap().0[ix::V];
            assert!(sign * (vp - vb) < 0.0, "{preset:?} A1 {sign}: v̇");
            let (b, p) = delta(&m, &x, &u, |s| s[ix::B1_SWASH] += sign * 0.01);
            assert!(sign * (p[ix::A1] - b[ix::A1]) < 0.0, "{preset:?} B1 {sign}");
            let ub = m.derivative(&b, &u, &Vector3::zeros()).unwrap().0[ix::U];
            let up = m.derivative(&p, &u, &Vector3::zeros()).unwrap().0[ix::U];
            assert!(sign * (up - ub) > 0.0, "{preset:?} B1 {sign}: u̇");
        }
    }
}

#[test]
fn table_10_1_hover_inputs() {
    let m = model(Preset::Thesis);
    let (x, u) = hover();
    let (b, p) = delta(&m, &x, &u, |s| s[ix::THETA0] += 0.01);
    assert!(p[ix::A0] > b[ix::A0], "θ0↑ → a0↑");
    let (b, p) = delta(&m, &x, &u, |s| s[ix::A1_SWASH] += 0.01);
    assert!(p[ix::B1] < b[ix::B1], "A1↑ → b1↓");
    let (b, p) = delta(&m, &x, &u, |s| s[ix::B1_SWASH] += 0.01);
    assert!(p[ix::A1] < b[ix::A1], "B1↑ → a1↓");
}

#[test]
fn table_10_1_hover_body_rates_primary_response() {
    // Constant p > 0 → b1 < 0 (flapping lags the shaft); constant q > 0 → a1 < 0.
    let m = model(Preset::Thesis);
    let (x, u) = hover();
    let (b, p) = delta(&m, &x, &u, |s| s[ix::P] = 0.2);
    assert!(p[ix::B1] < b[ix::B1]);
    let (b, p) = delta(&m, &x, &u, |s| s[ix::Q] = 0.2);
    assert!(p[ix::A1] < b[ix::A1]);
}

#[test]
fn table_10_1_hover_body_rates_secondary_response_needs_e_0_ks_0() {
    // MODEL.md §14: "p: a1 decreases", "q: b1 increases" hold in the 90°-lag
    // setting the thesis verified with (§10.2: e = 0; and Ks = 0). With the
    // nominal e = 0.08, Ks = 200 the hinge offset's phase shift reverses them.
    let mut params = Params::bergen_twin();
    params.main_rotor.hinge_offset_m = 0.0;
    params.main_rotor.spring_n_m_per_rad = 0.0;
    let m = Model::new(params, Preset::Thesis.options());
    let (x, u) = hover();
    let (b, p) = delta(&m, &x, &u, |s| s[ix::P] = 0.2);
    assert!(p[ix::A1] < b[ix::A1], "p → a1↓ with e = Ks = 0");
    let (b, p) = delta(&m, &x, &u, |s| s[ix::Q] = 0.2);
    assert!(p[ix::B1] > b[ix::B1], "q → b1↑ with e = Ks = 0");

    // and with the nominal parameters they indeed reverse (documented, not hidden)
    let m = model(Preset::Thesis);
    let (b, p) = delta(&m, &x, &u, |s| s[ix::P] = 0.2);
    assert!(p[ix::A1] > b[ix::A1]);
}

#[test]
fn table_10_1_forward_flight() {
    let m = model(Preset::Thesis);
    let (mut x, u) = hover();
    x[ix::U] = 5.0;
    let (b, p) = delta(&m, &x, &u, |s| s[ix::U] += 1.0);
    assert!(p[ix::A1] > b[ix::A1], "u↑ → a1↑ (blow-back)");
    let (b, p) = delta(&m, &x, &u, |s| s[ix::V] += 1.0);
    assert!(p[ix::B1] < b[ix::B1], "v↑ → b1↓ (dihedral)");
    let (b, p) = delta(&m, &x, &u, |s| s[ix::THETA0] += 0.01);
    assert!(
        p[ix::A0] > b[ix::A0] && p[ix::A1] > b[ix::A1],
        "θ0↑ → a0↑, a1↑"
    );

    let (xh, _) = hover();
    let (bh, ph) = delta(&m, &xh, &u, |s| s[ix::A1_SWASH] += 0.01);
    let (bf, pf) = delta(&m, &x, &u, |s| s[ix::A1_SWASH] += 0.01);
    let (dh, df) = (ph[ix::B1] - bh[ix::B1], pf[ix::B1] - bf[ix::B1]);
    assert!(df < 0.0);
    // "b1 decrease (equal to hover)": within 5 % (μ² effects at μ = 0.05 are ~0.4 %)
    assert!(
        (df - dh).abs() < 0.05 * dh.abs(),
        "A1: hover {dh}, forward {df}"
    );

    let (bh, ph) = delta(&m, &xh, &u, |s| s[ix::B1_SWASH] += 0.01);
    let (bf, pf) = delta(&m, &x, &u, |s| s[ix::B1_SWASH] += 0.01);
    let (dh, df) = (ph[ix::A1] - bh[ix::A1], pf[ix::A1] - bf[ix::A1]);
    assert!(
        df < dh && dh < 0.0,
        "B1: a1 decreases further than in hover: {dh} vs {df}"
    );
}

#[test]
fn table_10_2_main_and_tail_rotor() {
    let m = model(Preset::Thesis);
    let (x, u) = hover();
    let w0 = Vector3::zeros();
    let aux = |s: &State| m.derivative(s, &u, &w0).unwrap().1;
    let a = aux(&x);
    let mut s = x;
    s[ix::A1] += 0.01;
    let b = aux(&s);
    assert!(b.force_mr_hub_n.x < a.force_mr_hub_n.x && b.torque_mr_hub_nm.y > a.torque_mr_hub_nm.y);
    let mut s = x;
    s[ix::B1] += 0.01;
    let b = aux(&s);
    assert!(b.force_mr_hub_n.y > a.force_mr_hub_n.y && b.torque_mr_hub_nm.x > a.torque_mr_hub_nm.x);
    let mut s = x;
    s[ix::W] += 0.5;
    let b = aux(&s);
    assert!(a.lambda_mr < 0.0, "hover inflow is negative");
    assert!(b.lambda_mr > a.lambda_mr && b.force_mr_hub_n.z < a.force_mr_hub_n.z);
    let mut s = x;
    s[ix::THETA0] += 0.01;
    let b = aux(&s);
    assert!(
        a.torque_mr_hub_nm.z < 0.0,
        "hτz is negative in hover (§10.2.3)"
    );
    assert!(b.force_mr_hub_n.z < a.force_mr_hub_n.z && b.torque_mr_hub_nm.z < a.torque_mr_hub_nm.z);
    // tail rotor
    let mut s = x;
    s[ix::V] += 0.5;
    let b = aux(&s);
    assert!(b.lambda_tr > a.lambda_tr && b.force_tr_y_n < a.force_tr_y_n);
    let mut s = x;
    s[ix::THETA_TR] += 0.01;
    let b = aux(&s);
    assert!(b.force_tr_y_n < a.force_tr_y_n && b.torque_tr_body_nm.y < a.torque_tr_body_nm.y);
    // hover values quoted by the thesis/MODEL.md: hτz ≈ −7.85 N·m, tFy ≈ −7.85 N
    assert!(
        (a.torque_mr_hub_nm.z + 7.85).abs() < 0.05,
        "{}",
        a.torque_mr_hub_nm.z
    );
    assert!((a.force_tr_y_n + 7.85).abs() < 0.05, "{}", a.force_tr_y_n);
}

#[test]
fn table_10_3_rigid_body_kinematics() {
    use helicon_model::frames::{euler_rates, ned_from_body};
    use helicon_model::rigid_body::{angular_accel, linear_accel};
    // Positive pitch attitude and the thesis roll, as the table's discussion assumes.
    let (phi, theta) = (0.0573, 0.05);
    let r = ned_from_body(phi, theta, 0.0);
    let i = Vector3::new(0.199, 0.62, 0.6);
    let z = Vector3::zeros();
    // Fx → u̇ > 0 and, once u > 0, ż_e < 0
    assert!(linear_accel(&Vector3::new(1.0, 0.0, 0.0), 14.0, &z, &z).x > 0.0);
    assert!((r * Vector3::new(1.0, 0.0, 0.0)).z < 0.0);
    // Fy → v > 0, ż_e > 0
    assert!((r * Vector3::new(0.0, 1.0, 0.0)).z > 0.0);
    // Fz → w > 0, ẋ_e > 0, ẏ_e < 0
    let e = r * Vector3::new(0.0, 0.0, 1.0);
    assert!(e.x > 0.0 && e.y < 0.0);
    // τx → ṗ > 0; a roll rate changes only φ̇ (zeros of P_eb at (2,1), (3,1))
    assert!(angular_accel(&Vector3::new(1.0, 0.0, 0.0), &i, &z).x > 0.0);
    let d = euler_rates(phi, theta, &Vector3::new(1.0, 0.0, 0.0));
    assert!(d.x > 0.0 && d.y == 0.0 && d.z == 0.0);
    // τy → q > 0 → θ̇ > 0 and φ̇, ψ̇ affected
    let d = euler_rates(phi, theta, &Vector3::new(0.0, 1.0, 0.0));
    assert!(d.y > 0.0 && d.x != 0.0 && d.z != 0.0);
    // τz → r > 0 → ψ̇ > 0 and φ̇, θ̇ affected
    let d = euler_rates(phi, theta, &Vector3::new(0.0, 0.0, 1.0));
    assert!(d.z > 0.0 && d.x != 0.0 && d.y != 0.0);
}

#[test]
fn torque_free_rigid_body_conserves_momentum_and_energy() {
    use helicon_model::frames::{euler_rates, ned_from_body};
    use helicon_model::rigid_body::angular_accel;
    let inertia = Vector3::new(0.199, 0.62, 0.6);
    // state: [φ, θ, ψ, p, q, r] in the first six slots
    let f = |s: &State| -> Result<State, ()> {
        let w = Vector3::new(s[3], s[4], s[5]);
        let e = euler_rates(s[0], s[1], &w);
        let wd = angular_accel(&Vector3::zeros(), &inertia, &w);
        let mut d = State::zeros();
        for k in 0..3 {
            d[k] = e[k];
            d[3 + k] = wd[k];
        }
        Ok(d)
    };
    let h_ned = |s: &State| {
        ned_from_body(s[0], s[1], s[2]) * inertia.component_mul(&Vector3::new(s[3], s[4], s[5]))
    };
    let energy = |s: &State| {
        let w = Vector3::new(s[3], s[4], s[5]);
        0.5 * w.dot(&inertia.component_mul(&w))
    };
    let mut s = State::zeros();
    // spin mostly about the (stable) major axis with small wobble: θ stays far from ±π/2
    s[3] = 0.05;
    s[4] = 0.08;
    s[5] = 1.0;
    let (h0, e0) = (h_ned(&s), energy(&s));
    for _ in 0..10_000 {
        s = rk4(&s, 1e-3, f).unwrap();
    }
    // RK4 at dt·|ω| = 1e-3 over 10 s: local error ~(dt ω)⁵ → drift ≲ 1e-10
    assert!(
        (h_ned(&s) - h0).norm() < 1e-9 * h0.norm(),
        "{:?} vs {:?}",
        h_ned(&s),
        h0
    );
    assert!((energy(&s) - e0).abs() < 1e-9 * e0);
}

#[test]
fn rk4_global_error_drops_16x_when_the_step_halves_on_the_model() {
    // Smooth case: thesis preset from the hover trim with a small collective
    // offset (no saturation, no rate limit), 0.2 s. Reference at dt/16.
    let m = model(Preset::Thesis);
    let (x0, mut u) = hover();
    u[0] += 0.002;
    let run = |dt: f64| {
        let mut x = x0;
        let n = (0.2 / dt).round() as usize;
        for _ in 0..n {
            x = m.step(&x, &u, &Vector3::zeros(), dt).unwrap().0;
        }
        x
    };
    let reference = run(1.0 / 12800.0);
    let e1 = (run(1.0 / 800.0) - reference).norm();
    let e2 = (run(1.0 / 1600.0) - reference).norm();
    let ratio = e1 / e2;
    assert!(
        (13.0..19.0).contains(&ratio),
        "ratio {ratio} ({e1:e}, {e2:e})"
    );
}

#[test]
fn derivative_never_nan_over_random_states_and_inflow_converges() {
    // Issue 2: 100 000 random states (|u|,|v| ≤ 15 m/s, |w| ≤ 5 m/s, full
    // collective and tail ranges, both rotors): always converged, |g| < 1e-12.
    use rand_like::Lcg;
    let p = Params::bergen_twin();
    for preset in [Preset::Physical, Preset::Thesis] {
        let m = Model::new(p, preset.options());
        let mut rng = Lcg(0x1234_5678 + preset as u64);
        for _ in 0..50_000 {
            let mut x = State::zeros();
            x[ix::PHI] = rng.range(-0.5, 0.5);
            x[ix::THETA] = rng.range(-0.5, 0.5);
            x[ix::PSI] = rng.range(-3.0, 3.0);
            x[ix::U] = rng.range(-15.0, 15.0);
            x[ix::V] = rng.range(-15.0, 15.0);
            x[ix::W] = rng.range(-5.0, 5.0);
            for i in [ix::P, ix::Q, ix::R] {
                x[i] = rng.range(-2.0, 2.0);
            }
            for i in [ix::A0, ix::A1, ix::B1, ix::A1SB, ix::B1SB] {
                x[i] = rng.range(-0.1, 0.1);
            }
            for i in [
                ix::A0_DOT,
                ix::A1_DOT,
                ix::B1_DOT,
                ix::A1SB_DOT,
                ix::B1SB_DOT,
            ] {
                x[i] = rng.range(-2.0, 2.0);
            }
            let s = &p.servos;
            x[ix::THETA0] = s[0].gain_rad * rng.range(s[0].s_min, s[0].s_max);
            x[ix::A1_SWASH] = s[1].gain_rad * rng.range(s[1].s_min, s[1].s_max);
            x[ix::B1_SWASH] = s[2].gain_rad * rng.range(s[2].s_min, s[2].s_max);
            x[ix::THETA_TR] = s[3].gain_rad * rng.range(s[3].s_min, s[3].s_max);
            let u = Input::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            let wind = Vector3::new(
                rng.range(-5.0, 5.0),
                rng.range(-5.0, 5.0),
                rng.range(-2.0, 2.0),
            );
            let (xd, aux) = m.derivative(&x, &u, &wind).unwrap();
            assert!(xd.iter().all(|v| v.is_finite()), "{x:?}");
            assert!(
                aux.inflow_residual[0] < 1e-12 && aux.inflow_residual[1] < 1e-12,
                "{aux:?}"
            );
        }
    }
}

mod rand_like {
    /// A tiny deterministic generator (64-bit LCG, Knuth MMIX constants):
    /// enough to spread test states; not for statistics.
    pub struct Lcg(pub u64);
    impl Lcg {
        pub fn next_f64(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.next_f64()
        }
    }
}

#[test]
fn flapping_quadrature_matches_closed_forms_at_random_states() {
    // MODEL.md §6.3/§6.4: the closed-form D, K, J, E, G (K1 = θt = 0) against
    // the model's exact-quadrature harmonic balance, at random states and both
    // stabilizer-bar scalings, with and without body-acceleration torques.
    // Exact quadrature vs closed form: agreement to round-off (1e-12 relative
    // to the largest term, ~Ω²·a ≈ 1e2–1e4 rad/s²).
    use helicon_model::flapping::{
        FlapBody, MainRotorCoefficients, MainRotorConsts, StabilizerBarCoefficients,
    };
    use rand_like::Lcg;
    let p = Params::bergen_twin();
    let mr = p.main_rotor;
    let sb = p.stabilizer_bar;
    let rho = p.environment.rho_kg_m3;
    let mut rng = Lcg(42);
    for preset in [Preset::Thesis, Preset::Physical] {
        let m = Model::new(p, preset.options());
        for _ in 0..200 {
            let mut x = State::zeros();
            x[ix::THETA] = rng.range(-0.3, 0.3);
            x[ix::PHI] = rng.range(-0.3, 0.3);
            x[ix::U] = rng.range(-15.0, 15.0);
            x[ix::V] = rng.range(-15.0, 15.0);
            x[ix::W] = rng.range(-5.0, 5.0);
            for i in [
                ix::P,
                ix::Q,
                ix::R,
                ix::A0_DOT,
                ix::A1_DOT,
                ix::B1_DOT,
                ix::A1SB_DOT,
                ix::B1SB_DOT,
            ] {
                x[i] = rng.range(-1.0, 1.0);
            }
            for i in [
                ix::A0,
                ix::A1,
                ix::B1,
                ix::A1SB,
                ix::B1SB,
                ix::A1_SWASH,
                ix::B1_SWASH,
            ] {
                x[i] = rng.range(-0.05, 0.05);
            }
            x[ix::THETA0] = rng.range(0.0, 0.2);
            x[ix::THETA_TR] = rng.range(0.0, 0.2);
            let u = Input::zeros();
            let (xd, aux) = m.derivative(&x, &u, &Vector3::zeros()).unwrap();
            let mu = aux.mu_mr;
            let body = if preset == Preset::Physical {
                let (pr, qr, rr) = (x[ix::P], x[ix::Q], x[ix::R]);
                let g = p.geometry;
                let hx = x[ix::U] - qr * g.kappa_v_m;
                let hy = x[ix::V] + pr * g.kappa_v_m - rr * g.kappa_h_m;
                FlapBody {
                    p_rad_s: pr,
                    q_rad_s: qr,
                    p_dot_rad_s2: xd[ix::P],
                    q_dot_rad_s2: xd[ix::Q],
                    normal_accel_m_s2: xd[ix::W] + xd[ix::Q] * g.kappa_h_m - hx * qr + hy * pr,
                }
            } else {
                // thesis preset: (6.40) without hz̈, its velocity products kept
                let (pr, qr, rr) = (x[ix::P], x[ix::Q], x[ix::R]);
                let g = p.geometry;
                let hx = x[ix::U] - qr * g.kappa_v_m;
                let hy = x[ix::V] + pr * g.kappa_v_m - rr * g.kappa_h_m;
                FlapBody {
                    p_rad_s: pr,
                    q_rad_s: qr,
                    p_dot_rad_s2: 0.0,
                    q_dot_rad_s2: 0.0,
                    normal_accel_m_s2: -hx * qr + hy * pr,
                }
            };
            let consts = MainRotorConsts {
                omega: mr.omega_rad_s,
                radius: mr.radius_m,
                e: mr.hinge_offset_m,
                ib: mr.blade_inertia_kg_m2,
                mb: mr.blade_mass_moment_kg_m,
                ks: mr.spring_n_m_per_rad,
                a_cal: rho * mr.lift_slope_per_rad * mr.chord_m / (2.0 * mr.blade_inertia_kg_m2),
            };
            let c = MainRotorCoefficients::new(&consts, mu.x, mu.y, &body);
            let a = Vector3::new(x[ix::A0], x[ix::A1], x[ix::B1]);
            let ad = Vector3::new(x[ix::A0_DOT], x[ix::A1_DOT], x[ix::B1_DOT]);
            let ups = Vector3::new(
                x[ix::THETA0],
                mr.bell_factor * x[ix::A1_SWASH] - mr.hiller_factor * x[ix::B1SB],
                mr.bell_factor * x[ix::B1_SWASH] - mr.hiller_factor * x[ix::A1SB],
            );
            let closed = c.accel(&a, &ad, &ups, aux.lambda_mr_flap);
            let scale = (c.k * a).norm().max((c.j * ups).norm()).max(1.0);
            for k in 0..3 {
                let ours = xd[ix::A0_DOT + k];
                assert!(
                    (ours - closed[k]).abs() < 1e-12 * scale,
                    "main {k}: {ours} vs {}",
                    closed[k]
                );
            }
            let r_scale = if preset == Preset::Thesis {
                sb.outer_radius_m
            } else {
                mr.radius_m
            };
            let a_sb = rho * sb.lift_slope_per_rad * sb.chord_m / (2.0 * sb.paddle_inertia_kg_m2);
            let cs = StabilizerBarCoefficients::new(
                mr.omega_rad_s,
                a_sb,
                sb.inner_radius_m,
                sb.outer_radius_m,
                r_scale,
                mu.x,
                mu.y,
                &body,
            );
            let asb = nalgebra::Vector2::new(x[ix::A1SB], x[ix::B1SB]);
            let asbd = nalgebra::Vector2::new(x[ix::A1SB_DOT], x[ix::B1SB_DOT]);
            let usb = nalgebra::Vector2::new(x[ix::A1_SWASH], x[ix::B1_SWASH]);
            let closed = cs.accel(&asb, &asbd, &usb, aux.lambda_mr_flap);
            let scale = (cs.k * asb).norm().max((cs.j * usb).norm()).max(1.0);
            for k in 0..2 {
                let ours = xd[ix::A1SB_DOT + k];
                assert!(
                    (ours - closed[k]).abs() < 1e-12 * scale,
                    "sb {k}: {ours} vs {}",
                    closed[k]
                );
            }
        }
    }
}

#[test]
fn closed_forms_reproduce_model_md_hover_numbers() {
    // MODEL.md §6.3 hover values (all matching Appendix E).
    use helicon_model::flapping::{FlapBody, MainRotorCoefficients, MainRotorConsts};
    let p = Params::bergen_twin();
    let mr = p.main_rotor;
    let consts = MainRotorConsts {
        omega: mr.omega_rad_s,
        radius: mr.radius_m,
        e: mr.hinge_offset_m,
        ib: mr.blade_inertia_kg_m2,
        mb: mr.blade_mass_moment_kg_m,
        ks: mr.spring_n_m_per_rad,
        a_cal: p.environment.rho_kg_m3 * mr.lift_slope_per_rad * mr.chord_m
            / (2.0 * mr.blade_inertia_kg_m2),
    };
    let body = FlapBody {
        p_rad_s: 0.0,
        q_rad_s: 0.0,
        p_dot_rad_s2: 0.0,
        q_dot_rad_s2: 0.0,
        normal_accel_m_s2: 0.0,
    };
    let c = MainRotorCoefficients::new(&consts, 0.0, 0.0, &body);
    let close = |a: f64, b: f64| (a - b).abs() < 5e-4 * b.abs().max(1.0);
    assert!(close(c.d[(0, 0)], 20.626) && close(c.d[(1, 2)], -200.0));
    assert!(
        close(c.k[(0, 0)], 10746.7) && close(c.k[(1, 1)], 746.67) && close(c.k[(1, 2)], -2062.6)
    );
    assert!(close(c.j[(0, 0)], 2304.8) && close(c.j[(2, 2)], -2304.8));
    assert!(close(c.e[0], 3028.1));
}
