//! Gain-schedule design over the flight envelope: the thesis's recipe (trim,
//! linearise, ZOH-discretise, LQI with the pincer α, steady-state Kalman
//! predictor; [`crate::design`]) repeated at every point of a grid of
//! operating points — ground velocity in heading axes (forward, lateral,
//! down) — and the frozen-point stability check of the interpolated design.
//!
//! The envelope file (TOML):
//!
//! ```toml
//! name = "envelope"
//! preset = "physical"            # model preset ("physical" or "thesis")
//! # params = "my-heli.toml"      # parameter file (relative to this file)
//! [grid]                         # strictly increasing, m/s, heading axes
//! forward_m_s = [0.0, 2.5, 5.0, 7.5, 10.0, 12.5, 15.0]
//! lateral_m_s = [-5.0, 0.0, 5.0]
//! down_m_s = [-3.0, 0.0, 3.0]
//! accept_unphysical = false      # design at trims outside the model's validity (marked)
//! [controller]                   # ControllerConfig (the thesis's final design by default)
//! [check]
//! subdivisions = 2               # frozen points inserted between design points per axis
//! ```
//!
//! The schedule file (`schedule.json`, format [`SCHEDULE_FORMAT_VERSION`]):
//! `version`, `kind` (`"gain-schedule"`), `name`, `preset`, `sample_time_s`,
//! `axes` {`forward_m_s`, `lateral_m_s`, `down_m_s`}, and `points`, one per
//! grid point in the order of [`ScheduleAxes::index`] (down fastest), each
//! `{operating_point_m_s: [forward, lateral, down], unphysical?: "why",
//! gains: {…}}` where
//! `gains` is exactly a `gains.json` object (format 2, checked the same way).

pub use crate::design::integrator_output_map;
use crate::design::{ControllerConfig, DesignError, GAINS_FORMAT_VERSION, Gains, design};
use helicon_core::schedule::{GainSchedule, ScheduleAxes};
use helicon_core::state::{NM, NU, NX_REDUCED, NY};
use helicon_core::{CoreError, GainSet};
use helicon_model::linearize::linearize;
use helicon_model::trim::{Trim, TrimOptions, TrimTarget, trim};
use helicon_model::{ConfigError, InflowMode, Model, Params, Preset, ReducedState};
use nalgebra::{DMatrix, Vector3};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The version of the schedule file format.
pub const SCHEDULE_FORMAT_VERSION: u32 = 1;
/// Largest `check.subdivisions`.
pub const MAX_CHECK_SUBDIVISIONS: u32 = 8;
/// Largest number of frozen points of one check (each a trim, a
/// linearisation and a 58-state eigenvalue problem, ~5 ms: ~2 minutes).
pub const MAX_FROZEN_POINTS: usize = 25_000;

/// The grid of operating points (m/s, heading axes).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GridSection {
    /// Forward ground speed along the heading (m/s).
    pub forward_m_s: Vec<f64>,
    /// Lateral ground speed, right of the heading (m/s).
    pub lateral_m_s: Vec<f64>,
    /// Down velocity (m/s; negative climbs).
    pub down_m_s: Vec<f64>,
    /// Design at trims the model flags as outside its validity (e.g. a rotor
    /// in the vortex-ring state: steep descent, or sideways flight against
    /// the tail-rotor thrust, at low speed) instead of refusing them; they
    /// are marked in the schedule file and `envelope.csv`.
    pub accept_unphysical: bool,
}

impl Default for GridSection {
    /// Hover to 15 m/s every 2.5 m/s, ±5 m/s sideways, ±3 m/s climb/descent.
    fn default() -> Self {
        GridSection {
            forward_m_s: vec![0.0, 2.5, 5.0, 7.5, 10.0, 12.5, 15.0],
            lateral_m_s: vec![-5.0, 0.0, 5.0],
            down_m_s: vec![-3.0, 0.0, 3.0],
            accept_unphysical: false,
        }
    }
}

