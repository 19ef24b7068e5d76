#!/usr/bin/env python3
"""Plugins built against the previous release's SDK load and pass `pdyn check`
with this build's host (issue 28; the policy in docs/plugins.md, "Versions
and the ABI").

The previous release is the newest CHANGELOG.md entry that names the commit
it ends at and has an ABI this build loads (kOldestAbiVersion to
PDYN_ABI_VERSION; an older ABI's descriptor is read in its own layout); its public headers (kernel/include) and
four of its shipped plugins' sources (a pair force, a solver, a collider, a
writer: every plugin interface and the templates plugins instantiate from
the headers) are taken from git at that commit. Each plugin is compiled
against those old headers, linked with this build's kernel library, and
checked by this build's `pdyn check`: an accidental ABI break (a reordered
field, a new virtual, a removed symbol) fails here.

    check_previous_release.py --source DIR --work DIR --pdyn PATH
                              --kernel-lib-dir DIR --cxx PATH
    check_previous_release.py --source DIR --release-only

With --perturb-vtable the old headers first get a virtual function inserted
at the top of PluginObject (an ABI break: every later slot of every plugin
interface moves); the check of the check then passes only if `pdyn check`
refuses each plugin so built.
"""
import argparse
import pathlib
import re
import shlex
import shutil
import subprocess
import sys
import tarfile
import io

PLUGINS = [
    "plugins/forces/lennard_jones/lennard_jones.cpp",
    "plugins/solvers/verlet/verlet.cpp",
    "plugins/colliders/plane/plane.cpp",
    "plugins/writers/csv/csv.cpp",
]
ENTRY = re.compile(r"^## (\d+\.\d+\.\d+) .*ABI (\d+).*\(ends at commit ([0-9a-f]{7,40})\)", re.M)


def current_abi(source):
    text = (source / "kernel" / "include" / "pdyn" / "version.hpp").read_text()
    return int(re.search(r"#define PDYN_ABI_VERSION (\d+)u?", text).group(1))


def oldest_abi(source):
    """The oldest ABI whose plugins this kernel loads (kOldestAbiVersion)."""
    text = (source / "kernel" / "include" / "pdyn" / "version.hpp").read_text()
    found = re.search(r"kOldestAbiVersion = (\d+)u?;", text)
    return int(found.group(1)) if found else current_abi(source)


def previous_release(source):
    """(version, commit) of the newest released entry with an ABI this kernel loads."""
    lo, hi = oldest_abi(source), current_abi(source)
    for version, entry_abi, commit in ENTRY.findall((source / "CHANGELOG.md").read_text()):
        if lo <= int(entry_abi) <= hi:
            return version, commit
    return None


def git(source, *args, binary=False):
    return subprocess.run(["git", "-C", str(source), *args], check=True, capture_output=True,
                          text=not binary).stdout


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--source", required=True, type=pathlib.Path)
    ap.add_argument("--work", type=pathlib.Path)
    ap.add_argument("--pdyn", type=pathlib.Path)
    ap.add_argument("--kernel-lib-dir", type=pathlib.Path)
    ap.add_argument("--cxx", default="c++")
    ap.add_argument("--cxx-flags", default="",
                    help="the host build's CMAKE_CXX_FLAGS: a sanitizer build changes Eigen's "
                         "allocator (handmade aligned malloc under ASan), so a plugin must be "
                         "compiled with the same flags to share Eigen objects with the host")
    ap.add_argument("--perturb-vtable", action="store_true")
    ap.add_argument("--release-only", action="store_true",
                    help="print the previous release's commit if git has it, else nothing")
    a = ap.parse_args()

    found = previous_release(a.source)
    if a.release_only:
        if found:
            try:
                git(a.source, "cat-file", "-e", f"{found[1]}^{{commit}}")
                print(found[1], end="")
            except (subprocess.CalledProcessError, FileNotFoundError):
                pass
        return 0
    if not found:
        print(f"check_previous_release: CHANGELOG.md names no released commit with ABI "
              f"{oldest_abi(a.source)} to {current_abi(a.source)} (expected '## X.Y.Z ... ABI N "
              f"... (ends at commit H)')")
        return 1
    version, commit = found

    shutil.rmtree(a.work, ignore_errors=True)
    old = a.work / "old"
    old.mkdir(parents=True)
    archive = git(a.source, "archive", "--format=tar", commit, "kernel/include", *PLUGINS,
                  binary=True)
    tarfile.open(fileobj=io.BytesIO(archive)).extractall(old)
    plugins = PLUGINS
    if a.perturb_vtable:
        header = old / "kernel" / "include" / "pdyn" / "plugin_object.hpp"
        text = header.read_text()
        anchor = "virtual ~PluginObject() = default;"
        if anchor not in text:
            print(f"check_previous_release: {header} has no '{anchor}' to perturb after")
            return 1
        header.write_text(text.replace(anchor, anchor + " virtual void abi_probe_() {}", 1))
        plugins = PLUGINS[:2]

    eigen = "/usr/include/eigen3"
    failures = []
    refused = 0
    for src in plugins:
        name = pathlib.Path(src).stem
        lib = a.work / f"pdyn_old_{name}.so"
        cmd = [a.cxx, *shlex.split(a.cxx_flags), "-std=c++20", "-O2", "-fPIC", "-shared",
               "-fopenmp", "-DEIGEN_MPL2_ONLY",
               "-DFMT_SHARED", "-I", str(old / "kernel" / "include"), "-isystem", eigen,
               str(old / src), "-o", str(lib), "-L", str(a.kernel_lib_dir),
               f"-Wl,-rpath,{a.kernel_lib_dir}", "-lpdyn_kernel", "-lfmt"]
        built = subprocess.run(cmd, capture_output=True, text=True)
        if built.returncode != 0:
            failures.append(f"{src} at {version} ({commit}) does not build against its own "
                            f"headers:\n{built.stderr[-2000:]}")
            continue
        checked = subprocess.run([str(a.pdyn), "check", str(lib)], capture_output=True, text=True)
        summary = (checked.stdout.strip().splitlines() or [""])[-1]
        print(f"{name} built against {version}'s SDK ({commit}): pdyn check exit "
              f"{checked.returncode}: {summary}")
        refused += checked.returncode != 0
        if checked.returncode != 0 and not a.perturb_vtable:
            failures.append(f"{name} from {version} ({commit}), built against {version}'s "
                            f"headers, fails this build's `pdyn check {lib}` (exit "
                            f"{checked.returncode}; expected every check to pass within ABI "
                            f"{current_abi(a.source)}):\n{checked.stdout[-3000:]}"
                            f"{checked.stderr[-2000:]}")
    if a.perturb_vtable and refused != len(plugins) and not failures:
        failures.append(f"check_previous_release: with a virtual inserted into PluginObject, "
                        f"pdyn check refused {refused} of {len(plugins)} plugins (expected all)")
    for f in failures:
        print(f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
