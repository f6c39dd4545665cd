//! The ground blocks: landing gear (rest, force balance, drop, friction on
//! slopes), drivetrain (spool-up, governed speed), ground effect (against
//! the Cheeseman–Bennett closed form), and the blocks off leaving the
//! thesis's model bit for bit.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_model::drivetrain::{DriveCommand, RotorState, Spool, governed_state};
use helicon_model::landing_gear::{Anchors, rest_height_m, resting_state, static_compression_m};
use helicon_model::state::ix;
use helicon_model::trim::{TrimError, TrimOptions, TrimTarget, trim};
use helicon_model::{InflowMode, Input, Model, Params, PlantState, Preset, State};
use nalgebra::Vector3;

const DT: f64 = 0.0025;

/// The parameters with the fuselage drag off: the closed forms of a body
/// sliding or falling in vacuum.
fn without_drag(mut p: Params) -> Params {
    let f = &mut p.fuselage;
    for d in [
        &mut f.drag_x,
        &mut f.drag_y,
        &mut f.drag_z,
        &mut f.drag_fp,
        &mut f.drag_tf,
        &mut f.drag_tp,
    ] {
        *d = 0.0;
    }
    p
}

fn gear_params(slope_rad: f64, drivetrain: bool) -> Params {
    let mut p = Params::bergen_twin();
    p.landing_gear.enabled = 1.0;
    p.landing_gear.ground_slope_rad = slope_rad;
    p.landing_gear.ground_down_m = 0.0;
    p.drivetrain.enabled = f64::from(u8::from(drivetrain));
    p.validate("test").unwrap();
    p
}

fn resting(model: &Model, omega_rad_s: f64) -> PlantState {
    let p = model.params();
    let x = resting_state(
        &p.landing_gear,
        p.body.mass_kg,
        p.environment.g_m_s2,
        &State::zeros(),
    );
    PlantState {
        x,
        rotor: RotorState {
            omega_rad_s,
            governor_integral: 0.0,
        },
        anchors: Anchors::default(),
    }
}

fn stopped() -> DriveCommand {
    DriveCommand {
        engine_on: false,
        omega_ref_rad_s: 0.0,
    }
}

fn pos(x: &State) -> Vector3<f64> {
    Vector3::new(x[ix::X], x[ix::Y], x[ix::Z])
}

/// Fly `seconds` with `u` held; returns the aux of the last step.
fn run(
    model: &Model,
    s: &mut PlantState,
    u: &Input,
    drive: &DriveCommand,
    seconds: f64,
    mut each: impl FnMut(f64, &PlantState, &helicon_model::Aux),
) -> helicon_model::Aux {
    let n = (seconds / DT).round() as usize;
    let mut aux = helicon_model::Aux::default();
    for k in 0..n {
        aux = model
            .plant_step(s, u, &Vector3::zeros(), drive, DT)
            .unwrap();
        each(k as f64 * DT, s, &aux);
    }
    aux
}

#[test]
fn rests_level_at_the_static_compression_without_creeping_rotor_stopped() {
    let model = Model::new(gear_params(0.0, true), Preset::Physical.options());
    let p = *model.params();
    let mut s = resting(&model, 0.0);
    let x0 = s.x;
    let mut max_att: f64 = 0.0;
    run(
        &model,
        &mut s,
        &Input::zeros(),
        &stopped(),
        60.0,
        |_, s, _| {
            max_att = max_att.max(s.x[ix::PHI].abs()).max(s.x[ix::THETA].abs());
        },
    );
    let drift = (pos(&s.x) - pos(&x0)).xy().norm();
    let height = -s.x[ix::Z];
    let want = rest_height_m(&p.landing_gear, p.body.mass_kg, p.environment.g_m_s2);
    let delta = static_compression_m(&p.landing_gear, p.body.mass_kg, p.environment.g_m_s2);
    let delta_got = p.landing_gear.contact_z_m - height;
    eprintln!(
        "rotor stopped, 60 s: drift {drift:.3e} m, |attitude| max {max_att:.3e} rad, yaw {:.3e}, \
         height {height:.6} m (want {want:.6}), compression {delta_got:.6e} m (m g/4k = {delta:.6e})",
        s.x[ix::PSI]
    );
    assert!(drift < 1e-3, "drift {drift}");
    assert!(max_att < 0.01 && s.x[ix::PSI].abs() < 0.01, "{max_att}");
    assert!(
        ((delta_got - delta) / delta).abs() < 0.01,
        "{delta_got} vs {delta}"
    );
    assert!(((height - want) / want).abs() < 0.01);
}

