#!/usr/bin/env bash
# pdyn against LAMMPS on LAMMPS's Lennard-Jones melt (issue 13,
# docs/performance.md "Lennard-Jones melt"): the same 32,000 atoms from the
# same initial state, 100 velocity-Verlet steps of 0.005, thermo side by side
# and the time per atom-step, 1 thread / 1 MPI rank and 2 threads / 2 ranks.
#
#   bash scripts/lammps_compare.sh [BUILD_DIR]     (default: build)
#
# Needs LAMMPS (Debian: apt-get install lammps, binary lmp) for the reference;
# it is never a build dependency. Writes out/lammps/.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
command -v lmp >/dev/null || { echo "lammps_compare: needs lmp (apt-get install lammps)" >&2; exit 2; }
[[ -d "$build" ]] || cmake --preset default
cmake --build "$build" --target pdyn_bench_lj_melt
out=out/lammps
mkdir -p "$out"
cp bench/lammps/in.lj "$out/in.lj"
uptime
(cd "$out" && lmp -in in.lj -log log.1 -screen none)
if command -v mpirun >/dev/null; then
  (cd "$out" && mpirun --allow-run-as-root --oversubscribe -np 2 lmp -in in.lj -log log.2 -screen none) || true
fi
for log in "$out"/log.1 "$out"/log.2; do
  [[ -f "$log" ]] || continue
  echo "== LAMMPS ($(basename "$log"))"
  grep -A2 "^ *Step" "$log" | head -3
  grep -E "^Loop time|memory allocation|^Neighbor list builds" "$log"
done
for t in 1 2; do
  echo "== pdyn, $t thread(s)"
  "$build/bin/pdyn_bench_lj_melt" "$out/init.dump" --threads "$t"
done
uptime
