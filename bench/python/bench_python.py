#!/usr/bin/env python3
"""The Python module's costs, measured side by side in one run:

  step:  the 316 x 316 cloth (rk4) stepped by sim.step(N) against `pdyn run
         --steps N` on the same scene, each loop timed alone (pdyn run
         reports its step loop; Python times sim.step), alternating, median
         of the pairs' ratios;
  force: the cost of one call of a Python-defined force (a do-nothing
         add_forces on N particles) per force evaluation, against the same
         scene without it;
  sweep: 16 variants of a scene on a 2-process pool against one after the
         other.

Run on a quiet machine (it prints `uptime` before and after):
  PYTHONPATH=build/python /usr/bin/python3 bench/python/bench_python.py --pdyn build/bin/pdyn
"""
import argparse
import concurrent.futures
import multiprocessing
import os
import pathlib
import re
import statistics
import subprocess
import sys
import tempfile
import time

import pdyn

ROOT = pathlib.Path(__file__).resolve().parents[2]
CLOTH = ROOT / "configs" / "hanging_cloth.yaml"


def cloth_overrides(n, steps):
    # The hanging cloth at n x n, its spacing scaled to keep its size.
    h = 0.99 / (n - 1)
    return {"simulation.duration": None, "simulation.steps": steps, "output": None,
            "particles[0].grid.nx": n, "particles[0].grid.ny": n,
            "particles[0].grid.u": [h, 0, 0], "particles[0].grid.v": [0, 0, h],
            "particles[0].grid.mass": 1.0 / (n * n)}


def set_args(overrides):
    args = []
    for k, v in overrides.items():
        args += ["--set", f"{k}={pdyn._yaml(v)}"]
    return args


def bench_step(program, n, steps, rounds, threads):
    overrides = cloth_overrides(n, steps)
    ratios, cli, py = [], [], []
    for _ in range(rounds):
        out = subprocess.run([program, "run", str(CLOTH), "--threads", str(threads),
                              *set_args(overrides)], capture_output=True, text=True, check=True)
        m = re.search(r"with rk4 to t = \S+ s in ([0-9.e+-]+) s", out.stderr + out.stdout)
        if not m:
            sys.exit(f"pdyn run printed no step time:\n{out.stderr}")
        t_cli = float(m.group(1))
        sim = pdyn.load(CLOTH, set=overrides, threads=threads)
        t0 = time.perf_counter()
        sim.step(steps)
        t_py = time.perf_counter() - t0
        cli.append(t_cli)
        py.append(t_py)
        ratios.append(t_py / t_cli)
    return statistics.median(cli), statistics.median(py), statistics.median(ratios), ratios


class Nothing(pdyn.Force):
    """adds nothing: the cost of a call"""

    def add_forces(self, x, v, mass, f):
        pass


class PyDrag(pdyn.Force):
    """linear drag f = -k v, as the C++ drag plugin"""
    parameters = {"k": pdyn.param(0.1, unit="kg/s", doc="drag coefficient", min=0)}
    dissipative = True

    def add_forces(self, x, v, mass, f):
        f -= self.k * v


def bench_force(n, steps, rounds):
    scene = f"""
simulation: {{ dt: 0.001, steps: {steps}, solver: {{ type: rk4 }} }}
particles:
  - cloud: {{ n: {n}, box: {{ min: [0, 0, 0], max: [1, 1, 1] }}, mass: 1, seed: 1 }}
forces:
  - {{ type: gravity, g: [0, 0, -9.81] }}
"""
    # Per force evaluation: nothing added; a Python add_forces that does
    # nothing; drag in Python (NumPy); the C++ drag plugin.
    cases = {"none": lambda s: None, "python_nothing": lambda s: s.add_force(Nothing()),
             "python_drag": lambda s: s.add_force(PyDrag(k=0.1)),
             "cpp_drag": lambda s: s.add_force("drag", k=0.1)}
    per_eval = {name: [] for name in cases}
    for _ in range(rounds):
        for name, add in cases.items():
            sim = pdyn.loads(scene, threads=1)
            add(sim)
            e0 = sim.force_evaluations
            t0 = time.perf_counter()
            sim.step(steps)
            per_eval[name].append((time.perf_counter() - t0) / (sim.force_evaluations - e0))
    base = statistics.median(per_eval["none"])
    return {name: statistics.median(v) - base for name, v in per_eval.items() if name != "none"}


SWEEP_SCENE = """
simulation: { dt: 0.0002, steps: 1500 }
particles:
  - grid:
      origin: [0, 0, 1]
      u: [0.02, 0, 0]
      v: [0, 0.02, 0]
      nx: 60
      ny: 60
      mass: 0.001
      pin: [[0, -1], [-1, -1]]
      springs: { structural: { ks: 200, kd: 0.01 }, shear: { ks: 100, kd: 0.01 } }
forces:
  - { type: gravity, g: [0, 0, -9.81] }
"""


def final_z(sim):
    return float(sim.x[:, 2].mean())


def bench_sweep(rounds):
    grid = {"particles[0].grid.springs.structural.ks": [100.0, 200.0, 300.0, 400.0],
            "simulation.dt": [1e-4, 1.5e-4, 2e-4, 2.5e-4]}
    ratios = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        seq = pdyn.sweep(SWEEP_SCENE, grid, extract=final_z,
                         executor=concurrent.futures.ThreadPoolExecutor(1))
        t_seq = time.perf_counter() - t0
        with concurrent.futures.ProcessPoolExecutor(
                2, mp_context=multiprocessing.get_context("spawn")) as pool:
            t0 = time.perf_counter()
            par = pdyn.sweep(SWEEP_SCENE, grid, extract=final_z, executor=pool)
            t_par = time.perf_counter() - t0
        assert [r.value for r in seq] == [r.value for r in par]
        ratios.append((t_seq, t_par, t_seq / t_par))
    return ratios


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--pdyn", required=True, help="the pdyn program")
    ap.add_argument("--size", type=int, default=316)
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--only", choices=["step", "force", "sweep"])
    a = ap.parse_args()
    print("uptime:", os.popen("uptime").read().strip())
    if a.only in (None, "step"):
        cli, py, ratio, ratios = bench_step(a.pdyn, a.size, a.steps, a.rounds, a.threads)
        print(f"step: {a.size}x{a.size} cloth, rk4, {a.steps} steps, {a.threads} thread(s): "
              f"pdyn run {cli:.3f} s, sim.step {py:.3f} s; sim.step / pdyn run median "
              f"{ratio:.4f} (pairs: {', '.join(f'{r:.4f}' for r in ratios)})")
    if a.only in (None, "force"):
        for n, steps in ((100, 20000), (10000, 2000), (100000, 200)):
            c = bench_force(n, steps, a.rounds)
            print(f"force: {n} particles, cost per call over gravity alone: "
                  f"Python add_forces doing nothing {c['python_nothing'] * 1e6:.2f} us, "
                  f"drag in Python (NumPy) {c['python_drag'] * 1e6:.2f} us, "
                  f"C++ drag plugin {c['cpp_drag'] * 1e6:.2f} us")
    if a.only in (None, "sweep"):
        for t_seq, t_par, r in bench_sweep(a.rounds):
            print(f"sweep: 16 variants sequential {t_seq:.2f} s, 2 processes {t_par:.2f} s: "
                  f"{r:.2f}x")
    print("uptime:", os.popen("uptime").read().strip())


if __name__ == "__main__":
    main()
