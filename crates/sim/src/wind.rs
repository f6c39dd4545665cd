//! Wind: the air-mass velocity in NED (where the air moves **to**), m/s.
//!
//! Models, each a [`WindModel`]: steady wind, the 1-cosine discrete gust, the
//! thesis's wind model (14.38)–(14.42) and Dryden turbulence (MIL-F-8785C
//! low-altitude forms). [`Wind`] sums the components enabled in a
//! [`WindConfig`] (TOML). The helicopter model decides how wind enters the
//! dynamics (physical: `v_rel = v_body − R_be · wind`; the thesis added it,
//! (14.46)).

use nalgebra::{Matrix2, Matrix4, Vector2, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Feet per metre conversion used by the MIL-F-8785C forms (1 ft = 0.3048 m).
const FT: f64 = 0.3048;

/// A wind configuration out of range: the toolkit's one configuration error
/// shape (the file is `[wind]` until the caller places it in its own file
/// with [`helicon_model::ConfigError::within`]).
pub type WindError = helicon_model::ConfigError;

fn check(
    field: &'static str,
    value: f64,
    ok: bool,
    allowed: &'static str,
) -> Result<(), WindError> {
    if value.is_finite() && ok {
        Ok(())
    } else {
        Err(WindError::invalid(
            "[wind]",
            field,
            value,
            format!("allowed: {allowed}"),
        ))
    }
}

/// A wind model stepped in time.
pub trait WindModel {
    /// Air-mass velocity in NED (m/s) at time `t_s`, advancing the internal
    /// state by `dt_s` (time since the previous call; stochastic models use it
    /// to propagate their state, deterministic ones ignore it).
    fn step(&mut self, t_s: f64, dt_s: f64) -> Vector3<f64>;
}

// ---------------------------------------------------------------- steady

/// Steady wind.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SteadyWindConfig {
    /// Air-mass velocity in NED (m/s).
    pub wind_ned_m_s: [f64; 3],
}

impl WindModel for SteadyWindConfig {
    fn step(&mut self, _t_s: f64, _dt_s: f64) -> Vector3<f64> {
        Vector3::from(self.wind_ned_m_s)
    }
}

// ---------------------------------------------------------------- 1-cosine

/// Discrete 1-cosine gust (MIL-F-8785C §3.7.3 shape, in time):
/// `w(t) = (w_peak/2)(1 − cos(2π (t − t₀)/T))` for `t₀ ≤ t ≤ t₀ + T`, else 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OneMinusCosineGust {
    /// Gust start time `t₀` (s).
    pub start_s: f64,
    /// Full gust duration `T` (s), > 0.
    pub duration_s: f64,
    /// Peak air-mass velocity in NED (m/s), reached at `t₀ + T/2`.
    pub peak_ned_m_s: [f64; 3],
}

impl OneMinusCosineGust {
    fn validate(&self) -> Result<(), WindError> {
        check("gust.start_s", self.start_s, true, "finite")?;
        check(
            "gust.duration_s",
            self.duration_s,
            self.duration_s > 0.0,
            "> 0",
        )?;
        for v in self.peak_ned_m_s {
            check("gust.peak_ned_m_s", v, true, "finite")?;
        }
        Ok(())
    }

    /// Gust velocity at time `t_s`.
    pub fn at(&self, t_s: f64) -> Vector3<f64> {
        let tau = t_s - self.start_s;
        if tau < 0.0 || tau > self.duration_s {
            return Vector3::zeros();
        }
        Vector3::from(self.peak_ned_m_s) * 0.5 * (1.0 - (2.0 * PI * tau / self.duration_s).cos())
    }
}

impl WindModel for OneMinusCosineGust {
    fn step(&mut self, t_s: f64, _dt_s: f64) -> Vector3<f64> {
        self.at(t_s)
    }
}

// ---------------------------------------------------------------- thesis

