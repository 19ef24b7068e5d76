// `pdyn convert` (issue 44 item 6): LAMMPS input scripts converted and run.
// The Kremer-Grest melt (special_bonds fene, fene bonds, WCA pairs, read
// from its data file) and rigid trimers (fix rattle b 1 a 1, harmonic
// bond and angle coefficients, LAMMPS's default special bonds) follow
// LAMMPS's thermo to 1e-10 over 200 steps, as converted with no edit; the
// script's variables and continued lines are LAMMPS's; and each thing the
// converter does not know is refused at its word with the exact message.
#include "pdyn/host/convert.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdlib>
#include <map>
#include <sstream>

#include "host/resume_support.hpp"
#include "support/lammps_thermo.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;

// Converts tests/scenes/FOLDER/INPUT beside a copy of its data file, runs
// the scene, and compares its energy file with LAMMPS's thermo there.
void ExpectConvertedRunFollowsLammps(const std::string& folder, const std::string& input,
                                     const std::string& data, double pressure_scale,
                                     const std::string& reference, double tolerance = 1e-10) {
  const fs::path dir = test::temp_dir("convert-" + folder);
  for (const auto& f : {input, data}) {
    fs::copy_file(test::source_path("tests/scenes/" + folder + "/" + f), dir / f);
  }
  const auto converted = test::pdyn_in(dir, {"convert", input, "-o", "scene.yaml"});
  ASSERT_EQ(converted.status, 0) << converted.err;
  const auto run = test::pdyn_in(dir, {"run", "scene.yaml", "-q"});
  ASSERT_EQ(run.status, 0) << run.err << test::read_bytes(dir / "scene.yaml");
  // The scripts ask for thermo_style custom step temp press pe ke etotal,
  // norm no: LAMMPS's names in the header.
  auto ours = test::csv_columns(dir / (input + "-thermo.csv"));
  for (const auto& [lammps, pdyn] : {std::pair<std::string, std::string>{"Step", "step"},
                                     {"Temp", "kT"},
                                     {"Press", "pressure"},
                                     {"PotEng", "potential"},
                                     {"KinEng", "kinetic"},
                                     {"TotEng", "total"}}) {
    ASSERT_EQ(ours.count(lammps), 1u) << lammps << "\n" << test::read_bytes(dir / "scene.yaml");
    ours[pdyn] = ours[lammps];
  }
  test::expect_thermo_columns(folder, ours, tolerance, pressure_scale, reference);
}

// A LAMMPS input script of tests/scenes/FOLDER, converted beside copies of
// the files it reads and run; every column of its thermo, by LAMMPS's
// names, against REFERENCE (LAMMPS's log at 17 digits: `bash
// bench/convert_vs_lammps.sh`) at each thermo step the run reaches.
struct LammpsScript {
  std::string folder, input, reference, header;
  std::vector<std::string> files{};         // read by the script
  std::vector<std::string> convert_args{};  // after `convert INPUT`
  std::vector<std::string> run_args{};      // after `run scene.yaml`
  double tolerance = 1e-10;
};

