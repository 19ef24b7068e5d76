// The h5md writer plugin: H5MD 1.1 trajectories (de Buyl, Colberg and
// Hoefling, Comput. Phys. Commun. 185, 1546 (2014)). The format is written
// by its HDF5 part, h5md_hdf5.cpp, built as h5md/libpdyn_h5md_hdf5.so beside
// this plugin and loaded the first time a scene asks for the writer (or
// `pdyn check` reads a file back).
//
// Why two libraries: HDF5 and what Debian's build of it links (libcurl,
// OpenSSL, Kerberos, LDAP: about 40 libraries) took 20 ms to load, a third
// of the start-up of every `pdyn` process (57 ms -> 36 ms for a 3-step run),
// whether or not it wrote H5MD. The registry loads every plugin to read its
// descriptor, so the descriptor lives here, free of HDF5.
#include <dlfcn.h>
#include <fmt/format.h>

#include <filesystem>
#include <pdyn/plugin.hpp>

namespace {

namespace fs = std::filesystem;

struct Hdf5Part {
  pdyn::Writer* (*create)(const pdyn::Params&, const pdyn::WriterContext&) = nullptr;
  void (*read_back)(const fs::path&, std::vector<pdyn::FrameRecord>&) = nullptr;
};

// Loaded once, never unloaded (RTLD_NODELETE): HDF5 keeps per-thread data
// whose destructors run when a thread that used it exits, possibly after the
// registry has let the plugin go (the Python module's thread pools).
Hdf5Part load_hdf5_part() {
  Dl_info self{};
  if (dladdr(reinterpret_cast<void*>(&load_hdf5_part), &self) == 0 || self.dli_fname == nullptr) {
    throw pdyn::Error("h5md: cannot find the plugin's own file (dladdr failed)");
  }
  const fs::path lib = fs::path(self.dli_fname).parent_path() / "h5md" / "libpdyn_h5md_hdf5.so";
  void* handle = dlopen(lib.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
  if (handle == nullptr) {
    throw pdyn::Error(
        fmt::format("h5md: cannot load its HDF5 part {}: {} (expected it installed "
                    "with the plugin, in the folder h5md/ beside it)",
                    lib.string(), dlerror()));
  }
  Hdf5Part part;
  part.create = reinterpret_cast<decltype(part.create)>(dlsym(handle, "pdyn_h5md_create_writer"));
  part.read_back = reinterpret_cast<decltype(part.read_back)>(dlsym(handle, "pdyn_h5md_read_back"));
  if (part.create == nullptr || part.read_back == nullptr) {
    throw pdyn::Error(
        fmt::format("h5md: {} lacks pdyn_h5md_create_writer or pdyn_h5md_read_back "
                    "(expected the HDF5 part built with this plugin)",
                    lib.string()));
  }
  return part;
}

// A failed load throws and is tried again on the next use.
const Hdf5Part& hdf5_part() {
  static const Hdf5Part part = load_hdf5_part();
  return part;
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Writer;
  d.name = "h5md";
  d.version = "1.0.0";
  d.description =
      "H5MD 1.1 (HDF5): particles/all/position|velocity|force|image with step, time, value; "
      "chunked, optional gzip";
  pdyn::ParamSpec compression = pdyn::param::integer(
      "compression", 0, "gzip level of the time-dependent datasets (0: none, 1 fast .. 9 small)");
  compression.at_least(0).at_most(9);
  d.params = {compression};
  namespace f = pdyn::field;
  d.writer_traits.fields = {f::kId,     f::kVelocity, f::kMass,  f::kFixed,
                            f::kRadius, f::kType,     f::kForce, f::kImage};
  d.writer_traits.default_fields = {f::kId,    f::kVelocity, f::kMass,
                                    f::kFixed, f::kRadius,   f::kType};
  d.create_writer = [](const pdyn::Params& p, const pdyn::WriterContext& ctx) {
    return std::unique_ptr<pdyn::Writer>(hdf5_part().create(p, ctx));
  };
  d.read_back = [](const fs::path& path) {
    std::vector<pdyn::FrameRecord> frames;
    hdf5_part().read_back(path, frames);
    return frames;
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
