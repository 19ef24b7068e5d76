// The loader's particles and boxes from files: pdyn's CSV side files
// (side_files.hpp) and other programs' files (import_files.hpp), as
// `- file:` particle entries and `simulation: { box: { file: } }`, with the
// keys that say how to read them: format, frame, atom_style, mass, masses,
// types, periodic (docs/scenes.md, "Particles from LAMMPS and extended XYZ
// files"). Members of Loader (loader.hpp), apart from scene_loader.cpp for
// size.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "loader.hpp"
#include "pdyn/text.hpp"

namespace pdyn::loading {

namespace {

using import_files::Format;

// The keys a file entry takes: those of its format (all of them while the
// format is unknown, so that only the format is reported).
std::vector<std::string> file_keys(std::optional<Format> f, bool for_box) {
  std::vector<std::string> keys{"file", "format"};
  if (!f || import_files::has_frames(*f)) keys.push_back("frame");
  if (!f || *f == Format::LammpsData) keys.push_back("atom_style");
  if (for_box) {
    keys.push_back("periodic");
    return keys;
  }
  keys.push_back("mass");
  if (!f || *f != Format::Csv) keys.push_back("masses");
  if (!f || *f == Format::ExtXyz) keys.push_back("types");
  return keys;
}

std::string kinds_list(const std::vector<std::string>& kinds, const std::vector<bool>& which) {
  std::vector<std::string> out;
  for (std::size_t k = 0; k < kinds.size(); ++k) {
    if (which[k]) out.push_back(kinds[k]);
  }
  return fmt::format("{}", fmt::join(out, ", "));
}

// Which kinds (LAMMPS types, XYZ species) the file's particles have.
std::vector<bool> used_kinds(const import_files::Imported& in) {
  std::vector<bool> used(in.kinds.size(), false);
  for (const auto k : in.kind) used[k] = true;
  return used;
}

}  // namespace

// A file name as written in the scene: relative to the scene's folder.
fs::path Loader::scene_relative(const std::string& name) const {
  const fs::path p(name);
  return p.is_absolute() ? p : fs::path(file_).parent_path() / p;
}

// The `file` of a side-file mapping, relative to the scene's folder.
std::optional<fs::path> Loader::side_file(const YAML::Node& map, const std::string& path,
                                          const char* expected,
                                          const std::vector<std::string>& keys) {
  check_keys(map, path, keys);
  // A const lookup of a missing key gives an invalid node whose Is*() throw:
  // ask IsDefined() first (a fuzzer found `pairs: {}`).
  const YAML::Node f = map["file"];
  if (!f.IsDefined() || !f.IsScalar() || f.Scalar().empty()) {
    error(f.IsDefined() ? f : map, path + ".file",
          fmt::format("{}.file: is not a file name (expected {})", path, expected));
    return std::nullopt;
  }
  fs::path file = scene_relative(f.Scalar());
  read_files_.push_back({path + ".file", where(f, path + ".file"), file});
  return file;
}

// `format`, or else what the file's extension says.
std::optional<Format> Loader::file_format(const YAML::Node& map, const std::string& path) {
  if (const YAML::Node f = map["format"]; f.IsDefined()) {
    const auto format = f.IsScalar() ? import_files::parse_format(f.Scalar()) : std::nullopt;
    if (!format) {
      error(f, path + ".format",
            fmt::format("{}.format: '{}' is not a format pdyn reads (expected one of {})", path,
                        shown(f), import_files::format_names()));
    }
    return format;
  }
  const YAML::Node file = map["file"];
  if (!file.IsDefined() || !file.IsScalar() || file.Scalar().empty()) {
    return std::nullopt;  // side_file says so
  }
  const auto format = import_files::format_of_extension(file.Scalar());
  if (!format) {
    error(file, path + ".file",
          fmt::format("{}.file: '{}' has an extension that names no format (expected {}, or a "
                      "format: key, one of {})",
                      path, fs::path(file.Scalar()).filename().string(),
                      import_files::extension_names(), import_files::format_names()));
  }
  return format;
}

// `atom_style`: the LAMMPS atom style a data file's Atoms are in, as the
// input script's atom_style names it (a data file need not say it); empty
// when not given, nothing when it is not a style.
std::optional<std::string> Loader::read_atom_style(const YAML::Node& n, const std::string& path) {
  if (!n.IsDefined()) return std::string();
  if (!n.IsScalar() || !import_files::is_atom_style(n.Scalar())) {
    error(n, path,
          fmt::format("{}: '{}' is not an atom style pdyn reads (expected one of {})", path,
                      shown(n), import_files::atom_style_names()));
    return std::nullopt;
  }
  return n.Scalar();
}

// `frame`: 0 the first, 1 the second, ..., -1 (the default) the last.
std::optional<long long> Loader::read_frame(const YAML::Node& n, const std::string& path) {
  if (!n.IsDefined() || n.IsNull()) return -1;
  long long frame = 0;
  if (!n.IsScalar() || !YAML::convert<long long>::decode(n, frame)) {
    error(n, path,
          fmt::format("{}: '{}' is not a frame number (expected a whole number: 0 the first "
                      "frame, -1 the last)",
                      path, shown(n)));
    return std::nullopt;
  }
  return frame;
}

std::optional<import_files::Imported> Loader::import_file(const YAML::Node& map,
                                                          const std::string& path, bool for_box) {
  const auto format = file_format(map, path);
  const auto file = side_file(map, path,
                              "{ file: particles.csv } with header x,y,z,mass, or a LAMMPS data "
                              "or dump file or an extended XYZ file",
                              file_keys(format, for_box));
  const auto frame = read_frame(map["frame"], path + ".frame");
  const auto style = read_atom_style(map["atom_style"], path + ".atom_style");
  if (!file || !format || !frame || !style) return std::nullopt;
  // A file that gives the box and the particles is read once: its problems
  // are reported once.
  const std::string key = fmt::format("{}|{}|{}|{}", file->lexically_normal().string(),
                                      static_cast<int>(*format), *frame, *style);
  import_files::ReadResult r;
  if (const auto it = box_files_.find(key); it != box_files_.end() && !for_box) {
    r = std::move(it->second);
    box_files_.erase(it);
  } else {
    r = import_files::read(*file, *format, *frame, *style, file->string(), diags_);
  }
  if (r.no_such_frame) {
    const auto n = static_cast<long long>(r.frames);
    error(map["frame"], path + ".frame",
          fmt::format("{}.frame: {} is not a frame of '{}' (expected 0..{}, or -{}..-1 counting "
                      "from the end: the file has {})",
                      path, *frame, file->filename().string(), n - 1, n, count_of(n, "frame")));
  }
  if (for_box) {
    std::optional<import_files::Imported> only_box;
    if (r.imported) only_box.emplace().box = r.imported->box;
    box_files_[key] = std::move(r);
    return only_box;
  }
  return std::move(r.imported);
}

// A data file's topology (Bonds, Angles, ...) that no force or constraint
// of the scene takes: one line naming every such section, at the first
// one's title.
void Loader::warn_unread(const std::string& file,
                         const std::vector<import_files::Imported::Unread>& unread) {
  std::vector<std::string> parts;
  parts.reserve(unread.size());
  for (const auto& u : unread) {
    parts.push_back(fmt::format("{} ({})", u.section, count_of(u.rows, "row")));
  }
  const bool terms = std::all_of(unread.begin(), unread.end(), [](const auto& u) {
    return u.section == "Bonds" || u.section == "Angles" || u.section == "Dihedrals" ||
           u.section == "Impropers";
  });
  warnings_.push_back(fmt::format(
      "{}:{}:1: {} {} not read: {}, so these particles run without those terms (give the scene "
      "the forces or constraints they stand for{})",
      file, unread.front().line, fmt::join(parts, ", "), parts.size() == 1 ? "is" : "are",
      terms ? "no force or constraint of the scene takes them"
            : "pdyn takes a data file's atoms, masses, velocities and topology only",
      terms ? fmt::format(", e.g. pairs: {{ file: {} }} for the Bonds",
                          fs::path(file).filename().string())
            : ""));
}

// `mass` for every particle, or `masses` per kind (LAMMPS type, XYZ
// species); either replaces the file's masses. A file without masses needs
// one of them.
bool Loader::apply_masses(const YAML::Node& item, const std::string& path,
                          import_files::Imported& in) {
  const YAML::Node one = item["mass"], per = item["masses"];
  if (one.IsDefined() && per.IsDefined()) {
    error(per, path + ".masses",
          fmt::format("{}.masses: is given beside mass (expected one of them)", path));
    return false;
  }
  // (check_keys refused masses for a CSV file, which has its mass column.)
  if (per.IsDefined() && in.format == import_files::Format::Csv) return true;
  if (per.IsDefined()) return masses_by_kind(per, path + ".masses", in);
  if (!one.IsDefined()) {
    if (in.has_mass) return true;
    error(item["file"], path + ".file",
          fmt::format("{}.file: the file gives no masses (expected mass: KG or masses: {{ TYPE: "
                      "KG, ... }} beside file, or masses in the file)",
                      path));
    return false;
  }
  double mass = 0.0;
  if (!one.IsScalar() || !YAML::convert<double>::decode(one, mass) || !(mass > 0.0) ||
      !std::isfinite(mass)) {
    error(one, path + ".mass",
          fmt::format("{}.mass: '{}' is not a mass (expected a number > 0, kg)", path, shown(one)));
    return false;
  }
  std::fill(in.rows.mass.begin(), in.rows.mass.end(), mass);
  return true;
}

// `masses: { 1: 39.948, 2: 83.798 }` (LAMMPS types) or `{ Ar: 39.948 }`
// (XYZ species): every kind the file's particles have needs one.
bool Loader::masses_by_kind(const YAML::Node& per, const std::string& at,
                            import_files::Imported& in) {
  if (!per.IsMap() || in.kinds.empty()) {
    error(per, at,
          in.kinds.empty()
              ? fmt::format("{}: the file's particles have no types (expected mass: KG for all "
                            "of them)",
                            at)
              : fmt::format("{}: is not a mapping (expected {{ {}: KG, ... }})", at,
                            in.species ? "SPECIES" : "TYPE"));
    return false;
  }
  const char* what = in.species ? "species" : "type";
  const std::vector<bool> all(in.kinds.size(), true), used = used_kinds(in);
  std::vector<double> by_kind(in.kinds.size(), 0.0);
  bool ok = true;
  for (const auto& kv : per) {
    const std::string key = kv.first.Scalar(), here = at + "." + key;
    const auto k = static_cast<std::size_t>(std::find(in.kinds.begin(), in.kinds.end(), key) -
                                            in.kinds.begin());
    double mass = 0.0;
    if (k == in.kinds.size()) {
      error(kv.first, here,
            fmt::format("{}: '{}' is not a {} of the file (expected one of {})", at, key, what,
                        kinds_list(in.kinds, all)));
      ok = false;
    } else if (!kv.second.IsScalar() || !YAML::convert<double>::decode(kv.second, mass) ||
               !(mass > 0.0) || !std::isfinite(mass)) {
      error(kv.second, here,
            fmt::format("{}: '{}' is not a mass (expected a number > 0, kg)", here,
                        shown(kv.second)));
      ok = false;
    } else {
      by_kind[k] = mass;
    }
  }
  std::vector<bool> missing(in.kinds.size(), false);
  for (std::size_t k = 0; k < in.kinds.size(); ++k) missing[k] = used[k] && by_kind[k] == 0.0;
  if (ok && std::find(missing.begin(), missing.end(), true) != missing.end()) {
    error(per, at,
          fmt::format("{}: gives no mass for {} {} (expected one for each {} of the file's "
                      "particles: {})",
                      at, what, kinds_list(in.kinds, missing), what, kinds_list(in.kinds, used)));
    ok = false;
  }
  for (std::size_t i = 0; ok && i < in.rows.mass.size(); ++i) {
    in.rows.mass[i] = by_kind[in.kind[i]];
  }
  return ok;
}

// `types: { Ar: 1, Kr: 2 }`: an extended XYZ file's species as types.
bool Loader::apply_types(const YAML::Node& item, const std::string& path,
                         import_files::Imported& in) {
  const YAML::Node t = item["types"];
  // Only extended XYZ takes types (check_keys refused it for the others).
  if (!t.IsDefined() || t.IsNull() || in.format != import_files::Format::ExtXyz) return true;
  const std::string at = path + ".types";
  if (!t.IsMap() || in.kinds.empty()) {
    error(t, at,
          in.kinds.empty()
              ? fmt::format("{}: the file has no species column (expected types: only with "
                            "species)",
                            at)
              : fmt::format("{}: is not a mapping (expected {{ SPECIES: TYPE, ... }}, e.g. {{ "
                            "Ar: 1, Kr: 2 }})",
                            at));
    return false;
  }
  const std::vector<bool> all(in.kinds.size(), true), used = used_kinds(in);
  std::vector<std::int64_t> type_of(in.kinds.size(), -1);
  bool ok = true;
  for (const auto& kv : t) {
    const std::string key = kv.first.Scalar(), here = at + "." + key;
    const auto k = static_cast<std::size_t>(std::find(in.kinds.begin(), in.kinds.end(), key) -
                                            in.kinds.begin());
    long long type = -1;
    if (k == in.kinds.size()) {
      error(kv.first, here,
            fmt::format("{}: '{}' is not a species of the file (expected one of {})", at, key,
                        kinds_list(in.kinds, all)));
      ok = false;
    } else if (!kv.second.IsScalar() || !YAML::convert<long long>::decode(kv.second, type) ||
               type < 0 || type > std::numeric_limits<std::int32_t>::max()) {
      error(kv.second, here,
            fmt::format("{}: '{}' is not a particle type (expected a whole number in 0..{})", here,
                        shown(kv.second), std::numeric_limits<std::int32_t>::max()));
      ok = false;
    } else {
      type_of[k] = type;
    }
  }
  std::vector<bool> missing(in.kinds.size(), false);
  for (std::size_t k = 0; k < in.kinds.size(); ++k) missing[k] = used[k] && type_of[k] < 0;
  if (ok && std::find(missing.begin(), missing.end(), true) != missing.end()) {
    error(t, at,
          fmt::format("{}: gives no type for species {} (expected one for each species of the "
                      "file: {})",
                      at, kinds_list(in.kinds, missing), kinds_list(in.kinds, used)));
    ok = false;
  }
  for (std::size_t i = 0; ok && i < in.rows.type.size(); ++i) {
    in.rows.type[i] = static_cast<std::int32_t>(type_of[in.kind[i]]);
  }
  return ok;
}

// Along the box's periodic axes a file's particle starts inside the box,
// and its image count is the file's (LAMMPS's image flags) plus the box
// lengths the wrap moved it by (an unwrapped dump's xu): x + n L stays the
// file's unwrapped position. Along open axes (or without a box) image
// counts are 0, as the kernel keeps them.
bool Loader::wrap_imported(const YAML::Node& item, const std::string& path,
                           import_files::Imported& in) {
  auto& x = in.rows.x;
  if (!box_) {
    in.images.clear();
    return true;
  }
  if (in.images.empty()) in.images.assign(x.size(), {0, 0, 0});
  const Vec3 length = box_->length();
  bool any = false;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Vec3 wrapped = box_->wrap(x[i]);
    for (int k = 0; k < 3; ++k) {
      const double n = box_->periodic[k]
                           ? std::round((x[i][k] - wrapped[k]) / length[k]) + in.images[i][k]
                           : 0.0;
      if (std::abs(n) > std::numeric_limits<std::int32_t>::max()) {
        error(item["file"], path + ".file",
              fmt::format("{}.file: particle {} of the file is {} box lengths from "
                          "simulation.box along {} (expected fewer than 2^31)",
                          path, i, n, "xyz"[k]));
        return false;
      }
      in.images[i][k] = static_cast<std::int32_t>(n);
      any = any || n != 0.0;
    }
    x[i] = wrapped;
  }
  if (!any) in.images.clear();
  return true;
}

