//! The `[px4]` section: which of PX4's actuator outputs (the
//! `HIL_ACTUATOR_CONTROLS` channels) drive the rotor's throttle, the tail
//! and the swashplate, and the inverse of PX4's helicopter allocation that
//! turns them back into the Bergen Twin's inputs `S_col S_lat S_lon S_tr`
//! and the engine switch.
//!
//! PX4's side, as read in its sources (`ActuatorEffectivenessHelicopter`,
//! `SimulatorMavlink::actuator_controls_from_outputs`):
//!
//! ```text
//! motor   = throttle curve CA_HELI_THR_C0…4 of the collective thrust (0 … 1)
//! tail    = yaw·(CA_HELI_YAW_CCW ? −1 : 1) + collective/throttle feed-forward (−1 … 1)
//! servo_i = P + pitch·cos(a_i)·L_i − roll·sin(a_i)·L_i + trim_i            (−1 … 1)
//!   P the pitch curve CA_HELI_PITCH_C0…4, a_i = CA_SP0_ANGi, L_i = CA_SP0_ARM_Li,
//!   trim_i = CA_SV_CSi_TRIM; roll > 0 rolls right, pitch > 0 pitches nose up
//! controls[n−1] = the output n (PWM_MAIN_FUNCn) when armed, 0 when disarmed
//! ```
//!
//! The inverse solves the three swash servos' equations for `P`, `pitch`
//! and `roll` (exact for three servos), then: the collective blade pitch
//! is linear in `P` between `collective_pitch_at_minus1_deg` and
//! `collective_pitch_at_plus1_deg`, and the cyclic is the plate's tilt
//! through the same linkage: a roll of 1 at arm length 1 moves the servos
//! by one unit, half the collective's −1 … 1 travel, so it makes half the
//! collective's blade-pitch span of cyclic (times `cyclic_scale`). As for
//! ArduPilot, PX4's roll right and pitch up are negative A1 and B1 (the
//! thesis's Table 4.1: A1 > 0 moves the helicopter left, B1 > 0 forward).
//! The tail blade pitch is linear in the tail output between
//! `tail_pitch_at_minus1_deg` and `tail_pitch_at_plus1_deg` (+1: nose right).

use crate::swash::{ModelServos, invert, linear_deg};
use helicon_config::ConfigError;
use helicon_core::state::Input;
use helicon_model::Params;
use nalgebra::{Matrix3, Vector3};
use serde::Deserialize;
use std::path::Path;

/// The number of `HIL_ACTUATOR_CONTROLS` channels.
pub const CHANNELS: usize = 16;

/// The `[px4]` section as written (see `examples/px4/`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Px4Section {
    /// The output n (1 … 16, `PWM_MAIN_FUNCn` = Motor 1) of the rotor's
    /// throttle: `controls[n−1]`, 0 … 1.
    pub throttle_channel: u8,
    /// The output of the tail servo (the helicopter's first servo).
    pub tail_channel: u8,
    /// The outputs of swash servos 0, 1, 2 (`CA_SP0_ANG0 … 2`'s servos).
    pub swash_channels: [u8; 3],
    /// `CA_SP0_ANG0 … 2`: the servos' azimuths (deg, 0 forward, 90 right).
    pub swash_servo_angles_deg: [f64; 3],
    /// `CA_SP0_ARM_L0 … 2`: the servos' arm lengths (relative; 1 nominal).
    #[serde(default = "ones")]
    pub swash_arm_lengths: [f64; 3],
    /// `CA_SV_CS0_TRIM …`: the swash servos' trims (−1 … 1).
    #[serde(default)]
    pub swash_trims: [f64; 3],
    /// The collective blade pitch at the swash servos' −1 (deg).
    pub collective_pitch_at_minus1_deg: f64,
    /// The collective blade pitch at the swash servos' +1 (deg).
    pub collective_pitch_at_plus1_deg: f64,
    /// The swashplate's cyclic (A1, B1) per blade-pitch equivalent of the
    /// plate's tilt (1: the cyclic linkage has the collective's ratio).
    #[serde(default = "one")]
    pub cyclic_scale: f64,
    /// The tail blade pitch at the tail output −1 (deg).
    pub tail_pitch_at_minus1_deg: f64,
    /// The tail blade pitch at the tail output +1 (deg; nose right).
    pub tail_pitch_at_plus1_deg: f64,
    /// The engine runs while armed and the throttle output is at least
    /// this (0 … 1); below it, it is cut. Above it the model's governor
    /// spools the rotor up and holds the governed speed.
    pub engine_on_above: f64,
    /// Home: latitude of the ground start (deg, WGS-84).
    pub home_lat_deg: f64,
    /// Home: longitude (deg).
    pub home_lon_deg: f64,
    /// Home: the ground's altitude above mean sea level (m).
    pub home_alt_m: f64,
    /// The Earth's magnetic field at home, NED (gauss), rotated into the
    /// body for `HIL_SENSOR`'s magnetometer.
    pub mag_field_ned_gauss: [f64; 3],
}

