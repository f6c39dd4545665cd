//! The optimisation and the identifiability analysis.
//!
//! **Variables.** Each identified parameter p_i, bounded by [lo_i, hi_i], is
//! scaled by its start value, θ_i = p_i/p0_i, and mapped to an unbounded
//! variable by MINUIT's sine transform, θ_i = θlo_i + (θhi_i − θlo_i)(1 +
//! sin ξ_i)/2: the optimisers move ξ freely and the model never sees a value
//! outside the bounds (no projection, so the cost stays smooth). A parameter
//! that ends at a bound is reported as such.
//!
//! **Levenberg–Marquardt** (`levenberg-marquardt` crate, MINPACK's
//! algorithm with its diagonal scaling) minimises ‖r(ξ)‖² with a
//! forward-difference Jacobian, step 1e-6 in ξ (≈ 1e-6 of the half-range
//! of the parameter), columns evaluated in parallel (rayon).
//! **Nelder–Mead** (`argmin`'s simplex, the method MOSCA used) minimises the
//! same J(ξ) from the simplex ξ0 + 0.1 e_k.
//!
//! **Identifiability** (as `helicon_ident::fit` does for transfer functions):
//! at the optimum, with the Jacobian of the weighted residuals with respect
//! to θ (forward differences, step 1e-6), M = JᵀJ and s² = J_min/(n_r − n_p),
//! the Cramér–Rao bound of p_i is s √(M⁻¹)_ii · p0_i, the insensitivity
//! s/√M_ii · p0_i, both in per cent of the identified value, and the
//! correlation ρ_ij = (M⁻¹)_ij/√((M⁻¹)_ii (M⁻¹)_jj); a parameter whose
//! √M_ii is below 1e-4 of the largest carries no information (its column is
//! the trims' round-off through the finite difference) and is infinitely
//! insensitive. CIFER's guidelines:
//! CR ≤ 20 %, insensitivity ≤ 10 %. With `auto_fix`, the parameters failing
//! the insensitivity guideline are fixed at their start values (all at once),
//! else the one with the largest CR bound, and the fit is repeated until all
//! remaining parameters pass; each fixed parameter keeps its reason.

use crate::config::{Optimiser, Parameter};
use crate::cost::Cost;
use crate::error::{ParamIdError, Result};
use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Dyn, Owned};
use rayon::prelude::*;
use serde::Serialize;
use std::sync::atomic::{AtomicUsize, Ordering};

/// CIFER's guideline on the Cramér–Rao bound, per cent.
pub const CR_MAX_PCT: f64 = 20.0;
/// CIFER's guideline on the insensitivity, per cent.
pub const INSENSITIVITY_MAX_PCT: f64 = 10.0;
/// Forward-difference step in ξ (LM Jacobian) and θ (accuracy).
const FD_STEP: f64 = 1e-6;

/// Fit settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitOptions {
    /// Optimiser.
    pub optimiser: Optimiser,
    /// LM: Jacobian evaluations at most (patience); simplex: 20× that many iterations.
    pub max_iterations: usize,
    /// Fix the parameters failing the guidelines and fit again.
    pub auto_fix: bool,
}

/// One parameter's outcome.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParameterResult {
    /// `section.key`.
    pub key: String,
    /// Start value.
    pub start: f64,
    /// Identified value (the start when fixed).
    pub identified: f64,
    /// (identified − start)/start, per cent.
    pub change_pct: f64,
    /// Cramér–Rao bound, per cent of the identified value (null when fixed
    /// or not computable).
    pub cramer_rao_pct: Option<f64>,
    /// Insensitivity, per cent of the identified value.
    pub insensitivity_pct: Option<f64>,
    /// Passes the guidelines and was identified.
    pub identifiable: bool,
    /// Why it is not identifiable (or was fixed), when so.
    pub reason: Option<String>,
    /// Lower bound.
    pub min: f64,
    /// Upper bound.
    pub max: f64,
}

/// One optimisation pass.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Pass {
    /// Keys of the free parameters.
    pub free: Vec<String>,
    /// Cost at its start and end.
    pub cost_start: f64,
    /// Cost at its end.
    pub cost_end: f64,
    /// Cost evaluations.
    pub evaluations: usize,
    /// How the optimiser stopped.
    pub termination: String,
}

