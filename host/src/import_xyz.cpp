// Extended XYZ, as ASE's and OVITO's documentation describe it (the
// libAtoms/extxyz specification): frames back to back, each a line with the
// atom count, a comment line of key=value pairs (values may be quoted:
// Lattice="Lx 0 0 0 Ly 0 0 0 Lz", Properties=species:S:1:pos:R:3:...,
// pbc="T T T"), then one row per atom with the columns Properties names.
#include <fmt/format.h>

#include <algorithm>
#include <map>

#include "import_reader.hpp"
#include "pdyn/text.hpp"

namespace pdyn::import_files::detail {

namespace {

struct Value {
  std::string text;
  std::size_t column;  // of the key, 1-based
};
using KeyValues = std::map<std::string, Value>;

// The key=value pairs of a comment line; keys are case-insensitive. A bare
// word is a key without a value.
std::optional<KeyValues> key_values(const Line& l, Problems& problems) {
  const std::string_view s = l.raw;
  KeyValues out;
  auto blank = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  for (std::size_t k = 0; k < s.size();) {
    while (k < s.size() && blank(s[k])) ++k;
    const std::size_t start = k;
    while (k < s.size() && s[k] != '=' && !blank(s[k])) ++k;
    const std::string_view written = s.substr(start, k - start);
    std::string key(written);
    std::transform(key.begin(), key.end(), key.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    std::string value;
    if (k < s.size() && s[k] == '=') {
      ++k;
      if (k < s.size() && s[k] == '"') {
        const std::size_t close = s.find('"', k + 1);
        if (close == std::string_view::npos) {
          problems.add(l.number, k + 1,
                       fmt::format("the value of {} opens a '\"' that is never closed (expected "
                                   "key=\"value\")",
                                   written));
          return std::nullopt;
        }
        value = std::string(s.substr(k + 1, close - k - 1));
        k = close + 1;
      } else {
        const std::size_t v = k;
        while (k < s.size() && !blank(s[k])) ++k;
        value = std::string(s.substr(v, k - v));
      }
    }
    if (!key.empty()) out[key] = {value, start + 1};
  }
  return out;
}

// Where the columns pdyn reads are in a row (-1: absent).
struct Properties {
  int pos = -1, species = -1, id = -1;
  MoreColumns more;
  std::size_t width = 0;
};

// Properties=name:type:count:name:type:count..., type S, R, I or L; the
// default is species:S:1:pos:R:3.
bool read_properties(const KeyValues& kv, std::size_t line, Properties& p, Problems& problems) {
  const auto it = kv.find("properties");
  const std::string text = it == kv.end() ? "species:S:1:pos:R:3" : it->second.text;
  std::vector<std::string> parts;
  for (std::size_t k = 0; k <= text.size();) {
    const std::size_t colon = std::min(text.find(':', k), text.size());
    parts.push_back(text.substr(k, colon - k));
    k = colon + 1;
  }
  for (std::size_t k = 0; k < parts.size(); k += 3) {
    const auto count =
        k + 2 < parts.size() ? text_file::to_number<int>(parts[k + 2]) : std::nullopt;
    if (!count || *count < 1 || parts[k + 1].size() != 1 ||
        std::string_view("SRIL").find(parts[k + 1][0]) == std::string_view::npos) {
      problems.add(line, it->second.column,
                   fmt::format("Properties is malformed at '{}' (expected name:type:count "
                               "triples, type S, R, I or L, e.g. species:S:1:pos:R:3)",
                               parts[k]));
      return false;
    }
    const std::string& name = parts[k];
    const int at = static_cast<int>(p.width);
    const bool real = parts[k + 1] == "R";
    if (name == "pos" && *count == 3 && real) p.pos = at;
    if ((name == "velo" || name == "vel" || name == "velocities") && *count == 3 && real) {
      p.more.v = {at, at + 1, at + 2};
    }
    if ((name == "mass" || name == "masses") && *count == 1 && real) p.more.mass = at;
    if ((name == "radius" || name == "radii") && *count == 1 && real) p.more.radius = at;
    if ((name == "species" || name == "element") && *count == 1) p.species = at;
    if (name == "id" && *count == 1 && parts[k + 1] == "I") p.id = at;
    p.width += static_cast<std::size_t>(*count);
  }
  if (p.pos < 0) {
    problems.add(line, it == kv.end() ? 1 : it->second.column,
                 "Properties has no pos:R:3 (expected the positions)");
    return false;
  }
  return true;
}

// `count` numbers of a value ("Lattice", "Origin"), or a problem at its key.
std::optional<std::vector<double>> numbers(const Value& v, std::size_t line, std::size_t count,
                                           const char* what, Problems& problems) {
  std::vector<double> out;
  const auto fields = text_file::split_blanks(v.text);
  for (const auto& f : fields) {
    const auto x = text_file::to_number<double>(f.text);
    if (!x || !std::isfinite(*x)) break;
    out.push_back(*x);
  }
  if (out.size() != count || fields.size() != count) {
    problems.add(line, v.column,
                 fmt::format("{} is not {} finite numbers (expected {})", text_file::quoted(v.text),
                             count, what));
    return std::nullopt;
  }
  return out;
}

// Lattice (the cell's three vectors, a b c), Origin (OVITO: the box's
// corner; 0 otherwise) and pbc (T or F per axis; T T T with a Lattice,
// ASE's default).
bool read_box(const KeyValues& kv, std::size_t line, std::optional<Domain>& box,
              Problems& problems) {
  const auto lattice = kv.find("lattice");
  if (lattice == kv.end()) return true;
  const auto m = numbers(lattice->second, line, 9, "Lattice=\"Lx 0 0 0 Ly 0 0 0 Lz\"", problems);
  if (!m) return false;
  const auto& c = *m;
  if (c[1] != 0 || c[2] != 0 || c[3] != 0 || c[5] != 0 || c[6] != 0 || c[7] != 0 ||
      !(c[0] > 0 && c[4] > 0 && c[8] > 0)) {
    problems.add(line, lattice->second.column,
                 "Lattice is not an orthogonal box (expected \"Lx 0 0 0 Ly 0 0 0 Lz\" with Lx, "
                 "Ly, Lz > 0: pdyn's simulation box has no tilt)");
    return false;
  }
  Vec3 origin = Vec3::Zero();
  if (const auto o = kv.find("origin"); o != kv.end()) {
    const auto x = numbers(o->second, line, 3, "Origin=\"x y z\"", problems);
    if (!x) return false;
    origin = Vec3((*x)[0], (*x)[1], (*x)[2]);
  }
  std::array<bool, 3> periodic{true, true, true};
  if (const auto p = kv.find("pbc"); p != kv.end()) {
    const auto fields = text_file::split_blanks(p->second.text);
    bool ok = fields.size() == 3;
    for (std::size_t k = 0; ok && k < 3; ++k) {
      std::string t(fields[k].text);
      std::transform(t.begin(), t.end(), t.begin(),
                     [](unsigned char ch) { return static_cast<char>(std::toupper(ch)); });
      ok = t == "T" || t == "F" || t == "TRUE" || t == "FALSE";
      periodic[k] = t[0] == 'T';
    }
    if (!ok) {
      problems.add(line, p->second.column,
                   fmt::format("pbc={} is not three of T and F (expected e.g. pbc=\"T T F\")",
                               text_file::quoted(p->second.text)));
      return false;
    }
  }
  box = orthogonal_box(origin, origin + Vec3(c[0], c[4], c[8]), periodic);
  return true;
}

void read_xyz_row(const Line& row, long long index, const Properties& p,
                  std::map<std::string, std::uint32_t, std::less<>>& species, Atoms& atoms,
                  Imported& out, Problems& problems) {
  const auto& f = row.fields;
  if (f.size() != p.width) {
    problems.add(row.number, 1,
                 fmt::format("has {}, Properties gives {} (expected one per column)",
                             count_of(static_cast<long long>(f.size()), "field"), p.width));
    return;
  }
  auto field = [&](int k) -> const Field& { return f[static_cast<std::size_t>(k)]; };
  Atom a;
  a.id = index + 1;
  bool ok = true;
  for (int c = 0; c < 3; ++c) {
    const auto x = parse_real(field(p.pos + c), row.number, std::string(1, "xyz"[c]), problems);
    ok = ok && x;
    a.x[c] = x.value_or(0.0);
  }
  ok = read_more(f, row.number, p.more, a, problems) && ok;
  if (p.id >= 0) {
    const auto id = parse_whole(field(p.id), row.number, "id", problems, 0);
    ok = ok && id;
    a.id = id.value_or(0);
  }
  if (p.species >= 0) {
    const std::string_view s = field(p.species).text;
    auto it = species.find(s);
    if (it == species.end()) {
      it = species.emplace(std::string(s), static_cast<std::uint32_t>(out.kinds.size())).first;
      out.kinds.emplace_back(s);
    }
    a.kind = it->second;
  }
  if (ok) atoms.add(a, row.number);
}

// The frame whose count line is lines[start].
std::optional<Imported> read_xyz_frame(const std::vector<Line>& lines, std::size_t start,
                                       Problems& problems) {
  const auto n = *text_file::to_number<long long>(lines[start].fields[0].text);
  if (start + 1 >= lines.size()) {
    problems.add(lines[start].number, 1,
                 "the comment line is missing (expected key=value pairs after the atom count)");
    return std::nullopt;
  }
  const Line& comment = lines[start + 1];
  const auto kv = key_values(comment, problems);
  Properties p;
  Imported out;
  out.species = true;
  if (!kv || !read_properties(*kv, comment.number, p, problems) ||
      !read_box(*kv, comment.number, out.box, problems)) {
    return std::nullopt;
  }
  std::map<std::string, std::uint32_t, std::less<>> species;
  Atoms atoms;
  for (long long i = 0; i < n; ++i) {
    const std::size_t k = start + 2 + static_cast<std::size_t>(i);
    if (k >= lines.size()) {
      problems.add(lines.back().number, 1,
                   fmt::format("the file ends after {} of the frame's {} (expected a row per atom)",
                               i, count_of(n, "atom")));
      break;
    }
    read_xyz_row(lines[k], i, p, species, atoms, out, problems);
  }
  out.has_mass = p.more.mass >= 0;
  if (problems.any() || !to_rows(atoms, false, problems, out)) return std::nullopt;
  return out;
}

}  // namespace

ReadResult read_extxyz(const std::string& text, long long frame, Problems& problems) {
  const auto lines = text_file::split_lines(text, false);
  std::vector<std::size_t> starts;  // each frame's count line
  for (std::size_t at = 0; at < lines.size();) {
    if (lines[at].fields.empty()) {  // blank lines after the last frame
      ++at;
      continue;
    }
    const auto n = lines[at].fields.size() == 1
                       ? text_file::to_number<long long>(lines[at].fields[0].text)
                       : std::nullopt;
    if (!n || *n < 0) {
      problems.add(lines[at].number, 1,
                   fmt::format("{} is not an atom count (expected a line with the number of "
                               "atoms of frame {}{})",
                               quoted(text_file::trim(lines[at].raw)), starts.size(),
                               starts.empty() ? ": an extended XYZ file starts with it" : ""));
      return {};
    }
    starts.push_back(at);
    at += 2 + static_cast<std::size_t>(*n);
  }
  ReadResult r;
  const auto k = choose_frame(
      starts, frame, "the file is empty (expected an atom count, a comment line, then rows)",
      problems, r);
  if (!k) return r;
  r.imported = read_xyz_frame(lines, starts[*k], problems);
  return r;
}

}  // namespace pdyn::import_files::detail
