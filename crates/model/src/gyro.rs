//! The optional yaw-rate gyro block (thesis §3.1.1): the stock helicopter's
//! heading-hold gyro between the tail input and the tail servo, so that the
//! tail input becomes a yaw-rate command.
//!
//! The block is a discrete PI run at the control rate (sample time `ts_s`),
//! the way a stock gyro's microcontroller runs it:
//!
//! ```text
//! r_cmd  = max_rate · (S_tr,in − S_mid) / S_half        (S_mid, S_half: tail servo range)
//! e_k    = r_cmd,k − r_k                                 (yaw-rate error, rad/s)
//! S_tr,k = clamp(I_k + Kp·e_k, S_min, S_max)             (tail-servo command)
//! I_k+1  = clamp(I_k + Ki·Ts·e_k, S_min, S_max)          (heading-hold integrator)
//! ```
//!
//! Its one state, the integrator `I` (in tail-servo units), is carried beside
//! the plant state; the model's 30-state layout is unchanged. At hover the
//! integrator holds the trim tail-servo command and the tail input sits at
//! mid-range (0 rad/s commanded): [`YawGyroBlock::at_trim`].

use crate::params::{Params, YawGyro};
use nalgebra::DMatrix;

/// A discrete linear model of the wrong shape for [`YawGyroBlock::augment_discrete`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "yaw gyro augmentation: expected Φ n×n and Γ n×4 with the yaw rate at row {r_index} < n, \
     found Φ {phi_rows}×{phi_cols} and Γ {gamma_rows}×{gamma_cols}"
)]
pub struct AugmentShapeError {
    /// Rows of Φ.
    pub phi_rows: usize,
    /// Columns of Φ.
    pub phi_cols: usize,
    /// Rows of Γ.
    pub gamma_rows: usize,
    /// Columns of Γ.
    pub gamma_cols: usize,
    /// The yaw-rate index given.
    pub r_index: usize,
}

/// The running yaw-rate gyro: gains, ranges and its integrator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct YawGyroBlock {
    gyro: YawGyro,
    s_min: f64,
    s_max: f64,
    ts_s: f64,
    /// The heading-hold integrator (tail-servo units).
    pub integral: f64,
}

impl YawGyroBlock {
    /// The block of `params` (when `yaw_gyro.enabled`) at the equilibrium
    /// where it outputs the tail-servo command `trim_tail_servo` with zero
    /// yaw-rate error; `None` when the block is off. `params` are validated
    /// ([`Params::validate`]), so the ranges and gains are finite.
    pub fn at_trim(params: &Params, ts_s: f64, trim_tail_servo: f64) -> Option<YawGyroBlock> {
        if !params.yaw_gyro.is_enabled() {
            return None;
        }
        let servo = &params.servos[3];
        Some(YawGyroBlock {
            gyro: params.yaw_gyro,
            s_min: servo.s_min,
            s_max: servo.s_max,
            ts_s,
            integral: trim_tail_servo.clamp(servo.s_min, servo.s_max),
        })
    }

    /// The yaw-rate command at the ends of the tail input range (rad/s).
    pub fn max_rate_rad_s(&self) -> f64 {
        self.gyro.max_rate_rad_s
    }

    /// Yaw-rate command (rad/s) per unit of tail input: `max_rate / S_half`.
    pub fn rate_per_input_rad_s(&self) -> f64 {
        self.gyro.max_rate_rad_s / (0.5 * (self.s_max - self.s_min))
    }

    /// The tail input at mid-range: 0 rad/s commanded (the hover trim input).
    pub fn mid_input(&self) -> f64 {
        0.5 * (self.s_min + self.s_max)
    }

    /// The yaw-rate command (rad/s) a tail input stands for.
    pub fn rate_command_rad_s(&self, tail_input: f64) -> f64 {
        (tail_input - self.mid_input()) * self.rate_per_input_rad_s()
    }

    /// The tail input that commands `r_cmd_rad_s`.
    pub fn input_for_rate(&self, r_cmd_rad_s: f64) -> f64 {
        self.mid_input() + r_cmd_rad_s / self.rate_per_input_rad_s()
    }

    /// One control sample: from the tail input (yaw-rate command) and the
    /// measured yaw rate `r_rad_s` (body, FRD), the tail-servo command; the
    /// integrator advances by one sample. Non-finite inputs leave the
    /// integrator unchanged and hold its value as the output.
    pub fn step(&mut self, tail_input: f64, r_rad_s: f64) -> f64 {
        let e = self.rate_command_rad_s(tail_input) - r_rad_s;
        if !e.is_finite() {
            return self.integral;
        }
        let out = (self.integral + self.gyro.kp_s * e).clamp(self.s_min, self.s_max);
        self.integral =
            (self.integral + self.gyro.ki * self.ts_s * e).clamp(self.s_min, self.s_max);
        out
    }

