// The step loop: Witkin's simulation loop plus output.
#include "runner.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <ostream>

namespace pdyn {

namespace fs = std::filesystem;

AtomicFile::AtomicFile(fs::path path) : path_(std::move(path)) {
  std::error_code ec;
  if (path_.has_parent_path()) fs::create_directories(path_.parent_path(), ec);
  temp_ = path_;
  temp_ += fmt::format(".tmp-{}", ::getpid());
  file_ = std::fopen(temp_.c_str(), "wb");
  if (!file_) {
    throw Error(fmt::format("{}: cannot create output file ({})", path_.string(),
                            std::strerror(errno)));
  }
}

AtomicFile::~AtomicFile() {
  if (file_) {
    std::fclose(file_);
    std::error_code ec;
    fs::remove(temp_, ec);
  }
}

void AtomicFile::commit() {
  const bool ok = std::fflush(file_) == 0 && ::fsync(::fileno(file_)) == 0;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  std::error_code ec;
  if (ok && closed) fs::rename(temp_, path_, ec);
  if (!ok || !closed || ec) {
    fs::remove(temp_, ec);
    throw Error(fmt::format("{}: cannot write output file", path_.string()));
  }
}

namespace {

// Frames: t,id,x,y,z,vx,vy,vz with 17 significant digits, enough to
// round-trip a double exactly.
void write_frame(std::FILE* f, const System& sys) {
  const auto x = sys.positions();
  const auto v = sys.velocities();
  const double t = sys.time();
  fmt::memory_buffer buf;
  for (Index i = 0; i < sys.size(); ++i) {
    fmt::format_to(std::back_inserter(buf), "{:.17g},{},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g}\n",
                   t, i, x(0, i), x(1, i), x(2, i), v(0, i), v(1, i), v(2, i));
    if (buf.size() > (1 << 16)) {
      std::fwrite(buf.data(), 1, buf.size(), f);
      buf.clear();
    }
  }
  std::fwrite(buf.data(), 1, buf.size(), f);
}

void write_energy(std::FILE* f, const System& sys) {
  const double k = sys.kinetic_energy(), u = sys.potential_energy();
  fmt::print(f, "{:.17g},{:.17g},{:.17g},{:.17g}\n", sys.time(), k, u, k + u);
}

// Index of the first particle whose position or velocity is not finite, or -1.
Index first_non_finite(const System& sys) {
  if (sys.state().allFinite()) return -1;
  const auto x = sys.positions();
  const auto v = sys.velocities();
  for (Index i = 0; i < sys.size(); ++i) {
    if (!x.col(i).allFinite() || !v.col(i).allFinite()) return i;
  }
  return -1;
}

class Progress {
 public:
  Progress(std::ostream* out, std::int64_t total, double end_time)
      : out_(out), total_(total), end_time_(end_time), start_(Clock::now()), last_(start_) {}
  void update(std::int64_t step, double t, bool force = false) {
    if (!out_) return;
    const auto now = Clock::now();
    if (!force && now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const double rate = elapsed > 0 ? static_cast<double>(step) / elapsed : 0.0;
    const double eta = rate > 0 ? static_cast<double>(total_ - step) / rate : 0.0;
    const double frac = total_ > 0 ? static_cast<double>(step) / static_cast<double>(total_) : 1;
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(frac * kWidth);
    *out_ << fmt::format("\r[{:<{}}] {:>3.0f}%  step {}/{}  t = {:.4g}/{:.4g} s  {:.0f} steps/s  "
                         "ETA {:.1f} s ",
                         std::string(static_cast<std::size_t>(filled), '#'), kWidth, 100 * frac,
                         step, total_, t, end_time_, rate, eta)
          << std::flush;
  }
  void finish() {
    if (out_) *out_ << "\n" << std::flush;
  }

 private:
  using Clock = std::chrono::steady_clock;
  std::ostream* out_;
  std::int64_t total_;
  double end_time_;
  Clock::time_point start_, last_;
};

}  // namespace

namespace {

// Shared by the fixed-step and adaptive loops: output files and the
// last-good-state bookkeeping.
class Output {
 public:
  explicit Output(const Scene& scene) : sys_(*scene.system) {
    if (!scene.output.path.empty()) {
      frames_.emplace(scene.output.path);
      std::fputs("t,id,x,y,z,vx,vy,vz\n", frames_->stream());
    }
    if (!scene.output.energy.empty()) {
      energy_.emplace(scene.output.energy);
      std::fputs("t,kinetic,potential,total\n", energy_->stream());
    }
  }
  void emit() {
    if (frames_) write_frame(frames_->stream(), sys_);
    if (energy_) write_energy(energy_->stream(), sys_);
  }
  void commit() {
    if (frames_) frames_->commit();
    if (energy_) energy_->commit();
  }

