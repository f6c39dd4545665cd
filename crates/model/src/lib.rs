//! # helicon-model
//!
//! The first-principles nonlinear model of a miniature helicopter from the thesis
//! *Nonlinear Modeling and Optimal Control of a Miniature Autonomous Helicopter*
//! (Aalborg University, 2006), chapters 4–10 and appendices B–D, with the
//! readings and corrections documented in docs/model.md.
//!
//! The blocks of thesis Figure 4.4, one module each:
//! [`actuators`] (servos), [`flapping`] (main rotor and stabilizer bar),
//! [`rotor`] (blade-element forces and torques) with [`inflow`],
//! [`tail_rotor`], [`drag`], and [`rigid_body`]; [`model`] assembles them into
//! `ẋ = f(x, u, wind_ned)` and [`integrate`] steps it with RK4.
//! [`params`] holds the constants, [`options`] the presets, [`state`] the
//! layout and names, [`frames`] the rotations.
//!
//! ```
//! use helicon_model::{Model, Preset, State, Input};
//! let model = Model::bergen_twin(Preset::Physical);
//! let (xdot, aux) = model
//!     .derivative(&State::zeros(), &Input::zeros(), &nalgebra::Vector3::zeros())
//!     .unwrap();
//! assert!(xdot.iter().all(|v| v.is_finite()));
//! assert!(aux.lambda_mr.is_finite());
//! ```

pub mod actuators;
/// The one configuration error shape (`helicon-config`), re-exported where it was first defined.
pub mod config_error {
    pub use helicon_config::*;
}
pub mod drag;
pub mod drivetrain;
pub mod flapping;
pub mod ground;
pub mod ground_effect;
pub mod gyro;
pub mod inflow;
pub mod integrate;
pub mod landing_gear;
pub mod linearize;
pub mod model;
pub mod options;
pub mod params;
pub mod rigid_body;
pub mod rotor;
pub mod tail_rotor;
pub mod trim;

/// Frames and rotations (thesis chapter 9), shared with the flight software core.
pub use helicon_core::frames;
/// The state layout (thesis (4.7), (12.2)), shared with the flight software core.
pub use helicon_core::state;

pub use config_error::ConfigError;
pub use model::{Aux, Model, ModelError, NX_PLANT, PlantState, PlantVector};
pub use options::{InflowMode, ModelOptions, Preset};
pub use params::{ParamError, Params};
pub use state::{
    INPUT_NAMES, Input, NU, NX, NX_REDUCED, REDUCED_STATE_NAMES, ReducedState, STATE_NAMES, State,
};
