//! `helicon design --schedule ENVELOPE.toml --out DIR`: the gain schedule
//! over the flight envelope (trim, linearise and design at every grid point),
//! its frozen-point stability check, and the envelope map.
//!
//! Writes `DIR/schedule.json` (what a scenario's `[controller]
//! schedule_file` flies), `DIR/envelope.csv` (one row per design point:
//! operating point, trim inputs and attitude, design and frozen spectral
//! radii), `DIR/frozen_check.csv` (every frozen point) and
//! `DIR/envelope.png` (the envelope map). An unstable frozen point is an
//! error (after the files are written, so it can be inspected).

use anyhow::{Context, Result, bail};
use clap::Args;
use helicon_gnc::schedule::{
    EnvelopeConfig, FrozenCheck, Schedule, design_schedule, frozen_point_check,
};
use helicon_sim::plot::{Figure, Panel, Series};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// `helicon design`.
#[derive(Args, Debug)]
pub struct DesignArgs {
    /// Envelope file (TOML: grid of operating points, controller settings;
    /// see docs/envelope.md).
    #[arg(long, value_name = "ENVELOPE.toml")]
    pub schedule: PathBuf,
    /// Output folder (created).
    #[arg(long, default_value = "gains")]
    pub out: PathBuf,
    /// Skip the frozen-point check (and the frozen column of the map).
    #[arg(long)]
    pub no_check: bool,
}

/// Run `helicon design`.
pub fn run(args: &DesignArgs) -> Result<()> {
    let cfg = EnvelopeConfig::from_file(&args.schedule)?;
    let model = cfg.model()?;
    let n = cfg.axes().len();
    eprintln!(
        "designing {n} points over forward {:?}, lateral {:?}, down {:?} m/s",
        cfg.grid.forward_m_s, cfg.grid.lateral_m_s, cfg.grid.down_m_s
    );
    let schedule = design_schedule(&model, &cfg, &mut |_, _| {})
        .with_context(|| format!("{}: designing the schedule", args.schedule.display()))?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("{}: cannot create", args.out.display()))?;
    let file = args.out.join("schedule.json");
    schedule.save(&file)?;
    println!("wrote {} ({n} design points)", file.display());
    let flagged = schedule.unphysical.iter().filter(|u| u.is_some()).count();
    if flagged > 0 {
        println!(
            "note: {flagged} design points are outside the model's validity (accept_unphysical; \
             see the `unphysical` column of envelope.csv)"
        );
    }
    let check = if args.no_check {
        None
    } else {
        let gs = schedule.gain_schedule(&file.display().to_string())?;
        let c = frozen_point_check(
            &model,
            &gs,
            cfg.check.subdivisions,
            cfg.grid.accept_unphysical,
            &mut |_, _| {},
        )
        .context("frozen-point check")?;
        write_frozen_csv(&args.out.join("frozen_check.csv"), &c)?;
        Some(c)
    };
    let map = envelope_rows(&schedule, check.as_ref());
    write_text(&args.out.join("envelope.csv"), &map)?;
    envelope_figure(&schedule, check.as_ref(), &args.out.join("envelope.png"))?;
    if let Some(c) = &check {
        let w = &c.worst;
        println!(
            "frozen-point check: {} points, worst spectral radius {:.6} at forward {} lateral {} down {} m/s",
            c.points.len(),
            w.spectral_radius,
            w.operating_point_m_s[0],
            w.operating_point_m_s[1],
            w.operating_point_m_s[2]
        );
        if !c.stable() {
            bail!(
                "frozen-point check: the closed loop is unstable at forward {} lateral {} down {} m/s \
                 (spectral radius {}): refine the grid there",
                w.operating_point_m_s[0],
                w.operating_point_m_s[1],
                w.operating_point_m_s[2],
                w.spectral_radius
            );
        }
    }
    Ok(())
}

fn write_text(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).with_context(|| format!("{}: cannot write", path.display()))
}

