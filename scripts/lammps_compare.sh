#!/usr/bin/env bash
# pdyn against LAMMPS on LAMMPS's Lennard-Jones melt (issue 13,
# docs/performance.md "Lennard-Jones melt"): the same 32,000 atoms from the
# same initial state, 100 velocity-Verlet steps of 0.005, thermo side by side
# and the time per atom-step, 1 thread / 1 MPI rank and 2 threads / 2 ranks.
# Then (issue 30) the temperature and pressure of `pdyn run`'s energy writer
# against LAMMPS's thermo (bench/thermo_vs_lammps.sh), and whole `pdyn run`
# processes of the documented scene against `lmp` (bench/lj_run_vs_lammps.sh:
# the default path's ratio).
#
#   bash scripts/lammps_compare.sh [BUILD_DIR]     (default: build)
#
# ROUNDS=N (default 5) repeats the four timed runs (LAMMPS 1 rank, pdyn 1
# thread, LAMMPS 2 ranks, pdyn 2 threads) in turn N times and prints each
# one's median ns/atom-step and the median of the per-round ratios: on a
# shared virtual machine single runs vary by 20%, and alternating lets both
# programs see the same slow and fast moments.
#
# Needs LAMMPS (Debian: apt-get install lammps, binary lmp) for the reference;
# it is never a build dependency. Writes out/lammps/.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
command -v lmp >/dev/null || { echo "lammps_compare: needs lmp (apt-get install lammps)" >&2; exit 2; }
# The benchmarks on (the test command's build leaves them out).
if [[ "$build" == build ]]; then
  cmake --preset default -DPDYN_BUILD_BENCH=ON >/dev/null
else
  cmake -S . -B "$build" -DPDYN_BUILD_BENCH=ON >/dev/null
fi
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

# Timing rounds: the loop time of each run, in ns per atom-step.
rounds=${ROUNDS:-5}
natoms=32000
: >"$out/times"
lammps_ns() { awk -v n=$natoms '/^Loop time/ {printf "%.1f", $4 * 1e9 / (n * 100)}' "$1"; }
for ((r = 1; r <= rounds; r++)); do
  (cd "$out" && lmp -in in.lj -log log.t1 -screen none)
  p1=$("$build/bin/pdyn_bench_lj_melt" "$out/init.dump" --threads 1 | awk '/^Loop time/ {print $(NF-1)}')
  l2=""
  if command -v mpirun >/dev/null; then
    (cd "$out" && mpirun --allow-run-as-root --oversubscribe -np 2 lmp -in in.lj -log log.t2 -screen none) &&
      l2=$(lammps_ns "$out/log.t2")
  fi
  p2=$("$build/bin/pdyn_bench_lj_melt" "$out/init.dump" --threads 2 | awk '/^Loop time/ {print $(NF-1)}')
  echo "$(lammps_ns "$out/log.t1") $p1 ${l2:-nan} $p2" | tee -a "$out/times"
done
echo "== medians of $rounds rounds, ns/atom-step (columns: LAMMPS 1 rank, pdyn 1 thread, LAMMPS 2 ranks, pdyn 2 threads)"
python3 - "$out/times" <<'PY'
import statistics, sys
rows = [list(map(float, l.split())) for l in open(sys.argv[1]) if l.strip()]
col = lambda k: [r[k] for r in rows]
med = lambda v: statistics.median(v)
print("LAMMPS 1 rank %.1f | pdyn 1 thread %.1f | LAMMPS 2 ranks %.1f | pdyn 2 threads %.1f" %
      tuple(med(col(k)) for k in range(4)))
print("pdyn / LAMMPS: 1 thread %.3f, 2 threads %.3f (median of per-round ratios)" %
      (med([r[1] / r[0] for r in rows]), med([r[3] / r[2] for r in rows])))
print("pdyn 2 threads vs 1: %.3fx; LAMMPS 2 ranks vs 1: %.3fx" %
      (med([r[1] / r[3] for r in rows]), med([r[0] / r[2] for r in rows])))
PY
uptime
echo "== temperature and pressure: pdyn run's energy writer against LAMMPS's thermo"
bash bench/thermo_vs_lammps.sh "$build"
echo "== the default path: whole pdyn run processes against lmp"
ROUNDS=$rounds bash bench/lj_run_vs_lammps.sh "$build"
