//! Servo identification, thesis (5.1)–(5.4): the gain K, natural frequency
//! ωn, damping ζ and (when the data reach it) the rate limit of one servo
//! channel from a log of its command and its measured position (a bench
//! test with a potentiometer, or a flight log with the servo feedback).
//!
//! The model is the one the helicopter model flies, integrated the same way:
//!
//! θ̈ = K ωn² sat(S) − 2ζ ωn θ̇ − ωn² θ,
//!
//! the command S clipped to [S_min, S_max] (known, not identified), the
//! rate limit a *limited integrator* (the position moves at clip(θ̇, ±θ̇max);
//! the rate state stops accelerating outward once |θ̇| ≥ θ̇max), the command
//! held over each sample (zero-order hold) and one classical RK4 step per
//! sample (or `substeps` of them). The measured position is θ + b, b a
//! potentiometer offset; the log must start with the servo at rest at the
//! first command (θ = K sat(S₀), θ̇ = 0).
//!
//! The fit is a time-domain output-error fit: Levenberg–Marquardt on the
//! residuals y_model − y_measured with a central-difference Jacobian,
//! started from a grid search over (ωn, ζ) in which K and b are solved by
//! linear least squares. Standard errors are Cramér–Rao style, from the
//! residual: cov = σ̂² (JᵀJ)⁻¹ with σ̂² = RSS/(N − p) (exact for white
//! measurement noise). The rate limit is fitted only when the data show it:
//! a linear fit (no limit) and a limited fit are compared by the likelihood
//! ratio N ln(RSS_lin/RSS_lim) (χ²₁ under "no limit"); below the threshold,
//! or when the limited fit never engages its limit, the rate limit is
//! reported as not reached, with the fastest rate the data exercised as a
//! lower bound — never guessed.

use crate::error::{IdentError, Result};
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Dyn, Owned};
use serde::Serialize;

/// One servo channel of (5.1)–(5.4).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ServoModel {
    /// K, DC gain (rad per unit command).
    pub gain_rad: f64,
    /// ωn, natural frequency (rad/s).
    pub omega_n_rad_s: f64,
    /// ζ, damping ratio.
    pub zeta: f64,
    /// θ̇max, rate limit (rad/s); `f64::INFINITY` for none.
    pub rate_max_rad_s: f64,
    /// S_min, lower command saturation (`f64::NEG_INFINITY` for none).
    pub s_min: f64,
    /// S_max, upper command saturation (`f64::INFINITY` for none).
    pub s_max: f64,
}

impl ServoModel {
    /// Time derivatives `(θ̇_position, θ̈)` at command `s_cmd` and state
    /// `(θ, θ̇)`: the helicopter model's servo block (5.1)–(5.4),
    /// `helicon_model::actuators::servo_derivative`.
    #[inline]
    pub fn derivative(&self, s_cmd: f64, theta_rad: f64, theta_dot_rad_s: f64) -> (f64, f64) {
        helicon_model::actuators::servo_derivative(
            &self.as_servo(),
            s_cmd,
            theta_rad,
            theta_dot_rad_s,
        )
    }

    /// The model's servo parameters of this channel.
    pub fn as_servo(&self) -> helicon_model::params::Servo {
        helicon_model::params::Servo {
            gain_rad: self.gain_rad,
            omega_n_rad_s: self.omega_n_rad_s,
            zeta: self.zeta,
            rate_max_rad_s: self.rate_max_rad_s,
            s_min: self.s_min,
            s_max: self.s_max,
        }
    }

    /// One RK4 step of length `dt_s` with the command held, the stages
    /// combined as the helicopter model's integrator combines them.
    #[inline]
    pub fn rk4_step(&self, s_cmd: f64, x: [f64; 2], dt_s: f64) -> [f64; 2] {
        let f = |x: [f64; 2]| {
            let (a, b) = self.derivative(s_cmd, x[0], x[1]);
            [a, b]
        };
        let k1 = f(x);
        let k2 = f([x[0] + k1[0] * (0.5 * dt_s), x[1] + k1[1] * (0.5 * dt_s)]);
        let k3 = f([x[0] + k2[0] * (0.5 * dt_s), x[1] + k2[1] * (0.5 * dt_s)]);
        let k4 = f([x[0] + k3[0] * dt_s, x[1] + k3[1] * dt_s]);
        let c = |j: usize| x[j] + (k1[j] + (k2[j] + k3[j]) * 2.0 + k4[j]) * (dt_s / 6.0);
        [c(0), c(1)]
    }

