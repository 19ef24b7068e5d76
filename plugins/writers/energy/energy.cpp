// The energy writer: one row per frame of the columns a scene asks for
// (`columns`, LAMMPS's thermo_style custom), 17 significant digits. The
// default columns t,kinetic,potential,total (J), the potential summed from
// every force that reports one (Force::potential_energy), are the bytes of
// pdyn's energy log before writers were plugins (`output: { energy: FILE }`).
//
// Temperature and pressure are pdyn/thermo.hpp's: k_B T = 2 K / N_f with
// N_f = 3 N_free - extra_dof - the independent constraint rows
// (Frame::constraint_dof), P = (2 K + W) / (3 V) with the virial W of the
// forces and of the constraint forces (Frame::virial).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <pdyn/error.hpp>
#include <pdyn/output_file.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/thermo.hpp>
#include <string>
#include <string_view>

namespace {

enum class Column {
  Time,
  Step,
  Kinetic,
  Potential,
  Total,
  KT,
  Temperature,
  Pressure,
  Virial,
  Volume,
  Dof,
  Reservoir,
  Conserved
};

struct ColumnInfo {
  const char* name;
  Column column;
  const char* meaning;
};

constexpr std::array<ColumnInfo, 13> kColumns = {{
    {"t", Column::Time, "time, s"},
    {"step", Column::Step, "step"},
    {"kinetic", Column::Kinetic, "kinetic energy K, J"},
    {"potential", Column::Potential, "potential energy U, J"},
    {"total", Column::Total, "K + U, J"},
    {"kT", Column::KT, "k_B T = 2 K / N_f, J (reduced units: T*)"},
    {"temperature", Column::Temperature, "T, K"},
    {"pressure", Column::Pressure, "virial pressure (2 K + W) / (3 V), Pa (needs a box)"},
    {"virial", Column::Virial, "W = sum r . f, J (constraint forces included)"},
    {"volume", Column::Volume, "box volume V, m^3 (needs a box)"},
    {"dof", Column::Dof, "degrees of freedom N_f (less one per independent constraint row)"},
    {"reservoir", Column::Reservoir, "energy taken out by thermostats, J"},
    {"conserved", Column::Conserved, "K + U + reservoir, J"},
}};

std::vector<Column> read_columns(const pdyn::Params& p, const pdyn::Domain& domain) {
  std::vector<Column> out;
  const auto& names = p.strings("columns");
  if (names.empty()) throw pdyn::ParamError("columns", "no column (expected at least one)");
  for (std::size_t k = 0; k < names.size(); ++k) {
    const auto it = std::find_if(kColumns.begin(), kColumns.end(),
                                 [&](const ColumnInfo& c) { return names[k] == c.name; });
    if (it == kColumns.end()) {
      std::vector<std::string> known;
      known.reserve(kColumns.size());
      for (const auto& c : kColumns) known.emplace_back(c.name);
      throw pdyn::ParamError("columns",
                             fmt::format("unknown column '{}' (expected one of: {})", names[k],
                                         fmt::join(known, ", ")),
                             static_cast<long>(k));
    }
    const bool needs_box = it->column == Column::Pressure || it->column == Column::Volume;
    if (needs_box && !(domain.length().array() > 0).all()) {
      throw pdyn::ParamError("columns",
                             fmt::format("'{}' needs a box (expected simulation.box)", names[k]),
                             static_cast<long>(k));
    }
    out.push_back(it->column);
  }
  return out;
}

class Energy final : public pdyn::Writer {
 public:
  Energy(const pdyn::Params& p, const pdyn::WriterContext& ctx)
      : columns_(read_columns(p, ctx.particles.domain)),
        extra_dof_(p.real("extra_dof")),
        resume_(ctx.resuming ? std::optional(pdyn::FileMark::decode(ctx.resume)) : std::nullopt),
        file_(ctx.path, resume_ ? &*resume_ : nullptr) {
    if (!ctx.resuming) file_.write(fmt::format("{}\n", fmt::join(p.strings("columns"), ",")));
  }

