//! Controller and estimator design from a linear model at a trim (thesis
//! chapters 14 and 15).
//!
//! * Outputs (14.4): y = Hs x = [ψ, u, v, w] (yaw and body velocities).
//! * LQR with integral action (14.28)–(14.34) on the ZOH model (Φs, Γs) at Ts,
//!   with Bryson weights (14.14)–(14.16): Qe = Qy = diag(1/y_max²) (14.23),
//!   (14.35); Qi = `integral_weight`·Qe (14.36); Q2 = diag(1/u_max²) (14.24) or
//!   the retuned (14.27); ρ; and the pincer α from a settling time (14.22).
//! * Steady-state Kalman predictor (15.8) on the nine measured states (15.2)
//!   [φ θ ψ u v w p q r], with Rex = q·I₂₇ and Rey = r·I₉ (15.11)–(15.12).
//!
//! The result, [`Gains`], is plain data: it serialises to JSON so the on-board
//! runtime flies exactly the gains that were simulated.

use helicon_lti::lqr::{alpha_from_settling_time, bryson, dlqr_integral, dlqr_pincer};
use helicon_lti::{LtiError, dlqe};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// Number of controlled outputs (ψ, u, v, w).
pub const NY: usize = 4;
/// Number of measured states (15.2).
pub const NM: usize = 9;
/// Reduced state size.
pub const NXR: usize = 27;
/// Number of inputs.
pub const NUI: usize = 4;
/// Indices of the controlled outputs in the reduced state: ψ, u, v, w (14.4).
pub const OUTPUT_STATES: [usize; NY] = [2, 3, 4, 5];

/// The thesis's retuned input maxima (14.27): S_col, S_lat, S_lon, S_tr.
pub const U_MAX_RETUNED: [f64; 4] = [0.1, 0.7, 0.7, 0.04];
/// The thesis's original input maxima (14.24).
pub const U_MAX_ORIGINAL: [f64; 4] = [0.1, 0.7, 0.7, 0.4];

/// Design settings: the TOML `[controller]` section.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ControllerConfig {
    /// Bryson maximum deviations of the outputs [ψ (rad), u, v, w (m/s)], (14.23).
    pub output_max: [f64; NY],
    /// Bryson maximum deviations of the inputs [S_col, S_lat, S_lon, S_tr], (14.27).
    pub input_max: [f64; NUI],
    /// ρ, the output/input weighting (14.17).
    pub rho: f64,
    /// Settling time (s) for the pincer α (14.22); `None` for α = 1.
    pub settling_time_s: Option<f64>,
    /// Qi = integral_weight · Qe (14.36).
    pub integral_weight: f64,
    /// Controller sample time Ts (s), (14.5).
    pub sample_time_s: f64,
    /// Rex = process_noise · I₂₇ (15.11).
    pub process_noise: f64,
    /// Rey = measurement_noise · I₉ (15.12).
    pub measurement_noise: f64,
    /// Reference enters the proportional path too (the output states are fed
    /// back relative to the reference); off: the reference acts only through
    /// the integrators, as the thesis's Figure 14.4.
    pub reference_in_proportional: bool,
    /// Anti-windup by conditional integration: the integrators hold while
    /// any servo command is saturated. Off (default) integrates always, as
    /// the thesis's (14.29).
    pub anti_windup: bool,
    /// Integral action (14.28)–(14.34); off gives the proportional LQR of
    /// §14.3.3 (Figure 14.3), u = −Ls,α x with Q1 = Hsᵀ Qy Hs (14.14).
    pub integral_action: bool,
}

impl Default for ControllerConfig {
    /// The thesis's final design: (14.23), (14.27), ρ = 10, ts = 5 s, (14.36),
    /// 400 Hz, (15.11)–(15.12).
    fn default() -> Self {
        ControllerConfig {
            output_max: [3.0; NY],
            input_max: U_MAX_RETUNED,
            rho: 10.0,
            settling_time_s: Some(5.0),
            integral_weight: 1e-4,
            sample_time_s: 0.0025,
            process_noise: 1.0,
            measurement_noise: 1e-3,
            integral_action: true,
            reference_in_proportional: false,
            anti_windup: false,
        }
    }
}