fn ones() -> [f64; 3] {
    [1.0; 3]
}
fn one() -> f64 {
    1.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    px4: Px4Section,
}

/// The Bergen Twin's section, the one shipped as
/// `examples/px4/bergen_twin.toml` (the default of `helicon sitl --px4`).
pub const BERGEN_TWIN_TOML: &str = include_str!("../../../../examples/px4/bergen_twin.toml");

/// The decoded commands, in PX4's normalized units.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Px4Outputs {
    /// Roll torque (positive right).
    pub roll: f64,
    /// Pitch torque (positive nose up).
    pub pitch: f64,
    /// The collective `P` the swash servos carry (−1 … 1).
    pub collective: f64,
    /// The tail output (−1 … 1, positive nose right).
    pub tail: f64,
    /// The throttle (0 … 1).
    pub throttle: f64,
}

/// What one actuator message drives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Px4Decoded {
    /// The Bergen Twin's inputs (within the model's command limits).
    pub input: Input,
    /// The engine runs (armed and the throttle at or above the threshold).
    pub engine_on: bool,
    /// The commands in PX4's units.
    pub outputs: Px4Outputs,
}

/// The checked section with its allocation inverted: controls → inputs.
#[derive(Debug, Clone, PartialEq)]
pub struct Px4Map {
    /// The section it was built from.
    pub section: Px4Section,
    /// The allocation's rows (1, cos a·L, −sin a·L): servo from (P, pitch, roll).
    mix: Matrix3<f64>,
    unmix: Matrix3<f64>,
    servos: ModelServos,
}

impl Px4Section {
    /// Parse the `[px4]` section of `text`; `file` names it in errors.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Self, ConfigError> {
        let f: File = toml::from_str(text).map_err(|e| ConfigError::Parse {
            file: file.to_string(),
            message: e.to_string(),
        })?;
        Ok(f.px4)
    }

    /// Read the `[px4]` section of a file (bounded, regular files only).
    pub fn from_file(path: &Path) -> Result<Self, ConfigError> {
        let (file, text) = ConfigError::read_file(path)?;
        Self::from_toml_str(&text, &file)
    }
}

/// A control read as PX4 means it: NaN (no output, disarmed) is 0,
/// the rest within `lo … hi`.
fn control(controls: &[f32; CHANNELS], channel: u8, lo: f64, hi: f64) -> f64 {
    let v = f64::from(controls[usize::from(channel - 1)]);
    if v.is_finite() { v.clamp(lo, hi) } else { 0.0 }
}

impl Px4Map {
    /// Check `section` (errors name `file` and the field) and invert its
    /// allocation for the model `params`.
    pub fn new(section: Px4Section, params: &Params, file: &str) -> Result<Self, ConfigError> {
        check(&section, file)?;
        let s = &section;
        let mix = Matrix3::from_fn(|i, j| {
            let a = s.swash_servo_angles_deg[i].to_radians();
            let l = s.swash_arm_lengths[i];
            [1.0, a.cos() * l, -a.sin() * l][j]
        });
        let Some(unmix) = invert(&mix) else {
            return Err(ConfigError::invalid(
                file,
                "px4.swash_servo_angles_deg",
                s.swash_servo_angles_deg[0],
                "three servo azimuths that tilt the plate both ways (the allocation is singular)",
            ));
        };
        let servos = ModelServos::new(params, file, "px4")?;
        Ok(Px4Map {
            section,
            mix,
            unmix,
            servos,
        })
    }

