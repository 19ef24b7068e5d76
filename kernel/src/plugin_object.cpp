// Default implementations of the optional plugin hooks.
#include "pdyn/plugin_object.hpp"

#include <algorithm>

#include "pdyn/error.hpp"
#include "pdyn/solver.hpp"
#include "pdyn/system.hpp"

namespace pdyn {

void PluginObject::restore_state(std::span<const std::uint8_t> bytes) {
  if (!bytes.empty()) {
    throw Error("this plugin keeps no internal state, but the checkpoint holds some for it");
  }
}

double Solver::advance(System& sys, double t_stop, double h_hint) {
  const double h = std::min(h_hint, t_stop - sys.time());
  step(sys, h);
  return h;
}

}  // namespace pdyn
