//! The navigator (thesis Figure 3.5): missions and modes → the references the
//! LQI tracks, earth velocities `[vn ve vd]` and the heading ψ (the thesis's
//! controller outputs, §14.1).
//!
//! Every mode flies to a target position through one guidance law:
//!
//! 1. the wanted speed towards the target is the smallest of the leg's speed
//!    limit, the speed from which the acceleration limit still stops at the
//!    target (`√(2·a·d)`), and a proportional approach `k·d`;
//! 2. the commanded velocity moves towards the wanted one by at most
//!    `max_accel_m_s2·dt` per step (a vector rate limit: the reference the
//!    LQI sees never asks for more than the acceleration limit);
//! 3. the vertical part is limited to the climb speed upwards and the descent
//!    speed downwards;
//! 4. the heading reference turns towards the wanted heading by at most
//!    `yaw_rate_max_rad_s·dt` along the shorter way.
//!
//! A waypoint is reached when the estimated position is within its
//! acceptance radius (3-D); it is then held for its hold time. The local NED
//! frame is the home position's (the GPS receiver's origin); the ground is
//! `d = 0`. Allocation-free: a mission is a fixed-capacity [`Plan`].

use crate::fence::{Fence, FenceAction, Zones};
use crate::rally::RallyPoints;
use helicon_core::Reference;
use helicon_core::frames::wrap_pi;
use nalgebra::Vector3;

/// Largest number of items a mission holds.
pub const MAX_MISSION_ITEMS: usize = 64;

/// What the navigator does when the ground station's heartbeat is lost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LinkLossAction {
    /// Hold position (until the link returns and the operator acts).
    Hold,
    /// Hold for `link_loss_hold_s`, then return home and land.
    Return,
    /// Hold for `link_loss_hold_s`, then land where it is.
    Land,
}

impl LinkLossAction {
    /// The parameter's code (0 hold, 1 return, 2 land).
    pub fn code(self) -> u8 {
        match self {
            LinkLossAction::Hold => 0,
            LinkLossAction::Return => 1,
            LinkLossAction::Land => 2,
        }
    }

    /// The action of a code.
    pub fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(LinkLossAction::Hold),
            1 => Some(LinkLossAction::Return),
            2 => Some(LinkLossAction::Land),
            _ => None,
        }
    }
}

/// The navigator's tuning (the ground station's parameters; the
/// `[gcs.navigator]` section of the on-board configuration, every field
/// optional).
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NavigatorConfig {
    /// Horizontal speed of mission legs without a speed of their own (m/s).
    pub cruise_speed_m_s: f64,
    /// Largest horizontal speed any mode or target asks for (m/s).
    pub max_speed_m_s: f64,
    /// Largest change of the velocity reference (m/s²).
    pub max_accel_m_s2: f64,
    /// Largest upward speed (m/s).
    pub climb_speed_m_s: f64,
    /// Largest downward speed, and the landing speed (m/s).
    pub descent_speed_m_s: f64,
    /// Proportional approach gain: velocity per metre of position error (1/s).
    pub position_gain_1_s: f64,
    /// Largest heading rate of the reference (rad/s).
    pub yaw_rate_max_rad_s: f64,
    /// Default acceptance radius of a waypoint (m).
    pub acceptance_radius_m: f64,
    /// Takeoff height above home when a command gives none (m).
    pub takeoff_height_m: f64,
    /// Height above home at which a landing is complete (m).
    pub landed_height_m: f64,
    /// Guided velocity targets older than this are replaced by a hold (s).
    pub guided_timeout_s: f64,
    /// Ground-station heartbeat silence that is a link loss (s).
    pub link_loss_timeout_s: f64,
    /// Hold time before the link-loss action (s).
    pub link_loss_hold_s: f64,
    /// What a link loss does.
    pub link_loss_action: LinkLossAction,
    /// The geofence (`[gcs.navigator.fence]`): targets outside it are
    /// refused, a breach of the estimate acts.
    pub fence: Fence,
}

