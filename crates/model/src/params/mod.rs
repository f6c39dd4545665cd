//! Model parameters: every constant of the thesis Nomenclature (pp. XIII–XV)
//! plus the main-rotor speed Ω, loaded from TOML and validated.
//!
//! The Bergen Industrial Twin ships as `params/bergen_twin.toml` and is
//! embedded in the library ([`Params::bergen_twin`]). A user's file may
//! override any subset of its keys ([`Params::from_toml_str`] applies a file on
//! top of the embedded set). Every key is described once, in `DESCRIPTORS`:
//! its TOML section and name, its unit, its thesis symbol and the rule it must
//! obey; loading, validation and printing all walk that table.
//!
//! Ω = 100 rad/s is **not printed in the thesis**; it is inferred from
//! Appendix E (see `reference/NOTES.md`). The tail-rotor speed is
//! derived, Ωtr = G·Ω ([`Params::omega_tr_rad_s`]).

mod descriptors;

use descriptors::find;
pub use descriptors::{
    Descriptor, Field, MAGNITUDES, Magnitude, Rule, descriptor_count, descriptors, magnitude,
};
use std::fmt::Write as _;
use std::path::Path;

/// ``; did you mean `section.key`?`` for the parameter key nearest to an
/// unknown `key` (dotted, as the error names it), or nothing.
fn did_you_mean(key: &str) -> String {
    let names: Vec<String> = descriptors::descriptors()
        .map(|d| {
            if d.section.is_empty() {
                d.key.to_string()
            } else {
                format!("{}.{}", d.section, d.key)
            }
        })
        .collect();
    helicon_config::nearest(key, names.iter().map(String::as_str))
        .map_or_else(String::new, |n| format!("; did you mean `{n}`?"))
}

/// The shipped Bergen Industrial Twin parameter file.
pub const BERGEN_TWIN_TOML: &str = include_str!("../../../../params/bergen_twin.toml");

/// Errors from loading or validating parameters. Each names the file (or
/// `<embedded>` / `<string>`), the 1-based line of the offending key when the
/// error comes from a file's text (`file:LINE:`), the key as `section.key`,
/// and the rule broken.
#[derive(Debug, thiserror::Error)]
pub enum ParamError {
    /// The file could not be read.
    #[error("{file}: cannot read")]
    Io {
        /// File name.
        file: String,
        /// Underlying error.
        source: std::io::Error,
    },
    /// The file is not valid TOML (the parser's message carries line and column).
    #[error("{file}: not valid TOML: {message}")]
    Syntax {
        /// File name.
        file: String,
        /// Parser message.
        message: String,
    },
    /// A key that is not a model parameter.
    #[error("{}: unknown key `{key}`{} (run `helicon params` for the list of keys)", At(file, *line), did_you_mean(key))]
    UnknownKey {
        /// File name.
        file: String,
        /// 1-based line of the key in the file, when known.
        line: Option<usize>,
        /// The offending key.
        key: String,
    },
    /// A value of the wrong type.
    #[error("{}: key `{key}` must be a number, found {found}", At(file, *line))]
    WrongType {
        /// File name.
        file: String,
        /// 1-based line of the key in the file, when known.
        line: Option<usize>,
        /// The offending key.
        key: String,
        /// TOML type found.
        found: String,
    },
    /// A value that breaks its rule.
    #[error("{}: key `{key}` = {value:?} is invalid: {rule}", At(file, *line))]
    Invalid {
        /// File name.
        file: String,
        /// 1-based line of the key in the file, when known (`None` for
        /// values that were not read from a file, e.g. validated in memory,
        /// or a key missing from a complete file).
        line: Option<usize>,
        /// The offending key.
        key: String,
        /// The value given.
        value: f64,
        /// The rule broken.
        rule: String,
    },
}

/// `file` or `file:LINE` in error messages.
struct At<'a>(&'a str, Option<usize>);

impl std::fmt::Display for At<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.1 {
            Some(line) => write!(f, "{}:{line}", self.0),
            None => write!(f, "{}", self.0),
        }
    }
}

impl ParamError {
    /// The 1-based line of the offending key, when known.
    pub fn line(&self) -> Option<usize> {
        match self {
            ParamError::UnknownKey { line, .. }
            | ParamError::WrongType { line, .. }
            | ParamError::Invalid { line, .. } => *line,
            ParamError::Io { .. } | ParamError::Syntax { .. } => None,
        }
    }

