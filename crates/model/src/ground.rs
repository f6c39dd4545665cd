//! The ground experiments of thesis §11.1 as calculators: repeated readings
//! of a bench test in, a model parameter and its standard error out.
//!
//! Each calculator inverts the model's own formula for the quantity measured
//! at the test's condition (helicopter at rest, no wind, μ = 0, p = q = r =
//! 0), with the geometry from [`Params`] (rotor radii, chords, blade counts,
//! hinge offset, rotor speeds, air density), and fits the parameter to all
//! readings by least squares. The error is carried by the variable named in
//! [`Kind::error_variable`] (the other one is set and taken as exact); the
//! standard error is the least-squares one, σ̂² (gᵀg)⁻¹ with σ̂² the residual
//! variance, or through the derivative of the parameter's formula (delta
//! method) where the parameter is a function of the fitted slope.
//!
//! | kind | readings | model relation |
//! |---|---|---|
//! | `rotor-drag` | `omega_rad_s, torque_n_m` | (7.25) at zero pitch and thrust: τ = Cd·b ρ c Ω² (R⁴ − e⁴)/8 |
//! | `main-lift-slope` | `pitch_rad, thrust_n` | (7.9) at rest with momentum inflow (7.29): T = Cls·b ρ c Ω²/2·[θ0 (R³ − e³)/3 + θt (R⁴ − e⁴)/(4R) + λ R (R² − e²)/2], λ = −sgn(T)√(|T|/(2ρπR²(ΩR)²)) |
//! | `tail-lift-slope` | `pitch_rad, thrust_n` | (7.47) the same with e = 0, no twist, Ωtr = GΩ |
//! | `blade-spring` | `force_n, flap_rad` | restraint (6.31), rotor stopped: F (R − e) = Ks (β − β₀) |
//! | `bell-gain` | `swashplate_rad, blade_pitch_rad` | (4.2): blade cyclic pitch = Kb · swashplate tilt + offset |
//! | `hiller-gain` | `flybar_rad, blade_pitch_rad` | (4.2): blade cyclic pitch = Kh · stabilizer-bar flap + offset |
//! | `tail-fin-loss` | `thrust_no_fin_n, thrust_with_fin_n` | fin drag (7.61) in the tail-rotor wake: T − F = dtf Atf Ktf² T/(4π Rtr²) |
//! | `stabilizer-lift-slope` | `pitch_rad, thrust_n` | the paddles' lift element of (6.52) summed over both paddles (Ri … Ro, no twist, bar locked level, main blades off) with momentum inflow over the annulus they sweep: T = Cls,sb·ρ csb Ω²·[θ (Ro³ − Ri³)/3 + λ Ro (Ro² − Ri²)/2], λ = −sgn(T)√(\|T\|/(2ρπ(Ro² − Ri²)(ΩRo)²)) |

use crate::config_error::ConfigError;
use crate::params::Params;
use serde::Serialize;

/// A ground experiment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Kind {
    /// Blade drag coefficient Cd from the main-rotor torque at zero pitch, (7.25).
    RotorDrag,
    /// Main-rotor lift-curve slope Cls from thrust versus collective pitch, (7.9).
    MainLiftSlope,
    /// Tail-rotor lift-curve slope Cls,tr from thrust versus pitch, (7.47).
    TailLiftSlope,
    /// Flapping hinge spring Ks from a static deflection test.
    BladeSpring,
    /// Bell mixing gain Kb from blade pitch versus swashplate tilt.
    BellGain,
    /// Hiller mixing gain Kh from blade pitch versus stabilizer-bar flapping.
    HillerGain,
    /// Tail-fin loss factor Ktf from the tail thrust with and without the fin.
    TailFinLoss,
    /// Stabilizer-bar paddle lift-curve slope Cls,sb from the bar's thrust
    /// versus paddle pitch on a whirl stand, (6.52): the one paddle
    /// parameter flight data cannot separate from the paddle inertia.
    StabilizerLiftSlope,
}

/// Every kind, in the order of the docs.
pub const KINDS: [Kind; 8] = [
    Kind::RotorDrag,
    Kind::MainLiftSlope,
    Kind::TailLiftSlope,
    Kind::BladeSpring,
    Kind::BellGain,
    Kind::HillerGain,
    Kind::TailFinLoss,
    Kind::StabilizerLiftSlope,
];

