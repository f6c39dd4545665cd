//! Servo actuators, thesis (5.1)–(5.4) and (D.16)–(D.23).
//!
//! Each channel is a second-order system driven by the saturated command:
//! θ̈ = K ωn² sat(S) − 2ζ ωn θ̇ − ωn² θ, with `sat` clipping S to
//! [S_min, S_max] (Nomenclature "input saturation").
//!
//! **Rate limit semantics** (the thesis says only that "the position rates are
//! limited by setting saturations", (D.20)–(D.23)): a *limited integrator*.
//! The position rate is `clip(θ̇, ±θ̇max)`, and the rate state stops
//! accelerating outward once `|θ̇| ≥ θ̇max` (its derivative is set to 0 when the
//! unlimited acceleration points away from zero). Inside the limits the
//! channel is exactly linear, so the hover linear model has B = K ωn² = 7000
//! as in Appendix E.

use crate::params::Servo;

/// Time derivatives of one servo channel: `(θ̇_position, θ̈)`.
///
/// `s_cmd` is the raw command (saturated here), `theta_rad`/`theta_dot_rad_s`
/// the channel's two states.
#[inline]
pub fn servo_derivative(
    servo: &Servo,
    s_cmd: f64,
    theta_rad: f64,
    theta_dot_rad_s: f64,
) -> (f64, f64) {
    let s = s_cmd.clamp(servo.s_min, servo.s_max);
    let wn = servo.omega_n_rad_s;
    let mut acc = servo.gain_rad * wn * wn * s
        - 2.0 * servo.zeta * wn * theta_dot_rad_s
        - wn * wn * theta_rad;
    let lim = servo.rate_max_rad_s;
    if theta_dot_rad_s.abs() >= lim && acc * theta_dot_rad_s > 0.0 {
        acc = 0.0;
    }
    (theta_dot_rad_s.clamp(-lim, lim), acc)
}