    /// Fill in the line of the offending key from the file's `text` (for a
    /// cross-key rule whose key is not in the file, the line of its partner
    /// key, e.g. `s_max` for "`s_min` must be < `s_max`").
    fn located(mut self, text: &str) -> ParamError {
        if let ParamError::UnknownKey { key, line, .. }
        | ParamError::WrongType { key, line, .. }
        | ParamError::Invalid { key, line, .. } = &mut self
        {
            if line.is_none() {
                *line = key_line(text, key).or_else(|| {
                    CROSS_KEY_PARTNERS.iter().find_map(|(a, b)| {
                        key.strip_suffix(a)
                            .and_then(|section| key_line(text, &format!("{section}{b}")))
                    })
                });
            }
        }
        self
    }
}

/// Keys of the cross-key rules and the key they are compared with.
const CROSS_KEY_PARTNERS: [(&str, &str); 5] = [
    ("s_min", "s_max"),
    ("hinge_offset_m", "radius_m"),
    ("inner_radius_m", "outer_radius_m"),
    ("friction_dynamic", "friction_static"),
    ("contact_x_rear_m", "contact_x_front_m"),
];

/// The 1-based line where the dotted `key` (e.g. `servo.tail.s_min`) is
/// written in the TOML `text`, from the parser's spans.
fn key_line(text: &str, key: &str) -> Option<usize> {
    let doc = toml::de::DeTable::parse(text).ok()?;
    let mut table = doc.get_ref();
    let mut parts = key.split('.').peekable();
    while let Some(part) = parts.next() {
        let (k, v) = table.get_key_value(part)?;
        if parts.peek().is_none() {
            let start = k.span().start;
            return Some(1 + text.get(..start)?.matches('\n').count());
        }
        match v.get_ref() {
            toml::de::DeValue::Table(t) => table = t,
            _ => return None,
        }
    }
    None
}

/// Air and gravity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Environment {
    /// ρ, air density (kg/m³).
    pub rho_kg_m3: f64,
    /// g, gravitational acceleration (m/s²).
    pub g_m_s2: f64,
}

/// Rigid-body mass properties (principal axes = body axes, thesis (9.22)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Body {
    /// M, mass (kg).
    pub mass_kg: f64,
    /// I(1,1), roll inertia (kg·m²).
    pub ixx_kg_m2: f64,
    /// I(2,2), pitch inertia (kg·m²).
    pub iyy_kg_m2: f64,
    /// I(3,3), yaw inertia (kg·m²).
    pub izz_kg_m2: f64,
}

/// Distances from the centre of mass (κ of the thesis). Horizontal distances
/// are positive **aft** of the CM except `kappa_h_fp_m`, positive forward;
/// vertical distances are positive **above** the CM (MODEL.md §2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry {
    /// κh, main-rotor hub, horizontal (m, aft).
    pub kappa_h_m: f64,
    /// κv, main-rotor hub, vertical (m, above).
    pub kappa_v_m: f64,
    /// κh,fp, front plane, horizontal (m, forward).
    pub kappa_h_fp_m: f64,
    /// κh,tf, tail fin, horizontal (m, aft).
    pub kappa_h_tf_m: f64,
    /// κh,tp, tail plane, horizontal (m, aft).
    pub kappa_h_tp_m: f64,
    /// κh,tr, tail-rotor hub, horizontal (m, aft).
    pub kappa_h_tr_m: f64,
    /// κv,tf, tail fin, vertical (m, above).
    pub kappa_v_tf_m: f64,
    /// κv,tr, tail-rotor hub, vertical (m, above).
    pub kappa_v_tr_m: f64,
}

/// Main rotor (chapters 6–7).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MainRotor {
    /// b, number of blades.
    pub blades: f64,
    /// R, radius (m).
    pub radius_m: f64,
    /// c, blade chord (m).
    pub chord_m: f64,
    /// e, flapping-hinge offset (m).
    pub hinge_offset_m: f64,
    /// Cls, lift-curve slope (1/rad).
    pub lift_slope_per_rad: f64,
    /// Cd, blade profile drag coefficient.
    pub drag_coefficient: f64,
    /// Ib, blade flap inertia about the hinge (kg·m²).
    pub blade_inertia_kg_m2: f64,
    /// mb, first mass moment of a blade about the hinge (kg·m).
    pub blade_mass_moment_kg_m: f64,
    /// Ks, hinge spring (N·m/rad; printed "N/m").
    pub spring_n_m_per_rad: f64,
    /// K1, flap-pitch coupling.
    pub pitch_flap_coupling: f64,
    /// θt, blade twist (rad).
    pub twist_rad: f64,
    /// Kb, Bell mixing gain.
    pub bell_factor: f64,
    /// Kh, Hiller mixing gain.
    pub hiller_factor: f64,
    /// Ω, rotor speed (rad/s), inferred (not printed in the thesis).
    pub omega_rad_s: f64,
}

