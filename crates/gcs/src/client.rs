//! The ground-station side of the link (`helicon gcs`): what it knows of
//! each vehicle it hears ([`Fleet`]), and one operation at a time as a
//! state machine fed the vehicle's messages and the time ([`Operation`]):
//! no sockets, so each microservice is testable on its own.
//!
//! - **Commands** (`COMMAND_LONG`): resent every [`COMMAND_RETRY_S`] with
//!   `confirmation` incremented until the `COMMAND_ACK` of the command
//!   arrives (`MAV_RESULT_IN_PROGRESS` waits on;
//!   `MAV_RESULT_TEMPORARILY_REJECTED`, "retrying later should work" in
//!   MAVLink's words — a vehicle whose navigation is still aligning — is
//!   sent again as a new command every [`COMMAND_RETRY_S`] until the
//!   timeout); any other result but `MAV_RESULT_ACCEPTED` is a refusal.
//! - **Mission upload**: `MISSION_COUNT`, then the vehicle drives — each
//!   `MISSION_REQUEST_INT` (or `MISSION_REQUEST`) is answered with its item
//!   — until its `MISSION_ACK`. The count is resent while no request came.
//! - **Mission download**: `MISSION_REQUEST_LIST`, each item requested in
//!   turn (`MISSION_REQUEST_INT`) and requested again after
//!   [`MISSION_RETRY_S`] without it, then `MISSION_ACK` accepted.
//! - **Parameters**: `PARAM_REQUEST_READ` / `PARAM_SET` resent until the
//!   `PARAM_VALUE` of the name arrives; a set answered with another value
//!   is a refusal.
//! - **Waits** on the state the vehicle reports.
//!
//! Every operation is bounded by its timeout. Times are seconds of the
//! caller's clock (the wall clock in `helicon gcs`).

// the superseded MISSION_REQUEST is still answered
#![allow(deprecated)]

use crate::mission_item::item_float;
use crate::modes;
use mavlink::dialects::common::*;
use mavlink::{MavHeader, MessageData};
use std::collections::BTreeMap;

/// The ground station's system id (as QGroundControl's).
pub const GCS_SYSTEM_ID: u8 = 255;
/// The ground station's component id.
pub const GCS_COMPONENT_ID: u8 = MavComponent::MAV_COMP_ID_MISSIONPLANNER as u8;
/// A vehicle whose heartbeat is older than this (s) is shown as quiet.
pub const HEARTBEAT_SILENCE_S: f64 = 3.0;
/// A command, parameter request or mission count without an answer this
/// long (s) is sent again.
pub const COMMAND_RETRY_S: f64 = 1.0;
/// A download's item request without its item this long (s) is sent again
/// (the mission microservice's default item timeout).
pub const MISSION_RETRY_S: f64 = 1.5;
/// Sends of one message (the first and its repeats) before giving up.
pub const MAX_SENDS: u8 = 5;

/// Why an operation failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ClientError {
    /// The vehicle answered with a refusal (the result's name).
    #[error("refused: {0}")]
    Refused(String),
    /// No (complete) answer within the time allowed.
    #[error("timed out after {timeout_s} s: {waiting_for}")]
    Timeout {
        /// The timeout (s).
        timeout_s: f64,
        /// What was still awaited.
        waiting_for: String,
    },
    /// A parameter set answered with another value.
    #[error("refused: {name} stays {value}")]
    ParamRefused {
        /// The parameter.
        name: String,
        /// Its value now.
        value: f32,
    },
    /// The vehicle said it has no such parameter.
    #[error("no parameter {0}")]
    NoParam(String),
    /// A parameter name longer than MAVLink's 16 characters.
    #[error("parameter name `{0}`: longer than 16 characters")]
    ParamName(String),
    /// The mission is larger than MAVLink can count.
    #[error("{0} mission items: more than MAVLink counts")]
    TooManyItems(usize),
}

/// What one vehicle told last.
#[derive(Debug, Clone, Default)]
pub struct VehicleView {
    /// Its last heartbeat.
    pub heartbeat: Option<HEARTBEAT_DATA>,
    /// When it arrived (s).
    pub heartbeat_s: Option<f64>,
    /// Attitude.
    pub attitude: Option<ATTITUDE_DATA>,
    /// Global position.
    pub position: Option<GLOBAL_POSITION_INT_DATA>,
    /// Local position.
    pub local: Option<LOCAL_POSITION_NED_DATA>,
    /// The land detector's state.
    pub landed: Option<MavLandedState>,
    /// The mission's state (MISSION_CURRENT's last).
    pub mission_state: Option<MissionState>,
    /// The progress of the mission flown now ([`MissionProgress`]).
    pub mission: MissionProgress,
    /// Home's altitude AMSL (m).
    pub home_amsl_m: Option<f64>,
    /// Messages received.
    pub received: u64,
    /// Messages lost (sequence gaps per component).
    pub lost: u64,
    last_seq: BTreeMap<u8, u8>,
}

/// The mission this station waits for, as MAVLink tells it.
///
/// A mission begins with an upload or a `MAV_CMD_MISSION_START` accepted
/// from this station ([`Fleet::on_finished`]), or, once the last one is
/// done, with a `MISSION_CURRENT` that is not `COMPLETE` on another item
/// or another mission (flown again or replaced from elsewhere). It is done
/// when, after it began, `MISSION_ITEM_REACHED` names its last item, or
/// `MISSION_CURRENT` says `COMPLETE` after having said otherwise: a
/// `COMPLETE` left over from an earlier mission never ends a later one.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MissionProgress {
    /// Missions begun so far (the current one's number; 0: none seen
    /// begin).
    pub begun: u32,
    /// Items in the current mission (the count uploaded, or
    /// `MISSION_CURRENT`'s total).
    pub total: Option<u16>,
    /// The current mission was heard not complete since it began.
    pub heard_unfinished: bool,
    /// The current mission is done.
    pub done: bool,
}

