# Sourced by quickstart.sh, ci-extra.sh and fuzz.sh: compile through ccache
# where the machine has it (quickstart.sh installs it), so a second build of
# the same sources (another preset's shared objects, another clone, CI after
# a session on the same machine) is mostly a copy. Sets `launcher` for cmake.
launcher=()
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  # Paths relative to the clone, so that another clone's objects are reused;
  # the tests' precompiled header is cacheable only with pch_defines and
  # time_macros; three builds (default, asan, fuzz) need more than 5 GB.
  export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=1
  export CCACHE_SLOPPINESS="${CCACHE_SLOPPINESS:-pch_defines,time_macros,include_file_mtime,include_file_ctime}"
  export CCACHE_MAXSIZE="${CCACHE_MAXSIZE:-20G}"
  # Depend mode: a hit needs every header's bytes unchanged, never only the
  # same preprocessed text. A precompiled header records each header's
  # checksum, so a .gch reused after a comment-only edit (a preprocessor-mode
  # hit) made GCC's `#pragma once` miss and include the header twice. The
  # namespace leaves behind the entries made before this rule.
  export CCACHE_DEPEND=1 CCACHE_NAMESPACE=pdyn-depend
fi
