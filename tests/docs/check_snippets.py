#!/usr/bin/env python3
"""Every code snippet in pdyn's docs is checked, so the docs cannot drift.

  check_snippets.py --pdyn BUILD/bin/pdyn --source-dir SRC --cxx c++ \
      --include SRC/kernel/include --include SRC/conformance/include \
      --include /usr/include/eigen3 [--sdk-prefix PREFIX] [FILE.md ...]

Without FILE.md arguments it checks the shipped docs: README.md, docs/*.md,
plugins/*/*/README.md and examples/**/README.md. Each fenced block with a
language is checked by the function for its language:

  yaml   parsed; a whole scene is validated with `pdyn validate`, a fragment
         (a section, a list of plugin entries, one plugin entry, particle
         builders) is first merged into a small base scene
  cpp    compiled with -std=c++20 -fsyntax-only against the kernel and
         conformance headers, at namespace scope or else as a function body
  json   parsed
  cmake  the commands it calls exist (CMake's own or pdyn's package), and with
         --sdk-prefix the project is configured and built against that prefix
  sh     every `pdyn` command line: the subcommand exists and takes every
         option used (from `pdyn SUB --help`); the cheap self-contained ones
         are run; repository paths and CMake targets it names exist

HTML comments right before a fence (invisible on GitHub) steer the checker:

  <!-- snippet context: pdyn::System& system; pdyn::Vec3 mouse_point; -->
        names a C++ snippet uses without declaring them (the parameters of
        the function it is wrapped in)
  <!-- snippet file: cloth.csv -->
        the block is the content of a side file, created beside the scenes
        and CMake projects of the later blocks of the same doc
  <!-- snippet plugin: soft force -->
        the C++ block is a whole plugin (NAME and KIND): with --sdk-prefix it
        is also built as one against that install, and `pdyn check NAME`
        must pass every check on it
  <!-- snippet: not checked (REASON) -->
        an explicit opt-out, counted and printed; at most MAX_NOT_CHECKED

Prints one line per problem, `FILE:LINE: what is wrong` (LINE: the fence's
opening line, or the snippet's own line when the tool says where), then a
summary line; exits 1 if any block failed.

With --param-tables it checks, instead of the snippets, the `## Parameters`
table of each plugin README (plugins/*/*/README.md, or the FILE.md given,
whose folder names the plugin) against `pdyn plugins describe NAME`, both
ways: every parameter the plugin declares has a row, every row is a declared
parameter, and each row's type, default, unit and range (>=X, >X, <=X, <X,
[A, B], nonzero; other words in the range cell, such as "0..N-1, each once",
are prose) are the declared ones. A README whose plugin has no parameters
has a `## Parameters` section without a table. Each problem is reported at
the README's line: the row, or the table's header for a parameter missing
from it.
"""

import argparse
import collections
import copy
import glob
import json
import math
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time

import yaml

# More opt-outs than this and the test fails: an opt-out must stay the rare
# exception, not the way to make the test pass.
MAX_NOT_CHECKED = 5

# Languages that are fine without a checker (side files, program output).
# Any other language without a checker is a failure: a new kind of snippet
# needs a checker (or an explicit opt-out), not silence.
UNCHECKED_LANGUAGES = {"", "text", "csv"}

# A small scene that fragments are merged into: enough particles for the
# indices the docs use (ids up to 99 in the grid, 200 in all), groups named
# like the docs' examples (cloth, cloud), gravity, ten short steps.
BASE_SCENE = {
    "simulation": {"dt": 0.001, "steps": 10},
    "particles": [
        {"grid": {"origin": [0, 0, 1], "u": [0.1, 0, 0], "v": [0, 0.1, 0],
                  "nx": 10, "ny": 10, "mass": 0.01, "name": "cloth"}},
        {"cloud": {"n": 100, "box": {"min": [-1, -1, 1], "max": [1, 1, 2]},
                   "mass": 0.001, "seed": 1, "name": "cloud"}},
    ],
    "forces": [{"type": "gravity"}],
}
SCENE_SECTIONS = {"simulation", "output", "particles", "forces", "colliders", "constraints",
                  "checkpoint", "velocities", "special_bonds"}

# The fewest C++ blocks of one prelude worth precompiling it for (prelude_header).
PCH_MIN_BLOCKS = 4

CPP_PRELUDE = ["<pdyn/plugin.hpp>", "<pdyn/contact.hpp>", "<pdyn/targets.hpp>",
               "<pdyn/shape.hpp>", "<pdyn/pair.hpp>", "<pdyn/conformance.hpp>", "<cmath>"]

# pdyn subcommands run for real when their arguments are all available: they
# read only the source tree and write nothing outside the temporary folder.
RUNNABLE = {("validate",), ("run",), ("plugins",), ("plugins", "describe"), ("schema",),
            ("new",)}


class Block:
    def __init__(self, path, line, lang, text, notes):
        self.path = path          # as given (relative to the source dir for the docs)
        self.line = line          # 1-based line of the opening fence
        self.lang = lang
        self.text = text
        self.context = notes.get("context")
        self.side_file = notes.get("file")
        self.not_checked = notes.get("not checked")
        self.plugin = notes.get("plugin")


