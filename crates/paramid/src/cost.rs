//! The cost: thesis (11.1)–(11.2),
//!
//! J(p) = Σ_n Σ_i w_κ κ_n,i(p) W_n,i κ_n,i(p) + w_χ χ_n,i(p) W_n,i χ_n,i(p),
//!
//! over the operating points n and the frequency points i of every measured
//! response, κ the magnitude error and χ the phase error between the
//! measured response and the linearised model's, W_n,i the partial
//! coherence γ² of the measured point (thesis §11.2: "the partial coherence
//! between measured helicopter output and input at each frequency point").
//! The thesis writes κ = |G_data| − |G_model|; here it is taken in dB,
//! κ = 20 log10 |G_data| − 20 log10 |G_model|, and χ in degrees (wrapped
//! to ±180°), so that responses of different units weigh alike and the
//! weights are those of flight-test practice (w_κ = 1 per dB², w_χ = 0.01745
//! per deg²: 1 dB ≈ 7.57°).
//!
//! With `cost = "cifer"` each response's cost is CIFER's
//! (20/n_ω) Σ W_γ [W_g κ² + W_p χ²], W_γ = [1.58(1 − e^{−γ²})]²
//! (`helicon_ident::fit::coherence_weight`), W_g = `w_kappa`, W_p = `w_chi`,
//! and J is the sum over the responses and operating points.
//!
//! In both forms only the points with γ² > `min_coherence` enter. J is the
//! sum of squares of a residual vector (one magnitude and one phase residual
//! per point), which Levenberg–Marquardt minimises directly.

use crate::config::{CostForm, IdentConfig, Parameter};
use crate::data::PointData;
use crate::error::{ParamIdError, Result};
use crate::keys;
use crate::linear::{point_responses, target};
use helicon_ident::Complex64;
use helicon_ident::fit::coherence_weight;
use helicon_ident::frf::{composite_correlation, flat_correlation};
use helicon_model::trim::TrimTarget;
use helicon_model::{Params, Preset};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// 20 / ln 10: dB per neper.
const DB: f64 = 8.685_889_638_065_037;

/// One response's selected points and residual scales.
#[derive(Debug, Clone)]
pub struct Selected {
    /// `output/input`.
    pub label: String,
    /// Servo index.
    pub input: usize,
    /// Reduced-state row.
    pub state: usize,
    /// Frequencies, rad/s (γ² above the threshold).
    pub omega_rad_s: Vec<f64>,
    /// Measured response.
    pub h: Vec<Complex64>,
    /// Coherence γ².
    pub coherence: Vec<f64>,
    /// √(weight) of the magnitude residual (dB).
    pub scale_mag: Vec<f64>,
    /// √(weight) of the phase residual (deg).
    pub scale_ph: Vec<f64>,
    /// Normalised random error ε of each point (Bendat & Piersol: the
    /// relative standard deviation of |H|, and that of the phase in rad).
    pub random_error: Vec<f64>,
}

/// One operating point of the cost.
#[derive(Debug, Clone)]
pub struct PointCost {
    /// Name.
    pub name: String,
    /// Trim target.
    pub target: TrimTarget,
    /// Sample time of the data, s.
    pub ts_s: f64,
    /// Responses.
    pub responses: Vec<Selected>,
    /// The window lengths of the composite estimates, s: neighbouring
    /// frequency points closer than their resolution are correlated
    /// ([`Cost::residual_correlation`]).
    pub windows_s: Vec<f64>,
    /// With `spectra = "sweeps"`, the flat windows' lengths around each
    /// excitation, s (used instead of `windows_s` for the correlation);
    /// empty otherwise.
    pub sweep_windows_s: Vec<f64>,
}

/// The whole cost: operating points, the parameters it varies and the base
/// parameter set they are written into.
#[derive(Debug, Clone)]
pub struct Cost {
    /// Operating points.
    pub points: Vec<PointCost>,
    /// Model preset.
    pub preset: Preset,
    /// The parameters not identified come from here.
    pub base: Params,
    /// The parameters identified.
    pub parameters: Vec<Parameter>,
    /// Responses left out (no point above the coherence threshold), with why.
    pub skipped: Vec<String>,
    /// The scale of a prior residual: the RMS standard deviation of the
    /// data residuals, from the points' random errors (a data residual of
    /// one standard deviation and a prior one standard error off weigh
    /// alike); 0 for data without random error (a model's own responses).
    pub prior_scale: f64,
}

/// The residual scales of one point: (magnitude, phase).
fn scales(form: CostForm, wk: f64, wc: f64, gamma2: f64, n: usize) -> (f64, f64) {
    match form {
        CostForm::Thesis => ((wk * gamma2).sqrt(), (wc * gamma2).sqrt()),
        CostForm::Cifer => {
            let w = 20.0 / n as f64 * coherence_weight(gamma2);
            ((w * wk).sqrt(), (w * wc).sqrt())
        }
    }
}