    /// The state `[θ, θ̇]` at every sample of `commands` (sample k's command
    /// held over [t_k, t_k + dt)), from `x0` at sample 0, with `substeps`
    /// RK4 steps per sample.
    pub fn simulate(
        &self,
        commands: &[f64],
        dt_s: f64,
        substeps: usize,
        x0: [f64; 2],
    ) -> Vec<[f64; 2]> {
        let n_sub = substeps.max(1);
        let h = dt_s / n_sub as f64;
        let mut out = Vec::with_capacity(commands.len());
        let mut x = x0;
        for &s in commands {
            out.push(x);
            for _ in 0..n_sub {
                x = self.rk4_step(s, x, h);
            }
        }
        out
    }

    /// The state at rest under command `s`: `[K sat(s), 0]`.
    pub fn rest(&self, s: f64) -> [f64; 2] {
        [self.gain_rad * s.clamp(self.s_min, self.s_max), 0.0]
    }
}

/// Options of [`fit_servo`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoFitOptions {
    /// RK4 steps per log sample (1: the helicopter model's own scheme when the
    /// log's sample time is the model's step).
    pub substeps: usize,
    /// Known lower command saturation (`f64::NEG_INFINITY` for none).
    pub s_min: f64,
    /// Known upper command saturation (`f64::INFINITY` for none).
    pub s_max: f64,
    /// Likelihood-ratio threshold for accepting a rate limit: 10.83, the
    /// χ²₁ quantile at 0.1 % (a limit is reported only when the data make
    /// "no limit" that unlikely).
    pub lr_threshold: f64,
    /// Fewest samples the fitted response must spend on the limit for the
    /// limit to count as seen (5).
    pub min_samples_on_limit: usize,
}

impl Default for ServoFitOptions {
    fn default() -> Self {
        Self {
            substeps: 1,
            s_min: f64::NEG_INFINITY,
            s_max: f64::INFINITY,
            lr_threshold: 10.83,
            min_samples_on_limit: 5,
        }
    }
}

/// A parameter estimate and its standard error.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Estimate {
    /// The value.
    pub value: f64,
    /// Its standard error (one σ, Cramér–Rao style from the residual).
    pub std_error: f64,
}

/// What the data say about the rate limit.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum RateLimit {
    /// The data reach the limit: its estimate.
    Identified {
        /// θ̇max (rad/s) and its standard error.
        rate_max_rad_s: Estimate,
        /// Samples the fitted response spends on the limit.
        samples_on_limit: usize,
    },
    /// The data do not reach a limit: it is at least `lower_bound_rad_s`
    /// (the fastest rate of the fitted response), not identifiable here.
    NotReached {
        /// The fastest position rate the fitted (unlimited) response reaches, rad/s.
        lower_bound_rad_s: f64,
        /// Why it was not identified.
        reason: String,
    },
}

/// The identified servo.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ServoFit {
    /// K, rad per unit command.
    pub gain_rad: Estimate,
    /// ωn, rad/s.
    pub omega_n_rad_s: Estimate,
    /// ζ.
    pub zeta: Estimate,
    /// b, the measured position's offset (rad).
    pub position_offset_rad: Estimate,
    /// The rate limit, or why it is not identified.
    pub rate_limit: RateLimit,
    /// RMS of the residual y_model − y_measured at the optimum (rad).
    pub residual_rms_rad: f64,
    /// RMS of the residual of the fit without a rate limit (rad).
    pub residual_rms_linear_rad: f64,
    /// N ln(RSS_lin / RSS_lim), the likelihood-ratio statistic of the limit
    /// (0 when no limited fit improved on the linear one).
    pub lr_statistic: f64,
    /// Parameter correlation matrix, in the order K, ωn, ζ, b (, θ̇max).
    pub correlation: Vec<Vec<f64>>,
    /// Samples used.
    pub n_samples: usize,
    /// Sample time, s.
    pub dt_s: f64,
    /// Simulations run by the optimiser (residual and Jacobian evaluations).
    pub evaluations: usize,
    /// The fitted model (rate limit infinite when not identified), for overlays.
    pub model: ServoModel,
}

