#!/usr/bin/env bash
# Builds pdyn's Debian packages (cmake/PdynPackaging.cmake) in build-deb/:
# pdyn, pdyn-dev and python3-pdyn, installed under /usr. Needs what
# scripts/quickstart.sh installs, plus dpkg-dev (dpkg-shlibdeps).
#
#   bash scripts/package.sh          then: apt-get install ./build-deb/*.deb
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
source scripts/ccache.sh
dpkg-query -W -f='${Status}' dpkg-dev 2>/dev/null | grep -q "install ok installed" ||
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends dpkg-dev
[[ -d viewer/node_modules/three ]] || npm ci --prefix viewer --no-audit --no-fund --loglevel=error
cmake -S . -B build-deb -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_INSTALL_PREFIX=/usr \
  -DPDYN_BUILD_TESTS=OFF -DPDYN_BUILD_BENCH=OFF -DPDYN_WERROR=ON \
  -DPDYN_PYTHON_INSTALL_DIR=lib/python3/dist-packages "${launcher[@]}" >/dev/null  # where Debian's python3 looks
cmake --build build-deb
rm -f build-deb/*.deb
(cd build-deb && cpack -G DEB >/dev/null)
for deb in build-deb/*.deb; do
  printf '%s  %s\n' "$(du -h "$deb" | cut -f1)" "$deb"
done
