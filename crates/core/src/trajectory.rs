//! Jerk- and acceleration-limited references (allocation-free, closed form).
//!
//! A reference channel (a speed, a yaw rate, a climb rate) moves between
//! targets along the time-optimal "S-curve" of a double integrator with a
//! bounded derivative: for a change Δ with rate limit A and rate-of-rate limit
//! J the derivative ramps at ±J, holds ±A when |Δ| ≥ A²/J, and ramps back to
//! zero, reaching the target after T = |Δ|/A + A/J (or 2√(|Δ|/J) when the
//! change is too small to reach A). On a speed channel that is the
//! acceleration and jerk limit; on a yaw-rate channel the yaw acceleration and
//! its rate. Every quantity is an exact function of time (value, derivative
//! and integral), so a reference is continuous with a continuous derivative.
//!
//! [`Mission`] combines three channels — ground speed V, yaw rate ψ̇ and
//! down velocity — into the four references of the law: the horizontal
//! velocity follows the heading (coordinated flight, no sideslip):
//! vn = V cos ψ, ve = V sin ψ, with ψ = ψ0 + ∫ψ̇ dt.

use crate::error::CoreError;
use crate::lqi::Reference;
use nalgebra::Vector3;

/// Largest number of legs of one channel (fixed capacity: no allocation).
pub const MAX_LEGS: usize = 32;

/// One S-curve: a change `delta` with derivative limit `rate_max` and
/// second-derivative limit `accel_max`, starting at τ = 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SCurve {
    /// The change (signed).
    pub delta: f64,
    /// Peak |derivative| reached (≤ the rate limit).
    peak_rate: f64,
    /// Second-derivative limit J (> 0).
    jerk: f64,
    /// Duration of each ramp of the derivative, peak_rate / J.
    t_ramp: f64,
    /// Duration of the constant-derivative phase.
    t_hold: f64,
}

impl SCurve {
    /// The time-optimal S-curve for `delta` with |derivative| ≤ `rate_max`
    /// and |second derivative| ≤ `jerk_max` (both finite and > 0; checked by
    /// the callers' configuration).
    pub fn new(delta: f64, rate_max: f64, jerk_max: f64) -> Self {
        let d = delta.abs();
        let (peak, hold) = if d * jerk_max >= rate_max * rate_max {
            (rate_max, d / rate_max - rate_max / jerk_max)
        } else {
            ((d * jerk_max).sqrt(), 0.0)
        };
        SCurve {
            delta,
            peak_rate: peak,
            jerk: jerk_max,
            t_ramp: peak / jerk_max,
            t_hold: hold,
        }
    }

    /// Total duration (s).
    pub fn duration_s(&self) -> f64 {
        2.0 * self.t_ramp + self.t_hold
    }

    /// Peak |derivative| reached.
    pub fn peak_rate(&self) -> f64 {
        self.peak_rate
    }

    /// The value at τ seconds after the start (0 before, `delta` after).
    pub fn value(&self, tau: f64) -> f64 {
        self.delta.signum() * self.unsigned_value(tau)
    }

    fn unsigned_value(&self, tau: f64) -> f64 {
        let (j, t1, t2) = (self.jerk, self.t_ramp, self.t_hold);
        let total = self.duration_s();
        if tau <= 0.0 {
            0.0
        } else if tau < t1 {
            0.5 * j * tau * tau
        } else if tau < t1 + t2 {
            0.5 * j * t1 * t1 + self.peak_rate * (tau - t1)
        } else if tau < total {
            let r = total - tau;
            self.delta.abs() - 0.5 * j * r * r
        } else {
            self.delta.abs()
        }
    }

    /// The derivative at τ.
    pub fn rate(&self, tau: f64) -> f64 {
        let (j, t1, t2) = (self.jerk, self.t_ramp, self.t_hold);
        let total = self.duration_s();
        let r = if tau <= 0.0 || tau >= total {
            0.0
        } else if tau < t1 {
            j * tau
        } else if tau < t1 + t2 {
            self.peak_rate
        } else {
            j * (total - tau)
        };
        self.delta.signum() * r
    }

    /// ∫₀^τ value dt (0 before the start).
    pub fn integral(&self, tau: f64) -> f64 {
        let (j, t1, t2) = (self.jerk, self.t_ramp, self.t_hold);
        let total = self.duration_s();
        let d = self.delta.abs();
        let phase1 = |t: f64| j * t * t * t / 6.0;
        let phase2 = |t: f64| {
            phase1(t1) + 0.5 * j * t1 * t1 * (t - t1) + 0.5 * self.peak_rate * (t - t1).powi(2)
        };
        // phase 3: value = d − J (T − t)²/2
        let phase3 = |t: f64| {
            let s = t1 + t2;
            phase2(s) + d * (t - s) + j / 6.0 * ((total - t).powi(3) - (total - s).powi(3))
        };
        let u = if tau <= 0.0 {
            0.0
        } else if tau < t1 {
            phase1(tau)
        } else if tau < t1 + t2 {
            phase2(tau)
        } else if tau < total {
            phase3(tau)
        } else {
            phase3(total) + d * (tau - total)
        };
        self.delta.signum() * u
    }
}

/// One leg: at `t_s` the channel starts moving to `target`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Leg {
    /// Start time (s).
    pub t_s: f64,
    /// The curve from the previous target to this one.
    pub curve: SCurve,
}

