// Simulation: a scene stepped under a program's control, with pdyn run's
// step schedule (see run_fixed and run_adaptive in runner.cpp).
#include "pdyn/host/simulation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "pdyn/host/assembly.hpp"
#include "pdyn/host/threads.hpp"
#include "pdyn/parallel.hpp"

namespace pdyn {

namespace {

// What a failed step leaves: the caller's simulation is back at its start.
constexpr std::string_view kKept = "is kept: the simulation is at it";
// How often an interruption callback is asked: rarely enough to cost
// nothing, often enough to answer Ctrl-C within a fraction of a second.
constexpr std::int64_t kPollEvery = 64;

// A value written into the state from outside (a script) that no step
// could have produced: refused before stepping from it.
void require_finite(const System& sys) {
  const auto x = sys.positions();
  const auto v = sys.velocities();
  for (Index i = 0; i < sys.size(); ++i) {
    for (const auto& [name, col] : {std::pair{"position", x.col(i)}, {"velocity", v.col(i)}}) {
      if (!col.allFinite()) {
        throw Error(
            fmt::format("particle {} has a non-finite {} [{}, {}, {}] (expected finite "
                        "values: it was written from outside the simulation)",
                        i, name, col(0), col(1), col(2)));
      }
    }
  }
}

}  // namespace

Simulation::Simulation(Scene scene, int threads)
    : scene_(std::move(scene)),
      threads_(threads > 0          ? threads
               : scene_.threads > 0 ? scene_.threads
                                    : default_threads(scene_.system->size())) {
  set_threads(threads_);
  stepper_ = std::make_unique<Stepper>(*scene_.system, *scene_.solver, scene_.solver_label,
                                       scene_.neighbor_schedule);
}

template <class Take>
void Simulation::take(const Take& take_step) {
  if (!take_step()) {
    const StepFault& f = stepper_->fault();
    throw StepError(step_fault_message(f, scene_, steps_ + 1, kKept), f);
  }
  ++steps_;
}

std::int64_t Simulation::step(std::int64_t n, const std::function<bool()>& interrupted) {
  require_finite(system());
  for (std::int64_t i = 0; i < n; ++i) {
    if (interrupted && i > 0 && i % kPollEvery == 0 && interrupted()) return i;
    step_once(std::numeric_limits<double>::max());
  }
  return n;
}

std::int64_t Simulation::run_until(double t_end, std::int64_t max_steps,
                                   const std::function<bool()>& interrupted) {
  require_finite(system());
  // A time within rounding of t_end has reached it: 3 * 0.1 s is not 0.3 s.
  const double reached = t_end - 1e-9 * scene_.dt;
  std::int64_t taken = 0;
  while (system().time() < reached && taken < max_steps) {
    if (interrupted && taken > 0 && taken % kPollEvery == 0 && interrupted()) break;
    step_once(t_end);
    ++taken;
  }
  return taken;
}

std::int64_t Simulation::run_to_end(const std::function<bool()>& interrupted) {
  return run_until(scene_.end_time, std::numeric_limits<std::int64_t>::max(), interrupted);
}

void Simulation::step_once(double limit) {
  System& sys = system();
  Solver& solver = *scene_.solver;
  const double end = scene_.end_time, dt = scene_.dt;
  const std::int64_t k = steps_ + 1;
  if (!solver.adaptive()) {
    // pdyn run's step times: k dt, the last step of a `duration` scene on
    // the duration; after a change of dt or solver, from that time on.
    const double t = clock_step_ == 0 && clock_time_ == 0.0 && k == scene_.steps
                         ? end
                         : clock_time_ + static_cast<double>(k - clock_step_) * dt;
    if (t > limit + 1e-9 * dt) {  // shortened to end on `limit`; the step times restart there
      take([&] { return stepper_->step_to(limit); });
      restart_clock();
    } else {
      take([&] { return stepper_->step_to(t); });
    }
    return;
  }
  // Until the solver shows dense output, each step stops on the next frame
  // time of the scene's output, as in pdyn run; past the scene's end only
  // `limit` bounds it.
  const double frame_dt = static_cast<double>(scene_.output.period()) * dt;
  auto frame_time = [&](std::int64_t m) {
    return frame_dt > 0 ? std::min(static_cast<double>(m) * frame_dt, end) : end;
  };
  const double stop = std::min(sys.time() >= end ? std::numeric_limits<double>::max()
                               : has_dense_      ? end
                                                 : frame_time(next_frame_),
                               limit);
  take([&] { return stepper_->advance(stop, dt); });
  if (has_dense_) return;
  dense_.resize(sys.dimension());
  has_dense_ = solver.interpolate(sys.time(), dense_);
  if (!has_dense_ && frame_dt > 0 && static_cast<double>(next_frame_) * frame_dt <= end &&
      frame_time(next_frame_) <= sys.time()) {
    ++next_frame_;
  }
}

void Simulation::restart_clock() {
  clock_step_ = steps_;
  clock_time_ = system().time();
}

void Simulation::set_dt(double dt) {
  if (!(dt > 0) || !std::isfinite(dt)) {
    throw Error(fmt::format("dt = {} s (expected a finite time step > 0)", dt));
  }
  scene_.dt = dt;
  restart_clock();
}

void Simulation::solver_changed() {
  stepper_ = std::make_unique<Stepper>(*scene_.system, *scene_.solver, scene_.solver_label,
                                       scene_.neighbor_schedule);
  has_dense_ = false;
  restart_clock();
}

void Simulation::save_checkpoint(const std::filesystem::path& path) const {
  Checkpoint c = capture_checkpoint(scene_, steps_);
  c.next_frame = next_frame_;
  c.has_dense = has_dense_;
  write_checkpoint(path, c);
}

void Simulation::restore_checkpoint(const std::filesystem::path& path, bool force,
                                    std::string_view anyway) {
  const Checkpoint c = read_checkpoint(path);
  pdyn::restore_checkpoint(scene_, c, force, nullptr, anyway);
  steps_ = c.step;
  next_frame_ = c.next_frame > 0 ? c.next_frame : 1;
  has_dense_ = c.has_dense;
  // A checkpoint of a run whose step times never restarted is at k dt
  // exactly, and continues k dt as pdyn run --resume does; any other (dt
  // or the solver changed before it) continues from its own time.
  const bool at_origin = static_cast<double>(c.step) * scene_.dt == c.time ||
                         (c.step == scene_.steps && c.time == scene_.end_time);
  clock_step_ = at_origin ? 0 : c.step;
  clock_time_ = at_origin ? 0.0 : c.time;
}

std::unique_ptr<System> Simulation::add_particles(const Matrix3X& x, const Matrix3X& v,
                                                  const Eigen::VectorXd& mass,
                                                  const std::vector<std::uint8_t>& fixed) {
  const System& old = system();
  const Index n = old.size(), added = x.cols();
  Matrix3X xs(3, n + added), vs(3, n + added);
  xs << old.positions(), x;
  vs << old.velocities(), v;
  Eigen::VectorXd m(n + added);
  m << old.masses(), mass;
  std::vector<std::uint8_t> f = old.fixed();
  f.insert(f.end(), fixed.begin(), fixed.end());
  auto sys = std::make_unique<System>();
  const SystemAssembly assembly(*sys);
  assembly.set_particles(xs, vs, m, f);
  sys->set_time(old.time());
  assembly.set_domain(old.domain());
  if (!old.radii().empty()) {
    auto r = old.radii();
    r.resize(static_cast<std::size_t>(n + added), 0.0);
    assembly.set_radii(std::move(r));
  }
  if (!old.types().empty()) {
    auto t = old.types();
    t.resize(static_cast<std::size_t>(n + added), 0);
    assembly.set_types(std::move(t));
  }
  auto images = old.images();
  images.resize(static_cast<std::size_t>(n + added), {0, 0, 0});
  assembly.set_images(std::move(images));
  for (const auto& e : old.force_objects()) assembly.add_force(e.force, e.label);
  for (const auto& c : old.collider_objects()) assembly.add_collider(c.collider, c.label);
  std::swap(scene_.system, sys);
  stepper_ = std::make_unique<Stepper>(*scene_.system, *scene_.solver, scene_.solver_label,
                                       scene_.neighbor_schedule);
  return sys;
}

}  // namespace pdyn