impl Kind {
    /// The kind's name on the command line (`rotor-drag`, …).
    pub fn name(self) -> &'static str {
        match self {
            Kind::RotorDrag => "rotor-drag",
            Kind::MainLiftSlope => "main-lift-slope",
            Kind::TailLiftSlope => "tail-lift-slope",
            Kind::BladeSpring => "blade-spring",
            Kind::BellGain => "bell-gain",
            Kind::HillerGain => "hiller-gain",
            Kind::TailFinLoss => "tail-fin-loss",
            Kind::StabilizerLiftSlope => "stabilizer-lift-slope",
        }
    }

    /// The kind named `name`.
    pub fn from_name(name: &str) -> Option<Kind> {
        KINDS.iter().copied().find(|k| k.name() == name)
    }

    /// The two columns of the readings CSV: the variable set, then the one
    /// read (which carries the error, except for `tail-fin-loss`, where the
    /// error is in the second one too).
    pub fn columns(self) -> [&'static str; 2] {
        match self {
            Kind::RotorDrag => ["omega_rad_s", "torque_n_m"],
            Kind::MainLiftSlope | Kind::TailLiftSlope | Kind::StabilizerLiftSlope => {
                ["pitch_rad", "thrust_n"]
            }
            Kind::BladeSpring => ["force_n", "flap_rad"],
            Kind::BellGain => ["swashplate_rad", "blade_pitch_rad"],
            Kind::HillerGain => ["flybar_rad", "blade_pitch_rad"],
            Kind::TailFinLoss => ["thrust_no_fin_n", "thrust_with_fin_n"],
        }
    }

    /// The variable that carries the measurement error in the regression.
    pub fn error_variable(self) -> &'static str {
        match self {
            Kind::TailFinLoss => "thrust_with_fin_n (the loss T − F)",
            k => k.columns()[1],
        }
    }

    /// The parameter key (`helicon params`) the result sets.
    pub fn key(self) -> &'static str {
        match self {
            Kind::RotorDrag => "main_rotor.drag_coefficient",
            Kind::MainLiftSlope => "main_rotor.lift_slope_per_rad",
            Kind::TailLiftSlope => "tail_rotor.lift_slope_per_rad",
            Kind::BladeSpring => "main_rotor.spring_n_m_per_rad",
            Kind::BellGain => "main_rotor.bell_factor",
            Kind::HillerGain => "main_rotor.hiller_factor",
            Kind::TailFinLoss => "tail_rotor.fin_area_ratio",
            Kind::StabilizerLiftSlope => "stabilizer_bar.lift_slope_per_rad",
        }
    }

    /// The parameter's SI unit ("1" for dimensionless).
    pub fn unit(self) -> &'static str {
        match self {
            Kind::MainLiftSlope | Kind::TailLiftSlope | Kind::StabilizerLiftSlope => "1/rad",
            Kind::BladeSpring => "N*m/rad",
            _ => "1",
        }
    }

    /// A template readings CSV: the header, a comment and example rows
    /// (readings a Bergen Twin would give, rounded as a bench reads them).
    pub fn template(self) -> String {
        let [a, b] = self.columns();
        let (what, rows): (&str, &[(f64, f64)]) = match self {
            Kind::RotorDrag => (
                "main-rotor torque at zero blade pitch (torque = Newton-meter force x its arm), at several rotor speeds",
                &[(90.0, 1.68), (100.0, 2.06), (110.0, 2.49)],
            ),
            Kind::MainLiftSlope => (
                "collective blade pitch and rotor thrust (positive up: weight on the scale at rest minus the reading, times g)",
                &[(-0.05, -37.5), (-0.1, -98.5), (-0.15, -169.5)],
            ),
            Kind::TailLiftSlope => (
                "tail-rotor blade pitch and tail thrust (the rise of the Newton-meter force over the zero-pitch reading, fin removed)",
                &[(0.05, 2.32), (0.1, 6.69), (0.15, 12.07)],
            ),
            Kind::BladeSpring => (
                "force pulling the blade tip up (rotor stopped) and the flapping angle it gives",
                &[(0.0, -0.0101), (2.0, -0.0007), (4.0, 0.0085)],
            ),
            Kind::BellGain => (
                "swashplate cyclic tilt (stabilizer bar held level) and the blade's cyclic pitch",
                &[(-0.1, -0.0201), (0.0, 0.0001), (0.1, 0.0199)],
            ),
            Kind::HillerGain => (
                "stabilizer-bar flapping angle (swashplate level) and the blade's cyclic pitch, same sense",
                &[(-0.1, -0.0799), (0.0, 0.0002), (0.1, 0.0801)],
            ),
            Kind::TailFinLoss => (
                "tail thrust at the same pitch without and with the tail fin",
                &[(4.0, 3.9944), (8.0, 7.9891), (12.0, 11.9834)],
            ),
            Kind::StabilizerLiftSlope => (
                "stabilizer bar alone on the rotor head (main blades off) at the rotor speed of the parameters, bar locked level, both paddles at the same pitch: paddle pitch and the bar's thrust (positive in the direction a positive pitch pushes)",
                &STABILIZER_TEMPLATE,
            ),
        };
        let mut s = format!("# {}: {what}\n{a},{b}\n", self.name());
        for (x, y) in rows {
            s.push_str(&format!("{x},{y}\n"));
        }
        s
    }
}

