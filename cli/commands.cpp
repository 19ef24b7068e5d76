// The `pdyn` commands.
#include "commands.hpp"

#include <fmt/format.h>
#include <fmt/ostream.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <sstream>

#include "mpi_launch.hpp"
#include "pdyn/host/crash_report.hpp"
#include "pdyn/host/registry.hpp"
#include "pdyn/host/resolve.hpp"
#include "pdyn/host/runner.hpp"
#include "pdyn/host/scene.hpp"
#include "pdyn/host/version.hpp"
#include "pdyn/text.hpp"
#include "render.hpp"
#include "sdk_commands.hpp"

namespace pdyn::cli {

namespace fs = std::filesystem;

namespace {

struct Common {
  std::vector<std::string> plugin_path;
  std::vector<std::string> sets;
  bool quiet = false;
};

void add_plugin_path_option(CLI::App* app, Common& c) {
  cli::add_plugin_path_option(app, c.plugin_path);
}

PluginRegistry discover(const Common& c) {
  std::vector<fs::path> extra(c.plugin_path.begin(), c.plugin_path.end());
  PluginRegistry registry;
  registry.discover(PluginRegistry::search_path(extra, DefaultFolders::LibraryAndProgram));
  return registry;
}

// What a scene loaded but will not use (Scene::warnings): printed even with
// --quiet, as the run's result is probably not what the user meant.
void warn_scene(const Scene& scene, std::ostream& err) {
  for (const auto& w : scene.warnings) err << "pdyn: warning: " << w << "\n";
}

void warn_faults(const PluginRegistry& registry, std::ostream& err) {
  for (const auto& f : registry.faults()) {
    err << fmt::format("pdyn: warning: {}: plugin '{}' skipped: {}\n", f.library.string(), f.plugin,
                       f.message);
  }
}

// ---- run / validate ----

struct RunArgs {
  std::string scene;
  std::optional<std::int64_t> steps;
  std::optional<double> duration;
  std::string resume;             // checkpoint to continue from
  bool force = false;             // resume even if the scene changed
  bool strict = false;            // an energy that grows without a driving force: exit 4
  int threads = 0;                // --threads; 0: simulation.threads, else pdyn::default_threads
  std::string grid;               // --grid NX,NY,NZ under mpirun; "": the automatic grid
  std::vector<std::string> argv;  // the command as given, to print how to resume
};

// A word as a POSIX shell reads it back.
std::string shell_quote(const std::string& w) {
  if (!w.empty() && w.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                        "0123456789_-./=:,+@%") == std::string::npos) {
    return w;
  }
  std::string q = "'";
  for (char ch : w) q += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  return q + "'";
}

// "pdyn run ... --resume CKPT": the same command, continued from `checkpoint`.
std::string resume_command(const RunArgs& a, const fs::path& checkpoint) {
  std::string cmd = "pdyn";
  for (std::size_t i = 0; i < a.argv.size(); ++i) {
    if (a.argv[i] == "--resume") {
      ++i;
      continue;
    }
    if (a.argv[i].rfind("--resume=", 0) == 0) continue;
    cmd += " " + shell_quote(a.argv[i]);
  }
  return cmd + " --resume " + shell_quote(checkpoint.string());
}

Scene load(const RunArgs& a, const Common& c, const PluginRegistry& registry) {
  std::vector<Override> overrides;
  for (const auto& s : c.sets) overrides.push_back(parse_override(s));
  // --steps and --duration replace the scene's choice between the two.
  if (a.steps) {
    overrides.push_back({"simulation.duration", "~"});
    overrides.push_back({"simulation.steps", std::to_string(*a.steps)});
  } else if (a.duration) {
    overrides.push_back({"simulation.steps", "~"});
    overrides.push_back({"simulation.duration", fmt::format("{:.17g}", *a.duration)});
  }
  return load_scene(a.scene, registry, overrides);
}

int cmd_validate(const RunArgs& a, const Common& c, std::ostream& out, std::ostream& err) {
  const PluginRegistry registry = discover(c);
  if (!c.quiet) warn_faults(registry, err);
  try {
    Scene scene = load(a, c, registry);
    warn_scene(scene, err);
    if (!c.quiet) {
      // An adaptive solver chooses its own steps: dt is only the first one.
      const std::string stepping =
          scene.solver->adaptive()
              ? fmt::format("to t = {} s, first step {} s, then as the error tolerance allows",
                            scene.end_time, scene.dt)
              : fmt::format("{} of {} s", count_of(scene.steps, "step"), scene.dt);
      out << fmt::format(
          "{}: ok: {}, {}, {}, solver {}{}, {}\n", a.scene,
          count_of(scene.system->size(), "particle"),
          count_of(static_cast<long long>(scene.system->force_objects().size()), "force object"),
          count_of(static_cast<long long>(scene.system->collider_objects().size()), "collider"),
          scene.solver_name, scene.solver->adaptive() ? " (adaptive)" : "", stepping);
    }
    return kOk;
  } catch (...) {
    return report_error(std::current_exception(), err);
  }
}

// What `pdyn run` reports after a run: steps, particles, solver, wall
// time, force evaluations, where the outputs went.
void print_run_summary(std::ostream& out, const Scene& scene, const RunResult& r,
                       const std::optional<Checkpoint>& checkpoint, double wall,
                       std::uint64_t evaluations) {
  // A resumed run took only the steps after its checkpoint's.
  const std::int64_t first = checkpoint ? checkpoint->step : 0;
  const std::string steps =
      checkpoint ? fmt::format("{} (resumed at step {}; {} in all)",
                               count_of(r.steps_done - first, "step"), first, r.steps_done)
                 : count_of(r.steps_done, "step");
  out << fmt::format(
      "pdyn: {} of {} with {} to t = {} s in {:.3g} s (the steps {:.3g} s){}\n", steps,
      count_of(scene.system->size(), "particle"), scene.solver_name, r.time, wall, r.loop_seconds,
      scene.solver->adaptive() ? fmt::format(" ({} accepted, {} rejected)",
                                             count_of(r.counts.accepted, "step"), r.counts.rejected)
                               : "");
  // The cost of the run: what a solver or a plugin change is judged by.
  const double particle_steps =
      static_cast<double>(r.steps_done - first) * static_cast<double>(scene.system->size());
  out << fmt::format("pdyn: {}, {:.3g} particle-steps/s\n",
                     count_of(static_cast<long long>(evaluations), "force evaluation"),
                     wall > 0 ? particle_steps / wall : 0.0);
  for (const auto& w : scene.output.writers) {
    const std::string& type = w.record.descriptor->name;
    out << fmt::format("pdyn: {} written to {}\n",
                       type == "csv"      ? std::string("frames")
                       : type == "energy" ? std::string("energy")
                                          : type + " frames",
                       fs::absolute(w.path).string());
  }
  if (!r.checkpoint.empty()) {
    out << fmt::format("pdyn: checkpoint written to {}\n", fs::absolute(r.checkpoint).string());
  }
  if (!r.energy_warning.empty()) out << "pdyn: warning: " << r.energy_warning << "\n";
}

// Restores the --resume checkpoint into `scene`; the differences a --force
// resume accepts are told on `err`.
void restore_resumed(const RunArgs& a, const Checkpoint& checkpoint, Scene& scene,
                     std::ostream& err) {
  std::vector<std::string> differences;
  restore_checkpoint(scene, checkpoint, a.force, &differences);
  for (const auto& d : differences) {
    err << fmt::format("pdyn: warning: resuming with a changed scene (--force): {}\n", d);
  }
}

// The exit status of a finished run, with its one line on `err`.
std::optional<int> failed_run(const RunArgs& a, const RunResult& r, std::ostream& err) {
  switch (r.exit_code) {
    case 0:
      return std::nullopt;
    case 130:
      err << fmt::format("pdyn: interrupted at step {} (t = {} s); resume with: {}\n", r.steps_done,
                         r.time, resume_command(a, r.checkpoint));
      return kInterrupted;
    case 3:
      err << fmt::format("pdyn: {}; the last good frame and a checkpoint ({}) were written\n",
                         r.message, r.checkpoint.string());
      return kPluginFault;
    default:
      err << "pdyn: " << r.message << "\n";
      return kNonFinite;
  }
}

int cmd_run(const RunArgs& a, const Common& c, std::ostream& out, std::ostream& err,
            bool terminal) {
  // Under several MPI ranks (a pdyn built with MPI; docs/parallel.md) every
  // rank loads the scene, rank 0 a second copy that its output reads; only
  // rank 0 speaks, but for a rank's own failed step.
  if (!a.grid.empty() && mpi_world_size() <= 1) {
    err << fmt::format(
        "pdyn: --grid {}: a grid of MPI ranks, but this run has one process "
        "(expected mpirun -np N pdyn run ... --grid NX,NY,NZ)\n",
        a.grid);
    return kBadInput;
  }
  const std::unique_ptr<MpiRun> mpi = mpi_world_size() > 1 ? start_mpi_run() : nullptr;
  const bool root = mpi == nullptr || mpi->rank() == 0;
  std::ostringstream quiet_sink;
  std::ostream& say = root ? err : quiet_sink;
  const PluginRegistry registry = discover(c);
  if (!c.quiet) warn_faults(registry, say);
  try {
    Scene scene = load(a, c, registry);
    warn_scene(scene, say);
    RunOptions options;
    options.progress = terminal && !c.quiet && root;
    options.log = &err;
    options.handle_signals = true;
    options.threads = a.threads;
    options.strict = a.strict;
    std::optional<Checkpoint> checkpoint;
    if (!a.resume.empty()) {
      checkpoint = read_checkpoint(a.resume);
      restore_resumed(a, *checkpoint, scene, say);
      options.resume = &*checkpoint;
    }
    // A plugin that crashes is named in one line (crash_report.hpp).
    const crash::ReportCrashes report_crashes;
    const std::uint64_t evaluations_before = scene.system->force_evaluations();
    const auto start = std::chrono::steady_clock::now();
    std::optional<Scene> whole;
    const std::function<Scene()> load_whole = [&] {
      Scene w = load(a, c, registry);
      // Its warnings were told for the first copy.
      if (checkpoint) restore_resumed(a, *checkpoint, w, quiet_sink);
      return w;
    };
    const RunResult r =
        mpi == nullptr ? run_scene(scene, options)
                       : mpi->run(scene, root ? &load_whole : nullptr, whole, options, a.grid, err);
    if (!root) return r.exit_code;
    // Printed even with --quiet: the run's result is probably wrong.
    if (!r.energy_warning.empty()) err << "pdyn: warning: " << r.energy_warning << "\n";
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (const auto status = failed_run(a, r, err)) return *status;
    const std::uint64_t evaluations = mpi != nullptr
                                          ? mpi->evaluations()
                                          : scene.system->force_evaluations() - evaluations_before;
    if (!c.quiet) {
      print_run_summary(out, whole ? *whole : scene, r, checkpoint, wall, evaluations);
      if (mpi != nullptr) out << mpi->summary() << "\n";
    }
    return kOk;
  } catch (...) {
    const int status = report_error(std::current_exception(), say);
    if (mpi != nullptr) mpi->abort_if_running(status);
    return status;
  }
}

// ---- plugins ----

std::string range_text(const ParamSpec& s) {
  std::string r;
  if (s.min) r += fmt::format("{}{}", s.min_exclusive ? ">" : ">=", *s.min);
  if (s.max) r += fmt::format("{}<={}", r.empty() ? "" : ", ", *s.max);
  if (s.nonzero) r += r.empty() ? "nonzero" : ", nonzero";
  return r;
}

nlohmann::json to_json(const PluginRecord& r) {
  const PluginDescriptor& d = *r.descriptor;
  nlohmann::json j{{"kind", kind_name(d.kind)},
                   {"name", d.name},
                   {"version", d.version},
                   {"description", d.description},
                   {"library", r.library.string()}};
  if (d.kind == PluginKind::Solver) {
    j["order"] = d.solver_traits.order;
    j["symplectic"] = d.solver_traits.symplectic;
  }
  if (d.kind == PluginKind::Force) {
    j["internal"] = d.force_traits.internal;
    j["dissipative"] = d.force_traits.dissipative;
    j["singular"] = d.force_traits.singular;
  }
  if (d.kind == PluginKind::Writer) {
    j["fields"] = d.writer_traits.fields;
    j["default_fields"] = d.writer_traits.default_fields;
    j["energy"] = d.writer_traits.energy;
  }
  auto params = nlohmann::json::array();
  const Params defaults = resolve(d.params, Params{}).params;
  for (const auto& p : d.params) {
    nlohmann::json pj{{"name", p.name},
                      {"type", type_name(p.type)},
                      {"unit", p.unit},
                      {"doc", p.doc},
                      {"required", p.required}};
    if (const auto value = defaults.values().find(p.name); value != defaults.values().end()) {
      pj["default"] = format_value(value->second);
    }
    if (p.min) pj[p.min_exclusive ? "exclusive_minimum" : "minimum"] = *p.min;
    if (p.max) pj["maximum"] = *p.max;
    if (p.nonzero) pj["nonzero"] = true;
    params.push_back(pj);
  }
  j["params"] = params;
  return j;
}

std::string traits_text(const PluginDescriptor& d) {
  std::vector<std::string> t;
  if (d.kind == PluginKind::Solver) {
    if (d.solver_traits.order > 0) t.push_back(fmt::format("order {}", d.solver_traits.order));
    if (d.solver_traits.symplectic) t.push_back("symplectic");
  } else if (d.kind == PluginKind::Force) {
    if (d.force_traits.internal) t.push_back("internal");
    if (d.force_traits.dissipative) t.push_back("dissipative");
    if (d.force_traits.singular) t.push_back("singular");
  } else if (d.kind == PluginKind::Writer) {
    if (!d.writer_traits.fields.empty()) {
      t.push_back("fields " + join(d.writer_traits.fields, " "));
    }
    if (d.writer_traits.energy) t.push_back("energy");
  }
  return join(t);
}

int cmd_plugins(const Common& c, bool json, std::ostream& out) {
  const PluginRegistry registry = discover(c);
  if (json) {
    nlohmann::json j;
    j["plugins"] = nlohmann::json::array();
    for (const auto& r : registry.plugins()) j["plugins"].push_back(to_json(r));
    j["faults"] = nlohmann::json::array();
    for (const auto& f : registry.faults()) {
      j["faults"].push_back(
          {{"library", f.library.string()}, {"plugin", f.plugin}, {"message", f.message}});
    }
    j["shadowed"] = nlohmann::json::array();
    for (const auto& h : registry.shadowed()) {
      j["shadowed"].push_back(
          {{"library", h.library.string()}, {"plugin", h.plugin}, {"by", h.by.string()}});
    }
    j["searched"] = nlohmann::json::array();
    for (const auto& s : registry.searched()) j["searched"].push_back(s.string());
    out << j.dump(2) << "\n";
    return kOk;
  }
  // Columns as wide as their longest entry, so that long names stay aligned.
  std::size_t name_w = 12, version_w = 8, traits_w = 16;
  for (const auto& r : registry.plugins()) {
    name_w = std::max(name_w, r.descriptor->name.size());
    version_w = std::max(version_w, r.descriptor->version.size());
    traits_w = std::max(traits_w, traits_text(*r.descriptor).size());
  }
  out << fmt::format("{:<9} {:<{}} {:<{}} {:<{}} {}\n", "KIND", "NAME", name_w, "VERSION",
                     version_w, "TRAITS", traits_w, "DESCRIPTION");
  for (PluginKind kind : {PluginKind::Force, PluginKind::Solver, PluginKind::Collider,
                          PluginKind::Writer, PluginKind::Constraint}) {
    for (const auto& r : registry.plugins()) {
      const PluginDescriptor& d = *r.descriptor;
      if (d.kind != kind) continue;
      out << fmt::format("{:<9} {:<{}} {:<{}} {:<{}} {}\n", kind_name(d.kind), d.name, name_w,
                         d.version, version_w, traits_text(d), traits_w, d.description);
    }
  }
  out << "\nfrom:\n";
  for (const auto& s : registry.searched()) out << "  " << s.string() << "\n";
  for (const auto& h : registry.shadowed()) {
    out << fmt::format("\nshadowed: {}: plugin '{}' (provided by {}, an earlier default folder)\n",
                       h.library.string(), h.plugin, h.by.string());
  }
  for (const auto& f : registry.faults()) {
    out << fmt::format("\nerror: {}: plugin '{}': {}\n", f.library.string(), f.plugin, f.message);
  }
  return kOk;
}

int cmd_describe(const Common& c, const std::string& name, std::ostream& out, std::ostream& err) {
  const PluginRegistry registry = discover(c);
  const PluginRecord* r = registry.find_any(name);
  if (!r) {
    try {
      registry.require_healthy(name);
    } catch (const PluginError& e) {
      err << e.what() << "\n";
      return kPluginFault;
    }
    std::vector<std::string> all;
    for (const auto& p : registry.plugins()) all.push_back(p.descriptor->name);
    const std::string guess = closest_match(name, all);
    err << fmt::format("pdyn: no plugin named '{}' ({}expected one of: {})\n", name,
                       guess.empty() ? "" : fmt::format("did you mean '{}'? ", guess), join(all));
    return kBadInput;
  }
  const PluginDescriptor& d = *r->descriptor;
  out << fmt::format("{} {} {}\n  {}\n  library: {}\n", kind_name(d.kind), d.name, d.version,
                     d.description, r->library.string());
  if (const auto t = traits_text(d); !t.empty()) out << "  traits: " << t << "\n";
  if (d.params.empty()) {
    out << "  no parameters\n";
    return kOk;
  }
  // Columns as wide as their widest entry: a long unit (m^3/(kg s^2)) or
  // default must not push the rest of its row out of line.
  std::vector<std::array<std::string, 6>> rows{
      {"KEY", "TYPE", "DEFAULT", "UNIT", "RANGE", "MEANING"}};
  // The defaults as a scene gets them: from the one resolver, as the loader does.
  const Params defaults = resolve(d.params, Params{}).params;
  for (const auto& p : d.params) {
    const auto value = defaults.values().find(p.name);
    rows.push_back({p.name, type_name(p.type),
                    value != defaults.values().end() ? format_value(value->second)
                    : p.required                     ? "(required)"
                                                     : "(optional)",
                    p.unit.empty() ? "-" : p.unit, range_text(p), p.doc});
  }
  std::array<std::size_t, 5> width{};
  for (const auto& row : rows) {
    for (std::size_t col = 0; col < width.size(); ++col)
      width[col] = std::max(width[col], row[col].size());
  }
  out << "\n";
  for (const auto& row : rows) {
    out << fmt::format("  {:<{}} {:<{}} {:<{}} {:<{}} {:<{}} {}\n", row[0], width[0], row[1],
                       width[1], row[2], width[2], row[3], width[3], row[4], width[4], row[5]);
  }
  return kOk;
}

}  // namespace

