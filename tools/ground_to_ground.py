#!/usr/bin/env python3
"""From the ground to the ground in real time, flown by pymavlink.

Starts `helicon sitl SCENARIO --speed realtime --gcs udpin:127.0.0.1:PORT`
(the helicopter on the ground, disarmed, rotor stopped, running until
stopped) and, as a ground station would: waits a random 5-60 s (the seed's),
uploads a mission (take-off to 5 m, two waypoints, return to launch), arms,
starts the mission (the take-off waits for the rotor's run-up), sees the
landing and the disarm, waits 30 s more, and checks that the helicopter is
still on the ground (EXTENDED_SYS_STATE), upright (ATTITUDE), within 2 m of
home (LOCAL_POSITION_NED, and the simulator's truth in log.csv after the
run), and that the program still runs; then stops it with SIGINT (exit
130, its logs written).

    python3 tools/ground_to_ground.py --helicon target/release/helicon --seed 1 [--seed 2 …]

Seeds fly in parallel (one SITL each, its own port; SCHED_FIFO as on
board, so that three on two cores keep their deadlines). Exit status 0 when
every flight passed; one line per flight with its figures.
"""
import argparse
import contextlib
import csv
import math
import os
import random
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time

from pymavlink import mavutil

M = mavutil.mavlink


def free_port() -> int:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


class Vehicle:
    """The ground station's view of the vehicle (pymavlink)."""

    def __init__(self, port: int):
        self.m = mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}", source_system=255,
                                            source_component=190)
        self.landed_state = None
        self.armed = None
        self.texts = []
        self.local = None
        self.attitude = None
        self.last_hb = 0.0

    def heartbeat(self):
        if time.time() - self.last_hb > 0.5:
            self.m.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            self.last_hb = time.time()

    def poll(self, timeout=0.05):
        self.heartbeat()
        msg = self.m.recv_match(blocking=True, timeout=timeout)
        if msg is None or msg.get_srcSystem() != 1:
            return None
        t = msg.get_type()
        if t == "EXTENDED_SYS_STATE":
            self.landed_state = msg.landed_state
        elif t == "HEARTBEAT":
            self.armed = bool(msg.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED)
        elif t == "STATUSTEXT":
            self.texts.append(msg.text)
        elif t == "LOCAL_POSITION_NED":
            self.local = msg
        elif t == "ATTITUDE":
            self.attitude = msg
        return msg

    def until(self, seconds, done):
        end = time.time() + seconds
        while time.time() < end:
            if done():
                return True
            self.poll()
        return done()

    def command(self, cmd, p1=0.0, p7=0.0):
        for _ in range(10):
            self.m.mav.command_long_send(1, 1, cmd, 0, p1, 0, 0, 0, 0, 0, p7)
            end = time.time() + 1.0
            while time.time() < end:
                msg = self.poll()
                if msg is not None and msg.get_type() == "COMMAND_ACK" and msg.command == cmd:
                    return msg.result
        raise AssertionError(f"no COMMAND_ACK for {cmd}")

    def upload(self, items):
        """The mission microservice: MISSION_COUNT, each item on request, the ack."""
        for _ in range(5):
            self.m.mav.mission_count_send(1, 1, len(items), M.MAV_MISSION_TYPE_MISSION)
            end = time.time() + 3.0
            while time.time() < end:
                msg = self.poll()
                if msg is None:
                    continue
                t = msg.get_type()
                if t in ("MISSION_REQUEST_INT", "MISSION_REQUEST"):
                    cmd, n, e, z = items[msg.seq]
                    self.m.mav.mission_item_int_send(
                        1, 1, msg.seq, M.MAV_FRAME_LOCAL_NED, cmd, 0, 1,
                        0, 0, 0, float("nan"), int(n * 1e4), int(e * 1e4), z,
                        M.MAV_MISSION_TYPE_MISSION)
                elif t == "MISSION_ACK":
                    assert msg.type == M.MAV_MISSION_ACCEPTED, msg
                    return
        raise AssertionError("mission upload not acknowledged")