/// The stabilizer-bar template's readings: what the Bergen Twin's bar gives
/// at 0.05, 0.1, 0.15 rad (Cls,sb = 2.6/rad), rounded to 0.01 N.
const STABILIZER_TEMPLATE: [(f64, f64); 3] = [(0.05, 3.67), (0.1, 9.28), (0.15, 15.47)];

/// One reading: its line in the file and its two values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reading {
    /// Line in the file (1-based).
    pub line: u64,
    /// The set variable (first column).
    pub x: f64,
    /// The read variable (second column).
    pub y: f64,
}

/// The readings of one experiment, with the file they came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Readings {
    /// The file, for messages.
    pub file: String,
    /// The experiment.
    pub kind: Kind,
    /// The readings in file order.
    pub rows: Vec<Reading>,
}

/// The 1-based line of the record the reader places at a byte offset of a
/// text (its offset is where it started looking, before the blank lines it
/// skipped). The records come in file order, so the newlines are counted
/// from the previous record on: linear in the file, not quadratic.
#[cfg(feature = "readings-csv")]
struct LineCounter<'a> {
    bytes: &'a [u8],
    /// Where the count stopped, and the newlines before it.
    pos: usize,
    newlines: u64,
}

#[cfg(feature = "readings-csv")]
impl<'a> LineCounter<'a> {
    fn new(text: &'a str) -> Self {
        LineCounter {
            bytes: text.as_bytes(),
            pos: 0,
            newlines: 0,
        }
    }

    fn line_at(&mut self, at: u64) -> u64 {
        let bytes = self.bytes;
        let mut at = usize::try_from(at).map_or(bytes.len(), |b| b.min(bytes.len()));
        if at < self.pos {
            // not in file order (never, from the csv reader): count afresh
            self.pos = 0;
            self.newlines = 0;
        }
        self.newlines += bytes[self.pos..at].iter().filter(|b| **b == b'\n').count() as u64;
        self.pos = at;
        let mut line = self.newlines + 1;
        while at < bytes.len() && (bytes[at] == b'\n' || bytes[at] == b'\r') {
            line += u64::from(bytes[at] == b'\n');
            at += 1;
        }
        line
    }
}

fn parse_err(file: &str, message: String) -> ConfigError {
    ConfigError::Parse {
        file: file.to_string(),
        message,
    }
}

