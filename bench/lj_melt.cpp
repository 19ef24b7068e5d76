// The Lennard-Jones melt of LAMMPS's own benchmark (bench/lammps/in.lj: fcc at
// reduced density 0.8442, 32,000 atoms, T = 1.44, lj/cut 2.5 unshifted,
// skin 0.3, dt 0.005, velocity Verlet), run by pdyn from the exact state
// LAMMPS starts from: its write_dump of step 0 (scripts/lammps_compare.sh
// makes it). Prints LAMMPS-style thermo for steps 0 and 100 (temperature,
// potential and total energy per atom) and the time per atom-step.
//
//   pdyn_bench_lj_melt init.dump [--threads N] [--steps S] [--plugins DIR]
#include <fmt/format.h>

#include <chrono>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "pdyn/host/assembly.hpp"
#include "pdyn/host/registry.hpp"
#include "pdyn/host/resolve.hpp"
#include "pdyn/host/stepper.hpp"
#include "pdyn/host/threads.hpp"
#include "pdyn/pair.hpp"
#include "pdyn/parallel.hpp"
#include "pdyn/plugin.hpp"
#include "pdyn/system.hpp"

namespace {

struct Dump {
  pdyn::Domain box;
  pdyn::Matrix3X x, v;
};

// A LAMMPS text dump with columns id x y z vx vy vz, sorted by id.
Dump read_dump(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  Dump d;
  std::string line;
  pdyn::Index n = 0;
  while (std::getline(in, line)) {
    if (line.rfind("ITEM: NUMBER OF ATOMS", 0) == 0) {
      in >> n;
    } else if (line.rfind("ITEM: BOX BOUNDS", 0) == 0) {
      for (int k = 0; k < 3; ++k) in >> d.box.min[k] >> d.box.max[k];
      d.box.periodic = {true, true, true};
    } else if (line.rfind("ITEM: ATOMS", 0) == 0) {
      d.x.resize(3, n);
      d.v.resize(3, n);
      for (pdyn::Index i = 0; i < n; ++i) {
        long id = 0;
        in >> id >> d.x(0, i) >> d.x(1, i) >> d.x(2, i) >> d.v(0, i) >> d.v(1, i) >> d.v(2, i);
        if (id != i + 1) throw std::runtime_error("dump not sorted by id (modify sort id)");
      }
    }
  }
  if (n == 0 || d.x.cols() != n) throw std::runtime_error(path + " holds no atoms");
  return d;
}

std::unique_ptr<pdyn::Force> make_force(const pdyn::PluginRegistry& r, const pdyn::System& sys) {
  const auto& d = *r.find(pdyn::PluginKind::Force, "lennard_jones")->descriptor;
  pdyn::Params given;
  given.set("epsilon", 1.0);
  given.set("sigma", 1.0);
  given.set("cutoff", 2.5);
  given.set("skin", 0.3);
  return d.create_force(pdyn::resolve(d.params, given).params,
                        pdyn::SceneContext{sys.view(), nullptr});
}

void thermo(const pdyn::System& sys, long step) {
  const double n = static_cast<double>(sys.size());
  const double ke = sys.kinetic_energy(), pe = sys.potential_energy();
  // LAMMPS's temperature: 2 KE / (dof k_B), dof = 3N - 3 (momentum removed).
  const double temp = 2.0 * ke / (3.0 * n - 3.0);
  std::cout << fmt::format("{:8} {:.15g} {:.15g} {:.15g}\n", step, temp, pe / n, (ke + pe) / n);
}

// A line "Key:   123 kB" of /proc/self/status, in bytes (0 if absent).
double status_bytes(const std::string& key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(key + ":", 0) == 0) return 1024.0 * std::stod(line.substr(key.size() + 1));
  }
  return 0.0;
}

}  // namespace

// An error ends the benchmark with its message (std::terminate prints it).
// NOLINTNEXTLINE(bugprone-exception-escape)
int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: pdyn_bench_lj_melt init.dump [--threads N] [--steps S] [--plugins DIR]\n";
    return 2;
  }
  int threads = 1;
  long steps = 100;
  std::string plugins = PDYN_PLUGIN_DIR;  // another build's plugins, to compare two versions
  for (int k = 2; k + 1 < argc; k += 2) {
    const std::string opt = argv[k];
    if (opt == "--threads") threads = std::stoi(argv[k + 1]);
    if (opt == "--steps") steps = std::stol(argv[k + 1]);
    if (opt == "--plugins") plugins = argv[k + 1];
  }
  pdyn::set_threads(threads);
  const Dump dump = read_dump(argv[1]);
  pdyn::PluginRegistry registry;
  registry.discover({plugins});

  // Memory of the simulation: the peak resident set's growth from here
  // (the dump and the plugins already loaded), as LAMMPS's "Per MPI rank
  // memory allocation" counts its own arrays.
  const double rss_before = status_bytes("VmRSS");
  pdyn::System sys;
  pdyn::SystemAssembly(sys).set_particles(
      dump.x, dump.v, Eigen::VectorXd::Ones(dump.x.cols()),
      std::vector<std::uint8_t>(static_cast<std::size_t>(dump.x.cols()), 0));
  pdyn::SystemAssembly(sys).set_domain(dump.box);
  pdyn::SystemAssembly(sys).wrap_positions();
  pdyn::SystemAssembly(sys).add_force(make_force(registry, sys), "lennard_jones");
  const auto& sd = *registry.find(pdyn::PluginKind::Solver, "verlet")->descriptor;
  pdyn::Params solver_params;
  solver_params.set("reuse_forces", true);  // LJ depends on positions only: one evaluation per step
  const auto solver = sd.create_solver(pdyn::resolve(sd.params, solver_params).params,
                                       pdyn::SceneContext{sys.view(), nullptr});
  pdyn::Stepper stepper(sys, *solver, "verlet");

  std::cout << "    Step Temp PotEng TotEng\n";
  thermo(sys, 0);
  const double dt = 0.005;
  const auto start = std::chrono::steady_clock::now();
  for (long k = 1; k <= steps; ++k) {
    if (!stepper.step_to(static_cast<double>(k) * dt)) {
      std::cerr << "step " << k << " failed\n";
      return 4;
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  thermo(sys, steps);
  std::cout << fmt::format("force evaluations {}\n", sys.force_evaluations());
  const auto* pair =
      dynamic_cast<const pdyn::PairReference*>(sys.force_objects().front().force.get());
  if (const pdyn::NeighborList* list = pair ? pair->pair_neighbors() : nullptr) {
    std::cout << fmt::format("Neighbor list builds = {}, pairs listed = {}\n", list->builds(),
                             list->pair_count());
  }
  std::cout << fmt::format(
      "Loop time of {:.6g} s on {} threads for {} steps with {} atoms: {:.1f} ns/atom-step\n",
      seconds, threads, steps, sys.size(),
      1e9 * seconds / (static_cast<double>(steps) * static_cast<double>(sys.size())));
  const double bytes = status_bytes("VmHWM") - rss_before;
  std::cout << fmt::format("Memory {:.2f} Mbytes, {:.0f} bytes/atom (peak resident set growth)\n",
                           bytes / (1024.0 * 1024.0), bytes / static_cast<double>(sys.size()));
  return 0;
}