impl Cost {
    /// The cost of `cfg` on the measured `data` (one per operating point,
    /// in order). Responses that keep fewer than `min_points` points above the
    /// coherence threshold are left out (listed in [`Cost::skipped`]); errors if the
    /// residuals are fewer than the parameters.
    pub fn new(cfg: &IdentConfig, data: &[PointData]) -> Result<Self> {
        let mut points = Vec::with_capacity(data.len());
        let mut skipped = Vec::new();
        for (op, d) in cfg.operating_points.iter().zip(data) {
            let mut responses = Vec::with_capacity(d.responses.len());
            for m in &d.responses {
                let f = &m.frf;
                let idx: Vec<usize> = (0..f.len())
                    .filter(|&k| {
                        f.coherence[k] > cfg.min_coherence
                            && f.h[k].norm() > 0.0
                            && f.h[k].norm().is_finite()
                    })
                    .collect();
                if idx.len() < cfg.min_points {
                    skipped.push(format!(
                        "operating point `{}`, response {}: {} frequencies with γ² > {} (min_points = {}), left out of the cost",
                        op.name,
                        m.response.label(),
                        idx.len(),
                        cfg.min_coherence,
                        cfg.min_points
                    ));
                    continue;
                }
                let sc: Vec<(f64, f64)> = idx
                    .iter()
                    .map(|&k| scales(cfg.cost, cfg.w_kappa, cfg.w_chi, f.coherence[k], idx.len()))
                    .collect();
                let kept = f.select(&idx);
                responses.push(Selected {
                    label: m.response.label(),
                    input: m.input,
                    state: m.state,
                    omega_rad_s: kept.omega_rad_s,
                    h: kept.h,
                    coherence: kept.coherence,
                    scale_mag: sc.iter().map(|s| s.0).collect(),
                    scale_ph: sc.iter().map(|s| s.1).collect(),
                    random_error: kept.random_error,
                });
            }
            points.push(PointCost {
                name: op.name.clone(),
                target: target(op.velocity_ned_m_s, op.yaw_rad),
                ts_s: d.sample_time_s,
                responses,
                windows_s: cfg.windows_s.clone(),
                sweep_windows_s: d.sweep_windows_s.clone(),
            });
        }
        let prior_scale = data_residual_rms_std(&points);
        let cost = Cost {
            points,
            preset: cfg.preset,
            base: cfg.start,
            parameters: cfg.parameters.clone(),
            skipped,
            prior_scale,
        };
        if cost.residual_count() <= cfg.parameters.len() {
            return Err(ParamIdError::Fit(format!(
                "{} residuals for {} parameters",
                cost.residual_count(),
                cfg.parameters.len()
            )));
        }
        Ok(cost)
    }

    /// Number of residuals (two per selected point).
    pub fn residual_count(&self) -> usize {
        self.data_residual_count() + self.parameters.iter().filter(|p| p.prior.is_some()).count()
    }

    /// The residuals of the measured responses (the first ones).
    pub fn data_residual_count(&self) -> usize {
        self.points
            .iter()
            .flat_map(|p| &p.responses)
            .map(|r| 2 * r.omega_rad_s.len())
            .sum()
    }

    /// The parameter set with the identified parameters at `values` (SI,
    /// in [`Cost::parameters`] order).
    pub fn params_at(&self, values: &[f64]) -> Params {
        let mut p = self.base;
        for (q, v) in self.parameters.iter().zip(values) {
            keys::set(&mut p, q.descriptor, *v);
        }
        p
    }

    /// The model's responses at every operating point and response at the
    /// selected frequencies, for parameter values `values`.
    pub fn model_at(&self, values: &[f64]) -> Result<Vec<Vec<Vec<Complex64>>>> {
        self.model_at_omegas(values, None)
    }

    /// As [`Cost::model_at`], at the frequencies `omegas[point][response]`
    /// instead of the selected ones (e.g. every estimated point, for plots).
    pub fn model_at_omegas(
        &self,
        values: &[f64],
        omegas: Option<&[Vec<Vec<f64>>]>,
    ) -> Result<Vec<Vec<Vec<Complex64>>>> {
        let params = self.params_at(values);
        self.points
            .par_iter()
            .enumerate()
            .map(|(n, pt)| {
                let wanted: Vec<(usize, usize, &[f64])> = pt
                    .responses
                    .iter()
                    .enumerate()
                    .map(|(k, r)| {
                        let om = omegas.map_or(r.omega_rad_s.as_slice(), |o| o[n][k].as_slice());
                        (r.input, r.state, om)
                    })
                    .collect();
                point_responses(&params, self.preset, &pt.target, &pt.name, pt.ts_s, &wanted)
                    .map(|(h, _)| h)
            })
            .collect()
    }

