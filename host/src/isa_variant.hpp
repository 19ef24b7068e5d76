// Run-time ISA dispatch of plugin libraries (issue 46 item 3).
//
// The hot shipped plugins (the spring, pair and integrator loops) are also
// built for the x86-64 micro-architecture levels x86-64-v3 (AVX2) and
// x86-64-v4 (AVX-512) into isa/<level>/ beside the baseline library, as
// glibc's loader does with glibc-hwcaps/<level>/ for libraries it finds on
// a search path. Discovery loads the best variant this CPU runs. Every
// variant is compiled without fused multiply-adds (-ffp-contract=off for
// GCC's code, -mno-fma for Eigen's intrinsics; plugins/CMakeLists.txt) and
// GCC reorders no floating-point sums without -ffast-math, so a wider
// vector register changes how many elements an instruction takes, not one
// bit of a result: the isa.outputs_identical tests run scenes under each
// level and compare their output files byte for byte.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace pdyn::isa {

/// The levels with variants, best first.
inline const std::vector<std::string>& levels() {
  static const std::vector<std::string> all = {"x86-64-v4", "x86-64-v3"};
  return all;
}

/// The levels this process loads variants of, best first: those the CPU
/// (and the operating system's saved vector state) supports, none above
/// $PDYN_ISA when it is set ("baseline": none). Throws pdyn::Error for a
/// $PDYN_ISA that names no level.
std::vector<std::string> usable_levels();

/// `library`'s variant for the best usable level (FOLDER/isa/LEVEL/NAME)
/// if one is there, else `library` itself.
std::filesystem::path best_variant(const std::filesystem::path& library,
                                   const std::vector<std::string>& usable);

/// The folder `library` was discovered in: its own, or for a variant
/// (FOLDER/isa/LEVEL/NAME) FOLDER.
std::filesystem::path home_folder(const std::filesystem::path& library);

}  // namespace pdyn::isa
