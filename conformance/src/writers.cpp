// The checks of a writer plugin: files, not physics. The kit writes frames
// of its seeded 6-particle states (moving, with pairs, a triple and a plane
// obstacle, every field the writer supports) into a scratch folder and
// checks that the output appears only when committed, holds every frame
// (read back through the plugin's own reader, when it declares one), leaves
// no temporary file, and that an output resumed from a mark, after an
// extra frame past it as an interrupted run writes, ends as the same output
// written in one go.
#include <fmt/format.h>
#include <unistd.h>

#include <bit>
#include <cstdint>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include "checks.hpp"
#include "sample.hpp"

namespace pdyn::conformance::detail {

namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 5;
constexpr double kFrameDt = 0.01;

struct Scratch {
  fs::path dir;
  explicit Scratch(const std::string& name) {
    dir = fs::temp_directory_path() / fmt::format("pdyn-check-{}-{}", name, ::getpid());
    std::error_code ec;
    fs::remove_all(dir, ec);
    fs::create_directories(dir);
  }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

// The frames the kit writes: a seeded state moved by v each frame.
struct Frames {
  std::vector<State> states;
  std::vector<std::array<std::int32_t, 3>> images;
  std::vector<std::int32_t> type;
  Matrix3X force;
  explicit Frames(std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    State s = random_state(rng);
    images.assign(static_cast<std::size_t>(s.size()), {0, 0, 0});
    type.assign(static_cast<std::size_t>(s.size()), 1);
    force = Matrix3X::Random(3, s.size());
    for (int k = 0; k < kFrames; ++k) {
      s.t = k * kFrameDt;
      states.push_back(s);
      s.x += kFrameDt * s.v;
    }
  }
  Frame frame(int k) const {
    ParticleView v = states[static_cast<std::size_t>(k)].view();
    v.type = type;
    Frame f(v);
    f.step = k;
    f.images = images;
    f.force = &force;
    f.kinetic_energy = 1.5;
    f.potential_energy = -0.5;
    return f;
  }
};

WriterContext context(const PluginDescriptor& d, const Frames& frames, const fs::path& path) {
  ParticleView v = frames.states[0].view();
  v.type = frames.type;
  WriterContext ctx(v);
  ctx.path = path;
  ctx.fields = d.writer_traits.fields;
  ctx.every = 1;
  ctx.dt = kFrameDt;
  ctx.pairs = {{0, 1}, {1, 2}, {2, 3}};
  ctx.triples = {{0, 1, 2}};
  ctx.obstacles = {shape::Plane{Vec3(0, 0, -2), Vec3::UnitZ()}};
  return ctx;
}

std::map<std::string, std::string> files_in(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::ifstream in(e.path(), std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    out[fs::relative(e.path(), dir).generic_string()] = ss.str();
  }
  return out;
}

std::size_t temporaries(const fs::path& dir) {
  std::size_t n = 0;
  for (const auto& [name, bytes] : files_in(dir)) n += name.find(".tmp-") != std::string::npos;
  return n;
}

bool same_bits(const Matrix3X& a, const Matrix3X& b) {
  return a.cols() == b.cols() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

// Frames read back that differ from those written (count differences count).
std::size_t read_back_differences(const PluginDescriptor& d, const Frames& frames,
                                  const fs::path& path, std::string& detail) {
  const auto got = d.read_back(path);
  std::size_t bad =
      got.size() == kFrames ? 0 : 1 + std::abs(static_cast<long>(got.size()) - kFrames);
  for (std::size_t k = 0; k < std::min<std::size_t>(got.size(), kFrames); ++k) {
    const State& s = frames.states[k];
    const bool v_ok = got[k].v.size() == 0 || same_bits(got[k].v, s.v);
    const bool ok =
        std::bit_cast<std::uint64_t>(got[k].time) == std::bit_cast<std::uint64_t>(s.t) &&
        same_bits(got[k].x, s.x) && v_ok;
    if (!ok && detail.empty()) detail = fmt::format("frame {} differs", k);
    bad += !ok;
  }
  return bad;
}

// writer.atomic: an abandoned writer leaves nothing; a committed one's file
// appears only at commit, with no temporary left. Leaves the committed
// output in `whole` for the checks after it.
CheckResult atomic_check(const PluginDescriptor& d, const Params& params, const Frames& frames,
                         const Scratch& scratch, const fs::path& whole, const std::string& file) {
  // Abandoned: nothing under the final name, no temporary left.
  const fs::path dir = scratch.dir / "abandoned";
  fs::create_directories(dir);
  {
    auto w = d.create_writer(params, context(d, frames, dir / file));
    for (int k = 0; k < 2; ++k) w->write(frames.frame(k));
    w->mark();
  }
  const bool left = fs::exists(dir / file);
  const std::size_t temps = temporaries(dir);
  // Written and committed: the file only appears at commit.
  fs::create_directories(whole);
  auto w = d.create_writer(params, context(d, frames, whole / file));
  for (int k = 0; k < kFrames; ++k) w->write(frames.frame(k));
  const bool early = fs::exists(whole / file);
  w->commit();
  const bool there = fs::exists(whole / file);
  const std::size_t after = temporaries(whole);
  const std::size_t bad = left + temps + early + !there + after;
  return result("writer.atomic", bad == 0, static_cast<double>(bad), 0,
                fmt::format("{} under the final name before commit, {} after; abandoned: {} "
                            "final file, {} temporaries; committed: {} temporaries",
                            early ? "a file" : "nothing", there ? "the file" : "NOTHING",
                            left ? 1 : 0, temps, after));
}

// writer.resume_identical: an interrupted run resumed from a checkpoint's
// mark writes what one uninterrupted run (in `whole`) wrote.
CheckResult resume_check(const PluginDescriptor& d, const Params& params, const Frames& frames,
                         const fs::path& whole, const fs::path& split, const std::string& file) {
  // An interrupted run: frames 0..2, a checkpoint's mark, an extra frame,
  // committed; then resumed from the mark with frames 3..4.
  fs::create_directories(split);
  std::vector<std::uint8_t> mark;
  {
    auto w = d.create_writer(params, context(d, frames, split / file));
    for (int k = 0; k < 3; ++k) w->write(frames.frame(k));
    mark = w->mark();
    w->write(frames.frame(3));
    w->commit();
  }
  WriterContext ctx = context(d, frames, split / file);
  ctx.resume = mark;
  ctx.resuming = true;
  auto w = d.create_writer(params, ctx);
  for (int k = 3; k < kFrames; ++k) w->write(frames.frame(k));
  w->commit();
  const auto a = files_in(whole), b = files_in(split);
  std::size_t differ = a.size() == b.size() ? 0 : 1;
  for (const auto& [name, bytes] : a) {
    const auto it = b.find(name);
    differ += it == b.end() || it->second != bytes;
  }
  if (differ == 0) {
    return result("writer.resume_identical", true, 0, 0,
                  fmt::format("{} files byte-identical to one uninterrupted output", a.size()));
  }
  // A format whose layout may differ (HDF5): the frames must not.
  if (d.read_back && a.size() == b.size()) {
    std::string detail;
    const std::size_t bad = read_back_differences(d, frames, split / file, detail);
    return result("writer.resume_identical", bad == 0, static_cast<double>(bad), 0,
                  bad == 0 ? fmt::format("{} frames read back identical (the file's bytes "
                                         "differ in layout)",
                                         kFrames)
                           : detail);
  }
  return result(
      "writer.resume_identical", false, static_cast<double>(differ), 0,
      fmt::format("{} of {} files differ from an uninterrupted output", differ, a.size()));
}

}  // namespace

void writer_checks(const PluginDescriptor& d, const Options& o, std::vector<CheckResult>& out) {
  const Frames frames(o.seed);
  const Params params = sample_params(d, kParticles);
  Scratch scratch(d.name);
  const fs::path whole = scratch.dir / "whole", split = scratch.dir / "split";
  const std::string file = "out/check." + d.name;
  bool constructed = false;

  guarded(out, "construct.defaults", [&] {
    const fs::path dir = scratch.dir / "construct";
    fs::create_directories(dir);
    auto w = d.create_writer(params, context(d, frames, dir / file));
    constructed = w != nullptr;
    return result("construct.defaults", constructed, constructed ? 0 : 1, 0,
                  constructed ? fmt::format("a writer to {} with every field it supports ({})",
                                            file, fmt::join(d.writer_traits.fields, ", "))
                              : "the factory returned no object");
  });
  if (!constructed) return;

  guarded(out, "writer.atomic",
          [&] { return atomic_check(d, params, frames, scratch, whole, file); });

  guarded(out, "writer.read_back", [&] {
    if (!d.read_back) return skip("writer.read_back", "the plugin declares no reader (read_back)");
    std::string detail;
    const std::size_t bad = read_back_differences(d, frames, whole / file, detail);
    return result(
        "writer.read_back", bad == 0, static_cast<double>(bad), 0,
        bad == 0 ? fmt::format("{} frames: t, x and v read back bit for bit", kFrames) : detail);
  });

  guarded(out, "writer.resume_identical",
          [&] { return resume_check(d, params, frames, whole, split, file); });
}

}  // namespace pdyn::conformance::detail
