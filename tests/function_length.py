#!/usr/bin/env python3
"""No function over 80 lines in host/, conformance/, viewer/ and cli/
(issue 28): one function, one job, readable in one screen.

A function is a definition at namespace scope (pdyn's sources do not indent
namespaces): a line at column 0 that opens a parameter list, up to the `{`
that ends its header, through the `}` at column 0 that closes it. Its
length counts both lines.

Functions still over the limit are listed in tests/function_length.txt, each
with its length when listed: such a function may shrink but not grow, and
one that is back under the limit must leave the list (so the list stays the
list of work left). Anything else over the limit fails.

    function_length.py --source DIR [--self-test]

--self-test adds a file with an 83-line function and an 80-line one to the
files read, and passes only if exactly the first is reported beside what the
tree itself gives (the check of the check).
"""
import argparse
import pathlib
import re
import sys
import tempfile

LIMIT = 80
FOLDERS = ("host", "conformance", "viewer", "cli")
NOT_A_FUNCTION = re.compile(
    r"^(namespace|struct|class|enum|union|using|template|typedef|static_assert|extern|#|//|/\*)")


def functions(path):
    """(first line, length, name) of each namespace-scope function in `path`."""
    lines = path.read_text(errors="replace").split("\n")
    i = 0
    while i < len(lines):
        line = lines[i]
        if re.match(r"^[A-Za-z_]", line) and not NOT_A_FUNCTION.match(line) and "(" in line:
            j = i
            # The header ends at the line ending in `{` (a definition) or `;`
            # or `}` (a declaration, a one-line definition).
            while j < len(lines) and j < i + 10 and not re.search(r"[{;}]\s*$", lines[j]):
                j += 1
            if j < len(lines) and lines[j].rstrip().endswith("{") and not re.search(
                    r"=\s*\{\s*$", lines[j]):
                k = j + 1
                while k < len(lines) and not lines[k].startswith("}"):
                    k += 1
                name = re.sub(r"\(.*", "", line).split()[-1] if "(" in line else line
                yield i + 1, k - i + 1, name.lstrip("*&")
                i = k + 1
                continue
        i += 1


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--source", required=True, type=pathlib.Path)
    ap.add_argument("--self-test", action="store_true")
    a = ap.parse_args()
    extra = None
    if a.self_test:
        tmp = tempfile.TemporaryDirectory()
        extra = pathlib.Path(tmp.name) / "sample.cpp"
        body = "\n".join(f"  x += {k};" for k in range(78))
        extra.write_text(f"int too_long(int x) {{\n{body}\n  x += 1;\n  x += 2;\n  return x;\n}}\n\n"
                         f"int just_fits(int x) {{\n{body}\n}}\n")
    allowed = {}
    listing = a.source / "tests" / "function_length.txt"
    for row in listing.read_text().splitlines():
        if row.strip() and not row.startswith("#"):
            where, lines = row.split()[:2]
            allowed[where] = int(lines)
    files = [p for d in FOLDERS for p in sorted((a.source / d).rglob("*.cpp"))]
    if extra:
        files.append(extra)
    problems, seen = [], set()
    for path in files:
        rel = path.relative_to(a.source) if path.is_relative_to(a.source) else path
        for first, length, name in functions(path):
            key = f"{rel}:{name}"
            if key in allowed:
                seen.add(key)
                if length > allowed[key]:
                    problems.append(f"{rel}:{first}: {name} grew to {length} lines (listed at "
                                    f"{allowed[key]} in tests/function_length.txt: split it, "
                                    "do not grow it)")
                elif length <= LIMIT:
                    problems.append(f"{rel}:{first}: {name} is {length} lines now (expected it "
                                    "removed from tests/function_length.txt)")
            elif length > LIMIT:
                problems.append(f"{rel}:{first}: {name} is {length} lines (expected at most "
                                f"{LIMIT}: split it into functions that each do one thing)")
    for key in sorted(set(allowed) - seen):
        problems.append(f"tests/function_length.txt: {key} is not a function of the tree "
                        "(expected it removed from the list)")
    if a.self_test:
        mine = [p for p in problems if "sample.cpp" in p]
        ok = len(mine) == 1 and "too_long is 83 lines" in mine[0]
        print(f"function_length --self-test: {'ok' if ok else 'FAILED'}: {mine}")
        return 0 if ok else 1
    for p in problems:
        print(p)
    print(f"function_length: {len(files)} files, {len(allowed)} listed functions over "
          f"{LIMIT} lines; {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
