//! Shared test fixtures: the thesis hover trim read six digits deep.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_model::Input;
use helicon_model::state::{State, ix};

/// MODEL.md §12 "this reading": an independent implementation's hover trim
/// (thesis preset, converged inflow), 6 significant digits.
#[allow(dead_code)]
pub fn six_digit_hover_trim() -> (State, Input, f64, f64) {
    let mut x = State::zeros();
    let vals = [
        (ix::PHI, 5.72781e-2),
        (ix::THETA, -6.58128e-4),
        (ix::A0, 1.60806e-2),
        (ix::A1, 6.40736e-4),
        (ix::B1, 2.32171e-6),
        (ix::A1SB, 5.74145e-4),
        (ix::B1SB, -2.05493e-4),
        (ix::THETA0, 0.129482),
        (ix::A1_SWASH, 2.05493e-4),
        (ix::B1_SWASH, -5.74145e-4),
        (ix::THETA_TR, 0.111433),
    ];
    for (i, v) in vals {
        x[i] = v;
    }
    let u = Input::new(0.184975, 2.93562e-4, -8.20207e-4, 0.159190);
    (x, u, -4.14856e-2, -4.67841e-2)
}
