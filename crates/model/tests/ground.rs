//! The ground-experiment calculators of §11.1 (`helicon_model::ground`):
//! readings made by the model itself (its hub torque, thrust, tail thrust
//! and fin drag at rest) give the Bergen Twin's parameters back — exactly
//! without noise, within the stated standard errors with noise; hand-worked
//! cases; bad readings name the file, line and column.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_model::ground::{Kind, Readings, calculate};
use helicon_model::{Model, Params, Preset, STATE_NAMES, State};
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

fn idx(name: &str) -> usize {
    STATE_NAMES.iter().position(|n| *n == name).unwrap()
}

/// The model at rest (no wind, all rates zero) with the given servo
/// positions: its auxiliary outputs.
fn at_rest(p: &Params, theta0: f64, theta_tr: f64) -> helicon_model::Aux {
    let model = Model::new(*p, Preset::Physical.options());
    let mut x = State::zeros();
    x[idx("theta0")] = theta0;
    x[idx("theta_tr")] = theta_tr;
    let (_, aux) = model
        .derivative(&x, &helicon_model::Input::zeros(), &Vector3::zeros())
        .unwrap();
    aux
}

/// The stabilizer bar's thrust on the whirl stand (both paddles at pitch
/// θ, bar level, main blades off) from the model's own blade-element
/// quadrature of the paddles' lift (`rotor::blade_integrals` over Ri…Ro,
/// the lift element of (6.52)), with the momentum inflow through the
/// annulus solved by bisection to round-off: an independent computation of
/// what the calculator inverts in closed form.
fn stabilizer_thrust(p: &Params, pitch_rad: f64) -> f64 {
    use helicon_model::rotor::{BladeInputs, Grid, blade_integrals};
    let sb = &p.stabilizer_bar;
    let (ro, ri) = (sb.outer_radius_m, sb.inner_radius_m);
    let om = p.main_rotor.omega_rad_s;
    let rho = p.environment.rho_kg_m3;
    let bi = blade_integrals(
        &Grid::new(ri, ro),
        &BladeInputs {
            omega_rad_s: om,
            hinge_offset_m: 0.0,
            hub_u_m_s: 0.0,
            hub_v_m_s: 0.0,
            lambda_speed_m_s: om * ro,
            p_rad_s: 0.0,
            q_rad_s: 0.0,
            flap_rad: Vector3::zeros(),
            flap_rate_rad_s: Vector3::zeros(),
            theta0_rad: pitch_rad,
            cyclic_a_rad: 0.0,
            cyclic_b_rad: 0.0,
            twist_rad_per_m: 0.0,
            k1: 0.0,
            lift_k: 0.5 * rho * sb.chord_m * sb.lift_slope_per_rad,
            drag_k: 0.0,
        },
    );
    let area = std::f64::consts::PI * (ro * ro - ri * ri);
    // λ of a thrust T (momentum theory through the annulus), then the
    // residual T − 2·lift(λ), increasing in |T|
    let residual = |t: f64| {
        let lam = -t.signum() * (t.abs() / (2.0 * rho * area)).sqrt() / (om * ro);
        t - 2.0 * bi.lift.at(lam)
    };
    let no_inflow = 2.0 * bi.lift.at(0.0);
    let (mut lo, mut hi) = if no_inflow >= 0.0 {
        (0.0, no_inflow)
    } else {
        (no_inflow, 0.0)
    };
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if residual(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

fn csv(kind: Kind, rows: &[(f64, f64)]) -> String {
    let [a, b] = kind.columns();
    let mut s = format!("# made by the model\n{a},{b}\n");
    for (x, y) in rows {
        s.push_str(&format!("{x},{y}\n"));
    }
    s
}

fn run(kind: Kind, rows: &[(f64, f64)], p: &Params) -> helicon_model::ground::GroundResult {
    let r = Readings::parse_csv(&csv(kind, rows), "r.csv", kind).unwrap();
    calculate(&r, p).unwrap()
}

/// Readings of each kind made by the model (Bergen Twin), with additive
/// noise of σ (in the read variable's unit) from `seed`.
fn readings(kind: Kind, sigma: f64, seed: u64) -> Vec<(f64, f64)> {
    let p = Params::bergen_twin();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let d = Normal::new(0.0, 1.0).unwrap();
    let mut e = || sigma * d.sample(&mut rng);
    let mut out = Vec::new();
    for _ in 0..3 {
        for i in 0..6 {
            let f = i as f64;
            out.push(match kind {
                Kind::RotorDrag => {
                    let w = 80.0 + 8.0 * f;
                    let mut q = p;
                    q.main_rotor.omega_rad_s = w;
                    (w, -at_rest(&q, 0.0, 0.0).torque_mr_hub_nm.z + e())
                }
                Kind::MainLiftSlope => {
                    let t = -0.03 - 0.025 * f;
                    (t, -at_rest(&p, t, 0.0).force_mr_hub_n.z + e())
                }
                Kind::TailLiftSlope => {
                    let t = 0.03 + 0.03 * f;
                    (t, -at_rest(&p, 0.0, t).force_tr_y_n + e())
                }
                Kind::TailFinLoss => {
                    let a = at_rest(&p, 0.0, 0.03 + 0.03 * f);
                    let thrust = -a.force_tr_y_n;
                    (thrust, thrust - a.drag.tail_fin_n + e())
                }
                // the restraint (6.31): Ks (β − β0) = F (R − e), β0 = −0.02 rad
                Kind::BladeSpring => {
                    let m = &p.main_rotor;
                    let force = 2.0 * f;
                    let beta =
                        -0.02 + force * (m.radius_m - m.hinge_offset_m) / m.spring_n_m_per_rad;
                    (force, beta + e())
                }
                // (4.2) as the model mixes: blade cyclic = Kb·swashplate − Kh·flybar
                Kind::BellGain => {
                    let x = -0.1 + 0.04 * f;
                    (x, 0.003 + p.main_rotor.bell_factor * x + e())
                }
                Kind::HillerGain => {
                    let x = -0.1 + 0.04 * f;
                    (x, -0.002 + p.main_rotor.hiller_factor * x + e())
                }
                Kind::StabilizerLiftSlope => {
                    let t = -0.1 + 0.04 * f;
                    (t, stabilizer_thrust(&p, t) + e())
                }
            });
        }
    }
    out
}

fn truth(kind: Kind) -> f64 {
    let p = Params::bergen_twin();
    match kind {
        Kind::RotorDrag => p.main_rotor.drag_coefficient,
        Kind::MainLiftSlope => p.main_rotor.lift_slope_per_rad,
        Kind::TailLiftSlope => p.tail_rotor.lift_slope_per_rad,
        Kind::BladeSpring => p.main_rotor.spring_n_m_per_rad,
        Kind::BellGain => p.main_rotor.bell_factor,
        Kind::HillerGain => p.main_rotor.hiller_factor,
        Kind::TailFinLoss => p.tail_rotor.fin_area_ratio,
        Kind::StabilizerLiftSlope => p.stabilizer_bar.lift_slope_per_rad,
    }
}

#[test]
fn noise_free_readings_from_the_model_give_the_bergen_twin_back() {
    // The calculators' closed forms against the model's quadrature and
    // converged inflow: agreement to round-off (1e-9 relative).
    let p = Params::bergen_twin();
    for kind in helicon_model::ground::KINDS {
        let r = run(kind, &readings(kind, 0.0, 0), &p);
        let rel = (r.value - truth(kind)).abs() / truth(kind);
        eprintln!(
            "{}: {} = {} (truth {}), rel {rel:.1e}",
            kind.name(),
            r.key,
            r.value,
            truth(kind)
        );
        assert!(
            rel < 1e-9,
            "{}: {} vs {}",
            kind.name(),
            r.value,
            truth(kind)
        );
        assert!(
            r.std_error < 1e-6 * r.value.abs(),
            "{}: se {}",
            kind.name(),
            r.std_error
        );
        assert_eq!(r.key, kind.key());
        assert_eq!(r.n_readings, 18);
    }
}

#[test]
fn noisy_readings_give_values_within_their_standard_errors() {
    // Noise per kind, in the read variable's unit: torque 0.05 N·m (of
    // 1.6–3.4), thrust 2 N (of 20–200), tail thrust 0.1 N (of 1–8), fin
    // loss 0.002 N (of 0.01–0.1), flap 1 mrad, pitch 1 mrad. Twenty seeds
    // per kind: the normalised errors should look like |N(0, 1)|.
    let p = Params::bergen_twin();
    for (kind, sigma) in [
        (Kind::RotorDrag, 0.05),
        (Kind::MainLiftSlope, 2.0),
        (Kind::TailLiftSlope, 0.1),
        (Kind::TailFinLoss, 0.002),
        (Kind::BladeSpring, 0.001),
        (Kind::BellGain, 0.001),
        (Kind::HillerGain, 0.001),
        (Kind::StabilizerLiftSlope, 0.2),
    ] {
        let mut z: Vec<f64> = (0..20)
            .map(|seed| {
                let r = run(kind, &readings(kind, sigma, seed), &p);
                (r.value - truth(kind)).abs() / r.std_error
            })
            .collect();
        z.sort_by(f64::total_cmp);
        let (med, p90, max) = (z[9], z[17], z[19]);
        eprintln!(
            "{}: |error|/se median {med:.2}, 90th percentile {p90:.2}, max {max:.2}",
            kind.name()
        );
        assert!(
            z.iter().filter(|v| **v <= 2.0).count() >= 16,
            "{}: {z:?}",
            kind.name()
        );
        assert!(max < 4.0, "{}: {z:?}", kind.name());
    }
}

#[test]
fn hand_worked_cases() {
    let mut p = Params::bergen_twin();
    // rotor-drag: b = 2, ρ = 1.2, c = 0.1, R = 1, e = 0 → τ = Cd·0.03·Ω²;
    // Cd = 0.01: τ(100) = 3, τ(50) = 0.75.
    p.main_rotor.blades = 2.0;
    p.environment.rho_kg_m3 = 1.2;
    p.main_rotor.chord_m = 0.1;
    p.main_rotor.radius_m = 1.0;
    p.main_rotor.hinge_offset_m = 0.0;
    p.main_rotor.twist_rad = 0.0;
    let r = run(Kind::RotorDrag, &[(100.0, 3.0), (50.0, 0.75)], &p);
    assert!((r.value - 0.01).abs() < 1e-15 && r.std_error < 1e-15);
    // two readings 3.1 and 0.75: slope = Σxy/Σx² with x = 0.03Ω² = (300, 75):
    // Cd = (300·3.1 + 75·0.75)/(300² + 75²) = 986.25/95625
    let r = run(Kind::RotorDrag, &[(100.0, 3.1), (50.0, 0.75)], &p);
    assert!((r.value - 986.25 / 95625.0).abs() < 1e-15);
    // se: rss/(n−1)/Σx²
    let cd: f64 = 986.25 / 95625.0;
    let rss = (3.1 - 300.0 * cd).powi(2) + (0.75 - 75.0 * cd).powi(2);
    assert!((r.std_error - (rss / 95625.0).sqrt()).abs() < 1e-15);

    // main-lift-slope: Ω = 100, so k = bρcΩ²/2 = 1200, A = 1200 θ/3 = 400 θ,
    // B = 1200/2 = 600, √(2ρπR²(ΩR)²) = 100√(2.4π). Cls = 6, θ = 0.1:
    // T = 6(40 − 600 √T/(100√(2.4π))) → √T = (−β + √(β² + 960))/2, β = 36/√(2.4π).
    p.main_rotor.omega_rad_s = 100.0;
    let beta = 36.0 / (2.4 * std::f64::consts::PI).sqrt();
    let s = 0.5 * (-beta + (beta * beta + 960.0).sqrt());
    let t1 = s * s;
    let s2 = 0.5 * (-beta + (beta * beta + 1920.0).sqrt());
    let r = run(
        Kind::MainLiftSlope,
        &[(0.1, t1), (0.2, s2 * s2), (-0.1, -t1)],
        &p,
    );
    assert!((r.value - 6.0).abs() < 1e-12, "{}", r.value);

    // blade-spring: R − e = 1, β = 0.01 + 0.005 F → Ks = 200
    let r = run(
        Kind::BladeSpring,
        &[(0.0, 0.01), (1.0, 0.015), (2.0, 0.02)],
        &p,
    );
    assert!((r.value - 200.0).abs() < 1e-10 && r.std_error < 1e-9);
    assert!((r.intercept.unwrap()[0] - 0.01).abs() < 1e-15);
    // bell-gain: y = (0, 0.02, 0.05) at x = (0, 0.1, 0.2): slope 0.25,
    // intercept −0.005/3·… by hand: x̄ = 0.1, ȳ = 0.07/3; Sxy = 0.005, Sxx = 0.02
    let r = run(Kind::BellGain, &[(0.0, 0.0), (0.1, 0.02), (0.2, 0.05)], &p);
    assert!((r.value - 0.25).abs() < 1e-13);
    // residuals (1/6, −1/3, 1/6)·0.005·… : rss = 0.005²/6·… computed directly
    let b0 = 0.07 / 3.0 - 0.25 * 0.1;
    let rss: f64 = [(0.0, 0.0), (0.1, 0.02), (0.2, 0.05)]
        .iter()
        .map(|(x, y): &(f64, f64)| (y - b0 - 0.25 * x).powi(2))
        .sum();
    assert!((r.std_error - (rss / 1.0 / 0.02).sqrt()).abs() < 1e-13);

    // tail-fin-loss: Rtr = 0.18, dtf·Atf = 0.014: loss/T = k, Ktf = √(4π 0.0324 k / 0.014)
    let q = Params::bergen_twin();
    let r = run(Kind::TailFinLoss, &[(4.0, 3.96), (8.0, 7.92)], &q);
    let want = (4.0 * std::f64::consts::PI * 0.0324 * 0.01
        / (q.fuselage.drag_tf * q.fuselage.area_tf_m2))
        .sqrt();
    assert!((r.value - want).abs() < 1e-12, "{} vs {want}", r.value);
}

/// The stabilizer bar's lift slope: the calculator's closed-form root
/// against the model's quadrature and a bisected inflow, to 1e-12 relative,
/// the Bergen Twin's and another bar's; a hand-worked case; the fitted
/// thrust is the reading's.
#[test]
fn stabilizer_lift_slope_against_the_models_paddle_lift() {
    let mut p = Params::bergen_twin();
    for (ri, ro, chord, cls, omega) in [(0.5, 0.65, 0.1, 2.6, 100.0), (0.3, 0.45, 0.06, 4.1, 150.0)]
    {
        p.stabilizer_bar.inner_radius_m = ri;
        p.stabilizer_bar.outer_radius_m = ro;
        p.stabilizer_bar.chord_m = chord;
        p.stabilizer_bar.lift_slope_per_rad = cls;
        p.main_rotor.omega_rad_s = omega;
        let rows: Vec<(f64, f64)> = [-0.12, -0.05, 0.03, 0.08, 0.15]
            .iter()
            .map(|t| (*t, stabilizer_thrust(&p, *t)))
            .collect();
        let r = run(Kind::StabilizerLiftSlope, &rows, &p);
        let rel = (r.value - cls).abs() / cls;
        eprintln!(
            "stabilizer-lift-slope Ri {ri} Ro {ro}: {} (truth {cls}), rel {rel:.1e}, se {:.1e}",
            r.value, r.std_error
        );
        assert!(rel < 1e-12, "{} vs {cls}", r.value);
        assert!(r.std_error < 1e-10 * cls);
        for pt in &r.points {
            assert!((pt[1] - pt[2]).abs() <= 1e-12 * pt[1].abs().max(1.0));
        }
        assert_eq!(r.key, "stabilizer_bar.lift_slope_per_rad");
        assert_eq!(r.unit, "1/rad");
    }
    // by hand: ρ = 1.2, csb = 0.1, Ω = 100, Ri = 0, Ro = 1 (so the annulus
    // is the disc): T = Cls·1200·[θ/3 + λ/2], √(2ρπ(ΩRo)²) = 100√(2.4π);
    // Cls = 3, θ = 0.1: T = 3(40 − 600 √T/(100√(2.4π))) → √T = (−β +
    // √(β² + 480))/2, β = 18/√(2.4π)
    p.environment.rho_kg_m3 = 1.2;
    p.stabilizer_bar.inner_radius_m = 0.0;
    p.stabilizer_bar.outer_radius_m = 1.0;
    p.stabilizer_bar.chord_m = 0.1;
    p.main_rotor.omega_rad_s = 100.0;
    let beta = 18.0 / (2.4 * std::f64::consts::PI).sqrt();
    let root = |c: f64| {
        let s = 0.5 * (-beta + (beta * beta + c).sqrt());
        s * s
    };
    let r = run(
        Kind::StabilizerLiftSlope,
        &[(0.1, root(480.0)), (0.2, root(960.0)), (-0.1, -root(480.0))],
        &p,
    );
    assert!((r.value - 3.0).abs() < 1e-12, "{}", r.value);
    // a thrust against the pitch names the line
    let e = err(
        Kind::StabilizerLiftSlope,
        "pitch_rad,thrust_n\n0.1,9.3\n0.15,-15\n",
    );
    assert!(
        e.contains("bench.csv: line 3") && e.contains("`thrust_n` = -15"),
        "{e}"
    );
}

/// The stabilizer lift slope and its standard error on noisy readings
/// against the one-parameter least-squares conditions evaluated with this
/// test's own thrust (the model's quadrature, the inflow bisected):
/// at the fitted Cls the residuals r are orthogonal to g = ∂T/∂Cls, and
/// se² = Σr²/(n − 1)/Σg². g by central differences with h = 1e-5·Cls: the
/// truncation error (~h², 1e-10 relative) and the round-off (~1e-16/h,
/// 1e-11) are far below the 1e-6 asserted, while a Cls 0.1 % off gives a
/// cosine of 0.027 (tried).
#[test]
fn stabilizer_lift_slope_is_the_least_squares_fit_with_its_standard_error() {
    for seed in [3, 11] {
        let rows = readings(Kind::StabilizerLiftSlope, 0.2, seed);
        let r = run(Kind::StabilizerLiftSlope, &rows, &Params::bergen_twin());
        let thrust = |cls: f64, pitch: f64| {
            let mut p = Params::bergen_twin();
            p.stabilizer_bar.lift_slope_per_rad = cls;
            stabilizer_thrust(&p, pitch)
        };
        let h = 1e-5 * r.value;
        let (mut gr, mut gg, mut rr) = (0.0, 0.0, 0.0);
        for (pitch, t) in &rows {
            let g = (thrust(r.value + h, *pitch) - thrust(r.value - h, *pitch)) / (2.0 * h);
            let res = t - thrust(r.value, *pitch);
            gr += g * res;
            gg += g * g;
            rr += res * res;
        }
        let cos = gr / (gg * rr).sqrt();
        assert!(
            cos.abs() < 1e-6,
            "seed {seed}: residuals not orthogonal, {cos:e}"
        );
        let se = (rr / (rows.len() as f64 - 1.0) / gg).sqrt();
        assert!(
            ((r.std_error - se) / se).abs() < 1e-6,
            "seed {seed}: se {} vs {se}",
            r.std_error
        );
    }
}

fn err(kind: Kind, text: &str) -> String {
    match Readings::parse_csv(text, "bench.csv", kind) {
        Err(e) => e.to_string(),
        Ok(r) => calculate(&r, &Params::bergen_twin())
            .unwrap_err()
            .to_string(),
    }
}

/// A million readings are read in linear time (before: the line of each
/// reading was counted from the file's start, 33 s for 10⁵ rows through
/// the CLI) and keep their line numbers.
#[test]
fn a_million_readings_parse_in_linear_time_with_their_lines() {
    let mut text = String::from("# bench\npitch_rad,thrust_n\n");
    for i in 0..1_000_000u32 {
        let p = 0.02 + 0.13 * f64::from(i % 1000) / 1000.0;
        text.push_str(&format!("{p:.5},{:.4}\n", 100.0 * p));
    }
    text.push_str("0.1,nan\n");
    let e = err(Kind::StabilizerLiftSlope, &text);
    assert!(e.contains("bench.csv: line 1000003,"), "{e}");
    let r = Readings::parse_csv(
        &text[..text.len() - 8],
        "bench.csv",
        Kind::StabilizerLiftSlope,
    )
    .unwrap();
    assert_eq!(r.rows.len(), 1_000_000);
    assert_eq!(r.rows[999_999].line, 1_000_002);
    let out = calculate(&r, &Params::bergen_twin()).unwrap();
    assert!(out.value.is_finite() && out.std_error.is_finite());
}

#[test]
fn hostile_readings_name_file_line_and_column() {
    let k = Kind::MainLiftSlope;
    let e = err(k, "");
    assert!(e.contains("bench.csv") && e.contains("empty"), "{e}");
    let e = err(k, "pitch_rad,thrust_n\n");
    assert!(e.contains("0 reading"), "{e}");
    let e = err(k, "pitch_rad,thrust_n\n-0.1,-50\n");
    assert!(e.contains("1 reading") && e.contains("at least 2"), "{e}");
    let e = err(k, "pitch_rad,thrust_n\n-0.1,-50\n-0.2,NaN\n");
    assert!(
        e.contains("bench.csv") && e.contains("line 3") && e.contains("`thrust_n`"),
        "{e}"
    );
    let e = err(k, "pitch_rad,thrust_n\n-0.1,-50\n# a comment\n-0.2,inf\n");
    assert!(e.contains("line 4") && e.contains("`thrust_n`"), "{e}");
    // comments and blank lines before the header and between readings count as lines
    let e = err(k, "# c\n\npitch_rad,thrust_n\n-0.1,-50\n\n# x\n-0.2,nan\n");
    assert!(e.contains("line 7,") && e.contains("`thrust_n`"), "{e}");
    let e = err(k, "pitch_rad,thrust_n\r\n-0.1,-50\r\n\r\n-0.2,x\r\n");
    assert!(e.contains("line 4,"), "{e}");
    let e = err(k, "pitch_rad,thrust_n\n-0.1,-50\n0.2,-90\n");
    assert!(
        e.contains("bench.csv: line 3") && e.contains("`thrust_n` = -90"),
        "{e}"
    );
    let e = err(k, "pitch_rad,thrust\n-0.1,-50\n");
    assert!(e.contains("no column `thrust_n`"), "{e}");
    let e = err(k, "pitch_rad,thrust_n,thrust_n\n-0.1,-50,1\n");
    assert!(e.contains("twice"), "{e}");
    let e = err(k, "pitch_rad,thrust_n\n-0.1,-50\n-0.2\n");
    assert!(e.contains("bench.csv"), "{e}");
    let e = err(k, "pitch_rad,thrust_n\n0,0\n0,0\n");
    assert!(e.contains("do not vary"), "{e}");
    let e = err(Kind::RotorDrag, "omega_rad_s,torque_n_m\n100,2\n-90,1.5\n");
    assert!(e.contains("line 3") && e.contains("`omega_rad_s`"), "{e}");
    let e = err(Kind::RotorDrag, "omega_rad_s,torque_n_m\n100,2\n90,-1.5\n");
    assert!(
        e.contains("line 3") && e.contains("`torque_n_m` = -1.5"),
        "{e}"
    );
    let e = err(
        Kind::TailFinLoss,
        "thrust_no_fin_n,thrust_with_fin_n\n4,3.9\n-1,-1\n",
    );
    assert!(
        e.contains("line 3") && e.contains("`thrust_no_fin_n`"),
        "{e}"
    );
    let e = err(
        Kind::TailFinLoss,
        "thrust_no_fin_n,thrust_with_fin_n\n4,4.1\n8,8.2\n",
    );
    assert!(e.contains("no loss"), "{e}");
    let e = err(
        Kind::BladeSpring,
        "force_n,flap_rad\n0,0.01\n1,0.005\n2,0.0\n",
    );
    assert!(e.contains("does not rise"), "{e}");
    let e = err(
        Kind::HillerGain,
        "flybar_rad,blade_pitch_rad\n0,0\n0.1,-0.08\n0.2,-0.16\n",
    );
    assert!(e.contains("same sense"), "{e}");
    // a pitch in degrees, and one overflowing the thrust, named (before: a
    // lift slope of 0.026 from degrees; "do not vary" for 1e200)
    for kind in [
        Kind::MainLiftSlope,
        Kind::TailLiftSlope,
        Kind::StabilizerLiftSlope,
    ] {
        for text in [
            "pitch_rad,thrust_n\n3,3.67\n6,9.28\n9,15.47\n",
            "pitch_rad,thrust_n\n0.1,9\n1e200,1e300\n",
            "pitch_rad,thrust_n\n0.1,9\n-0.8,-20\n",
        ] {
            let e = err(kind, text);
            assert!(
                e.contains("bench.csv: line ")
                    && e.contains("`pitch_rad`")
                    && e.contains("degrees"),
                "{}: {e}",
                kind.name()
            );
        }
    }
    // every template parses and computes
    for kind in helicon_model::ground::KINDS {
        let r = Readings::parse_csv(&kind.template(), "t.csv", kind).unwrap();
        let out = calculate(&r, &Params::bergen_twin()).unwrap();
        assert!(
            out.value.is_finite() && out.std_error.is_finite(),
            "{}",
            kind.name()
        );
        assert_eq!(Kind::from_name(kind.name()), Some(kind));
    }
}
