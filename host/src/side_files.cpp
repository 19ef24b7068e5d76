// CSV side files (see side_files.hpp). One pass over the file held in
// memory, fields split at commas, numbers parsed with std::from_chars: no
// streams, no locale, no allocation per field.
#include "pdyn/host/side_files.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string_view>

#include "pdyn/text.hpp"
#include "text_file.hpp"

namespace pdyn::side_files {

namespace {

using text_file::Field;
using text_file::parse_real;
using text_file::Problems;
using text_file::quoted;
using text_file::slurp;
using text_file::trim;

// Splits `line` at commas into `fields` (reused, so no allocation per line).
void split(std::string_view line, std::vector<Field>& fields) {
  fields.clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    const std::size_t end = comma == std::string_view::npos ? line.size() : comma;
    std::string_view raw = line.substr(start, end - start);
    std::size_t lead = 0;
    while (lead < raw.size() && (raw[lead] == ' ' || raw[lead] == '\t')) ++lead;
    fields.push_back({trim(raw), start + lead + 1});
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
}

// Calls row(line_number, fields) for every non-empty line after the header,
// after header(fields) accepted the first line.
template <class Header, class Row>
void for_each_row(const std::string& text, Problems& problems, Header&& header, Row&& row) {
  std::vector<Field> fields;
  std::size_t pos = 0, line = 0;
  bool have_header = false;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    const std::string_view l(text.data() + pos, end - pos);
    pos = end + 1;
    ++line;
    if (trim(l).empty()) continue;
    split(l, fields);
    if (!have_header) {
      if (!header(line, fields)) return;
      have_header = true;
      continue;
    }
    row(line, fields);
  }
  if (!have_header) problems.add(1, 1, "the file is empty (expected a header row, then records)");
}

std::string column_count_message(std::size_t got, std::size_t want, const std::string& header) {
  return fmt::format("has {}, the header has {} (expected {} comma-separated values: {})",
                     count_of(static_cast<long long>(got), "field"), want, want, header);
}

// A particle CSV file read row by row: the header fixes which field holds
// which column; each record is checked and appended to `rows`.
class ParticleCsv {
 public:
  enum Col { X, Y, Z, VX, VY, VZ, MASS, RADIUS, FIXED, TYPE, N_COLS };

  ParticleCsv(Problems& problems, std::size_t estimate) : problems_(problems), estimate_(estimate) {
    at_.fill(-1);
    rows.x.reserve(estimate);
    rows.v.reserve(estimate);
    rows.mass.reserve(estimate);
    rows.fixed.reserve(estimate);
  }

  bool header(std::size_t line, const std::vector<Field>& fields) {
    width_ = fields.size();
    for (std::size_t k = 0; k < fields.size(); ++k) {
      header_text_ += (k ? "," : "") + std::string(fields[k].text);
      int c = 0;
      while (c < N_COLS && fields[k].text != kNames[c]) ++c;
      if (c == N_COLS) {
        problems_.add(line, fields[k].column,
                      fmt::format("unknown column {} (expected x, y, z, vx, vy, vz, mass, fixed, "
                                  "radius, type)",
                                  quoted(fields[k].text)));
      } else if (at_[c] >= 0) {
        problems_.add(
            line, fields[k].column,
            fmt::format("column '{}' appears twice (expected each column once)", kNames[c]));
      } else {
        at_[c] = static_cast<int>(k);
      }
    }
    for (int c : {X, Y, Z, MASS}) {
      if (at_[c] < 0) {
        problems_.add(line, 1,
                      fmt::format("the header has no column '{}' (expected x,y,z[,vx,vy,vz],mass"
                                  "[,fixed][,radius][,type])",
                                  kNames[c]));
      }
    }
    const int velocities = (at_[VX] >= 0) + (at_[VY] >= 0) + (at_[VZ] >= 0);
    if (velocities != 0 && velocities != 3) {
      problems_.add(line, 1, "the header has only some of vx, vy, vz (expected all three or none)");
    }
    if (!problems_.any()) {
      if (at_[RADIUS] >= 0) rows.radius.reserve(estimate_);
      if (at_[TYPE] >= 0) rows.type.reserve(estimate_);
    }
    return !problems_.any();
  }

