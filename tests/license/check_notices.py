#!/usr/bin/env python3
"""license.notices: THIRD_PARTY_NOTICES.md lists everything the shipped
binaries load, under licenses that leave them shippable under Apache-2.0
(CONTRIBUTING.md, "Dependencies and licenses").

For every shipped ELF file in the build tree (bin/pdyn, lib/libpdyn_*.so,
the shipped plugins, the Python module) it reads the NEEDED entries
(`readelf -d`), resolves each to a file (`ldd`) and that file to its Debian
package (`dpkg -S`); each package must be a row of the notices' first
table. Every npm dependency of viewer/package.json must be a row of the
second. A shipped row's license must be one of ALLOWED.

With --drop PKG,... it first removes those packages' rows, as if someone
had forgotten them, and succeeds only if it then reports exactly those
packages missing (the check of the check)."""
import argparse
import functools
import glob
import json
import os
import re
import subprocess
import sys

# Licenses a shipped row may have (SPDX expressions as written in the table).
ALLOWED = {
    "MIT", "BSD-2-Clause", "BSD-3-Clause", "BSL-1.0", "Apache-2.0", "MPL-2.0", "Zlib", "PSF-2.0",
    "LGPL-2.1-only OR MPL-1.1", "LGPL-2.1-or-later", "GPL-3.0-or-later WITH GCC-exception-3.1",
}


def tables(text):
    """The rows of each markdown table under a '## ' heading, by heading."""
    out, heading = {}, None
    for line in text.splitlines():
        if line.startswith("## "):
            heading = line[3:].strip()
        elif line.startswith("|") and heading and not re.match(r"^\|[-| ]+\|$", line):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            out.setdefault(heading, []).append(cells)
    return {h: rows[1:] for h, rows in out.items()}  # drop each header row


def shipped_files(build):
    files = [os.path.join(build, "bin", "pdyn")]
    files += [f for f in glob.glob(os.path.join(build, "lib", "libpdyn_*.so.*")) if not os.path.islink(f)]
    files += glob.glob(os.path.join(build, "lib", "pdyn", "plugins", "*.so"))
    files += glob.glob(os.path.join(build, "python", "pdyn", "_pdyn*.so"))
    return files


@functools.lru_cache(maxsize=None)
def owner_package(path):
    """The Debian package that installed `path` (or its target), or None.
    Cached: each `dpkg -S` reads dpkg's whole database (about 0.3 s), and
    thirty binaries name the same ten libraries."""
    for candidate in (path, os.path.realpath(path)):
        owner = subprocess.run(["dpkg", "-S", candidate], capture_output=True, text=True)
        if owner.returncode == 0:
            return owner.stdout.split(":")[0].strip()
    return None


def needed_packages(files):
    """{package: [(binary, soname)]} for every NEEDED library outside pdyn."""
    found = {}
    for f in files:
        dyn = subprocess.run(["readelf", "-d", f], capture_output=True, text=True, check=True).stdout
        needed = re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", dyn)
        ldd = subprocess.run(["ldd", f], capture_output=True, text=True).stdout
        where = dict(re.findall(r"^\s*(\S+) => (\S+)", ldd, re.M))
        # The dynamic loader is listed by its path alone: /lib64/ld-linux-x86-64.so.2 (0x...).
        where.update((os.path.basename(p), p) for p in re.findall(r"^\s*(/\S+) \(0x", ldd, re.M))
        for soname in needed:
            if soname.startswith("libpdyn_"):
                continue
            path = where.get(soname)
            if not path or path == "not":
                raise SystemExit(f"license.notices: {f} needs {soname}, which ldd does not find")
            pkg = owner_package(path)
            if pkg is None:
                raise SystemExit(f"license.notices: {f} needs {soname} ({path}), which no Debian package owns")
            found.setdefault(pkg, []).append((os.path.basename(f), soname))
    return found


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--source-dir", required=True)
    ap.add_argument("--build-dir", required=True)
    ap.add_argument("--drop", default="")
    a = ap.parse_args()
    notices = os.path.join(a.source_dir, "THIRD_PARTY_NOTICES.md")
    t = tables(open(notices, encoding="utf-8").read())
    drop = set(filter(None, a.drop.split(",")))
    shipped = [r for r in t.get("Shipped with or linked into pdyn's binaries", []) if r[1] not in drop]
    page = [r for r in t.get("The viewer page (npm, copied next to the program at build time)", [])
            if r[1] not in drop]
    problems, missing = [], []

    listed = {}
    for row in shipped:
        for pkg in re.split(r",\s*", row[1]):
            listed[pkg] = row
        if row[2] not in ALLOWED:
            problems.append(f"{row[0]} ({row[1]}) is shipped under '{row[2]}', which is not allowed "
                            f"(expected one of: {', '.join(sorted(ALLOWED))})")

    files = shipped_files(a.build_dir)
    if len(files) < 10:
        problems.append(f"found only {len(files)} shipped binaries under {a.build_dir} (expected the program, "
                        "libraries and plugins: is the build complete?)")
    packages = needed_packages(files)
    for pkg, users in sorted(packages.items()):
        if pkg not in listed:
            missing.append(pkg)
            problems.append(f"{users[0][0]} needs {users[0][1]} from the Debian package {pkg}, "
                            f"which {os.path.basename(notices)} does not list")

    npm = json.load(open(os.path.join(a.source_dir, "viewer", "package.json"))).get("dependencies", {})
    page_names = {row[1] for row in page}
    for name in sorted(npm):
        if name not in page_names:
            missing.append(name)
            problems.append(f"the viewer page depends on the npm package {name}, which "
                            f"{os.path.basename(notices)} does not list")
    for row in page:
        if row[2] not in ALLOWED:
            problems.append(f"{row[0]} (npm {row[1]}) is under '{row[2]}', which is not allowed")

    for p in problems:
        print("license.notices:", p)
    if drop:
        expected = sorted(drop)
        ok = sorted(missing) == expected
        print(f"license.notices: reported missing {sorted(missing)}, expected {expected}: {'ok' if ok else 'WRONG'}")
        return 0 if ok else 1
    print(f"license.notices: {len(files)} binaries checked, loading {', '.join(sorted(packages))}: "
          + ("ok" if not problems else f"{len(problems)} problem(s)"))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
