//! The mission microservice of the server: uploads (with the item
//! timeout), downloads and clears of the flight mission, the fence and the
//! rally points.

// ground stations still send the superseded *_INT mission frames
#![allow(deprecated)]

use super::{Dest, MISSION_ITEM_RETRIES, MISSION_ITEM_TIMEOUT_S, Server, UPLOAD_IDLE_S, Upload};
use crate::fence::{MAX_FENCE_ITEMS, ZoneError, Zones};
use crate::geo::{MissionError, plan_of};
use crate::link::Uplink;
use crate::mission_item::item_float;
use crate::rally::{MAX_RALLY_POINTS, RallyPoints};
use mavlink::dialects::common::*;

impl Server {
    pub(super) fn mission_ack(&mut self, result: MavMissionResult, mission_type: MavMissionType) {
        let (target_system, target_component) = self.src;
        self.send(&MavMessage::MISSION_ACK(MISSION_ACK_DATA {
            target_system,
            target_component,
            mavtype: result,
            mission_type,
            ..MISSION_ACK_DATA::DEFAULT
        }));
    }

    /// Request item `seq` of the upload from its owner (addressed to its
    /// system and component) and start the item timeout.
    pub(super) fn request_item(&mut self, seq: u16) {
        let now = self.now_s();
        let Upload::Receiving {
            from,
            requester,
            requested_s,
            mission_type,
            ..
        } = &mut self.upload
        else {
            return;
        };
        *requested_s = now;
        let (to, (target_system, target_component)) = (*from, *requester);
        let mission_type = *mission_type;
        self.send_to(
            &MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
                seq,
                target_system,
                target_component,
                mission_type,
            }),
            Some(to),
        );
    }

    /// The upload's item timeout (on each status): the expected item is
    /// requested again after [`MISSION_ITEM_TIMEOUT_S`], and the upload is
    /// cancelled after [`MISSION_ITEM_RETRIES`] requests went unanswered.
    pub(super) fn upload_timeout(&mut self) {
        let now = self.now_s();
        let Upload::Receiving {
            from,
            requester,
            requested_s,
            retries,
            items,
            mission_type,
            ..
        } = &mut self.upload
        else {
            return;
        };
        let mission_type = *mission_type;
        if now - *requested_s < MISSION_ITEM_TIMEOUT_S {
            return;
        }
        let expected = items.len() as u16;
        if *retries < MISSION_ITEM_RETRIES {
            *retries += 1;
            self.request_item(expected);
            return;
        }
        let (to, (target_system, target_component)) = (*from, *requester);
        self.upload = Upload::Idle;
        self.say_to(
            MavSeverity::MAV_SEVERITY_WARNING,
            &format!("mission upload cancelled: no item {expected}"),
            Some(to),
        );
        self.send_to(
            &MavMessage::MISSION_ACK(MISSION_ACK_DATA {
                target_system,
                target_component,
                mavtype: MavMissionResult::MAV_MISSION_OPERATION_CANCELLED,
                mission_type,
                ..MISSION_ACK_DATA::DEFAULT
            }),
            Some(to),
        );
    }

    /// The flight mission, the fence and the rally points are offered;
    /// another type (ALL outside a clear) is refused
    /// (`MAV_MISSION_UNSUPPORTED`, answered in that type). `true`: one
    /// offered.
    pub(super) fn mission_type_ok(&mut self, mission_type: MavMissionType) -> bool {
        if matches!(
            mission_type,
            MavMissionType::MAV_MISSION_TYPE_MISSION
                | MavMissionType::MAV_MISSION_TYPE_FENCE
                | MavMissionType::MAV_MISSION_TYPE_RALLY
        ) {
            return true;
        }
        self.mission_ack(MavMissionResult::MAV_MISSION_UNSUPPORTED, mission_type);
        false
    }

    /// The items uploaded of a type (the mission's, the fence's or the
    /// rally points').
    pub(super) fn items_of(&self, mission_type: MavMissionType) -> &[MISSION_ITEM_INT_DATA] {
        match mission_type {
            MavMissionType::MAV_MISSION_TYPE_FENCE => &self.fence_items,
            MavMissionType::MAV_MISSION_TYPE_RALLY => &self.rally_items,
            _ => &self.mission,
        }
    }

    /// An upload refused: the operator told which item broke which rule (a
    /// `STATUSTEXT`), the station answered the protocol's result in the
    /// upload's type; what was there before is kept.
    fn refuse_upload(
        &mut self,
        what: &str,
        seq: u16,
        rule: &str,
        result: MavMissionResult,
        mission: MavMissionType,
    ) {
        self.say(
            MavSeverity::MAV_SEVERITY_WARNING,
            &format!("{what} refused: item {seq}: {rule}"),
        );
        self.mission_ack(result, mission);
    }

    /// Clear the rally points (a return flies home).
    pub(super) fn clear_rally(&mut self) {
        self.rally_items.clear();
        self.uplink(Uplink::Rally(Box::default()));
    }

    /// Clear the fence's zones (the cylinder stays).
    pub(super) fn clear_fence(&mut self) {
        self.fence_items.clear();
        self.zones = Zones::default();
        self.uplink(Uplink::Zones(Box::default()));
    }

    pub(super) fn mission_count(&mut self, c: &MISSION_COUNT_DATA, from: Dest) {
        if !self.mission_type_ok(c.mission_type) {
            return;
        }
        let mission = c.mission_type;
        let fence = mission == MavMissionType::MAV_MISSION_TYPE_FENCE;
        let rally = mission == MavMissionType::MAV_MISSION_TYPE_RALLY;
        let now = self.now_s();
        if let Upload::Receiving {
            from: owner,
            last_s,
            ..
        } = &self.upload
            && *owner != from
            && now - *last_s < UPLOAD_IDLE_S
        {
            // another ground station is uploading
            self.say(
                MavSeverity::MAV_SEVERITY_WARNING,
                "mission refused: another upload in progress",
            );
            self.mission_ack(MavMissionResult::MAV_MISSION_DENIED, mission);
            return;
        }
        let room = if fence {
            MAX_FENCE_ITEMS
        } else if rally {
            MAX_RALLY_POINTS
        } else {
            crate::navigator::MAX_MISSION_ITEMS * 2
        };
        if usize::from(c.count) > room {
            self.mission_ack(MavMissionResult::MAV_MISSION_NO_SPACE, mission);
            return;
        }
        if c.count == 0 && fence {
            self.upload = Upload::Idle;
            self.clear_fence();
            self.mission_ack(MavMissionResult::MAV_MISSION_ACCEPTED, mission);
            return;
        }
        if c.count == 0 && rally {
            self.upload = Upload::Idle;
            self.clear_rally();
            self.mission_ack(MavMissionResult::MAV_MISSION_ACCEPTED, mission);
            return;
        }
        if c.count == 0 {
            self.upload = Upload::Idle;
            self.mission.clear();
            self.mission_complete = false;
            self.uplink(Uplink::Plan(Box::default()));
            self.mission_ack(MavMissionResult::MAV_MISSION_ACCEPTED, mission);
            return;
        }
        self.upload = Upload::Receiving {
            from,
            requester: self.src,
            last_s: now,
            requested_s: now,
            retries: 0,
            mission_type: mission,
            count: c.count,
            items: Vec::with_capacity(usize::from(c.count)),
        };
        self.request_item(0);
    }

    pub(super) fn mission_item(&mut self, it: &MISSION_ITEM_INT_DATA, from: Dest) {
        let now = self.now_s();
        let Upload::Receiving {
            from: owner,
            last_s,
            retries,
            count,
            items,
            mission_type,
            ..
        } = &mut self.upload
        else {
            return;
        };
        if *owner != from || it.mission_type != *mission_type {
            return; // not the uploading ground station's, or not its type
        }
        let mission = *mission_type;
        *last_s = now;
        let expected = items.len() as u16;
        if it.seq < expected {
            // a repeat (its request was repeated): already taken
            return;
        }
        if it.seq > expected {
            // a skip: ask for the one expected
            self.request_item(expected);
            return;
        }
        *retries = 0;
        items.push(it.clone());
        if items.len() < usize::from(*count) {
            self.request_item(expected + 1);
            return;
        }
        let items = std::mem::take(items);
        self.upload = Upload::Idle;
        if mission == MavMissionType::MAV_MISSION_TYPE_FENCE {
            match Zones::from_items(&self.home, &items) {
                Ok(zones) => {
                    self.fence_items = items;
                    self.zones = zones;
                    self.uplink(Uplink::Zones(Box::new(zones)));
                    self.mission_ack(MavMissionResult::MAV_MISSION_ACCEPTED, mission);
                }
                Err(ZoneError { seq, rule, result }) => {
                    self.refuse_upload("fence", seq, rule, result, mission);
                }
            }
            return;
        }
        let fence = *self.fence();
        if mission == MavMissionType::MAV_MISSION_TYPE_RALLY {
            match RallyPoints::from_items(&self.home, &fence, &self.zones, &items) {
                Ok(points) => {
                    self.rally_items = items;
                    self.uplink(Uplink::Rally(Box::new(points)));
                    self.mission_ack(MavMissionResult::MAV_MISSION_ACCEPTED, mission);
                }
                Err(MissionError { seq, rule, result }) => {
                    self.refuse_upload("rally", seq, rule, result, mission);
                }
            }
            return;
        }
        match plan_of(&self.home, &fence, &self.zones, &items) {
            Ok(plan) => {
                self.mission = items;
                self.mission_complete = false;
                self.uplink(Uplink::Plan(Box::new(plan)));
                self.mission_ack(MavMissionResult::MAV_MISSION_ACCEPTED, mission);
            }
            Err(MissionError { seq, rule, result }) => {
                self.refuse_upload("mission", seq, rule, result, mission);
            }
        }
    }

    /// A download's item `seq`, as `MISSION_ITEM_INT` (`int`) or the legacy
    /// `MISSION_ITEM` (answer to `MISSION_REQUEST`), in the requested type.
    pub(super) fn send_item(&mut self, seq: u16, mission_type: MavMissionType, int: bool) {
        if !self.mission_type_ok(mission_type) {
            return;
        }
        let Some(it) = self.items_of(mission_type).get(usize::from(seq)).cloned() else {
            self.mission_ack(MavMissionResult::MAV_MISSION_INVALID_SEQUENCE, mission_type);
            return;
        };
        let (target_system, target_component) = self.src;
        let it = MISSION_ITEM_INT_DATA {
            target_system,
            target_component,
            ..it
        };
        let msg = if int {
            MavMessage::MISSION_ITEM_INT(it)
        } else {
            MavMessage::MISSION_ITEM(item_float(&it))
        };
        self.send(&msg);
    }

    pub(super) fn clear_all(&mut self, mission_type: MavMissionType) {
        // "all" clears the flight mission, the fence's zones and the rally
        // points; each type clears its own only
        let all = mission_type == MavMissionType::MAV_MISSION_TYPE_ALL;
        if !all && !self.mission_type_ok(mission_type) {
            return;
        }
        if all || mission_type == MavMissionType::MAV_MISSION_TYPE_FENCE {
            self.clear_fence();
        }
        if all || mission_type == MavMissionType::MAV_MISSION_TYPE_RALLY {
            self.clear_rally();
        }
        if all || mission_type == MavMissionType::MAV_MISSION_TYPE_MISSION {
            self.mission.clear();
            self.mission_complete = false;
            self.uplink(Uplink::Plan(Box::default()));
        }
        self.mission_ack(MavMissionResult::MAV_MISSION_ACCEPTED, mission_type);
    }
}