    /// The helicopter as flown with the gyro, linear and discrete: the ZOH
    /// model (Φ, Γ) of the plant (n states, inputs `[S_col, S_lat, S_lon,
    /// S_tr]`, the yaw rate at row `r_index`) closed by the block
    /// (unsaturated), with the integrator appended as state n and the tail
    /// input becoming the yaw-rate command input. Deviations from the trim:
    /// `[x; I]_k+1 = Φa [x; I]_k + Γa [S_col, S_lat, S_lon, S_tr,in]_k` with
    ///
    /// ```text
    /// Φa = [ Φ − Kp Γtr e_rᵀ    Γtr ]    Γa = [ Γcol Γlat Γlon   Kp c Γtr ]
    ///      [ −Ki Ts e_rᵀ          1  ]         [  0    0    0     Ki Ts c  ]
    /// ```
    ///
    /// (c = [`Self::rate_per_input_rad_s`], Γtr Γ's tail column).
    pub fn augment_discrete(
        &self,
        phi: &DMatrix<f64>,
        gamma: &DMatrix<f64>,
        r_index: usize,
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), AugmentShapeError> {
        let n = phi.nrows();
        if phi.ncols() != n || gamma.nrows() != n || gamma.ncols() != 4 || r_index >= n {
            return Err(AugmentShapeError {
                phi_rows: n,
                phi_cols: phi.ncols(),
                gamma_rows: gamma.nrows(),
                gamma_cols: gamma.ncols(),
                r_index,
            });
        }
        let (kp, ki, ts) = (self.gyro.kp_s, self.gyro.ki, self.ts_s);
        let c = self.rate_per_input_rad_s();
        let g_tr = gamma.column(3);
        let mut phi_a = DMatrix::zeros(n + 1, n + 1);
        phi_a.view_mut((0, 0), (n, n)).copy_from(phi);
        for i in 0..n {
            phi_a[(i, r_index)] -= kp * g_tr[i];
            phi_a[(i, n)] = g_tr[i];
        }
        phi_a[(n, r_index)] = -ki * ts;
        phi_a[(n, n)] = 1.0;
        let mut gamma_a = DMatrix::zeros(n + 1, 4);
        gamma_a
            .view_mut((0, 0), (n, 3))
            .copy_from(&gamma.columns(0, 3));
        for i in 0..n {
            gamma_a[(i, 3)] = kp * c * g_tr[i];
        }
        gamma_a[(n, 3)] = ki * ts * c;
        Ok((phi_a, gamma_a))
    }

    /// The block's linear discrete closed loop around the scalar yaw
    /// dynamics ṙ = N_r·r + N_δ·S_tr (ZOH at `ts_s`), with state `[r, I]` and
    /// input the commanded yaw rate: `(Φ, Γ)` with `z_k+1 = Φ z_k + Γ r_cmd,k`.
    /// Its eigenvalues are the block's design poles.
    pub fn scalar_closed_loop(&self, n_r: f64, n_delta: f64) -> ([[f64; 2]; 2], [f64; 2]) {
        let ts = self.ts_s;
        let a = (n_r * ts).exp();
        // ZOH input gain ∫0^Ts e^{N_r s} ds · N_δ (the limit Ts·N_δ for N_r → 0).
        let b = if (n_r * ts).abs() < 1e-12 {
            ts * n_delta
        } else {
            (a - 1.0) / n_r * n_delta
        };
        let (kp, ki) = (self.gyro.kp_s, self.gyro.ki);
        // S = I + Kp (r_cmd − r); r+ = a r + b S; I+ = I + Ki Ts (r_cmd − r)
        ([[a - b * kp, b], [-ki * ts, 1.0]], [b * kp, ki * ts])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block() -> YawGyroBlock {
        let mut p = Params::bergen_twin();
        p.yaw_gyro.enabled = 1.0;
        YawGyroBlock::at_trim(&p, 0.0025, 0.1).unwrap_or_else(|| unreachable!())
    }

    #[test]
    fn off_by_default_and_mid_input_commands_zero_rate() {
        assert!(YawGyroBlock::at_trim(&Params::bergen_twin(), 0.0025, 0.1).is_none());
        let b = block();
        assert_eq!(b.rate_command_rad_s(b.mid_input()), 0.0);
        // S_max commands +max_rate
        assert!((b.rate_command_rad_s(0.62) - 3.0).abs() < 1e-12);
        assert!(
            (b.input_for_rate(1.0) - b.mid_input() - 1.0 / b.rate_per_input_rad_s()).abs() < 1e-15
        );
    }

    #[test]
    fn at_equilibrium_the_integrator_holds_the_trim_servo() {
        let mut b = block();
        for _ in 0..100 {
            assert_eq!(b.step(b.mid_input(), 0.0), 0.1);
        }
        assert_eq!(b.integral, 0.1);
    }

    #[test]
    fn output_and_integrator_stay_in_the_servo_range_and_nan_is_held() {
        let mut b = block();
        for _ in 0..10_000 {
            let s = b.step(0.62, -10.0);
            assert!((-0.37..=0.62).contains(&s));
        }
        assert_eq!(b.integral, 0.62);
        assert_eq!(b.step(f64::NAN, 0.0), 0.62);
        assert_eq!(b.integral, 0.62);
    }
}
