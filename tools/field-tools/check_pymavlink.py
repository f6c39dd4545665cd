#!/usr/bin/env python3
"""pymavlink against `helicon sitl --gcs`: what MAVProxy and scripts rely on.

Two ground stations at once (system 255 and 254 on their own ports): the
HEARTBEAT names PX4's autopilot and modes as pymavlink decodes them;
AUTOPILOT_VERSION's capabilities; a command id the common dialect does not
define (ArduPilot's 42424) answered MAV_RESULT_UNSUPPORTED; a rally-point
upload refused MAV_MISSION_UNSUPPORTED in its own type; each station's answers to
it alone; arm, takeoff (NaN: the default height), the mode LAND set by name
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
    for cap in ("MISSION_INT", "COMMAND_INT", "MAVLINK2", "PARAM_FLOAT"):
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

    # a rally-point upload: refused in its own type, the mission untouched
    b.mav.mission_count_send(1, 1, 3, M.MAV_MISSION_TYPE_RALLY)
    ack = recv(b, "MISSION_ACK", d, "rally MISSION_ACK")
    expect(ack.type == M.MAV_MISSION_UNSUPPORTED and ack.mission_type == M.MAV_MISSION_TYPE_RALLY, f"{ack}")

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
    return f"PX4 modes {' → '.join(seen)}; unknown command and rally points refused; two stations"


if __name__ == "__main__":
    port = int(sys.argv[1]) if len(sys.argv) > 1 else 14601
    sys.exit(run("pymavlink", lambda: check(port)))
