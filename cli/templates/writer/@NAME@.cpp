// @NAME@: a pdyn writer plugin. It writes extended XYZ, a text format that
// OVITO, ASE and VMD read: per frame, the particle count, a comment line
// with the time, then one line per particle, "P x y z" (m), with
// `digits` significant digits. Replace the format with yours; keep the
// three rules every writer follows (docs/plugins.md, docs/output.md):
//   - nothing partial under the final name: pdyn::OutputFile writes to
//     PATH.tmp-PID and renames at commit();
//   - mark() says how far the output went, for checkpoints; a writer
//     created with ctx.resuming continues from it (OutputFile checks the
//     bytes it continues with a CRC-32);
//   - after a failed write (a full disk), mark() and commit() keep the
//     file up to its last whole frame: OutputFile does it, given
//     begin_frame() before each frame and flush() after it.
#include <fmt/format.h>

#include <cstdlib>
#include <fstream>
#include <optional>
#include <pdyn/output_file.hpp>
#include <pdyn/plugin.hpp>

namespace {

class Writer final : public pdyn::Writer {
 public:
  Writer(const pdyn::WriterContext& ctx, int digits)
      : digits_(digits),
        resume_(ctx.resuming ? std::optional(pdyn::FileMark::decode(ctx.resume)) : std::nullopt),
        file_(ctx.path, resume_ ? &*resume_ : nullptr) {}

  void write(const pdyn::Frame& frame) override {
    file_.begin_frame();
    const auto& p = frame.particles;
    fmt::memory_buffer buf;
    fmt::format_to(std::back_inserter(buf), "{}\nTime={:.17g} Properties=species:S:1:pos:R:3\n",
                   p.size(), frame.time());
    for (pdyn::Index i = 0; i < p.size(); ++i) {
      fmt::format_to(std::back_inserter(buf), "P {:.{}g} {:.{}g} {:.{}g}\n", p.x(0, i), digits_,
                     p.x(1, i), digits_, p.x(2, i), digits_);
    }
    file_.write(buf.data(), buf.size());
    file_.flush();  // a full disk is met at this frame
  }
  std::vector<std::uint8_t> mark() override { return file_.mark().encode(); }
  void commit() override { file_.commit(); }
  std::vector<std::filesystem::path> temp_files() const override { return {file_.temp_path()}; }

 private:
  int digits_;
  std::optional<pdyn::FileMark> resume_;
  pdyn::OutputFile file_;
};

// Optional: reads the output back, so that `pdyn check` compares every
// frame with what it wrote (bit for bit with digits: 17).
std::vector<pdyn::FrameRecord> read_back(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw pdyn::Error(fmt::format("{}: cannot read", path.string()));
  std::vector<pdyn::FrameRecord> frames;
  std::string line;
  while (std::getline(in, line)) {
    const long n = std::strtol(line.c_str(), nullptr, 10);
    std::getline(in, line);
    pdyn::FrameRecord f;
    f.time = std::strtod(line.c_str() + line.find('=') + 1, nullptr);
    f.x.resize(3, n);
    for (long i = 0; i < n && std::getline(in, line); ++i) {
      const char* p = line.c_str() + 1;
      for (int k = 0; k < 3; ++k) {
        char* end = nullptr;
        f.x(k, i) = std::strtod(p, &end);
        p = end;
      }
    }
    frames.push_back(std::move(f));
  }
  return frames;
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Writer;
  d.name = "@NAME@";
  d.version = "0.1.0";
  d.description = "extended XYZ frames: count, time, one 'P x y z' line per particle";
  pdyn::ParamSpec digits = pdyn::param::integer(
      "digits", 17, "significant digits of each coordinate (17: reads back exactly)");
  digits.at_least(1).at_most(17);
  d.params = {digits};
  d.create_writer = [](const pdyn::Params& p, const pdyn::WriterContext& ctx) {
    return std::make_unique<Writer>(ctx, static_cast<int>(p.integer("digits")));
  };
  d.read_back = read_back;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