  void row(std::size_t line, const std::vector<Field>& fields) {
    if (fields.size() != width_) {
      problems_.add(line, fields.back().column + fields.back().text.size(),
                    column_count_message(fields.size(), width_, header_text_));
      return;
    }
    bool ok = true;
    double value[N_COLS] = {};
    for (int c = X; c <= RADIUS; ++c) {
      if (at_[c] < 0) continue;
      const auto x =
          parse_real(fields[static_cast<std::size_t>(at_[c])], line, kNames[c], problems_);
      ok = ok && x;
      if (x) value[c] = *x;
    }
    if (ok && !(value[MASS] > 0.0)) {
      problems_.add(line, fields[static_cast<std::size_t>(at_[MASS])].column,
                    fmt::format("mass: {} is not positive (expected a mass > 0 kg)",
                                fields[static_cast<std::size_t>(at_[MASS])].text));
      ok = false;
    }
    if (at_[RADIUS] >= 0 && ok && !(value[RADIUS] >= 0.0)) {
      const Field& f = fields[static_cast<std::size_t>(at_[RADIUS])];
      problems_.add(line, f.column,
                    fmt::format("radius: {} is negative (expected a radius >= 0 m)", f.text));
      ok = false;
    }
    std::int32_t type = 0;
    if (at_[TYPE] >= 0)
      ok = read_type(fields[static_cast<std::size_t>(at_[TYPE])], line, type) && ok;
    std::uint8_t fixed = 0;
    if (at_[FIXED] >= 0) {
      ok = read_fixed(fields[static_cast<std::size_t>(at_[FIXED])], line, fixed) && ok;
    }
    if (!ok) return;
    rows.x.emplace_back(value[X], value[Y], value[Z]);
    // A nailed particle does not move: its velocity is zeroed on assembly.
    rows.v.emplace_back(value[VX], value[VY], value[VZ]);
    rows.mass.push_back(value[MASS]);
    rows.fixed.push_back(fixed);
    if (at_[RADIUS] >= 0) rows.radius.push_back(value[RADIUS]);
    if (at_[TYPE] >= 0) rows.type.push_back(type);
  }

  ParticleRows rows;

 private:
  static constexpr const char* kNames[N_COLS] = {"x",  "y",    "z",      "vx",    "vy",
                                                 "vz", "mass", "radius", "fixed", "type"};

  bool read_type(const Field& f, std::size_t line, std::int32_t& type) {
    const long long t = text_file::to_number<long long>(f.text).value_or(-1);
    if (t < 0 || t > std::numeric_limits<std::int32_t>::max()) {
      problems_.add(line, f.column,
                    fmt::format("type: {} is not a particle type (expected a whole number in "
                                "[0, {}])",
                                quoted(f.text), std::numeric_limits<std::int32_t>::max()));
      return false;
    }
    type = static_cast<std::int32_t>(t);
    return true;
  }

  bool read_fixed(const Field& f, std::size_t line, std::uint8_t& fixed) {
    if (f.text == "1" || f.text == "true") {
      fixed = 1;
    } else if (!(f.text == "0" || f.text == "false")) {
      problems_.add(
          line, f.column,
          fmt::format("fixed: {} is not a flag (expected 0, 1, true or false)", quoted(f.text)));
      return false;
    }
    return true;
  }

  Problems& problems_;
  std::size_t estimate_;
  std::array<int, N_COLS> at_{};  // field index of each column, -1 if absent
  std::size_t width_ = 0;
  std::string header_text_;
};

}  // namespace

std::optional<ParticleRows> read_particles(const std::filesystem::path& file,
                                           const std::string& shown, std::vector<Diagnostic>& out) {
  Problems problems(shown, out);
  const auto text = slurp(file);
  if (!text) {
    problems.add_file("cannot read the particle file (expected a readable CSV file)");
    return std::nullopt;
  }
  ParticleCsv csv(problems, text->size() / 40);  // typical record length
  for_each_row(
      *text, problems,
      [&](std::size_t line, const std::vector<Field>& fields) { return csv.header(line, fields); },
      [&](std::size_t line, const std::vector<Field>& fields) { csv.row(line, fields); });
  if (problems.any()) {
    problems.finish();
    return std::nullopt;
  }
  if (csv.rows.x.empty()) {
    problems.add_file("the file has a header but no particles (expected at least one record)");
    return std::nullopt;
  }
  return std::move(csv.rows);
}

