//! What crosses between the control task and the ground-station server
//! thread: two lock-free `rtrb` rings (the control task never blocks on the
//! server: a full ring drops the status, never waits), and the vehicle-side
//! half, [`Vehicle`], that the control task calls once per sample.

use crate::navigator::{
    Events, GuidedTarget, NavEvent, NavInput, NavMode, Navigator, NavigatorConfig, Plan,
};
use helicon_core::state::Input;
use helicon_core::{Reference, Telemetry};
use nalgebra::Vector3;

/// From the ground station to the vehicle.
#[derive(Debug, Clone, PartialEq)]
pub enum Uplink {
    /// A ground-station heartbeat arrived.
    GcsHeartbeat,
    /// Arm (`true`) or disarm.
    Arm(bool),
    /// Take off to this height above home (m).
    Takeoff(f64),
    /// Land where it is.
    Land,
    /// Return home and land.
    Return,
    /// Hold position.
    Hold,
    /// Fly the mission from its start.
    StartMission,
    /// A new mission (boxed: the ring stays small; the control task drops
    /// the box only when a mission is replaced, never in steady state).
    Plan(Box<Plan>),
    /// New navigator tuning (validated by the server).
    Config(NavigatorConfig),
    /// New fence zones (an upload of `MAV_MISSION_TYPE_FENCE`, checked by
    /// the server; boxed like a plan).
    Zones(Box<crate::fence::Zones>),
    /// New rally points (an upload of `MAV_MISSION_TYPE_RALLY`, checked by
    /// the server; boxed like a plan).
    Rally(Box<crate::rally::RallyPoints>),
    /// A guided target.
    Guided(GuidedTarget),
    /// A status text the server told the operator of its own accord (a
    /// refusal, a reply): for the flight log.
    Text(OperatorText),
}

/// The longest operator text the flight log keeps (bytes; a longer one is
/// cut at a character boundary).
pub const OPERATOR_TEXT_BYTES: usize = 120;

/// A status text of the ground-station server, fixed-size (it crosses the
/// uplink ring without allocation).
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct OperatorText {
    /// MAVLink's `MAV_SEVERITY` (0 emergency … 7 debug, as syslog and
    /// ULog's levels).
    pub severity: u8,
    len: u8,
    bytes: [u8; OPERATOR_TEXT_BYTES],
}

impl std::fmt::Debug for OperatorText {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "OperatorText({}, {:?})", self.severity, self.as_str())
    }
}

impl OperatorText {
    /// `text` at `severity` (clamped to 0..=7), cut to
    /// [`OPERATOR_TEXT_BYTES`] at a character boundary.
    pub fn new(severity: u8, text: &str) -> Self {
        let mut end = text.len().min(OPERATOR_TEXT_BYTES);
        while !text.is_char_boundary(end) {
            end -= 1;
        }
        let mut bytes = [0u8; OPERATOR_TEXT_BYTES];
        bytes[..end].copy_from_slice(&text.as_bytes()[..end]);
        OperatorText {
            severity: severity.min(7),
            len: u8::try_from(end).unwrap_or(u8::MAX),
            bytes,
        }
    }

    /// The text.
    pub fn as_str(&self) -> &str {
        std::str::from_utf8(&self.bytes[..usize::from(self.len)]).unwrap_or("")
    }
}

/// The most operator texts one control sample carries to the flight log;
/// more are counted in [`OperatorTexts::dropped`].
pub const OPERATOR_TEXTS_PER_SAMPLE: usize = 4;

/// The operator texts that arrived in one control sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct OperatorTexts {
    items: [Option<OperatorText>; OPERATOR_TEXTS_PER_SAMPLE],
    len: usize,
    /// Texts beyond [`OPERATOR_TEXTS_PER_SAMPLE`] in this sample, not kept.
    pub dropped: u32,
}

impl OperatorTexts {
    /// Keep `t` (or count it dropped when full).
    pub fn push(&mut self, t: OperatorText) {
        if self.len < OPERATOR_TEXTS_PER_SAMPLE {
            self.items[self.len] = Some(t);
            self.len += 1;
        } else {
            self.dropped = self.dropped.saturating_add(1);
        }
    }

    /// The texts kept, in arrival order.
    pub fn iter(&self) -> impl Iterator<Item = &OperatorText> {
        self.items[..self.len].iter().flatten()
    }

    /// No text kept and none dropped.
    pub fn is_empty(&self) -> bool {
        self.len == 0 && self.dropped == 0
    }
}

/// The flight software's mode as the ground station is told it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FlightMode {
    /// The supervisor's mode name (`auto`, `hold`, `manual`, …).
    pub name: &'static str,
    /// The law (not the trim or the pilot) flies the servos.
    pub law_flies: bool,
}

