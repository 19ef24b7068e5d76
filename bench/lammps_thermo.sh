#!/usr/bin/env bash
# LAMMPS's bonded styles and a data file's topology, pdyn against LAMMPS
# (issue 44): for each case LAMMPS writes its state at step 0 and its thermo
# (the case's make_reference*.lmp in tests/scenes/), pdyn continues that
# state with the case's scene, and this prints the worst relative
# difference of each column (temp, press, pe, ke, etotal against kT,
# pressure, potential, kinetic, total; the pressure against |press| + N kT
# / V, as the tests do). Fails unless every column agrees to 1e-8. Without
# lmp it compares with the shipped references. With --write-reference it
# copies LAMMPS's new state and thermo into tests/scenes/ (what the tests
# compare with).
#
#   bash bench/lammps_thermo.sh [--build DIR] [--write-reference] [CASE ...]
#
# tests/cli/convert_test.cpp runs the same states from LAMMPS input
# scripts converted by `pdyn convert` (in.kg, in.trimers, in.molecular,
# in.cosine, in.improper beside the data files).
#   cases: fene (bond_style fene), molecular (harmonic bonds and angles, OPLS
#   dihedrals), cosine (angle cosine/squared, dihedral harmonic), improper
#   (improper harmonic), kg (the Kremer-Grest melt with special_bonds fene),
#   scaled (special_bonds lj 0.2 0.5 0.25), trimers (fix rattle b 1 a 1);
#   default all
set -euo pipefail
cd "$(dirname "$0")/.."
build=build
write=0
cases=()
while (($#)); do
  case "$1" in
    --build) build=$2; shift ;;
    --write-reference) write=1 ;;
    *) cases+=("$1") ;;
  esac
  shift
done
((${#cases[@]})) || cases=(fene molecular cosine improper kg scaled trimers)
pdyn="$PWD/$build/bin/pdyn"
[[ -x "$pdyn" ]] || { echo "lammps_thermo: no $pdyn (build pdyn first)" >&2; exit 2; }
have_lmp=0
command -v lmp >/dev/null && have_lmp=1
((write == 0 || have_lmp)) || { echo "lammps_thermo: --write-reference needs lmp" >&2; exit 2; }
((have_lmp)) && echo "LAMMPS: $(lmp -h | grep -m1 -o "[0-9]\+ [A-Z][a-z]\+ [0-9]\{4\}.*")"
status=0
for c in "${cases[@]}"; do
  # folder, LAMMPS input, its thermo, its state, pdyn's scene, pdyn's energy file
  case "$c" in
    fene) set -- fene make_reference.lmp reference.thermo fene_start.data fene.yaml out/fene-energy.csv ;;
    molecular) set -- molecular make_reference.lmp reference.thermo molecular_start.data molecular.yaml out/molecular-energy.csv ;;
    cosine) set -- molecular make_reference_cosine.lmp cosine.thermo cosine_start.data cosine.yaml out/cosine-energy.csv ;;
    improper) set -- molecular make_reference_improper.lmp improper.thermo improper_start.data improper.yaml out/improper-energy.csv ;;
    kg) set -- special make_reference_kg.lmp kg.thermo kg_start.data kg.yaml out/kg-energy.csv ;;
    scaled) set -- special make_reference_scaled.lmp scaled.thermo scaled_start.data scaled.yaml out/scaled-energy.csv ;;
    trimers) set -- trimers make_reference.lmp reference.thermo trimers_start.data trimers.yaml out/trimers-energy.csv ;;
    *) echo "lammps_thermo: unknown case '$c' (expected fene, molecular, cosine, improper, kg, scaled or trimers)" >&2; exit 2 ;;
  esac
  scene=tests/scenes/$1
  out=out/lammps-thermo/$c
  rm -rf "$out"
  mkdir -p "$out"
  cp "$scene"/* "$out/"
  if ((have_lmp)); then
    (cd "$out" && lmp -in "$2" -log none -echo none |
      python3 ../../../tests/scenes/thermo/extract_thermo.py >"$3")
    if ((write)); then
      cp "$out/$3" "$out/$4" "$scene/"
      echo "lammps_thermo: wrote $scene/$3 and $scene/$4"
    fi
  fi
  (cd "$out" && "$pdyn" run "$5" -q)
  python3 - "$c" "$out/$3" "$out/$6" "$out/$4" <<'PY' || status=1
import csv, sys
case, ref, ours, data = sys.argv[1:]
lammps = list(csv.DictReader(open(ref)))
pdyn = list(csv.DictReader(open(ours)))
assert [r["step"] for r in lammps] == [r["step"] for r in pdyn], "different steps"
# N kT / V, the ideal gas's pressure: the scale the pressure is compared at.
head = open(data).read().split("\n")
atoms = next(int(l.split()[0]) for l in head if l.endswith(" atoms"))
lo_hi = [l.split() for l in head if l.endswith("hi")]
volume = 1.0
for lo, hi, *_ in lo_hi:
    volume *= float(hi) - float(lo)
worst = {}
for theirs, mine in (("temp", "kT"), ("press", "pressure"), ("pe", "potential"),
                     ("ke", "kinetic"), ("etotal", "total")):
    w = 0.0
    for a, b in zip(lammps, pdyn):
        scale = abs(float(a[theirs]))
        if mine == "pressure":
            scale += atoms * float(a["temp"]) / volume
        w = max(w, abs(float(b[mine]) - float(a[theirs])) / scale)
    worst[mine] = w
print(f"{case}: {len(lammps)} thermo steps to {lammps[-1]['step']}; worst relative difference: " +
      ", ".join(f"{k} {v:.1e}" for k, v in worst.items()))
bad = [k for k, v in worst.items() if not v <= 1e-8]
if bad:
    sys.exit(f"lammps_thermo: {case}: {', '.join(bad)} differ from LAMMPS by more than 1e-8")
PY
done
exit $status
