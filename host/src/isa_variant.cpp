// Run-time ISA dispatch of plugin libraries: isa_variant.hpp.
#include "isa_variant.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cstdlib>
#include <string_view>

#include "pdyn/error.hpp"

namespace pdyn::isa {

namespace {

// Whether the CPU runs code built with -march=LEVEL. GCC's
// __builtin_cpu_supports knows the levels (since GCC 12) and checks that the
// operating system saves the vector registers (XGETBV), not only CPUID.
bool cpu_runs(std::string_view level) {
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 12
  __builtin_cpu_init();
  if (level == "x86-64-v4") return __builtin_cpu_supports("x86-64-v4") != 0;
  if (level == "x86-64-v3") return __builtin_cpu_supports("x86-64-v3") != 0;
#else
  (void)level;
#endif
  return false;
}

}  // namespace

std::vector<std::string> usable_levels() {
  const char* cap = std::getenv("PDYN_ISA");
  std::size_t first = 0;  // the best level allowed
  if (cap != nullptr && *cap != '\0') {
    const std::string_view want = cap;
    const auto& all = levels();
    if (want == "baseline") return {};
    first = all.size();
    for (std::size_t k = 0; k < all.size(); ++k) {
      if (all[k] == want) first = k;
    }
    if (first == all.size()) {
      throw Error(fmt::format("PDYN_ISA={}: no such level (expected baseline, {})", want,
                              fmt::join(all, ", ")));
    }
  }
  std::vector<std::string> usable;
  for (std::size_t k = first; k < levels().size(); ++k) {
    if (cpu_runs(levels()[k])) usable.push_back(levels()[k]);
  }
  return usable;
}

std::filesystem::path best_variant(const std::filesystem::path& library,
                                   const std::vector<std::string>& usable) {
  for (const auto& level : usable) {
    auto variant = library.parent_path() / "isa" / level / library.filename();
    std::error_code ec;
    if (std::filesystem::is_regular_file(variant, ec)) return variant;
  }
  return library;
}

std::filesystem::path home_folder(const std::filesystem::path& library) {
  const auto level = library.parent_path();
  if (level.parent_path().filename() == "isa") return level.parent_path().parent_path();
  return library.parent_path();
}

}  // namespace pdyn::isa