/// Stabilizer (Bell-Hiller) bar (§6.11).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StabilizerBar {
    /// Ri, hub to the inner paddle edge (m).
    pub inner_radius_m: f64,
    /// Ro, hub to the outer paddle edge (m).
    pub outer_radius_m: f64,
    /// csb, paddle chord (m).
    pub chord_m: f64,
    /// Cls,sb, paddle lift-curve slope (1/rad).
    pub lift_slope_per_rad: f64,
    /// Ib,sb, paddle flap inertia about the hub (kg·m²).
    pub paddle_inertia_kg_m2: f64,
}

/// Tail rotor (§7.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TailRotor {
    /// btr, number of blades.
    pub blades: f64,
    /// Rtr, radius (m).
    pub radius_m: f64,
    /// ctr, blade chord (m).
    pub chord_m: f64,
    /// Cls,tr, lift-curve slope (1/rad).
    pub lift_slope_per_rad: f64,
    /// Cd,tr, blade profile drag coefficient.
    pub drag_coefficient: f64,
    /// G, gear ratio Ωtr/Ω.
    pub gear_ratio: f64,
    /// Ktf, part of the tail fin in the tail-rotor wake.
    pub fin_area_ratio: f64,
}

/// Fuselage and surfaces drag (§7.4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fuselage {
    /// Ax (m²).
    pub area_x_m2: f64,
    /// Ay (m²).
    pub area_y_m2: f64,
    /// Az (m²).
    pub area_z_m2: f64,
    /// Afp, front plane (m²).
    pub area_fp_m2: f64,
    /// Atf, tail fin (m²).
    pub area_tf_m2: f64,
    /// Atp, tail plane (m²).
    pub area_tp_m2: f64,
    /// dx.
    pub drag_x: f64,
    /// dy.
    pub drag_y: f64,
    /// dz.
    pub drag_z: f64,
    /// dfp.
    pub drag_fp: f64,
    /// dtf.
    pub drag_tf: f64,
    /// dtp.
    pub drag_tp: f64,
}

/// One servo channel (5.1)–(5.4), (D.16)–(D.23).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Servo {
    /// K, DC gain (rad per unit command).
    pub gain_rad: f64,
    /// ωn, natural frequency (rad/s; printed "rad").
    pub omega_n_rad_s: f64,
    /// ζ, damping ratio.
    pub zeta: f64,
    /// θ̇max, rate limit (rad/s).
    pub rate_max_rad_s: f64,
    /// S_min, lower command saturation.
    pub s_min: f64,
    /// S_max, upper command saturation.
    pub s_max: f64,
}

/// Controller constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Control {
    /// Ts, sampling time (s), (14.5).
    pub sample_time_s: f64,
}

/// The optional yaw-rate gyro between the tail input and the tail servo
/// (thesis §3.1.1: the stock helicopter's heading-hold gyro), see
/// [`crate::gyro`]. Disabled by default: the tail input is then the tail
/// servo command, as in the thesis's model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct YawGyro {
    /// 1 when the block is on, 0 when off (TOML `true`/`false` or 1/0).
    pub enabled: f64,
    /// Proportional gain Kp (tail-servo command per rad/s of yaw-rate error,
    /// i.e. s/rad). Its sign is the gyro's direction (the "reverse" switch of
    /// a stock gyro): it must make a positive error drive the yaw rate up.
    pub kp_s: f64,
    /// Heading-hold integral gain Ki (tail-servo command per rad of
    /// accumulated yaw-angle error), same sign as `kp_s`.
    pub ki: f64,
    /// Yaw-rate command at the ends of the tail input range (rad/s): the
    /// input's mid-range is 0 rad/s, `s_max` is +`max_rate_rad_s`.
    pub max_rate_rad_s: f64,
}

impl YawGyro {
    /// Whether the block is on.
    pub fn is_enabled(&self) -> bool {
        self.enabled != 0.0
    }
}

/// The optional landing gear (skids as four contact points) and the flat
/// ground it stands on, see [`crate::landing_gear`]. Disabled by default:
/// the thesis's model has no ground.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LandingGear {
    /// 1 when the block is on, 0 when off (TOML `true`/`false` or 1/0).
    pub enabled: f64,
    /// The ground plane's NED down coordinate under the NED origin (m).
    pub ground_down_m: f64,
    /// The ground's slope (rad): the plane rises toward north by this angle.
    pub ground_slope_rad: f64,
    /// Body x of the front skid ends (m, forward of the CM).
    pub contact_x_front_m: f64,
    /// Body x of the rear skid ends (m, forward of the CM; negative aft).
    pub contact_x_rear_m: f64,
    /// Half the skid track (m): the skids are at body y = ±this.
    pub contact_y_half_m: f64,
    /// Body z of the skids (m, below the CM).
    pub contact_z_m: f64,
    /// Normal (and tangential) spring per contact point (N/m).
    pub stiffness_n_m: f64,
    /// Normal (and tangential) damper per contact point (N·s/m).
    pub damping_n_s_m: f64,
    /// μs, static friction coefficient.
    pub friction_static: f64,
    /// μd, dynamic (sliding) friction coefficient.
    pub friction_dynamic: f64,
    /// Sliding speed of the smooth static-to-dynamic transition (m/s).
    pub stribeck_speed_m_s: f64,
}

