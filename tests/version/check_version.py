#!/usr/bin/env python3
"""version.agree: every place that states pdyn's version or its plugin ABI
version says the same (CHANGELOG.md, "Versions and the ABI" in
docs/plugins.md):

- the project version in CMakeLists.txt, `pdyn --version`, the CMake package
  (pdynConfigVersion.cmake), and the Python module's pdyn.__version__;
- PDYN_ABI_VERSION in <pdyn/version.hpp>, `pdyn --version`, pdyn.abi_version,
  and the shared libraries' sonames (libpdyn_kernel.so.ABI; their files
  libpdyn_kernel.so.ABI.MINOR.PATCH);
- CHANGELOG.md's newest entry ("## X.Y.Z — DATE — ABI N") names both;
- docs/plugins.md's ABI table ends at this ABI, at this release or an
  earlier one of the same ABI (then the text says "X.Y.Z keeps ABI N").

Prints each disagreement and exits 1 if there is one."""
import argparse
import os
import re
import subprocess
import sys


def read(path):
    with open(path, encoding="utf-8") as f:
        return f.read()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--pdyn", required=True)
    ap.add_argument("--source-dir", required=True)
    ap.add_argument("--build-dir", required=True)
    ap.add_argument("--python", choices=["on", "off"], default="off")
    a = ap.parse_args()
    problems = []

    project = re.search(r"project\(pdyn VERSION (\d+\.\d+\.\d+)", read(os.path.join(a.source_dir, "CMakeLists.txt")))
    version = project.group(1)
    abi = re.search(r"#define PDYN_ABI_VERSION (\d+)u",
                    read(os.path.join(a.source_dir, "kernel/include/pdyn/version.hpp"))).group(1)
    print(f"CMakeLists.txt: {version}; pdyn/version.hpp: ABI {abi}")

    out = subprocess.run([a.pdyn, "--version"], capture_output=True, text=True).stdout.strip()
    if out != f"pdyn {version} (plugin ABI {abi})":
        problems.append(f"pdyn --version prints '{out}' (expected 'pdyn {version} (plugin ABI {abi})')")

    entry = re.search(r"^## (\S+) — (\d{4}-\d\d-\d\d) — ABI (\d+)", read(os.path.join(a.source_dir, "CHANGELOG.md")), re.M)
    if not entry:
        problems.append("CHANGELOG.md has no entry '## X.Y.Z — YYYY-MM-DD — ABI N'")
    elif (entry.group(1), entry.group(3)) != (version, abi):
        problems.append(f"CHANGELOG.md's newest entry is {entry.group(1)} with ABI {entry.group(3)} "
                        f"(expected {version} with ABI {abi})")

    plugins_md = read(os.path.join(a.source_dir, "docs/plugins.md"))
    rows = re.findall(r"^\| (\d+) \| (\d+\.\d+) \|", plugins_md, re.M)
    major_minor = ".".join(version.split(".")[:2])
    if not rows:
        problems.append("docs/plugins.md has no ABI table rows '| ABI | pdyn |'")
    else:
        row_abi, row_version = rows[-1]
        if row_abi != abi:
            problems.append(f"docs/plugins.md's ABI table ends at ABI {row_abi} (expected {abi})")
        elif row_version != major_minor and f"{version} keeps ABI {abi}" not in plugins_md:
            problems.append(f"docs/plugins.md's ABI table gives ABI {abi} to pdyn {row_version}, and its text "
                            f"does not say '{version} keeps ABI {abi}'")

    config = os.path.join(a.build_dir, "pdynConfigVersion.cmake")
    package = re.search(r'set\(PACKAGE_VERSION "([^"]+)"\)', read(config))
    if not package or package.group(1) != version:
        problems.append(f"{config} says {package.group(1) if package else 'nothing'} (expected {version})")

    # The libraries are named for the ABI (docs/plugins.md): the soname
    # libpdyn_kernel.so.ABI, the file libpdyn_kernel.so.ABI.MINOR.PATCH.
    minor_patch = version.split(".", 1)[1]
    for lib in ("libpdyn_kernel.so", "libpdyn_host.so"):
        path = os.path.join(a.build_dir, "lib", f"{lib}.{abi}.{minor_patch}")
        if not os.path.exists(path):
            problems.append(f"{path} does not exist (the library's VERSION is not "
                            f"{abi}.{minor_patch}, ABI.MINOR.PATCH)")
            continue
        dynamic = subprocess.run(["objdump", "-p", path], capture_output=True, text=True).stdout
        soname = re.search(r"^\s*SONAME\s+(\S+)", dynamic, re.M)
        if not soname or soname.group(1) != f"{lib}.{abi}":
            problems.append(f"{path}'s soname is {soname.group(1) if soname else 'missing'} "
                            f"(expected {lib}.{abi}, the plugin ABI)")

    if a.python == "on":
        env = dict(os.environ, PYTHONPATH=os.path.join(a.build_dir, "python"))
        got = subprocess.run([sys.executable, "-c", "import pdyn; print(pdyn.__version__, pdyn.abi_version)"],
                             capture_output=True, text=True, env=env)
        if got.stdout.split() != [version, abi]:
            problems.append(f"pdyn.__version__, pdyn.abi_version are '{got.stdout.strip()}' {got.stderr.strip()} "
                            f"(expected '{version} {abi}')")

    for p in problems:
        print("version.agree:", p)
    print("version.agree:", "ok" if not problems else f"{len(problems)} disagreement(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
