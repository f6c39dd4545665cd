#!/usr/bin/env python3
"""pymavlink over TCP against `helicon sitl --gcs udpin:…,tcpin:…`.

Two TCP ground stations (`tcp:127.0.0.1:TCP_PORT`, systems 255 and 254) and
one UDP station (system 253) at once, each sent heartbeats; from the first
TCP station: a fence (one circle inclusion about home) and a mission
uploaded, both downloaded and compared with what was sent, every request and
answer addressed to that station (target_system, target_component) and none
reaching the others; then arm, take off, land (the mode LAND by name), the
disarm at touchdown; the UDP station still hears the vehicle at the end.

    python3 tools/field-tools/check_tcp.py UDP_PORT TCP_PORT
"""
import math
import os
import sys
import time

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sitl import Deadline, Sitl, connect, expect, recv, run, wait_heartbeat  # noqa: E402

M = mavutil.mavlink
ME = (255, 190)


def check(udp_port, tcp_port):
    gcs = f"udpin:127.0.0.1:{udp_port},tcpin:127.0.0.1:{tcp_port}"
    with Sitl(udp_port, gcs=gcs) as sitl:
        d = Deadline(90)
        try:
            return fly(udp_port, tcp_port, d)
        except Exception:
            print(sitl.tail(), file=sys.stderr)
            raise


def connect_tcp(port, system, d):
    """A TCP ground station (the SITL may still be starting: tried again)."""
    while True:
        d.check(f"no TCP connection to {port}")
        try:
            return mavutil.mavlink_connection(f"tcp:127.0.0.1:{port}", source_system=system,
                                              source_component=190, retries=0)
        except Exception:  # refused while the SITL starts
            time.sleep(0.2)


def addressed_to_me(m):
    return (m.target_system, m.target_component) == ME


def upload(a, d, mission_type, items):
    """Upload `items` (tuples of MISSION_ITEM_INT's fields) of `mission_type`
    from `a`; the MISSION_ACK's result."""
    a.mav.mission_count_send(1, 1, len(items), mission_type)
    while True:
        m = recv(a, ["MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK"], d,
                 f"upload of type {mission_type}")
        expect(addressed_to_me(m), f"not addressed to the uploader: {m}")
        expect(m.mission_type == mission_type, f"wrong type: {m}")
        if m.get_type() == "MISSION_ACK":
            return m.type
        frame, command, p1, x, y, z = items[m.seq]
        a.mav.mission_item_int_send(1, 1, m.seq, frame, command, 0, 1, p1, 0, 0, math.nan, x, y, z,
                                    mission_type)


def download(a, d, mission_type):
    """The items of `mission_type` as `a` downloads them."""
    a.mav.mission_request_list_send(1, 1, mission_type)
    n = recv(a, "MISSION_COUNT", d, f"count of type {mission_type}")
    expect(addressed_to_me(n) and n.mission_type == mission_type, f"{n}")
    out = []
    for seq in range(n.count):
        a.mav.mission_request_int_send(1, 1, seq, mission_type)
        it = recv(a, "MISSION_ITEM_INT", d, f"item {seq} of type {mission_type}",
                  lambda m, seq=seq: m.seq == seq)
        expect(addressed_to_me(it), f"item not addressed to the downloader: {it}")
        out.append((it.frame, it.command, it.param1, it.x, it.y, it.z))
    a.mav.mission_ack_send(1, 1, M.MAV_MISSION_ACCEPTED, mission_type)
    return out


def same(sent, got):
    return len(sent) == len(got) and all(
        s[:2] == g[:2] and s[3:5] == g[3:5] and abs(s[2] - g[2]) < 1e-3 and abs(s[5] - g[5]) < 1e-3
        for s, g in zip(sent, got))


def stray(m, types, within_s=0.5):
    """A message of `types` reached `m` within `within_s`."""
    return m.recv_match(type=types, blocking=True, timeout=within_s) is not None


