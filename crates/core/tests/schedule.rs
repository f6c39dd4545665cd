//! The gain schedule on board and the jerk-limited references: the
//! interpolation against hand-computed blends, continuity (bumpless), the
//! scheduled law at a node equal to the fixed law, no allocation per
//! sample, and the S-curves against their closed forms and limits.
#![allow(clippy::unwrap_used)] // tests: a failed unwrap is a failed test

use helicon_core::schedule::{GainSchedule, ScheduleAxes, ScheduledLqi, ScheduledPredictor};
use helicon_core::state::{Input, MeasuredStates, ReducedState};
use helicon_core::trajectory::{Channel, Mission, SCurve};
use helicon_core::{
    GainSet, KalmanPredictor, Lqi, LqiOptions, Predictor, Reference, ServoLimits, StateFeedback,
};
use nalgebra::{SMatrix, Vector3};
use std::sync::Arc;

use helicon_test_support::allocations;

#[global_allocator]
static ALLOC: helicon_test_support::Counting = helicon_test_support::Counting;

/// A synthetic, flyable gain set of the operating point (forward `f`,
/// lateral `l`), level: trim body velocity (f, l, 0), entries depending on
/// v = f + 0.1 l (so blends are visible), stable Φ, small gains.
fn gain_set_at(f: f64, l: f64) -> GainSet {
    let v = f + 0.1 * l;
    let mut x_trim = ReducedState::zeros();
    x_trim[3] = f;
    x_trim[4] = l;
    x_trim[12] = 0.01 * v;
    GainSet {
        sample_time_s: 0.0025,
        alpha: 1.002,
        x_trim,
        u_trim: Input::new(0.16 + 0.001 * v, 0.0, 0.02 * v, 0.1),
        phi: SMatrix::identity() * (0.9 + 0.001 * v),
        gamma: SMatrix::from_fn(|i, j| 0.001 * ((i + j) as f64) * (1.0 + v)),
        ls: SMatrix::from_fn(|i, j| 0.01 * ((i * 3 + j) % 7) as f64 * (1.0 + 0.1 * v)),
        li: SMatrix::from_fn(|i, j| 1e-4 * ((i + 2 * j) % 3) as f64 * (1.0 + v)),
        k: SMatrix::from_fn(|i, j| if i == j { 0.5 + 0.01 * v } else { 0.0 }),
        options: LqiOptions {
            integral_action: true,
            reference_in_proportional: false,
            anti_windup: false,
        },
    }
}

fn schedule() -> Arc<GainSchedule> {
    let axes = ScheduleAxes {
        forward_m_s: vec![0.0, 5.0, 10.0],
        lateral_m_s: vec![-5.0, 5.0],
        down_m_s: vec![0.0],
    };
    let mut points = Vec::new();
    for f in [0.0, 5.0, 10.0] {
        for l in [-5.0, 5.0] {
            points.push(gain_set_at(f, l));
        }
    }
    Arc::new(GainSchedule::new(axes, points).unwrap())
}

fn limits() -> ServoLimits {
    ServoLimits {
        min: Input::repeat(-1.0),
        max: Input::repeat(1.0),
    }
}

/// Bilinear weights by hand at (7.5, 0): halfway between forward 5 and 10,
/// halfway between lateral ∓5 → the mean of four sets.
#[test]
fn interpolation_is_the_hand_computed_bilinear_blend() {
    let s = schedule();
    let g = s.at(&Vector3::new(7.5, 0.0, 0.0));
    let corners =
        [(5.0, -5.0), (5.0, 5.0), (10.0, -5.0), (10.0, 5.0)].map(|(f, l)| gain_set_at(f, l));
    let mean_ls = corners.iter().fold(SMatrix::zeros(), |a, c| a + c.ls) / 4.0;
    assert!((g.ls - mean_ls).amax() < 1e-15);
    let mean_phi = corners.iter().fold(SMatrix::zeros(), |a, c| a + c.phi) / 4.0;
    assert!((g.phi - mean_phi).amax() < 1e-15);
    // at a node: that node's set exactly
    assert_eq!(s.at(&Vector3::new(5.0, 5.0, 0.0)), gain_set_at(5.0, 5.0));
    // outside the grid: clamped to the edge
    assert_eq!(s.at(&Vector3::new(-3.0, -9.0, 7.0)), gain_set_at(0.0, -5.0));
}

