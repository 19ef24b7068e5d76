#!/usr/bin/env bash
# Installs the Debian packages of scripts/package.sh on this machine, uses
# them as a new user would with no build tree on any path, and removes them
# (also when a step fails). Run by CI (scripts/ci-extra.sh); needs root.
#
#   bash scripts/package_smoke.sh [DEB_DIR]      (default build-deb)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
debs=("${1:-build-deb}"/*.deb)
work=$(mktemp -d)
# quickstart.sh points Debian's python3 at the build tree (a .pth file in
# site-packages): set it aside so that `import pdyn` finds the package.
site=$(/usr/bin/python3 -c "import sysconfig; print(sysconfig.get_path('purelib'))")
moved=""
cleanup() {
  DEBIAN_FRONTEND=noninteractive apt-get remove -y -qq pdyn pdyn-dev python3-pdyn >/dev/null 2>&1 || true
  [[ -n "$moved" ]] && mv "$moved" "$site/pdyn-build.pth"
  rm -rf "$work"
}
trap cleanup EXIT
if [[ -f "$site/pdyn-build.pth" ]]; then
  moved="$work/pdyn-build.pth"
  mv "$site/pdyn-build.pth" "$moved"
fi
export PATH=/usr/sbin:/usr/bin:/sbin:/bin
unset PDYN_PLUGIN_PATH PYTHONPATH

start=$(date +%s.%N)
DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${debs[@]/#/./}" >/dev/null
installed=$(date +%s.%N)
[[ "$(command -v pdyn)" == /usr/bin/pdyn ]] || { echo "package_smoke: pdyn is not /usr/bin/pdyn" >&2; exit 1; }
pdyn --version
(cd "$work" && pdyn run /usr/share/pdyn/configs/demo.yaml >/dev/null && test -s out/demo.csv)
ran=$(date +%s.%N)

# A plugin from nothing against the installed SDK.
(cd "$work" && pdyn new force wind >/dev/null &&
  cmake -S wind -B wind/build -G Ninja >/dev/null && cmake --build wind/build >/dev/null &&
  pdyn check wind --plugin-path wind/build >/dev/null)
# The Python module, installed for Debian's python3.
(cd "$work" && /usr/bin/python3 - <<'PY'
import pdyn
assert pdyn.__file__.startswith("/usr/lib/python3/dist-packages/"), pdyn.__file__
sim = pdyn.load("/usr/share/pdyn/configs/demo.yaml")
assert sim.step(10) == 10 and sim.t > 0
print("python3-pdyn", pdyn.__version__, "from", pdyn.__file__)
PY
)
awk -v a="$start" -v b="$installed" -v c="$ran" \
  'BEGIN { printf "package_smoke: install %.1f s, install to the demo'"'"'s end %.1f s\n", b - a, c - a }'
for deb in "${debs[@]}"; do printf 'package_smoke: %s %s\n' "$(du -h "$deb" | cut -f1)" "$(basename "$deb")"; done
cleanup
trap - EXIT
[[ ! -e /usr/bin/pdyn ]] || { echo "package_smoke: /usr/bin/pdyn is still there after removal" >&2; exit 1; }
echo "package_smoke: installed, used (demo, pdyn new + cmake + pdyn check, import pdyn) and removed"