/// Parameters of the thesis's wind model (14.38)–(14.42).
///
/// Defaults are the thesis's values: `|w_max| = 2 m/s`, gust frequency 2 Hz
/// (`ω_g = 4π rad/s`, (14.39)), `ω_θ = 2π/3 rad/s`, `ω_φ = 2π/5 rad/s`
/// (§14.3, text after (14.42)), and turbulence variance `σ_t² = 0.1 (m/s)²`.
/// The thesis is inconsistent here: the text says "σ_t² = 0.1" while (14.39)
/// prints `N_w(0, 0.1²)`. The default follows the text (σ_t = 0.316 m/s),
/// which also matches the −1…3 m/s range of its Figure 14.6; set
/// `turbulence_sigma_m_s = 0.1` for the printed (14.39).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ThesisWindConfig {
    /// `|w_max|` (m/s), the gust amplitude peak-to-peak (14.38).
    pub max_gust_m_s: f64,
    /// Standard deviation `σ_t` of the white-noise turbulence term (m/s).
    pub turbulence_sigma_m_s: f64,
    /// Gust angular frequency `ω_g` (rad/s).
    pub gust_omega_rad_s: f64,
    /// Longitude angular frequency `ω_θ` (rad/s), (14.41).
    pub longitude_omega_rad_s: f64,
    /// Latitude angular frequency `ω_φ` (rad/s), (14.42).
    pub latitude_omega_rad_s: f64,
}

impl Default for ThesisWindConfig {
    fn default() -> Self {
        Self {
            max_gust_m_s: 2.0,
            turbulence_sigma_m_s: 0.1f64.sqrt(),
            gust_omega_rad_s: 4.0 * PI,
            longitude_omega_rad_s: 2.0 * PI / 3.0,
            latitude_omega_rad_s: 2.0 * PI / 5.0,
        }
    }
}

impl ThesisWindConfig {
    fn validate(&self) -> Result<(), WindError> {
        check(
            "thesis.max_gust_m_s",
            self.max_gust_m_s,
            self.max_gust_m_s >= 0.0,
            ">= 0",
        )?;
        check(
            "thesis.turbulence_sigma_m_s",
            self.turbulence_sigma_m_s,
            self.turbulence_sigma_m_s >= 0.0,
            ">= 0",
        )?;
        check(
            "thesis.gust_omega_rad_s",
            self.gust_omega_rad_s,
            true,
            "finite",
        )?;
        check(
            "thesis.longitude_omega_rad_s",
            self.longitude_omega_rad_s,
            true,
            "finite",
        )?;
        check(
            "thesis.latitude_omega_rad_s",
            self.latitude_omega_rad_s,
            true,
            "finite",
        )?;
        Ok(())
    }

    /// Deterministic part of the speed (14.38): `|w_max|/2 · sin(ω_g t) + |w_max|/2`.
    pub fn gust_speed(&self, t_s: f64) -> f64 {
        0.5 * self.max_gust_m_s * (self.gust_omega_rad_s * t_s).sin() + 0.5 * self.max_gust_m_s
    }

    /// Unit direction (14.40) with longitude (14.41) `θ_w = π sin(ω_θ t) + π`
    /// and latitude (14.42) `φ_w = (π/2) sin(ω_φ t) + π/2`.
    pub fn direction(&self, t_s: f64) -> Vector3<f64> {
        let theta_w = PI * (self.longitude_omega_rad_s * t_s).sin() + PI;
        let phi_w = 0.5 * PI * (self.latitude_omega_rad_s * t_s).sin() + 0.5 * PI;
        Vector3::new(
            theta_w.cos() * phi_w.sin(),
            theta_w.sin() * phi_w.sin(),
            phi_w.cos(),
        )
    }
}

/// The thesis's wind model (14.38)–(14.42) with its own RNG stream.
///
/// `|w(t)| = N(0, σ_t²) + |w_max|/2 sin(ω_g t) + |w_max|/2` (14.38), a fresh
/// independent normal sample at every call, times the direction (14.40). As in
/// the thesis the "speed" may become negative when the noise exceeds the gust
/// term (the vector then points the other way); it is kept exactly. Being
/// sampled white noise, its spectral intensity depends on the call rate — that
/// is a property of the thesis model; use [`DrydenTurbulence`] for turbulence
/// independent of the time step.
#[derive(Debug, Clone)]
pub struct ThesisWind {
    /// Parameters.
    pub config: ThesisWindConfig,
    rng: ChaCha8Rng,
}

