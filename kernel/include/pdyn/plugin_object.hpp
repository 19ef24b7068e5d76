// pdyn/plugin_object.hpp — what every plugin object (force, solver, collider) has.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pdyn/export.hpp"

namespace pdyn {

class PDYN_API PluginObject {
 public:
  virtual ~PluginObject() = default;

  /// Internal state that a checkpoint must carry so that a resumed run is
  /// bit-identical to an uninterrupted one (e.g. an adaptive solver's next
  /// step size, an anchor's moved targets), in the plugin's own byte format.
  /// Stateless plugins keep the default: nothing.
  virtual std::vector<std::uint8_t> save_state() const { return {}; }

  /// Restores what save_state() returned. Throws pdyn::Error if `bytes` is
  /// not something save_state() of this plugin could have written.
  virtual void restore_state(std::span<const std::uint8_t> bytes);
};

}  // namespace pdyn
