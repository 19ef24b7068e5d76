// The converter of LAMMPS input scripts (pdyn/host/convert.hpp): one
// function per command, in convert_lammps.cpp (the script, the force field,
// the run, the scene written) and convert_lammps_atoms.cpp (the atoms the
// script makes itself: lattice, region, create_box, create_atoms, mass,
// velocity).
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "lammps_atoms.hpp"
#include "pdyn/host/convert.hpp"
#include "pdyn/host/scene.hpp"

namespace pdyn::lammps {

/// A whole number from lo to hi: what a type, a count or a seed must be.
inline bool whole_in(double v, double lo, double hi) {
  return v >= lo && v <= hi && v == std::floor(v);
}

struct Word {
  std::string text;
  int column = 1;  // 1-based, in the line the word starts on
};
struct Command {
  int line = 1;  // 1-based, where the command starts
  std::vector<Word> words;
  const std::string& name() const { return words.front().text; }
};

// `fix nvt temp T T DAMP [tchain N]`.
// `fix nvt temp T T DAMP [tchain N]`, and `fix npt` with `iso P P PDAMP
// [pchain N]`: nose_hoover with its barostat.
struct Nvt {
  double kT = 1.0, tdamp = 0.1;
  long chain = 3;
  std::optional<double> pressure, pdamp;
  long pchain = 3;
};

// `fix rattle`'s rods: bond and angle types.
struct Rigid {
  std::vector<long> bonds, angles;
  double tolerance = 1e-12;
  Command at;  // the fix command, where its problems are located
};

class Converter {
 public:
  /// `options`: the command line's variables (lmp -var NAME VALUE) and
  /// the folder read_data's names are relative to.
  Converter(std::string file, const ConvertOptions& options)
      : file_(std::move(file)), variables_(options.variables), data_folder_(options.data_folder) {
    for (const auto& [name, value] : options.variables) command_line_.insert(name);
  }
  /// The scene, and the data file it reads when the script made its own
  /// atoms (`STEM.data`, beside the scene).
  ConvertedScene convert(const std::string& text, const std::string& stem);

 private:
  // ---- reading ----
  std::vector<Command> split(const std::string& text);
  std::string substitute(const std::string& line, int number);
  void define_variable(const Command& c);
  // ---- diagnostics ----
  void fail(const Command& c, std::size_t word, const std::string& what);
  std::optional<double> number(const Command& c, std::size_t word, const char* what);
  bool arity(const Command& c, std::size_t least, std::size_t most, const char* form);
  // ---- the commands ----
  void command(const Command& c);
  void units(const Command& c);
  void atom_style(const Command& c);
  void boundary(const Command& c);
  void special_bonds(const Command& c);
  void read_data(const Command& c);
  void pair_style(const Command& c);
  void pair_coeff(const Command& c);
  void pair_modify(const Command& c);
  void bonded_style(const Command& c);
  void bonded_coeff(const Command& c);
  void neighbor(const Command& c);
  void neigh_modify(const Command& c);
  // ---- the atoms the script makes (convert_lammps_atoms.cpp) ----
  void lattice(const Command& c);
  void region(const Command& c);
  void create_box(const Command& c);
  void create_atoms(const Command& c);
  void mass(const Command& c);
  void velocity(const Command& c);
  std::optional<std::array<double, 6>> block_bounds(const Command& c, std::size_t first,
                                                    bool lattice_units);
  std::string data_file() const;
  void fix(const Command& c);
  void rattle(const Command& c);
  void nvt(const Command& c);
  void langevin(const Command& c);
  void thermo_style(const Command& c);
  void thermo_modify(const Command& c);
  void run(const Command& c);
  // ---- writing ----
  std::string yaml() const;
  std::string bonded_entries() const;
  std::string rigid_entries() const;
  std::string langevin_entry() const;
  std::string output_entry() const;
  const std::map<long, std::vector<double>>& coeffs_of(const std::string& kind) const;
  void check_coefficients();

  std::string file_;
  std::vector<Diagnostic> diags_;
  std::map<std::string, std::string> variables_;
  std::set<std::string> command_line_;  // the variables given on the command line
  std::string data_folder_;             // ConvertOptions::data_folder
  // What the script set.
  std::string data_;                               // read_data's file
  std::string atom_style_;                         // atom_style, or empty
  std::optional<double> dt_;                       // timestep
  std::optional<long> steps_;                      // run
  bool nve_ = false;                               // fix nve
  std::array<double, 3> special_{0.0, 0.0, 0.0};   // LAMMPS's default special_bonds
  std::optional<double> cutoff_;                   // pair_style lj/cut
  std::vector<std::string> pair_rows_;             // pair_coeff I J eps sigma [rc]
  std::optional<std::array<double, 2>> pair_all_;  // pair_coeff * * eps sigma
  std::optional<std::array<double, 3>> type_one_;  // pair_coeff 1 1: eps, sigma, its cutoff
  bool shift_ = false;
  bool zero_pair_ = false;  // pair_style zero
  std::string mix_;
  double skin_ = 0.3;                     // LAMMPS's default skin in lj units
  RebuildSchedule rebuild_{1, 10, true};  // LAMMPS's default neigh_modify
  // The atoms the script makes: the lattice, its regions, the box, the
  // atoms (in id order), their types (1-based) and velocities, type masses.
  std::vector<Vec3> basis_;
  double spacing_ = 0.0;
  std::map<std::string, Block> regions_;
  std::optional<Block> box_;
  long types_ = 0;
  Matrix3X x_;
  std::vector<long> type_;
  std::optional<Matrix3X> v_;
  std::map<long, double> mass_;
  // bond/angle style and coefficients by type (1-based), as given.
  std::map<std::string, std::string> style_;  // "bond" -> "fene"
  std::map<std::string, Command> style_at_;   // "bond" -> its bond_style command
  std::map<std::string, std::map<long, std::vector<double>>> coeffs_;
  std::optional<Rigid> rigid_;
  std::optional<Nvt> nvt_;
  struct Langevin {
    double kT, damp;
    long seed;
  };
  std::optional<Langevin> langevin_;  // fix langevin
  double pair_cutoff_max_ = 0.0;      // the largest pair cutoff, for the atom sort's bins
  long thermo_every_ = 0;
  // LAMMPS's thermo_style one: Step Temp E_pair E_mol TotEng Press.
  std::vector<std::string> columns_{"step", "kT", "pair", "bonded", "total", "pressure"};
  bool normalized_ = true;  // LAMMPS's thermo_modify norm in lj units
};

}  // namespace pdyn::lammps
