//! Transfer-function fits to frequency responses with the coherence-weighted
//! cost of rotorcraft practice (CIFER/NAVFIT):
//!
//! J = (20/n_ω) Σ W_γ [W_g (|T̂| − |T|)²_dB + W_p (∠T̂ − ∠T)²_deg],
//! W_g = 1, W_p = 0.01745, W_γ = [1.58 (1 − e^{−γ²})]²,
//!
//! over the points with γ² above a threshold (0.6 by default); the
//! Cramér–Rao bounds and insensitivities of the fitted parameters; and the
//! time-domain verification of a fit on other data (Theil inequality
//! coefficient).
//!
//! The model is T(s) = (b_m s^m + … + b_0)/(s^n + a_{n−1} s^{n−1} + … + a_0)
//! · e^{−τs}. The start comes from a linear least-squares fit (Levy's
//! method with Sanathanan–Koerner reweighting, on a scaled frequency), then
//! Levenberg–Marquardt minimises J with the analytic Jacobian.

pub use crate::cost::{CostOptions, coherence_weight};
use crate::cost::{Points, percent, select, separable_accuracy};
use crate::error::{IdentError, Result};
use crate::frf::Frf;
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Dyn, Owned};
use rustfft::num_complex::Complex64;
use serde::Serialize;

/// The structure of the transfer function to fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TfStructure {
    /// Numerator order m (≤ n).
    pub num_order: usize,
    /// Denominator order n (≥ 1; the denominator is monic).
    pub den_order: usize,
    /// Fit a time delay τ.
    pub delay: bool,
}

/// A fitted transfer function with its cost and accuracy.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TfFit {
    /// Numerator coefficients, highest power first (m + 1 of them).
    pub num: Vec<f64>,
    /// Denominator coefficients, highest power first, the first one 1.
    pub den: Vec<f64>,
    /// Time delay τ, s (0 when not fitted).
    pub delay_s: f64,
    /// The cost J at the optimum.
    pub cost: f64,
    /// Parameter names in the order of the bounds: `b<k>`, `a<k>`, `tau_s`.
    pub names: Vec<String>,
    /// The fitted parameters, in `names` order.
    pub params: Vec<f64>,
    /// Cramér–Rao bounds (one standard deviation), in `names` order;
    /// infinite for a parameter the data do not determine.
    pub cramer_rao: Vec<f64>,
    /// Cramér–Rao bounds in % of the parameter.
    pub cramer_rao_pct: Vec<f64>,
    /// Insensitivities in % of the parameter.
    pub insensitivity_pct: Vec<f64>,
    /// Frequency points used (γ² above the threshold).
    pub n_points: usize,
    /// Cost evaluations used by Levenberg–Marquardt.
    pub evaluations: usize,
}

impl TfFit {
    /// Whether parameter `i` is determined by the data
    /// ([`crate::cost::identifiable`]: Cramér–Rao bound and insensitivity
    /// finite and below [`crate::cost::NOT_IDENTIFIABLE_PCT`] of the value).
    pub fn identifiable(&self, i: usize) -> bool {
        crate::cost::identifiable(self.cramer_rao_pct[i], self.insensitivity_pct[i])
    }

    /// T(jω).
    pub fn eval(&self, omega_rad_s: f64) -> Complex64 {
        let s = Complex64::new(0.0, omega_rad_s);
        poly(&self.num, s) / poly(&self.den, s) * (-s * self.delay_s).exp()
    }
}

/// Σ c_i s^{len−1−i} (highest power first), Horner.
fn poly(c: &[f64], s: Complex64) -> Complex64 {
    c.iter()
        .fold(Complex64::new(0.0, 0.0), |acc, v| acc * s + v)
}

/// The least-squares problem of the cost: residuals [mag, phase] per point.
struct Problem<'a> {
    pts: &'a Points,
    st: TfStructure,
    theta: DVector<f64>,
}

