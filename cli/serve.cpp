// `pdyn serve SCENE`: the interactive viewer (docs/viewer.md). The command
// only finds the page's files, loads the scene into a viewer Session and
// hands both to the server.
#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <memory>
#include <ostream>

#include "commands.hpp"
#include "pdyn/host/registry.hpp"
#include "pdyn/host/threads.hpp"
#include "pdyn/parallel.hpp"
#include "sdk_commands.hpp"
#include "server.hpp"
#include "session.hpp"

namespace pdyn::cli {

namespace fs = std::filesystem;

namespace {

struct ServeArgs {
  std::string scene;
  std::string host = "127.0.0.1";
  int port = 8080;
  std::string viewer;
  int threads = 0;
  std::vector<std::string> sets;
  std::vector<std::string> plugin_path;
};

// The page: --viewer, else next to the program (the build tree's
// bin/viewer), else the install tree's share/pdyn/viewer.
std::vector<fs::path> viewer_candidates(const ServeArgs& a) {
  if (!a.viewer.empty()) return {a.viewer};
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  const fs::path bin = exe.parent_path();
  return {bin / "viewer", bin.parent_path() / "share" / "pdyn" / "viewer"};
}

int cmd_serve(const ServeArgs& a, std::ostream& out, std::ostream& err) {
  if (a.port < 0 || a.port > 65535) {
    err << fmt::format(
        "pdyn serve: --port {} is out of range (expected 0..65535; 0 picks a free port)\n", a.port);
    return kBadInput;
  }
  if (a.threads < 0) {
    err << fmt::format("pdyn serve: --threads {} (expected >= 1, or 0 for the default)\n",
                       a.threads);
    return kBadInput;
  }
  fs::path root;
  std::string looked;
  for (const auto& c : viewer_candidates(a)) {
    std::error_code ec;
    if (fs::is_regular_file(c / "index.html", ec)) {
      root = c;
      break;
    }
    looked += (looked.empty() ? "" : ", ") + c.string();
  }
  if (root.empty()) {
    err << fmt::format(
        "pdyn serve: the viewer's page was not found (looked for index.html in {}; "
        "expected pdyn built with the viewer after `npm ci --prefix viewer`, or "
        "--viewer DIR)\n",
        looked.empty() ? "no folder" : looked);
    return kFailure;
  }
  try {
    viewer::SessionOptions so;
    so.scene = a.scene;
    for (const auto& s : a.sets) so.overrides.push_back(parse_override(s));
    so.plugin_path.assign(a.plugin_path.begin(), a.plugin_path.end());
    viewer::Session session(std::move(so));
    viewer::ServerOptions options;
    options.host = a.host;
    options.port = static_cast<unsigned short>(a.port);
    options.root = root;
    options.threads = a.threads > 0                 ? a.threads
                      : session.scene_threads() > 0 ? session.scene_threads()
                                                    : default_threads(session.particle_count());
    viewer::serve(session, options, out, a.scene);
    return kOk;
  } catch (...) {
    return report_error(std::current_exception(), err);
  }
}

}  // namespace

SdkCommand add_serve_command(CLI::App& app) {
  auto a = std::make_shared<ServeArgs>();
  CLI::App* sub =
      app.add_subcommand("serve", "run a scene in the interactive browser viewer (docs/viewer.md)");
  sub->add_option("scene", a->scene, "scene file (YAML)")->required();
  sub->add_option("--port", a->port, "TCP port (default 8080; 0: any free port, printed)");
  sub->add_option("--host", a->host,
                  "address to listen on (default 127.0.0.1: this machine only; 0.0.0.0: all)");
  sub->add_option("--viewer", a->viewer,
                  "folder of the page's files (default: bin/viewer next to pdyn, else "
                  "share/pdyn/viewer)");
  sub->add_option("--threads", a->threads,
                  "threads for forces and solvers (default: simulation.threads, else one per 4096 "
                  "particles, up to all cores)");
  add_scene_options(sub, a->sets, a->plugin_path);
  return {sub, [a](std::ostream& out, std::ostream& err) { return cmd_serve(*a, out, err); }};
}

}  // namespace pdyn::cli
