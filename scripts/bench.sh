#!/usr/bin/env bash
# Hanging-cloth benchmark (issue 4, docs/performance.md), one command:
#
#   bash scripts/bench.sh [BUILD_DIR]       (default: build, the default preset)
#
# Builds pdyn_bench_cloth and the plugins, then writes into out/bench/:
#   cloth.json      Google Benchmark JSON: ns per particle-step of pdyn (runner
#                   and bare solver step, 1 and 2 threads), the hand-fused
#                   reference and Boost.Odeint at 100^2, 316^2 and 1000^2
#                   particles, after the same-state check (exit 1 if it fails)
#   memory.jsonl    peak resident bytes per particle, 1000 x 1000, each
#                   variant in its own process
#   load.jsonl      scene load times
#   performance.png the plot (scripts/plot_performance.py, needs matplotlib
#                   or gnuplot; skipped with a note if neither is installed)
# and prints the Markdown table of docs/performance.md's "Wall time" (its
# dated figures: docs/log/performance.md).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
# The benchmarks on (the test command's build leaves them out).
if [[ "$build" == build ]]; then
  cmake --preset default -DPDYN_BUILD_BENCH=ON >/dev/null
else
  cmake -S . -B "$build" -DPDYN_BUILD_BENCH=ON >/dev/null
fi
cmake --build "$build" --target pdyn_bench_cloth pdyn_plugins -j"$(nproc)"
mkdir -p out/bench
bin="$build/bin/pdyn_bench_cloth"
"$bin" --benchmark_out=out/bench/cloth.json --benchmark_out_format=json \
       --benchmark_repetitions="${PDYN_BENCH_REPETITIONS:-3}" \
       --benchmark_report_aggregates_only=true
: > out/bench/memory.jsonl
for v in fused "pdyn 1000 1" "pdyn 1000 2"; do
  set -- $v
  "$bin" --memory "$1" 1000 "${3:-1}" >> out/bench/memory.jsonl
done
"$bin" --load > out/bench/load.jsonl
cat out/bench/memory.jsonl out/bench/load.jsonl
python3 scripts/plot_performance.py out/bench docs/img/performance.png || \
  echo "bench.sh: no plot (needs python3 with matplotlib, or gnuplot)"
