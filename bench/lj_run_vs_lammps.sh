#!/usr/bin/env bash
# `pdyn run` against `lmp` on LAMMPS's Lennard-Jones melt, whole processes
# (issue 30, item 1): the documented scene, with no tuning (`solver: { type:
# verlet }`, no reuse_forces), from LAMMPS's exact initial state (32,000
# atoms, fcc at reduced density 0.8442, T = 1.44, cutoff 2.5, skin 0.3, the
# neighbor list checked every step in both), 100 steps of 0.005. It
# alternates the runs, LAMMPS 1 rank, pdyn 1 thread, LAMMPS 2 ranks, pdyn 2
# threads, ROUNDS times (default 5), and prints each round's loop times and
# the median ratios: pdyn's is the time `pdyn run` reports for its steps
# ("the steps X s": after the set-up force evaluation and first frames, as
# LAMMPS's "Loop time" is after its setup), LAMMPS's the log's "Loop time".
# Each round also times both whole processes (load, set-up, output and
# exit included), and their median ratio is printed too.
#
#   bash bench/lj_run_vs_lammps.sh [BUILD_DIR]      (default: build)
#   MPI=1 bash bench/lj_run_vs_lammps.sh            (also pdyn on 2 MPI ranks, 1 thread each,
#                                                    and on 1 rank under mpirun: issue 43;
#                                                    docs/parallel.md)
#
# Needs Debian's lammps (lmp) and, for 2 ranks, mpirun; never a build
# dependency. Writes out/lj_run/. Run it on a quiet machine.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
rounds=${ROUNDS:-5}
command -v lmp >/dev/null || { echo "lj_run_vs_lammps: needs lmp (apt-get install lammps)" >&2; exit 2; }
pdyn="$build/bin/pdyn"
[[ -x "$pdyn" ]] || { echo "lj_run_vs_lammps: no $pdyn (build pdyn first)" >&2; exit 2; }
out=out/lj_run
mkdir -p "$out"
cp bench/lammps/in.lj "$out/in.lj"
(cd "$out" && lmp -in in.lj -log log.setup -screen none)
# The box from the dump's header: three lines "lo hi" after ITEM: BOX BOUNDS.
read -r lo hi < <(awk '/ITEM: BOX BOUNDS/{getline; print $1, $2; exit}' "$out/init.dump")
cat > "$out/melt.yaml" <<SCENE
# LAMMPS's LJ melt as a pdyn scene: written by bench/lj_run_vs_lammps.sh.
simulation:
  dt: 0.005
  steps: 100
  solver: { type: verlet }
  box: { min: [$lo, $lo, $lo], max: [$hi, $hi, $hi], periodic: [true, true, true] }
particles:
  - { file: init.dump, masses: { 1: 1 } }
forces:
  - { type: lennard_jones, epsilon: 1, sigma: 1, cutoff: 2.5, skin: 0.3 }
SCENE
lammps_loop() {  # ranks -> the log's Loop time, s
  local log="log.$1" t0 t1
  t0=$(date +%s.%N)
  if [[ $1 == 1 ]]; then
    (cd "$out" && lmp -in in.lj -log "$log" -screen none)
  else
    (cd "$out" && mpirun --allow-run-as-root --oversubscribe -np "$1" lmp -in in.lj -log "$log" -screen none)
  fi
  t1=$(date +%s.%N)
  echo "$t0 $t1" >"$out/lammps.wall"
  awk '/^Loop time of/{print $4}' "$out/$log"
}
pdyn_loop() {  # threads [ranks] -> the steps' time pdyn run reports, s; checks one evaluation per step
  local text t0 t1 launch=()
  [[ -n ${2:-} ]] && launch=(env OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun --oversubscribe -np "$2")
  t0=$(date +%s.%N)
  text=$(cd "$out" && "${launch[@]}" "../../$pdyn" run melt.yaml --threads "$1")
  t1=$(date +%s.%N)
  echo "$t0 $t1" >"$out/pdyn.wall"
  grep -q "pdyn: 101 force evaluations" <<<"$text" ||
    { echo "lj_run_vs_lammps: expected 101 force evaluations:" >&2; echo "$text" >&2; exit 1; }
  sed -n 's/^pdyn: 100 steps of .* (the steps \([0-9.e+-]*\) s).*/\1/p' <<<"$text"
}
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
declare -a r1 r2 r3 s3 o1 w1 w2
printf '| round | LAMMPS 1 rank, s | pdyn 1 thread, s | ratio | LAMMPS 2 ranks, s | pdyn 2 threads, s | ratio |\n|---|---|---|---|---|---|---|\n'
for ((k = 1; k <= rounds; ++k)); do
  wall_ratio() { awk -v p="$(cat "$out/pdyn.wall")" -v l="$(cat "$out/lammps.wall")" \
    'BEGIN{split(p, a, " "); split(l, b, " "); printf "%.3f", (a[2] - a[1]) / (b[2] - b[1])}'; }
  l1=$(lammps_loop 1); p1=$(pdyn_loop 1); w1+=("$(wall_ratio)")
  if command -v mpirun >/dev/null; then l2=$(lammps_loop 2); else l2=nan; fi
  p2=$(pdyn_loop 2); w2+=("$(wall_ratio)")
  a=$(awk -v p="$p1" -v l="$l1" 'BEGIN{printf "%.3f", p / l}')
  b=$(awk -v p="$p2" -v l="$l2" 'BEGIN{printf "%.3f", (l == "nan") ? 0 : p / l}')
  r1+=("$a"); r2+=("$b")
  printf '| %d | %s | %s | %s | %s | %s | %s |\n' "$k" "$l1" "$p1" "$a" "$l2" "$p2" "$b"
  if [[ ${MPI:-0} == 1 ]]; then
    m2=$(pdyn_loop 1 2)
    c=$(awk -v p="$m2" -v l="$l2" 'BEGIN{printf "%.3f", p / l}')
    s=$(awk -v p="$p1" -v m="$m2" 'BEGIN{printf "%.3f", p / m}')
    m1=$(pdyn_loop 1 1)
    o=$(awk -v p="$p1" -v m="$m1" 'BEGIN{printf "%.3f", m / p}')
    r3+=("$c"); s3+=("$s"); o1+=("$o")
    printf '|   | pdyn 2 MPI ranks, 1 thread each: %s s | / LAMMPS 2 ranks %s | faster than pdyn 1 thread %sx | mpirun -np 1: %s s | / pdyn 1 thread %s | |\n' "$m2" "$c" "$s" "$m1" "$o"
  fi
done
median() { printf '%s\n' "$@" | sort -g | awk '{v[NR]=$1} END{print (NR % 2) ? v[(NR+1)/2] : (v[NR/2] + v[NR/2+1]) / 2}'; }
echo "median pdyn / LAMMPS: 1 thread / 1 rank $(median "${r1[@]}") (target <= 1.0), 2 threads / 2 ranks $(median "${r2[@]}") (target <= 1.0)"
echo "median whole-process wall time, pdyn run / lmp: 1 thread / 1 rank $(median "${w1[@]}"), 2 threads / 2 ranks $(median "${w2[@]}")"
[[ ${MPI:-0} == 1 ]] &&
  echo "median pdyn 2 MPI ranks: / LAMMPS 2 ranks $(median "${r3[@]}") (target <= 1.0), faster than 1 rank $(median "${s3[@]}")x (target >= 1.6); 1 rank under mpirun / plain $(median "${o1[@]}") (target <= 1.03)"
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
