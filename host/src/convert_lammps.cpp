// `pdyn convert`: a LAMMPS input script as a pdyn scene (issue 44 item 6).
// The script is read as LAMMPS reads it (a command per line, `#` comments,
// `&` continuing a line, `${name}` and `$x` replaced by variables), each
// command is converted by its own function into the scene's entries, and
// the scene is written as commented YAML, each entry naming the commands it
// came from. What this converter does not know is refused at the word,
// "IN:LINE:COLUMN: what (supported: ...)", never dropped: a converted scene
// either runs what the script runs or does not exist.
#include "convert_lammps.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <vector>

#include "import_files.hpp"
#include "pdyn/host/convert.hpp"
#include "text_file.hpp"

namespace pdyn::lammps {
namespace {

constexpr const char* kCommands =
    "units, atom_style, boundary, variable, lattice, region, create_box, create_atoms, mass, "
    "velocity, special_bonds, read_data, pair_style, pair_coeff, "
    "pair_modify, bond_style, bond_coeff, angle_style, angle_coeff, dihedral_style, "
    "dihedral_coeff, improper_style, improper_coeff, neighbor, neigh_modify, comm_modify, "
    "timestep, fix nve, fix nvt, fix npt, fix langevin, fix rattle, fix shake, thermo, "
    "thermo_style, "
    "thermo_modify, run";

// LAMMPS's bonded styles and the plugins that run them: each coefficient of
// `KIND_coeff TYPE C1 C2 ...` becomes a per-type list of the plugin's, times
// a factor (LAMMPS's harmonic E = K x^2 is the plugins' k = 2 K; degrees to
// radians).
struct Coefficient {
  const char* key;
  std::size_t index;  // in the coeff command, after the type
  double scale;
};
struct BondedStyle {
  const char* kind;  // bond, angle, dihedral, improper
  const char* style;
  const char* plugin;
  const char* form;  // the coeff command's arguments
  std::vector<Coefficient> coefficients;
  const char* note;
};
constexpr double kDegree = M_PI / 180.0;
const std::vector<BondedStyle>& bonded_styles() {
  static const std::vector<BondedStyle> kStyles = {
      {"bond",
       "fene",
       "fene",
       "TYPE K R0 EPSILON SIGMA",
       {{"k", 0, 1.0}, {"r0", 1, 1.0}, {"epsilon", 2, 1.0}, {"sigma", 3, 1.0}},
       "bond_style fene"},
      {"bond",
       "harmonic",
       "spring",
       "TYPE K R0",
       {{"ks", 0, 2.0}, {"rest", 1, 1.0}},
       "bond_style harmonic, E = K (r - r0)^2: ks = 2 K"},
      {"angle",
       "harmonic",
       "angle",
       "TYPE K THETA0",
       {{"k", 0, 2.0}, {"rest", 1, kDegree}},
       "angle_style harmonic, E = K (theta - theta0)^2: k = 2 K, rest in radians"},
      {"angle",
       "cosine/squared",
       "angle_cosine_squared",
       "TYPE K THETA0",
       {{"k", 0, 1.0}, {"theta0", 1, kDegree}},
       "angle_style cosine/squared, theta0 in radians"},
      {"dihedral",
       "opls",
       "dihedral_opls",
       "TYPE K1 K2 K3 K4",
       {{"k1", 0, 1.0}, {"k2", 1, 1.0}, {"k3", 2, 1.0}, {"k4", 3, 1.0}},
       "dihedral_style opls"},
      {"dihedral",
       "harmonic",
       "dihedral_harmonic",
       "TYPE K D N",
       {{"k", 0, 1.0}, {"d", 1, 1.0}, {"n", 2, 1.0}},
       "dihedral_style harmonic"},
      {"improper",
       "harmonic",
       "improper_harmonic",
       "TYPE K CHI0",
       {{"k", 0, 1.0}, {"chi0", 1, kDegree}},
       "improper_style harmonic, chi0 in radians"}};
  return kStyles;
}
const BondedStyle* find_style(const std::string& kind, const std::string& style) {
  for (const auto& b : bonded_styles()) {
    if (kind == b.kind && style == b.style) return &b;
  }
  return nullptr;
}

}  // namespace

// ---------------------------------------------------------------------------
// Reading

// `${name}` and `$x`, replaced as LAMMPS replaces them before it parses.
std::string Converter::substitute(const std::string& line, int number) {
  std::string out;
  for (std::size_t k = 0; k < line.size(); ++k) {
    if (line[k] != '$' || k + 1 == line.size()) {
      out += line[k];
      continue;
    }
    std::string name;
    std::size_t end = k + 1;
    if (line[k + 1] == '{') {
      end = line.find('}', k + 2);
      if (end == std::string::npos) end = line.size() - 1;
      name = line.substr(k + 2, end - k - 2);
    } else {
      name = line.substr(k + 1, 1);
    }
    const auto it = variables_.find(name);
    if (it == variables_.end()) {
      diags_.push_back({fmt::format("{}:{}:{}", file_, number, k + 1),
                        fmt::format("variable '{}' is not defined (expected a `variable {} "
                                    "index|equal|string VALUE` before it, or pdyn convert --var "
                                    "{} VALUE as lmp -var)",
                                    name, name, name)});
    } else {
      out += it->second;
    }
    k = end;
  }
  return out;
}

std::vector<Command> Converter::split(const std::string& text) {
  std::vector<Command> out;
  std::istringstream in(text);
  std::string raw;
  Command pending;
  for (int number = 1; std::getline(in, raw); ++number) {
    if (const auto hash = raw.find('#'); hash != std::string::npos) raw.erase(hash);
    std::string line = raw.find('$') == std::string::npos ? raw : substitute(raw, number);
    bool more = false;
    const auto last = line.find_last_not_of(" \t\r");
    if (last != std::string::npos && line[last] == '&') {
      line.erase(last);
      more = true;
    }
    if (pending.words.empty()) pending.line = number;
    for (const text_file::Field& f : text_file::split_blanks(line)) {
      pending.words.push_back({std::string(f.text), static_cast<int>(f.column)});
    }
    if (!more && !pending.words.empty()) {
      if (pending.name() == "variable") {
        define_variable(pending);
      } else {
        out.push_back(pending);
      }
      pending = Command{};
    }
  }
  if (!pending.words.empty()) out.push_back(pending);
  return out;
}

void Converter::define_variable(const Command& c) {
  if (c.words.size() != 4 ||
      (c.words[2].text != "index" && c.words[2].text != "equal" && c.words[2].text != "string")) {
    fail(c, std::min<std::size_t>(2, c.words.size() - 1),
         "a variable pdyn convert cannot evaluate (supported: variable NAME index|equal|string "
         "VALUE, one value)");
    return;
  }
  // LAMMPS's rule: an index variable given on the command line (-var, here
  // --var) is not redefined by the script's; equal and string ones are.
  const std::string& name = c.words[1].text;
  if (c.words[2].text == "index" && command_line_.count(name) != 0) return;
  variables_[name] = c.words[3].text;
}

// ---------------------------------------------------------------------------
// Diagnostics

void Converter::fail(const Command& c, std::size_t word, const std::string& what) {
  const int column = word < c.words.size() ? c.words[word].column : c.words.back().column;
  diags_.push_back({fmt::format("{}:{}:{}", file_, c.line, column), what});
}

std::optional<double> Converter::number(const Command& c, std::size_t word, const char* what) {
  if (word >= c.words.size()) {
    fail(c, word, fmt::format("{}: {} is missing (expected a number)", c.name(), what));
    return std::nullopt;
  }
  const std::string& t = c.words[word].text;
  const auto v = text_file::to_number<double>(t);  // exact, whatever the locale
  if (!v || !std::isfinite(*v)) {
    fail(c, word, fmt::format("{}: '{}' is not a number (expected {})", c.name(), t, what));
    return std::nullopt;
  }
  return v;
}

bool Converter::arity(const Command& c, std::size_t least, std::size_t most, const char* form) {
  const std::size_t n = c.words.size() - 1;
  if (n >= least && n <= most) return true;
  fail(c, std::min(c.words.size() - 1, most + 1),
       fmt::format("{}: {} arguments (expected {})", c.name(), n, form));
  return false;
}

// ---------------------------------------------------------------------------
// The commands

void Converter::command(const Command& c) {
  static const std::map<std::string, void (Converter::*)(const Command&)> kTable = {
      {"units", &Converter::units},
      {"atom_style", &Converter::atom_style},
      {"boundary", &Converter::boundary},
      {"special_bonds", &Converter::special_bonds},
      {"read_data", &Converter::read_data},
      {"pair_style", &Converter::pair_style},
      {"pair_coeff", &Converter::pair_coeff},
      {"pair_modify", &Converter::pair_modify},
      {"bond_style", &Converter::bonded_style},
      {"angle_style", &Converter::bonded_style},
      {"bond_coeff", &Converter::bonded_coeff},
      {"angle_coeff", &Converter::bonded_coeff},
      {"dihedral_style", &Converter::bonded_style},
      {"dihedral_coeff", &Converter::bonded_coeff},
      {"improper_style", &Converter::bonded_style},
      {"improper_coeff", &Converter::bonded_coeff},
      {"neighbor", &Converter::neighbor},
      {"neigh_modify", &Converter::neigh_modify},
      {"lattice", &Converter::lattice},
      {"region", &Converter::region},
      {"create_box", &Converter::create_box},
      {"create_atoms", &Converter::create_atoms},
      {"mass", &Converter::mass},
      {"velocity", &Converter::velocity},
      {"fix", &Converter::fix},
      {"thermo_style", &Converter::thermo_style},
      {"thermo_modify", &Converter::thermo_modify},
      {"run", &Converter::run}};
  const std::string& name = c.name();
  if (const auto it = kTable.find(name); it != kTable.end()) {
    (this->*(it->second))(c);
  } else if (name == "timestep") {
    if (arity(c, 1, 1, "timestep DT")) dt_ = number(c, 1, "the time step");
  } else if (name == "thermo") {
    if (const auto n = arity(c, 1, 1, "thermo N") ? number(c, 1, "a step count") : std::nullopt) {
      thermo_every_ = static_cast<long>(*n);
    }
  } else if (name == "comm_modify") {
    // Ghost atoms are LAMMPS's own: nothing in the scene.
  } else {
    fail(c, 0,
         fmt::format("'{}' is not a command pdyn convert knows (supported: {})", name, kCommands));
  }
}

void Converter::units(const Command& c) {
  if (arity(c, 1, 1, "units STYLE") && c.words[1].text != "lj") {
    fail(c, 1, fmt::format("units {}: not converted yet (supported: lj)", c.words[1].text));
  }
}

void Converter::atom_style(const Command& c) {
  static const std::set<std::string> kStyles = {"atomic", "bond", "angle", "molecular"};
  if (!arity(c, 1, 1, "atom_style STYLE")) return;
  if (kStyles.count(c.words[1].text) == 0) {
    fail(c, 1,
         fmt::format("atom_style {}: not converted (supported: atomic, bond, angle, molecular; "
                     "pdyn has no charges)",
                     c.words[1].text));
    return;
  }
  atom_style_ = c.words[1].text;
}

void Converter::boundary(const Command& c) {
  if (!arity(c, 3, 3, "boundary X Y Z")) return;
  for (std::size_t k = 1; k <= 3; ++k) {
    if (c.words[k].text != "p") {
      fail(c, k, fmt::format("boundary {}: not converted yet (supported: p p p)", c.words[k].text));
    }
  }
}

void Converter::special_bonds(const Command& c) {
  // LAMMPS's older form, three bare weights, is lj/coul (LAMMPS's in.chain benchmark).
  if (c.words.size() == 4 && std::isdigit(static_cast<unsigned char>(c.words[1].text[0])) != 0) {
    for (std::size_t a = 0; a < 3; ++a) {
      if (const auto v = number(c, 1 + a, "a weight from 0 to 1")) special_[a] = *v;
    }
    return;
  }
  for (std::size_t k = 1; k < c.words.size(); ++k) {
    const std::string& w = c.words[k].text;
    if (w == "fene") {
      special_ = {0.0, 1.0, 1.0};
    } else if (w == "charmm") {
      special_ = {0.0, 0.0, 0.0};
    } else if (w == "amber") {
      special_ = {0.0, 0.0, 0.5};
    } else if (w == "dreiding") {
      special_ = {0.0, 0.0, 1.0};
    } else if (w == "lj" || w == "lj/coul" || w == "coul") {
      for (std::size_t a = 0; a < 3; ++a) {
        const auto v = number(c, k + 1 + a, "a weight from 0 to 1");
        if (v && w != "coul") special_[a] = *v;  // pdyn has no charges: coul changes nothing
      }
      k += 3;
    } else {
      fail(c, k,
           fmt::format("special_bonds: '{}' is not converted (supported: lj, lj/coul, coul, "
                       "fene, charmm, amber, dreiding)",
                       w));
    }
  }
}

void Converter::read_data(const Command& c) {
  if (!arity(c, 1, 1, "read_data FILE, with no keywords")) return;
  // Relative to lmp's working directory, seen from the scene's folder.
  const std::filesystem::path file(c.words[1].text);
  data_ = file.is_absolute() || data_folder_.empty()
              ? file.generic_string()
              : (std::filesystem::path(data_folder_) / file).lexically_normal().generic_string();
}

void Converter::pair_style(const Command& c) {
  if (!arity(c, 1, 2, "pair_style lj/cut CUTOFF, or zero [CUTOFF]")) return;
  if (c.words[1].text == "zero") {  // no pair force
    zero_pair_ = true;
    if (c.words.size() == 3) {
      if (const auto rc = number(c, 2, "the cutoff")) pair_cutoff_max_ = *rc;
    }
    return;
  }
  if (c.words.size() != 3 || c.words[1].text != "lj/cut") {
    fail(
        c, 1,
        fmt::format("pair_style {}: not converted yet (supported: lj/cut, zero)", c.words[1].text));
    return;
  }
  cutoff_ = number(c, 2, "the global cutoff");
}

void Converter::pair_coeff(const Command& c) {
  if (zero_pair_ && c.words.size() == 3) return;  // pair_style zero's pair_coeff * *
  if (!arity(c, 4, 5, "pair_coeff I J EPSILON SIGMA [CUTOFF]")) return;
  const auto eps = number(c, 3, "epsilon"), sigma = number(c, 4, "sigma");
  std::optional<double> rc;
  if (c.words.size() == 6) rc = number(c, 5, "the pair's cutoff");
  if (!eps || !sigma) return;
  if (c.words[1].text == "*" && c.words[2].text == "*") {
    pair_all_ = std::array<double, 2>{*eps, *sigma};
    if (rc) cutoff_ = rc;
    if (cutoff_) pair_cutoff_max_ = std::max(pair_cutoff_max_, *cutoff_);
    return;
  }
  for (std::size_t k = 1; k <= 2; ++k) {
    if (c.words[k].text.find('*') != std::string::npos) {
      fail(c, k, "pair_coeff: a range of types is not converted yet (supported: * * or I J)");
      return;
    }
  }
  pair_rows_.push_back(fmt::format("{} {} {} {}{}", c.words[1].text, c.words[2].text, *eps, *sigma,
                                   rc ? fmt::format(" {}", *rc) : std::string()));
  // LAMMPS's pair without a cutoff takes the global one as it is now.
  const std::optional<double> pair_cutoff = rc ? rc : cutoff_;
  if (!pair_cutoff) return;
  if (c.words[1].text == "1" && c.words[2].text == "1") {
    type_one_ = std::array<double, 3>{*eps, *sigma, *pair_cutoff};
  }
  pair_cutoff_max_ = std::max(pair_cutoff_max_, *pair_cutoff);
}

void Converter::pair_modify(const Command& c) {
  for (std::size_t k = 1; k + 1 < c.words.size(); k += 2) {
    const std::string &key = c.words[k].text, &value = c.words[k + 1].text;
    if (key == "shift" && (value == "yes" || value == "no")) {
      shift_ = value == "yes";
    } else if (key == "mix" && (value == "geometric" || value == "arithmetic")) {
      mix_ = value;
    } else {
      fail(c, k,
           fmt::format("pair_modify {} {}: not converted (supported: shift yes|no, mix "
                       "geometric|arithmetic)",
                       key, value));
    }
  }
}

void Converter::bonded_style(const Command& c) {
  const std::string kind = c.name().substr(0, c.name().find('_'));  // bond, angle, ...
  if (!arity(c, 1, 1, "one style")) return;
  if (!find_style(kind, c.words[1].text)) {
    std::vector<std::string> known;
    for (const auto& b : bonded_styles()) {
      if (kind == b.kind) known.push_back(b.style);
    }
    fail(c, 1,
         fmt::format("{} {}: not converted yet (supported: {})", c.name(), c.words[1].text,
                     fmt::join(known, ", ")));
    return;
  }
  style_[kind] = c.words[1].text;
  style_at_[kind] = c;
}

void Converter::bonded_coeff(const Command& c) {
  const std::string kind = c.name().substr(0, c.name().find('_'));
  const BondedStyle* b = style_.count(kind) ? find_style(kind, style_.at(kind)) : nullptr;
  if (!b) {
    fail(c, 0, fmt::format("{}: before {}_style (expected the style first)", c.name(), kind));
    return;
  }
  const std::size_t n = b->coefficients.size();
  if (!arity(c, n + 1, n + 1, b->form)) return;
  const auto type = number(c, 1, "a type number");
  std::vector<double> values;
  for (std::size_t k = 2; k < c.words.size(); ++k) {
    const auto v = number(c, k, "a coefficient");
    if (!v) return;
    values.push_back(*v);
  }
  if (type && !whole_in(*type, 1, std::numeric_limits<double>::infinity())) {
    fail(c, 1, fmt::format("{}: type {} (expected a whole type number from 1)", c.name(), *type));
    return;
  }
  if (type) coeffs_[kind][static_cast<long>(*type)] = values;
}

void Converter::neighbor(const Command& c) {
  if (!arity(c, 2, 2, "neighbor SKIN bin")) return;
  if (const auto s = number(c, 1, "the skin")) skin_ = *s;
  if (c.words[2].text != "bin") fail(c, 2, "neighbor: not converted (supported: bin)");
}

// neigh_modify every N delay D check yes|no: the scene's simulation.neighbor,
// so that the lists are rebuilt at LAMMPS's steps and miss what LAMMPS's
// miss. `one` and `page` size LAMMPS's memory, which pdyn sizes itself.
void Converter::neigh_modify(const Command& c) {
  for (std::size_t k = 1; k < c.words.size(); k += 2) {
    const std::string& key = c.words[k].text;
    if (k + 1 >= c.words.size()) {
      fail(c, k, fmt::format("neigh_modify {}: no value (expected {} VALUE)", key, key));
      break;
    }
    if (key == "every" || key == "delay") {
      const auto v = number(c, k + 1, key == "every" ? "a step count >= 1" : "a step count >= 0");
      if (v && !whole_in(*v, key == "every" ? 1 : 0, std::numeric_limits<double>::infinity())) {
        fail(c, k + 1,
             fmt::format("neigh_modify {}: {} (expected a whole number of steps, >= {})", key,
                         c.words[k + 1].text, key == "every" ? 1 : 0));
      } else if (v) {
        (key == "every" ? rebuild_.every : rebuild_.delay) = static_cast<std::int64_t>(*v);
      }
    } else if (key == "check") {
      const std::string& v = c.words[k + 1].text;
      if (v != "yes" && v != "no") {
        fail(c, k + 1, fmt::format("neigh_modify check {}: (expected yes or no)", v));
      }
      rebuild_.check = v == "yes";
    } else if (key != "one" && key != "page") {
      fail(c, k,
           fmt::format("neigh_modify {}: not converted (supported: every, delay, check, one, "
                       "page)",
                       key));
    }
  }
}

void Converter::fix(const Command& c) {
  if (!arity(c, 3, 64, "fix ID GROUP STYLE ...")) return;
  if (c.words[2].text != "all") {
    fail(c, 2, "fix: a group other than all is not converted yet (supported: all)");
    return;
  }
  const std::string& style = c.words[3].text;
  if (style == "nve" && c.words.size() == 4) {
    nve_ = true;
  } else if (style == "nvt" || style == "npt") {
    nvt(c);
  } else if (style == "langevin") {
    langevin(c);
  } else if (style == "rattle" || style == "shake") {
    rattle(c);
  } else {
    fail(
        c, 3,
        fmt::format("fix {}: not converted yet (supported: nve, nvt, npt, langevin, rattle, shake)",
                    style));
  }
}

// fix ID all nvt temp TSTART TSTOP TDAMP [tchain N]: nose_hoover, which
// follows LAMMPS's fix nvt step for step (its chain and dof defaults).
// fix nvt temp TSTART TSTOP TDAMP [tchain N], and fix npt with iso PSTART
// PSTOP PDAMP [pchain N] as well: nose_hoover, which follows LAMMPS's fix nvt
// and fix npt iso step for step.
void Converter::nvt(const Command& c) {
  const std::string& style = c.words[3].text;
  const bool npt = style == "npt";
  const char* form = npt ? "temp TSTART TSTOP TDAMP iso PSTART PSTOP PDAMP [tchain N] [pchain N]"
                         : "temp TSTART TSTOP TDAMP [tchain N]";
  if (c.words.size() < 8 || c.words[4].text != "temp") {
    fail(c, std::min<std::size_t>(4, c.words.size() - 1),
         fmt::format("fix {}: expected {}", style, form));
    return;
  }
  const auto start = number(c, 5, "TSTART"), stop = number(c, 6, "TSTOP"),
             damp = number(c, 7, "TDAMP");
  if (!start || !stop || !damp) return;
  if (*start != *stop) {
    fail(c, 6,
         fmt::format("fix {}: a ramped temperature is not converted yet (expected TSTOP = "
                     "TSTART)",
                     style));
    return;
  }
  Nvt t{*start, *damp, 3, std::nullopt, std::nullopt, 3};
  for (std::size_t k = 8; k < c.words.size(); k += 2) {
    const std::string& key = c.words[k].text;
    if (npt && (key == "aniso" || key == "tri" || key == "x" || key == "y" || key == "z")) {
      fail(c, k,
           fmt::format("fix npt: '{}' is not converted yet (supported: iso; pdyn's barostat is "
                       "isotropic)",
                       key));
      return;
    }
    if (npt && key == "iso" && k + 3 < c.words.size()) {
      const auto p0 = number(c, k + 1, "PSTART"), p1 = number(c, k + 2, "PSTOP"),
                 pd = number(c, k + 3, "PDAMP");
      if (!p0 || !p1 || !pd) return;
      if (*p0 != *p1) {
        fail(c, k + 2, "fix npt: a ramped pressure is not converted yet (expected PSTOP = PSTART)");
        return;
      }
      t.pressure = *p0;
      t.pdamp = *pd;
      k += 2;  // and the loop's 2
      continue;
    }
    const bool chain = key == "tchain" || (npt && key == "pchain");
    const auto v =
        chain && k + 1 < c.words.size() ? number(c, k + 1, "the chain length") : std::nullopt;
    if (!v) {
      fail(c, k,
           fmt::format("fix {}: '{}' is not converted (supported: {})", style, key,
                       npt ? "iso, tchain N, pchain N" : "tchain N"));
      return;
    }
    (key == "tchain" ? t.chain : t.pchain) = static_cast<long>(*v);
  }
  if (npt && !t.pressure) {
    fail(c, 3, fmt::format("fix npt: no iso PSTART PSTOP PDAMP (expected {})", form));
    return;
  }
  nvt_ = t;
}

// fix ID all langevin TSTART TSTOP DAMP SEED: the langevin force, LAMMPS's
// drag m v / DAMP and random force of the same variance, with LAMMPS's
// generator (seed + rank 0) in the order of LAMMPS's atom sort, and verlet
// feeding the forces v_half as fix nve does: the run follows LAMMPS's
// (langevin's generator: lammps, verlet's velocity_forces: half_step).
void Converter::langevin(const Command& c) {
  if (c.words.size() != 8) {
    fail(c, std::min<std::size_t>(8, c.words.size() - 1),
         "fix langevin: expected TSTART TSTOP DAMP SEED and no keywords");
    return;
  }
  const auto start = number(c, 4, "TSTART"), stop = number(c, 5, "TSTOP"),
             damp = number(c, 6, "DAMP"), seed = number(c, 7, "SEED");
  if (!start || !stop || !damp || !seed) return;
  if (*start != *stop) {
    fail(c, 5, "fix langevin: a ramped temperature is not converted yet (expected TSTOP = TSTART)");
    return;
  }
  if (!whole_in(*seed, 1, 900000000)) {
    fail(c, 7,
         fmt::format("fix langevin: seed {} is not one LAMMPS takes (expected a whole number, 1 "
                     "to 900000000)",
                     c.words[7].text));
    return;
  }
  langevin_ = Langevin{*start, *damp, static_cast<long>(*seed)};
}

// fix ID all rattle TOL ITER N b T... a T...
void Converter::rattle(const Command& c) {
  Rigid r;
  if (const auto tol = number(c, 4, "the tolerance")) r.tolerance = *tol;
  std::vector<long>* list = nullptr;
  for (std::size_t k = 7; k < c.words.size(); ++k) {
    const std::string& w = c.words[k].text;
    if (w == "b" || w == "a") {
      list = w == "b" ? &r.bonds : &r.angles;
    } else if (const auto t = list ? number(c, k, "a type") : std::nullopt) {
      list->push_back(static_cast<long>(*t));
    } else if (!list) {
      fail(c, k,
           fmt::format("fix {}: '{}' is not converted (supported: b TYPES, a TYPES)",
                       c.words[3].text, w));
    }
  }
  r.at = c;
  rigid_ = r;
}

void Converter::thermo_style(const Command& c) {
  static const std::map<std::string, std::string> kColumns = {
      {"step", "step"},    {"temp", "kT"},     {"press", "pressure"},
      {"pe", "potential"}, {"ke", "kinetic"},  {"etotal", "total"},
      {"epair", "pair"},   {"emol", "bonded"}, {"vol", "volume"}};
  if (!arity(c, 1, 64, "thermo_style custom KEYWORDS")) return;
  if (c.words[1].text != "custom") {
    if (c.words[1].text != "one")
      fail(c, 1, "thermo_style: not converted (supported: one, custom)");
    return;
  }
  columns_.clear();
  for (std::size_t k = 2; k < c.words.size(); ++k) {
    const auto it = kColumns.find(c.words[k].text);
    if (it == kColumns.end()) {
      fail(c, k,
           fmt::format("thermo_style custom: '{}' is not converted yet (supported: step, "
                       "temp, press, pe, ke, etotal, epair, emol, vol)",
                       c.words[k].text));
    } else {
      columns_.push_back(it->second);
    }
  }
}

void Converter::thermo_modify(const Command& c) {
  for (std::size_t k = 1; k + 1 < c.words.size(); ++k) {
    if (c.words[k].text == "norm") {
      normalized_ = c.words[k + 1].text == "yes";
      ++k;
    } else if (c.words[k].text == "format") {
      k = c.words.size();  // the printed digits: pdyn writes every double exactly
    } else {
      fail(c, k,
           fmt::format("thermo_modify {}: not converted (supported: norm, format)",
                       c.words[k].text));
    }
  }
}

void Converter::run(const Command& c) {
  if (steps_) {
    fail(c, 0, "run: a second run is not converted yet (expected one run command)");
    return;
  }
  if (arity(c, 1, 1, "run N")) {
    if (const auto n = number(c, 1, "a step count")) steps_ = static_cast<long>(*n);
  }
}

// ---------------------------------------------------------------------------
// Writing

ConvertedScene Converter::convert(const std::string& text, const std::string& stem) {
  const std::vector<Command> commands = split(text);
  for (const Command& c : commands) command(c);
  // What the whole script lacks is located at the script, not at a line.
  auto lacks = [&](const char* what) { diags_.push_back({file_, what}); };
  if (data_.empty() == (x_.cols() == 0)) {
    lacks(data_.empty() ? "no read_data or create_atoms (expected the particles from a data file "
                          "or a lattice)"
                        : "both read_data and create_atoms (expected one of them)");
  }
  if (!steps_) lacks("no run command (expected run N)");
  if (!dt_) dt_ = 0.005;  // LAMMPS's default in lj units
  if (nve_ == nvt_.has_value()) {
    lacks("no fix nve, nvt or npt, or more than one (expected one of fix ID all nve, nvt, npt)");
  }
  if (nvt_ && rigid_) lacks("fix nvt or npt with fix rattle is not converted yet (expected nve)");
  check_coefficients();
  ConvertedScene out;
  for (long t = 1; x_.cols() > 0 && t <= types_; ++t) {
    if (mass_.count(t) == 0) {
      lacks("atom types without a mass (expected mass TYPE VALUE for each type)");
      break;
    }
  }
  if (x_.cols() > 0) {
    data_ = stem + ".data";
    out.files.emplace_back(data_, data_file());
  }
  if (!diags_.empty()) throw SceneError(diags_);
  out.scene = yaml();
  return out;
}

std::string Converter::bonded_entries() const {
  static const std::map<std::string, std::string> kTerms = {
      {"bond", "pairs: { file: DATA"},
      {"angle", "triples: { file: DATA"},
      {"dihedral", "quads: { file: DATA"},
      {"improper", "quads: { file: DATA, section: Impropers"}};
  std::string out;
  for (const auto& [kind, style] : style_) {
    const BondedStyle& b = *find_style(kind, style);
    const auto& by_type = coeffs_of(kind);
    // The bonds and angles fix rattle holds are SHAKE's, not the force's.
    const std::vector<long> none;
    const std::vector<long>& rigid = !rigid_           ? none
                                     : kind == "bond"  ? rigid_->bonds
                                     : kind == "angle" ? rigid_->angles
                                                       : none;
    std::vector<long> free_types;
    for (const auto& [t, v] : by_type) {
      if (std::find(rigid.begin(), rigid.end(), t) == rigid.end()) free_types.push_back(t);
    }
    if (free_types.empty()) continue;
    std::string terms = kTerms.at(kind);
    terms.replace(terms.find("DATA"), 4, data_);
    out += fmt::format("  # {}, {}_coeff\n  - {{ type: {}, {}, types: [{}] }}", b.note, kind,
                       b.plugin, terms, fmt::join(free_types, ", "));
    for (const Coefficient& k : b.coefficients) {
      std::vector<double> v;
      v.reserve(by_type.size());
      for (const auto& [t, c] : by_type) v.push_back(k.scale * c[k.index]);
      out += fmt::format(", {}: [{}]", k.key, fmt::join(v, ", "));
    }
    out += " }\n";
  }
  return out;
}

// fix langevin's force: LAMMPS sorts its atoms in bins of half the
// neighbor cutoff (Atom::sort), and draws in that order.
std::string Converter::langevin_entry() const {
  if (!langevin_) return "";
  std::string out = fmt::format(
      "  # fix langevin: LAMMPS's numbers, drawn in the order of its atom sort\n"
      "  - {{ type: langevin, kT: {}, damp: {}, seed: {}, generator: lammps, "
      "lammps_sort_bin: {} }}\n",
      langevin_->kT, langevin_->damp, langevin_->seed, 0.5 * (pair_cutoff_max_ + skin_));
  if (*steps_ > 1000) {
    out +=
        "  # LAMMPS sorts its atoms again every 1000 steps (atom_modify sort), and from then on\n"
        "  # gives its numbers to other atoms: the runs agree in distribution after that.\n";
  }
  return out;
}

std::string Converter::yaml() const {
  std::string out = fmt::format(
      "# Converted by `pdyn convert` from the LAMMPS input script {}.\n"
      "simulation:\n  dt: {}\n  steps: {}\n",
      file_, *dt_, *steps_);
  out += fmt::format("  neighbor: {{ every: {}, delay: {}, check: {} }}  # neigh_modify{}\n",
                     rebuild_.every, rebuild_.delay, rebuild_.check ? "true" : "false",
                     rebuild_ == RebuildSchedule{1, 10, true} ? " (LAMMPS's default)" : "");
  if (nvt_) {
    const std::string barostat = nvt_->pressure
                                     ? fmt::format(", pressure: {}, pdamp: {}, pchain: {}",
                                                   *nvt_->pressure, *nvt_->pdamp, nvt_->pchain)
                                     : "";
    out +=
        fmt::format("  solver: {{ type: nose_hoover, kT: {}, tdamp: {}, chain: {}{} }}  # fix {}\n",
                    nvt_->kT, nvt_->tdamp, nvt_->chain, barostat, nvt_->pressure ? "npt" : "nvt");
  } else {
    out += fmt::format("  solver: {{ type: verlet{}{} }}  # fix nve{}\n",
                       langevin_ ? ", velocity_forces: half_step" : "",
                       rigid_ ? fmt::format(", rattle_tolerance: {}", rigid_->tolerance) : "",
                       rigid_ ? ", fix rattle" : "");
  }
  // A data file is read in the script's atom_style, as read_data reads it
  // (the file need not say its style); by its format when its name does
  // not say it (LAMMPS's data.NAME).
  std::string keys;
  if (x_.cols() == 0) {
    if (import_files::format_of_extension(data_) != import_files::Format::LammpsData) {
      keys += ", format: lammps_data";
    }
    if (!atom_style_.empty()) keys += ", atom_style: " + atom_style_;
  }
  out += fmt::format("  box: {{ file: {}{} }}\nparticles:\n  - {{ file: {}{} }}\n", data_, keys,
                     data_, keys);
  if (!style_.empty()) {
    out += fmt::format("special_bonds: {{ lj: [{}] }}  # LAMMPS's special_bonds (default 0 0 0)\n",
                       fmt::join(special_, ", "));
  }
  out += "forces:\n";
  // One row, `pair_coeff 1 1`: LAMMPS runs it only with one atom type (it
  // refuses pairs without coefficients), so the law needs no types: the
  // same numbers, without the per-pair table lookup (about 10% of a pair
  // loop).
  const bool one_type = pair_rows_.size() == 1 && type_one_ && !pair_all_;
  if (cutoff_ && one_type) {
    out += fmt::format(
        "  # pair_style lj/cut, pair_coeff 1 1 (one atom type), neighbor\n  - {{ type: "
        "lennard_jones, cutoff: {}, skin: {}, shift: {}, epsilon: {}, sigma: {}",
        (*type_one_)[2], skin_, shift_ ? "true" : "false", (*type_one_)[0], (*type_one_)[1]);
    if (!mix_.empty()) out += ", mix: " + mix_;
    out += " }\n";
  } else if (cutoff_) {
    out += fmt::format(
        "  # pair_style lj/cut, pair_coeff, neighbor\n  - {{ type: lennard_jones, "
        "cutoff: {}, skin: {}, shift: {}",
        *cutoff_, skin_, shift_ ? "true" : "false");
    if (pair_all_) out += fmt::format(", epsilon: {}, sigma: {}", (*pair_all_)[0], (*pair_all_)[1]);
    if (!pair_rows_.empty()) {
      out += fmt::format(", pair_coeff: [\"{}\"]", fmt::join(pair_rows_, "\", \""));
    }
    if (!mix_.empty()) out += ", mix: " + mix_;
    out += " }\n";
  }
  out += bonded_entries();
  out += langevin_entry();
  out += rigid_entries();
  out += output_entry();
  return out;
}

std::string Converter::rigid_entries() const {
  if (!rigid_) return {};
  std::string out = "constraints:\n";
  // check_coefficients() saw every type 1..T of each given.
  const auto& bonds = coeffs_of("bond");
  const auto& angles = coeffs_of("angle");
  auto r0 = [&](long t) { return bonds.at(t)[1]; };
  if (!rigid_->bonds.empty()) {
    std::vector<double> lengths;
    for (long t = 1; t <= bonds.rbegin()->first; ++t) lengths.push_back(r0(t));
    out += fmt::format(
        "  # fix rattle b: the bonds' r0\n  - {{ type: distance, pairs: {{ file: {}, "
        "types: [{}] }}, length: [{}] }}\n",
        data_, fmt::join(rigid_->bonds, ", "), fmt::join(lengths, ", "));
  }
  if (!rigid_->angles.empty()) {
    // The ends of an angle theta0 between two bonds of r0 (the rigid bonds'
    // length: every rigid bond type has the first's).
    const double b = r0(rigid_->bonds.front());
    std::vector<double> lengths;
    for (long t = 1; t <= angles.rbegin()->first; ++t) {
      const double theta = angles.at(t)[1] * M_PI / 180.0;
      lengths.push_back(std::sqrt(2.0 * b * b - 2.0 * b * b * std::cos(theta)));
    }
    out += fmt::format(
        "  # fix rattle a: the ends of each angle, sqrt(2 r0^2 (1 - cos theta0))\n"
        "  - {{ type: distance, triples: {{ file: {}, types: [{}] }}, length: [{}] "
        "}}\n",
        data_, fmt::join(rigid_->angles, ", "), fmt::join(lengths, ", "));
  }
  return out;
}

const std::map<long, std::vector<double>>& Converter::coeffs_of(const std::string& kind) const {
  static const std::map<long, std::vector<double>> kNone;
  const auto it = coeffs_.find(kind);
  return it == coeffs_.end() ? kNone : it->second;
}

// Every bonded style has coefficients for its types 1..T, without a gap
// (the plugins' per-type lists are indexed by t - 1), and fix rattle's
// types have theirs: a style without them would drop its terms from the
// scene, and a rod its length.
void Converter::check_coefficients() {
  for (const auto& [kind, at] : style_at_) {
    const auto& by_type = coeffs_of(kind);
    if (by_type.empty()) {
      fail(at, 1,
           fmt::format("{}_style {}: no {}_coeff (expected one per {} type; pdyn convert does "
                       "not read a data file's Coeffs sections yet)",
                       kind, style_.at(kind), kind, kind));
      continue;
    }
    for (long t = 1; t <= by_type.rbegin()->first; ++t) {
      if (by_type.count(t) == 0) {
        fail(at, 1,
             fmt::format("{}_style {}: no {}_coeff for type {} (expected coefficients for "
                         "every type 1..{})",
                         kind, style_.at(kind), kind, t, by_type.rbegin()->first));
        break;
      }
    }
  }
  if (!rigid_) return;
  if (!rigid_->angles.empty() && rigid_->bonds.empty()) {
    fail(rigid_->at, 3,
         "fix rattle: angles without bonds (expected b TYPES too: SHAKE holds an angle's two "
         "bonds with it)");
  }
  for (const auto& [kind, types] :
       {std::pair<std::string, const std::vector<long>&>{"bond", rigid_->bonds},
        {"angle", rigid_->angles}}) {
    for (const long t : types) {
      if (coeffs_of(kind).count(t) == 0) {
        fail(rigid_->at, 3,
             fmt::format("fix rattle: {} type {} has no {}_coeff (expected its {} to hold it "
                         "at)",
                         kind, t, kind, kind == "bond" ? "r0" : "theta0"));
      }
    }
  }
}

std::string Converter::output_entry() const {
  if (thermo_every_ <= 0) return {};
  const std::string stem = std::filesystem::path(file_).filename().string();
  return fmt::format(
      "output:\n  # thermo, thermo_style, thermo_modify: LAMMPS's columns, names and "
      "normalization\n  - {{ type: energy, path: {}-thermo.csv, every: {}, columns: [{}], header: "
      "lammps, per_particle: {} }}\n",
      stem, thermo_every_, fmt::join(columns_, ", "), normalized_ ? "true" : "false");
}

}  // namespace pdyn::lammps

namespace pdyn {

ConvertedScene convert_lammps_script(const std::string& text, const std::string& file,
                                     const std::string& stem) {
  return convert_lammps_script(text, file, stem, ConvertOptions{});
}

ConvertedScene convert_lammps_script(const std::string& text, const std::string& file,
                                     const std::string& stem, const ConvertOptions& options) {
  return lammps::Converter(file, options).convert(text, stem);
}

std::string convert_lammps_input(const std::string& text, const std::string& file) {
  ConvertedScene out = convert_lammps_script(text, file, "scene");
  if (!out.files.empty()) {
    throw SceneError({{file,
                       "the script makes its own atoms, which go to a data file beside the scene "
                       "(expected pdyn convert IN -o SCENE.yaml)"}});
  }
  return std::move(out.scene);
}

}  // namespace pdyn
