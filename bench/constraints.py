#!/usr/bin/env python3
"""Constraint enforcement costs and the constrained cloth's time to solution
(issue 29, docs/performance.md "Constraints"). Run through
scripts/bench_constraints.sh, which builds pdyn first.

Whole `pdyn run` processes, each configuration `--repeat` times in turn
(round robin, so that a noisy machine's drift falls on all alike); the
figure kept is the fastest "the steps" time pdyn prints (the step loop,
without start-up and output). Prints uptime's load average before and after.

1. Cost per constraint row per step, for each method, on
   configs/hanging_chain.yaml (50 rods) and on the 30 x 30 cloth of
   configs/xpbd_cloth.yaml with structural rods only, hung from one corner
   (1,740 rods; with shear and bend rods as well the rigid rows are
   redundant, and so is the top edge pulled taut between two pins: Witkin's
   force and RATTLE refuse a singular J W J^T, XPBD does not mind):
   (t - t0) / (rows x steps),
   t0 the same scene with no constraints stepped by the same solver. For
   xpbd "per step" is per substep.
2. Time to solution of xpbd_cloth.yaml's picture (2 s of the same cloth
   under gravity and the gust) at a largest structural-edge strain of at
   most 1 % at every step: xpbd as shipped, and the same cloth with springs
   (ks = 20000 N/m structural, 10000 shear) under implicit_euler and rk4 at
   the largest steps that keep the strain bound (measured: 2 ms and 0.1 ms;
   implicit_euler at 10 ms stretches by 3.3 %, rk4 at 0.2 ms blows up).
"""
import argparse
import csv
import math
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def load():
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


def steps_time(pdyn, scene, sets, out):
    """Runs pdyn on `scene` (a path) with --set `sets`; the step loop's seconds."""
    args = [pdyn, "run", scene, "--set", f"output.path={out}/f.csv",
            "--set", f"output.energy={out}/e.csv"]
    for s in sets:
        args += ["--set", s]
    r = subprocess.run(args, capture_output=True, text=True, check=True)
    m = re.search(r"\(the steps ([0-9.e+-]+) s\)", r.stderr + r.stdout)
    if not m:
        sys.exit(f"constraints.py: no step time in the output of {' '.join(args)}")
    return float(m.group(1))


def strain(csv_path, n, spacing):
    """Largest | |x_a - x_b| / spacing - 1 | over the structural edges of an n x n grid."""
    frames = {}
    with open(csv_path) as f:
        for r in csv.DictReader(f):
            frames.setdefault(r["t"], []).append((float(r["x"]), float(r["y"]), float(r["z"])))
    worst = 0.0
    for x in frames.values():
        for j in range(n):
            for i in range(n):
                a = x[j * n + i]
                if i + 1 < n:
                    worst = max(worst, abs(math.dist(a, x[j * n + i + 1]) / spacing - 1))
                if j + 1 < n:
                    worst = max(worst, abs(math.dist(a, x[(j + 1) * n + i]) / spacing - 1))
    return worst


def write(path, text):
    with open(path, "w") as f:
        f.write(text)
    return path


def cloth_scene(tmp, links, solver, dt, name, one_pin=False):
    """xpbd_cloth.yaml with its links and solver replaced; `one_pin` hangs it
    from one corner."""
    with open(os.path.join(ROOT, "configs/xpbd_cloth.yaml")) as f:
        text = f.read()
    if one_pin:
        text = text.replace("pin: [[0, -1], [-1, -1]]", "pin: [[0, -1]]")
    start = text.index("      rods:")
    end = text.index("\nforces:")
    text = text[:start] + links + text[end:]
    text = re.sub(r"  solver: \{[^}]*\}", "  solver: " + solver, text)
    text = re.sub(r"  dt: 0\.01 ", f"  dt: {dt} ", text)
    return write(os.path.join(tmp, name + ".yaml"), text)


