//! The server's commands (COMMAND_LONG/INT, SET_MODE, the stream
//! requests), parameters and guided targets.

// ground stations still send the superseded REQUEST_DATA_STREAM and SET_MODE
#![allow(deprecated)]

use super::*;

impl Server {
    pub(super) fn ack(&mut self, command: MavCmd, result: MavResult, sys: u8, comp: u8) {
        self.send(&MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
            command,
            result,
            target_system: sys,
            target_component: comp,
            ..COMMAND_ACK_DATA::DEFAULT
        }));
    }

    /// The vehicle's mode when it is returning or landing (guided targets
    /// do not take it out of either).
    pub(super) fn returning_or_landing(&self) -> Option<NavMode> {
        self.status
            .map(|s| s.nav_mode)
            .filter(|m| matches!(m, NavMode::Return | NavMode::Land))
    }

    pub(super) fn armed(&self) -> bool {
        self.arm_requested
            .unwrap_or(self.status.is_some_and(|s| s.armed))
    }

    pub(super) fn accepted(&mut self, u: Uplink) -> MavResult {
        if self.uplink(u) {
            MavResult::MAV_RESULT_ACCEPTED
        } else {
            MavResult::MAV_RESULT_TEMPORARILY_REJECTED
        }
    }

    /// A takeoff height (m above home) the fence allows, or the refusal.
    pub(super) fn takeoff_height(&mut self, h: f64) -> Result<f64, MavResult> {
        match self.fence().check_height_in(&self.zones, h) {
            Ok(()) if h > 0.0 => Ok(h),
            Ok(()) => {
                self.say(
                    MavSeverity::MAV_SEVERITY_WARNING,
                    &format!(
                        "takeoff refused: {:.1} m AMSL is not above home ({:.1} m AMSL)",
                        h + self.config.home.height_m,
                        self.config.home.height_m
                    ),
                );
                Err(MavResult::MAV_RESULT_DENIED)
            }
            Err(v) => {
                self.say(
                    MavSeverity::MAV_SEVERITY_WARNING,
                    &format!("takeoff refused: {v}"),
                );
                Err(MavResult::MAV_RESULT_DENIED)
            }
        }
    }

    /// On the ground: the land detector's word, or (a flight without one)
    /// the navigator idle.
    pub(super) fn on_ground(&self) -> bool {
        self.status
            .is_some_and(|s| s.ground.on_ground().unwrap_or(s.nav_mode == NavMode::Idle))
    }

    /// Take off, or (disarmed on the ground) take off at the arming, as PX4
    /// does: QGroundControl sends the takeoff first and arms when it is
    /// accepted.
    pub(super) fn takeoff(&mut self, h: f64) -> MavResult {
        let h = match self.takeoff_height(h) {
            Ok(h) => h,
            Err(r) => return r,
        };
        self.flying_or_pending(Uplink::Takeoff(h), Pending::Takeoff(h))
    }

    /// `u` when armed; disarmed on the ground, `p` at the arming.
    pub(super) fn flying_or_pending(&mut self, u: Uplink, p: Pending) -> MavResult {
        if self.armed() {
            self.pending = None;
            return self.accepted(u);
        }
        if !self.on_ground() {
            self.say(MavSeverity::MAV_SEVERITY_WARNING, "refused: not armed");
            return MavResult::MAV_RESULT_DENIED;
        }
        self.pending = Some(p);
        MavResult::MAV_RESULT_ACCEPTED
    }

    pub(super) fn command(&mut self, command: MavCmd, p: [f32; 7]) -> MavResult {
        let needs_armed = matches!(
            command,
            MavCmd::MAV_CMD_NAV_LAND
                | MavCmd::MAV_CMD_NAV_RETURN_TO_LAUNCH
                | MavCmd::MAV_CMD_NAV_LOITER_UNLIM
                | MavCmd::MAV_CMD_DO_PAUSE_CONTINUE
        );
        if needs_armed && !self.armed() {
            self.say(MavSeverity::MAV_SEVERITY_WARNING, "refused: not armed");
            return MavResult::MAV_RESULT_DENIED;
        }
        match command {
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM => self.arm(p[0], p[1]),
            MavCmd::MAV_CMD_NAV_TAKEOFF => {
                // param7: the altitude AMSL (PX4's, QGC's and MAVSDK's
                // reading); NaN: `NAV_TKOFF_ALT` above home
                let amsl = f64::from(p[6]);
                let h = if amsl.is_nan() {
                    self.params.config().takeoff_height_m
                } else {
                    amsl - self.config.home.height_m
                };
                self.takeoff(h)
            }
            MavCmd::MAV_CMD_NAV_LAND => self.accepted(Uplink::Land),
            MavCmd::MAV_CMD_NAV_RETURN_TO_LAUNCH => self.accepted(Uplink::Return),
            MavCmd::MAV_CMD_NAV_LOITER_UNLIM => self.accepted(Uplink::Hold),
            MavCmd::MAV_CMD_DO_PAUSE_CONTINUE if p[0] == 0.0 => self.accepted(Uplink::Hold),
            MavCmd::MAV_CMD_DO_PAUSE_CONTINUE => {
                // the navigator restarts a mission, it does not resume one
                self.say(
                    MavSeverity::MAV_SEVERITY_WARNING,
                    "continue not offered: MISSION_START flies the mission again",
                );
                MavResult::MAV_RESULT_UNSUPPORTED
            }
            MavCmd::MAV_CMD_MISSION_START => self.start_mission(),
            MavCmd::MAV_CMD_DO_SET_MODE => {
                // PX4's layout: param2 the main mode, param3 the sub mode
                let byte = |v: f32| {
                    if (0.0..=255.0).contains(&v) {
                        v as u8
                    } else {
                        0
                    }
                };
                self.set_mode(byte(p[1]), byte(p[2]))
            }
            MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL => self.set_interval(p[0], p[1]),
            MavCmd::MAV_CMD_GET_MESSAGE_INTERVAL => self.message_interval(p[0]),
            MavCmd::MAV_CMD_REQUEST_MESSAGE => self.request_message(p[0] as u32),
            MavCmd::MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES => {
                self.request_message(AUTOPILOT_VERSION_DATA::ID)
            }
            MavCmd::MAV_CMD_REQUEST_PROTOCOL_VERSION => {
                self.request_message(PROTOCOL_VERSION_DATA::ID)
            }
            MavCmd::MAV_CMD_GET_HOME_POSITION => self.request_message(HOME_POSITION_DATA::ID),
            _ => MavResult::MAV_RESULT_UNSUPPORTED,
        }
    }

    pub(super) fn start_mission(&mut self) -> MavResult {
        if self.mission.is_empty() {
            self.say(MavSeverity::MAV_SEVERITY_WARNING, "refused: no mission");
            return MavResult::MAV_RESULT_DENIED;
        }
        self.flying_or_pending(Uplink::StartMission, Pending::Mission)
    }

    /// `MAV_CMD_REQUEST_MESSAGE` (and the older requests of one message):
    /// the message to the peer that asked. `BATTERY_STATUS` is refused:
    /// this airframe has no battery monitor (SYS_STATUS says so with its
    /// battery fields −1 and `UINT16_MAX`).
    pub(super) fn request_message(&mut self, id: u32) -> MavResult {
        let Some(s) = self.status else {
            return MavResult::MAV_RESULT_TEMPORARILY_REJECTED;
        };
        if STREAMS.iter().any(|(i, _, _)| *i == id) {
            self.send_stream(id, &s);
            return MavResult::MAV_RESULT_ACCEPTED;
        }
        let msg = match id {
            AUTOPILOT_VERSION_DATA::ID => MavMessage::AUTOPILOT_VERSION(autopilot_version()),
            PROTOCOL_VERSION_DATA::ID => MavMessage::PROTOCOL_VERSION(PROTOCOL_VERSION_DATA {
                version: 200,
                min_version: 100,
                max_version: 200,
                ..PROTOCOL_VERSION_DATA::DEFAULT
            }),
            _ => return MavResult::MAV_RESULT_UNSUPPORTED,
        };
        self.send(&msg);
        MavResult::MAV_RESULT_ACCEPTED
    }

    /// `MAV_CMD_GET_MESSAGE_INTERVAL`: the peer's interval of a stream in a
    /// `MESSAGE_INTERVAL` (−1 off; 0: not a message the server streams).
    pub(super) fn message_interval(&mut self, id: f32) -> MavResult {
        let Some(p) = self.current else {
            return MavResult::MAV_RESULT_FAILED;
        };
        let id = if (0.0..=f32::from(u16::MAX)).contains(&id) {
            id as u16
        } else {
            return MavResult::MAV_RESULT_DENIED;
        };
        let interval_us = match STREAMS.iter().position(|(m, _, _)| *m == u32::from(id)) {
            Some(i) => self.peers[p].intervals_s[i].map_or(-1, |iv| (iv * 1e6).round() as i32),
            None => 0,
        };
        self.send(&MavMessage::MESSAGE_INTERVAL(MESSAGE_INTERVAL_DATA {
            interval_us,
            message_id: id,
        }));
        MavResult::MAV_RESULT_ACCEPTED
    }

    /// `MAV_CMD_DO_REPOSITION` in a global frame (x, y degrees × 10⁷,
    /// `i32::MAX`: unchanged; z, NaN: unchanged; param4 the yaw, radians
    /// as PX4 reads it, NaN: unchanged): a guided goto, inside the fence only,
    /// and not while returning or landing. Position and altitude both
    /// unchanged is PX4's pause (QGroundControl's Pause): hold where it is.
    pub(super) fn reposition(
        &mut self,
        frame: MavFrame,
        p: [f32; 7],
        x: i32,
        y: i32,
        z: f32,
    ) -> MavResult {
        if !self.armed() {
            self.say(MavSeverity::MAV_SEVERITY_WARNING, "refused: not armed");
            return MavResult::MAV_RESULT_DENIED;
        }
        let keep_xy = x == i32::MAX || y == i32::MAX;
        if keep_xy && z.is_nan() {
            return self.accepted(Uplink::Hold);
        }
        if let Some(mode) = self.returning_or_landing() {
            self.say(
                MavSeverity::MAV_SEVERITY_WARNING,
                &format!("goto refused: mode {} (set HOLD first)", mode.as_str()),
            );
            return MavResult::MAV_RESULT_DENIED;
        }
        let yaw = f64::from(p[3]);
        let yaw = yaw.is_finite().then_some(yaw);
        let here = self.status.map_or(Vector3::zeros(), |s| s.position_ned_m);
        let target = if keep_xy {
            global_position_ned_m(&self.home, frame, 0, 0, z)
                .map(|t| Vector3::new(here.x, here.y, t.z))
        } else {
            global_position_ned_m(&self.home, frame, x, y, z).map(|t| {
                if z.is_nan() {
                    Vector3::new(t.x, t.y, here.z)
                } else {
                    t
                }
            })
        };
        let Ok(p) = target else {
            self.say(
                MavSeverity::MAV_SEVERITY_WARNING,
                "goto refused: position or frame not valid",
            );
            return MavResult::MAV_RESULT_DENIED;
        };
        if let Err(v) = self.fence().check_target_in(&self.zones, &p) {
            self.say(
                MavSeverity::MAV_SEVERITY_WARNING,
                &format!("goto refused: {v}"),
            );
            return MavResult::MAV_RESULT_DENIED;
        }
        self.accepted(Uplink::Guided(GuidedTarget::Position(p, yaw)))
    }

    pub(super) fn arm(&mut self, arm: f32, force: f32) -> MavResult {
        let Some(s) = self.status else {
            return MavResult::MAV_RESULT_TEMPORARILY_REJECTED;
        };
        if arm == 1.0 {
            if !s.navigation_ok {
                self.say(
                    MavSeverity::MAV_SEVERITY_WARNING,
                    "refused: no navigation solution",
                );
                // (aligning: the station may try again, as PX4 answers a
                // failed arming check)
                return MavResult::MAV_RESULT_TEMPORARILY_REJECTED;
            }
            if !s.armed && s.ground.on_ground() == Some(false) {
                self.say(
                    MavSeverity::MAV_SEVERITY_WARNING,
                    "refused: arm off the ground",
                );
                return MavResult::MAV_RESULT_DENIED;
            }
            let r = self.accepted(Uplink::Arm(true));
            if r == MavResult::MAV_RESULT_ACCEPTED {
                self.arm_requested = Some(true);
                // what was asked for before the arming flies now
                match self.pending.take() {
                    Some(Pending::Takeoff(h)) => {
                        self.uplink(Uplink::Takeoff(h));
                    }
                    Some(Pending::Mission) => {
                        self.uplink(Uplink::StartMission);
                    }
                    None => {}
                }
            }
            r
        } else if arm == 0.0 {
            // disarming in the air stops the law: only on the ground, or forced
            if !self.on_ground() && force != 21196.0 {
                self.say(
                    MavSeverity::MAV_SEVERITY_WARNING,
                    "refused: disarm in flight (force with 21196)",
                );
                return MavResult::MAV_RESULT_DENIED;
            }
            self.pending = None;
            let r = self.accepted(Uplink::Arm(false));
            if r == MavResult::MAV_RESULT_ACCEPTED {
                self.arm_requested = Some(false);
            }
            r
        } else {
            MavResult::MAV_RESULT_DENIED
        }
    }

    /// A PX4 mode (main, sub) to fly ([`modes`]): set by `MAV_CMD_DO_SET_MODE`
    /// and `SET_MODE`. Disarmed on the ground, TAKEOFF and MISSION fly at
    /// the arming and HOLD cancels them; a mode helicon does not fly is
    /// denied.
    pub(super) fn set_mode(&mut self, main: u8, sub: u8) -> MavResult {
        let Some(mode) = modes::nav_of(main, sub) else {
            self.say(
                MavSeverity::MAV_SEVERITY_WARNING,
                &format!("mode refused: PX4 mode {main}/{sub} is not flown"),
            );
            return MavResult::MAV_RESULT_DENIED;
        };
        let armed = self.armed();
        match mode {
            NavMode::Takeoff => self.takeoff(self.params.config().takeoff_height_m),
            NavMode::Mission => self.start_mission(),
            NavMode::Hold if !armed => {
                self.pending = None;
                MavResult::MAV_RESULT_ACCEPTED
            }
            _ if !armed => {
                self.say(MavSeverity::MAV_SEVERITY_WARNING, "refused: not armed");
                MavResult::MAV_RESULT_DENIED
            }
            NavMode::Hold => self.accepted(Uplink::Hold),
            NavMode::Return => self.accepted(Uplink::Return),
            NavMode::Land => self.accepted(Uplink::Land),
            NavMode::Guided if self.status.is_some_and(|s| s.nav_mode == NavMode::Guided) => {
                MavResult::MAV_RESULT_ACCEPTED
            }
            NavMode::Guided => {
                self.say(
                    MavSeverity::MAV_SEVERITY_WARNING,
                    "OFFBOARD: entered by a SET_POSITION_TARGET_* target",
                );
                MavResult::MAV_RESULT_DENIED
            }
            NavMode::Idle => MavResult::MAV_RESULT_DENIED,
        }
    }

    /// A stream interval of the peer being answered.
    pub(super) fn set_interval(&mut self, id: f32, interval_us: f32) -> MavResult {
        let id = id as u32;
        let Some(i) = STREAMS.iter().position(|(m, _, _)| *m == id) else {
            return MavResult::MAV_RESULT_UNSUPPORTED;
        };
        let Some(p) = self.current else {
            return MavResult::MAV_RESULT_FAILED;
        };
        let us = f64::from(interval_us);
        let interval = if us == -1.0 {
            None
        } else if us == 0.0 {
            interval_of(STREAMS[i].2)
        } else if us.is_finite() && us >= 10_000.0 {
            Some(us * 1e-6)
        } else {
            // faster than 100 Hz: the status period
            return MavResult::MAV_RESULT_DENIED;
        };
        let now = self.now_s();
        let peer = &mut self.peers[p];
        peer.intervals_s[i] = interval;
        peer.next_due_s[i] = now;
        MavResult::MAV_RESULT_ACCEPTED
    }

    pub(super) fn request_stream(&mut self, r: &REQUEST_DATA_STREAM_DATA) {
        let ids: &[u32] = match r.req_stream_id {
            MavDataStream::MAV_DATA_STREAM_ALL => &[
                SYS_STATUS_DATA::ID,
                ATTITUDE_DATA::ID,
                GLOBAL_POSITION_INT_DATA::ID,
                LOCAL_POSITION_NED_DATA::ID,
                GPS_RAW_INT_DATA::ID,
                VFR_HUD_DATA::ID,
                SERVO_OUTPUT_RAW_DATA::ID,
                RC_CHANNELS_DATA::ID,
            ],
            MavDataStream::MAV_DATA_STREAM_RAW_SENSORS => &[GPS_RAW_INT_DATA::ID],
            MavDataStream::MAV_DATA_STREAM_EXTENDED_STATUS => &[SYS_STATUS_DATA::ID],
            MavDataStream::MAV_DATA_STREAM_RC_CHANNELS => {
                &[RC_CHANNELS_DATA::ID, SERVO_OUTPUT_RAW_DATA::ID]
            }
            MavDataStream::MAV_DATA_STREAM_POSITION => {
                &[GLOBAL_POSITION_INT_DATA::ID, LOCAL_POSITION_NED_DATA::ID]
            }
            MavDataStream::MAV_DATA_STREAM_EXTRA1 => &[ATTITUDE_DATA::ID],
            MavDataStream::MAV_DATA_STREAM_EXTRA2 => &[VFR_HUD_DATA::ID],
            _ => &[],
        };
        let interval = if r.start_stop == 0 || r.req_message_rate == 0 {
            -1.0
        } else {
            1e6 / f32::from(r.req_message_rate.min(100))
        };
        for id in ids {
            let _ = self.set_interval(*id as f32, interval);
        }
    }

    pub(super) fn param_value(&mut self, i: usize) {
        self.param_value_to(i, self.current.map(|p| self.peers[p].addr));
    }

    pub(super) fn param_value_to(&mut self, i: usize, to: Option<Dest>) {
        let Some((name, value)) = self.params.get(i) else {
            return;
        };
        self.send_to(
            &MavMessage::PARAM_VALUE(PARAM_VALUE_DATA {
                param_value: value,
                param_count: PARAMS.len() as u16,
                param_index: i as u16,
                param_id: name.into(),
                param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
            }),
            to,
        );
    }

    pub(super) fn param_set(&mut self, p: &PARAM_SET_DATA) {
        let name = p
            .param_id
            .to_str()
            .unwrap_or("")
            .trim_end_matches('\0')
            .to_string();
        match self.params.set(&name, p.param_value) {
            Ok(i) => {
                self.uplink(Uplink::Config(*self.params.config()));
                // every live ground station sees the new value
                self.param_value_to(i, None);
            }
            Err(ParamError::Unknown(_)) => {
                self.say(
                    MavSeverity::MAV_SEVERITY_WARNING,
                    &format!("no parameter {name}"),
                );
            }
            Err(e @ ParamError::Rejected { .. }) => {
                self.say(MavSeverity::MAV_SEVERITY_WARNING, &format!("refused {e}"));
                // the answer is the unchanged value
                if let Some(i) = self.params.index_of(&name) {
                    self.param_value(i);
                }
            }
        }
    }

    /// A `MISSION_ACK` to the peer and the system/component being answered.
    /// A guided target as the server takes it: finite, plausible, and a
    /// position inside the fence; a refusal is told in a status text
    /// (SET_POSITION_TARGET_* has no acknowledgement).
    pub(super) fn guided_target(&mut self, target: GuidedTarget) {
        if !self.armed() {
            self.say(
                MavSeverity::MAV_SEVERITY_WARNING,
                "guided refused: not armed",
            );
            return;
        }
        if let Some(mode) = self.returning_or_landing() {
            self.say(
                MavSeverity::MAV_SEVERITY_WARNING,
                &format!("guided refused: mode {} (set HOLD first)", mode.as_str()),
            );
            return;
        }
        let refusal = match target {
            GuidedTarget::Position(p, y) => match self.fence().check_target_in(&self.zones, &p) {
                Err(v) => Some(v.to_string()),
                Ok(()) if y.is_some_and(|y| !y.is_finite()) => Some("yaw not finite".into()),
                Ok(()) => None,
            },
            GuidedTarget::Velocity(v, y) => {
                if !(v.iter().all(|x| x.is_finite()) && y.is_none_or(f64::is_finite)) {
                    Some("velocity or yaw not finite".into())
                } else if v.norm() > MAX_GUIDED_SPEED_M_S {
                    Some(format!("velocity {:.0} m/s", v.norm()))
                } else {
                    None
                }
            }
        };
        if let Some(why) = refusal {
            self.say(
                MavSeverity::MAV_SEVERITY_WARNING,
                &format!("guided refused: {why}"),
            );
            return;
        }
        self.uplink(Uplink::Guided(target));
    }

    pub(super) fn guided(&mut self, t: &SET_POSITION_TARGET_LOCAL_NED_DATA) {
        if t.coordinate_frame != MavFrame::MAV_FRAME_LOCAL_NED {
            self.say(
                MavSeverity::MAV_SEVERITY_WARNING,
                "guided: only MAV_FRAME_LOCAL_NED",
            );
            return;
        }
        let position = Vector3::new(f64::from(t.x), f64::from(t.y), f64::from(t.z));
        if let Some(target) = target_of(t.type_mask, t.yaw, position, [t.vx, t.vy, t.vz]) {
            self.guided_target(target);
        }
    }

    pub(super) fn guided_global(&mut self, t: &SET_POSITION_TARGET_GLOBAL_INT_DATA) {
        let m = t.type_mask;
        let pos_ignored = m.contains(
            PositionTargetTypemask::POSITION_TARGET_TYPEMASK_X_IGNORE
                | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_Y_IGNORE
                | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_Z_IGNORE,
        );
        let position = if pos_ignored {
            Vector3::zeros()
        } else {
            let frame = match t.coordinate_frame {
                MavFrame::MAV_FRAME_GLOBAL_INT => MavFrame::MAV_FRAME_GLOBAL,
                MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT => {
                    MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT
                }
                f => f,
            };
            match global_position_ned_m(&self.home, frame, t.lat_int, t.lon_int, t.alt) {
                Ok(p) => p,
                Err(_) => {
                    self.say(
                        MavSeverity::MAV_SEVERITY_WARNING,
                        "guided refused: position or frame not valid",
                    );
                    return;
                }
            }
        };
        if let Some(target) = target_of(m, t.yaw, position, [t.vx, t.vy, t.vz]) {
            self.guided_target(target);
        }
    }
}