/// The result of [`identify`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitResult {
    /// Per parameter, in the IDENT.toml's order.
    pub parameters: Vec<ParameterResult>,
    /// The identified values (fixed ones at their start), SI.
    pub values: Vec<f64>,
    /// Total cost at the start parameters.
    pub cost_start: f64,
    /// Total cost at the identified parameters.
    pub cost_final: f64,
    /// Cost per operating point and response at the start.
    pub costs_start: Vec<Vec<f64>>,
    /// Cost per operating point and response at the identified parameters.
    pub costs_final: Vec<Vec<f64>>,
    /// Keys of the parameters the correlation matrix is about (the free
    /// ones of the last pass).
    pub correlation_keys: Vec<String>,
    /// Correlation matrix of the last pass's free parameters.
    pub correlation: Vec<Vec<f64>>,
    /// The optimisation passes.
    pub passes: Vec<Pass>,
    /// Residuals (two per frequency point).
    pub residuals: usize,
}

/// The sine transform of one parameter, in start-scaled units.
#[derive(Debug, Clone, Copy)]
struct Transform {
    p0: f64,
    lo: f64,
    hi: f64,
}

impl Transform {
    fn new(p: &Parameter) -> Self {
        let (a, b) = (p.min / p.start, p.max / p.start);
        Transform {
            p0: p.start,
            lo: a.min(b),
            hi: a.max(b),
        }
    }
    fn value(&self, xi: f64) -> f64 {
        self.p0 * (self.lo + (self.hi - self.lo) * 0.5 * (1.0 + xi.sin()))
    }
    fn xi(&self, v: f64) -> f64 {
        let t = (2.0 * (v / self.p0 - self.lo) / (self.hi - self.lo) - 1.0).clamp(-1.0, 1.0);
        t.asin()
    }
}

struct Vars<'a> {
    cost: &'a Cost,
    free: &'a [usize],
    values: Vec<f64>,
    tr: Vec<Transform>,
    evals: AtomicUsize,
}

impl Vars<'_> {
    fn at(&self, xi: &[f64]) -> Vec<f64> {
        let mut v = self.values.clone();
        for (k, &i) in self.free.iter().enumerate() {
            v[i] = self.tr[i].value(xi[k]);
        }
        v
    }
    fn residuals(&self, xi: &[f64]) -> Result<DVector<f64>> {
        self.evals.fetch_add(1, Ordering::Relaxed);
        self.cost.residuals(&self.at(xi))
    }
}

struct Lm<'a> {
    vars: &'a Vars<'a>,
    xi: DVector<f64>,
    r: Option<DVector<f64>>,
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Lm<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.xi.copy_from(x);
        self.r = self.vars.residuals(x.as_slice()).ok();
    }

    fn params(&self) -> DVector<f64> {
        self.xi.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        self.r.clone()
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let r0 = self.r.as_ref()?;
        let cols: Vec<Option<DVector<f64>>> = (0..self.xi.len())
            .into_par_iter()
            .map(|k| {
                let mut x = self.xi.clone();
                x[k] += FD_STEP;
                let r = self.vars.residuals(x.as_slice()).ok()?;
                Some((r - r0) / FD_STEP)
            })
            .collect();
        let mut j = DMatrix::zeros(r0.len(), self.xi.len());
        for (k, c) in cols.into_iter().enumerate() {
            j.set_column(k, &c?);
        }
        Some(j)
    }
}

/// J(ξ) for the simplex.
struct Simplex<'a>(&'a Vars<'a>);

impl CostFunction for Simplex<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, xi: &Self::Param) -> std::result::Result<f64, argmin::core::Error> {
        // a failed trim is a very bad point, not an abort of the search
        Ok(self.0.residuals(xi).map_or(1e30, |r| r.norm_squared()))
    }
}

/// Minimise over the `free` parameters, the others held at `values`;
/// returns the new values and the pass record.
fn minimise(
    cost: &Cost,
    free: &[usize],
    values: &[f64],
    opts: &FitOptions,
) -> Result<(Vec<f64>, Pass)> {
    let tr: Vec<Transform> = cost.parameters.iter().map(Transform::new).collect();
    let vars = Vars {
        cost,
        free,
        values: values.to_vec(),
        tr,
        evals: AtomicUsize::new(0),
    };
    let xi0: Vec<f64> = free.iter().map(|&i| vars.tr[i].xi(values[i])).collect();
    let cost_start = vars.residuals(&xi0)?.norm_squared();
    let (xi, termination) = match opts.optimiser {
        Optimiser::Lm => {
            let mut p = Lm {
                vars: &vars,
                xi: DVector::from_vec(xi0.clone()),
                r: None,
            };
            p.set_params(&DVector::from_vec(xi0));
            let (p, report) = LevenbergMarquardt::new()
                .with_patience(opts.max_iterations)
                .minimize(p);
            if report.termination.was_usage_issue() {
                return Err(ParamIdError::Fit(format!("{:?}", report.termination)));
            }
            (
                p.xi.iter().copied().collect::<Vec<_>>(),
                format!("{:?}", report.termination),
            )
        }
        Optimiser::Simplex => {
            let mut simplex = vec![xi0.clone()];
            for k in 0..xi0.len() {
                let mut v = xi0.clone();
                v[k] += 0.1;
                simplex.push(v);
            }
            let solver = NelderMead::new(simplex)
                .with_sd_tolerance(1e-16)
                .map_err(|e| ParamIdError::Fit(e.to_string()))?;
            let res = Executor::new(Simplex(&vars), solver)
                .configure(|s| s.max_iters(20 * opts.max_iterations as u64))
                .run()
                .map_err(|e| ParamIdError::Fit(e.to_string()))?;
            let best = res
                .state()
                .get_best_param()
                .cloned()
                .ok_or_else(|| ParamIdError::Fit("the simplex found no point".into()))?;
            (best, format!("{:?}", res.state().get_termination_status()))
        }
    };
    let out = vars.at(&xi);
    let cost_end = cost.residuals(&out)?.norm_squared();
    let pass = Pass {
        free: free.iter().map(|&i| cost.parameters[i].key()).collect(),
        cost_start,
        cost_end,
        evaluations: vars.evals.load(Ordering::Relaxed),
        termination,
    };
    Ok((out, pass))
}

