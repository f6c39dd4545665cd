//! Take-off and landing failures of a campaign whose scenario has a
//! `[ground]` section: the criteria (the campaign file's `[landing]`
//! table, with defaults), each run's classification, and the failure
//! rate's confidence interval.
//!
//! ```toml
//! [landing]
//! max_touchdown_vertical_speed_m_s = 2.0     # hard landing (14 CFR 27.725's 8-inch drop)
//! max_touchdown_horizontal_speed_m_s = 0.5   # a skid caught while sliding sideways
//! max_tilt_on_ground_rad = 0.13962634015954636 # 8°: dynamic rollover, a skid loaded
//! max_liftoff_delay_s = 3.0                  # lift-off this long after the take-off ramp began
//! max_liftoff_drift_m = 0.25                 # slide on the skids before lift-off
//! max_touchdown_offset_m = 1.0               # landing point from the lift-off point
//! max_touchdown_drift_m = 0.25               # slide on the skids after touchdown
//! ```
//!
//! A limit may be `inf` (TOML's infinity): that criterion is off. The
//! reasons for the defaults are in `docs/monte-carlo.md` ("Take-offs and
//! landings").

use super::{GROUND_METRIC_NAMES, METRIC_NAMES, RunOutcome, RunRecord};
use crate::scenario::ScenarioError;
use helicon_model::Params;
use serde::{Deserialize, Serialize};

/// The campaign file's `[landing]` table: the limits of a take-off and a
/// landing (each optional; a missing one takes its default).
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LandingSection {
    /// See [`LandingCriteria::max_touchdown_vertical_speed_m_s`].
    pub max_touchdown_vertical_speed_m_s: Option<f64>,
    /// See [`LandingCriteria::max_touchdown_horizontal_speed_m_s`].
    pub max_touchdown_horizontal_speed_m_s: Option<f64>,
    /// See [`LandingCriteria::max_tilt_on_ground_rad`].
    pub max_tilt_on_ground_rad: Option<f64>,
    /// See [`LandingCriteria::max_liftoff_delay_s`].
    pub max_liftoff_delay_s: Option<f64>,
    /// See [`LandingCriteria::max_liftoff_drift_m`].
    pub max_liftoff_drift_m: Option<f64>,
    /// See [`LandingCriteria::max_touchdown_offset_m`].
    pub max_touchdown_offset_m: Option<f64>,
    /// See [`LandingCriteria::max_touchdown_drift_m`].
    pub max_touchdown_drift_m: Option<f64>,
}

/// The limits a run's take-off and landing are judged by (resolved:
/// defaults filled in, the scenario's take-off time copied). Written in
/// `manifest.json` and `stats.json`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LandingCriteria {
    /// Hard landing: the vertical speed (down) at touchdown above this (m/s).
    pub max_touchdown_vertical_speed_m_s: f64,
    /// The horizontal speed at touchdown above this (m/s).
    pub max_touchdown_horizontal_speed_m_s: f64,
    /// Tip-over: the airframe's tilt from the ground's normal with a skid
    /// loaded above this (rad).
    pub max_tilt_on_ground_rad: f64,
    /// No lift-off within this time after the take-off ramp began (s).
    pub max_liftoff_delay_s: f64,
    /// The slide on the skids from the start to lift-off above this (m).
    pub max_liftoff_drift_m: f64,
    /// The touchdown farther than this from the lift-off point (m).
    pub max_touchdown_offset_m: f64,
    /// The slide on the skids after touchdown above this (m).
    pub max_touchdown_drift_m: f64,
    /// The scenario's `ground.takeoff_s` (s; not a campaign-file field).
    pub takeoff_s: f64,
}

/// 8°, the upper end of the critical (dynamic) rollover angle.
const DEFAULT_TILT_RAD: f64 = 8.0 * std::f64::consts::PI / 180.0;