impl ThesisWind {
    /// A new model; `seed` and `stream` select the random sequence.
    pub fn new(config: ThesisWindConfig, seed: u64, stream: u64) -> Result<Self, WindError> {
        config.validate()?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(stream);
        Ok(Self { config, rng })
    }

    /// The speed `|w(t)|` (14.38) of the next sample and its direction.
    pub fn sample(&mut self, t_s: f64) -> (f64, Vector3<f64>) {
        let n: f64 = StandardNormal.sample(&mut self.rng);
        let speed = self.config.turbulence_sigma_m_s * n + self.config.gust_speed(t_s);
        (speed, self.config.direction(t_s))
    }
}

impl WindModel for ThesisWind {
    fn step(&mut self, t_s: f64, _dt_s: f64) -> Vector3<f64> {
        let (speed, dir) = self.sample(t_s);
        dir * speed
    }
}

// ---------------------------------------------------------------- Dryden

/// Dryden turbulence parameters (MIL-F-8785C, low altitude, h < 1000 ft).
///
/// `σ_w = 0.1 W₂₀`, `σ_u = σ_v = σ_w / (0.177 + 0.000823 h)^0.4`,
/// `L_w = h`, `L_u = L_v = h / (0.177 + 0.000823 h)^1.2` (h, L in ft; converted
/// here). Components: u along the mean-wind heading, v horizontal to its
/// right, w down (the low-altitude turbulence axes are aligned with the mean
/// wind). Taylor's frozen-turbulence hypothesis uses the airspeed `V`; for a
/// hovering helicopter it is ill-defined and should be set to a representative
/// relative speed (≥ 0.5 m/s here).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DrydenConfig {
    /// Wind speed at 20 ft (6.1 m), `W₂₀` (m/s): 7.7 light, 15.4 moderate, 23 severe.
    pub w20_m_s: f64,
    /// Altitude above ground (m), clamped to ≥ 10 ft (3.05 m) per the standard.
    pub altitude_m: f64,
    /// Airspeed `V` (m/s) for the frozen-turbulence time scale, ≥ 0.5.
    pub airspeed_m_s: f64,
    /// Mean-wind heading (rad, from north towards east) defining the u axis.
    pub heading_rad: f64,
}

impl Default for DrydenConfig {
    /// Light turbulence (W₂₀ = 7.7 m/s ≈ 15 kt) at 10 m, V = 5 m/s.
    fn default() -> Self {
        Self {
            w20_m_s: 7.7,
            altitude_m: 10.0,
            airspeed_m_s: 5.0,
            heading_rad: 0.0,
        }
    }
}

/// Derived Dryden scales.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrydenScales {
    /// σ of u, v, w (m/s).
    pub sigma_m_s: [f64; 3],
    /// Scale lengths L_u, L_v, L_w (m).
    pub length_m: [f64; 3],
    /// Airspeed V (m/s).
    pub airspeed_m_s: f64,
}

impl DrydenConfig {
    fn validate(&self) -> Result<(), WindError> {
        check("dryden.w20_m_s", self.w20_m_s, self.w20_m_s >= 0.0, ">= 0")?;
        check(
            "dryden.altitude_m",
            self.altitude_m,
            self.altitude_m >= 0.0 && self.altitude_m < 1000.0 * FT,
            "0 <= h < 304.8 m (low-altitude model)",
        )?;
        check(
            "dryden.airspeed_m_s",
            self.airspeed_m_s,
            self.airspeed_m_s >= 0.5,
            ">= 0.5",
        )?;
        check("dryden.heading_rad", self.heading_rad, true, "finite")?;
        Ok(())
    }