/// Design failures.
#[derive(Debug, thiserror::Error)]
pub enum DesignError {
    /// A setting is out of range.
    #[error("controller setting `{field}` = {value} is invalid: {rule}")]
    Config {
        /// Field name.
        field: &'static str,
        /// Value.
        value: f64,
        /// Rule.
        rule: &'static str,
    },
    /// The linear-algebra design failed.
    #[error("controller design: {0}")]
    Lti(#[from] LtiError),
    /// Matrix dimensions do not match the 27-state model.
    #[error("controller design: {what} has shape {rows}×{cols}, expected {er}×{ec}")]
    Shape {
        /// Matrix.
        what: &'static str,
        /// Rows.
        rows: usize,
        /// Columns.
        cols: usize,
        /// Expected rows.
        er: usize,
        /// Expected columns.
        ec: usize,
    },
    /// Reading or writing a gains file failed.
    #[error("{file}: {message}")]
    File {
        /// File.
        file: String,
        /// Message.
        message: String,
    },
}

impl ControllerConfig {
    /// Check every setting.
    pub fn validate(&self) -> Result<(), DesignError> {
        let pos = |field: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(DesignError::Config {
                    field,
                    value: v,
                    rule: "must be finite and > 0",
                })
            }
        };
        for v in self.output_max {
            pos("output_max", v)?;
        }
        for v in self.input_max {
            pos("input_max", v)?;
        }
        pos("rho", self.rho)?;
        if let Some(t) = self.settling_time_s {
            pos("settling_time_s", t)?;
        }
        if !(self.integral_weight.is_finite() && self.integral_weight >= 0.0) {
            return Err(DesignError::Config {
                field: "integral_weight",
                value: self.integral_weight,
                rule: "must be finite and >= 0",
            });
        }
        pos("sample_time_s", self.sample_time_s)?;
        pos("process_noise", self.process_noise)?;
        pos("measurement_noise", self.measurement_noise)?;
        Ok(())
    }
}

/// Designed gains and the operating point they belong to. Matrices are
/// row-major nested vectors (JSON friendly).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Gains {
    /// Format version.
    pub version: u32,
    /// The settings used.
    pub config: ControllerConfig,
    /// Trim state (27, [`helicon_model::REDUCED_STATE_NAMES`] order).
    pub x_trim: Vec<f64>,
    /// Trim input (4).
    pub u_trim: Vec<f64>,
    /// Pincer α.
    pub alpha: f64,
    /// Φs (27×27).
    pub phi: Vec<Vec<f64>>,
    /// Γs (27×4).
    pub gamma: Vec<Vec<f64>>,
    /// State-feedback gain Ls,α(0) (4×27), (14.34).
    pub ls: Vec<Vec<f64>>,
    /// Integral gain Li,α(0) (4×4), (14.34).
    pub li: Vec<Vec<f64>>,
    /// Kalman predictor gain K(0) (27×9), (15.8).
    pub k: Vec<Vec<f64>>,
    /// Closed-loop (augmented) discrete poles, as [re, im].
    pub closed_loop_poles: Vec<[f64; 2]>,
    /// Estimator-error discrete poles eig(Φ − K Hm), as [re, im].
    pub estimator_poles: Vec<[f64; 2]>,
}

fn rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|i| m.row(i).iter().copied().collect())
        .collect()
}

/// Dense matrix from nested rows, checking the shape.
pub fn from_rows(
    what: &'static str,
    r: &[Vec<f64>],
    er: usize,
    ec: usize,
) -> Result<DMatrix<f64>, DesignError> {
    let cols = r.first().map_or(0, Vec::len);
    if r.len() != er || r.iter().any(|row| row.len() != ec) {
        return Err(DesignError::Shape {
            what,
            rows: r.len(),
            cols,
            er,
            ec,
        });
    }
    if r.iter().flatten().any(|v| !v.is_finite()) {
        return Err(DesignError::Config {
            field: what,
            value: f64::NAN,
            rule: "entries must be finite",
        });
    }
    Ok(DMatrix::from_fn(er, ec, |i, j| r[i][j]))
}

/// Hs (4×27): ψ, u, v, w (14.4).
pub fn output_matrix() -> DMatrix<f64> {
    let mut hs = DMatrix::zeros(NY, NXR);
    for (row, &col) in OUTPUT_STATES.iter().enumerate() {
        hs[(row, col)] = 1.0;
    }
    hs
}

/// Hm (9×27): the first nine reduced states (15.2).
pub fn measurement_matrix() -> DMatrix<f64> {
    let mut hm = DMatrix::zeros(NM, NXR);
    for i in 0..NM {
        hm[(i, i)] = 1.0;
    }
    hm
}

