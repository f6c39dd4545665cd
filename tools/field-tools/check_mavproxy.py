#!/usr/bin/env python3
"""MAVProxy (its shell fed on stdin; `--non-interactive` reads no commands) against
`helicon sitl --gcs`: `wp load` of a QGC WPL 110 file, the mode LOITER,
`arm throttle`, `takeoff` (AMSL, as PX4 reads NAV_TAKEOFF), the mode MISSION,
the return, while a pymavlink station on its own port watches the vehicle (the
waits are on what it sees: the mission count, the armed flag, the height,
MISSION_ITEM_REACHED, the disarm at home).

MAVProxy 1.8.75's `mode NAME` (and `rtl`, `loiter`, typed as mode names)
cannot set a PX4 vehicle's mode: its mode module hands pymavlink's px4_map
tuple to `set_mode`, which fails client-side ("required argument is not a
float") and sends nothing. The modes are set with `long DO_SET_MODE 1 MAIN
SUB` (what `set_mode_px4` would have sent) and the return with
`long NAV_RETURN_TO_LAUNCH`.

    python3 tools/field-tools/check_mavproxy.py PORT
"""
import os
import subprocess
import sys
import tempfile
import threading

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sitl import Deadline, Sitl, connect, expect, recv, run, wait_heartbeat  # noqa: E402

M = mavutil.mavlink


class MavProxy:
    """mavproxy.py --master=udpout:…, its shell fed on stdin; its output
    kept."""

    def __init__(self, port, workdir):
        exe = os.path.join(os.path.dirname(sys.executable), "mavproxy.py")
        self.lines = []
        self.proc = subprocess.Popen(
            [sys.executable, exe, f"--master=udpout:127.0.0.1:{port}",
             "--source-system=250", f"--state-basedir={workdir}", "--default-modules=wp,mode,arm,cmdlong"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
            cwd=workdir)
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for line in self.proc.stdout:
            self.lines.append(line.rstrip())

    def cmd(self, line):
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()

    def saw(self, text):
        return any(text in x for x in self.lines)

    def stop(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.proc.kill()


def check(port):
    work = tempfile.mkdtemp(prefix="helicon-mavproxy-")
    with Sitl(port) as sitl:
        d = Deadline(90)
        mp = None
        try:
            obs = connect(port, 254, 190)
            wait_heartbeat(obs, d)
            obs.mav.command_long_send(1, 1, M.MAV_CMD_REQUEST_MESSAGE, 0, M.MAVLINK_MSG_ID_HOME_POSITION,
                                      0, 0, 0, 0, 0, 0)
            home = recv(obs, "HOME_POSITION", d, "HOME_POSITION")
            lat, lon, amsl = home.latitude / 1e7, home.longitude / 1e7, home.altitude / 1000.0
            north = lat + 8.0 / 111_320.0
            mission = os.path.join(work, "mission.txt")
            with open(mission, "w") as f:
                f.write("QGC WPL 110\n")
                f.write(f"0\t1\t0\t16\t0\t0\t0\t0\t{lat:.7f}\t{lon:.7f}\t{amsl:.2f}\t1\n")
                f.write("1\t0\t3\t22\t0\t0\t0\t0\t0\t0\t5\t1\n")
                f.write(f"2\t0\t3\t16\t0\t1.5\t0\tnan\t{north:.7f}\t{lon:.7f}\t5\t1\n")
            mp = MavProxy(port, work)
            while not mp.saw("online system 1"):
                d.check("MAVProxy never saw the vehicle")
                expect(mp.proc.poll() is None, f"MAVProxy exited: {mp.lines[-5:]}")
                recv(obs, "HEARTBEAT", d, "heartbeat")
            mp.cmd(f"wp load {mission}")
            # MAVProxy's line when the vehicle has requested the last item
            while not mp.saw("Loaded 3 waypoints in"):
                d.check(f"wp load: {mp.lines[-5:]}")
                recv(obs, "HEARTBEAT", d, "heartbeat")
            obs.mav.mission_request_list_send(1, 1, M.MAV_MISSION_TYPE_MISSION)
            n = recv(obs, "MISSION_COUNT", d, "MISSION_COUNT")
            expect(n.count == 3, f"mission count {n.count}")
            mp.cmd("long DO_SET_MODE 1 4 3")  # AUTO.LOITER
            mp.cmd("arm throttle")
            recv(obs, "HEARTBEAT", d, "armed", lambda m: m.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED)
            mp.cmd(f"takeoff {amsl + 5.0:.1f}")
            recv(obs, "GLOBAL_POSITION_INT", d, "takeoff to 4.5 m", lambda m: m.relative_alt > 4500)
            mp.cmd("long DO_SET_MODE 1 4 4")  # AUTO.MISSION
            recv(obs, "MISSION_ITEM_REACHED", d, "waypoint 2 reached", lambda m: m.seq == 2)
            mp.cmd("long NAV_RETURN_TO_LAUNCH")
            recv(obs, "HEARTBEAT", d, "RTL", lambda m: obs.flightmode == "RTL")
            recv(obs, "HEARTBEAT", d, "disarm at home", lambda m: not m.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED)
            g = recv(obs, "GLOBAL_POSITION_INT", d, "position")
            dn = (g.lat / 1e7 - lat) * 111_320.0
            expect(abs(dn) < 3.0, f"landed {dn:.1f} m from home")
            acks = sum("Got COMMAND_ACK: DO_SET_MODE: ACCEPTED" in x for x in mp.lines)
            expect(acks == 2, f"DO_SET_MODE accepted {acks} times: {mp.lines[-20:]}")
            return (f"wp load (3 items), LOITER, arm, takeoff, MISSION, RTL: landed {abs(dn):.1f} m "
                    "from home")
        except Exception:
            print(sitl.tail(), file=sys.stderr)
            if mp is not None:
                print("\n".join(mp.lines[-30:]), file=sys.stderr)
            raise
        finally:
            if mp is not None:
                mp.stop()


if __name__ == "__main__":
    port = int(sys.argv[1]) if len(sys.argv) > 1 else 14603
    sys.exit(run("mavproxy", lambda: check(port)))