/// Bumpless: the interpolated gains move continuously with the operating
/// point — across a grid node the jump of every entry over ±1e-9 m/s is
/// below 1e-9 × the entries' scale.
#[test]
fn interpolation_is_continuous_across_nodes() {
    let s = schedule();
    for node in [5.0, 0.0, 10.0] {
        let a = s.at(&Vector3::new(node - 1e-9, 0.0, 0.0));
        let b = s.at(&Vector3::new(node + 1e-9, 0.0, 0.0));
        assert!((a.ls - b.ls).amax() < 1e-9);
        assert!((a.u_trim - b.u_trim).amax() < 1e-9);
        assert!((a.k - b.k).amax() < 1e-9);
    }
}

/// The scheduled law at a grid node gives the fixed law's commands (the
/// interpolation is exact there; the trim heading is the reference's).
#[test]
fn scheduled_law_at_a_node_is_the_fixed_law() {
    let s = schedule();
    let g = gain_set_at(5.0, -5.0);
    let mut fixed = Lqi::new(&g, limits(), true).unwrap();
    let mut sched = ScheduledLqi::new(Arc::clone(&s), limits(), true).unwrap();
    let reference = Reference {
        velocity_ned_m_s: Vector3::new(5.0, -5.0, 0.0),
        yaw_rad: 0.0,
    };
    let mut x = g.x_trim;
    x[0] = 0.02;
    x[4] = -4.8;
    for _ in 0..10 {
        let a = fixed.command(&x, &reference);
        let b = sched.command(&x, &reference);
        assert_eq!(a, b);
        x[4] += 0.01;
    }
    assert_eq!(sched.operating_point(), Vector3::new(5.0, -5.0, 0.0));
}

/// The scheduled predictor at a node predicts as the fixed one (to
/// round-off: the deviation is re-expressed about the same trim).
#[test]
fn scheduled_predictor_at_a_node_is_the_fixed_predictor() {
    let s = schedule();
    let g = gain_set_at(5.0, -5.0);
    let x0 = g.x_trim;
    let mut fixed = KalmanPredictor::new(&g, &x0).unwrap();
    let mut sched = ScheduledPredictor::new(Arc::clone(&s), &x0).unwrap();
    let mut y = MeasuredStates::from_fn(|i, _| x0[i]);
    for k in 0..20 {
        y[2] = 0.01 * f64::from(k);
        let a = fixed.absorb(&y).unwrap();
        let b = Predictor::absorb(&mut sched, &y).unwrap();
        assert!((a - b).amax() < 1e-12, "{}", (a - b).amax());
        fixed.advance(&g.u_trim).unwrap();
        Predictor::advance(&mut sched, &g.u_trim).unwrap();
    }
}

/// No allocation per sample: 4000 samples of the scheduled law and
/// predictor with the operating point sweeping the grid.
#[test]
fn scheduled_law_and_predictor_do_not_allocate() {
    let s = schedule();
    let mut law = ScheduledLqi::new(Arc::clone(&s), limits(), true).unwrap();
    let x0 = gain_set_at(0.0, -5.0).x_trim;
    let mut pred = ScheduledPredictor::new(Arc::clone(&s), &x0).unwrap();
    let mission = Mission {
        speed_m_s: Channel::new("speed", 0.0, &[(1.0, 10.0)], 1.0, 0.5).unwrap(),
        yaw_rate_rad_s: Channel::new("yaw_rate", 0.0, &[(2.0, 0.1)], 0.05, 0.05).unwrap(),
        down_m_s: Channel::new("down", 0.0, &[], 0.5, 0.5).unwrap(),
        yaw0_rad: 0.0,
    };
    let before = allocations();
    let mut acc = 0.0;
    for k in 0..4000 {
        let t = f64::from(k) * 0.0025;
        let r = mission.at(t);
        let y = MeasuredStates::from_fn(|i, _| if i == 3 { r.velocity_ned_m_s.x } else { 0.0 });
        let x = Predictor::absorb(&mut pred, &y).unwrap();
        let c = law.command(&x, &r);
        Predictor::advance(&mut pred, &c.u).unwrap();
        acc += c.u[0];
    }
    let after = allocations();
    assert!(acc.is_finite());
    assert_eq!(after - before, 0, "allocated {} times", after - before);
}

