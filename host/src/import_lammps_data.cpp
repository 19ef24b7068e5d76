// LAMMPS data files, as LAMMPS's read_data documentation describes them
// ("Format of a data file"): a title line; a header of counts ("256 atoms",
// "2 atom types", ...) and box bounds ("0 6.7 xlo xhi"); then sections, each
// a title line (which may carry a comment, "Atoms # full"), a blank line
// and as many rows as the header's count for it says. Atoms, Masses and
// Velocities are read, and the topology (Bonds, Angles, Dihedrals,
// Impropers) into Imported::topology with atom ids turned into particle
// indices; the other sections (Pair Coeffs, ...) are skipped by their
// counts, and those that hold particles' topology or shape (kUnread) are
// listed in Imported::unread for the loader to warn about unless a force
// or constraint of the scene takes them.
#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <numbers>

#include "import_reader.hpp"
#include "pdyn/text.hpp"

namespace pdyn::import_files::detail {

namespace {

// The columns of an Atoms row per atom style (read_data's "Atoms section"
// table): id first, then where type, x and the style's extras are.
struct AtomStyle {
  const char* name;
  int width, type, x, diameter, density;  // -1: the style has no such column
};
constexpr AtomStyle kStyles[] = {
    {"atomic", 5, 1, 2, -1, -1},     // id type x y z
    {"charge", 6, 1, 3, -1, -1},     // id type q x y z
    {"sphere", 7, 1, 4, 2, 3},       // id type diameter density x y z
    {"bond", 6, 2, 3, -1, -1},       // id molecule type x y z
    {"angle", 6, 2, 3, -1, -1},      // id molecule type x y z
    {"molecular", 6, 2, 3, -1, -1},  // id molecule type x y z
    {"full", 7, 2, 4, -1, -1},       // id molecule type q x y z
};
constexpr const char* kStyleNames = "atomic, charge, sphere, bond, angle, molecular, full";

// Every section read_data knows and the header count that gives its rows
// (nullptr: Bodies, whose rows per body vary; "atom type pairs": PairIJ
// Coeffs, one row per pair I <= J).
struct Section {
  const char* title;
  const char* count;
};
constexpr Section kSections[] = {
    {"Atoms", "atoms"},
    {"Velocities", "atoms"},
    {"Masses", "atom types"},
    {"Ellipsoids", "ellipsoids"},
    {"Lines", "lines"},
    {"Triangles", "triangles"},
    {"Bodies", nullptr},
    {"Bonds", "bonds"},
    {"Angles", "angles"},
    {"Dihedrals", "dihedrals"},
    {"Impropers", "impropers"},
    {"Pair Coeffs", "atom types"},
    {"PairIJ Coeffs", "atom type pairs"},
    {"Bond Coeffs", "bond types"},
    {"Angle Coeffs", "angle types"},
    {"Dihedral Coeffs", "dihedral types"},
    {"Improper Coeffs", "improper types"},
    {"BondBond Coeffs", "angle types"},
    {"BondAngle Coeffs", "angle types"},
    {"MiddleBondTorsion Coeffs", "dihedral types"},
    {"EndBondTorsion Coeffs", "dihedral types"},
    {"AngleTorsion Coeffs", "dihedral types"},
    {"AngleAngleTorsion Coeffs", "dihedral types"},
    {"BondBond13 Coeffs", "dihedral types"},
    {"AngleAngle Coeffs", "improper types"},
    {"Atom Type Labels", "atom types"},
    {"Bond Type Labels", "bond types"},
    {"Angle Type Labels", "angle types"},
    {"Dihedral Type Labels", "dihedral types"},
    {"Improper Type Labels", "improper types"},
};
// The sections whose rows change the physics and that pdyn does not read:
// loading such a file without a word would run a molecule as free atoms
// (issue 42). Coefficient sections go with the scene's own forces and are
// not listed.
constexpr const char* kUnread[] = {"Bonds",      "Angles", "Dihedrals", "Impropers",
                                   "Ellipsoids", "Lines",  "Triangles", "Bodies"};

// The header lines that count something ("N atoms", "N atom types", ...).
constexpr const char* kCounts[] = {"atoms",          "bonds",         "angles",     "dihedrals",
                                   "impropers",      "ellipsoids",    "lines",      "triangles",
                                   "bodies",         "atom types",    "bond types", "angle types",
                                   "dihedral types", "improper types"};

// A section title starts with a capital letter; header lines and rows
// start with a number.
bool is_title(const Line& l) {
  return !l.fields.empty() && l.fields[0].text[0] >= 'A' && l.fields[0].text[0] <= 'Z';
}

// The words of a line before its comment: "Pair Coeffs".
std::string words(const Line& l, std::size_t from = 0) {
  std::string s;
  for (std::size_t k = from; k < l.fields.size(); ++k) {
    s += (k > from ? " " : "") + std::string(l.fields[k].text);
  }
  return s;
}

struct DataFile {
  std::map<std::string, long long> counts;                   // header counts by keyword
  std::size_t atoms_line = 1;                                // the header's "N atoms"
  Vec3 lo = Vec3::Constant(-0.5), hi = Vec3::Constant(0.5);  // read_data's default box
  const AtomStyle* style = nullptr;
  Atoms atoms;
  bool have_atoms = false, have_masses = false;
  bool bad_masses = false;  // a Masses row was refused: its type's atoms are not blamed too
  std::map<long long, double> type_mass;
  std::map<long long, std::pair<Vec3, std::size_t>> velocity;  // id -> v, line
  std::vector<Imported::Unread> unread;
  // Topology rows as written: atom ids (and their columns), turned into
  // particle indices once every atom is read.
  struct TermRows {
    Imported::Terms terms;
    std::vector<std::array<long long, 4>> ids;
    std::vector<std::array<std::size_t, 4>> columns;
  };
  std::vector<TermRows> topology;