impl LandingGear {
    /// Whether the block is on.
    pub fn is_enabled(&self) -> bool {
        self.enabled != 0.0
    }
}

/// The optional ground effect on the main rotor's inflow (Cheeseman and
/// Bennett), see [`crate::ground_effect`]. Needs the landing gear's ground
/// plane; disabled by default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundEffect {
    /// 1 when the block is on, 0 when off.
    pub enabled: f64,
    /// The smallest hub height over R the formula is used at (below it the
    /// height is clamped to this): 0.5, where the closed form's validity ends.
    pub min_height_ratio: f64,
}

impl GroundEffect {
    /// Whether the block is on.
    pub fn is_enabled(&self) -> bool {
        self.enabled != 0.0
    }
}

/// The optional drivetrain: rotor speed Ω as a state driven by an engine
/// under a governor, see [`crate::drivetrain`]. Disabled by default: Ω is
/// the constant `main_rotor.omega_rad_s`, as in the thesis (ch. 5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drivetrain {
    /// 1 when the block is on, 0 when off.
    pub enabled: f64,
    /// Rotor, stabilizer bar and transmission inertia about the main shaft
    /// (kg·m²), the tail rotor's referred to it.
    pub inertia_kg_m2: f64,
    /// Engine torque at full throttle, at the main shaft (N·m).
    pub engine_torque_max_n_m: f64,
    /// Transmission friction, viscous (N·m per rad/s, i.e. N·m·s/rad).
    pub friction_n_m_s: f64,
    /// Governor proportional gain (throttle per rad/s of speed error).
    pub governor_kp_s: f64,
    /// Governor integral gain (throttle per rad of accumulated speed error).
    pub governor_ki_per_rad: f64,
    /// Spool-up time (s): the governor's speed reference ramps from 0 to Ω
    /// in this time.
    pub spool_up_s: f64,
    /// Below this rotor speed the blade aerodynamics are evaluated at it and
    /// the rotors' forces scaled by (Ω / this)² (rad/s): the model's
    /// ratios divide by ΩR.
    pub aero_floor_rad_s: f64,
}

impl Drivetrain {
    /// Whether the block is on.
    pub fn is_enabled(&self) -> bool {
        self.enabled != 0.0
    }
}

/// Every model constant. Build with [`Params::bergen_twin`] or
/// [`Params::from_toml_str`] / [`Params::from_file`]; all are validated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Params {
    /// Air and gravity.
    pub environment: Environment,
    /// Mass properties.
    pub body: Body,
    /// CM distances.
    pub geometry: Geometry,
    /// Main rotor.
    pub main_rotor: MainRotor,
    /// Stabilizer bar.
    pub stabilizer_bar: StabilizerBar,
    /// Tail rotor.
    pub tail_rotor: TailRotor,
    /// Fuselage drag.
    pub fuselage: Fuselage,
    /// Servos in input order `[S_col, S_lat, S_lon, S_tr]` →
    /// `[θ0, A1, B1, θtr]`.
    pub servos: [Servo; 4],
    /// Controller constants.
    pub control: Control,
    /// The optional yaw-rate gyro (off by default).
    pub yaw_gyro: YawGyro,
    /// The optional landing gear and ground (off by default).
    pub landing_gear: LandingGear,
    /// The optional ground effect (off by default).
    pub ground_effect: GroundEffect,
    /// The optional drivetrain, rotor speed as a state (off by default).
    pub drivetrain: Drivetrain,
}

const ZERO_SERVO: Servo = Servo {
    gain_rad: 0.0,
    omega_n_rad_s: 0.0,
    zeta: 0.0,
    rate_max_rad_s: 0.0,
    s_min: 0.0,
    s_max: 0.0,
};

