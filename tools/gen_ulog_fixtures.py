#!/usr/bin/env python3
"""ULog fixtures for crates/ulog/tests/pyulog_fixtures.rs, parsed by pyulog
(pip install pyulog==1.3.0), the PX4 project's Python ULog reader.

1. crates/ulog/tests/fixtures/helicon_sample.ulg is written by helicon's own
   writer (cargo run -p helicon-ulog --example ulog_sample -- FILE); this
   script parses it with pyulog and writes what pyulog read to
   helicon_sample.pyulog.json: the tests check helicon's reader and writer
   against it.
2. Conversely, a small log written by pyulog's writer with real PX4 message
   formats (nested types, several instances, float/bool/int/char fields,
   text messages, multi-part information): give the path of a PX4 log (e.g. pyulog's own test log
   test/sample_log_small.ulg, BSD-3-Clause, from the pyulog repository) as
   --px4 FILE; a few topics and rows are kept, written with
   ULog.write_ulog to px4_trimmed.ulg and parsed back by pyulog into
   px4_trimmed.pyulog.json.

3. The columns fixture: columns_sample.ulg (cargo run -p helicon-ulog
   --example ulog_columns_sample -- FILE: jittered control steps, three
   dropped samples, excitation and servo_output stamped 4.7 ms after their
   step on the step's clock, imu_health starting late) read by pyulog, and
   the rule of helicon_ulog::columns (control grid, ±10 % jitter, up to 4
   missing samples filled by linear interpolation, step-clock topics with
   their control record, other topics held at or before t + T/2) applied here
   independently with numpy, written to columns_sample.columns.json.

Floats are written with Python's repr (shortest round trip), so the Rust
tests compare bit for bit (the columns fixture to 1e-12: the interpolation
is the same arithmetic in a possibly different order).

Usage: python3 tools/gen_ulog_fixtures.py [--px4 sample_log_small.ulg]
"""

import argparse
import json
import os

import numpy as np
from pyulog import ULog

HERE = os.path.dirname(os.path.abspath(__file__))
FIX = os.path.join(HERE, "..", "crates", "ulog", "tests", "fixtures")

# topics kept from the PX4 log, rows kept per topic instance
PX4_TOPICS = ["position_setpoint_triplet", "telemetry_status", "vehicle_attitude",
              "input_rc", "vehicle_status", "battery_status"]
PX4_ROWS = 12
PX4_PARAMS = 16


def plain(v):
    """numpy scalar -> JSON value (floats widened exactly)."""
    if isinstance(v, (np.floating, float)):
        v = float(v)
        if v != v:
            return "NaN"
        if v in (float("inf"), float("-inf")):
            return "inf" if v > 0 else "-inf"
        return v
    if isinstance(v, (np.bool_, bool)):
        return bool(v)
    if isinstance(v, (np.integer, int)):
        return int(v)
    if isinstance(v, bytes):
        return v.decode("utf-8", "replace")
    return v


def dump(ulg_path, json_path):
    u = ULog(ulg_path)
    out = {
        "start_timestamp": int(u.start_timestamp),
        "file_corruption": bool(u.file_corruption),
        "info": {k: plain(v) for k, v in sorted(u.msg_info_dict.items())},
        # each sequence of INFO_MULTIPLE parts joined
        "info_multiple": {k: ["".join(plain(p) for p in seq) for seq in v]
                          for k, v in sorted(u.msg_info_multiple_dict.items())},
        "initial_parameters": {k: plain(v) for k, v in sorted(u.initial_parameters.items())},
        "changed_parameters": [[int(t), n, plain(v)] for t, n, v in u.changed_parameters],
        "logged_messages": [[int(m.timestamp), int(m.log_level), m.log_level_str(), m.message]
                            for m in u.logged_messages],
        "dropouts": [[int(d.timestamp), int(d.duration)] for d in u.dropouts],
        "data": {},
    }
    for d in sorted(u.data_list, key=lambda d: (d.name, d.multi_id)):
        cols = [f.field_name for f in d.field_data]
        types = {f.field_name: f.type_str for f in d.field_data}
        out["data"][f"{d.name}_{d.multi_id}"] = {
            "columns": cols,
            "types": types,
            "values": {c: [plain(x) for x in d.data[c]] for c in cols},
        }
    with open(json_path, "w", encoding="utf-8") as f:
        json.dump(out, f, indent=0, sort_keys=True)
        f.write("\n")
    print(f"{json_path}: {len(out['data'])} topic instances")