impl Problem<'_> {
    fn split(&self) -> (Vec<f64>, Vec<f64>, f64) {
        let m = self.st.num_order + 1;
        let n = self.st.den_order;
        let num = self.theta.as_slice()[..m].to_vec();
        let mut den = vec![1.0];
        den.extend_from_slice(&self.theta.as_slice()[m..m + n]);
        let tau = if self.st.delay {
            self.theta[m + n]
        } else {
            0.0
        };
        (num, den, tau)
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.theta.copy_from(x);
    }

    fn params(&self) -> DVector<f64> {
        self.theta.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        let (num, den, tau) = self.split();
        let p = self.pts;
        let mut r = DVector::zeros(2 * p.omega.len());
        for (k, &w) in p.omega.iter().enumerate() {
            let s = Complex64::new(0.0, w);
            let t = poly(&num, s) / poly(&den, s) * (-s * tau).exp();
            (r[2 * k], r[2 * k + 1]) = p.residuals(k, t);
        }
        r.iter().all(|v| v.is_finite()).then_some(r)
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let (num, den, _) = self.split();
        let p = self.pts;
        let (m, n) = (self.st.num_order + 1, self.st.den_order);
        let np = self.theta.len();
        let mut jac = DMatrix::zeros(2 * p.omega.len(), np);
        for (k, &w) in p.omega.iter().enumerate() {
            let s = Complex64::new(0.0, w);
            let (nv, dv) = (poly(&num, s), poly(&den, s));
            // d log T / dθ: s^i/N for the numerator, −s^i/D for the denominator, −s for τ.
            for j in 0..np {
                let d = if j < m {
                    s.powu((m - 1 - j) as u32) / nv
                } else if j < m + n {
                    -s.powu((n - 1 - (j - m)) as u32) / dv
                } else {
                    -s
                };
                (jac[(2 * k, j)], jac[(2 * k + 1, j)]) = p.jacobian(k, d);
            }
        }
        jac.iter().all(|v| v.is_finite()).then_some(jac)
    }
}

/// The start: Levy's linear fit N(jω) − T·(D(jω) − (jω)^n) = T·(jω)^n on
/// s/ω_ref, reweighted by 1/|D_prev| (Sanathanan–Koerner, 5 passes),
/// coefficients then unscaled. A delay, when fitted, starts at 0.
fn levy_start(pts: &Points, st: TfStructure) -> Option<Vec<f64>> {
    let (m, n) = (st.num_order + 1, st.den_order);
    let wref = (pts.omega.first()? * pts.omega.last()?).sqrt();
    let mut den_prev = vec![1.0; n + 1];
    let mut theta = vec![0.0; m + n];
    for _ in 0..5 {
        let rows = 2 * pts.omega.len();
        let mut a = DMatrix::zeros(rows, m + n);
        let mut b = DVector::zeros(rows);
        for (k, &w) in pts.omega.iter().enumerate() {
            let s = Complex64::new(0.0, w / wref);
            let wt = (pts.scale_mag[k] + 1e-12) / poly(&den_prev, s).norm();
            let t = pts.h[k];
            for j in 0..m {
                let v = s.powu((m - 1 - j) as u32) * wt;
                a[(2 * k, j)] = v.re;
                a[(2 * k + 1, j)] = v.im;
            }
            for j in 0..n {
                let v = -t * s.powu((n - 1 - j) as u32) * wt;
                a[(2 * k, m + j)] = v.re;
                a[(2 * k + 1, m + j)] = v.im;
            }
            let rhs = t * s.powu(n as u32) * wt;
            b[2 * k] = rhs.re;
            b[2 * k + 1] = rhs.im;
        }
        let sol = a.svd(true, true).solve(&b, 1e-12).ok()?;
        den_prev = std::iter::once(1.0)
            .chain(sol.iter().skip(m).copied())
            .collect();
        theta = sol.iter().copied().collect();
    }
    // Unscale: s' = s/ω_ref. Numerator b'_i s'^i / (s'^n + a'_j s'^j) =
    // (b'_i ω_ref^{n−i}) s^i / (s^n + a'_j ω_ref^{n−j} s^j).
    // Exponents n − i ≥ 0, at most 12: repeated products, no casts.
    let pow = |e: usize| (0..e).fold(1.0, |acc, _| acc * wref);
    for j in 0..m {
        theta[j] *= pow(n - (m - 1 - j));
    }
    for j in 0..n {
        theta[m + j] *= pow(n - (n - 1 - j));
    }
    theta.iter().all(|v| v.is_finite()).then_some(theta)
}

