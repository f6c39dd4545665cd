//! The envelope mission (`scenarios/envelope-mission.toml`) flown with the
//! gain schedule for N seeds (default 20), and the single hover design on
//! the same mission: tracking RMS per segment (median and worst over the
//! seeds) and each flight's outcome. The numbers of docs/envelope.md.
//!
//! ```text
//! cargo run --release --example 05_envelope_mission -- [SEEDS]
//! ```

use anyhow::{Context, Result};
use helicon_sim::closed_loop::{Flight, fly, prepare};
use helicon_sim::envelope::segment_rms;
use helicon_sim::scenario::Scenario;
use std::path::Path;

/// The mission's segments (s), from its legs.
const SEGMENTS: [(&str, f64, f64); 7] = [
    ("hover", 0.0, 5.0),
    ("accelerate + climb", 5.0, 22.0),
    ("cruise 15 m/s", 22.0, 30.0),
    ("turn 0.1 rad/s", 30.0, 64.4),
    ("cruise after turn", 64.4, 75.0),
    ("decelerate", 75.0, 92.0),
    ("hover", 92.0, 105.0),
];

fn fly_seed(base: &Scenario, seed: u64, schedule: bool) -> Result<Flight> {
    let mut s = base.clone();
    s.wind.seed = seed;
    s.sensors.seed = seed;
    if !schedule {
        s.controller.schedule = None;
    }
    let p = prepare(&s).context("preparing")?;
    Ok(fly(&s, &p, None)?)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        f64::NAN
    } else {
        v[v.len() / 2]
    }
}

fn table(name: &str, flights: &[Flight]) {
    let completed = flights
        .iter()
        .filter(|f| f.summary.reason.is_none())
        .count();
    println!("\n### {name}: {completed}/{} completed\n", flights.len());
    for f in flights.iter().filter(|f| f.summary.reason.is_some()) {
        println!(
            "- seed {}: {}",
            f.summary.wind_seed,
            f.summary.reason.as_deref().unwrap_or("")
        );
    }
    println!(
        "\n| segment | t (s) | flown | horizontal RMS median / worst (m/s) | vertical RMS median / worst (m/s) | heading RMS median / worst (deg) |"
    );
    println!("|---|---|---|---|---|---|");
    for (seg, t0, t1) in SEGMENTS {
        let rms: Vec<_> = flights
            .iter()
            .filter_map(|f| segment_rms(&f.log, t0, t1))
            .collect();
        let mut h: Vec<f64> = rms.iter().map(|r| r.horizontal_m_s).collect();
        let mut v: Vec<f64> = rms.iter().map(|r| r.vertical_m_s).collect();
        let mut p: Vec<f64> = rms.iter().map(|r| r.heading_rad.to_degrees()).collect();
        let worst = |x: &[f64]| x.iter().copied().fold(f64::NAN, f64::max);
        println!(
            "| {seg} | {t0}–{t1} | {} | {:.3} / {:.3} | {:.3} / {:.3} | {:.2} / {:.2} |",
            rms.len(),
            median(&mut h.clone()),
            worst(&h),
            median(&mut v.clone()),
            worst(&v),
            median(&mut p.clone()),
            worst(&p)
        );
        h.clear();
        v.clear();
        p.clear();
    }
}

/// The frozen closed loop at forward speeds 0–15 m/s (straight and level)
/// with the schedule interpolated there, and with the hover design's gains
/// held: the largest |z| of each (the margin the hover design loses).
fn frozen_comparison(base: &Scenario) -> Result<()> {
    use helicon_gnc::schedule::{discrete_model_at, frozen_closed_loop};
    let p = prepare(base)?;
    let Some(schedule) = &p.schedule else {
        return Ok(());
    };
    let mut hover = base.clone();
    hover.controller.schedule = None;
    let hover = prepare(&hover)?;
    let ts = hover.gains.set.sample_time_s;
    println!("\n| forward speed (m/s) | schedule |z|max | hover design |z|max |");
    println!("|---|---|---|");
    for v in [0.0, 2.5, 5.0, 7.5, 10.0, 12.5, 15.0] {
        let sigma = nalgebra::Vector3::new(v, 0.0, 0.0);
        let (phi, gamma, t) = discrete_model_at(&p.model, &sigma, ts)?;
        let radius = |g: &helicon_core::GainSet| -> Result<f64> {
            Ok(helicon_lti::analysis::spectral_radius(
                &frozen_closed_loop(&phi, &gamma, &t.x, g),
            )?)
        };
        println!(
            "| {v} | {:.6} | {:.6} |",
            radius(&schedule.at(&sigma))?,
            radius(&hover.gains.set)?
        );
    }
    Ok(())
}

fn main() -> Result<()> {
    let seeds: u64 = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()
        .context("SEEDS must be a positive integer")?
        .unwrap_or(20);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/envelope-mission.toml");
    let base = Scenario::from_file(&path)?;
    frozen_comparison(&base)?;
    let mut scheduled = Vec::new();
    let mut hover = Vec::new();
    for seed in 1..=seeds {
        scheduled.push(fly_seed(&base, seed, true)?);
        hover.push(fly_seed(&base, seed, false)?);
        eprintln!("seed {seed} flown");
    }
    table("gain schedule", &scheduled);
    table("single hover design", &hover);
    Ok(())
}
