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

RunResult run_scene(Scene& scene, const RunOptions& options) {
  System& sys = *scene.system;
  RunResult result;
  std::optional<AtomicFile> frames, energy;
  if (!scene.output.path.empty()) {
    frames.emplace(scene.output.path);
    std::fputs("t,id,x,y,z,vx,vy,vz\n", frames->stream());
  }
  if (!scene.output.energy.empty()) {
    energy.emplace(scene.output.energy);
    std::fputs("t,kinetic,potential,total\n", energy->stream());
  }
  auto emit = [&] {
    if (frames) write_frame(frames->stream(), sys);
    if (energy) write_energy(energy->stream(), sys);
  };

  const std::int64_t n_steps = scene.steps;
  const std::int64_t every = scene.output.every;
  Progress progress(options.progress ? options.log : nullptr, n_steps, scene.end_time);
  Eigen::VectorXd previous(sys.dimension());
  const double t0 = sys.time();
  emit();
  bool last_written = true;
  for (std::int64_t k = 1; k <= n_steps; ++k) {
    // Step k ends at t0 + k dt, computed rather than accumulated so that time
    // carries no round-off drift; the last step of a `duration` run is
    // shortened to end exactly on it.
    const double t_begin = sys.time();
    const double t_end = k == n_steps ? t0 + scene.end_time : t0 + static_cast<double>(k) * scene.dt;
    const double h = t_end - t_begin;
    previous = sys.state();
    scene.solver->step(sys, h);
    sys.set_time(t_end);
    sys.respond_to_collisions(h);
    if (const Index bad = first_non_finite(sys); bad >= 0) {
      const auto x = sys.positions().col(bad);
      result.exit_code = 4;
      result.message = fmt::format(
          "the state became non-finite at step {} (t = {:.17g} s): particle {} has position "
          "[{}, {}, {}]; the last good state (step {}) was written as the final frame. Try a "
          "smaller dt or a more stable solver.",
          k, t_end, bad, x(0), x(1), x(2), k - 1);
      sys.state() = previous;
      sys.set_time(t_begin);
      if (!last_written) emit();
      break;
    }
    result.steps_done = k;
    last_written = (every > 0 && k % every == 0) || k == n_steps;
    if (last_written) emit();
    progress.update(k, t_end);
  }
  progress.update(result.steps_done, sys.time(), true);
  progress.finish();
  result.time = sys.time();
  if (frames) frames->commit();
  if (energy) energy->commit();
  return result;
}

}  // namespace pdyn