class Checker:
    def __init__(self, args):
        self.args = args
        self.src = os.path.abspath(args.source_dir)
        self.tmp = tempfile.mkdtemp(prefix="pdyn-docs-")
        self.failed_blocks = set()
        self.checked = {}
        self.not_checked = []
        self.side_files = {}      # doc path -> {name: text}, filled in document order
        self._help = {}
        self._kinds = None
        self._cmake_commands = None
        self._prelude_pch = {}    # with GoogleTest or not -> the prelude header, or None
        self._cpp_blocks = collections.Counter()  # with GoogleTest or not -> C++ blocks to compile
        # The shipped plugins only, as in schema.scenes: not a user's PDYN_PLUGIN_PATH.
        self.env = dict(os.environ)
        self.env.pop("PDYN_PLUGIN_PATH", None)

    # ---- reporting -------------------------------------------------------------------------

    def fail(self, block, message, line=None):
        print(f"{block.path}:{line or block.line}: {message}", flush=True)
        self.failed_blocks.add((block.path, block.line))

    def note(self, block, message, line=None):
        """What was done with a block that passed (with --verbose)."""
        if self.args.verbose:
            print(f"{block.path}:{line or block.line}: ok: {message}", flush=True)

    def pdyn(self, *argv, cwd=None):
        return subprocess.run([self.args.pdyn, *argv], cwd=cwd or self.src, env=self.env,
                              capture_output=True, text=True, timeout=120)

    def block_dir(self, block):
        name = re.sub(r"[^A-Za-z0-9]+", "_", f"{block.path}_{block.line}")
        d = os.path.join(self.tmp, name)
        os.makedirs(d, exist_ok=True)
        for file_name, text in self.side_files.get(block.path, {}).items():
            with open(os.path.join(d, file_name), "w") as f:
                f.write(text)
        return d

    # ---- yaml ------------------------------------------------------------------------------

    def plugin_kinds(self):
        """name -> force/solver/collider, from `pdyn plugins --json`."""
        if self._kinds is None:
            r = self.pdyn("plugins", "--json")
            if r.returncode != 0:
                sys.exit(f"check_snippets: `pdyn plugins --json` failed: {r.stderr}")
            self._kinds = {p["name"]: p["kind"] for p in json.loads(r.stdout)["plugins"]}
        return self._kinds

    def scene_from_fragment(self, block, data):
        """The base scene with the fragment merged in at its place, or None."""
        scene = copy.deepcopy(BASE_SCENE)
        kinds = self.plugin_kinds()

        def place_plugin(entry):
            kind = kinds.get(entry.get("type"))
            if kind is None:
                self.fail(block, f"yaml: unknown plugin type '{entry.get('type')}' "
                                 f"(pdyn plugins lists {', '.join(sorted(kinds))})")
                return False
            if kind == "solver":
                scene["simulation"]["solver"] = entry
            elif kind == "writer":                               # an output list entry
                placed.setdefault("output", []).append(entry)
            else:
                placed.setdefault(kind + "s", []).append(entry)
            return True

        placed = {}
        if isinstance(data, dict) and "type" in data:            # one plugin entry
            if not place_plugin(data):
                return None
        elif isinstance(data, dict) and data and set(data) <= SCENE_SECTIONS:
            for key, value in data.items():                      # some sections
                if isinstance(value, dict) and isinstance(scene.get(key), dict):
                    if key == "simulation" and {"steps", "duration"} & set(value):
                        # The fragment's length replaces the base's: one of the two only.
                        scene[key].pop("steps", None)
                    scene[key].update(value)
                else:
                    placed[key] = value
        elif isinstance(data, list) and data and all(isinstance(e, dict) for e in data):
            if all("type" in e for e in data):                   # plugin entries
                for entry in data:
                    if not place_plugin(entry):
                        return None
            elif not any("type" in e for e in data):             # particle builders
                placed["particles"] = data
            else:
                self.fail(block, "yaml: a list mixing plugin entries and particles")
                return None
        else:
            self.fail(block, "yaml: neither a scene, nor scene sections, nor plugin "
                             "entries, nor particles")
            return None
        # A section the fragment shows replaces the base's: its indices and
        # groups refer to its own particles.
        scene.update(placed)
        return scene

    def check_yaml(self, block):
        try:
            docs = list(yaml.safe_load_all(block.text))
        except yaml.YAMLError as e:
            mark = getattr(e, "problem_mark", None)
            line = block.line + 1 + mark.line if mark else None
            self.fail(block, f"yaml: does not parse: {getattr(e, 'problem', e)}", line)
            return
        if len(docs) != 1:
            self.fail(block, f"yaml: {len(docs)} documents, expected one")
            return
        data = docs[0]
        d = self.block_dir(block)
        missing = [f for f in side_file_names(data) if not os.path.exists(os.path.join(d, f))]
        if missing:
            self.fail(block, f"yaml: names {', '.join(missing)}, which the doc does not show "
                             f"before it (show it in a block marked <!-- snippet file: "
                             f"{missing[0]} -->, or mark this one not checked)")
            return
        scene_path = os.path.join(d, "scene.yaml")
        whole = isinstance(data, dict) and "simulation" in data and "particles" in data
        if whole:
            # The text itself, so that pdyn's scene.yaml:LINE is the doc's line.
            with open(scene_path, "w") as f:
                f.write(block.text)
        else:
            scene = self.scene_from_fragment(block, data)
            if scene is None:
                return
            with open(scene_path, "w") as f:
                yaml.safe_dump(scene, f, default_flow_style=None, sort_keys=False)
        r = self.pdyn("validate", scene_path, "--quiet", cwd=d)
        if r.returncode != 0:
            message = first_line(r.stderr) or f"exit status {r.returncode}"
            line = None
            m = re.match(re.escape(scene_path) + r":(\d+):(?:\d+:)?\s*(.*)", message)
            if m:
                message = m.group(2)
                if whole:
                    line = block.line + int(m.group(1))
            kind = "scene" if whole else "fragment (in the base scene)"
            self.fail(block, f"yaml: pdyn validate refuses the {kind}: {message}", line)
        else:
            self.note(block, "pdyn validate: the scene" if whole else
                      "pdyn validate: the fragment merged into the base scene")

    # ---- cpp -------------------------------------------------------------------------------

    def include_flags(self):
        flags = []
        for inc in self.args.include:
            flags += ["-isystem" if "eigen" in inc.lower() else "-I", inc]
        return flags

    def prelude_header(self, gtest):
        """The prelude every block is compiled after, as a header precompiled
        once (GCC's .gch beside it): parsing the SDK, Eigen and GoogleTest is
        most of a block's compile time. None if the compiler cannot make
        one, or if fewer than PCH_MIN_BLOCKS blocks will compile after it:
        GCC takes about three times as long to write the header (150 MB) as
        to parse it once, so a header for one or two blocks costs more than
        it saves. Blocks then compile without it, the same way."""
        if self._cpp_blocks[gtest] < PCH_MIN_BLOCKS:
            return None
        if gtest not in self._prelude_pch:
            d = os.path.join(self.tmp, "prelude-gtest" if gtest else "prelude")
            os.makedirs(d, exist_ok=True)
            header = os.path.join(d, "prelude.hpp")
            with open(header, "w") as f:
                f.write("\n".join(cpp_prelude(gtest)) + "\n")
            r = subprocess.run([self.args.cxx, "-std=c++20", "-x", "c++-header"]
                               + self.include_flags() + [header, "-o", header + ".gch"],
                               capture_output=True, text=True, timeout=300, cwd=self.src)
            self._prelude_pch[gtest] = header if r.returncode == 0 else None
        return self._prelude_pch[gtest]

    def compile_cpp(self, source, d, name, gtest=False):
        path = os.path.join(d, name)
        with open(path, "w") as f:
            f.write(source)
        cmd = [self.args.cxx, "-std=c++20", "-fsyntax-only", "-x", "c++"] + self.include_flags()
        # The source begins with the same includes, which the header's guards
        # then skip: a block compiles the same with the header or without.
        header = self.prelude_header(gtest)
        if header:
            cmd += ["-include", header]
        r = subprocess.run(cmd + [path], capture_output=True, text=True, timeout=300,
                           cwd=self.src)
        if r.returncode == 0:
            return None
        errors = [l for l in r.stderr.splitlines() if re.search(r"\berror\b", l)]
        return errors[0] if errors else first_line(r.stderr) or "the compiler failed"

    def check_cpp(self, block):
        lines = block.text.split("\n")
        gtest = uses_gtest(block.text)
        prelude = cpp_prelude(gtest)
        # `#line` makes the compiler say the doc's file and line.
        here = f'#line {block.line + 1} "{block.path}"'
        d = self.block_dir(block)
        # Statements: in a function whose parameters are the snippet's
        # context; its #include lines go before the function.
        params = ", ".join(p.strip() for p in (block.context or "").split(";") if p.strip())
        hoisted, body = [], []
        for k, l in enumerate(lines):
            if l.lstrip().startswith("#"):
                hoisted += [f'#line {block.line + 1 + k} "{block.path}"', l]
                body.append("")
            else:
                body.append(l)
        wrapped = prelude + hoisted + [f"void pdyn_doc_snippet({params}) {{", here] + body + ["}"]

        # A block passes if it compiles either way. Statements (a block that
        # names its context, or asserts outside a TEST) are tried as a body
        # first: each compile costs seconds, and the other one would fail.
        wrapped_error = None
        if not block.plugin and statements_first(block):
            wrapped_error = self.compile_cpp("\n".join(wrapped) + "\n", d, "wrapped.cpp", gtest)
            if wrapped_error is None:
                return self.note(block, f"compiles as the body of a function({params})")
        # Declarations (a class, a plugin): as they are, at namespace scope.
        error = self.compile_cpp("\n".join(prelude + [here] + lines) + "\n", d, "snippet.cpp", gtest)
        if error is None and block.plugin:
            return self.check_plugin(block, d)
        if error is None:
            return self.note(block, "compiles at namespace scope")
        if wrapped_error is None:
            wrapped_error = self.compile_cpp("\n".join(wrapped) + "\n", d, "wrapped.cpp", gtest)
        if wrapped_error is None:
            return self.note(block, f"compiles as the body of a function({params})")
        # Both failed: report the attempt that got further into the snippet.
        if error_line(error, block.path) > error_line(wrapped_error, block.path):
            wrapped_error = error
        m = re.match(re.escape(block.path) + r":(\d+):(?:\d+:)?\s*(?:error:\s*)?(.*)",
                     wrapped_error)
        if m:
            self.fail(block, f"cpp: {m.group(2)}", int(m.group(1)))
        else:
            self.fail(block, f"cpp: {wrapped_error}")

    def check_plugin(self, block, d):
        """A whole plugin: built against the SDK as its author would, then
        `pdyn check NAME` on it (every row must pass)."""
        name, kind = block.plugin.split()
        if not self.args.sdk_prefix:
            return self.note(block, "compiles (a plugin; built and checked only with --sdk-prefix)")
        with open(os.path.join(d, f"{name}.cpp"), "w") as f:
            f.write(block.text)
        with open(os.path.join(d, "CMakeLists.txt"), "w") as f:
            f.write(f"cmake_minimum_required(VERSION 3.25)\nproject({name} LANGUAGES CXX)\n"
                    f"find_package(pdyn REQUIRED)\n"
                    f"pdyn_add_plugin({name} KIND {kind} SOURCES {name}.cpp)\n")
        error = self.build_project(d)
        if error:
            return self.fail(block, f"cpp: the plugin {name} does not build: {error}")
        r = self.pdyn("check", name, "--plugin-path", os.path.join(d, "build"))
        if r.returncode != 0:
            rows = [l.strip() for l in r.stdout.splitlines() if re.search(r"\bFAIL", l)]
            return self.fail(block, f"cpp: `pdyn check {name}` fails on the plugin as written: "
                                    f"{'; '.join(rows) or first_line(r.stderr + r.stdout)}")
        self.note(block, f"built as the plugin {name} and passed `pdyn check {name}`")

    def build_project(self, d):
        """Configures and builds the CMake project in `d` against the SDK
        prefix; the first error line, or None."""
        build = os.path.join(d, "build")
        for what, cmd in [
                ("configure", [self.args.cmake, "-S", d, "-B", build, "-G", self.args.generator,
                               f"-DCMAKE_CXX_COMPILER={self.args.cxx}",
                               f"-DCMAKE_PREFIX_PATH={self.args.sdk_prefix}",
                               "-DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF"]),
                ("build", [self.args.cmake, "--build", build])]:
            r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
            if r.returncode != 0:
                out = r.stderr + r.stdout
                errors = [l for l in out.splitlines() if "rror" in l]
                return f"{what} against {self.args.sdk_prefix} failed: " \
                       f"{(errors or [first_line(out)])[0].strip()}"
        return None

    # ---- json ------------------------------------------------------------------------------

    def check_json(self, block):
        try:
            json.loads(block.text)
        except json.JSONDecodeError as e:
            self.fail(block, f"json: does not parse: {e.msg}", block.line + e.lineno)
            return
        self.note(block, "parses")

    # ---- cmake -----------------------------------------------------------------------------

    def cmake_commands(self):
        """CMake's own commands and the functions pdyn's package defines."""
        if self._cmake_commands is None:
            r = subprocess.run([self.args.cmake, "--help-command-list"], capture_output=True,
                               text=True, check=True)
            names = set(r.stdout.split())
            for f in glob.glob(os.path.join(self.src, "cmake", "*.cmake*")):
                names |= set(re.findall(r"^\s*(?:function|macro)\s*\(\s*(\w+)",
                                        open(f).read(), re.M | re.I))
            self._cmake_commands = {n.lower() for n in names}
        return self._cmake_commands

    def check_cmake(self, block):
        text = re.sub(r"#.*", "", block.text)
        for k, l in enumerate(block.text.split("\n")):
            m = re.match(r"\s*(\w+)\s*\(", re.sub(r"#.*", "", l))
            if m and m.group(1).lower() not in self.cmake_commands():
                self.fail(block, f"cmake: unknown command {m.group(1)}() (neither CMake's "
                                 "nor pdyn's package's)", block.line + 1 + k)
        # pdyn_add_plugin's KIND: the values its own check accepts.
        plugin_cmake = open(os.path.join(self.src, "cmake", "PdynPlugin.cmake")).read()
        kinds = re.search(r'ARG_KIND MATCHES "\^\(([\w|]+)\)\$"', plugin_cmake).group(1).split("|")
        sources = []
        for m in re.finditer(r"pdyn_add_plugin\s*\(([^)]*)\)", text):
            words = m.group(1).split()
            if "KIND" not in words or words.index("KIND") + 1 >= len(words):
                self.fail(block, "cmake: pdyn_add_plugin without KIND")
                continue
            kind = words[words.index("KIND") + 1]
            if kind not in kinds:
                self.fail(block, f"cmake: pdyn_add_plugin KIND {kind}: expected one of "
                                 f"{', '.join(kinds)}")
            if "SOURCES" in words:
                sources += [w for w in words[words.index("SOURCES") + 1:] if not w.isupper()]
        # Variables a plugin project gets from find_package(pdyn).
        config = open(os.path.join(self.src, "cmake", "pdynConfig.cmake.in")).read()
        for var in set(re.findall(r"\$\{(PDYN_\w+)\}", text)):
            if not re.search(r"set(_and_check)?\(\s*" + var + r"\b", config + plugin_cmake):
                self.fail(block, f"cmake: ${{{var}}} is not set by find_package(pdyn)")
        if "find_package(pdyn" not in text or not self.args.sdk_prefix:
            return self.note(block, "calls only commands that exist")
        # For real: configure and build it against the installed SDK, with the
        # source files the doc shows.
        d = self.block_dir(block)
        missing = [s for s in sources if not os.path.exists(os.path.join(d, s))]
        if missing:
            self.fail(block, f"cmake: the doc does not show {', '.join(missing)} (mark its "
                             f"block <!-- snippet file: {missing[0]} -->)")
            return
        with open(os.path.join(d, "CMakeLists.txt"), "w") as f:
            f.write(block.text)
        started = time.monotonic()
        error = self.build_project(d)
        if error:
            return self.fail(block, f"cmake: {error}")
        self.note(block, f"configured and built against {self.args.sdk_prefix} with "
                         f"{', '.join(sources)} in {time.monotonic() - started:.0f} s")

    # ---- sh --------------------------------------------------------------------------------

    def cli_help(self, path):
        """Subcommands, options and which options take a value, of `pdyn PATH... --help`."""
        if path not in self._help:
            r = self.pdyn(*path, "--help")
            subs, options, valued = set(), set(), set()
            section = None
            for l in r.stdout.splitlines():
                if re.match(r"^[A-Z][A-Za-z ]*:\s*$", l):    # CLI11: "Options:", "Subcommands:"
                    section = l.split(":")[0].lower()
                    continue
                # An entry, not the continuation of a long description.
                m = re.match(r"^\s{1,4}(\S.*?)(?:\s{2,}|$)", l)
                if not m:
                    continue
                head = m.group(1)
                if section == "subcommands":
                    subs.add(head.split()[0])
                elif head.startswith("-"):
                    names = head.split()[0].split(",")
                    options |= set(names)
                    if len(head.split()) > 1:      # `--set TEXT ...`: takes a value
                        valued |= set(names)
            self._help[path] = (subs, options, valued)
        return self._help[path]

    def check_sh(self, block):
        # Join continued lines, drop prompts; keep each command's doc line.
        commands, pending, start = [], "", None
        for k, l in enumerate(block.text.split("\n")):
            l = re.sub(r"^\s*\$ ", "", l)
            start = block.line + 1 + k if not pending else start
            if l.rstrip().endswith("\\"):
                pending += l.rstrip()[:-1] + " "
                continue
            commands.append((start, pending + l))
            pending = ""
        for line, text in commands:
            try:
                lex = shlex.shlex(text, posix=True, punctuation_chars=True)
                lex.whitespace_split = True
                lex.commenters = "#"
                tokens = list(lex)
            except ValueError as e:
                self.fail(block, f"sh: does not parse: {e}", line)
                continue
            for words in simple_commands(tokens):
                self.check_sh_paths(block, line, words)
                if words and os.path.basename(words[0]) == "pdyn":
                    self.check_pdyn_command(block, line, words[1:])

    def check_sh_paths(self, block, line, words):
        """Repository files and CMake targets the command names exist."""
        for w in words:
            if re.match(r"^(scripts|configs|examples|docs|tests|cli|kernel|plugins)/[\w./-]+$", w) \
                    and not os.path.exists(os.path.join(self.src, w)):
                self.fail(block, f"sh: {w} does not exist", line)
        if words[:1] == ["cmake"] and "--target" in words:
            target = words[words.index("--target") + 1]
            if target not in cmake_targets(self.src):
                self.fail(block, f"sh: no CMake target {target}", line)

    def check_pdyn_command(self, block, line, args):
        path = ()
        while args and args[0] in self.cli_help(path)[0]:
            path, args = path + (args[0],), args[1:]
        if not path and not (args and args[0] in self.cli_help(())[1]):
            what = f"unknown subcommand '{args[0]}'" if args else "no subcommand"
            self.fail(block, f"sh: pdyn: {what} (pdyn --help lists "
                             f"{', '.join(sorted(self.cli_help(())[0]))})", line)
            return
        _, options, valued = self.cli_help(path)
        positionals, opts, k = [], [], 0
        while k < len(args):
            # `[--seed N]`: an optional option in a usage line.
            bracketed = args[k].startswith("[")
            word = args[k].strip("[]") if bracketed else args[k]
            if re.match(r"^--?[A-Za-z]", word):
                name = word.split("=")[0]
                if name not in options:
                    self.fail(block, f"sh: pdyn {' '.join(path)}: unknown option {name} "
                                     f"(pdyn {' '.join(path)} --help: "
                                     f"{', '.join(sorted(options))})", line)
                    return
                value = None
                if name in valued and "=" not in word and k + 1 < len(args):
                    value, k = args[k + 1], k + 1
                    if bracketed:
                        value = value.rstrip("]")
                opts.append((name, value))
            else:
                positionals.append(word)
            k += 1
        self.note(block, f"pdyn {' '.join(path)} takes {' '.join(o for o, _ in opts) or 'no options'}",
                  line)
        self.run_pdyn_command(block, line, path, positionals, opts)

    def run_pdyn_command(self, block, line, path, positionals, opts):
        """Runs the command if it is cheap and all it needs is in the source tree."""
        if path not in RUNNABLE or any(o == "--help" for o, _ in opts):
            return
        for o, v in opts:
            if o == "--plugin-path" and not os.path.isdir(os.path.join(self.src, v or "")):
                return                               # a user's plugin: syntax only
        # Its own folder: two `pdyn new` of one block must not collide.
        cwd = os.path.join(self.block_dir(block), f"line{line}")
        os.makedirs(cwd, exist_ok=True)
        argv = list(path)
        if path in {("validate",), ("run",)}:
            # A run is validated, with its overrides: --set paths drift too.
            if not positionals or not os.path.isfile(os.path.join(self.src, positionals[0])):
                return                               # a user's scene.yaml: syntax only
            argv = ["validate", os.path.join(self.src, positionals[0]), "--quiet"]
            keep = {"--set", "--plugin-path"}
        elif path == ("plugins", "describe"):
            if not positionals or positionals[0] not in self.plugin_kinds():
                return
            argv += positionals[:1]
            keep = {"--plugin-path"}
        elif path == ("new",):
            argv += positionals[:2]                  # never a DIR of the doc's: cwd is temporary
            keep = set()
        else:                                        # plugins, schema: output to stdout
            keep = {"--plugin-path", "--json"}
        for o, v in opts:
            if o in keep:
                argv += [o] + ([os.path.join(self.src, v) if o == "--plugin-path" else v]
                               if v is not None else [])
        r = self.pdyn(*argv, cwd=cwd)
        if r.returncode == 0:
            self.note(block, f"ran `pdyn {' '.join(argv)}`", line)
        else:
            self.fail(block, f"sh: `pdyn {' '.join(argv)}` failed ({r.returncode}): "
                             f"{first_line(r.stderr)}", line)

    # ---- python ----------------------------------------------------------------------------

    def check_python(self, block):
        """A block with `if __name__ == "__main__":` is a whole script, run alone; the
        others of a doc run in order in one interpreter (a tour: later blocks use the
        names of earlier ones). Run from a temporary folder holding a link to configs/,
        with the build's Python package on PYTHONPATH; the first failing block fails."""
        if self.args.python == "off":
            self.note(block, "not run: this build has no Python module")
            return
        if not hasattr(self, "_python_results"):
            self._python_results = {}
        if block.path not in self._python_results:
            self._python_results[block.path] = self.run_python_doc(block.path)
        problem = self._python_results[block.path].get(block.line)
        if problem:
            self.fail(block, f"python: {problem}")
        else:
            self.note(block, "ran")

    def run_python_doc(self, path):
        blocks = [b for b in read_blocks(os.path.join(self.src, path), self.src)
                  if b.lang == "python" and b.not_checked is None]
        d = self.block_dir(Block(path, 0, "python", "", {}))
        if not os.path.exists(os.path.join(d, "configs")):
            os.symlink(os.path.join(self.src, "configs"), os.path.join(d, "configs"))
        env = dict(self.env)
        package = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(self.args.pdyn))),
                               "python")
        env["PYTHONPATH"] = package + os.pathsep + env.get("PYTHONPATH", "")
        env["MPLBACKEND"] = "Agg"
        results, tour = {}, []
        for b in blocks:
            if 'if __name__ == "__main__":' not in b.text:
                tour.append(b)
                continue
            script = os.path.join(d, f"block{b.line}.py")
            with open(script, "w") as f:
                f.write(b.text)
            r = subprocess.run([sys.executable, script], cwd=d, env=env, capture_output=True,
                               text=True, timeout=300)
            if r.returncode != 0:
                results[b.line] = first_line(r.stderr.strip().splitlines()[-1] if r.stderr.strip()
                                             else f"exit status {r.returncode}")
        if tour:
            runner = ["import sys, traceback", "ns = {'__name__': '__main__'}"]
            for b in tour:
                runner += [f"try:\n    exec(compile({b.text!r}, {f'{path}:{b.line}'!r}, 'exec'), ns)",
                           f"except BaseException as e:\n    print('FAILED {b.line}', "
                           "''.join(traceback.format_exception_only(e)).strip(), "
                           "file=sys.stderr)\n    sys.exit(1)"]
            script = os.path.join(d, "tour.py")
            with open(script, "w") as f:
                f.write("\n".join(runner) + "\n")
            r = subprocess.run([sys.executable, script], cwd=d, env=env, capture_output=True,
                               text=True, timeout=600)
            m = re.search(r"^FAILED (\d+) (.*)", r.stderr, re.M | re.S)
            if m:
                results[int(m.group(1))] = m.group(2).strip().splitlines()[-1]
                # the blocks after it did not run
                for b in tour:
                    if b.line > int(m.group(1)):
                        results[b.line] = f"not run: the block at line {m.group(1)} failed"
            elif r.returncode != 0:
                for b in tour:
                    results[b.line] = f"the tour failed: {first_line(r.stderr)}"
        return results

    # ---- driver ----------------------------------------------------------------------------

    def check(self, block):
        if block.not_checked is not None:
            self.not_checked.append(block)
            return
        checker = getattr(self, f"check_{block.lang}", None)
        if checker is None:
            if block.lang not in UNCHECKED_LANGUAGES:
                self.fail(block, f"no checker for ```{block.lang} blocks (add one, or mark "
                                 "the block <!-- snippet: not checked (REASON) -->)")
            return
        self.checked[block.lang] = self.checked.get(block.lang, 0) + 1
        try:
            checker(block)
        except subprocess.TimeoutExpired as e:
            self.fail(block, f"{block.lang}: timed out: {' '.join(map(str, e.cmd))}")

    def run(self, docs):
        blocks = [block for doc in docs for block in read_blocks(doc, self.src)]
        self._cpp_blocks.update(uses_gtest(block.text) for block in blocks
                                if block.lang == "cpp" and block.not_checked is None)
        for block in blocks:
            self.check(block)
            if block.side_file:
                self.side_files.setdefault(block.path, {})[block.side_file] = block.text
        for b in self.not_checked:
            print(f"{b.path}:{b.line}: not checked ({b.lang}): {b.not_checked}")
        if len(self.not_checked) > MAX_NOT_CHECKED:
            print(f"docs.snippets: {len(self.not_checked)} blocks not checked, more than "
                  f"the {MAX_NOT_CHECKED} allowed (MAX_NOT_CHECKED in {__file__})")
        total = sum(self.checked.values())
        by_lang = ", ".join(f"{lang} {n}" for lang, n in sorted(self.checked.items()))
        print(f"docs.snippets: {total} checked ({by_lang}), {len(self.not_checked)} not "
              f"checked, {len(self.failed_blocks)} failed")
        return len(self.failed_blocks) == 0 and len(self.not_checked) <= MAX_NOT_CHECKED


