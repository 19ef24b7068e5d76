#!/usr/bin/env python3
"""A parameter sweep: the period of a mass on a spring against its stiffness.

One particle of mass m on an undamped `spring` to a nailed anchor is run
once per stiffness ks (pdyn.sweep over "forces[0].ks", on a process pool),
and each run measures its own period from the upward zero crossings of the
spring's stretch. The period must be T = 2 pi sqrt(m / ks).

pdyn.sweep runs each variant to the scene's end and then calls
`extract(sim)`; it has no per-step hook. So the scene here is zero steps
long, and `measure_period`, the extract, steps the simulation itself with
sim.step() while recording the stretch. The extract is defined at the
module's top level (the worker processes unpickle it by name), and the
sweep runs under `if __name__ == "__main__":` (the pool starts its workers
with spawn, which imports this file again).

    PYTHONPATH=build/python python3 examples/python/stiffness_sweep.py [OUT_DIR]

OUT_DIR defaults to out/examples under the current directory.
"""

import math
import sys
from pathlib import Path

import numpy as np
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

import pdyn

M = 0.1          # kg
REST = 0.5       # m
A = 0.05         # m, initial stretch (released at rest)
DT = 0.001       # s: h omega = 0.1 at the stiffest spring, ks = 1000 N/m
STIFFNESSES = [1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0]   # N/m
PERIODS = 3      # measured over 3 full periods (4 upward crossings)

# The measured period matched 2 pi sqrt(m / ks) to 4e-7 (relative) at
# worst, at ks = 1000 (h omega = 0.1); the bound leaves a wide margin.
MAX_REL_ERROR = 1e-5

SCENE = f"""
simulation: {{ dt: {DT!r}, steps: 0 }}       # measure_period does the stepping
particles:
  - {{ position: [0, 0, 0], mass: {M!r}, fixed: true }}    # 0: the anchor
  - {{ position: [{REST + A!r}, 0, 0], mass: {M!r} }}      # 1: stretched by A, at rest
forces:
  - {{ type: spring, pairs: [[0, 1]], ks: 1.0, rest: {REST!r} }}
"""


def measure_period(sim):
    """The extract: steps `sim` until the stretch u = L - r has crossed zero
    upwards PERIODS + 1 times (each crossing time linearly interpolated
    between steps) and returns the mean period, s, and the steps taken."""
    def stretch():
        return float(np.linalg.norm(sim.x[1] - sim.x[0])) - REST

    crossings, steps = [], 0
    t0, u0 = sim.t, stretch()
    while len(crossings) < PERIODS + 1:
        if steps >= 200_000:
            raise RuntimeError(f"only {len(crossings)} upward zero crossings in {steps} steps")
        sim.step()
        steps += 1
        t1, u1 = sim.t, stretch()
        if u0 < 0.0 <= u1:
            crossings.append(t0 + (t1 - t0) * -u0 / (u1 - u0))
        t0, u0 = t1, u1
    return {"period": (crossings[-1] - crossings[0]) / PERIODS, "steps": steps}


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else Path.cwd() / "out" / "examples")
    out.mkdir(parents=True, exist_ok=True)

    results = pdyn.sweep(SCENE, {"forces[0].ks": STIFFNESSES}, extract=measure_period)

    ks = np.array([r.params["forces[0].ks"] for r in results])
    measured = np.array([r.value["period"] for r in results])
    analytic = 2 * math.pi * np.sqrt(M / ks)
    rel = measured / analytic - 1
    print(f"{'ks (N/m)':>10} {'steps':>7} {'T measured (s)':>16} {'2 pi sqrt(m/ks)':>16} {'rel. error':>11}")
    for k, r, tm, ta, e in zip(ks, results, measured, analytic, rel):
        print(f"{k:10g} {r.value['steps']:7d} {tm:16.10f} {ta:16.10f} {e:11.2e}")
    worst = np.abs(rel).max()
    slope = np.polyfit(np.log(ks), np.log(measured), 1)[0]
    print(f"worst relative error {worst:.2e}; log-log slope of T(ks) = {slope:.6f} (expected -0.5)")

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), sharex=True,
                                      gridspec_kw={"height_ratios": [2, 1]})
    fine = np.geomspace(ks.min() / 1.5, ks.max() * 1.5, 200)
    top.loglog(fine, 2 * math.pi * np.sqrt(M / fine), color="0.6", lw=3,
               label="analytic  T = 2π sqrt(m / ks)")
    top.loglog(ks, measured, "o", color="C0", label="measured (zero crossings), pdyn.sweep")
    top.set_ylabel("period T (s)")
    top.set_title(f"mass on a spring, m = {M} kg, rk4 at dt = {DT} s")
    top.legend()
    bottom.semilogx(ks, np.abs(rel), "o-", color="C1")
    bottom.set_yscale("log")
    bottom.axhline(MAX_REL_ERROR, color="C3", ls="--", lw=1, label=f"bound {MAX_REL_ERROR:g}")
    bottom.set_xlabel("ks (N/m)")
    bottom.set_ylabel("|T / T_exact - 1|")
    bottom.legend()
    fig.tight_layout()
    png = out / "stiffness_sweep.png"
    fig.savefig(png, dpi=110)
    print(f"wrote {png}")

    if len(results) != len(STIFFNESSES) or list(ks) != STIFFNESSES:
        raise SystemExit(f"the sweep returned {list(ks)} (expected {STIFFNESSES}, in order)")
    if not worst < MAX_REL_ERROR:
        raise SystemExit(f"period error {worst:.2e} exceeds the bound {MAX_REL_ERROR:g}")
    if not abs(slope + 0.5) < 1e-5:
        raise SystemExit(f"T ~ ks^{slope:.6f} (expected ks^-0.5)")
    print(f"ok: every period within {MAX_REL_ERROR:g} of 2 pi sqrt(m/ks)")


if __name__ == "__main__":
    main()