fn write_frozen_csv(path: &Path, c: &FrozenCheck) -> Result<()> {
    let mut s = String::from("forward_m_s,lateral_m_s,down_m_s,design_point,spectral_radius\n");
    for p in &c.points {
        let [f, l, d] = p.operating_point_m_s;
        let _ = writeln!(s, "{f},{l},{d},{},{}", p.design_point, p.spectral_radius);
    }
    write_text(path, &s)
}

/// The frozen spectral radius at a design point, when checked.
fn frozen_at(check: Option<&FrozenCheck>, point: [f64; 3]) -> Option<f64> {
    check?
        .points
        .iter()
        .find(|p| p.design_point && p.operating_point_m_s == point)
        .map(|p| p.spectral_radius)
}

fn envelope_rows(schedule: &Schedule, check: Option<&FrozenCheck>) -> String {
    let mut s = String::from(
        "forward_m_s,lateral_m_s,down_m_s,S_col,S_lat,S_lon,S_tr,phi_rad,theta_rad,\
         design_spectral_radius,estimator_spectral_radius,frozen_spectral_radius,unphysical\n",
    );
    for (i, g) in schedule.points.iter().enumerate() {
        let [f, l, d] = schedule.operating_point(i);
        let u = &g.set.u_trim;
        let est = g
            .estimator_poles
            .iter()
            .map(|z| z[0].hypot(z[1]))
            .fold(0.0, f64::max);
        let frozen = frozen_at(check, [f, l, d]).map_or(String::new(), |r| r.to_string());
        let why = schedule.unphysical[i].as_deref().unwrap_or("");
        let _ = writeln!(
            s,
            "{f},{l},{d},{},{},{},{},{},{},{},{est},{frozen},\"{why}\"",
            u[0],
            u[1],
            u[2],
            u[3],
            g.set.x_trim[0],
            g.set.x_trim[1],
            g.spectral_radius()
        );
    }
    s
}

/// The points of one line of a figure panel.
type Points = Vec<(f64, f64)>;

/// The envelope map: trim inputs, attitudes and spectral radii versus
/// forward speed, one line per (lateral, down) pair of the grid.
fn envelope_figure(schedule: &Schedule, check: Option<&FrozenCheck>, path: &Path) -> Result<()> {
    let axes = &schedule.axes;
    let mut lines: Vec<(String, [Points; 8])> = Vec::new();
    for j in 0..axes.lateral_m_s.len() {
        for k in 0..axes.down_m_s.len() {
            let mut cols: [Points; 8] = Default::default();
            for i in 0..axes.forward_m_s.len() {
                let g = &schedule.points[axes.index(i, j, k)];
                let f = axes.forward_m_s[i];
                for c in 0..4 {
                    cols[c].push((f, g.set.u_trim[c]));
                }
                cols[4].push((f, g.set.x_trim[0].to_degrees()));
                cols[5].push((f, g.set.x_trim[1].to_degrees()));
                cols[6].push((f, g.spectral_radius()));
                let op = [f, axes.lateral_m_s[j], axes.down_m_s[k]];
                if let Some(r) = frozen_at(check, op) {
                    cols[7].push((f, r));
                }
            }
            lines.push((
                format!("v {} / d {} m/s", axes.lateral_m_s[j], axes.down_m_s[k]),
                cols,
            ));
        }
    }
    let labels = [
        "S_col trim [-]",
        "S_lat trim [-]",
        "S_lon trim [-]",
        "S_tr trim [-]",
        "φ trim [deg]",
        "θ trim [deg]",
        "|z| max, design [-]",
        "|z| max, frozen [-]",
    ];
    let mut fig = Figure::new(
        &format!(
            "Envelope map `{}`: trims and stability versus forward speed",
            schedule.name
        ),
        "forward speed [m/s]",
    );
    for (c, label) in labels.iter().enumerate() {
        if c == 7 && check.is_none() {
            continue;
        }
        let mut p = Panel::new(label);
        for (name, cols) in &lines {
            p = p.series(Series::new(name, &cols[c]));
        }
        if c >= 6 {
            p.y_include.push(1.0);
        }
        fig = fig.panel(p);
    }
    fig.panel_height_px = 170;
    fig.write(path)
        .with_context(|| format!("{}: cannot write the envelope map", path.display()))?;
    Ok(())
}