/// Design the controller and estimator for the discrete model (Φs, Γs) at
/// the trim (x_trim, u_trim).
pub fn design(
    phi: &DMatrix<f64>,
    gamma: &DMatrix<f64>,
    x_trim: &[f64],
    u_trim: &[f64],
    config: &ControllerConfig,
) -> Result<Gains, DesignError> {
    config.validate()?;
    if phi.shape() != (NXR, NXR) {
        return Err(DesignError::Shape {
            what: "Phi",
            rows: phi.nrows(),
            cols: phi.ncols(),
            er: NXR,
            ec: NXR,
        });
    }
    if gamma.shape() != (NXR, NUI) {
        return Err(DesignError::Shape {
            what: "Gamma",
            rows: gamma.nrows(),
            cols: gamma.ncols(),
            er: NXR,
            ec: NUI,
        });
    }
    if x_trim.len() != NXR || u_trim.len() != NUI {
        return Err(DesignError::Shape {
            what: "trim",
            rows: x_trim.len(),
            cols: u_trim.len(),
            er: NXR,
            ec: NUI,
        });
    }
    let alpha = match config.settling_time_s {
        Some(ts) => alpha_from_settling_time(config.sample_time_s, ts)?,
        None => 1.0,
    };
    let hs = output_matrix();
    let qe = bryson(&config.output_max)?;
    let qi = &qe * config.integral_weight;
    let q2 = bryson(&config.input_max)?;
    let (ls, li, poles) = if config.integral_action {
        let lqr = dlqr_integral(phi, gamma, &hs, &qe, &qi, &q2, config.rho, alpha)?;
        (lqr.ls, lqr.li, lqr.poles)
    } else {
        let mut q1 = hs.transpose() * &qe * &hs;
        q1 = (&q1 + q1.transpose()) * 0.5;
        let lqr = dlqr_pincer(phi, gamma, &q1, &(q2 * config.rho), None, alpha)?;
        (lqr.k, DMatrix::zeros(NUI, NY), lqr.poles)
    };
    let hm = measurement_matrix();
    let rex = DMatrix::<f64>::identity(NXR, NXR) * config.process_noise;
    let rey = DMatrix::<f64>::identity(NM, NM) * config.measurement_noise;
    let kal = dlqe(phi, None, &hm, &rex, &rey)?;
    Ok(Gains {
        version: 1,
        config: config.clone(),
        x_trim: x_trim.to_vec(),
        u_trim: u_trim.to_vec(),
        alpha,
        phi: rows(phi),
        gamma: rows(gamma),
        ls: rows(&ls),
        li: rows(&li),
        k: rows(&kal.l),
        closed_loop_poles: poles.iter().map(|z| [z.re, z.im]).collect(),
        estimator_poles: kal.poles.iter().map(|z| [z.re, z.im]).collect(),
    })
}

impl Gains {
    /// Write as pretty JSON.
    pub fn save(&self, path: &std::path::Path) -> Result<(), DesignError> {
        let file = path.display().to_string();
        let text = serde_json::to_string_pretty(self).map_err(|e| DesignError::File {
            file: file.clone(),
            message: e.to_string(),
        })?;
        std::fs::write(path, text).map_err(|e| DesignError::File {
            file,
            message: e.to_string(),
        })
    }

    /// Read a gains file written by [`Gains::save`], checking every shape.
    pub fn load(path: &std::path::Path) -> Result<Gains, DesignError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| DesignError::File {
            file: file.clone(),
            message: format!("cannot read: {e}"),
        })?;
        let g: Gains = serde_json::from_str(&text).map_err(|e| DesignError::File {
            file: file.clone(),
            message: e.to_string(),
        })?;
        g.check().map_err(|e| DesignError::File {
            file,
            message: e.to_string(),
        })?;
        Ok(g)
    }

    /// Check the shapes and finiteness of every matrix.
    pub fn check(&self) -> Result<(), DesignError> {
        from_rows("phi", &self.phi, NXR, NXR)?;
        from_rows("gamma", &self.gamma, NXR, NUI)?;
        from_rows("ls", &self.ls, NUI, NXR)?;
        from_rows("li", &self.li, NUI, NY)?;
        from_rows("k", &self.k, NXR, NM)?;
        from_rows("x_trim", std::slice::from_ref(&self.x_trim), 1, NXR)?;
        from_rows("u_trim", std::slice::from_ref(&self.u_trim), 1, NUI)?;
        self.config.validate()
    }
}