    /// The weighted residuals at `values`: for each operating point, response
    /// and frequency, the magnitude (dB) and phase (deg) errors times the
    /// square roots of their weights; J = ‖r‖².
    pub fn residuals(&self, values: &[f64]) -> Result<DVector<f64>> {
        let model = self.model_at(values)?;
        let mut r = DVector::zeros(self.residual_count());
        let mut i = 0;
        for (pt, hm) in self.points.iter().zip(&model) {
            for (s, h) in pt.responses.iter().zip(hm) {
                for k in 0..s.omega_rad_s.len() {
                    let ratio = s.h[k] / h[k];
                    r[i] = s.scale_mag[k] * DB * ratio.norm().ln();
                    r[i + 1] = s.scale_ph[k] * wrap_deg(ratio.arg().to_degrees());
                    i += 2;
                }
            }
        }
        // the prior measurements (a ground experiment's value and standard
        // error): r = s·(θ − θ_prior)/σ_prior with s the data residuals'
        // standard deviation, so that J is the negative log-likelihood of
        // data and priors together (up to s²) and its minimum the
        // inverse-variance combination of the two
        for (q, v) in self.parameters.iter().zip(values) {
            if let Some((p0, sd)) = q.prior {
                r[i] = self.prior_scale * (v - p0) / sd;
                i += 1;
            }
        }
        if r.iter().all(|v| v.is_finite()) {
            Ok(r)
        } else {
            Err(ParamIdError::Fit("non-finite residual".into()))
        }
    }

    /// JᵀRJ for the Jacobian `jac` of [`Cost::residuals`] (rows in their
    /// order, one column per parameter) and R the residuals' correlation:
    /// within a response, the magnitude residuals at ω_k and ω_l are
    /// correlated by the composite estimate's window overlap
    /// (`helicon_ident::frf::composite_correlation`; with sweep windows the
    /// mean of their `flat_correlation`s), and so are the phase
    /// residuals; magnitude and phase residuals, responses and operating
    /// points are taken as uncorrelated. For the Cramér–Rao bounds of
    /// correlated residuals (`helicon_ident::cost::accuracy_correlated`).
    pub fn residual_correlation(&self, jac: &DMatrix<f64>) -> DMatrix<f64> {
        let np = jac.ncols();
        let mut g = DMatrix::zeros(np, np);
        let mut o = 0;
        for pt in &self.points {
            for s in &pt.responses {
                let w = &s.omega_rad_s;
                for k in 0..w.len() {
                    for l in 0..w.len() {
                        let rho = if k == l {
                            1.0
                        } else if pt.sweep_windows_s.is_empty() {
                            composite_correlation(w[k], w[l], &pt.windows_s)
                        } else {
                            // each estimate holds every excitation's window:
                            // their mean correlation
                            pt.sweep_windows_s
                                .iter()
                                .map(|t| flat_correlation(w[k] - w[l], *t))
                                .sum::<f64>()
                                / pt.sweep_windows_s.len() as f64
                        };
                        if rho == 0.0 {
                            continue;
                        }
                        for part in 0..2 {
                            let (a, b) = (jac.row(o + 2 * k + part), jac.row(o + 2 * l + part));
                            g += rho * a.transpose() * b;
                        }
                    }
                }
                o += 2 * w.len();
            }
        }
        // the prior rows: independent of everything
        for k in o..jac.nrows() {
            let a = jac.row(k);
            g += a.transpose() * a;
        }
        g
    }

    /// The cost of each response (points × responses) from residuals `r`.
    pub fn split(&self, r: &DVector<f64>) -> Vec<Vec<f64>> {
        let mut i = 0;
        self.points
            .iter()
            .map(|pt| {
                pt.responses
                    .iter()
                    .map(|s| {
                        let n = 2 * s.omega_rad_s.len();
                        let c = r.rows(i, n).norm_squared();
                        i += n;
                        c
                    })
                    .collect()
            })
            .collect()
    }
}

/// The RMS standard deviation of the data residuals, √(mean σ²) over the
/// magnitude and phase residuals of every point: σ = scale · 8.69 dB · ε and
/// scale · 57.3° · ε (Bendat & Piersol's small-error forms for log |H| and
/// the phase).
fn data_residual_rms_std(points: &[PointCost]) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for s in points.iter().flat_map(|p| &p.responses) {
        for k in 0..s.omega_rad_s.len() {
            let e = s.random_error[k];
            sum += (s.scale_mag[k] * DB * e).powi(2) + (s.scale_ph[k] * e.to_degrees()).powi(2);
            n += 2;
        }
    }
    if n == 0 || !sum.is_finite() {
        0.0
    } else {
        (sum / n as f64).sqrt()
    }
}

/// A phase difference in degrees brought into (−180, 180].
pub fn wrap_deg(d: f64) -> f64 {
    d - 360.0 * ((d - 180.0) / 360.0).ceil()
}

#[cfg(test)]
mod tests {
    use super::wrap_deg;

    #[test]
    fn phase_differences_wrap_to_plus_minus_180() {
        for (d, w) in [
            (0.0, 0.0),
            (180.0, 180.0),
            (-180.0, 180.0),
            (190.0, -170.0),
            (-190.0, 170.0),
            (725.0, 5.0),
            (-359.0, 1.0),
        ] {
            assert!((wrap_deg(d) - w).abs() < 1e-12, "{d} -> {}", wrap_deg(d));
        }
    }
}