impl MissionProgress {
    /// A new mission begins (`total` items, when known).
    pub fn begin(&mut self, total: Option<u16>) {
        self.begun = self.begun.wrapping_add(1);
        if total.is_some() {
            self.total = total;
        }
        self.heard_unfinished = false;
        self.done = false;
    }

    /// A `MISSION_CURRENT`: item `seq` of `total` in `state`.
    pub fn on_current(&mut self, seq: u16, total: u16, state: MissionState) {
        if state == MissionState::MISSION_STATE_COMPLETE {
            // a COMPLETE not preceded by this mission's running is an
            // earlier mission's
            self.done |= self.heard_unfinished;
            return;
        }
        if self.done && (self.total != Some(total) || seq.saturating_add(1) < total) {
            // flown again or replaced, not by this station
            self.begin(Some(total));
        }
        if !self.done {
            self.total = Some(total);
            self.heard_unfinished = true;
        }
    }

    /// A `MISSION_ITEM_REACHED` of item `seq`.
    pub fn on_reached(&mut self, seq: u16) {
        if self
            .total
            .is_some_and(|n| n > 0 && u32::from(seq) + 1 >= u32::from(n))
        {
            self.done = true;
        }
    }
}

/// ψ (rad) in degrees, wrapped to (−180°, 180°].
pub fn wrap_deg(angle_rad: f64) -> f64 {
    let d = angle_rad.to_degrees().rem_euclid(360.0);
    if d > 180.0 { d - 360.0 } else { d }
}

impl VehicleView {
    /// Armed, as its heartbeat says.
    pub fn armed(&self) -> Option<bool> {
        self.heartbeat.as_ref().map(|h| {
            h.base_mode
                .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED)
        })
    }

    /// Its PX4 main and sub mode, as its heartbeat says.
    pub fn mode(&self) -> Option<(u8, u8)> {
        self.heartbeat
            .as_ref()
            .map(|h| modes::main_sub(h.custom_mode))
    }

    /// On the ground: the land detector's word, or without one disarmed.
    pub fn on_ground(&self) -> bool {
        match self.landed {
            Some(MavLandedState::MAV_LANDED_STATE_ON_GROUND) => true,
            None | Some(MavLandedState::MAV_LANDED_STATE_UNDEFINED) => self.armed() == Some(false),
            _ => false,
        }
    }

    /// Its status line at `now_s` (`sysid` names it).
    pub fn line(&self, sysid: u8, now_s: f64) -> String {
        let (Some(hb), Some(t)) = (&self.heartbeat, self.heartbeat_s) else {
            return format!("vehicle {sysid}: no heartbeat yet");
        };
        let quiet_s = now_s - t;
        if quiet_s > HEARTBEAT_SILENCE_S {
            return format!("vehicle {sysid}: no heartbeat for {quiet_s:.0} s");
        }
        let armed = self.armed() == Some(true);
        let (main, sub) = modes::main_sub(hb.custom_mode);
        let mode = modes::nav_of(main, sub)
            .map_or_else(|| modes::qgc_name(main, sub), crate::NavMode::as_str);
        let mut s = format!(
            "vehicle {sysid}: {:?} {} {:<8}",
            hb.mavtype,
            if armed { "ARMED   " } else { "disarmed" },
            mode
        );
        if let Some(a) = &self.attitude {
            s += &format!(
                " | φ {:6.1}° θ {:6.1}° ψ {:6.1}°",
                f64::from(a.roll).to_degrees(),
                f64::from(a.pitch).to_degrees(),
                wrap_deg(f64::from(a.yaw))
            );
        }
        if let Some(l) = &self.local {
            s += &format!(" | N {:7.2} E {:7.2} D {:7.2} m", l.x, l.y, l.z);
        }
        if let Some(p) = &self.position {
            s += &format!(
                " | {:.7} {:.7} rel {:.2} m",
                f64::from(p.lat) * 1e-7,
                f64::from(p.lon) * 1e-7,
                f64::from(p.relative_alt) * 1e-3
            );
        }
        let total = self.received + self.lost;
        let quality = if total > 0 {
            100.0 * self.received as f64 / total as f64
        } else {
            0.0
        };
        s + &format!(" | link {quality:.0} % ({} msgs)", self.received)
    }
}

/// The vehicles heard, by system id.
#[derive(Debug, Clone, Default)]
pub struct Fleet {
    /// Each vehicle's view.
    pub vehicles: BTreeMap<u8, VehicleView>,
}

impl Fleet {
    /// A message from `header`'s system at `now_s` (ground stations' own
    /// messages are not vehicles').
    pub fn on_message(&mut self, header: &MavHeader, msg: &MavMessage, now_s: f64) {
        if let MavMessage::HEARTBEAT(h) = msg
            && h.mavtype == MavType::MAV_TYPE_GCS
        {
            return;
        }
        if header.system_id == GCS_SYSTEM_ID {
            return;
        }
        let v = self.vehicles.entry(header.system_id).or_default();
        if let Some(last) = v.last_seq.insert(header.component_id, header.sequence) {
            v.lost += u64::from(header.sequence.wrapping_sub(last).wrapping_sub(1));
        }
        v.received += 1;
        match msg {
            MavMessage::HEARTBEAT(h) => {
                v.heartbeat = Some(h.clone());
                v.heartbeat_s = Some(now_s);
            }
            MavMessage::ATTITUDE(a) => v.attitude = Some(a.clone()),
            MavMessage::GLOBAL_POSITION_INT(p) => v.position = Some(p.clone()),
            MavMessage::LOCAL_POSITION_NED(l) => v.local = Some(l.clone()),
            MavMessage::EXTENDED_SYS_STATE(e) => v.landed = Some(e.landed_state),
            MavMessage::MISSION_CURRENT(m) => {
                v.mission_state = Some(m.mission_state);
                v.mission.on_current(m.seq, m.total, m.mission_state);
            }
            MavMessage::MISSION_ITEM_REACHED(r) => v.mission.on_reached(r.seq),
            MavMessage::HOME_POSITION(h) => v.home_amsl_m = Some(f64::from(h.altitude) * 1e-3),
            _ => {}
        }
    }

