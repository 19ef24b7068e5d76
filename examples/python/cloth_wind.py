#!/usr/bin/env python3
"""A force written in Python: wind, f_i = k (w - v_i) on every particle (a
drag towards the wind's velocity w), blowing on a small hanging cloth.

Checks, with numbers:

  1. One free particle under Wind alone (the force used by name in a scene,
     as any plugin) follows v(t) = w + (v0 - w) exp(-k t / m) exactly, to
     rk4's accuracy.
  2. The cloth (configs/hanging_cloth.yaml, shrunk with set= overrides to
     16 x 16 particles, started at rest) is blown downwind: its centre of
     mass moves along +y, while without wind it stays at y = 0.
  3. At rest in the wind, f_i = k w + m g is the same on every particle,
     and the two pins exert no torque about the line through them: so the
     centre of mass of the free particles hangs from that line along
     k w + m g, tilted by tan(theta) = k |w| / (m g). The run is long enough
     for the swing to die out (the wind itself damps it, time m / k).
  4. pdyn.check(Wind): the conformance kit passes.

Plots the cloth seen from the side (y-z) with and without wind.

    PYTHONPATH=build/python python3 examples/python/cloth_wind.py [OUT_DIR]

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

SCENE = Path(__file__).resolve().parents[2] / "configs" / "hanging_cloth.yaml"
G = 9.81          # m/s^2, the scene's gravity
MASS = 0.001      # kg per cloth particle
K = 2.5e-3        # kg/s: the wind's drag coefficient; m / k = 0.4 s
W = (0.0, 2.0, 0.0)   # m/s, the wind: horizontal, across the sheet
DURATION = 6.0    # s: 15 decay times m / k, the cloth comes to rest

# Tolerances (measured values in the comments, this build):
SINGLE_MAX_ERROR = 1e-8      # m/s; measured 2.5e-9 (rk4, dt = 0.01 s)
TILT_REL_ERROR = 1e-3        # measured 4e-5 after 6 s (the swing not quite gone)
MIN_DOWNWIND = 0.05          # m; measured 0.104
MAX_FINAL_SPEED = 1e-2       # m/s; measured 1e-3: the cloth in the wind is at rest


class Wind(pdyn.Force):
    """wind: a drag towards the wind velocity w, f = k (w - v) on every particle"""

    parameters = {
        "k": pdyn.param(0.001, unit="kg/s", doc="drag coefficient", min=0),
        "w": pdyn.param((1.0, 0.0, 0.0), unit="m/s", doc="wind velocity"),
    }
    # Not dissipative (the wind does positive work on a particle slower
    # than it), not internal (it pushes the whole body): the defaults.

    # The factory (a scene's `type: wind`) calls the class with the checked
    # parameters as keywords; pdyn.Force has no constructor that stores them.
    def __init__(self, k=0.001, w=(1.0, 0.0, 0.0)):
        self.k = float(k)
        self.w = np.asarray(w, dtype=float)

    def add_forces(self, x, v, mass, f):
        f += self.k * (self.w - v)      # add into f; x, v, mass are read-only


def single_particle():
    """Max |v - v_exact| of one particle blown by Wind alone, and its record."""
    m, k, w, v0 = 0.2, 0.5, np.array([2.0, 0.0, -1.0]), np.array([0.0, 1.0, 0.5])
    sim = pdyn.loads(f"""
simulation: {{ dt: 0.01, duration: 2.0 }}
particles:
  - {{ position: [0, 0, 0], velocity: {v0.tolist()}, mass: {m} }}
forces:
  - {{ type: wind, k: {k}, w: {w.tolist()} }}      # the Python class, by its plugin name
