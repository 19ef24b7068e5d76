// pdyn/host/version.hpp — the release this host library belongs to.
#pragma once

#include "pdyn/host/export.hpp"

namespace pdyn::host {

/// pdyn's version, "MAJOR.MINOR.PATCH" (CHANGELOG.md; CMake's
/// PROJECT_VERSION). Every tool reports this one: `pdyn --version`, the
/// Python module's `pdyn.__version__`. The plugin ABI version is a separate
/// number (pdyn::kAbiVersion, <pdyn/version.hpp>).
PDYN_HOST_API const char* version() noexcept;

}  // namespace pdyn::host