# ---- plugin parameter tables (--param-tables) ------------------------------------------------

# The columns of a README's parameter table, as `pdyn plugins describe` prints them.
TABLE_COLUMNS = ["key", "type", "default", "unit", "range", "meaning"]
COMPARED_COLUMNS = ["type", "default", "unit", "range"]
KIND_FOLDERS = {"forces": "force", "solvers": "solver", "colliders": "collider",
                "writers": "writer", "constraints": "constraint"}
NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|-?pi"


class ParamTables(Checker):
    """Each plugin README's `## Parameters` table against `pdyn plugins describe NAME`."""

    def __init__(self, args):
        super().__init__(args)
        self.plugins_checked = 0
        self.params_checked = 0
        self.problems = 0

    def fail_at(self, path, line, message):
        print(f"{path}:{line}: {message}", flush=True)
        self.failed_blocks.add((path, line))
        self.problems += 1

    def describe(self, name):
        """(kind, {key: {column: text}}) from `pdyn plugins describe NAME`, or (None, error)."""
        r = self.pdyn("plugins", "describe", name)
        if r.returncode != 0:
            return None, first_line(r.stderr)
        lines = r.stdout.splitlines()
        kind = lines[0].split()[0] if lines and lines[0].split() else ""
        header = next((i for i, l in enumerate(lines) if l.split()[:2] == ["KEY", "TYPE"]), None)
        if header is None:
            if not any(l.strip() == "no parameters" for l in lines):
                return None, "neither a parameter table nor 'no parameters' in its output"
            return kind, {}
        # The columns are padded to their widest entry: each starts where its title does.
        starts = [lines[header].index(c.upper()) for c in TABLE_COLUMNS]
        params = {}
        for l in lines[header + 1:]:
            if not l.strip():
                continue
            cells = [l[a:b].strip() for a, b in zip(starts, starts[1:] + [None])]
            params[cells[0]] = dict(zip(TABLE_COLUMNS, cells))
        return kind, params

    def readme_table(self, doc, path):
        """(line of `## Parameters`, line of the table's header, {key: (line, {column: text})}),
        reporting malformed tables; None without a Parameters section."""
        lines = open(doc).read().split("\n")
        section = next((i for i, l in enumerate(lines) if re.match(r"^##\s+Parameters\s*$", l)),
                       None)
        if section is None:
            return None
        end = next((i for i in range(section + 1, len(lines)) if re.match(r"^#{1,2}\s", lines[i])),
                   len(lines))
        header, columns, rows = None, None, {}
        for i in range(section + 1, end):
            if not lines[i].strip().startswith("|"):
                if header is not None and rows:
                    break                                # the first table only
                continue
            cells = [c.strip() for c in re.split(r"(?<!\\)\|", lines[i].strip().strip("|"))]
            if header is None:
                header, columns = i + 1, [c.lower() for c in cells]
                missing = [c for c in TABLE_COLUMNS if c not in columns]
                if missing:
                    self.fail_at(path, header, f"parameter table: no column {', '.join(missing)} "
                                               f"(expected | {' | '.join(TABLE_COLUMNS)} |)")
                continue
            if all(re.fullmatch(r":?-+:?", c) for c in cells):
                continue
            row = dict(zip(columns, cells))
            key = row.get("key", "").strip("`")
            if key in rows:
                self.fail_at(path, i + 1, f"parameter '{key}' has a second row (the first at "
                                          f"line {rows[key][0]})")
                continue
            rows[key] = (i + 1, row)
        return section + 1, header, rows

    def check_readme(self, doc, name, kind_folder=None):
        path = os.path.relpath(os.path.abspath(doc), self.src)
        kind, declared = self.describe(name)
        if kind is None:
            self.fail_at(path, 1, f"`pdyn plugins describe {name}` failed: {declared}")
            return
        self.plugins_checked += 1
        if kind_folder and KIND_FOLDERS.get(kind_folder) != kind:
            self.fail_at(path, 1, f"'{name}' is a {kind} plugin, but its README is under "
                                  f"plugins/{kind_folder}/")
        table = self.readme_table(doc, path)
        if table is None:
            self.fail_at(path, 1, "no `## Parameters` section (a table of the parameters, or "
                                  "'None.' for a plugin without any)")
            return
        section, header, rows = table
        where = header or section
        for key in declared:
            if key not in rows:
                self.fail_at(path, where, f"parameter '{key}' ({declared[key]['type']}) is declared "
                                          f"by `pdyn plugins describe {name}` but has no row in "
                                          "the README's table")
        for key, (line, row) in rows.items():
            if key not in declared:
                self.fail_at(path, line, f"parameter '{key}' is documented but `pdyn plugins "
                                         f"describe {name}` does not declare it (it declares "
                                         f"{', '.join(declared) or 'no parameters'})")
                continue
            self.params_checked += 1
            want = declared[key]
            for column in COMPARED_COLUMNS:
                same = {"type": same_words, "default": same_default, "unit": same_unit,
                        "range": same_range}[column]
                problem = same(row.get(column, ""), want[column])
                if problem:
                    self.fail_at(path, line, f"parameter '{key}': {column} '{row.get(column, '')}'"
                                             f" in the README, '{want[column]}' from `pdyn "
                                             f"plugins describe {name}`{problem}")

    def run(self, docs):
        shipped = not docs
        if shipped:
            docs = sorted(glob.glob(os.path.join(self.src, "plugins", "*", "*", "README.md")))
            # Both ways: every shipped plugin has a README where this finds it.
            for name, kind in sorted(self.plugin_kinds().items()):
                readme = os.path.join(self.src, "plugins", kind + "s", name, "README.md")
                if not os.path.isfile(readme):
                    print(f"plugins/{kind}s/{name}/README.md: missing: the {kind} plugin '{name}' "
                          "has no README with its parameter table", flush=True)
                    self.failed_blocks.add((f"plugins/{kind}s/{name}/README.md", 0))
                    self.problems += 1
        for doc in docs:
            parts = os.path.abspath(doc).split(os.sep)
            folder = parts[-3] if shipped else None
            self.check_readme(doc, parts[-2], folder)
        print(f"docs.param_tables: {self.plugins_checked} plugins, {self.params_checked} "
              f"parameters checked, {self.problems} problems on {len(self.failed_blocks)} lines")
        return not self.failed_blocks


