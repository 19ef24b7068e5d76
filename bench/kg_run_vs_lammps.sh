#!/usr/bin/env bash
# `pdyn run` against `lmp` on the Kremer-Grest bead-spring melt (issue 44's
# speed target): 32,000 beads in 3200 FENE chains with WCA pairs and
# `special_bonds fene`, LAMMPS's own in.chain benchmark model, from one state that
# LAMMPS writes (bench/lammps/in.kg_make), 1000 velocity Verlet steps of
# 0.005, the neighbor list (skin 0.4) checked every step in both. It
# alternates LAMMPS 1 rank, pdyn 1 thread, LAMMPS 2 ranks, pdyn 2 threads,
# ROUNDS times (default 3), and prints each round's loop times and their
# ratios: LAMMPS's "Loop time", pdyn's "the steps X s" (both after set-up).
#
#   bash bench/kg_run_vs_lammps.sh [--shipped] [BUILD_DIR]   (default: build)
#
# --shipped times LAMMPS's own script instead: in.chain of its COUPLE/multiple
# example as Debian ships it (tests/scenes/chain, lmp -var t 1.0: the same
# model from its data.chain, fix langevin, neigh_modify every 1 delay 1,
# 500 steps of 0.012), converted by `pdyn convert in.chain --var t 1.0`.
#
# Needs Debian's lammps (lmp) and, for 2 ranks, mpirun; never a build
# dependency. Writes out/kg_run/. Run it on a quiet machine.
set -euo pipefail
cd "$(dirname "$0")/.."
shipped=0
if [[ ${1:-} == --shipped ]]; then
  shipped=1
  shift
fi
build=${1:-build}
rounds=${ROUNDS:-3}
command -v lmp >/dev/null || { echo "kg_run_vs_lammps: needs lmp (apt-get install lammps)" >&2; exit 2; }
pdyn="$PWD/$build/bin/pdyn"
[[ -x "$pdyn" ]] || { echo "kg_run_vs_lammps: no $pdyn (build pdyn first)" >&2; exit 2; }
out=out/kg_run
mkdir -p "$out"
input=in.kg scene=kg.yaml steps=1000 vars=()
if ((shipped)); then
  input=in.chain scene=chain.yaml steps=500 vars=(-var t 1.0)
  cp tests/scenes/chain/in.chain tests/scenes/chain/data.chain "$out/"
  (cd "$out" && "$pdyn" convert in.chain --var t 1.0 -o chain.yaml)
fi
cp bench/lammps/in.kg_make bench/lammps/in.kg tests/scenes/special/chain.mol "$out/"
[[ -f "$out/kg32k.data" ]] || (cd "$out" && lmp -in in.kg_make -log none -screen none)
cat > "$out/kg.yaml" <<SCENE
# The Kremer-Grest melt as a pdyn scene: written by bench/kg_run_vs_lammps.sh.
simulation:
  dt: 0.005
  steps: 1000
  solver: { type: verlet }
  box: { file: kg32k.data }
particles:
  - file: kg32k.data
special_bonds: fene
forces:
  - { type: lennard_jones, epsilon: 1, sigma: 1, cutoff: 1.122462048309373, shift: true, skin: 0.4 }
  - { type: fene, pairs: { file: kg32k.data }, k: 30, r0: 1.5, epsilon: 1, sigma: 1 }
SCENE
lammps_loop() {  # ranks -> the Loop time, s
  if [[ $1 == 1 ]]; then
    (cd "$out" && lmp "${vars[@]}" -in "$input" -log log.1 -screen none)
  else
    (cd "$out" && OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 \
      mpirun --oversubscribe -np "$1" lmp "${vars[@]}" -in "$input" -log "log.$1" -screen none)
  fi
  awk '/^Loop time of/{print $4}' "$out/log.$1"
}
pdyn_loop() {  # threads -> the steps' time, s
  local text
  text=$(cd "$out" && "$pdyn" run "$scene" --threads "$1")
  sed -n "s/^pdyn: $steps steps of .* (the steps \([0-9.e+-]*\) s).*/\1/p" <<<"$text"
}
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
printf '| round | LAMMPS 1 rank, s | pdyn 1 thread, s | ratio | LAMMPS 2 ranks, s | pdyn 2 threads, s | ratio |\n|---|---|---|---|---|---|---|\n'
for ((k = 1; k <= rounds; ++k)); do
  l1=$(lammps_loop 1); p1=$(pdyn_loop 1)
  if command -v mpirun >/dev/null; then l2=$(lammps_loop 2); else l2=nan; fi
  p2=$(pdyn_loop 2)
  printf '| %d | %s | %s | %s | %s | %s | %s |\n' "$k" "$l1" "$p1" \
    "$(awk -v p="$p1" -v l="$l1" 'BEGIN{printf "%.2f", p / l}')" "$l2" "$p2" \
    "$(awk -v p="$p2" -v l="$l2" 'BEGIN{printf "%.2f", (l == "nan") ? 0 : p / l}')"
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