int report_error(const std::exception_ptr& error, std::ostream& err) {
  try {
    std::rethrow_exception(error);
  } catch (const SceneError& e) {
    for (const auto& d : e.diagnostics()) err << d.text() << "\n";
    return kBadInput;
  } catch (const PluginError& e) {
    err << e.what() << "\n";
    return kPluginFault;
  } catch (const CheckpointError& e) {
    err << "pdyn: " << e.what() << "\n";
    return kBadInput;
  } catch (const std::exception& e) {
    err << "pdyn: " << e.what() << "\n";
    return kFailure;
  } catch (...) {
    // Rethrowing it from here would end the process with std::terminate.
    err << "pdyn: internal error: a non-standard exception\n";
    return kFailure;
  }
}

int write_text_output(const std::string& text, const std::string& output, std::ostream& out,
                      std::ostream& err) {
  if (output.empty()) {
    out << text;
    return kOk;
  }
  const fs::path target(output), tmp = fs::path(output + ".tmp");
  std::ofstream file(tmp, std::ios::binary);
  file << text;
  file.close();
  std::error_code ec;
  if (!file || (fs::rename(tmp, target, ec), ec)) {
    fs::remove(tmp, ec);
    err << fmt::format("pdyn: cannot write {}\n", output);
    return kFailure;
  }
  return kOk;
}

