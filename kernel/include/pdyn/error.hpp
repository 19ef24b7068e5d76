// pdyn/error.hpp — the exceptions a plugin may throw and the host reports.
#pragma once

#include <stdexcept>
#include <string>

#include "pdyn/export.hpp"

namespace pdyn {

/// Base of every error pdyn reports. The message is one line, already
/// readable by a user ("what is wrong (what was expected)").
class PDYN_API Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Thrown by a plugin factory when a parameter that passed the descriptor's
/// generic checks is still unacceptable (e.g. a spring joining a particle to
/// itself). The scene loader turns it into `FILE:LINE:COLUMN: ...` pointing at
/// the parameter, or at element `element` of a list parameter when >= 0.
class PDYN_API ParamError : public Error {
 public:
  ParamError(std::string param, const std::string& message, long element = -1)
      : Error(message), param_(std::move(param)), element_(element) {}
  /// Name of the offending parameter, as spelled in the descriptor.
  const std::string& param() const noexcept { return param_; }
  /// Index of the offending list element, or -1 for the whole parameter.
  long element() const noexcept { return element_; }

 private:
  std::string param_;
  long element_;
};

/// A plugin library could not be used: exit status 3. The message names the
/// library path and, where known, the plugin.
class PDYN_API PluginError : public Error {
 public:
  using Error::Error;
};

/// A plugin object threw while the simulation ran: exit status 3. `label`
/// names the plugin and its place in the scene.
class PDYN_API PluginRuntimeError : public PluginError {
 public:
  PluginRuntimeError(std::string label, const std::string& what)
      : PluginError(label + ": " + what), label_(std::move(label)) {}
  const std::string& label() const noexcept { return label_; }

 private:
  std::string label_;
};

}  // namespace pdyn
