//! The `[ardupilot]` section: which of ArduPilot's servo outputs drive the
//! swashplate, the tail and the engine, and the inverse of ArduPilot's
//! traditional-helicopter mixer that turns their PWM back into the Bergen
//! Twin's inputs `S_col S_lat S_lon S_tr` and the engine switch.
//!
//! ArduPilot's side, as read in its sources (`AP_MotorsHeli_Single`,
//! `AP_MotorsHeli_Swash`, `SRV_Channel`):
//!
//! ```text
//! c   = collective·(H_COL_MAX − H_COL_MIN)/1000 + (H_COL_MIN − 1000)/1000   (0 … 1)
//! c   = 1 − c                                    when H_SW_COL_DIR reversed
//! o_i = 0.45·(R_i·roll + P_i·pitch) + C_i·c  (+ 0.5 for H1's servos 1 and 2)
//! s_i = 2·o_i − 1                              (−1 … 1)
//! n_i = (u16)(1500 + 500·s_i)                  (truncated)
//! PWM_i = n_i − 1500 + SERVOn_TRIM   (reversed: 1500 − n_i + SERVOn_TRIM), clamped to 1000 … 2000
//! H3 generic:  R_i = cos(pos_i − phase + 90°), P_i = cos(pos_i − phase), C_i = 1
//! H3-120:      positions −60°, 60°, 180°, no phase;  H3-140: R = (1, −1, 0), P = (1, 1, −1)
//! H1:          servo 1 roll, servo 2 pitch, servo 3 collective
//! tail:        PWM = TRIM + yaw·(MAX − TRIM) (yaw > 0), TRIM + yaw·(TRIM − MIN) (yaw < 0); reversed: −yaw
//! throttle:    PWM = MIN + out·(MAX − MIN) (reversed: 1 − out)   (HeliRSC, SERVOn_FUNCTION 31)
//! ```
//!
//! The inverse solves the three swash servos' equations for `roll`,
//! `pitch`, `c` (exact for three servos), then gives the blade pitch: the
//! collective `θ0 = H_COL_ANG_MIN + (1000 + 1000·c − H_COL_MIN)/(H_COL_MAX −
//! H_COL_MIN)·(H_COL_ANG_MAX − H_COL_ANG_MIN)`, and the cyclic the plate's
//! tilt makes with the same linkage: a roll of 1 moves the plate by 0.45 of
//! the servos' full collective travel at the servos' azimuth, that is
//! `450 µs·(H_COL_ANG_MAX − H_COL_ANG_MIN)/(H_COL_MAX − H_COL_MIN)` of
//! cyclic blade pitch (times `cyclic_scale`). The model's swashplate
//! angles are `A1 = K_A·S_lat`, `B1 = K_B·S_lon` with A1 > 0 rolling left
//! and B1 > 0 pitching nose down (the thesis's Table 4.1: A1 > 0 moves the
//! helicopter left, B1 > 0 forward; the tests check the signs), so ArduPilot's roll
//! right and pitch up are negative A1 and B1.

use crate::swash::{ModelServos, invert, linear_deg};
use helicon_config::ConfigError;
use helicon_core::state::Input;
use helicon_model::Params;
use nalgebra::{Matrix3, Vector3};
use serde::Deserialize;
use std::path::Path;

/// ArduPilot's swashplate types (`H_SW_TYPE`) the backend inverts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
pub enum SwashType {
    /// `H_SW_TYPE = 0`: three servos at the azimuths `H_SW_H3_SV1_POS …
    /// SV3_POS`, with the phase angle `H_SW_H3_PHANG`.
    #[serde(rename = "h3")]
    H3Generic,
    /// `H_SW_TYPE = 1`: no mixing (servo 1 roll, servo 2 pitch, servo 3
    /// collective) — a flybar helicopter's mechanical mixer.
    #[serde(rename = "h1")]
    H1,
    /// `H_SW_TYPE = 2`: three servos, 140°.
    #[serde(rename = "h3_140")]
    H3_140,
    /// `H_SW_TYPE = 3`: three servos, 120° (CCPM).
    #[serde(rename = "h3_120")]
    H3_120,
}