/// Fit the transfer function of structure `st` to `frf` with the cost of
/// `opts`, started from `start` (parameters in [`TfFit::names`] order) or
/// from the linear fit. Errors: a structure that is improper or needs more
/// parameters than points, no point above the coherence threshold, a
/// failed start, a non-finite or singular result.
pub fn fit_tf(
    frf: &Frf,
    st: TfStructure,
    opts: &CostOptions,
    start: Option<&[f64]>,
) -> Result<TfFit> {
    if st.den_order == 0 || st.num_order > st.den_order || st.den_order > 12 {
        return Err(IdentError::Fit(format!(
            "numerator order {} and denominator order {}: need 1 ≤ den ≤ 12 and num ≤ den",
            st.num_order, st.den_order
        )));
    }
    let pts = select(frf, opts, 0.0, f64::INFINITY);
    let np = st.num_order + 1 + st.den_order + usize::from(st.delay);
    if 2 * pts.omega.len() <= np {
        return Err(IdentError::Fit(format!(
            "{} points with γ² > {} for {np} parameters",
            pts.omega.len(),
            opts.min_coherence
        )));
    }
    let mut theta: Vec<f64> = match start {
        Some(s) if s.len() == np && s.iter().all(|v| v.is_finite()) => s.to_vec(),
        Some(s) => {
            return Err(IdentError::Fit(format!(
                "start has {} values (finite) for {np} parameters",
                s.len()
            )));
        }
        None => {
            let mut t = levy_start(&pts, st)
                .ok_or_else(|| IdentError::Fit("the linear start fit failed".into()))?;
            if st.delay {
                t.push(0.0);
            }
            t
        }
    };
    let problem = Problem {
        pts: &pts,
        st,
        theta: DVector::from_vec(std::mem::take(&mut theta)),
    };
    let (problem, report) = LevenbergMarquardt::new()
        .with_patience(400)
        .minimize(problem);
    if report.termination.was_usage_issue() {
        return Err(IdentError::Fit(format!("{:?}", report.termination)));
    }
    let r = problem
        .residuals()
        .ok_or_else(|| IdentError::Fit("non-finite residuals at the optimum".into()))?;
    let jac = problem
        .jacobian()
        .ok_or_else(|| IdentError::Fit("non-finite Jacobian at the optimum".into()))?;
    let cost = r.norm_squared();
    let params: Vec<f64> = problem.theta.iter().copied().collect();
    let acc = separable_accuracy(&jac, cost)?;
    if params.iter().any(|v| !v.is_finite()) {
        return Err(IdentError::Fit(
            "a non-finite parameter at the optimum".into(),
        ));
    }
    let (num, den, tau) = problem.split();
    Ok(TfFit {
        num,
        den,
        delay_s: tau,
        cost,
        names: names(st),
        cramer_rao_pct: percent(&acc.cramer_rao, &params),
        insensitivity_pct: percent(&acc.insensitivity, &params),
        cramer_rao: acc.cramer_rao,
        params,
        n_points: pts.omega.len(),
        evaluations: report.number_of_evaluations,
    })
}

/// Parameter names: `b<k>` (numerator, power k), `a<k>`, `tau_s`.
fn names(st: TfStructure) -> Vec<String> {
    let mut v: Vec<String> = (0..=st.num_order).rev().map(|k| format!("b{k}")).collect();
    v.extend((0..st.den_order).rev().map(|k| format!("a{k}")));
    if st.delay {
        v.push("tau_s".into());
    }
    v
}

