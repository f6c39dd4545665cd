//! State feedback: the [`StateFeedback`] extension point and its first
//! implementation, the thesis's LQR with integral action ([`Lqi`], Figure
//! 14.4, (14.29), (14.34)).
//!
//! Per sample, given the absolute state estimate x̂ and the reference:
//! 1. outputs ŷ = [ψ̂, û, v̂, ŵ] from x̂;
//! 2. output errors e: ψ_ref − ψ̂ (wrapped to (−π, π]) and, for the
//!    velocities, r_ned − R_eb(Θ̂) v̂_body — the references are NED velocities
//!    and yaw, as the thesis plots them ((14.37), Figure 14.5);
//! 3. u = u_trim − Ls,α x_fb − Li,α x_i,body (14.34), where x_fb is x̂ − x_trim
//!    (with the reference subtracted on the four output states when
//!    `reference_in_proportional`) and x_i,body is the integral state with its
//!    velocity part (kept in NED, so it survives heading changes) rotated into
//!    body axes;
//! 4. u saturated to the servo limits;
//! 5. x_i ← x_i + e (14.29) (held while saturated with anti-windup).

use crate::frames::{EulerTrig, wrap_pi};
use crate::gains::{GainSet, LqiOptions, ServoLimits};
use crate::state::{Input, NU, NX_REDUCED, NY, ReducedState};
use nalgebra::{SMatrix, SVector, Vector3};

/// Reference for the four controlled outputs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Reference {
    /// Velocity in NED (m/s).
    pub velocity_ned_m_s: Vector3<f64>,
    /// Heading ψ (rad).
    pub yaw_rad: f64,
}

/// What a state-feedback law decided this sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Command {
    /// Servo commands after saturation.
    pub u: Input,
    /// Which commands were saturated.
    pub saturated: [bool; NU],
    /// Output errors [ψ (rad), vn, ve, vd (m/s)], reference − estimate.
    pub tracking_error: SVector<f64, NY>,
    /// Integral states [ψ (rad·samples), vn, ve, vd (m/s·samples)] after this sample.
    pub integral: SVector<f64, NY>,
}

/// The extension point for control laws: the absolute state estimate and
/// the reference in, saturated servo commands out. Implementations must not
/// allocate in [`StateFeedback::command`].
pub trait StateFeedback {
    /// One sample of the control law.
    fn command(&mut self, estimate: &ReducedState, reference: &Reference) -> Command;
    /// One sample of the control law with `offset` (servo units, rad) added
    /// to the law's command *before* saturation: a flight-test excitation
    /// injected on the servos. The default adds it to [`StateFeedback::command`]'s
    /// output; laws that saturate must override it so the offset is
    /// saturated (and seen by the anti-windup) like the rest of the command.
    fn command_with_offset(
        &mut self,
        estimate: &ReducedState,
        reference: &Reference,
        offset: &Input,
    ) -> Command {
        let mut c = self.command(estimate, reference);
        c.u += offset;
        c
    }
    /// Forget any internal state (integrators).
    fn reset(&mut self);
}

/// The thesis's LQR with integral action (fixed-size; no allocation).
#[derive(Debug, Clone, PartialEq)]
pub struct Lqi {
    pub(crate) ls: SMatrix<f64, NU, NX_REDUCED>,
    pub(crate) li: SMatrix<f64, NU, NY>,
    pub(crate) x_trim: ReducedState,
    pub(crate) u_trim: Input,
    limits: ServoLimits,
    options: LqiOptions,
    enabled: bool,
    x_i: SVector<f64, NY>,
}

impl Lqi {
    /// The law of a gain set, saturating to `limits`. With `enabled = false`
    /// it holds the trim commands (open loop; the integrators still run so
    /// the logs show what the law would have done).
    pub fn new(
        gains: &GainSet,
        limits: ServoLimits,
        enabled: bool,
    ) -> Result<Self, crate::CoreError> {
        gains.check()?;
        limits.check()?;
        Ok(Lqi {
            ls: gains.ls,
            li: gains.li,
            x_trim: gains.x_trim,
            u_trim: gains.u_trim,
            limits,
            options: gains.options,
            enabled,
            x_i: SVector::zeros(),
        })
    }

    /// The integral states [ψ, vn, ve, vd].
    pub fn integral_states(&self) -> &SVector<f64, NY> {
        &self.x_i
    }
}

impl StateFeedback for Lqi {
    // `&self.ls * x`: by reference on purpose, the by-value `Mul` copies the
    // matrix each call.
    #[inline]
    fn command(&mut self, estimate: &ReducedState, reference: &Reference) -> Command {
        self.command_with_offset(estimate, reference, &Input::zeros())
    }

    #[allow(clippy::op_ref)]
    #[inline]
    fn command_with_offset(
        &mut self,
        estimate: &ReducedState,
        reference: &Reference,
        offset: &Input,
    ) -> Command {
        let trig = EulerTrig::new(estimate[0], estimate[1], estimate[2]);
        let ned_from_body = trig.ned_from_body();
        let v_body = Vector3::new(estimate[3], estimate[4], estimate[5]);
        let v_ned = ned_from_body * v_body;
        let e_psi = wrap_pi(reference.yaw_rad - estimate[2]);
        let e_v = reference.velocity_ned_m_s - v_ned;
        let error = SVector::<f64, NY>::new(e_psi, e_v.x, e_v.y, e_v.z);

        let u = if self.enabled {
            let mut x_fb = estimate - self.x_trim;
            if self.options.reference_in_proportional {
                // output states relative to the reference (ψ error, body velocity error)
                x_fb[2] = -e_psi;
                let r_body = ned_from_body.transpose() * reference.velocity_ned_m_s;
                for i in 0..3 {
                    x_fb[3 + i] = v_body[i] - r_body[i];
                }
            }
            let xi_v_body =
                ned_from_body.transpose() * Vector3::new(self.x_i[1], self.x_i[2], self.x_i[3]);
            let xi_body =
                SVector::<f64, NY>::new(self.x_i[0], xi_v_body.x, xi_v_body.y, xi_v_body.z);
            self.u_trim - &self.ls * x_fb - &self.li * xi_body
        } else {
            self.u_trim
        } + offset;
        let mut u_sat = u;
        let mut saturated = [false; NU];
        for i in 0..NU {
            u_sat[i] = u[i].clamp(self.limits.min[i], self.limits.max[i]);
            saturated[i] = u_sat[i] != u[i];
        }
        // integral action (14.29)
        if !(self.options.anti_windup && saturated.iter().any(|&b| b)) {
            self.x_i += error;
        }
        Command {
            u: u_sat,
            saturated,
            tracking_error: error,
            integral: self.x_i,
        }
    }

    fn reset(&mut self) {
        self.x_i = SVector::zeros();
    }
}
