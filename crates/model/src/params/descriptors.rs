//! The parameter table: every key once, with its TOML section and name, its
//! unit, its thesis symbol, the rule it must obey and the magnitude bounds of
//! its unit family. Loading, validation and printing all walk this table.

use super::*;

/// The rule a parameter must obey.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rule {
    /// Finite and > 0.
    Positive,
    /// Finite and ≥ 0.
    NonNegative,
    /// Finite.
    Finite,
    /// A whole number ≥ 1.
    Count,
    /// A switch: 0 (off) or 1 (on); TOML `false`/`true` are accepted.
    Flag,
}

/// The magnitude range of a family of parameters (the parameters with one
/// SI unit): every value must satisfy |v| ≤ `max_abs`, and a value that must
/// be positive ([`Rule::Positive`], the divisors and scales of the model)
/// must be ≥ `min_positive`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Magnitude {
    /// The family, for messages.
    pub family: &'static str,
    /// Smallest value of a positive parameter.
    pub min_positive: f64,
    /// Largest magnitude.
    pub max_abs: f64,
}

/// The parameter families by unit, with their ranges. The ranges are wide
/// enough for anything from a 1 g micro-rotorcraft to 50 times the largest
/// helicopter built (Mi-26: 56 t, R = 16 m), and narrow enough that every
/// product and quotient in the derivative stays finite: at the extremes the
/// largest term (the blade-element flap torque, ∝ b·ρ·c·Cls·(ΩR)²·R⁴ / Ib)
/// stays below ~1e70 and the smallest divisor (M, I, Ib, ΩR) above 1e-9, far
/// from f64's 1.8e308 (test
/// `parameters_at_the_ends_of_their_ranges_keep_the_derivative_finite`
/// evaluates the model with every key at an end of its range). A value
/// beyond them is a unit or typing mistake, not a helicopter.
pub const MAGNITUDES: [(&str, Magnitude); 18] = [
    ("m", mag("length", 1e-4, 1e3)),
    ("m^2", mag("area", 1e-8, 1e6)),
    ("kg", mag("mass", 1e-3, 1e6)),
    ("kg*m^2", mag("inertia", 1e-9, 1e12)),
    ("kg*m", mag("mass moment", 1e-9, 1e9)),
    ("N*m/rad", mag("hinge spring", 1e-9, 1e9)),
    ("rad", mag("angle", 1e-6, std::f64::consts::TAU)),
    ("rad/s", mag("angular rate", 1e-3, 1e5)),
    ("1/rad", mag("lift slope", 1e-6, 1e3)),
    ("1", mag("dimensionless", 1e-9, 1e6)),
    ("kg/m^3", mag("density", 1e-6, 1e4)),
    ("m/s^2", mag("acceleration", 1e-3, 1e3)),
    ("s", mag("time", 1e-6, 1e3)),
    ("N/m", mag("stiffness", 1e-3, 1e9)),
    ("N*s/m", mag("damping", 1e-6, 1e7)),
    ("m/s", mag("speed", 1e-6, 1e3)),
    ("N*m", mag("torque", 1e-6, 1e7)),
    ("N*m*s/rad", mag("rotary damping", 1e-9, 1e6)),
];

const fn mag(family: &'static str, min_positive: f64, max_abs: f64) -> Magnitude {
    Magnitude {
        family,
        min_positive,
        max_abs,
    }
}

/// The magnitude range of the parameters with SI unit `unit`.
pub fn magnitude(unit: &str) -> Option<Magnitude> {
    MAGNITUDES.iter().find(|(u, _)| *u == unit).map(|(_, m)| *m)
}

