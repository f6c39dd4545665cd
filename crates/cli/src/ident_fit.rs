//! `helicon ident fit` and `helicon ident demo`: identification of the
//! model's physical parameters from flight frequency responses at several
//! operating points (thesis chapter 11, MOSCA; see docs/paramid.md).

use anyhow::{Context, Result, bail};
use clap::Args;
use helicon_ident::Complex64;
use helicon_model::Params;
use helicon_paramid::config::IdentConfig;
use helicon_paramid::demo::{DemoOptions, FLIGHTS, TRUTHS, run_demo};
use helicon_paramid::report::{Identification, run};
use helicon_sim::plot::{Figure, HLine, Panel, Series};
use std::path::{Path, PathBuf};

/// `helicon ident fit`.
#[derive(Args, Debug)]
pub struct FitArgs {
    /// The identification file (operating points, logs, responses, parameters; docs/paramid.md).
    pub ident: PathBuf,
    /// Output directory: identified.toml, report.json, report.md, Bode overlays.
    #[arg(long)]
    pub out: PathBuf,
}

/// `helicon ident demo`.
#[derive(Args, Debug)]
pub struct DemoArgs {
    /// The true helicopter (a parameter file; default: the shipped truth-a).
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// The identification flights to fly and fit, comma-separated (hover, fwd5, fwd10).
    #[arg(long, value_delimiter = ',', default_value = "hover,fwd5,fwd10")]
    pub flights: Vec<String>,
    /// Turbulence and sensor-noise seed (default: the scenarios').
    #[arg(long)]
    pub seed: Option<u64>,
    /// Frequency points per response.
    #[arg(long, default_value_t = 40)]
    pub points: usize,
    /// Skip the doublet verification flight.
    #[arg(long)]
    pub no_verify: bool,
    /// Skip the simulated ground experiments (§11.1): start from the Bergen
    /// Twin's drag coefficient, lift slopes and hinge spring.
    #[arg(long)]
    pub no_ground: bool,
    /// Output directory: flights/, start.toml, IDENT.toml and the fit's outputs.
    #[arg(long)]
    pub out: PathBuf,
}

/// Run `helicon ident fit`.
pub fn run_fit(a: &FitArgs) -> Result<()> {
    let cfg = IdentConfig::from_file(&a.ident)?;
    let t0 = std::time::Instant::now();
    let spinner = crate::console::spinner("identifying the parameters");
    let id = run(&cfg);
    spinner.finish_and_clear();
    let id = id?;
    finish(&id, &a.out, t0.elapsed().as_secs_f64())
}

/// Run `helicon ident demo`.
pub fn run_demo_cmd(a: &DemoArgs) -> Result<()> {
    let truth = match &a.truth {
        Some(p) => Params::from_file(p)?,
        None => Params::from_toml_str(TRUTHS[0].1, "params/truths/truth-a.toml")?,
    };
    for f in &a.flights {
        if !FLIGHTS.iter().any(|g| g.0 == f) {
            bail!("--flights: unknown flight `{f}` (hover, fwd5, fwd10)");
        }
    }
    if !(2..=2000).contains(&a.points) {
        bail!("--points = {}: must be in 2..=2000", a.points);
    }
    let opts = DemoOptions {
        flights: a.flights.clone(),
        seed: a.seed,
        verify: !a.no_verify,
        points: a.points,
        ground: !a.no_ground,
        ..DemoOptions::default()
    };
    let t0 = std::time::Instant::now();
    let spinner = crate::console::spinner(format!(
        "identifying from simulated flights ({})",
        a.flights.join(", ")
    ));
    let id = run_demo(&truth, &a.out, &opts);
    spinner.finish_and_clear();
    let id = id?;
    finish(&id, &a.out, t0.elapsed().as_secs_f64())?;
    print_demo(&id, &truth)
}