def fly(helicon: str, scenario: str, seed: int, out_root: str) -> str:
    wait_s = random.Random(seed).uniform(5.0, 60.0)
    port = free_port()
    out = os.path.join(out_root, f"seed{seed}")
    proc = subprocess.Popen(
        [helicon, "sitl", scenario, "--speed", "realtime",
         "--gcs", f"udpin:127.0.0.1:{port}", "--out", out],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        v = Vehicle(port)
        assert v.until(30, lambda: v.landed_state is not None and v.armed is not None), \
            "no heartbeat or EXTENDED_SYS_STATE"
        stayed = [True]

        def on_ground_disarmed():
            stayed[0] &= v.landed_state == M.MAV_LANDED_STATE_ON_GROUND and v.armed is False
            return False

        v.until(wait_s, on_ground_disarmed)
        assert stayed[0], f"left the ground while disarmed: {v.texts}"
        assert proc.poll() is None, "the run ended while waiting on the ground"
        v.upload([
            (M.MAV_CMD_NAV_TAKEOFF, 0.0, 0.0, 5.0),
            (M.MAV_CMD_NAV_WAYPOINT, 12.0, 0.0, -5.0),
            (M.MAV_CMD_NAV_WAYPOINT, 12.0, 8.0, -6.0),
            (M.MAV_CMD_NAV_RETURN_TO_LAUNCH, 0.0, 0.0, 0.0),
        ])
        assert v.command(M.MAV_CMD_COMPONENT_ARM_DISARM, 1.0) == M.MAV_RESULT_ACCEPTED
        assert v.until(5, lambda: v.armed is True), "not armed"
        t_arm = time.time()
        assert v.command(M.MAV_CMD_MISSION_START) == M.MAV_RESULT_ACCEPTED
        assert v.until(30, lambda: v.landed_state == M.MAV_LANDED_STATE_IN_AIR), \
            f"never in the air: {v.texts}"
        liftoff_s = time.time() - t_arm
        assert v.until(150, lambda: v.armed is False), f"not disarmed: {v.texts}"
        for want in ["rotor at speed: ready for take-off", "lift-off", "mode RETURN",
                     "touchdown: on the ground", "disarmed"]:
            assert want in v.texts, f"no `{want}`: {v.texts}"
        stayed[0] = True
        v.until(30, on_ground_disarmed)
        assert stayed[0], "left the ground after the landing"
        assert proc.poll() is None, "the program stopped by itself"
        est_m = math.hypot(v.local.x, v.local.y)
        tilt = max(abs(v.attitude.roll), abs(v.attitude.pitch))
        assert est_m < 2.0, f"estimated {est_m:.2f} m from home"
        assert tilt < 0.1, f"not upright: {tilt:.3f} rad"
        proc.send_signal(signal.SIGINT)
        rc = proc.wait(timeout=60)
        assert rc == 130, f"exit {rc} after SIGINT: {proc.stdout.read()}"
        with open(os.path.join(out, "log.csv"), newline="") as f:
            rows = list(csv.DictReader(f))
        first, last = rows[0], rows[-1]
        true_m = math.hypot(float(last["x"]) - float(first["x"]),
                            float(last["y"]) - float(first["y"]))
        up_m = float(first["z"]) - float(last["z"])
        assert true_m < 2.0, f"truly {true_m:.2f} m from home"
        assert abs(up_m) < 0.05, f"not on the ground: {up_m:.3f} m above the start"
        assert os.path.getsize(os.path.join(out, "flight.ulg")) > 0
        return (f"seed {seed}: waited {wait_s:.1f} s, in the air {liftoff_s:.1f} s after arming, "
                f"landed {true_m:.2f} m from home (estimate {est_m:.2f} m), tilt {tilt:.3f} rad, "
                f"exit {rc} on SIGINT")
    except AssertionError as e:
        # the program's own account (termination, final mode, timing)
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
        try:
            tail = proc.communicate(timeout=30)[0].strip().splitlines()[-4:]
        except subprocess.TimeoutExpired:
            tail = ["(no answer to SIGINT)"]
        raise AssertionError(f"{e}; the program said: {' | '.join(tail)}") from None
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--helicon", default="target/release/helicon")
    ap.add_argument("--scenario", default="scenarios/demo.toml")
    ap.add_argument("--seed", type=int, action="append")
    ap.add_argument("--keep", metavar="DIR",
                    help="write each seed's outputs to DIR/seedN and keep them")
    a = ap.parse_args()
    seeds = a.seed or [1, 2, 3]
    results = {}
    if a.keep:
        os.makedirs(a.keep, exist_ok=True)
    with (contextlib.nullcontext(a.keep) if a.keep
          else tempfile.TemporaryDirectory(prefix="helicon-g2g-")) as out_root:
        def run(seed):
            try:
                results[seed] = (True, fly(a.helicon, a.scenario, seed, out_root))
            except Exception as e:  # noqa: BLE001 - every failure is reported
                results[seed] = (False, f"seed {seed}: FAILED: {e}")
        threads = [threading.Thread(target=run, args=(s,)) for s in seeds]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    ok = True
    for seed in seeds:
        passed, line = results[seed]
        ok &= passed
        print(line)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