impl Rule {
    fn check(self, v: f64, magnitude: Option<Magnitude>) -> Result<(), String> {
        if !v.is_finite() {
            return Err("must be finite".into());
        }
        match self {
            Rule::Positive if v <= 0.0 => return Err("must be > 0".into()),
            Rule::NonNegative if v < 0.0 => return Err("must be >= 0".into()),
            Rule::Count if v < 1.0 || v.fract() != 0.0 => {
                return Err("must be a whole number >= 1".into());
            }
            Rule::Flag if v != 0.0 && v != 1.0 => {
                return Err("must be true/false (or 1/0)".into());
            }
            _ => {}
        }
        if let Some(m) = magnitude {
            if v.abs() > m.max_abs {
                return Err(format!(
                    "must be within +-{:e} ({} range; beyond it the model's products overflow)",
                    m.max_abs, m.family
                ));
            }
            if self == Rule::Positive && v < m.min_positive {
                return Err(format!(
                    "must be >= {:e} ({} range; smaller divisors make the model's quotients overflow)",
                    m.min_positive, m.family
                ));
            }
        }
        Ok(())
    }
}

/// Accessor for one field of [`Params`].
pub type Field = fn(&mut Params) -> &mut f64;

/// Description of one parameter key.
#[derive(Clone, Copy)]
pub struct Descriptor {
    /// TOML section (dotted for nested tables, e.g. `servo.tail`).
    pub section: &'static str,
    /// Key inside the section.
    pub key: &'static str,
    /// SI unit ("1" for dimensionless).
    pub unit: &'static str,
    /// Thesis symbol and meaning.
    pub symbol: &'static str,
    /// Validation rule.
    pub rule: Rule,
    /// Accessor.
    pub field: Field,
}

impl Descriptor {
    /// Check `v` against this key's rule and its family's magnitude range
    /// ([`MAGNITUDES`]); the error is the rule broken.
    pub fn check(&self, v: f64) -> Result<(), String> {
        self.rule.check(v, magnitude(self.unit))
    }
}

macro_rules! d {
    ($sec:literal, $key:literal, $unit:literal, $sym:literal, $rule:ident, |$p:ident| $e:expr) => {
        Descriptor {
            section: $sec,
            key: $key,
            unit: $unit,
            symbol: $sym,
            rule: Rule::$rule,
            field: |$p: &mut Params| &mut $e,
        }
    };
}

macro_rules! servo_descriptors {
    ($sec:literal, $i:literal, $k:literal, $wn:literal, $z:literal, $rm:literal, $smin:literal, $smax:literal) => {
        [
            d!($sec, "gain_rad", "rad", $k, Positive, |p| p.servos[$i]
                .gain_rad),
            d!($sec, "omega_n_rad_s", "rad/s", $wn, Positive, |p| p.servos
                [$i]
                .omega_n_rad_s),
            d!($sec, "zeta", "1", $z, Positive, |p| p.servos[$i].zeta),
            d!($sec, "rate_max_rad_s", "rad/s", $rm, Positive, |p| p.servos
                [$i]
                .rate_max_rad_s),
            d!($sec, "s_min", "1", $smin, Finite, |p| p.servos[$i].s_min),
            d!($sec, "s_max", "1", $smax, Finite, |p| p.servos[$i].s_max),
        ]
    };
}

const SERVO_COL: [Descriptor; 6] = servo_descriptors!(
    "servo.collective",
    0,
    "K0",
    "ωn,0",
    "ζ0",
    "θ̇max,0",
    "Scol,min",
    "Scol,max"
);
const SERVO_LAT: [Descriptor; 6] = servo_descriptors!(
    "servo.lateral",
    1,
    "KA",
    "ωn,A",
    "ζA",
    "θ̇max,A",
    "Slat,min",
    "Slat,max"
);
const SERVO_LON: [Descriptor; 6] = servo_descriptors!(
    "servo.longitudinal",
    2,
    "KB",
    "ωn,B",
    "ζB",
    "θ̇max,B",
    "Slon,min",
    "Slon,max"
);
const SERVO_TR: [Descriptor; 6] = servo_descriptors!(
    "servo.tail",
    3,
    "Ktr",
    "ωn,tr",
    "ζtr",
    "θ̇max,tr",
    "Str,min",
    "Str,max"
);