/// One channel: an initial value and up to [`MAX_LEGS`] S-curve legs that
/// do not overlap (each starts after the previous one has finished).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Channel {
    initial: f64,
    legs: [Leg; MAX_LEGS],
    len: usize,
}

impl Channel {
    /// A channel starting at `initial`, moving to each `(t_s, target)` in turn
    /// with |rate| ≤ `rate_max` and |rate of rate| ≤ `jerk_max`. Errors (naming
    /// `what`) on non-finite numbers, limits ≤ 0, more than [`MAX_LEGS`] legs,
    /// or a leg starting before the previous one has finished.
    pub fn new(
        what: &'static str,
        initial: f64,
        legs: &[(f64, f64)],
        rate_max: f64,
        jerk_max: f64,
    ) -> Result<Self, CoreError> {
        let bad = |rule| Err(CoreError::InvalidReference { what, rule });
        if !(rate_max.is_finite() && rate_max > 0.0 && jerk_max.is_finite() && jerk_max > 0.0) {
            return bad("limits must be finite and > 0");
        }
        if !initial.is_finite() {
            return bad("initial value must be finite");
        }
        if legs.len() > MAX_LEGS {
            return bad("has more than MAX_LEGS (32) legs");
        }
        let empty = Leg {
            t_s: 0.0,
            curve: SCurve::new(0.0, rate_max, jerk_max),
        };
        let mut out = Channel {
            initial,
            legs: [empty; MAX_LEGS],
            len: legs.len(),
        };
        let mut previous = initial;
        let mut free_at = f64::NEG_INFINITY;
        for (i, &(t_s, target)) in legs.iter().enumerate() {
            if !(t_s.is_finite() && target.is_finite()) {
                return bad("leg times and targets must be finite");
            }
            if t_s < free_at {
                return bad(
                    "a leg starts before the previous one has reached its target \
                     (space the legs by at least the previous leg's duration)",
                );
            }
            let curve = SCurve::new(target - previous, rate_max, jerk_max);
            out.legs[i] = Leg { t_s, curve };
            free_at = t_s + curve.duration_s();
            previous = target;
        }
        Ok(out)
    }

    /// The legs.
    pub fn legs(&self) -> &[Leg] {
        &self.legs[..self.len]
    }

    /// The value at time `t_s`.
    pub fn value(&self, t_s: f64) -> f64 {
        self.initial
            + self
                .legs()
                .iter()
                .map(|l| l.curve.value(t_s - l.t_s))
                .sum::<f64>()
    }

    /// The derivative at time `t_s`.
    pub fn rate(&self, t_s: f64) -> f64 {
        self.legs().iter().map(|l| l.curve.rate(t_s - l.t_s)).sum()
    }

    /// ∫₀^t value dt.
    pub fn integral(&self, t_s: f64) -> f64 {
        self.initial * t_s.max(0.0)
            + self
                .legs()
                .iter()
                .map(|l| l.curve.integral(t_s - l.t_s))
                .sum::<f64>()
    }
}

/// A mission reference: ground speed along the heading, yaw rate and down
/// velocity, each jerk-limited (coordinated flight: the velocity points
/// along the heading).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mission {
    /// Ground speed V (m/s), along the heading.
    pub speed_m_s: Channel,
    /// Yaw rate ψ̇ (rad/s).
    pub yaw_rate_rad_s: Channel,
    /// Down velocity (m/s).
    pub down_m_s: Channel,
    /// Heading at t = 0 (rad).
    pub yaw0_rad: f64,
}

impl Mission {
    /// The reference at time `t_s` (no allocation).
    pub fn at(&self, t_s: f64) -> Reference {
        let psi = self.yaw0_rad + self.yaw_rate_rad_s.integral(t_s);
        let v = self.speed_m_s.value(t_s);
        Reference {
            velocity_ned_m_s: Vector3::new(v * psi.cos(), v * psi.sin(), self.down_m_s.value(t_s)),
            yaw_rad: psi,
        }
    }

    /// The NED acceleration of the reference at `t_s` (m/s²): along-track
    /// V̇ and the centripetal V ψ̇.
    pub fn acceleration_ned_m_s2(&self, t_s: f64) -> Vector3<f64> {
        let psi = self.yaw0_rad + self.yaw_rate_rad_s.integral(t_s);
        let v = self.speed_m_s.value(t_s);
        let dv = self.speed_m_s.rate(t_s);
        let r = self.yaw_rate_rad_s.value(t_s);
        let (s, c) = psi.sin_cos();
        Vector3::new(
            dv * c - v * r * s,
            dv * s + v * r * c,
            self.down_m_s.rate(t_s),
        )
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// Closed forms: T = Δ/A + A/J when the limit is reached, 2√(Δ/J) when not.
    #[test]
    fn durations_match_the_closed_forms() {
        let c = SCurve::new(15.0, 1.5, 1.0);
        assert!((c.duration_s() - (10.0 + 1.5)).abs() < 1e-12);
        let c = SCurve::new(-1.0, 1.5, 1.0);
        assert!((c.duration_s() - 2.0).abs() < 1e-12);
        assert!((c.peak_rate() - 1.0).abs() < 1e-12);
    }
}