/// The frozen-point check settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CheckSection {
    /// Frozen points inserted between neighbouring design points on each axis.
    pub subdivisions: u32,
}

impl Default for CheckSection {
    fn default() -> Self {
        CheckSection { subdivisions: 2 }
    }
}

fn default_name() -> String {
    "envelope".into()
}

fn default_preset() -> String {
    "physical".into()
}

/// An envelope file: where to design and how.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvelopeConfig {
    /// Name (reports, the schedule file).
    #[serde(default = "default_name")]
    pub name: String,
    /// Model preset.
    #[serde(default = "default_preset")]
    pub preset: String,
    /// Parameter file (relative to the envelope file); the Bergen Twin when absent.
    #[serde(default)]
    pub params: Option<PathBuf>,
    /// The grid.
    #[serde(default)]
    pub grid: GridSection,
    /// The design settings at every point.
    #[serde(default)]
    pub controller: ControllerConfig,
    /// The frozen-point check.
    #[serde(default)]
    pub check: CheckSection,
    /// Folder of the file (relative paths); not in the TOML.
    #[serde(skip)]
    pub base_dir: Option<PathBuf>,
}

/// Schedule design, check and file failures.
#[derive(Debug, thiserror::Error)]
pub enum ScheduleError {
    /// The envelope file.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The parameter file.
    #[error(transparent)]
    Params(#[from] helicon_model::ParamError),
    /// Trim, linearisation or design failed at one operating point.
    #[error(
        "operating point forward {:.3} m/s, lateral {:.3} m/s, down {:.3} m/s: {message}",
        point[0], point[1], point[2]
    )]
    Point {
        /// [forward, lateral, down] (m/s).
        point: [f64; 3],
        /// What failed.
        message: String,
    },
    /// A gains object of the schedule.
    #[error(transparent)]
    Design(#[from] DesignError),
    /// The schedule cannot be flown.
    #[error("{file}: {source}")]
    Core {
        /// File (or `(design)`).
        file: String,
        /// The core's reason.
        source: CoreError,
    },
    /// Reading or writing the schedule file (names the field).
    #[error("{file}: {message}")]
    File {
        /// File.
        file: String,
        /// What was wrong.
        message: String,
        /// The I/O error, when there was one.
        #[source]
        source: Option<std::io::Error>,
    },
}