    /// The MIL-F-8785C low-altitude intensities and scale lengths.
    pub fn scales(&self) -> DrydenScales {
        let h_ft = (self.altitude_m / FT).max(10.0);
        let k = 0.177 + 0.000823 * h_ft;
        let sigma_w = 0.1 * self.w20_m_s;
        let sigma_uv = sigma_w / k.powf(0.4);
        let l_uv = h_ft / k.powf(1.2) * FT;
        let l_w = h_ft * FT;
        DrydenScales {
            sigma_m_s: [sigma_uv, sigma_uv, sigma_w],
            length_m: [l_uv, l_uv, l_w],
            airspeed_m_s: self.airspeed_m_s,
        }
    }
}

impl DrydenScales {
    /// Analytic one-sided PSD in (m/s)²/Hz of component `axis` (0 u, 1 v, 2 w)
    /// at `f_hz`, MIL-F-8785C: with Ω = 2πf and `τ = L/V`,
    /// `Φ_u = σ² (2L/πV) / (1 + (τΩ)²)`, `Φ_{v,w} = σ² (L/πV)(1 + 3(τΩ)²)/(1 + (τΩ)²)²`
    /// per rad/s (integrating to σ² over 0…∞), times 2π per Hz.
    pub fn psd_one_sided(&self, axis: usize, f_hz: f64) -> f64 {
        let s = self.sigma_m_s[axis];
        let l = self.length_m[axis];
        let v = self.airspeed_m_s;
        let x = l / v * 2.0 * PI * f_hz;
        let per_rad = if axis == 0 {
            s * s * 2.0 * l / (PI * v) / (1.0 + x * x)
        } else {
            s * s * l / (PI * v) * (1.0 + 3.0 * x * x) / (1.0 + x * x).powi(2)
        };
        2.0 * PI * per_rad
    }
}

/// Exactly discretised second-order shaping filter (one axis).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Shaping2 {
    /// Continuous A, noise input b = [0, 1], output c.
    a: Matrix2<f64>,
    c: Vector2<f64>,
    phi: Matrix2<f64>,
    chol: Matrix2<f64>,
    dt: f64,
    x: Vector2<f64>,
}

/// Intensity of the continuous white noise driving the shaping filters, so
/// that `∫₀^∞ |H(jΩ)|² dΩ = σ²` gives variance σ² (two-sided density π).
const NOISE_INTENSITY: f64 = PI;

impl Shaping2 {
    /// `H(s) = g (1 + √3 τ s)/(1 + τ s)²` (v, w) or, with `first_order`,
    /// `g/(1 + τ s)` realised in the same 2-state form (u: an extra stable
    /// mode not observed).
    fn new(gain: f64, tau: f64, first_order: bool) -> Self {
        // Companion form: x1' = x2, x2' = −x1/τ² − 2 x2/τ + η.
        let a = if first_order {
            // x1' = −x1/τ + η… realised as state 2 drives nothing: use
            // x2' = −x2/τ + η, x1' = −x1/τ (unobserved, stays 0).
            Matrix2::new(-1.0 / tau, 0.0, 0.0, -1.0 / tau)
        } else {
            Matrix2::new(0.0, 1.0, -1.0 / (tau * tau), -2.0 / tau)
        };
        let c = if first_order {
            // g/(1+τs) = (g/τ)/(s + 1/τ).
            Vector2::new(0.0, gain / tau)
        } else {
            Vector2::new(gain / (tau * tau), gain * 3f64.sqrt() / tau)
        };
        Self {
            a,
            c,
            phi: Matrix2::identity(),
            chol: Matrix2::zeros(),
            dt: f64::NAN,
            x: Vector2::zeros(),
        }
    }

    /// Stationary covariance: Lyapunov `A P + P Aᵀ + S b bᵀ = 0`.
    fn stationary(&self, tau: f64, first_order: bool) -> Matrix2<f64> {
        if first_order {
            Matrix2::new(0.0, 0.0, 0.0, NOISE_INTENSITY * tau / 2.0)
        } else {
            // Companion form with a0 = 1/τ², a1 = 2/τ: P = diag(S/(2 a0 a1), S/(2 a1)).
            Matrix2::new(
                NOISE_INTENSITY * tau.powi(3) / 4.0,
                0.0,
                0.0,
                NOISE_INTENSITY * tau / 4.0,
            )
        }
    }

