#!/usr/bin/env bash
# clang-tidy-14 with the repository's .clang-tidy over every .cpp of the
# product folders (kernel, host, plugins, conformance, cli, viewer, python,
# bench) that BUILD_DIR/compile_commands.json compiles, and over the headers
# of those folders that they include; or, given FILEs, over those of them
# (the pre-commit hook: the staged ones). Prints each finding once (a
# header's finding is reported by every file including it), then one
# summary line; exits 1 on any finding, 2 when it cannot run.
#
#   bash scripts/tidy.sh [BUILD_DIR] [FILE...]   (default build/; PDYN_TIDY_JOBS, default nproc)
#   bash scripts/tidy.sh [BUILD_DIR] --since REV  (CI: what changed since REV)
#
# --since REV analyses the product folders' sources that changed since the
# commit REV (`git diff REV`, committed or not), and for each changed header
# one source that includes it (a header's findings are the same from any
# includer). CI (scripts/ci-extra.sh) runs it from scripts/tidy-clean-at,
# the last commit at which a whole run found nothing: a whole run takes 24
# to 28 minutes at one job on a 2-core machine, more than CI can hold (each
# plugin's file alone is 12 to 20 s: the checks match over all of Eigen).
#
# The libraries are unity builds (cmake/PdynUnity.cmake): their entries in
# the compile database are CMake's batch files, so each batch is expanded to
# its sources here, with the batch's flags, into BUILD_DIR/tidy/. The plugins'
# precompiled header (a GCC .gch) is left out: each file is read as written.
set -euo pipefail
build=build
if (($#)) && [[ -d "$1" ]]; then
  build=$(cd "$1" && pwd)
  shift
fi
since=""
if (($#)) && [[ "$1" == "--since" ]]; then
  if (($# != 2)); then
    echo "tidy.sh: --since takes one commit and nothing after it (expected [BUILD_DIR] --since REV)" >&2
    exit 2
  fi
  since="$2"
  set --
fi
only=()  # the FILEs, absolute
for f in "$@"; do
  if [[ ! -f "$f" ]]; then
    echo "tidy.sh: no file $f (expected [BUILD_DIR] [FILE...])" >&2
    exit 2
  fi
  only+=("$(realpath "$f")")
done
cd "$(dirname "${BASH_SOURCE[0]}")/.."
root="$PWD"
# The product folders: the files analysed, and the headers whose findings count.
product="kernel|host|plugins|conformance|cli|viewer|python|bench"
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
headers=()  # --since: the changed headers, absolute
if [[ -n "$since" ]]; then
  if ! git rev-parse --verify --quiet "$since^{commit}" >/dev/null; then
    echo "tidy.sh: no commit $since in this clone's history (a shallow clone? expected a commit)" >&2
    exit 2
  fi
  while IFS= read -r f; do
    [[ -f "$f" && "$f" =~ ^($product)/ ]] || continue  # deleted since, or no product's
    case "$f" in
      *.cpp) only+=("$root/$f") ;;
      *.hpp) headers+=("$root/$f") ;;
    esac
  done < <(git diff --name-only "$since" --)
  if ((${#only[@]} + ${#headers[@]} == 0)); then
    echo "tidy.sh: no product source or header changed since $since (load average" \
      "$(cut -d' ' -f1-3 /proc/loadavg))"
    exit 0
  fi
fi

python3 - "$build/compile_commands.json" "$root" "$out" "$product" "${#headers[@]}" "${headers[@]}" \
  "${only[@]}" <<'EOF'
import json, os, re, shlex, sys
db, root, out, product, n = sys.argv[1:4] + [sys.argv[4].split("|"), int(sys.argv[5])]
headers, only = sys.argv[6:6 + n], set(sys.argv[6 + n:])
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
        if only and not headers and src not in only:
            continue
        seen.add(src)
        entries.append({"directory": e["directory"], "file": src,
                        "arguments": [src if a == path else a for a in flags]})
# --since: one includer of each changed header, if the changed sources hold
# none (`#include` lines naming the header by a tail of its path).
if headers:
    every = entries
    entries = [x for x in every if x["file"] in only]
    included = re.compile(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]', re.M)
    texts = {}
    def includes(src, header):
        if src not in texts:
            texts[src] = included.findall(open(src, errors="replace").read())
        return any(header.endswith("/" + i) for i in texts[src])
    for h in headers:
        if any(includes(x["file"], h) for x in entries):
            continue
        for x in every:
            if includes(x["file"], h):
                entries.append(x)
                break
        else:
            print(f"tidy.sh: no source includes {os.path.relpath(h, root)}: not analysed")
for src in sorted(only - {x["file"] for x in entries}):
    print(f"tidy.sh: {os.path.relpath(src, root)} is not compiled in this build: not analysed")
entries.sort(key=lambda x: x["file"])
json.dump(entries, open(os.path.join(out, "compile_commands.json"), "w"), indent=1)
with open(os.path.join(out, "files.txt"), "w") as f:
    f.writelines(x["file"] + "\n" for x in entries)
EOF

files=$(wc -l <"$out/files.txt")
# Each file's output to its own log; clang-tidy exits non-zero on a finding
# (WarningsAsErrors) or when it cannot parse the file.
export tidy out
header_filter="^$root/($product)/"
export header_filter
xargs -a "$out/files.txt" -P "$jobs" -I{} bash -c \
  'f="$1"; log="$out/logs/$(echo "${f#/}" | tr / _).log"
   "$tidy" -p "$out" --quiet --header-filter="$header_filter" "$f" >"$log" 2>&1 || echo "$f" >>"$out/failed"' _ {}

# Each finding once, with its notes and code lines; the whole log of a file
# that failed without a finding (it did not parse, clang-tidy crashed).
python3 - "$out" <<'EOF'
import os, re, sys
out = sys.argv[1]
diag = re.compile(r"^(/\S+?):(\d+):(\d+): (warning|error): (.*?)(?: \[([\w.,-]+)\])?$")
noise = re.compile(r"^\d+ (warnings?|errors?)( and \d+ errors?)? generated\.$|^Suppressed |^Use -header-filter")
failed = set()
if os.path.exists(os.path.join(out, "failed")):
    failed = set(open(os.path.join(out, "failed")).read().split())
blocks, order, broken = {}, [], 0
for src in open(os.path.join(out, "files.txt")).read().split():
    lines = open(os.path.join(out, "logs", src.lstrip("/").replace("/", "_") + ".log"),
                 errors="replace").read().splitlines()
    current, found = None, False
    for line in lines:
        if noise.match(line):
            continue
        m = diag.match(line)
        if m:
            found = True
            current = line if line not in blocks else None  # else printed from another file
            if current:
                blocks[line] = [line]
                order.append(line)
        elif current is not None:
            blocks[current].append(line)
    if src in failed and not found:
        broken += 1
        print(f"{src}: clang-tidy failed without a finding:")
        print("\n".join(lines))
checks = {}
for key in order:
    print("\n".join(blocks[key]))
    for c in (diag.match(key).group(6) or "compiler").split(","):
        if c != "-warnings-as-errors":
            checks[c] = checks.get(c, 0) + 1
if checks:
    print("by check: " + ", ".join(f"{c} {n}" for c, n in sorted(checks.items(), key=lambda x: -x[1])))
open(os.path.join(out, "count"), "w").write(f"{len(order)} {broken}\n")
EOF

read -r findings broken <"$out/count"
load=$(cut -d' ' -f1-3 /proc/loadavg)
echo "tidy.sh: $files files, $findings findings, $broken files not analysed, in $((SECONDS - start)) s" \
  "(-j $jobs, load average $load)"
[[ "$findings" == 0 && "$broken" == 0 ]]