def chain_scene(tmp, rods, name):
    with open(os.path.join(ROOT, "configs/hanging_chain.yaml")) as f:
        text = f.read()
    if not rods:
        text = text.replace("      rods: {}", "      springs: { ks: 0 }")
    return write(os.path.join(tmp, name + ".yaml"), text)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--pdyn", default=os.path.join(ROOT, "build/bin/pdyn"))
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--only", default="",
                    help="run only the cost rows whose label contains this text (e.g. "
                         "\"cloth, Witkin\"), without the time-to-solution table")
    a = ap.parse_args()
    print(f"load average before: {load()}")
    tmp = tempfile.mkdtemp(prefix="pdyn-bench-constraints-")

    structural = "      rods: { structural: {} }\n"
    no_links = "      springs: { structural: { ks: 0 } }\n"
    chain = chain_scene(tmp, True, "chain")
    chain0 = chain_scene(tmp, False, "chain0")
    # (label, scene, baseline scene, sets, rows, steps per run, substeps)
    xp = "{ type: xpbd, substeps: 1 }"
    costs = [
        ("chain, RATTLE (verlet)", chain, chain0, [], 50, 20000, 1),
        ("chain, Witkin's force (rk4)", chain, chain0, ["simulation.solver={ type: rk4 }"], 50,
         20000, 1),
        ("chain, XPBD (1 substep)", chain, chain0, [f"simulation.solver={xp}"], 50, 20000, 1),
        ("cloth, RATTLE (verlet)",
         cloth_scene(tmp, structural, "{ type: verlet }", 0.00025, "cv", True),
         cloth_scene(tmp, no_links, "{ type: verlet }", 0.00025, "cv0", True),
         ["simulation.duration=0.05"], 1740, 200, 1),
        ("cloth, Witkin's force (rk4)",
         cloth_scene(tmp, structural, "{ type: rk4 }", 0.00025, "cr", True),
         cloth_scene(tmp, no_links, "{ type: rk4 }", 0.00025, "cr0", True),
         ["simulation.duration=0.05"], 1740, 200, 1),
        ("cloth, XPBD (80 substeps)",
         cloth_scene(tmp, structural, "{ type: xpbd, substeps: 80 }", 0.01, "cx", True),
         cloth_scene(tmp, no_links, "{ type: xpbd, substeps: 80 }", 0.01, "cx0", True),
         ["simulation.duration=0.5"], 1740, 50, 80),
    ]
    costs = [c for c in costs if a.only in c[0]]
    springs = ("      springs:\n        structural: { ks: 20000, kd: 0.4 }\n"
               "        shear: { ks: 10000, kd: 0.2 }\n        bend: { ks: 100, kd: 0.0 }\n")
    solutions = [] if a.only else [
        ("xpbd, 10 ms steps of 80 substeps", os.path.join(ROOT, "configs/xpbd_cloth.yaml"), 0.01),
        ("springs, implicit_euler, 2 ms",
         cloth_scene(tmp, springs, "{ type: implicit_euler }", 0.002, "si"), 0.002),
        ("springs, rk4, 0.1 ms", cloth_scene(tmp, springs, "{ type: rk4 }", 0.0001, "sr"), 0.0001),
    ]
    best = {}
    for _ in range(a.repeat):
        for label, scene, base, sets, *_ in costs:
            for key, s in ((label, scene), (label + " (none)", base)):
                t = steps_time(a.pdyn, s, sets, tmp)
                best[key] = min(best.get(key, t), t)
        for label, scene, _ in solutions:
            t = steps_time(a.pdyn, scene, [], tmp)
            best[label] = min(best.get(label, t), t)
    strains = {}  # from a run writing every step, not timed
    for label, scene, _ in solutions:
        steps_time(a.pdyn, scene, ["output.every=1"], tmp)
        strains[label] = strain(os.path.join(tmp, "f.csv"), 30, 0.02)

    print("\n| scene and method | rows | steps | time (s) | without constraints (s) "
          "| per row per step (ns) |")
    print("|---|---|---|---|---|---|")
    for label, _, _, _, rows, steps, sub in costs:
        t, t0 = best[label], best[label + " (none)"]
        per = (t - t0) / (rows * steps * sub) * 1e9
        unit = "per row per substep" if sub > 1 else ""
        print(f"| {label} | {rows} | {steps} | {t:.3f} | {t0:.3f} | {per:.0f} {unit}|")
    if solutions:
        print("\n| 2 s of the cloth, largest edge strain <= 1 % | step (ms) | strain | time (s) "
              "| vs xpbd |")
        print("|---|---|---|---|---|")
    for label, _, dt in solutions:
        ref = best[solutions[0][0]]
        print(f"| {label} | {dt * 1e3:g} | {strains[label] * 100:.2f} % | {best[label]:.2f} "
              f"| {best[label] / ref:.1f}x |")
    print(f"\nload average after: {load()}")


if __name__ == "__main__":
    main()
