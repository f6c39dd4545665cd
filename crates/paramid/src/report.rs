//! The identification run and its outputs: `identified.toml` (a complete
//! parameter file, loadable wherever `--params` is), `report.json` and
//! `report.md`.

use crate::config::IdentConfig;
use crate::cost::Cost;
use crate::data::{PointData, measure};
use crate::error::{ParamIdError, Result};
use crate::fit::{FitOptions, FitResult, ParameterResult, Pass, identify};
use crate::verify::{VerificationResult, verify};
use helicon_model::{ConfigError, Params};
use rayon::prelude::*;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// A finished identification.
#[derive(Debug, Clone)]
pub struct Identification {
    /// The configuration.
    pub config: IdentConfig,
    /// Measured responses per operating point.
    pub data: Vec<PointData>,
    /// The cost (selected points and weights).
    pub cost: Cost,
    /// The fit.
    pub fit: FitResult,
    /// The identified parameter set (start with the identified values).
    pub identified: Params,
    /// Wall time of the fit alone (optimisation passes and accuracy), s.
    pub fit_time_s: f64,
    /// Time-domain verifications.
    pub verification: Vec<VerificationResult>,
    /// Ground measurements that built the start parameters (the demo's;
    /// empty for `helicon ident fit`).
    pub ground: Vec<GroundValue>,
    /// The cost against the true helicopter's own responses (the demo's,
    /// where the truth is known; `None` otherwise).
    pub truth_model_cost: Option<TruthModelCost>,
}

/// A parameter measured on the ground (thesis §11.1) and put into the start
/// parameters.
#[derive(Debug, Clone, Serialize)]
pub struct GroundValue {
    /// Its `helicon params` key.
    pub key: String,
    /// The measured value (SI).
    pub value: f64,
    /// Its standard error (one σ, SI).
    pub std_error: f64,
    /// The experiment (`helicon ident ground KIND`).
    pub kind: String,
    /// The readings file, relative to the output directory.
    pub file: String,
    /// Readings used.
    pub n_readings: usize,
}

/// The cost (11.1) of the start and of the identified model against the
/// true helicopter's own responses (its ZOH linearisations) at the same
/// operating points, frequencies and weights, without noise: how much nearer
/// the model came to the truth, independently of the flight data's noise.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct TruthModelCost {
    /// Of the parameters before the ground experiments (the Bergen Twin with
    /// the weighed mass and inertias), when there were ground experiments.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub before_ground: Option<f64>,
    /// At the start parameters.
    pub start: f64,
    /// At the identified parameters.
    pub identified: f64,
}

impl Identification {
    /// The [`TruthModelCost`] of this identification for the true
    /// helicopter `truth`: the cost's measured responses replaced by the
    /// truth's model responses at the same frequencies (the weights kept);
    /// also of `before_ground`, the parameters before the ground
    /// experiments, when given.
    pub fn truth_model_cost(
        &self,
        truth: &Params,
        before_ground: Option<&Params>,
    ) -> Result<TruthModelCost> {
        let mut of_truth = self.cost.clone();
        of_truth.base = *truth;
        let truth_values: Vec<f64> = self
            .cost
            .parameters
            .iter()
            .map(|p| crate::keys::get(truth, p.descriptor))
            .collect();
        let h = of_truth.model_at(&truth_values)?;
        let mut c = self.cost.clone();
        // the model's responses only: no prior measurement enters
        c.prior_scale = 0.0;
        for (pt, hp) in c.points.iter_mut().zip(h) {
            for (r, hr) in pt.responses.iter_mut().zip(hp) {
                r.h = hr;
            }
        }
        let start: Vec<f64> = c.parameters.iter().map(|p| p.start).collect();
        let before_ground = match before_ground {
            Some(b) => {
                let values: Vec<f64> = c
                    .parameters
                    .iter()
                    .map(|p| crate::keys::get(b, p.descriptor))
                    .collect();
                let mut cb = c.clone();
                cb.base = *b;
                Some(cb.residuals(&values)?.norm_squared())
            }
            None => None,
        };
        let tc = TruthModelCost {
            before_ground,
            start: c.residuals(&start)?.norm_squared(),
            identified: c.residuals(&self.fit.values)?.norm_squared(),
        };
        if tc.start.is_finite()
            && tc.identified.is_finite()
            && tc.before_ground.is_none_or(f64::is_finite)
        {
            Ok(tc)
        } else {
            Err(ParamIdError::Fit("non-finite truth-model cost".into()))
        }
    }
}

