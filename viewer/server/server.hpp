// `pdyn serve`'s network side: Boost.Beast HTTP (the page, /api/state) and
// WebSocket (/ws) on one port, a simulation thread stepping the Session at
// real time, and frames broadcast at most ~60 times a second with the
// oldest dropped for a slow client (docs/viewer.md).
#pragma once

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>

#include "session.hpp"

namespace pdyn::viewer {

struct ServerOptions {
  std::string host = "127.0.0.1";
  unsigned short port = 8080;  ///< 0: any free port
  std::filesystem::path root;  ///< the page's files (index.html, vendor/three/...)
  double frame_rate = 60.0;    ///< frames per second, at most
  int threads = 0;             ///< threads for forces and solvers; 0: OpenMP's default
};

/// Serves `session` until SIGINT or SIGTERM (or `stop` is called from
/// another thread). Prints `pdyn serve: http://HOST:PORT/ (SCENE)` to `out`
/// once listening. Throws Error if the address cannot be bound.
void serve(Session& session, const ServerOptions& options, std::ostream& out,
           const std::string& scene_name);

}  // namespace pdyn::viewer
