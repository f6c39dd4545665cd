#!/usr/bin/env python3
"""A stand-in for ArduPilot's SITL on its JSON physics interface (no
ArduPilot needed): sends the 16-channel servo packet (magic 18458) of
SIM_JSON.cpp to a physics backend, lock-step, and reads each reply line.
It holds fixed PWMs (default: helicon's Bergen Twin example disarmed on the
ground, then the engine on) and reports the lock-step frame rate reached.

    helicon sitl scenarios/demo.toml --ardupilot-json 127.0.0.1:9002 &
    python3 tools/ardupilot/json_standin.py --frames 40000 --rate 400

Only the standard library.
"""
import argparse
import json
import socket
import struct
import time

p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
p.add_argument("--to", default="127.0.0.1:9002", help="the physics' HOST:PORT")
p.add_argument("--rate", type=int, default=400, help="frame_rate (Hz)")
p.add_argument("--frames", type=int, default=20000, help="frames to send")
p.add_argument("--pwm", default="1500,1500,1500,1500,1000,1000,1000,1000",
               help="SERVO1.. PWM (µs), comma-separated (the rest 0)")
p.add_argument("--throttle-on-at", type=float, default=None,
               help="set SERVO8 to 1700 µs (engine on) from this model time (s)")
a = p.parse_args()
host, port = a.to.rsplit(":", 1)
to = (host, int(port))
pwm = [int(v) for v in a.pwm.split(",")] + [0] * 16
pwm = pwm[:16]
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.settimeout(5.0)
last = None
t0 = time.perf_counter()
for k in range(a.frames):
    if a.throttle_on_at is not None and k / a.rate >= a.throttle_on_at:
        pwm[7] = 1700
    s.sendto(struct.pack("<HHI16H", 18458, a.rate, k, *pwm), to)
    data, _ = s.recvfrom(4096)
    last = data
wall = time.perf_counter() - t0
state = json.loads(last.decode().strip())
print(f"{a.frames} frames at {a.rate} Hz in {wall:.3f} s: {a.frames / wall:.0f} frames/s, "
      f"{a.frames / a.rate / wall:.1f}x real time; last timestamp {state['timestamp']} s, "
      f"position {state['position']}, attitude {state['attitude']}")
