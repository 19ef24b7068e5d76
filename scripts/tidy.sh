#!/usr/bin/env bash
# clang-tidy-14 with the repository's .clang-tidy over every .cpp of the
# product folders (kernel, host, plugins, conformance, cli, viewer, python,
# bench) that BUILD_DIR/compile_commands.json compiles, and over the headers
# of those folders that they include. Prints each finding once (a header's
# finding is reported by every file including it), then one summary line;
# exits 1 on any finding, 2 when it cannot run.
#
#   bash scripts/tidy.sh [BUILD_DIR]      (default build/; PDYN_TIDY_JOBS, default nproc)
#
# The libraries are unity builds (cmake/PdynUnity.cmake): their entries in
# the compile database are CMake's batch files, so each batch is expanded to
# its sources here, with the batch's flags, into BUILD_DIR/tidy/. The plugins'
# precompiled header (a GCC .gch) is left out: each file is read as written.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
root="$PWD"
build="${1:-build}"
jobs="${PDYN_TIDY_JOBS:-$(nproc)}"
tidy="${CLANG_TIDY:-clang-tidy-14}"
if [[ ! -f "$build/compile_commands.json" ]]; then
  echo "tidy.sh: no $build/compile_commands.json: configure first (cmake --preset default)" >&2
  exit 2
fi
if ! command -v "$tidy" >/dev/null 2>&1; then
  echo "tidy.sh: $tidy not found (Debian 12: apt-get install clang-tidy-14)" >&2
  exit 2
fi
start=$SECONDS
out="$(cd "$build" && pwd)/tidy"
rm -rf "$out"
mkdir -p "$out/logs"

python3 - "$build/compile_commands.json" "$root" "$out" <<'EOF'
import json, os, re, shlex, sys
db, root, out = sys.argv[1], sys.argv[2], sys.argv[3]
product = ("kernel", "host", "plugins", "conformance", "cli", "viewer", "python", "bench")
entries, seen = [], set()
for e in json.load(open(db)):
    args = e["arguments"] if "arguments" in e else shlex.split(e["command"])
    # Without the precompiled header (GCC's, which clang cannot read) and
    # -Werror: the compiler's own warnings are GCC's to give (the build),
    # and GCC's -Wno-* options are unknown to clang.
    flags, i = [], 0
    while i < len(args):
        if args[i] == "-include" and i + 1 < len(args) and "cmake_pch" in args[i + 1]:
            i += 2
            continue
        if args[i] not in ("-Winvalid-pch", "-Werror"):
            flags.append(args[i])
        i += 1
    flags.insert(1, "-Wno-unknown-warning-option")
    path = os.path.normpath(os.path.join(e["directory"], e["file"]))
    sources = [path]
    if re.search(r"/Unity/unity_\d+_cxx\.cxx$", path):
        sources = re.findall(r'^#include "([^"]+)"', open(path).read(), re.M)
    for src in sources:
        rel = os.path.relpath(src, root)
        if not rel.endswith(".cpp") or rel.split(os.sep)[0] not in product or src in seen:
            continue
        seen.add(src)
        entries.append({"directory": e["directory"], "file": src,
                        "arguments": [src if a == path else a for a in flags]})
entries.sort(key=lambda x: x["file"])
json.dump(entries, open(os.path.join(out, "compile_commands.json"), "w"), indent=1)
with open(os.path.join(out, "files.txt"), "w") as f:
    f.writelines(x["file"] + "\n" for x in entries)
EOF

files=$(wc -l <"$out/files.txt")
# Each file's output to its own log; clang-tidy exits non-zero on a finding
# (WarningsAsErrors) or when it cannot parse the file.
export tidy out
header_filter="^$root/(kernel|host|plugins|conformance|cli|viewer|python|bench)/"
export header_filter
xargs -a "$out/files.txt" -P "$jobs" -I{} bash -c \
  'f="$1"; log="$out/logs/$(echo "${f#/}" | tr / _).log"
   "$tidy" -p "$out" --quiet --header-filter="$header_filter" "$f" >"$log" 2>&1 || echo "$f" >>"$out/failed"' _ {}

# Each finding once, with its notes and code lines.
python3 - "$out" <<'EOF'
import glob, os, re, sys
out = sys.argv[1]
diag = re.compile(r"^(/\S+?):(\d+):(\d+): (warning|error): (.*?)(?: \[([\w.,-]+)\])?$")
blocks, order = {}, []
for log in sorted(glob.glob(os.path.join(out, "logs", "*.log"))):
    current = None
    for line in open(log, errors="replace").read().splitlines():
        if re.match(r"^\d+ (warnings?|errors?)( and \d+ errors?)? generated\.$", line) or \
           line.startswith(("Suppressed ", "Use -header-filter", "Error while processing")):
            continue
        m = diag.match(line)
        if m:
            current = line
            if line not in blocks:
                blocks[line] = [line]
                order.append(line)
                current = line
            else:
                current = None  # already printed from another file
        elif current is not None:
            blocks[current].append(line)
checks = {}
for key in order:
    print("\n".join(blocks[key]))
    m = diag.match(key)
    for c in (m.group(6) or "compiler").split(","):
        if c != "-warnings-as-errors":
            checks[c] = checks.get(c, 0) + 1
with open(os.path.join(out, "count"), "w") as f:
    f.write(f"{len(order)}\n")
if checks:
    print("by check: " + ", ".join(f"{c} {n}" for c, n in sorted(checks.items(), key=lambda x: -x[1])))
EOF

findings=$(cat "$out/count")
failed=0
[[ -f "$out/failed" ]] && failed=$(wc -l <"$out/failed")
if [[ "$findings" == 0 && "$failed" != 0 ]]; then  # a failure without a finding: show its log
  while read -r f; do cat "$out/logs/$(echo "${f#/}" | tr / _).log"; done <"$out/failed"
fi
load=$(cut -d' ' -f1-3 /proc/loadavg)
echo "tidy.sh: $files files, $findings findings ($failed files failing) in $((SECONDS - start)) s, -j $jobs, load average $load"
[[ "$findings" == 0 && "$failed" == 0 ]]
