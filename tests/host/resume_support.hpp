// Helpers shared by the checkpoint, resume, signal and plugin-fault tests:
// the test scene, file and CSV helpers, running `pdyn` in-process in a given
// working directory, and spawning the real binary (PDYN_BIN) as a child.
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "pdyn/conformance.hpp"
#include "pdyn/host/checkpoint.hpp"
#include "support/physics_support.hpp"
#include "support/test_support.hpp"

extern char** environ;

namespace pdyn::test {

namespace fs = std::filesystem;

/// The solver entry `{ type: NAME, ... }` with the parameters a solver
/// cannot do without (a thermostat's temperature and damping time) at the
/// values `pdyn check` builds it with (conformance::sample_params).
inline std::string solver_entry(const std::string& name) {
  const PluginRecord* rec = shipped_plugins().find(PluginKind::Solver, name);
  if (rec == nullptr) return "{ type: " + name + " }";
  const Params p = conformance::sample_params(*rec->descriptor, 1);
  std::string entry = "{ type: " + name;
  for (const ParamSpec& spec : rec->descriptor->params) {
    if (!p.has(spec.name)) continue;
    if (spec.type == ParamType::Real) {
      entry += ", " + spec.name + ": " + Num(p.real(spec.name));
    } else if (spec.type == ParamType::Integer) {
      entry += ", " + spec.name + ": " + std::to_string(p.integer(spec.name));
    }
  }
  return entry + " }";
}

/// A 6 x 6 sheet joined by the grid builder's three spring families, under
/// gravity and drag, falling onto a floor plane it reaches after ~0.1 s
/// (so collision responses happen inside every run). Outputs are relative:
/// out/frames.csv (a frame every `every` steps), out/energy.csv, and the
/// checkpoint out/run.ckpt every `ckpt_every` steps (0: at the end only;
/// negative: no checkpoint section, so none unless the run is stopped).
inline std::string sheet_scene(const std::string& solver, int every = 5, int ckpt_every = 0,
                               double dt = 0.001, int nx = 6) {
  std::ostringstream s;
  s << "simulation:\n"
    << "  dt: " << dt << "\n"
    << "  steps: 200\n"
    << "  solver: " << solver_entry(solver) << "\n"
    << "output:\n"
    << "  path: out/frames.csv\n"
    << "  every: " << every << "\n"
    << "  energy: out/energy.csv\n"
    << (ckpt_every >= 0
            ? "  checkpoint: { path: out/run.ckpt, every: " + std::to_string(ckpt_every) + " }\n"
            : std::string())
    << "particles:\n"
    << "  - grid:\n"
    << "      name: sheet\n"
    << "      origin: [-0.25, -0.25, 0.05]\n"
    << "      u: [0.1, 0, 0]\n"
    << "      v: [0, 0.1, 0.02]\n"
    << "      nx: " << nx << "\n"
    << "      ny: " << nx << "\n"
    << "      mass: 0.01\n"
    << "      velocity: [0.2, 0.1, -1.0]\n"
    << "      springs:\n"
    << "        structural: { ks: 10, kd: 0.02 }\n"
    << "        shear: { ks: 5, kd: 0.01 }\n"
    << "        bend: { ks: 1, kd: 0.005 }\n"
    << "forces:\n"
    << "  - { type: gravity, g: [0, 0, -9.81] }\n"
    << "  - { type: drag, k: 0.001 }\n"
    << "colliders:\n"
    << "  - { type: plane, point: [0, 0, 0], normal: [0, 0, 1], restitution: 0.3 }\n";
  return s.str();
}

/// Three particles with radii and types under gravity and drag in a box
/// periodic along x and y (0.2 m x 0.3 m) and open along z, each crossing
/// the periodic faces several times in 200 steps. The frames file has the
/// unwrapped columns, which differ from x only by the image counts, so a
/// resume that lost them writes different files. Outputs as sheet_scene's.
inline std::string periodic_scene(const std::string& solver, int every = 5, int ckpt_every = 0) {
  std::ostringstream s;
  s << "simulation:\n"
    << "  dt: 0.001\n"
    << "  steps: 200\n"
    << "  solver: " << solver_entry(solver) << "\n"
    << "  box: { min: [0, 0, -1000], max: [0.2, 0.3, 1000], periodic: [true, true, false] }\n"
    << "output:\n"
    << "  path: out/frames.csv\n"
    << "  every: " << every << "\n"
    << "  energy: out/energy.csv\n"
    << "  unwrapped: true\n"
    << "  checkpoint: { path: out/run.ckpt, every: " << ckpt_every << " }\n"
    << "particles:\n"
    << "  - { position: [0.15, 0.05, 0], velocity: [3, -2, 1], mass: 1 }\n"
    << "  - { position: [0.01, 0.29, 0], velocity: [-4.1, 2.7, 0], mass: 0.5, type: 2 }\n"
    << "  - { position: [0.1, 0.15, 0], velocity: [1.3, 0.9, -2], mass: 2, radius: 0.01 }\n"
    << "forces:\n"
    << "  - { type: gravity, g: [0, 0, -9.81] }\n"
    << "  - { type: drag, k: 0.05 }\n";
  return s.str();
}

/// Writes `bytes` to a new file at `p`. The old file is removed first
/// rather than truncated: ext4 flushes a file truncated and rewritten on
/// close, which made thousands of rewrites take seconds.
inline void write_bytes(const fs::path& p, const std::string& bytes) {
  std::error_code ec;
  fs::remove(p, ec);
  std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
}

inline std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

inline bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

/// Files in `dir` whose names start with `prefix`.
inline std::vector<fs::path> files_starting(const fs::path& dir, const std::string& prefix) {
  std::vector<fs::path> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (e.path().filename().string().rfind(prefix, 0) == 0) out.push_back(e.path());
  }
  return out;
}

