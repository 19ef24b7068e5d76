#!/usr/bin/env python3
"""docs.architecture: the tree in docs/architecture.md ("Where things are")
is true to the repository, both ways:

- every file name it shows (NAME.cpp, .hpp, .md, .py, .sh) exists in the
  repository, and every top-level folder it shows (`├── NAME/`) exists;
- every kernel header (kernel/include/pdyn/), kernel and host source
  (kernel/src/, host/src/), host header (host/include/pdyn/host/), bench
  file (bench/*.cpp, .hpp, .py, .sh), every plugin folder (plugins/KIND/NAME)
  and every docs/*.md page is named in it (a .cpp may be named by its .hpp
  and the other way round, as the tree's "one .cpp per header" says).

Prints each disagreement and exits 1 if there is one. With --drop NAME,...
it first removes those names from the tree, as if someone had forgotten
them, and succeeds only if it then reports exactly them (the check of the
check)."""
import argparse
import glob
import os
import re
import sys


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--source-dir", required=True)
    ap.add_argument("--drop", default="")
    a = ap.parse_args()
    src = a.source_dir
    drop = [d for d in a.drop.split(",") if d]
    doc = open(os.path.join(src, "docs", "architecture.md"), encoding="utf-8").read()
    start = doc.index("## Where things are")
    tree = doc[doc.index("```", start) + 3:]
    tree = tree[:tree.index("```")]
    words = set(re.findall(r"[\w@.+-]+", tree)) - set(drop)
    problems = []

    everything = set()
    for root, dirs, files in os.walk(src):
        dirs[:] = [d for d in dirs if not d.startswith((".", "build")) and d != "node_modules"]
        everything.update(files)
    for name in sorted(w for w in words if re.fullmatch(r"[\w-]+\.(cpp|hpp|md|py|sh)", w)):
        if name not in everything:
            problems.append(f"docs/architecture.md names {name}, which is nowhere in the repository")
    for folder in re.findall(r"^[├└]── ([\w.-]+)/", tree, re.M):
        if not os.path.isdir(os.path.join(src, folder)):
            problems.append(f"docs/architecture.md shows the folder {folder}/, which does not exist")

    must = []
    for pattern in ("kernel/include/pdyn/*.hpp", "kernel/src/*.cpp", "host/src/*.cpp", "host/src/*.hpp",
                    "host/include/pdyn/host/*.hpp", "bench/*.cpp", "bench/*.hpp", "bench/*.py",
                    "bench/*.sh", "docs/*.md"):
        must += [os.path.basename(p) for p in glob.glob(os.path.join(src, pattern))]
    must += [os.path.basename(p) for p in glob.glob(os.path.join(src, "plugins", "*", "*"))
             if os.path.isdir(p)]
    # The tree's own rules: kernel/src holds "one .cpp per header that needs
    # one", and a source's private header sits beside it (frame_snapshot.cpp
    # and .hpp): X.cpp is covered by X.hpp and the other way round.
    def named(name):
        stem, ext = os.path.splitext(name)
        twin = {".cpp": ".hpp", ".hpp": ".cpp"}.get(ext)
        return name in words or (twin is not None and stem + twin in words)
    for name in sorted(set(must)):
        if name != "architecture.md" and not named(name):
            problems.append(f"{name} is in the repository but not in docs/architecture.md's tree")

    for p in problems:
        print("docs.architecture:", p)
    if drop:
        missed = sorted(n for n in drop if not any(p.startswith(n + " is in the repository")
                                                   for p in problems))
        ok = not missed and len(problems) == len(drop)
        print(f"docs.architecture: dropped {drop}: {'all reported' if ok else 'NOT reported as expected'}")
        return 0 if ok else 1
    print("docs.architecture:", "ok" if not problems else f"{len(problems)} disagreement(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
