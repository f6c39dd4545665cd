//! `helicon ident demo`: the identification programme end to end on a
//! simulated helicopter whose true parameters are known. The shipped
//! identification flights (`scenarios/ident/hover.toml`, `fwd5.toml`,
//! `fwd10.toml`: sweeps on each servo in turn under the LQI, sensor noise,
//! light turbulence) and the doublet verification flight
//! (`hover-doublets.toml`) are flown with the true parameters, the
//! controller designed on the nominal Bergen Twin (as a team would design
//! it before knowing the truth); the IDENT.toml is written and the fit run
//! from the nominal Bergen Twin.

use crate::config::{IdentConfig, Spectra};
use crate::error::{ParamIdError, Result};
use crate::report::{Identification, run};
use helicon_model::{ConfigError, Params};
use helicon_sim::closed_loop::{Outcome, fly, prepare_with_params};
use helicon_sim::log_csv::write_log;
use helicon_sim::scenario::Scenario;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::Path;

/// The identification flights: (name, forward speed m/s, scenario text).
pub const FLIGHTS: [(&str, f64, &str); 3] = [
    (
        "hover",
        0.0,
        include_str!("../../../scenarios/ident/hover.toml"),
    ),
    (
        "fwd5",
        5.0,
        include_str!("../../../scenarios/ident/fwd5.toml"),
    ),
    (
        "fwd10",
        10.0,
        include_str!("../../../scenarios/ident/fwd10.toml"),
    ),
];

/// The verification flight (doublets in hover).
pub const VERIFY_FLIGHT: &str = include_str!("../../../scenarios/ident/hover-doublets.toml");

/// The shipped true helicopters (name, parameter file text).
pub const TRUTHS: [(&str, &str); 3] = [
    (
        "truth-a",
        include_str!("../../../params/truths/truth-a.toml"),
    ),
    (
        "truth-b",
        include_str!("../../../params/truths/truth-b.toml"),
    ),
    (
        "truth-c",
        include_str!("../../../params/truths/truth-c.toml"),
    ),
];

/// The parameters measured on the ground before the flights (thesis §11.1:
/// mass and inertias by weighing and pendulum tests): the demo takes them
/// from the truth into the start parameters. The cyclic responses cannot
/// tell them apart from the rotor's: scaling the lift-curve slope, the blade
/// inertia, the hinge spring and the body inertias together leaves the
/// flapping (Lock number, Ks/Ib) and the body's angular acceleration
/// unchanged (a fit that tried showed them all 60 % high together, each
/// within a 15 % Cramér–Rao bound but correlated to 0.99). Likewise the
/// flight data determine only the stabilizer bar's Lock-number-like ratio
/// of paddle lift slope to paddle inertia (ρ = 1.000 between the two): the
/// paddle inertia is weighed and measured on the ground.
pub const GROUND_MEASURED: [&str; 5] = [
    "body.mass_kg",
    "stabilizer_bar.paddle_inertia_kg_m2",
    "body.ixx_kg_m2",
    "body.iyy_kg_m2",
    "body.izz_kg_m2",
];

/// The parameters the demo identifies, with bounds 0.5–2 × the nominal
/// value: the rotor, stabilizer-bar and tail-rotor parameters the shipped
/// truths change, and the four servo bandwidths.
pub const DEMO_PARAMETERS: [&str; 10] = [
    "main_rotor.lift_slope_per_rad",
    "main_rotor.drag_coefficient",
    "main_rotor.blade_inertia_kg_m2",
    "main_rotor.spring_n_m_per_rad",
    "stabilizer_bar.lift_slope_per_rad",
    "tail_rotor.lift_slope_per_rad",
    "servo.collective.omega_n_rad_s",
    "servo.lateral.omega_n_rad_s",
    "servo.longitudinal.omega_n_rad_s",
    "servo.tail.omega_n_rad_s",
];

/// The parameters that the ground experiments measure more precisely than
/// the flights determine them: with the ground programme on, the demo keeps
/// them at their ground values instead of identifying them again. The tail
/// rotor's lift slope is measured on the ground to 1–2 % (one standard
/// error); identified again from the yaw responses it came out 7–10 % off
/// (3.6–4.0 Cramér–Rao bounds) on four of nine runs (truths a, b, c at
/// seeds 1, 3, 7), the sign changing with the seed, and pulled the tail
/// servo's bandwidth with it; with its ground value as a prior still up to
/// 5.2 % (4.2 bounds) (docs/paramid.md).
pub const GROUND_KEPT: [&str; 1] = ["tail_rotor.lift_slope_per_rad"];