// Returns the folder it ran in.
fs::path ExpectScriptFollowsLammps(const LammpsScript& c) {
  const fs::path dir = test::temp_dir("convert-" + c.input);
  for (const auto& f : c.files)
    fs::copy_file(test::source_path("tests/scenes/" + c.folder + "/" + f), dir / f);
  fs::copy_file(test::source_path("tests/scenes/" + c.folder + "/" + c.input), dir / c.input);
  std::vector<std::string> convert{"convert", c.input};
  convert.insert(convert.end(), c.convert_args.begin(), c.convert_args.end());
  convert.insert(convert.end(), {"-o", "scene.yaml"});
  const auto converted = test::pdyn_in(dir, convert);
  EXPECT_EQ(converted.status, 0) << converted.err;
  std::vector<std::string> run_args{"run", "scene.yaml", "-q"};
  run_args.insert(run_args.end(), c.run_args.begin(), c.run_args.end());
  const auto run = test::pdyn_in(dir, run_args);
  EXPECT_EQ(run.status, 0) << run.err;
  const std::string ours = test::read_bytes(dir / (c.input + "-thermo.csv"));
  EXPECT_EQ(ours.substr(0, ours.find('\n')), c.header);
  auto mine = test::csv_columns(dir / (c.input + "-thermo.csv"));
  auto lammps =
      test::csv_columns(test::source_path("tests/scenes/" + c.folder + "/" + c.reference));
  const std::size_t steps = mine["Step"].size();
  EXPECT_TRUE(steps > 0 && steps <= lammps["Step"].size() &&
              std::equal(mine["Step"].begin(), mine["Step"].end(), lammps["Step"].begin()))
      << "steps " << ours;
  if (steps == 0 || steps > lammps["Step"].size()) return dir;
  for (const auto& [name, values] : lammps) {
    if (name == "Step") continue;
    double worst = 0.0;
    for (std::size_t s = 0; s < steps; ++s) {
      const double a = mine[name].at(s), b = values[s];
      EXPECT_LE(std::abs(a - b), c.tolerance * std::abs(b))
          << name << " at step " << lammps["Step"][s];
      if (b != 0.0) worst = std::max(worst, std::abs(a - b) / std::abs(b));
    }
    std::cout << c.input << ": " << name << " vs LAMMPS: worst relative difference " << worst
              << " over " << steps << " thermo steps\n";
  }
  return dir;
}

// LAMMPS's 3-d Lennard-Jones melt as its examples ship it (in.melt of the
// melt example, Debian 12's lammps-examples): an fcc lattice, velocity create ... loop
// geom, neigh_modify every 20 delay 0 check no (LAMMPS then misses pairs,
// 4e-5 in the temperature at step 20 against check yes, and pdyn misses the
// same ones), and the default thermo: Step Temp E_pair E_mol TotEng Press
// per atom. Every column at every thermo step, by LAMMPS's names
// (melt.thermo: `bash bench/convert_vs_lammps.sh`, LAMMPS printing 17 digits).
TEST(Convert, ShippedMeltFollowsLammps) {
  const fs::path dir = ExpectScriptFollowsLammps(
      {"melt", "in.melt", "melt.thermo", "Step,Temp,E_pair,E_mol,TotEng,Press"});
  // With LAMMPS's default schedule (check yes) the run is another run:
  // the test can fail.
  std::string scene = test::read_bytes(dir / "scene.yaml");
  scene.replace(scene.find("every: 20, delay: 0, check: false"), 33,
                "every: 1, delay: 0, check: true");
  test::write_file(dir / "scene.yaml", scene);
  ASSERT_EQ(test::pdyn_in(dir, {"run", "scene.yaml", "-q"}).status, 0);
  const double checked = test::csv_columns(dir / "in.melt-thermo.csv")["Temp"].at(1);
  const auto lammps = test::csv_columns(test::source_path("tests/scenes/melt/melt.thermo"));
  EXPECT_GT(std::abs(checked - lammps.at("Temp").at(1)), 1e-6);
}

// LAMMPS's FENE bead-spring benchmark as its COUPLE/multiple example ships
// it (Debian 12's lammps-examples; in.chain with lmp -var t 1.0): 32,000
// beads in 320 chains read from data.chain (Atoms without a style comment,
// atom_style bond), bond_style fene, special_bonds fene, WCA pairs,
// neigh_modify every 1 delay 1, and fix langevin. The bath's numbers are
// LAMMPS's: RANMAR drawn in the order of LAMMPS's atom sort, the forces at
// v_half as fix nve evaluates them. The run is chaotic (a rounding
// difference grows tenfold in about 50 steps; LAMMPS on 1 and 2 ranks
// differs by 5e-7 at step 500), so the 1e-8 holds to step 300: 4
// thermo steps, about 6e-11 at the worst.
TEST(Convert, ShippedFeneChainWithLangevinFollowsLammps) {
  const fs::path dir = ExpectScriptFollowsLammps({"chain",
                                                  "in.chain",
                                                  "chain.thermo",
                                                  "Step,Temp,E_pair,E_mol,TotEng,Press",
                                                  {"data.chain"},
                                                  {"--var", "t", "1.0"},
                                                  {"--steps", "300"},
                                                  1e-8});
  const std::string scene = test::read_bytes(dir / "scene.yaml");
  for (const char* line :
       {"  solver: { type: verlet, velocity_forces: half_step }  # fix nve\n",
        "  box: { file: data.chain, format: lammps_data, atom_style: bond }\n",
        "  - { type: langevin, kT: 1, damp: 1, seed: 904297, generator: lammps, lammps_sort_bin: "
        "0.76 }\n"}) {
    EXPECT_NE(scene.find(line), std::string::npos) << line << "\n" << scene;
  }
}

