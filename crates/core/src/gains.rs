//! The gains the flight software flies, as fixed-size matrices.
//!
//! A [`GainSet`] is the product of the off-board design (LQR with integral
//! action (14.28)–(14.34) and the steady-state Kalman predictor (15.8)) at
//! one operating point: the trim it linearised about, the discrete model
//! (Φs, Γs) the predictor propagates, and the gains. The design crate builds
//! it and reads/writes it as `gains.json`; the core only checks and flies it.

use crate::error::CoreError;
use crate::state::{Input, NM, NU, NX_REDUCED, NY, ReducedState};
use nalgebra::SMatrix;

/// How the LQI law is wired (the thesis's options and two extensions).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LqiOptions {
    /// Integral action (14.28)–(14.34); off: the proportional LQR of §14.3.3.
    pub integral_action: bool,
    /// The reference enters the proportional path too (output states fed
    /// back relative to the reference); off: only through the integrators,
    /// as the thesis's Figure 14.4.
    pub reference_in_proportional: bool,
    /// Conditional integration: integrators hold while a servo saturates.
    pub anti_windup: bool,
}

/// Everything the core needs to fly one design point.
#[derive(Debug, Clone, PartialEq)]
pub struct GainSet {
    /// Controller sample time Ts (s) the design was discretised at.
    pub sample_time_s: f64,
    /// Pincer α of the design (14.22).
    pub alpha: f64,
    /// Trim state (absolute, reduced 27-state).
    pub x_trim: ReducedState,
    /// Trim servo commands.
    pub u_trim: Input,
    /// Φs, the discrete state transition (27×27).
    pub phi: SMatrix<f64, NX_REDUCED, NX_REDUCED>,
    /// Γs, the discrete input matrix (27×4).
    pub gamma: SMatrix<f64, NX_REDUCED, NU>,
    /// State-feedback gain Ls,α(0) (4×27), (14.34).
    pub ls: SMatrix<f64, NU, NX_REDUCED>,
    /// Integral gain Li,α(0) (4×4), (14.34).
    pub li: SMatrix<f64, NU, NY>,
    /// Kalman predictor gain K(0) (27×9), (15.8).
    pub k: SMatrix<f64, NX_REDUCED, NM>,
    /// How the law is wired.
    pub options: LqiOptions,
}

impl GainSet {
    /// Check that the gain set can be flown: a positive finite sample time,
    /// finite α in (0, ∞), and every matrix entry finite.
    pub fn check(&self) -> Result<(), CoreError> {
        if !(self.sample_time_s.is_finite() && self.sample_time_s > 0.0) {
            return Err(CoreError::InvalidGains {
                what: "sample_time_s",
                rule: "must be finite and > 0",
            });
        }
        if !(self.alpha.is_finite() && self.alpha > 0.0) {
            return Err(CoreError::InvalidGains {
                what: "alpha",
                rule: "must be finite and > 0",
            });
        }
        let finite = |s: &[f64]| s.iter().all(|v| v.is_finite());
        for (what, ok) in [
            ("x_trim", finite(self.x_trim.as_slice())),
            ("u_trim", finite(self.u_trim.as_slice())),
            ("phi", finite(self.phi.as_slice())),
            ("gamma", finite(self.gamma.as_slice())),
            ("ls", finite(self.ls.as_slice())),
            ("li", finite(self.li.as_slice())),
            ("k", finite(self.k.as_slice())),
        ] {
            if !ok {
                return Err(CoreError::InvalidGains {
                    what,
                    rule: "entries must be finite",
                });
            }
        }
        Ok(())
    }
}

/// The servo command range `[S_min, S_max]` per input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoLimits {
    /// Lower limits.
    pub min: Input,
    /// Upper limits.
    pub max: Input,
}

impl ServoLimits {
    /// Check every limit is finite and `min < max`.
    pub fn check(&self) -> Result<(), CoreError> {
        for i in 0..NU {
            if !(self.min[i].is_finite() && self.max[i].is_finite() && self.min[i] < self.max[i]) {
                return Err(CoreError::InvalidGains {
                    what: "servo limits",
                    rule: "must be finite with min < max",
                });
            }
        }
        Ok(())
    }
}
