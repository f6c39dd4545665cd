//! Controller and estimator design from a linear model at a trim (thesis
//! chapters 14 and 15).
//!
//! * Outputs (14.4): y = Hs x = [ψ, u, v, w] (yaw and body velocities) at
//!   hover; at speed the linearisation of what the on-board law integrates
//!   (ψ and the NED velocity in body axes, [`integrator_output_map`]).
//! * LQR with integral action (14.28)–(14.34) on the ZOH model (Φs, Γs) at Ts,
//!   with Bryson weights (14.14)–(14.16): Qe = Qy = diag(1/y_max²) (14.23),
//!   (14.35); Qi = `integral_weight`·Qe (14.36); Q2 = diag(1/u_max²) (14.24) or
//!   the retuned (14.27); ρ; and the pincer α from a settling time (14.22).
//! * Steady-state Kalman predictor (15.8) on the nine measured states (15.2)
//!   [φ θ ψ u v w p q r], with Rex = q·I₂₇ and Rey = r·I₉ (15.11)–(15.12).
//!
//! The sample time Ts is the helicopter's parameter `control.sample_time_s`
//! (one value: the design discretises at it and the flight computer runs at it).
//!
//! The result, [`Gains`], carries the core's fixed-size [`GainSet`] (what
//! flies) and the design record (settings, poles); it is written to and read
//! from `gains.json` (format version [`GAINS_FORMAT_VERSION`]) so the on-board
//! runtime flies exactly the gains that were simulated.

use helicon_core::frames::EulerTrig;
use helicon_core::gains::{GainSet, LqiOptions};
use helicon_core::state::{Input, NM, NU, NX_REDUCED, NY, OUTPUT_STATES, ReducedState};
use helicon_lti::lqr::{alpha_from_settling_time, bryson, dlqr_integral, dlqr_pincer};
use helicon_lti::{LtiError, dlqe};
use nalgebra::{DMatrix, SMatrix, Vector3};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The version of the `gains.json` format written by [`Gains::save`].
pub const GAINS_FORMAT_VERSION: u32 = 2;

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
    pub input_max: [f64; NU],
    /// ρ, the output/input weighting (14.17).
    pub rho: f64,
    /// Settling time (s) for the pincer α (14.22); `None` for α = 1.
    pub settling_time_s: Option<f64>,
    /// Qi = integral_weight · Qe (14.36).
    pub integral_weight: f64,
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
    /// With the yaw-rate gyro on (`[yaw_gyro]` in the parameters), the
    /// Bryson maximum of the tail input as the yaw-rate command it stands
    /// for (rad/s): the tail weight becomes 1/(this / c)², c the gyro's
    /// rate per unit input, replacing `input_max[3]` (a tail-pitch
    /// deflection, meaningless for a rate command). `None`: the gyro's full
    /// range `max_rate_rad_s`. Unused without the gyro.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub yaw_rate_command_max_rad_s: Option<f64>,
}

