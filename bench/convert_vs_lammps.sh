#!/usr/bin/env bash
# LAMMPS input scripts as shipped, run by LAMMPS and, converted by `pdyn
# convert`, by pdyn (issue 44 item 6): prints the worst relative difference
# of every thermo column (LAMMPS's names, LAMMPS's normalization) over every
# thermo step, and fails unless each is within 1e-8. LAMMPS runs a copy of
# the script with `thermo_modify format float %.17g` added before its run,
# so that it prints every digit; nothing else changes. Without lmp it
# compares with the shipped references. With --write-reference it copies
# LAMMPS's thermo into tests/scenes/ (what tests/cli/convert_test.cpp
# compares with).
#
#   bash bench/convert_vs_lammps.sh [--build DIR] [--write-reference] [CASE ...]
#
#   cases: melt (in.melt of LAMMPS's melt example: fcc lattice, velocity create
#   loop geom, lj/cut, neigh_modify every 20 check no, 250 steps), npt (the
#   same melt under fix npt iso, in.npt), chain (in.chain of LAMMPS's
#   COUPLE/multiple example with -var t 1.0: 32,000 beads in FENE chains from
#   its data.chain, special_bonds fene, fix langevin, 500 steps); default all
#
# The chain's run is chaotic: a difference of rounding grows about tenfold
# every 50 steps, so that LAMMPS on 1 and on 2 ranks differ by 5e-7 at step
# 500 (the same script without fix langevin, whose numbers depend on the
# rank count). Its steps up to 300 are held to 1e-8; the later ones are
# printed.
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
((${#cases[@]})) || cases=(melt npt chain)
pdyn="$PWD/$build/bin/pdyn"
[[ -x "$pdyn" ]] || { echo "convert_vs_lammps: no $pdyn (build pdyn first)" >&2; exit 2; }
have_lmp=0
command -v lmp >/dev/null && have_lmp=1
((write == 0 || have_lmp)) || { echo "convert_vs_lammps: --write-reference needs lmp" >&2; exit 2; }
((have_lmp)) && echo "LAMMPS: $(lmp -h | grep -m1 -o "[0-9]\+ [A-Z][a-z]\+ [0-9]\{4\}.*")"
status=0
for c in "${cases[@]}"; do
  # folder, input script, LAMMPS's thermo, the last step held to 1e-8,
  # variables (lmp -var, pdyn convert --var)
  case "$c" in
    melt) set -- melt in.melt melt.thermo 250 ;;
    npt) set -- melt in.npt npt.thermo 200 ;;
    chain) set -- chain in.chain chain.thermo 300 t 1.0 ;;
    *) echo "convert_vs_lammps: unknown case '$c' (expected melt, npt or chain)" >&2; exit 2 ;;
  esac
  lmp_vars=()
  pdyn_vars=()
  if (($# > 4)); then
    lmp_vars=(-var "$5" "$6")
    pdyn_vars=(--var "$5" "$6")
  fi
  scene=tests/scenes/$1
  out=out/convert-vs-lammps/$c
  rm -rf "$out"
  mkdir -p "$out"
  cp "$scene"/* "$out/"
  if ((have_lmp)); then
    sed '0,/^run/s//thermo_modify format float %.17g\nrun/' "$scene/$2" >"$out/lammps.in"
    (cd "$out" && lmp "${lmp_vars[@]}" -in lammps.in -log none -echo none |
      python3 ../../../tests/scenes/thermo/extract_thermo.py --as-printed >"$3")
    if ((write)); then
      cp "$out/$3" "$scene/"
      echo "convert_vs_lammps: wrote $scene/$3"
    fi
  fi
  (cd "$out" && "$pdyn" convert "$2" "${pdyn_vars[@]}" -o scene.yaml && "$pdyn" run scene.yaml -q)
  python3 - "$c" "$out/$3" "$out/$2-thermo.csv" "$4" <<'PY' || status=1
import csv, sys
case, ref, ours, last = sys.argv[1:]
lammps = list(csv.DictReader(open(ref)))
pdyn = list(csv.DictReader(open(ours)))
assert list(lammps[0]) == list(pdyn[0]), f"columns {list(pdyn[0])}, LAMMPS's {list(lammps[0])}"
assert [r["Step"] for r in lammps] == [r["Step"] for r in pdyn], "different steps"
def differences(a, b):
    return {name: abs(float(a[name]) - float(b[name])) / abs(float(a[name]))
            if float(a[name]) != 0 else abs(float(b[name])) for name in list(a)[1:]}
held = [(a, b) for a, b in zip(lammps, pdyn) if int(a["Step"]) <= int(last)]
worst = {name: max(differences(a, b)[name] for a, b in held) for name in list(lammps[0])[1:]}
print(f"{case}: {len(held)} thermo steps to {held[-1][0]['Step']}; worst relative difference: " +
      ", ".join(f"{k} {v:.1e}" for k, v in worst.items()))
for a, b in zip(lammps[len(held):], pdyn[len(held):]):
    print(f"  step {a['Step']} (not held): " +
          ", ".join(f"{k} {v:.1e}" for k, v in differences(a, b).items()))
bad = [k for k, v in worst.items() if not v <= 1e-8]
if bad:
    sys.exit(f"convert_vs_lammps: {case}: {', '.join(bad)} differ from LAMMPS by more than 1e-8")
PY
done
exit $status
