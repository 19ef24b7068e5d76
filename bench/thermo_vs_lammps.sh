#!/usr/bin/env bash
# Temperature and pressure, pdyn against LAMMPS (issue 30, item 4): LAMMPS
# writes a 256-atom Lennard-Jones liquid's starting state and its thermo
# (tests/scenes/thermo/make_reference.lmp), pdyn continues the same state
# with the documented scene (thermo.yaml: `pdyn run`, verlet, the energy
# writer's kT and pressure columns), and this prints both side by side at
# every tenth step, 0 to 100, with the worst relative difference of each.
# Without lmp it compares with the shipped reference.thermo instead.
#
#   bash bench/thermo_vs_lammps.sh [BUILD_DIR]      (default: build)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
pdyn="$PWD/$build/bin/pdyn"
[[ -x "$pdyn" ]] || { echo "thermo_vs_lammps: no $pdyn (build pdyn first)" >&2; exit 2; }
out=out/thermo
rm -rf "$out"
mkdir -p "$out"
cp tests/scenes/thermo/{make_reference.lmp,extract_thermo.py,thermo.yaml,thermo_start.data} "$out/"
if command -v lmp >/dev/null; then
  echo "LAMMPS: $(lmp -h | awk '/^Large-scale/{getline; print; exit}' | xargs)"
  (cd "$out" && lmp -in make_reference.lmp -log none | python3 extract_thermo.py >reference.thermo)
else
  echo "thermo_vs_lammps: no lmp; comparing with the shipped tests/scenes/thermo/reference.thermo"
  cp tests/scenes/thermo/reference.thermo "$out/"
fi
(cd "$out" && "$pdyn" run thermo.yaml -q)
python3 - "$out/reference.thermo" "$out/out/thermo-energy.csv" <<'PY'
import csv, sys
lammps = list(csv.DictReader(open(sys.argv[1])))
pdyn = list(csv.DictReader(open(sys.argv[2])))
assert [r["step"] for r in lammps] == [r["step"] for r in pdyn], "different steps"
print("| step | LAMMPS temp | pdyn kT | LAMMPS press | pdyn pressure |")
print("|---|---|---|---|---|")
for a, b in zip(lammps, pdyn):
    print(f"| {a['step']} | {a['temp']} | {b['kT']} | {a['press']} | {b['pressure']} |")
for theirs, ours in (("temp", "kT"), ("press", "pressure"), ("pe", "potential"),
                     ("ke", "kinetic"), ("etotal", "total")):
    worst = max(abs(float(b[ours]) - float(a[theirs])) / abs(float(a[theirs]))
                for a, b in zip(lammps, pdyn))
    print(f"{ours} vs LAMMPS {theirs}: worst relative difference {worst:.2e}")
PY
