"""A helicon flight log read by PX4's own tools as a PX4 log.

`helicon sitl` flies the demo (lock-step); pyulog reads its `flight.ulg`:
every PX4 topic helicon writes has exactly the fields of its uORB
definition (`px4_fields.json`, made by `gen_px4_fields.py` from the `.msg`
files), its timestamps increase, the log lasts, carries its parameters and
INFO fields, and pyulog's command-line tools (`ulog_info`, `ulog_params`,
`ulog2csv`, `ulog2kml`) run on it; the KML track lies at the SITL home.
"""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from pyulog import ULog

ROOT = Path(__file__).resolve().parents[2]
HELICON = ROOT / "target" / "release" / "helicon"
FIELDS = json.loads((Path(__file__).with_name("px4_fields.json")).read_text())
BIN = Path(sys.executable).parent
HOME_LAT, HOME_LON = 57.0146, 9.9869
# topics a SITL flight writes (the land detector's is the lead's to call)
NOT_WRITTEN_IN_SITL = {"vehicle_land_detected"}


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    out = tmp_path_factory.mktemp("sitl")
    run = subprocess.run(
        [str(HELICON), "sitl", str(ROOT / "scenarios" / "demo.toml"), "--speed", "max",
         "--out", str(out)],
        capture_output=True, text=True, cwd=ROOT, check=False)
    assert run.returncode == 0, run.stderr
    path = out / "flight.ulg"
    return path, ULog(str(path))


def test_every_px4_topic_has_the_uorb_fields(flight):
    _, ulog = flight
    logged = {d.name for d in ulog.data_list}
    for topic, want in FIELDS.items():
        fmt = ulog.message_formats.get(topic)
        assert fmt is not None, f"no format {topic}"
        got = [[t, n, a if a > 0 else None] for t, a, n in fmt.fields]
        assert got == want, topic
        if topic not in NOT_WRITTEN_IN_SITL:
            assert topic in logged, f"{topic} has no record"


def test_timestamps_increase_and_the_log_lasts(flight):
    _, ulog = flight
    for d in ulog.data_list:
        ts = d.data["timestamp"].astype(np.int64)
        assert len(ts) > 0, d.name
        assert np.all(np.diff(ts) > 0), d.name
    duration_s = (ulog.last_timestamp - ulog.start_timestamp) * 1e-6
    assert duration_s > 15.0  # the demo flies 20 s


def test_parameters_info_and_messages(flight):
    _, ulog = flight
    assert ulog.initial_parameters["HC_CTRL_DT_S"] == pytest.approx(0.0025, rel=1e-6)
    for key in ("sys_name", "ver_sw", "ver_hw", "sys_uuid", "time_ref_utc", "sys_toolchain"):
        assert key in ulog.msg_info_dict, key
    assert ulog.msg_info_dict["ver_hw"] == "HELICON_SITL"
    texts = [(m.log_level_str(), m.message) for m in ulog.logged_messages]
    assert any("armed" in t and level == "NOTICE" for level, t in texts), texts


def test_values_agree_with_helicons_topics(flight):
    _, ulog = flight
    ctl = ulog.get_dataset("control").data
    att = ulog.get_dataset("vehicle_attitude").data
    index = {int(t): i for i, t in enumerate(ctl["timestamp"])}
    rows = [index[int(t)] for t in att["timestamp"]]
    q = np.stack([att[f"q[{i}]"] for i in range(4)], axis=1).astype(np.float64)
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-6)
    w, x, y, z = q.T
    roll = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2 * (w * y - z * x), -1, 1))
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    for got, k in ((roll, 0), (pitch, 1), (yaw, 2)):
        want = ctl[f"estimate[{k}]"][rows]
        err = np.angle(np.exp(1j * (got - want)))
        assert np.max(np.abs(err)) < 1e-5, k
    nav = ulog.get_dataset("navigation").data
    lpos = ulog.get_dataset("vehicle_local_position").data
    nidx = {int(t): i for i, t in enumerate(nav["timestamp"])}
    rows = [nidx[int(t)] for t in lpos["timestamp"]]
    for axis, k in (("x", 0), ("y", 1), ("z", 2)):
        assert np.allclose(lpos[axis], nav[f"position_ned_m[{k}]"][rows].astype(np.float32))
    assert np.all(lpos["xy_valid"] == 1) and np.all(lpos["xy_global"] == 1)
    assert lpos["ref_lat"][0] == pytest.approx(HOME_LAT, abs=1e-6)
    status = ulog.get_dataset("vehicle_status").data
    assert np.all(status["vehicle_type"] == 1)  # rotary wing
    assert status["arming_state"][-1] == 2  # armed: SITL without a ground station


def test_pyulog_tools_run(flight, tmp_path):
    path, _ = flight
    for tool in ("ulog_info", "ulog_params", "ulog_messages"):
        run = subprocess.run([str(BIN / tool), str(path)], capture_output=True, text=True,
                             check=False)
        assert run.returncode == 0, (tool, run.stderr)
    run = subprocess.run([str(BIN / "ulog_params"), str(path)], capture_output=True, text=True,
                         check=True)
    assert "HC_CTRL_DT_S" in run.stdout
    csv = tmp_path / "csv"
    run = subprocess.run([str(BIN / "ulog2csv"), str(path), "-o", str(csv)],
                         capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr
    assert (csv / "flight_vehicle_attitude_0.csv").is_file()
    assert (csv / "flight_vehicle_gps_position_0.csv").is_file()


def test_ulog2kml_track_is_at_home(flight, tmp_path):
    path, _ = flight
    kml = tmp_path / "track.kml"
    run = subprocess.run([str(BIN / "ulog2kml"), str(path), "-o", str(kml)],
                         capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr
    coords = [c.split(",") for block in re.findall(r"<coordinates>([^<]*)</coordinates>",
                                                   kml.read_text())
              for c in block.split()]
    assert len(coords) > 50
    for lon, lat, alt in ((float(a), float(b), float(c)) for a, b, c in coords):
        assert math.isfinite(alt)
        assert abs(lat - HOME_LAT) < 0.01 and abs(lon - HOME_LON) < 0.01, (lat, lon)
