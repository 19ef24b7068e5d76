#!/usr/bin/env python3
"""Writes configs/lj_liquid.csv: 256 Lennard-Jones atoms on an fcc lattice
(4 x 4 x 4 cells) at the reduced density 0.8442 of LAMMPS's melt benchmark,
with Maxwell-Boltzmann velocities at T = 1.44 (seed 87287), the total momentum
removed and the temperature set exactly (dof = 3N - 3). Units: sigma = 1 m,
epsilon = 1 J, mass 1 kg.

    python3 scripts/make_lj_liquid.py > configs/lj_liquid.csv
"""
import math
import random

cells, density, temperature = 4, 0.8442, 1.44
a = (4.0 / density) ** (1.0 / 3.0)
basis = [(0, 0, 0), (0.5, 0.5, 0), (0.5, 0, 0.5), (0, 0.5, 0.5)]
rng = random.Random(87287)
x, v = [], []
for i in range(cells):
    for j in range(cells):
        for k in range(cells):
            for b in basis:
                x.append(tuple(a * (c + o + 0.25) for c, o in zip((i, j, k), b)))
                v.append([rng.gauss(0.0, 1.0) for _ in range(3)])
n = len(x)
mean = [sum(vi[d] for vi in v) / n for d in range(3)]
v = [[vi[d] - mean[d] for d in range(3)] for vi in v]
kinetic = 0.5 * sum(c * c for vi in v for c in vi)
scale = math.sqrt(temperature * (3 * n - 3) / (2 * kinetic))
print("x,y,z,vx,vy,vz,mass")
for xi, vi in zip(x, v):
    print(",".join(f"{c:.17g}" for c in (*xi, *(scale * c for c in vi))) + ",1")
