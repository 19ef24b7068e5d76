// pdyn/kernel/plugin_call.hpp — which plugin call is in progress, for crash reports.
//
// The kernel marks every call it makes into a plugin object (a force's
// add_forces, a collider's respond, ...) with a CallScope: two stores, no
// allocation, no lock; the host marks its own (a solver's step, a writer's
// write). A host that installs a fatal-signal handler (`pdyn run` does)
// reads the innermost scope to name the plugin that crashed.
//
// This is the one thing the kernel library offers hosts and not plugins, so
// it lives outside the plugin SDK's folder (kernel/include/pdyn/): the
// record has to be the kernel's, because the kernel makes the calls, and
// the host's, because the host reads it (tests/kernel/check_sdk.py).
#pragma once

#include <string>

#include "pdyn/export.hpp"

namespace pdyn::crash {

/// One plugin call in progress: the label the System holds for the object
/// (its address identifies the object) and the hook being called.
struct PluginCall {
  const std::string* label;
  const char* hook;  ///< a string literal: "add_forces", "step", ...
};

/// The calling thread's innermost plugin call, or null.
PDYN_API extern thread_local const PluginCall* t_current_call;

/// Marks a plugin call for its lifetime. Nested scopes (the forces a
/// solver's step calls) restore the outer one on exit. Per thread, so two
/// systems stepped in two threads keep apart; the fatal-signal handler
/// falls back to the thread that installed it when the crash happens in a
/// plugin's own worker thread (OpenMP).
class CallScope {
 public:
  CallScope(const std::string& label, const char* hook) noexcept
      : call_{&label, hook}, previous_(t_current_call) {
    t_current_call = &call_;
  }
  ~CallScope() { t_current_call = previous_; }
  CallScope(const CallScope&) = delete;
  CallScope& operator=(const CallScope&) = delete;

 private:
  PluginCall call_;
  const PluginCall* previous_;
};

}  // namespace pdyn::crash
