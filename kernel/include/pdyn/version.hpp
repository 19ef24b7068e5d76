// pdyn/version.hpp — the plugin ABI version.
#pragma once

#include <cstdint>

/// Version of the binary interface between the kernel and plugins. A plugin
/// built against another version is refused before any of its code runs
/// beyond the version query. Bump it whenever a public header changes a type
/// layout or a virtual function.
#define PDYN_ABI_VERSION 7u
// 4 (pdyn 0.2): ParticleView and MutableParticleView gained domain, radius
//   and type at their ends (the simulation box, per-particle radii and
//   types). Rebuild plugins; no source change (docs/plugins.md, "ABI").
// 5 (pdyn 0.3): PluginKind gained Writer and PluginDescriptor gained
//   writer_traits and create_writer at its end (output writers,
//   pdyn/writer.hpp). Rebuild plugins; no source change (docs/plugins.md, "ABI").
// 6 (pdyn 0.4): Force gained the virtual dependence() at the end of its
//   vtable, and System a state version (state_version(), touch()) that its
//   writable accessors count. Rebuild plugins; no source change: a force
//   that does not override dependence() is taken to depend on velocity and
//   time, as before (docs/plugins.md, "ABI").
// 7 (pdyn 0.9): PluginKind gained Constraint and PluginDescriptor gained
//   create_constraint at its end (constraint plugins, pdyn/constraint.hpp);
//   System gained its constraints after every member it had. Plugins built
//   for ABI 6 keep loading unchanged (kOldestAbiVersion): the host reads
//   their descriptors without the new member (docs/plugins.md, "ABI").

namespace pdyn {
inline constexpr std::uint32_t kAbiVersion = PDYN_ABI_VERSION;
/// The oldest ABI whose plugin binaries this kernel still loads.
inline constexpr std::uint32_t kOldestAbiVersion = 6u;
/// The two symbols every plugin library exports (see PDYN_PLUGIN).
inline constexpr const char* kAbiSymbol = "pdyn_plugin_abi_version";
inline constexpr const char* kDescriptorSymbol = "pdyn_plugin_descriptor";
/// Optional third symbol (since pdyn 0.1, same ABI): how the plugin was compiled.
inline constexpr const char* kBuildFlagsSymbol = "pdyn_plugin_build_flags";
/// Bit of the build flags: the plugin was compiled with optimisation (-O1 or more).
inline constexpr std::uint32_t kBuildOptimised = 1u;
}  // namespace pdyn