def fly(udp_port, tcp_port, d):
    a = connect_tcp(tcp_port, 255, d)
    b = connect_tcp(tcp_port, 254, d)
    u = connect(udp_port, 253, 190)
    for m, name in ((a, "TCP a"), (b, "TCP b"), (u, "UDP u")):
        hb = wait_heartbeat(m, d)
        expect(hb.autopilot == M.MAV_AUTOPILOT_PX4, f"{name}: autopilot {hb.autopilot}")
    pos = recv(a, "GLOBAL_POSITION_INT", d, "a position")
    lat, lon = pos.lat, pos.lon

    # a fence about home: one circle of 100 m
    rel = M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
    fence = [(rel, M.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION, 100.0, lat, lon, 0.0)]
    r = upload(a, d, M.MAV_MISSION_TYPE_FENCE, fence)
    expect(r == M.MAV_MISSION_ACCEPTED, f"fence upload: result {r}")
    # a mission: take off to 5 m, a waypoint 10 m north
    mission = [(rel, M.MAV_CMD_NAV_TAKEOFF, 0.0, 0, 0, 5.0),
               (rel, M.MAV_CMD_NAV_WAYPOINT, 0.0, lat + 900, lon, 5.0)]
    r = upload(a, d, M.MAV_MISSION_TYPE_MISSION, mission)
    expect(r == M.MAV_MISSION_ACCEPTED, f"mission upload: result {r}")
    # a waypoint 200 m north, outside the fence: refused
    far = [mission[0], (rel, M.MAV_CMD_NAV_WAYPOINT, 0.0, lat + 18_000, lon, 5.0)]
    r = upload(a, d, M.MAV_MISSION_TYPE_MISSION, far)
    expect(r == M.MAV_MISSION_DENIED, f"mission outside the fence: result {r}")
    got_fence = download(a, d, M.MAV_MISSION_TYPE_FENCE)
    expect(same(fence, got_fence), f"fence downloaded {got_fence} != uploaded {fence}")
    got_mission = download(a, d, M.MAV_MISSION_TYPE_MISSION)
    expect(same(mission, got_mission), f"mission downloaded {got_mission} != uploaded {mission}")
    # none of a's protocol reached b or u
    for m, name in ((b, "b"), (u, "u")):
        expect(not stray(m, ["MISSION_REQUEST_INT", "MISSION_ACK", "MISSION_COUNT", "MISSION_ITEM_INT"]),
               f"a's mission protocol reached {name}")

    # arm, take off, land
    a.mav.command_long_send(1, 1, M.MAV_CMD_COMPONENT_ARM_DISARM, 0, 1, 0, 0, 0, 0, 0, 0)
    ack = recv(a, "COMMAND_ACK", d, "arm ack", lambda m: m.command == M.MAV_CMD_COMPONENT_ARM_DISARM)
    expect(ack.result == M.MAV_RESULT_ACCEPTED and addressed_to_me(ack), f"arm: {ack}")
    expect(not stray(b, "COMMAND_ACK"), "a's ack reached b")
    a.mav.command_long_send(1, 1, M.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, math.nan, math.nan, math.nan, math.nan)
    ack = recv(a, "COMMAND_ACK", d, "takeoff ack", lambda m: m.command == M.MAV_CMD_NAV_TAKEOFF)
    expect(ack.result == M.MAV_RESULT_ACCEPTED and addressed_to_me(ack), f"takeoff: {ack}")
    recv(a, "GLOBAL_POSITION_INT", d, "climb to 4.5 m", lambda m: m.relative_alt > 4500)
    # b sees the flight too (streams go to every peer)
    recv(b, "GLOBAL_POSITION_INT", d, "b sees the climb", lambda m: m.relative_alt > 4000)
    a.set_mode("LAND")
    ack = recv(a, "COMMAND_ACK", d, "DO_SET_MODE ack", lambda m: m.command == M.MAV_CMD_DO_SET_MODE)
    expect(ack.result == M.MAV_RESULT_ACCEPTED and addressed_to_me(ack), f"mode LAND: {ack}")
    recv(a, "HEARTBEAT", d, "disarm at touchdown",
         lambda m: m.get_srcSystem() == 1 and not m.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED)
    recv(u, "HEARTBEAT", d, "u still hears the vehicle", lambda m: m.get_srcSystem() == 1)
    left = d.left()
    return (f"2 TCP + 1 UDP stations; fence and mission up and down over TCP, the far waypoint refused; "
            f"flown and landed; {90 - left:.0f} s of 90")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.exit(run("tcp", lambda: check(int(sys.argv[1]), int(sys.argv[2]))))
