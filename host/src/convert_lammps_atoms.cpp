// `pdyn convert`: the atoms a LAMMPS script makes itself. `lattice`,
// `region ID block`, `create_box` and `create_atoms` place them,
// `mass` weighs them and `velocity create` moves them, as LAMMPS does on one
// process (lammps_atoms.hpp); the converter writes them to a LAMMPS data
// file beside the scene, which the scene reads (`STEM.data`).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>

#include "convert_lammps.hpp"

namespace pdyn::lammps {

void Converter::lattice(const Command& c) {
  if (!arity(c, 2, 2, "lattice STYLE RHO, with no keywords")) return;
  const std::vector<Vec3> basis = lattice_basis(c.words[1].text);
  if (basis.empty()) {
    fail(c, 1,
         fmt::format("lattice {}: not converted yet (supported: sc, bcc, fcc)", c.words[1].text));
    return;
  }
  const auto rho = number(c, 2, "the reduced density");
  if (!rho) return;
  if (!(*rho > 0.0)) {
    fail(c, 2, fmt::format("lattice: density {} (expected > 0)", c.words[2].text));
    return;
  }
  basis_ = basis;
  spacing_ = lattice_spacing(basis.size(), *rho);
}

// xlo xhi ylo yhi zlo zhi from word `first` on, in box units or lattice
// spacings (RegBlock: xscale * value).
std::optional<std::array<double, 6>> Converter::block_bounds(const Command& c, std::size_t first,
                                                             bool lattice_units) {
  std::array<double, 6> b{};
  for (std::size_t k = 0; k < 6; ++k) {
    const std::string& w = c.words[first + k].text;
    if (w == "INF" || w == "EDGE") {
      fail(c, first + k, fmt::format("region: {} is not converted (expected a number)", w));
      return std::nullopt;
    }
    const auto v = number(c, first + k, "a bound");
    if (!v) return std::nullopt;
    b[k] = lattice_units ? spacing_ * *v : *v;
  }
  for (std::size_t a = 0; a < 3; ++a) {
    if (!(b[2 * a] < b[2 * a + 1])) {
      fail(c, first + 2 * a + 1,
           fmt::format("region: the {} bounds {} {} are empty (expected lo < hi)", "xyz"[a],
                       c.words[first + 2 * a].text, c.words[first + 2 * a + 1].text));
      return std::nullopt;
    }
  }
  return b;
}

void Converter::region(const Command& c) {
  if (!arity(c, 8, 12, "region ID block XLO XHI YLO YHI ZLO ZHI [units lattice|box]")) return;
  if (c.words[2].text != "block") {
    fail(c, 2, fmt::format("region {}: not converted yet (supported: block)", c.words[2].text));
    return;
  }
  bool lattice_units = true;
  for (std::size_t k = 9; k < c.words.size(); k += 2) {
    const std::string& key = c.words[k].text;
    const std::string value = k + 1 < c.words.size() ? c.words[k + 1].text : "";
    if (key == "units" && (value == "lattice" || value == "box")) {
      lattice_units = value == "lattice";
    } else if (!(key == "side" && value == "in")) {
      fail(c, k,
           fmt::format("region: '{} {}' is not converted (supported: units lattice, units box, "
                       "side in)",
                       key, value));
      return;
    }
  }
  if (lattice_units && basis_.empty()) {
    fail(c, 0, "region: in lattice units before any lattice command (expected lattice first)");
    return;
  }
  if (const auto b = block_bounds(c, 3, lattice_units)) {
    regions_[c.words[1].text] = Block{{(*b)[0], (*b)[2], (*b)[4]}, {(*b)[1], (*b)[3], (*b)[5]}};
  }
}

void Converter::create_box(const Command& c) {
  if (!arity(c, 2, 2, "create_box N REGION, with no keywords")) return;
  const auto n = number(c, 1, "the number of atom types");
  if (!n) return;
  if (!whole_in(*n, 1, std::numeric_limits<double>::infinity())) {
    fail(c, 1, fmt::format("create_box: {} atom types (expected a whole number >= 1)", *n));
    return;
  }
  const auto r = regions_.find(c.words[2].text);
  if (r == regions_.end()) {
    fail(c, 2,
         fmt::format("create_box: no region '{}' (expected a region block)", c.words[2].text));
    return;
  }
  box_ = r->second;
  types_ = static_cast<long>(*n);
}

void Converter::create_atoms(const Command& c) {
  if (!arity(c, 2, 3, "create_atoms TYPE box, or create_atoms TYPE region ID")) return;
  if (!box_ || basis_.empty()) {
    fail(c, 0, "create_atoms: no box or no lattice yet (expected lattice and create_box first)");
    return;
  }
  const auto t = number(c, 1, "an atom type");
  if (!t) return;
  if (!whole_in(*t, 1, static_cast<double>(types_))) {
    fail(c, 1, fmt::format("create_atoms: type {} (expected 1..{})", c.words[1].text, types_));
    return;
  }
  const Block* region = nullptr;
  if (c.words[2].text == "region" && c.words.size() == 4) {
    const auto r = regions_.find(c.words[3].text);
    if (r == regions_.end()) {
      fail(c, 3, fmt::format("create_atoms: no region '{}'", c.words[3].text));
      return;
    }
    region = &r->second;
  } else if (c.words[2].text != "box" || c.words.size() != 3) {
    fail(
        c, 2,
        fmt::format("create_atoms {}: not converted (supported: box, region ID)", c.words[2].text));
    return;
  }
  const std::vector<Vec3> sites = lattice_sites(basis_, spacing_, *box_, region);
  const Index before = x_.cols();
  x_.conservativeResize(3, before + static_cast<Index>(sites.size()));
  for (std::size_t i = 0; i < sites.size(); ++i) x_.col(before + static_cast<Index>(i)) = sites[i];
  type_.insert(type_.end(), sites.size(), static_cast<long>(*t));
  v_.reset();  // velocities are drawn for every atom there is, so after the last ones
}

void Converter::mass(const Command& c) {
  if (!arity(c, 2, 2, "mass TYPE VALUE")) return;
  const auto m = number(c, 2, "a mass");
  if (!m) return;
  if (!(*m > 0.0)) {
    fail(c, 2, fmt::format("mass: {} (expected > 0)", c.words[2].text));
    return;
  }
  if (c.words[1].text == "*") {
    for (long t = 1; t <= types_; ++t) mass_[t] = *m;
    return;
  }
  const auto t = number(c, 1, "an atom type or *");
  if (t && !whole_in(*t, 1, static_cast<double>(types_))) {
    fail(c, 1,
         fmt::format("mass: type {} (expected 1..{} after create_box, or *)", c.words[1].text,
                     types_));
  } else if (t) {
    mass_[static_cast<long>(*t)] = *m;
  }
}

// velocity all create T SEED [dist D] [loop L] [mom yes|no] [rot no] [sum no].
void Converter::velocity(const Command& c) {
  if (!arity(c, 4, 16, "velocity all create T SEED [keywords]")) return;
  if (c.words[1].text != "all") {
    fail(c, 1, "velocity: a group other than all is not converted yet (supported: all)");
    return;
  }
  if (c.words[2].text != "create") {
    fail(c, 2, fmt::format("velocity {}: not converted yet (supported: create)", c.words[2].text));
    return;
  }
  if (x_.cols() == 0) {
    fail(c, 0,
         "velocity create: no atoms made by create_atoms before it (supported: velocity create "
         "after create_atoms; a data file gives its own Velocities)");
    return;
  }
  VelocityCreate spec;
  const auto t = number(c, 3, "a temperature");
  const auto seed = number(c, 4, "a seed");
  if (!t || !seed) return;
  if (!whole_in(*seed, 1, 2147483647.0)) {
    fail(c, 4,
         fmt::format("velocity create: seed {} (expected a whole number from 1 to 2^31 - 1)",
                     c.words[4].text));
    return;
  }
  spec.temperature = *t;
  spec.seed = static_cast<int>(*seed);
  static const std::map<std::string, std::map<std::string, int>> kKeywords = {
      {"dist", {{"uniform", 0}, {"gaussian", 1}}},
      {"loop", {{"all", 0}, {"local", 1}, {"geom", 2}}},
      {"mom", {{"no", 0}, {"yes", 1}}},
      {"rot", {{"no", 0}}},
      {"sum", {{"no", 0}}}};
  for (std::size_t k = 5; k < c.words.size(); k += 2) {
    const std::string& key = c.words[k].text;
    const auto it = kKeywords.find(key);
    const std::string value = k + 1 < c.words.size() ? c.words[k + 1].text : "";
    if (it == kKeywords.end() || it->second.count(value) == 0) {
      fail(c, k,
           fmt::format("velocity create: '{} {}' is not converted (supported: dist uniform|"
                       "gaussian, loop all|local|geom, mom yes|no, rot no, sum no)",
                       key, value));
      return;
    }
    const int v = it->second.at(value);
    if (key == "dist") spec.gaussian = v == 1;
    if (key == "loop") spec.loop = static_cast<VelocityCreate::Loop>(v);
    if (key == "mom") spec.momentum = v == 1;
  }
  std::vector<double> m(type_.size());
  for (std::size_t i = 0; i < type_.size(); ++i) {
    const auto it = mass_.find(type_[i]);
    if (it == mass_.end()) {
      fail(c, 0,
           fmt::format("velocity create: atom type {} has no mass yet (expected mass {} VALUE "
                       "before it, as LAMMPS does)",
                       type_[i], type_[i]));
      return;
    }
    m[i] = it->second;
  }
  try {
    v_ = velocity_create(x_, m, spec);
  } catch (const Error& e) {
    fail(c, 0, e.what());
  }
}

// A LAMMPS data file (atom_style atomic) of the atoms made, every number
// with 17 significant digits: read back, each is the same double.
std::string Converter::data_file() const {
  std::string out = fmt::format(
      "LAMMPS data file: the atoms {} makes (lattice, create_atoms, velocity), by pdyn "
      "convert\n\n{} atoms\n{} atom types\n\n",
      file_, x_.cols(), types_);
  for (int a = 0; a < 3; ++a) {
    out += fmt::format("{:.17g} {:.17g} {}lo {}hi\n", box_->lo[a], box_->hi[a], "xyz"[a], "xyz"[a]);
  }
  out += "\nMasses\n\n";
  for (const auto& [t, m] : mass_) out += fmt::format("{} {:.17g}\n", t, m);
  out += "\nAtoms # atomic\n\n";
  for (Index i = 0; i < x_.cols(); ++i) {
    out += fmt::format("{} {} {:.17g} {:.17g} {:.17g}\n", i + 1, type_[static_cast<std::size_t>(i)],
                       x_(0, i), x_(1, i), x_(2, i));
  }
  if (v_) {
    out += "\nVelocities\n\n";
    for (Index i = 0; i < x_.cols(); ++i) {
      out +=
          fmt::format("{} {:.17g} {:.17g} {:.17g}\n", i + 1, (*v_)(0, i), (*v_)(1, i), (*v_)(2, i));
    }
  }
  return out;
}

}  // namespace pdyn::lammps