// The melt under fix npt iso (LAMMPS's defaults): nose_hoover's barostat,
// step for step, the volume included.
TEST(Convert, MeltUnderNptFollowsLammps) {
  const fs::path dir = ExpectScriptFollowsLammps(
      {"melt", "in.npt", "npt.thermo", "Step,Temp,Press,PotEng,KinEng,TotEng,Volume"});
  EXPECT_NE(test::read_bytes(dir / "scene.yaml")
                .find("  solver: { type: nose_hoover, kT: 1.5, tdamp: 0.5, chain: 3, pressure: 1, "
                      "pdamp: 5, pchain: 3 }  # fix npt\n"),
            std::string::npos)
      << test::read_bytes(dir / "scene.yaml");
}

// The atoms of lattice, region, create_box, create_atoms and mass, and the
// velocities of velocity create with each loop style (gaussian, momentum
// removed), written to the data file beside the scene: bit for bit LAMMPS's
// write_data (tests/scenes/melt/make_velocities.lmp).
std::map<long, std::array<double, 3>> DataSection(const fs::path& file, const std::string& name,
                                                  std::size_t first) {
  std::map<long, std::array<double, 3>> rows;
  std::istringstream in(test::read_bytes(file));
  std::string line;
  bool inside = false;
  while (std::getline(in, line)) {
    if (line.rfind(name, 0) == 0) {
      inside = true;
      std::getline(in, line);  // the blank line after the header
      continue;
    }
    if (!inside) continue;
    if (line.empty()) break;
    std::istringstream row(line);
    std::vector<std::string> words;
    for (std::string w; row >> w;) words.push_back(w);
    rows[std::stol(words.at(0))] = {std::strtod(words.at(first).c_str(), nullptr),
                                    std::strtod(words.at(first + 1).c_str(), nullptr),
                                    std::strtod(words.at(first + 2).c_str(), nullptr)};
  }
  return rows;
}

TEST(Convert, LatticeAndVelocitiesAreLammpsBitForBit) {
  for (const std::string loop : {"all", "local", "geom"}) {
    const fs::path dir = test::temp_dir("convert-velocities-" + loop);
    test::write_file(dir / "in.v",
                     "units lj\natom_style atomic\nlattice bcc 0.5\nregion box block 0 4 0 4 0 4\n"
                     "region left block 0 2 0 4 0 4\n"
                     "region right block 2.25 4 0 4 0 4 units lattice\ncreate_box 2 box\n"
                     "create_atoms 1 region left\ncreate_atoms 2 region right\nmass 1 1.0\n"
                     "mass 2 3.0\nvelocity all create 1.5 4928 dist gaussian loop " +
                         loop +
                         " mom yes\npair_style lj/cut 2.5\npair_coeff * * 1.0 1.0\n"
                         "fix 1 all nve\nrun 0\n");
    const auto converted = test::pdyn_in(dir, {"convert", "in.v", "-o", "v.yaml"});
    ASSERT_EQ(converted.status, 0) << converted.err;
    const fs::path lammps = test::source_path("tests/scenes/melt/velocities_" + loop + ".data");
    const auto atoms = DataSection(dir / "v.data", "Atoms", 2);
    EXPECT_EQ(atoms.size(), 128u);
    EXPECT_EQ(atoms, DataSection(lammps, "Atoms", 2)) << loop;
    EXPECT_EQ(DataSection(dir / "v.data", "Velocities", 1), DataSection(lammps, "Velocities", 1))
        << loop;
  }
}