    /// One status line per vehicle that sent a heartbeat (another system
    /// without one, e.g. a second ground station, is not a vehicle).
    pub fn lines(&self, now_s: f64) -> Vec<String> {
        self.vehicles
            .iter()
            .filter(|(_, v)| v.heartbeat.is_some())
            .map(|(id, v)| v.line(*id, now_s))
            .collect()
    }

    /// `op` finished with `result`: an upload or a `MAV_CMD_MISSION_START`
    /// accepted begins a new mission on its vehicle ([`MissionProgress`]).
    pub fn on_finished(&mut self, op: &Operation, result: &Result<Outcome, ClientError>) {
        let total = match (&op.request, result) {
            (Request::Upload(items), Ok(Outcome::Uploaded(..))) => {
                Some(u16::try_from(items.len()).unwrap_or(u16::MAX))
            }
            (
                Request::Command {
                    command: MavCmd::MAV_CMD_MISSION_START,
                    ..
                },
                Ok(Outcome::Command(_)),
            ) => None,
            _ => return,
        };
        self.vehicles
            .entry(op.target)
            .or_default()
            .mission
            .begin(total);
    }

    /// A vehicle's view.
    pub fn get(&self, sysid: u8) -> Option<&VehicleView> {
        self.vehicles.get(&sysid)
    }
}

/// A state to wait for.
#[derive(Debug, Clone, PartialEq)]
pub enum WaitFor {
    /// Armed.
    Armed,
    /// Disarmed.
    Disarmed,
    /// On the ground ([`VehicleView::on_ground`]).
    Landed,
    /// In this PX4 main and sub mode (the name as given).
    Mode(u8, u8, String),
    /// This long (s; bounded by itself, not by the timeout).
    Seconds(f64),
    /// The current mission flown to its end ([`MissionProgress::done`]):
    /// the one begun last, not an earlier one's completion.
    MissionDone,
}

/// What to do.
#[derive(Debug, Clone, PartialEq)]
pub enum Request {
    /// A `COMMAND_LONG`.
    Command {
        /// The command.
        command: MavCmd,
        /// Its seven parameters.
        params: [f32; 7],
    },
    /// Take off to this height above home (m; `None`: the vehicle's
    /// `NAV_TKOFF_ALT`): `MAV_CMD_NAV_TAKEOFF` with param7 AMSL, as PX4
    /// reads it, from the home the vehicle reports.
    Takeoff(Option<f64>),
    /// Upload a mission.
    Upload(Vec<MISSION_ITEM_INT_DATA>),
    /// Download the mission.
    Download,
    /// Read a parameter.
    ParamGet(String),
    /// Set a parameter.
    ParamSet(String, f32),
    /// Wait for a state.
    Wait(WaitFor),
}

/// A finished operation's answer.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// The command's result (accepted).
    Command(MavResult),
    /// The upload's answer and the items uploaded.
    Uploaded(MavMissionResult, usize),
    /// The mission downloaded.
    Downloaded(Vec<MISSION_ITEM_INT_DATA>),
    /// A parameter's name and value.
    Param(String, f32),
    /// The state waited for was reached.
    Reached,
}

/// What a step of an operation produced.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Step {
    /// Messages to send to the vehicle.
    pub send: Vec<MavMessage>,
    /// The end (`None`: still running).
    pub done: Option<Result<Outcome, ClientError>>,
}

#[derive(Debug, Clone, PartialEq)]
enum Phase {
    /// Not sent yet (waiting for the vehicle, or for its home).
    Start,
    /// Sent; the count of sends so far.
    Sent(u8),
    /// Answered `MAV_RESULT_TEMPORARILY_REJECTED`: sent again (a new
    /// command) after [`COMMAND_RETRY_S`].
    Rejected,
    /// Upload: the vehicle requests items.
    Uploading,
    /// Download: items expected (count), received, sends of this request.
    Downloading(u16, Vec<MISSION_ITEM_INT_DATA>, u8),
}

/// One operation on one vehicle.
#[derive(Debug, Clone)]
pub struct Operation {
    request: Request,
    target: u8,
    started_s: f64,
    timeout_s: f64,
    last_sent_s: f64,
    home_asked: bool,
    phase: Phase,
}

fn param_id(name: &str) -> CharArray16 {
    name.into()
}

type CharArray16 = mavlink::types::CharArray<16>;

fn name_of(id: &CharArray16) -> String {
    id.to_str().unwrap_or("").trim_end_matches('\0').to_string()
}

impl Operation {
    /// `request` to vehicle `target`, started at `now_s`, bounded by
    /// `timeout_s`. A parameter name longer than 16 characters or a mission
    /// MAVLink cannot count is refused here.
    pub fn new(
        request: Request,
        target: u8,
        now_s: f64,
        timeout_s: f64,
    ) -> Result<Self, ClientError> {
        match &request {
            Request::ParamGet(n) | Request::ParamSet(n, _) if n.len() > 16 => {
                return Err(ClientError::ParamName(n.clone()));
            }
            Request::Upload(items) if items.len() > usize::from(u16::MAX) => {
                return Err(ClientError::TooManyItems(items.len()));
            }
            _ => {}
        }
        Ok(Operation {
            request,
            target,
            started_s: now_s,
            timeout_s,
            last_sent_s: now_s,
            home_asked: false,
            phase: Phase::Start,
        })
    }