def same_words(doc, declared):
    """'' if the cells say the same, ignoring case, backticks and spacing."""
    def norm(t):
        return re.sub(r"\s+", " ", t.replace("`", "").strip().lower())
    return "" if norm(doc) == norm(declared) else " (different)"


def same_unit(doc, declared):
    def norm(t):
        t = re.sub(r"\s+", " ", t.replace("`", "").strip())
        return "" if t in {"", "-"} else t
    return "" if norm(doc) == norm(declared) else " (different)"


def default_value(text):
    """A default as a comparable value: a number, a tuple of numbers, or normalised text."""
    t = text.replace("`", "").strip()
    try:
        return float(t)
    except ValueError:
        pass
    m = re.fullmatch(r"\[(.*)\]", t)
    if m:
        items = [x.strip() for x in m.group(1).split(",")] if m.group(1).strip() else []
        try:
            return tuple(float(x) for x in items)
        except ValueError:
            pass
    return re.sub(r"\s+", "", t.lower())


def same_default(doc, declared):
    return "" if default_value(doc) == default_value(declared) else " (a different value)"


def bounds(text):
    """The bounds a range cell states, as {(op, value)}, and its other words (prose)."""
    t = text.replace("`", "").strip()
    if t in {"", "-"}:
        return set(), []
    found = set()

    def num(s):
        return {"pi": math.pi, "-pi": -math.pi}.get(s) or float(s)

    def interval(m):
        found.update({(">=", num(m.group(1))), ("<=", num(m.group(2)))})
        return ""
    t = re.sub(rf"\[\s*({NUMBER})\s*,\s*({NUMBER})\s*\]", interval, t)
    prose = []
    for part in (p.strip() for p in t.split(",")):
        m = re.fullmatch(rf"(>=|>|<=|<)\s*({NUMBER})", part)
        if m:
            found.add((m.group(1), num(m.group(2))))
        elif part == "nonzero":
            found.add(("nonzero", None))
        elif part:
            prose.append(part)
    return found, prose


