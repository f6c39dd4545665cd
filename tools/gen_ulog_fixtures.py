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

Floats are written with Python's repr (shortest round trip), so the Rust
tests compare bit for bit.

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


if __name__ == "__main__":
    main()