    /// Decode one `HIL_ACTUATOR_CONTROLS`' `controls` with its armed flag.
    pub fn decode(&self, controls: &[f32; CHANNELS], armed: bool) -> Px4Decoded {
        let s = &self.section;
        let mut o = Vector3::zeros();
        for i in 0..3 {
            o[i] = control(controls, s.swash_channels[i], -1.0, 1.0) - s.swash_trims[i];
        }
        let ppr = self.unmix * o;
        let throttle = control(controls, s.throttle_channel, 0.0, 1.0);
        let outputs = Px4Outputs {
            collective: ppr[0],
            pitch: ppr[1],
            roll: ppr[2],
            tail: control(controls, s.tail_channel, -1.0, 1.0),
            throttle,
        };
        Px4Decoded {
            input: self.input_from(&outputs),
            engine_on: armed && throttle >= s.engine_on_above,
            outputs,
        }
    }

    /// The cyclic (A1 or B1) per unit of PX4's roll or pitch (deg).
    fn cyclic_per_unit_deg(&self) -> f64 {
        let s = &self.section;
        0.5 * (s.collective_pitch_at_plus1_deg - s.collective_pitch_at_minus1_deg) * s.cyclic_scale
    }

    /// The model's inputs that PX4's normalized commands make.
    pub fn input_from(&self, o: &Px4Outputs) -> Input {
        let s = &self.section;
        let theta0 = linear_deg(
            o.collective,
            -1.0,
            1.0,
            s.collective_pitch_at_minus1_deg,
            s.collective_pitch_at_plus1_deg,
        );
        let cyc = self.cyclic_per_unit_deg();
        let tail = linear_deg(
            o.tail.clamp(-1.0, 1.0),
            -1.0,
            1.0,
            s.tail_pitch_at_minus1_deg,
            s.tail_pitch_at_plus1_deg,
        );
        // roll right: A1 < 0; pitch up: B1 < 0 (thesis Table 4.1)
        self.servos
            .input_from_deg(&[theta0, -cyc * o.roll, -cyc * o.pitch, tail])
    }

    /// PX4's normalized commands that make the model's inputs `u` (the
    /// inverse of [`Px4Map::input_from`], without its limits): what PX4
    /// must output to fly `u`, e.g. the hover trim.
    pub fn outputs_for(&self, u: &Input, throttle: f64) -> Px4Outputs {
        let s = &self.section;
        let d = self.servos.deg_of(u);
        let cyc = self.cyclic_per_unit_deg();
        Px4Outputs {
            collective: linear_deg(
                d[0],
                s.collective_pitch_at_minus1_deg,
                s.collective_pitch_at_plus1_deg,
                -1.0,
                1.0,
            ),
            roll: -d[1] / cyc,
            pitch: -d[2] / cyc,
            tail: linear_deg(
                d[3],
                s.tail_pitch_at_minus1_deg,
                s.tail_pitch_at_plus1_deg,
                -1.0,
                1.0,
            ),
            throttle,
        }
    }

    /// PX4's actuator controls for `o` (armed): what PX4's allocation
    /// outputs, channel by channel (the forward of [`Px4Map::decode`]).
    pub fn controls_for(&self, o: &Px4Outputs) -> [f32; CHANNELS] {
        let s = &self.section;
        let mut c = [0f32; CHANNELS];
        let v = self.mix * Vector3::new(o.collective, o.pitch, o.roll);
        for i in 0..3 {
            c[usize::from(s.swash_channels[i] - 1)] = (v[i] + s.swash_trims[i]) as f32;
        }
        c[usize::from(s.tail_channel - 1)] = o.tail as f32;
        c[usize::from(s.throttle_channel - 1)] = o.throttle as f32;
        c
    }
}

fn invalid(file: &str, field: &str, v: f64, rule: &str) -> Result<(), ConfigError> {
    Err(ConfigError::invalid(file, format!("px4.{field}"), v, rule))
}