/// Estimate the responses of every operating point (in parallel), fit,
/// and verify on the doublet logs.
pub fn run(cfg: &IdentConfig) -> Result<Identification> {
    let data: Vec<PointData> = (0..cfg.operating_points.len())
        .into_par_iter()
        .map(|i| measure(cfg, i))
        .collect::<Result<_>>()?;
    run_on(cfg, data)
}

/// As [`run`] on responses already estimated (or synthesised).
pub fn run_on(cfg: &IdentConfig, data: Vec<PointData>) -> Result<Identification> {
    let cost = Cost::new(cfg, &data)?;
    let t0 = std::time::Instant::now();
    let fit = identify(
        &cost,
        &FitOptions {
            optimiser: cfg.optimiser,
            max_iterations: cfg.max_iterations,
            auto_fix: cfg.auto_fix,
        },
    )?;
    let fit_time_s = t0.elapsed().as_secs_f64();
    let identified = cost.params_at(&fit.values);
    identified
        .validate("identified parameters")
        .map_err(|e| ParamIdError::Fit(e.to_string()))?;
    let verification = (0..cfg.verification.len())
        .map(|i| verify(cfg, i, &cfg.start, &identified))
        .collect::<Result<_>>()?;
    Ok(Identification {
        config: cfg.clone(),
        data,
        cost,
        fit,
        identified,
        fit_time_s,
        verification,
        ground: Vec::new(),
        truth_model_cost: None,
    })
}

/// One response's cost in the report.
#[derive(Debug, Clone, Serialize)]
pub struct ResponseCost {
    /// Operating point.
    pub operating_point: String,
    /// `output/input`.
    pub response: String,
    /// Frequency points in the cost (γ² above the threshold).
    pub points: usize,
    /// Its cost at the start parameters.
    pub start: f64,
    /// Its cost at the identified parameters.
    pub identified: f64,
}

/// `report.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// The IDENT.toml.
    pub ident_file: String,
    /// `thesis` or `cifer`.
    pub cost_form: crate::config::CostForm,
    /// `lm` or `simplex`.
    pub optimiser: crate::config::Optimiser,
    /// Coherence threshold.
    pub min_coherence: f64,
    /// Fit wall time, s.
    pub fit_time_s: f64,
    /// Number of residuals.
    pub residuals: usize,
    /// Each parameter.
    pub parameters: Vec<ParameterResult>,
    /// Total cost at the start.
    pub cost_start: f64,
    /// Total cost at the identified parameters.
    pub cost_identified: f64,
    /// Per operating point and response.
    pub costs: Vec<ResponseCost>,
    /// Keys of the correlation matrix.
    pub correlation_keys: Vec<String>,
    /// Correlation matrix of the identified (free) parameters.
    pub correlation: Vec<Vec<f64>>,
    /// Optimisation passes.
    pub passes: Vec<Pass>,
    /// Time-domain verifications.
    pub verification: Vec<VerificationResult>,
    /// Responses left out of the cost, with why.
    pub skipped_responses: Vec<String>,
    /// Ground measurements in the start parameters (the demo's; empty
    /// for `helicon ident fit`).
    pub ground: Vec<GroundValue>,
    /// The demo's cost against the true helicopter's model responses.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth_model_cost: Option<TruthModelCost>,
}