  long long count(const std::string& key) const {
    if (key == "atom type pairs") {
      const long long n = count("atom types");
      return n < 0 ? -1 : n * (n + 1) / 2;
    }
    const auto it = counts.find(key);
    return it == counts.end() ? -1 : it->second;
  }
};

void read_box_line(const Line& l, DataFile& d, Problems& problems) {
  const auto& f = l.fields;
  const int axis = f[2].text[0] - 'x';
  if (axis < 0 || axis > 2 || f[2].text.substr(1) != "lo" || f[3].text[0] != f[2].text[0]) return;
  const auto a = parse_real(f[0], l.number, f[2].text, problems);
  const auto b = parse_real(f[1], l.number, f[3].text, problems);
  if (!a || !b) return;
  if (!(*a < *b)) {
    problems.add(l.number, f[1].column,
                 fmt::format("{} {} is not above {} {} (expected hi > lo)", f[3].text, f[1].text,
                             f[2].text, f[0].text));
    return;
  }
  d.lo[axis] = *a;
  d.hi[axis] = *b;
}

// The header, from line 2 to the first section title; returns that title's
// index. Lines read_data knows but pdyn does not need ("1 extra bond per
// atom") are passed over.
std::size_t read_header(const std::vector<Line>& lines, DataFile& d, Problems& problems) {
  std::size_t k = 1;  // line 1 is the title, whatever it says
  for (; k < lines.size() && !is_title(lines[k]); ++k) {
    const Line& l = lines[k];
    const auto& f = l.fields;
    if (f.size() == 4 && f[2].text.size() == 3 && f[3].text.size() == 3 &&
        f[3].text.substr(1) == "hi") {
      read_box_line(l, d, problems);
    } else if (f.size() == 6 && f[3].text == "xy") {
      problems.add(l.number, f[3].column,
                   "the box is triclinic (xy xz yz tilt factors) (expected an orthogonal box: "
                   "pdyn's simulation box has no tilt)");
    } else if (f.size() >= 2) {
      const std::string key = words(l, 1);
      if (std::find(std::begin(kCounts), std::end(kCounts), key) == std::end(kCounts)) continue;
      if (auto n = parse_whole(f[0], l.number, key, problems, 0)) d.counts[key] = *n;
      if (key == "atoms") d.atoms_line = l.number;
    }
  }
  if (d.count("atoms") < 0) {
    problems.add(std::clamp<std::size_t>(lines.size(), 1, 2), 1,
                 "the header has no 'N atoms' line (expected a LAMMPS data file, whose header "
                 "counts its atoms)");
  }
  return k;
}

void read_masses(const std::vector<const Line*>& rows, DataFile& d, Problems& problems) {
  d.have_masses = true;
  for (const Line* r : rows) {
    if (r->fields.size() != 2) {
      problems.add(r->number, 1,
                   fmt::format("a Masses row has {} (expected 2: type mass)",
                               count_of(static_cast<long long>(r->fields.size()), "field")));
      d.bad_masses = true;
      continue;
    }
    const auto t = parse_whole(r->fields[0], r->number, "type", problems, 1);
    const auto m = parse_mass(r->fields[1], r->number, problems);
    d.bad_masses = d.bad_masses || !t || !m;
    if (t && m && !d.type_mass.emplace(*t, *m).second) {
      problems.add(r->number, 1,
                   fmt::format("type {} has a second Masses row (expected one per type)", *t));
    }
  }
}

void read_velocities(const std::vector<const Line*>& rows, DataFile& d, Problems& problems) {
  for (const Line* r : rows) {
    const auto& f = r->fields;
    // Atom style sphere adds the angular velocity wx wy wz, which pdyn's
    // point masses do not have.
    if (f.size() != 4 && f.size() != 7) {
      problems.add(r->number, 1,
                   fmt::format("a Velocities row has {} (expected 4: id vx vy vz, or 7 for atom "
                               "style sphere: id vx vy vz wx wy wz)",
                               count_of(static_cast<long long>(f.size()), "field")));
      continue;
    }
    const auto id = parse_whole(f[0], r->number, "id", problems, 1);
    Vec3 v;
    bool ok = id.has_value();
    for (int c = 0; c < 3; ++c) {
      const auto x = parse_real(f[1 + c], r->number, std::string("v") + "xyz"[c], problems);
      ok = ok && x;
      if (x) v[c] = *x;
    }
    if (ok && !d.velocity.emplace(*id, std::pair{v, r->number}).second) {
      problems.add(r->number, 1,
                   fmt::format("atom {} has a second Velocities row (expected one per atom; the "
                               "first at line {})",
                               *id, d.velocity[*id].second));
    }
  }
}

// Atom style sphere: radius = diameter / 2 and, for a finite diameter, the
// density times the volume, computed as LAMMPS's AtomVecSphere::
// data_atom_post does (rmass *= 4 pi / 3 r^3, same order, same bits); a
// point particle (diameter 0) has its density as its mass.
bool read_sphere(const std::vector<Field>& f, std::size_t line, const AtomStyle& s, Atom& a,
                 Problems& problems) {
  const auto d = parse_size(f[static_cast<std::size_t>(s.diameter)], line, "diameter", problems);
  const auto& rho_field = f[static_cast<std::size_t>(s.density)];
  const auto rho = parse_real(rho_field, line, "density", problems);
  if (rho && !(*rho > 0.0)) {
    problems.add(line, rho_field.column,
                 fmt::format("density: {} is not positive (expected a density > 0 kg/m^3, or "
                             "the mass in kg of a particle of diameter 0)",
                             rho_field.text));
    return false;
  }
  if (!d || !rho) return false;
  const double r = 0.5 * *d;
  a.radius = r;
  a.mass = r > 0.0 ? *rho * (4.0 * std::numbers::pi / 3.0 * r * r * r) : *rho;
  return true;
}

void read_atom_row(const Line& r, DataFile& d, Problems& problems) {
  const AtomStyle& s = *d.style;
  const auto& f = r.fields;
  const auto width = static_cast<std::size_t>(s.width);
  if (f.size() != width && f.size() != width + 3) {
    problems.add(
        r.number, 1,
        fmt::format("an Atoms row of style {} has {} (expected {}, or {} with image "
                    "flags)",
                    s.name, count_of(static_cast<long long>(f.size()), "field"), width, width + 3));
    return;
  }
  Atom a;
  const auto id = parse_whole(f[0], r.number, "id", problems, 1);
  const auto& type_field = f[static_cast<std::size_t>(s.type)];
  const auto type = parse_whole(type_field, r.number, "type", problems, 1);
  bool ok = id && type;
  const long long types = d.count("atom types");
  if (type && types >= 0 && *type > types) {
    problems.add(r.number, type_field.column,
                 fmt::format("type: {} is above the header's {} (expected 1..{})", *type,
                             count_of(types, "atom type"), types));
    ok = false;
  }
  for (int c = 0; c < 3; ++c) {
    const auto x = parse_real(f[static_cast<std::size_t>(s.x) + static_cast<std::size_t>(c)],
                              r.number, std::string(1, "xyz"[c]), problems);
    ok = ok && x;
    if (x) a.x[c] = *x;
  }
  for (std::size_t c = 0; c < 3 && f.size() == width + 3; ++c) {
    const auto n = parse_image(f[width + c], r.number, static_cast<int>(c), problems);
    ok = ok && n;
    a.image[c] = n.value_or(0);
  }
  if (s.diameter >= 0) ok = read_sphere(f, r.number, s, a, problems) && ok;
  if (!ok) return;
  a.id = *id;
  a.type = *type;
  d.atoms.add(a, r.number);
}

const AtomStyle* find_style(std::string_view name) {
  for (const auto& s : kStyles) {
    if (name == s.name) return &s;
  }
  return nullptr;
}

// The style is the input script's atom_style when the scene gives it (as
// LAMMPS's read_data takes it), else the first word after the title's '#'
// (write_data writes it); a title without either is read as atomic,
// read_data's default. A title naming a style whose columns differ from
// the given one is refused: one of the two is wrong, and reading the rows
// either way could give wrong positions.
void read_atoms(const Line& title, const std::vector<const Line*>& rows, std::string_view given,
                DataFile& d, Problems& problems) {
  d.have_atoms = true;
  std::string_view name = "atomic";
  std::size_t column = 1;
  bool commented = false;
  if (const auto hash = title.raw.find('#'); hash != std::string_view::npos) {
    const std::string_view comment = text_file::trim(title.raw.substr(hash + 1));
    name = comment.substr(0, comment.find_first_of(" \t"));
    column = static_cast<std::size_t>(comment.data() - title.raw.data()) + 1;
    commented = true;
  }
  if (!given.empty()) {
    d.style = find_style(given);
    const AtomStyle* said = commented ? find_style(name) : nullptr;
    if (said != nullptr && (said->width != d.style->width || said->type != d.style->type ||
                            said->x != d.style->x || said->diameter != d.style->diameter)) {
      problems.add(title.number, column,
                   fmt::format("the title says atom style {} but the scene's atom_style is {}, "
                               "whose columns differ (expected the style the file was written in)",
                               name, given));
      return;
    }
  } else {
    d.style = find_style(name);
  }
  if (!d.style) {
    problems.add(title.number, column,
                 fmt::format("atom style {} is not one pdyn reads (expected one of {}, or the "
                             "scene's atom_style: beside file)",
                             quoted(name), kStyleNames));
    return;
  }
  for (const Line* r : rows) read_atom_row(*r, d, problems);
}

// A section's rows: the `count` lines after its title that are not blank.
// Fewer, or more before the next title, is a count mismatch at the title.
std::vector<const Line*> section_rows(const std::vector<Line>& lines, std::size_t& k,
                                      const Section& s, const DataFile& d, Problems& problems) {
  const Line& title = lines[k++];
  const long long count = s.count ? d.count(s.count) : -1;
  // (A missing "N atoms" is reported once, by read_header.)
  if (s.count && count < 0 && s.count != std::string_view("atoms")) {
    problems.add(title.number, 1,
                 fmt::format("the header has no 'N {}' line (expected one before the {} section)",
                             s.count, s.title));
  }
  std::vector<const Line*> rows;
  for (; k < lines.size() && !is_title(lines[k]); ++k) {
    if (!lines[k].fields.empty()) rows.push_back(&lines[k]);
  }
  if (count >= 0 && static_cast<long long>(rows.size()) != count) {
    const std::string key = s.count;
    const std::string says = key == "atom type pairs"
                                 ? fmt::format("the header's {} make {} pairs",
                                               count_of(d.count("atom types"), "atom type"), count)
                                 : fmt::format("the header says {} {}", count, key);
    problems.add(title.number, 1,
                 fmt::format("the {} section has {} but {} (expected a row per {})", s.title,
                             count_of(static_cast<long long>(rows.size()), "row"), says,
                             key.substr(0, key.size() - 1)));
  }
  return rows;
}

// The topology sections: their title, the particles per term and the
// header count of their types.
struct TopologySection {
  const char* title;
  int arity;
  const char* count;  // the header's count of rows
  const char* types;  // the header's count of types
};
constexpr TopologySection kTopology[] = {{"Bonds", 2, "bonds", "bond types"},
                                         {"Angles", 3, "angles", "angle types"},
                                         {"Dihedrals", 4, "dihedrals", "dihedral types"},
                                         {"Impropers", 4, "impropers", "improper types"}};

// A Bonds, Angles, Dihedrals or Impropers section: rows "id type atom1 ...
// atomN", the type within the header's count (read_data's "Bonds section").
void read_terms(const TopologySection& sec, const Line& title, const std::vector<const Line*>& rows,
                DataFile& d, Problems& problems) {
  DataFile::TermRows t;
  t.terms.section = sec.title;
  t.terms.arity = sec.arity;
  const long long types = std::max(0LL, d.count(sec.types));          // the header's count
  const std::string singular(sec.types, std::strlen(sec.types) - 1);  // "bond type"
  if (d.count(sec.count) < 0) return;  // section_rows said so: one problem is enough
  if (types == 0 && !rows.empty()) {
    problems.add(title.number, 1,
                 fmt::format("the header has no 'N {}' line (expected one before the {} section)",
                             sec.types, sec.title));
    return;
  }
  for (const Line* r : rows) {
    const auto& f = r->fields;
    if (f.size() != 2 + static_cast<std::size_t>(sec.arity)) {
      problems.add(r->number, 1,
                   fmt::format("the row has {} (expected {} in {}: id, type and {} atom ids)",
                               count_of(static_cast<long long>(f.size()), "field"), 2 + sec.arity,
                               sec.title, sec.arity));
      continue;
    }
    const auto type = parse_whole(f[1], r->number, singular, problems, 1);
    if (type && *type > types) {
      problems.add(r->number, f[1].column,
                   fmt::format("{} {} is above the header's {} (expected 1..{})", singular, *type,
                               count_of(types, singular), types));
    }
    std::array<long long, 4> ids{};
    std::array<std::size_t, 4> columns{};
    bool ok = type && *type <= types;
    for (int a = 0; a < sec.arity; ++a) {
      const auto id = parse_whole(f[2 + a], r->number, "atom id", problems, 1);
      ok = ok && id;
      ids[a] = id.value_or(0);
      columns[a] = f[2 + a].column;
    }
    if (!ok) continue;
    t.terms.type.push_back(*type);
    t.terms.lines.push_back(r->number);
    t.ids.push_back(ids);
    t.columns.push_back(columns);
  }
  d.topology.push_back(std::move(t));
}

// The topology's atom ids as particle indices (the atoms in id order): an
// id that Atoms does not have, or one named twice by a term, is refused
// where it is written.
void index_topology(DataFile& d, Imported& out, Problems& problems) {
  std::vector<long long> ids;
  ids.reserve(d.atoms.atoms.size());
  for (const Atom& a : d.atoms.atoms) ids.push_back(a.id);
  std::sort(ids.begin(), ids.end());
  for (auto& t : d.topology) {
    Imported::Terms& terms = t.terms;
    terms.particles.resize(t.ids.size());
    for (std::size_t s = 0; s < t.ids.size(); ++s) {
      for (int a = 0; a < terms.arity; ++a) {
        const long long id = t.ids[s][a];
        const auto at = std::lower_bound(ids.begin(), ids.end(), id);
        if (at == ids.end() || *at != id) {
          problems.add(terms.lines[s], t.columns[s][a],
                       fmt::format("{} names atom {}, which Atoms does not have (expected the ids "
                                   "of Atoms)",
                                   terms.section, id));
        }
        for (int b = 0; b < a; ++b) {
          if (t.ids[s][b] == id) {
            problems.add(terms.lines[s], t.columns[s][a],
                         fmt::format("{} names atom {} twice in one term (expected {} distinct "
                                     "atoms)",
                                     terms.section, id, terms.arity));
          }
        }
        terms.particles[s][a] = static_cast<std::size_t>(at - ids.begin());
      }
    }
    out.topology.push_back(std::move(terms));
  }
}

// Masses and velocities onto the atoms, once every section is read.
void complete(DataFile& d, Imported& out, Problems& problems) {
  const bool sphere = d.style && d.style->diameter >= 0;
  for (std::size_t i = 0; i < d.atoms.atoms.size() && !sphere && d.have_masses; ++i) {
    Atom& a = d.atoms.atoms[i];
    if (const auto m = d.type_mass.find(a.type); m != d.type_mass.end()) {
      a.mass = m->second;
    } else if (!d.bad_masses) {
      problems.add(d.atoms.lines[i], 1,
                   fmt::format("atom {} has type {}, which the Masses section does not give "
                               "(expected a mass for every type)",
                               a.id, a.type));
    }
  }
  out.has_mass = sphere || d.have_masses;
  for (Atom& a : d.atoms.atoms) {
    if (const auto v = d.velocity.find(a.id); v != d.velocity.end()) {
      a.v = v->second.first;
      d.velocity.erase(v);
    }
  }
  for (const auto& [id, v] : d.velocity) {
    problems.add(v.second, 1,
                 fmt::format("Velocities gives atom {}, which Atoms does not have (expected the "
                             "ids of Atoms)",
                             id));
  }
}

}  // namespace

ReadResult read_lammps_data(const std::string& text, std::string_view atom_style,
                            Problems& problems) {
  const auto lines = text_file::split_lines(text, true);
  DataFile d;
  std::size_t k = read_header(lines, d, problems);
  while (k < lines.size()) {
    const Line& title = lines[k];
    const std::string name = words(title);
    const auto s = std::find_if(std::begin(kSections), std::end(kSections),
                                [&](const Section& x) { return name == x.title; });
    if (s == std::end(kSections)) {
      problems.add(title.number, 1,
                   fmt::format("unknown section '{}' (expected a section of LAMMPS's read_data: "
                               "Atoms, Velocities, Masses, Bonds, Pair Coeffs, ...)",
                               name));
      return {std::nullopt, 1, false};
    }
    const auto rows = section_rows(lines, k, *s, d, problems);
    if (!rows.empty() &&
        std::find(std::begin(kUnread), std::end(kUnread), name) != std::end(kUnread)) {
      d.unread.push_back({name, static_cast<long long>(rows.size()), title.number});
    }
    if (name == "Atoms") read_atoms(title, rows, atom_style, d, problems);
    if (name == "Masses") read_masses(rows, d, problems);
    if (name == "Velocities") read_velocities(rows, d, problems);
    for (const auto& sec : kTopology) {
      if (name == sec.title) read_terms(sec, title, rows, d, problems);
    }
  }
  if (!d.have_atoms && d.count("atoms") > 0) {
    problems.add(d.atoms_line, 1,
                 fmt::format("the header says {} but the file has no Atoms section (expected "
                             "one)",
                             count_of(d.count("atoms"), "atom")));
  }
  Imported out;
  out.unread = std::move(d.unread);
  complete(d, out, problems);
  index_topology(d, out, problems);
  // read_data's boundary is the input script's; its default is periodic.
  out.box = orthogonal_box(d.lo, d.hi, {true, true, true});
  lammps_kinds(d.atoms, std::max(0LL, d.count("atom types")), out);
  const bool images = std::any_of(d.atoms.atoms.begin(), d.atoms.atoms.end(), [](const Atom& a) {
    return a.image != std::array<std::int32_t, 3>{};
  });
  if (problems.any() || !to_rows(d.atoms, images, problems, out)) return {std::nullopt, 1, false};
  return {std::move(out), 1, false};
}

}  // namespace pdyn::import_files::detail

namespace pdyn::import_files {

std::string atom_style_names() { return detail::kStyleNames; }

bool is_atom_style(std::string_view name) { return detail::find_style(name) != nullptr; }

}  // namespace pdyn::import_files
