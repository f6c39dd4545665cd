//! The envelope mission (`scenarios/envelope-mission.toml`) flown with the
//! gain schedule and with the single hover design on the same seeds (wind
//! and sensor seed 1…N, default 20): tracking RMS per segment for both,
//! side by side and paired per seed (hover − schedule), the mean along- and
//! cross-track lag, and the frozen-point spectral radii. The numbers of
//! docs/envelope.md.
//!
//! ```text
//! cargo run --release -p helicon-examples --example 05_envelope_mission -- \
//!     [SEEDS] [--navigation thesis|eskf] [--turn RAD_S] [--w20 M_S] [--extra-cruise S]
//! ```
//!
//! The options push the mission: another navigation, another turn rate
//! (the heading change stays 180°), another Dryden intensity (W₂₀, 7.7 m/s
//! light, 15.4 moderate), and the 15 m/s cruise held longer before the turn.

use anyhow::{Context, Result, bail};
use helicon_core::trajectory::SCurve;
use helicon_sim::closed_loop::{Flight, fly, prepare};
use helicon_sim::envelope::{LegSection, segment_lag, segment_rms};
use helicon_sim::scenario::{EstimatorKind, Scenario};
use std::path::Path;

/// A named window of the mission: (name, t0 s, t1 s).
type Segment = (String, f64, f64);

/// The command line.
struct Options {
    seeds: u64,
    navigation: Option<EstimatorKind>,
    turn_rad_s: Option<f64>,
    w20_m_s: Option<f64>,
    extra_cruise_s: f64,
}

fn options() -> Result<Options> {
    let mut o = Options {
        seeds: 20,
        navigation: None,
        turn_rad_s: None,
        w20_m_s: None,
        extra_cruise_s: 0.0,
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = |name: &str| -> Result<f64> {
            let v = args
                .next()
                .with_context(|| format!("{name} needs a value"))?;
            let x: f64 = v
                .parse()
                .with_context(|| format!("{name} {v}: not a number"))?;
            if !(x.is_finite() && x >= 0.0) {
                bail!("{name} {v}: must be finite and >= 0");
            }
            Ok(x)
        };
        match a.as_str() {
            "--navigation" => {
                o.navigation = Some(match args.next().as_deref() {
                    Some("thesis") => EstimatorKind::Thesis,
                    Some("eskf") => EstimatorKind::Eskf,
                    other => bail!("--navigation {other:?}: thesis or eskf"),
                });
            }
            "--turn" => o.turn_rad_s = Some(value("--turn")?),
            "--w20" => o.w20_m_s = Some(value("--w20")?),
            "--extra-cruise" => o.extra_cruise_s = value("--extra-cruise")?,
            s => {
                o.seeds = s
                    .parse()
                    .with_context(|| format!("{s}: SEEDS must be a positive integer"))?;
            }
        }
    }
    if o.seeds == 0 {
        bail!("SEEDS must be a positive integer");
    }
    Ok(o)
}

/// The mission with the options applied, and its segments (name, t0, t1):
/// from its legs (two speed legs: up and down; two yaw-rate legs: into and
/// out of the turn).
fn mission(base: &Scenario, o: &Options) -> Result<(Scenario, Vec<Segment>)> {
    let mut s = base.clone();
    if let Some(n) = o.navigation {
        s.estimator.kind = n;
    }
    if let Some(w) = o.w20_m_s {
        s.wind
            .dryden
            .as_mut()
            .context("the mission has no [wind.dryden]")?
            .w20_m_s = w;
    }
    let tr = s
        .trajectory
        .as_mut()
        .context("the mission has no [trajectory]")?;
    let (&[up, down], &[into, out]) = (tr.speed.as_slice(), tr.yaw_rate.as_slice()) else {
        bail!("the mission must have two speed legs and two yaw-rate legs");
    };
    let rate = o.turn_rad_s.unwrap_or(into.value);
    if rate <= 0.0 {
        bail!("--turn must be > 0");
    }
    let x = o.extra_cruise_s;
    let heading_change = into.value * (out.t_s - into.t_s);
    let t_turn = into.t_s + x;
    let t_out = t_turn + heading_change / rate;
    let turn = SCurve::new(rate, tr.max_yaw_accel_rad_s2, tr.max_yaw_jerk_rad_s3).duration_s();
    // the deceleration starts where it did (shifted by the extra cruise), or
    // 10 s after a slower turn ends
    let t_down = (down.t_s + x).max(t_out + turn + 10.0);
    tr.yaw_rate = vec![
        LegSection {
            t_s: t_turn,
            value: rate,
        },
        LegSection {
            t_s: t_out,
            value: 0.0,
        },
    ];
    tr.speed = vec![
        up,
        LegSection {
            t_s: t_down,
            value: down.value,
        },
    ];
    let speed = |d: f64| SCurve::new(d, tr.max_accel_m_s2, tr.max_jerk_m_s3).duration_s();
    let t_up_end = up.t_s + speed(up.value);
    let t_down_end = t_down + speed(up.value - down.value);
    s.duration_s = base.duration_s + (t_down - down.t_s);
    let segments = vec![
        ("hover".to_string(), 0.0, up.t_s),
        ("accelerate + climb".into(), up.t_s, t_up_end),
        (format!("cruise {} m/s", up.value), t_up_end, t_turn),
        (format!("turn {rate} rad/s"), t_turn, t_out + turn),
        ("cruise after turn".into(), t_out + turn, t_down),
        ("decelerate".into(), t_down, t_down_end),
        ("hover".into(), t_down_end, s.duration_s),
    ];
    Ok((s, segments))
}

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

