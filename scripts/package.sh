#!/usr/bin/env bash
# Builds pdyn's Debian packages (cmake/PdynPackaging.cmake) in build-deb/:
# pdyn, pdyn-dev and python3-pdyn, installed under /usr. Needs what
# scripts/quickstart.sh installs, plus dpkg-dev and help2man, which it
# installs if missing (scripts/packages.sh). The compiler flags are the default preset's, so
# ccache serves the objects of an earlier build of the same sources.
#
#   bash scripts/package.sh          then: apt-get install ./build-deb/*.deb
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
source scripts/ccache.sh
# dpkg-dev: dpkg-shlibdeps, for the packages' dependencies; help2man: the
# manual page.
source scripts/packages.sh
install_missing dpkg-dev help2man
[[ -d viewer/node_modules/three ]] || npm ci --prefix viewer --no-audit --no-fund --loglevel=error
# The changelog entry's date: the commit's, so that two builds of one commit agree.
if [[ -z "${SOURCE_DATE_EPOCH:-}" ]] && git rev-parse --git-dir >/dev/null 2>&1; then
  SOURCE_DATE_EPOCH=$(git log -1 --format=%ct)
  export SOURCE_DATE_EPOCH
fi
# Linked with -z now (all symbols bound at load, then read-only, as Debian's
# hardening flags link): a link option, so the compiled objects stay cached.
now="-Wl,-z,relro,-z,now"
cmake -S . -B build-deb -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_INSTALL_PREFIX=/usr \
  -DPDYN_BUILD_TESTS=OFF -DPDYN_BUILD_BENCH=OFF -DPDYN_WERROR=ON -DPDYN_MANPAGE=ON \
  -DCMAKE_EXE_LINKER_FLAGS="$now" -DCMAKE_SHARED_LINKER_FLAGS="$now" -DCMAKE_MODULE_LINKER_FLAGS="$now" \
  -DPDYN_PYTHON_INSTALL_DIR=lib/python3/dist-packages "${launcher[@]}" >/dev/null  # where Debian's python3 looks
cmake --build build-deb
rm -f build-deb/*.deb
# cpack's log names every plugin as a shared object without a soname (true:
# they are dlopen'ed modules, not libraries to link): shown only on failure.
(cd build-deb && cpack -G DEB >cpack.log 2>&1) || { cat build-deb/cpack.log >&2; exit 1; }
for deb in build-deb/*.deb; do
  printf '%s  %s\n' "$(du -h "$deb" | cut -f1)" "$deb"
done