void add_plugin_path_option(CLI::App* sub, std::vector<std::string>& plugin_path,
                            const char* help) {
  const CLI::Validator folder(
      [](std::string& dir) -> std::string { return PluginRegistry::folder_problem(dir); },
      "FOLDER");
  sub->add_option("--plugin-path", plugin_path,
                  help ? help
                       : "folder to search for plugins before $PDYN_PLUGIN_PATH and the shipped "
                         "ones (repeatable)")
      ->allow_extra_args(false)
      ->check(folder);
}

void add_scene_options(CLI::App* sub, std::vector<std::string>& sets,
                       std::vector<std::string>& plugin_path) {
  // One value per occurrence, so that `--set K=V scene.yaml` leaves the scene
  // to the positional argument.
  sub->add_option("--set", sets,
                  "override a scene value: KEY.PATH=VALUE, e.g. simulation.dt=0.0005 or "
                  "forces[0].g=[0,0,-1.62] (repeatable)")
      ->allow_extra_args(false);
  add_plugin_path_option(sub, plugin_path);
}

// A lower bound, printed as "at least 0". CLI11's NonNegativeNumber checks
// the range [0, DBL_MAX] and prints the upper bound in full: 309 digits.
// Text that is not a number is left to the option's own conversion.
CLI::Validator at_least(double min) {
  return CLI::Validator(
      [min](std::string& text) -> std::string {
        char* end = nullptr;
        const double x = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || x >= min) return {};
        return fmt::format("{} is out of range (expected at least {})", text, min);
      },
      fmt::format(">= {}", min));
}

