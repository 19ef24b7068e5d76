#!/usr/bin/env python3
"""A damped oscillator against its exact solution: one particle on a damped
`spring` to a nailed anchor particle, moving along x only.

The spring plugin's force (plugins/forces/spring/README.md) is

    f_1 = -[ks (L - r) + kd dL/dt] (x_1 - x_0) / L

so the stretch u = L - r obeys m u'' = -ks u - kd u': a damped harmonic
oscillator with omega_0 = sqrt(ks / m), gamma = kd / (2 m) and, underdamped,
omega_d = sqrt(omega_0^2 - gamma^2). Started at u(0) = A with
u'(0) = -gamma A, its solution is exactly

    u(t) = A exp(-gamma t) cos(omega_d t).

The script runs it with rk4 at two time steps, records t and u with
sim.run(every=..., callback=...), checks the largest error against a bound
and that halving dt divides the error by ~16 (rk4 is fourth order), and
plots the numerical solution over the analytic one.

    PYTHONPATH=build/python python3 examples/python/damped_oscillator.py [OUT_DIR]

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

M = 0.5          # kg, the moving particle (the anchor is fixed: its mass does not matter)
KS = 50.0        # N/m
KD = 1.0         # N s/m, damping along the spring
REST = 1.0       # m, rest length
A = 0.1          # m, initial stretch
DURATION = 3.0   # s: about 4.7 periods, the amplitude decays to exp(-3) = 5 %

OMEGA_0 = math.sqrt(KS / M)                   # 10 rad/s
GAMMA = KD / (2 * M)                          # 1 /s
OMEGA_D = math.sqrt(OMEGA_0**2 - GAMMA**2)    # 9.95 rad/s

DT = 0.01                # s: h omega_0 = 0.1
# The largest |u_numeric - u_exact| over the run measured 3.1e-7 m at DT
# (rk4, this build); the bound is about 3x that.
MAX_ERROR = 1e-6         # m
ORDER_RANGE = (3.5, 4.5)  # rk4: the error falls as dt^4


def exact(t):
    return A * np.exp(-GAMMA * t) * np.cos(OMEGA_D * t)


def simulate(dt):
    """(t, u, y and z of the particle) recorded at every step, t = 0 included."""
    sim = pdyn.loads(f"""
simulation: {{ dt: {dt!r}, duration: {DURATION!r}, solver: {{ type: rk4 }} }}
particles:
  - {{ position: [0, 0, 0], mass: {M!r}, fixed: true }}                   # 0: the anchor
  - {{ position: [{REST + A!r}, 0, 0], velocity: [{-GAMMA * A!r}, 0, 0], mass: {M!r} }}
forces:
  - {{ type: spring, pairs: [[0, 1]], ks: {KS!r}, kd: {KD!r}, rest: {REST!r} }}
""", name="damped_oscillator")
    t, u, off_axis = [], [], []

    def record(s):
        t.append(s.t)
        u.append(s.x[1, 0] - s.x[0, 0] - REST)
        off_axis.append(np.abs(s.x[1, 1:]).max())

    record(sim)
    steps = sim.run(every=1, callback=record)
    assert steps == round(DURATION / dt), f"{steps} steps at dt = {dt} (expected {DURATION / dt:g})"
    return np.array(t), np.array(u), max(off_axis)


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else Path.cwd() / "out" / "examples")
    out.mkdir(parents=True, exist_ok=True)

    print(f"omega_0 = {OMEGA_0:.6g} rad/s, gamma = {GAMMA:.6g} 1/s, omega_d = {OMEGA_D:.6g} rad/s")
    runs = {}
    for dt in (DT, DT / 2):
        t, u, off_axis = simulate(dt)
        err = np.abs(u - exact(t)).max()
        runs[dt] = (t, u, err)
        print(f"dt = {dt:g} s: {len(t) - 1} steps, max |u - u_exact| = {err:.3e} m, "
              f"max |y|, |z| = {off_axis:.1e} m")
        if off_axis != 0.0:
            raise SystemExit(f"the motion left the x axis by {off_axis:.3e} m (expected 1-D motion)")

    err, err_half = runs[DT][2], runs[DT / 2][2]
    order = math.log2(err / err_half)
    print(f"error ratio dt / (dt/2) = {err / err_half:.2f}, measured order = {order:.3f}")

    t, u, _ = runs[DT]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 6), sharex=True,
                                      gridspec_kw={"height_ratios": [2, 1]})
    fine = np.linspace(0.0, DURATION, 2000)
    top.plot(fine, exact(fine), color="0.6", lw=3, label="analytic  A e^(-γt) cos(ω_d t)")
    top.plot(t[::5], u[::5], ".", ms=4, color="C0", label=f"pdyn rk4, dt = {DT:g} s")
    top.plot(fine, A * np.exp(-GAMMA * fine), "--", color="C3", lw=1, label="envelope ±A e^(-γt)")
    top.plot(fine, -A * np.exp(-GAMMA * fine), "--", color="C3", lw=1)
    top.set_ylabel("stretch u = L - r (m)")
    top.set_title(f"damped spring: m = {M} kg, ks = {KS} N/m, kd = {KD} N s/m")
    top.legend(loc="upper right", fontsize=8)
    for dt, (tt, uu, e) in runs.items():
        bottom.semilogy(tt[1:], np.abs(uu - exact(tt))[1:] + 1e-18, lw=1,
                        label=f"dt = {dt:g} s (max {e:.1e} m)")
    bottom.set_xlabel("t (s)")
    bottom.set_ylabel("|u - u_exact| (m)")
    bottom.legend(fontsize=8)
    fig.tight_layout()
    png = out / "damped_oscillator.png"
    fig.savefig(png, dpi=110)
    print(f"wrote {png}")

    if not err < MAX_ERROR:
        raise SystemExit(f"max error {err:.3e} m at dt = {DT} s exceeds the bound {MAX_ERROR:g} m")
    if not ORDER_RANGE[0] <= order <= ORDER_RANGE[1]:
        raise SystemExit(f"measured order {order:.3f} is outside {ORDER_RANGE} (rk4 is fourth order)")
    print(f"ok: max error {err:.2e} m < {MAX_ERROR:g} m, order {order:.2f} in {ORDER_RANGE}")


if __name__ == "__main__":
    main()
