// Resuming from a checkpoint: match it to the scene, then apply it.
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>

#include "pdyn/force_reuse.hpp"
#include "pdyn/host/assembly.hpp"
#include "pdyn/host/crash_report.hpp"
#include "pdyn/host/runner.hpp"
#include "pdyn/text.hpp"

namespace pdyn {

namespace {

std::string flow(const YAML::Node& n) {
  if (!n.IsDefined()) return "(absent)";
  YAML::Node one_line = YAML::Clone(n);  // a block-style node keeps its style otherwise
  one_line.SetStyle(YAML::EmitterStyle::Flow);
  YAML::Emitter e;
  e << one_line;
  return e.c_str();
}

// One line per path where the two scene trees differ.
void diff(const YAML::Node& a, const YAML::Node& b, const std::string& path,
          std::vector<std::string>& out) {
  const std::string here = path.empty() ? "(scene)" : path;
  // A key on one side only: yaml-cpp's missing node throws on anything but
  // IsDefined(), so it is told apart first.
  const bool both = a.IsDefined() && b.IsDefined();
  if (both && a.IsMap() && b.IsMap()) {
    std::vector<std::string> keys;
    for (const auto& kv : a) keys.push_back(kv.first.Scalar());
    for (const auto& kv : b) {
      if (!a[kv.first.Scalar()].IsDefined()) keys.push_back(kv.first.Scalar());
    }
    for (const auto& k : keys) {
      diff(a[k], b[k], path.empty() ? k : path + "." + k, out);
    }
    return;
  }
  if (both && a.IsSequence() && b.IsSequence() && a.size() == b.size()) {
    for (std::size_t i = 0; i < a.size(); ++i)
      diff(a[i], b[i], fmt::format("{}[{}]", path, i), out);
    return;
  }
  const std::string fa = flow(a), fb = flow(b);
  if (fa != fb) out.push_back(fmt::format("{}: {} in the checkpoint, {} now", here, fa, fb));
}

// The checkpoint's scene against this one: refused unless `force`, else
// the differences listed in `differences`.
void compare_scenes(const Scene& scene, const Checkpoint& c, bool force,
                    std::vector<std::string>* differences, std::string_view anyway) {
  if (c.scene_text != scene.canonical_text) {
    std::vector<std::string> lines;
    try {
      diff(YAML::Load(c.scene_text), YAML::Load(scene.canonical_text), "", lines);
    } catch (const YAML::Exception&) {
      lines.push_back("(the checkpoint's scene text cannot be parsed)");
    }
    if (lines.empty()) lines.push_back("(formatting only)");
    if (!force) {
      throw CheckpointError(fmt::format(
          "the checkpoint was written for a different scene ({}): {} (expected the same scene; "
          "{})",
          c.scene_file,
          lines.front() + (lines.size() > 1 ? fmt::format(" and {} more", lines.size() - 1) : ""),
          anyway));
    }
    if (differences) *differences = lines;
  }
}

// Particles, image counts, plugin objects and the run's end: refused
// unless they match.
void check_counts(const Scene& scene, const Checkpoint& c) {
  const System& sys = *scene.system;
  if (c.mass.size() != sys.size()) {
    throw CheckpointError(
        fmt::format("the checkpoint holds {} but the scene has {} "
                    "(expected the same particles)",
                    count_of(static_cast<long long>(c.mass.size()), "particle"), sys.size()));
  }
  if (!c.images.empty() && static_cast<Index>(c.images.size()) != sys.size()) {
    throw CheckpointError(fmt::format(
        "the checkpoint holds image counts of {} but the scene has {} (expected the same "
        "particles)",
        count_of(static_cast<long long>(c.images.size()), "particle"), sys.size()));
  }
  if (c.box) {  // a barostat's box: the scene's periodic axes, open axes unchanged
    const Domain& d = sys.domain();
    for (int k = 0; k < 3; ++k) {
      const bool same_kind = c.box->periodic[k] == d.periodic[k];
      const bool sound = d.periodic[k]
                             ? std::isfinite(c.box->min[k]) && std::isfinite(c.box->max[k]) &&
                                   c.box->min[k] < c.box->max[k]
                             : c.box->min[k] == d.min[k] && c.box->max[k] == d.max[k];
      if (!same_kind || !sound) {
        throw CheckpointError(fmt::format(
            "the checkpoint's box runs from {} to {} m along {} ({}), which the scene's box "
            "cannot become (expected the same periodic axes, min < max along them, the open "
            "axes' bounds unchanged)",
            c.box->min[k], c.box->max[k], "xyz"[k], c.box->periodic[k] ? "periodic" : "open"));
      }
    }
  }
  const std::size_t expected = 1 + sys.force_objects().size() + sys.collider_objects().size();
  if (c.plugin_states.size() != expected) {
    throw CheckpointError(
        fmt::format("the checkpoint holds the state of {} plugin objects but "
                    "the scene has {} (expected the same solver, forces and "
                    "colliders)",
                    c.plugin_states.size(), expected));
  }
  // An adaptive solver's steps are accepted steps, unrelated to the scene's
  // nominal step count: only the time tells whether it is past the end.
  const bool adaptive = scene.solver && scene.solver->adaptive();
  if ((!adaptive && c.step > scene.steps) || c.time > scene.end_time) {
    throw CheckpointError(
        fmt::format("the checkpoint is at step {} (t = {} s), past the end of "
                    "this run (step {}, t = {} s); expected a longer run",
                    c.step, c.time, scene.steps, scene.end_time));
  }
}

}  // namespace

void restore_checkpoint(Scene& scene, const Checkpoint& c, bool force,
                        std::vector<std::string>* differences, std::string_view anyway) {
  System& sys = *scene.system;
  compare_scenes(scene, c, force, differences, anyway);
  check_counts(scene, c);
  // Every check passed: apply. A plugin that refuses its bytes leaves the
  // run unstarted (the caller exits), so nothing half-applied is simulated.
  auto restore = [&](PluginObject& obj, std::size_t i) {
    try {
      obj.restore_state(c.plugin_states[i].second);
    } catch (const std::exception& e) {
      throw CheckpointError(fmt::format("{}: cannot restore its state from the checkpoint: {}",
                                        c.plugin_states[i].first, e.what()));
    }
  };
  std::size_t i = 0;
  restore(*scene.solver, i++);
  for (const auto& f : sys.force_objects()) restore(*f.force, i++);
  for (const auto& col : sys.collider_objects()) restore(*col.collider, i++);
  Matrix3X x = Eigen::Map<const Matrix3X>(c.state.data(), 3, sys.size());
  Matrix3X v = Eigen::Map<const Matrix3X>(c.state.data() + 3 * sys.size(), 3, sys.size());
  // Radii and types are the scene's (which the checkpoint matches);
  // set_particles clears them. The box and the images are the run's (a
  // barostat changes the box; an older checkpoint keeps the scene's).
  std::vector<double> radius = sys.radii();
  std::vector<std::int32_t> type = sys.types();
  const SystemAssembly assembly(sys);
  assembly.set_particles(x, v, c.mass, c.fixed);
  assembly.set_radii(std::move(radius));
  assembly.set_types(std::move(type));
  if (c.images.empty()) {  // a checkpoint made in memory without them: nothing wrapped
    assembly.set_images(std::vector<std::array<std::int32_t, 3>>(c.mass.size(), {0, 0, 0}));
  } else {
    assembly.set_images(c.images);
  }
  if (c.box) assembly.set_domain(*c.box);
  sys.set_time(c.time);
  // Last, after every write above: the end-of-step accelerations the solver
  // kept when the checkpoint was taken stand in for its next a0 again
  // (pdyn/force_reuse.hpp), as in the uninterrupted run.
  if (auto* holder = dynamic_cast<ForceReuseHolder*>(scene.solver.get());
      holder != nullptr && c.reused.cols() == sys.size()) {
    holder->restore_kept_accelerations(sys, c.reused);
  }
}

Checkpoint capture_checkpoint(const Scene& scene, std::int64_t step) {
  const System& sys = *scene.system;
  Checkpoint c;
  c.scene_file = scene.file;
  c.scene_text = scene.canonical_text;
  c.step = step;
  c.time = sys.time();
  c.state = sys.state();
  c.mass = sys.masses();
  c.fixed = sys.fixed();
  c.images = sys.images();
  c.box = sys.domain();
  if (const auto* holder = dynamic_cast<const ForceReuseHolder*>(scene.solver.get())) {
    if (const Matrix3X* a1 = holder->kept_accelerations(sys)) c.reused = *a1;
  }
  {
    const crash::CallScope call(scene.solver_label, "save_state");
    c.plugin_states.emplace_back(scene.solver_label, scene.solver->save_state());
  }
  for (const auto& f : sys.force_objects()) {
    const crash::CallScope call(f.label, "save_state");
    c.plugin_states.emplace_back(f.label, f.force->save_state());
  }
  for (const auto& col : sys.collider_objects()) {
    const crash::CallScope call(col.label, "save_state");
    c.plugin_states.emplace_back(col.label, col.collider->save_state());
  }
  return c;
}

}  // namespace pdyn