TEST(Convert, KremerGrestInputFollowsLammps) {
  ExpectConvertedRunFollowsLammps("special", "in.kg", "kg_start.data", 0.8, "kg.thermo");
}

// Harmonic bonds and angles with OPLS dihedrals; cosine/squared angles with
// harmonic dihedrals; harmonic impropers: LAMMPS's bonded styles from their
// coeff commands (the reference runs of tests/scenes/molecular).
TEST(Convert, BondedStylesInputsFollowLammps) {
  // OPLS: 2.6e-10 against LAMMPS, as the scene written by hand (data_topology_test.cpp).
  ExpectConvertedRunFollowsLammps("molecular", "in.molecular", "molecular_start.data", 0.2,
                                  "reference.thermo", 1e-8);
  ExpectConvertedRunFollowsLammps("molecular", "in.cosine", "cosine_start.data", 0.2,
                                  "cosine.thermo");
  ExpectConvertedRunFollowsLammps("molecular", "in.improper", "improper_start.data", 0.2,
                                  "improper.thermo");
}

TEST(Convert, RattleInputFollowsLammps) {
  ExpectConvertedRunFollowsLammps("trimers", "in.trimers", "trimers_start.data", 0.3,
                                  "reference.thermo");
}

// The script as LAMMPS reads it: `${name}` and `$x`, `&` continuing a
// line, `#` comments.
TEST(Convert, VariablesAndContinuedLinesAreLammps) {
  const std::string scene = convert_lammps_input(
      "variable steps index 50\nvariable c equal 2.5\n"
      "units lj   # reduced units\natom_style atomic\npair_style lj/cut ${c}\n"
      "read_data melt.data\npair_coeff * * &\n  1.0 1.0\nfix 1 all nve\nthermo 10\nrun ${steps}\n",
      "in.melt");
  EXPECT_NE(scene.find("steps: 50\n"), std::string::npos) << scene;
  EXPECT_NE(scene.find("{ type: lennard_jones, cutoff: 2.5, skin: 0.3, shift: false, epsilon: 1, "
                       "sigma: 1 }"),
            std::string::npos)
      << scene;
  EXPECT_EQ(scene.find("special_bonds"), std::string::npos);  // no bonds, no special bonds
}

// fix nvt is nose_hoover, which follows LAMMPS's fix nvt step for step
// (docs/solvers.md), with LAMMPS's chain length unless tchain says.
TEST(Convert, FixNvtIsNoseHoover) {
  const std::string scene = convert_lammps_input(
      "units lj\natom_style atomic\npair_style lj/cut 2.5\nread_data melt.data\n"
      "pair_coeff 1 1 1.0 1.0\nfix 1 all nvt temp 1.5 1.5 0.5 tchain 5\nrun 100\n",
      "in.nvt");
  EXPECT_NE(
      scene.find("  solver: { type: nose_hoover, kT: 1.5, tdamp: 0.5, chain: 5 }  # fix nvt\n"),
      std::string::npos)
      << scene;
  // One atom type: its coefficients, without the per-type table.
  EXPECT_NE(scene.find("{ type: lennard_jones, cutoff: 2.5, skin: 0.3, shift: false, epsilon: 1, "
                       "sigma: 1 }"),
            std::string::npos)
      << scene;
}

