//! What the ArduPilot and PX4 mappings share: the Bergen Twin's servo
//! commands from blade pitch (its servo gains and command limits), and the
//! inversion of a three-servo swashplate mixer.

use helicon_config::ConfigError;
use helicon_core::state::Input;
use helicon_model::Params;
use nalgebra::Matrix3;

/// The model's servo gains (rad of blade pitch per command unit) and
/// command limits, for `S_col S_lat S_lon S_tr`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ModelServos {
    k_rad: [f64; 4],
    s_min: [f64; 4],
    s_max: [f64; 4],
}

impl ModelServos {
    /// The servos of `params`; a zero or non-finite gain is an error
    /// naming `file` and `section`.
    pub(crate) fn new(params: &Params, file: &str, section: &str) -> Result<Self, ConfigError> {
        let k_rad = [
            params.servos[0].gain_rad,
            params.servos[1].gain_rad,
            params.servos[2].gain_rad,
            params.servos[3].gain_rad,
        ];
        for (i, k) in k_rad.iter().enumerate() {
            if !(k.is_finite() && k.abs() > 1e-9) {
                return Err(ConfigError::invalid(
                    file,
                    format!("{section}.(model) servos[{i}].gain_rad"),
                    *k,
                    "a non-zero servo gain: the model's inputs cannot be found from blade pitch",
                ));
            }
        }
        let lim = params.servo_limits();
        Ok(ModelServos {
            k_rad,
            s_min: [lim.min[0], lim.min[1], lim.min[2], lim.min[3]],
            s_max: [lim.max[0], lim.max[1], lim.max[2], lim.max[3]],
        })
    }

    /// The inputs for the blade pitch `[θ0, A1, B1, θ_tr]` (deg), within
    /// the command limits.
    pub(crate) fn input_from_deg(&self, deg: &[f64; 4]) -> Input {
        Input::from_fn(|i, _| {
            (deg[i].to_radians() / self.k_rad[i]).clamp(self.s_min[i], self.s_max[i])
        })
    }

    /// The blade pitch of the inputs `u` (deg; no limits).
    pub(crate) fn deg_of(&self, u: &Input) -> [f64; 4] {
        [0, 1, 2, 3].map(|i| (u[i] * self.k_rad[i]).to_degrees())
    }

    /// Command units per radian of blade pitch of input `i`.
    pub(crate) fn per_rad(&self, i: usize) -> f64 {
        1.0 / self.k_rad[i]
    }
}

/// The inverse of a three-servo mixer (each row one servo's factors),
/// `None` when it is (nearly) singular: servos that cannot tilt the plate
/// both ways and move it up and down.
pub(crate) fn invert(mix: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    if mix.determinant().abs() > 1e-3 {
        mix.try_inverse()
    } else {
        None
    }
}

/// A blade pitch linear in a normalized command: `lo_deg` at `lo`, `hi_deg` at `hi`.
pub(crate) fn linear_deg(x: f64, lo: f64, hi: f64, lo_deg: f64, hi_deg: f64) -> f64 {
    lo_deg + (x - lo) / (hi - lo) * (hi_deg - lo_deg)
}