impl SwashType {
    /// ArduPilot's `H_SW_TYPE` number.
    pub fn h_sw_type(self) -> u8 {
        match self {
            SwashType::H3Generic => 0,
            SwashType::H1 => 1,
            SwashType::H3_140 => 2,
            SwashType::H3_120 => 3,
        }
    }
}

/// One of ArduPilot's servo outputs (`SERVOn_*`).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServoOutput {
    /// The output number n of `SERVOn` (1-based, as ArduPilot numbers them).
    pub channel: u8,
    /// `SERVOn_MIN` (µs).
    #[serde(default = "min_us")]
    pub min_us: u16,
    /// `SERVOn_TRIM` (µs).
    #[serde(default = "trim_us")]
    pub trim_us: u16,
    /// `SERVOn_MAX` (µs).
    #[serde(default = "max_us")]
    pub max_us: u16,
    /// `SERVOn_REVERSED`.
    #[serde(default)]
    pub reversed: bool,
}

fn min_us() -> u16 {
    1000
}
fn trim_us() -> u16 {
    1500
}
fn max_us() -> u16 {
    2000
}

/// The `[ardupilot]` section as written (see `examples/ardupilot/`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArduPilotSection {
    /// `H_SW_TYPE`: `"h3"` (generic), `"h1"`, `"h3_140"`, `"h3_120"`.
    pub swash_type: SwashType,
    /// `H_SW_COL_DIR` = 1 (reversed).
    #[serde(default)]
    pub collective_reversed: bool,
    /// `H_SW_H3_SV1_POS … SV3_POS` (deg), H3 generic only.
    #[serde(default = "h3_positions")]
    pub h3_servo_positions_deg: [f64; 3],
    /// `H_SW_H3_PHANG` (deg), H3 generic only.
    #[serde(default)]
    pub h3_phase_angle_deg: f64,
    /// `H_COL_MIN` (µs).
    pub collective_min_us: u16,
    /// `H_COL_MAX` (µs).
    pub collective_max_us: u16,
    /// `H_COL_ANG_MIN`: the blade pitch at `H_COL_MIN` (deg).
    pub collective_pitch_min_deg: f64,
    /// `H_COL_ANG_MAX`: the blade pitch at `H_COL_MAX` (deg).
    pub collective_pitch_max_deg: f64,
    /// The swashplate's cyclic (A1, B1) per blade-pitch equivalent of the
    /// plate's tilt (1: the cyclic linkage has the collective's ratio).
    #[serde(default = "one")]
    pub cyclic_scale: f64,
    /// The tail blade pitch at ArduPilot's yaw output −1 (deg).
    pub tail_pitch_at_yaw_min_deg: f64,
    /// The tail blade pitch at ArduPilot's yaw output +1 (deg).
    pub tail_pitch_at_yaw_max_deg: f64,
    /// The engine runs while the throttle output (0 … 1 of its range) is
    /// at least this; below it, it is cut. Above it the model's governor
    /// spools the rotor up and holds the governed speed.
    pub engine_on_above: f64,
    /// Swash servo 1 (`H_SW_TYPE` motor 1: left on H3-120/140, roll on H1).
    pub swash1: ServoOutput,
    /// Swash servo 2 (right on H3-120/140, pitch on H1).
    pub swash2: ServoOutput,
    /// Swash servo 3 (elevator/rear on H3-120/140, collective on H1).
    pub swash3: ServoOutput,
    /// The tail servo (motor 4, `SERVOn_FUNCTION = 36`).
    pub tail: ServoOutput,
    /// The engine's throttle (HeliRSC, `SERVOn_FUNCTION = 31`).
    pub throttle: ServoOutput,
}

