//! The optional ground effect on the main rotor (Cheeseman and Bennett,
//! 1955): the ground, seen as the rotor's mirror image (a source under the
//! ground), slows the flow through a rotor at height z above it. Their
//! result, for a rotor of radius R at constant power,
//!
//! ```text
//! T_IGE / T_OGE = 1 / (1 − (R / 4z)²)
//! ```
//!
//! comes from the induced velocity at a given thrust being reduced by the
//! factor k_G = 1 − (R/4z)² (the power T·vi at that thrust falls by k_G, so
//! at the power of the rotor out of ground effect the thrust is T/k_G).
//! The model applies it where the closed form does: to the induced
//! velocity of momentum theory (7.29)–(7.33), whose induced part
//! C_T / (2√(μ² + λ²)) is multiplied by k_G. The blade-element thrust
//! then rises at a fixed collective through the smaller inflow, and the
//! induced power at a fixed thrust falls by k_G exactly.
//!
//! z is the main-rotor hub's height above the ground plane (along its
//! normal). The formula is valid for z/R ≳ 0.5 (at z/R = 0.25 it diverges);
//! below `min_height_ratio` (≥ 0.5) the height is clamped to it: k_G ≥ 0.75
//! at the default, a thrust gain of at most 1/0.75 = 1.333.

/// k_G = 1 − (R / 4z)² at hub height `height_m` above the ground, with
/// z/R clamped to at least `min_height_ratio`: the factor on the induced
/// velocity (1 far from the ground). Returns (k_G, the z/R used).
#[inline]
pub fn inflow_factor(height_m: f64, radius_m: f64, min_height_ratio: f64) -> (f64, f64) {
    let ratio = (height_m / radius_m).max(min_height_ratio);
    let q = 1.0 / (4.0 * ratio);
    (1.0 - q * q, ratio)
}

/// The closed form T_IGE / T_OGE = 1 / (1 − (R/4z)²) at z/R = `height_ratio`.
pub fn thrust_ratio_closed_form(height_ratio: f64) -> f64 {
    let q = 1.0 / (4.0 * height_ratio);
    1.0 / (1.0 - q * q)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factor_values_and_clamp() {
        // z/R = 1: 1 − 1/16
        assert_eq!(inflow_factor(1.0, 1.0, 0.5), (1.0 - 1.0 / 16.0, 1.0));
        // below the clamp the factor is the one at z/R = 0.5
        assert_eq!(inflow_factor(0.1, 1.0, 0.5), (0.75, 0.5));
        assert!((inflow_factor(1e6, 1.0, 0.5).0 - 1.0).abs() < 1e-12);
        assert_eq!(thrust_ratio_closed_form(0.5), 1.0 / 0.75);
    }
}
