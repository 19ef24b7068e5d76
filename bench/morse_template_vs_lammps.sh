#!/usr/bin/env bash
# A pair law written from `pdyn new pair`'s template as a third party would
# write it (issue 42, item 7), against LAMMPS: Morse, U = D0 (e^-2a(r-r0) -
# 2 e^-a(r-r0)) within rc, on a 4,000-atom melt (fcc at reduced density
# 0.8442, T = 1.44, rc 2.5, skin 0.3, the neighbor list checked every step
# in both), 1000 steps of 0.005, through plain `pdyn run` and `lmp`.
#
# The plugin is made exactly as docs/pairs.md tells an author: the SDK
# installed into a prefix, `pdyn new pair morse`, the template's law and
# parameters replaced by Morse's (bench/morse_law.py: nothing else of the
# template changes, so its evaluate_beyond_cutoff line stays), `cmake` with
# the template's own CMakeLists, then `pdyn check morse`. The first step's
# potential energy must equal LAMMPS's to 1e-12 relative (the same physics),
# then the runs alternate, LAMMPS 1 rank and pdyn 1 thread, ROUNDS times
# (default 5), printing each round's loop times (pdyn's "the steps X s",
# LAMMPS's "Loop time") and the median ratio, and the whole processes' too.
#
#   bash bench/morse_template_vs_lammps.sh [BUILD_DIR]      (default: build)
#
# Needs Debian's lammps (lmp); never a build dependency. Writes
# out/morse_template/. Run it on a quiet machine.
set -euo pipefail
cd "$(dirname "$0")/.."
build=$(realpath "${1:-build}")
rounds=${ROUNDS:-5}
command -v lmp >/dev/null || { echo "morse_template_vs_lammps: needs lmp (apt-get install lammps)" >&2; exit 2; }
[[ -x "$build/bin/pdyn" ]] || { echo "morse_template_vs_lammps: no $build/bin/pdyn (build pdyn first)" >&2; exit 2; }
out=$PWD/out/morse_template
rm -rf "$out"
mkdir -p "$out"

# The SDK as an author has it, and the plugin made from the template.
cmake --install "$build" --prefix "$out/prefix" >/dev/null
pdyn="$out/prefix/bin/pdyn"
(cd "$out" && PDYN_PLUGIN_PATH= "$pdyn" new pair morse >/dev/null)
python3 bench/morse_law.py "$out/morse/morse.cpp"
cmake -S "$out/morse" -B "$out/morse/build" -DCMAKE_PREFIX_PATH="$out/prefix" >/dev/null
cmake --build "$out/morse/build" >/dev/null
"$pdyn" check morse --plugin-path "$out/morse/build" >"$out/check.txt" ||
  { cat "$out/check.txt" >&2; echo "morse_template_vs_lammps: pdyn check morse failed" >&2; exit 1; }
grep -E "^pair\.selecting_loop +pass" "$out/check.txt" ||
  { cat "$out/check.txt" >&2; echo "morse_template_vs_lammps: the template's law does not select" >&2; exit 1; }

# D0 = 1, a = 6, r0 = 2^(1/6): a well as deep and about as stiff as
# Lennard-Jones's, so the melt stays a liquid at T = 1.44.
cat >"$out/in.morse" <<'LMP'
units           lj
atom_style      atomic
lattice         fcc 0.8442
region          box block 0 10 0 10 0 10
create_box      1 box
create_atoms    1 box
mass            1 1.0
velocity        all create 1.44 87287 loop geom
pair_style      morse 2.5
pair_coeff      1 1 1.0 6.0 1.122462048309373
neighbor        0.3 bin
neigh_modify    delay 0 every 1 check yes
fix             1 all nve
write_dump      all custom init.dump id x y z vx vy vz modify sort id format float %.17g
thermo_style    custom step pe
thermo_modify   format float %.17g
thermo          1000
run             1000
LMP
(cd "$out" && lmp -in in.morse -log log.setup -screen none)
read -r lo hi < <(awk '/ITEM: BOX BOUNDS/{getline; print $1, $2; exit}' "$out/init.dump")
cat >"$out/melt.yaml" <<SCENE
# The Morse melt as a pdyn scene: written by bench/morse_template_vs_lammps.sh.
simulation:
  dt: 0.005
  steps: 1000
  solver: { type: verlet }
  box: { min: [$lo, $lo, $lo], max: [$hi, $hi, $hi], periodic: [true, true, true] }
