// What the host's readers of text files share (side_files.cpp for CSV,
// import_lammps_data.cpp, import_lammps_dump.cpp and import_xyz.cpp for
// other programs' files): the file in memory, fields located by line and
// column, numbers parsed exactly with std::from_chars (C locale, exact round
// trip), and the file's problems, capped at kMaxProblemsPerFile.
#pragma once

#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pdyn/host/scene.hpp"
#include "pdyn/host/side_files.hpp"

namespace pdyn::text_file {

using side_files::kMaxProblemsPerFile;

// The problems of one file, capped.
class Problems {
 public:
  Problems(std::string shown, std::vector<Diagnostic>& out) : shown_(std::move(shown)), out_(out) {}
  void add(std::size_t line, std::size_t column, std::string message) {
    if (count_++ < kMaxProblemsPerFile) {
      out_.push_back({fmt::format("{}:{}:{}", shown_, line, column), std::move(message)});
    }
  }
  void add_file(std::string message) {
    out_.push_back({shown_, std::move(message)});
    ++count_;
  }
  bool any() const { return count_ > 0; }
  void finish() {
    if (count_ > kMaxProblemsPerFile) {
      out_.push_back({shown_, fmt::format("{} more problems not shown (expected a valid file)",
                                          count_ - kMaxProblemsPerFile)});
    }
  }

 private:
  std::string shown_;
  std::vector<Diagnostic>& out_;
  std::size_t count_ = 0;
};

inline std::optional<std::string> slurp(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return std::nullopt;
  std::string s;
  in.seekg(0, std::ios::end);
  s.resize(static_cast<std::size_t>(in.tellg()));
  in.seekg(0);
  in.read(s.data(), static_cast<std::streamsize>(s.size()));
  return s;
}

struct Field {
  std::string_view text;  // without surrounding blanks
  std::size_t column;     // 1-based character column of the field's start
};

inline std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

inline std::string quoted(std::string_view s) {
  return s.empty() ? std::string("an empty field") : fmt::format("'{}'", s);
}

// The number `text` is, all of it, or nothing. from_chars refuses a leading
// '+', which C's strtod (and so LAMMPS, Python) accepts: it is skipped.
template <class Number>
std::optional<Number> to_number(std::string_view text) {
  Number x{};
  const char* b = text.data();
  const char* e = b + text.size();
  if (!text.empty() && *b == '+') ++b;
  const auto [end, ec] = std::from_chars(b, e, x);
  if (ec != std::errc() || end != e || b == e) return std::nullopt;
  return x;
}

// A whole number >= `least`, or a located problem naming the field.
inline std::optional<long long> parse_whole(const Field& f, std::size_t line, std::string_view name,
                                            Problems& problems, long long least) {
  const auto n = to_number<long long>(f.text);
  if (!n || *n < least) {
    problems.add(line, f.column,
                 fmt::format("{}: {} is not a whole number >= {} (expected one)", name,
                             quoted(f.text), least));
    return std::nullopt;
  }
  return n;
}

inline std::optional<double> parse_real(const Field& f, std::size_t line, std::string_view name,
                                        Problems& problems) {
  const auto x = to_number<double>(f.text);
  if (!x) {
    problems.add(line, f.column,
                 fmt::format("{}: {} is not a number (expected a real number, e.g. 0.25)", name,
                             quoted(f.text)));
    return std::nullopt;
  }
  if (!std::isfinite(*x)) {
    problems.add(line, f.column,
                 fmt::format("{}: {} is not finite (expected a finite number)", name, f.text));
    return std::nullopt;
  }
  return x;
}

// One line of a file whose fields are separated by blanks (LAMMPS, XYZ).
struct Line {
  std::size_t number = 0;     // 1-based
  std::string_view raw;       // the whole line, without its '\n'
  std::vector<Field> fields;  // split at blanks, before any '#' when comments count
};

// The blank-separated fields of `s`, columns counted from 1 at s's start.
inline std::vector<Field> split_blanks(std::string_view s) {
  std::vector<Field> out;
  for (std::size_t k = 0; k < s.size();) {
    while (k < s.size() && std::isspace(static_cast<unsigned char>(s[k]))) ++k;
    const std::size_t start = k;
    while (k < s.size() && !std::isspace(static_cast<unsigned char>(s[k]))) ++k;
    if (k > start) out.push_back({s.substr(start, k - start), start + 1});
  }
  return out;
}

// The lines of `text`, each split at blanks; with `comments`, a '#' starts
// a comment that runs to the end of the line (LAMMPS data files).
inline std::vector<Line> split_lines(const std::string& text, bool comments) {
  std::vector<Line> out;
  std::size_t pos = 0, number = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    const std::string_view raw(text.data() + pos, end - pos);
    out.push_back({++number, raw, split_blanks(comments ? raw.substr(0, raw.find('#')) : raw)});
    pos = end + 1;
  }
  return out;
}

}  // namespace pdyn::text_file
