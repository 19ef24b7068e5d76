#!/usr/bin/env python3
"""No function over 80 lines in any product folder (issues 28 and 45): one
function, one job, readable in one screen.

The product folders are kernel/, host/, plugins/, conformance/, cli/,
viewer/, python/ and bench/; the files their C++ sources and headers
(.cpp, .cc, .hpp, .h).

A function is any body with a parameter list: a definition at namespace
scope, a member function defined in its class body (at any indentation), a
constructor with its member-initialiser list, an operator, a macro that
opens a body (PYBIND11_MODULE), and a lambda at namespace or class scope.
A lambda or block inside a function is part of that function. The sources
are read by a small tokenizer that skips comments, strings (raw strings
included), character literals and preprocessor lines (of an #if whose
branches do not each balance their brackets, only the first), then braces
are matched: a `{` is a function body when the header before it (since the
previous `;`, `{` or `}` of its scope) ends in a parameter list `)`
followed only by qualifiers (const, noexcept, override, final, mutable,
`-> type`, `requires ...`) or a member-initialiser list; `class`, `struct`, `union`, `namespace`,
`extern "C"` open scopes, `enum` and `= {` open initialisers. A function's
length runs from the first line of its header (template line included) to
its closing `}`, both counted.

Functions still over the limit are listed in tests/function_length.txt, each
with its length when listed: such a function may shrink but not grow, and
one that is back under the limit must leave the list (so the list stays the
list of work left). Anything else over the limit fails.

    function_length.py --source DIR [--self-test] [--list]

--self-test adds a file with an 83-line function and an 80-line one, at
namespace scope and as in-class members indented by two, among decoys (long
classes, namespaces and initialisers; braces in strings, comments,
character literals and the branches of an #if), and passes only if exactly
the two 83-line ones are reported beside what the tree itself gives (the
check of the check).
--list prints every function over 60 lines, longest first.
"""
import argparse
import pathlib
import re
import sys
import tempfile

LIMIT = 80
FOLDERS = ("kernel", "host", "plugins", "conformance", "cli", "viewer", "python", "bench")
SUFFIXES = (".cpp", ".cc", ".hpp", ".h")

TOKEN = re.compile(r"""
    (?P<ws>[ \t\r\f\v]+)
  | (?P<nl>\n)
  | (?P<line_comment>//[^\n]*)
  | (?P<block_comment>/\*.*?\*/)
  | (?P<raw>(?:u8|u|U|L)?R"(?P<delim>[^()\\ \n]{0,16})\()
  | (?P<string>(?:u8|u|U|L)?"(?:\\.|[^"\\\n])*")
  | (?P<char>(?:u8|u|U|L)?'(?:\\.|[^'\\\n])+')
  | (?P<number>\.?[0-9](?:[eEpP][+-]|'?[0-9A-Za-z_.])*)
  | (?P<ident>[A-Za-z_][A-Za-z_0-9]*)
  | (?P<op>::|->|\.\.\.|&&|\|\||==|!=|<=|>=|<<|\+\+|--|[-+*/%^&|!=<]=|.)
""", re.VERBOSE | re.DOTALL)

QUALIFIERS = {"const", "volatile", "noexcept", "override", "final", "mutable", "&", "&&",
              "constexpr", "consteval", "try"}
OPENERS = {"(": ")", "[": "]", "{": "}"}
CLOSERS = {")", "]", "}"}
CLASS_KEYS = {"class", "struct", "union"}
ACCESS = {"public", "private", "protected"}


def preprocessor(text):
    """`text` with its preprocessor lines blanked (newlines kept), and the
    line ranges [first, end) of the branches of each #if, in order."""
    out, groups, open_ = [], [], []
    lines = text.split("\n")
    i = 0
    while i < len(lines):
        # A directive runs on over lines ending in a backslash.
        j = i
        while lines[j].endswith("\\") and j + 1 < len(lines):
            j += 1
        directive = re.match(r"\s*#\s*(\w*)", lines[i])
        if directive:
            word = directive.group(1)
            if word.startswith("if"):
                open_.append([[j + 2, None]])
            elif word.startswith("el") and open_:
                open_[-1][-1][1] = i + 1
                open_[-1].append([j + 2, None])
            elif word == "endif" and open_:
                open_[-1][-1][1] = i + 1
                groups.append(open_.pop())
            out.extend([""] * (j - i + 1))
        else:
            out.extend(lines[i:j + 1])
        i = j + 1
    return "\n".join(out), groups