#[test]
fn rests_without_creeping_with_the_rotor_turning_at_flat_pitch() {
    // constant Ω (drivetrain off): the main rotor's drag torque (≈ 2 N·m)
    // is held by the skids' friction
    let model = Model::new(gear_params(0.0, false), Preset::Physical.options());
    let mut s = resting(&model, 100.0);
    let mut max_att: f64 = 0.0;
    run(
        &model,
        &mut s,
        &Input::zeros(),
        &stopped(),
        1.0,
        |_, _, _| {},
    );
    let x1 = s.x;
    let aux = run(
        &model,
        &mut s,
        &Input::zeros(),
        &stopped(),
        59.0,
        |_, s, _| {
            max_att = max_att.max(s.x[ix::PHI].abs()).max(s.x[ix::THETA].abs());
        },
    );
    let drift = (pos(&s.x) - pos(&x1)).xy().norm();
    let yaw = s.x[ix::PSI] - x1[ix::PSI];
    eprintln!(
        "flat pitch at 100 rad/s, 1..60 s: drift {drift:.3e} m, yaw {yaw:.3e} rad, |att| {max_att:.3e}, \
         rotor torque {:.3} N·m",
        aux.torque_mr_hub_nm.z
    );
    assert!(
        aux.torque_mr_hub_nm.z.abs() > 1.0,
        "the test needs a rotor torque"
    );
    assert!(drift < 1e-3, "{drift}");
    assert!(yaw.abs() < 1e-3, "{yaw}");
    assert!(max_att < 0.01);
}

#[test]
fn normal_forces_carry_the_weight_at_rest() {
    let model = Model::new(gear_params(0.0, true), Preset::Physical.options());
    let p = *model.params();
    let mut s = resting(&model, 0.0);
    let aux = run(
        &model,
        &mut s,
        &Input::zeros(),
        &stopped(),
        5.0,
        |_, _, _| {},
    );
    let w = p.body.mass_kg * p.environment.g_m_s2;
    let n = aux.contact.total_normal_n();
    eprintln!(
        "sum of normal forces {n:.4} N, m g = {w:.4} N, per point {:?}",
        aux.contact.normal_n
    );
    assert!(((n - w) / w).abs() < 1e-3, "{n} vs {w}");
    for ni in aux.contact.normal_n {
        assert!((ni - w / 4.0).abs() / (w / 4.0) < 0.01, "{ni}");
    }
}

/// Rigid-body energy plus the gear springs' (J): ½ m v² + ½ ωᵀ I ω + m g h + ½ k Σ δ².
fn energy(model: &Model, s: &PlantState) -> f64 {
    let p = model.params();
    let x = &s.x;
    let v2 = x[ix::U].powi(2) + x[ix::V].powi(2) + x[ix::W].powi(2);
    let rot = p.body.ixx_kg_m2 * x[ix::P].powi(2)
        + p.body.iyy_kg_m2 * x[ix::Q].powi(2)
        + p.body.izz_kg_m2 * x[ix::R].powi(2);
    let pe = -p.body.mass_kg * p.environment.g_m_s2 * x[ix::Z];
    let plane = model.ground_plane();
    let r = helicon_model::frames::ned_from_body(x[ix::PHI], x[ix::THETA], x[ix::PSI]);
    let spring: f64 = model
        .contact_points_body_m()
        .iter()
        .map(|rb| {
            let d = (-plane.height_m(&(pos(x) + r * rb))).max(0.0);
            0.5 * p.landing_gear.stiffness_n_m * d * d
        })
        .sum();
    0.5 * p.body.mass_kg * v2 + 0.5 * rot + pe + spring
}