/// Drive one servo channel through `commands` (sample k's command held over
/// [t_k, t_k + `dt_s`), as the flight computer holds it) with the model's
/// own integrator ([`crate::integrate::rk4`], one step per sample) from the
/// state `x0 = [θ, θ̇]`; returns the state at every sample (the first is
/// `x0`). This is what a bench test of the servo measures, without noise:
/// `helicon ident servo-bench` writes it, and the servo identification is
/// tested against it.
pub fn servo_response(servo: &Servo, commands: &[f64], dt_s: f64, x0: [f64; 2]) -> Vec<[f64; 2]> {
    let mut x = crate::state::State::zeros();
    x[0] = x0[0];
    x[1] = x0[1];
    let mut out = Vec::with_capacity(commands.len());
    for &s in commands {
        out.push([x[0], x[1]]);
        let next = crate::integrate::rk4(&x, dt_s, |st| {
            let (a, b) = servo_derivative(servo, s, st[0], st[1]);
            let mut d = crate::state::State::zeros();
            d[0] = a;
            d[1] = b;
            Ok::<_, std::convert::Infallible>(d)
        });
        x = match next {
            Ok(v) => v,
            Err(never) => match never {},
        };
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;

    /// Integrate one channel with RK4 (its own small loop; the model's RK4 is
    /// tested separately).
    fn simulate(servo: &Servo, s: f64, t_end: f64, dt: f64) -> Vec<(f64, f64, f64)> {
        let f = |x: [f64; 2]| {
            let (a, b) = servo_derivative(servo, s, x[0], x[1]);
            [a, b]
        };
        let mut x = [0.0, 0.0];
        let mut out = vec![(0.0, 0.0, 0.0)];
        let n = (t_end / dt).round() as usize;
        for i in 0..n {
            let k1 = f(x);
            let k2 = f([x[0] + 0.5 * dt * k1[0], x[1] + 0.5 * dt * k1[1]]);
            let k3 = f([x[0] + 0.5 * dt * k2[0], x[1] + 0.5 * dt * k2[1]]);
            let k4 = f([x[0] + dt * k3[0], x[1] + dt * k3[1]]);
            for j in 0..2 {
                x[j] += dt / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
            }
            out.push(((i + 1) as f64 * dt, x[0], x[1]));
        }
        out
    }

    /// Analytic step response of K ωn²/(s² + 2ζωn s + ωn²) to a step S (ζ < 1).
    fn analytic(servo: &Servo, s: f64, t: f64) -> f64 {
        let (wn, z) = (servo.omega_n_rad_s, servo.zeta);
        let wd = wn * (1.0 - z * z).sqrt();
        let phi = (1.0 - z * z).sqrt().atan2(z);
        servo.gain_rad
            * s
            * (1.0 - (-z * wn * t).exp() / (1.0 - z * z).sqrt() * (wd * t + phi).sin())
    }

    #[test]
    fn fig_10_1a_step_matches_analytic_second_order() {
        // Figure 10.1(a): a small step (no rate limiting) follows the analytic
        // 2nd-order response. RK4 at 1/4000 s: error O(dt⁴·ωn⁴) ≈ 4e-8 of the step.
        let servo = Params::bergen_twin().servos[0];
        for (t, th, _) in simulate(&servo, 0.05, 0.1, 2.5e-4) {
            assert!((th - analytic(&servo, 0.05, t)).abs() < 1e-9, "t={t}");
        }
    }

    #[test]
    fn fig_10_1b_rate_limit_engaged_for_1_not_for_0_1() {
        let servo = Params::bergen_twin().servos[0];
        // S_col = 0.1: peak rate of the linear response stays below 5 rad/s.
        let small = simulate(&servo, 0.1, 0.3, 2.5e-4);
        let peak_small = small.iter().map(|r| r.2.abs()).fold(0.0, f64::max);
        assert!(peak_small < 0.9 * servo.rate_max_rad_s, "peak {peak_small}");
        assert!((small.last().unwrap().1 - 0.07).abs() < 1e-6);
        // S_col = 1 saturates at 0.30 → θ = 0.21 rad; the linear response would
        // peak above 5 rad/s, so the rate is clipped and the rise is slower.
        let big = simulate(&servo, 1.0, 0.2, 2.5e-4);
        let peak_big = big.iter().map(|r| r.2.abs()).fold(0.0, f64::max);
        // The rate *state* may overshoot within an RK4 step (stages see the
        // unclipped state); the *position* never moves faster than the limit.
        assert!(peak_big <= 1.01 * servo.rate_max_rad_s, "peak {peak_big}");
        assert!(
            peak_big > servo.rate_max_rad_s - 1e-9,
            "limit not reached: {peak_big}"
        );
        let max_slope = big
            .windows(2)
            .map(|w| (w[1].1 - w[0].1) / (w[1].0 - w[0].0))
            .fold(0.0, f64::max);
        assert!(
            max_slope <= servo.rate_max_rad_s + 1e-9,
            "slope {max_slope}"
        );
        let t_half = big.iter().find(|r| r.1 >= 0.105).unwrap().0;
        let t_half_linear = (1..2000)
            .map(|i| i as f64 * 1e-5)
            .find(|&t| analytic(&servo, 0.3, t) >= 0.105)
            .unwrap();
        assert!(t_half > 1.2 * t_half_linear, "{t_half} vs {t_half_linear}");
        // while limited, the position moves at exactly 5 rad/s
        assert!((0.105 / t_half - 5.0).abs() < 1.0);
        assert!((big.last().unwrap().1 - 0.21).abs() < 1e-4);
    }

    #[test]
    fn saturation_clips_commands() {
        let servo = Params::bergen_twin().servos[0];
        let (_, a_hi) = servo_derivative(&servo, 5.0, 0.0, 0.0);
        let (_, a_sat) = servo_derivative(&servo, 0.30, 0.0, 0.0);
        assert_eq!(a_hi, a_sat);
        // B entry of Appendix E: K ωn² = 7000
        assert!((a_sat / 0.30 - 7000.0).abs() < 1e-9);
    }
}
