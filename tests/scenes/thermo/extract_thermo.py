#!/usr/bin/env python3
"""LAMMPS thermo output (a log file, or the screen output on stdin) to the
CSV reference.thermo: header step,temp,press,pe,ke,etotal, one row per thermo
line, the values exactly as LAMMPS printed them (format float %.17g).
    lmp -in make_reference.lmp -log none | python3 extract_thermo.py > reference.thermo
With --as-printed, the first run's thermo with LAMMPS's own header (Step,
Temp, E_pair, ...), whatever its columns: what a converted scene's energy
writer writes with `header: lammps`.
"""
import sys

args = [a for a in sys.argv[1:] if a != "--as-printed"]
as_printed = len(args) != len(sys.argv) - 1
HEADER = ["Step", "Temp", "Press", "PotEng", "KinEng", "TotEng"]

lines = (open(args[0]) if args else sys.stdin).read().splitlines()
if as_printed:
    start = next(i for i, l in enumerate(lines) if l.split()[:1] == ["Step"])
    HEADER = lines[start].split()
    print(",".join(HEADER))
else:
    start = next(i for i, l in enumerate(lines) if l.split() == HEADER)
    print("step,temp,press,pe,ke,etotal")
for line in lines[start + 1:]:
    if line.startswith("Loop time"):
        break
    fields = line.split()
    assert len(fields) == len(HEADER), line
    int(fields[0])
    [float(f) for f in fields[1:]]
    print(",".join(fields))