    /// Exact discretisation by Van Loan's method: `Φ = e^{A dt}`,
    /// `Q_d = ∫₀^dt e^{Aτ} S b bᵀ e^{Aᵀτ} dτ`.
    fn discretise(&mut self, dt: f64) {
        let mut m = Matrix4::zeros();
        m.fixed_view_mut::<2, 2>(0, 0).copy_from(&(-self.a * dt));
        m[(1, 3)] = NOISE_INTENSITY * dt; // S b bᵀ with b = [0, 1]
        m.fixed_view_mut::<2, 2>(2, 2)
            .copy_from(&(self.a.transpose() * dt));
        let e = m.exp();
        let g12 = e.fixed_view::<2, 2>(0, 2).into_owned();
        let phi = e.fixed_view::<2, 2>(2, 2).transpose();
        let mut qd = phi * g12;
        qd = (qd + qd.transpose()) * 0.5;
        // 2×2 Cholesky with a guard for the (exactly) singular first-order case.
        let l11 = qd[(0, 0)].max(0.0).sqrt();
        let l21 = if l11 > 0.0 { qd[(1, 0)] / l11 } else { 0.0 };
        let l22 = (qd[(1, 1)] - l21 * l21).max(0.0).sqrt();
        self.phi = phi;
        self.chol = Matrix2::new(l11, 0.0, l21, l22);
        self.dt = dt;
    }

    fn step(&mut self, dt: f64, n: Vector2<f64>) -> f64 {
        if dt > 0.0 {
            if dt != self.dt {
                self.discretise(dt);
            }
            self.x = self.phi * self.x + self.chol * n;
        }
        self.c.dot(&self.x)
    }
}

/// Dryden turbulence (MIL-F-8785C low altitude) as exactly discretised
/// shaping filters: the sampled process has the continuous-time statistics
/// (σ, autocorrelation) whatever the step, so its intensity does not depend
/// on `dt`. The state starts in its stationary distribution.
#[derive(Debug, Clone)]
pub struct DrydenTurbulence {
    /// Parameters.
    pub config: DrydenConfig,
    scales: DrydenScales,
    filters: [Shaping2; 3],
    rng: ChaCha8Rng,
}

impl DrydenTurbulence {
    /// A new model; `seed` and `stream` select the random sequence.
    pub fn new(config: DrydenConfig, seed: u64, stream: u64) -> Result<Self, WindError> {
        config.validate()?;
        let scales = config.scales();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(stream);
        let v = scales.airspeed_m_s;
        let mut filters = [Shaping2::new(0.0, 1.0, true); 3];
        for (axis, f) in filters.iter_mut().enumerate() {
            let (s, l) = (scales.sigma_m_s[axis], scales.length_m[axis]);
            let tau = l / v;
            let first = axis == 0;
            let gain = if first {
                s * (2.0 * l / (PI * v)).sqrt()
            } else {
                s * (l / (PI * v)).sqrt()
            };
            *f = Shaping2::new(gain, tau, first);
            // Stationary initial state: x0 = chol(P∞) n.
            let p = f.stationary(tau, first);
            let n0: Vector2<f64> = Vector2::new(
                StandardNormal.sample(&mut rng),
                StandardNormal.sample(&mut rng),
            );
            f.x = Vector2::new(p[(0, 0)].sqrt() * n0.x, p[(1, 1)].sqrt() * n0.y);
        }
        Ok(Self {
            config,
            scales,
            filters,
            rng,
        })
    }

    /// The derived intensities and scale lengths.
    pub fn scales(&self) -> &DrydenScales {
        &self.scales
    }

    /// Advance by `dt_s` and return the turbulence `[u, v, w]` in the
    /// mean-wind axes (m/s).
    pub fn step_uvw(&mut self, dt_s: f64) -> Vector3<f64> {
        let mut out = Vector3::zeros();
        for axis in 0..3 {
            let n = Vector2::new(
                StandardNormal.sample(&mut self.rng),
                StandardNormal.sample(&mut self.rng),
            );
            out[axis] = self.filters[axis].step(dt_s, n);
        }
        out
    }
}