""", name="single_particle")
    t, v = [sim.t], [sim.v[0].copy()]
    sim.run(every=1, callback=lambda s: (t.append(s.t), v.append(s.v[0].copy())))
    t, v = np.array(t), np.array(v)
    exact = w + (v0 - w) * np.exp(-k * t / m)[:, None]
    return np.abs(v - exact).max(), t, v, exact, m / k


def cloth(wind):
    """The shrunk hanging cloth run for DURATION, with or without wind."""
    g = "particles[0].grid."
    sim = pdyn.load(SCENE, set={
        g + "nx": 16, g + "ny": 16,                    # 256 particles (the scene: 10 000)
        g + "u": [0.03, 0, 0], g + "v": [0, 0, 0.03],  # 3 cm spacing: a 0.45 m sheet
        g + "origin": [-0.225, 0, 1.55],               # top edge at z = 2 m
        g + "mass": MASS,
        g + "velocity": [0, 0, 0],                     # no gust: at rest in the x-z plane
        "simulation.dt": 5e-4, "simulation.duration": DURATION,
    })
    if wind:
        label = sim.add_force(Wind(k=K, w=W))
        print(f"  added {label!r}; forces: {len(sim.forces)}")
    sim.run()
    return sim


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else Path.cwd() / "out" / "examples")
    out.mkdir(parents=True, exist_ok=True)
    failures = []

    def check(ok, message):
        print(("ok:   " if ok else "FAIL: ") + message)
        if not ok:
            failures.append(message)

    # 1. One particle.
    err, t1, v1, exact1, tau = single_particle()
    print(f"single particle: {len(t1) - 1} steps over {t1[-1]:g} s (decay time m/k = {tau:g} s), "
          f"max |v - v_exact| = {err:.2e} m/s")
    check(err < SINGLE_MAX_ERROR, f"single particle: {err:.2e} m/s < {SINGLE_MAX_ERROR:g} m/s")

    # 2, 3. The cloth with and without wind.
    print("cloth without wind")
    calm = cloth(wind=False)
    print("cloth with wind")
    windy = cloth(wind=True)
    results = {}
    for name, sim in (("calm", calm), ("windy", windy)):
        free = ~sim.fixed
        pins = sim.x[sim.fixed]
        com = sim.x[free].mean(axis=0)          # equal masses
        axis_y, axis_z = pins[:, 1].mean(), pins[:, 2].mean()
        tilt = (com[1] - axis_y) / (axis_z - com[2])
        speed = np.linalg.norm(sim.v, axis=1).max()
        results[name] = (sim.x.copy(), com, tilt, (axis_y, axis_z))
        print(f"  {name}: t = {sim.t:g} s, {sim.n} particles ({len(pins)} pinned), centre of mass "
              f"of the free ones {np.array2string(com, precision=4)}, tan(tilt) = {tilt:.6f}, "
              f"max speed {speed:.1e} m/s")
        if name == "windy":   # the calm one still sways: only the scene's weak drag damps it
            check(speed < MAX_FINAL_SPEED,
                  f"{name}: at rest, max speed {speed:.1e} < {MAX_FINAL_SPEED:g} m/s")

    calm_y, windy_y = results["calm"][1][1], results["windy"][1][1]
    check(abs(calm_y) < 1e-12, f"without wind the cloth stays in its plane: y_com = {calm_y:.1e} m")
    shift = windy_y - calm_y
    check(shift > MIN_DOWNWIND, f"blown downwind (+y): y_com moved by {shift:.4f} m > {MIN_DOWNWIND} m")
    expected = K * math.hypot(*W) / (MASS * G)
    tilt = results["windy"][2]
    rel = abs(tilt / expected - 1)
    check(rel < TILT_REL_ERROR, f"tan(tilt) = {tilt:.6f}, k|w|/(m g) = {expected:.6f}: "
                                f"relative error {rel:.1e} < {TILT_REL_ERROR:g}")

    # 4. The conformance kit.
    report = pdyn.check(Wind)
    print(str(report))
    check(report.passed, f"pdyn.check(Wind) passed ({len(report.failed)} failed)")

    # The plot: the cloth from the side, and the single particle's velocity.
    fig, (side, vel) = plt.subplots(1, 2, figsize=(11, 5.5), gridspec_kw={"width_ratios": [1, 1.2]})
    for name, color in (("calm", "C0"), ("windy", "C1")):
        x, com, _, (ay, az) = results[name]
        side.plot(x[:, 1], x[:, 2], ".", ms=3, color=color,
                  label=("no wind" if name == "calm" else f"wind: k = {K} kg/s, |w| = {math.hypot(*W):g} m/s"))
        side.plot(com[1], com[2], "x", ms=10, mew=2, color=color)
    ay, az = results["windy"][3]
    length = az - results["windy"][1][2]
    side.plot([ay, ay + expected * length], [az, az - length], "k--", lw=1,
              label="pin line along k w + m g")
    side.plot([ay], [az], "ks", ms=6, label="pins (seen end-on)")
    side.set_xlim(-0.05, 0.35)
    side.set_aspect("equal")
    side.set_xlabel("y (m), downwind")
    side.set_ylabel("z (m)")
    side.set_title(f"cloth at t = {DURATION:g} s seen along x\n(x marks: centres of mass)", fontsize=10)
    side.legend(fontsize=7, loc="upper right")
    for i, axis in enumerate("xyz"):
        vel.plot(t1, exact1[:, i], color="0.6", lw=3)
        vel.plot(t1[::10], v1[::10, i], ".", color=f"C{i}", label=f"v_{axis}")
    vel.plot([], [], color="0.6", lw=3, label="w + (v0 - w) e^(-kt/m)")
    vel.set_xlabel("t (s)")
    vel.set_ylabel("v (m/s)")
    vel.set_title(f"one particle under Wind alone (max error {err:.1e} m/s)")
    vel.legend(fontsize=8)
    fig.tight_layout()
    png = out / "cloth_wind.png"
    fig.savefig(png, dpi=110)
    print(f"wrote {png}")

    if failures:
        raise SystemExit(f"{len(failures)} check(s) failed: " + "; ".join(failures))


if __name__ == "__main__":
    main()