impl LandingSection {
    /// The criteria: the limits given, the defaults for the others, with
    /// the scenario's take-off time; `file` names the campaign file in errors.
    pub fn resolve(&self, file: &str, takeoff_s: f64) -> Result<LandingCriteria, ScenarioError> {
        let pick = |field: &str, v: Option<f64>, default: f64| -> Result<f64, ScenarioError> {
            let x = v.unwrap_or(default);
            // NaN fails both; +inf (criterion off) passes
            if x > 0.0 && x != f64::NEG_INFINITY {
                Ok(x)
            } else {
                Err(ScenarioError::invalid(
                    file,
                    format!("landing.{field}"),
                    x,
                    "must be > 0 (or inf: the criterion off)",
                ))
            }
        };
        Ok(LandingCriteria {
            max_touchdown_vertical_speed_m_s: pick(
                "max_touchdown_vertical_speed_m_s",
                self.max_touchdown_vertical_speed_m_s,
                2.0,
            )?,
            max_touchdown_horizontal_speed_m_s: pick(
                "max_touchdown_horizontal_speed_m_s",
                self.max_touchdown_horizontal_speed_m_s,
                0.5,
            )?,
            max_tilt_on_ground_rad: pick(
                "max_tilt_on_ground_rad",
                self.max_tilt_on_ground_rad,
                DEFAULT_TILT_RAD,
            )?,
            max_liftoff_delay_s: pick("max_liftoff_delay_s", self.max_liftoff_delay_s, 3.0)?,
            max_liftoff_drift_m: pick("max_liftoff_drift_m", self.max_liftoff_drift_m, 0.25)?,
            max_touchdown_offset_m: pick(
                "max_touchdown_offset_m",
                self.max_touchdown_offset_m,
                1.0,
            )?,
            max_touchdown_drift_m: pick("max_touchdown_drift_m", self.max_touchdown_drift_m, 0.25)?,
            takeoff_s,
        })
    }
}

/// One way a take-off or landing fails.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LandingFailure {
    /// Not flown: an invalid draw or an error before or after the flight.
    NotFlown,
    /// The flight stopped early (attitude, rate, model, …).
    Diverged,
    /// No lift-off within `max_liftoff_delay_s` of the take-off ramp's start,
    /// or one the on-board program never detected.
    NoLiftoff,
    /// Slid more than `max_liftoff_drift_m` before lift-off.
    LiftoffDrift,
    /// Tilted more than `max_tilt_on_ground_rad` with a skid loaded.
    TipOver,
    /// Completed without touching down after `ground.land_after_s`.
    NoTouchdown,
    /// Touched down faster than `max_touchdown_vertical_speed_m_s`.
    HardLanding,
    /// Touched down moving sideways faster than `max_touchdown_horizontal_speed_m_s`.
    TouchdownSideways,
    /// Touched down farther than `max_touchdown_offset_m` from the lift-off point.
    TouchdownOffset,
    /// Slid more than `max_touchdown_drift_m` after touchdown.
    TouchdownDrift,
}

impl LandingFailure {
    /// Every criterion, in the order of the report.
    pub const ALL: [LandingFailure; 10] = [
        LandingFailure::NotFlown,
        LandingFailure::Diverged,
        LandingFailure::NoLiftoff,
        LandingFailure::LiftoffDrift,
        LandingFailure::TipOver,
        LandingFailure::NoTouchdown,
        LandingFailure::HardLanding,
        LandingFailure::TouchdownSideways,
        LandingFailure::TouchdownOffset,
        LandingFailure::TouchdownDrift,
    ];

    /// The word of `runs.csv`'s `landing` column and `stats.json`.
    pub fn as_str(self) -> &'static str {
        match self {
            LandingFailure::NotFlown => "not_flown",
            LandingFailure::Diverged => "diverged",
            LandingFailure::NoLiftoff => "no_liftoff",
            LandingFailure::LiftoffDrift => "liftoff_drift",
            LandingFailure::TipOver => "tip_over",
            LandingFailure::NoTouchdown => "no_touchdown",
            LandingFailure::HardLanding => "hard_landing",
            LandingFailure::TouchdownSideways => "touchdown_sideways",
            LandingFailure::TouchdownOffset => "touchdown_offset",
            LandingFailure::TouchdownDrift => "touchdown_drift",
        }
    }

    fn bit(self) -> u16 {
        1 << (self as u16)
    }
}

