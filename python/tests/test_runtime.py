"""The GIL is released during long calls, and Ctrl-C stops a campaign between runs and a flight within its run."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np

import helicon


def test_the_batch_derivative_releases_the_gil():
    x = np.zeros((200_000, 30))
    m = helicon.Model()
    done = threading.Event()
    ticks = 0

    def work():
        m.derivative(x, np.zeros(4))
        done.set()

    th = threading.Thread(target=work)
    th.start()
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    th.join()
    # with the GIL held for the whole call this loop could not run meanwhile
    assert ticks > 5


def _interrupted(call: str, what: str) -> None:
    """Run `call` in a child interpreter, send it SIGINT 1.5 s into the call
    and check it raised KeyboardInterrupt within 10 s of the signal."""
    code = textwrap.dedent(
        f"""
        import sys, helicon
        print("started", flush=True)
        try:
            {call}
        except KeyboardInterrupt:
            print("interrupted", flush=True)
            sys.exit(3)
        print("finished", flush=True)
        """
    )
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert p.stdout is not None
    assert p.stdout.readline().strip() == "started"
    time.sleep(1.5)
    t0 = time.monotonic()
    os.kill(p.pid, signal.SIGINT)
    try:
        out, err = p.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        p.kill()
        raise AssertionError(f"{what} did not stop on SIGINT")
    assert p.returncode == 3, (out, err)
    assert "interrupted" in out
    assert time.monotonic() - t0 < 10


def test_ctrl_c_stops_a_campaign_between_runs(tmp_path):
    camp = tmp_path / "long.toml"
    camp.write_text(
        textwrap.dedent(
            """
            name = "long"
            runs = 5000
            seed = 1
            [scenario]
            duration_s = 20.0
            [[dispersion]]
            param = "body.mass_kg"
            distribution = "uniform"
            kind = "relative"
            half_width = 0.05
            """
        )
    )
    _interrupted(f"helicon.mc({str(camp)!r})", "the campaign")


def test_ctrl_c_stops_one_long_flight(tmp_path):
    # ten hours of flight (about a minute of work): without a stop inside the
    # flight, Ctrl-C would wait for its end
    scen = tmp_path / "long.toml"
    scen.write_text(
        textwrap.dedent(
            """
            name = "ten hours"
            duration_s = 36000.0
            [log]
            decimation = 1000
            """
        )
    )
    _interrupted(f"helicon.sim({str(scen)!r})", "the flight")
