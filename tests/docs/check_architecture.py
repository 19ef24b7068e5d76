#!/usr/bin/env python3
"""docs.architecture: the tree in docs/architecture.md ("Where things are")
is true to the repository, both ways:

- every folder it shows (`├── NAME/` at any depth) exists, and every file it
  names (NAME.cpp, .hpp, .md, .py, .sh, .cmake, .yaml) exists under the
  folder of the tree's line that names it (a name with a `/` is a path from
  that folder's top-level folder or from the root; a bare page NAME.md that
  is not there is a page of docs/, as the tree writes "pairs.md");
- every kernel header (kernel/include/pdyn/), kernel and host source
  (kernel/src/, host/src/), host header (host/include/pdyn/host/), file of
  bench/ (its subfolders too), plugin folder (plugins/KIND/NAME) and
  docs/*.md page is named on its own folder's lines. By the tree's rules a
  kernel/src/X.cpp may be named by its header X.hpp ("one .cpp per header")
  and a host/src/X.hpp by the X.cpp it sits beside (frame_snapshot.cpp and
  .hpp).

Prints each disagreement and exits 1 if there is one. The check of the
check: with --drop NAME,... it first removes those names from the tree, as
if someone had forgotten them, and with --misplace NAME@FOLDER,... it adds
NAME to FOLDER's lines, as if someone had put it in the wrong place; it
then succeeds only if it reports exactly those names."""
import argparse
import glob
import os
import re
import sys

FILE = re.compile(r"[\w/.-]*[\w-]+\.(cpp|hpp|md|py|sh|cmake|yaml)")


def read_tree(doc):
    """[(folder, tokens)] for each line of the tree: the folder the line
    belongs to (relative to the root, "" for the root) and its words."""
    start = doc.index("## Where things are")
    tree = doc[doc.index("```", start) + 3:]
    tree = tree[:tree.index("```")]
    lines, stack, folder, folders = [], [], "", []
    for line in tree.splitlines()[2:]:  # after the fence's newline and "pdyn/"
        m = re.match(r"^((?:[│ ]   )*)[├└]── (\S+)(.*)$", line)
        if m:
            stack = stack[:len(m.group(1)) // 4]
            name, rest = m.group(2), m.group(3)
            if name.endswith("/"):
                stack.append(name.rstrip("/"))
                folders.append("/".join(stack))
            else:  # a file at this level ("├── LICENSE CHANGELOG.md")
                rest = name + rest
            folder = "/".join(stack)
        else:
            rest = line
        lines.append((folder, re.findall(r"[\w@.+/{},-]+", rest)))
    return lines, folders


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--source-dir", required=True)
    ap.add_argument("--drop", default="")
    ap.add_argument("--misplace", default="")
    a = ap.parse_args()
    src = a.source_dir
    drop = {d for d in a.drop.split(",") if d}
    doc = open(os.path.join(src, "docs", "architecture.md"), encoding="utf-8").read()
    lines, folders = read_tree(doc)
    lines = [(folder, [t for t in tokens if t.strip(",;:()") not in drop]) for folder, tokens in lines]
    misplace = [m.split("@") for m in a.misplace.split(",") if m]
    lines += [(folder, [name]) for name, folder in misplace]
    problems = []

    def files_under(folder):
        found = set()
        for root, dirs, files in os.walk(os.path.join(src, folder)):
            dirs[:] = [d for d in dirs if not d.startswith((".", "build")) and d != "node_modules"]
            found.update(files)
        return found

    for folder in folders:
        if not os.path.isdir(os.path.join(src, folder)):
            problems.append(f"docs/architecture.md shows the folder {folder}/, which does not exist")
    cache = {}
    named = set()  # (folder, name) as the tree names them
    for folder, tokens in lines:
        for token in tokens:
            token = token.strip(",;:()")
            named.add((folder, token))
            if not FILE.fullmatch(token):
                continue
            top = folder.split("/")[0]
            if "/" in token:
                ok = any(os.path.isfile(os.path.join(src, base, token)) for base in (top, ""))
            else:
                if folder not in cache:
                    cache[folder] = files_under(folder)
                ok = token in cache[folder] or (
                    token.endswith(".md") and os.path.isfile(os.path.join(src, "docs", token)))
            if not ok:
                problems.append(f"docs/architecture.md names {token} under {folder or 'the root'}/, "
                                "which is not there")

    must = []
    for pattern in ("kernel/include/pdyn/*.hpp", "kernel/src/*.cpp", "host/src/*.cpp", "host/src/*.hpp",
                    "host/include/pdyn/host/*.hpp", "docs/*.md"):
        must += [os.path.relpath(p, src) for p in glob.glob(os.path.join(src, pattern))]
    must += [os.path.relpath(p, src) for p in glob.glob(os.path.join(src, "bench", "**", "*"),
                                                        recursive=True)
             if os.path.isfile(p) and os.path.basename(p) != "CMakeLists.txt"]
    must += [os.path.relpath(p, src) for p in glob.glob(os.path.join(src, "plugins", "*", "*"))
             if os.path.isdir(p)]

    def is_named(path):
        folder, name = os.path.split(path)
        if folder.startswith("bench/"):  # bench/lammps/in.lj: on bench's lines, as lammps/in.lj or in.lj
            sub = os.path.relpath(path, "bench")
            return ("bench", sub) in named or ("bench", name) in named
        if (folder, name) in named:
            return True
        stem, ext = os.path.splitext(name)
        if folder == "kernel/src" and ext == ".cpp":
            return ("kernel/include/pdyn", stem + ".hpp") in named
        if folder == "host/src" and ext == ".hpp":
            return ("host/src", stem + ".cpp") in named
        return False

    for path in sorted(set(must)):
        if path != "docs/architecture.md" and not is_named(path):
            problems.append(f"{path} is in the repository but not in docs/architecture.md's tree")

    for p in problems:
        print("docs.architecture:", p)
    if drop or misplace:
        missed = sorted(n for n in drop if not any(
            p.endswith(f"/{n} is in the repository but not in docs/architecture.md's tree")
            for p in problems))
        missed += sorted(n for n, folder in misplace if f"docs/architecture.md names {n} under "
                         f"{folder}/, which is not there" not in problems)
        ok = not missed and len(problems) == len(drop) + len(misplace)
        print(f"docs.architecture: dropped {sorted(drop)}, misplaced {misplace}: "
              f"{'all reported' if ok else 'NOT reported as expected'}")
        return 0 if ok else 1
    print("docs.architecture:", "ok" if not problems else f"{len(problems)} disagreement(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