/// S-curves against their closed forms: the duration Δ/A + A/J (or
/// 2√(Δ/J)), the value reaching Δ exactly, the peak derivative, and the
/// limits |derivative| ≤ A, |second derivative| ≤ J checked by finite
/// differences of `value` and `rate` (h = 1e-4 s; tolerance 1e-6 relative
/// for the first, J·(1 + 1e-3) for the second, at the phase corners the
/// difference quotient averages across the kink).
#[test]
fn s_curves_match_their_closed_forms_and_limits() {
    for (delta, a, j) in [
        (15.0, 1.0, 0.5),
        (-2.0, 0.5, 0.5),
        (0.1, 0.05, 0.05),
        (0.3, 1.0, 2.0),
    ] {
        let c = SCurve::new(delta, a, j);
        let d = f64::abs(delta);
        let expected = if d * j >= a * a {
            d / a + a / j
        } else {
            2.0 * (d / j).sqrt()
        };
        assert!((c.duration_s() - expected).abs() < 1e-12 * expected);
        assert_eq!(c.value(c.duration_s() + 1.0), delta);
        assert_eq!(c.value(-1.0), 0.0);
        // the midpoint of a symmetric S-curve is Δ/2
        assert!((c.value(0.5 * c.duration_s()) - 0.5 * delta).abs() < 1e-12 * d);
        let h = 1e-4;
        let n = (c.duration_s() / h) as usize + 10;
        for k in 0..n {
            let t = k as f64 * h;
            let dv = (c.value(t + h) - c.value(t)) / h;
            assert!(dv.abs() <= a * (1.0 + 1e-6) + 1e-12, "rate {dv} at {t}");
            let da = (c.rate(t + h) - c.rate(t)) / h;
            assert!(da.abs() <= j * (1.0 + 1e-3), "jerk {da} at {t}");
            // the integral's derivative is the value
            let di = (c.integral(t + h) - c.integral(t - h)) / (2.0 * h);
            assert!(
                (di - c.value(t)).abs() < 1e-6 * d.max(1.0),
                "integral at {t}"
            );
        }
        // ∫ over a finished curve: Δ·(t − T/2) by symmetry
        let t = c.duration_s() + 3.0;
        let closed = delta * (t - 0.5 * c.duration_s());
        assert!((c.integral(t) - closed).abs() < 1e-9 * closed.abs().max(1.0));
    }
}

/// A mission's half turn: the heading turns by exactly rate × (t_off − t_on)
/// (S-curves up and down are symmetric), and the velocity follows it.
#[test]
fn mission_turn_angle_and_velocity_direction() {
    let m = Mission {
        speed_m_s: Channel::new("speed", 15.0, &[], 1.0, 0.5).unwrap(),
        yaw_rate_rad_s: Channel::new(
            "yaw_rate",
            0.0,
            &[(10.0, 0.1), (10.0 + 10.0 * std::f64::consts::PI, 0.0)],
            0.05,
            0.05,
        )
        .unwrap(),
        down_m_s: Channel::new("down", 0.0, &[], 0.5, 0.5).unwrap(),
        yaw0_rad: 0.0,
    };
    let r = m.at(60.0);
    assert!(
        (r.yaw_rad - std::f64::consts::PI).abs() < 1e-9,
        "{}",
        r.yaw_rad
    );
    assert!((r.velocity_ned_m_s - Vector3::new(-15.0, 0.0, 0.0)).norm() < 1e-7);
    // centripetal acceleration V r in the steady part of the turn
    let a = m.acceleration_ned_m_s2(25.0);
    assert!((a.norm() - 1.5).abs() < 1e-9);
}

/// Legs that overlap, non-finite targets and too many legs are refused.
#[test]
fn channel_rules() {
    let e = Channel::new("speed", 0.0, &[(0.0, 15.0), (5.0, 0.0)], 1.0, 0.5).unwrap_err();
    assert!(
        e.to_string().contains("speed") && e.to_string().contains("previous"),
        "{e}"
    );
    assert!(Channel::new("speed", 0.0, &[(0.0, f64::NAN)], 1.0, 0.5).is_err());
    assert!(Channel::new("speed", 0.0, &[], 0.0, 0.5).is_err());
    let many: Vec<(f64, f64)> = (0..33).map(|i| (100.0 * f64::from(i), 1.0)).collect();
    assert!(Channel::new("speed", 0.0, &many, 1.0, 0.5).is_err());
}