impl Default for NavigatorConfig {
    fn default() -> Self {
        NavigatorConfig {
            cruise_speed_m_s: 2.0,
            max_speed_m_s: 5.0,
            max_accel_m_s2: 1.0,
            climb_speed_m_s: 1.0,
            descent_speed_m_s: 0.5,
            position_gain_1_s: 0.5,
            yaw_rate_max_rad_s: 0.5,
            acceptance_radius_m: 1.0,
            takeoff_height_m: 5.0,
            landed_height_m: 0.2,
            guided_timeout_s: 1.0,
            link_loss_timeout_s: 5.0,
            link_loss_hold_s: 5.0,
            link_loss_action: LinkLossAction::Return,
            fence: Fence::default(),
        }
    }
}

/// A tuning value outside its range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field} = {value}: {rule}")]
pub struct ConfigRangeError {
    /// The field (the parameter's name in the table).
    pub field: &'static str,
    /// The value refused.
    pub value: f64,
    /// The rule it breaks.
    pub rule: &'static str,
}

fn in_range(field: &'static str, value: f64, lo: f64, hi: f64) -> Result<(), ConfigRangeError> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(())
    } else {
        Err(ConfigRangeError {
            field,
            value,
            rule: "outside its range (see the parameter table)",
        })
    }
}

impl NavigatorConfig {
    /// The ranges of the fields, `(field, low, high)`.
    pub const RANGES: [(&'static str, f64, f64); 13] = [
        ("cruise_speed_m_s", 0.1, 15.0),
        ("max_speed_m_s", 0.1, 15.0),
        ("max_accel_m_s2", 0.1, 5.0),
        ("climb_speed_m_s", 0.1, 5.0),
        ("descent_speed_m_s", 0.1, 3.0),
        ("position_gain_1_s", 0.05, 2.0),
        ("yaw_rate_max_rad_s", 0.05, 2.0),
        ("acceptance_radius_m", 0.2, 20.0),
        ("takeoff_height_m", 1.0, 100.0),
        ("landed_height_m", 0.05, 2.0),
        ("guided_timeout_s", 0.1, 10.0),
        ("link_loss_timeout_s", 1.0, 120.0),
        ("link_loss_hold_s", 0.0, 120.0),
    ];

    /// The numeric fields in the order of [`NavigatorConfig::RANGES`].
    pub fn values(&self) -> [f64; 13] {
        [
            self.cruise_speed_m_s,
            self.max_speed_m_s,
            self.max_accel_m_s2,
            self.climb_speed_m_s,
            self.descent_speed_m_s,
            self.position_gain_1_s,
            self.yaw_rate_max_rad_s,
            self.acceptance_radius_m,
            self.takeoff_height_m,
            self.landed_height_m,
            self.guided_timeout_s,
            self.link_loss_timeout_s,
            self.link_loss_hold_s,
        ]
    }

    /// A tuning from the numeric fields (in the order of
    /// [`NavigatorConfig::RANGES`]), the link-loss action and the fence;
    /// not validated.
    pub fn from_values(v: [f64; 13], link_loss_action: LinkLossAction, fence: Fence) -> Self {
        NavigatorConfig {
            cruise_speed_m_s: v[0],
            max_speed_m_s: v[1],
            max_accel_m_s2: v[2],
            climb_speed_m_s: v[3],
            descent_speed_m_s: v[4],
            position_gain_1_s: v[5],
            yaw_rate_max_rad_s: v[6],
            acceptance_radius_m: v[7],
            takeoff_height_m: v[8],
            landed_height_m: v[9],
            guided_timeout_s: v[10],
            link_loss_timeout_s: v[11],
            link_loss_hold_s: v[12],
            link_loss_action,
            fence,
        }
    }

    /// Check every field against its range (the fence's as `fence.…`), and
    /// the cruise speed against the largest speed.
    pub fn validate(&self) -> Result<(), ConfigRangeError> {
        for ((field, lo, hi), v) in Self::RANGES.iter().zip(self.values()) {
            in_range(field, v, *lo, *hi)?;
        }
        self.fence.validate().map_err(|e| ConfigRangeError {
            field: match e.field {
                "max_hor_dist_m" => "fence.max_hor_dist_m",
                _ => "fence.max_ver_dist_m",
            },
            value: e.value,
            rule: e.rule,
        })?;
        if self.cruise_speed_m_s > self.max_speed_m_s {
            return Err(ConfigRangeError {
                field: "cruise_speed_m_s",
                value: self.cruise_speed_m_s,
                rule: "greater than max_speed_m_s",
            });
        }
        Ok(())
    }
}

/// What a mission item asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ItemKind {
    /// Climb vertically to the item's height.
    Takeoff,
    /// Fly to the item's position.
    Waypoint,
    /// Land at the item's horizontal position.
    Land,
    /// Return home and land.
    Return,
}