/// Every field of the section.
fn check(s: &Px4Section, file: &str) -> Result<(), ConfigError> {
    let bad = |field: &str, v: f64, rule: &str| invalid(file, field, v, rule);
    let channels = [
        ("throttle_channel".to_string(), s.throttle_channel),
        ("tail_channel".to_string(), s.tail_channel),
        ("swash_channels[0]".to_string(), s.swash_channels[0]),
        ("swash_channels[1]".to_string(), s.swash_channels[1]),
        ("swash_channels[2]".to_string(), s.swash_channels[2]),
    ];
    for (i, (name, c)) in channels.iter().enumerate() {
        if !(1..=16).contains(c) {
            return bad(
                name,
                f64::from(*c),
                "an output number in 1 ..= 16 (HIL_ACTUATOR_CONTROLS' controls[0 … 15])",
            );
        }
        for (other, d) in &channels[..i] {
            if d == c {
                return bad(
                    name,
                    f64::from(*c),
                    &format!("already the channel of `px4.{other}`"),
                );
            }
        }
    }
    for i in 0..3 {
        let a = s.swash_servo_angles_deg[i];
        if !(a.is_finite() && (0.0..=360.0).contains(&a)) {
            return bad(
                &format!("swash_servo_angles_deg[{i}]"),
                a,
                "in 0 … 360 deg (CA_SP0_ANGn)",
            );
        }
        let l = s.swash_arm_lengths[i];
        if !(l.is_finite() && l > 0.0 && l <= 10.0) {
            return bad(
                &format!("swash_arm_lengths[{i}]"),
                l,
                "in (0, 10] (CA_SP0_ARM_Ln)",
            );
        }
        let t = s.swash_trims[i];
        if !(t.is_finite() && t.abs() <= 1.0) {
            return bad(
                &format!("swash_trims[{i}]"),
                t,
                "in −1 … 1 (CA_SV_CSn_TRIM)",
            );
        }
    }
    for (f, v) in [
        (
            "collective_pitch_at_minus1_deg",
            s.collective_pitch_at_minus1_deg,
        ),
        (
            "collective_pitch_at_plus1_deg",
            s.collective_pitch_at_plus1_deg,
        ),
        ("tail_pitch_at_minus1_deg", s.tail_pitch_at_minus1_deg),
        ("tail_pitch_at_plus1_deg", s.tail_pitch_at_plus1_deg),
    ] {
        if !(v.is_finite() && v.abs() <= 45.0) {
            return bad(f, v, "a blade pitch in −45 … 45 deg");
        }
    }
    if s.collective_pitch_at_plus1_deg <= s.collective_pitch_at_minus1_deg {
        return bad(
            "collective_pitch_at_plus1_deg",
            s.collective_pitch_at_plus1_deg,
            "above collective_pitch_at_minus1_deg",
        );
    }
    if s.tail_pitch_at_plus1_deg == s.tail_pitch_at_minus1_deg {
        return bad(
            "tail_pitch_at_plus1_deg",
            s.tail_pitch_at_plus1_deg,
            "different from tail_pitch_at_minus1_deg",
        );
    }
    if !(s.cyclic_scale.is_finite() && s.cyclic_scale > 0.0 && s.cyclic_scale <= 10.0) {
        return bad("cyclic_scale", s.cyclic_scale, "in (0, 10]");
    }
    if !(s.engine_on_above.is_finite() && s.engine_on_above > 0.0 && s.engine_on_above < 1.0) {
        return bad(
            "engine_on_above",
            s.engine_on_above,
            "in (0, 1): a fraction of the throttle output",
        );
    }
    if !(s.home_lat_deg.is_finite() && s.home_lat_deg.abs() <= 85.0) {
        return bad("home_lat_deg", s.home_lat_deg, "in −85 … 85 deg");
    }
    if !(s.home_lon_deg.is_finite() && s.home_lon_deg.abs() <= 180.0) {
        return bad("home_lon_deg", s.home_lon_deg, "in −180 … 180 deg");
    }
    if !(s.home_alt_m.is_finite() && (-400.0..=8000.0).contains(&s.home_alt_m)) {
        return bad("home_alt_m", s.home_alt_m, "in −400 … 8000 m");
    }
    let norm = s
        .mag_field_ned_gauss
        .iter()
        .map(|b| b * b)
        .sum::<f64>()
        .sqrt();
    if !(norm.is_finite() && (0.2..=0.7).contains(&norm)) {
        return bad(
            "mag_field_ned_gauss",
            norm,
            "an Earth field of 0.2 … 0.7 gauss in magnitude",
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with(edit: &str, replace: &str) -> Result<Px4Map, ConfigError> {
        assert!(BERGEN_TWIN_TOML.contains(edit), "{edit}");
        let text = BERGEN_TWIN_TOML.replacen(edit, replace, 1);
        let s = Px4Section::from_toml_str(&text, "p.toml")?;
        Px4Map::new(s, &Params::bergen_twin(), "p.toml")
    }

    #[test]
    fn the_example_is_valid_and_its_allocation_inverts() {
        let m = with("throttle_channel = 1", "throttle_channel = 1").unwrap();
        let o = Px4Outputs {
            roll: 0.2,
            pitch: -0.3,
            collective: 0.4,
            tail: 0.1,
            throttle: 0.8,
        };
        let d = m.decode(&m.controls_for(&o), true);
        assert!((d.outputs.roll - o.roll).abs() < 1e-6, "{d:?}");
        assert!((d.outputs.pitch - o.pitch).abs() < 1e-6, "{d:?}");
        assert!((d.outputs.collective - o.collective).abs() < 1e-6, "{d:?}");
        assert!((d.outputs.tail - o.tail).abs() < 1e-6, "{d:?}");
        assert!(d.engine_on);
        assert!(!m.decode(&m.controls_for(&o), false).engine_on);
        // roll right is negative lateral cyclic, pitch up negative longitudinal
        assert!(d.input[1] < 0.0 && d.input[2] > 0.0, "{d:?}");
    }

    #[test]
    fn errors_name_the_file_and_the_field() {
        let cases = [
            ("tail_channel = 2", "tail_channel = 1", "px4.tail_channel"),
            (
                "throttle_channel = 1",
                "throttle_channel = 17",
                "px4.throttle_channel",
            ),
            (
                "swash_servo_angles_deg = [300.0, 60.0, 180.0]",
                "swash_servo_angles_deg = [400.0, 60.0, 180.0]",
                "px4.swash_servo_angles_deg[0]",
            ),
            (
                "swash_servo_angles_deg = [300.0, 60.0, 180.0]",
                "swash_servo_angles_deg = [60.0, 60.0, 60.0]",
                "px4.swash_servo_angles_deg",
            ),
            (
                "swash_arm_lengths = [1.0, 1.0, 1.0]",
                "swash_arm_lengths = [1.0, 0.0, 1.0]",
                "px4.swash_arm_lengths[1]",
            ),
            (
                "collective_pitch_at_plus1_deg = 12.0",
                "collective_pitch_at_plus1_deg = -5.0",
                "px4.collective_pitch_at_plus1_deg",
            ),
            (
                "engine_on_above = 0.1",
                "engine_on_above = 0.0",
                "px4.engine_on_above",
            ),
            (
                "home_lat_deg = 57.014",
                "home_lat_deg = 91.0",
                "px4.home_lat_deg",
            ),
            (
                "mag_field_ned_gauss = [0.1615, 0.0113, 0.4840]",
                "mag_field_ned_gauss = [0.0, 0.0, 0.0]",
                "px4.mag_field_ned_gauss",
            ),
        ];
        for (edit, replace, field) in cases {
            let e = with(edit, replace).unwrap_err();
            match &e {
                ConfigError::Invalid { file, field: f, .. } => {
                    assert_eq!(file, "p.toml");
                    assert_eq!(f, field, "{e}");
                }
                other => panic!("{other}"),
            }
            assert!(e.to_string().starts_with("p.toml: "), "{e}");
        }
        let e = with("cyclic_scale = 1.0", "cyclic_scale = 1.0\ntypo = 1").unwrap_err();
        assert!(
            matches!(&e, ConfigError::Parse { file, message } if file == "p.toml" && message.contains("typo")),
            "{e}"
        );
    }

    #[test]
    fn a_nan_control_reads_as_zero() {
        let m = with("throttle_channel = 1", "throttle_channel = 1").unwrap();
        let mut c = [0f32; CHANNELS];
        c[0] = f32::NAN;
        c[2] = f32::NAN;
        let d = m.decode(&c, true);
        assert_eq!(d.outputs.throttle, 0.0);
        assert!(!d.engine_on);
        assert!(d.input.iter().all(|v| v.is_finite()));
    }
}
