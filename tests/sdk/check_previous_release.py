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


def release_soname(source, commit):
    """The kernel's soname at `commit`: libpdyn_kernel.so.0 until it followed
    the ABI (libpdyn_kernel.so.<ABI> since pdyn 0.10)."""
    cmake = git(source, "show", f"{commit}:kernel/CMakeLists.txt")
    if "SOVERSION ${PDYN_ABI_VERSION}" in cmake:
        abi = re.search(r"#define PDYN_ABI_VERSION (\d+)",
                        git(source, "show", f"{commit}:kernel/include/pdyn/version.hpp")).group(1)
        return f"libpdyn_kernel.so.{abi}"
    return "libpdyn_kernel.so.0"


def make_stub_kernel(a, soname):
    """An empty library named as the release's kernel was: a plugin linked
    against it records that soname, as the release's own binaries do, and
    finds its symbols at load time in whatever library carries that name."""
    stub_dir = a.work / "stub"
    stub_dir.mkdir(parents=True, exist_ok=True)
    source = stub_dir / "stub.cpp"
    source.write_text("// the release's kernel library, by name only\n")
    subprocess.run([a.cxx, "-shared", "-fPIC", str(source), f"-Wl,-soname,{soname}", "-o",
                    str(stub_dir / "libpdyn_kernel.so")], check=True)
    return stub_dir


def build_old_plugin(a, src, name, stub):
    """Compiles `src` against the release's headers (a.work/old), then links
    it twice: against this build's kernel with no undefined symbol allowed
    (every symbol the release's plugin calls is still exported), and as the
    release linked it (the binary `pdyn check` loads). (library, problem)."""
    obj = a.work / f"pdyn_old_{name}.o"
    lib = a.work / f"pdyn_old_{name}.so"
    compiled = subprocess.run(
        [a.cxx, *shlex.split(a.cxx_flags), "-std=c++20", "-O2", "-fPIC", "-fopenmp",
         "-DEIGEN_MPL2_ONLY", "-DFMT_SHARED", "-I", str(a.work / "old" / "kernel" / "include"),
         "-isystem", "/usr/include/eigen3", "-c", str(src), "-o", str(obj)],
        capture_output=True, text=True)
    if compiled.returncode != 0:
        return lib, f"does not build against its own headers:\n{compiled.stderr[-2000:]}"
    link = [a.cxx, *shlex.split(a.cxx_flags), "-shared", "-fopenmp", str(obj), "-lfmt"]
    checked = subprocess.run(link + ["-o", str(lib), "-Wl,--no-undefined", "-L",
                                     str(a.kernel_lib_dir), "-lpdyn_kernel"],
                             capture_output=True, text=True)
    if checked.returncode != 0:
        return lib, (f"calls what this build's kernel no longer exports (expected every "
                     f"symbol of the release's SDK exported, tests/kernel/kernel_exports.txt):"
                     f"\n{checked.stderr[-2000:]}")
    # --no-as-needed: the stub defines nothing, and the linker would drop it.
    linked = subprocess.run(link + ["-o", str(lib), "-L", str(stub), "-Wl,--no-as-needed",
                                    "-lpdyn_kernel", f"-Wl,-rpath,{a.kernel_lib_dir}"],
                            capture_output=True, text=True)
    if linked.returncode != 0:
        return lib, f"does not link as its release did:\n{linked.stderr[-2000:]}"
    dynamic = subprocess.run(["objdump", "-p", str(lib)], capture_output=True, text=True).stdout
    soname = subprocess.run(["objdump", "-p", str(stub / "libpdyn_kernel.so")],
                            capture_output=True, text=True).stdout
    wanted = re.search(r"SONAME\s+(\S+)", soname).group(1)
    if not re.search(rf"NEEDED\s+{re.escape(wanted)}$", dynamic, re.M):
        return lib, f"was linked without NEEDED {wanted} (expected the release's soname)"
    return lib, None


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

    soname = release_soname(a.source, commit)
    stub = make_stub_kernel(a, soname)
    failures = []
    refused = 0
    for src in plugins:
        name = pathlib.Path(src).stem
        lib, problem = build_old_plugin(a, old / src, name, stub)
        if problem:
            failures.append(f"{src} at {version} ({commit}): {problem}")
            continue
        checked = subprocess.run([str(a.pdyn), "check", str(lib)], capture_output=True, text=True)
        summary = (checked.stdout.strip().splitlines() or [""])[-1]
        print(f"{name} built against {version}'s SDK ({commit}), linked as {soname}: pdyn check exit "
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
