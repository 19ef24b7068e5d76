// Checks of the conformance kit that live in files of their own.
#pragma once

#include "pdyn/conformance.hpp"

namespace pdyn::conformance::detail {

/// "params.bad_rejected": bad values generated from the descriptor, each in
/// a small scene of the particles `x` given to the real scene loader, must be
/// refused with a message naming the key; the sample values must be accepted.
CheckResult check_bad_params(const PluginDescriptor& d, const Params& sample, const Matrix3X& x);

}  // namespace pdyn::conformance::detail
