//! The on-board mission: where each control step's reference comes from
//! (a scenario's `[[reference]]` schedule, one held reference, or the
//! ground station's navigator) and the flight-test excitation flown on top
//! of the law (`[[excitation]]`, as in scenarios), with what the control
//! task did last step as the navigator sees it.

use crate::control::ControlTask;
use crate::safety::Mode;
use helicon_core::{Reference, Telemetry};
use helicon_gcs::link::{FlightMode, OperatorTexts, Vehicle, VehicleEvent};
use helicon_gcs::navigator::{Events, NavigatorConfig};
use helicon_setup::excitation::Excitations;
use helicon_setup::plan::ReferenceSchedule;
use nalgebra::Vector3;

/// Where the references come from.
pub enum References {
    /// A schedule of reference changes (a scenario's `[[reference]]`).
    Schedule(Box<ReferenceSchedule>),
    /// One constant reference.
    Hold(Reference),
    /// The ground station's navigator (the vehicle half of `helicon-gcs`):
    /// each step it takes the operator's commands from the server thread's
    /// ring (never blocking), runs on the last step's telemetry and arms or
    /// disarms the control task when the operator (or a landing) asks.
    Ground(Box<Vehicle>),
}

impl std::fmt::Debug for References {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            References::Schedule(_) => f.write_str("References::Schedule"),
            References::Hold(r) => write!(f, "References::Hold({r:?})"),
            References::Ground(_) => f.write_str("References::Ground"),
        }
    }
}

/// The mission: the references and the flight-test excitation.
///
/// The excitation is the sum of the `[[excitation]]` inputs, in servo
/// units, added to the law's command before saturation. Its clock starts
/// when the control task first enters `auto` (on-board time 0 in SITL,
/// which starts armed, so SITL's excitation is `helicon sim`'s sample for
/// sample); it is applied only in `auto`, and leaving `auto` for any reason
/// (the pilot's switch, a failsafe, disarming) ends it for the rest of the
/// flight: an identification run is not resumed halfway
/// ([`ControlTask::step_with`]).
#[derive(Debug)]
pub struct Mission {
    references: References,
    excitation: Excitations,
    news: Option<NavigatorNews>,
}

/// What the ground station's navigator did in a sample that the flight
/// log records: its events (mode changes, items reached, link lost, the
/// fence) and a tuning the operator set (before, after).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NavigatorNews {
    /// The navigator's events.
    pub events: Events,
    /// The tuning set, before and after.
    pub config_change: Option<(NavigatorConfig, NavigatorConfig)>,
    /// The ground-station server's own texts to the operator (replies,
    /// refusals).
    pub texts: OperatorTexts,
}

/// What the control task did last step, as the ground station's navigator
/// sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LastStep {
    /// The last telemetry the flight computer produced (`None` before the
    /// first).
    pub telemetry: Option<Telemetry>,
    /// The mode then.
    pub mode: Mode,
    /// The servo commands then.
    pub servo: helicon_core::state::Input,
    /// Its compute time over the control period.
    pub load: f64,
}

/// The flight software's mode as the ground station reports it.
pub fn flight_mode(m: Mode) -> FlightMode {
    FlightMode {
        name: m.as_str(),
        law_flies: matches!(m, Mode::Auto | Mode::Hold | Mode::Descent),
    }
}

impl Mission {
    /// A mission flying `references`, without excitation.
    pub fn new(references: References) -> Self {
        Mission {
            references,
            excitation: Excitations::default(),
            news: None,
        }
    }

    /// The same mission with a flight-test excitation.
    #[must_use]
    pub fn with_excitation(mut self, excitation: Excitations) -> Self {
        self.excitation = excitation;
        self
    }

    /// The references.
    pub fn references(&self) -> &References {
        &self.references
    }

    /// The excitation schedule (empty without `[[excitation]]`).
    pub fn excitation(&self) -> &Excitations {
        &self.excitation
    }

    /// The reference at on-board time `t_s` of a time-scheduled mission;
    /// `None` for [`References::Ground`] (its reference depends on the
    /// telemetry: [`Mission::step`]). No allocation.
    pub fn at(&self, t_s: f64) -> Option<Reference> {
        match &self.references {
            References::Schedule(s) => {
                let r = s.at(t_s);
                Some(Reference {
                    velocity_ned_m_s: Vector3::new(r[0], r[1], r[2]),
                    yaw_rad: r[3],
                })
            }
            References::Hold(r) => Some(*r),
            References::Ground(_) => None,
        }
    }

    /// This step's reference at on-board time `t_s`; the ground station's
    /// navigator reads `last` and arms or disarms `task` (taking effect in
    /// this very step). No allocation in the steady state.
    pub fn step(&mut self, t_s: f64, last: &LastStep, task: &mut ControlTask) -> Reference {
        match &mut self.references {
            References::Ground(v) => {
                if let Some(l) = task.landing() {
                    v.set_ground(l.ground_state());
                }
                // the flight software disarmed by itself (after a landing,
                // the pilot's kill) or refused the arming (off the ground)
                if v.armed() && !task.armed() {
                    v.disarmed(t_s);
                }
                let out = v.step(
                    t_s,
                    last.telemetry.as_ref(),
                    flight_mode(last.mode),
                    &last.servo,
                    last.load,
                );
                if let Some(a) = out.arm
                    && !task.set_armed(a)
                {
                    v.notify(t_s, VehicleEvent::Warning("arm refused: not on the ground"));
                }
                if out.events.iter().next().is_some()
                    || out.config_change.is_some()
                    || !out.texts.is_empty()
                {
                    self.news = Some(NavigatorNews {
                        events: out.events,
                        config_change: out.config_change,
                        texts: out.texts,
                    });
                }
                out.reference
            }
            References::Schedule(_) | References::Hold(_) => self.at(t_s).unwrap_or_default(),
        }
    }

    /// What the navigator did since the last call that the flight log
    /// records (`None`: nothing, or no ground station).
    pub fn take_news(&mut self) -> Option<NavigatorNews> {
        self.news.take()
    }

    /// Tell the ground station's operator (a status text), when the
    /// mission is the ground station's; otherwise nothing. Never blocks.
    pub fn notify(&mut self, t_s: f64, event: VehicleEvent) {
        if let References::Ground(v) = &mut self.references {
            v.notify(t_s, event);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use helicon_gcs::link::{Downlink, channel};
    use helicon_gcs::navigator::{Navigator, NavigatorConfig};

    /// A warning reaches the ground station's server ring (its status
    /// text); a mission without a ground station ignores it.
    #[test]
    fn warnings_go_to_the_ground_station() {
        let (vehicle_end, mut server_end) = channel(8);
        let nav = Navigator::new(NavigatorConfig::default()).unwrap();
        let mut m = Mission::new(References::Ground(Box::new(Vehicle::new(
            nav,
            vehicle_end,
            1,
        ))));
        m.notify(
            2.5,
            VehicleEvent::Warning("IMU health: vibration above threshold"),
        );
        assert_eq!(
            server_end.downlink.pop().ok(),
            Some(Downlink::Event(
                2.5,
                VehicleEvent::Warning("IMU health: vibration above threshold")
            ))
        );
        let mut hold = Mission::new(References::Hold(Reference::default()));
        hold.notify(2.5, VehicleEvent::Warning("x"));
        assert!(hold.excitation().is_empty());
    }
}
