// The simulation behind `pdyn serve`: one loaded scene stepped at real time,
// and Witkin's interactions ("Basic 2-D interaction", SIGGRAPH '97 notes)
// applied to it as real changes — a mouse spring to drag a particle, nailing,
// creating particles and attaching springs — plus the controls of the page.
// No networking here: the server (server.hpp) and the tests call it alike.
//
// Thread safety: every member function locks the session, so the simulation
// thread (advance, frame) and the network thread (apply, observers) may call
// it concurrently.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "pdyn/error.hpp"
#include "pdyn/host/registry.hpp"
#include "pdyn/host/scene.hpp"
#include "pdyn/host/scene_drawables.hpp"
#include "protocol.hpp"

namespace pdyn::viewer {

/// A command was refused; what() says why and what was expected.
class CommandError : public Error {
 public:
  using Error::Error;
};

struct SessionOptions {
  std::filesystem::path scene;                     ///< the scene file
  std::vector<Override> overrides;                 ///< --set
  std::vector<std::filesystem::path> plugin_path;  ///< --plugin-path, before the default ones
};

class Session {
 public:
  /// Loads the scene. Throws SceneError or PluginError as load_scene does.
  explicit Session(SessionOptions options);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  /// Applies one command from client `client` (its mouse spring is its own).
  /// Returns the new particle's index for `create`. Throws CommandError if
  /// the command is refused (the simulation is unchanged), or, for `reload`,
  /// with every diagnostic of the new scene, one per line (the running
  /// simulation is kept).
  std::optional<Index> apply(const Command& command, int client);
  /// Removes client's mouse spring, if it has one (it disconnected).
  void forget_client(int client);

  /// Advances the simulation, if playing, by speed x `wall_seconds` of
  /// simulated time, stepping for at most `budget_seconds` of wall time: a
  /// simulation slower than real time runs as fast as it can and the time it
  /// could not catch up is dropped, not owed.
  void advance(double wall_seconds, double budget_seconds);

  /// The current positions and energies.
  Frame frame() const;
  /// Changes on every step and every command: a frame is worth sending.
  std::uint64_t version() const;
  /// Changes when particles, links or fixed flags do: the `scene` message.
  std::uint32_t topology() const;
  /// `scene`, `status` and /api/state JSON (docs/viewer.md).
  std::string scene_json() const;
  std::string status_json() const;
  std::string state_json() const;

  // ---- for tests ----
  const System& system() const { return *scene_.system; }
  bool playing() const;
  std::uint64_t steps() const;
  double dt() const;
  const std::string& solver_name() const { return scene_.solver_name; }
  /// simulation.threads of the scene as first loaded (0: not given).
  int scene_threads() const { return scene_.threads; }
  Index particle_count() const { return scene_.system->size(); }
  /// Stiffness (N/m) and damping (N s/m) of a mouse spring on particle i
  /// when the page gives none (see session.cpp).
  std::pair<double, double> default_mouse_spring(Index i) const;

 private:
  // The commands apply() hands on (with the session's lock held).
  void reload();
  void choose_solver(const std::string& name);
  void start_drag(const Command& c, int client);
  void attach(const Command& c);
  struct Drag {
    std::shared_ptr<Force> force;
    Index particle = 0;
  };
  // One constraint object as the page draws it: the `constraints` of the
  // scene message.
  struct ConstraintRows {
    std::string type;   // the plugin's name, the scene's `type:`
    std::string label;  // "distance (scene.yaml:30:5)", as in messages
    ConstraintPattern pattern;
  };
  static std::vector<ConstraintRows> constraint_rows(const Scene& scene);

  void load(bool from_disk);
  void step_locked();
  void fail(std::string message);
  void check_particle(const Command& c, const char* field, Index i) const;
  void refresh_solver();
  std::shared_ptr<Force> make_force(const char* type, const Params& params,
                                    const std::string& label);
  Params defaults_of(const PluginRecord& r, const Params& given) const;

  mutable std::mutex mutex_;
  SessionOptions options_;
  std::unique_ptr<PluginRegistry> registry_;
  Scene scene_;
  Drawables obstacles_;  // the colliders' shapes, from the last load (links: scene_links)
  std::vector<ConstraintRows> constraints_;  // the constraints' rows, from the last load
  std::string text_;  // the scene file as last loaded: what reset starts from
  std::map<std::filesystem::path, std::filesystem::file_time_type> library_times_;
  std::map<int, Drag> drags_;
  bool playing_ = false;
  double speed_ = 1.0;
  double dt_ = 0.0;
  double debt_ = 0.0;  // simulated time owed to real time, s
  std::uint64_t steps_ = 0;
  std::uint64_t version_ = 0;
  std::uint32_t topology_ = 1;
  std::string message_;  // why the simulation stopped itself
  int attached_ = 0;     // springs made by `attach`, to label them
  // (wall clock, simulated time) over the last second: the real-time factor.
  std::deque<std::pair<std::chrono::steady_clock::time_point, double>> rate_;
};

}  // namespace pdyn::viewer