impl Default for ControllerConfig {
    /// The thesis's final design: (14.23), (14.27), ρ = 10, ts = 5 s, (14.36),
    /// (15.11)–(15.12).
    fn default() -> Self {
        ControllerConfig {
            output_max: [3.0; NY],
            input_max: U_MAX_RETUNED,
            rho: 10.0,
            settling_time_s: Some(5.0),
            integral_weight: 1e-4,
            process_noise: 1.0,
            measurement_noise: 1e-3,
            integral_action: true,
            reference_in_proportional: false,
            anti_windup: false,
            yaw_rate_command_max_rad_s: None,
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
    /// The sample time is not a positive finite number.
    #[error("controller design: sample time {0} s must be finite and > 0")]
    SampleTime(f64),
    /// Reading or writing a gains file failed.
    #[error("{file}: {message}")]
    File {
        /// File.
        file: String,
        /// What was wrong (names the field).
        message: String,
        /// The I/O error, when there was one.
        #[source]
        source: Option<std::io::Error>,
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
        if let Some(r) = self.yaw_rate_command_max_rad_s {
            pos("yaw_rate_command_max_rad_s", r)?;
        }
        if !(self.integral_weight.is_finite() && self.integral_weight >= 0.0) {
            return Err(DesignError::Config {
                field: "integral_weight",
                value: self.integral_weight,
                rule: "must be finite and >= 0",
            });
        }
        pos("process_noise", self.process_noise)?;
        pos("measurement_noise", self.measurement_noise)?;
        Ok(())
    }
}

// The law's wiring options, from the settings.
impl ControllerConfig {
    /// The core's wiring options of the law these settings design.
    pub fn lqi_options(&self) -> LqiOptions {
        LqiOptions {
            integral_action: self.integral_action,
            reference_in_proportional: self.reference_in_proportional,
            anti_windup: self.anti_windup,
        }
    }
}

/// A design: the gain set that flies and the record of how it was made.
#[derive(Debug, Clone, PartialEq)]
pub struct Gains {
    /// The settings used.
    pub config: ControllerConfig,
    /// What the flight computer flies.
    pub set: GainSet,
    /// Closed-loop (augmented) discrete poles, as [re, im].
    pub closed_loop_poles: Vec<[f64; 2]>,
    /// Estimator-error discrete poles eig(Φ − K Hm), as [re, im].
    pub estimator_poles: Vec<[f64; 2]>,
}

impl Gains {
    /// Largest |z| of the closed-loop design poles.
    pub fn spectral_radius(&self) -> f64 {
        self.closed_loop_poles
            .iter()
            .map(|z| z[0].hypot(z[1]))
            .fold(0.0, f64::max)
    }
}

/// `gains.json` as written on disk: matrices as row-major nested arrays.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct GainsFile {
    version: u32,
    config: ControllerConfig,
    sample_time_s: f64,
    x_trim: Vec<f64>,
    u_trim: Vec<f64>,
    alpha: f64,
    phi: Vec<Vec<f64>>,
    gamma: Vec<Vec<f64>>,
    ls: Vec<Vec<f64>>,
    li: Vec<Vec<f64>>,
    k: Vec<Vec<f64>>,
    closed_loop_poles: Vec<[f64; 2]>,
    estimator_poles: Vec<[f64; 2]>,
}

fn rows<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> Vec<Vec<f64>> {
    (0..R)
        .map(|i| (0..C).map(|j| m[(i, j)]).collect())
        .collect()
}

fn dyn_to_fixed<const R: usize, const C: usize>(
    what: &'static str,
    m: &DMatrix<f64>,
) -> Result<SMatrix<f64, R, C>, DesignError> {
    if m.shape() != (R, C) {
        return Err(DesignError::Shape {
            what,
            rows: m.nrows(),
            cols: m.ncols(),
            er: R,
            ec: C,
        });
    }
    Ok(SMatrix::<f64, R, C>::from_fn(|i, j| m[(i, j)]))
}

/// A fixed-size matrix from nested rows, checking the shape and finiteness.
pub fn from_rows<const R: usize, const C: usize>(
    what: &'static str,
    r: &[Vec<f64>],
) -> Result<SMatrix<f64, R, C>, DesignError> {
    let cols = r.first().map_or(0, Vec::len);
    if r.len() != R || r.iter().any(|row| row.len() != C) {
        return Err(DesignError::Shape {
            what,
            rows: r.len(),
            cols,
            er: R,
            ec: C,
        });
    }
    if let Some(v) = r.iter().flatten().find(|v| !v.is_finite()) {
        return Err(DesignError::Config {
            field: what,
            value: *v,
            rule: "entries must be finite",
        });
    }
    Ok(SMatrix::<f64, R, C>::from_fn(|i, j| r[i][j]))
}

/// Hs (4×27): ψ, u, v, w (14.4).
pub fn output_matrix() -> DMatrix<f64> {
    let mut hs = DMatrix::zeros(NY, NX_REDUCED);
    for (row, &col) in OUTPUT_STATES.iter().enumerate() {
        hs[(row, col)] = 1.0;
    }
    hs
}

/// C (4×27): the linearised integrator input of the on-board law about a
/// trim: ψ, and the NED velocity R_eb(Θ) v rotated back into body axes
/// (at hover this is Hs (14.4); at speed the attitude enters through R_eb v:
/// a yaw change δψ at speed V adds V δψ of sideways velocity, a pitch change
/// δθ adds V δθ of vertical velocity). What [`design`] integrates.
pub fn integrator_output_map(trim_x: &ReducedState) -> DMatrix<f64> {
    let mut c = DMatrix::zeros(NY, NX_REDUCED);
    c[(0, 2)] = 1.0;
    let (phi, theta, psi) = (trim_x[0], trim_x[1], trim_x[2]);
    let v = Vector3::new(trim_x[3], trim_x[4], trim_x[5]);
    let r = EulerTrig::new(phi, theta, psi).ned_from_body();
    let rt = r.transpose();
    // ∂(R v)/∂Θ by central differences (h = 1e-6 rad: truncation ~1e-12 · |v|)
    let h = 1e-6;
    for a in 0..3 {
        let mut p = [phi, theta, psi];
        let mut m = p;
        p[a] += h;
        m[a] -= h;
        let d = (EulerTrig::new(p[0], p[1], p[2]).ned_from_body() * v
            - EulerTrig::new(m[0], m[1], m[2]).ned_from_body() * v)
            / (2.0 * h);
        let d_body = rt * d;
        for row in 0..3 {
            c[(1 + row, a)] = d_body[row];
        }
    }
    for row in 0..3 {
        c[(1 + row, 3 + row)] = 1.0;
    }
    c
}

/// Hm (9×27): the first nine reduced states (15.2).
pub fn measurement_matrix() -> DMatrix<f64> {
    let mut hm = DMatrix::zeros(NM, NX_REDUCED);
    for i in 0..NM {
        hm[(i, i)] = 1.0;
    }
    hm
}

/// Design the controller and estimator for the discrete model (Φs, Γs) at
/// sample time `sample_time_s` about the trim (x_trim, u_trim).
///
/// The integrated outputs are what the on-board law integrates, linearised
/// about this trim ([`integrator_output_map`]): at hover the thesis's
/// Hs = [ψ u v w] (14.4); at speed ψ and the NED velocity in body axes,
/// which depends on the attitude. A design at speed with Hs itself leaves a
/// lateral–directional mode of the flown loop (≈ 1.6 rad/s at 10 m/s)
/// damped at only −0.02 to −0.05 1/s, unstable at 15 m/s.
pub fn design(
    phi: &DMatrix<f64>,
    gamma: &DMatrix<f64>,
    x_trim: &ReducedState,
    u_trim: &Input,
    sample_time_s: f64,
    config: &ControllerConfig,
) -> Result<Gains, DesignError> {
    design_with_outputs(
        phi,
        gamma,
        &integrator_output_map(x_trim),
        x_trim,
        u_trim,
        sample_time_s,
        config,
    )
}

/// As [`design`] with the integrated outputs y = `hs` x (4×27) given: for
/// analyses of other output choices (the thesis's Hs = [ψ, u, v, w] (14.4)
/// at every speed is [`output_matrix`]). [`design`] and the gain schedule
/// pass [`integrator_output_map`], the linearisation of what the on-board
/// law integrates.
pub fn design_with_outputs(
    phi: &DMatrix<f64>,
    gamma: &DMatrix<f64>,
    hs: &DMatrix<f64>,
    x_trim: &ReducedState,
    u_trim: &Input,
    sample_time_s: f64,
    config: &ControllerConfig,
) -> Result<Gains, DesignError> {
    config.validate()?;
    if hs.shape() != (NY, NX_REDUCED) {
        return Err(DesignError::Shape {
            what: "Hs",
            rows: hs.nrows(),
            cols: hs.ncols(),
            er: NY,
            ec: NX_REDUCED,
        });
    }
    if !(sample_time_s.is_finite() && sample_time_s > 0.0) {
        return Err(DesignError::SampleTime(sample_time_s));
    }
    let phi_s = dyn_to_fixed::<NX_REDUCED, NX_REDUCED>("Phi", phi)?;
    let gamma_s = dyn_to_fixed::<NX_REDUCED, NU>("Gamma", gamma)?;
    let alpha = match config.settling_time_s {
        Some(ts) => alpha_from_settling_time(sample_time_s, ts)?,
        None => 1.0,
    };
    let qe = bryson(&config.output_max)?;
    let qi = &qe * config.integral_weight;
    let q2 = bryson(&config.input_max)?;
    let (ls, li, poles) = if config.integral_action {
        let lqr = dlqr_integral(phi, gamma, hs, &qe, &qi, &q2, config.rho, alpha)?;
        (lqr.ls, lqr.li, lqr.poles)
    } else {
        let mut q1 = hs.transpose() * &qe * hs;
        q1 = (&q1 + q1.transpose()) * 0.5;
        let lqr = dlqr_pincer(phi, gamma, &q1, &(q2 * config.rho), None, alpha)?;
        (lqr.k, DMatrix::zeros(NU, NY), lqr.poles)
    };
    let hm = measurement_matrix();
    let rex = DMatrix::<f64>::identity(NX_REDUCED, NX_REDUCED) * config.process_noise;
    let rey = DMatrix::<f64>::identity(NM, NM) * config.measurement_noise;
    let kal = dlqe(phi, None, &hm, &rex, &rey)?;
    let set = GainSet {
        sample_time_s,
        alpha,
        x_trim: *x_trim,
        u_trim: *u_trim,
        phi: phi_s,
        gamma: gamma_s,
        ls: dyn_to_fixed("Ls", &ls)?,
        li: dyn_to_fixed("Li", &li)?,
        k: dyn_to_fixed("K", &kal.l)?,
        options: config.lqi_options(),
    };
    set.check().map_err(|e| DesignError::File {
        file: "(design)".into(),
        message: e.to_string(),
        source: None,
    })?;
    Ok(Gains {
        config: config.clone(),
        set,
        closed_loop_poles: poles.iter().map(|z| [z.re, z.im]).collect(),
        estimator_poles: kal.poles.iter().map(|z| [z.re, z.im]).collect(),
    })
}

impl Gains {
    fn to_file(&self) -> GainsFile {
        let s = &self.set;
        GainsFile {
            version: GAINS_FORMAT_VERSION,
            config: self.config.clone(),
            sample_time_s: s.sample_time_s,
            x_trim: s.x_trim.iter().copied().collect(),
            u_trim: s.u_trim.iter().copied().collect(),
            alpha: s.alpha,
            phi: rows(&s.phi),
            gamma: rows(&s.gamma),
            ls: rows(&s.ls),
            li: rows(&s.li),
            k: rows(&s.k),
            closed_loop_poles: self.closed_loop_poles.clone(),
            estimator_poles: self.estimator_poles.clone(),
        }
    }

