//! State and input layout (thesis (4.7), (12.2), (14.2)).
//!
//! The full state has 30 entries: NED position, 3-2-1 Euler angles, body (FRD)
//! velocity and rates, main-rotor flapping and its rates, stabilizer-bar
//! flapping and its rates, the four servo angles and their rates. The reduced
//! state used by trim and linearization (27 entries) drops the position.
//! The names are the exact strings used in every file format.

use nalgebra::SVector;

/// Number of full states (thesis (4.7)).
pub const NX: usize = 30;
/// Number of reduced states (no position), thesis (12.2)/(14.2).
pub const NX_REDUCED: usize = 27;
/// Number of inputs (servo commands).
pub const NU: usize = 4;

/// Full 30-state vector, ordered as [`STATE_NAMES`].
pub type State = SVector<f64, NX>;
/// Reduced 27-state vector, ordered as [`REDUCED_STATE_NAMES`].
pub type ReducedState = SVector<f64, NX_REDUCED>;
/// Input vector `[S_col, S_lat, S_lon, S_tr]` (dimensionless servo commands).
pub type Input = SVector<f64, NU>;

/// Names of the 30 states, in order. Units: m, rad, m/s, rad/s.
pub const STATE_NAMES: [&str; NX] = [
    "x",
    "y",
    "z",
    "phi",
    "theta",
    "psi",
    "u",
    "v",
    "w",
    "p",
    "q",
    "r",
    "a0",
    "a1",
    "b1",
    "a0_dot",
    "a1_dot",
    "b1_dot",
    "a1sb",
    "b1sb",
    "a1sb_dot",
    "b1sb_dot",
    "theta0",
    "A1",
    "B1",
    "theta_tr",
    "theta0_dot",
    "A1_dot",
    "B1_dot",
    "theta_tr_dot",
];

/// Names of the 27 reduced states (the full list without `x y z`), derived
/// from [`STATE_NAMES`].
pub const REDUCED_STATE_NAMES: [&str; NX_REDUCED] = {
    let mut out = [""; NX_REDUCED];
    let mut i = 0;
    while i < NX_REDUCED {
        out[i] = STATE_NAMES[i + REDUCED_OFFSET];
        i += 1;
    }
    out
};

/// Units of the 30 states, in order (SI).
pub const STATE_UNITS: [&str; NX] = [
    "m", "m", "m", "rad", "rad", "rad", "m/s", "m/s", "m/s", "rad/s", "rad/s", "rad/s", "rad",
    "rad", "rad", "rad/s", "rad/s", "rad/s", "rad", "rad", "rad/s", "rad/s", "rad", "rad", "rad",
    "rad", "rad/s", "rad/s", "rad/s", "rad/s",
];

/// Names of the 4 inputs, in order (dimensionless servo commands).
pub const INPUT_NAMES: [&str; NU] = ["S_col", "S_lat", "S_lon", "S_tr"];

/// Number of measured states (15.2): `[φ θ ψ u v w p q r]`, the first nine
/// reduced states.
pub const NM: usize = 9;
/// The nine measured states (15.2), absolute values.
pub type MeasuredStates = SVector<f64, NM>;
/// Number of controlled outputs (14.4): ψ, u, v, w.
pub const NY: usize = 4;
/// Indices of the controlled outputs ψ, u, v, w in the reduced state (14.4).
pub const OUTPUT_STATES: [usize; NY] = [
    ix::PSI - REDUCED_OFFSET,
    ix::U - REDUCED_OFFSET,
    ix::V - REDUCED_OFFSET,
    ix::W - REDUCED_OFFSET,
];

/// Index of each state in the full 30-vector. Subtract [`REDUCED_OFFSET`] for
/// the reduced 27-vector.
#[allow(missing_docs)]
pub mod ix {
    pub const X: usize = 0;
    pub const Y: usize = 1;
    pub const Z: usize = 2;
    pub const PHI: usize = 3;
    pub const THETA: usize = 4;
    pub const PSI: usize = 5;
    pub const U: usize = 6;
    pub const V: usize = 7;
    pub const W: usize = 8;
    pub const P: usize = 9;
    pub const Q: usize = 10;
    pub const R: usize = 11;
    pub const A0: usize = 12;
    pub const A1: usize = 13;
    pub const B1: usize = 14;
    pub const A0_DOT: usize = 15;
    pub const A1_DOT: usize = 16;
    pub const B1_DOT: usize = 17;
    pub const A1SB: usize = 18;
    pub const B1SB: usize = 19;
    pub const A1SB_DOT: usize = 20;
    pub const B1SB_DOT: usize = 21;
    pub const THETA0: usize = 22;
    pub const A1_SWASH: usize = 23;
    pub const B1_SWASH: usize = 24;
    pub const THETA_TR: usize = 25;
    pub const THETA0_DOT: usize = 26;
    pub const A1_SWASH_DOT: usize = 27;
    pub const B1_SWASH_DOT: usize = 28;
    pub const THETA_TR_DOT: usize = 29;
}

/// Index of each input in the input vector.
#[allow(missing_docs)]
pub mod iu {
    pub const S_COL: usize = 0;
    pub const S_LAT: usize = 1;
    pub const S_LON: usize = 2;
    pub const S_TR: usize = 3;
}

/// Offset between full and reduced indices (the three position states).
pub const REDUCED_OFFSET: usize = 3;

/// Index of a state by name in the full 30-vector.
pub fn state_index(name: &str) -> Option<usize> {
    STATE_NAMES.iter().position(|n| *n == name)
}

/// Index of an input by name.
pub fn input_index(name: &str) -> Option<usize> {
    INPUT_NAMES.iter().position(|n| *n == name)
}

/// The reduced 27-state part of a full state (drops `x y z`).
pub fn reduce(x: &State) -> ReducedState {
    ReducedState::from_fn(|i, _| x[i + REDUCED_OFFSET])
}

/// A full state from a reduced one and a NED position in metres.
pub fn expand(xr: &ReducedState, position_ned_m: [f64; 3]) -> State {
    State::from_fn(|i, _| {
        if i < REDUCED_OFFSET {
            position_ned_m[i]
        } else {
            xr[i - REDUCED_OFFSET]
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reduced_names_are_full_names_without_position() {
        assert_eq!(&STATE_NAMES[REDUCED_OFFSET..], &REDUCED_STATE_NAMES[..]);
        assert_eq!(state_index("theta_tr_dot"), Some(ix::THETA_TR_DOT));
        assert_eq!(state_index("A1"), Some(ix::A1_SWASH));
        assert_eq!(input_index("S_tr"), Some(iu::S_TR));
        assert_eq!(state_index("nope"), None);
    }

    #[test]
    fn reduce_expand_roundtrip() {
        let x = State::from_fn(|i, _| i as f64);
        let xr = reduce(&x);
        assert_eq!(xr[0], 3.0);
        assert_eq!(expand(&xr, [0.0, 1.0, 2.0]), x);
    }
}