#[test]
fn a_drop_from_half_a_metre_settles_without_bouncing_away_or_gaining_energy() {
    // no air drag: all the energy lost is the gear's
    let model = Model::new(
        without_drag(gear_params(0.0, true)),
        Preset::Physical.options(),
    );
    let mut s = resting(&model, 0.0);
    let rest_z = s.x[ix::Z];
    s.x[ix::Z] -= 0.5;
    let e0 = energy(&model, &s);
    let mut touched = false;
    let mut max_rise_after_touch = f64::NEG_INFINITY;
    let mut min_z_after: f64 = f64::INFINITY;
    let mut e_max_rise: f64 = 0.0;
    let mut e_prev = e0;
    let mut touchdown_speed = 0.0;
    let mut w_prev = 0.0;
    run(
        &model,
        &mut s,
        &Input::zeros(),
        &stopped(),
        5.0,
        |_, s, aux| {
            let e = energy(&model, s);
            e_max_rise = e_max_rise.max(e - e_prev);
            e_prev = e;
            // `aux` is at the start of the step: the speed at the last sample
            // before the skids touch
            if aux.contact.on_ground() && !touched {
                touched = true;
                touchdown_speed = w_prev;
            }
            w_prev = s.x[ix::W];
            if touched {
                max_rise_after_touch = max_rise_after_touch.max(rest_z - s.x[ix::Z]);
                min_z_after = min_z_after.min(-s.x[ix::Z]);
            }
        },
    );
    let settled = (s.x[ix::Z] - rest_z).abs();
    let v = (s.x[ix::U].powi(2) + s.x[ix::V].powi(2) + s.x[ix::W].powi(2)).sqrt();
    let e_end = energy(&model, &s);
    eprintln!(
        "drop 0.5 m: touchdown {touchdown_speed:.3} m/s, highest rebound above rest {max_rise_after_touch:.4e} m, \
         end offset {settled:.2e} m, speed {v:.2e} m/s, energy {e0:.3} -> {e_end:.3} J, \
         largest step rise {e_max_rise:.3e} J"
    );
    assert!(touched);
    // v = √(2 g h) at touchdown (the skids fall 0.5 m less the static
    // compression)
    let p = model.params();
    let fall = 0.5 - static_compression_m(&p.landing_gear, p.body.mass_kg, p.environment.g_m_s2);
    let v_free = (2.0 * p.environment.g_m_s2 * fall).sqrt();
    assert!(
        (touchdown_speed - v_free).abs() < 0.05 * v_free,
        "{touchdown_speed} vs {v_free}"
    );
    assert!(
        max_rise_after_touch < 0.05,
        "bounced {max_rise_after_touch} m"
    );
    assert!(settled < 1e-4 && v < 1e-3);
    // the gear dissipates: the energy never rises by more than round-off
    assert!(
        e_max_rise < 1e-6 * e0.abs(),
        "energy rose by {e_max_rise} J"
    );
    assert!(e_end < e0);
}

/// Displacement along the ground over `seconds` after settling 1 s on a
/// slope of `slope_deg`; also the last second's acceleration.
fn slope_run(slope_deg: f64, seconds: f64) -> (f64, f64) {
    let model = Model::new(
        without_drag(gear_params(slope_deg.to_radians(), true)),
        Preset::Physical.options(),
    );
    let mut s = resting(&model, 0.0);
    run(
        &model,
        &mut s,
        &Input::zeros(),
        &stopped(),
        1.0,
        |_, _, _| {},
    );
    let x1 = pos(&s.x);
    let mut speeds = Vec::new();
    run(
        &model,
        &mut s,
        &Input::zeros(),
        &stopped(),
        seconds,
        |_, s, _| {
            let r =
                helicon_model::frames::ned_from_body(s.x[ix::PHI], s.x[ix::THETA], s.x[ix::PSI]);
            speeds.push((r * Vector3::new(s.x[ix::U], s.x[ix::V], s.x[ix::W])).norm());
        },
    );
    let n = speeds.len();
    let per_s = (1.0 / DT) as usize;
    let accel = (speeds[n - 1] - speeds[n - 1 - per_s]) / 1.0;
    ((pos(&s.x) - x1).norm(), accel)
}