impl Readings {
    /// Parse a readings CSV: a header naming the kind's two columns (any
    /// order, other columns ignored), `#` comment lines, one reading per
    /// row. Every value must be a finite number; errors name the file, the
    /// line and the column.
    #[cfg(feature = "readings-csv")]
    pub fn parse_csv(text: &str, file: &str, kind: Kind) -> Result<Readings, ConfigError> {
        // `#` comment lines are blanked rather than left to the reader, and
        // the line is counted from the record's byte offset ([`LineCounter`]):
        // the reader's own line count skips comment and blank lines.
        let blanked: String = text
            .lines()
            .map(|l| {
                if l.trim_start().starts_with('#') {
                    ""
                } else {
                    l
                }
            })
            .collect::<Vec<_>>()
            .join("\n");
        let mut rdr = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .from_reader(blanked.as_bytes());
        let header = rdr
            .headers()
            .map_err(|e| parse_err(file, format!("no header row: {e}")))?
            .clone();
        if header.iter().all(str::is_empty) {
            return Err(parse_err(
                file,
                format!(
                    "empty: no header row (a {} file has columns {})",
                    kind.name(),
                    kind.columns().join(", ")
                ),
            ));
        }
        let mut idx = [0usize; 2];
        for (slot, name) in idx.iter_mut().zip(kind.columns()) {
            let found: Vec<usize> = header
                .iter()
                .enumerate()
                .filter(|(_, h)| *h == name)
                .map(|(i, _)| i)
                .collect();
            *slot = match found.as_slice() {
                [i] => *i,
                [] => {
                    return Err(parse_err(
                        file,
                        format!(
                            "no column `{name}` (a {} file has columns {}; found: {})",
                            kind.name(),
                            kind.columns().join(", "),
                            header.iter().collect::<Vec<_>>().join(", ")
                        ),
                    ));
                }
                _ => return Err(parse_err(file, format!("column `{name}` appears twice"))),
            };
        }
        let mut rows = Vec::new();
        let mut lines = LineCounter::new(&blanked);
        for rec in rdr.records() {
            let rec = rec.map_err(|e| parse_err(file, format!("malformed CSV: {e}")))?;
            let line = rec.position().map_or(0, |p| lines.line_at(p.byte()));
            let mut v = [0.0; 2];
            for (c, &i) in idx.iter().enumerate() {
                let name = kind.columns()[c];
                let text = rec.get(i).unwrap_or("");
                v[c] = text
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| {
                        parse_err(
                            file,
                            format!(
                                "line {line}, column `{name}`: `{text}` is not a finite number"
                            ),
                        )
                    })?;
            }
            rows.push(Reading {
                line,
                x: v[0],
                y: v[1],
            });
        }
        Ok(Readings {
            file: file.to_string(),
            kind,
            rows,
        })
    }

    fn invalid(&self, r: &Reading, column: usize, value: f64, rule: String) -> ConfigError {
        ConfigError::invalid(
            &format!("{}: line {}", self.file, r.line),
            self.kind.columns()[column],
            value,
            rule,
        )
    }
}

/// The result of a ground experiment.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GroundResult {
    /// The experiment.
    pub kind: Kind,
    /// The parameter key it sets (`helicon params`).
    pub key: &'static str,
    /// The estimate.
    pub value: f64,
    /// Its standard error (one σ).
    pub std_error: f64,
    /// The parameter's unit.
    pub unit: &'static str,
    /// Readings used.
    pub n_readings: usize,
    /// The variable that carries the error in the regression.
    pub error_variable: &'static str,
    /// RMS of the residuals of the read variable (its unit).
    pub residual_rms: f64,
    /// The intercept of a fit with one (blade-spring: β₀; Bell and Hiller:
    /// the gauge's zero offset), with its standard error.
    pub intercept: Option<[f64; 2]>,
    /// The constants of [`Params`] the calculation used, `(key, value)`.
    pub constants: Vec<(&'static str, f64)>,
    /// The readings (x, y) and the fitted relation at the same x, for plots.
    pub points: Vec<[f64; 3]>,
    /// The fitted relation at 50 points across the readings' range of x.
    pub curve: Vec<[f64; 2]>,
}

/// Straight-line least squares y = a·x (+ b): slope, its standard error,
/// the intercept with its standard error, and the residual RMS.
struct Line {
    slope: f64,
    slope_se: f64,
    intercept: Option<[f64; 2]>,
    rms: f64,
}

