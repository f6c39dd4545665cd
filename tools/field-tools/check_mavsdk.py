#!/usr/bin/env python3
"""MAVSDK-Python (its wheel's mavsdk_server) against `helicon sitl --gcs`:
connect, wait for a position, action.arm, action.takeoff, a one-waypoint
mission uploaded and started, its progress to the end, action.land and
the disarm, with the flight modes MAVSDK decodes on the way. With
`--tcp TCPPORT` the same over TCP: the SITL listens on both (`--gcs
udpin:…,tcpin:…`) and mavsdk_server connects to the TCP port
(`tcpout://`), as to a vehicle's TCP port 5760.

    python3 tools/field-tools/check_mavsdk.py PORT [--tcp TCPPORT]
"""
import asyncio
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sitl import CheckFailed, Sitl, expect, run  # noqa: E402


async def first(aiter, pred=lambda x: True):
    async for x in aiter:
        if pred(x):
            return x


STAGE = ["start"]


async def fly(address, grpc_port):
    from mavsdk import System
    from mavsdk.mission import MissionItem, MissionPlan
    drone = System(port=grpc_port)
    await drone.connect(system_address=address)
    await first(drone.core.connection_state(), lambda s: s.is_connected)
    STAGE[0] = "connected"
    modes = []

    async def watch():
        async for m in drone.telemetry.flight_mode():
            if not modes or modes[-1] != str(m):
                modes.append(str(m))
    watcher = asyncio.ensure_future(watch())
    pos = await first(drone.telemetry.position(), lambda p: not math.isnan(p.latitude_deg))
    STAGE[0] = "position"
    await drone.action.arm()
    STAGE[0] = "armed"
    await drone.action.takeoff()
    STAGE[0] = "takeoff accepted"
    await first(drone.telemetry.position(), lambda p: p.relative_altitude_m > 4.0)
    STAGE[0] = "climbed"
    north = pos.latitude_deg + 8.0 / 111_320.0
    item = MissionItem(north, pos.longitude_deg, 5.0, float("nan"), True, float("nan"), float("nan"),
                       MissionItem.CameraAction.NONE, float("nan"), float("nan"), 1.5, float("nan"),
                       float("nan"), MissionItem.VehicleAction.NONE)
    await drone.mission.upload_mission(MissionPlan([item]))
    STAGE[0] = "uploaded"
    await drone.mission.start_mission()
    STAGE[0] = "started"
    while not await drone.mission.is_mission_finished():
        await asyncio.sleep(0.5)
    STAGE[0] = "mission done"
    await drone.action.land()
    STAGE[0] = "landing"
    await first(drone.telemetry.armed(), lambda a: not a)
    watcher.cancel()
    return modes


def check(port, tcp_port=None):
    if tcp_port is None:
        gcs, address, grpc_port = None, f"udpout://127.0.0.1:{port}", 50061
    else:
        gcs = f"udpin:127.0.0.1:{port},tcpin:127.0.0.1:{tcp_port}"
        address, grpc_port = f"tcpout://127.0.0.1:{tcp_port}", 50062
    with Sitl(port, gcs=gcs) as sitl:
        try:
            modes = asyncio.run(asyncio.wait_for(fly(address, grpc_port), 90))
        except asyncio.TimeoutError:
            print(sitl.tail(), file=sys.stderr)
            raise CheckFailed(f"timed out after the stage {STAGE[0]!r}")
        except Exception as e:  # MAVSDK's ActionError, MissionError …
            print(sitl.tail(), file=sys.stderr)
            raise CheckFailed(f"after the stage {STAGE[0]!r}: {type(e).__name__}: {e}")
        expect("TAKEOFF" in modes and "MISSION" in modes and "LAND" in modes, f"modes {modes}")
        over = "" if tcp_port is None else " over TCP"
        return f"arm, takeoff, mission (1 item), land{over}; modes {' → '.join(modes)}"


if __name__ == "__main__":
    port = int(sys.argv[1]) if len(sys.argv) > 1 else 14604
    tcp = int(sys.argv[3]) if len(sys.argv) > 3 and sys.argv[2] == "--tcp" else None
    sys.exit(run("mavsdk" if tcp is None else "mavsdk-tcp", lambda: check(port, tcp)))