/// Median, smallest and largest of `v` (NaN when empty).
fn spread(v: &[f64]) -> (f64, f64, f64) {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    match (v.first(), v.last()) {
        (Some(&lo), Some(&hi)) => (v[v.len() / 2], lo, hi),
        _ => (f64::NAN, f64::NAN, f64::NAN),
    }
}

fn outcomes(name: &str, flights: &[Flight]) {
    let completed = flights
        .iter()
        .filter(|f| f.summary.reason.is_none())
        .count();
    println!("{name}: {completed}/{} completed", flights.len());
    for f in flights.iter().filter(|f| f.summary.reason.is_some()) {
        println!(
            "- seed {}: {}",
            f.summary.wind_seed,
            f.summary.reason.as_deref().unwrap_or("")
        );
    }
}

/// One quantity per segment, both controllers and the paired difference.
fn paired_table(
    what: &str,
    segments: &[Segment],
    scheduled: &[Flight],
    hover: &[Flight],
    value: &dyn Fn(&Flight, f64, f64) -> Option<f64>,
) {
    println!(
        "\n{what}: median [min–max] over the seeds; paired: hover − schedule, per seed; \
         hover worse: seeds where its |value| is the larger\n\n\
         | segment | t (s) | schedule | hover design | paired difference | hover worse |\n\
         |---|---|---|---|---|---|"
    );
    for (seg, t0, t1) in segments {
        let mut s = Vec::new();
        let mut h = Vec::new();
        let mut d = Vec::new();
        let mut worse = 0;
        for (fs, fh) in scheduled.iter().zip(hover) {
            let (a, b) = (value(fs, *t0, *t1), value(fh, *t0, *t1));
            if let Some(a) = a {
                s.push(a);
            }
            if let Some(b) = b {
                h.push(b);
            }
            if let (Some(a), Some(b)) = (a, b) {
                d.push(b - a);
                worse += usize::from(b.abs() > a.abs());
            }
        }
        let f = |(m, lo, hi): (f64, f64, f64)| format!("{m:.3} [{lo:.3}–{hi:.3}]");
        println!(
            "| {seg} | {t0:.1}–{t1:.1} | {} | {} | {} | {}/{} |",
            f(spread(&s)),
            f(spread(&h)),
            f(spread(&d)),
            worse,
            d.len()
        );
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
    let o = options()?;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/envelope-mission.toml");
    let (base, segments) = mission(&Scenario::from_file(&path)?, &o)?;
    frozen_comparison(&base)?;
    let mut scheduled = Vec::new();
    let mut hover = Vec::new();
    for seed in 1..=o.seeds {
        scheduled.push(fly_seed(&base, seed, true)?);
        hover.push(fly_seed(&base, seed, false)?);
        eprintln!("seed {seed} flown");
    }
    println!();
    outcomes("gain schedule", &scheduled);
    outcomes("single hover design", &hover);
    let rms = |pick: fn(&helicon_sim::envelope::SegmentRms) -> f64| {
        move |f: &Flight, t0: f64, t1: f64| segment_rms(&f.log, t0, t1).map(|r| pick(&r))
    };
    paired_table(
        "Horizontal velocity RMS (m/s)",
        &segments,
        &scheduled,
        &hover,
        &rms(|r| r.horizontal_m_s),
    );
    paired_table(
        "Vertical velocity RMS (m/s)",
        &segments,
        &scheduled,
        &hover,
        &rms(|r| r.vertical_m_s),
    );
    paired_table(
        "Heading RMS (deg)",
        &segments,
        &scheduled,
        &hover,
        &rms(|r| r.heading_rad.to_degrees()),
    );
    paired_table(
        "Mean along-track lag (m/s, + slower than the reference)",
        &segments,
        &scheduled,
        &hover,
        &|f, t0, t1| segment_lag(&f.log, t0, t1).map(|l| l.along_m_s),
    );
    paired_table(
        "Mean cross-track error (m/s, + velocity left of the reference: behind a right turn)",
        &segments,
        &scheduled,
        &hover,
        &|f, t0, t1| segment_lag(&f.log, t0, t1).map(|l| l.cross_m_s),
    );
    Ok(())
}