/// One mission item in the local NED frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Item {
    /// The ground station's sequence number (for MISSION_CURRENT / REACHED).
    pub seq: u16,
    /// What it asks for.
    pub kind: ItemKind,
    /// Target position NED about home (m).
    pub position_ned_m: Vector3<f64>,
    /// Horizontal speed of the leg to it (m/s; `None`: the cruise speed).
    pub speed_m_s: Option<f64>,
    /// Heading at it (rad; `None`: along the leg).
    pub yaw_rad: Option<f64>,
    /// Acceptance radius (m; `None`: the configured one).
    pub acceptance_m: Option<f64>,
    /// Time held at it once reached (s).
    pub hold_s: f64,
}

/// A mission: fixed capacity, no allocation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plan {
    items: [Option<Item>; MAX_MISSION_ITEMS],
    len: usize,
}

impl Default for Plan {
    fn default() -> Self {
        Plan {
            items: [None; MAX_MISSION_ITEMS],
            len: 0,
        }
    }
}

impl Plan {
    /// Append an item; `false` when the plan is full or the item has a
    /// non-finite number.
    pub fn push(&mut self, item: Item) -> bool {
        let finite = item.position_ned_m.iter().all(|v| v.is_finite())
            && item.speed_m_s.is_none_or(|v| v.is_finite() && v > 0.0)
            && item.yaw_rad.is_none_or(f64::is_finite)
            && item.acceptance_m.is_none_or(|v| v.is_finite() && v > 0.0)
            && item.hold_s.is_finite()
            && item.hold_s >= 0.0;
        if self.len >= MAX_MISSION_ITEMS || !finite {
            return false;
        }
        self.items[self.len] = Some(item);
        self.len += 1;
        true
    }

    /// Number of items.
    pub fn len(&self) -> usize {
        self.len
    }

    /// No items.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The item at `i`.
    pub fn get(&self, i: usize) -> Option<&Item> {
        self.items.get(i).and_then(Option::as_ref)
    }
}

/// The navigator's mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NavMode {
    /// On the ground or disarmed: the reference is zero velocity, heading held.
    Idle,
    /// Climbing to the takeoff height, then hold.
    Takeoff,
    /// Flying the mission.
    Mission,
    /// Holding a position and heading.
    Hold,
    /// Flying to the nearest of home and the rally points at the current
    /// height, then landing there.
    Return,
    /// Descending to the ground where it is.
    Land,
    /// Following the ground station's velocity or position targets.
    Guided,
}

impl NavMode {
    /// The name shown to the operator.
    pub fn as_str(self) -> &'static str {
        match self {
            NavMode::Idle => "IDLE",
            NavMode::Takeoff => "TAKEOFF",
            NavMode::Mission => "MISSION",
            NavMode::Hold => "HOLD",
            NavMode::Return => "RETURN",
            NavMode::Land => "LAND",
            NavMode::Guided => "GUIDED",
        }
    }

    /// A code (0..=6 in declaration order): helicon's own number of the mode
    /// (the HEARTBEAT reports PX4's custom modes instead: `crate::modes`).
    pub fn code(self) -> u32 {
        self as u32
    }

    /// The mode of a code.
    pub fn from_code(code: u32) -> Option<Self> {
        [
            NavMode::Idle,
            NavMode::Takeoff,
            NavMode::Mission,
            NavMode::Hold,
            NavMode::Return,
            NavMode::Land,
            NavMode::Guided,
        ]
        .get(code as usize)
        .copied()
    }
}