template <std::size_t K>
std::optional<std::vector<std::array<Index, K>>> read_tuples(const std::filesystem::path& file,
                                                             const std::string& shown,
                                                             Index n_particles,
                                                             std::vector<Diagnostic>& out) {
  Problems problems(shown, out);
  const auto text = slurp(file);
  if (!text) {
    problems.add_file("cannot read the index file (expected a readable CSV file)");
    return std::nullopt;
  }
  static const char* const kNames[4] = {"i", "j", "k", "l"};
  const std::string header_text = K == 2 ? "i,j" : K == 3 ? "i,j,k" : "i,j,k,l";
  std::vector<std::array<Index, K>> tuples;
  tuples.reserve(text->size() / (4 * K));
  auto header = [&](std::size_t line, const std::vector<Field>& fields) {
    bool ok = fields.size() == K;
    for (std::size_t k = 0; ok && k < K; ++k) ok = fields[k].text == kNames[k];
    if (!ok) {
      problems.add(
          line, 1,
          fmt::format("the header is not {} (expected the columns {})", header_text, header_text));
    }
    return ok;
  };
  auto row = [&](std::size_t line, const std::vector<Field>& fields) {
    if (fields.size() != K) {
      problems.add(line, fields.back().column + fields.back().text.size(),
                   column_count_message(fields.size(), K, header_text));
      return;
    }
    std::array<Index, K> t{};
    for (std::size_t k = 0; k < K; ++k) {
      const Field& f = fields[k];
      const auto index = text_file::to_number<long long>(f.text);
      if (!index) {
        problems.add(line, f.column,
                     fmt::format("{}: {} is not a particle index (expected a whole number)",
                                 kNames[k], quoted(f.text)));
        return;
      }
      const long long i = *index;
      if (n_particles >= 0 && (i < 0 || i >= n_particles)) {
        problems.add(line, f.column,
                     fmt::format("{}: particle index {} is out of range (expected 0..{}: the "
                                 "scene has {})",
                                 kNames[k], i, n_particles - 1, count_of(n_particles, "particle")));
        return;
      }
      t[k] = i;
    }
    tuples.push_back(t);
  };
  for_each_row(*text, problems, header, row);
  if (problems.any()) {
    problems.finish();
    return std::nullopt;
  }
  return tuples;
}

template std::optional<std::vector<std::array<Index, 2>>> read_tuples<2>(
    const std::filesystem::path&, const std::string&, Index, std::vector<Diagnostic>&);
template std::optional<std::vector<std::array<Index, 3>>> read_tuples<3>(
    const std::filesystem::path&, const std::string&, Index, std::vector<Diagnostic>&);
template std::optional<std::vector<std::array<Index, 4>>> read_tuples<4>(
    const std::filesystem::path&, const std::string&, Index, std::vector<Diagnostic>&);

void write_particles(const std::filesystem::path& file, const ParticleRows& rows) {
  fmt::memory_buffer buf;
  const bool radius = !rows.radius.empty(), type = !rows.type.empty();
  fmt::format_to(std::back_inserter(buf), "x,y,z,vx,vy,vz,mass,fixed{}{}\n",
                 radius ? ",radius" : "", type ? ",type" : "");
  for (std::size_t i = 0; i < rows.x.size(); ++i) {
    fmt::format_to(std::back_inserter(buf),
                   "{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{}", rows.x[i].x(),
                   rows.x[i].y(), rows.x[i].z(), rows.v[i].x(), rows.v[i].y(), rows.v[i].z(),
                   rows.mass[i], int{rows.fixed[i]});
    if (radius) fmt::format_to(std::back_inserter(buf), ",{:.17g}", rows.radius[i]);
    if (type) fmt::format_to(std::back_inserter(buf), ",{}", rows.type[i]);
    buf.push_back('\n');
  }
  std::ofstream(file, std::ios::binary).write(buf.data(), static_cast<std::streamsize>(buf.size()));
}

void write_pairs(const std::filesystem::path& file, const std::vector<IndexPair>& pairs) {
  fmt::memory_buffer buf;
  fmt::format_to(std::back_inserter(buf), "i,j\n");
  for (const auto& p : pairs) fmt::format_to(std::back_inserter(buf), "{},{}\n", p[0], p[1]);
  std::ofstream(file, std::ios::binary).write(buf.data(), static_cast<std::streamsize>(buf.size()));
}

}  // namespace pdyn::side_files
