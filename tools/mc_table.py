#!/usr/bin/env python3
"""Robustness table (Markdown) from Monte Carlo output folders' stats.json.

    tools/mc_table.py out/mc/robustness-10 out/mc/robustness-20 ...

One row per folder: runs, failure fraction, failures by typed class
(outcome: termination), and for each output the RMS tracking error
p50 [p5-p95] and the p95 of the largest error over the completed runs
(docs/monte-carlo.md). Reads stats.json format version 2.
"""
import json
import sys
from pathlib import Path


def fmt(m, digits=3):
    if m["n"] == 0:
        return "–"
    return f"{m['p50']:.{digits}f} [{m['p5']:.{digits}f}–{m['p95']:.{digits}f}]"


head = ("| campaign | runs | failed | failures | vn rms (m/s) | ve rms (m/s) | vd rms (m/s) | ψ rms (rad) "
        "| p95 max err vn / ve / vd / ψ |")
print(head)
print("|---|---:|---:|---|---|---|---|---|---|")
for d in sys.argv[1:]:
    s = json.loads((Path(d) / "stats.json").read_text())
    if s.get("format_version") != 2:
        sys.exit(f"{d}/stats.json: format version {s.get('format_version', 1)}, this script reads 2")
    m = s["metrics"]
    reasons = "; ".join(
        f"{f['runs']} {f['outcome']}: {f['termination']}" for f in sorted(s["failures"], key=lambda f: -f["runs"])
    )
    p95max = " / ".join(
        "–" if m[f"{o}_max_abs"]["n"] == 0 else f"{m[f'{o}_max_abs']['p95']:.2f}" for o in ["vn", "ve", "vd", "psi"]
    )
    print(
        f"| {s['campaign']} | {s['runs']} | {100 * s['failure_fraction']:.1f} % | {reasons or '–'} "
        f"| {fmt(m['vn_rms'])} | {fmt(m['ve_rms'])} | {fmt(m['vd_rms'])} | {fmt(m['psi_rms'])} | {p95max} |"
    )