fn h3_positions() -> [f64; 3] {
    [-60.0, 60.0, 180.0]
}
fn one() -> f64 {
    1.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    ardupilot: ArduPilotSection,
}

/// The Bergen Twin's section, the one shipped as
/// `examples/ardupilot/bergen_twin.toml` (the default of
/// `helicon sitl --ardupilot-json`).
pub const BERGEN_TWIN_TOML: &str = include_str!("../../../../examples/ardupilot/bergen_twin.toml");

/// The decoded commands, in ArduPilot's normalized units.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AutopilotOutputs {
    /// Roll (−1 … 1, positive right).
    pub roll: f64,
    /// Pitch (−1 … 1, positive nose up).
    pub pitch: f64,
    /// The scaled collective `c` the swash servos carry (0 … 1 of the
    /// servos' 1000 µs travel), before `H_SW_COL_DIR`.
    pub collective: f64,
    /// Yaw (−1 … 1, positive nose right).
    pub yaw: f64,
    /// Throttle (0 … 1 of its output's range).
    pub throttle: f64,
}

/// The checked section with its mixer inverted: PWM → Bergen Twin inputs.
#[derive(Debug, Clone, PartialEq)]
pub struct ArduPilotMap {
    /// The section it was built from.
    pub section: ArduPilotSection,
    /// The mixer's rows (R_i, P_i, C_i), the 0.45 included.
    mix: Matrix3<f64>,
    /// Its inverse.
    unmix: Matrix3<f64>,
    /// H1's constant 0.5 on servos 1 and 2.
    offset: Vector3<f64>,
    /// The model's servo gains and command limits.
    servos: ModelServos,
}

/// What one servo packet drives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Decoded {
    /// The Bergen Twin's inputs (within the model's command limits).
    pub input: Input,
    /// The engine runs.
    pub engine_on: bool,
    /// The commands in ArduPilot's units.
    pub outputs: AutopilotOutputs,
}

impl ArduPilotSection {
    /// Parse the `[ardupilot]` section of `text`; `file` names it in errors.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Self, ConfigError> {
        let f: File = toml::from_str(text).map_err(|e| ConfigError::Parse {
            file: file.to_string(),
            message: e.to_string(),
        })?;
        Ok(f.ardupilot)
    }

    /// Read the `[ardupilot]` section of a file (bounded, regular files only).
    pub fn from_file(path: &Path) -> Result<Self, ConfigError> {
        let (file, text) = ConfigError::read_file(path)?;
        Self::from_toml_str(&text, &file)
    }
}