void Loader::read_particle_file(const YAML::Node& item, const std::string& path) {
  auto imported = import_file(item, path, false);
  if (!imported) {  // said, here or where the same file gave the box
    particles_ok_ = false;
    return;
  }
  const bool masses = apply_masses(item, path, *imported);
  if (!apply_types(item, path, *imported) || !masses || !wrap_imported(item, path, *imported)) {
    return;
  }
  auto& rows = imported->rows;
  if (static_cast<std::int64_t>(x_.size() + rows.x.size()) > kMaxParticles) {
    error(item, path,
          fmt::format("{}: {} particles is too many (expected at most {} particles "
                      "in a scene)",
                      path, x_.size() + rows.x.size(), kMaxParticles));
    return;
  }
  const auto first = x_.size();
  x_.insert(x_.end(), rows.x.begin(), rows.x.end());
  v_.insert(v_.end(), rows.v.begin(), rows.v.end());
  m_.insert(m_.end(), rows.mass.begin(), rows.mass.end());
  fixed_.insert(fixed_.end(), rows.fixed.begin(), rows.fixed.end());
  // The columns radius and type, if the file has them (others get 0).
  const auto at = static_cast<std::ptrdiff_t>(first);
  if (!rows.radius.empty()) {
    radius_.resize(x_.size(), 0.0);
    std::copy(rows.radius.begin(), rows.radius.end(), radius_.begin() + at);
  }
  if (!rows.type.empty()) {
    type_.resize(x_.size(), 0);
    std::copy(rows.type.begin(), rows.type.end(), type_.begin() + at);
  }
  if (!imported->images.empty()) {
    images_.resize(first, {0, 0, 0});
    images_.insert(images_.end(), imported->images.begin(), imported->images.end());
  }
  if (!imported->topology.empty() || !imported->unread.empty()) {
    const fs::path file = scene_relative(item["file"].Scalar());
    DataTopology& t = topology_[file.lexically_normal().string()];
    ++t.entries;
    t.first = static_cast<Index>(first);
    t.shown = file.string();
    t.sections = std::move(imported->topology);
    t.unread = std::move(imported->unread);
  }
}

// `box: { file: melt.data }`: the box of a LAMMPS data or dump file or an
// extended XYZ file's Lattice; `periodic` beside it replaces the file's
// (a data file says nothing, and is taken as periodic along every axis).
void Loader::read_box_file(const YAML::Node& n, const std::string& path) {
  std::array<bool, 3> periodic{};
  const bool periodic_ok = read_periodic(n["periodic"], path + ".periodic", periodic);
  const auto imported = import_file(n, path, true);
  if (!imported || !periodic_ok) return;
  if (!imported->box) {
    error(n["file"], path + ".file",
          fmt::format("{}.file: the file has no box (expected a LAMMPS data or dump file, or an "
                      "extended XYZ file with a Lattice)",
                      path));
    return;
  }
  box_ = imported->box;
  if (n["periodic"].IsDefined() && !n["periodic"].IsNull()) box_->periodic = periodic;
}

}  // namespace pdyn::loading