impl EnvelopeConfig {
    /// Parse and check TOML text; `file` names the source in errors.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Self, ConfigError> {
        let cfg: EnvelopeConfig = toml::from_str(text).map_err(|e| ConfigError::Parse {
            file: file.to_string(),
            message: e.to_string(),
        })?;
        cfg.validate(file)?;
        Ok(cfg)
    }

    /// Read an envelope file (relative paths resolve against its folder).
    pub fn from_file(path: &Path) -> Result<Self, ConfigError> {
        let (file, text) = helicon_model::ConfigError::read_file(path)?;
        let mut cfg = Self::from_toml_str(&text, &file)?;
        cfg.base_dir = path.parent().map(Path::to_path_buf);
        Ok(cfg)
    }

    /// Check every field (file, field and rule in the error).
    pub fn validate(&self, file: &str) -> Result<(), ConfigError> {
        self.preset
            .parse::<Preset>()
            .map_err(|e| ConfigError::Invalid {
                file: file.to_string(),
                field: "preset".into(),
                value: self.preset.clone(),
                rule: e.to_string(),
            })?;
        let g = &self.grid;
        for (field, axis) in [
            ("grid.forward_m_s", &g.forward_m_s),
            ("grid.lateral_m_s", &g.lateral_m_s),
            ("grid.down_m_s", &g.down_m_s),
        ] {
            if let Some(v) = axis.iter().find(|v| !(v.is_finite() && v.abs() <= 50.0)) {
                return Err(ConfigError::invalid(
                    file,
                    field,
                    *v,
                    "must be finite and within +-50 m/s",
                ));
            }
        }
        self.axes().check().map_err(|e| ConfigError::Invalid {
            file: file.to_string(),
            field: "grid".into(),
            value: format!(
                "{} x {} x {} points",
                g.forward_m_s.len(),
                g.lateral_m_s.len(),
                g.down_m_s.len()
            ),
            rule: e.to_string(),
        })?;
        self.controller.validate().map_err(|e| ConfigError::Parse {
            file: file.to_string(),
            message: format!("[controller]: {e}"),
        })?;
        if self.check.subdivisions > MAX_CHECK_SUBDIVISIONS {
            return Err(ConfigError::invalid(
                file,
                "check.subdivisions",
                f64::from(self.check.subdivisions),
                "must be at most 8 (MAX_CHECK_SUBDIVISIONS)",
            ));
        }
        let fine: usize = self
            .axes()
            .as_array()
            .iter()
            .map(|a| (a.len() - 1) * (self.check.subdivisions as usize + 1) + 1)
            .product();
        if fine > MAX_FROZEN_POINTS {
            return Err(ConfigError::invalid(
                file,
                "check.subdivisions",
                f64::from(self.check.subdivisions),
                format!(
                    "the check would take {fine} frozen points, beyond 25000 \
                     (MAX_FROZEN_POINTS): fewer subdivisions or grid points"
                ),
            ));
        }
        Ok(())
    }

    /// The grid as the core's axes.
    pub fn axes(&self) -> ScheduleAxes {
        ScheduleAxes {
            forward_m_s: self.grid.forward_m_s.clone(),
            lateral_m_s: self.grid.lateral_m_s.clone(),
            down_m_s: self.grid.down_m_s.clone(),
        }
    }

    /// The model the envelope is designed on.
    pub fn model(&self) -> Result<Model, ScheduleError> {
        let preset: Preset = self.preset.parse().map_err(|e| ConfigError::Invalid {
            file: "(envelope)".into(),
            field: "preset".into(),
            value: self.preset.clone(),
            rule: format!("{e}"),
        })?;
        let params = match &self.params {
            Some(p) => {
                let path = match &self.base_dir {
                    Some(d) if p.is_relative() => d.join(p),
                    _ => p.clone(),
                };
                Params::from_file(&path)?
            }
            None => Params::bergen_twin(),
        };
        Ok(Model::new(params, preset.options()))
    }
}

/// A designed schedule: one [`Gains`] per grid point and the trims.
#[derive(Debug, Clone, PartialEq)]
pub struct Schedule {
    /// Name.
    pub name: String,
    /// Model preset designed on.
    pub preset: String,
    /// The grid.
    pub axes: ScheduleAxes,
    /// One design per grid point, in the order of [`ScheduleAxes::index`].
    pub points: Vec<Gains>,
    /// Per point: why its trim is outside the model's validity (`None`
    /// when physical; only with `grid.accept_unphysical`).
    pub unphysical: Vec<Option<String>>,
}

/// The trim of a velocity in heading axes at heading 0 (NED = heading axes).
fn trim_at(
    model: &Model,
    sigma: &Vector3<f64>,
    initial: Option<(ReducedState, helicon_core::state::Input)>,
    accept_unphysical: bool,
) -> Result<(Trim, Option<String>), String> {
    let target = TrimTarget {
        velocity_ned_m_s: *sigma,
        yaw_rad: 0.0,
        wind_ned_m_s: Vector3::zeros(),
    };
    let opts = TrimOptions {
        initial,
        ..TrimOptions::default()
    };
    let t = match trim(model, &target, &opts) {
        Ok(t) => t,
        // a warm start that failed: try cold
        Err(_) if initial.is_some() => {
            trim(model, &target, &TrimOptions::default()).map_err(|e| e.to_string())?
        }
        Err(e) => return Err(e.to_string()),
    };
    if accept_unphysical {
        let v = t.validity(model);
        let why = (!v.is_physical()).then(|| {
            v.violations
                .iter()
                .map(|x| format!("{} = {:.4}", x.quantity, x.value))
                .collect::<Vec<_>>()
                .join("; ")
        });
        return Ok((t, why));
    }
    Ok((t.require_physical(model).map_err(|e| e.to_string())?, None))
}