impl ArduPilotMap {
    /// Check `section` (errors name `file` and the field) and invert its
    /// mixer for the model `params` (its servo gains and command limits).
    pub fn new(
        section: ArduPilotSection,
        params: &Params,
        file: &str,
    ) -> Result<Self, ConfigError> {
        check_outputs(&section, file)?;
        check_numbers(&section, file)?;
        let s = &section;
        let bad = |field: &str, v: f64, rule: &str| {
            Err(ConfigError::invalid(
                file,
                format!("ardupilot.{field}"),
                v,
                rule,
            ))
        };
        let angle = |pos_deg: f64| {
            let a = pos_deg.to_radians();
            // AP_MotorsHeli_Swash::add_servo_angle
            [(a + std::f64::consts::FRAC_PI_2).cos(), a.cos(), 1.0]
        };
        let rows: [[f64; 3]; 3] = match s.swash_type {
            SwashType::H3Generic => {
                let p = s.h3_servo_positions_deg;
                let ph = s.h3_phase_angle_deg;
                [angle(p[0] - ph), angle(p[1] - ph), angle(p[2] - ph)]
            }
            SwashType::H3_120 => [angle(-60.0), angle(60.0), angle(180.0)],
            SwashType::H3_140 => [[1.0, 1.0, 1.0], [-1.0, 1.0, 1.0], [0.0, -1.0, 1.0]],
            SwashType::H1 => [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        };
        let mix = Matrix3::from_fn(|i, j| if j < 2 { 0.45 * rows[i][j] } else { rows[i][j] });
        let offset = if s.swash_type == SwashType::H1 {
            Vector3::new(0.5, 0.5, 0.0)
        } else {
            Vector3::zeros()
        };
        let unmix = match invert(&mix) {
            Some(m) => m,
            None => {
                return bad(
                    "h3_servo_positions_deg",
                    s.h3_servo_positions_deg[0],
                    "three servo azimuths that tilt the plate both ways (the mixer is singular)",
                );
            }
        };
        let servos = ModelServos::new(params, file, "ardupilot")?;
        Ok(ArduPilotMap {
            section,
            mix,
            unmix,
            offset,
            servos,
        })
    }

    /// The blade pitch per unit of `c`, the swash servos' scaled collective (deg).
    fn pitch_per_c_deg(&self) -> f64 {
        let s = &self.section;
        1000.0 * (s.collective_pitch_max_deg - s.collective_pitch_min_deg)
            / f64::from(s.collective_max_us - s.collective_min_us)
    }

    /// The cyclic (A1 or B1) per unit of ArduPilot's roll or pitch (deg).
    fn cyclic_per_unit_deg(&self) -> f64 {
        0.45 * self.pitch_per_c_deg() * self.section.cyclic_scale
    }

    /// The largest lateral cyclic command (model units) ArduPilot's roll of ±1 makes.
    pub fn lateral_per_roll(&self) -> f64 {
        self.cyclic_per_unit_deg().to_radians() * self.servos.per_rad(1)
    }

    /// Decode one packet's PWM (`pwm[n-1]` is `SERVOn`; a channel beyond the
    /// packet or reading 0 — no output yet — counts as its trim, the
    /// throttle as its minimum).
    pub fn decode(&self, pwm: &[u16]) -> Decoded {
        let s = &self.section;
        let read = |o: &ServoOutput, idle: u16| match pwm.get(usize::from(o.channel) - 1) {
            Some(&v) if v != 0 => f64::from(v),
            _ => f64::from(idle),
        };
        let mut o = Vector3::zeros();
        for (i, out) in [&s.swash1, &s.swash2, &s.swash3].into_iter().enumerate() {
            let p = read(out, out.trim_us).clamp(1000.0, 2000.0);
            let trim = f64::from(out.trim_us);
            // the nominal 1500-centred value, +0.5 µs for the u16 truncation
            let n = if out.reversed {
                1500.0 + trim - p
            } else {
                p + 1500.0 - trim
            } + 0.5;
            let servo = (n - 1500.0) / 500.0;
            o[i] = (servo + 1.0) / 2.0 - self.offset[i];
        }
        let rpc = self.unmix * o;
        let (roll, pitch, c_dir) = (rpc[0], rpc[1], rpc[2]);
        let c = if s.collective_reversed {
            1.0 - c_dir
        } else {
            c_dir
        };
        // the tail servo: SRV_Channel::pwm_from_angle inverted
        let t = &s.tail;
        let tp = read(t, t.trim_us).clamp(f64::from(t.min_us), f64::from(t.max_us));
        let (tmin, ttrim, tmax) = (
            f64::from(t.min_us),
            f64::from(t.trim_us),
            f64::from(t.max_us),
        );
        let mut yaw = if tp >= ttrim {
            (tp - ttrim) / (tmax - ttrim)
        } else {
            (tp - ttrim) / (ttrim - tmin)
        };
        if t.reversed {
            yaw = -yaw;
        }
        // the throttle: SRV_Channel::pwm_from_range inverted
        let h = &s.throttle;
        let hp = read(h, if h.reversed { h.max_us } else { h.min_us });
        let mut throttle =
            ((hp - f64::from(h.min_us)) / f64::from(h.max_us - h.min_us)).clamp(0.0, 1.0);
        if h.reversed {
            throttle = 1.0 - throttle;
        }
        let outputs = AutopilotOutputs {
            roll,
            pitch,
            collective: c,
            yaw,
            throttle,
        };
        Decoded {
            input: self.input_from(&outputs),
            engine_on: throttle >= s.engine_on_above,
            outputs,
        }
    }

    /// The model's inputs that ArduPilot's normalized commands make.
    pub fn input_from(&self, o: &AutopilotOutputs) -> Input {
        let s = &self.section;
        let c_us = 1000.0 + 1000.0 * o.collective;
        let theta0_deg = linear_deg(
            c_us,
            f64::from(s.collective_min_us),
            f64::from(s.collective_max_us),
            s.collective_pitch_min_deg,
            s.collective_pitch_max_deg,
        );
        let cyc = self.cyclic_per_unit_deg();
        // roll right: A1 < 0; pitch up: B1 < 0 (thesis Table 4.1)
        let a1_deg = -cyc * o.roll;
        let b1_deg = -cyc * o.pitch;
        let mid = 0.5 * (s.tail_pitch_at_yaw_max_deg + s.tail_pitch_at_yaw_min_deg);
        let half = 0.5 * (s.tail_pitch_at_yaw_max_deg - s.tail_pitch_at_yaw_min_deg);
        let tail_deg = mid + half * o.yaw.clamp(-1.0, 1.0);
        self.servos
            .input_from_deg(&[theta0_deg, a1_deg, b1_deg, tail_deg])
    }

    /// ArduPilot's normalized commands that make the model's inputs `u`
    /// (the inverse of [`ArduPilotMap::input_from`], without its limits):
    /// what ArduPilot must output to fly `u`, e.g. the trim.
    pub fn outputs_for(&self, u: &Input, throttle: f64) -> AutopilotOutputs {
        let s = &self.section;
        let d = self.servos.deg_of(u);
        let deg = |i: usize| d[i];
        let c_us = f64::from(s.collective_min_us)
            + (deg(0) - s.collective_pitch_min_deg)
                / (s.collective_pitch_max_deg - s.collective_pitch_min_deg)
                * f64::from(s.collective_max_us - s.collective_min_us);
        let cyc = self.cyclic_per_unit_deg();
        let mid = 0.5 * (s.tail_pitch_at_yaw_max_deg + s.tail_pitch_at_yaw_min_deg);
        let half = 0.5 * (s.tail_pitch_at_yaw_max_deg - s.tail_pitch_at_yaw_min_deg);
        AutopilotOutputs {
            roll: -deg(1) / cyc,
            pitch: -deg(2) / cyc,
            collective: (c_us - 1000.0) / 1000.0,
            yaw: (deg(3) - mid) / half,
            throttle,
        }
    }

    /// ArduPilot's `H_COL_*`-scaled collective (0 … 1 between `H_COL_MIN`
    /// and `H_COL_MAX`, the attitude controller's collective) for the
    /// servos' scaled collective `c`.
    pub fn collective_fraction(&self, c: f64) -> f64 {
        let s = &self.section;
        (1000.0 + 1000.0 * c - f64::from(s.collective_min_us))
            / f64::from(s.collective_max_us - s.collective_min_us)
    }

    /// The mixer's rows (roll, pitch, collective factor per swash servo,
    /// ArduPilot's 0.45 included) and H1's offsets: for a reader checking
    /// the inversion.
    pub fn mixer(&self) -> ([[f64; 3]; 3], [f64; 3]) {
        (
            [
                [self.mix[(0, 0)], self.mix[(0, 1)], self.mix[(0, 2)]],
                [self.mix[(1, 0)], self.mix[(1, 1)], self.mix[(1, 2)]],
                [self.mix[(2, 0)], self.mix[(2, 1)], self.mix[(2, 2)]],
            ],
            [self.offset[0], self.offset[1], self.offset[2]],
        )
    }
}

/// An out-of-range field of the section.
fn invalid(file: &str, field: &str, v: f64, rule: &str) -> Result<(), ConfigError> {
    Err(ConfigError::invalid(
        file,
        format!("ardupilot.{field}"),
        v,
        rule,
    ))
}

/// The five servo outputs: channels distinct and in range, endpoints and trims.
fn check_outputs(s: &ArduPilotSection, file: &str) -> Result<(), ConfigError> {
    let bad = |field: &str, v: f64, rule: &str| invalid(file, field, v, rule);
    let outputs = [
        ("swash1", &s.swash1),
        ("swash2", &s.swash2),
        ("swash3", &s.swash3),
        ("tail", &s.tail),
        ("throttle", &s.throttle),
    ];
    for (i, (name, o)) in outputs.iter().enumerate() {
        if !(1..=32).contains(&o.channel) {
            return bad(
                &format!("{name}.channel"),
                f64::from(o.channel),
                "an output number in 1 ..= 32 (SERVO1 … SERVO32)",
            );
        }
        for (other, p) in &outputs[..i] {
            if p.channel == o.channel {
                return bad(
                    &format!("{name}.channel"),
                    f64::from(o.channel),
                    &format!("already the channel of `ardupilot.{other}`"),
                );
            }
        }
        let swash = name.starts_with("swash");
        if swash && (o.min_us != 1000 || o.max_us != 2000) {
            let (f, v) = if o.min_us != 1000 {
                ("min_us", o.min_us)
            } else {
                ("max_us", o.max_us)
            };
            return bad(
                &format!("{name}.{f}"),
                f64::from(v),
                "1000 / 2000: ArduPilot forces a swash servo's endpoints to 1000 … 2000 µs (AP_MotorsHeli_Swash::add_servo_raw)",
            );
        }
        if !(500..=2500).contains(&o.min_us) {
            return bad(
                &format!("{name}.min_us"),
                f64::from(o.min_us),
                "in 500 ..= 2500 µs",
            );
        }
        if !(500..=2500).contains(&o.max_us) || o.max_us <= o.min_us {
            return bad(
                &format!("{name}.max_us"),
                f64::from(o.max_us),
                "in 500 ..= 2500 µs and above min_us",
            );
        }
        if *name != "throttle" && !(o.min_us < o.trim_us && o.trim_us < o.max_us) {
            return bad(
                &format!("{name}.trim_us"),
                f64::from(o.trim_us),
                "strictly between min_us and max_us",
            );
        }
    }
    Ok(())
}

/// The collective, tail, engine and H3 numbers.
fn check_numbers(s: &ArduPilotSection, file: &str) -> Result<(), ConfigError> {
    let bad = |field: &str, v: f64, rule: &str| invalid(file, field, v, rule);
    if !(1000..=2000).contains(&s.collective_min_us) {
        return bad(
            "collective_min_us",
            f64::from(s.collective_min_us),
            "in 1000 ..= 2000 µs (H_COL_MIN)",
        );
    }
    if !(1000..=2000).contains(&s.collective_max_us) || s.collective_max_us <= s.collective_min_us {
        return bad(
            "collective_max_us",
            f64::from(s.collective_max_us),
            "in 1000 ..= 2000 µs and above collective_min_us (H_COL_MAX)",
        );
    }
    for (f, v) in [
        ("collective_pitch_min_deg", s.collective_pitch_min_deg),
        ("collective_pitch_max_deg", s.collective_pitch_max_deg),
        ("tail_pitch_at_yaw_min_deg", s.tail_pitch_at_yaw_min_deg),
        ("tail_pitch_at_yaw_max_deg", s.tail_pitch_at_yaw_max_deg),
    ] {
        if !(v.is_finite() && v.abs() <= 45.0) {
            return bad(f, v, "a blade pitch in −45 … 45 deg");
        }
    }
    if s.collective_pitch_max_deg <= s.collective_pitch_min_deg {
        return bad(
            "collective_pitch_max_deg",
            s.collective_pitch_max_deg,
            "above collective_pitch_min_deg",
        );
    }
    if s.tail_pitch_at_yaw_max_deg == s.tail_pitch_at_yaw_min_deg {
        return bad(
            "tail_pitch_at_yaw_max_deg",
            s.tail_pitch_at_yaw_max_deg,
            "different from tail_pitch_at_yaw_min_deg",
        );
    }
    if !(s.cyclic_scale.is_finite() && s.cyclic_scale > 0.0 && s.cyclic_scale <= 10.0) {
        return bad("cyclic_scale", s.cyclic_scale, "in (0, 10]");
    }
    if !(s.engine_on_above.is_finite() && s.engine_on_above > 0.0 && s.engine_on_above < 1.0) {
        return bad(
            "engine_on_above",
            s.engine_on_above,
            "in (0, 1): a fraction of the throttle output's range",
        );
    }
    for (i, v) in s.h3_servo_positions_deg.iter().enumerate() {
        if !(v.is_finite() && v.abs() <= 180.0) {
            return bad(
                &format!("h3_servo_positions_deg[{i}]"),
                *v,
                "in −180 … 180 deg (H_SW_H3_SVn_POS)",
            );
        }
    }
    if !(s.h3_phase_angle_deg.is_finite() && s.h3_phase_angle_deg.abs() <= 30.0) {
        return bad(
            "h3_phase_angle_deg",
            s.h3_phase_angle_deg,
            "in −30 … 30 deg (H_SW_H3_PHANG, ArduPilot's arming check)",
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with(edit: &str, replace: &str) -> Result<ArduPilotMap, ConfigError> {
        assert!(BERGEN_TWIN_TOML.contains(edit), "{edit}");
        let text = BERGEN_TWIN_TOML.replacen(edit, replace, 1);
        let s = ArduPilotSection::from_toml_str(&text, "h.toml")?;
        ArduPilotMap::new(s, &Params::bergen_twin(), "h.toml")
    }

    fn field_of(e: &ConfigError) -> String {
        match e {
            ConfigError::Invalid { file, field, .. } => {
                assert_eq!(file, "h.toml");
                field.clone()
            }
            other => panic!("{other}"),
        }
    }

    #[test]
    fn the_example_is_valid() {
        assert!(with("channel = 1", "channel = 1").is_ok());
    }

    #[test]
    fn errors_name_the_file_and_the_field() {
        let cases = [
            ("channel = 2", "channel = 1", "ardupilot.swash2.channel"),
            ("channel = 8", "channel = 33", "ardupilot.throttle.channel"),
            (
                "channel = 1\n",
                "channel = 1\nmin_us = 900\n",
                "ardupilot.swash1.min_us",
            ),
            (
                "trim_us = 1500                   # SERVO4_TRIM",
                "trim_us = 2100",
                "ardupilot.tail.trim_us",
            ),
            (
                "collective_max_us = 1750",
                "collective_max_us = 1200",
                "ardupilot.collective_max_us",
            ),
            (
                "collective_pitch_max_deg = 12.0",
                "collective_pitch_max_deg = -5.0",
                "ardupilot.collective_pitch_max_deg",
            ),
            (
                "tail_pitch_at_yaw_max_deg = 14.4",
                "tail_pitch_at_yaw_max_deg = 90.0",
                "ardupilot.tail_pitch_at_yaw_max_deg",
            ),
            (
                "engine_on_above = 0.1",
                "engine_on_above = 1.0",
                "ardupilot.engine_on_above",
            ),
            (
                "h3_phase_angle_deg = 0.0",
                "h3_phase_angle_deg = 45.0",
                "ardupilot.h3_phase_angle_deg",
            ),
            (
                "cyclic_scale = 1.0",
                "cyclic_scale = 0.0",
                "ardupilot.cyclic_scale",
            ),
        ];
        for (edit, replace, field) in cases {
            let e = with(edit, replace).unwrap_err();
            assert_eq!(field_of(&e), field, "{e}");
            assert!(e.to_string().starts_with("h.toml: "), "{e}");
        }
    }

    #[test]
    fn a_singular_h3_mixer_and_unknown_fields_are_refused() {
        let e = with(
            "swash_type = \"h3_120\"",
            "swash_type = \"h3\"\nh3_servo_positions_deg = [0.0, 0.0, 0.0]",
        );
        // (the default positions line follows: a duplicate key is a parse error)
        assert!(e.is_err());
        let text = BERGEN_TWIN_TOML
            .replacen("swash_type = \"h3_120\"", "swash_type = \"h3\"", 1)
            .replacen("[-60.0, 60.0, 180.0]", "[10.0, 10.0, 10.0]", 1);
        let s = ArduPilotSection::from_toml_str(&text, "h.toml").unwrap();
        let e = ArduPilotMap::new(s, &Params::bergen_twin(), "h.toml").unwrap_err();
        assert_eq!(field_of(&e), "ardupilot.h3_servo_positions_deg");
        let e = with("cyclic_scale = 1.0", "cyclic_scale = 1.0\nswash_typo = 1").unwrap_err();
        assert!(
            matches!(&e, ConfigError::Parse { file, message } if file == "h.toml" && message.contains("swash_typo")),
            "{e}"
        );
        let e = with("\"h3_120\"", "\"h4_90\"").unwrap_err();
        assert!(matches!(e, ConfigError::Parse { .. }), "{e}");
    }

    #[test]
    fn the_generic_h3_at_the_h3_120_positions_is_the_h3_120() {
        let text = BERGEN_TWIN_TOML.replacen("swash_type = \"h3_120\"", "swash_type = \"h3\"", 1);
        let s = ArduPilotSection::from_toml_str(&text, "h.toml").unwrap();
        let generic = ArduPilotMap::new(s, &Params::bergen_twin(), "h.toml").unwrap();
        let s = ArduPilotSection::from_toml_str(BERGEN_TWIN_TOML, "h.toml").unwrap();
        let h3_120 = ArduPilotMap::new(s, &Params::bergen_twin(), "h.toml").unwrap();
        let (a, _) = generic.mixer();
        let (b, _) = h3_120.mixer();
        for i in 0..3 {
            for j in 0..3 {
                assert!((a[i][j] - b[i][j]).abs() < 1e-12);
            }
        }
        // ArduPilot's factors: left servo +0.3897 roll, +0.225 pitch; rear −0.45 pitch
        assert!((b[0][0] - 0.45 * 0.866_025_403_784_438_6).abs() < 1e-12);
        assert!((b[0][1] - 0.225).abs() < 1e-12);
        assert!((b[2][1] + 0.45).abs() < 1e-12 && b[2][0].abs() < 1e-12);
    }

    #[test]
    fn h1_and_h3_140_invert_their_mixers() {
        for kind in ["h1", "h3_140"] {
            let text = BERGEN_TWIN_TOML.replacen("\"h3_120\"", &format!("\"{kind}\""), 1);
            let s = ArduPilotSection::from_toml_str(&text, "h.toml").unwrap();
            let m = ArduPilotMap::new(s, &Params::bergen_twin(), "h.toml").unwrap();
            let (rows, off) = m.mixer();
            let (roll, pitch, c) = (0.2, -0.3, 0.6);
            let mut pwm = [0u16; 16];
            for i in 0..3 {
                let o = rows[i][0] * roll + rows[i][1] * pitch + rows[i][2] * c + off[i];
                pwm[i] = (1500.0 + 500.0 * (2.0 * o - 1.0)) as u16;
            }
            pwm[3] = 1500;
            pwm[7] = 1000;
            let d = m.decode(&pwm).outputs;
            assert!((d.roll - roll).abs() < 3e-3, "{kind}: {d:?}");
            assert!((d.pitch - pitch).abs() < 3e-3, "{kind}: {d:?}");
            assert!((d.collective - c).abs() < 2e-3, "{kind}: {d:?}");
        }
    }
}