impl WindModel for DrydenTurbulence {
    fn step(&mut self, _t_s: f64, dt_s: f64) -> Vector3<f64> {
        let uvw = self.step_uvw(dt_s);
        let (s, c) = self.config.heading_rad.sin_cos();
        Vector3::new(c * uvw.x - s * uvw.y, s * uvw.x + c * uvw.y, uvw.z)
    }
}

// ---------------------------------------------------------------- composite

/// Wind configuration (TOML): every present section adds a component.
///
/// ```toml
/// seed = 7
/// [steady]
/// wind_ned_m_s = [3.0, 1.0, 0.0]
/// [dryden]
/// w20_m_s = 7.7
/// altitude_m = 10.0
/// airspeed_m_s = 5.0
/// ```
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindConfig {
    /// Seed of the random streams (thesis noise and Dryden).
    #[serde(default)]
    pub seed: u64,
    /// Steady wind.
    #[serde(default)]
    pub steady: Option<SteadyWindConfig>,
    /// 1-cosine discrete gust.
    #[serde(default)]
    pub gust: Option<OneMinusCosineGust>,
    /// The thesis's wind model (14.38)–(14.42).
    #[serde(default)]
    pub thesis: Option<ThesisWindConfig>,
    /// Dryden turbulence.
    #[serde(default)]
    pub dryden: Option<DrydenConfig>,
}

impl WindConfig {
    /// Parse TOML text; `file` names the source in errors (TOML errors name
    /// the key; range errors the dotted field).
    pub fn from_toml_str(text: &str, file: &str) -> Result<Self, WindConfigError> {
        let cfg: Self = toml::from_str(text).map_err(|e| WindConfigError::Parse {
            file: file.to_string(),
            message: e.to_string(),
        })?;
        // Validate by building once (same checks as `Wind::from_config`).
        Wind::from_config(&cfg).map_err(|e| e.within(file, ""))?;
        Ok(cfg)
    }

    /// Load and validate a TOML file.
    pub fn from_file(path: &std::path::Path) -> Result<Self, WindConfigError> {
        let (file, text) = helicon_model::ConfigError::read_file(path)?;
        Self::from_toml_str(&text, &file)
    }
}

/// Error loading a wind configuration file (the one configuration error shape).
pub type WindConfigError = helicon_model::ConfigError;

/// The sum of the configured wind components.
#[derive(Debug, Clone)]
pub struct Wind {
    steady: Option<SteadyWindConfig>,
    gust: Option<OneMinusCosineGust>,
    thesis: Option<ThesisWind>,
    dryden: Option<DrydenTurbulence>,
}

impl Wind {
    /// Build from a configuration (validated; thesis and Dryden get their own
    /// streams of the seed).
    pub fn from_config(config: &WindConfig) -> Result<Self, WindError> {
        if let Some(s) = &config.steady {
            for v in s.wind_ned_m_s {
                check("steady.wind_ned_m_s", v, true, "finite")?;
            }
        }
        if let Some(g) = &config.gust {
            g.validate()?;
        }
        Ok(Self {
            steady: config.steady,
            gust: config.gust,
            thesis: config
                .thesis
                .map(|c| ThesisWind::new(c, config.seed, 1))
                .transpose()?,
            dryden: config
                .dryden
                .map(|c| DrydenTurbulence::new(c, config.seed, 2))
                .transpose()?,
        })
    }

    /// Calm air.
    pub fn calm() -> Self {
        Self {
            steady: None,
            gust: None,
            thesis: None,
            dryden: None,
        }
    }
}