/// Φ, Γ of the model linearised at a trim and discretised at `ts`.
fn discrete_model(
    model: &Model,
    t: &Trim,
    ts: f64,
) -> Result<(DMatrix<f64>, DMatrix<f64>), String> {
    let lm = linearize(model, &t.x, &t.u, &Vector3::zeros(), InflowMode::Converged)
        .map_err(|e| format!("linearisation: {e}"))?;
    lm.discretize(ts)
        .map_err(|e| format!("discretisation: {e}"))
}

/// The model trimmed at the operating point `sigma` (heading axes, still
/// air, heading 0), linearised and discretised at `ts`: (Φ, Γ, trim).
pub fn discrete_model_at(
    model: &Model,
    sigma: &Vector3<f64>,
    ts: f64,
) -> Result<(DMatrix<f64>, DMatrix<f64>, Trim), ScheduleError> {
    let fail = |message: String| ScheduleError::Point {
        point: [sigma.x, sigma.y, sigma.z],
        message,
    };
    let (t, _) = trim_at(model, sigma, None, true).map_err(fail)?;
    let (phi, gamma) = discrete_model(model, &t, ts).map_err(fail)?;
    Ok((phi, gamma, t))
}

/// Design the schedule: at every grid point trim (warm-started from the
/// previous forward speed), linearise, discretise at the helicopter's
/// `control.sample_time_s` and design. `progress(done, total)` is called
/// after each point. The first failing point is an error naming it.
pub fn design_schedule(
    model: &Model,
    cfg: &EnvelopeConfig,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Schedule, ScheduleError> {
    let axes = cfg.axes();
    axes.check().map_err(|source| ScheduleError::Core {
        file: "(design)".into(),
        source,
    })?;
    let ts = model.params().control.sample_time_s;
    let n = axes.len();
    let mut trims: Vec<Option<Trim>> = vec![None; n];
    let mut points: Vec<Option<Gains>> = vec![None; n];
    let mut unphysical: Vec<Option<String>> = vec![None; n];
    let mut done = 0;
    for j in 0..axes.lateral_m_s.len() {
        for k in 0..axes.down_m_s.len() {
            for i in 0..axes.forward_m_s.len() {
                let sigma = axes.point(i, j, k);
                let fail = |message: String| ScheduleError::Point {
                    point: [sigma.x, sigma.y, sigma.z],
                    message,
                };
                let warm = (i > 0)
                    .then(|| trims[axes.index(i - 1, j, k)].as_ref())
                    .flatten()
                    .map(|t| (t.x, t.u));
                let (t, why) =
                    trim_at(model, &sigma, warm, cfg.grid.accept_unphysical).map_err(fail)?;
                let (phi, gamma) = discrete_model(model, &t, ts).map_err(fail)?;
                // integrating what the on-board law integrates (NED
                // velocity), linearised here: `design`'s own outputs
                let g = design(&phi, &gamma, &t.x, &t.u, ts, &cfg.controller)
                    .map_err(|e| fail(e.to_string()))?;
                let idx = axes.index(i, j, k);
                unphysical[idx] = why;
                trims[idx] = Some(t);
                points[idx] = Some(g);
                done += 1;
                progress(done, n);
            }
        }
    }
    let points = points.into_iter().flatten().collect();
    let s = Schedule {
        name: cfg.name.clone(),
        preset: cfg.preset.clone(),
        axes,
        points,
        unphysical,
    };
    s.gain_schedule("(design)")?;
    Ok(s)
}

/// One point of the frozen-point check.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FrozenPoint {
    /// [forward, lateral, down] (m/s).
    pub operating_point_m_s: [f64; 3],
    /// Whether the point is a design point of the grid.
    pub design_point: bool,
    /// Largest |z| of the frozen closed loop (plant, integrators, predictor).
    pub spectral_radius: f64,
}