/// Something the operator is told about.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NavEvent {
    /// The mode changed.
    Mode(NavMode),
    /// The mission item with this sequence number is now the target.
    Current(u16),
    /// The mission item with this sequence number was reached.
    Reached(u16),
    /// The landing is complete (the vehicle disarms).
    Landed,
    /// The ground station's heartbeat was lost: the failsafe started.
    LinkLost,
    /// The heartbeat came back.
    LinkRegained,
    /// The estimate left the fence while flying: the fence's action began
    /// (`true`: the horizontal limit, `false`: the height).
    FenceBreach(bool),
}

/// The estimated state the navigator flies from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NavInput {
    /// On-board time (s).
    pub t_s: f64,
    /// Estimated position NED about home (m).
    pub position_ned_m: Vector3<f64>,
    /// Estimated heading (rad).
    pub yaw_rad: f64,
    /// The flight software's land detector: on the ground or not (`None`:
    /// it has none, and a landing ends at `landed_height_m` above home).
    pub on_ground: Option<bool>,
}

/// A guided target from the ground station.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GuidedTarget {
    /// Velocity NED (m/s), with an optional heading (rad).
    Velocity(Vector3<f64>, Option<f64>),
    /// Position NED about home (m), with an optional heading (rad).
    Position(Vector3<f64>, Option<f64>),
}

/// The navigator's state.
#[derive(Debug, Clone)]
pub struct Navigator {
    config: NavigatorConfig,
    mode: NavMode,
    plan: Plan,
    current: usize,
    /// Target position of the mode now (NED, m).
    target_ned_m: Vector3<f64>,
    target_yaw_rad: Option<f64>,
    leg_speed_m_s: f64,
    reached_at_s: Option<f64>,
    velocity_ref: Vector3<f64>,
    yaw_ref_rad: f64,
    initialised: bool,
    guided: Option<(GuidedTarget, f64)>,
    link_lost_at_s: Option<f64>,
    last_t_s: Option<f64>,
    /// A breach was acted on and the estimate has not come back inside.
    fence_breached: bool,
    /// The zones uploaded into the fence (none: the cylinder alone).
    zones: Zones,
    /// The rally points (none: a return flies home).
    rally: RallyPoints,
}

impl Navigator {
    /// An idle navigator with this tuning (validated).
    pub fn new(config: NavigatorConfig) -> Result<Self, ConfigRangeError> {
        config.validate()?;
        Ok(Navigator {
            config,
            mode: NavMode::Idle,
            plan: Plan::default(),
            current: 0,
            target_ned_m: Vector3::zeros(),
            target_yaw_rad: None,
            leg_speed_m_s: config.cruise_speed_m_s,
            reached_at_s: None,
            velocity_ref: Vector3::zeros(),
            yaw_ref_rad: 0.0,
            initialised: false,
            guided: None,
            link_lost_at_s: None,
            last_t_s: None,
            fence_breached: false,
            zones: Zones::default(),
            rally: RallyPoints::default(),
        })
    }

    /// The tuning.
    pub fn config(&self) -> &NavigatorConfig {
        &self.config
    }

    /// Replace the tuning (validated; the old one stays on error).
    pub fn set_config(&mut self, config: NavigatorConfig) -> Result<(), ConfigRangeError> {
        config.validate()?;
        self.config = config;
        Ok(())
    }

    /// The mode now.
    pub fn mode(&self) -> NavMode {
        self.mode
    }

    /// The mission.
    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// The index of the current mission item.
    pub fn current_index(&self) -> usize {
        self.current
    }

