// Runs one of tests/scenes' LAMMPS comparisons: the scene continues
// LAMMPS's state (its data file), and its energy file's columns kT,
// pressure, potential, kinetic and total must equal the temp, press, pe,
// ke and etotal that LAMMPS printed at the same steps (the folder's
// reference.thermo, written by its make_reference.lmp).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "host/resume_support.hpp"
#include "support/physics_support.hpp"
#include "support/test_support.hpp"

namespace pdyn::test {

/// Checks the energy file columns `ours` against LAMMPS's thermo
/// tests/scenes/FOLDER/REFERENCE: every column at every thermo step to
/// `tolerance` relative; the pressure, which passes through zero, relative
/// to |press| + `pressure_scale` (Pa: N kT / V, the ideal gas's). Prints
/// the worst difference of each column.
inline void expect_thermo_columns(const std::string& folder,
                                  std::map<std::string, std::vector<double>> ours, double tolerance,
                                  double pressure_scale, const std::string& reference) {
  auto lammps = csv_columns(source_path("tests/scenes/" + folder + "/" + reference));
  EXPECT_FALSE(lammps["step"].empty());
  EXPECT_EQ(ours["step"], lammps["step"]);
  if (ours["step"] != lammps["step"]) return;
  for (const auto& [mine, theirs] : {std::pair<std::string, std::string>{"kT", "temp"},
                                     {"pressure", "press"},
                                     {"potential", "pe"},
                                     {"kinetic", "ke"},
                                     {"total", "etotal"}}) {
    double worst = 0.0;
    for (std::size_t s = 0; s < lammps["step"].size(); ++s) {
      const double a = ours.at(mine).at(s), b = lammps.at(theirs).at(s);
      const double scale = std::abs(b) + (mine == "pressure" ? pressure_scale : 0.0);
      worst = std::max(worst, std::abs(a - b) / scale);
      EXPECT_LE(std::abs(a - b), tolerance * scale)
          << folder << ": " << mine << " at step " << lammps["step"][s] << ": " << Num(a)
          << " against LAMMPS's " << Num(b);
    }
    std::cout << folder << ": " << mine << " vs LAMMPS " << theirs << ": worst relative difference "
              << worst << " over " << lammps["step"].size() << " thermo steps\n";
  }
}

/// Runs `pdyn run SCENE -q` on a copy of tests/scenes/FOLDER's `files`
/// (the scene first) and checks its energy file against LAMMPS's thermo
/// `reference` in the folder (expect_thermo_columns). Returns the energy
/// file's columns.
inline std::map<std::string, std::vector<double>> expect_lammps_thermo(
    const std::string& folder, const std::vector<std::string>& files,
    const std::string& energy_file, double tolerance, double pressure_scale,
    const std::string& reference = "reference.thermo") {
  namespace fs = std::filesystem;
  const fs::path dir = temp_dir("lammps-thermo-" + folder);
  for (const auto& f : files) {
    fs::copy_file(source_path("tests/scenes/" + folder + "/" + f), dir / f);
  }
  const auto run = pdyn_in(dir, {"run", files.front(), "-q"});
  EXPECT_EQ(run.status, 0) << run.err;
  auto ours = csv_columns(dir / energy_file);
  if (run.status == 0) expect_thermo_columns(folder, ours, tolerance, pressure_scale, reference);
  return ours;
}

}  // namespace pdyn::test
