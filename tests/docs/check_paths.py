#!/usr/bin/env python3
"""docs.paths: every repository path that the docs and the sources' comments
name exists (issue 45), so that a moved or removed file cannot leave its old
name behind.

    check_paths.py --source-dir DIR [--self-test]

What is read:

- README.md and docs/**/*.md, whole (prose, code blocks and tables);
- the comments of the sources under the product folders (FOLDERS below):
  `//` and `/* */` comments in .cpp, .hpp and .h files, `#` comments in
  .py, .cmake, .sh and CMakeLists.txt files (the root's and cmake/'s too).

What is a repository path:

- a word that starts with one of the repository's top-level folders (the
  folders of its tracked files, e.g. kernel/, bench/, docs/) followed by `/`,
  and is not itself the tail of a longer path (`build/tests/...`,
  `${CMAKE_CURRENT_SOURCE_DIR}/docs/...` and `/usr/share/pdyn/configs` are
  not). Its trailing punctuation, a `:LINE[:COLUMN]` suffix and a `#anchor`
  are dropped. It exists if it is there from the root, or from a folder that
  holds the file naming it (tests/CMakeLists.txt names tests/docs/x.py as
  docs/x.py);
- in README.md and docs/, the target of a relative Markdown link
  `[text](target)`, from the page's own folder, and its `#anchor`, which
  must be a heading of the target page (GitHub's slugs).

Placeholders are not paths: a word with `*` (a glob), `<`, `{` or `$` (a
name to fill in, a brace list, a variable), `...` or a part in capitals
(`tests/scenes/shared/NAME`) is skipped (PLACEHOLDER below). Build output
and what the build installs are not repository paths: `build/`, `out/` are
not among the top-level folders, and a path the repository ignores
(.gitignore: `viewer/node_modules`) is not checked.

Prints `FILE:LINE: names PATH, which does not exist` for each, and exits 1 if
there is one. --self-test adds a sample source and a sample page naming two
missing paths, a missing anchor and an existing path, and passes only if
exactly the three missing ones are reported for them (the check of the
check).
"""
import argparse
import fnmatch
import os
import re
import subprocess
import sys
import tempfile

FOLDERS = ("kernel", "host", "plugins", "conformance", "cli", "viewer", "python", "bench", "tests",
           "scripts", "examples", "configs", "fuzz", "cmake")
HASH_COMMENTS = (".py", ".cmake", ".sh")
SLASH_COMMENTS = (".cpp", ".hpp", ".h")
SKIP_DIRS = {"node_modules", "__pycache__", ".git"}
PLACEHOLDER = re.compile(r"[*<{$]|\.\.\.")
CAPITALS = re.compile(r"(^|/)[A-Z][A-Z0-9_]*(/|$)")  # tests/scenes/shared/NAME
LINK = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s]+)\)|!\[[^\]]*\]\(([^)\s]+)\)")


def top_folders(src):
    """The repository's top-level folders: those of `git ls-files`, else the
    folders at the root but hidden ones, build* and out (build output)."""
    try:
        files = subprocess.run(["git", "-C", src, "ls-files"], check=True, text=True,
                               capture_output=True).stdout.split("\n")
        tops = {f.split("/")[0] for f in files if "/" in f}
    except (OSError, subprocess.CalledProcessError):
        tops = set()
    if not tops:
        tops = {d for d in os.listdir(src) if os.path.isdir(os.path.join(src, d))
                and not d.startswith((".", "build")) and d != "out"}
    return sorted(t for t in tops if not t.startswith("."))


def hash_comments(lines, shell):
    """(line number, text) of each `#` comment (not inside a quoted string;
    in shell only a `#` that starts a word)."""
    for n, line in enumerate(lines, 1):
        quote = None
        for i, c in enumerate(line):
            if quote:
                if c == "\\":
                    continue
                if c == quote:
                    quote = None
            elif c in "\"'":
                quote = c
            elif c == "#" and (not shell or i == 0 or line[i - 1] in " \t;(|&"):
                yield n, line[i + 1:]
                break


