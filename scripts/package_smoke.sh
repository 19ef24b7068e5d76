#!/usr/bin/env bash
# Installs the Debian packages of scripts/package.sh on this machine, uses
# them as a new user would with no build tree on any path, and removes them
# (apt-get purge, so that dpkg keeps no record of them either), also when a
# step fails or the script is interrupted. Run by CI (scripts/ci-extra.sh);
# needs root. pdyn packages installed before are removed too.
#
#   bash scripts/package_smoke.sh [DEB_DIR]      (default build-deb)
#
# Checks: `pdyn --version`; the demo from /usr/share/pdyn/configs writes its
# outputs; the hanging cloth steps with implicit_euler (OpenBLAS, loaded
# at its first factorisation, from the Depends); every plugin in the
# package is found from the installed layout;
# `pdyn serve` serves the page and its three.js from /usr/share/pdyn/viewer;
# `pdyn new force wind` builds against pdyn-dev with a plain
# `cmake -S wind -B wind/build` and passes `pdyn check`; `import pdyn` comes
# from /usr/lib/python3/dist-packages and ends the demo on the program's
# last frame, bit for bit; no installed file names the build tree and every
# RUNPATH is relative to $ORIGIN; after removal nothing is left in /usr.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
repo=$PWD
debs=()
for deb in "${1:-build-deb}"/*.deb; do debs+=("$(realpath "$deb")"); done
((${#debs[@]} == 3)) || { echo "package_smoke: expected 3 packages in ${1:-build-deb}, found ${#debs[@]}" >&2; exit 1; }
packages=(pdyn pdyn-dev python3-pdyn)
fail() { echo "package_smoke: $*" >&2; exit 1; }

# quickstart.sh points Debian's python3 at the build tree (pdyn-build.pth in
# /usr/local/lib/python3.X/dist-packages), which would shadow the installed
# module: it is renamed (python3 reads only *.pth) for the test and renamed
# back on exit. A run killed before it could rename it back leaves the
# .smoke name, which the next run restores first.
site=$(/usr/bin/python3 -c "import sysconfig; print(sysconfig.get_path('purelib'))")
pth="$site/pdyn-build.pth"
[[ -f "$pth.smoke" && ! -e "$pth" ]] && mv "$pth.smoke" "$pth"
work=$(mktemp -d)
server=""
cleanup() {
  [[ -n "$server" ]] && kill "$server" 2>/dev/null && wait "$server" 2>/dev/null
  DEBIAN_FRONTEND=noninteractive apt-get purge -y -qq "${packages[@]}" >/dev/null 2>&1 || true
  [[ -f "$pth.smoke" ]] && mv "$pth.smoke" "$pth"
  rm -rf "$work"
}
trap cleanup EXIT
trap 'exit 130' INT TERM HUP
[[ -f "$pth" ]] && mv "$pth" "$pth.smoke"
export PATH=/usr/sbin:/usr/bin:/sbin:/bin
unset PDYN_PLUGIN_PATH PYTHONPATH PYTHONHOME PYTHONUSERBASE

start=$(date +%s.%N)
DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${debs[@]}" >/dev/null
installed=$(date +%s.%N)
[[ "$(command -v pdyn)" == /usr/bin/pdyn ]] || fail "pdyn is $(command -v pdyn), not /usr/bin/pdyn"
pdyn --version
mkdir "$work/demo"
(cd "$work/demo" && pdyn run /usr/share/pdyn/configs/demo.yaml --quiet)
ran=$(date +%s.%N)
# implicit_euler's direct solve loads OpenBLAS itself (dlopen, not linked):
# the package's Depends must have brought it.
mkdir "$work/implicit"
(cd "$work/implicit" && pdyn run /usr/share/pdyn/configs/hanging_cloth.yaml --quiet --steps 3 \
  --set simulation.solver.type=implicit_euler --set simulation.dt=0.01) ||
  fail "the hanging cloth did not run with implicit_euler (its BLAS)"
# 2500 steps, a frame every 40 and the last: 64 frames of 900 particles.
rows=$(wc -l <"$work/demo/out/demo.csv")
((rows == 64 * 900 + 1)) || fail "out/demo.csv has $rows lines (expected $((64 * 900 + 1)))"
energy=$(wc -l <"$work/demo/out/demo-energy.csv")
((energy == 64 + 1)) || fail "out/demo-energy.csv has $energy lines (expected 65)"

# The registry finds every shipped plugin from /usr/bin/pdyn alone
# (PDYN_BIN_TO_PLUGINS, PDYN_LIB_TO_PLUGINS), with no fault.
shipped=$(dpkg -L pdyn | grep -c '^/usr/lib/x86_64-linux-gnu/pdyn/plugins/pdyn_.*\.so$')
pdyn plugins --json | /usr/bin/python3 -c "
import json, sys
d = json.load(sys.stdin)
libs = {p['library'] for p in d['plugins']}
assert len(d['plugins']) == $shipped and not d['faults'], (len(d['plugins']), d['faults'])
assert all(l.startswith('/usr/lib/x86_64-linux-gnu/pdyn/plugins/') for l in libs), libs"

# The viewer: the page and the three.js it imports, from the installed tree.
pdyn serve /usr/share/pdyn/configs/demo.yaml --port 0 >"$work/serve.log" 2>&1 &
server=$!
for _ in $(seq 100); do grep -q "^pdyn serve: http" "$work/serve.log" && break; sleep 0.1; done
url=$(sed -n 's/^pdyn serve: \(http:[^ ]*\) .*/\1/p' "$work/serve.log")
[[ -n "$url" ]] || fail "pdyn serve printed no address: $(cat "$work/serve.log")"
/usr/bin/python3 -c "
import sys, urllib.request
for path, size in (('', 1000), ('vendor/three/build/three.module.js', 100000)):
    body = urllib.request.urlopen(sys.argv[1] + path, timeout=10).read()
    assert len(body) > size, (path, len(body))" "$url"
