#!/usr/bin/env bash
# Fuzzes the scene loader for a bounded time with libFuzzer (clang, ASan,
# UBSan), seeded with configs/, the malformed test scenes and the regression
# corpus. Fails on any crash, hang, leak or sanitizer report; the input that
# caused it is saved under build-fuzz/findings/ — add it to
# tests/robustness/fuzz_regressions/ once fixed.
#
#   bash scripts/fuzz.sh [SECONDS]     (default 120)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
seconds="${1:-120}"
# clang with its sanitizer runtimes, OpenMP for clang (g++ brings libgomp).
source scripts/packages.sh
install_missing clang libclang-rt-14-dev libomp-dev
source scripts/ccache.sh
cmake --preset fuzz "${launcher[@]}" >/dev/null
cmake --build --preset fuzz --target scene_fuzzer pdyn_plugins
work=build-fuzz/corpus
rm -rf "$work" build-fuzz/findings && mkdir -p "$work" build-fuzz/findings
seeds=(configs tests/scenes/bad tests/robustness/fuzz_regressions)
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
log=build-fuzz/fuzz.log
set +e
(cd build-fuzz && ./bin/scene_fuzzer -max_total_time="$seconds" -timeout=20 -rss_limit_mb=4096 \
  -print_final_stats=1 -artifact_prefix=findings/ corpus "${seeds[@]/#/../}") >"$log" 2>&1
status=$?
set -e
grep -E "stat::number_of_executed_units|stat::peak_rss_mb|ERROR|SUMMARY|Test unit written" "$log" || true
if [[ $status -ne 0 ]]; then
  echo "fuzz: FAILED (exit $status); last lines of $log:" >&2
  tail -40 "$log" >&2
  exit 1
fi
echo "fuzz: no crash, hang or sanitizer report in ${seconds} s"