/// Cramér–Rao bounds (%), insensitivities (%) and correlation matrix.
pub type AccuracyParts = (Vec<f64>, Vec<f64>, Vec<Vec<f64>>);

/// Accuracy of the free parameters at `values`: (CR %, insensitivity %,
/// correlation); CR is ∞ where the information matrix is singular.
pub fn accuracy(cost: &Cost, free: &[usize], values: &[f64]) -> Result<AccuracyParts> {
    let r0 = cost.residuals(values)?;
    let np = free.len();
    let cols: Vec<Result<DVector<f64>>> = free
        .par_iter()
        .map(|&i| {
            let mut v = values.to_vec();
            let p0 = cost.parameters[i].start;
            v[i] += FD_STEP * p0;
            Ok((cost.residuals(&v)? - &r0) / FD_STEP)
        })
        .collect();
    let mut jac = DMatrix::zeros(r0.len(), np);
    for (k, c) in cols.into_iter().enumerate() {
        jac.set_column(k, &c?);
    }
    // a column below 1e-4 of the largest is the trim's round-off seen
    // through the finite difference (trim tolerance 1e-10 over the step
    // 1e-6 gives ~1e-4 relative; a parameter the responses do not depend on
    // measured 5e-5): no information, infinitely insensitive
    // the grid is finer than the windows' resolution at low frequency
    // (40 log-spaced points: several per bin of a 12 s window below
    // 3 rad/s), so the residuals are correlated: the sandwich covariance
    let jrj = cost.residual_correlation(&jac);
    let acc = helicon_ident::cost::accuracy_correlated(&jac, r0.norm_squared(), 1e-4, Some(&jrj))
        .map_err(|e| ParamIdError::Fit(e.to_string()))?;
    // θ units (fractions of the start value) → per cent of the identified value
    let pct: Vec<f64> = free
        .iter()
        .map(|&i| 100.0 * cost.parameters[i].start / values[i].abs())
        .collect();
    let scale = |v: &[f64]| -> Vec<f64> { v.iter().zip(&pct).map(|(v, p)| v * p).collect() };
    let corr = (0..np)
        .map(|i| (0..np).map(|j| acc.correlation[(i, j)]).collect())
        .collect();
    Ok((scale(&acc.cramer_rao), scale(&acc.insensitivity), corr))
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// Identify the parameters of `cost`: minimise, analyse, and with
/// `auto_fix` fix the parameters failing the guidelines and repeat.
pub fn identify(cost: &Cost, opts: &FitOptions) -> Result<FitResult> {
    let np = cost.parameters.len();
    let start: Vec<f64> = cost.parameters.iter().map(|p| p.start).collect();
    let r_start = cost.residuals(&start)?;
    let mut free: Vec<usize> = (0..np).collect();
    let mut reasons: Vec<Option<String>> = vec![None; np];
    let mut passes = Vec::new();
    let mut values = start.clone();
    let (cr, ins, corr) = loop {
        if free.is_empty() {
            return Err(ParamIdError::Fit(
                "every parameter failed the identifiability guidelines and was fixed: the data cannot determine any of them".into(),
            ));
        }
        let mut trial = start.clone();
        for &i in &free {
            trial[i] = values[i];
        }
        let (v, pass) = minimise(cost, &free, &trial, opts)?;
        values = v;
        passes.push(pass);
        let (cr, ins, corr) = accuracy(cost, &free, &values)?;
        if !opts.auto_fix {
            break (cr, ins, corr);
        }
        let n_pass = passes.len();
        let insensitive: Vec<usize> = (0..free.len())
            .filter(|&k| !ins[k].is_finite() || ins[k] > INSENSITIVITY_MAX_PCT)
            .collect();
        if !insensitive.is_empty() {
            for &k in &insensitive {
                reasons[free[k]] = Some(format!(
                    "insensitive: the cost hardly changes with it (insensitivity {:.3} % > {INSENSITIVITY_MAX_PCT} % in pass {n_pass}); fixed at its start value",
                    ins[k]
                ));
            }
            let drop: Vec<usize> = insensitive.iter().map(|&k| free[k]).collect();
            free.retain(|i| !drop.contains(i));
            continue;
        }
        let worst = (0..free.len()).max_by(|&a, &b| cr[a].total_cmp(&cr[b]));
        match worst {
            Some(k) if !cr[k].is_finite() || cr[k] > CR_MAX_PCT => {
                let partner = (0..free.len())
                    .filter(|&j| j != k)
                    .max_by(|&a, &b| corr[k][a].abs().total_cmp(&corr[k][b].abs()));
                let with = partner.map_or(String::new(), |j| {
                    format!(
                        "; most correlated with {} (ρ = {:.3})",
                        cost.parameters[free[j]].key(),
                        corr[k][j]
                    )
                });
                reasons[free[k]] = Some(format!(
                    "not separable: Cramér–Rao bound {:.3} % > {CR_MAX_PCT} % in pass {n_pass}{with}; fixed at its start value",
                    cr[k]
                ));
                free.remove(k);
            }
            _ => break (cr, ins, corr),
        }
    };
    let r_final = cost.residuals(&values)?;
    let parameters = cost
        .parameters
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let k = free.iter().position(|&f| f == i);
            let (c, s) = k.map_or((None, None), |k| (finite(cr[k]), finite(ins[k])));
            let passes_rules = c.is_some_and(|c| c <= CR_MAX_PCT)
                && s.is_some_and(|s| s <= INSENSITIVITY_MAX_PCT);
            let at_bound = k.is_some()
                && ((values[i] - p.min).abs() <= 1e-6 * (p.max - p.min)
                    || (values[i] - p.max).abs() <= 1e-6 * (p.max - p.min));
            let reason = if let Some(r) = &reasons[i] {
                Some(r.clone())
            } else if k.is_some() && !passes_rules {
                Some(format!(
                    "fails the guidelines (CR {} %, insensitivity {} %; limits {CR_MAX_PCT} %, {INSENSITIVITY_MAX_PCT} %)",
                    c.map_or("∞".into(), |c| format!("{c:.3}")),
                    s.map_or("∞".into(), |s| format!("{s:.3}"))
                ))
            } else if at_bound {
                Some("ended at a bound: widen the bounds or fix it".into())
            } else {
                None
            };
            ParameterResult {
                key: p.key(),
                start: p.start,
                identified: values[i],
                change_pct: 100.0 * (values[i] - p.start) / p.start,
                cramer_rao_pct: c,
                insensitivity_pct: s,
                identifiable: k.is_some() && passes_rules && !at_bound,
                reason,
                min: p.min,
                max: p.max,
            }
        })
        .collect();
    Ok(FitResult {
        parameters,
        cost_start: r_start.norm_squared(),
        cost_final: r_final.norm_squared(),
        costs_start: cost.split(&r_start),
        costs_final: cost.split(&r_final),
        correlation_keys: free.iter().map(|&i| cost.parameters[i].key()).collect(),
        correlation: corr
            .iter()
            .map(|row| {
                row.iter()
                    .map(|v| if v.is_finite() { *v } else { 0.0 })
                    .collect()
            })
            .collect(),
        values,
        passes,
        residuals: r_start.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::keys;

    #[test]
    fn the_sine_transform_keeps_values_inside_the_bounds_and_round_trips() {
        let d = keys::find("body.iyy_kg_m2").unwrap_or_else(|| unreachable!());
        let p = Parameter {
            descriptor: d,
            start: 0.62,
            min: 0.31,
            max: 1.24,
        };
        let t = Transform::new(&p);
        for v in [0.31, 0.4, 0.62, 1.0, 1.24] {
            let back = t.value(t.xi(v));
            assert!((back - v).abs() < 1e-12 * v, "{v} -> {back}");
        }
        for xi in [-100.0, -2.0, 0.0, 1.0, 7.5, 1e6] {
            let v = t.value(xi);
            assert!((0.31 - 1e-12..=1.24 + 1e-12).contains(&v), "{xi} -> {v}");
        }
        // outside the bounds is clamped to the bound
        assert!((t.value(t.xi(5.0)) - 1.24).abs() < 1e-12);
    }
}
