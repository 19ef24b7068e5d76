#!/usr/bin/env bash
# What CI runs after the README's test command (scripts/quickstart.sh test):
# the benchmarks' build, clang-tidy on the sources changed since its last
# whole clean run, the whole suite built with AddressSanitizer +
# UndefinedBehaviorSanitizer, then a bounded libFuzzer run of the scene
# loader, then the Debian packages built, installed, tried and removed
# (scripts/package_smoke.sh). Slower than the default suite, so users get a
# fast answer from the quick start and CI stays complete.
#
#   bash scripts/ci-extra.sh     (PDYN_FUZZ_SECONDS, default 120)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
# Google Benchmark for bench/, clang-tidy for the static analysis
# (scripts/fuzz.sh and package.sh install what they need themselves).
source scripts/packages.sh
install_missing libbenchmark-dev clang-tidy-14
source scripts/ccache.sh
# The benchmarks compile (the test command leaves them out): the build for use
# with them on, then as the test command left it.
cmake --preset default -DPDYN_BUILD_BENCH=ON "${launcher[@]}"
cmake --build --preset default
# clang-tidy on what changed since the last whole clean run (with the
# benchmarks in the compile database): scripts/tidy.sh, CONTRIBUTING.md.
# A clone without that commit (a shallow one) skips it, saying so.
tidy_clean=$(cat scripts/tidy-clean-at)
if git rev-parse --verify --quiet "$tidy_clean^{commit}" >/dev/null; then
  bash scripts/tidy.sh build --since "$tidy_clean"
else
  echo "ci-extra: clang-tidy skipped: this clone lacks $tidy_clean (a shallow clone)"
fi
cmake --preset default -DPDYN_BUILD_BENCH=OFF "${launcher[@]}"
cmake --preset asan -DPDYN_BROWSER_TEST=OFF "${launcher[@]}"  # the browser test runs on the build for use
cmake --build --preset asan
ctest --preset asan
bash scripts/fuzz.sh "${PDYN_FUZZ_SECONDS:-120}"
# The Debian packages: built, installed on this machine, used as a new user
# would (no build tree on any path) and removed again.
bash scripts/package.sh
bash scripts/package_smoke.sh