namespace {

// Parses `args` into `app`; an exit status when the command is done
// already: help or the version printed, a bad command line, or several MPI
// ranks (each would run the whole scene and overwrite the others' files:
// refused before anything is read).
std::optional<int> parse_command_line(CLI::App& app, const std::vector<std::string>& args,
                                      std::ostream& out, std::ostream& err) {
  std::vector<std::string> reversed(args.rbegin(), args.rend());
  try {
    app.parse(reversed);
  } catch (const CLI::CallForHelp&) {
    out << app.help();
    return kOk;
  } catch (const CLI::CallForAllHelp&) {
    out << app.help("", CLI::AppFormatMode::All);
    return kOk;
  } catch (const CLI::CallForVersion& e) {
    out << e.what() << "\n";
    return kOk;
  } catch (const CLI::ParseError& e) {
    err << "pdyn: " << e.what() << " (see pdyn --help)\n";
    return kBadInput;
  }
  const std::string command =
      app.get_subcommands().empty() ? "" : app.get_subcommands().front()->get_name();
  if (const std::string why = several_mpi_ranks(command); !why.empty()) {
    err << "pdyn: " << why << "\n";
    return kBadInput;
  }
  return std::nullopt;
}

}  // namespace

int run_command(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
                bool terminal) {
  CLI::App app{"pdyn: plugin-based particle dynamics (Witkin's particle systems)", "pdyn"};
  app.require_subcommand(1);
  // The program's version and the plugin ABI it loads: what a plugin built
  // elsewhere must match (pdyn/version.hpp).
  app.set_version_flag("--version",
                       fmt::format("pdyn {} (plugin ABI {})", host::version(), kAbiVersion));
  Common common;
  RunArgs run_args;

  auto scene_options = [&](CLI::App* sub) {
    sub->add_option("scene", run_args.scene, "scene file (YAML)")->required();
    add_scene_options(sub, common.sets, common.plugin_path);
    sub->add_flag("--quiet,-q", common.quiet, "print only errors");
  };
  CLI::App* run = app.add_subcommand("run", "run a scene");
  scene_options(run);
  auto* steps = run->add_option("--steps", run_args.steps, "number of steps (replaces the scene's)")
                    ->check(at_least(0));
  run->add_option("--duration", run_args.duration, "simulated time in s (replaces the scene's)")
      ->check(at_least(0))
      ->excludes(steps);
  run->add_option("--threads", run_args.threads,
                  "threads for forces and solvers (default: simulation.threads, else one per "
                  "4096 particles, up to all cores); results are bit-identical for every count")
      ->check(CLI::Range(1, 1024));
  run->add_option("--resume", run_args.resume,
                  "continue from a checkpoint written by an earlier run of this scene");
  run->add_flag("--force", run_args.force,
                "with --resume: continue even if the scene changed (says what differs)");
  run->add_option("--grid", run_args.grid,
                  "under mpirun: the ranks' grid of subdomains, NX,NY,NZ (default: the grid with "
                  "the least subdomain surface; docs/parallel.md)");
  run->add_flag("--strict", run_args.strict,
                "stop with exit status 4 when the total energy grows more than a millionfold "
                "with no force driving it (default: a warning)");

  CLI::App* validate = app.add_subcommand("validate", "check a scene without simulating");
  scene_options(validate);

  CLI::App* plugins = app.add_subcommand("plugins", "list the plugins found");
  bool json = false;
  plugins->add_flag("--json", json, "machine-readable listing");
  add_plugin_path_option(plugins, common);
  std::string describe_name;
  CLI::App* describe_cmd = plugins->add_subcommand("describe", "show one plugin's parameters");
  describe_cmd->add_option("name", describe_name, "plugin name")->required();
  add_plugin_path_option(describe_cmd, common);
  std::vector<SdkCommand> sdk = add_sdk_commands(app);
  sdk.push_back(add_render_command(app));
  sdk.push_back(add_serve_command(app));
  sdk.push_back(add_convert_command(app));

  if (const auto stop = parse_command_line(app, args, out, err)) return *stop;
  try {
    run_args.argv = args;
    if (run->parsed()) return cmd_run(run_args, common, out, err, terminal);
    if (validate->parsed()) return cmd_validate(run_args, common, out, err);
    if (describe_cmd->parsed()) return cmd_describe(common, describe_name, out, err);
    if (plugins->parsed()) return cmd_plugins(common, json, out);
    for (const auto& command : sdk)
      if (command.sub->parsed()) return command.run(out, err);
  } catch (...) {
    return report_error(std::current_exception(), err);
  }
  return kBadInput;
}

}  // namespace pdyn::cli