def slash_comments(lines):
    """(line number, text) of each line of `//` and `/* */` comments, outside
    string and character literals."""
    in_block = False
    for n, line in enumerate(lines, 1):
        i, quote, out = 0, None, []
        while i < len(line):
            c = line[i]
            if in_block:
                end = line.find("*/", i)
                out.append(line[i:] if end < 0 else line[i:end])
                if end < 0:
                    break
                in_block, i = False, end + 2
                continue
            if quote:
                if c == "\\":
                    i += 2
                    continue
                if c == quote:
                    quote = None
            elif c in "\"'" and not (c == "'" and i > 0 and line[i - 1].isalnum()):
                quote = c  # (a digit separator 1'000 is not a character literal)
            elif line.startswith("//", i):
                out.append(line[i + 2:])
                break
            elif line.startswith("/*", i):
                in_block, i = True, i + 2
                continue
            i += 1
        if out:
            yield n, " ".join(out)


def slug(heading):
    """GitHub's anchor of a Markdown heading."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def anchors(path, cache={}):
    """The anchors of a Markdown page's headings (outside code blocks)."""
    if path not in cache:
        found, seen, fence = set(), {}, False
        with open(path, encoding="utf-8", errors="replace") as f:
            for line in f:
                if line.startswith("```"):
                    fence = not fence
                m = None if fence else re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
                if m:
                    s = slug(m.group(1))
                    found.add(s if s not in seen else f"{s}-{seen[s]}")
                    seen[s] = seen.get(s, 0) + 1
                found.update(re.findall(r'<a (?:id|name)="([^"]+)"', line))
        cache[path] = found
    return cache[path]


class Checker:
    def __init__(self, src):
        self.src = os.path.abspath(src)
        self.tops = top_folders(self.src)
        self.word = re.compile(r"(?<![\w./$}-])((?:%s)/[^\s`'\"()\[\]<>|,;]*)"
                               % "|".join(map(re.escape, self.tops)))
        self.problems = []

    def rel(self, path):
        path = os.path.abspath(path)
        return os.path.relpath(path, self.src) if path.startswith(self.src + os.sep) else path

    def report(self, path, line, name):
        self.problems.append(f"{self.rel(path)}:{line}: names {name}, which does not exist")

    def ignored(self, name):
        """True if the root's .gitignore ignores `name` or a folder of it: build
        or install output (its patterns: NAME anywhere, /NAME from the root)."""
        if not hasattr(self, "_ignore"):
            self._ignore = []
            gitignore = os.path.join(self.src, ".gitignore")
            if os.path.isfile(gitignore):
                with open(gitignore, encoding="utf-8") as f:
                    self._ignore = [p.strip() for p in f if p.strip() and not p.startswith(("#", "!"))]
        parts = name.strip("/").split("/")
        for pattern in self._ignore:
            anchored, pattern = pattern.startswith("/"), pattern.strip("/")
            for k in range(1, len(parts) + 1):
                if fnmatch.fnmatchcase("/".join(parts[:k]) if anchored else parts[k - 1], pattern):
                    return True
        return False

    def exists(self, path, name):
        """`name` from the root, or from a folder that holds `path`."""
        if os.path.exists(os.path.join(self.src, name)):
            return True
        folder = os.path.dirname(os.path.abspath(path))
        while folder.startswith(self.src + os.sep) or folder == os.path.dirname(os.path.abspath(path)):
            if os.path.exists(os.path.join(folder, name)):
                return True
            parent = os.path.dirname(folder)
            if parent == folder or folder == self.src:
                break
            folder = parent
        return False

    def check_words(self, path, n, text):
        for m in self.word.finditer(text):
            name = m.group(1)
            if PLACEHOLDER.search(name):
                continue
            name = re.sub(r"#.*$", "", name)                 # an anchor
            name = re.sub(r"(:\d+)+[.:]?$", "", name)        # FILE:LINE[:COLUMN]
            name = name.rstrip(".:!?")                       # the sentence's punctuation
            if CAPITALS.search(name):
                continue
            if not self.exists(path, name) and not self.ignored(name):
                self.report(path, n, name)

    def check_links(self, path, n, line):
        for m in LINK.finditer(line):
            target = m.group(1) or m.group(2)
            if re.match(r"^[a-z]+:", target) or PLACEHOLDER.search(target) or CAPITALS.search(target):
                continue                                     # http:, mailto:, ...
            file, _, anchor = target.partition("#")
            full = os.path.normpath(os.path.join(os.path.dirname(path), file)) if file else path
            if not os.path.exists(full):
                self.report(path, n, target)
            elif anchor and full.endswith(".md") and anchor not in anchors(full):
                self.report(path, n, target)

    def check_page(self, path):
        with open(path, encoding="utf-8", errors="replace") as f:
            for n, line in enumerate(f, 1):
                self.check_words(path, n, line)
                self.check_links(path, n, line)

    def check_source(self, path):
        with open(path, encoding="utf-8", errors="replace") as f:
            lines = f.read().split("\n")
        name = os.path.basename(path)
        if name.endswith(SLASH_COMMENTS):
            comments = slash_comments(lines)
        else:
            comments = hash_comments(lines, shell=name.endswith(".sh"))
        for n, text in comments:
            self.check_words(path, n, text)

    def pages(self):
        found = [os.path.join(self.src, "README.md")]
        for root, dirs, files in os.walk(os.path.join(self.src, "docs")):
            dirs[:] = sorted(d for d in dirs if d not in SKIP_DIRS)
            found += [os.path.join(root, f) for f in sorted(files) if f.endswith(".md")]
        return found

    def sources(self):
        found = [os.path.join(self.src, "CMakeLists.txt")]
        for folder in FOLDERS:
            for root, dirs, files in os.walk(os.path.join(self.src, folder)):
                dirs[:] = sorted(d for d in dirs if d not in SKIP_DIRS)
                found += [os.path.join(root, f) for f in sorted(files)
                          if f.endswith(SLASH_COMMENTS + HASH_COMMENTS) or f == "CMakeLists.txt"]
        return found