/// On the ground or in the air, as MAVLink's `MAV_LANDED_STATE` tells it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LandedState {
    /// The flight software has no land detector (a flight that starts in
    /// the air): nothing is claimed.
    #[default]
    Undefined,
    /// Resting on the ground (disarmed, spooling, ready, landed).
    OnGround,
    /// Flying.
    InAir,
    /// Taking off: the commands ramping from ground idle, not yet lifted off.
    Takeoff,
    /// Landing: descending to touch down.
    Landing,
}

impl LandedState {
    /// `MAV_LANDED_STATE`'s value (0 undefined … 4 landing).
    pub fn code(self) -> u8 {
        match self {
            LandedState::Undefined => 0,
            LandedState::OnGround => 1,
            LandedState::InAir => 2,
            LandedState::Takeoff => 3,
            LandedState::Landing => 4,
        }
    }
}

/// The main rotor's run-up, as the ground station is told it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RotorRunup {
    /// The engine is off and the rotor at rest.
    Stopped,
    /// The engine runs and the rotor is coming up to speed.
    SpoolingUp,
    /// At the governed speed (also: a flight without a spool state).
    #[default]
    AtSpeed,
    /// The engine is cut and the rotor running down.
    SpoolingDown,
}

/// The flight software's ground state for the ground station: whether it
/// is on the ground and where the rotor's run-up is (the defaults: no land
/// detector, the rotor at speed).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct GroundState {
    /// On the ground or in the air.
    pub landed: LandedState,
    /// The rotor's run-up.
    pub rotor: RotorRunup,
}

impl GroundState {
    /// The land detector's word for the navigator: `None` without one,
    /// otherwise whether the helicopter is on the ground.
    pub fn on_ground(&self) -> Option<bool> {
        match self.landed {
            LandedState::Undefined => None,
            LandedState::OnGround => Some(true),
            _ => Some(false),
        }
    }
}

/// One sample's state for the ground station.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VehicleStatus {
    /// On-board time (s).
    pub t_s: f64,
    /// Armed by the ground station.
    pub armed: bool,
    /// The navigator's mode.
    pub nav_mode: NavMode,
    /// The flight software's mode.
    pub flight_mode: FlightMode,
    /// Estimated attitude [φ θ ψ] (rad).
    pub attitude_rad: Vector3<f64>,
    /// Estimated body rates [p q r] (rad/s).
    pub rates_rad_s: Vector3<f64>,
    /// Estimated position NED about home (m).
    pub position_ned_m: Vector3<f64>,
    /// Estimated velocity NED (m/s).
    pub velocity_ned_m_s: Vector3<f64>,
    /// 1σ of the position (m).
    pub position_sigma_m: Vector3<f64>,
    /// A navigation solution exists.
    pub navigation_ok: bool,
    /// A GPS fix was fused in the last second.
    pub gps_ok: bool,
    /// The servo commands sent.
    pub servo: Input,
    /// The reference flown.
    pub reference: Reference,
    /// The current mission item's sequence number and the mission's length.
    pub mission_current: (u16, u16),
    /// The ground-station link is lost (failsafe).
    pub link_lost: bool,
    /// The control task's load (compute time / period, 0..1).
    pub load: f64,
    /// On the ground or in the air, and the rotor's run-up.
    pub ground: GroundState,
}

/// Something to tell the operator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum VehicleEvent {
    /// From the navigator.
    Nav(NavEvent),
    /// Armed (`true`) or disarmed.
    Armed(bool),
    /// The flight software's mode changed (name, reason).
    FlightMode(&'static str, &'static str),
    /// A warning of the flight software for the operator (a status text
    /// at warning severity), e.g. the IMU health monitor's.
    Warning(&'static str),
    /// A notice of the flight software for the operator (a status text at
    /// info severity), e.g. the rotor at speed.
    Notice(&'static str),
}

/// From the vehicle to the ground station.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Downlink {
    /// The state of a sample.
    Status(VehicleStatus),
    /// An event.
    Event(f64, VehicleEvent),
}

/// The vehicle's ends of the rings.
pub struct VehicleEnd {
    /// Commands in.
    pub uplink: rtrb::Consumer<Uplink>,
    /// Status and events out.
    pub downlink: rtrb::Producer<Downlink>,
}

/// The server's ends of the rings.
pub struct ServerEnd {
    /// Commands out.
    pub uplink: rtrb::Producer<Uplink>,
    /// Status and events in.
    pub downlink: rtrb::Consumer<Downlink>,
}