/// The responses the demo fits at every operating point (input, output
/// column), each over 1.5–25 rad/s: the cyclic ones on axis and
/// cross-coupled, the yaw rate to the tail servo and the heave velocity to
/// the collective. The yaw rate to the collective (the main rotor's torque)
/// is left out: at the truth it keeps the highest cost per point of all
/// (0.74 at hover, the others 0.1–0.6) and fitting it pulled truth b's
/// paddle lift slope from −6.7 % to −19 % (docs/paramid.md). A response
/// with fewer than `min_points` coherent points at an operating point is
/// left out there and listed (the heave response at 5 and 10 m/s, where the
/// turbulence swamps it). The heave output is the body velocity `w` of the simulator's log: the
/// log's `meas_w` is the navigation filter's GPS/IMU blend, whose own
/// dynamics the model's C does not have (docs/paramid.md). Without the
/// instruments only the four cyclic responses are fitted: the conditioned
/// yaw and heave responses are biased by the feedback (a fit with them
/// ended at cost ratio 0.44 with the tail servo's bandwidth 29 % off).
pub const DEMO_RESPONSES: [(&str, &str); 6] = [
    ("S_lat", "meas_p"),
    ("S_lat", "meas_q"),
    ("S_lon", "meas_p"),
    ("S_lon", "meas_q"),
    ("S_tr", "meas_r"),
    ("S_col", "w"),
];

/// Demo settings.
#[derive(Debug, Clone)]
pub struct DemoOptions {
    /// The flights to fly and fit (names of [`FLIGHTS`]; default hover, fwd5 and fwd10).
    pub flights: Vec<String>,
    /// Turbulence and sensor-noise seed (default: the scenarios').
    pub seed: Option<u64>,
    /// Fly the doublet verification flight and verify on it.
    pub verify: bool,
    /// Frequency points per response.
    pub points: usize,
    /// Parameters identified (default [`DEMO_PARAMETERS`]).
    pub parameters: Vec<String>,
    /// Estimate the responses with the logged excitations as instruments
    /// (default) instead of conditioning on the servos.
    pub instruments: bool,
    /// Simulate the ground experiments (§11.1) on the truth and start from
    /// their measured values ([`crate::ground_sim`]; default true).
    pub ground: bool,
    /// With instruments: one flat window per sweep (default) or the
    /// overlapped Hann windows.
    pub spectra: Spectra,
}

impl Default for DemoOptions {
    fn default() -> Self {
        DemoOptions {
            // fwd10 tightens every Cramér–Rao bound (docs/paramid.md) for
            // ~2 s more (three flights in parallel on two cores, fit 2 s)
            flights: vec!["hover".into(), "fwd5".into(), "fwd10".into()],
            seed: None,
            verify: true,
            points: 40,
            parameters: DEMO_PARAMETERS.iter().map(|s| s.to_string()).collect(),
            instruments: true,
            ground: true,
            spectra: Spectra::Sweeps,
        }
    }
}

/// Fly one scenario text with the true parameters (controller designed
/// on the nominal model) and write its `log.csv` to `log`.
pub fn fly_scenario(
    name: &str,
    text: &str,
    truth: &Params,
    seed: Option<u64>,
    log: &Path,
) -> Result<()> {
    let file = format!("scenarios/ident/{name}.toml");
    let mut s = Scenario::from_toml_str(text, &file)?;
    if let Some(seed) = seed {
        s.wind.seed = seed;
        s.sensors.seed = seed;
    }
    let err = |e: helicon_sim::closed_loop::ClosedLoopError| ParamIdError::Model {
        point: name.to_string(),
        reason: e.to_string(),
    };
    let nominal = prepare_with_params(&s, Params::bergen_twin()).map_err(err)?;
    let mut p = prepare_with_params(&s, *truth).map_err(err)?;
    p.gains = nominal.gains;
    let f = fly(&s, &p, None).map_err(err)?;
    if f.summary.outcome != Outcome::Completed {
        return Err(ParamIdError::Model {
            point: name.to_string(),
            reason: format!(
                "the identification flight did not complete: {}",
                f.summary.reason.unwrap_or_default()
            ),
        });
    }
    if let Some(dir) = log.parent() {
        std::fs::create_dir_all(dir).map_err(|source| ConfigError::Io {
            file: dir.display().to_string(),
            action: "create",
            source,
        })?;
    }
    write_log(log, &f.log, 1).map_err(crate::error::LogError::from)?;
    Ok(())
}

