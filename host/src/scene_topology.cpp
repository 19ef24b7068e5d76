// A bonded force's or constraint's terms from a LAMMPS data file
// (issue 44): `pairs: { file: polymer.data }` takes the Bonds of a data
// file the scene's particles came from, `triples:` its Angles, `quads:` its
// Dihedrals (or `section: Impropers`), with each term's type: LAMMPS's
// type t is the plugin's term type t - 1, so that `ks: [K1, K2]` lists the
// coefficients of bond types 1 and 2 in order (docs/bonded.md). `types:
// [1, 3]` takes only the terms of those LAMMPS types, as `fix shake ... b 1
// 3` names the bonds it holds rigid (issue 44 item 4). Members of Loader
// (loader.hpp), apart from scene_files.cpp for size.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <set>

#include "loader.hpp"
#include "pdyn/text.hpp"

namespace pdyn::loading {

namespace {

// The section a term list of K particles takes by default.
const char* default_section(std::size_t k) {
  return k == 2 ? "Bonds" : k == 3 ? "Angles" : "Dihedrals";
}

// The sections holding terms of K particles: "Bonds", or "Dihedrals, Impropers".
const char* sections_of(std::size_t k) {
  return k == 2 ? "Bonds" : k == 3 ? "Angles" : "Dihedrals or Impropers";
}

}  // namespace

template <std::size_t K>
std::optional<std::vector<std::array<Index, K>>> Loader::read_data_terms(const YAML::Node& n,
                                                                         const std::string& path) {
  const auto file = side_file(n, path, "{ file: NAME.data }, a data file of the scene's particles",
                              {"file", "format", "section", "types"});
  if (!file) return std::nullopt;
  const auto it = topology_.find(file->lexically_normal().string());
  if (it == topology_.end() || it->second.entries != 1) {
    error(n["file"], path + ".file",
          fmt::format("{}.file: '{}' {} (expected the data file of one `particles: - file:` "
                      "entry: the terms name its atoms)",
                      path, file->filename().string(),
                      it == topology_.end() ? "gives none of the scene's particles"
                                            : "gives the scene's particles more than once"));
    return std::nullopt;
  }
  DataTopology& t = it->second;
  std::string section = default_section(K);
  if (const YAML::Node s = n["section"]; s.IsDefined()) {
    const bool fits = s.IsScalar() &&
                      (s.Scalar() == section || (K == 4 && s.Scalar() == std::string("Impropers")));
    if (!fits) {
      error(s, path + ".section",
            fmt::format("{}.section: '{}' is not a section of {}-particle terms (expected {})",
                        path, shown(s), K, sections_of(K)));
      return std::nullopt;
    }
    section = s.Scalar();
  }
  const auto terms = std::find_if(t.sections.begin(), t.sections.end(),
                                  [&](const auto& x) { return x.section == section; });
  if (terms == t.sections.end() || terms->particles.empty()) {
    error(n["file"], path + ".file",
          fmt::format("{}.file: '{}' has no {} (expected a data file with a {} section)", path,
                      file->filename().string(), section, section));
    return std::nullopt;
  }
  const auto selected = selected_types(n, path, *terms, file->filename().string());
  if (!selected) return std::nullopt;
  std::vector<std::array<Index, K>> out;
  std::vector<long long> types;
  for (std::size_t s = 0; s < terms->particles.size(); ++s) {
    if (!selected->empty() && selected->count(terms->type[s]) == 0) continue;
    std::array<Index, K> term{};
    for (std::size_t a = 0; a < K; ++a) {
      term[a] = t.first + static_cast<Index>(terms->particles[s][a]);
    }
    out.push_back(term);
    types.push_back(terms->type[s]);
  }
  if (std::find(t.used.begin(), t.used.end(), section) == t.used.end()) t.used.push_back(section);
  data_types_ = DataTypes{path.substr(path.rfind('.') + 1), section, file->filename().string(),
                          std::move(types)};
  return out;
}

// The mapping's `types: [t, ...]` (LAMMPS's numbers), each a type some
// term of the section has; empty: every term.
std::optional<std::set<long long>> Loader::selected_types(
    const YAML::Node& n, const std::string& path, const import_files::Imported::Terms& terms,
    const std::string& file) {
  std::set<long long> out;
  const YAML::Node list = n["types"];
  if (!list.IsDefined()) return out;
  const std::set<long long> present(terms.type.begin(), terms.type.end());
  const std::string expected = fmt::format("expected a list of the LAMMPS types of its {}: {}",
                                           terms.section, fmt::join(present, ", "));
  if (!list.IsSequence() || list.size() == 0) {
    error(list, path + ".types",
          fmt::format("{}.types: '{}' is not a list of types ({})", path, shown(list), expected));
    return std::nullopt;
  }
  for (std::size_t k = 0; k < list.size(); ++k) {
    long long t = 0;
    if (!list[k].IsScalar() || !YAML::convert<long long>::decode(list[k], t) ||
        present.count(t) == 0) {
      error(list[k], path + ".types",
            fmt::format("{}.types[{}]: '{}' is not a type of the {} of '{}' ({})", path, k,
                        shown(list[k]), terms.section, file, expected));
      return std::nullopt;
    }
    out.insert(t);
  }
  return out;
}

template std::optional<std::vector<std::array<Index, 2>>> Loader::read_data_terms<2>(
    const YAML::Node&, const std::string&);
template std::optional<std::vector<std::array<Index, 3>>> Loader::read_data_terms<3>(
    const YAML::Node&, const std::string&);
template std::optional<std::vector<std::array<Index, 4>>> Loader::read_data_terms<4>(
    const YAML::Node&, const std::string&);

// The term list just read came from a data file: the plugin's `types` are
// the file's (a bonded force), or the plugin takes none and the file's
// terms must all be of one type (a constraint).
void Loader::apply_data_types(const YAML::Node& map, const std::string& path,
                              const std::vector<ParamSpec>& specs, Params& given) {
  const DataTypes d = std::move(*data_types_);
  data_types_.reset();
  const bool typed = std::any_of(specs.begin(), specs.end(), [](const ParamSpec& s) {
    return s.name == "types" && s.type == ParamType::IntegerList;
  });
  if (typed) {
    if (const YAML::Node t = map["types"]; t.IsDefined() && !t.IsNull()) {
      error(t, path + ".types",
            fmt::format("{}.types: is given beside {} from '{}' (expected no types: the file "
                        "gives each term its type, LAMMPS type t being term type t - 1)",
                        path, d.key, d.file));
      return;
    }
    IntegerValues types;
    types.reserve(d.type.size());
    for (const long long t : d.type) types.push_back(t - 1);
    given.set("types", ParamValue(std::move(types)));
    return;
  }
  const std::set<long long> distinct(d.type.begin(), d.type.end());
  if (distinct.size() > 1) {
    error(map[d.key], path + "." + d.key,
          fmt::format("{}.{}: the {} of '{}' are of {} and this plugin takes no types (expected "
                      "terms of one type)",
                      path, d.key, d.section, d.file,
                      count_of(static_cast<long long>(distinct.size()), "type")));
  }
}

void Loader::warn_unused_topology() {
  for (const auto& [key, t] : topology_) {
    std::vector<import_files::Imported::Unread> unread;
    for (const auto& u : t.unread) {
      if (std::find(t.used.begin(), t.used.end(), u.section) == t.used.end()) unread.push_back(u);
    }
    if (!unread.empty()) warn_unread(t.shown, unread);
  }
}

}  // namespace pdyn::loading
