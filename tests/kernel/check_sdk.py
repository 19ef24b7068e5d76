#!/usr/bin/env python3
"""The kernel is the plugin SDK and nothing else (issue 28, docs/plugins.md).

Two checks, each failing with one line per offender:

1. Headers: every header under kernel/include/pdyn/ is one a plugin uses:
   included by a shipped plugin, a `pdyn new` template or the conformance
   kit's header (what a plugin author's test includes), directly or through
   another kernel header so included.
2. Symbols: every symbol the kernel library exports in namespace pdyn names
   something those headers declare (a class, function or variable of the
   SDK), so nothing host-only is compiled into the library every plugin
   loads.
3. The exported list: the library is compiled with hidden visibility
   (pdyn/export.hpp), so what it exports is what the headers mark PDYN_API.
   Its exported pdyn symbols (mangled) must be exactly those of
   tests/kernel/kernel_exports.txt: one lost breaks every plugin binary
   that calls it (a missing PDYN_API, or an ABI bump that says so), one new
   is added to the list on purpose (--write-exports).

The one exception is what the kernel offers hosts only, in its own folder
kernel/host_include/pdyn/kernel/ (the crash record: the kernel marks the
plugin calls it makes, the host reads the mark): names declared there may be
exported, and are listed.

    check_sdk.py --source DIR --kernel-lib libpdyn_kernel.so
                 [--pretend-header NAME ...] [--pretend-symbol SYMBOL ...]
                 [--pretend-lost MANGLED ...] [--expect-pretended] [--allow-new]
    check_sdk.py --source DIR --kernel-lib libpdyn_kernel.so --write-exports

--pretend-header and --pretend-symbol add a header no plugin includes or an
exported symbol (demangled) no header declares, --pretend-lost removes a
listed symbol from what the library exports; with --expect-pretended the
check passes only if exactly those are reported (the check of the check).
"""
import argparse
import pathlib
import re
import subprocess
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s*[<"](pdyn/[^>"]+)[>"]', re.M)
WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def includes(path):
    return INCLUDE.findall(path.read_text(errors="replace"))


def code_of(text):
    """The text without comments: a name only a comment mentions is not declared."""
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    return re.sub(r"//[^\n]*", " ", text)


def plugin_sources(root):
    yield from sorted((root / "plugins").rglob("*.cpp"))
    yield from sorted((root / "plugins").rglob("*.hpp"))
    yield from sorted(p for p in (root / "cli" / "templates").rglob("*") if p.is_file())
    yield from sorted((root / "conformance" / "include").rglob("*.hpp"))


def used_headers(root, kernel_headers):
    """Kernel headers a plugin includes, closed over the kernel's own includes."""
    seen, todo = set(), []
    for src in plugin_sources(root):
        todo += [h for h in includes(src) if h in kernel_headers]
    while todo:
        h = todo.pop()
        if h in seen:
            continue
        seen.add(h)
        todo += [i for i in includes(kernel_headers[h]) if i in kernel_headers]
    return seen


def exported_names(lib):
    out = subprocess.run(["nm", "-D", "--defined-only", "-C", str(lib)], check=True,
                         capture_output=True, text=True).stdout
    for line in out.splitlines():
        parts = line.split(" ", 2)
        if len(parts) == 3 and parts[1] in "TtWwVvDdBbRru" and "pdyn::" in parts[2]:
            yield parts[2]


# A pdyn function or variable (_ZN4pdyn..., _ZNK4pdyn...), a pdyn class's
# vtable, type information or its name (_ZTV, _ZTI, _ZTS) or a thunk into
# one (_ZThn): what a plugin binary can have linked against. Not the
# standard library's templates instantiated for pdyn's types, which the
# compiler emits or inlines as its optimisation level decides.
PDYN_SYMBOL = re.compile(r"^_Z(?:T[VIS]|Th-?\d+_)?NK?4pdyn")


def exported_mangled(lib):
    """The library's exported symbols of namespace pdyn, mangled."""
    out = subprocess.run(["nm", "-D", "--defined-only", str(lib)], check=True,
                         capture_output=True, text=True).stdout
    return {parts[2] for parts in (line.split(" ", 2) for line in out.splitlines())
            if len(parts) == 3 and parts[1] in "TtWwVvDdBbRru" and PDYN_SYMBOL.match(parts[2])}


def demangle(symbols):
    out = subprocess.run(["c++filt"], input="\n".join(symbols), check=True,
                         capture_output=True, text=True).stdout
    return dict(zip(symbols, out.splitlines()))


def check_exports(source, lib, pretend_lost, allow_new):
    """Problems with the exported list (check 3), and the pretended ones."""
    listing = source / "tests" / "kernel" / "kernel_exports.txt"
    listed = {row for row in listing.read_text().splitlines() if row and not row.startswith("#")}
    exported = exported_mangled(lib) - set(pretend_lost)
    lost, new = sorted(listed - exported), sorted(exported - listed)
    names = demangle(lost + new)
    problems, pretended = [], []
    for sym in lost:
        (pretended if sym in pretend_lost else problems).append(
            f"{lib.name}: no longer exports {names[sym]} ({sym}), which {listing.name} lists "
            "(expected PDYN_API on its declaration; a plugin binary linked against it would "
            "not load, so losing it needs an ABI bump, CHANGELOG.md)")
    for sym in [] if allow_new else new:
        problems.append(f"{lib.name}: exports {names[sym]} ({sym}), which {listing.name} does "
                        "not list (expected the list to name every export: --write-exports)")
    return problems, pretended


def write_exports(source, lib):
    listing = source / "tests" / "kernel" / "kernel_exports.txt"
    head = [row for row in listing.read_text().splitlines() if row.startswith("#")] \
        if listing.exists() else []
    tmp = listing.with_suffix(".tmp")
    tmp.write_text("\n".join(head + sorted(exported_mangled(lib))) + "\n")
    tmp.replace(listing)
    print(f"check_sdk: wrote {listing}")


def owner(symbol):
    """The first name after `pdyn::` (and its sub-namespaces) that a header
    must declare: `pdyn::System::derivative(...)` -> System,
    `vtable for pdyn::Force` -> Force, `pdyn::crash::t_current_call` ->
    t_current_call. None for what no header spells (lambdas, anonymous
    namespaces)."""
    s = re.sub(r"^(vtable|typeinfo name|typeinfo|VTT|guard variable|TLS init function|"
               r"TLS wrapper function|non-virtual thunk to|virtual thunk to) for ", "", symbol)
    s = s.split("(", 1)[0]
    depth, name = 0, ""
    for c in s:  # drop template arguments
        depth += c == "<"
        if depth == 0:
            name += c
        depth -= c == ">"
    if "{lambda" in name or "(anonymous namespace)" in name:
        return None
    parts = [p.strip() for p in name.split("::")]
    if "pdyn" not in parts:
        return None
    parts = parts[parts.index("pdyn") + 1:]
    while len(parts) > 1 and parts[0] in ("crash", "detail", "neighbors"):
        parts = parts[1:]
    m = WORD.match(parts[0]) if parts else None
    return m.group(0) if m else None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--source", required=True, type=pathlib.Path)
    ap.add_argument("--kernel-lib", required=True, type=pathlib.Path)
    ap.add_argument("--pretend-header", action="append", default=[])
    ap.add_argument("--pretend-symbol", action="append", default=[])
    ap.add_argument("--pretend-lost", action="append", default=[])
    ap.add_argument("--expect-pretended", action="store_true")
    ap.add_argument("--write-exports", action="store_true")
    ap.add_argument("--allow-new", action="store_true",
                    help="report only lost exports: a sanitizer build (-O1) emits out of line "
                         "some template instantiations that -O2 inlines away")
    a = ap.parse_args()
    if a.write_exports:
        write_exports(a.source, a.kernel_lib)
        return 0
    inc = a.source / "kernel" / "include"
    kernel_headers = {str(p.relative_to(inc)): p for p in sorted((inc / "pdyn").rglob("*.hpp"))}
    problems, pretended = [], []

    used = used_headers(a.source, kernel_headers)
    for h in sorted(set(kernel_headers) | {f"pdyn/{n}" for n in a.pretend_header}):
        if h not in used:
            (pretended if h[5:] in a.pretend_header else problems).append(f"kernel/include/{h}: no plugin, template or conformance header "
                            "includes it, directly or through another kernel header (expected "
                            "only what plugins use in the kernel: move host-only code to host/)")

    declared = set()
    for h in used:
        declared |= set(WORD.findall(code_of(kernel_headers[h].read_text())))
    for_hosts = set()
    for h in sorted((a.source / "kernel" / "host_include").rglob("*.hpp")):
        for_hosts |= set(WORD.findall(code_of(h.read_text()))) - declared
    names = sorted(set(exported_names(a.kernel_lib)) | set(a.pretend_symbol))
    hosts_only = set()
    for sym in names:
        name = owner(sym)
        if name in for_hosts:
            hosts_only.add(name)
        elif name is not None and name not in declared:
            (pretended if sym in a.pretend_symbol else problems).append(f"{a.kernel_lib.name}: exports {sym}, which no kernel header a "
                            f"plugin uses declares ('{name}'; expected host-only code in "
                            "libpdyn_host)")

    lost_problems, lost_pretended = check_exports(a.source, a.kernel_lib, a.pretend_lost,
                                                  a.allow_new)
    problems += lost_problems
    pretended += lost_pretended

    for p in problems + pretended:
        print(p)
    print(f"check_sdk: {len(kernel_headers)} kernel headers, {len(used)} used by plugins; "
          f"{len(names)} exported pdyn symbols, for hosts only: {', '.join(sorted(hosts_only))}; "
          f"{len(problems) + len(pretended)} problems")
    if a.expect_pretended:
        want = len(a.pretend_header) + len(a.pretend_symbol) + len(a.pretend_lost)
        if problems or len(pretended) != want:
            print(f"check_sdk: expected exactly the {want} pretended problems")
            return 1
        return 0
    return 1 if problems or pretended else 0


if __name__ == "__main__":
    sys.exit(main())