  void write(const pdyn::Frame& frame) override {
    file_.begin_frame();
    const double k = frame.kinetic_energy, u = frame.potential_energy;
    std::optional<pdyn::Thermo> thermo;
    auto state = [&]() -> const pdyn::Thermo& {
      if (!thermo)
        thermo = pdyn::thermo(frame.particles, frame.virial, extra_dof_ + frame.constraint_dof);
      return *thermo;
    };
    std::string row;
    for (std::size_t c = 0; c < columns_.size(); ++c) {
      if (c > 0) row += ',';
      switch (columns_[c]) {
        case Column::Step:
          row += fmt::format("{}", frame.step);
          continue;
        case Column::Pressure:
        case Column::Virial:
          if (std::isnan(frame.virial) && frame.virial_missing == "solver") {
            throw pdyn::Error(fmt::format(
                "{}: the pressure needs the constraint forces' virial, and the solver keeps the "
                "constraints without reporting it (expected a solver that does, "
                "pdyn::ConstraintVirialSource in pdyn/thermo.hpp: verlet's RATTLE, or Witkin's "
                "constraint force with any other; xpbd reports none)",
                file_.path().string()));
          }
          if (std::isnan(frame.virial) && frame.virial_missing.starts_with(pdyn::kSolverFailed)) {
            throw pdyn::Error(fmt::format(
                "{}: the pressure needs the constraint forces' virial, which the solver could not "
                "compute at step {}: {} (expected a state its constraints can be solved at)",
                file_.path().string(), frame.step,
                frame.virial_missing.substr(std::string_view(pdyn::kSolverFailed).size())));
          }
          if (std::isnan(frame.virial)) {
            throw pdyn::Error(fmt::format(
                "{}: the pressure needs every force's virial, and {} reports none (expected "
                "forces built with pdyn 0.8 or later, pdyn/thermo.hpp)",
                file_.path().string(), frame.virial_missing));
          }
          break;
        default:
          break;
      }
      row += fmt::format("{:.17g}", value(columns_[c], frame, k, u, state));
    }
    row += '\n';
    file_.write(row);
    file_.flush();  // a full disk is met at this frame, not at a later one
  }
  // After a failed write, both stop at the last complete frame (OutputFile).
  std::vector<std::uint8_t> mark() override { return file_.mark().encode(); }
  void commit() override { file_.commit(); }
  std::vector<std::filesystem::path> temp_files() const override { return {file_.temp_path()}; }

 private:
  template <class State>
  static double value(Column c, const pdyn::Frame& frame, double k, double u, State& state) {
    switch (c) {
      case Column::Time:
        return frame.time();
      case Column::Kinetic:
        return k;
      case Column::Potential:
        return u;
      case Column::Total:
        return k + u;
      case Column::KT:
        return state().kT;
      case Column::Temperature:
        return state().temperature;
      case Column::Pressure:
        return state().pressure;
      case Column::Virial:
        return frame.virial;
      case Column::Volume:
        return state().volume;
      case Column::Dof:
        return state().dof;
      case Column::Reservoir:
        return frame.reservoir_energy;
      case Column::Conserved:
        return k + u + frame.reservoir_energy;
      case Column::Step:
        break;
    }
    return 0.0;
  }

  std::vector<Column> columns_;
  double extra_dof_;
  std::optional<pdyn::FileMark> resume_;
  pdyn::OutputFile file_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Writer;
  d.name = "energy";
  d.version = "1.2.0";
  d.description =
      "energy log: a row per frame of t,kinetic,potential,total (J), or the columns asked for "
      "(temperature, pressure, ...), 17 significant digits";
  std::vector<std::string> names;
  names.reserve(kColumns.size());
  for (const auto& c : kColumns) names.emplace_back(c.name);
  pdyn::ParamSpec columns =
      pdyn::param::optional("columns", pdyn::ParamType::StringList, "",
                            fmt::format("the columns, in order: {}", fmt::join(names, ", ")));
  columns.fallback = std::vector<std::string>{"t", "kinetic", "potential", "total"};
  d.params = {
      std::move(columns),
      pdyn::param::real("extra_dof", 3.0, "",
                        "degrees of freedom removed from 3 N_free for the temperature (3: the "
                        "total momentum, as LAMMPS), besides one per independent constraint row")
          .at_least(0),
  };
  d.writer_traits.energy = true;
  d.create_writer = [](const pdyn::Params& p, const pdyn::WriterContext& ctx) {
    return std::make_unique<Energy>(p, ctx);
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
