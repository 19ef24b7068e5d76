#!/usr/bin/env bash
# pdyn quick start, for a fresh Debian 12 machine (run as root, or with sudo).
#
#   bash scripts/quickstart.sh demo   # install what is missing, build, run the demo
#   bash scripts/quickstart.sh test   # install what is missing, build, run the whole test
#                                     # suite as built for use (browser test included)
#
# CI (.ci/run) runs `test` and then scripts/ci-extra.sh: the suite under
# ASan + UBSan and a fuzz run of the scene loader, which take longer.
#
# Everything comes from Debian's packages; nothing is downloaded at build time.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

what="${1:-demo}"
case "$what" in demo|test) ;; *) echo "usage: $0 demo|test" >&2; exit 2 ;; esac

# What the demo builds (the program, the plugins, the Python module) needs:
packages=(
  g++ cmake ninja-build ccache     # toolchain (ccache: rebuilds are copies)
  libeigen3-dev                    # math and state vectors
  librandom123-dev                 # reproducible noise (pdyn/random.hpp), header-only
  libboost-dev                     # Boost.DLL (plugin loading), header-only here
  libyaml-cpp-dev                  # scenes
  libmuparser-dev pkg-config       # the field force's expressions
  libfmt-dev libcli11-dev          # messages, command line
  nlohmann-json3-dev               # pdyn plugins --json
  libcairo2-dev                    # pdyn render (PNG pictures)
  libhdf5-dev                      # the h5md writer (HDF5 C library)
  libopenblas-serial-dev           # implicit_euler's dense kernels (BLAS, LAPACK)
  libopenmpi-dev openmpi-bin       # one scene across MPI ranks (docs/parallel.md)
  pybind11-dev python3-dev python3-numpy   # `import pdyn` (python/)
)
# The tests, the benchmarks and CI's other builds need more; the demo does
# without them (Chromium and VTK are the largest).
[[ "$what" == test ]] && packages+=(
  libgtest-dev libgmock-dev        # tests (CMake finds them when it configures)
)
# CI's further builds bring their own: clang and its sanitizer runtimes for
# the fuzz run (scripts/fuzz.sh), Google Benchmark for bench/ and dpkg-dev
# with help2man for the Debian packages (scripts/ci-extra.sh, package.sh).
# pdyn serve's page takes three.js from the npm registry (viewer/package.json
# and its lock file); Node.js and npm come from Debian unless the machine
# already has them.
command -v npm >/dev/null 2>&1 || packages+=(nodejs npm)
# What only the tests run, never the build: installed while the build runs
# (the downloads overlap the compiler; about a minute of the test command on
# a fresh machine), and waited for before the first test.
test_packages=(
  python3-jsonschema python3-yaml  # the test validating scenes against `pdyn schema`
  clang-format-14                  # the formatting check (tests/format.cmake)
  chromium                         # the browser test drives Debian's Chromium headless
  python3-vtk9 python3-h5py        # the writers' read-back tests: VTK's and h5py's own readers
  # The Python module's tests and examples: pytest, dask.distributed for the
  # sweep across workers, matplotlib for the examples' plots.
  python3-pytest python3-distributed python3-matplotlib
)
source scripts/packages.sh
install_missing "${packages[@]}"
if [[ "$what" == test ]]; then
  mkdir -p build
  # sudo asks for a password here, if at all, not in the background.
  [[ $(id -u) -ne 0 ]] && sudo -v
  install_missing "${test_packages[@]}" >build/quickstart-test-packages.log 2>&1 &
  test_install=$!
  trap 'wait' EXIT  # a failed build still lets apt finish before the script ends
fi

# three.js (and, for the tests, playwright-core) into viewer/node_modules,
# exactly as the lock file pins them.
npm ci --prefix viewer --no-audit --no-fund --loglevel=error

source scripts/ccache.sh

if [[ "$what" == demo ]]; then
  # Only what the demo needs: the program, the shipped plugins, the Python
  # module; no tests or benchmarks, whose packages it did not install.
  cmake --preset default -DPDYN_BUILD_TESTS=OFF -DPDYN_BUILD_BENCH=OFF "${launcher[@]}"
  cmake --build --preset default --target pdyn pdyn_plugins pdyn_python
else
  # Tests on (a demo before may have turned them off); the browser test
  # fails, not skips, if it cannot run. The benchmarks are no test: the
  # scripts that run them (scripts/bench.sh, bench_targets.sh,
  # lammps_compare.sh) build them, and CI's scripts/ci-extra.sh compiles them.
  # Chromium is named by its path: it may still be being installed.
  cmake --preset default -DPDYN_BUILD_TESTS=ON -DPDYN_BUILD_BENCH=OFF -DPDYN_BROWSER_TEST=ON \
    -DPDYN_CHROMIUM=/usr/bin/chromium "${launcher[@]}"
  cmake --build --preset default
  if ! wait "$test_install"; then
    echo "quickstart: installing the tests' packages failed (build/quickstart-test-packages.log):" >&2
    cat build/quickstart-test-packages.log >&2
    exit 1
  fi
  cat build/quickstart-test-packages.log
fi

# `import pdyn` for Debian's python3 from anywhere: a .pth file in its
# site-packages naming this build's package folder (a development install;
# `cmake --install build` installs a copy instead).
sudo=""
[[ $(id -u) -ne 0 ]] && sudo="sudo"
site=$(/usr/bin/python3 -c "import sysconfig; print(sysconfig.get_path('purelib'))")
{ $sudo mkdir -p "$site" && echo "$PWD/build/python" | $sudo tee "$site/pdyn-build.pth" >/dev/null; } ||
  echo "quickstart: could not write $site/pdyn-build.pth: use PYTHONPATH=$PWD/build/python" >&2

if [[ "$what" == demo ]]; then
  ./build/bin/pdyn run configs/demo.yaml
else
  ctest --preset default
fi
