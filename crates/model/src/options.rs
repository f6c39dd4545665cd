//! Model presets as data (MODEL.md §11, DESIGN.md "Model presets").
//!
//! * [`Preset::Physical`] (default): the printed equations, including the
//!   body-acceleration flap torques (6.36)/(6.40), physical stabilizer-bar
//!   velocities (normalised by R), front-plane velocity `w − q·κh,fp` per
//!   (7.62), drag torques per (7.64), physical wind sign
//!   (`v_air = v_body − body_from_ned · wind_ned`), converged inflow.
//! * [`Preset::Thesis`]: what the thesis implementation computed (MODEL.md
//!   §11 items 3–5): no body-acceleration flap torques (6.36) and no hub
//!   normal acceleration hz̈ in (6.40) (its velocity products −hẋ·q + hẏ·p
//!   stay), stabilizer-bar velocities scaled by Ro/R, front-plane
//!   `+q·κh,fp`, wind added to the body velocity ((14.46)), converged inflow.
//!
//! The thesis inflow *iteration* (items 1–2) is not a preset but an
//! [`InflowMode`] chosen per derivative call, because it needs the inflow
//! ratios to start from.

use std::str::FromStr;

/// How the wind enters the aerodynamic velocity.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WindSign {
    /// `v_air = v_body − body_from_ned · wind_ned` (wind = air-mass velocity).
    Physical,
    /// `v_air = v_body + body_from_ned · wind_ned`, thesis (14.46).
    Thesis,
}

/// Which radius normalises the translational velocities seen by the
/// stabilizer-bar paddles (MODEL.md §6.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SbVelocityScale {
    /// Physical: the paddles see the hub velocities (normalised by R).
    Physical,
    /// Thesis implementation: velocities scaled by Ro/R (R replaced by Ro in
    /// (6.14)/(6.17)), reproducing Appendix E.
    OuterRadius,
}

/// Sign of the pitch-rate term in the front-plane velocity (7.62).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrontPlaneQ {
    /// `w − q·κh,fp`: the printed (7.62) and the kinematics of a point forward of the CM.
    Printed,
    /// `w + q·κh,fp`: what Appendix E shows the thesis implementation used.
    Thesis,
}

impl FrontPlaneQ {
    /// The sign s in `w + s·q·κh,fp`.
    pub fn sign(self) -> f64 {
        match self {
            FrontPlaneQ::Printed => -1.0,
            FrontPlaneQ::Thesis => 1.0,
        }
    }
}

/// The modelling choices that distinguish the presets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModelOptions {
    /// Include the body angular-acceleration torques (6.36) and the hub normal
    /// acceleration hz̈ of the body normal torque (6.40) in the flapping
    /// equations. The velocity-product part of (6.40), mb·(−hẋ·q + hẏ·p), is
    /// included either way (MODEL.md §11 item 3: the thesis implementation
    /// dropped only the acceleration terms).
    pub flap_accel: bool,
    /// Stabilizer-bar velocity normalisation.
    pub sb_velocity: SbVelocityScale,
    /// Front-plane pitch-rate sign.
    pub front_plane_q: FrontPlaneQ,
    /// Wind sign convention.
    pub wind: WindSign,
}

/// A named set of [`ModelOptions`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Preset {
    /// Printed equations, physically consistent (default).
    #[default]
    Physical,
    /// The equations the thesis implementation used (MODEL.md §11 items 3–5).
    Thesis,
}

impl Preset {
    /// The options of this preset.
    pub fn options(self) -> ModelOptions {
        match self {
            Preset::Physical => ModelOptions {
                flap_accel: true,
                sb_velocity: SbVelocityScale::Physical,
                front_plane_q: FrontPlaneQ::Printed,
                wind: WindSign::Physical,
            },
            Preset::Thesis => ModelOptions {
                flap_accel: false,
                sb_velocity: SbVelocityScale::OuterRadius,
                front_plane_q: FrontPlaneQ::Thesis,
                wind: WindSign::Thesis,
            },
        }
    }

