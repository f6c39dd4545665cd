#!/usr/bin/env python3
"""Write px4_fields.json: the fields of the PX4 topics helicon logs, as
PX4's message generator lays them out in a ULog file, read from the uORB
definitions (``msg/*.msg`` and ``msg/versioned/*.msg``) of a PX4-Autopilot
checkout.

    python3 tools/ulog-check/gen_px4_fields.py PATH/TO/PX4-Autopilot

PX4's generator sorts a message's fields by the size of their base type,
largest first (a stable sort: the definition's order is kept among equals),
and pads the struct to a multiple of 8 bytes with ``uint8_t[n] _padding0``
(declared in the format, not logged). Constants (``type NAME = value``)
are not fields.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

# topic -> definition file (CamelCase name of the .msg)
TOPICS = {
    "vehicle_attitude": "VehicleAttitude",
    "vehicle_angular_velocity": "VehicleAngularVelocity",
    "vehicle_local_position": "VehicleLocalPosition",
    "vehicle_local_position_setpoint": "VehicleLocalPositionSetpoint",
    "vehicle_global_position": "VehicleGlobalPosition",
    "sensor_combined": "SensorCombined",
    "sensor_gps": "SensorGps",
    "vehicle_gps_position": "SensorGps",
    "vehicle_magnetometer": "VehicleMagnetometer",
    "actuator_outputs": "ActuatorOutputs",
    "input_rc": "InputRc",
    "vehicle_status": "VehicleStatus",
    "vehicle_land_detected": "VehicleLandDetected",
    "cpuload": "Cpuload",
}

C_TYPES = {
    "int8": ("int8_t", 1), "uint8": ("uint8_t", 1), "int16": ("int16_t", 2),
    "uint16": ("uint16_t", 2), "int32": ("int32_t", 4), "uint32": ("uint32_t", 4),
    "int64": ("int64_t", 8), "uint64": ("uint64_t", 8), "float32": ("float", 4),
    "float64": ("double", 8), "bool": ("bool", 1), "char": ("char", 1),
}

FIELD = re.compile(r"^([a-z0-9]+)(?:\[(\d+)\])?\s+([A-Za-z_][A-Za-z0-9_]*)$")


def fields_of(text: str) -> list[list]:
    """[c type, name, array length or None] in PX4's logged order."""
    parsed = []
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if not line or "=" in line:
            continue
        m = FIELD.match(line)
        if m is None:
            raise ValueError(f"not a field: {line!r}")
        base, n, name = m.group(1), m.group(2), m.group(3)
        ctype, size = C_TYPES[base]
        parsed.append((size, ctype, name, int(n) if n else None))
    parsed.sort(key=lambda f: f[0], reverse=True)  # stable
    total = sum(size * (n or 1) for size, _, _, n in parsed)
    out = [[ctype, name, n] for _, ctype, name, n in parsed]
    if total % 8:
        out.append(["uint8_t", "_padding0", 8 - total % 8])
    return out


def find(msg_dir: Path, name: str) -> Path:
    for sub in ("", "versioned"):
        p = msg_dir / sub / f"{name}.msg"
        if p.is_file():
            return p
    raise FileNotFoundError(f"{name}.msg under {msg_dir}")


def main() -> None:
    if len(sys.argv) != 2:
        sys.exit("usage: gen_px4_fields.py PATH/TO/PX4-Autopilot")
    msg_dir = Path(sys.argv[1]) / "msg"
    table = {t: fields_of(find(msg_dir, m).read_text()) for t, m in TOPICS.items()}
    out = Path(__file__).with_name("px4_fields.json")
    out.write_text(json.dumps(table, indent=1) + "\n")
    print(f"wrote {out} ({len(table)} topics)")


if __name__ == "__main__":
    main()