    /// The target position of the mode now (NED, m).
    pub fn target_ned_m(&self) -> Vector3<f64> {
        self.target_ned_m
    }

    /// The ground-station link is lost (failsafe active).
    pub fn link_lost(&self) -> bool {
        self.link_lost_at_s.is_some()
    }

    /// Replace the mission (the mode is unchanged; a running mission
    /// restarts at its first item on the next [`Navigator::start_mission`]).
    pub fn set_plan(&mut self, plan: Plan) {
        self.plan = plan;
        self.current = 0;
    }

    /// Replace the fence's uploaded zones (checked by the server).
    pub fn set_zones(&mut self, zones: Zones) {
        self.zones = zones;
    }

    /// The fence's uploaded zones.
    pub fn zones(&self) -> &Zones {
        &self.zones
    }

    /// Replace the rally points (checked by the server): the next return
    /// flies to the nearest of home and them.
    pub fn set_rally(&mut self, rally: RallyPoints) {
        self.rally = rally;
    }

    /// The rally points.
    pub fn rally(&self) -> &RallyPoints {
        &self.rally
    }

    fn enter(&mut self, mode: NavMode, events: &mut Events) {
        if self.mode != mode {
            self.mode = mode;
            events.push(NavEvent::Mode(mode));
        }
        self.reached_at_s = None;
    }

    /// Climb from `at` to `height_m` above home, then hold; `false`
    /// (nothing changes) for a height that is not positive or is above the
    /// fence.
    pub fn takeoff(&mut self, at: &NavInput, height_m: f64, events: &mut Events) -> bool {
        if !height_m.is_finite()
            || height_m <= 0.0
            || self
                .config
                .fence
                .check_height_in(&self.zones, height_m)
                .is_err()
        {
            return false;
        }
        self.init(at);
        self.target_ned_m = Vector3::new(at.position_ned_m.x, at.position_ned_m.y, -height_m);
        self.target_yaw_rad = Some(at.yaw_rad);
        self.enter(NavMode::Takeoff, events);
        true
    }

    /// Hold the position and heading of `at`.
    pub fn hold(&mut self, at: &NavInput, events: &mut Events) {
        self.init(at);
        self.target_ned_m = at.position_ned_m;
        self.target_yaw_rad = Some(at.yaw_rad);
        self.enter(NavMode::Hold, events);
    }

    /// Land where it is.
    pub fn land(&mut self, at: &NavInput, events: &mut Events) {
        self.init(at);
        self.target_ned_m = Vector3::new(at.position_ned_m.x, at.position_ned_m.y, 0.0);
        self.target_yaw_rad = Some(at.yaw_rad);
        self.enter(NavMode::Land, events);
    }

    /// Fly to the nearest of home and the rally points at the current
    /// height, then land there.
    pub fn return_home(&mut self, at: &NavInput, events: &mut Events) {
        self.init(at);
        let (place, _) = self.rally.nearest(&at.position_ned_m);
        self.target_ned_m = Vector3::new(place.x, place.y, at.position_ned_m.z);
        self.target_yaw_rad = None;
        self.leg_speed_m_s = self.config.cruise_speed_m_s;
        self.enter(NavMode::Return, events);
    }

    /// Back to idle (after disarming).
    pub fn idle(&mut self, at: &NavInput, events: &mut Events) {
        self.init(at);
        self.velocity_ref = Vector3::zeros();
        self.enter(NavMode::Idle, events);
    }

    /// Fly the mission from its first item; `false` when it is empty.
    pub fn start_mission(&mut self, at: &NavInput, events: &mut Events) -> bool {
        if self.plan.is_empty() {
            return false;
        }
        self.init(at);
        self.enter(NavMode::Mission, events);
        self.select(0, at, events);
        true
    }