    /// The preset's name as used on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Physical => "physical",
            Preset::Thesis => "thesis",
        }
    }
}

/// Error for an unknown preset name.
#[derive(Debug, Clone, thiserror::Error)]
#[error("unknown model preset `{0}` (expected `physical` or `thesis`)")]
pub struct UnknownPreset(pub String);

impl FromStr for Preset {
    type Err = UnknownPreset;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "physical" => Ok(Preset::Physical),
            "thesis" => Ok(Preset::Thesis),
            other => Err(UnknownPreset(other.to_string())),
        }
    }
}

/// How the inflow ratios are obtained in one derivative evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum InflowMode {
    /// Solve (7.33)/(7.56) to convergence; flapping and forces use the same λ.
    Converged,
    /// As `Converged`, with the solver's Newton iteration started from the
    /// given ratios (e.g. the previous step's): the same converged root, fewer
    /// iterations. For simulation loops.
    ConvergedFrom {
        /// Main-rotor λ to start from.
        lambda_mr_hint: f64,
        /// Tail-rotor λ to start from.
        lambda_tr_hint: f64,
    },
    /// Emulate the thesis implementation (MODEL.md §8, §11 items 1–2): the
    /// flapping uses the given λ (carried as a state in the thesis), and the
    /// forces use λ after `iterations` plain Newton–Raphson steps (7.33)/(D.32)
    /// and (7.56)/(D.41) started from it. `iterations = 7` reproduces Appendix E.
    ThesisIteration {
        /// Main-rotor inflow ratio to start from.
        lambda_mr_in: f64,
        /// Tail-rotor inflow ratio to start from.
        lambda_tr_in: f64,
        /// Number of plain Newton–Raphson steps.
        iterations: u32,
    },
}

impl InflowMode {
    /// [`InflowMode::ThesisIteration`], checked: at least one Newton–Raphson
    /// step and finite starting ratios (the derivative rejects the same
    /// values when the variant is built directly).
    pub fn thesis_iteration(
        lambda_mr_in: f64,
        lambda_tr_in: f64,
        iterations: u32,
    ) -> Result<InflowMode, crate::model::ModelError> {
        use crate::model::ModelError;
        if iterations == 0 {
            return Err(ModelError::ZeroInflowIterations);
        }
        for (name, value) in [
            ("lambda_mr_in", lambda_mr_in),
            ("lambda_tr_in", lambda_tr_in),
        ] {
            if !value.is_finite() {
                return Err(ModelError::NonFinite {
                    what: "inflow",
                    name,
                    value,
                });
            }
        }
        Ok(InflowMode::ThesisIteration {
            lambda_mr_in,
            lambda_tr_in,
            iterations,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_parse_and_differ_where_documented() {
        assert_eq!("thesis".parse::<Preset>().unwrap(), Preset::Thesis);
        assert!("Thesis".parse::<Preset>().is_err());
        let p = Preset::Physical.options();
        let t = Preset::Thesis.options();
        assert!(p.flap_accel && !t.flap_accel);
        assert_eq!(p.front_plane_q.sign(), -1.0);
        assert_eq!(t.front_plane_q.sign(), 1.0);
        assert_ne!(p.wind, t.wind);
        assert_ne!(p.sb_velocity, t.sb_velocity);
        assert_eq!(Preset::default(), Preset::Physical);
    }

    #[test]
    fn zero_thesis_inflow_iterations_is_a_typed_error() {
        use crate::model::ModelError;
        assert!(matches!(
            InflowMode::thesis_iteration(-0.04, -0.05, 0),
            Err(ModelError::ZeroInflowIterations)
        ));
        assert!(matches!(
            InflowMode::thesis_iteration(f64::NAN, -0.05, 7),
            Err(ModelError::NonFinite { .. })
        ));
        assert!(InflowMode::thesis_iteration(-0.04, -0.05, 7).is_ok());
    }
}