 private:
  const System& sys_;
  std::optional<AtomicFile> frames_, energy_;
};

std::string blow_up_message(const System& sys, Index bad, std::int64_t step, double t) {
  const auto x = sys.positions().col(bad);
  return fmt::format(
      "the state became non-finite at step {} (t = {:.17g} s): particle {} has position "
      "[{}, {}, {}]; the last good state (step {}) was written as the final frame. Try a "
      "smaller dt or a more stable solver.",
      step, t, bad, x(0), x(1), x(2), step - 1);
}

// Fixed steps of dt: step k ends at t0 + k dt, computed rather than
// accumulated so that time carries no round-off drift; the last step of a
// `duration` run is shortened to end exactly on it.
void run_fixed(Scene& scene, Output& out, Progress& progress, RunResult& result) {
  System& sys = *scene.system;
  const std::int64_t n_steps = scene.steps, every = scene.output.every;
  Eigen::VectorXd previous(sys.dimension());
  const double t0 = sys.time();
  bool last_written = true;
  for (std::int64_t k = 1; k <= n_steps; ++k) {
    const double t_begin = sys.time();
    const double t_end =
        k == n_steps ? t0 + scene.end_time : t0 + static_cast<double>(k) * scene.dt;
    const double h = t_end - t_begin;
    previous = sys.state();
    scene.solver->step(sys, h);
    sys.set_time(t_end);
    sys.respond_to_collisions(h);
    if (const Index bad = first_non_finite(sys); bad >= 0) {
      result.exit_code = 4;
      result.message = blow_up_message(sys, bad, k, t_end);
      sys.state() = previous;
      sys.set_time(t_begin);
      if (!last_written) out.emit();
      return;
    }
    result.steps_done = k;
    last_written = (every > 0 && k % every == 0) || k == n_steps;
    if (last_written) out.emit();
    progress.update(k, t_end);
  }
}

// Adaptive steps: the solver chooses each step's length; frames are due at
// t0 + m every dt (the times a fixed-step run would write them) and at the
// end. With dense output a frame is interpolated inside the step that
// crosses its time, so the step sequence does not depend on the output; a
// solver without it is stopped at each frame time instead.
void run_adaptive(Scene& scene, Output& out, Progress& progress, RunResult& result) {
  System& sys = *scene.system;
  Solver& solver = *scene.solver;
  const double t0 = sys.time(), t_end = t0 + scene.end_time;
  const double frame_dt = static_cast<double>(scene.output.every) * scene.dt;
  std::int64_t next_frame = 1;
  auto frame_time = [&](std::int64_t m) {
    const double tf = frame_dt > 0 ? t0 + static_cast<double>(m) * frame_dt : t_end;
    return std::min(tf, t_end);
  };
  Eigen::VectorXd previous(sys.dimension()), dense(sys.dimension()), current(sys.dimension());
  // Until a step has shown that the solver interpolates, stop on frame times.
  bool has_dense = false;
  std::int64_t k = 0;
  while (sys.time() < t_end) {
    const double t_begin = sys.time();
    const double t_stop = has_dense ? t_end : frame_time(next_frame);
    previous = sys.state();
    const double h = solver.advance(sys, t_stop, scene.dt);
    ++k;
    const double t_new = sys.time();
    if (const Index bad = first_non_finite(sys); bad >= 0) {
      result.exit_code = 4;
      result.message = blow_up_message(sys, bad, k, t_new);
      sys.state() = previous;
      sys.set_time(t_begin);
      out.emit();
      result.counts = solver.counts();
      return;
    }
    if (!has_dense) has_dense = solver.interpolate(t_new, dense);
    // Frames strictly inside this step come from the dense output, before the
    // collision response changes the state at the step's end.
    for (double tf; next_frame >= 0 && (tf = frame_time(next_frame)) < t_new;) {
      if (!solver.interpolate(tf, dense)) break;
      current = sys.state();
      sys.state() = dense;
      sys.set_time(tf);
      out.emit();
      sys.state() = current;
      sys.set_time(t_new);
      ++next_frame;
    }
    sys.respond_to_collisions(h);
    result.steps_done = k;
    if (next_frame >= 0 && frame_time(next_frame) <= t_new) {
      out.emit();
      next_frame = frame_time(next_frame) >= t_end ? -1 : next_frame + 1;
    }
    progress.update(k, t_new);
  }
  result.counts = solver.counts();
}

}  // namespace

RunResult run_scene(Scene& scene, const RunOptions& options) {
  System& sys = *scene.system;
  RunResult result;
  Output out(scene);
  Progress progress(options.progress ? options.log : nullptr, scene.steps, scene.end_time);
  out.emit();
  if (scene.solver->adaptive()) {
    run_adaptive(scene, out, progress, result);
  } else {
    run_fixed(scene, out, progress, result);
  }
  progress.update(result.steps_done, sys.time(), true);
  progress.finish();
  result.time = sys.time();
  out.commit();
  return result;
}

}  // namespace pdyn