const BASE: [Descriptor; 53] = [
    d!(
        "environment",
        "rho_kg_m3",
        "kg/m^3",
        "ρ air density",
        Positive,
        |p| p.environment.rho_kg_m3
    ),
    d!(
        "environment",
        "g_m_s2",
        "m/s^2",
        "g gravity",
        Positive,
        |p| p.environment.g_m_s2
    ),
    d!("body", "mass_kg", "kg", "M mass", Positive, |p| p
        .body
        .mass_kg),
    d!(
        "body",
        "ixx_kg_m2",
        "kg*m^2",
        "I(1,1) roll inertia",
        Positive,
        |p| p.body.ixx_kg_m2
    ),
    d!(
        "body",
        "iyy_kg_m2",
        "kg*m^2",
        "I(2,2) pitch inertia",
        Positive,
        |p| p.body.iyy_kg_m2
    ),
    d!(
        "body",
        "izz_kg_m2",
        "kg*m^2",
        "I(3,3) yaw inertia",
        Positive,
        |p| p.body.izz_kg_m2
    ),
    d!("geometry", "kappa_h_m", "m", "κh hub, aft", Finite, |p| p
        .geometry
        .kappa_h_m),
    d!(
        "geometry",
        "kappa_v_m",
        "m",
        "κv hub, above",
        Finite,
        |p| p.geometry.kappa_v_m
    ),
    d!(
        "geometry",
        "kappa_h_fp_m",
        "m",
        "κh,fp front plane, forward",
        Finite,
        |p| p.geometry.kappa_h_fp_m
    ),
    d!(
        "geometry",
        "kappa_h_tf_m",
        "m",
        "κh,tf tail fin, aft",
        Finite,
        |p| p.geometry.kappa_h_tf_m
    ),
    d!(
        "geometry",
        "kappa_h_tp_m",
        "m",
        "κh,tp tail plane, aft",
        Finite,
        |p| p.geometry.kappa_h_tp_m
    ),
    d!(
        "geometry",
        "kappa_h_tr_m",
        "m",
        "κh,tr tail-rotor hub, aft",
        Finite,
        |p| p.geometry.kappa_h_tr_m
    ),
    d!(
        "geometry",
        "kappa_v_tf_m",
        "m",
        "κv,tf tail fin, above",
        Finite,
        |p| p.geometry.kappa_v_tf_m
    ),
    d!(
        "geometry",
        "kappa_v_tr_m",
        "m",
        "κv,tr tail-rotor hub, above",
        Finite,
        |p| p.geometry.kappa_v_tr_m
    ),
    d!(
        "main_rotor",
        "blades",
        "1",
        "b number of blades",
        Count,
        |p| p.main_rotor.blades
    ),
    d!("main_rotor", "radius_m", "m", "R radius", Positive, |p| p
        .main_rotor
        .radius_m),
    d!("main_rotor", "chord_m", "m", "c chord", Positive, |p| p
        .main_rotor
        .chord_m),
    d!(
        "main_rotor",
        "hinge_offset_m",
        "m",
        "e hinge offset",
        NonNegative,
        |p| p.main_rotor.hinge_offset_m
    ),
    d!(
        "main_rotor",
        "lift_slope_per_rad",
        "1/rad",
        "Cls lift slope",
        Positive,
        |p| p.main_rotor.lift_slope_per_rad
    ),
    d!(
        "main_rotor",
        "drag_coefficient",
        "1",
        "Cd blade drag",
        NonNegative,
        |p| p.main_rotor.drag_coefficient
    ),
    d!(
        "main_rotor",
        "blade_inertia_kg_m2",
        "kg*m^2",
        "Ib blade inertia",
        Positive,
        |p| p.main_rotor.blade_inertia_kg_m2
    ),
    d!(
        "main_rotor",
        "blade_mass_moment_kg_m",
        "kg*m",
        "mb blade mass moment",
        NonNegative,
        |p| p.main_rotor.blade_mass_moment_kg_m
    ),
    d!(
        "main_rotor",
        "spring_n_m_per_rad",
        "N*m/rad",
        "Ks hinge spring",
        NonNegative,
        |p| p.main_rotor.spring_n_m_per_rad
    ),
    d!(
        "main_rotor",
        "pitch_flap_coupling",
        "1",
        "K1 flap-pitch coupling",
        Finite,
        |p| p.main_rotor.pitch_flap_coupling
    ),
    d!(
        "main_rotor",
        "twist_rad",
        "rad",
        "θt blade twist",
        Finite,
        |p| p.main_rotor.twist_rad
    ),
    d!(
        "main_rotor",
        "bell_factor",
        "1",
        "Kb Bell factor",
        Finite,
        |p| p.main_rotor.bell_factor
    ),
    d!(
        "main_rotor",
        "hiller_factor",
        "1",
        "Kh Hiller factor",
        Finite,
        |p| p.main_rotor.hiller_factor
    ),
    d!(
        "main_rotor",
        "omega_rad_s",
        "rad/s",
        "Ω rotor speed (inferred)",
        Positive,
        |p| p.main_rotor.omega_rad_s
    ),
    d!(
        "stabilizer_bar",
        "inner_radius_m",
        "m",
        "Ri inner radius",
        NonNegative,
        |p| p.stabilizer_bar.inner_radius_m
    ),
    d!(
        "stabilizer_bar",
        "outer_radius_m",
        "m",
        "Ro outer radius",
        Positive,
        |p| p.stabilizer_bar.outer_radius_m
    ),
    d!(
        "stabilizer_bar",
        "chord_m",
        "m",
        "csb paddle chord",
        Positive,
        |p| p.stabilizer_bar.chord_m
    ),
    d!(
        "stabilizer_bar",
        "lift_slope_per_rad",
        "1/rad",
        "Cls,sb lift slope",
        Positive,
        |p| p.stabilizer_bar.lift_slope_per_rad
    ),
    d!(
        "stabilizer_bar",
        "paddle_inertia_kg_m2",
        "kg*m^2",
        "Ib,sb paddle inertia",
        Positive,
        |p| p.stabilizer_bar.paddle_inertia_kg_m2
    ),
    d!(
        "tail_rotor",
        "blades",
        "1",
        "btr number of blades",
        Count,
        |p| p.tail_rotor.blades
    ),
    d!("tail_rotor", "radius_m", "m", "Rtr radius", Positive, |p| p
        .tail_rotor
        .radius_m),
    d!("tail_rotor", "chord_m", "m", "ctr chord", Positive, |p| p
        .tail_rotor
        .chord_m),
    d!(
        "tail_rotor",
        "lift_slope_per_rad",
        "1/rad",
        "Cls,tr lift slope",
        Positive,
        |p| p.tail_rotor.lift_slope_per_rad
    ),
    d!(
        "tail_rotor",
        "drag_coefficient",
        "1",
        "Cd,tr blade drag",
        NonNegative,
        |p| p.tail_rotor.drag_coefficient
    ),
    d!(
        "tail_rotor",
        "gear_ratio",
        "1",
        "G gear ratio",
        Positive,
        |p| p.tail_rotor.gear_ratio
    ),
    d!(
        "tail_rotor",
        "fin_area_ratio",
        "1",
        "Ktf fin/wake ratio",
        NonNegative,
        |p| p.tail_rotor.fin_area_ratio
    ),
    d!("fuselage", "area_x_m2", "m^2", "Ax", NonNegative, |p| p
        .fuselage
        .area_x_m2),
    d!("fuselage", "area_y_m2", "m^2", "Ay", NonNegative, |p| p
        .fuselage
        .area_y_m2),
    d!("fuselage", "area_z_m2", "m^2", "Az", NonNegative, |p| p
        .fuselage
        .area_z_m2),
    d!("fuselage", "area_fp_m2", "m^2", "Afp", NonNegative, |p| p
        .fuselage
        .area_fp_m2),
    d!("fuselage", "area_tf_m2", "m^2", "Atf", NonNegative, |p| p
        .fuselage
        .area_tf_m2),
    d!("fuselage", "area_tp_m2", "m^2", "Atp", NonNegative, |p| p
        .fuselage
        .area_tp_m2),
    d!("fuselage", "drag_x", "1", "dx", NonNegative, |p| p
        .fuselage
        .drag_x),
    d!("fuselage", "drag_y", "1", "dy", NonNegative, |p| p
        .fuselage
        .drag_y),
    d!("fuselage", "drag_z", "1", "dz", NonNegative, |p| p
        .fuselage
        .drag_z),
    d!("fuselage", "drag_fp", "1", "dfp", NonNegative, |p| p
        .fuselage
        .drag_fp),
    d!("fuselage", "drag_tf", "1", "dtf", NonNegative, |p| p
        .fuselage
        .drag_tf),
    d!("fuselage", "drag_tp", "1", "dtp", NonNegative, |p| p
        .fuselage
        .drag_tp),
    d!(
        "control",
        "sample_time_s",
        "s",
        "Ts sampling time",
        Positive,
        |p| p.control.sample_time_s
    ),
];