    /// Follow a guided target (enters guided); `false` (nothing changes) for
    /// a non-finite one, a position outside the fence, or while returning or
    /// landing: a stream of targets already on its way must not take the
    /// vehicle out of a failsafe's return, so leaving RETURN or LAND takes an
    /// explicit mode change (HOLD) first.
    pub fn guided(&mut self, at: &NavInput, target: GuidedTarget, events: &mut Events) -> bool {
        if matches!(self.mode, NavMode::Return | NavMode::Land) {
            return false;
        }
        let ok = match target {
            GuidedTarget::Velocity(v, y) => {
                v.iter().all(|x| x.is_finite()) && y.is_none_or(f64::is_finite)
            }
            // the fence is checked here too: the server refuses such targets,
            // the navigator never flies one
            GuidedTarget::Position(p, y) => {
                self.config.fence.check_target_in(&self.zones, &p).is_ok()
                    && y.is_none_or(f64::is_finite)
            }
        };
        if !ok {
            return false;
        }
        self.init(at);
        self.guided = Some((target, at.t_s));
        if let GuidedTarget::Position(p, y) = target {
            self.target_ned_m = p;
            self.target_yaw_rad = y;
            self.leg_speed_m_s = self.config.cruise_speed_m_s;
        }
        self.enter(NavMode::Guided, events);
        true
    }

    fn init(&mut self, at: &NavInput) {
        if !self.initialised {
            self.yaw_ref_rad = at.yaw_rad;
            self.initialised = true;
        }
    }

    fn select(&mut self, i: usize, at: &NavInput, events: &mut Events) {
        self.current = i;
        self.reached_at_s = None;
        let Some(item) = self.plan.get(i).copied() else {
            // mission complete: hold the last item's position
            self.enter(NavMode::Hold, events);
            return;
        };
        events.push(NavEvent::Current(item.seq));
        self.leg_speed_m_s = item
            .speed_m_s
            .unwrap_or(self.config.cruise_speed_m_s)
            .min(self.config.max_speed_m_s);
        self.target_yaw_rad = item.yaw_rad;
        self.target_ned_m = match item.kind {
            ItemKind::Takeoff => Vector3::new(
                at.position_ned_m.x,
                at.position_ned_m.y,
                item.position_ned_m.z,
            ),
            // first over the landing point at the current height
            ItemKind::Land => Vector3::new(
                item.position_ned_m.x,
                item.position_ned_m.y,
                at.position_ned_m.z,
            ),
            ItemKind::Waypoint => item.position_ned_m,
            ItemKind::Return => {
                events.push(NavEvent::Reached(item.seq));
                self.return_home(at, events);
                return;
            }
        };
        if item.kind == ItemKind::Takeoff {
            self.target_yaw_rad = Some(self.target_yaw_rad.unwrap_or(at.yaw_rad));
        }
    }

    /// The ground station's heartbeat state: `silence_s` since its last
    /// heartbeat (`None`: never heard, no failsafe before a first contact).
    /// Starts the failsafe (hold) once the silence passes the timeout while
    /// flying; after `link_loss_hold_s` of it the configured action follows.
    pub fn link(&mut self, at: &NavInput, silence_s: Option<f64>, events: &mut Events) {
        let lost = silence_s.is_some_and(|s| s > self.config.link_loss_timeout_s);
        match (self.link_lost_at_s, lost) {
            (None, true) if self.mode != NavMode::Idle => {
                self.link_lost_at_s = Some(at.t_s);
                events.push(NavEvent::LinkLost);
                if !matches!(self.mode, NavMode::Land | NavMode::Return) {
                    self.hold(at, events);
                }
            }
            (Some(_), false) => {
                self.link_lost_at_s = None;
                events.push(NavEvent::LinkRegained);
            }
            (Some(t0), true)
                if self.mode == NavMode::Hold && at.t_s - t0 >= self.config.link_loss_hold_s =>
            {
                match self.config.link_loss_action {
                    LinkLossAction::Hold => {}
                    LinkLossAction::Return => self.return_home(at, events),
                    LinkLossAction::Land => self.land(at, events),
                }
            }
            _ => {}
        }
    }

