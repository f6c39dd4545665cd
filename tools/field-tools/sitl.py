"""The helicon SITL as the field tools' vehicle: `helicon sitl --gcs udpin:`
on 127.0.0.1, started and stopped by the checks, and the waits they share.

Every wait is on the vehicle's state (HEARTBEAT, EXTENDED_SYS_STATE,
GLOBAL_POSITION_INT), never on a fixed time; each check has an overall
deadline (`Deadline`), at most 90 s.
"""
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
HELICON = os.environ.get("HELICON", os.path.join(ROOT, "target", "release", "helicon"))
SCENARIO = os.path.join(ROOT, "scenarios", "demo.toml")


class CheckFailed(Exception):
    """A check's expectation not met (the message says which)."""


def expect(ok, what):
    """Raise CheckFailed(what) unless ok."""
    if not ok:
        raise CheckFailed(what)


class Deadline:
    """The overall time of one check (s)."""

    def __init__(self, seconds):
        self.end = time.monotonic() + seconds

    def left(self):
        return self.end - time.monotonic()

    def check(self, what):
        expect(self.left() > 0, f"timed out: {what}")


class Sitl:
    """`helicon sitl SCENARIO --speed realtime --gcs udpin:127.0.0.1:PORT`
    (the scenario's duration lengthened: the run ends when the check stops
    it); `gcs`: another `--gcs` address (a list, TCP)."""

    def __init__(self, port, duration_s=300, gcs=None):
        self.port = port
        gcs = gcs or f"udpin:127.0.0.1:{port}"
        self.out = tempfile.mkdtemp(prefix="helicon-field-tools-")
        self.log = open(os.path.join(self.out, "sitl.log"), "w")
        self.proc = subprocess.Popen(
            [HELICON, "sitl", SCENARIO, "--speed", "realtime", "--duration", str(duration_s),
             "--out", os.path.join(self.out, "run"), "--gcs", gcs],
            stdout=self.log, stderr=subprocess.STDOUT, start_new_session=True)

    def stop(self):
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGINT)
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()
        self.log.close()

    def tail(self, n=20):
        with open(os.path.join(self.out, "sitl.log")) as f:
            return "".join(f.readlines()[-n:])

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        self.stop()
        # a passed check leaves nothing behind; a failed one keeps its folder
        # (the SITL's log and flight) for a look
        if exc_type is None and not os.environ.get("HELICON_KEEP_SCRATCH"):
            shutil.rmtree(self.out, ignore_errors=True)


def connect(port, source_system=255, source_component=190):
    """A pymavlink ground station speaking to the SITL's udpin port (it sends
    first: its heartbeat makes it a peer)."""
    from pymavlink import mavutil
    return mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}", source_system=source_system,
                                      source_component=source_component)


def gcs_heartbeat(m):
    from pymavlink import mavutil
    m.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_GCS, mavutil.mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)


def wait_heartbeat(m, deadline):
    """The vehicle's first HEARTBEAT (sending ours once a second meanwhile)."""
    while True:
        deadline.check("no HEARTBEAT from the vehicle")
        gcs_heartbeat(m)
        hb = m.recv_match(type="HEARTBEAT", blocking=True, timeout=1)
        if hb is not None and m.target_system == hb.get_srcSystem():
            return hb


def recv(m, types, deadline, what, pred=lambda msg: True):
    """The next message of `types` that `pred` accepts (our heartbeat sent
    once a second meanwhile: the vehicle's link-loss failsafe counts it)."""
    last = 0.0
    while True:
        deadline.check(what)
        if time.monotonic() - last > 1.0:
            gcs_heartbeat(m)
            last = time.monotonic()
        msg = m.recv_match(type=types, blocking=True, timeout=0.5)
        if msg is not None and pred(msg):
            return msg


def run(name, check):
    """Run one check (a function returning a one-line result); print
    `name: ok: result` or `name: FAILED: why`; the exit status."""
    t0 = time.monotonic()
    try:
        result = check()
    except CheckFailed as e:
        print(f"{name}: FAILED: {e} ({time.monotonic() - t0:.0f} s)", flush=True)
        return 1
    print(f"{name}: ok: {result} ({time.monotonic() - t0:.0f} s)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit("a library of the field-tool checks; run .ci/field-tools")