impl ServoFit {
    /// The fitted measured position at every sample of `commands`
    /// (θ + b, from rest at the first command).
    pub fn predict(&self, commands: &[f64], substeps: usize) -> Vec<f64> {
        predict(
            &self.model,
            self.position_offset_rad.value,
            commands,
            self.dt_s,
            substeps,
        )
    }
}

fn predict(m: &ServoModel, offset: f64, cmd: &[f64], dt: f64, substeps: usize) -> Vec<f64> {
    let x0 = cmd.first().map_or([0.0, 0.0], |s| m.rest(*s));
    m.simulate(cmd, dt, substeps, x0)
        .iter()
        .map(|x| x[0] + offset)
        .collect()
}

/// The output-error problem; parameters [K, ωn, ζ, b] or [K, ωn, ζ, b, θ̇max].
struct Problem<'a> {
    cmd: &'a [f64],
    y: &'a [f64],
    dt: f64,
    opts: ServoFitOptions,
    p: DVector<f64>,
    evaluations: std::cell::Cell<usize>,
}

impl Problem<'_> {
    fn residuals_at(&self, p: &DVector<f64>) -> Option<DVector<f64>> {
        if p[1] <= 0.0 || p[2] <= 0.0 || (p.len() > 4 && p[4] <= 0.0) {
            return None;
        }
        self.evaluations.set(self.evaluations.get() + 1);
        let (m, b) = model_and_offset(p, &self.opts);
        let yp = predict(&m, b, self.cmd, self.dt, self.opts.substeps);
        let r = DVector::from_iterator(self.y.len(), yp.iter().zip(self.y).map(|(a, b)| a - b));
        r.iter().all(|v| v.is_finite()).then_some(r)
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.p.copy_from(x);
    }

    fn params(&self) -> DVector<f64> {
        self.p.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        self.residuals_at(&self.p)
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let np = self.p.len();
        let mut jac = DMatrix::zeros(self.y.len(), np);
        for j in 0..np {
            // central differences, step relative to the parameter (the offset b
            // on the scale of the gain, as positions are K·S)
            let scale = if j == 3 {
                self.p[0].abs().max(1e-3)
            } else {
                self.p[j].abs().max(1e-9)
            };
            let h = 1e-6 * scale;
            let mut pp = self.p.clone();
            pp[j] += h;
            let rp = self.residuals_at(&pp)?;
            pp[j] -= 2.0 * h;
            let rm = self.residuals_at(&pp)?;
            jac.set_column(j, &((rp - rm) / (2.0 * h)));
        }
        Some(jac)
    }
}

/// Result of one LM run: parameters, RSS, Jacobian at the optimum.
struct Solved {
    p: DVector<f64>,
    rss: f64,
    jac: DMatrix<f64>,
}

fn solve(
    cmd: &[f64],
    y: &[f64],
    dt: f64,
    opts: ServoFitOptions,
    start: DVector<f64>,
    evals: &mut usize,
) -> Option<Solved> {
    let problem = Problem {
        cmd,
        y,
        dt,
        opts,
        p: start,
        evaluations: std::cell::Cell::new(0),
    };
    let (problem, report) = LevenbergMarquardt::new()
        .with_patience(200)
        .with_ftol(1e-15)
        .with_xtol(1e-15)
        .minimize(problem);
    *evals += problem.evaluations.get();
    if report.termination.was_usage_issue() {
        return None;
    }
    let r = problem.residuals()?;
    let jac = problem.jacobian()?;
    *evals += problem.evaluations.get();
    Some(Solved {
        rss: r.norm_squared(),
        p: problem.p,
        jac,
    })
}