impl Identification {
    /// The report.
    pub fn report(&self) -> Report {
        let mut costs = Vec::new();
        for (n, pt) in self.cost.points.iter().enumerate() {
            for (k, r) in pt.responses.iter().enumerate() {
                costs.push(ResponseCost {
                    operating_point: pt.name.clone(),
                    response: r.label.clone(),
                    points: r.omega_rad_s.len(),
                    start: self.fit.costs_start[n][k],
                    identified: self.fit.costs_final[n][k],
                });
            }
        }
        Report {
            ident_file: self.config.file.clone(),
            cost_form: self.config.cost,
            optimiser: self.config.optimiser,
            min_coherence: self.config.min_coherence,
            fit_time_s: self.fit_time_s,
            residuals: self.fit.residuals,
            parameters: self.fit.parameters.clone(),
            cost_start: self.fit.cost_start,
            cost_identified: self.fit.cost_final,
            costs,
            correlation_keys: self.fit.correlation_keys.clone(),
            correlation: self.fit.correlation.clone(),
            passes: self.fit.passes.clone(),
            verification: self.verification.clone(),
            skipped_responses: self.cost.skipped.clone(),
            ground: self.ground.clone(),
            truth_model_cost: self.truth_model_cost,
        }
    }

    /// `identified.toml`: the complete parameter set.
    pub fn identified_toml(&self) -> String {
        let mut s = format!(
            "# Identified by `helicon ident fit` from {} ({} of {} parameters identifiable;\n# see report.md). The other keys are the start values.\n",
            self.config.file,
            self.fit
                .parameters
                .iter()
                .filter(|p| p.identifiable)
                .count(),
            self.fit.parameters.len()
        );
        s.push_str(&self.identified.to_toml());
        s
    }

    /// Write `identified.toml`, `report.json` and `report.md` to `dir`.
    pub fn write(&self, dir: &Path) -> Result<()> {
        let io = |file: &Path| {
            let f = file.display().to_string();
            move |source| ConfigError::Io {
                file: f,
                action: "write",
                source,
            }
        };
        std::fs::create_dir_all(dir).map_err(io(dir))?;
        let p = dir.join("identified.toml");
        std::fs::write(&p, self.identified_toml()).map_err(io(&p))?;
        let report = self.report();
        let json = serde_json::to_string_pretty(&report)
            .map_err(|e| ParamIdError::Fit(format!("report.json: {e}")))?;
        let p = dir.join("report.json");
        std::fs::write(&p, json + "\n").map_err(io(&p))?;
        let p = dir.join("report.md");
        std::fs::write(&p, markdown(&report)).map_err(io(&p))?;
        Ok(())
    }
}

fn opt(v: Option<f64>) -> String {
    v.map_or("–".into(), |v| format!("{v:.2}"))
}

/// The demo's sections of `report.md`: the cost against the truth's model
/// responses and the ground measurements.
fn demo_sections(s: &mut String, r: &Report) {
    if let Some(t) = r.truth_model_cost {
        let before = t.before_ground.map_or(String::new(), |b| {
            format!("{b:.4e} before the ground experiments, ")
        });
        let _ = writeln!(
            s,
            "Against the true helicopter's own model responses (same points, frequencies and weights, no noise): {before}{:.4e} at the start, {:.4e} identified (ratio {:.2e}).\n",
            t.start,
            t.identified,
            t.identified / t.start
        );
    }
    if !r.ground.is_empty() {
        let _ = writeln!(
            s,
            "## Ground measurements (thesis §11.1, in the start parameters)\n\n| key | value | standard error | % | kind | readings |\n|---|---|---|---|---|---|"
        );
        for g in &r.ground {
            let _ = writeln!(
                s,
                "| `{}` | {:.6} | {:.2e} | {:.2} | {} | {} ({}) |",
                g.key,
                g.value,
                g.std_error,
                100.0 * g.std_error / g.value.abs(),
                g.kind,
                g.file,
                g.n_readings
            );
        }
        let _ = writeln!(s);
    }
}

