//! The optional drivetrain: the rotor speed Ω as a state, driven by an
//! engine under a governor, loaded by the rotors' aerodynamic torques
//! (thesis ch. 7: the main-rotor torque hτz (7.25) and the tail-rotor shaft
//! torque tτy (7.50), referred to the main shaft by the gear ratio G).
//!
//! ```text
//! J Ω̇ = Q_engine − Q_mr − G·Q_tr − f·Ω                 (shaft balance)
//! Q_engine = throttle · Q_max,   throttle ∈ [0, 1]
//! throttle = clamp(I + Kp (Ω_ref − Ω), 0, 1)           (governor, PI on rotor speed)
//! İ = Ki (Ω_ref − Ω)   (held while the throttle is saturated in that direction)
//! ```
//!
//! The governor is a PI on rotor speed, as ArduPilot's helicopter governor
//! (a throttle trim plus a proportional and an integral correction). Its
//! speed reference is ramped by [`Spool`]: from the rotor's speed to the
//! governed speed Ω_gov = `main_rotor.omega_rad_s` at Ω_gov/`spool_up_s`
//! (spool-up, the "runup" of a helicopter speed controller), and the
//! engine is cut at shut-down (throttle 0; the rotor winds down against its
//! drag and the transmission friction).
//!
//! The engine's reaction on the airframe is −Q_engine about the shaft: the
//! airframe's yaw torque from the main rotor is hτz − J·Ω̇ (= hτz in steady
//! state, the thesis's torque; the rotor's acceleration adds to it while the
//! speed changes).
//!
//! The thesis took the governor–engine loop as without dynamics (ch. 5):
//! with the block off (the default) Ω is the constant `main_rotor.omega_rad_s`
//! and the 30-state model, its trim and its linearization are the thesis's.
//! With it on, the two states [Ω, I] are appended to the model's 30
//! ([`crate::model::PlantState`]); trim and linearization stay on the 30.

use crate::params::{Drivetrain, Params};

/// The drivetrain states.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotorState {
    /// Main-rotor speed Ω (rad/s).
    pub omega_rad_s: f64,
    /// The governor's integrator (throttle units, 0 … 1).
    pub governor_integral: f64,
}

/// What drives the engine over one step (held, like the servo inputs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriveCommand {
    /// Engine running (false: throttle 0, the governor's integrator held).
    pub engine_on: bool,
    /// The governor's speed reference (rad/s).
    pub omega_ref_rad_s: f64,
}

/// The governor's throttle (0 … 1) at `state` under `cmd`.
#[inline]
pub fn throttle(d: &Drivetrain, cmd: &DriveCommand, state: &RotorState) -> f64 {
    if !cmd.engine_on {
        return 0.0;
    }
    (state.governor_integral + d.governor_kp_s * (cmd.omega_ref_rad_s - state.omega_rad_s))
        .clamp(0.0, 1.0)
}

/// The drivetrain derivative: (Ω̇, İ, throttle) with the rotors' load
/// torque at the main shaft `load_n_m` (Q_mr + G·Q_tr, positive against
/// the rotation).
#[inline]
pub fn derivative(
    d: &Drivetrain,
    cmd: &DriveCommand,
    state: &RotorState,
    load_n_m: f64,
) -> (f64, f64, f64) {
    let thr = throttle(d, cmd, state);
    let q_engine = thr * d.engine_torque_max_n_m;
    let omega_dot = (q_engine - load_n_m - d.friction_n_m_s * state.omega_rad_s) / d.inertia_kg_m2;
    let e = cmd.omega_ref_rad_s - state.omega_rad_s;
    let i_dot = if !cmd.engine_on
        || (state.governor_integral >= 1.0 && e > 0.0)
        || (state.governor_integral <= 0.0 && e < 0.0)
    {
        0.0
    } else {
        d.governor_ki_per_rad * e
    };
    (omega_dot, i_dot, thr)
}

/// The governor's speed-reference ramp: spool-up and shut-down.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spool {
    omega_gov_rad_s: f64,
    ramp_rad_s2: f64,
    /// The current command.
    pub command: DriveCommand,
}