    fn command_long(&self, command: MavCmd, params: [f32; 7], confirmation: u8) -> MavMessage {
        MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
            param1: params[0],
            param2: params[1],
            param3: params[2],
            param4: params[3],
            param5: params[4],
            param6: params[5],
            param7: params[6],
            command,
            target_system: self.target,
            target_component: MavComponent::MAV_COMP_ID_AUTOPILOT1 as u8,
            confirmation,
        })
    }

    /// The message of the request, the `sends`-th time (0: the first).
    fn message(&self, fleet: &Fleet, sends: u8) -> Option<MavMessage> {
        let t = self.target;
        let c = MavComponent::MAV_COMP_ID_AUTOPILOT1 as u8;
        Some(match &self.request {
            Request::Command { command, params } => self.command_long(*command, *params, sends),
            Request::Takeoff(h) => {
                let p7 = match h {
                    None => f32::NAN,
                    Some(h) => (fleet.get(t)?.home_amsl_m? + h) as f32,
                };
                let mut p = [0.0; 7];
                p[6] = p7;
                self.command_long(MavCmd::MAV_CMD_NAV_TAKEOFF, p, sends)
            }
            Request::Upload(items) => MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
                count: items.len() as u16,
                target_system: t,
                target_component: c,
                mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
                ..MISSION_COUNT_DATA::DEFAULT
            }),
            Request::Download => MavMessage::MISSION_REQUEST_LIST(MISSION_REQUEST_LIST_DATA {
                target_system: t,
                target_component: c,
                mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
            }),
            Request::ParamGet(n) => MavMessage::PARAM_REQUEST_READ(PARAM_REQUEST_READ_DATA {
                param_index: -1,
                target_system: t,
                target_component: c,
                param_id: param_id(n),
            }),
            Request::ParamSet(n, v) => MavMessage::PARAM_SET(PARAM_SET_DATA {
                param_value: *v,
                target_system: t,
                target_component: c,
                param_id: param_id(n),
                param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
            }),
            Request::Wait(_) => return None,
        })
    }

    fn what(&self) -> String {
        match &self.request {
            Request::Command { command, .. } => format!("COMMAND_ACK of {command:?}"),
            Request::Takeoff(_) => "COMMAND_ACK of MAV_CMD_NAV_TAKEOFF".into(),
            Request::Upload(_) => "MISSION_REQUEST_INT or MISSION_ACK".into(),
            Request::Download => match &self.phase {
                Phase::Downloading(n, got, _) => format!("mission item {} of {n}", got.len()),
                _ => "MISSION_COUNT".into(),
            },
            Request::ParamGet(n) | Request::ParamSet(n, _) => format!("PARAM_VALUE of {n}"),
            Request::Wait(w) => format!("{w:?}"),
        }
    }

    fn timeout(&self) -> ClientError {
        let waiting_for = match (&self.phase, &self.request) {
            (Phase::Start, Request::Takeoff(Some(_))) => {
                format!("vehicle {}'s HOME_POSITION", self.target)
            }
            (Phase::Start, _) => format!("vehicle {}'s heartbeat", self.target),
            _ => self.what(),
        };
        ClientError::Timeout {
            timeout_s: self.timeout_s,
            waiting_for,
        }
    }

    fn request_item(&self, seq: u16) -> MavMessage {
        MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
            seq,
            target_system: self.target,
            target_component: MavComponent::MAV_COMP_ID_AUTOPILOT1 as u8,
            mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
        })
    }

    fn ack(&self) -> MavMessage {
        MavMessage::MISSION_ACK(MISSION_ACK_DATA {
            target_system: self.target,
            target_component: MavComponent::MAV_COMP_ID_AUTOPILOT1 as u8,
            mavtype: MavMissionResult::MAV_MISSION_ACCEPTED,
            mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
            ..MISSION_ACK_DATA::DEFAULT
        })
    }

    /// The passing of time: first sends, repeats, waits, the timeout.
    pub fn poll(&mut self, fleet: &Fleet, now_s: f64) -> Step {
        let mut step = Step::default();
        let elapsed = now_s - self.started_s;
        if let Request::Wait(w) = &self.request {
            let v = fleet.get(self.target);
            let reached = match w {
                WaitFor::Seconds(s) => elapsed >= *s,
                WaitFor::Armed => v.and_then(VehicleView::armed) == Some(true),
                WaitFor::Disarmed => v.and_then(VehicleView::armed) == Some(false),
                WaitFor::Landed => v.is_some_and(VehicleView::on_ground),
                WaitFor::Mode(main, sub, _) => v.and_then(VehicleView::mode) == Some((*main, *sub)),
                WaitFor::MissionDone => v.is_some_and(|v| v.mission.done),
            };
            if reached {
                step.done = Some(Ok(Outcome::Reached));
            } else if !matches!(w, WaitFor::Seconds(_)) && elapsed >= self.timeout_s {
                step.done = Some(Err(self.timeout()));
            }
            return step;
        }
        if elapsed >= self.timeout_s {
            step.done = Some(Err(self.timeout()));
            return step;
        }
        let since = now_s - self.last_sent_s;
        match self.phase.clone() {
            Phase::Start => {
                let heard = fleet
                    .get(self.target)
                    .is_some_and(|v| v.heartbeat.is_some());
                if !heard {
                    return step;
                }
                match self.message(fleet, 0) {
                    Some(m) => {
                        step.send.push(m);
                        self.phase = Phase::Sent(1);
                        self.last_sent_s = now_s;
                    }
                    None => {
                        // a takeoff height without home yet: ask for it
                        if since >= COMMAND_RETRY_S || !self.home_asked {
                            self.home_asked = true;
                            let mut p = [0.0; 7];
                            p[0] = HOME_POSITION_DATA::ID as f32;
                            step.send.push(self.command_long(
                                MavCmd::MAV_CMD_REQUEST_MESSAGE,
                                p,
                                0,
                            ));
                            self.last_sent_s = now_s;
                        }
                    }
                }
            }
            Phase::Sent(n) if since >= COMMAND_RETRY_S => {
                if n >= MAX_SENDS {
                    step.done = Some(Err(self.timeout()));
                } else if let Some(m) = self.message(fleet, n) {
                    step.send.push(m);
                    self.phase = Phase::Sent(n + 1);
                    self.last_sent_s = now_s;
                }
            }
            Phase::Rejected if since >= COMMAND_RETRY_S => {
                if let Some(m) = self.message(fleet, 0) {
                    step.send.push(m);
                    self.phase = Phase::Sent(1);
                    self.last_sent_s = now_s;
                }
            }
            Phase::Downloading(count, got, n) if since >= MISSION_RETRY_S => {
                if n >= MAX_SENDS {
                    step.done = Some(Err(self.timeout()));
                } else {
                    step.send.push(self.request_item(got.len() as u16));
                    self.phase = Phase::Downloading(count, got, n + 1);
                    self.last_sent_s = now_s;
                }
            }
            // an upload is driven by the vehicle: it repeats its requests
            _ => {}
        }
        step
    }

    /// The outcome of a command's `COMMAND_ACK` at `now_s`: accepted, a
    /// refusal, or nothing yet (in progress; temporarily rejected: sent
    /// again after [`COMMAND_RETRY_S`], the operation's timeout bounding it).
    fn ack_result(&mut self, r: MavResult, now_s: f64) -> Option<Result<Outcome, ClientError>> {
        match r {
            MavResult::MAV_RESULT_ACCEPTED => Some(Ok(Outcome::Command(r))),
            MavResult::MAV_RESULT_IN_PROGRESS => None,
            MavResult::MAV_RESULT_TEMPORARILY_REJECTED => {
                self.phase = Phase::Rejected;
                self.last_sent_s = now_s;
                None
            }
            _ => Some(Err(ClientError::Refused(format!("{r:?}")))),
        }
    }

    /// A message from (`sysid`, `compid`) at `now_s`.
    pub fn on_message(&mut self, sysid: u8, msg: &MavMessage, now_s: f64) -> Step {
        let mut step = Step::default();
        if sysid != self.target || matches!(self.phase, Phase::Start) {
            return step;
        }
        let for_me = |t: Option<u8>| t.is_none_or(|t| t == 0 || t == GCS_SYSTEM_ID);
        if !for_me(mavlink::Message::target_system_id(msg)) {
            return step;
        }
        match (&self.request, msg) {
            (Request::Command { command, .. }, MavMessage::COMMAND_ACK(a))
                if a.command == *command =>
            {
                step.done = self.ack_result(a.result, now_s);
            }
            (Request::Takeoff(_), MavMessage::COMMAND_ACK(a))
                if a.command == MavCmd::MAV_CMD_NAV_TAKEOFF =>
            {
                step.done = self.ack_result(a.result, now_s);
            }
            (
                Request::Upload(items),
                MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
                    seq, mission_type, ..
                }),
            )
            | (
                Request::Upload(items),
                MavMessage::MISSION_REQUEST(MISSION_REQUEST_DATA {
                    seq, mission_type, ..
                }),
            ) if *mission_type == MavMissionType::MAV_MISSION_TYPE_MISSION => {
                if let Some(it) = items.get(usize::from(*seq)) {
                    let it = MISSION_ITEM_INT_DATA {
                        seq: *seq,
                        target_system: self.target,
                        target_component: MavComponent::MAV_COMP_ID_AUTOPILOT1 as u8,
                        mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
                        ..it.clone()
                    };
                    step.send
                        .push(if matches!(msg, MavMessage::MISSION_REQUEST(_)) {
                            MavMessage::MISSION_ITEM(item_float(&it))
                        } else {
                            MavMessage::MISSION_ITEM_INT(it)
                        });
                    self.phase = Phase::Uploading;
                    self.last_sent_s = now_s;
                }
            }
            (Request::Upload(items), MavMessage::MISSION_ACK(a)) => {
                step.done = Some(if a.mavtype == MavMissionResult::MAV_MISSION_ACCEPTED {
                    Ok(Outcome::Uploaded(a.mavtype, items.len()))
                } else {
                    Err(ClientError::Refused(format!("{:?}", a.mavtype)))
                });
            }
            (Request::Download, MavMessage::MISSION_COUNT(c))
                if matches!(self.phase, Phase::Sent(_)) =>
            {
                if c.count == 0 {
                    step.send.push(self.ack());
                    step.done = Some(Ok(Outcome::Downloaded(Vec::new())));
                } else {
                    step.send.push(self.request_item(0));
                    self.phase = Phase::Downloading(c.count, Vec::new(), 1);
                    self.last_sent_s = now_s;
                }
            }
            (Request::Download, MavMessage::MISSION_ITEM_INT(it)) => {
                if let Phase::Downloading(count, got, _) = &mut self.phase
                    && usize::from(it.seq) == got.len()
                {
                    got.push(MISSION_ITEM_INT_DATA {
                        target_system: 0,
                        target_component: 0,
                        ..it.clone()
                    });
                    if got.len() == usize::from(*count) {
                        let items = std::mem::take(got);
                        step.send.push(self.ack());
                        step.done = Some(Ok(Outcome::Downloaded(items)));
                    } else {
                        let next = got.len() as u16;
                        self.phase = Phase::Downloading(*count, std::mem::take(got), 1);
                        step.send.push(self.request_item(next));
                        self.last_sent_s = now_s;
                    }
                }
            }
            (Request::Download, MavMessage::MISSION_ACK(a))
                if a.mavtype != MavMissionResult::MAV_MISSION_ACCEPTED =>
            {
                step.done = Some(Err(ClientError::Refused(format!("{:?}", a.mavtype))));
            }
            (Request::ParamGet(n), MavMessage::PARAM_VALUE(p)) if name_of(&p.param_id) == *n => {
                step.done = Some(Ok(Outcome::Param(n.clone(), p.param_value)));
            }
            (Request::ParamSet(n, v), MavMessage::PARAM_VALUE(p)) if name_of(&p.param_id) == *n => {
                step.done = Some(if p.param_value == *v {
                    Ok(Outcome::Param(n.clone(), p.param_value))
                } else {
                    Err(ClientError::ParamRefused {
                        name: n.clone(),
                        value: p.param_value,
                    })
                });
            }
            (Request::ParamGet(n) | Request::ParamSet(n, _), MavMessage::STATUSTEXT(t))
                if t.text.to_str().unwrap_or("").trim_end_matches('\0')
                    == format!("no parameter {n}") =>
            {
                step.done = Some(Err(ClientError::NoParam(n.clone())));
            }
            _ => {}
        }
        step
    }
}

