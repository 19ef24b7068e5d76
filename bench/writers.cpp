// Output writers on the hanging cloth (issue 15): the 316 x 316 cloth of
// tests/scenes/shared/cloth.yaml with rk4, a frame every 10th step, run
// side by side in one process with no writer, csv, vtk and h5md (and csv
// + vtk + h5md together). For each: wall time, overhead over the run without
// output, the run's own time spent on output (copying frames for the output
// thread and waiting for it), bytes written, bytes per particle-frame and
// the writer's throughput in MB/s (bytes / its time in write() on the
// output thread, which overlaps the steps, and in commit()).
// Each variant runs `repeats` times, interleaved, and the fastest run of
// each is reported, so that a slow moment of the machine hits all alike.
//
//   pdyn_bench_writers [N [STEPS [DIR [REPEATS [THREADS]]]]]
//     N 316, STEPS 200, DIR /tmp/pdyn-bench-writers (the disk measured),
//     REPEATS 3, THREADS 0 (all cores)
//
// bench/writers_dd.sh runs it beside dd writing to the same folder.
#include <fmt/format.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "pdyn/host/registry.hpp"
#include "pdyn/host/runner.hpp"
#include "pdyn/host/scene.hpp"

namespace {

namespace fs = std::filesystem;

struct Variant {
  std::string name;
  std::string output;  // the value of `output:` (YAML), or "" for none
  double best = std::numeric_limits<double>::infinity();
  double writing = 0.0, stalled = 0.0;  // of the fastest run, s
  std::uintmax_t bytes = 0;
};

std::uintmax_t bytes_under(const fs::path& dir) {
  std::uintmax_t n = 0;
  std::error_code ec;
  if (!fs::exists(dir, ec)) return 0;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) n += e.file_size();
  }
  return n;
}

}  // namespace

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::atoi(argv[1]) : 316;
  const int steps = argc > 2 ? std::atoi(argv[2]) : 200;
  const fs::path dir = argc > 3 ? fs::path(argv[3]) : fs::path("/tmp/pdyn-bench-writers");
  const int repeats = argc > 4 ? std::atoi(argv[4]) : 3;
  const int threads = argc > 5 ? std::atoi(argv[5]) : 0;
  constexpr int kEvery = 10;
  pdyn::PluginRegistry registry;
  registry.discover({PDYN_PLUGIN_DIR});

  auto entry = [&](const char* type, const char* file, const char* extra = "") {
    return fmt::format("{{type: {}, path: '{}', every: {}{}}}", type, (dir / "out" / file).string(),
                       kEvery, extra);
  };
  std::vector<Variant> variants = {
      {"none", ""},
      {"csv", "[" + entry("csv", "run.csv") + "]"},
      {"vtk", "[" + entry("vtk", "run.pvd", ", fields: [velocity]") + "]"},
      {"h5md", "[" + entry("h5md", "run.h5", ", fields: [velocity]") + "]"},
      {"vtk+h5md+csv", "[" + entry("vtk", "all.pvd", ", fields: [velocity]") + ", " +
                           entry("h5md", "all.h5", ", fields: [velocity]") + ", " +
                           entry("csv", "all.csv") + "]"},
  };
  const double frames = steps / kEvery + 1;  // NOLINT(bugprone-integer-division): whole frames
  const double particle_frames = frames * n * n;
  fmt::print(
      "pdyn_bench_writers: {0} x {0} cloth, rk4, {1} steps, a frame every {2} steps ({3} "
      "frames), {4} repeats, output in {5}\n",
      n, steps, kEvery, frames, repeats, dir.string());
  for (int r = 0; r < repeats; ++r) {
    for (auto& v : variants) {
      std::error_code ec;
      fs::remove_all(dir / "out", ec);
      std::vector<pdyn::Override> set = {{"particles[0].grid.nx", std::to_string(n)},
                                         {"particles[0].grid.ny", std::to_string(n)},
                                         {"simulation.steps", std::to_string(steps)},
                                         {"output", v.output.empty() ? "null" : v.output}};
      pdyn::Scene scene = pdyn::load_scene(PDYN_BENCH_CLOTH, registry, set);
      pdyn::RunOptions options;
      options.threads = threads;
      const auto t0 = std::chrono::steady_clock::now();
      const pdyn::RunResult result = pdyn::run_scene(scene, options);
      const double wall =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (result.exit_code != 0) {
        fmt::print(stderr, "{}: the run failed: {}\n", v.name, result.message);
        return 1;
      }
      if (wall < v.best) {
        v.best = wall;
        v.writing = result.output_writing;
        v.stalled = result.output_stalled;
      }
      v.bytes = bytes_under(dir / "out");
    }
  }
  const double base = variants[0].best;
  fmt::print("{:<14} {:>8} {:>9} {:>9} {:>10} {:>11} {:>14} {:>8}\n", "writer", "wall s",
             "overhead", "stalled", "writing s", "MB written", "B/particle-fr", "MB/s");
  for (const auto& v : variants) {
    fmt::print(
        "{:<14} {:>8.3f} {:>8.1f}% {:>8.1f}% {:>10.3f} {:>11.1f} {:>14.1f} {:>8}\n", v.name, v.best,
        100 * (v.best - base) / base, 100 * v.stalled / base, v.writing, v.bytes / 1e6,
        v.bytes / particle_frames,
        v.writing > 0.0 ? fmt::format("{:.0f}", v.bytes / 1e6 / v.writing) : std::string("-"));
  }
  std::error_code ec;
  fs::remove_all(dir / "out", ec);
  return 0;
}