def same_range(doc, declared):
    doc_bounds, _ = bounds(doc)
    declared_bounds, declared_prose = bounds(declared)
    if declared_prose:
        return f" (cannot read {', '.join(declared_prose)})"
    show = lambda b: ", ".join(f"{op}{'' if v is None else f'{v:g}'}" for op, v in sorted(
        b, key=lambda x: (x[0], x[1] or 0)))
    problems = []
    if declared_bounds - doc_bounds:
        problems.append(f"declared but not documented: {show(declared_bounds - doc_bounds)}")
    if doc_bounds - declared_bounds:
        problems.append(f"documented but not declared: {show(doc_bounds - declared_bounds)}")
    return f" ({'; '.join(problems)})" if problems else ""


# ---- helpers -------------------------------------------------------------------------------

def first_line(text):
    return next((l.strip() for l in text.splitlines() if l.strip()), "")


def uses_gtest(text):
    """Whether a C++ block asserts or defines a TEST (GoogleTest's prelude)."""
    return bool(re.search(r"\b(EXPECT_|ASSERT_|TEST(_F)?\s*\()", text))


def cpp_prelude(gtest):
    """The #include lines every C++ block is compiled after; GoogleTest's
    for a block that asserts or defines a TEST."""
    return [f"#include {h}" for h in CPP_PRELUDE] + (["#include <gtest/gtest.h>"] if gtest else [])