impl WindModel for Wind {
    fn step(&mut self, t_s: f64, dt_s: f64) -> Vector3<f64> {
        let mut w = Vector3::zeros();
        if let Some(s) = &mut self.steady {
            w += s.step(t_s, dt_s);
        }
        if let Some(g) = &mut self.gust {
            w += g.step(t_s, dt_s);
        }
        if let Some(m) = &mut self.thesis {
            w += m.step(t_s, dt_s);
        }
        if let Some(m) = &mut self.dryden {
            w += m.step(t_s, dt_s);
        }
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn one_minus_cosine_shape() {
        let g = OneMinusCosineGust {
            start_s: 1.0,
            duration_s: 2.0,
            peak_ned_m_s: [4.0, 0.0, -2.0],
        };
        assert_eq!(g.at(0.5), Vector3::zeros());
        assert_relative_eq!(g.at(2.0), Vector3::new(4.0, 0.0, -2.0), epsilon = 1e-12);
        assert_relative_eq!(g.at(3.0), Vector3::zeros(), epsilon = 1e-12);
        assert_relative_eq!(g.at(1.5), Vector3::new(2.0, 0.0, -1.0), epsilon = 1e-12);
    }

    #[test]
    fn dryden_scales_match_mil_f_8785c_at_20_ft() {
        // h = 20 ft: k = 0.177 + 0.01646 = 0.19346; σ_u/σ_w = k^-0.4 = 1.929.
        let c = DrydenConfig {
            w20_m_s: 10.0,
            altitude_m: 20.0 * FT,
            airspeed_m_s: 10.0,
            heading_rad: 0.0,
        };
        let s = c.scales();
        assert_relative_eq!(s.sigma_m_s[2], 1.0, epsilon = 1e-12);
        assert_relative_eq!(s.sigma_m_s[0], 0.19346f64.powf(-0.4), epsilon = 1e-9);
        assert_relative_eq!(s.length_m[2], 20.0 * FT, epsilon = 1e-12);
        assert_relative_eq!(
            s.length_m[0],
            20.0 / 0.19346f64.powf(1.2) * FT,
            epsilon = 1e-9
        );
    }

    #[test]
    fn discretisation_matches_closed_form_first_order() {
        let mut f = Shaping2::new(1.0, 2.0, true);
        f.discretise(0.1);
        let e = (-0.1f64 / 2.0).exp();
        assert_relative_eq!(f.phi[(1, 1)], e, epsilon = 1e-14);
        let q = NOISE_INTENSITY * 2.0 / 2.0 * (1.0 - (-2.0 * 0.1f64 / 2.0).exp());
        assert_relative_eq!(f.chol[(1, 1)].powi(2), q, epsilon = 1e-13);
    }

    #[test]
    fn wind_toml_sum_and_errors() {
        let cfg = WindConfig::from_toml_str(
            "seed = 3\n[steady]\nwind_ned_m_s = [3.0, 1.0, 0.0]\n[gust]\nstart_s = 1.0\nduration_s = 2.0\npeak_ned_m_s = [0.0, 2.0, 0.0]\n",
            "w.toml",
        )
        .unwrap();
        let mut w = Wind::from_config(&cfg).unwrap();
        assert_relative_eq!(
            w.step(2.0, 0.01),
            Vector3::new(3.0, 3.0, 0.0),
            epsilon = 1e-12
        );
        let e = WindConfig::from_toml_str("[dryden]\nairspeed_m_s = 0.1\n", "x.toml").unwrap_err();
        let m = e.to_string();
        assert!(
            m.contains("x.toml") && m.contains("dryden.airspeed_m_s"),
            "{m}"
        );
        let e = WindConfig::from_toml_str("[thesis]\nsigma = 1.0\n", "y.toml").unwrap_err();
        let m = e.to_string();
        assert!(m.contains("y.toml") && m.contains("sigma"), "{m}");
        let mut calm = Wind::calm();
        assert_eq!(calm.step(0.0, 0.01), Vector3::zeros());
    }

    #[test]
    fn invalid_config_names_field() {
        let c = DrydenConfig {
            airspeed_m_s: 0.0,
            ..Default::default()
        };
        let e = DrydenTurbulence::new(c, 0, 0).unwrap_err();
        assert!(e.to_string().contains("dryden.airspeed_m_s"));
    }
}
