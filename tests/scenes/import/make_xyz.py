#!/usr/bin/env python3
"""Writes melt.xyz, the extended XYZ sample, from LAMMPS's melt.dump (same
state, numbers copied as written): type 1 as species Ar, type 2 as Kr."""
lines = open("melt.dump").read().split("\n")
n = int(lines[3])
hi = [line.split()[1] for line in lines[5:8]]
rows = [line.split() for line in lines[9:9 + n]]
with open("melt.xyz", "w") as out:
    out.write(f"{n}\n")
    out.write(f'Lattice="{hi[0]} 0 0 0 {hi[1]} 0 0 0 {hi[2]}" '
              'Properties=species:S:1:pos:R:3:velo:R:3:mass:R:1 pbc="T T T"\n')
    for r in rows:
        out.write(" ".join([{"1": "Ar", "2": "Kr"}[r[1]]] + r[2:8] + [r[8]]) + "\n")