kill "$server" && wait "$server" 2>/dev/null || true
server=""

# A plugin from nothing against the installed SDK (pdyn-dev), with CMake's
# default generator as a user would type it.
(cd "$work" && pdyn new force wind >/dev/null &&
  cmake -S wind -B wind/build >/dev/null && cmake --build wind/build >/dev/null &&
  pdyn check wind --plugin-path wind/build >/dev/null) || fail "pdyn new + cmake + pdyn check failed"

# The Python module, installed for Debian's python3, runs the demo to the
# state the program wrote last (CSV with 17 significant digits: exact).
(cd "$work" && /usr/bin/python3 - "$work/demo/out/demo.csv" <<'PY'
import sys
import numpy as np
import pdyn
assert pdyn.__file__ == "/usr/lib/python3/dist-packages/pdyn/__init__.py", pdyn.__file__
sim = pdyn.load("/usr/share/pdyn/configs/demo.yaml")
sim.step(10)
assert sim.steps == 10 and sim.t == 10 * sim.dt, (sim.steps, sim.t)
sim.step(round(sim.end_time / sim.dt) - 10)
last = np.loadtxt(sys.argv[1], delimiter=",", skiprows=1)[-sim.n:]
assert last[0, 0] == sim.t == sim.end_time == 2.5, (last[0, 0], sim.t, sim.end_time)
assert np.array_equal(last[:, 2:5], sim.x) and np.array_equal(last[:, 5:8], sim.v)
print("python3-pdyn", pdyn.__version__, "from", pdyn.__file__, "ends the demo on pdyn run's last frame")
PY
) || fail "import pdyn from /usr/lib/python3/dist-packages failed"

# Two installations side by side (issue 42): where quickstart.sh pointed
# Debian's python3 at a build tree, that tree's `import pdyn` and its pdyn
# program still run the demo with the packages installed, each with its own
# plugins and no fault (the registry no longer searches the folder beside an
# embedding interpreter, /usr/bin/python3's ../lib, the packages' own).
if [[ -f "$pth.smoke" ]]; then
  mv "$pth.smoke" "$pth"
  tree=$(dirname "$(cat "$pth")")  # BUILD/python -> BUILD
  mkdir "$work/side"
  (cd "$work/side" && "$tree/bin/pdyn" run /usr/share/pdyn/configs/demo.yaml --quiet) ||
    fail "the build tree's pdyn did not run the demo beside the packages"
  "$tree/bin/pdyn" plugins --json | /usr/bin/python3 -c "
import json, sys
d = json.load(sys.stdin)
assert not d['faults'] and not d['shadowed'], (d['faults'], d['shadowed'])
assert all(p['library'].startswith(sys.argv[1]) for p in d['plugins'])" "$tree/" ||
    fail "the build tree's pdyn did not take its own plugins"
  (cd "$work/side" && /usr/bin/python3 - "$tree" "$work/side/out/demo.csv" <<'PY'
import sys
import numpy as np
import pdyn
tree = sys.argv[1]
assert pdyn.__file__.startswith(tree + "/"), pdyn.__file__
libs = {p["library"] for p in pdyn.plugins()}
assert all(l.startswith(tree + "/") for l in libs), libs
sim = pdyn.load("/usr/share/pdyn/configs/demo.yaml")
sim.step(round(sim.end_time / sim.dt))
last = np.loadtxt(sys.argv[2], delimiter=",", skiprows=1)[-sim.n:]
assert np.array_equal(last[:, 2:5], sim.x) and np.array_equal(last[:, 5:8], sim.v)
print("build tree's import pdyn beside python3-pdyn: its own", len(libs), "plugins, the demo to its end")
PY
  ) || fail "the build tree's import pdyn failed beside the packages"
  mv "$pth" "$pth.smoke"
fi

# Nothing installed names the build tree; every RUNPATH is relative.
files=$(dpkg -L "${packages[@]}" | while read -r f; do if [[ -f "$f" && ! -L "$f" ]]; then echo "$f"; fi; done)
! grep -l -F "$repo" $files || fail "installed files name the build tree $repo"
for f in $files; do
  [[ "$(head -c 4 "$f" | od -An -c | tr -d ' ')" == 177ELF ]] || continue
  runpath=$(readelf -d "$f" | sed -n 's/.*(R.*PATH).*\[\(.*\)\]/\1/p')
  [[ -z "$runpath" || "$runpath" == '$ORIGIN'* ]] || fail "$f has RUNPATH $runpath"
done

awk -v a="$start" -v b="$installed" -v c="$ran" \
  'BEGIN { printf "package_smoke: install %.1f s, install to the demo'"'"'s end %.1f s\n", b - a, c - a }'
for deb in "${debs[@]}"; do printf 'package_smoke: %s %s\n' "$(du -h "$deb" | cut -f1)" "$(basename "$deb")"; done
cleanup
trap - EXIT
for gone in /usr/bin/pdyn /usr/share/pdyn /usr/lib/x86_64-linux-gnu/pdyn /usr/lib/python3/dist-packages/pdyn \
  /usr/lib/x86_64-linux-gnu/cmake/pdyn /usr/include/pdyn; do
  [[ ! -e "$gone" ]] || fail "$gone is still there after apt-get purge"
done
! dpkg-query -W "${packages[@]}" >/dev/null 2>&1 || fail "dpkg still lists a pdyn package"
echo "package_smoke: installed, used (demo, plugins, serve, pdyn new + cmake + pdyn check, import pdyn) and removed"