#[test]
fn friction_holds_on_5_degrees_and_slides_on_30() {
    let (d5, _) = slope_run(5.0, 59.0);
    let (d30, a30) = slope_run(30.0, 2.0);
    let p = Params::bergen_twin().landing_gear;
    let g = 9.82;
    let t = 30f64.to_radians();
    let want = g * (t.sin() - p.friction_dynamic * t.cos());
    eprintln!(
        "5 deg: moved {d5:.3e} m in 59 s; 30 deg: moved {d30:.3} m in 2 s, acceleration {a30:.4} m/s² \
         (g (sin − μd cos) = {want:.4})"
    );
    assert!(d5 < 1e-3, "crept {d5} m on 5 deg");
    assert!(d30 > 1.0, "held on 30 deg: {d30}");
    assert!((a30 - want).abs() / want < 0.02, "{a30} vs {want}");
}

#[test]
fn spool_up_reaches_the_governed_speed_and_holds_it() {
    let model = Model::new(gear_params(0.0, true), Preset::Physical.options());
    let p = *model.params();
    let mut s = resting(&model, 0.0);
    let mut spool = Spool::stopped(&p);
    spool.start(0.0);
    let omega_gov = p.main_rotor.omega_rad_s;
    let mut t99 = None;
    let mut moved: f64 = 0.0;
    let x0 = pos(&s.x);
    let n = (12.0 / DT) as usize;
    let mut max_omega: f64 = 0.0;
    for k in 0..n {
        model
            .plant_step(
                &mut s,
                &Input::zeros(),
                &Vector3::zeros(),
                &spool.command,
                DT,
            )
            .unwrap();
        spool.step(DT);
        let w = s.rotor.omega_rad_s;
        max_omega = max_omega.max(w);
        if t99.is_none() && w >= 0.99 * omega_gov {
            t99 = Some((k + 1) as f64 * DT);
        }
        moved = moved.max((pos(&s.x) - x0).norm());
    }
    let t99 = t99.unwrap();
    let err = s.rotor.omega_rad_s - omega_gov;
    eprintln!(
        "spool-up: 99 % of {omega_gov} rad/s at {t99:.3} s (ramp {} s), overshoot {:.3} rad/s, \
         error after 12 s {err:.2e} rad/s, moved {moved:.2e} m, yaw {:.2e} rad",
        p.drivetrain.spool_up_s,
        max_omega - omega_gov,
        s.x[ix::PSI]
    );
    assert!(t99 > 0.98 * p.drivetrain.spool_up_s && t99 < p.drivetrain.spool_up_s + 0.5);
    assert!(max_omega - omega_gov < 0.01 * omega_gov);
    assert!(err.abs() < 1e-3 * omega_gov);
    assert!(moved < 1e-3 && s.x[ix::PSI].abs() < 0.01);
    // shut-down: the rotor winds down, never backwards
    spool.stop();
    let mut prev = s.rotor.omega_rad_s;
    for _ in 0..(20.0 / DT) as usize {
        model
            .plant_step(
                &mut s,
                &Input::zeros(),
                &Vector3::zeros(),
                &spool.command,
                DT,
            )
            .unwrap();
        assert!(s.rotor.omega_rad_s <= prev + 1e-12 && s.rotor.omega_rad_s >= 0.0);
        prev = s.rotor.omega_rad_s;
    }
    eprintln!("20 s after shut-down: {prev:.2} rad/s");
    assert!(prev < 0.5 * omega_gov);
}