/// Start values: a grid over ωn (`nw` log-spaced values from the record
/// length to the Nyquist frequency) and ζ, with K and b from linear least
/// squares on each unit-gain response. With a rate limit the channel is
/// homogeneous in K (θ = K φ, φ the unit-gain response limited to
/// θ̇max/|K|), so K and b stay a linear least-squares problem for a given
/// unit-gain limit `unit_limit` (∞: none): `(RSS, [K, ωn, ζ, b])` of the best
/// grid point.
fn grid_start(
    cmd: &[f64],
    y: &[f64],
    dt: f64,
    opts: ServoFitOptions,
    unit_limit: f64,
    nw: usize,
    zetas: &[f64],
) -> Option<(f64, [f64; 4])> {
    let n = cmd.len() as f64;
    let (w_lo, w_hi) = (2.0 * std::f64::consts::PI / (n * dt), 0.9 / dt);
    let mut best: Option<(f64, [f64; 4])> = None;
    for i in 0..nw {
        let wn = w_lo * (w_hi / w_lo).powf(i as f64 / (nw - 1) as f64);
        for &zeta in zetas {
            let m = ServoModel {
                gain_rad: 1.0,
                omega_n_rad_s: wn,
                zeta,
                rate_max_rad_s: unit_limit,
                s_min: opts.s_min,
                s_max: opts.s_max,
            };
            let g = predict(&m, 0.0, cmd, dt, opts.substeps);
            // y ≈ K g + b
            let (sg, sy) = (g.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
            let sgg: f64 = g.iter().map(|v| (v - sg) * (v - sg)).sum();
            let sgy: f64 = g.iter().zip(y).map(|(a, b)| (a - sg) * (b - sy)).sum();
            if sgg.is_nan() || sgg <= 0.0 {
                continue;
            }
            let k = sgy / sgg;
            let b = sy - k * sg;
            let rss: f64 = g.iter().zip(y).map(|(a, c)| (k * a + b - c).powi(2)).sum();
            if rss.is_finite() && best.is_none_or(|(r, _)| rss < r) {
                best = Some((rss, [k, wn, zeta, b]));
            }
        }
    }
    best
}

/// Starts of the limited fit: the linear fit's K, ωn, ζ, b with its limit
/// at 0.6 and 0.9 of `peak` (the fastest rate of the linear fit), and the
/// two best points of a grid over ωn, ζ and the unit-gain limit (0.15 …
/// 0.9 of `peak`/|K|), which finds the servo when heavy rate limiting has
/// biased the linear fit.
fn limited_starts(
    cmd: &[f64],
    y: &[f64],
    dt: f64,
    opts: ServoFitOptions,
    lin: &DVector<f64>,
    peak: f64,
) -> Vec<DVector<f64>> {
    let mut starts: Vec<DVector<f64>> = [0.6, 0.9]
        .iter()
        .map(|f| {
            let mut p: Vec<f64> = lin.iter().copied().collect();
            p.push(f * peak);
            DVector::from_vec(p)
        })
        .collect();
    let k_lin = lin[0].abs().max(1e-12);
    let mut grid: Vec<(f64, Vec<f64>)> = [0.15, 0.3, 0.5, 0.7, 0.9]
        .iter()
        .filter_map(|f| {
            let unit = f * peak / k_lin;
            grid_start(cmd, y, dt, opts, unit, 20, &[0.4, 0.8, 1.3, 2.0])
                .map(|(rss, p)| (rss, vec![p[0], p[1], p[2], p[3], unit * p[0].abs()]))
        })
        .collect();
    grid.sort_by(|a, b| a.0.total_cmp(&b.0));
    starts.extend(grid.into_iter().take(2).map(|(_, p)| DVector::from_vec(p)));
    starts
}

/// Standard errors and correlation from the Jacobian and residual.
fn covariance(s: &Solved, n: usize) -> Result<(Vec<f64>, Vec<Vec<f64>>)> {
    let np = s.p.len();
    let sigma2 = s.rss / (n - np) as f64;
    let info = s.jac.transpose() * &s.jac;
    let inv = info.clone().try_inverse().ok_or_else(|| {
        IdentError::Fit("singular information matrix: the log does not excite the servo".into())
    })?;
    let se: Vec<f64> = (0..np)
        .map(|i| (sigma2 * inv[(i, i)]).max(0.0).sqrt())
        .collect();
    let corr = (0..np)
        .map(|i| {
            (0..np)
                .map(|j| inv[(i, j)] / (inv[(i, i)] * inv[(j, j)]).sqrt())
                .collect()
        })
        .collect();
    Ok((se, corr))
}

/// Samples at which the response of `m` is on its rate limit.
fn samples_on_limit(m: &ServoModel, cmd: &[f64], dt: f64, substeps: usize) -> usize {
    let x0 = cmd.first().map_or([0.0, 0.0], |s| m.rest(*s));
    m.simulate(cmd, dt, substeps, x0)
        .iter()
        .filter(|x| x[1].abs() >= m.rate_max_rad_s)
        .count()
}

/// Check the inputs of [`fit_servo`].
fn check_inputs(cmd: &[f64], y: &[f64], dt: f64, opts: &ServoFitOptions) -> Result<()> {
    crate::error::check_range("dt_s", dt, 1e-7, 10.0)?;
    if cmd.len() != y.len() {
        return Err(IdentError::data(
            "servo log",
            format!("{} commands but {} positions", cmd.len(), y.len()),
        ));
    }
    if cmd.len() < 32 {
        return Err(IdentError::data(
            "servo log",
            format!("{} samples; at least 32 are needed", cmd.len()),
        ));
    }
    if let Some(i) = cmd.iter().chain(y).position(|v| !v.is_finite()) {
        return Err(IdentError::data(
            "servo log",
            format!("sample {} is not finite", i % cmd.len()),
        ));
    }
    if opts.substeps == 0 || opts.substeps > 1000 {
        return Err(IdentError::invalid(
            "substeps",
            opts.substeps as f64,
            "must be 1 … 1000",
        ));
    }
    if opts.s_min.is_nan() || opts.s_max.is_nan() || opts.s_min >= opts.s_max {
        return Err(IdentError::Invalid {
            field: "s_min, s_max".into(),
            value: format!("{}, {}", opts.s_min, opts.s_max),
            rule: "need s_min < s_max".into(),
        });
    }
    let (lo, hi) = cmd
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    if hi - lo <= 0.0 {
        return Err(IdentError::data(
            "servo log",
            "the command is constant: nothing to identify",
        ));
    }
    Ok(())
}

/// Identify the servo from `commands` and measured `positions` (rad)
/// sampled every `dt_s`. Errors: mismatched or short data, non-finite
/// values, a constant command, a fit that fails or whose information
/// matrix is singular.
pub fn fit_servo(
    commands: &[f64],
    positions: &[f64],
    dt_s: f64,
    opts: &ServoFitOptions,
) -> Result<ServoFit> {
    check_inputs(commands, positions, dt_s, opts)?;
    let n = commands.len();
    let mut evals = 0;
    let (_, start) = grid_start(
        commands,
        positions,
        dt_s,
        *opts,
        f64::INFINITY,
        40,
        &[0.3, 0.6, 0.9, 1.3, 2.0],
    )
    .ok_or_else(|| IdentError::Fit("no start value gives a finite response".into()))?;
    let lin = solve(
        commands,
        positions,
        dt_s,
        *opts,
        DVector::from_row_slice(&start),
        &mut evals,
    )
    .ok_or_else(|| IdentError::Fit("the fit without a rate limit failed".into()))?;
    let lin_model = ServoModel {
        gain_rad: lin.p[0],
        omega_n_rad_s: lin.p[1],
        zeta: lin.p[2],
        rate_max_rad_s: f64::INFINITY,
        s_min: opts.s_min,
        s_max: opts.s_max,
    };
    let x0 = lin_model.rest(commands[0]);
    let peak = lin_model
        .simulate(commands, dt_s, opts.substeps, x0)
        .iter()
        .map(|x| x[1].abs())
        .fold(0.0, f64::max);
    // the limited fit from several starts below the unlimited response's peak rate
    let mut limited: Option<Solved> = None;
    for p0 in limited_starts(commands, positions, dt_s, *opts, &lin.p, peak) {
        let s = solve(commands, positions, dt_s, *opts, p0, &mut evals);
        if let Some(s) = s.filter(|s| limited.as_ref().is_none_or(|b| s.rss < b.rss)) {
            limited = Some(s);
        }
    }
    let accepted = limited.and_then(|s| {
        let (m, _) = model_and_offset(&s.p, opts);
        let on = samples_on_limit(&m, commands, dt_s, opts.substeps);
        let lr = lr_statistic(n, lin.rss, s.rss);
        (on >= opts.min_samples_on_limit && lr > opts.lr_threshold).then_some((s, on, lr))
    });
    let rms = |rss: f64| (rss / n as f64).sqrt();
    let lin_rms = rms(lin.rss);
    let (best, rate_limit, lr) = match accepted {
        Some((s, on, lr)) => {
            let (se, _) = covariance(&s, n)?;
            let rl = RateLimit::Identified {
                rate_max_rad_s: Estimate {
                    value: s.p[4],
                    std_error: se[4],
                },
                samples_on_limit: on,
            };
            (s, rl, lr)
        }
        None => (
            lin,
            RateLimit::NotReached {
                lower_bound_rad_s: peak,
                reason: format!(
                    "the data show no rate limit up to {peak:.4} rad/s (the fitted response's fastest rate): \
                     a fit with a limit engages it on fewer than {} samples or does not improve the fit \
                     significantly (likelihood ratio ≤ {}); excite the servo with larger or faster steps",
                    opts.min_samples_on_limit, opts.lr_threshold
                ),
            },
            0.0,
        ),
    };
    let (se, correlation) = covariance(&best, n)?;
    let (model, offset) = model_and_offset(&best.p, opts);
    let est = |i: usize| Estimate {
        value: best.p[i],
        std_error: se[i],
    };
    let fit = ServoFit {
        gain_rad: est(0),
        omega_n_rad_s: est(1),
        zeta: est(2),
        position_offset_rad: Estimate {
            value: offset,
            std_error: se[3],
        },
        rate_limit,
        residual_rms_rad: rms(best.rss),
        residual_rms_linear_rad: lin_rms,
        lr_statistic: lr,
        correlation,
        n_samples: n,
        dt_s,
        evaluations: evals,
        model,
    };
    let finite = [
        fit.gain_rad.value,
        fit.omega_n_rad_s.value,
        fit.zeta.value,
        fit.residual_rms_rad,
    ]
    .iter()
    .chain(&se)
    .all(|v| v.is_finite());
    if !finite {
        return Err(IdentError::Fit("a non-finite estimate".into()));
    }
    Ok(fit)
}

fn model_and_offset(p: &DVector<f64>, opts: &ServoFitOptions) -> (ServoModel, f64) {
    (
        ServoModel {
            gain_rad: p[0],
            omega_n_rad_s: p[1],
            zeta: p[2],
            rate_max_rad_s: if p.len() > 4 { p[4] } else { f64::INFINITY },
            s_min: opts.s_min,
            s_max: opts.s_max,
        },
        p[3],
    )
}

/// N ln(RSS_lin / RSS_lim) (an exact limited fit counts as RSS = the
/// smallest positive f64, so the statistic stays finite), 0 when the
/// limited fit is no better.
fn lr_statistic(n: usize, rss_lin: f64, rss_lim: f64) -> f64 {
    if rss_lim >= rss_lin {
        0.0
    } else {
        n as f64 * (rss_lin / rss_lim.max(f64::MIN_POSITIVE)).ln()
    }
}

/// A bench-test command for a servo: steps of several sizes about the middle
/// of the command range (up, back, down, back, each held `hold_s`), then
/// full-range steps (S_min → S_max → S_min), then a frequency sweep
/// ([`crate::inputs::Sweep`]) about the middle. Small steps show K, ωn and ζ
/// in the linear range; the large ones reach the rate limit; the sweep
/// gives a frequency response to cross-check.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchInput {
    /// Lowest command (the channel's S_min).
    pub s_min: f64,
    /// Highest command (the channel's S_max).
    pub s_max: f64,
    /// Step sizes as fractions of the half range (each in (0, 1]).
    pub step_fractions: Vec<f64>,
    /// Time each step level is held, s.
    pub hold_s: f64,
    /// The sweep after the steps (`None`: no sweep). Its amplitude is in
    /// command units, about the middle of the range.
    pub sweep: Option<crate::inputs::Sweep>,
}