def trim_px4(src, dst):
    u = ULog(src, PX4_TOPICS)
    for d in u.data_list:
        for k in d.data:
            d.data[k] = d.data[k][:PX4_ROWS]
    keep = sorted(u.initial_parameters)[:PX4_PARAMS]
    u._initial_parameters = {k: u.initial_parameters[k] for k in keep}
    u._changed_parameters = []
    u._default_parameters = {}
    u.write_ulog(dst)


# log.csv column -> (topic, field) for the columns fixture (the names of
# helicon_ulog::columns::ULOG_COLUMNS that the sample's topics carry)
COLUMNS = {
    "S_col": ("control", "command[0]"), "S_lat": ("control", "command[1]"),
    "S_lon": ("control", "command[2]"), "S_tr": ("control", "command[3]"),
    "ref_vd": ("control", "ref_vel_ned_m_s[2]"), "ref_psi": ("control", "ref_yaw_rad"),
    "est_p": ("control", "estimate[6]"), "meas_p": ("control", "measured[6]"),
    "meas_q": ("control", "measured[7]"),
    "exc_lat": ("excitation", "offset[1]"), "exc_active": ("excitation", "active"),
    "imu_vib_rms_m_s2": ("imu_health", "vibration_rms_m_s2"),
    "imu_health_flags": ("imu_health", "flags"),
    "servo_source": ("servo_output", "source"),
}


def columns(ulg_path, json_path, period_s=0.0025):
    """The columns of helicon_ulog::columns, computed from pyulog's data."""
    u = ULog(ulg_path)
    data = {d.name: d.data for d in u.data_list if d.multi_id == 0}
    tc = data["control"]["timestamp"].astype(np.float64) * 1e-6
    steps = np.diff(tc)
    m = np.rint(steps / period_s)
    assert np.all(np.abs(steps - m * period_s) <= 0.1 * period_s)
    assert np.all(m - 1 <= 4)
    slot = np.concatenate([[0], np.cumsum(m)]).astype(int)
    # held record index per topic at each control sample; start = first
    # sample where every topic has one
    held = {}
    start = 0
    for topic in {t for t, _ in COLUMNS.values()} - {"control"}:
        if topic in ("excitation", "servo_output"):
            # stamped on the step's clock: the sample writes one record after
            # each control record, so the k-th belongs to the k-th
            assert len(data[topic]["timestamp"]) == len(tc)
            held[topic] = np.arange(len(tc))
            continue
        tr = data[topic]["timestamp"].astype(np.float64) * 1e-6
        idx = np.searchsorted(tr, tc + 0.5 * period_s, side="right") - 1
        first = int(np.argmax(idx >= 0))
        start = max(start, first)
        held[topic] = idx
    grid = np.arange(slot[start], slot[-1] + 1)
    out = {"period_s": period_s, "skipped_start": start,
           "t_s": [float(tc[0] + n * period_s) for n in grid], "columns": {}}
    for name, (topic, field) in COLUMNS.items():
        v = data[topic][field].astype(np.float64)
        at = v[start:] if topic == "control" else v[held[topic][start:]]
        # linear interpolation over the missing grid samples
        out["columns"][name] = [float(x) for x in np.interp(grid, slot[start:], at)]
    out["filled"] = [[float(tc[0] + (slot[k] + 1) * period_s), int(slot[k + 1] - slot[k] - 1)]
                     for k in range(start, len(slot) - 1) if slot[k + 1] - slot[k] > 1]
    with open(json_path, "w", encoding="utf-8") as f:
        json.dump(out, f, indent=0, sort_keys=True)
        f.write("\n")
    print(f"{json_path}: {len(grid)} samples, {len(COLUMNS)} columns")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--px4", help="a PX4 ULog file to trim into px4_trimmed.ulg")
    args = ap.parse_args()
    dump(os.path.join(FIX, "helicon_sample.ulg"), os.path.join(FIX, "helicon_sample.pyulog.json"))
    trimmed = os.path.join(FIX, "px4_trimmed.ulg")
    if args.px4:
        trim_px4(args.px4, trimmed)
    if os.path.exists(trimmed):
        dump(trimmed, os.path.join(FIX, "px4_trimmed.pyulog.json"))
    sample = os.path.join(FIX, "columns_sample.ulg")
    if os.path.exists(sample):
        columns(sample, os.path.join(FIX, "columns_sample.columns.json"))


if __name__ == "__main__":
    main()
