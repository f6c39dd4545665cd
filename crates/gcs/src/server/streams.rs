//! What the server sends on its own: the vehicle's statuses as the
//! streams (each peer at its rates, on on-board time) and its events as
//! status texts and protocol messages.

// MISSION_CURRENT's and the stream messages' superseded fields are filled
#![allow(deprecated)]

use super::*;

impl Server {
    pub(super) fn on_status(&mut self, s: &VehicleStatus) {
        self.status = Some(*s);
        self.upload_timeout();
        if self.arm_requested == Some(s.armed) {
            self.arm_requested = None;
        }
        if s.flight_mode.name != self.last_flight_mode {
            if !self.last_flight_mode.is_empty() {
                let text = format!("flight mode {}", s.flight_mode.name);
                let sev = if s.flight_mode.name == "auto" || s.flight_mode.name == "disarmed" {
                    MavSeverity::MAV_SEVERITY_INFO
                } else {
                    MavSeverity::MAV_SEVERITY_WARNING
                };
                self.text_to(sev, &text, None);
            }
            self.last_flight_mode = s.flight_mode.name;
        }
        // a change of the landed state is sent at once (EXTENDED_SYS_STATE
        // due now, to every peer that streams it; its grid restarts there):
        // at 1 Hz a short take-off or landing state would be missed
        let landed_changed = self.last_landed.is_some_and(|l| l != s.ground.landed);
        self.last_landed = Some(s.ground.landed);
        for p in 0..self.peers.len() {
            if landed_changed {
                self.peers[p].next_due_s[EXTENDED_SYS_STATE_STREAM] = s.t_s;
            }
            let peer = &self.peers[p];
            let heartbeat_only = !peer.trusted && peer.configured;
            let silent =
                !peer.configured && peer.heard_s.is_none_or(|h| s.t_s - h > PEER_SILENCE_S);
            if (!peer.trusted && !heartbeat_only) || silent {
                continue;
            }
            for i in 0..STREAMS.len() {
                let peer = &self.peers[p];
                let Some(iv) = peer.intervals_s[i] else {
                    continue;
                };
                if heartbeat_only && STREAMS[i].0 != HEARTBEAT_DATA::ID {
                    continue;
                }
                let due = peer.next_due_s[i];
                if s.t_s + 1e-9 >= due {
                    self.current = Some(p);
                    self.send_stream(STREAMS[i].0, s);
                    self.current = None;
                    // stay on the grid; resynchronise after a gap
                    self.peers[p].next_due_s[i] = if s.t_s - due > iv {
                        s.t_s + iv
                    } else {
                        due + iv
                    };
                }
            }
        }
    }
    pub(super) fn on_event(&mut self, t_s: f64, e: VehicleEvent) {
        match e {
            VehicleEvent::Armed(a) => {
                self.text(
                    MavSeverity::MAV_SEVERITY_INFO,
                    if a { "armed" } else { "disarmed" },
                );
            }
            VehicleEvent::Warning(text) => {
                self.text(MavSeverity::MAV_SEVERITY_WARNING, text);
            }
            VehicleEvent::Notice(text) => {
                self.text(MavSeverity::MAV_SEVERITY_INFO, text);
            }
            VehicleEvent::FlightMode(name, reason) => {
                self.text(
                    MavSeverity::MAV_SEVERITY_WARNING,
                    &format!("{name}: {reason}"),
                );
            }
            VehicleEvent::Nav(n) => match n {
                NavEvent::Mode(m) => {
                    self.text(
                        MavSeverity::MAV_SEVERITY_INFO,
                        &format!("mode {}", m.as_str()),
                    );
                }
                NavEvent::Current(seq) => {
                    self.mission_complete = false;
                    if let Some(s) = self.status {
                        let m = self.mission_current(seq, &s);
                        self.send(&m);
                    }
                }
                NavEvent::Reached(seq) => {
                    self.mission_complete = usize::from(seq) + 1 >= self.mission.len();
                    self.send(&MavMessage::MISSION_ITEM_REACHED(
                        MISSION_ITEM_REACHED_DATA { seq },
                    ));
                }
                NavEvent::Landed => self.text(MavSeverity::MAV_SEVERITY_INFO, "landed"),
                NavEvent::LinkLost => self.text(
                    MavSeverity::MAV_SEVERITY_CRITICAL,
                    &format!("failsafe: ground-station link lost at {t_s:.1} s"),
                ),
                NavEvent::LinkRegained => {
                    self.text(
                        MavSeverity::MAV_SEVERITY_NOTICE,
                        "ground-station link regained",
                    );
                }
                NavEvent::FenceBreach(horizontal) => {
                    let limit = if horizontal {
                        "GF_MAX_HOR_DIST"
                    } else {
                        "GF_MAX_VER_DIST"
                    };
                    let action = match self.fence().action {
                        crate::fence::FenceAction::Warn => "warning only",
                        crate::fence::FenceAction::Hold => "hold",
                        crate::fence::FenceAction::Return => "return",
                        crate::fence::FenceAction::Land => "land",
                    };
                    self.text(
                        MavSeverity::MAV_SEVERITY_CRITICAL,
                        &format!("fence breached ({limit}): {action}"),
                    );
                }
            },
        }
    }