/// The summary of a frozen-point check.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrozenCheck {
    /// Every point checked.
    pub points: Vec<FrozenPoint>,
    /// The worst point (largest spectral radius).
    pub worst: FrozenPoint,
}

impl FrozenCheck {
    /// Whether every frozen closed loop is stable (|z| < 1).
    pub fn stable(&self) -> bool {
        self.worst.spectral_radius < 1.0
    }
}

/// The frozen-point closed loop at one operating point: the model trimmed
/// and linearised there (Φ, Γ), the schedule interpolated there (gains,
/// predictor model), and the on-board law's integrator of the NED velocity
/// error rotated into body axes linearised about the trim.
///
/// ```text
/// x⁺  = Φ x + Γ u,                u = −Ls x̂ − Li xᵢ
/// xᵢ⁺ = xᵢ − C x                  (C: ψ and R_beᵀ ∂(R_eb v)/∂x)
/// x̂⁺  = Φg x̂ + Γg u + Kg Hm (x − x̂)
/// ```
pub fn frozen_closed_loop(
    phi: &DMatrix<f64>,
    gamma: &DMatrix<f64>,
    trim_x: &ReducedState,
    g: &GainSet,
) -> DMatrix<f64> {
    let n = NX_REDUCED;
    let c = integrator_output_map(trim_x);
    let ls = DMatrix::from_column_slice(NU, n, g.ls.as_slice());
    let li = DMatrix::from_column_slice(NU, NY, g.li.as_slice());
    let phig = DMatrix::from_column_slice(n, n, g.phi.as_slice());
    let gammag = DMatrix::from_column_slice(n, NU, g.gamma.as_slice());
    let k = DMatrix::from_column_slice(n, NM, g.k.as_slice());
    let mut hm = DMatrix::zeros(NM, n);
    for i in 0..NM {
        hm[(i, i)] = 1.0;
    }
    let khm = &k * &hm;
    let dim = 2 * n + NY;
    let mut a = DMatrix::zeros(dim, dim);
    // blocks in the order [x, xi, x̂]
    a.view_mut((0, 0), (n, n)).copy_from(phi);
    a.view_mut((0, n), (n, NY)).copy_from(&(-(gamma * &li)));
    a.view_mut((0, n + NY), (n, n)).copy_from(&(-(gamma * &ls)));
    a.view_mut((n, 0), (NY, n)).copy_from(&(-&c));
    a.view_mut((n, n), (NY, NY)).fill_with_identity();
    a.view_mut((n + NY, 0), (n, n)).copy_from(&khm);
    a.view_mut((n + NY, n), (n, NY))
        .copy_from(&(-(&gammag * &li)));
    a.view_mut((n + NY, n + NY), (n, n))
        .copy_from(&(&phig - &gammag * &ls - &khm));
    a
}

/// The points of the fine grid: each axis with `subdivisions` points
/// inserted between neighbours.
fn fine_axis(axis: &[f64], subdivisions: u32) -> Vec<(f64, bool)> {
    let mut out = Vec::new();
    for w in axis.windows(2) {
        out.push((w[0], true));
        for s in 1..=subdivisions {
            let f = f64::from(s) / f64::from(subdivisions + 1);
            out.push((w[0] + f * (w[1] - w[0]), false));
        }
    }
    if let Some(&last) = axis.last() {
        out.push((last, true));
    }
    out
}