    /// The estimate outside the fence while flying starts the fence's
    /// action once (hold, return at most at the fence's height and land,
    /// land, or a warning only); it is armed again when the estimate is
    /// back inside. A landing or a return already under way goes on.
    pub fn fence(&mut self, at: &NavInput, events: &mut Events) {
        let Some(v) = self
            .config
            .fence
            .outside_in(&self.zones, &at.position_ned_m)
        else {
            self.fence_breached = false;
            return;
        };
        if self.fence_breached || self.mode == NavMode::Idle {
            return;
        }
        self.fence_breached = true;
        events.push(NavEvent::FenceBreach(v.is_horizontal()));
        if matches!(self.mode, NavMode::Land | NavMode::Return) {
            return;
        }
        match self.config.fence.action {
            FenceAction::Warn => {}
            FenceAction::Hold => self.hold(at, events),
            FenceAction::Land => self.land(at, events),
            FenceAction::Return => {
                self.return_home(at, events);
                self.target_ned_m.z = self.target_ned_m.z.max(-self.config.fence.max_ver_dist_m);
            }
        }
    }

    /// One navigation step: the reference for the LQI now. Events of the
    /// step (waypoint reached, mode changes) go to `events`.
    pub fn step(&mut self, at: &NavInput, events: &mut Events) -> Reference {
        self.init(at);
        let dt = match self.last_t_s {
            Some(t) if at.t_s > t => (at.t_s - t).min(0.1),
            _ => 0.0,
        };
        self.last_t_s = Some(at.t_s);
        let wanted = match self.mode {
            NavMode::Idle => {
                self.velocity_ref = Vector3::zeros();
                self.yaw_ref_rad = at.yaw_rad;
                return self.reference();
            }
            NavMode::Guided => self.guided_velocity(at, events),
            _ => {
                self.progress(at, events);
                self.approach(at, self.speed_now())
            }
        };
        if self.mode == NavMode::Idle {
            return self.reference();
        }
        self.limit(wanted, dt);
        self.turn(at, dt);
        self.reference()
    }

    fn reference(&self) -> Reference {
        Reference {
            velocity_ned_m_s: self.velocity_ref,
            yaw_rad: self.yaw_ref_rad,
        }
    }

    fn speed_now(&self) -> f64 {
        match self.mode {
            NavMode::Mission | NavMode::Return | NavMode::Guided => self.leg_speed_m_s,
            _ => self.config.cruise_speed_m_s,
        }
    }

    fn guided_velocity(&mut self, at: &NavInput, events: &mut Events) -> Vector3<f64> {
        match self.guided {
            Some((GuidedTarget::Velocity(v, y), t0)) => {
                if at.t_s - t0 > self.config.guided_timeout_s {
                    self.hold(at, events);
                    return self.approach(at, self.config.cruise_speed_m_s);
                }
                self.target_yaw_rad = y;
                let h = v.xy().norm();
                let s = if h > self.config.max_speed_m_s {
                    self.config.max_speed_m_s / h
                } else {
                    1.0
                };
                Vector3::new(v.x * s, v.y * s, v.z)
            }
            _ => self.approach(at, self.leg_speed_m_s),
        }
    }

    /// Mode transitions on arrival.
    fn progress(&mut self, at: &NavInput, events: &mut Events) {
        let error = self.target_ned_m - at.position_ned_m;
        match self.mode {
            // arrived: hold the takeoff point (not where the arrival began)
            NavMode::Takeoff if error.z.abs() <= 0.3 => self.enter(NavMode::Hold, events),
            NavMode::Return if error.xy().norm() <= self.config.acceptance_radius_m => {
                self.land(at, events);
            }
            // touchdown: the land detector's word when there is one (the
            // descent crawls on below the target until it comes), else the
            // height above home
            NavMode::Land
                if at
                    .on_ground
                    .unwrap_or(at.position_ned_m.z >= -self.config.landed_height_m) =>
            {
                events.push(NavEvent::Landed);
                self.idle(at, events);
            }
            NavMode::Mission => self.mission_progress(at, error, events),
            _ => {}
        }
    }