    /// The PX4 mode reported: the navigator's ([`modes::reported`]), or
    /// disarmed with a takeoff or mission asked for, that mode (as PX4 is in
    /// it before the arming, and QGroundControl waits to see it).
    pub(super) fn reported_mode(&self, s: &VehicleStatus) -> (u8, u8) {
        match self.pending {
            Some(Pending::Takeoff(_)) if !s.armed => modes::px4_of(NavMode::Takeoff),
            Some(Pending::Mission) if !s.armed => modes::px4_of(NavMode::Mission),
            _ => modes::reported(s.nav_mode, s.flight_mode.name),
        }
    }

    pub(super) fn heartbeat(&self, s: &VehicleStatus) -> HEARTBEAT_DATA {
        let (main, sub) = self.reported_mode(s);
        // PX4's base mode: custom mode enabled, armed, and the flags of the
        // mode's kind (pymavlink decodes the auto modes only with all three)
        let mut base = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
            | MavModeFlag::MAV_MODE_FLAG_STABILIZE_ENABLED;
        if s.armed {
            base |= MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED;
        }
        if main == modes::MAIN_MANUAL {
            base |= MavModeFlag::MAV_MODE_FLAG_MANUAL_INPUT_ENABLED;
        } else {
            base |=
                MavModeFlag::MAV_MODE_FLAG_GUIDED_ENABLED | MavModeFlag::MAV_MODE_FLAG_AUTO_ENABLED;
        }
        let system_status = if s.link_lost || !matches!(s.flight_mode.name, "auto" | "disarmed") {
            MavState::MAV_STATE_CRITICAL
        } else if s.armed {
            MavState::MAV_STATE_ACTIVE
        } else {
            MavState::MAV_STATE_STANDBY
        };
        HEARTBEAT_DATA {
            custom_mode: modes::custom_mode(main, sub),
            mavtype: MavType::MAV_TYPE_HELICOPTER,
            autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
            base_mode: base,
            system_status,
            mavlink_version: 3,
        }
    }

    /// MISSION_CURRENT: the item flown (the status's) and the mission's
    /// state.
    pub(super) fn mission_current(&self, seq: u16, s: &VehicleStatus) -> MavMessage {
        let total = self.mission.len() as u16;
        let mission_state = if total == 0 {
            MissionState::MISSION_STATE_NO_MISSION
        } else if self.mission_complete {
            MissionState::MISSION_STATE_COMPLETE
        } else if s.nav_mode == NavMode::Mission {
            MissionState::MISSION_STATE_ACTIVE
        } else {
            MissionState::MISSION_STATE_NOT_STARTED
        };
        MavMessage::MISSION_CURRENT(MISSION_CURRENT_DATA {
            seq,
            total,
            mission_state,
            ..MISSION_CURRENT_DATA::DEFAULT
        })
    }