impl Spool {
    /// A stopped engine (rotor at rest).
    pub fn stopped(p: &Params) -> Spool {
        let d = &p.drivetrain;
        Spool {
            omega_gov_rad_s: p.main_rotor.omega_rad_s,
            ramp_rad_s2: p.main_rotor.omega_rad_s / d.spool_up_s,
            command: DriveCommand {
                engine_on: false,
                omega_ref_rad_s: 0.0,
            },
        }
    }

    /// Running at the governed speed (the thesis's flight condition).
    pub fn governed(p: &Params) -> Spool {
        let mut s = Spool::stopped(p);
        s.command = DriveCommand {
            engine_on: true,
            omega_ref_rad_s: s.omega_gov_rad_s,
        };
        s
    }

    /// The governed speed Ω_gov (rad/s).
    pub fn governed_speed_rad_s(&self) -> f64 {
        self.omega_gov_rad_s
    }

    /// Start the engine: the reference ramps from the rotor's present speed.
    pub fn start(&mut self, rotor_omega_rad_s: f64) {
        if !self.command.engine_on {
            self.command = DriveCommand {
                engine_on: true,
                omega_ref_rad_s: rotor_omega_rad_s.clamp(0.0, self.omega_gov_rad_s),
            };
        }
    }

    /// Cut the engine (shut-down).
    pub fn stop(&mut self) {
        self.command = DriveCommand {
            engine_on: false,
            omega_ref_rad_s: 0.0,
        };
    }

    /// Advance the ramp by `dt_s`.
    pub fn step(&mut self, dt_s: f64) {
        if self.command.engine_on {
            self.command.omega_ref_rad_s =
                (self.command.omega_ref_rad_s + self.ramp_rad_s2 * dt_s).min(self.omega_gov_rad_s);
        }
    }
}

/// The rotor states at the governed speed with the integrator holding the
/// throttle that balances `load_n_m` (the steady state of a trim).
pub fn governed_state(p: &Params, load_n_m: f64) -> RotorState {
    let d = &p.drivetrain;
    let omega = p.main_rotor.omega_rad_s;
    RotorState {
        omega_rad_s: omega,
        governor_integral: ((load_n_m + d.friction_n_m_s * omega) / d.engine_torque_max_n_m)
            .clamp(0.0, 1.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn governed_state_balances_the_load() {
        let mut p = Params::bergen_twin();
        p.drivetrain.enabled = 1.0;
        let s = governed_state(&p, 8.0);
        let cmd = Spool::governed(&p).command;
        let (w_dot, i_dot, thr) = derivative(&p.drivetrain, &cmd, &s, 8.0);
        assert!(w_dot.abs() < 1e-12, "{w_dot}");
        assert_eq!(i_dot, 0.0);
        assert!(thr > 0.0 && thr < 1.0);
    }

    #[test]
    fn engine_off_gives_no_torque_and_holds_the_integrator() {
        let p = Params::bergen_twin();
        let cmd = Spool::stopped(&p).command;
        let s = RotorState {
            omega_rad_s: 50.0,
            governor_integral: 0.3,
        };
        let (w_dot, i_dot, thr) = derivative(&p.drivetrain, &cmd, &s, 2.0);
        assert_eq!((i_dot, thr), (0.0, 0.0));
        assert!(w_dot < 0.0);
    }

    #[test]
    fn spool_ramp_reaches_the_governed_speed_in_the_spool_up_time() {
        let p = Params::bergen_twin();
        let mut s = Spool::stopped(&p);
        s.start(0.0);
        let n = (p.drivetrain.spool_up_s / 0.0025).round() as usize;
        for _ in 0..n - 1 {
            s.step(0.0025);
        }
        assert!(s.command.omega_ref_rad_s < 100.0);
        s.step(0.0025);
        s.step(0.0025);
        assert_eq!(s.command.omega_ref_rad_s, 100.0);
        s.stop();
        assert!(!s.command.engine_on);
    }
}