/// The response of the fitted transfer function to `u` sampled every `dt_s`
/// from rest: controllable canonical form, zero-order hold (exact for a held
/// input), the delay applied by linear interpolation of the input at t − τ.
pub fn simulate(fit: &TfFit, u: &[f64], dt_s: f64) -> Result<Vec<f64>> {
    if fit.den.len() < 2 || fit.den[0] != 1.0 || fit.num.len() > fit.den.len() || fit.num.is_empty()
    {
        return Err(IdentError::Fit(
            "simulation needs a proper transfer function with a monic denominator of order ≥ 1"
                .into(),
        ));
    }
    if !(fit.delay_s.is_finite() && fit.delay_s >= 0.0) {
        return Err(IdentError::invalid(
            "delay_s",
            fit.delay_s,
            "must be finite and ≥ 0",
        ));
    }
    let n = fit.den.len() - 1;
    // Proper: T = d + (N − d·D)/D.
    let mut num = vec![0.0; n + 1 - fit.num.len()];
    num.extend_from_slice(&fit.num);
    let d = num[0];
    let rem: Vec<f64> = (1..=n).map(|i| num[i] - d * fit.den[i]).collect();
    let a = DMatrix::from_fn(n, n, |i, j| {
        if i + 1 < n {
            if j == i + 1 { 1.0 } else { 0.0 }
        } else {
            -fit.den[n - j]
        }
    });
    let b = DMatrix::from_fn(n, 1, |i, _| if i + 1 == n { 1.0 } else { 0.0 });
    // y = Σ rem coefficients on states: x_1 = z, x_{i+1} = z^{(i)}; rem is
    // highest power first, so state i takes rem[n − 1 − i].
    let c: Vec<f64> = (0..n).map(|i| rem[n - 1 - i]).collect();
    let (phi, gamma) =
        helicon_lti::c2d(&a, &b, dt_s).map_err(|e| IdentError::Fit(format!("simulation: {e}")))?;
    let shift = fit.delay_s / dt_s;
    let delayed = |k: usize| {
        let t = k as f64 - shift;
        if t < 0.0 {
            return 0.0;
        }
        let i = t.floor() as usize;
        let f = t - i as f64;
        let at = |j: usize| u.get(j).copied().unwrap_or(0.0);
        at(i) * (1.0 - f) + at(i + 1) * f
    };
    let mut x = DVector::zeros(n);
    let mut y = Vec::with_capacity(u.len());
    for k in 0..u.len() {
        let uk = delayed(k);
        y.push(c.iter().zip(x.iter()).map(|(c, x)| c * x).sum::<f64>() + d * uk);
        x = &phi * &x + gamma.column(0) * uk;
    }
    if y.iter().all(|v| v.is_finite()) {
        Ok(y)
    } else {
        Err(IdentError::Fit(
            "the fitted system diverges on this input".into(),
        ))
    }
}

/// Theil's inequality coefficient of a simulated output against the measured
/// one: √(mean (y − ŷ)²) / (√(mean y²) + √(mean ŷ²)), 0 for a perfect match,
/// 1 at worst (below ~0.25–0.3 counts as a good fit in flight-test practice).
pub fn theil(measured: &[f64], simulated: &[f64]) -> Result<f64> {
    let n = measured.len();
    if n == 0 || simulated.len() != n {
        return Err(IdentError::data(
            "Theil coefficient",
            format!("{n} measured and {} simulated samples", simulated.len()),
        ));
    }
    let rms = |v: &mut dyn Iterator<Item = f64>| (v.map(|x| x * x).sum::<f64>() / n as f64).sqrt();
    let e = rms(&mut measured.iter().zip(simulated).map(|(a, b)| a - b));
    let den = rms(&mut measured.iter().copied()) + rms(&mut simulated.iter().copied());
    let u = e / den;
    if u.is_finite() {
        Ok(u)
    } else {
        Err(IdentError::data(
            "Theil coefficient",
            "both signals are zero",
        ))
    }
}