/// The two rings (`capacity` entries each).
pub fn channel(capacity: usize) -> (VehicleEnd, ServerEnd) {
    let (up_tx, up_rx) = rtrb::RingBuffer::new(capacity);
    let (down_tx, down_rx) = rtrb::RingBuffer::new(capacity);
    (
        VehicleEnd {
            uplink: up_rx,
            downlink: down_tx,
        },
        ServerEnd {
            uplink: up_tx,
            downlink: down_rx,
        },
    )
}

/// What the vehicle side decided this sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VehicleOutput {
    /// The reference for the LQI.
    pub reference: Reference,
    /// Arm (`Some(true)`) or disarm (`Some(false)`) the flight software now.
    pub arm: Option<bool>,
    /// The navigator's events of this sample (also sent to the server):
    /// for the flight log.
    pub events: Events,
    /// The tuning the operator set this sample, before and after (the
    /// parameter table's values): for the flight log.
    pub config_change: Option<(NavigatorConfig, NavigatorConfig)>,
    /// The server's own texts to the operator this sample: for the flight
    /// log.
    pub texts: OperatorTexts,
}

/// The vehicle-side half: the navigator fed by the uplink, its status on
/// the downlink. Allocation-free per sample (a mission replaced drops the
/// old one's box: an operator's action, not the steady state).
pub struct Vehicle {
    nav: Navigator,
    end: VehicleEnd,
    armed: bool,
    last_heartbeat_s: Option<f64>,
    last_gps_s: Option<f64>,
    at: NavInput,
    status_every: u64,
    samples: u64,
    dropped: u64,
    sent: u64,
    ground: GroundState,
    config_change: Option<(NavigatorConfig, NavigatorConfig)>,
    texts: OperatorTexts,
}

impl Vehicle {
    /// A disarmed vehicle with this navigator, sending its status every
    /// `status_every` samples (at 400 Hz, 4 → 100 Hz, the fastest stream
    /// the ground station can ask for).
    pub fn new(nav: Navigator, end: VehicleEnd, status_every: u64) -> Self {
        Vehicle {
            nav,
            end,
            armed: false,
            last_heartbeat_s: None,
            last_gps_s: None,
            at: NavInput {
                t_s: 0.0,
                position_ned_m: Vector3::zeros(),
                yaw_rad: 0.0,
                on_ground: None,
            },
            status_every: status_every.max(1),
            samples: 0,
            dropped: 0,
            sent: 0,
            ground: GroundState::default(),
            config_change: None,
            texts: OperatorTexts::default(),
        }
    }

    /// The flight software's ground state of this sample (call before
    /// [`Vehicle::step`]; without a call: no land detector, the rotor at
    /// speed). With a land detector, a landing ends at touchdown and the
    /// flight software disarms ([`Vehicle::disarmed`] tells the vehicle).
    pub fn set_ground(&mut self, ground: GroundState) {
        self.ground = ground;
        self.at.on_ground = ground.on_ground();
    }

    /// The flight software disarmed by itself (on the ground after a
    /// landing, or the pilot's kill): the navigator idles and the operator
    /// is told.
    pub fn disarmed(&mut self, t_s: f64) {
        if self.armed {
            self.armed = false;
            let mut events = Events::default();
            self.nav.idle(&self.at, &mut events);
            self.send(Downlink::Event(t_s, VehicleEvent::Armed(false)));
            for e in events.iter() {
                self.send(Downlink::Event(t_s, VehicleEvent::Nav(e)));
            }
        }
    }

    /// The navigator.
    pub fn navigator(&self) -> &Navigator {
        &self.nav
    }

    /// Armed by the ground station.
    pub fn armed(&self) -> bool {
        self.armed
    }

    /// Statuses and events dropped because the server's ring was full.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Statuses and events handed to the server (for lock-step runs: the
    /// server's [`crate::server::ServerHandle::processed`] catches up).
    pub fn sent(&self) -> u64 {
        self.sent
    }

    /// Tell the operator `event` (time `t_s`); never blocks (a full ring
    /// drops it and counts it).
    pub fn notify(&mut self, t_s: f64, event: VehicleEvent) {
        self.send(Downlink::Event(t_s, event));
    }

    fn send(&mut self, d: Downlink) {
        if self.end.downlink.push(d).is_err() {
            self.dropped += 1;
        } else {
            self.sent += 1;
        }
    }

