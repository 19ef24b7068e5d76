// The csv writer: one text row per particle and frame, t,id,x,y,z,vx,vy,vz
// (and xu,yu,zu with `unwrapped`), every number with 17 significant digits,
// which is enough for a double to round-trip exactly. The bytes are those
// pdyn wrote before writers were plugins (tests/host/config_outputs.sha256).
#include <fmt/format.h>

#include <array>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <pdyn/output_file.hpp>
#include <pdyn/plugin.hpp>

namespace {

class Csv final : public pdyn::Writer {
 public:
  Csv(const pdyn::WriterContext& ctx, bool unwrapped)
      : unwrapped_(unwrapped),
        resume_(ctx.resuming ? std::optional(pdyn::FileMark::decode(ctx.resume)) : std::nullopt),
        file_(ctx.path, resume_ ? &*resume_ : nullptr) {
    if (!ctx.resuming) {
      file_.write(unwrapped_ ? "t,id,x,y,z,vx,vy,vz,xu,yu,zu\n" : "t,id,x,y,z,vx,vy,vz\n");
    }
  }

  void write(const pdyn::Frame& frame) override {
    file_.begin_frame();
    const auto& p = frame.particles;
    const double t = frame.time();
    const pdyn::Vec3 length = p.domain.length();
    buf_.clear();
    for (pdyn::Index i = 0; i < p.size(); ++i) {
      fmt::format_to(std::back_inserter(buf_),
                     "{:.17g},{},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g}", t, i, p.x(0, i),
                     p.x(1, i), p.x(2, i), p.v(0, i), p.v(1, i), p.v(2, i));
      if (unwrapped_) {
        pdyn::Vec3 u = p.x.col(i);
        for (int k = 0; k < 3; ++k) {
          if (p.domain.periodic[k]) {
            u[k] += frame.images[static_cast<std::size_t>(i)][k] * length[k];
          }
        }
        fmt::format_to(std::back_inserter(buf_), ",{:.17g},{:.17g},{:.17g}", u.x(), u.y(), u.z());
      }
      buf_.push_back('\n');
      if (buf_.size() > (1 << 16)) {
        file_.write(buf_.data(), buf_.size());
        buf_.clear();
      }
    }
    file_.write(buf_.data(), buf_.size());
    file_.flush();  // a full disk is met at this frame, not at a later one
  }

  // After a failed write, both stop at the last complete frame (OutputFile).
  std::vector<std::uint8_t> mark() override { return file_.mark().encode(); }
  void commit() override { file_.commit(); }
  std::vector<std::filesystem::path> temp_files() const override { return {file_.temp_path()}; }

 private:
  bool unwrapped_;
  std::optional<pdyn::FileMark> resume_;  // where a resumed run continues the file
  pdyn::OutputFile file_;
  fmt::memory_buffer buf_;
};

// The reader (pdyn check): every frame's t, x and v; 17 significant digits
// read back to the same doubles.
std::vector<pdyn::FrameRecord> read_back(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw pdyn::Error(fmt::format("{}: cannot read", path.string()));
  std::string line;
  std::getline(in, line);  // header
  std::vector<pdyn::FrameRecord> frames;
  std::vector<std::array<double, 6>> rows;
  double t = 0.0;
  auto flush = [&] {
    if (rows.empty()) return;
    pdyn::FrameRecord f;
    f.time = t;
    const auto n = static_cast<pdyn::Index>(rows.size());
    f.x.resize(3, n);
    f.v.resize(3, n);
    for (pdyn::Index i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) {
        f.x(k, i) = rows[static_cast<std::size_t>(i)][k];
        f.v(k, i) = rows[static_cast<std::size_t>(i)][3 + k];
      }
    }
    frames.push_back(std::move(f));
    rows.clear();
  };
  while (std::getline(in, line)) {
    std::array<double, 8> c{};
    const char* p = line.c_str();
    for (auto& value : c) {
      char* end = nullptr;
      value = std::strtod(p, &end);
      p = *end == ',' ? end + 1 : end;
    }
    if (!rows.empty() && c[0] != t) flush();
    t = c[0];
    rows.push_back({c[2], c[3], c[4], c[5], c[6], c[7]});
  }
  flush();
  return frames;
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Writer;
  d.name = "csv";
  d.version = "1.0.0";
  d.description = "text frames: t,id,x,y,z,vx,vy,vz per particle and frame, 17 significant digits";
  d.params = {
      pdyn::param::boolean("unwrapped", false,
                           "append the unwrapped positions xu,yu,zu (x + images * box length)"),
  };
  d.create_writer = [](const pdyn::Params& p, const pdyn::WriterContext& ctx) {
    return std::make_unique<Csv>(ctx, p.boolean("unwrapped"));
  };
  d.read_back = read_back;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