fn fit_line(xs: &[f64], ys: &[f64], with_intercept: bool) -> Option<Line> {
    let n = xs.len() as f64;
    let p = if with_intercept { 2.0 } else { 1.0 };
    if n <= p {
        return None;
    }
    let (mx, my) = if with_intercept {
        (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n)
    } else {
        (0.0, 0.0)
    };
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    let sxy: f64 = xs.iter().zip(ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    if sxx.is_nan() || sxx <= 0.0 {
        return None;
    }
    let slope = sxy / sxx;
    let b = my - slope * mx;
    let rss: f64 = xs
        .iter()
        .zip(ys)
        .map(|(x, y)| (y - slope * x - b).powi(2))
        .sum();
    let s2 = rss / (n - p);
    let intercept = with_intercept.then(|| [b, (s2 * (1.0 / n + mx * mx / sxx)).sqrt()]);
    Some(Line {
        slope,
        slope_se: (s2 / sxx).sqrt(),
        intercept,
        rms: (rss / n).sqrt(),
    })
}

/// A rotor's constants for the thrust relation.
#[derive(Debug, Clone, Copy)]
struct Rotor {
    blades: f64,
    chord_m: f64,
    radius_m: f64,
    hinge_m: f64,
    omega_rad_s: f64,
    twist_rad: f64,
    rho: f64,
    /// The area of the momentum inflow (m²): the disc πR² of a rotor, the
    /// annulus π(Ro² − Ri²) the paddles sweep.
    wake_area_m2: f64,
    /// The parameter keys of the constants, for the result.
    keys: [&'static str; 6],
}

impl Rotor {
    fn main(p: &Params) -> Rotor {
        let m = &p.main_rotor;
        Rotor {
            blades: m.blades,
            chord_m: m.chord_m,
            radius_m: m.radius_m,
            hinge_m: m.hinge_offset_m,
            omega_rad_s: m.omega_rad_s,
            twist_rad: m.twist_rad,
            rho: p.environment.rho_kg_m3,
            wake_area_m2: std::f64::consts::PI * m.radius_m * m.radius_m,
            keys: [
                "main_rotor.blades",
                "main_rotor.chord_m",
                "main_rotor.radius_m",
                "main_rotor.hinge_offset_m",
                "main_rotor.omega_rad_s",
                "main_rotor.twist_rad",
            ],
        }
    }

    fn tail(p: &Params) -> Rotor {
        let t = &p.tail_rotor;
        Rotor {
            blades: t.blades,
            chord_m: t.chord_m,
            radius_m: t.radius_m,
            hinge_m: 0.0,
            omega_rad_s: p.omega_tr_rad_s(),
            twist_rad: 0.0,
            rho: p.environment.rho_kg_m3,
            wake_area_m2: std::f64::consts::PI * t.radius_m * t.radius_m,
            keys: [
                "tail_rotor.blades",
                "tail_rotor.chord_m",
                "tail_rotor.radius_m",
                "hinge offset (none on the tail rotor), m",
                "tail-rotor speed G*main_rotor.omega_rad_s, rad/s",
                "twist (none on the tail rotor), rad",
            ],
        }
    }

    /// The stabilizer bar's two paddles as a rotor: radius Ro, lifting from
    /// Ri (the role of the hinge offset in the thrust integral), no twist,
    /// turning with the main rotor; the inflow through their annulus.
    fn stabilizer(p: &Params) -> Rotor {
        let sb = &p.stabilizer_bar;
        let (ro, ri) = (sb.outer_radius_m, sb.inner_radius_m);
        Rotor {
            blades: 2.0,
            chord_m: sb.chord_m,
            radius_m: ro,
            hinge_m: ri,
            omega_rad_s: p.main_rotor.omega_rad_s,
            twist_rad: 0.0,
            rho: p.environment.rho_kg_m3,
            wake_area_m2: std::f64::consts::PI * (ro * ro - ri * ri),
            keys: [
                "paddles (two), count",
                "stabilizer_bar.chord_m",
                "stabilizer_bar.outer_radius_m",
                "stabilizer_bar.inner_radius_m",
                "main_rotor.omega_rad_s",
                "twist (none on the paddles), rad",
            ],
        }
    }

    /// Thrust per unit lift slope at pitch θ and inflow ratio λ: (A, B) with
    /// T/Cls = A + B λ.
    fn per_slope(&self, pitch_rad: f64) -> (f64, f64) {
        let (r, e) = (self.radius_m, self.hinge_m);
        let k = 0.5 * self.blades * self.rho * self.chord_m * self.omega_rad_s.powi(2);
        let a = k
            * (pitch_rad * (r.powi(3) - e.powi(3)) / 3.0
                + self.twist_rad * (r.powi(4) - e.powi(4)) / (4.0 * r));
        let b = k * r * (r * r - e * e) / 2.0;
        (a, b)
    }

    /// √(2ρA(ΩR)²), A the wake area (πR² for a rotor): λ = −sgn(T) √|T| /
    /// this (momentum theory at rest, (7.29)).
    fn momentum(&self) -> f64 {
        let r = self.radius_m;
        (2.0 * self.rho * self.wake_area_m2 * (self.omega_rad_s * r).powi(2)).sqrt()
    }

    /// The thrust at pitch θ with lift slope `cls` and converged momentum
    /// inflow: the root of T = Cls (A + B λ(T)) (sign of A).
    fn thrust(&self, pitch_rad: f64, cls: f64) -> f64 {
        let (a, b) = self.per_slope(pitch_rad);
        let beta = cls * b / self.momentum();
        let s = 0.5 * (-beta + (beta * beta + 4.0 * cls * a.abs()).sqrt());
        a.signum() * s * s
    }

    /// The constants used, for the result.
    fn constants(&self) -> Vec<(&'static str, f64)> {
        let keys = self.keys;
        let values = [
            self.blades,
            self.chord_m,
            self.radius_m,
            self.hinge_m,
            self.omega_rad_s,
            self.twist_rad,
        ];
        let mut v: Vec<(&'static str, f64)> = keys.into_iter().zip(values).collect();
        v.push(("environment.rho_kg_m3", self.rho));
        v
    }
}

/// Run the calculator of `readings.kind` with the geometry of `params`.
/// Errors (each naming the file, and the line and column of the reading at
/// fault): too few readings, a reading the physics forbids (a negative
/// rotor speed or torque, a thrust against the pitch, a non-positive thrust
/// for the fin test), no spread in the set variable, a fit that gives no
/// physical value.
pub fn calculate(readings: &Readings, params: &Params) -> Result<GroundResult, ConfigError> {
    let kind = readings.kind;
    let need = match kind {
        Kind::BladeSpring | Kind::BellGain | Kind::HillerGain => 3,
        _ => 2,
    };
    if readings.rows.len() < need {
        return Err(parse_err(
            &readings.file,
            format!(
                "{} reading(s): a {} fit needs at least {need} for a standard error",
                readings.rows.len(),
                kind.name()
            ),
        ));
    }
    check_physics(readings)?;
    match kind {
        Kind::RotorDrag => rotor_drag(readings, params),
        Kind::MainLiftSlope => lift_slope(readings, Rotor::main(params)),
        Kind::TailLiftSlope => lift_slope(readings, Rotor::tail(params)),
        Kind::StabilizerLiftSlope => lift_slope(readings, Rotor::stabilizer(params)),
        Kind::BladeSpring => blade_spring(readings, params),
        Kind::BellGain | Kind::HillerGain => mixing_gain(readings),
        Kind::TailFinLoss => fin_loss(readings, params),
    }
}

/// The largest blade or paddle pitch a lift-slope reading may have, rad
/// (45°): the lift is linear in the pitch only well below stall (about 12°
/// to 15°), and a pitch of a few radians is a reading in degrees.
pub const MAX_PITCH_RAD: f64 = std::f64::consts::FRAC_PI_4;

/// The per-reading rules of each kind.
fn check_physics(rd: &Readings) -> Result<(), ConfigError> {
    for r in &rd.rows {
        match rd.kind {
            Kind::RotorDrag => {
                if r.x <= 0.0 {
                    return Err(rd.invalid(r, 0, r.x, "the rotor speed must be > 0".into()));
                }
                if r.y < 0.0 {
                    return Err(rd.invalid(
                        r,
                        1,
                        r.y,
                        "the drag torque is a magnitude (the torque the rotor takes), >= 0".into(),
                    ));
                }
            }
            Kind::MainLiftSlope | Kind::TailLiftSlope | Kind::StabilizerLiftSlope
                if r.x.abs() > MAX_PITCH_RAD =>
            {
                return Err(rd.invalid(
                    r,
                    0,
                    r.x,
                    format!(
                        "a blade pitch beyond ±{MAX_PITCH_RAD:.4} rad (45°) is no lift-slope reading (the blade has stalled long before): is it in degrees?"
                    ),
                ));
            }
            Kind::MainLiftSlope | Kind::TailLiftSlope | Kind::StabilizerLiftSlope
                if r.y != 0.0 && r.x != 0.0 && r.y.signum() != r.x.signum() =>
            {
                return Err(rd.invalid(
                    r,
                    1,
                    r.y,
                    format!(
                        "a blade pitch of {} rad cannot give a thrust of the other sign (thrust is positive in the direction a positive pitch pushes)",
                        r.x
                    ),
                ));
            }
            Kind::TailFinLoss => {
                if r.x <= 0.0 {
                    return Err(rd.invalid(
                        r,
                        0,
                        r.x,
                        "the tail thrust must be > 0 (set a positive tail pitch)".into(),
                    ));
                }
                if r.y < 0.0 {
                    return Err(rd.invalid(
                        r,
                        1,
                        r.y,
                        "the thrust with the fin must be >= 0".into(),
                    ));
                }
            }
            _ => {}
        }
    }
    Ok(())
}

fn no_spread(rd: &Readings) -> ConfigError {
    parse_err(
        &rd.file,
        format!(
            "column `{}`: the readings do not vary (or are all zero): no slope to fit",
            rd.kind.columns()[0]
        ),
    )
}

fn xy(rd: &Readings) -> (Vec<f64>, Vec<f64>) {
    (
        rd.rows.iter().map(|r| r.x).collect(),
        rd.rows.iter().map(|r| r.y).collect(),
    )
}

fn result(
    rd: &Readings,
    value: f64,
    std_error: f64,
    line: &Line,
    constants: Vec<(&'static str, f64)>,
    model_y: impl Fn(f64) -> f64,
) -> Result<GroundResult, ConfigError> {
    if !(value.is_finite() && std_error.is_finite()) {
        return Err(parse_err(
            &rd.file,
            format!("the fit gives a non-finite {}", rd.kind.key()),
        ));
    }
    Ok(GroundResult {
        kind: rd.kind,
        key: rd.kind.key(),
        value,
        std_error,
        unit: rd.kind.unit(),
        n_readings: rd.rows.len(),
        error_variable: rd.kind.error_variable(),
        residual_rms: line.rms,
        intercept: line.intercept,
        constants,
        points: rd.rows.iter().map(|r| [r.x, r.y, model_y(r.x)]).collect(),
        curve: {
            let (lo, hi) = rd
                .rows
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
                    (a.min(r.x), b.max(r.x))
                });
            (0..50)
                .map(|i| {
                    let x = lo + (hi - lo) * f64::from(i) / 49.0;
                    [x, model_y(x)]
                })
                .collect()
        },
    })
}

/// (7.25) at zero pitch and zero thrust (λ = 0, Up = 0): the hub torque is
/// the profile drag alone, τ = Cd · b ρ c Ω² (R⁴ − e⁴)/8. Torque on Ω²·k,
/// through the origin, torque carrying the error.
fn rotor_drag(rd: &Readings, p: &Params) -> Result<GroundResult, ConfigError> {
    let m = &p.main_rotor;
    let rho = p.environment.rho_kg_m3;
    let k = m.blades * rho * m.chord_m * (m.radius_m.powi(4) - m.hinge_offset_m.powi(4)) / 8.0;
    let (w, tau) = xy(rd);
    let x: Vec<f64> = w.iter().map(|w| k * w * w).collect();
    let line = fit_line(&x, &tau, false).ok_or_else(|| no_spread(rd))?;
    if line.slope <= 0.0 {
        return Err(parse_err(
            &rd.file,
            format!(
                "column `torque_n_m`: the fit gives Cd = {} (must be > 0)",
                line.slope
            ),
        ));
    }
    let constants = vec![
        ("main_rotor.blades", m.blades),
        ("main_rotor.chord_m", m.chord_m),
        ("main_rotor.radius_m", m.radius_m),
        ("main_rotor.hinge_offset_m", m.hinge_offset_m),
        ("environment.rho_kg_m3", rho),
    ];
    let cd = line.slope;
    result(rd, cd, line.slope_se, &line, constants, |w| cd * k * w * w)
}

/// (7.9)/(7.47), or the paddles' lift of (6.52), with momentum inflow:
/// one-parameter nonlinear least squares on the thrust (Gauss–Newton on the
/// closed-form root), thrust carrying the error.
fn lift_slope(rd: &Readings, rotor: Rotor) -> Result<GroundResult, ConfigError> {
    let (pitch, thrust) = xy(rd);
    // start: no inflow, T = Cls·A
    let a: Vec<f64> = pitch.iter().map(|t| rotor.per_slope(*t).0).collect();
    let start = fit_line(&a, &thrust, false).ok_or_else(|| no_spread(rd))?;
    if start.slope <= 0.0 {
        return Err(parse_err(
            &rd.file,
            "column `thrust_n`: the thrust does not grow with the pitch (lift slope <= 0)".into(),
        ));
    }
    let mut cls = start.slope;
    let grad = |c: f64| -> Vec<f64> {
        let h = 1e-7 * c;
        pitch
            .iter()
            .map(|t| (rotor.thrust(*t, c + h) - rotor.thrust(*t, c - h)) / (2.0 * h))
            .collect()
    };
    for _ in 0..50 {
        let g = grad(cls);
        let r: Vec<f64> = pitch
            .iter()
            .zip(&thrust)
            .map(|(t, y)| y - rotor.thrust(*t, cls))
            .collect();
        let gg: f64 = g.iter().map(|v| v * v).sum();
        let step = g.iter().zip(&r).map(|(a, b)| a * b).sum::<f64>() / gg;
        if !step.is_finite() {
            return Err(no_spread(rd));
        }
        cls = (cls + step).max(0.5 * cls);
        if step.abs() <= 1e-14 * cls {
            break;
        }
    }
    let g = grad(cls);
    let gg: f64 = g.iter().map(|v| v * v).sum();
    let rss: f64 = pitch
        .iter()
        .zip(&thrust)
        .map(|(t, y)| (y - rotor.thrust(*t, cls)).powi(2))
        .sum();
    let n = pitch.len() as f64;
    let line = Line {
        slope: cls,
        slope_se: (rss / (n - 1.0) / gg).sqrt(),
        intercept: None,
        rms: (rss / n).sqrt(),
    };
    result(rd, cls, line.slope_se, &line, rotor.constants(), |t| {
        rotor.thrust(t, cls)
    })
}

/// The restraint (6.31) with the rotor stopped: a force F pulling the tip up
/// (arm R − e from the hinge) holds the blade where Ks (β − β₀) = F (R − e),
/// β₀ the rest angle under the blade's weight. β on F with an intercept (β
/// carrying the error): slope c = (R − e)/Ks, Ks = (R − e)/c, se by the
/// delta method.
fn blade_spring(rd: &Readings, p: &Params) -> Result<GroundResult, ConfigError> {
    let arm = p.main_rotor.radius_m - p.main_rotor.hinge_offset_m;
    let (f, beta) = xy(rd);
    let line = fit_line(&f, &beta, true).ok_or_else(|| no_spread(rd))?;
    if line.slope <= 0.0 {
        return Err(parse_err(
            &rd.file,
            format!(
                "column `flap_rad`: the flapping angle does not rise with the force (slope {} rad/N)",
                line.slope
            ),
        ));
    }
    let ks = arm / line.slope;
    let se = ks * line.slope_se / line.slope;
    let constants = vec![
        ("main_rotor.radius_m", p.main_rotor.radius_m),
        ("main_rotor.hinge_offset_m", p.main_rotor.hinge_offset_m),
    ];
    let (c, b0) = (line.slope, line.intercept.map_or(0.0, |v| v[0]));
    result(rd, ks, se, &line, constants, |x| b0 + c * x)
}

/// Blade cyclic pitch on swashplate tilt (Bell) or stabilizer-bar flapping
/// (Hiller), with an intercept (the gauge's zero), pitch carrying the error.
fn mixing_gain(rd: &Readings) -> Result<GroundResult, ConfigError> {
    let (x, y) = xy(rd);
    let line = fit_line(&x, &y, true).ok_or_else(|| no_spread(rd))?;
    if line.slope <= 0.0 {
        return Err(parse_err(
            &rd.file,
            format!(
                "column `blade_pitch_rad`: gain {} <= 0: count both angles positive in the same sense (see docs/ground-and-servo.md)",
                line.slope
            ),
        ));
    }
    let (c, b0) = (line.slope, line.intercept.map_or(0.0, |v| v[0]));
    result(rd, c, line.slope_se, &line, Vec::new(), |x| b0 + c * x)
}

/// The fin sits in the tail-rotor wake: at rest the fin sees Ktf·vi,tr and
/// its drag (7.61) takes (ρ/2) dtf Atf Ktf² vi,tr² from the thrust, with
/// vi,tr² = T/(2ρπRtr²) (momentum): loss T − F = k T, k = dtf Atf Ktf²/(4π
/// Rtr²). Loss on T through the origin, Ktf = √(4π Rtr² k/(dtf Atf)), se by
/// the delta method.
fn fin_loss(rd: &Readings, p: &Params) -> Result<GroundResult, ConfigError> {
    let f = &p.fuselage;
    let r = p.tail_rotor.radius_m;
    let area = f.drag_tf * f.area_tf_m2;
    if area.is_nan() || area <= 0.0 {
        return Err(ConfigError::invalid(
            &rd.file,
            "fuselage.drag_tf * fuselage.area_tf_m2",
            area,
            "must be > 0: the parameters give the fin no drag, so no loss factor can explain a loss",
        ));
    }
    let (t, fw) = xy(rd);
    let loss: Vec<f64> = t.iter().zip(&fw).map(|(a, b)| a - b).collect();
    let line = fit_line(&t, &loss, false).ok_or_else(|| no_spread(rd))?;
    if line.slope <= 0.0 {
        return Err(parse_err(
            &rd.file,
            format!(
                "column `thrust_with_fin_n`: no loss measured (loss/thrust = {}); Ktf = 0 if the fin is out of the wake",
                line.slope
            ),
        ));
    }
    let c = 4.0 * std::f64::consts::PI * r * r / area;
    let ktf = (c * line.slope).sqrt();
    let se = ktf * line.slope_se / (2.0 * line.slope);
    let constants = vec![
        ("tail_rotor.radius_m", r),
        ("fuselage.drag_tf", f.drag_tf),
        ("fuselage.area_tf_m2", f.area_tf_m2),
    ];
    let k = line.slope;
    result(rd, ktf, se, &line, constants, |x| x - k * x)
}