/// The ground station's heartbeat.
pub fn gcs_heartbeat() -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype: MavType::MAV_TYPE_GCS,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        base_mode: MavModeFlag::empty(),
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(sysid: u8) -> MavHeader {
        MavHeader {
            system_id: sysid,
            component_id: 1,
            sequence: 0,
        }
    }

    /// A fleet that has heard vehicle 1 (home 20 m AMSL).
    fn fleet() -> Fleet {
        let mut f = Fleet::default();
        let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            mavtype: MavType::MAV_TYPE_HELICOPTER,
            ..HEARTBEAT_DATA::DEFAULT
        });
        f.on_message(&header(1), &hb, 0.0);
        let home = MavMessage::HOME_POSITION(HOME_POSITION_DATA {
            altitude: 20_000,
            ..HOME_POSITION_DATA::DEFAULT
        });
        f.on_message(&header(1), &home, 0.0);
        f
    }

    fn ack(command: MavCmd, result: MavResult) -> MavMessage {
        MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
            command,
            result,
            target_system: GCS_SYSTEM_ID,
            ..COMMAND_ACK_DATA::DEFAULT
        })
    }

    #[test]
    fn a_command_is_resent_with_confirmation_until_acknowledged() {
        let f = fleet();
        let arm = MavCmd::MAV_CMD_COMPONENT_ARM_DISARM;
        let mut params = [0.0; 7];
        params[0] = 1.0;
        let mut op = Operation::new(
            Request::Command {
                command: arm,
                params,
            },
            1,
            0.0,
            10.0,
        )
        .unwrap();
        let s = op.poll(&f, 0.0);
        let conf = |s: &Step| match &s.send[..] {
            [MavMessage::COMMAND_LONG(c)] => (c.command, c.confirmation, c.param1),
            other => panic!("{other:?}"),
        };
        assert_eq!(conf(&s), (arm, 0, 1.0));
        assert!(op.poll(&f, 0.5).send.is_empty());
        assert_eq!(conf(&op.poll(&f, 1.1)), (arm, 1, 1.0));
        // another vehicle's ack, another command's ack: not this one's
        assert_eq!(
            op.on_message(2, &ack(arm, MavResult::MAV_RESULT_ACCEPTED), 1.2)
                .done,
            None
        );
        let land = ack(MavCmd::MAV_CMD_NAV_LAND, MavResult::MAV_RESULT_ACCEPTED);
        assert_eq!(op.on_message(1, &land, 1.2).done, None);
        let inprog = ack(arm, MavResult::MAV_RESULT_IN_PROGRESS);
        assert_eq!(op.on_message(1, &inprog, 1.3).done, None);
        let done = op
            .on_message(1, &ack(arm, MavResult::MAV_RESULT_DENIED), 1.4)
            .done;
        assert_eq!(
            done,
            Some(Err(ClientError::Refused("MAV_RESULT_DENIED".into())))
        );
    }

    /// Temporarily rejected (the navigation aligning): sent again as a new
    /// command (confirmation 0) a retry period later, accepted then; the
    /// operation's timeout bounds the retries.
    #[test]
    fn a_temporarily_rejected_command_is_tried_again_until_its_timeout() {
        let f = fleet();
        let arm = MavCmd::MAV_CMD_COMPONENT_ARM_DISARM;
        let mut params = [0.0; 7];
        params[0] = 1.0;
        let request = Request::Command {
            command: arm,
            params,
        };
        let mut op = Operation::new(request.clone(), 1, 0.0, 10.0).unwrap();
        assert_eq!(op.poll(&f, 0.0).send.len(), 1);
        let later = ack(arm, MavResult::MAV_RESULT_TEMPORARILY_REJECTED);
        assert_eq!(op.on_message(1, &later, 0.1).done, None);
        assert!(op.poll(&f, 0.6).send.is_empty());
        match &op.poll(&f, 1.2).send[..] {
            [MavMessage::COMMAND_LONG(c)] => assert_eq!((c.command, c.confirmation), (arm, 0)),
            other => panic!("{other:?}"),
        }
        let done = op
            .on_message(1, &ack(arm, MavResult::MAV_RESULT_ACCEPTED), 1.3)
            .done;
        assert_eq!(
            done,
            Some(Ok(Outcome::Command(MavResult::MAV_RESULT_ACCEPTED)))
        );
        // rejected every time: the timeout ends it
        let mut op = Operation::new(request, 1, 0.0, 3.0).unwrap();
        let mut t = 0.0;
        let mut end = None;
        while end.is_none() && t < 10.0 {
            let s = op.poll(&f, t);
            end = s.done;
            if !s.send.is_empty() {
                assert_eq!(op.on_message(1, &later, t + 0.05).done, None);
            }
            t += 0.1;
        }
        assert!(matches!(end, Some(Err(_))) && t <= 3.2, "{end:?} at {t}");
    }

    #[test]
    fn a_command_times_out_after_its_sends() {
        let f = fleet();
        let mut op = Operation::new(Request::Takeoff(Some(3.0)), 1, 0.0, 100.0).unwrap();
        let s = op.poll(&f, 0.0);
        // param7 AMSL: home 20 m + 3 m
        assert!(matches!(&s.send[..], [MavMessage::COMMAND_LONG(c)] if c.param7 == 23.0));
        let mut sends = 1;
        let mut t = 0.0;
        loop {
            t += 0.25;
            let s = op.poll(&f, t);
            sends += s.send.len();
            if let Some(d) = s.done {
                assert!(matches!(d, Err(ClientError::Timeout { .. })), "{d:?}");
                break;
            }
            assert!(t < 20.0);
        }
        assert_eq!(sends, usize::from(MAX_SENDS));
    }

    #[test]
    fn a_takeoff_height_asks_for_home_first() {
        let mut f = Fleet::default();
        let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA::DEFAULT);
        f.on_message(&header(1), &hb, 0.0);
        let mut op = Operation::new(Request::Takeoff(Some(2.0)), 1, 0.0, 10.0).unwrap();
        let s = op.poll(&f, 0.01);
        assert!(
            matches!(&s.send[..], [MavMessage::COMMAND_LONG(c)] if c.command == MavCmd::MAV_CMD_REQUEST_MESSAGE && c.param1 == 242.0),
            "{s:?}"
        );
        assert!(op.poll(&f, 0.5).send.is_empty());
        let home = MavMessage::HOME_POSITION(HOME_POSITION_DATA {
            altitude: 30_000,
            ..HOME_POSITION_DATA::DEFAULT
        });
        f.on_message(&header(1), &home, 0.6);
        let s = op.poll(&f, 0.7);
        assert!(
            matches!(&s.send[..], [MavMessage::COMMAND_LONG(c)] if c.command == MavCmd::MAV_CMD_NAV_TAKEOFF && c.param7 == 32.0),
            "{s:?}"
        );
    }

    #[test]
    fn nothing_is_sent_before_the_vehicle_is_heard() {
        let mut op = Operation::new(Request::Download, 9, 0.0, 2.0).unwrap();
        assert!(op.poll(&fleet(), 0.0).send.is_empty());
        let e = op.poll(&fleet(), 2.0).done.unwrap().unwrap_err();
        assert!(e.to_string().contains("vehicle 9's heartbeat"), "{e}");
    }

    fn items(n: u16) -> Vec<MISSION_ITEM_INT_DATA> {
        (0..n)
            .map(|seq| MISSION_ITEM_INT_DATA {
                seq,
                x: 570_146_000 + i32::from(seq),
                command: MavCmd::MAV_CMD_NAV_WAYPOINT,
                ..MISSION_ITEM_INT_DATA::DEFAULT
            })
            .collect()
    }

    #[test]
    fn an_upload_answers_the_vehicles_requests() {
        let f = fleet();
        let mut op = Operation::new(Request::Upload(items(3)), 1, 0.0, 10.0).unwrap();
        let s = op.poll(&f, 0.0);
        assert!(matches!(&s.send[..], [MavMessage::MISSION_COUNT(c)] if c.count == 3));
        // no request yet: the count again
        assert!(matches!(
            &op.poll(&f, 1.1).send[..],
            [MavMessage::MISSION_COUNT(_)]
        ));
        let req = |seq| {
            MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
                seq,
                target_system: GCS_SYSTEM_ID,
                ..MISSION_REQUEST_INT_DATA::DEFAULT
            })
        };
        for seq in [0, 1, 1, 2] {
            let s = op.on_message(1, &req(seq), 1.2);
            assert!(
                matches!(&s.send[..], [MavMessage::MISSION_ITEM_INT(i)] if i.seq == seq && i.target_system == 1)
            );
        }
        // the vehicle drives now: no count repeated
        assert!(op.poll(&f, 5.0).send.is_empty());
        let a = MavMessage::MISSION_ACK(MISSION_ACK_DATA {
            mavtype: MavMissionResult::MAV_MISSION_ACCEPTED,
            target_system: GCS_SYSTEM_ID,
            ..MISSION_ACK_DATA::DEFAULT
        });
        assert_eq!(
            op.on_message(1, &a, 5.1).done,
            Some(Ok(Outcome::Uploaded(
                MavMissionResult::MAV_MISSION_ACCEPTED,
                3
            )))
        );
    }

    #[test]
    fn a_download_requests_each_item_and_retries() {
        let f = fleet();
        let want = items(2);
        let mut op = Operation::new(Request::Download, 1, 0.0, 10.0).unwrap();
        assert!(matches!(
            &op.poll(&f, 0.0).send[..],
            [MavMessage::MISSION_REQUEST_LIST(_)]
        ));
        let count = MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
            count: 2,
            target_system: GCS_SYSTEM_ID,
            ..MISSION_COUNT_DATA::DEFAULT
        });
        let s = op.on_message(1, &count, 0.1);
        assert!(matches!(&s.send[..], [MavMessage::MISSION_REQUEST_INT(r)] if r.seq == 0));
        // item 0 lost: requested again after the item timeout
        assert!(op.poll(&f, 1.0).send.is_empty());
        let s = op.poll(&f, 0.1 + MISSION_RETRY_S);
        assert!(matches!(&s.send[..], [MavMessage::MISSION_REQUEST_INT(r)] if r.seq == 0));
        let item = |i: usize| {
            MavMessage::MISSION_ITEM_INT(MISSION_ITEM_INT_DATA {
                target_system: GCS_SYSTEM_ID,
                ..want[i].clone()
            })
        };
        let s = op.on_message(1, &item(0), 2.0);
        assert!(matches!(&s.send[..], [MavMessage::MISSION_REQUEST_INT(r)] if r.seq == 1));
        // a repeat of item 0 is not taken twice
        assert!(op.on_message(1, &item(0), 2.1).done.is_none());
        let s = op.on_message(1, &item(1), 2.2);
        assert!(
            matches!(&s.send[..], [MavMessage::MISSION_ACK(a)] if a.mavtype == MavMissionResult::MAV_MISSION_ACCEPTED)
        );
        assert_eq!(s.done, Some(Ok(Outcome::Downloaded(want))));
    }

    #[test]
    fn a_parameter_set_to_another_value_is_a_refusal() {
        let f = fleet();
        let mut op = Operation::new(
            Request::ParamSet("NAV_TKOFF_ALT".into(), 900.0),
            1,
            0.0,
            10.0,
        )
        .unwrap();
        assert!(
            matches!(&op.poll(&f, 0.0).send[..], [MavMessage::PARAM_SET(p)] if p.param_value == 900.0)
        );
        let v = MavMessage::PARAM_VALUE(PARAM_VALUE_DATA {
            param_value: 5.0,
            param_id: "NAV_TKOFF_ALT".into(),
            ..PARAM_VALUE_DATA::DEFAULT
        });
        assert_eq!(
            op.on_message(1, &v, 0.1).done,
            Some(Err(ClientError::ParamRefused {
                name: "NAV_TKOFF_ALT".into(),
                value: 5.0
            }))
        );
        assert!(
            Operation::new(
                Request::ParamGet("A_NAME_LONGER_THAN_16".into()),
                1,
                0.0,
                1.0
            )
            .is_err()
        );
    }

    #[test]
    fn a_quiet_vehicle_is_told_and_yaw_is_wrapped() {
        let mut f = Fleet::default();
        let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            mavtype: MavType::MAV_TYPE_HELICOPTER,
            ..HEARTBEAT_DATA::DEFAULT
        });
        let att = MavMessage::ATTITUDE(ATTITUDE_DATA {
            yaw: 3.5,
            ..ATTITUDE_DATA::DEFAULT
        });
        let h = |sequence| MavHeader {
            sequence,
            ..header(1)
        };
        f.on_message(&h(0), &hb, 0.0);
        f.on_message(&h(1), &att, 0.5);
        let l = f.lines(1.0).remove(0);
        assert!(l.contains("ψ -159.5°"), "{l}");
        assert!(l.contains("link 100 % (2 msgs)"), "{l}");
        // two lost
        f.on_message(&h(4), &att, 0.6);
        assert!(f.lines(1.0)[0].contains("link 60 % (3 msgs)"));
        let l = f.lines(10.0).remove(0);
        assert_eq!(l, "vehicle 1: no heartbeat for 10 s");
        assert_eq!(wrap_deg(std::f64::consts::PI), 180.0);
        assert!((wrap_deg(-std::f64::consts::PI) - 180.0).abs() < 1e-9);
        assert!((wrap_deg(7.0_f64.to_radians() + 4.0 * std::f64::consts::PI) - 7.0).abs() < 1e-9);
    }
    #[test]
    fn waiting_for_a_mission_is_not_ended_by_an_earlier_ones_completion() {
        let mut f = fleet();
        let current = |seq, total, mission_state| {
            MavMessage::MISSION_CURRENT(MISSION_CURRENT_DATA {
                seq,
                total,
                mission_state,
                ..MISSION_CURRENT_DATA::DEFAULT
            })
        };
        let reached = |seq| MavMessage::MISSION_ITEM_REACHED(MISSION_ITEM_REACHED_DATA { seq });
        let done = |f: &Fleet| {
            let mut w = Operation::new(Request::Wait(WaitFor::MissionDone), 1, 0.0, 10.0).unwrap();
            w.poll(f, 0.0).done == Some(Ok(Outcome::Reached))
        };
        // a COMPLETE heard first is no mission seen running: not done
        f.on_message(
            &header(1),
            &current(1, 2, MissionState::MISSION_STATE_COMPLETE),
            0.0,
        );
        assert!(!done(&f));
        // a first mission (2 items) flown to its end
        f.on_message(
            &header(1),
            &current(0, 2, MissionState::MISSION_STATE_ACTIVE),
            1.0,
        );
        assert!(!done(&f));
        f.on_message(
            &header(1),
            &current(1, 2, MissionState::MISSION_STATE_COMPLETE),
            2.0,
        );
        assert!(done(&f));
        // a second (3 items) uploaded and started from here: the last
        // COMPLETE, and another still stale, are the first's
        let upload = Operation::new(Request::Upload(items(3)), 1, 3.0, 10.0).unwrap();
        f.on_finished(
            &upload,
            &Ok(Outcome::Uploaded(MavMissionResult::MAV_MISSION_ACCEPTED, 3)),
        );
        let start = Operation::new(
            Request::Command {
                command: MavCmd::MAV_CMD_MISSION_START,
                params: [0.0; 7],
            },
            1,
            3.0,
            10.0,
        )
        .unwrap();
        let accepted = Ok(Outcome::Command(MavResult::MAV_RESULT_ACCEPTED));
        f.on_finished(&start, &accepted);
        assert_eq!(f.get(1).unwrap().mission.begun, 2);
        assert!(!done(&f));
        f.on_message(
            &header(1),
            &current(1, 2, MissionState::MISSION_STATE_COMPLETE),
            3.1,
        );
        assert!(!done(&f));
        f.on_message(
            &header(1),
            &current(0, 3, MissionState::MISSION_STATE_ACTIVE),
            3.2,
        );
        f.on_message(&header(1), &reached(1), 4.0);
        assert!(!done(&f), "item 1 of 3 is not the last");
        f.on_message(&header(1), &reached(2), 5.0);
        assert!(done(&f));
        // an ACTIVE still on the last item is the same mission's
        f.on_message(
            &header(1),
            &current(2, 3, MissionState::MISSION_STATE_ACTIVE),
            5.1,
        );
        assert!(done(&f));
        // the mission flown again from elsewhere (back at item 0): a new one
        f.on_message(
            &header(1),
            &current(0, 3, MissionState::MISSION_STATE_ACTIVE),
            6.0,
        );
        assert!(!done(&f));
        assert_eq!(f.get(1).unwrap().mission.begun, 3);
        // a refused command or another command begins nothing
        f.on_finished(
            &start,
            &Err(ClientError::Refused("MAV_RESULT_DENIED".into())),
        );
        assert_eq!(f.get(1).unwrap().mission.begun, 3);
        f.on_message(
            &header(1),
            &current(2, 3, MissionState::MISSION_STATE_COMPLETE),
            7.0,
        );
        assert!(done(&f));
    }
}