// LAMMPS's own bead-spring benchmark script (in.chain in the bench folder
// of LAMMPS's sources, not in Debian's package): the old form of
// special_bonds (three bare weights) and fix langevin (DAMP 10). The
// COUPLE/multiple example's copy of it runs above.
TEST(Convert, LammpsChainBenchmarkScriptConverts) {
  const std::string scene = convert_lammps_input(
      "# FENE beadspring benchmark\n\nunits\t\tlj\natom_style\tbond\n"
      "special_bonds   0.0 1.0 1.0\n\nread_data\tdata.chain\n\nneighbor\t0.4 bin\n"
      "neigh_modify\tevery 1 delay 1\n\nbond_style      fene\nbond_coeff\t1 30.0 1.5 1.0 1.0\n\n"
      "pair_style\tlj/cut 1.12\npair_modify\tshift yes\npair_coeff\t1 1 1.0 1.0 1.12\n\n"
      "fix\t\t1 all nve\nfix\t\t2 all langevin 1.0 1.0 10.0 904297\n\nthermo          100\n"
      "timestep\t0.012\n\nrun\t\t100\n",
      "in.chain");
  for (const char* entry :
       {"  dt: 0.012\n  steps: 100\n", "special_bonds: { lj: [0, 1, 1] }",
        "{ type: lennard_jones, cutoff: 1.12, skin: 0.4, shift: true, epsilon: 1, sigma: 1 }",
        "{ type: fene, pairs: { file: data.chain, types: [1] }, k: [30], r0: [1.5], epsilon: [1], "
        "sigma: [1] }",
        "{ type: langevin, kT: 1, damp: 10, seed: 904297, generator: lammps, lammps_sort_bin: "
        "0.76 }",
        "particles:\n  - { file: data.chain, format: lammps_data, atom_style: bond }\n",
        "{ type: energy, path: in.chain-thermo.csv, every: 100, columns: [step, kT, pair, "
        "bonded, total, pressure], header: lammps, per_particle: true }",
        "neighbor: { every: 1, delay: 1, check: true }  # neigh_modify\n"}) {
    EXPECT_NE(scene.find(entry), std::string::npos) << entry << "\n" << scene;
  }
}

// read_data names its file relative to lmp's working directory: a scene
// written to another folder names it from there, and runs.
TEST(Convert, ReadDataIsFoundFromASceneWrittenElsewhere) {
  const fs::path dir = test::temp_dir("convert-elsewhere");
  fs::copy_file(test::source_path("tests/scenes/thermo/thermo_start.data"), dir / "start.data");
  test::write_file(dir / "in.x",
                   "units lj\natom_style atomic\npair_style lj/cut 2.5\nread_data start.data\n"
                   "pair_coeff 1 1 1.0 1.0\nfix 1 all nve\nrun 10\n");
  fs::create_directories(dir / "scenes");
  const auto converted = test::pdyn_in(dir, {"convert", "in.x", "-o", "scenes/x.yaml"});
  ASSERT_EQ(converted.status, 0) << converted.err;
  const std::string scene = test::read_bytes(dir / "scenes/x.yaml");
  EXPECT_NE(
      scene.find("  box: { file: ../start.data, atom_style: atomic }\nparticles:\n  - { file: "
                 "../start.data, atom_style: atomic }\n"),
      std::string::npos)
      << scene;
  const auto run = test::pdyn_in(dir, {"run", "scenes/x.yaml", "-q"});
  EXPECT_EQ(run.status, 0) << run.err;
}

