#!/bin/sh
# The writers' throughput beside dd's to the same disk (issue 15).
#   bench/writers_dd.sh [BUILD_DIR [DIR [N [STEPS]]]]
# dd writes 512 MB of zeros with fdatasync (the disk's sequential write
# speed); then pdyn_bench_writers runs the cloth with each writer into the
# same folder. Run it on a quiet machine.
set -eu
build=${1:-build}
dir=${2:-/tmp/pdyn-bench-writers}
n=${3:-316}
steps=${4:-200}
mkdir -p "$dir"
echo "dd to $dir:"
dd if=/dev/zero of="$dir/dd.bin" bs=1M count=512 conv=fdatasync 2>&1 | tail -1
rm -f "$dir/dd.bin"
"$build/bin/pdyn_bench_writers" "$n" "$steps" "$dir"
