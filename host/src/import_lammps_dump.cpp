// LAMMPS text dumps (dump atom and dump custom), as LAMMPS's dump
// documentation describes them: frames, each "ITEM: TIMESTEP", "ITEM:
// NUMBER OF ATOMS", "ITEM: BOX BOUNDS xx yy zz" (boundary flags: pp
// periodic; f, s, m not) with three "lo hi" lines, and "ITEM: ATOMS" naming
// the columns, followed by one row per atom in any order (each processor
// writes its own atoms). LAMMPS may put "ITEM: UNITS" and "ITEM: TIME"
// before a frame's TIMESTEP; they are passed over.
#include <fmt/format.h>

#include <algorithm>
#include <map>

#include "import_reader.hpp"
#include "pdyn/text.hpp"

namespace pdyn::import_files::detail {

namespace {

bool is_item(const Line& l, std::string_view item) {
  return l.raw.starts_with("ITEM: ") && l.raw.substr(6).starts_with(item);
}

struct Bounds {
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
  std::array<bool, 3> periodic{true, true, true};
};

// One boundary flag pair: LAMMPS's `boundary` per axis, lower then upper
// face: p (periodic, both faces or neither), f, s or m.
bool read_flag(const Field& f, std::size_t line, bool& periodic, Problems& problems) {
  const auto t = f.text;
  const bool ok = t == "pp" || (t.size() == 2 && t.find_first_not_of("fsm") == std::string::npos);
  if (!ok) {
    problems.add(line, f.column,
                 fmt::format("boundary flags {} are not LAMMPS's (expected pp, or two of f, s, "
                             "m: ff, fs, sm, ...)",
                             quoted(t)));
  }
  periodic = t == "pp";
  return ok;
}

// "ITEM: BOX BOUNDS pp pp pp" at lines[k], then its three "lo hi" lines.
// Old dumps without flags are read as periodic, LAMMPS's default boundary.
bool read_bounds(const std::vector<Line>& lines, std::size_t k, std::size_t end, Bounds& b,
                 Problems& problems) {
  const Line& l = lines[k];
  const auto& f = l.fields;
  if (f.size() > 3 && (f[3].text == "xy" || f[3].text == "abc")) {
    problems.add(l.number, f[3].column,
                 "the box is triclinic (tilt factors) (expected an orthogonal box: pdyn's "
                 "simulation box has no tilt)");
    return false;
  }
  if (f.size() != 3 && f.size() != 6) {
    problems.add(l.number, 1,
                 "ITEM: BOX BOUNDS has no three boundary flags (expected ITEM: BOX BOUNDS xx yy "
                 "zz, e.g. pp pp pp)");
    return false;
  }
  bool ok = true;
  for (std::size_t c = 0; c < 3 && f.size() == 6; ++c) {
    ok = read_flag(f[3 + c], l.number, b.periodic[c], problems) && ok;
  }
  for (int c = 0; c < 3; ++c) {
    const std::size_t at = k + 1 + static_cast<std::size_t>(c);
    if (at >= end || lines[at].fields.size() != 2) {
      problems.add(at < end ? lines[at].number : l.number, 1,
                   fmt::format("the box's {} bounds are not a line 'lo hi' (expected three such "
                               "lines after ITEM: BOX BOUNDS)",
                               "xyz"[c]));
      return false;
    }
    const Line& line = lines[at];
    const auto lo = parse_real(line.fields[0], line.number, "lo", problems);
    const auto hi = parse_real(line.fields[1], line.number, "hi", problems);
    if (lo && hi && !(*lo < *hi)) {
      problems.add(line.number, line.fields[1].column,
                   fmt::format("hi {} is not above lo {} (expected hi > lo)", line.fields[1].text,
                               line.fields[0].text));
    }
    ok = ok && lo && hi && *lo < *hi;
    b.lo[c] = lo.value_or(0.0);
    b.hi[c] = hi.value_or(0.0);
  }
  return ok;
}

// Where the columns pdyn reads are in a row (-1: absent). A position is
// wrapped (x), unwrapped (xu), scaled (xs) or scaled and unwrapped (xsu),
// the first of these the dump has.
struct Columns {
  int id = -1, type = -1;
  MoreColumns more;
  std::array<int, 3> x{-1, -1, -1}, image{-1, -1, -1};
  std::array<bool, 3> scaled{}, unwrapped{};
  std::size_t width = 0;
};

bool read_columns(const Line& l, Columns& c, Problems& problems) {
  std::map<std::string_view, int> at;
  for (std::size_t k = 2; k < l.fields.size(); ++k) {
    at.emplace(l.fields[k].text, static_cast<int>(k - 2));
  }
  c.width = l.fields.size() - 2;
  auto find = [&](std::string_view name) {
    const auto it = at.find(name);
    return it == at.end() ? -1 : it->second;
  };
  c.id = find("id");
  c.type = find("type");
  c.more.mass = find("mass");
  c.more.radius = find("radius");
  if (c.more.radius < 0 && (c.more.radius = find("diameter")) >= 0) c.more.diameter = true;
  for (int k = 0; k < 3; ++k) {
    const std::string a(1, "xyz"[k]);
    for (const auto& [suffix, scaled, unwrapped] : {std::tuple{"", false, false},
                                                    {"u", false, true},
                                                    {"s", true, false},
                                                    {"su", true, true}}) {
      if (c.x[k] >= 0) break;
      c.x[k] = find(a + suffix);
      c.scaled[k] = scaled;
      c.unwrapped[k] = unwrapped;
    }
    c.more.v[k] = find("v" + a);
    c.image[k] = find("i" + a);
  }
  if (c.id < 0 || c.x[0] < 0 || c.x[1] < 0 || c.x[2] < 0) {
    problems.add(l.number, 1,
                 "the ATOMS columns lack id or a position (expected id and x y z, xu yu zu, xs ys "
                 "zs or xsu ysu zsu)");
    return false;
  }
  return true;
}

void read_dump_row(const Line& row, const Columns& c, const Bounds& b, Atoms& atoms,
                   Problems& problems) {
  const auto& f = row.fields;
  if (f.size() != c.width) {
    problems.add(row.number, 1,
                 fmt::format("has {}, ITEM: ATOMS names {} (expected one per column)",
                             count_of(static_cast<long long>(f.size()), "field"), c.width));
    return;
  }
  auto field = [&](int k) -> const Field& { return f[static_cast<std::size_t>(k)]; };
  Atom a;
  const auto id = parse_whole(field(c.id), row.number, "id", problems, 1);
  bool ok = id.has_value();
  if (c.type >= 0) {
    const auto t = parse_whole(field(c.type), row.number, "type", problems, 1);
    ok = ok && t;
    a.type = t.value_or(1);
  }
  for (int k = 0; k < 3; ++k) {
    const auto p = parse_real(field(c.x[k]), row.number, std::string(1, "xyz"[k]), problems);
    // Scaled coordinates are fractions of the box (dump's xs = (x - lo) / L).
    a.x[k] = c.scaled[k] ? b.lo[k] + p.value_or(0.0) * (b.hi[k] - b.lo[k]) : p.value_or(0.0);
    ok = ok && p;
    if (c.image[k] >= 0) {
      const auto n = parse_image(field(c.image[k]), row.number, k, problems);
      ok = ok && n;
      a.image[k] = n.value_or(0);
    }
  }
  ok = read_more(f, row.number, c.more, a, problems) && ok;
  if (!ok) return;
  a.id = *id;
  atoms.add(a, row.number);
}

// The lines of the frame [begin, end), from its ITEM: TIMESTEP on.
std::optional<Imported> read_frame(const std::vector<Line>& lines, std::size_t begin,
                                   std::size_t end, Problems& problems) {
  long long n = -1;
  Bounds box;
  bool box_seen = false, box_ok = false;
  for (std::size_t k = begin; k < end; ++k) {
    const Line& l = lines[k];
    if (is_item(l, "NUMBER OF ATOMS")) {
      if (k + 1 < end && lines[k + 1].fields.size() == 1) {
        n = parse_whole(lines[k + 1].fields[0], lines[k + 1].number, "number of atoms", problems, 0)
                .value_or(-1);
      } else {
        problems.add(l.number, 1, "ITEM: NUMBER OF ATOMS has no count after it (expected one)");
      }
    } else if (is_item(l, "BOX BOUNDS")) {
      box_seen = true;
      box_ok = read_bounds(lines, k, end, box, problems);
    } else if (is_item(l, "ATOMS")) {
      if (n < 0 || !box_seen) {
        problems.add(
            l.number, 1,
            fmt::format("ITEM: ATOMS comes before ITEM: {} (expected the frame's {} "
                        "first)",
                        n < 0 ? "NUMBER OF ATOMS" : "BOX BOUNDS", n < 0 ? "atom count" : "box"));
        return std::nullopt;
      }
      if (!box_ok) return std::nullopt;  // said at ITEM: BOX BOUNDS
      Columns c;
      if (!read_columns(l, c, problems)) return std::nullopt;
      Atoms atoms;
      long long rows = 0;
      for (std::size_t r = k + 1; r < end && !lines[r].raw.starts_with("ITEM:"); ++r) {
        if (lines[r].fields.empty()) continue;
        ++rows;
        read_dump_row(lines[r], c, box, atoms, problems);
      }
      if (rows != n) {
        problems.add(l.number, 1,
                     fmt::format("the frame has {} but NUMBER OF ATOMS says {} (expected a row "
                                 "per atom)",
                                 count_of(rows, "atom row"), n));
      }
      Imported out;
      out.box = orthogonal_box(box.lo, box.hi, box.periodic);
      out.has_mass = c.more.mass >= 0;
      lammps_kinds(atoms, 0, out);
      // An unwrapped position holds its images already.
      bool images = false;
      for (int a = 0; a < 3; ++a) images = images || (c.image[a] >= 0 && !c.unwrapped[a]);
      if (problems.any() || !to_rows(atoms, images, problems, out)) return std::nullopt;
      return out;
    }
  }
  problems.add(lines[begin].number, 1, "the frame has no ITEM: ATOMS (expected one)");
  return std::nullopt;
}

}  // namespace

ReadResult read_lammps_dump(const std::string& text, long long frame, Problems& problems) {
  const auto lines = text_file::split_lines(text, false);
  std::vector<std::size_t> starts;  // each frame's ITEM: TIMESTEP
  for (std::size_t k = 0; k < lines.size(); ++k) {
    if (is_item(lines[k], "TIMESTEP")) starts.push_back(k);
  }
  ReadResult r;
  const auto k = choose_frame(
      starts, frame, "no 'ITEM: TIMESTEP' line (expected a LAMMPS text dump)", problems, r);
  if (!k) return r;
  const std::size_t end = *k + 1 < starts.size() ? starts[*k + 1] : lines.size();
  r.imported = read_frame(lines, starts[*k], end, problems);
  return r;
}

}  // namespace pdyn::import_files::detail
