"""The closed-loop vibration table of docs/vibration.md.

Flies the beyond-the-thesis flight without vibration and with vibration on a
±2 g and a ±20 g accelerometer for seeds 1..N (`helicon sim --seed`), and
prints per configuration the median [min–max] over seeds of: the vertical
speed tracking error RMS, the navigation's vertical-velocity and tilt errors
(RMS), the height gained against the reference, and the fraction of the
flight (after the monitor's first 5 s) the IMU health monitor flagged a
gravity deficit (likely hidden saturation). The fourth configuration puts the
±2 g part on a vibration isolator (natural frequency 25 Hz, damping 0.2).

Run: cargo build --release && python3 tools/vibration_table.py target/release/helicon 10
"""
import csv
import json
import math
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

helicon = sys.argv[1] if len(sys.argv) > 1 else "target/release/helicon"
seeds = int(sys.argv[2]) if len(sys.argv) > 2 else 10
root = Path(__file__).resolve().parent.parent
cases = [
    ("no vibration (±10 g)", "scenarios/beyond-physical-turbulence.toml"),
    ("vibration, ±20 g", "scenarios/beyond-vibration-20g.toml"),
    ("vibration, ±2 g", "scenarios/beyond-vibration-2g.toml"),
    ("vibration, ±2 g on a 25 Hz isolator (ζ = 0.2)", "isolated"),
]
ISOLATOR = "enabled = true\nisolator_natural_frequency_hz = 25.0\nisolator_damping_ratio = 0.2\n"


def isolated_scenario(tmp):
    """The ±2 g scenario with the IMU on an isolator (a temporary copy)."""
    text = (root / "scenarios/beyond-vibration-2g.toml").read_text()
    text = text.replace("[sensors.imu.vibration]\nenabled = true\n",
                        "[sensors.imu.vibration]\n" + ISOLATOR, 1)
    path = Path(tmp) / "beyond-vibration-2g-isolated.toml"
    path.write_text(text)
    return path


def one(scenario, seed, out):
    subprocess.run([helicon, "sim", str(scenario), "--seed", str(seed), "--out", out],
                   check=True, stdout=subprocess.DEVNULL)
    s = json.load(open(Path(out) / "summary.json"))
    rows = list(csv.DictReader(open(Path(out) / "log.csv")))
    n = len(rows)
    vd = math.sqrt(sum((float(r["vd"]) - float(r["ref_vd"])) ** 2 for r in rows) / n)
    tilt = math.sqrt(s["estimator_error_rms"][0] ** 2 + s["estimator_error_rms"][1] ** 2)
    # height gained beyond what the vertical-speed reference asks for
    dt = float(rows[1]["t_s"]) - float(rows[0]["t_s"])
    climb_ref = -sum(float(r["ref_vd"]) for r in rows) * dt
    climb = -(float(rows[-1]["z"]) - float(rows[0]["z"]))
    late = [r for r in rows if float(r["t_s"]) > 5.0]
    flagged = sum(1 for r in late if int(float(r["imu_health_flags"])) & 4) / len(late)
    return s["outcome"], vd, s["estimator_error_rms"][5], tilt, climb - climb_ref, flagged


def fmt(xs, digits):
    return f"{statistics.median(xs):.{digits}f} [{min(xs):.{digits}f}–{max(xs):.{digits}f}]"


print("| configuration | completed | vd tracking RMS (m/s) | nav. w error RMS (m/s) | "
      "tilt error RMS (rad) | height gained vs ref. (m) | gravity deficit flagged |")
print("|---|---|---|---|---|---|---|")
with tempfile.TemporaryDirectory() as tmp:
    for name, scenario in cases:
        scenario = isolated_scenario(tmp) if scenario == "isolated" else root / scenario
        res = [one(scenario, k, f"{tmp}/{k}") for k in range(1, seeds + 1)]
        done = sum(1 for r in res if r[0] == "completed")
        cols = list(zip(*res))
        print(f"| {name} | {done}/{seeds} | {fmt(cols[1], 2)} | {fmt(cols[2], 2)} | "
              f"{fmt(cols[3], 3)} | {fmt(cols[4], 0)} | {fmt([100 * f for f in cols[5]], 0)} % |")