def statements_first(block):
    """Whether a C++ block looks like statements: it names the context it runs
    in, or asserts (EXPECT_, ASSERT_) without defining a TEST."""
    if block.context:
        return True
    return bool(re.search(r"\b(EXPECT|ASSERT)_", block.text)) and \
        not re.search(r"\bTEST(_F)?\s*\(", block.text)


def error_line(message, path):
    m = re.match(re.escape(path) + r":(\d+):", message)
    return int(m.group(1)) if m else 0


def side_file_names(data):
    """The `file:` values of a scene or fragment (particles, pairs from CSV files)."""
    if isinstance(data, dict):
        names = [data["file"]] if isinstance(data.get("file"), str) else []
        return names + [n for v in data.values() for n in side_file_names(v)]
    if isinstance(data, list):
        return [n for v in data for n in side_file_names(v)]
    return []


def simple_commands(tokens):
    """The words of each simple command: split at ; && || | and shell keywords,
    without redirections and their targets, without VAR=value prefixes."""
    words, skip = [], False
    for t in tokens + [";"]:
        if skip:
            skip = False
        elif t in {"<", ">", ">>", "2>", "&>"} or re.fullmatch(r"[<>&]+", t) and ">" in t:
            skip = True
        elif re.fullmatch(r"[;&|()]+", t) or (not words and t in {"do", "then", "else"}):
            if words:
                yield words
            words = []
        elif not words and re.match(r"^\w+=", t):
            continue
        else:
            words.append(t)