/// The demo's own printout: the ground measurements, the cost against the
/// truth's model responses, and the truth beside the identified values.
fn print_demo(id: &Identification, truth: &Params) -> Result<()> {
    if !id.ground.is_empty() {
        println!(
            "ground measurements on the true helicopter (in start.toml; mass and inertias weighed and pendulum-measured):"
        );
    }
    for g in &id.ground {
        let d = helicon_paramid::keys::find(&g.key).context("ground key")?;
        let want = helicon_paramid::keys::get(truth, d);
        println!(
            "  {:38} {:>10.5} ± {:.2e} ({:.2} %, {} readings, {})  truth {:>10.5}  error {:+6.2} %",
            g.key,
            g.value,
            g.std_error,
            100.0 * g.std_error / g.value.abs(),
            g.n_readings,
            g.file,
            want,
            100.0 * (g.value - want) / want
        );
    }
    if let Some(t) = id.truth_model_cost {
        let before = t.before_ground.map_or(String::new(), |b| {
            format!("{b:.4e} before the ground tests -> ")
        });
        println!(
            "cost against the truth's own model responses (no noise): {before}{:.4e} start -> {:.4e} identified ({:.0}x lower than the start)",
            t.start,
            t.identified,
            t.start / t.identified
        );
    }
    println!("truth vs identified (the truth is known in the demo):");
    for p in &id.fit.parameters {
        let d = helicon_paramid::keys::find(&p.key).context("parameter key")?;
        let want = helicon_paramid::keys::get(truth, d);
        println!(
            "  {:38} truth {:>10.5}  identified {:>10.5}  error {:+7.2} %{}",
            p.key,
            want,
            p.identified,
            100.0 * (p.identified - want) / want,
            if p.identifiable {
                ""
            } else {
                "  (not identifiable)"
            }
        );
    }
    Ok(())
}

fn finish(id: &Identification, out: &Path, elapsed_s: f64) -> Result<()> {
    id.write(out)?;
    let plots = bode_overlays(id, out)?;
    let vplots = verification_plots(id, out)?;
    let r = id.report();
    println!(
        "cost {:.4e} -> {:.4e} ({} residuals, {} pass(es), fit {:.2} s)",
        r.cost_start,
        r.cost_identified,
        r.residuals,
        r.passes.len(),
        r.fit_time_s
    );
    for k in &r.skipped_responses {
        println!("  note: {k}");
    }
    println!(
        "  {:38} {:>11} {:>12} {:>9} {:>8} {:>8}  identifiable",
        "parameter", "start", "identified", "change %", "CR %", "ins %"
    );
    let f = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.2}"));
    for p in &r.parameters {
        println!(
            "  {:38} {:>11.5} {:>12.6} {:>+9.2} {:>8} {:>8}  {}{}",
            p.key,
            p.start,
            p.identified,
            p.change_pct,
            f(p.cramer_rao_pct),
            f(p.insensitivity_pct),
            if p.identifiable { "yes" } else { "NO" },
            p.reason
                .as_deref()
                .map_or(String::new(), |s| format!(" ({s})"))
        );
    }
    for v in &r.verification {
        for o in &v.outputs {
            println!(
                "  verification {} {}: Theil {:.3} (start) -> {:.3} (identified)",
                v.log, o.output, o.theil_start, o.theil_identified
            );
        }
    }
    println!(
        "wrote identified.toml, report.json, report.md and {} plots to {} ({elapsed_s:.1} s)",
        plots + vplots,
        out.display()
    );
    Ok(())
}

