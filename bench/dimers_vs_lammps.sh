#!/usr/bin/env bash
# Temperature and pressure with constraints, pdyn against LAMMPS (issue 42,
# item 3): LAMMPS melts a liquid of 256 rigid Lennard-Jones dimers under
# fix rattle and writes its state and thermo (tests/scenes/dimers/
# make_reference.lmp); pdyn continues the same state with verlet's RATTLE
# (dimers.yaml: the energy writer's kT, pressure, dof, ... columns), and
# this prints both at steps 0, 100 and 200 with the relative difference of
# each. Fails unless temperature and pressure agree to 1e-8 relative.
# Without lmp it compares with the shipped reference instead. With
# --write-reference it copies LAMMPS's dimers_start.data and reference.thermo
# into tests/scenes/dimers/ (what the test compares with).
#
#   bash bench/dimers_vs_lammps.sh [BUILD_DIR] [--write-reference]   (default: build)
set -euo pipefail
cd "$(dirname "$0")/.."
build=build
write=0
for a in "$@"; do
  case "$a" in
    --write-reference) write=1 ;;
    *) build=$a ;;
  esac
done
pdyn="$PWD/$build/bin/pdyn"
[[ -x "$pdyn" ]] || { echo "dimers_vs_lammps: no $pdyn (build pdyn first)" >&2; exit 2; }
scene=tests/scenes/dimers
out=out/dimers
rm -rf "$out"
mkdir -p "$out"
cp "$scene"/{make_reference.lmp,dimer.mol,dimers.yaml} "$out/"
if command -v lmp >/dev/null; then
  echo "LAMMPS: $(lmp -h | grep -m1 -o "[0-9]\+ [A-Z][a-z]\+ [0-9]\{4\}.*")"
  (cd "$out" && lmp -in make_reference.lmp -log none -echo none |
    python3 ../../tests/scenes/thermo/extract_thermo.py >reference.thermo)
  if ((write)); then
    cp "$out"/{dimers_start.data,reference.thermo} "$scene/"
    echo "dimers_vs_lammps: wrote $scene/dimers_start.data and $scene/reference.thermo"
  fi
else
  ((write == 0)) || { echo "dimers_vs_lammps: --write-reference needs lmp" >&2; exit 2; }
  echo "dimers_vs_lammps: no lmp; comparing with the shipped $scene/reference.thermo"
  cp "$scene"/{dimers_start.data,reference.thermo} "$out/"
fi
(cd "$out" && "$pdyn" run dimers.yaml -q)
python3 - "$out" <<'PY'
import csv, re, sys
out = sys.argv[1]
# The rods of dimers.yaml are the data file's bonds (pairs: { file: ... }).
data = open(f"{out}/dimers_start.data").read()
bonds = [b for b in data[data.index("\nBonds\n"):].split("\n\n")[1].split("\n") if b.strip()]
scene = open(f"{out}/dimers.yaml").read()
assert re.search(r"pairs: \{ file: dimers_start.data \}", scene), "dimers.yaml's rods are not the data file's bonds"
lammps = list(csv.DictReader(open(f"{out}/reference.thermo")))
pdyn = list(csv.DictReader(open(f"{out}/out/dimers-energy.csv")))
assert [r["step"] for r in lammps] == [r["step"] for r in pdyn], "different steps"
print(f"{len(bonds)} rods; pdyn's dof {pdyn[0]['dof']} (LAMMPS: 3 N - 3 - rods)")
print("| step | LAMMPS temp | pdyn kT | rel. diff | LAMMPS press | pdyn pressure | rel. diff |")
print("|---|---|---|---|---|---|---|")
worst = {}
for a, b in zip(lammps, pdyn):
    dt = abs(float(b["kT"]) - float(a["temp"])) / abs(float(a["temp"]))
    dp = abs(float(b["pressure"]) - float(a["press"])) / abs(float(a["press"]))
    print(f"| {a['step']} | {a['temp']} | {b['kT']} | {dt:.1e} | {a['press']} | {b['pressure']} | {dp:.1e} |")
for theirs, ours in (("temp", "kT"), ("press", "pressure"), ("pe", "potential"),
                     ("ke", "kinetic"), ("etotal", "total")):
    worst[ours] = max(abs(float(b[ours]) - float(a[theirs])) / abs(float(a[theirs]))
                      for a, b in zip(lammps, pdyn))
    print(f"{ours} vs LAMMPS {theirs}: worst relative difference {worst[ours]:.2e}")
bad = [k for k in ("kT", "pressure") if not worst[k] <= 1e-8]
if bad:
    sys.exit(f"dimers_vs_lammps: {', '.join(bad)} differ from LAMMPS by more than 1e-8")
PY
