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
  Conserved,
  Pair,
  Bonded
};

// Each column with its LAMMPS thermo header (`header: lammps`) and whether
// it is extensive (divided by N with `per_particle: true`, as LAMMPS's
// thermo_modify norm yes divides its energies).
struct ColumnInfo {
  const char* name;
  Column column;
  const char* meaning;
  const char* lammps;
  bool extensive;
};

constexpr std::array<ColumnInfo, 15> kColumns = {{
    {"t", Column::Time, "time, s", "Time", false},
    {"step", Column::Step, "step", "Step", false},
    {"kinetic", Column::Kinetic, "kinetic energy K, J", "KinEng", true},
    {"potential", Column::Potential, "potential energy U, J", "PotEng", true},
    {"total", Column::Total, "K + U, J", "TotEng", true},
    {"kT", Column::KT, "k_B T = 2 K / N_f, J (reduced units: T*)", "Temp", false},
    {"temperature", Column::Temperature, "T, K", "Temp", false},
    {"pressure", Column::Pressure, "virial pressure (2 K + W) / (3 V), Pa (needs a box)", "Press",
     false},
    {"virial", Column::Virial, "W = sum r . f, J (constraint forces included)", "Virial", true},
    {"volume", Column::Volume, "box volume V, m^3 (needs a box)", "Volume", false},
    {"dof", Column::Dof, "degrees of freedom N_f (less one per independent constraint row)", "Dof",
     false},
    {"reservoir", Column::Reservoir, "energy taken out by thermostats, J", "Reservoir", true},
    {"conserved", Column::Conserved, "K + U + reservoir, J", "Conserved", true},
    {"pair", Column::Pair, "U of every force but the bonded terms, J (LAMMPS's E_pair)", "E_pair",
     true},
    {"bonded", Column::Bonded, "U of the bonded terms (bonds, angles, dihedrals, impropers), J",
     "E_mol", true},
}};

std::vector<const ColumnInfo*> read_columns(const pdyn::Params& p, const pdyn::Domain& domain) {
  std::vector<const ColumnInfo*> out;
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
    out.push_back(&*it);
  }
  return out;
}

bool lammps_header(const pdyn::Params& p) {
  const std::string& header = p.string("header");
  if (header != "pdyn" && header != "lammps") {
    throw pdyn::ParamError("header",
                           fmt::format("'{}' is not a header (expected pdyn or lammps)", header));
  }
  return header == "lammps";
}

class Energy final : public pdyn::Writer {
 public:
  Energy(const pdyn::Params& p, const pdyn::WriterContext& ctx)
      : columns_(read_columns(p, ctx.particles.domain)),
        extra_dof_(p.real("extra_dof")),
        per_particle_(p.boolean("per_particle")),
        lammps_header_(lammps_header(p)),
        resume_(ctx.resuming ? std::optional(pdyn::FileMark::decode(ctx.resume)) : std::nullopt),
        file_(ctx.path, resume_ ? &*resume_ : nullptr) {
    if (ctx.resuming) return;
    if (lammps_header_) {
      std::vector<std::string> names;
      for (const ColumnInfo* c : columns_) names.emplace_back(c->lammps);
      file_.write(fmt::format("{}\n", fmt::join(names, ",")));
    } else {
      file_.write(fmt::format("{}\n", fmt::join(p.strings("columns"), ",")));
    }
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
      switch (columns_[c]->column) {
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
      double x = value(columns_[c]->column, frame, k, u, state);
      // LAMMPS's thermo_modify norm yes: extensive values per particle.
      if (per_particle_ && columns_[c]->extensive && frame.particles.x.cols() > 0) {
        x /= static_cast<double>(frame.particles.x.cols());
      }
      row += fmt::format("{:.17g}", x);
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
      case Column::Pair:
        return u - frame.bonded_energy;
      case Column::Bonded:
        return frame.bonded_energy;
      case Column::Step:
        break;
    }
    return 0.0;
  }

  std::vector<const ColumnInfo*> columns_;  // entries of kColumns
  double extra_dof_;
  bool per_particle_;
  bool lammps_header_;  // checked before the file is opened
  std::optional<pdyn::FileMark> resume_;
  pdyn::OutputFile file_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Writer;
  d.name = "energy";
  d.version = "1.3.0";
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
      pdyn::param::string(
          "header", "pdyn",
          "pdyn or lammps: the header line: the column names, or LAMMPS's thermo names (Step, "
          "Temp, E_pair, E_mol, TotEng, Press, ...)"),
      pdyn::param::boolean("per_particle", false,
                           "divide the energies and the virial by the number of particles, as "
                           "LAMMPS's thermo_modify norm yes (its default in lj units)"),
  };
  d.writer_traits.energy = true;
  d.create_writer = [](const pdyn::Params& p, const pdyn::WriterContext& ctx) {
    return std::make_unique<Energy>(p, ctx);
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