/// The demo's IDENT.toml (logs under `flights/<name>/log.csv`).
pub fn ident_toml(opts: &DemoOptions) -> String {
    ident_toml_with_ground(opts, &[])
}

/// [`ident_toml`] with the ground experiments' values: each identified
/// parameter the ground measured gets its value and standard error as a
/// prior (`prior`, `prior_std`), so that the fit weighs the ground and the
/// flight by their errors.
pub fn ident_toml_with_ground(opts: &DemoOptions, ground: &[crate::report::GroundValue]) -> String {
    let mut s = String::from(
        "# Written by `helicon ident demo`: the identification of a simulated helicopter\n\
         # from its identification flights (docs/paramid.md).\n\
         # start.toml: the Bergen Twin with the ground-measured mass and inertias (body, paddles)
\
         start = \"start.toml\"\n\
         cost = \"thesis\"\noptimiser = \"lm\"\nauto_fix = true\nmin_coherence = 0.6\n",
    );
    match (opts.instruments, opts.spectra) {
        // one flat window per sweep: no Hann-window bias (docs/paramid.md,
        // "How good are the Cramér–Rao bounds"); the 12 s overlapped
        // windows give the equation error's spectrum for the random error
        (true, Spectra::Sweeps) => s.push_str(
            "# one flat window around each sweep (the flights rest 4 s between sweeps); the\n\
             # random error from the equation error in 12 s overlapped windows (docs/paramid.md)\n\
             spectra = \"sweeps\"\nsweep_pad_s = 2.0\nsweep_taper_s = 2.0\nwindows_s = [12.0]\n",
        ),
        // each 27 s sweep spans several 12 s windows; in 24 s ones the tail
        // sweep's last 6 s fell in none
        (true, Spectra::Welch) => s.push_str(
            "# 12 and 6 s overlapped windows: each 27 s sweep spans several (docs/paramid.md)\n\
             windows_s = [12.0, 6.0]\n",
        ),
        (false, _) => {}
    }
    let _ = writeln!(s, "points = {}", opts.points);
    for (name, v, _) in FLIGHTS
        .iter()
        .filter(|f| opts.flights.iter().any(|n| n == f.0))
    {
        let _ = write!(
            s,
            "\n[[operating_point]]\nname = \"{name}\"\nvelocity_ned_m_s = [{v:?}, 0.0, 0.0]\nlog = \"flights/{name}/log.csv\"\n{}",
            if opts.instruments {
                "instruments = [\"exc_col\", \"exc_lat\", \"exc_lon\", \"exc_tr\"]\n"
            } else {
                ""
            }
        );
    }
    // conditioned (no instruments) the yaw and heave responses are biased by
    // the feedback far beyond the cyclic ones: the cyclic responses only
    let cyclic = |input: &str| input == "S_lat" || input == "S_lon";
    for (input, output) in DEMO_RESPONSES
        .iter()
        .filter(|r| opts.instruments || cyclic(r.0))
    {
        let _ = write!(
            s,
            "\n[[response]]\ninput = \"{input}\"\noutput = \"{output}\"\nomega_min_rad_s = 1.5\nomega_max_rad_s = 25.0\n"
        );
    }
    let nominal = Params::bergen_twin();
    for key in &opts.parameters {
        if opts.ground && GROUND_KEPT.contains(&key.as_str()) {
            let _ = write!(
                s,
                "\n# {key}: kept at its ground-measured value in start.toml\n"
            );
            continue;
        }
        let v = crate::keys::find(key).map_or(1.0, |d| crate::keys::get(&nominal, d));
        let _ = write!(
            s,
            "\n[[parameter]]\nkey = \"{key}\"\nmin = {:?}\nmax = {:?}\n",
            0.5 * v,
            2.0 * v
        );
        if let Some(g) = ground.iter().find(|g| &g.key == key) {
            let _ = write!(
                s,
                "prior = {:?}       # {}\nprior_std = {:?}\n",
                g.value, g.file, g.std_error
            );
        }
    }
    if opts.verify && opts.flights.iter().any(|f| f == "hover") {
        for (t0, t1) in [(1.0, 4.0), (4.5, 7.5), (8.0, 11.0), (11.0, 14.0)] {
            let _ = write!(
                s,
                "\n[[verification]]\noperating_point = \"hover\"\nlog = \"flights/hover-doublets/log.csv\"\noutputs = [\"meas_p\", \"meas_q\", \"meas_r\"]\nt_start_s = {t0:?}\nt_end_s = {t1:?}\n"
            );
        }
    }
    s
}