/// The criteria a run failed (a set of [`LandingFailure`]; empty: a good
/// take-off and landing).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct LandingVerdict(u16);

impl LandingVerdict {
    /// No criterion failed.
    pub fn ok(self) -> bool {
        self.0 == 0
    }

    /// Did it fail `f`?
    pub fn has(self, f: LandingFailure) -> bool {
        self.0 & f.bit() != 0
    }

    /// The criteria failed, in report order.
    pub fn failures(self) -> impl Iterator<Item = LandingFailure> {
        LandingFailure::ALL
            .into_iter()
            .filter(move |f| self.has(*f))
    }

    /// `ok`, or the failed criteria joined by `;` (`hard_landing;tip_over`).
    pub fn words(self) -> String {
        if self.ok() {
            return "ok".into();
        }
        self.failures()
            .map(LandingFailure::as_str)
            .collect::<Vec<_>>()
            .join(";")
    }
}

/// Index of a ground metric in a ground campaign's record metrics.
pub(super) fn ground_index(name: &str) -> usize {
    METRIC_NAMES.len()
        + GROUND_METRIC_NAMES
            .iter()
            .position(|n| *n == name)
            .unwrap_or(GROUND_METRIC_NAMES.len())
}

impl LandingCriteria {
    /// Classify a run of a ground campaign (its metrics hold the ground
    /// metrics after [`METRIC_NAMES`], in [`GROUND_METRIC_NAMES`] order).
    ///
    /// A run not flown fails `not_flown`, a flight that stopped early
    /// `diverged`; every criterion with a value is checked as well (a
    /// tip-over that ended the flight is `diverged` and `tip_over`). The
    /// criteria of something missing (`no_liftoff`, `no_touchdown`) apply to
    /// completed flights only.
    pub fn classify(&self, r: &RunRecord) -> LandingVerdict {
        let mut v = 0u16;
        match r.outcome() {
            RunOutcome::Completed => {}
            RunOutcome::Diverged => v |= LandingFailure::Diverged.bit(),
            RunOutcome::Invalid | RunOutcome::Error => {
                // a completed flight with a non-finite metric still has its ground values
                if r.t_end_s <= 0.0 {
                    return LandingVerdict(LandingFailure::NotFlown.bit());
                }
                v |= LandingFailure::NotFlown.bit();
            }
        }
        let g = |name: &str| r.metrics.get(ground_index(name)).copied().flatten();
        let over = |x: Option<f64>, limit: f64| x.is_some_and(|x| x > limit);
        let completed = r.completed();
        let mut set = |f: LandingFailure, fails: bool| {
            if fails {
                v |= f.bit();
            }
        };
        let liftoff = g("liftoff_time_s");
        // the delay from the on-board take-off's start (the rotor at speed,
        // in auto, a climb asked), or from the operator's `takeoff_s` when
        // it never began
        let takeoff = g("takeoff_start_s").unwrap_or(self.takeoff_s);
        // a lift-off the on-board program never detected (a hover in ground
        // effect below `liftoff_height_m`, the take-off then withdrawn or
        // given up) is none either
        let detected = g("liftoff_detected_s");
        set(
            LandingFailure::NoLiftoff,
            (completed && (liftoff.is_none() || detected.is_none()))
                || over(liftoff, takeoff + self.max_liftoff_delay_s),
        );
        set(
            LandingFailure::LiftoffDrift,
            over(g("liftoff_drift_m"), self.max_liftoff_drift_m),
        );
        set(
            LandingFailure::TipOver,
            over(g("max_tilt_on_ground_rad"), self.max_tilt_on_ground_rad),
        );
        set(
            LandingFailure::NoTouchdown,
            completed && g("touchdown_time_s").is_none(),
        );
        set(
            LandingFailure::HardLanding,
            over(
                g("touchdown_vertical_speed_m_s"),
                self.max_touchdown_vertical_speed_m_s,
            ),
        );
        set(
            LandingFailure::TouchdownSideways,
            over(
                g("touchdown_horizontal_speed_m_s"),
                self.max_touchdown_horizontal_speed_m_s,
            ),
        );
        set(
            LandingFailure::TouchdownOffset,
            over(g("touchdown_offset_m"), self.max_touchdown_offset_m),
        );
        set(
            LandingFailure::TouchdownDrift,
            over(g("touchdown_drift_m"), self.max_touchdown_drift_m),
        );
        LandingVerdict(v)
    }
}