#[test]
fn governor_holds_the_speed_at_the_hover_trim_in_the_air() {
    let mut p = Params::bergen_twin();
    p.drivetrain.enabled = 1.0;
    let model = Model::new(p, Preset::Physical.options());
    let t = trim(&model, &TrimTarget::hover(), &TrimOptions::default()).unwrap();
    let x = helicon_model::state::expand(&t.x, [0.0; 3]);
    let rotor = governed_state(&p, t.aux.rotor_load_n_m);
    let mut s = PlantState {
        x,
        rotor,
        anchors: Anchors::default(),
    };
    let cmd = Spool::governed(&p).command;
    // a collective step of +0.02 (the load rises): the governor recovers the speed
    let mut u = t.u;
    u[0] += 0.02;
    let mut worst: f64 = 0.0;
    for _ in 0..(5.0 / DT) as usize {
        model
            .plant_step(&mut s, &u, &Vector3::zeros(), &cmd, DT)
            .unwrap();
        worst = worst.max((s.rotor.omega_rad_s - 100.0).abs());
    }
    let err = s.rotor.omega_rad_s - 100.0;
    eprintln!(
        "hover load {:.3} N·m; collective +0.02: largest droop {worst:.3} rad/s, error after 5 s {err:.2e} rad/s",
        t.aux.rotor_load_n_m
    );
    assert!(
        t.aux.rotor_load_n_m > 0.0,
        "the rotors load the shaft in hover"
    );
    assert!(worst < 2.0 && err.abs() < 1e-2, "{worst} {err}");
}

#[test]
fn disabled_blocks_leave_the_model_bit_identical() {
    let (x, u, _, _) = common::six_digit_hover_trim();
    let mut x = x;
    x[ix::U] = 1.3;
    x[ix::Q] = 0.2;
    let wind = Vector3::new(1.0, -2.0, 0.3);
    for preset in [Preset::Physical, Preset::Thesis] {
        let base = Model::bergen_twin(preset);
        let (d0, _) = base.derivative(&x, &u, &wind).unwrap();
        let plant = PlantState {
            x,
            rotor: RotorState {
                omega_rad_s: 37.0,
                governor_integral: 0.0,
            },
            anchors: Anchors::default(),
        };
        let (d1, r1, _) = base
            .plant_derivative(&plant, &u, &wind, InflowMode::Converged, &stopped())
            .unwrap();
        for i in 0..x.len() {
            assert_eq!(d0[i].to_bits(), d1[i].to_bits(), "state {i}");
        }
        assert_eq!((r1.omega_rad_s, r1.governor_integral), (0.0, 0.0));
        // the drivetrain on at the governed speed gives the same forces; the
        // only change is the rotor's acceleration reaction on yaw
        let mut p = Params::bergen_twin();
        p.drivetrain.enabled = 1.0;
        let on = Model::new(p, preset.options());
        let plant = PlantState {
            rotor: RotorState {
                omega_rad_s: 100.0,
                governor_integral: 0.5,
            },
            ..plant
        };
        let (d2, r2, _) = on
            .plant_derivative(
                &plant,
                &u,
                &wind,
                InflowMode::Converged,
                &Spool::governed(&p).command,
            )
            .unwrap();
        assert!(r2.omega_rad_s != 0.0);
        for i in 0..x.len() {
            if i != ix::R && i != ix::PSI {
                assert_eq!(d0[i].to_bits(), d2[i].to_bits(), "state {i}");
            }
        }
        let dr = d2[ix::R] - d0[ix::R];
        let want = -p.drivetrain.inertia_kg_m2 * r2.omega_rad_s / p.body.izz_kg_m2;
        assert!(
            (dr - want).abs() < 1e-9 * want.abs().max(1.0),
            "{dr} vs {want}"
        );
    }
}