const YAW_GYRO: [Descriptor; 4] = [
    d!(
        "yaw_gyro",
        "enabled",
        "1",
        "yaw-rate gyro block on (thesis §3.1.1)",
        Flag,
        |p| p.yaw_gyro.enabled
    ),
    d!(
        "yaw_gyro",
        "kp_s",
        "s",
        "Kp gyro proportional gain (S_tr per rad/s)",
        Finite,
        |p| p.yaw_gyro.kp_s
    ),
    d!(
        "yaw_gyro",
        "ki",
        "1",
        "Ki gyro heading-hold gain (S_tr per rad)",
        Finite,
        |p| p.yaw_gyro.ki
    ),
    d!(
        "yaw_gyro",
        "max_rate_rad_s",
        "rad/s",
        "yaw-rate command at full tail input",
        Positive,
        |p| p.yaw_gyro.max_rate_rad_s
    ),
];

const LANDING_GEAR: [Descriptor; 12] = [
    d!(
        "landing_gear",
        "enabled",
        "1",
        "landing gear and ground on (skid contact points)",
        Flag,
        |p| p.landing_gear.enabled
    ),
    d!(
        "landing_gear",
        "ground_down_m",
        "m",
        "NED down coordinate of the ground under the origin",
        Finite,
        |p| p.landing_gear.ground_down_m
    ),
    d!(
        "landing_gear",
        "ground_slope_rad",
        "rad",
        "ground slope, rising toward north",
        Finite,
        |p| p.landing_gear.ground_slope_rad
    ),
    d!(
        "landing_gear",
        "contact_x_front_m",
        "m",
        "body x of the front skid ends (forward)",
        Finite,
        |p| p.landing_gear.contact_x_front_m
    ),
    d!(
        "landing_gear",
        "contact_x_rear_m",
        "m",
        "body x of the rear skid ends (forward; negative aft)",
        Finite,
        |p| p.landing_gear.contact_x_rear_m
    ),
    d!(
        "landing_gear",
        "contact_y_half_m",
        "m",
        "half the skid track (body y = +-this)",
        Positive,
        |p| p.landing_gear.contact_y_half_m
    ),
    d!(
        "landing_gear",
        "contact_z_m",
        "m",
        "body z of the skids (below the CM)",
        Positive,
        |p| p.landing_gear.contact_z_m
    ),
    d!(
        "landing_gear",
        "stiffness_n_m",
        "N/m",
        "k spring per contact point",
        Positive,
        |p| p.landing_gear.stiffness_n_m
    ),
    d!(
        "landing_gear",
        "damping_n_s_m",
        "N*s/m",
        "c damper per contact point",
        NonNegative,
        |p| p.landing_gear.damping_n_s_m
    ),
    d!(
        "landing_gear",
        "friction_static",
        "1",
        "μs static friction",
        NonNegative,
        |p| p.landing_gear.friction_static
    ),
    d!(
        "landing_gear",
        "friction_dynamic",
        "1",
        "μd sliding friction",
        NonNegative,
        |p| p.landing_gear.friction_dynamic
    ),
    d!(
        "landing_gear",
        "stribeck_speed_m_s",
        "m/s",
        "sliding speed of the static-to-dynamic transition",
        Positive,
        |p| p.landing_gear.stribeck_speed_m_s
    ),
];