def balanced(toks):
    """Whether brackets of every kind open and close within `toks`."""
    depth = 0
    for t in toks:
        depth += 1 if t in OPENERS else -1 if t in CLOSERS else 0
        if depth < 0:
            return False
    return depth == 0


def tokens(text):
    """(token, line) of each token of C++ `text`, without comments, strings,
    character literals and preprocessor lines. Every branch of an #if is
    read when each opens and closes its own brackets; otherwise only the
    first (an `if (a) {` under #if and `if (b) {` under #else), so that
    brackets stay balanced."""
    text, groups = preprocessor(text)
    pos, line, out = 0, 1, []
    while pos < len(text):
        m = TOKEN.match(text, pos)
        kind = m.lastgroup
        if kind == "raw":
            end = text.find(")" + m.group("delim") + '"', m.end())
            end = len(text) if end < 0 else end + len(m.group("delim")) + 2
            line += text.count("\n", pos, end)
            pos = end
            continue
        if kind in ("ident", "number", "op"):
            out.append((m.group(), line))
        line += m.group().count("\n")
        pos = m.end()
    dropped = set()
    for branches in groups:
        parts = [[t for t, n in out if first <= n < end] for first, end in branches]
        if not all(balanced(part) for part in parts):
            for first, end in branches[1:]:
                dropped.update(range(first, end))
    return [(t, n) for t, n in out if n not in dropped]


def match_forward(toks, i):
    """Index of the closer of the group opened at toks[i]."""
    depth = 0
    for j in range(i, len(toks)):
        if toks[j] in OPENERS:
            depth += 1
        elif toks[j] in CLOSERS:
            depth -= 1
            if depth == 0:
                return j
    return len(toks) - 1


def match_back(toks, j):
    """Index of the opener of the group closed at toks[j]."""
    depth = 0
    for i in range(j, -1, -1):
        if toks[i] in CLOSERS:
            depth += 1
        elif toks[i] in OPENERS:
            depth -= 1
            if depth == 0:
                return i
    return 0


def skip_templates(h):
    """Index of the first token of header `h` after its `template <...>`
    clauses and `[[attributes]]`."""
    i = 0
    while i < len(h):
        if h[i] == "template" and i + 1 < len(h) and h[i + 1] == "<":
            depth, i = 0, i + 1
            while i < len(h):
                if h[i] in ("(", "["):
                    i = match_forward(h, i)
                elif h[i] == "<":
                    depth += 1
                elif h[i] == ">":
                    depth -= 1
                    if depth == 0:
                        break
                i += 1
            i += 1
        elif h[i] == "[" and i + 1 < len(h) and h[i + 1] == "[":
            i = match_forward(h, i) + 1
        else:
            return i
    return i


def top_level(h, start=0):
    """Indices of the tokens of `h` from `start` outside any (), [] or {}."""
    depth = 0
    for i in range(start, len(h)):
        if h[i] in CLOSERS:
            depth -= 1
        if depth == 0:
            yield i
        if h[i] in OPENERS:
            depth += 1


def tail_kind(t):
    """What follows a parameter list: 'body' (qualifiers only), 'init' (a
    member-initialiser list) or None (not a parameter list)."""
    j = 0
    while j < len(t):
        if t[j] in QUALIFIERS:
            j += 1
            if t[j - 1] in ("noexcept", "throw") and j < len(t) and t[j] == "(":
                j = match_forward(t, j) + 1
        elif t[j] == "throw" and j + 1 < len(t) and t[j + 1] == "(":
            j = match_forward(t, j + 1) + 1
        elif t[j] == "[" and j + 1 < len(t) and t[j + 1] == "[":
            j = match_forward(t, j) + 1
        elif t[j] in ("->", "requires"):
            return "body"
        elif t[j] == ":":
            return "init"
        else:
            return None
    return "body"


def is_lambda_introducer(h, close):
    """Whether the `]` at h[close] ends a lambda's capture list (not an
    array declarator, an attribute or operator[])."""
    if h[close] != "]":
        return False
    open_ = match_back(h, close)
    before = h[open_ - 1] if open_ > 0 else None
    if before == "operator" or before == "[" or (close > 0 and h[close - 1] == "]"):
        return False
    return before is None or not (re.match(r"\w", before) or before in (")", "]", ">"))