    #[allow(clippy::too_many_lines)] // one message per arm
    pub(super) fn send_stream(&mut self, id: u32, s: &VehicleStatus) {
        let ms = (s.t_s * 1000.0).clamp(0.0, f64::from(u32::MAX)) as u32;
        let geo = self.home.to_geodetic(&s.position_ned_m);
        let lat = (geo.latitude_deg * 1e7) as i32;
        let lon = (geo.longitude_deg * 1e7) as i32;
        let alt_mm = (geo.height_m * 1000.0) as i32;
        let rel_mm = (-s.position_ned_m.z * 1000.0) as i32;
        let v = s.velocity_ned_m_s;
        let cm = |x: f64| (x * 100.0).clamp(-32767.0, 32767.0) as i16;
        let heading_deg = s.attitude_rad.z.to_degrees().rem_euclid(360.0);
        let servo_us =
            |u: f64| (1500.0 + u.to_degrees() * 500.0 / 30.0).clamp(800.0, 2200.0) as u16;
        let msg = match id {
            HEARTBEAT_DATA::ID => MavMessage::HEARTBEAT(self.heartbeat(s)),
            SYS_STATUS_DATA::ID => {
                let present = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_GYRO
                    | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_ACCEL
                    | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_MAG
                    | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_GPS
                    | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL
                    | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_ATTITUDE_STABILIZATION
                    | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL
                    | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_Z_ALTITUDE_CONTROL;
                let mut health = present;
                if !s.gps_ok {
                    health &= !MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_GPS;
                }
                if !s.navigation_ok {
                    health &= !(MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_GYRO
                        | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_ACCEL
                        | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_MAG);
                }
                MavMessage::SYS_STATUS(SYS_STATUS_DATA {
                    onboard_control_sensors_present: present,
                    onboard_control_sensors_enabled: present,
                    onboard_control_sensors_health: health,
                    load: (s.load * 1000.0).clamp(0.0, 1000.0) as u16,
                    voltage_battery: u16::MAX,
                    current_battery: -1,
                    battery_remaining: -1,
                    ..SYS_STATUS_DATA::DEFAULT
                })
            }
            EXTENDED_SYS_STATE_DATA::ID => {
                MavMessage::EXTENDED_SYS_STATE(EXTENDED_SYS_STATE_DATA {
                    vtol_state: MavVtolState::MAV_VTOL_STATE_UNDEFINED,
                    landed_state: match s.ground.landed {
                        LandedState::Undefined => MavLandedState::MAV_LANDED_STATE_UNDEFINED,
                        LandedState::OnGround => MavLandedState::MAV_LANDED_STATE_ON_GROUND,
                        LandedState::InAir => MavLandedState::MAV_LANDED_STATE_IN_AIR,
                        LandedState::Takeoff => MavLandedState::MAV_LANDED_STATE_TAKEOFF,
                        LandedState::Landing => MavLandedState::MAV_LANDED_STATE_LANDING,
                    },
                })
            }
            ATTITUDE_DATA::ID => MavMessage::ATTITUDE(ATTITUDE_DATA {
                time_boot_ms: ms,
                roll: s.attitude_rad.x as f32,
                pitch: s.attitude_rad.y as f32,
                yaw: s.attitude_rad.z as f32,
                rollspeed: s.rates_rad_s.x as f32,
                pitchspeed: s.rates_rad_s.y as f32,
                yawspeed: s.rates_rad_s.z as f32,
            }),
            GLOBAL_POSITION_INT_DATA::ID => {
                MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
                    time_boot_ms: ms,
                    lat,
                    lon,
                    alt: alt_mm,
                    relative_alt: rel_mm,
                    vx: cm(v.x),
                    vy: cm(v.y),
                    vz: cm(v.z),
                    hdg: (heading_deg * 100.0) as u16,
                })
            }
            LOCAL_POSITION_NED_DATA::ID => {
                MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
                    time_boot_ms: ms,
                    x: s.position_ned_m.x as f32,
                    y: s.position_ned_m.y as f32,
                    z: s.position_ned_m.z as f32,
                    vx: v.x as f32,
                    vy: v.y as f32,
                    vz: v.z as f32,
                })
            }
            GPS_RAW_INT_DATA::ID => MavMessage::GPS_RAW_INT(GPS_RAW_INT_DATA {
                time_usec: (s.t_s * 1e6).max(0.0) as u64,
                lat,
                lon,
                alt: alt_mm,
                eph: (s.position_sigma_m.xy().norm() * 100.0).clamp(0.0, 65534.0) as u16,
                epv: (s.position_sigma_m.z * 100.0).clamp(0.0, 65534.0) as u16,
                vel: (v.xy().norm() * 100.0).clamp(0.0, 65534.0) as u16,
                cog: (v.y.atan2(v.x).to_degrees().rem_euclid(360.0) * 100.0) as u16,
                fix_type: if s.gps_ok {
                    GpsFixType::GPS_FIX_TYPE_3D_FIX
                } else {
                    GpsFixType::GPS_FIX_TYPE_NO_FIX
                },
                satellites_visible: u8::MAX,
                ..GPS_RAW_INT_DATA::DEFAULT
            }),
            VFR_HUD_DATA::ID => MavMessage::VFR_HUD(VFR_HUD_DATA {
                airspeed: v.norm() as f32,
                groundspeed: v.xy().norm() as f32,
                alt: geo.height_m as f32,
                climb: (-v.z) as f32,
                heading: heading_deg as i16,
                // the collective servo's place in its 1000–2000 µs range
                throttle: ((f64::from(servo_us(s.servo[0])) - 1000.0) / 10.0).clamp(0.0, 100.0)
                    as u16,
            }),
            MISSION_CURRENT_DATA::ID => self.mission_current(s.mission_current.0, s),
            HOME_POSITION_DATA::ID => {
                let home = self.config.home;
                MavMessage::HOME_POSITION(HOME_POSITION_DATA {
                    latitude: (home.latitude_deg * 1e7).round() as i32,
                    longitude: (home.longitude_deg * 1e7).round() as i32,
                    altitude: (home.height_m * 1000.0).round() as i32,
                    q: [1.0, 0.0, 0.0, 0.0],
                    time_usec: (s.t_s * 1e6).max(0.0) as u64,
                    ..HOME_POSITION_DATA::DEFAULT
                })
            }
            SERVO_OUTPUT_RAW_DATA::ID => MavMessage::SERVO_OUTPUT_RAW(SERVO_OUTPUT_RAW_DATA {
                time_usec: ((s.t_s * 1e6) as u64 & u64::from(u32::MAX)) as u32,
                servo1_raw: servo_us(s.servo[0]),
                servo2_raw: servo_us(s.servo[1]),
                servo3_raw: servo_us(s.servo[2]),
                servo4_raw: servo_us(s.servo[3]),
                ..SERVO_OUTPUT_RAW_DATA::DEFAULT
            }),
            RC_CHANNELS_DATA::ID => MavMessage::RC_CHANNELS(RC_CHANNELS_DATA {
                time_boot_ms: ms,
                chan1_raw: servo_us(s.servo[0]),
                chan2_raw: servo_us(s.servo[1]),
                chan3_raw: servo_us(s.servo[2]),
                chan4_raw: servo_us(s.servo[3]),
                chancount: 4,
                rssi: u8::MAX,
                ..RC_CHANNELS_DATA::DEFAULT
            }),
            _ => return,
        };
        self.send(&msg);
    }
}