const GROUND_EFFECT: [Descriptor; 2] = [
    d!(
        "ground_effect",
        "enabled",
        "1",
        "ground effect on the main-rotor inflow on",
        Flag,
        |p| p.ground_effect.enabled
    ),
    d!(
        "ground_effect",
        "min_height_ratio",
        "1",
        "z/R below which the height is clamped (>= 0.5)",
        Positive,
        |p| p.ground_effect.min_height_ratio
    ),
];

const DRIVETRAIN: [Descriptor; 8] = [
    d!(
        "drivetrain",
        "enabled",
        "1",
        "rotor speed as a state (engine, governor) on",
        Flag,
        |p| p.drivetrain.enabled
    ),
    d!(
        "drivetrain",
        "inertia_kg_m2",
        "kg*m^2",
        "J rotor + transmission inertia, main shaft",
        Positive,
        |p| p.drivetrain.inertia_kg_m2
    ),
    d!(
        "drivetrain",
        "engine_torque_max_n_m",
        "N*m",
        "engine torque at full throttle, main shaft",
        Positive,
        |p| p.drivetrain.engine_torque_max_n_m
    ),
    d!(
        "drivetrain",
        "friction_n_m_s",
        "N*m*s/rad",
        "transmission friction (viscous)",
        NonNegative,
        |p| p.drivetrain.friction_n_m_s
    ),
    d!(
        "drivetrain",
        "governor_kp_s",
        "s",
        "governor Kp, throttle per rad/s",
        NonNegative,
        |p| p.drivetrain.governor_kp_s
    ),
    d!(
        "drivetrain",
        "governor_ki_per_rad",
        "1/rad",
        "governor Ki, throttle per rad",
        NonNegative,
        |p| p.drivetrain.governor_ki_per_rad
    ),
    d!(
        "drivetrain",
        "spool_up_s",
        "s",
        "spool-up time, 0 to governed speed",
        Positive,
        |p| p.drivetrain.spool_up_s
    ),
    d!(
        "drivetrain",
        "aero_floor_rad_s",
        "rad/s",
        "rotor speed floor of the blade aerodynamics",
        Positive,
        |p| p.drivetrain.aero_floor_rad_s
    ),
];

/// All parameter descriptors, in file order.
pub fn descriptors() -> impl Iterator<Item = &'static Descriptor> {
    BASE.iter()
        .chain(SERVO_COL.iter())
        .chain(SERVO_LAT.iter())
        .chain(SERVO_LON.iter())
        .chain(SERVO_TR.iter())
        .chain(YAW_GYRO.iter())
        .chain(LANDING_GEAR.iter())
        .chain(GROUND_EFFECT.iter())
        .chain(DRIVETRAIN.iter())
}

/// Number of parameter keys.
pub fn descriptor_count() -> usize {
    descriptors().count()
}

pub(super) fn find(section: &str, key: &str) -> Option<&'static Descriptor> {
    descriptors().find(|d| d.section == section && d.key == key)
}