    /// The design as `gains.json` text (pretty JSON).
    pub fn to_json(&self) -> Result<String, DesignError> {
        serde_json::to_string_pretty(&self.to_file()).map_err(|e| DesignError::File {
            file: "gains.json".into(),
            message: format!("cannot serialise: {e}"),
            source: None,
        })
    }

    /// Write as pretty JSON.
    pub fn save(&self, path: &Path) -> Result<(), DesignError> {
        let text = self.to_json()?;
        std::fs::write(path, text).map_err(|e| DesignError::File {
            file: path.display().to_string(),
            message: "cannot write".into(),
            source: Some(e),
        })
    }

    /// Read a gains file written by [`Gains::save`], checking the version,
    /// every shape, finiteness, and that α is the one the recorded settling
    /// time gives at the recorded sample time (an edited file is refused).
    pub fn load(path: &Path) -> Result<Gains, DesignError> {
        let file = path.display().to_string();
        let text = helicon_model::config_error::read_text_bounded(
            path,
            helicon_model::config_error::MAX_TEXT_BYTES,
        )
        .map_err(|e| DesignError::File {
            file: file.clone(),
            message: "cannot read".into(),
            source: Some(e.into_io()),
        })?;
        Gains::from_json(&text).map_err(|e| match e {
            DesignError::File { message, .. } => DesignError::File {
                file,
                message,
                source: None,
            },
            other => DesignError::File {
                file,
                message: other.to_string(),
                source: None,
            },
        })
    }