/// Fly the flights with `truth`, write `out/IDENT.toml` and identify.
pub fn run_demo(truth: &Params, out: &Path, opts: &DemoOptions) -> Result<Identification> {
    for f in &opts.flights {
        if !FLIGHTS.iter().any(|g| g.0 == f) {
            return Err(ParamIdError::Fit(format!(
                "unknown demo flight `{f}` (hover, fwd5, fwd10)"
            )));
        }
    }
    let mut jobs: Vec<(&str, &str)> = FLIGHTS
        .iter()
        .filter(|f| opts.flights.iter().any(|n| n == f.0))
        .map(|f| (f.0, f.2))
        .collect();
    if opts.verify {
        jobs.push(("hover-doublets", VERIFY_FLIGHT));
    }
    jobs.par_iter()
        .map(|(name, text)| {
            fly_scenario(
                name,
                text,
                truth,
                opts.seed,
                &out.join("flights").join(name).join("log.csv"),
            )
        })
        .collect::<Result<Vec<()>>>()?;
    // the ground experiments (§11.1) on the true helicopter: their measured
    // values, not the truth's, go into the start parameters
    let mut start = Params::bergen_twin();
    for key in GROUND_MEASURED {
        if let Some(d) = crate::keys::find(key) {
            crate::keys::set(&mut start, d, crate::keys::get(truth, d));
        }
    }
    let before_ground = start;
    let ground = if opts.ground {
        // the flights' seed: the one given, else the scenarios' own
        let seed = match opts.seed {
            Some(s) => s,
            None => {
                Scenario::from_toml_str(FLIGHTS[0].2, "scenarios/ident/hover.toml")?
                    .wind
                    .seed
            }
        };
        crate::ground_sim::measure_on_ground(truth, &start, &out.join("ground"), seed)?
    } else {
        Vec::new()
    };
    for g in &ground {
        if let Some(d) = crate::keys::find(&g.key) {
            crate::keys::set(&mut start, d, g.value);
        }
    }
    let path = out.join("start.toml");
    let header = start_header(&ground);
    std::fs::write(&path, header + &start.to_toml()).map_err(|source| ConfigError::Io {
        file: path.display().to_string(),
        action: "write",
        source,
    })?;
    let path = out.join("IDENT.toml");
    std::fs::write(&path, ident_toml_with_ground(opts, &ground)).map_err(|source| {
        ConfigError::Io {
            file: path.display().to_string(),
            action: "write",
            source,
        }
    })?;
    let cfg = IdentConfig::from_file(&path)?;
    let mut id = run(&cfg)?;
    id.ground = ground;
    let before = (!id.ground.is_empty()).then_some(&before_ground);
    id.truth_model_cost = Some(id.truth_model_cost(truth, before)?);
    Ok(id)
}

/// The comment heading `start.toml`: where its values come from.
fn start_header(ground: &[crate::report::GroundValue]) -> String {
    let mut s = String::from(
        "# Start parameters of `helicon ident demo`: the Bergen Twin with the mass and the\n\
         # body and paddle inertias weighed and pendulum-measured (taken from the truth)\n",
    );
    if ground.is_empty() {
        s.push_str("# and no ground experiments (--no-ground).\n");
    } else {
        s.push_str("# and the values the simulated ground experiments (thesis 11.1) measured:\n");
    }
    for g in ground {
        let _ = writeln!(
            s,
            "# {} = {} +- {:.3e} (1 sigma): helicon ident ground {} {}",
            g.key, g.value, g.std_error, g.kind, g.file
        );
    }
    s
}
