#!/usr/bin/env python3
"""pymavlink against `helicon sitl --gcs`: what MAVProxy and scripts rely on.

Two ground stations at once (system 255 and 254 on their own ports): the
HEARTBEAT names PX4's autopilot and modes as pymavlink decodes them;
AUTOPILOT_VERSION's capabilities; a command id the common dialect does not
define (ArduPilot's 42424) answered MAV_RESULT_UNSUPPORTED; a rally point
uploaded and downloaded in its own mission type (MAV_MISSION_TYPE_RALLY), the
flight mission untouched; each station's answers to it alone; arm, takeoff (NaN: the default height), the mode LAND set by name
(pymavlink's px4_map) and the disarm at touchdown.

    python3 tools/field-tools/check_pymavlink.py PORT
"""
import math
import os
import sys

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sitl import Deadline, Sitl, connect, expect, recv, run, wait_heartbeat  # noqa: E402

M = mavutil.mavlink


def check(port):
    with Sitl(port) as sitl:
        d = Deadline(90)
        try:
            return fly(port, d)
        except Exception:
            print(sitl.tail(), file=sys.stderr)
            raise


def fly(port, d):
    a = connect(port, 255, 190)
    b = connect(port, 254, 190)
    hb = wait_heartbeat(a, d)
    wait_heartbeat(b, d)
    expect(hb.autopilot == M.MAV_AUTOPILOT_PX4, f"autopilot {hb.autopilot}")
    expect(hb.type == M.MAV_TYPE_HELICOPTER, f"type {hb.type}")
    expect(a.mode_mapping() is mavutil.px4_map, "pymavlink does not use its PX4 mode map")

    # AUTOPILOT_VERSION to A only
    a.mav.command_long_send(1, 1, M.MAV_CMD_REQUEST_MESSAGE, 0, M.MAVLINK_MSG_ID_AUTOPILOT_VERSION,
                            0, 0, 0, 0, 0, 0)
    av = recv(a, "AUTOPILOT_VERSION", d, "AUTOPILOT_VERSION")
    for cap in ("MISSION_INT", "COMMAND_INT", "MAVLINK2", "PARAM_FLOAT", "MISSION_FENCE", "MISSION_RALLY"):
        expect(av.capabilities & getattr(M, f"MAV_PROTOCOL_CAPABILITY_{cap}"), f"capability {cap}")
    ack = recv(a, "COMMAND_ACK", d, "REQUEST_MESSAGE ack",
               lambda m: m.command == M.MAV_CMD_REQUEST_MESSAGE)
    expect(ack.result == M.MAV_RESULT_ACCEPTED and ack.target_system == 255, f"{ack}")

    # an id the common dialect does not define, from B: answered to B
    b.mav.command_long_send(1, 1, 42424, 0, 0, 0, 0, 0, 0, 0, 0)
    ack = recv(b, "COMMAND_ACK", d, "ack of command 42424", lambda m: m.command == 42424)
    expect(ack.result == M.MAV_RESULT_UNSUPPORTED and (ack.target_system, ack.target_component) == (254, 190),
           f"{ack}")
    stray = a.recv_match(type="COMMAND_ACK", blocking=True, timeout=0.5,
                         condition="COMMAND_ACK.command==42424")
    expect(stray is None, "B's answer reached A")

    # a rally point 30 m north of home, uploaded from B in its own type and read back
    rally = M.MAV_MISSION_TYPE_RALLY
    x, y = round((57.0146 + 30.0 / 111_400.0) * 1e7), round(9.9869 * 1e7)
    b.mav.mission_count_send(1, 1, 1, rally)
    req = recv(b, "MISSION_REQUEST_INT", d, "rally MISSION_REQUEST_INT", lambda m: m.mission_type == rally)
    expect(req.seq == 0 and (req.target_system, req.target_component) == (254, 190), f"{req}")
    b.mav.mission_item_int_send(1, 1, 0, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, M.MAV_CMD_NAV_RALLY_POINT,
                                0, 0, 0, 0, 0, 0, x, y, 10.0, rally)
    ack = recv(b, "MISSION_ACK", d, "rally MISSION_ACK")
    expect(ack.type == M.MAV_MISSION_ACCEPTED and ack.mission_type == rally, f"{ack}")
    b.mav.mission_request_list_send(1, 1, rally)
    n = recv(b, "MISSION_COUNT", d, "rally MISSION_COUNT", lambda m: m.mission_type == rally)
    expect(n.count == 1, f"{n}")
    b.mav.mission_request_int_send(1, 1, 0, rally)
    it = recv(b, "MISSION_ITEM_INT", d, "rally MISSION_ITEM_INT", lambda m: m.mission_type == rally)
    expect((it.x, it.y, it.command) == (x, y, M.MAV_CMD_NAV_RALLY_POINT), f"{it}")
    b.mav.mission_request_list_send(1, 1, M.MAV_MISSION_TYPE_MISSION)
    n = recv(b, "MISSION_COUNT", d, "mission MISSION_COUNT",
             lambda m: m.mission_type == M.MAV_MISSION_TYPE_MISSION)
    expect(n.count == 0, f"the flight mission changed: {n}")

    # fly from A: arm, take off to the default height, land by mode name
    a.mav.command_long_send(1, 1, M.MAV_CMD_COMPONENT_ARM_DISARM, 0, 1, 0, 0, 0, 0, 0, 0)
    ack = recv(a, "COMMAND_ACK", d, "arm ack", lambda m: m.command == M.MAV_CMD_COMPONENT_ARM_DISARM)
    expect(ack.result == M.MAV_RESULT_ACCEPTED, f"arm: {ack}")
    a.mav.command_long_send(1, 1, M.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, math.nan, math.nan, math.nan, math.nan)
    ack = recv(a, "COMMAND_ACK", d, "takeoff ack", lambda m: m.command == M.MAV_CMD_NAV_TAKEOFF)
    expect(ack.result == M.MAV_RESULT_ACCEPTED, f"takeoff: {ack}")
    modes = []

    def climbed(m):
        if m.get_type() == "HEARTBEAT" and a.flightmode not in modes[-1:]:
            modes.append(a.flightmode)
        return m.get_type() == "GLOBAL_POSITION_INT" and m.relative_alt > 4500
    recv(a, ["GLOBAL_POSITION_INT", "HEARTBEAT"], d, "climb to 4.5 m", climbed)
    recv(a, "HEARTBEAT", d, "LOITER after the takeoff",
         lambda m: (modes.append(a.flightmode) or True) and a.flightmode == "LOITER")
    a.set_mode("LAND")
    ack = recv(a, "COMMAND_ACK", d, "DO_SET_MODE ack", lambda m: m.command == M.MAV_CMD_DO_SET_MODE)
    expect(ack.result == M.MAV_RESULT_ACCEPTED, f"mode LAND: {ack}")
    recv(a, "HEARTBEAT", d, "disarm at touchdown",
         lambda m: (modes.append(a.flightmode) or True)
         and not m.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED)
    seen = [x for i, x in enumerate(modes) if i == 0 or modes[i - 1] != x]
    expect("TAKEOFF" in seen and "LAND" in seen, f"modes {seen}")
    return f"PX4 modes {' → '.join(seen)}; unknown command refused; a rally point up and down; two stations"


if __name__ == "__main__":
    port = int(sys.argv[1]) if len(sys.argv) > 1 else 14601
    sys.exit(run("pymavlink", lambda: check(port)))