    /// Parse `gains.json` text (see [`Gains::load`]).
    pub fn from_json(text: &str) -> Result<Gains, DesignError> {
        let bad = |message: String| DesignError::File {
            file: "gains.json".into(),
            message,
            source: None,
        };
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| bad(format!("not valid JSON: {e}")))?;
        reject_duplicate_keys(text).map_err(bad)?;
        let version = value.get("version").and_then(serde_json::Value::as_u64);
        if version != Some(u64::from(GAINS_FORMAT_VERSION)) {
            return Err(bad(format!(
                "`version` = {}: this helicon reads gains format {GAINS_FORMAT_VERSION} \
                 (redesign with this version to get one)",
                version.map_or_else(|| "missing".to_string(), |v| v.to_string())
            )));
        }
        let f: GainsFile = serde_json::from_value(value).map_err(|e| bad(e.to_string()))?;
        f.config.validate()?;
        let ts = f.sample_time_s;
        if !(ts.is_finite() && ts > 0.0) {
            return Err(bad(format!(
                "`sample_time_s` = {ts}: must be finite and > 0"
            )));
        }
        let expected_alpha = match f.config.settling_time_s {
            Some(t) => alpha_from_settling_time(ts, t)?,
            None => 1.0,
        };
        // NaN compares false: written so that a NaN α is refused too
        let alpha_matches = (f.alpha - expected_alpha).abs() <= 1e-12 * expected_alpha.abs();
        if !alpha_matches {
            return Err(bad(format!(
                "`alpha` = {} does not match `settling_time_s` = {} at `sample_time_s` = {ts} s \
                 (which gives {expected_alpha}): the file was edited",
                f.alpha,
                f.config
                    .settling_time_s
                    .map_or_else(|| "none".to_string(), |t| format!("{t} s"))
            )));
        }
        let x_trim = from_rows::<1, NX_REDUCED>("x_trim", std::slice::from_ref(&f.x_trim))?;
        let u_trim = from_rows::<1, NU>("u_trim", std::slice::from_ref(&f.u_trim))?;
        let set = GainSet {
            sample_time_s: ts,
            alpha: f.alpha,
            x_trim: x_trim.transpose(),
            u_trim: u_trim.transpose(),
            phi: from_rows("phi", &f.phi)?,
            gamma: from_rows("gamma", &f.gamma)?,
            ls: from_rows("ls", &f.ls)?,
            li: from_rows("li", &f.li)?,
            k: from_rows("k", &f.k)?,
            options: f.config.lqi_options(),
        };
        set.check().map_err(|e| bad(e.to_string()))?;
        Ok(Gains {
            config: f.config,
            set,
            closed_loop_poles: f.closed_loop_poles,
            estimator_poles: f.estimator_poles,
        })
    }
}