def lambda_before_brace(h):
    """Whether the `{` following header `h` opens a lambda's body."""
    j = len(h) - 1
    # A trailing return type: skip back to its arrow, if the arrow is near.
    for k in range(len(h) - 1, max(-1, len(h) - 12), -1):
        if h[k] == "->":
            j = k - 1
            break
        if h[k] in (";", ",", "=", "{", "}") or (h[k] in OPENERS and k > 0):
            break
    while j >= 0 and h[j] in QUALIFIERS:
        j -= 1
    if j < 0:
        return False
    if h[j] == ")":
        j = match_back(h, j) - 1
    return j >= 0 and is_lambda_introducer(h, j)


def function_name(h, open_):
    """The name of the function whose parameter list opens at h[open_]."""
    j = open_ - 1
    if j >= 0 and h[j] == ")" and j >= 2 and h[j - 2] == "operator":  # operator()
        return "operator()"
    if j >= 0 and h[j] == "]" and is_lambda_introducer(h, j):
        eq = [k for k in top_level(h) if h[k] == "=" and k < j]
        return (h[eq[-1] - 1] if eq else "lambda")
    if j >= 0 and h[j] == ">":  # f<T>(...): skip the template arguments
        depth = 0
        while j >= 0:
            depth += {">": 1, "<": -1}.get(h[j], 0)
            j -= 1
            if depth == 0:
                break
    for k in range(j, max(-1, j - 4), -1):
        if h[k] == "operator":
            return "operator" + "".join(h[k + 1:j + 1])
    parts = []
    while j >= 0 and (re.match(r"\w", h[j]) or h[j] == "~"):
        parts.insert(0, h[j])
        if j >= 1 and h[j - 1] == "~":
            parts.insert(0, "~")
            j -= 1
        if j >= 2 and h[j - 1] == "::" and re.match(r"\w", h[j - 2]):
            parts.insert(0, "::")
            j -= 2
        else:
            break
    return "".join(parts) or "?"


def classify(h):
    """What the `{` after header `h` (at its scope's top level) opens:
    ('function', name), ('class', name), ('namespace', None) or
    ('init', None)."""
    start = skip_templates(h)
    body = h[start:]
    if not body:
        return "init", None
    if body[-1] == "requires":
        return "init", None
    tops = list(top_level(h, start))
    if body == ["extern"] or (body[0] == "namespace" or (body[0] == "inline" and len(body) > 1
                                                           and body[1] == "namespace")):
        return "namespace", None
    if lambda_before_brace(h):
        close = len(h) - 1
        while h[close] != "]" and h[close] != ")":
            close -= 1
        if h[close] == ")":
            return "function", function_name(h, match_back(h, close))
        return "function", function_name(h, close + 1)
    for k in tops:
        if h[k] in CLASS_KEYS:
            name = next((h[m] for m in tops if m > k and re.match(r"\w", h[m])
                         and h[m] not in ("final", "alignas")), None)
            if name is not None and tops.index(k) + 1 < len(tops):
                after = h[tops[tops.index(k) + 1]]
                name = None if after in ("{", ":") else name
            return "class", name
        if h[k] == "enum":
            return "init", None
    for k in tops:
        if h[k] == "=" and (k == 0 or h[k - 1] != "operator"):
            return "init", None
    for k in tops:
        if h[k] != ")":
            continue
        kind = tail_kind(h[k + 1:])
        if kind is None:
            continue
        open_ = match_back(h, k)
        if open_ > 0 and h[open_ - 1] == "requires":
            return "init", None
        if kind == "init" and h[-1] not in (")", "}", "..."):
            return "init", None  # a member's brace initialiser
        return "function", function_name(h, open_)
    return "init", None


def functions(path):
    """(first line, length, name) of each function in `path` (see above)."""
    toks = tokens(path.read_text(errors="replace"))
    words = [t for t, _ in toks]
    scopes = []  # class names (None for namespaces) of the scopes we are in
    header, depth = [], 0  # the tokens since the last boundary; their nesting
    i = 0
    while i < len(toks):
        tok, line = toks[i]
        if tok == ";" and depth == 0:
            header = []
        elif tok == ":" and depth == 0 and [t for t, _ in header] in ([a] for a in ACCESS):
            header = []
        elif tok == "{" and depth > 0:
            h = [t for t, _ in header]
            if lambda_before_brace(h):
                kind, name = classify(h)
                end = match_forward(words, i)
                if kind == "function":
                    first = header[0][1]
                    yield first, toks[end][1] - first + 1, qualify(scopes, name)
                header += [("{", line), ("}", toks[end][1])]
                i = end + 1
                continue
            header.append((tok, line))
            depth += 1
        elif tok == "{":
            kind, name = classify([t for t, _ in header])
            if kind == "function":
                end = match_forward(words, i)
                first = header[0][1] if header else line
                yield first, toks[end][1] - first + 1, qualify(scopes, name)
                header = []
                i = end + 1
                continue
            if kind in ("class", "namespace"):
                scopes.append(name if kind == "class" else None)
                header = []
            else:
                header.append((tok, line))
                depth += 1
        elif tok == "}" and depth == 0:
            if scopes:
                scopes.pop()
            header = []
        else:
            if tok in OPENERS:
                depth += 1
            elif tok in CLOSERS:
                depth -= 1
            header.append((tok, line))
        i += 1