_targets = None


def cmake_targets(src):
    global _targets
    if _targets is None:
        _targets = set()
        for f in glob.glob(os.path.join(src, "**", "CMakeLists.txt"), recursive=True):
            if "node_modules" in f or "/build" in f:
                continue
            _targets |= set(re.findall(r"add_(?:executable|library|custom_target)\(\s*([\w.-]+)",
                                       open(f).read()))
    return _targets


def read_blocks(doc, src):
    """The fenced blocks of a markdown file, with the snippet comments right before them."""
    path = os.path.relpath(os.path.abspath(doc), src)
    lines = open(doc).read().split("\n")
    k = 0
    while k < len(lines):
        m = re.match(r"^(\s*)(`{3,})\s*([\w+-]*)", lines[k])
        if not m:
            k += 1
            continue
        indent, fence, lang = m.groups()
        end = k + 1
        while end < len(lines) and not lines[end].strip().startswith(fence):
            end += 1
        body = [l[len(indent):] if l.startswith(indent) else l for l in lines[k + 1:end]]
        notes, j = {}, k - 1
        while j >= 0:
            c = re.match(r"^\s*<!--\s*snippet(?::\s*(not checked)\s*\((.*)\)|\s+(context|file|plugin):"
                         r"\s*(.*?))\s*-->\s*$", lines[j])
            if not c:
                break
            if c.group(1):
                notes["not checked"] = c.group(2)
            else:
                notes[c.group(3)] = c.group(4)
            j -= 1
        yield Block(path, k + 1, lang.lower(), "\n".join(body) + "\n", notes)
        k = end + 1


