"""Shared fixtures: the repository root and the ``helicon`` command line.

The CLI comparisons run the ``helicon`` binary of this checkout:
``$HELICON_CLI`` when set, else ``target/release/helicon`` (``cargo build
--release`` builds it; ``.ci/python`` makes sure it is there).
"""

from __future__ import annotations

import csv
import json
import os
import subprocess
from pathlib import Path
from typing import Dict, List

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]


def cli_path() -> Path:
    env = os.environ.get("HELICON_CLI")
    return Path(env) if env else REPO / "target" / "release" / "helicon"


@pytest.fixture(scope="session")
def repo() -> Path:
    return REPO


@pytest.fixture(scope="session")
def cli():
    """Run the CLI: ``cli("trim", "--json")`` → CompletedProcess (checked)."""
    exe = cli_path()
    if not exe.exists():
        pytest.skip(f"the helicon CLI is not built at {exe} (cargo build --release -p helicon-cli)")

    def run(*args: str, cwd: Path = REPO, check: bool = True) -> subprocess.CompletedProcess:
        p = subprocess.run([str(exe), *map(str, args)], cwd=cwd, capture_output=True, text=True)
        if check and p.returncode != 0:
            raise AssertionError(f"helicon {' '.join(map(str, args))} failed:\n{p.stderr}")
        return p

    return run


def read_named_csv(path: Path) -> np.ndarray:
    """A matrix CSV of ``helicon linearize`` (``row,<cols>`` header, a name per row)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return np.array([[float(v) for v in r[1:]] for r in rows[1:]])


def read_columns(path: Path) -> Dict[str, np.ndarray]:
    """A numeric CSV with a header as ``{column: float64 array}`` (exact: Python parses shortest repr)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    head, data = rows[0], rows[1:]
    return {h: np.array([float(r[j]) for r in data]) for j, h in enumerate(head)}


def read_csv_rows(path: Path) -> List[Dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def read_json(path: Path):
    with open(path) as f:
        return json.load(f)