impl Params {
    fn zeroed() -> Params {
        Params {
            environment: Environment {
                rho_kg_m3: 0.0,
                g_m_s2: 0.0,
            },
            body: Body {
                mass_kg: 0.0,
                ixx_kg_m2: 0.0,
                iyy_kg_m2: 0.0,
                izz_kg_m2: 0.0,
            },
            geometry: Geometry {
                kappa_h_m: 0.0,
                kappa_v_m: 0.0,
                kappa_h_fp_m: 0.0,
                kappa_h_tf_m: 0.0,
                kappa_h_tp_m: 0.0,
                kappa_h_tr_m: 0.0,
                kappa_v_tf_m: 0.0,
                kappa_v_tr_m: 0.0,
            },
            main_rotor: MainRotor {
                blades: 0.0,
                radius_m: 0.0,
                chord_m: 0.0,
                hinge_offset_m: 0.0,
                lift_slope_per_rad: 0.0,
                drag_coefficient: 0.0,
                blade_inertia_kg_m2: 0.0,
                blade_mass_moment_kg_m: 0.0,
                spring_n_m_per_rad: 0.0,
                pitch_flap_coupling: 0.0,
                twist_rad: 0.0,
                bell_factor: 0.0,
                hiller_factor: 0.0,
                omega_rad_s: 0.0,
            },
            stabilizer_bar: StabilizerBar {
                inner_radius_m: 0.0,
                outer_radius_m: 0.0,
                chord_m: 0.0,
                lift_slope_per_rad: 0.0,
                paddle_inertia_kg_m2: 0.0,
            },
            tail_rotor: TailRotor {
                blades: 0.0,
                radius_m: 0.0,
                chord_m: 0.0,
                lift_slope_per_rad: 0.0,
                drag_coefficient: 0.0,
                gear_ratio: 0.0,
                fin_area_ratio: 0.0,
            },
            fuselage: Fuselage {
                area_x_m2: 0.0,
                area_y_m2: 0.0,
                area_z_m2: 0.0,
                area_fp_m2: 0.0,
                area_tf_m2: 0.0,
                area_tp_m2: 0.0,
                drag_x: 0.0,
                drag_y: 0.0,
                drag_z: 0.0,
                drag_fp: 0.0,
                drag_tf: 0.0,
                drag_tp: 0.0,
            },
            servos: [ZERO_SERVO; 4],
            control: Control { sample_time_s: 0.0 },
            yaw_gyro: YawGyro {
                enabled: 0.0,
                kp_s: 0.0,
                ki: 0.0,
                max_rate_rad_s: 0.0,
            },
            landing_gear: LandingGear {
                enabled: 0.0,
                ground_down_m: 0.0,
                ground_slope_rad: 0.0,
                contact_x_front_m: 0.0,
                contact_x_rear_m: 0.0,
                contact_y_half_m: 0.0,
                contact_z_m: 0.0,
                stiffness_n_m: 0.0,
                damping_n_s_m: 0.0,
                friction_static: 0.0,
                friction_dynamic: 0.0,
                stribeck_speed_m_s: 0.0,
            },
            ground_effect: GroundEffect {
                enabled: 0.0,
                min_height_ratio: 0.0,
            },
            drivetrain: Drivetrain {
                enabled: 0.0,
                inertia_kg_m2: 0.0,
                engine_torque_max_n_m: 0.0,
                friction_n_m_s: 0.0,
                governor_kp_s: 0.0,
                governor_ki_per_rad: 0.0,
                spool_up_s: 0.0,
                aero_floor_rad_s: 0.0,
            },
        }
    }

    /// The Bergen Industrial Twin (thesis Nomenclature), from the embedded
    /// `params/bergen_twin.toml`, parsed once per process (parsing the TOML
    /// costs about as much as a hundred control steps, and every flight's
    /// sensor suite asks for these parameters).
    pub fn bergen_twin() -> Params {
        static PARSED: std::sync::OnceLock<Params> = std::sync::OnceLock::new();
        // The embedded file is complete and valid: `tests::embedded_file_is_complete`
        // parses it in full, so this cannot fail at run time.
        #[allow(clippy::expect_used)]
        *PARSED.get_or_init(|| {
            Self::parse_complete(BERGEN_TWIN_TOML, "<embedded bergen_twin.toml>")
                .expect("embedded bergen_twin.toml is valid")
        })
    }