particles:
  - { file: init.dump, masses: { 1: 1 } }
forces:
  - { type: morse, d0: 1, alpha: 6, r0: 1.122462048309373, cutoff: 2.5, skin: 0.3 }
output:
  - { type: energy, path: energy.csv, every: 1000 }
SCENE

# The same physics: the first potential energy per atom, pdyn's against LAMMPS's.
(cd "$out" && "$pdyn" run melt.yaml --plugin-path morse/build --steps 0 --quiet)
lammps_pe=$(awk '/^ *Step/{getline; print $2; exit}' "$out/log.setup")
pdyn_pe=$(python3 -c "
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print(repr(float(rows[0]['potential']) / 4000))" "$out/energy.csv")
python3 -c "
import sys
p, l = float(sys.argv[1]), float(sys.argv[2])
d = abs(p - l) / abs(l)
print(f'potential energy per atom at step 0: pdyn {p!r}, LAMMPS {l!r}, relative difference {d:.2e}')
sys.exit(0 if d <= 1e-12 else 1)" "$pdyn_pe" "$lammps_pe" ||
  { echo "morse_template_vs_lammps: pdyn and LAMMPS disagree on the Morse energy" >&2; exit 1; }

lammps_loop() {
  local t0 t1
  t0=$(date +%s.%N)
  (cd "$out" && lmp -in in.morse -log log.run -screen none)
  t1=$(date +%s.%N)
  echo "$t0 $t1" >"$out/lammps.wall"
  awk '/^Loop time of/{print $4}' "$out/log.run"
}
pdyn_loop() {
  local text t0 t1
  t0=$(date +%s.%N)
  text=$(cd "$out" && "$pdyn" run melt.yaml --plugin-path morse/build --threads 1)
  t1=$(date +%s.%N)
  echo "$t0 $t1" >"$out/pdyn.wall"
  sed -n 's/^pdyn: 1000 steps of .* (the steps \([0-9.e+-]*\) s).*/\1/p' <<<"$text"
}
median() { printf '%s\n' "$@" | sort -g | awk '{v[NR]=$1} END{print (NR % 2) ? v[(NR+1)/2] : (v[NR/2] + v[NR/2+1]) / 2}'; }
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
declare -a loop whole
printf '| round | LAMMPS 1 rank, s | pdyn 1 thread, s | ratio | whole processes, ratio |\n|---|---|---|---|---|\n'
for ((k = 1; k <= rounds; ++k)); do
  # Alternate which goes first, so that neither always meets a warm cache.
  if ((k % 2)); then l=$(lammps_loop); p=$(pdyn_loop); else p=$(pdyn_loop); l=$(lammps_loop); fi
  a=$(awk -v p="$p" -v l="$l" 'BEGIN{printf "%.3f", p / l}')
  w=$(awk -v p="$(cat "$out/pdyn.wall")" -v l="$(cat "$out/lammps.wall")" \
    'BEGIN{split(p, a, " "); split(l, b, " "); printf "%.3f", (a[2] - a[1]) / (b[2] - b[1])}')
  loop+=("$a")
  whole+=("$w")
  printf '| %d | %s | %s | %s | %s |\n' "$k" "$l" "$p" "$a" "$w"
done
echo "median pdyn / LAMMPS, Morse from the template, 1 thread / 1 rank: loop $(median "${loop[@]}") (target <= 1.0), whole process $(median "${whole[@]}")"
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
