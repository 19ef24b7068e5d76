// The energy writer: one row t,kinetic,potential,total per frame (J, 17
// significant digits), the potential summed from every force that reports
// one (Force::potential_energy). The bytes are those of pdyn's energy log
// before writers were plugins (`output: { energy: FILE }`).
#include <fmt/format.h>

#include <optional>
#include <pdyn/output_file.hpp>
#include <pdyn/plugin.hpp>

namespace {

class Energy final : public pdyn::Writer {
 public:
  explicit Energy(const pdyn::WriterContext& ctx)
      : resume_(ctx.resuming ? std::optional(pdyn::FileMark::decode(ctx.resume)) : std::nullopt),
        file_(ctx.path, resume_ ? &*resume_ : nullptr) {
    if (!ctx.resuming) file_.write("t,kinetic,potential,total\n");
  }

  void write(const pdyn::Frame& frame) override {
    file_.begin_frame();
    const double k = frame.kinetic_energy, u = frame.potential_energy;
    file_.write(fmt::format("{:.17g},{:.17g},{:.17g},{:.17g}\n", frame.time(), k, u, k + u));
    file_.flush();  // a full disk is met at this frame, not at a later one
  }
  // After a failed write, both stop at the last complete frame (OutputFile).
  std::vector<std::uint8_t> mark() override { return file_.mark().encode(); }
  void commit() override { file_.commit(); }
  std::vector<std::filesystem::path> temp_files() const override { return {file_.temp_path()}; }

 private:
  std::optional<pdyn::FileMark> resume_;
  pdyn::OutputFile file_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Writer;
  d.name = "energy";
  d.version = "1.0.0";
  d.description = "energy log: t,kinetic,potential,total (J) per frame, 17 significant digits";
  d.writer_traits.energy = true;
  d.create_writer = [](const pdyn::Params&, const pdyn::WriterContext& ctx) {
    return std::make_unique<Energy>(ctx);
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
