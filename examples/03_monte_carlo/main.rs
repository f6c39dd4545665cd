//! A Monte Carlo campaign from TOML text (thesis controller robustness).
#![allow(missing_docs)]

use helicon_sim::mc::{Campaign, RunOptions, run};

fn main() -> anyhow::Result<()> {
    let campaign = Campaign::from_toml_str(
        r#"
name = "example-robustness"
runs = 24
seed = 7
design = "nominal"
disperse_wind_seed = true
trace_rate_hz = 10.0

[scenario]
name = "hover in turbulence"
duration_s = 10.0
[[scenario.reference]]
t_s = 1.0
output = "vn"
value = 1.0
[scenario.wind.thesis]
max_gust_m_s = 1.0

[[dispersion]]
param = "body.mass_kg"
distribution = "normal"
kind = "relative"
sigma = 0.05

[[dispersion]]
param = "main_rotor.omega_rad_s"
distribution = "uniform"
kind = "relative"
half_width = 0.05
"#,
        "<example>",
        None,
    )?;
    let out = std::env::temp_dir().join("helicon-example-mc");
    let report = run(&campaign, &RunOptions::default(), &out, None)?;
    let s = &report.stats;
    println!(
        "{} runs flown ({} already there), {} failed ({:.1} %)",
        report.flown,
        report.skipped,
        s.failed,
        100.0 * s.failure_fraction
    );
    if let Some(m) = s.metrics.get("vn_rms") {
        println!(
            "vn RMS error over {} completed runs: p5 {:?}, median {:?}, p95 {:?} m/s",
            m.n, m.p5, m.p50, m.p95
        );
    }
    println!("results in {}", out.display());
    Ok(())
}