#[test]
fn ground_effect_matches_cheeseman_bennett() {
    use helicon_model::ground_effect::{inflow_factor, thrust_ratio_closed_form};
    let mut p = Params::bergen_twin();
    let oge = Model::new(p, Preset::Physical.options());
    p.landing_gear.enabled = 1.0;
    p.ground_effect.enabled = 1.0;
    p.landing_gear.ground_down_m = 0.0;
    let ige = Model::new(p, Preset::Physical.options());
    let r = p.main_rotor.radius_m;
    let rho = p.environment.rho_kg_m3;
    let area = std::f64::consts::PI * r * r;
    let (x0, u0, _, _) = common::six_digit_hover_trim();
    // a level hover state (the rotor disc parallel to the ground)
    let mut x = x0;
    x[ix::PHI] = 0.0;
    x[ix::THETA] = 0.0;
    let thrust = |m: &Model, x: &State, col: f64| {
        let mut u = u0;
        u[0] = col;
        let mut xs = *x;
        xs[ix::THETA0] = 0.7 * col;
        let (_, a) = m.derivative(&xs, &u, &Vector3::zeros()).unwrap();
        (-a.force_mr_hub_n.z, a.vi_mr_m_s, a.ground_effect_factor)
    };
    let col0 = u0[0];
    let (t_oge, vi_oge, _) = thrust(&oge, &x, col0);
    for zr in [0.5, 1.0, 2.0] {
        let mut xg = x;
        // hub at z/R above the ground: hub = CM − κv (level)
        xg[ix::Z] = -(zr * r) + p.geometry.kappa_v_m;
        let (t_fixed, vi, k) = thrust(&ige, &xg, col0);
        let (k_want, _) = inflow_factor(zr * r, r, 0.5);
        assert_eq!(k, k_want);
        // momentum theory with the image: vi = k_G √(T / 2ρA) in hover
        let vi_momentum = (t_fixed / (2.0 * rho * area)).sqrt();
        assert!(
            (vi / vi_momentum - k).abs() < 1e-9,
            "{vi} {vi_momentum} {k}"
        );
        // the collective of the OGE thrust in ground effect (bisection):
        // the induced power T·vi at that thrust is k_G times the OGE one,
        // which is Cheeseman–Bennett's T_IGE/T_OGE = 1/k_G at that power
        let (mut lo, mut hi) = (col0 - 0.1, col0);
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if thrust(&ige, &xg, mid).0 > t_oge {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let (t_same, vi_same, _) = thrust(&ige, &xg, 0.5 * (lo + hi));
        let power_ratio = (t_same * vi_same) / (t_oge * vi_oge);
        let thrust_ratio_at_power = 1.0 / power_ratio;
        let closed = thrust_ratio_closed_form(zr);
        eprintln!(
            "z/R = {zr}: k_G = {k:.5}; thrust ratio at the same power {thrust_ratio_at_power:.6} \
             (closed form {closed:.6}); at the same collective {:.4}",
            t_fixed / t_oge
        );
        assert!((t_same - t_oge).abs() < 1e-6 * t_oge);
        assert!((thrust_ratio_at_power - closed).abs() < 1e-6 * closed);
        assert!(t_fixed > t_oge);
    }
    // below the clamp the factor is the one at 0.5 R
    let mut xg = x;
    xg[ix::Z] = -(0.2 * r) + p.geometry.kappa_v_m;
    assert_eq!(thrust(&ige, &xg, col0).2, 0.75);
}

#[test]
fn trim_on_the_ground_is_refused_naming_the_field() {
    let mut p = Params::bergen_twin();
    p.landing_gear.enabled = 1.0;
    p.landing_gear.ground_down_m = 0.2;
    let model = Model::new(p, Preset::Physical.options());
    let e = trim(&model, &TrimTarget::hover(), &TrimOptions::default()).unwrap_err();
    assert!(matches!(e, TrimError::OnGround { .. }));
    let msg = e.to_string();
    eprintln!("{msg}");
    assert!(
        msg.contains("landing_gear.ground_down_m") && msg.contains("0.2"),
        "{msg}"
    );
    // in the air it trims, to the thesis's hover
    p.landing_gear.ground_down_m = 5.0;
    let t = trim(
        &Model::new(p, Preset::Physical.options()),
        &TrimTarget::hover(),
        &TrimOptions::default(),
    )
    .unwrap();
    let t0 = trim(
        &Model::bergen_twin(Preset::Physical),
        &TrimTarget::hover(),
        &TrimOptions::default(),
    )
    .unwrap();
    assert_eq!(t.x, t0.x);
    assert_eq!(t.u, t0.u);
}

mod common;
