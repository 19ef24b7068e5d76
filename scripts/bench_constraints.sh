#!/usr/bin/env bash
# Constraint benchmarks (issue 29, docs/performance.md "Constraints"), one
# command:
#
#   bash scripts/bench_constraints.sh [REPEAT]     (default 5)
#
# Builds pdyn and the plugins (default preset), then runs whole `pdyn run`
# processes round robin (bench/constraints.py) and prints two Markdown
# tables: the cost per constraint row per step of RATTLE, Witkin's
# constraint force and XPBD on the 50-rod chain and the 30 x 30 cloth, and
# the time to solution of the cloth at an edge strain of at most 1 % with
# xpbd against the same cloth with springs under implicit_euler and rk4.
# Run it on a quiet machine: it prints the load average before and after.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset default >/dev/null
cmake --build --preset default --target pdyn pdyn_plugins
python3 bench/constraints.py --repeat "${1:-5}"