std::string ConvertProblems(const std::string& script) {
  try {
    convert_lammps_input(script, "in.test");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(converted)";
}

TEST(Convert, WhatItDoesNotKnowIsRefusedAtTheWord) {
  const std::string tail = "read_data x.data\nfix 1 all nve\nrun 10\n";
  EXPECT_EQ(ConvertProblems("units real\n" + tail),
            "in.test:1:7: units real: not converted yet (supported: lj)");
  EXPECT_EQ(
      ConvertProblems("pair_style lj/cut/coul/long 10.0\n" + tail),
      "in.test:1:12: pair_style lj/cut/coul/long: not converted yet (supported: lj/cut, zero)");
  EXPECT_EQ(ConvertProblems("fix 2 all nph iso 1 1 1\n" + tail),
            "in.test:1:11: fix nph: not converted yet (supported: nve, nvt, npt, langevin, rattle, "
            "shake)");
  EXPECT_EQ(ConvertProblems("fix 2 all npt temp 1 1 0.1 aniso 1 1 1\n" + tail),
            "in.test:1:28: fix npt: 'aniso' is not converted yet (supported: iso; pdyn's "
            "barostat is isotropic)");
  EXPECT_EQ(ConvertProblems("fix 2 all npt temp 1 1 0.1 iso 1 2 1\n" + tail),
            "in.test:1:34: fix npt: a ramped pressure is not converted yet (expected PSTOP = "
            "PSTART)");
  EXPECT_EQ(ConvertProblems("run ${n}\n" + tail),
            "in.test:1:5: variable 'n' is not defined (expected a `variable n "
            "index|equal|string VALUE` before it, or pdyn convert --var n VALUE as lmp -var)\n"
            "in.test:1:1: run: 0 arguments (expected run N)");
  EXPECT_EQ(ConvertProblems("timestep 0.005\n  dump 1 all atom 50 dump.melt\n" + tail),
            "in.test:2:3: 'dump' is not a command pdyn convert knows (supported: units, "
            "atom_style, boundary, variable, lattice, region, create_box, create_atoms, mass, "
            "velocity, special_bonds, read_data, pair_style, pair_coeff, "
            "pair_modify, bond_style, bond_coeff, angle_style, angle_coeff, dihedral_style, "
            "dihedral_coeff, improper_style, improper_coeff, neighbor, neigh_modify, "
            "comm_modify, timestep, fix nve, fix nvt, fix npt, fix langevin, fix rattle, fix "
            "shake, thermo, thermo_style, thermo_modify, run)");
  EXPECT_EQ(ConvertProblems("atom_style full\n"),
            "in.test:1:12: atom_style full: not converted (supported: atomic, bond, angle, "
            "molecular; pdyn has no charges)\n"
            "in.test: no read_data or create_atoms (expected the particles from a data file or a "
            "lattice)\n"
            "in.test: no run command (expected run N)\n"
            "in.test: no fix nve, nvt or npt, or more than one (expected one of fix ID all nve, "
            "nvt, npt)");
}

// A bonded style without its coefficients would drop its terms from the
// scene, and a rod without its length crashed the converter: both refused.
TEST(Convert, MissingCoefficientsAreRefusedNotDropped) {
  const std::string head = "units lj\natom_style bond\nread_data x.data\nfix 1 all nve\nrun 10\n";
  EXPECT_EQ(ConvertProblems(head + "bond_style fene\n"),
            "in.test:6:12: bond_style fene: no bond_coeff (expected one per bond type; pdyn "
            "convert does not read a data file's Coeffs sections yet)");
  EXPECT_EQ(ConvertProblems(head + "bond_style harmonic\nbond_coeff 1 100 1\nbond_coeff 3 100 1\n"),
            "in.test:6:12: bond_style harmonic: no bond_coeff for type 2 (expected coefficients "
            "for every type 1..3)");
  EXPECT_EQ(ConvertProblems(head + "bond_style harmonic\nbond_coeff 0 100 1\n"),
            "in.test:7:12: bond_coeff: type 0 (expected a whole type number from 1)\n"
            "in.test:6:12: bond_style harmonic: no bond_coeff (expected one per bond type; pdyn "
            "convert does not read a data file's Coeffs sections yet)");
  EXPECT_EQ(ConvertProblems(head + "fix 2 all rattle 1e-4 20 0 b 1\n"),
            "in.test:6:11: fix rattle: bond type 1 has no bond_coeff (expected its r0 to hold it "
            "at)");
  EXPECT_EQ(ConvertProblems(head + "bond_style harmonic\nbond_coeff 1 100 1\nangle_style harmonic\n"
                                   "angle_coeff 1 50 109.47\nfix 2 all rattle 1e-4 20 0 a 1\n"),
            "in.test:10:11: fix rattle: angles without bonds (expected b TYPES too: SHAKE holds "
            "an angle's two bonds with it)");
}

}  // namespace
}  // namespace pdyn