impl BenchInput {
    /// Steps of 0.1, 0.25, 0.5 and 1 of the half range held 0.3 s each, and
    /// a sweep of 0.1 of the half range from 5 to 300 rad/s over 12 s: a
    /// bench test for servos with ωn of some 20 to 200 rad/s.
    pub fn new(s_min: f64, s_max: f64) -> Result<Self> {
        let half = 0.5 * (s_max - s_min);
        let b = BenchInput {
            s_min,
            s_max,
            step_fractions: vec![0.1, 0.25, 0.5, 1.0],
            hold_s: 0.3,
            sweep: Some(crate::inputs::Sweep::new(0.1 * half, 5.0, 300.0, 12.0)?),
        };
        b.check()?;
        Ok(b)
    }

    /// Check every field.
    pub fn check(&self) -> Result<()> {
        if !(self.s_min.is_finite() && self.s_max.is_finite() && self.s_min < self.s_max) {
            return Err(IdentError::Invalid {
                field: "s_min, s_max".into(),
                value: format!("{}, {}", self.s_min, self.s_max),
                rule: "must be finite with s_min < s_max".into(),
            });
        }
        crate::error::check_range("hold_s", self.hold_s, 1e-3, 60.0)?;
        for f in &self.step_fractions {
            if !(f.is_finite() && *f > 0.0 && *f <= 1.0) {
                return Err(IdentError::invalid(
                    "step_fractions",
                    *f,
                    "each must be in (0, 1]",
                ));
            }
        }
        if let Some(s) = &self.sweep {
            s.check()?;
        }
        Ok(())
    }

