// The release version, compiled into the host library once so that the
// program, the viewer and the Python module cannot disagree about it.
#include "pdyn/host/version.hpp"

namespace pdyn::host {

const char* version() noexcept { return PDYN_VERSION_STRING; }

}  // namespace pdyn::host