    fn mission_progress(&mut self, at: &NavInput, error: Vector3<f64>, events: &mut Events) {
        let Some(item) = self.plan.get(self.current).copied() else {
            return;
        };
        let radius = item.acceptance_m.unwrap_or(self.config.acceptance_radius_m);
        match item.kind {
            ItemKind::Land if error.xy().norm() <= radius => {
                // over the landing point: the landing mode reports Landed
                events.push(NavEvent::Reached(item.seq));
                self.land(at, events);
                return;
            }
            ItemKind::Land | ItemKind::Return => return,
            ItemKind::Takeoff if error.z.abs() > radius => return,
            ItemKind::Waypoint if error.norm() > radius => return,
            _ => {}
        }
        let t_reached = match self.reached_at_s {
            Some(t) => t,
            None => {
                events.push(NavEvent::Reached(item.seq));
                self.reached_at_s = Some(at.t_s);
                at.t_s
            }
        };
        if at.t_s - t_reached >= item.hold_s {
            self.select(self.current + 1, at, events);
        }
    }

    /// The wanted velocity towards the target.
    fn approach(&self, at: &NavInput, speed_m_s: f64) -> Vector3<f64> {
        let c = &self.config;
        let error = self.target_ned_m - at.position_ned_m;
        let d = error.norm();
        if d < 1e-9 {
            return Vector3::zeros();
        }
        let braking = (2.0 * c.max_accel_m_s2 * d).sqrt();
        let speed = speed_m_s.min(braking).min(c.position_gain_1_s * d);
        let mut v = error * (speed / d);
        if self.mode == NavMode::Land {
            // straight down at the descent speed, slowing near the ground
            // to a crawl (0.3 m/s at the default: PX4's MPC_LAND_CRWL,
            // faster than the land detector's "no vertical movement")
            v.z = c
                .descent_speed_m_s
                .min((c.position_gain_1_s * error.z).max(0.6 * c.descent_speed_m_s));
        }
        v
    }

    /// Apply the acceleration, speed and vertical limits.
    fn limit(&mut self, wanted: Vector3<f64>, dt: f64) {
        let c = &self.config;
        let mut w = wanted;
        let h = w.xy().norm();
        if h > c.max_speed_m_s {
            w.x *= c.max_speed_m_s / h;
            w.y *= c.max_speed_m_s / h;
        }
        w.z = w.z.clamp(-c.climb_speed_m_s, c.descent_speed_m_s);
        let dv = w - self.velocity_ref;
        let step = c.max_accel_m_s2 * dt;
        let n = dv.norm();
        self.velocity_ref += if n > step { dv * (step / n) } else { dv };
    }

    /// Turn the heading reference towards the wanted heading.
    fn turn(&mut self, at: &NavInput, dt: f64) {
        let error = self.target_ned_m - at.position_ned_m;
        let wanted = match self.target_yaw_rad {
            Some(y) => y,
            // along the leg while far from the target, else keep it
            None if error.xy().norm() > 2.0 => error.y.atan2(error.x),
            None => self.yaw_ref_rad,
        };
        let step = self.config.yaw_rate_max_rad_s * dt;
        self.yaw_ref_rad += wrap_pi(wanted - self.yaw_ref_rad).clamp(-step, step);
    }
}

/// The events of one step: a small fixed-capacity list (no allocation).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Events {
    items: [Option<NavEvent>; 8],
    len: usize,
}

impl Events {
    /// Add an event (the ninth and later of one step are dropped).
    pub fn push(&mut self, e: NavEvent) {
        if self.len < self.items.len() {
            self.items[self.len] = Some(e);
            self.len += 1;
        }
    }

    /// The events in order.
    pub fn iter(&self) -> impl Iterator<Item = NavEvent> + '_ {
        self.items[..self.len].iter().filter_map(|e| *e)
    }

    /// Empty the list.
    pub fn clear(&mut self) {
        self.len = 0;
    }
}