    fn handle(&mut self, u: Uplink, events: &mut Events) -> Option<bool> {
        let at = self.at;
        let flying = self.armed;
        match u {
            Uplink::GcsHeartbeat => self.last_heartbeat_s = Some(at.t_s),
            Uplink::Arm(a) if a != self.armed => {
                self.armed = a;
                if !a {
                    self.nav.idle(&at, events);
                }
                return Some(a);
            }
            Uplink::Takeoff(h) if flying => {
                self.nav.takeoff(&at, h, events);
            }
            Uplink::Land if flying => self.nav.land(&at, events),
            Uplink::Return if flying => self.nav.return_home(&at, events),
            Uplink::Hold if flying => self.nav.hold(&at, events),
            Uplink::StartMission if flying => {
                self.nav.start_mission(&at, events);
            }
            Uplink::Plan(p) => self.nav.set_plan(*p),
            Uplink::Zones(z) => self.nav.set_zones(*z),
            Uplink::Rally(r) => self.nav.set_rally(*r),
            Uplink::Config(c) => {
                // validated by the server; a refusal here keeps the old one
                let before = *self.nav.config();
                if self.nav.set_config(c).is_ok() {
                    self.config_change = Some((before, c));
                }
            }
            Uplink::Guided(g) if flying => {
                self.nav.guided(&at, g, events);
            }
            Uplink::Text(t) => self.texts.push(t),
            _ => {}
        }
        None
    }

    /// One control sample: take the ground station's commands, run the
    /// navigator on the last sample's telemetry (the estimate the law used),
    /// send the status. `flight_mode` and `servo` are the flight software's
    /// last; `load` the control task's compute time over its period.
    pub fn step(
        &mut self,
        t_s: f64,
        telemetry: Option<&Telemetry>,
        flight_mode: FlightMode,
        servo: &Input,
        load: f64,
    ) -> VehicleOutput {
        // the navigator flies from the last finite estimate (the flight
        // software refuses non-finite samples; this keeps it so here too)
        if let Some(t) = telemetry {
            if let Some(n) = &t.navigation
                && n.position_ned_m.iter().all(|v| v.is_finite())
            {
                self.at.position_ned_m = n.position_ned_m;
                if n.gps_fused {
                    self.last_gps_s = Some(t_s);
                }
            }
            if t.estimate[2].is_finite() {
                self.at.yaw_rad = t.estimate[2];
            }
        }
        self.at.t_s = t_s;
        let mut events = Events::default();
        let mut arm = None;
        while let Ok(u) = self.end.uplink.pop() {
            if let Some(a) = self.handle(u, &mut events) {
                arm = Some(a);
            }
        }
        if let Some(a) = arm {
            self.send(Downlink::Event(t_s, VehicleEvent::Armed(a)));
        }
        let silence = self.last_heartbeat_s.map(|h| t_s - h);
        let at = self.at;
        self.nav.link(&at, silence, &mut events);
        self.nav.fence(&at, &mut events);
        let reference = self.nav.step(&at, &mut events);
        for e in events.iter() {
            // with a land detector the flight software disarms after its
            // time on the ground, not the navigator at touchdown
            if e == NavEvent::Landed && self.armed && self.ground.on_ground().is_none() {
                self.armed = false;
                arm = Some(false);
                self.send(Downlink::Event(t_s, VehicleEvent::Armed(false)));
            }
            self.send(Downlink::Event(t_s, VehicleEvent::Nav(e)));
        }
        if self.samples % self.status_every == 0 {
            let status = self.status(t_s, telemetry, flight_mode, servo, reference, load);
            self.send(Downlink::Status(status));
        }
        self.samples += 1;
        VehicleOutput {
            reference,
            arm,
            events,
            config_change: self.config_change.take(),
            texts: std::mem::take(&mut self.texts),
        }
    }

    fn status(
        &self,
        t_s: f64,
        telemetry: Option<&Telemetry>,
        flight_mode: FlightMode,
        servo: &Input,
        reference: Reference,
        load: f64,
    ) -> VehicleStatus {
        let plan = self.nav.plan();
        let current = plan.get(self.nav.current_index()).map_or(0, |i| i.seq);
        let nav = telemetry.and_then(|t| t.navigation);
        let est = telemetry.map(|t| t.estimate);
        VehicleStatus {
            t_s,
            armed: self.armed,
            nav_mode: self.nav.mode(),
            flight_mode,
            attitude_rad: est.map_or(Vector3::zeros(), |e| Vector3::new(e[0], e[1], e[2])),
            rates_rad_s: est.map_or(Vector3::zeros(), |e| Vector3::new(e[6], e[7], e[8])),
            position_ned_m: self.at.position_ned_m,
            velocity_ned_m_s: nav.map_or(Vector3::zeros(), |n| n.velocity_ned_m_s),
            position_sigma_m: nav.map_or(Vector3::repeat(f64::MAX), |n| n.position_sigma_m),
            navigation_ok: nav.is_some(),
            gps_ok: self.last_gps_s.is_some_and(|g| t_s - g <= 1.0),
            servo: *servo,
            reference,
            mission_current: (current, u16::try_from(plan.len()).unwrap_or(u16::MAX)),
            link_lost: self.nav.link_lost(),
            load,
            ground: self.ground,
        }
    }
}
