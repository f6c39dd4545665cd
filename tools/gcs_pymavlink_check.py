#!/usr/bin/env python3
"""Fly the gcs_sitl example from pymavlink, an independent MAVLink client.

Start the SITL first (real time), then this script:

    cargo run --release -p helicon-gcs --example gcs_sitl -- udpout:127.0.0.1:14550 120 &
    python3 tools/gcs_pymavlink_check.py [PORT]

It checks: a HEARTBEAT of a helicopter, the full parameter list, a rejected
PARAM_SET answered with the unchanged value, arm, takeoff to 5 m, land,
disarmed. Exit status 0 when every check passed.
"""
import sys
import time

from pymavlink import mavutil


def main() -> int:
    port = int(sys.argv[1]) if len(sys.argv) > 1 else 14550
    m = mavutil.mavlink_connection(f"udpin:127.0.0.1:{port}", source_system=255)
    hb = m.wait_heartbeat(timeout=20)
    if hb is None:
        print("no heartbeat")
        return 1
    assert hb.type == mavutil.mavlink.MAV_TYPE_HELICOPTER, hb
    print(f"heartbeat: system {m.target_system} component {m.target_component} type {hb.type}")
    m.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_GCS, mavutil.mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)

    m.mav.param_request_list_send(m.target_system, m.target_component)
    params = {}
    deadline = time.time() + 10
    while time.time() < deadline:
        p = m.recv_match(type="PARAM_VALUE", blocking=True, timeout=1)
        if p is None:
            continue
        params[p.param_id] = p.param_value
        if len(params) == p.param_count:
            break
    print(f"parameters: {len(params)}: {sorted(params)}")
    assert len(params) == p.param_count, params

    m.mav.param_set_send(m.target_system, m.target_component, b"NAV_MAX_ACC", 100.0,
                         mavutil.mavlink.MAV_PARAM_TYPE_REAL32)
    p = None
    deadline = time.time() + 5
    while time.time() < deadline and (p is None or p.param_id != "NAV_MAX_ACC"):
        p = m.recv_match(type="PARAM_VALUE", blocking=True, timeout=1)
    assert p is not None and p.param_id == "NAV_MAX_ACC" and p.param_value == params["NAV_MAX_ACC"], p
    print(f"rejected set answered with {p.param_value}")

    def command(cmd, *params7):
        m.mav.command_long_send(m.target_system, m.target_component, cmd, 0, *params7)
        ack = m.recv_match(type="COMMAND_ACK", blocking=True, timeout=5)
        assert ack is not None and ack.command == cmd, ack
        return ack.result

    assert command(mavutil.mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1, 0, 0, 0, 0, 0, 0) == 0
    # param7 NaN: the default height (NAV_TKOFF_ALT, 5 m); a number is AMSL, as PX4 reads it
    assert command(mavutil.mavlink.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, float("nan")) == 0
    top = 0.0
    deadline = time.time() + 30
    while time.time() < deadline and top < 4.7:
        g = m.recv_match(type="GLOBAL_POSITION_INT", blocking=True, timeout=1)
        if g is not None:
            top = max(top, g.relative_alt / 1000.0)
        m.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_GCS, mavutil.mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    print(f"took off to {top:.2f} m")
    assert top >= 4.7
    assert command(mavutil.mavlink.MAV_CMD_NAV_LAND, 0, 0, 0, 0, 0, 0, 0) == 0
    deadline = time.time() + 40
    armed = True
    while time.time() < deadline and armed:
        hb = m.recv_match(type="HEARTBEAT", blocking=True, timeout=1)
        if hb is not None:
            armed = bool(hb.base_mode & mavutil.mavlink.MAV_MODE_FLAG_SAFETY_ARMED)
        m.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_GCS, mavutil.mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    print("landed and disarmed" if not armed else "still armed")
    return 0 if not armed else 1


if __name__ == "__main__":
    sys.exit(main())