/// Runs `pdyn ARGS` in-process with `cwd` as the working directory (the
/// scenes' output paths are relative to it).
inline CommandResult pdyn_in(const fs::path& cwd, const std::vector<std::string>& args) {
  const fs::path old = fs::current_path();
  fs::current_path(cwd);
  CommandResult r = pdyn(args);
  fs::current_path(old);
  return r;
}

/// Checks a frames CSV: the header, 8 numeric fields on every row, frames of
/// exactly `particles` rows with ids 0..particles-1 and one time each.
/// Returns the number of frames (or -1 after a failed assertion).
inline int check_frames_file(const fs::path& p, int particles, double* last_time = nullptr) {
  const std::string text = read_bytes(p);
  EXPECT_FALSE(text.empty()) << p;
  EXPECT_EQ(text.back(), '\n') << p << " does not end with a complete line";
  const auto lines = lines_of(text);
  if (lines.empty() || lines[0] != "t,id,x,y,z,vx,vy,vz") {
    ADD_FAILURE() << p << ": no header";
    return -1;
  }
  const std::size_t rows = lines.size() - 1;
  if (rows % static_cast<std::size_t>(particles) != 0) {
    ADD_FAILURE() << p << ": " << rows << " rows, not whole frames of " << particles;
    return -1;
  }
  for (std::size_t i = 1; i < lines.size(); ++i) {
    std::vector<std::string> fields;
    std::istringstream row(lines[i]);
    for (std::string f; std::getline(row, f, ',');) fields.push_back(f);
    if (fields.size() != 8) {
      ADD_FAILURE() << p << ":" << i + 1 << ": " << fields.size() << " fields: " << lines[i];
      return -1;
    }
    const long id = std::stol(fields[1]);
    if (id != static_cast<long>((i - 1) % static_cast<std::size_t>(particles))) {
      ADD_FAILURE() << p << ":" << i + 1 << ": particle id " << id << " out of order";
      return -1;
    }
    if (id > 0 && fields[0] != lines[i - 1].substr(0, lines[i - 1].find(','))) {
      ADD_FAILURE() << p << ":" << i + 1 << ": time changes inside a frame";
      return -1;
    }
    if (last_time) *last_time = std::stod(fields[0]);
  }
  return static_cast<int>(rows / static_cast<std::size_t>(particles));
}

/// Exactly equal doubles (bit for bit, NaN payloads included).
inline bool same_bits(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), static_cast<std::size_t>(a.size()) * sizeof(double)) == 0;
}