/// Refuse JSON text with a key given twice in one object (serde_json keeps
/// the last one silently; in an edited gains file that is ambiguous), naming
/// the key by its path.
fn reject_duplicate_keys(text: &str) -> Result<(), String> {
    struct NoDuplicateKeys(String);
    impl<'de> serde::de::DeserializeSeed<'de> for NoDuplicateKeys {
        type Value = ();
        fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
            d.deserialize_any(self)
        }
    }
    impl<'de> serde::de::Visitor<'de> for NoDuplicateKeys {
        type Value = ();
        fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("any JSON value")
        }
        fn visit_bool<E>(self, _: bool) -> Result<(), E> {
            Ok(())
        }
        fn visit_i64<E>(self, _: i64) -> Result<(), E> {
            Ok(())
        }
        fn visit_u64<E>(self, _: u64) -> Result<(), E> {
            Ok(())
        }
        fn visit_f64<E>(self, _: f64) -> Result<(), E> {
            Ok(())
        }
        fn visit_str<E>(self, _: &str) -> Result<(), E> {
            Ok(())
        }
        fn visit_unit<E>(self) -> Result<(), E> {
            Ok(())
        }
        fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut a: A) -> Result<(), A::Error> {
            let mut i = 0usize;
            while a
                .next_element_seed(NoDuplicateKeys(format!("{}[{i}]", self.0)))?
                .is_some()
            {
                i += 1;
            }
            Ok(())
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(self, mut m: A) -> Result<(), A::Error> {
            let mut seen = std::collections::BTreeSet::new();
            while let Some(k) = m.next_key::<String>()? {
                let path = if self.0.is_empty() {
                    k.clone()
                } else {
                    format!("{}.{k}", self.0)
                };
                if !seen.insert(k) {
                    return Err(serde::de::Error::custom(format!(
                        "duplicate key `{path}` (a key given twice is ambiguous)"
                    )));
                }
                m.next_value_seed(NoDuplicateKeys(path))?;
            }
            Ok(())
        }
    }
    serde::de::DeserializeSeed::deserialize(
        NoDuplicateKeys(String::new()),
        &mut serde_json::Deserializer::from_str(text),
    )
    .map_err(|e| e.to_string())
}