def qualify(scopes, name):
    """`name` prefixed with the classes it is defined in."""
    return "::".join([s for s in scopes if s] + [name])


SAMPLE_BODY = "\n".join(f"  x += {k};" for k in range(78))


def sample():
    """The self-test's file: two 83-line functions to report (one at
    namespace scope, one in a class body), two 80-line ones and decoys."""
    indented = SAMPLE_BODY.replace("\n", "\n  ")
    decoy_class = "\n".join(f"  int f{k}(int x) const {{ return x + {k}; }}" for k in range(90))
    decoy_table = ",\n".join(f"    {{{k}, \"{{\"}}" for k in range(90))
    tricky = "\n".join([
        '  const char* s = "}}}"; // }',
        "  char c = '}'; /* { */",
        '  auto raw = R"x(})x";',
        "  auto l = [&](int y) { return y + x; };",
        "  x = l(1'000);",
    ] * 14 + [
        "#ifdef SOMETHING",
        "  if (x) {",
        "#else",
        "  if (x > 1) {",
        "#endif",
        "    x += 1;",
        "  }",
    ])
    return f"""// braces in a comment: {{{{
int too_long(int x) {{
{SAMPLE_BODY}
  x += 1;
  x += 2;
  return x;
}}

int just_fits(int x) {{
{SAMPLE_BODY}
}}

namespace decoy {{
struct Table {{
  int key;
  const char* text;
}};
const Table kTable[] = {{
{decoy_table}
}};
class Many {{
 public:
  Many() : a_{{1}}, b_(2) {{}}
{decoy_class}
 private:
  int a_, b_;
}};
int tricky(int x) {{
{tricky}
  return x;
}}
}}  // namespace decoy

class Sample {{
 public:
  template <class T>
  auto member_too_long(T x) const -> T {{
  {indented}
    x += 1;
    return x;
  }}
  int member_just_fits(int x) const noexcept {{
  {indented}
  }}
}};
"""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--source", required=True, type=pathlib.Path)
    ap.add_argument("--self-test", action="store_true")
    ap.add_argument("--list", action="store_true")
    a = ap.parse_args()
    extra = None
    if a.self_test:
        tmp = tempfile.TemporaryDirectory()
        extra = pathlib.Path(tmp.name) / "sample.cpp"
        extra.write_text(sample())
    allowed = {}
    listing = a.source / "tests" / "function_length.txt"
    for row in listing.read_text().splitlines():
        if row.strip() and not row.startswith("#"):
            where, lines = row.split()[:2]
            allowed[where] = int(lines)
    files = [p for d in FOLDERS for p in sorted((a.source / d).rglob("*"))
             if p.suffix in SUFFIXES and p.is_file()]
    if extra:
        files.append(extra)
    problems, seen, found = [], set(), []
    for path in files:
        rel = path.relative_to(a.source) if path.is_relative_to(a.source) else path
        for first, length, name in functions(path):
            found.append((length, f"{rel}:{first}: {name}"))
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
    if a.list:
        for length, where in sorted(found, reverse=True):
            if length > 60:
                print(f"{length:4d} {where}")
    if a.self_test:
        mine = [p for p in problems if "sample.cpp" in p]
        ok = (len(mine) == 2 and "too_long is 83 lines" in mine[0]
              and "Sample::member_too_long is 83 lines" in mine[1])
        print(f"function_length --self-test: {'ok' if ok else 'FAILED'}: {mine}")
        return 0 if ok else 1
    for p in problems:
        print(p)
    print(f"function_length: {len(files)} files, {len(found)} functions, {len(allowed)} "
          f"listed over {LIMIT} lines; {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