SAMPLE_SOURCE = """// A sample source: its comments name kernel/src/no_such_file.cpp:12, and
/* kernel/include/pdyn/system.hpp, which exists. */
const char* sample = "kernel/src/not_a_comment.cpp";  // code, not a comment
"""
SAMPLE_PAGE = """# Sample

See [the missing page](no_such_page.md), [a missing anchor](#no-such-heading)
and [this heading](#sample).
"""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--source-dir", required=True)
    ap.add_argument("--self-test", action="store_true")
    a = ap.parse_args()
    checker = Checker(a.source_dir)
    pages, sources = checker.pages(), checker.sources()
    for page in pages:
        checker.check_page(page)
    for source in sources:
        checker.check_source(source)
    if a.self_test:
        with tempfile.TemporaryDirectory() as tmp:
            source, page = os.path.join(tmp, "sample.cpp"), os.path.join(tmp, "sample.md")
            with open(source, "w") as f:
                f.write(SAMPLE_SOURCE)
            with open(page, "w") as f:
                f.write(SAMPLE_PAGE)
            before = len(checker.problems)
            checker.check_source(source)
            checker.check_page(page)
            mine = [p.replace(tmp + os.sep, "") for p in checker.problems[before:]]
        want = ["sample.cpp:1: names kernel/src/no_such_file.cpp, which does not exist",
                "sample.md:3: names no_such_page.md, which does not exist",
                "sample.md:3: names #no-such-heading, which does not exist"]
        ok = mine == want
        print(f"docs.paths --self-test: {'ok' if ok else 'FAILED'}: {mine}")
        return 0 if ok else 1
    for p in checker.problems:
        print(p)
    print(f"docs.paths: {len(pages)} pages and the comments of {len(sources)} sources; "
          f"{len(checker.problems)} missing path(s)")
    return 1 if checker.problems else 0


if __name__ == "__main__":
    sys.exit(main())