/// Runs the scene file `scene` in `dir` whole, then again stopped after
/// `stop` steps and resumed from its checkpoint: its outputs out/frames.csv
/// (not empty) and out/energy.csv, and the final checkpoint out/run.ckpt's
/// state and plugin states, must be the same bytes. The two final
/// checkpoints (the whole run's, the resumed run's) go to `whole` and
/// `resumed` for the caller's own checks.
inline void expect_resumed_run_is_whole_run(const fs::path& dir, const std::string& scene, int stop,
                                            Checkpoint& whole, Checkpoint& resumed) {
  auto all = pdyn_in(dir, {"run", scene, "-q"});
  ASSERT_EQ(all.status, 0) << all.err;
  const std::string frames = read_bytes(dir / "out/frames.csv");
  const std::string energy = read_bytes(dir / "out/energy.csv");
  ASSERT_FALSE(frames.empty());
  whole = read_checkpoint(dir / "out/run.ckpt");
  auto half = pdyn_in(dir, {"run", scene, "--steps", std::to_string(stop), "-q"});
  ASSERT_EQ(half.status, 0) << half.err;
  auto rest = pdyn_in(dir, {"run", scene, "--resume", "out/run.ckpt", "-q"});
  ASSERT_EQ(rest.status, 0) << rest.err;
  EXPECT_EQ(read_bytes(dir / "out/frames.csv"), frames);
  EXPECT_EQ(read_bytes(dir / "out/energy.csv"), energy);
  resumed = read_checkpoint(dir / "out/run.ckpt");
  EXPECT_TRUE(same_bits(whole.state, resumed.state));
  EXPECT_EQ(whole.plugin_states, resumed.plugin_states);
}

/// A child `pdyn` process (the real binary), with stderr captured to a file.
class Child {
 public:
  Child(const std::vector<std::string>& args, const fs::path& cwd) : err_(cwd / "child.err") {
    std::vector<std::string> storage = args;
    storage.insert(storage.begin(), PDYN_BIN);
    std::vector<char*> argv;
    for (auto& s : storage) argv.push_back(s.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 2, err_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    // The child gets default signal dispositions and its own working folder.
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    sigset_t all;
    sigemptyset(&all);
    sigaddset(&all, SIGINT);
    sigaddset(&all, SIGTERM);
    posix_spawnattr_setsigdefault(&attr, &all);
    sigset_t none;
    sigemptyset(&none);
    posix_spawnattr_setsigmask(&attr, &none);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
    const fs::path old = fs::current_path();
    fs::current_path(cwd);
    const int rc = posix_spawn(&pid_, PDYN_BIN, &actions, &attr, argv.data(), environ);
    fs::current_path(old);
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attr);
    if (rc != 0) {
      pid_ = -1;
      ADD_FAILURE() << "cannot start " << PDYN_BIN;
    }
  }
  ~Child() {
    if (pid_ > 0 && !done_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status_, 0);
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  pid_t pid() const { return pid_; }
  bool running() {
    if (pid_ <= 0 || done_) return false;
    if (::waitpid(pid_, &status_, WNOHANG) == pid_) done_ = true;
    return !done_;
  }
  void signal(int sig) const {
    if (pid_ > 0) ::kill(pid_, sig);
  }
  /// Waits for the child to end; returns false if it is still running after `timeout`.
  bool wait(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (running()) {
      if (std::chrono::steady_clock::now() > deadline) return false;
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    return done_;
  }
  int status() const { return status_; }
  std::string err() const { return read_bytes(err_); }

 private:
  pid_t pid_ = -1;
  int status_ = 0;
  bool done_ = false;
  fs::path err_;
};

/// Polls `ready` every 100 us until it holds or `timeout` passes.
inline bool wait_until(const std::function<bool()>& ready, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!ready()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(100));
  }
  return true;
}

/// The names of the shipped solvers (whatever plugins/ holds today).
inline std::vector<std::string> shipped_solvers() {
  return shipped_plugins().names(PluginKind::Solver);
}

/// Whether the shipped solver `name` is adaptive (driven by advance()).
inline bool solver_is_adaptive(const std::string& name) {
  Scene s = load_text(sheet_scene(name));
  return s.solver->adaptive();
}

}  // namespace pdyn::test
