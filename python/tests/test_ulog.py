"""helicon.ulog.read against pyulog's reading of the same files and ``helicon log export``."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import helicon
from helicon import HeliconError

from conftest import read_csv_rows

FIXTURES = "crates/ulog/tests/fixtures"


def pyulog_key(name: str) -> str:
    """pyulog's ``topic_<multi_id>`` for helicon's ``topic`` / ``topic_<k>``."""
    base, _, k = name.rpartition("_")
    return name if (base and k.isdigit()) else f"{name}_0"


@pytest.mark.parametrize("fixture", ["helicon_sample", "px4_trimmed"])
def test_every_value_equals_pyulog(repo, fixture):
    got = helicon.ulog.read(repo / FIXTURES / f"{fixture}.ulg")
    want = json.loads((repo / FIXTURES / f"{fixture}.pyulog.json").read_text())
    data = want["data"]
    assert sorted(pyulog_key(k) for k in got) == sorted(data)
    for name, fields in got.items():
        ref = data[pyulog_key(name)]
        # pyulog lists the padding of nested types; helicon skips padding
        assert list(fields) == [c for c in ref["columns"] if "_padding" not in c], name
        for field, col in fields.items():
            values = ref["values"][field]
            kind = ref["types"][field]
            assert len(col) == len(values)
            if kind in ("float", "double"):
                assert col.dtype == np.float64
                exp = np.array([float(v) for v in values])  # 'NaN' strings too
                assert np.array_equal(col, exp, equal_nan=True), (name, field)
            else:
                assert col.dtype.kind in "iub", (name, field, col.dtype)
                assert [int(v) for v in col] == [int(v) for v in values], (name, field)
    assert got[next(iter(got))]["timestamp"].dtype == np.uint64


def test_read_all_has_info_parameters_and_start(repo):
    got = helicon.ulog.read_all(repo / FIXTURES / "px4_trimmed.ulg")
    want = json.loads((repo / FIXTURES / "px4_trimmed.pyulog.json").read_text())
    assert got["start_timestamp_us"] == want["start_timestamp"]
    assert got["truncated"] is False
    assert set(want["info"]) <= set(got["info"])
    for k, v in want["initial_parameters"].items():
        assert got["parameters"][k] == pytest.approx(v, rel=1e-7, abs=0), k


def test_equals_the_cli_export(cli, repo, tmp_path):
    src = repo / FIXTURES / "helicon_sample.ulg"
    cli("log", "export", "--csv", tmp_path, src)
    got = helicon.ulog.read(src)
    for name, fields in got.items():
        topic, multi = (name, 0) if not name.rpartition("_")[2].isdigit() else (name.rpartition("_")[0], int(name.rpartition("_")[2]))
        rows = read_csv_rows(tmp_path / f"helicon_sample_{topic}_{multi}.csv")
        assert list(rows[0]) == list(fields)
        for field, col in fields.items():
            for v, text in zip(col, (r[field] for r in rows)):
                if col.dtype.kind == "f":
                    t = float(text.replace("NaN", "nan"))
                    # floats print in their own type's shortest form
                    assert (math.isnan(t) and math.isnan(v)) or t == v or np.float32(t) == np.float32(v), field
                else:
                    assert int(v) == int(text), field


def test_truncated_and_bad_files(repo, tmp_path):
    data = (repo / FIXTURES / "helicon_sample.ulg").read_bytes()
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(data[: len(data) * 2 // 3])
    whole = helicon.ulog.read(repo / FIXTURES / "helicon_sample.ulg")
    part = helicon.ulog.read_all(cut)
    assert part["truncated"] is True
    some = next(iter(part["topics"]))
    assert 0 < len(part["topics"][some]["timestamp"]) <= len(whole[some]["timestamp"])
    with pytest.raises(HeliconError, match="missing.ulg"):
        helicon.ulog.read(tmp_path / "missing.ulg")
    junk = tmp_path / "junk.ulg"
    junk.write_bytes(b"not a ulog file at all")
    with pytest.raises(HeliconError, match="junk.ulg"):
        helicon.ulog.read(junk)
