// Readers of LAMMPS data files, LAMMPS text dumps and extended XYZ (see
// import_files.hpp). Formats as LAMMPS's read_data, dump and ASE's extxyz
// documentation describe them; only what a particle system needs is read
// (ids, types, positions, velocities, masses, radii, the box), other
// sections are skipped by their headers.
#include "import_files.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <numeric>

#include "pdyn/text.hpp"
#include "text_file.hpp"

namespace pdyn::import_files {

namespace {

using text_file::Field;
using text_file::parse_real;
using text_file::Problems;
using text_file::quoted;

struct Line {
  std::size_t number = 0;     // 1-based
  std::string_view raw;       // the whole line
  std::vector<Field> fields;  // whitespace-separated, before any '#'
};

// The file's lines, each split at blanks; a '#' starts a comment when
// `comments`.
std::vector<Line> lines_of(const std::string& text, bool comments) {
  std::vector<Line> out;
  std::size_t pos = 0, number = 0;
  while (pos <= text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    Line l{++number, std::string_view(text.data() + pos, end - pos), {}};
    std::string_view body = l.raw;
    if (comments) body = body.substr(0, body.find('#'));
    for (std::size_t k = 0; k < body.size();) {
      while (k < body.size() && std::isspace(static_cast<unsigned char>(body[k]))) ++k;
      const std::size_t start = k;
      while (k < body.size() && !std::isspace(static_cast<unsigned char>(body[k]))) ++k;
      if (k > start) l.fields.push_back({body.substr(start, k - start), start + 1});
    }
    out.push_back(std::move(l));
    pos = end + 1;
  }
  return out;
}

std::optional<long long> parse_whole(const Field& f, std::size_t line, std::string_view name,
                                     Problems& problems, long long least) {
  long long n = 0;
  const auto [end, ec] = std::from_chars(f.text.data(), f.text.data() + f.text.size(), n);
  if (ec != std::errc() || end != f.text.data() + f.text.size() || n < least) {
    problems.add(line, f.column,
                 fmt::format("{}: {} is not a whole number >= {} (expected one)", name,
                             quoted(f.text), least));
    return std::nullopt;
  }
  return n;
}

// One particle as a reader collects it, before the sort by id.
struct Atom {
  long long id = 0;
  long long type = 1;  // LAMMPS's, 1-based
  Vec3 x = Vec3::Zero(), v = Vec3::Zero();
  double mass = 0.0, radius = -1.0;  // radius < 0: not given
};

// Sorts by id, refuses duplicates (at their lines), and fills `out`.
bool to_rows(std::vector<Atom>& atoms, const std::vector<std::size_t>& lines, Problems& problems,
             Imported& out) {
  std::vector<std::size_t> order(atoms.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return atoms[a].id < atoms[b].id; });
  for (std::size_t k = 1; k < order.size(); ++k) {
    if (atoms[order[k]].id == atoms[order[k - 1]].id) {
      problems.add(lines[order[k]], 1,
                   fmt::format("atom id {} appears twice (expected unique ids; first at line {})",
                               atoms[order[k]].id, lines[order[k - 1]]));
    }
  }
  if (problems.any()) return false;
  auto& r = out.rows;
  const bool radii =
      std::any_of(atoms.begin(), atoms.end(), [](const Atom& a) { return a.radius >= 0.0; });
  for (std::size_t k : order) {
    const Atom& a = atoms[k];
    r.x.push_back(a.x);
    r.v.push_back(a.v);
    r.mass.push_back(a.mass);
    r.fixed.push_back(0);
    r.type.push_back(static_cast<std::int32_t>(a.type - 1));
    if (radii) r.radius.push_back(std::max(a.radius, 0.0));
  }
  return true;
}

Domain orthogonal_box(const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                      const std::array<bool, 3>& periodic) {
  Domain d;
  d.min = Vec3(lo[0], lo[1], lo[2]);
  d.max = Vec3(hi[0], hi[1], hi[2]);
  d.periodic = periodic;
  return d;
}

// ---------------------------------------------------------------------------
// LAMMPS data files (read_data): a header of counts and box bounds, then
// sections, each a title line, a blank line and its rows.

// Columns of the Atoms section per atom style: where id, type, x and the
// style's extras are.
struct AtomStyle {
  const char* name;
  int width, type, x, mol, q, diameter, density;
};
constexpr AtomStyle kStyles[] = {
    {"atomic", 5, 1, 2, -1, -1, -1, -1}, {"charge", 6, 1, 3, -1, 2, -1, -1},
    {"sphere", 7, 1, 4, -1, -1, 2, 3},   {"bond", 6, 2, 3, 1, -1, -1, -1},
    {"angle", 6, 2, 3, 1, -1, -1, -1},   {"molecular", 6, 2, 3, 1, -1, -1, -1},
    {"full", 7, 2, 4, 1, 3, -1, -1},
};
constexpr const char* kStyleNames = "atomic, charge, sphere, bond, angle, molecular, full";

bool is_section_title(const Line& l) {
  static const char* const kTitles[] = {
      "Atoms",        "Velocities",      "Masses",          "Bonds",           "Angles",
      "Dihedrals",    "Impropers",       "Pair Coeffs",     "PairIJ Coeffs",   "Bond Coeffs",
      "Angle Coeffs", "Dihedral Coeffs", "Improper Coeffs", "BondBond Coeffs", "BondAngle Coeffs",
      "Ellipsoids",   "Lines",           "Triangles",       "Bodies"};
  if (l.fields.empty()) return false;
  const std::string_view first = l.fields[0].text;
  for (const char* t : kTitles) {
    const std::string_view title(t);
    const std::string_view head = title.substr(0, title.find(' '));
    if (first == head &&
        (head.size() == title.size() ||
         (l.fields.size() > 1 && l.fields[1].text == title.substr(head.size() + 1))))
      return true;
  }
  return false;
}

std::optional<Imported> read_lammps_data(const std::string& text, Problems& problems) {
  const auto lines = lines_of(text, true);
  Imported out;
  long long n_atoms = -1;
  std::array<double, 3> lo{}, hi{};
  std::array<bool, 3> have_axis{};
  std::size_t k = 1;  // line 1 is LAMMPS's title
  for (; k < lines.size() && !is_section_title(lines[k]); ++k) {
    const Line& l = lines[k];
    const auto& f = l.fields;
    if (f.size() == 2 && f[1].text == "atoms") {
      if (auto n = parse_whole(f[0], l.number, "atoms", problems, 0)) n_atoms = *n;
    } else if (f.size() == 4 && f[2].text.size() == 3 && f[3].text.size() == 3 &&
               f[2].text.substr(1) == "lo" && f[3].text.substr(1) == "hi") {
      const int axis = f[2].text[0] - 'x';
      if (axis < 0 || axis > 2) continue;
      const auto a = parse_real(f[0], l.number, f[2].text, problems);
      const auto b = parse_real(f[1], l.number, f[3].text, problems);
      if (!a || !b) continue;
      if (!(*a < *b)) {
        problems.add(l.number, f[1].column,
                     fmt::format("{} {} is not above {} {} (expected hi > lo)", f[3].text, *b,
                                 f[2].text, *a));
      }
      lo[axis] = *a;
      hi[axis] = *b;
      have_axis[axis] = true;
    } else if (f.size() == 6 && f[3].text == "xy") {
      problems.add(l.number, f[3].column,
                   "the box is triclinic (xy xz yz tilt factors) (expected an orthogonal box: "
                   "pdyn's simulation box has no tilt)");
    }
  }
  if (n_atoms < 0) {
    problems.add(2, 1, "the header has no 'N atoms' line (expected a LAMMPS data file)");
  }
  if (have_axis[0] && have_axis[1] && have_axis[2]) {
    out.box = orthogonal_box(lo, hi, {true, true, true});
  }
  std::map<long long, double> type_mass;
  std::map<long long, Vec3> velocity;
  std::map<long long, std::size_t> velocity_line;
  std::vector<Atom> atoms;
  std::vector<std::size_t> atom_lines;
  bool have_atoms = false;
  while (k < lines.size()) {
    const Line& title = lines[k++];
    std::vector<const Line*> rows;
    for (; k < lines.size() && !is_section_title(lines[k]); ++k) {
      if (!lines[k].fields.empty()) rows.push_back(&lines[k]);
    }
    const std::string_view name = title.fields[0].text;
    if (name == "Masses") {
      for (const Line* r : rows) {
        if (r->fields.size() < 2) {
          problems.add(r->number, 1, "a Masses row has fewer than 2 fields (expected: type mass)");
          continue;
        }
        const auto t = parse_whole(r->fields[0], r->number, "type", problems, 1);
        const auto m = parse_real(r->fields[1], r->number, "mass", problems);
        if (m && !(*m > 0.0)) {
          problems.add(r->number, r->fields[1].column,
                       fmt::format("mass: {} is not positive (expected a mass > 0 kg)", *m));
        } else if (t && m) {
          type_mass[*t] = *m;
        }
      }
    } else if (name == "Velocities") {
      for (const Line* r : rows) {
        if (r->fields.size() < 4) {
          problems.add(r->number, 1,
                       "a Velocities row has fewer than 4 fields (expected: id vx vy vz)");
          continue;
        }
        const auto id = parse_whole(r->fields[0], r->number, "id", problems, 1);
        Vec3 v;
        bool ok = id.has_value();
        for (int c = 0; c < 3; ++c) {
          const auto x =
              parse_real(r->fields[1 + c], r->number, std::string("v") + "xyz"[c], problems);
          ok = ok && x;
          if (x) v[c] = *x;
        }
        if (ok) {
          velocity[*id] = v;
          velocity_line[*id] = r->number;
        }
      }
    } else if (name == "Atoms") {
      have_atoms = true;
      const std::string_view comment =
          title.raw.find('#') == std::string_view::npos
              ? std::string_view("atomic")
              : text_file::trim(title.raw.substr(title.raw.find('#') + 1));
      const AtomStyle* style = nullptr;
      for (const auto& s : kStyles) {
        if (comment == s.name) style = &s;
      }
      if (!style) {
        // At the style's word, after the '#'.
        problems.add(title.number, static_cast<std::size_t>(comment.data() - title.raw.data()) + 1,
                     fmt::format("atom style {} is not one pdyn reads (expected one of {})",
                                 quoted(comment), kStyleNames));
        continue;
      }
      for (const Line* r : rows) {
        const auto& f = r->fields;
        // Image flags may follow (3 more fields).
        if (f.size() != static_cast<std::size_t>(style->width) &&
            f.size() != static_cast<std::size_t>(style->width + 3)) {
          problems.add(r->number, 1,
                       fmt::format("an Atoms row of style {} has {} (expected {} or {} with image "
                                   "flags)",
                                   style->name, count_of(static_cast<long long>(f.size()), "field"),
                                   style->width, style->width + 3));
          continue;
        }
        Atom a;
        const auto id = parse_whole(f[0], r->number, "id", problems, 1);
        const auto type = parse_whole(f[style->type], r->number, "type", problems, 1);
        bool ok = id && type;
        for (int c = 0; c < 3; ++c) {
          const auto x = parse_real(f[style->x + c], r->number, std::string(1, "xyz"[c]), problems);
          ok = ok && x;
          if (x) a.x[c] = *x;
        }
        if (style->diameter >= 0) {
          const auto d = parse_real(f[style->diameter], r->number, "diameter", problems);
          const auto rho = parse_real(f[style->density], r->number, "density", problems);
          ok = ok && d && rho;
          if (d && rho) {
            if (*d < 0.0 || !(*rho > 0.0)) {
              problems.add(r->number, f[style->diameter].column,
                           "diameter < 0 or density <= 0 (expected a diameter >= 0 and a "
                           "density > 0)");
              ok = false;
            }
            // LAMMPS: a finite diameter makes density a mass per volume; a
            // point particle (diameter 0) has density = its mass.
            a.radius = *d / 2.0;
            a.mass = *d > 0.0 ? *rho * std::numbers::pi / 6.0 * *d * *d * *d : *rho;
          }
        }
        if (!ok) continue;
        a.id = *id;
        a.type = *type;
        atoms.push_back(a);
        atom_lines.push_back(r->number);
      }
      if (n_atoms >= 0 && static_cast<long long>(rows.size()) != n_atoms) {
        problems.add(title.number, 1,
                     fmt::format("the Atoms section has {} but the header says {} atoms (expected "
                                 "as many rows as atoms)",
                                 count_of(static_cast<long long>(rows.size()), "row"), n_atoms));
      }
    }
  }
  if (!have_atoms) {
    problems.add(lines.size(), 1, "the file has no Atoms section (expected one)");
  }
  const bool per_atom_mass = !atoms.empty() && atoms[0].radius >= 0.0;
  for (std::size_t i = 0; i < atoms.size() && !per_atom_mass; ++i) {
    const auto m = type_mass.find(atoms[i].type);
    if (m != type_mass.end()) {
      atoms[i].mass = m->second;
    } else if (!type_mass.empty()) {
      problems.add(atom_lines[i], 1,
                   fmt::format("atom {} has type {}, which the Masses section does not give "
                               "(expected a mass for every type)",
                               atoms[i].id, atoms[i].type));
    }
  }
  out.has_mass = per_atom_mass || !type_mass.empty();
  for (auto& a : atoms) {
    if (const auto v = velocity.find(a.id); v != velocity.end()) {
      a.v = v->second;
      velocity.erase(v);
    }
  }
  for (const auto& [id, v] : velocity) {
    problems.add(velocity_line[id], 1,
                 fmt::format("Velocities gives atom {}, which Atoms does not have (expected the "
                             "ids of Atoms)",
                             id));
  }
  if (problems.any() || !to_rows(atoms, atom_lines, problems, out)) return std::nullopt;
  return out;
}

// ---------------------------------------------------------------------------
// LAMMPS text dumps: frames of "ITEM: TIMESTEP", "ITEM: NUMBER OF ATOMS",
// "ITEM: BOX BOUNDS xx yy zz" (pp: periodic; f, s, m: not) and
// "ITEM: ATOMS <column names>" followed by one row per atom, in any order.

std::optional<Imported> read_lammps_dump(const std::string& text, Problems& problems) {
  const auto lines = lines_of(text, false);
  // The last frame: its "ITEM: TIMESTEP" line.
  std::size_t start = lines.size();
  for (std::size_t k = 0; k < lines.size(); ++k) {
    if (lines[k].raw.starts_with("ITEM: TIMESTEP")) start = k;
  }
  if (start == lines.size()) {
    problems.add(1, 1, "no 'ITEM: TIMESTEP' line (expected a LAMMPS text dump)");
    return std::nullopt;
  }
  Imported out;
  long long n = -1;
  std::array<double, 3> lo{}, hi{};
  std::array<bool, 3> periodic{};
  bool have_box = false;
  for (std::size_t k = start; k < lines.size(); ++k) {
    const Line& l = lines[k];
    if (l.raw.starts_with("ITEM: NUMBER OF ATOMS") && k + 1 < lines.size() &&
        !lines[k + 1].fields.empty()) {
      n = parse_whole(lines[k + 1].fields[0], lines[k + 1].number, "number of atoms", problems, 0)
              .value_or(-1);
    } else if (l.raw.starts_with("ITEM: BOX BOUNDS")) {
      if (l.fields.size() != 6 || k + 3 >= lines.size()) {
        problems.add(l.number, 1,
                     "the box is not orthogonal or its bounds are missing (expected ITEM: BOX "
                     "BOUNDS xx yy zz and three lines 'lo hi')");
        return std::nullopt;
      }
      for (int c = 0; c < 3; ++c) {
        periodic[c] = l.fields[3 + c].text == "pp";
        const Line& b = lines[k + 1 + c];
        if (b.fields.size() != 2) {
          problems.add(b.number, 1, "a box line has not 2 fields (expected: lo hi)");
          continue;
        }
        const auto a = parse_real(b.fields[0], b.number, "lo", problems);
        const auto z = parse_real(b.fields[1], b.number, "hi", problems);
        if (a && z) {
          lo[c] = *a;
          hi[c] = *z;
        }
      }
      have_box = true;
    } else if (l.raw.starts_with("ITEM: ATOMS")) {
      std::map<std::string_view, std::size_t> col;
      for (std::size_t c = 2; c < l.fields.size(); ++c) col[l.fields[c].text] = c - 2;
      auto at = [&](std::initializer_list<std::string_view> names) -> std::pair<int, int> {
        int which = 0;
        for (auto name : names) {
          if (const auto it = col.find(name); it != col.end())
            return {static_cast<int>(it->second), which};
          ++which;
        }
        return {-1, -1};
      };
      const auto id = at({"id"});
      const auto type = at({"type"});
      const auto mass = at({"mass"});
      const auto radius = at({"radius", "diameter"});
      std::array<std::pair<int, int>, 3> x, v;
      for (int c = 0; c < 3; ++c) {
        const std::string a(1, "xyz"[c]);
        x[c] = at({a, a + "u", a + "s"});  // wrapped, unwrapped, scaled
        v[c] = at({"v" + a});
      }
      if (id.first < 0 || x[0].first < 0 || x[1].first < 0 || x[2].first < 0) {
        problems.add(l.number, 1,
                     "the ATOMS columns lack id or a position (expected id and x y z, xu yu zu or "
                     "xs ys zs)");
        return std::nullopt;
      }
      std::vector<Atom> atoms;
      std::vector<std::size_t> atom_lines;
      const std::size_t width = l.fields.size() - 2;
      for (std::size_t r = k + 1; r < lines.size() && !lines[r].raw.starts_with("ITEM:"); ++r) {
        const Line& row = lines[r];
        if (row.fields.empty()) continue;
        if (row.fields.size() != width) {
          problems.add(
              row.number, 1,
              fmt::format("has {}, ITEM: ATOMS names {} (expected one per column)",
                          count_of(static_cast<long long>(row.fields.size()), "field"), width));
          continue;
        }
        auto real = [&](int c, std::string_view name) {
          return parse_real(row.fields[static_cast<std::size_t>(c)], row.number, name, problems);
        };
        Atom a;
        const auto i = parse_whole(row.fields[static_cast<std::size_t>(id.first)], row.number, "id",
                                   problems, 1);
        bool ok = i.has_value();
        if (type.first >= 0) {
          const auto t = parse_whole(row.fields[static_cast<std::size_t>(type.first)], row.number,
                                     "type", problems, 1);
          ok = ok && t;
          a.type = t.value_or(1);
        }
        for (int c = 0; c < 3; ++c) {
          const auto p = real(x[c].first, l.fields[2 + static_cast<std::size_t>(x[c].first)].text);
          ok = ok && p;
          if (!p) continue;
          // Scaled coordinates are fractions of the box.
          a.x[c] = x[c].second == 2 ? lo[c] + *p * (hi[c] - lo[c]) : *p;
          if (v[c].first >= 0) {
            const auto s = real(v[c].first, "velocity");
            ok = ok && s;
            a.v[c] = s.value_or(0.0);
          }
        }
        if (mass.first >= 0) {
          const auto m = real(mass.first, "mass");
          if (m && !(*m > 0.0)) {
            problems.add(row.number, row.fields[static_cast<std::size_t>(mass.first)].column,
                         fmt::format("mass: {} is not positive (expected a mass > 0 kg)", *m));
          }
          ok = ok && m && *m > 0.0;
          a.mass = m.value_or(0.0);
        }
        if (radius.first >= 0) {
          const auto s = real(radius.first, radius.second ? "diameter" : "radius");
          ok = ok && s && *s >= 0.0;
          a.radius = s.value_or(0.0) / (radius.second ? 2.0 : 1.0);
        }
        if (!ok) continue;
        a.id = *i;
        atoms.push_back(a);
        atom_lines.push_back(row.number);
      }
      if (n >= 0 && static_cast<long long>(atoms.size()) != n && !problems.any()) {
        problems.add(l.number, 1,
                     fmt::format("the frame has {} but NUMBER OF ATOMS says {} (expected as many "
                                 "rows as atoms)",
                                 count_of(static_cast<long long>(atoms.size()), "atom row"), n));
      }
      if (have_box) out.box = orthogonal_box(lo, hi, periodic);
      out.has_mass = mass.first >= 0;
      if (problems.any() || !to_rows(atoms, atom_lines, problems, out)) return std::nullopt;
      return out;
    }
  }
  problems.add(lines[start].number, 1, "the last frame has no ITEM: ATOMS (expected one)");
  return std::nullopt;
}

// ---------------------------------------------------------------------------
// Extended XYZ: per frame, a count line, a comment line of key=value pairs
// (Lattice="ax ay az bx by bz cx cy cz", Properties=name:type:count:...,
// pbc="T T T"), then one row per atom in the order Properties gives.

// key=value pairs of an extended XYZ comment line (values may be quoted).
std::map<std::string, std::pair<std::string, std::size_t>> key_values(std::string_view s) {
  std::map<std::string, std::pair<std::string, std::size_t>> out;
  std::size_t k = 0;
  while (k < s.size()) {
    while (k < s.size() && std::isspace(static_cast<unsigned char>(s[k]))) ++k;
    const std::size_t key_start = k;
    while (k < s.size() && s[k] != '=' && !std::isspace(static_cast<unsigned char>(s[k]))) ++k;
    std::string key(s.substr(key_start, k - key_start));
    std::string value;
    if (k < s.size() && s[k] == '=') {
      ++k;
      if (k < s.size() && s[k] == '"') {
        const std::size_t close = s.find('"', k + 1);
        value =
            std::string(s.substr(k + 1, close == std::string_view::npos ? s.npos : close - k - 1));
        k = close == std::string_view::npos ? s.size() : close + 1;
      } else {
        const std::size_t v = k;
        while (k < s.size() && !std::isspace(static_cast<unsigned char>(s[k]))) ++k;
        value = std::string(s.substr(v, k - v));
      }
    }
    std::transform(key.begin(), key.end(), key.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    if (!key.empty()) out[key] = {value, key_start + 1};
  }
  return out;
}

std::optional<Imported> read_extxyz(const std::string& text, Problems& problems) {
  const auto lines = lines_of(text, false);
  // Frames back to back: find the last one's count line.
  std::size_t at = 0, last = std::string::npos;
  while (at < lines.size() && lines[at].fields.size() == 1) {
    long long n = 0;
    const auto& f = lines[at].fields[0].text;
    const auto [end, ec] = std::from_chars(f.data(), f.data() + f.size(), n);
    if (ec != std::errc() || end != f.data() + f.size() || n < 0) break;
    last = at;
    at += 2 + static_cast<std::size_t>(n);
  }
  if (last == std::string::npos) {
    problems.add(1, 1, "the first line is not an atom count (expected an extended XYZ file)");
    return std::nullopt;
  }
  const long long n = std::stoll(std::string(lines[last].fields[0].text));
  if (last + 1 >= lines.size()) {
    problems.add(lines[last].number, 1, "the comment line is missing (expected key=value pairs)");
    return std::nullopt;
  }
  const Line& comment = lines[last + 1];
  const auto kv = key_values(comment.raw);
  Imported out;
  // Properties: name:S|R|I|L:count, ...; default species:S:1:pos:R:3.
  std::string props = "species:S:1:pos:R:3";
  if (const auto p = kv.find("properties"); p != kv.end()) props = p->second.first;
  std::vector<std::tuple<std::string, char, int>> columns;
  for (std::size_t k = 0; k < props.size();) {
    std::array<std::string, 3> part;
    for (auto& s : part) {
      const std::size_t colon = props.find(':', k);
      s = props.substr(k, colon == std::string::npos ? std::string::npos : colon - k);
      k = colon == std::string::npos ? props.size() : colon + 1;
    }
    const int count = std::atoi(part[2].c_str());
    if (part[1].size() != 1 || count < 1) {
      problems.add(comment.number, kv.at("properties").second,
                   fmt::format("Properties is malformed near '{}' (expected name:S|R|I|L:count, "
                               "...)",
                               part[0]));
      return std::nullopt;
    }
    columns.emplace_back(part[0], part[1][0], count);
  }
  int pos = -1, velo = -1, mass = -1, species = -1, radius = -1, width = 0;
  for (const auto& [name, type, count] : columns) {
    if (name == "pos" && count == 3) pos = width;
    if ((name == "velo" || name == "vel" || name == "velocities") && count == 3) velo = width;
    if ((name == "mass" || name == "masses") && count == 1) mass = width;
    if ((name == "species" || name == "element") && count == 1) species = width;
    if ((name == "radius" || name == "radii") && count == 1) radius = width;
    width += count;
  }
  if (pos < 0) {
    problems.add(comment.number, 1, "Properties has no pos:R:3 (expected positions)");
    return std::nullopt;
  }
  if (const auto l = kv.find("lattice"); l != kv.end()) {
    std::array<double, 9> m{};
    int got = 0;
    std::string_view rest(l->second.first);
    for (int c = 0; c < 9; ++c) {
      while (!rest.empty() && rest.front() == ' ') rest.remove_prefix(1);
      const auto [end, ec] = std::from_chars(rest.data(), rest.data() + rest.size(), m[c]);
      if (ec != std::errc()) break;
      rest.remove_prefix(static_cast<std::size_t>(end - rest.data()));
      ++got;
    }
    if (got != 9 || m[1] != 0 || m[2] != 0 || m[3] != 0 || m[5] != 0 || m[6] != 0 || m[7] != 0) {
      problems.add(comment.number, l->second.second,
                   "Lattice is not 9 numbers of an orthogonal box (expected \"Lx 0 0 0 Ly 0 0 0 "
                   "Lz\": pdyn's simulation box has no tilt)");
      return std::nullopt;
    }
    std::array<bool, 3> periodic{true, true, true};
    if (const auto p = kv.find("pbc"); p != kv.end()) {
      std::string_view s(p->second.first);
      for (int c = 0; c < 3; ++c) {
        while (!s.empty() && s.front() == ' ') s.remove_prefix(1);
        periodic[c] = !s.empty() && (s.front() == 'T' || s.front() == 't');
        if (!s.empty()) s.remove_prefix(std::min(s.size(), s.find(' ')));
      }
    }
    out.box = orthogonal_box({0.0, 0.0, 0.0}, {m[0], m[4], m[8]}, periodic);
  }
  std::map<std::string, long long, std::less<>> types;
  std::vector<Atom> atoms;
  std::vector<std::size_t> atom_lines;
  for (long long i = 0; i < n; ++i) {
    const std::size_t k = last + 2 + static_cast<std::size_t>(i);
    if (k >= lines.size()) {
      problems.add(
          lines.back().number, 1,
          fmt::format("the file ends after {} of {} atoms (expected one row per atom)", i, n));
      break;
    }
    const Line& row = lines[k];
    if (row.fields.size() != static_cast<std::size_t>(width)) {
      problems.add(
          row.number, 1,
          fmt::format("has {}, Properties gives {} (expected one per column)",
                      count_of(static_cast<long long>(row.fields.size()), "field"), width));
      continue;
    }
    Atom a;
    a.id = i + 1;
    bool ok = true;
    for (int c = 0; c < 3; ++c) {
      const auto x = parse_real(row.fields[static_cast<std::size_t>(pos + c)], row.number,
                                std::string(1, "xyz"[c]), problems);
      ok = ok && x;
      a.x[c] = x.value_or(0.0);
      if (velo >= 0) {
        const auto s = parse_real(row.fields[static_cast<std::size_t>(velo + c)], row.number,
                                  "velocity", problems);
        ok = ok && s;
        a.v[c] = s.value_or(0.0);
      }
    }
    if (mass >= 0) {
      const auto m =
          parse_real(row.fields[static_cast<std::size_t>(mass)], row.number, "mass", problems);
      if (m && !(*m > 0.0)) {
        problems.add(row.number, row.fields[static_cast<std::size_t>(mass)].column,
                     fmt::format("mass: {} is not positive (expected a mass > 0 kg)", *m));
      }
      ok = ok && m && *m > 0.0;
      a.mass = m.value_or(0.0);
    }
    if (radius >= 0) {
      const auto r =
          parse_real(row.fields[static_cast<std::size_t>(radius)], row.number, "radius", problems);
      ok = ok && r && *r >= 0.0;
      a.radius = r.value_or(0.0);
    }
    if (species >= 0) {
      const auto s = row.fields[static_cast<std::size_t>(species)].text;
      const auto it = types.find(s);
      a.type = it != types.end() ? it->second
                                 : types.emplace(std::string(s), types.size() + 1).first->second;
    }
    if (!ok) continue;
    atoms.push_back(a);
    atom_lines.push_back(row.number);
  }
  out.has_mass = mass >= 0;
  if (problems.any() || !to_rows(atoms, atom_lines, problems, out)) return std::nullopt;
  return out;
}

}  // namespace

std::string format_names() {
  return fmt::format("{}", fmt::join(side_files::kParticleFileFormats, ", "));
}

std::optional<Format> parse_format(std::string_view name) {
  // In the order of side_files::kParticleFileFormats.
  constexpr Format kFormats[] = {Format::Csv, Format::LammpsData, Format::LammpsDump,
                                 Format::ExtXyz};
  for (std::size_t k = 0; k < std::size(kFormats); ++k) {
    if (name == side_files::kParticleFileFormats[k]) return kFormats[k];
  }
  return std::nullopt;
}

std::optional<Format> format_of_extension(const std::filesystem::path& file) {
  const std::string e = file.extension().string();
  if (e == ".csv") return Format::Csv;
  if (e == ".data" || e == ".lmp") return Format::LammpsData;
  if (e == ".dump" || e == ".lammpstrj") return Format::LammpsDump;
  if (e == ".xyz" || e == ".extxyz") return Format::ExtXyz;
  return std::nullopt;
}

std::optional<Imported> read(const std::filesystem::path& file, Format format,
                             const std::string& shown, std::vector<Diagnostic>& out) {
  if (format == Format::Csv) {
    auto rows = side_files::read_particles(file, shown, out);
    if (!rows) return std::nullopt;
    return Imported{std::move(*rows), true, std::nullopt};
  }
  Problems problems(shown, out);
  const auto text = text_file::slurp(file);
  if (!text) {
    problems.add_file("cannot read the particle file (expected a readable file)");
    return std::nullopt;
  }
  std::optional<Imported> got;
  switch (format) {
    case Format::LammpsData:
      got = read_lammps_data(*text, problems);
      break;
    case Format::LammpsDump:
      got = read_lammps_dump(*text, problems);
      break;
    default:
      got = read_extxyz(*text, problems);
      break;
  }
  problems.finish();
  return got;
}

}  // namespace pdyn::import_files
