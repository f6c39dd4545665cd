#!/usr/bin/env python3
"""A MAVLink 1 ground station (pymavlink without MAVLINK20) against
`helicon sitl --gcs`: it is answered in MAVLink 1 — the HEARTBEAT, a
parameter read and a COMMAND_ACK all in MAVLink 1 frames (0xFE).

    python3 tools/field-tools/check_mavlink1.py PORT
"""
import os
import sys

os.environ.pop("MAVLINK20", None)
from pymavlink import mavutil  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sitl import Deadline, Sitl, connect, expect, recv, run, wait_heartbeat  # noqa: E402

M = mavutil.mavlink


def check(port):
    with Sitl(port) as sitl:
        d = Deadline(60)
        try:
            m = connect(port)
            expect(not m.mavlink20(), "pymavlink speaks MAVLink 2")
            hb = wait_heartbeat(m, d)
            frames = {hb.get_msgbuf()[0]}
            m.mav.param_request_read_send(1, 1, b"NAV_MAX_SPD", -1)
            p = recv(m, "PARAM_VALUE", d, "PARAM_VALUE", lambda x: x.param_id == "NAV_MAX_SPD")
            frames.add(p.get_msgbuf()[0])
            m.mav.command_long_send(1, 1, M.MAV_CMD_REQUEST_MESSAGE, 0, M.MAVLINK_MSG_ID_HEARTBEAT,
                                    0, 0, 0, 0, 0, 0)
            ack = recv(m, "COMMAND_ACK", d, "COMMAND_ACK")
            frames.add(ack.get_msgbuf()[0])
            expect(frames == {0xFE}, f"frame starts {sorted(hex(f) for f in frames)}")
            expect(ack.result == M.MAV_RESULT_ACCEPTED, f"{ack}")
            return f"HEARTBEAT, PARAM_VALUE ({p.param_value}), COMMAND_ACK in MAVLink 1"
        except Exception:
            print(sitl.tail(), file=sys.stderr)
            raise


if __name__ == "__main__":
    port = int(sys.argv[1]) if len(sys.argv) > 1 else 14602
    sys.exit(run("mavlink1", lambda: check(port)))
