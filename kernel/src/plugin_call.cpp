// The calling thread's innermost plugin call (see pdyn/kernel/plugin_call.hpp).
#include "pdyn/kernel/plugin_call.hpp"

namespace pdyn::crash {

thread_local const PluginCall* t_current_call = nullptr;

}  // namespace pdyn::crash