/// The frozen-point check over the fine grid between the design points:
/// at each point the model is trimmed (warm-started from the interpolated
/// trim) and linearised, the schedule interpolated, and the spectral radius
/// of [`frozen_closed_loop`] computed.
pub fn frozen_point_check(
    model: &Model,
    schedule: &GainSchedule,
    subdivisions: u32,
    accept_unphysical: bool,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<FrozenCheck, ScheduleError> {
    let axes = schedule.axes();
    let ts = schedule.points()[0].sample_time_s;
    let [f, l, d] = axes
        .as_array()
        .map(|a| fine_axis(a, subdivisions.min(MAX_CHECK_SUBDIVISIONS)));
    let total = f.len() * l.len() * d.len();
    let mut points = Vec::with_capacity(total);
    for &(vf, nf) in &f {
        for &(vl, nl) in &l {
            for &(vd, nd) in &d {
                let sigma = Vector3::new(vf, vl, vd);
                let fail = |message: String| ScheduleError::Point {
                    point: [vf, vl, vd],
                    message,
                };
                let g = schedule.at(&sigma);
                let (t, _) = trim_at(model, &sigma, Some((g.x_trim, g.u_trim)), accept_unphysical)
                    .map_err(fail)?;
                let (phi, gamma) = discrete_model(model, &t, ts).map_err(fail)?;
                let a = frozen_closed_loop(&phi, &gamma, &t.x, &g);
                let rho = helicon_lti::analysis::spectral_radius(&a)
                    .map_err(|e| fail(format!("eigenvalues: {e}")))?;
                points.push(FrozenPoint {
                    operating_point_m_s: [vf, vl, vd],
                    design_point: nf && nl && nd,
                    spectral_radius: rho,
                });
                progress(points.len(), total);
            }
        }
    }
    let worst = points
        .iter()
        .copied()
        .max_by(|a, b| a.spectral_radius.total_cmp(&b.spectral_radius))
        .ok_or_else(|| ScheduleError::File {
            file: "(check)".into(),
            message: "empty grid".into(),
            source: None,
        })?;
    Ok(FrozenCheck { points, worst })
}

/// The schedule file as written.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ScheduleFile {
    version: u32,
    kind: String,
    name: String,
    preset: String,
    sample_time_s: f64,
    axes: GridSection,
    points: Vec<PointFile>,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PointFile {
    operating_point_m_s: [f64; 3],
    #[serde(default, skip_serializing_if = "Option::is_none")]
    unphysical: Option<String>,
    gains: serde_json::Value,
}

const KIND: &str = "gain-schedule";

impl Schedule {
    /// The core's schedule (what flies); `file` names the source in errors.
    pub fn gain_schedule(&self, file: &str) -> Result<GainSchedule, ScheduleError> {
        GainSchedule::new(
            self.axes.clone(),
            self.points.iter().map(|g| g.set.clone()).collect(),
        )
        .map_err(|source| ScheduleError::Core {
            file: file.to_string(),
            source,
        })
    }

    /// The sample time of the designs (s).
    pub fn sample_time_s(&self) -> f64 {
        self.points
            .first()
            .map_or(f64::NAN, |g| g.set.sample_time_s)
    }

    /// The operating point of design `index` [forward, lateral, down] (m/s).
    pub fn operating_point(&self, index: usize) -> [f64; 3] {
        let (nl, nd) = (self.axes.lateral_m_s.len(), self.axes.down_m_s.len());
        let (i, j, k) = (index / (nl * nd), (index / nd) % nl, index % nd);
        let p = self.axes.point(i, j, k);
        [p.x, p.y, p.z]
    }

    /// The schedule as JSON text.
    pub fn to_json(&self) -> Result<String, ScheduleError> {
        let bad = |e: String| ScheduleError::File {
            file: "schedule.json".into(),
            message: e,
            source: None,
        };
        let mut points = Vec::with_capacity(self.points.len());
        for (i, g) in self.points.iter().enumerate() {
            let v: serde_json::Value =
                serde_json::from_str(&g.to_json()?).map_err(|e| bad(e.to_string()))?;
            points.push(PointFile {
                operating_point_m_s: self.operating_point(i),
                unphysical: self.unphysical.get(i).cloned().flatten(),
                gains: v,
            });
        }
        let f = ScheduleFile {
            version: SCHEDULE_FORMAT_VERSION,
            kind: KIND.into(),
            name: self.name.clone(),
            preset: self.preset.clone(),
            sample_time_s: self.sample_time_s(),
            axes: GridSection {
                forward_m_s: self.axes.forward_m_s.clone(),
                lateral_m_s: self.axes.lateral_m_s.clone(),
                down_m_s: self.axes.down_m_s.clone(),
                accept_unphysical: self.unphysical.iter().any(Option::is_some),
            },
            points,
        };
        serde_json::to_string(&f).map_err(|e| bad(format!("cannot serialise: {e}")))
    }

    /// Write the schedule file.
    pub fn save(&self, path: &Path) -> Result<(), ScheduleError> {
        let text = self.to_json()?;
        std::fs::write(path, text).map_err(|e| ScheduleError::File {
            file: path.display().to_string(),
            message: "cannot write".into(),
            source: Some(e),
        })
    }

    /// Read a schedule file written by [`Schedule::save`].
    pub fn load(path: &Path) -> Result<Schedule, ScheduleError> {
        let file = path.display().to_string();
        let text = helicon_model::config_error::read_text_bounded(
            path,
            helicon_model::config_error::MAX_TEXT_BYTES,
        )
        .map_err(|e| ScheduleError::File {
            file: file.clone(),
            message: "cannot read".into(),
            source: Some(e.into_io()),
        })?;
        Schedule::from_json(&text, &file)
    }

    /// Parse schedule JSON text: the version, the grid, one point per grid
    /// node at its operating point, each gains object checked as a
    /// `gains.json` (shapes, finiteness, α), one sample time.
    pub fn from_json(text: &str, file: &str) -> Result<Schedule, ScheduleError> {
        let bad = |message: String| ScheduleError::File {
            file: file.to_string(),
            message,
            source: None,
        };
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| bad(format!("not valid JSON: {e}")))?;
        let version = value.get("version").and_then(serde_json::Value::as_u64);
        if version != Some(u64::from(SCHEDULE_FORMAT_VERSION)) {
            return Err(bad(format!(
                "`version` = {}: this helicon reads gain-schedule format {SCHEDULE_FORMAT_VERSION}",
                version.map_or_else(|| "missing".to_string(), |v| v.to_string())
            )));
        }
        let f: ScheduleFile = serde_json::from_value(value).map_err(|e| bad(e.to_string()))?;
        if f.kind != KIND {
            return Err(bad(format!("`kind` = {:?}: expected {KIND:?}", f.kind)));
        }
        let axes = ScheduleAxes {
            forward_m_s: f.axes.forward_m_s,
            lateral_m_s: f.axes.lateral_m_s,
            down_m_s: f.axes.down_m_s,
        };
        axes.check().map_err(|e| bad(format!("`axes`: {e}")))?;
        if f.points.len() != axes.len() {
            return Err(bad(format!(
                "`points` holds {} entries, the axes need {}",
                f.points.len(),
                axes.len()
            )));
        }
        let mut s = Schedule {
            name: f.name,
            preset: f.preset,
            axes,
            points: Vec::with_capacity(f.points.len()),
            unphysical: Vec::with_capacity(f.points.len()),
        };
        for (i, p) in f.points.into_iter().enumerate() {
            let expected = s.operating_point(i);
            if p.operating_point_m_s != expected {
                return Err(bad(format!(
                    "`points[{i}].operating_point_m_s` = {:?}: the axes put {expected:?} there",
                    p.operating_point_m_s
                )));
            }
            let g = Gains::from_json(&p.gains.to_string())
                .map_err(|e| bad(format!("`points[{i}].gains`: {e}")))?;
            if g.set.sample_time_s != f.sample_time_s {
                return Err(bad(format!(
                    "`points[{i}].gains.sample_time_s` = {} differs from `sample_time_s` = {}",
                    g.set.sample_time_s, f.sample_time_s
                )));
            }
            s.points.push(g);
            s.unphysical.push(p.unphysical);
        }
        s.gain_schedule(file)?;
        Ok(s)
    }
}

/// The gains format a schedule's points are written in.
pub const POINT_FORMAT_VERSION: u32 = GAINS_FORMAT_VERSION;
