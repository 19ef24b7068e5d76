// Which reader reads a file (import_files.hpp), and what the readers share
// (import_reader.hpp): atoms to rows in id order, kinds, box, frames.
#include "import_files.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <numeric>
#include <set>

#include "import_reader.hpp"

namespace pdyn::import_files {

namespace {

// In the order of side_files::kParticleFileFormats.
constexpr Format kFormats[] = {Format::Csv, Format::LammpsData, Format::LammpsDump, Format::ExtXyz};

struct Extension {
  const char* text;
  Format format;
};
constexpr Extension kExtensions[] = {
    {".csv", Format::Csv},         {".data", Format::LammpsData},      {".lmp", Format::LammpsData},
    {".dump", Format::LammpsDump}, {".lammpstrj", Format::LammpsDump}, {".xyz", Format::ExtXyz},
    {".extxyz", Format::ExtXyz},
};

}  // namespace

std::string format_names() {
  return fmt::format("{}", fmt::join(side_files::kParticleFileFormats, ", "));
}

std::string extension_names() {
  std::string s;
  for (std::size_t k = 0; k < std::size(kExtensions); ++k) {
    s += k == 0 ? "" : k + 1 == std::size(kExtensions) ? " or " : ", ";
    s += kExtensions[k].text;
  }
  return s;
}

std::optional<Format> parse_format(std::string_view name) {
  for (std::size_t k = 0; k < std::size(kFormats); ++k) {
    if (name == side_files::kParticleFileFormats[k]) return kFormats[k];
  }
  return std::nullopt;
}

std::optional<Format> format_of_extension(const std::filesystem::path& file) {
  const std::string e = file.extension().string();
  for (const auto& x : kExtensions) {
    if (e == x.text) return x.format;
  }
  return std::nullopt;
}

bool has_frames(Format format) { return format == Format::LammpsDump || format == Format::ExtXyz; }

ReadResult read(const std::filesystem::path& file, Format format, long long frame,
                std::string_view atom_style, const std::string& shown,
                std::vector<Diagnostic>& out) {
  if (format == Format::Csv) {
    auto rows = side_files::read_particles(file, shown, out);
    ReadResult r;
    r.frames = 1;
    if (rows) {
      r.imported.emplace().rows = std::move(*rows);
      r.imported->has_mass = true;
    }
    return r;
  }
  text_file::Problems problems(shown, out);
  const auto text = text_file::slurp(file);
  if (!text) {
    problems.add_file("cannot read the particle file (expected a readable file)");
    return {};
  }
  ReadResult r;
  switch (format) {
    case Format::LammpsData:
      r = detail::read_lammps_data(*text, atom_style, problems);
      break;
    case Format::LammpsDump:
      r = detail::read_lammps_dump(*text, frame, problems);
      break;
    default:
      r = detail::read_extxyz(*text, frame, problems);
      break;
  }
  problems.finish();
  if (r.imported) r.imported->format = format;
  return r;
}

namespace detail {

void lammps_kinds(Atoms& atoms, long long declared, Imported& out) {
  std::set<long long> types;
  for (long long t = 1; t <= declared; ++t) types.insert(t);
  for (const Atom& a : atoms.atoms) types.insert(a.type);
  std::vector<long long> order(types.begin(), types.end());
  for (long long t : order) out.kinds.push_back(std::to_string(t));
  for (Atom& a : atoms.atoms) {
    a.kind = static_cast<std::uint32_t>(std::lower_bound(order.begin(), order.end(), a.type) -
                                        order.begin());
  }
}

bool to_rows(Atoms& in, bool images, Problems& problems, Imported& out) {
  const auto& atoms = in.atoms;
  std::vector<std::size_t> order(atoms.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return atoms[a].id < atoms[b].id; });
  for (std::size_t k = 1; k < order.size(); ++k) {
    if (atoms[order[k]].id == atoms[order[k - 1]].id) {
      problems.add(in.lines[order[k]], 1,
                   fmt::format("atom id {} appears twice (expected unique ids; first at line {})",
                               atoms[order[k]].id, in.lines[order[k - 1]]));
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
    r.type.push_back(out.species ? static_cast<std::int32_t>(a.kind)
                                 : static_cast<std::int32_t>(a.type));
    if (radii) r.radius.push_back(std::max(a.radius, 0.0));
    if (images) out.images.push_back(a.image);
    if (!out.kinds.empty()) out.kind.push_back(a.kind);
  }
  return true;
}

Domain orthogonal_box(const Vec3& lo, const Vec3& hi, const std::array<bool, 3>& periodic) {
  Domain d;
  d.min = lo;
  d.max = hi;
  d.periodic = periodic;
  return d;
}

std::optional<std::size_t> choose_frame(const std::vector<std::size_t>& starts, long long frame,
                                        std::string_view empty, Problems& problems, ReadResult& r) {
  r.frames = starts.size();
  if (starts.empty()) {
    problems.add(1, 1, std::string(empty));
    return std::nullopt;
  }
  const auto n = static_cast<long long>(starts.size());
  const long long k = frame < 0 ? n + frame : frame;
  if (k < 0 || k >= n) {
    r.no_such_frame = true;
    return std::nullopt;
  }
  return static_cast<std::size_t>(k);
}

std::optional<double> parse_mass(const Field& f, std::size_t line, Problems& problems) {
  const auto m = parse_real(f, line, "mass", problems);
  if (m && !(*m > 0.0)) {
    problems.add(line, f.column,
                 fmt::format("mass: {} is not positive (expected a mass > 0 kg)", f.text));
    return std::nullopt;
  }
  return m;
}

std::optional<double> parse_size(const Field& f, std::size_t line, std::string_view name,
                                 Problems& problems) {
  const auto s = parse_real(f, line, name, problems);
  if (s && *s < 0.0) {
    problems.add(line, f.column,
                 fmt::format("{}: {} is negative (expected a {} >= 0 m)", name, f.text, name));
    return std::nullopt;
  }
  return s;
}

std::optional<std::int32_t> parse_image(const Field& f, std::size_t line, int axis,
                                        Problems& problems) {
  const auto n = text_file::to_number<std::int32_t>(f.text);
  if (!n) {
    problems.add(line, f.column,
                 fmt::format("image flag {}: {} is not a whole number (expected the count of box "
                             "lengths the atom has crossed along {})",
                             "xyz"[axis], quoted(f.text), "xyz"[axis]));
  }
  return n;
}

bool read_more(const std::vector<Field>& f, std::size_t line, const MoreColumns& c, Atom& a,
               Problems& problems) {
  auto field = [&](int k) -> const Field& { return f[static_cast<std::size_t>(k)]; };
  bool ok = true;
  for (int k = 0; k < 3; ++k) {
    if (c.v[k] < 0) continue;
    const auto v = parse_real(field(c.v[k]), line, std::string("v") + "xyz"[k], problems);
    ok = ok && v;
    a.v[k] = v.value_or(0.0);
  }
  if (c.mass >= 0) {
    const auto m = parse_mass(field(c.mass), line, problems);
    ok = ok && m;
    a.mass = m.value_or(0.0);
  }
  if (c.radius >= 0) {
    const auto s = parse_size(field(c.radius), line, c.diameter ? "diameter" : "radius", problems);
    ok = ok && s;
    a.radius = s.value_or(0.0) * (c.diameter ? 0.5 : 1.0);
  }
  return ok;
}

}  // namespace detail

}  // namespace pdyn::import_files
