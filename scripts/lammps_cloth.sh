#!/usr/bin/env bash
# pdyn against LAMMPS on the hanging cloth with velocity Verlet (issue 17,
# item 5; docs/performance.md "The cloth beside LAMMPS"): the undamped cloth
# of tests/scenes/shared/cloth.yaml (springs, gravity, two pinned corners),
# the same initial bits in both programs. For each size it
#   1. checks that the two states after 200 steps agree to rounding
#      (bench/lammps/cloth.py compare: positions within 1e-12 of the cloth's
#      size, else it fails);
#   2. times ROUNDS rounds of LAMMPS 1 rank, pdyn 1 thread, LAMMPS 2 ranks,
#      pdyn 2 threads in turn, and prints each one's median ns per
#      particle-step and the median of the per-round ratios pdyn / LAMMPS.
# Both times are the programs' own loop times (LAMMPS's "Loop time", pdyn's
# "in X s" for the steps), without loading and output.
#
#   bash scripts/lammps_cloth.sh [BUILD_DIR]       (default: build)
#   SIZES="316 1000" ROUNDS=5 bash scripts/lammps_cloth.sh
#   ONE_CORE=1 ...                 only the 1-rank / 1-thread runs
#
# Needs LAMMPS (Debian: apt-get install lammps, binary lmp; mpirun for 2
# ranks) for the reference; it is never a build dependency. Writes out/lammps-cloth/.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
command -v lmp >/dev/null || { echo "lammps_cloth: needs lmp (apt-get install lammps)" >&2; exit 2; }
[[ -d "$build" ]] || cmake --preset default
cmake --build "$build" --target pdyn pdyn_plugins >/dev/null
out=out/lammps-cloth
mkdir -p "$out"
rounds=${ROUNDS:-5}
sizes=${SIZES:-"100 316 1000"}
rest_shear=$(/usr/bin/python3 -c 'import math; print(repr(0.01 * math.sqrt(2.0)))')

# pdyn's run of the cloth: n x n, `steps` steps, more --set overrides after.
pdyn_cloth() {
  local n=$1 steps=$2
  shift 2
  "$build/bin/pdyn" run tests/scenes/shared/cloth.yaml \
    --set "particles[0].grid.nx=$n" --set "particles[0].grid.ny=$n" \
    --set "particles[0].grid.springs.structural={ ks: 1000, kd: 0, rest: 0.01 }" \
    --set "particles[0].grid.springs.shear={ ks: 500, kd: 0, rest: $rest_shear }" \
    --set 'forces=[{ type: gravity, g: [0, 0, -9.81] }]' \
    --set 'simulation.solver={ type: verlet }' --set "simulation.steps=$steps" "$@"
}
lammps_cloth() {  # n steps ranks dump
  local n=$1 steps=$2 ranks=$3 dump=$4 run=(lmp)
  ((ranks > 1)) && run=(mpirun --allow-run-as-root --oversubscribe -np "$ranks" lmp)
  (cd "$out" && "${run[@]}" -in ../../bench/lammps/in.cloth -log "log.$n.$ranks" -screen none \
    -var data "cloth$n.data" -var steps "$steps" -var dump "$dump" \
    -var pin1 $(((n - 1) * n + 1)) -var pin2 $((n * n)))
}
ns_lammps() {  # log n steps
  awk -v p=$(($2 * $2 * $3)) '/^Loop time/ {printf "%.1f", $4 * 1e9 / p}' "$1"
}
ns_pdyn() {  # n steps threads
  pdyn_cloth "$1" "$2" --set output=null --threads "$3" 2>&1 |
    awk -v p=$(($1 * $1 * $2)) '/ steps of / {for (k = 1; k <= NF; ++k) if ($k == "in") t = $(k + 1)}
                                END {printf "%.1f", t * 1e9 / p}'
}

uptime
for n in $sizes; do
  # Steps so that each run takes a few seconds on one core (10^8
  # particle-steps), 100 to 1000.
  steps=$((100000000 / (n * n)))
  ((steps > 1000)) && steps=1000
  ((steps < 100)) && steps=100
  echo "== cloth $n x $n, $steps steps of 0.0002 s"
  pdyn_cloth "$n" 0 --set "output=[{ type: csv, path: $out/frame0-$n.csv }]" >/dev/null 2>&1
  /usr/bin/python3 bench/lammps/cloth.py data "$out/frame0-$n.csv" "$n" "$n" "$out/cloth$n.data"
  # Agreement after 200 steps: the undamped cloth in a 1 m/s gust is chaotic
  # enough that rounding differences grow ~1e4-fold per 1000 steps (at 100 x
  # 100: 4.7e-15 of its size after 300 steps, 2.5e-10 after 1000).
  pdyn_cloth "$n" 200 --threads 1 \
    --set "output=[{ type: csv, path: $out/pdyn-$n.csv, every: 200 }]" >/dev/null 2>&1
  lammps_cloth "$n" 200 1 "final-$n.dump"
  /usr/bin/python3 bench/lammps/cloth.py compare "$out/pdyn-$n.csv" "$out/final-$n.dump" "$n"

  : >"$out/times-$n"
  for ((r = 1; r <= rounds; r++)); do
    lammps_cloth "$n" "$steps" 1 /dev/null
    l1=$(ns_lammps "$out/log.$n.1" "$n" "$steps")
    p1=$(ns_pdyn "$n" "$steps" 1)
    l2=nan p2=nan
    if [[ ${ONE_CORE:-0} == 0 ]]; then
      if command -v mpirun >/dev/null && lammps_cloth "$n" "$steps" 2 /dev/null; then
        l2=$(ns_lammps "$out/log.$n.2" "$n" "$steps")
      fi
      p2=$(ns_pdyn "$n" "$steps" 2)
    fi
    echo "$l1 $p1 $l2 $p2" | tee -a "$out/times-$n"
  done
  /usr/bin/python3 - "$out/times-$n" "$n" <<'PY'
import math, statistics, sys
rows = [list(map(float, l.split())) for l in open(sys.argv[1]) if l.strip()]
col = lambda k: [r[k] for r in rows]
med = lambda xs: statistics.median(xs) if xs and not any(math.isnan(x) for x in xs) else float("nan")
n = sys.argv[2]
print(f"| cloth | LAMMPS 1 rank | pdyn 1 thread | pdyn / LAMMPS | LAMMPS 2 ranks | pdyn 2 threads | pdyn / LAMMPS |")
print(f"|---|---|---|---|---|---|---|")
r1 = med([r[1] / r[0] for r in rows])
r2 = med([r[3] / r[2] for r in rows])
print(f"| {n} x {n} | {med(col(0)):.1f} ns | {med(col(1)):.1f} ns | **{r1:.3f}** "
      f"({min(r[1] / r[0] for r in rows):.3f}-{max(r[1] / r[0] for r in rows):.3f}) | "
      f"{med(col(2)):.1f} ns | {med(col(3)):.1f} ns | **{r2:.3f}** "
      f"({min(r[3] / r[2] for r in rows):.3f}-{max(r[3] / r[2] for r in rows):.3f}) | "
      f"({len(rows)} rounds)")
PY
done
uptime