    /// Total duration, s.
    pub fn duration_s(&self) -> f64 {
        let levels = 4 * self.step_fractions.len() + 3;
        levels as f64 * self.hold_s + self.sweep.map_or(0.0, |s| s.duration_s)
    }

    /// The command every `dt_s` (clipped to [S_min, S_max]).
    pub fn sample(&self, dt_s: f64) -> Result<Vec<f64>> {
        self.check()?;
        crate::error::check_range("dt_s", dt_s, 1e-6, 1.0)?;
        if self.duration_s() / dt_s > 1e8 {
            return Err(IdentError::invalid(
                "dt_s",
                dt_s,
                "gives more than 1e8 samples",
            ));
        }
        let mid = 0.5 * (self.s_min + self.s_max);
        let half = 0.5 * (self.s_max - self.s_min);
        let mut levels = vec![mid];
        for f in &self.step_fractions {
            levels.extend([mid + f * half, mid, mid - f * half, mid]);
        }
        levels.extend([self.s_min, self.s_max]);
        let per = (self.hold_s / dt_s).round().max(1.0) as usize;
        let mut out: Vec<f64> = levels
            .iter()
            .flat_map(|v| std::iter::repeat_n(*v, per))
            .collect();
        if let Some(s) = &self.sweep {
            let n = (s.duration_s / dt_s).round() as usize;
            out.extend((0..n).map(|k| mid + s.value(k as f64 * dt_s)));
        }
        Ok(out
            .into_iter()
            .map(|v| v.clamp(self.s_min, self.s_max))
            .collect())
    }
}
