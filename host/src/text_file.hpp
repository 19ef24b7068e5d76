// What the host's readers of text files share (side_files.cpp for CSV,
// import_files.cpp for LAMMPS and extended XYZ): the file in memory, fields
// located by line and column, numbers parsed exactly with std::from_chars,
// and the file's problems, capped at kMaxProblemsPerFile.
#pragma once

#include <fmt/format.h>

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

inline std::optional<double> parse_real(const Field& f, std::size_t line, std::string_view name,
                                        Problems& problems) {
  double x = 0.0;
  const char* b = f.text.data();
  const char* e = b + f.text.size();
  if (!f.text.empty() && *b == '+') ++b;  // from_chars refuses a leading '+'
  const auto [end, ec] = std::from_chars(b, e, x);
  if (ec != std::errc() || end != e || f.text.empty()) {
    problems.add(line, f.column,
                 fmt::format("{}: {} is not a number (expected a real number, e.g. 0.25)", name,
                             quoted(f.text)));
    return std::nullopt;
  }
  if (!std::isfinite(x)) {
    problems.add(line, f.column,
                 fmt::format("{}: {} is not finite (expected a finite number)", name, f.text));
    return std::nullopt;
  }
  return x;
}

}  // namespace pdyn::text_file