    /// Parse a complete parameter file: every key must be present.
    fn parse_complete(text: &str, file: &str) -> Result<Params, ParamError> {
        let table: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| ParamError::Syntax {
                file: file.to_string(),
                message: e.to_string(),
            })?;
        if let Some(d) = descriptors().find(|d| {
            !OPTIONAL_SECTIONS.contains(&d.section) && lookup(&table, d.section, d.key).is_none()
        }) {
            return Err(ParamError::Invalid {
                file: file.to_string(),
                line: None,
                key: format!("{}.{}", d.section, d.key),
                value: f64::NAN,
                rule: "missing from a complete parameter file".into(),
            });
        }
        let mut p = Params::zeroed();
        // the optional blocks' sections may be left out: their values are
        // then the embedded file's (the block off)
        let embedded: toml::Table =
            BERGEN_TWIN_TOML
                .parse()
                .map_err(|e: toml::de::Error| ParamError::Syntax {
                    file: "<embedded bergen_twin.toml>".to_string(),
                    message: e.to_string(),
                })?;
        for section in OPTIONAL_SECTIONS {
            if let Some(toml::Value::Table(t)) = embedded.get(section) {
                p.apply_table(t, section, "<embedded bergen_twin.toml>", &mut 0)?;
            }
        }
        p.apply_table(&table, "", file, &mut 0)
            .map_err(|e| e.located(text))?;
        p.validate(file).map_err(|e| e.located(text))?;
        Ok(p)
    }

    /// Parameters from TOML text: the Bergen Twin with the keys of `text`
    /// overriding it (any subset). `file` names the source in errors.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Params, ParamError> {
        let mut p = Params::bergen_twin();
        p.apply_toml(text, file).map_err(|e| e.located(text))?;
        p.validate(file).map_err(|e| e.located(text))?;
        Ok(p)
    }

    /// Parameters from a TOML file overriding the Bergen Twin.
    pub fn from_file(path: &Path) -> Result<Params, ParamError> {
        let file = path.display().to_string();
        let text =
            crate::config_error::read_text_bounded(path, crate::config_error::MAX_TEXT_BYTES)
                .map_err(|e| ParamError::Io {
                    file: file.clone(),
                    source: e.into_io(),
                })?;
        Self::from_toml_str(&text, &file)
    }

    /// Apply the keys in `text` to `self`; returns how many were set.
    fn apply_toml(&mut self, text: &str, file: &str) -> Result<usize, ParamError> {
        let table: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| ParamError::Syntax {
                file: file.to_string(),
                message: e.to_string(),
            })?;
        let mut count = 0;
        self.apply_table(&table, "", file, &mut count)?;
        Ok(count)
    }

    fn apply_table(
        &mut self,
        table: &toml::Table,
        prefix: &str,
        file: &str,
        count: &mut usize,
    ) -> Result<(), ParamError> {
        for (key, value) in table {
            let full = if prefix.is_empty() {
                key.clone()
            } else {
                format!("{prefix}.{key}")
            };
            match value {
                toml::Value::Table(sub) => self.apply_table(sub, &full, file, count)?,
                _ => {
                    let d = find(prefix, key).ok_or_else(|| ParamError::UnknownKey {
                        file: file.to_string(),
                        line: None,
                        key: full.clone(),
                    })?;
                    let v = match value {
                        toml::Value::Boolean(b) if d.rule == Rule::Flag => f64::from(u8::from(*b)),
                        toml::Value::Float(f) => *f,
                        toml::Value::Integer(i) => *i as f64,
                        other => {
                            return Err(ParamError::WrongType {
                                file: file.to_string(),
                                line: None,
                                key: full,
                                found: other.type_str().to_string(),
                            });
                        }
                    };
                    d.check(v).map_err(|rule| ParamError::Invalid {
                        file: file.to_string(),
                        line: None,
                        key: full.clone(),
                        value: v,
                        rule,
                    })?;
                    *(d.field)(self) = v;
                    *count += 1;
                }
            }
        }
        Ok(())
    }

    /// Check every key against its rule and the cross-key rules
    /// (saturation min < max, e < R, Ri < Ro).
    pub fn validate(&self, file: &str) -> Result<(), ParamError> {
        let mut copy = *self;
        for d in descriptors() {
            let v = *(d.field)(&mut copy);
            d.check(v).map_err(|rule| ParamError::Invalid {
                file: file.to_string(),
                line: None,
                key: format!("{}.{}", d.section, d.key),
                value: v,
                rule,
            })?;
        }
        let invalid = |key: &str, value: f64, rule: &str| ParamError::Invalid {
            file: file.to_string(),
            line: None,
            key: key.to_string(),
            value,
            rule: rule.to_string(),
        };
        for (s, name) in self.servos.iter().zip(SERVO_SECTIONS) {
            if s.s_min >= s.s_max {
                return Err(invalid(
                    &format!("{name}.s_min"),
                    s.s_min,
                    "must be < s_max",
                ));
            }
        }
        let mr = &self.main_rotor;
        if mr.hinge_offset_m >= mr.radius_m {
            return Err(invalid(
                "main_rotor.hinge_offset_m",
                mr.hinge_offset_m,
                "must be < main_rotor.radius_m",
            ));
        }
        let sb = &self.stabilizer_bar;
        if sb.inner_radius_m >= sb.outer_radius_m {
            return Err(invalid(
                "stabilizer_bar.inner_radius_m",
                sb.inner_radius_m,
                "must be < stabilizer_bar.outer_radius_m",
            ));
        }
        let lg = &self.landing_gear;
        if lg.ground_slope_rad.abs() >= 1.0 {
            return Err(invalid(
                "landing_gear.ground_slope_rad",
                lg.ground_slope_rad,
                "must be within +-1 rad (57 deg): a steeper ground is a wall",
            ));
        }
        if lg.friction_dynamic > lg.friction_static {
            return Err(invalid(
                "landing_gear.friction_dynamic",
                lg.friction_dynamic,
                "must be <= landing_gear.friction_static",
            ));
        }
        if lg.contact_x_rear_m >= lg.contact_x_front_m {
            return Err(invalid(
                "landing_gear.contact_x_rear_m",
                lg.contact_x_rear_m,
                "must be < landing_gear.contact_x_front_m",
            ));
        }
        if self.ground_effect.min_height_ratio < 0.5 {
            return Err(invalid(
                "ground_effect.min_height_ratio",
                self.ground_effect.min_height_ratio,
                "must be >= 0.5: below z/R = 0.5 the Cheeseman-Bennett formula is outside its validity \
                 (and its factor reaches zero at z/R = 0.25)",
            ));
        }
        if self.ground_effect.is_enabled() && !lg.is_enabled() {
            return Err(invalid(
                "ground_effect.enabled",
                1.0,
                "needs landing_gear.enabled: the ground effect needs the ground plane",
            ));
        }
        Ok(())
    }

    /// The servo range, as the control law saturates to it.
    pub fn servo_limits(&self) -> helicon_core::ServoLimits {
        helicon_core::ServoLimits {
            min: helicon_core::state::Input::from_fn(|i, _| self.servos[i].s_min),
            max: helicon_core::state::Input::from_fn(|i, _| self.servos[i].s_max),
        }
    }

    /// Ωtr = G·Ω, the tail-rotor speed (rad/s).
    pub fn omega_tr_rad_s(&self) -> f64 {
        self.tail_rotor.gear_ratio * self.main_rotor.omega_rad_s
    }

    /// The effective parameter set as a complete TOML file, with units and
    /// thesis symbols in comments: a starting point for a user's helicopter.
    pub fn to_toml(&self) -> String {
        let mut copy = *self;
        let mut out = String::from(
            "# helicon model parameters (SI units). Keys, units and thesis symbols:\n\
             # see `params/bergen_twin.toml`. Ω is inferred (not printed in the thesis).\n",
        );
        let mut section = "";
        let embedded = Params::bergen_twin();
        let mut defaults = embedded;
        for d in descriptors() {
            // an optional block left at the embedded values (off) is not
            // written: the file (and every hash of it) is the one of before
            // the block existed
            if OPTIONAL_SECTIONS.contains(&d.section)
                && descriptors()
                    .filter(|o| o.section == d.section)
                    .all(|o| *(o.field)(&mut copy.clone()) == *(o.field)(&mut defaults))
            {
                continue;
            }
            if d.section != section {
                section = d.section;
                let _ = write!(out, "\n[{section}]\n");
            }
            let v = *(d.field)(&mut copy);
            let value = if d.rule == Rule::Count {
                format!("{v:.0}")
            } else if d.rule == Rule::Flag {
                (v != 0.0).to_string()
            } else {
                format!("{v:?}")
            };
            let _ = writeln!(out, "{} = {}  # {} [{}]", d.key, value, d.symbol, d.unit);
        }
        out
    }
}

