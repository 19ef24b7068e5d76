#!/usr/bin/env python3
"""Writes melt.xyz, the extended XYZ sample, from LAMMPS's files of the same
run (make_samples.lmp), numbers copied as LAMMPS printed them, type 1 as
species Ar and type 2 as Kr, two frames: the start (step 0, the first frame
of melt.lammpstrj: no masses) and the state of melt.data and melt.dump
(step 50, with masses)."""
SPECIES = {"1": "Ar", "2": "Kr"}


def frames(path):
    """Each frame of a LAMMPS text dump: (box his, column names, rows by id)."""
    lines = open(path).read().split("\n")
    out, k = [], 0
    while k < len(lines) and lines[k].startswith("ITEM: TIMESTEP"):
        n = int(lines[k + 3])
        his = [line.split()[1] for line in lines[k + 5:k + 8]]
        names = lines[k + 8].split()[2:]
        rows = sorted((line.split() for line in lines[k + 9:k + 9 + n]), key=lambda r: int(r[0]))
        out.append((his, names, rows))
        k += 9 + n
    return out


def write_frame(out, his, names, rows, columns, properties):
    out.write(f"{len(rows)}\n")
    out.write(f'Lattice="{his[0]} 0 0 0 {his[1]} 0 0 0 {his[2]}" '
              f'Properties={properties} pbc="T T T"\n')
    at = [names.index(c) for c in columns]
    for r in rows:
        out.write(" ".join([SPECIES[r[names.index("type")]]] + [r[i] for i in at]) + "\n")


with open("melt.xyz", "w") as out:
    his, names, rows = frames("melt.lammpstrj")[0]
    write_frame(out, his, names, rows, ["xu", "yu", "zu", "vx", "vy", "vz"],
                "species:S:1:pos:R:3:velo:R:3")
    his, names, rows = frames("melt.dump")[0]
    write_frame(out, his, names, rows, ["x", "y", "z", "vx", "vy", "vz", "mass"],
                "species:S:1:pos:R:3:velo:R:3:mass:R:1")