def shipped_docs(src):
    docs = [os.path.join(src, "README.md")]
    docs += sorted(glob.glob(os.path.join(src, "docs", "*.md")))
    docs += sorted(glob.glob(os.path.join(src, "plugins", "*", "*", "README.md")))
    docs += sorted(glob.glob(os.path.join(src, "examples", "**", "README.md"), recursive=True))
    return docs


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--pdyn", required=True)
    p.add_argument("--source-dir", required=True)
    p.add_argument("--cxx", default="c++")
    p.add_argument("--include", action="append", default=[])
    p.add_argument("--cmake", default="cmake")
    p.add_argument("--generator", default="Ninja")
    p.add_argument("--sdk-prefix", help="an installed pdyn SDK: configure and build the "
                                        "CMake snippets against it")
    p.add_argument("--python", default="on", choices=["on", "off"],
                   help="off: the build has no Python module (sanitizer builds): Python blocks "
                        "pass unrun")
    p.add_argument("--verbose", action="store_true", help="also say what passed, and how")
    p.add_argument("--expect-failed-lines", help="self-test: succeed if exactly the blocks "
                   "opening at these comma-separated lines failed, and nothing else")
    p.add_argument("--param-tables", action="store_true", help="check the plugin READMEs' "
                   "parameter tables against `pdyn plugins describe` instead of the snippets")
    p.add_argument("docs", nargs="*")
    args = p.parse_args()
    if args.param_tables:
        checker, name, what = ParamTables(args), "docs.param_tables", "lines"
    else:
        checker, name, what = Checker(args), "docs.snippets", "blocks"
    try:
        if args.param_tables:
            ok = checker.run(args.docs)
        else:
            ok = checker.run(args.docs or shipped_docs(os.path.abspath(args.source_dir)))
    finally:
        shutil.rmtree(checker.tmp, ignore_errors=True)
    if args.expect_failed_lines is not None:
        expected = {int(n) for n in args.expect_failed_lines.split(",")}
        got = {line for _, line in checker.failed_blocks}
        if got != expected:
            print(f"{name}_catch_drift: failed {what} at lines {sorted(got)}, "
                  f"expected {sorted(expected)}")
            return 1
        print(f"{name}_catch_drift: the {len(expected)} drifted {what} were caught")
        return 0
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