fn file_stem(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// One Bode overlay per operating point and response in the cost:
/// estimate (all points), start and identified model, coherence panel.
fn bode_overlays(id: &Identification, out: &Path) -> Result<usize> {
    // the model at every estimated point of each response in the cost
    let mut omegas = Vec::new();
    let mut measured = Vec::new();
    for (pt, data) in id.cost.points.iter().zip(&id.data) {
        let mut om = Vec::new();
        let mut ms = Vec::new();
        for r in &pt.responses {
            let m = data
                .responses
                .iter()
                .find(|m| m.response.label() == r.label)
                .context("response of the cost without data")?;
            om.push(m.frf.omega_rad_s.clone());
            ms.push(m);
        }
        omegas.push(om);
        measured.push(ms);
    }
    let start: Vec<f64> = id.cost.parameters.iter().map(|p| p.start).collect();
    let h0 = id.cost.model_at_omegas(&start, Some(&omegas))?;
    let h1 = id.cost.model_at_omegas(&id.fit.values, Some(&omegas))?;
    let mut n = 0;
    for (p, pt) in id.cost.points.iter().enumerate() {
        for (k, r) in pt.responses.iter().enumerate() {
            let f = &measured[p][k].frf;
            let lw = |v: &[f64]| -> Vec<(f64, f64)> {
                f.omega_rad_s
                    .iter()
                    .zip(v)
                    .map(|(w, y)| (w.log10(), *y))
                    .collect()
            };
            let db = |h: &[Complex64]| -> Vec<f64> {
                h.iter().map(|z| 20.0 * z.norm().log10()).collect()
            };
            let near = |h: &[Complex64]| crate::ident_cmd::phase_near_estimate(f, h);
            let (mag_d, ph_d, coh) = (lw(&f.mag_db()), lw(&f.phase_deg()), lw(&f.coherence));
            let (mag_s, ph_s) = (lw(&db(&h0[p][k])), lw(&near(&h0[p][k])));
            let (mag_i, ph_i) = (lw(&db(&h1[p][k])), lw(&near(&h1[p][k])));
            let mut pc = Panel::new("coherence γ² [-]").series(Series::new("γ²", &coh));
            pc.hlines.push(HLine {
                y: id.config.min_coherence,
                label: format!("{}", id.config.min_coherence),
                color: [127, 127, 127],
            });
            pc.y_include = vec![0.0, 1.0];
            let path = out.join(format!(
                "bode_{}_{}.png",
                file_stem(&pt.name),
                file_stem(&r.label)
            ));
            Figure::new(&format!("{}: {}", pt.name, r.label), "ω [rad/s]")
                .log_x()
                .panel(
                    Panel::new("magnitude [dB]")
                        .series(Series::new("flight data", &mag_d))
                        .series(Series::new("start model", &mag_s).dashed())
                        .series(Series::new("identified model", &mag_i)),
                )
                .panel(
                    Panel::new("phase [deg]")
                        .series(Series::new("flight data", &ph_d))
                        .series(Series::new("start model", &ph_s).dashed())
                        .series(Series::new("identified model", &ph_i)),
                )
                .panel(pc)
                .write(&path)
                .with_context(|| path.display().to_string())?;
            n += 1;
        }
    }
    Ok(n)
}

/// One overlay per verification flight: the log and both models, per output.
fn verification_plots(id: &Identification, out: &Path) -> Result<usize> {
    for (i, v) in id.verification.iter().enumerate() {
        let series: Vec<[Vec<(f64, f64)>; 3]> = v
            .traces
            .iter()
            .map(|tr| {
                std::array::from_fn(|j| v.t_s.iter().zip(&tr[j]).map(|(t, y)| (*t, *y)).collect())
            })
            .collect();
        let mut fig = Figure::new(
            &format!(
                "verification {} ({}), perturbations from the first sample",
                i + 1,
                v.operating_point
            ),
            "time − t0 [s]",
        );
        for (o, s) in v.outputs.iter().zip(&series) {
            fig = fig.panel(
                Panel::new(&format!(
                    "{} [{}]",
                    o.output,
                    helicon_sim::log_csv::log_unit(&o.output).unwrap_or("-")
                ))
                .series(Series::new("flight log", &s[0]))
                .series(Series::new("start model", &s[1]).dashed())
                .series(Series::new("identified model", &s[2])),
            );
        }
        let path = out.join(format!("verify_{}.png", i + 1));
        fig.write(&path)
            .with_context(|| path.display().to_string())?;
    }
    Ok(id.verification.len())
}
