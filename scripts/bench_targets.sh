#!/usr/bin/env bash
# Issue 17's targets in one table (docs/performance.md): builds what the
# benchmarks need, then runs bench/targets.py, which measures every target
# side by side and prints one row per target with "met" or by how much it is
# missed. About 25 minutes on the 2-core machine; run it on a quiet machine.
# A whole run (PARTS not set) also rewrites docs/performance.md's generated
# block (the current results); a run of some PARTS only prints its rows.
#
#   bash scripts/bench_targets.sh [BUILD_DIR]
#   ROUNDS=3 STIFF="30 100" bash scripts/bench_targets.sh
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
# The benchmarks on (the test command's build leaves them out).
if [[ "$build" == build ]]; then
  cmake --preset default -DPDYN_BUILD_BENCH=ON >/dev/null
else
  cmake -S . -B "$build" -DPDYN_BUILD_BENCH=ON >/dev/null
fi
cmake --build "$build" --target pdyn pdyn_plugins pdyn_bench_cloth pdyn_bench_stiff_cloth pdyn_bench_triad -j"$(nproc)"
if [[ -z "${PARTS:-}" ]]; then
  exec /usr/bin/python3 bench/targets.py "$build" --markdown docs/performance.md
fi
exec /usr/bin/python3 bench/targets.py "$build"