/// `report.md`.
pub fn markdown(r: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Parameter identification\n");
    let _ = writeln!(
        s,
        "From `{}`: cost `{}`, optimiser `{}`, γ² > {}, {} residuals; fit {:.2} s.\n",
        r.ident_file,
        format!("{:?}", r.cost_form).to_lowercase(),
        format!("{:?}", r.optimiser).to_lowercase(),
        r.min_coherence,
        r.residuals,
        r.fit_time_s
    );
    let _ = writeln!(
        s,
        "Cost {:.4e} at the start, {:.4e} identified (ratio {:.2e}).\n",
        r.cost_start,
        r.cost_identified,
        r.cost_identified / r.cost_start
    );
    demo_sections(&mut s, r);
    for k in &r.skipped_responses {
        let _ = writeln!(s, "- {k}");
    }
    if !r.skipped_responses.is_empty() {
        let _ = writeln!(s);
    }
    let _ = writeln!(s, "## Parameters\n");
    let _ = writeln!(
        s,
        "| key | start | prior ± σ | identified | change % | CR % | insensitivity % | identifiable | reason |\n|---|---|---|---|---|---|---|---|---|"
    );
    for p in &r.parameters {
        let prior = match (p.prior, p.prior_std) {
            (Some(v), Some(sd)) => format!("{v} ± {sd:.3e}"),
            _ => "–".into(),
        };
        let _ = writeln!(
            s,
            "| `{}` | {} | {} | {:.6} | {:+.2} | {} | {} | {} | {} |",
            p.key,
            p.start,
            prior,
            p.identified,
            p.change_pct,
            opt(p.cramer_rao_pct),
            opt(p.insensitivity_pct),
            if p.identifiable { "yes" } else { "**no**" },
            p.reason.as_deref().unwrap_or("")
        );
    }
    let _ = writeln!(
        s,
        "\nGuidelines (CIFER): Cramér–Rao bound ≤ 20 %, insensitivity ≤ 10 %.\n"
    );
    let _ = writeln!(s, "## Cost per response\n");
    let _ = writeln!(
        s,
        "| operating point | response | points | start | identified |\n|---|---|---|---|---|"
    );
    for c in &r.costs {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.4e} | {:.4e} |",
            c.operating_point, c.response, c.points, c.start, c.identified
        );
    }
    if !r.correlation_keys.is_empty() {
        let _ = writeln!(s, "\n## Correlation of the identified parameters\n");
        let _ = write!(s, "| |");
        for k in 0..r.correlation_keys.len() {
            let _ = write!(s, " {} |", k + 1);
        }
        let _ = write!(s, "\n|---|");
        for _ in &r.correlation_keys {
            let _ = write!(s, "---|");
        }
        let _ = writeln!(s);
        for (i, k) in r.correlation_keys.iter().enumerate() {
            let _ = write!(s, "| {} `{k}` |", i + 1);
            for v in &r.correlation[i] {
                let _ = write!(s, " {v:+.2} |");
            }
            let _ = writeln!(s);
        }
    }
    let _ = writeln!(s, "\n## Passes\n");
    for (i, p) in r.passes.iter().enumerate() {
        let _ = writeln!(
            s,
            "{}. {} free: cost {:.4e} → {:.4e}, {} evaluations, {}",
            i + 1,
            p.free.len(),
            p.cost_start,
            p.cost_end,
            p.evaluations,
            p.termination
        );
    }
    if !r.verification.is_empty() {
        let _ = writeln!(
            s,
            "\n## Time-domain verification (Theil inequality coefficient)\n"
        );
        let _ = writeln!(
            s,
            "| log | point | start state | wind | output | start | identified |\n|---|---|---|---|---|---|---|"
        );
        for v in &r.verification {
            for o in &v.outputs {
                let _ = writeln!(
                    s,
                    "| {} | {} | {:?} | {:?} | {} | {:.3} | {:.3} |",
                    v.log,
                    v.operating_point,
                    v.initial_state,
                    v.wind,
                    o.output,
                    o.theil_start,
                    o.theil_identified
                );
            }
        }
    }
    s
}