/// The two-sided 95 % normal quantile, z = Φ⁻¹(0.975).
pub const Z_95: f64 = 1.959_963_984_540_054;

/// Wilson's score interval of a binomial proportion, `failed` of `runs`,
/// at the normal quantile `z` (`Z_95` for 95 %): (low, high), within
/// [0, 1]. `runs = 0` gives (0, 1).
pub fn wilson_interval(failed: usize, runs: usize, z: f64) -> (f64, f64) {
    if runs == 0 {
        return (0.0, 1.0);
    }
    let n = runs as f64;
    let p = failed as f64 / n;
    let z2 = z * z;
    let centre = (p + z2 / (2.0 * n)) / (1.0 + z2 / n);
    let half = z / (1.0 + z2 / n) * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt();
    // at 0 or `runs` failures the bound is exactly 0 or 1
    let lo = if failed == 0 { 0.0 } else { centre - half };
    let hi = if failed == runs { 1.0 } else { centre + half };
    (lo.clamp(0.0, 1.0), hi.clamp(0.0, 1.0))
}

/// The sideways speed (m/s) at which a skid that catches tips the airframe
/// over it with the rotor stopped: the airframe's angular momentum about
/// the skid, m v h, must lift the CM over it,
/// (m v h)² / (2 I) > m g (√(h² + b²) − h), with I = Ixx + m (h² + b²),
/// h = `landing_gear.contact_z_m`, b = `landing_gear.contact_y_half_m`.
/// With the rotor carrying weight the restoring moment shrinks, so the
/// campaign's default limit is a third of it (see the docs).
pub fn caught_skid_tip_over_speed_m_s(p: &Params) -> f64 {
    let m = p.body.mass_kg;
    let g = p.environment.g_m_s2;
    let h = p.landing_gear.contact_z_m;
    let b = p.landing_gear.contact_y_half_m;
    let r = h.hypot(b);
    let i = p.body.ixx_kg_m2 + m * r * r;
    (2.0 * g * (r - h) * i / m).sqrt() / h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_matches_its_closed_form_values() {
        // 0 of 20: upper bound z²/(n + z²)
        let (lo, hi) = wilson_interval(0, 20, Z_95);
        assert_eq!(lo, 0.0);
        assert!(
            (hi - Z_95 * Z_95 / (20.0 + Z_95 * Z_95)).abs() < 1e-15,
            "{hi}"
        );
        // 10 of 100: the textbook (0.0552, 0.1744)
        let (lo, hi) = wilson_interval(10, 100, Z_95);
        assert!(
            (lo - 0.05523).abs() < 5e-5 && (hi - 0.17437).abs() < 5e-5,
            "{lo} {hi}"
        );
        assert_eq!(wilson_interval(5, 5, Z_95).1, 1.0);
    }

    #[test]
    fn the_caught_skid_speed_of_the_bergen_twin() {
        let v = caught_skid_tip_over_speed_m_s(&Params::bergen_twin());
        assert!((v - 1.599).abs() < 0.005, "{v}");
    }
}