/// The sections of the optional blocks beyond the thesis's model (landing
/// gear, ground effect, drivetrain): a complete file may leave them out
/// (their embedded values apply, the blocks off), and [`Params::to_toml`]
/// leaves them out while they hold the embedded values.
pub const OPTIONAL_SECTIONS: [&str; 3] = ["landing_gear", "ground_effect", "drivetrain"];

/// Servo TOML sections in input order.
pub const SERVO_SECTIONS: [&str; 4] = [
    "servo.collective",
    "servo.lateral",
    "servo.longitudinal",
    "servo.tail",
];

fn lookup<'a>(table: &'a toml::Table, section: &str, key: &str) -> Option<&'a toml::Value> {
    let mut t = table;
    for part in section.split('.') {
        t = t.get(part)?.as_table()?;
    }
    t.get(key)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_file_is_complete() {
        let table: toml::Table = BERGEN_TWIN_TOML.parse().unwrap();
        for d in descriptors() {
            assert!(
                lookup(&table, d.section, d.key).is_some(),
                "{}.{} missing",
                d.section,
                d.key
            );
        }
        let p = Params::parse_complete(BERGEN_TWIN_TOML, "x").unwrap();
        assert_eq!(p, Params::bergen_twin());
    }

    #[test]
    fn bergen_twin_matches_reference_values() {
        // shared/reference/thesis_params.toml (Nomenclature) values.
        let p = Params::bergen_twin();
        assert_eq!(p.body.mass_kg, 14.0);
        assert_eq!(p.body.ixx_kg_m2, 0.199);
        assert_eq!(p.main_rotor.omega_rad_s, 100.0);
        assert_eq!(p.omega_tr_rad_s(), 650.0);
        assert_eq!(p.main_rotor.spring_n_m_per_rad, 200.0);
        assert_eq!(p.servos[0].s_max, 0.30);
        assert_eq!(p.servos[3].s_min, -0.37);
        assert_eq!(p.stabilizer_bar.outer_radius_m, 0.65);
        assert_eq!(p.tail_rotor.radius_m, 0.18);
        assert_eq!(descriptor_count(), 103);
    }

    #[test]
    fn override_subset_and_roundtrip() {
        let p = Params::from_toml_str(
            "[body]\nmass_kg = 12\n[servo.tail]\ns_max = 0.5\n",
            "u.toml",
        )
        .unwrap();
        assert_eq!(p.body.mass_kg, 12.0);
        assert_eq!(p.servos[3].s_max, 0.5);
        assert_eq!(p.body.iyy_kg_m2, 0.62);
        let again = Params::parse_complete(&p.to_toml(), "roundtrip").unwrap();
        assert_eq!(again, p);
    }

    #[test]
    fn optional_blocks_at_their_defaults_are_left_out_and_round_trip_when_set() {
        let p = Params::bergen_twin();
        let text = p.to_toml();
        for s in OPTIONAL_SECTIONS {
            assert!(!text.contains(&format!("[{s}]")), "{s}");
        }
        assert_eq!(Params::parse_complete(&text, "t").unwrap(), p);
        let mut q = p;
        q.landing_gear.enabled = 1.0;
        q.drivetrain.spool_up_s = 3.0;
        let text = q.to_toml();
        assert!(text.contains("[landing_gear]") && text.contains("[drivetrain]"));
        assert!(!text.contains("[ground_effect]"));
        assert_eq!(Params::parse_complete(&text, "t").unwrap(), q);
    }

    #[test]
    fn errors_name_file_key_and_rule() {
        let e = Params::from_toml_str("[body]\nmass_kg = -1.0\n", "heli.toml").unwrap_err();
        let s = e.to_string();
        assert!(
            s.contains("heli.toml") && s.contains("body.mass_kg") && s.contains("> 0"),
            "{s}"
        );

        let e = Params::from_toml_str("[body]\nmas_kg = 1.0\n", "heli.toml").unwrap_err();
        assert!(matches!(e, ParamError::UnknownKey { .. }), "{e}");
        assert!(e.to_string().contains("body.mas_kg"));
        assert!(
            e.to_string()
                .contains("unknown key `body.mas_kg`; did you mean `body.mass_kg`?"),
            "{e}"
        );
        let e = Params::from_toml_str(
            "[body]
zzz = 1.0
",
            "heli.toml",
        )
        .unwrap_err();
        assert!(!e.to_string().contains("did you mean"), "{e}");

        let e = Params::from_toml_str("[body]\nmass_kg = \"heavy\"\n", "h.toml").unwrap_err();
        assert!(matches!(e, ParamError::WrongType { .. }), "{e}");

        let e = Params::from_toml_str("[servo.collective]\ns_min = 0.5\n", "h.toml").unwrap_err();
        assert!(e.to_string().contains("servo.collective.s_min"), "{e}");

        let e = Params::from_toml_str("[body]\nmass_kg = nan\n", "h.toml").unwrap_err();
        assert!(e.to_string().contains("finite"), "{e}");

        let e = Params::from_toml_str("[main_rotor]\nradius_m = 0.0\n", "h.toml").unwrap_err();
        assert!(e.to_string().contains("main_rotor.radius_m"), "{e}");

        let e = Params::from_toml_str("[main_rotor]\nblades = 2.5\n", "h.toml").unwrap_err();
        assert!(e.to_string().contains("whole number"), "{e}");

        let e = Params::from_toml_str("[body\n", "h.toml").unwrap_err();
        assert!(matches!(e, ParamError::Syntax { .. }), "{e}");

        let e = Params::from_file(Path::new("/nonexistent/x.toml")).unwrap_err();
        assert!(e.to_string().contains("/nonexistent/x.toml"));
    }
}
