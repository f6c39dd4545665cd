# %% [markdown]
# # helicon in Python: a notebook-style tour
#
# Run as a script (`python examples/python/tour.py [--out DIR]`) or cell by
# cell (`# %%` cells: VS Code, Jupyter via jupytext, Spyder). Needs the
# package (`pip install ./python`); plots need matplotlib and are written as
# PNG files to `out/python-tour/` (without matplotlib the numbers are printed).
#
# 1. trim and linearize over the forward-flight envelope, and the poles;
# 2. fly a closed-loop scenario and plot it;
# 3. a parameter sweep: the mass, from trim to closed-loop tracking.

# %%
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import helicon

REPO = Path(__file__).resolve().parents[2]

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("--out", type=Path, default=REPO / "out" / "python-tour")
args, _ = parser.parse_known_args()
args.out.mkdir(parents=True, exist_ok=True)

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:  # the numbers are printed all the same
    plt = None

print(f"helicon {helicon.__version__}: {len(helicon.state_names())} states, inputs {helicon.input_names()}")

# %% [markdown]
# ## 1. Trim and linearize over the envelope
#
# `helicon.trim` returns the CLI's `trim --json` dict; `helicon.linearize`
# the 27-state `(A, B)` of `A.csv`/`B.csv`. The poles are the eigenvalues of A.

# %%
speeds = np.arange(0.0, 14.5, 1.0)  # m/s forward (north at heading 0)
t0 = time.perf_counter()
trims, poles = [], []
for v in speeds:
    t = helicon.trim(velocity_ned=(v, 0.0, 0.0))
    A, B = helicon.linearize(velocity_ned=(v, 0.0, 0.0), allow_unphysical=True)
    trims.append(t)
    poles.append(np.linalg.eigvals(A))
print(f"{len(speeds)} trims and linearizations in {time.perf_counter() - t0:.2f} s")
print(" v [m/s]  theta [deg]  S_col    S_lon    unstable poles  physical")
for v, t, p in zip(speeds, trims, poles):
    unstable = int(np.sum(p.real > 1e-8))
    print(
        f"{v:7.1f}  {np.degrees(t['state']['theta']):10.3f}  {t['input']['S_col']:7.4f}  "
        f"{t['input']['S_lon']:7.4f}  {unstable:14d}  {t['validity']['physical']}"
    )

if plt is not None:
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 5))
    cmap = plt.get_cmap("viridis")
    for v, p in zip(speeds, poles):
        c = cmap(v / speeds[-1])
        ax1.scatter(p.real, p.imag, s=12, color=c)
        slow = p[np.abs(p) < 15]
        ax2.scatter(slow.real, slow.imag, s=16, color=c)
    for ax, title in [(ax1, "all 27 poles"), (ax2, "|s| < 15 rad/s (rigid body)")]:
        ax.axvline(0, color="k", lw=0.6)
        ax.axhline(0, color="k", lw=0.6)
        ax.set_xlabel("Re s [rad/s]")
        ax.set_ylabel("Im s [rad/s]")
        ax.set_title(title)
        ax.grid(alpha=0.3)
    sm = plt.cm.ScalarMappable(cmap=cmap, norm=plt.Normalize(speeds[0], speeds[-1]))
    fig.colorbar(sm, ax=ax2, label="forward speed [m/s]")
    fig.suptitle("Bergen Twin, physical preset: poles of the linearization, 0-14 m/s forward")
    fig.tight_layout()
    fig.savefig(args.out / "poles.png", dpi=110)
    plt.close(fig)

# %% [markdown]
# ## 2. Fly a closed-loop scenario
#
# `helicon.sim` trims, designs the LQR + Kalman gains and flies the
# nonlinear model with wind and sensors, as `helicon sim`; each case comes
# back with its `log.csv` columns as arrays and its `summary.json`.

# %%
t0 = time.perf_counter()
(run,) = helicon.sim(REPO / "scenarios" / "demo.toml", duration=20.0)
print(f"{run.name}: {run.outcome} in {time.perf_counter() - t0:.2f} s wall, {len(run.t_s)} log rows")
for out in ("vn", "ve", "vd", "psi"):
    m = run.summary["metrics"][out]
    print(f"  {out}: RMS error {m['rms_error']:.4f}, max {m['max_abs_error']:.4f}")

if plt is not None:
    log = run.log
    fig, axes = plt.subplots(3, 1, figsize=(11, 9), sharex=True)
    for name, color in [("vn", "C0"), ("ve", "C1"), ("vd", "C2")]:
        axes[0].plot(run.t_s, log[f"ref_{name}"], color=color, ls="--", lw=1)
        axes[0].plot(run.t_s, log[name], color=color, label=name)
    axes[0].set_ylabel("velocity NED [m/s]")
    axes[0].legend(loc="upper right", ncol=3)
    for name in ("phi", "theta"):
        axes[1].plot(run.t_s, np.degrees(log[name]), label=name)
    axes[1].set_ylabel("attitude [deg]")
    axes[1].legend(loc="upper right")
    for name in helicon.input_names():
        axes[2].plot(run.t_s, log[name], label=name, lw=1)
    axes[2].set_ylabel("servo command [-]")
    axes[2].set_xlabel("t [s]")
    axes[2].legend(loc="upper right", ncol=4)
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.suptitle(f"{run.name}: closed loop in turbulence (dashed: references)")
    fig.tight_layout()
    fig.savefig(args.out / "flight.png", dpi=110)
    plt.close(fig)

# %% [markdown]
# ## 3. A parameter sweep: the mass
#
# `helicon.Params` edits are validated as a parameter file is. For each mass:
# the hover collective, the slowest pole, and the tracking of the thesis's
# Figure 14.5 velocity steps (case a) flown with that plant.

# %%
masses = np.linspace(11.0, 17.0, 7)  # kg (the Bergen Twin: 14 kg)
rows = []
for mass in masses:
    p = helicon.Params().replace({"body.mass_kg": float(mass)})
    t = helicon.trim(params=p)
    A, _ = helicon.linearize(params=p)
    eig = np.linalg.eigvals(A)
    (case_a, *_) = helicon.sim(REPO / "scenarios" / "thesis-fig14-5.toml", params=p)
    rows.append(
        (mass, t["input"]["S_col"], eig.real.max(), case_a.summary["metrics"]["vn"]["rms_error"], case_a.outcome)
    )
print(" mass [kg]  S_col   max Re(s) [1/s]  vn RMS error [m/s]  outcome")
for mass, s_col, re_max, rms, outcome in rows:
    print(f"{mass:9.1f}  {s_col:6.4f}  {re_max:15.4f}  {rms:18.4f}  {outcome}")

if plt is not None:
    r = np.array([row[:4] for row in rows])
    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    for ax, k, label in [
        (axes[0], 1, "hover S_col [-]"),
        (axes[1], 2, "largest Re(pole) [1/s]"),
        (axes[2], 3, "Fig. 14.5 (a): vn RMS error [m/s]"),
    ]:
        ax.plot(r[:, 0], r[:, k], "o-")
        ax.axvline(14.0, color="k", lw=0.6, ls=":")
        ax.set_xlabel("mass [kg]")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    fig.suptitle("mass sweep around the Bergen Twin (dotted: 14 kg nominal)")
    fig.tight_layout()
    fig.savefig(args.out / "mass_sweep.png", dpi=110)
    plt.close(fig)

if plt is not None:
    print(f"plots: {', '.join(str(args.out / f) for f in ('poles.png', 'flight.png', 'mass_sweep.png'))}")
