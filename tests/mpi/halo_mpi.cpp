// The halo exchange under mpirun (issue 43; pdyn/host/halo.hpp): every rank
// holds the same plain system and, beside it, its own decomposed share,
// owned particles and ghosts by global id; the owned particles' forces must
// be the plain run's bit for bit, for any rank count, grid and thread count
// (ctest runs this program on 1 to 4 ranks, mpi.halo.*). Run as
//   mpirun -np N pdyn_mpi_tests [--gtest_filter=...]
// with PDYN_TEST_GRID=NX,NY,NZ to impose a grid.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <mpi.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <random>

#include "pdyn/host/assembly.hpp"
#include "pdyn/host/decomposed.hpp"
#include "pdyn/host/halo.hpp"
#include "pdyn/host/registry.hpp"
#include "pdyn/host/scene.hpp"
#include "pdyn/host/simulation.hpp"
#include "pdyn/host/threads.hpp"
#include "pdyn/system.hpp"

namespace pdyn {
namespace {

int world_rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}
int world_size() {
  int n = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &n);
  return n;
}

const PluginRegistry& plugins() {
  static const PluginRegistry registry = [] {
    PluginRegistry r;
    r.discover({PDYN_PLUGIN_DIR});
    return r;
  }();
  return registry;
}

// A Lennard-Jones liquid of n^3 particles at LAMMPS's melt density 0.8442
// (spacing 1.0583 m), each jittered by up to 0.2 m off a simple cubic
// lattice, with velocities: the scene's cloud is only the particle count.
constexpr int kSide = 20;
constexpr double kSpacing = 1.0583;
const double kBox = kSide * kSpacing;

Scene liquid(const std::string& solver = "verlet") {
  const std::string text = fmt::format(
      "simulation: {{ dt: 0.005, steps: 1, solver: {{ type: {2} }},\n"
      "  box: {{ min: [0, 0, 0], max: [{0}, {0}, {0}], periodic: [true, true, true] }} }}\n"
      "particles:\n"
      "  - cloud: {{ n: {1}, box: {{ min: [0, 0, 0], max: [1, 1, 1] }}, mass: 1 }}\n"
      "forces:\n"
      "  - {{ type: lennard_jones, epsilon: 1, sigma: 1, cutoff: 2.5, skin: 0.3, shift: true }}\n",
      kBox, kSide * kSide * kSide, solver);
  return load_scene_text(text, "liquid.yaml", plugins());
}

void jitter(System& s, double amplitude = 0.4) {
  std::mt19937_64 g(7);
  auto u = [&] { return static_cast<double>(g() >> 11) * 0x1p-53 - 0.5; };
  auto x = s.positions();
  auto v = s.velocities();
  for (Index i = 0; i < s.size(); ++i) {
    const Index a = i % kSide, b = (i / kSide) % kSide, c = i / (kSide * kSide);
    x.col(i) = kSpacing * Vec3(static_cast<double>(a) + 0.5, static_cast<double>(b) + 0.5,
                               static_cast<double>(c) + 0.5) +
               amplitude * Vec3(u(), u(), u());
    v.col(i) = Vec3(u(), u(), u());
  }
}

RankGrid grid_for(const Scene& scene) {
  const char* text = std::getenv("PDYN_TEST_GRID");
  if (text != nullptr && *text != '\0') return parse_rank_grid(text, world_size());
  return choose_rank_grid(world_size(), scene.system->domain().length());
}

ParticleRecord record_of(const System& s, Index i) {
  ParticleRecord r;
  r.id = i;
  for (int a = 0; a < 3; ++a) {
    r.x[static_cast<std::size_t>(a)] = s.positions()(a, i);
    r.place[static_cast<std::size_t>(a)] = r.x[static_cast<std::size_t>(a)];
    r.v[static_cast<std::size_t>(a)] = s.velocities()(a, i);
  }
  r.mass = s.masses()[i];
  r.fixed = s.fixed()[static_cast<std::size_t>(i)];
  return r;
}

// Loads `halo`'s local particles into `s`.
void load_local(const Halo& halo, System& s) {
  const auto& local = halo.local();
  const auto n = static_cast<Index>(local.size());
  Matrix3X x(3, n), v(3, n);
  Eigen::VectorXd mass(n);
  std::vector<std::uint8_t> fixed(local.size());
  for (Index k = 0; k < n; ++k) {
    const ParticleRecord& r = local[static_cast<std::size_t>(k)];
    x.col(k) = Vec3(r.x[0], r.x[1], r.x[2]);
    v.col(k) = Vec3(r.v[0], r.v[1], r.v[2]);
    mass[k] = r.mass;
    fixed[static_cast<std::size_t>(k)] = r.fixed;
  }
  SystemAssembly(s).set_particles(x, v, mass, fixed);
}

// How many owned forces differ from the plain run's in any bit.
Index differing_forces(const Halo& halo, const System& local, const System& plain) {
  Index differ = 0;
  for (std::size_t k = 0; k < halo.local().size(); ++k) {
    if (halo.ghost()[k] != 0) continue;
    const Index id = halo.local()[k].id;
    const auto kk = static_cast<Index>(k);
    if (std::memcmp(local.forces().col(kk).data(), plain.forces().col(id).data(),
                    3 * sizeof(double)) != 0) {
      ++differ;
    }
  }
  return differ;
}

Index total(Index mine) {
  long long sum = 0, v = mine;
  MPI_Allreduce(&v, &sum, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  return static_cast<Index>(sum);
}

TEST(Halo, OwnedForcesAreThePlainRunsBitForBitOnEveryRank) {
  // Threads differ by rank (1 or 2): the result must not depend on them.
  set_threads(1 + world_rank() % 2);
  Scene plain_scene = liquid();
  System& plain = *plain_scene.system;
  jitter(plain);
  plain.compute_accelerations();

  Scene local_scene = liquid();
  const Domain& box = plain.domain();
  Halo halo(MPI_COMM_WORLD,
            Decomposition(grid_for(plain_scene), box.min, box.max, box.periodic, 2.8));
  // Each rank starts with every ranks()-th particle: all of them migrate.
  std::vector<ParticleRecord> held;
  for (Index i = world_rank(); i < plain.size(); i += world_size())
    held.push_back(record_of(plain, i));
  halo.exchange(held);
  EXPECT_EQ(total(halo.owned()), plain.size());
  for (std::size_t k = 0; k < halo.local().size(); ++k) {
    const ParticleRecord& r = halo.local()[k];
    const bool mine = halo.decomposition().owner(Vec3(r.x[0], r.x[1], r.x[2])) == world_rank();
    ASSERT_EQ(mine, halo.ghost()[k] == 0) << "particle " << r.id;
    if (k > 0) {
      ASSERT_LT(halo.local()[k - 1].id, r.id);
    }
  }
  load_local(halo, *local_scene.system);
  local_scene.system->compute_accelerations();
  EXPECT_EQ(total(differing_forces(halo, *local_scene.system, plain)), 0);

  // Everyone moves by up to 0.1 m (< skin / 2): forward() brings the ghosts
  // along, and the forces stay the plain run's without a new exchange.
  std::mt19937_64 g(11);
  Matrix3X step(3, plain.size());
  for (Index i = 0; i < plain.size(); ++i) {
    for (int a = 0; a < 3; ++a) step(a, i) = 0.1 * (static_cast<double>(g() >> 11) * 0x1p-53 - 0.5);
  }
  plain.positions() += step;
  plain.compute_accelerations();
  System& mine = *local_scene.system;
  for (std::size_t k = 0; k < halo.local().size(); ++k) {
    const auto kk = static_cast<Index>(k);
    if (halo.ghost()[k] == 0) {
      mine.positions().col(kk) += step.col(halo.local()[k].id);
    } else {
      mine.positions().col(kk).setConstant(std::nan(""));  // forward() must overwrite it
    }
  }
  halo.forward(mine.positions(), mine.velocities());
  mine.compute_accelerations();
  EXPECT_EQ(total(differing_forces(halo, mine, plain)), 0);
}

// `steps` steps of the liquid under `solver`, plain on every rank and
// decomposed, compared bit for bit on rank 0: positions, velocities and
// image counts. Returns the decomposed run's exchanges.
std::int64_t expect_plain_steps(const std::string& solver, std::int64_t steps) {
  const int threads = 1 + world_rank() % 2;
  Scene plain_scene = liquid(solver), local_scene = liquid(solver);
  jitter(*plain_scene.system, 0.1);
  jitter(*local_scene.system, 0.1);
  Simulation plain(std::move(plain_scene), threads), mine(std::move(local_scene), threads);
  DecomposedSystem decomposed(MPI_COMM_WORLD, mine.scene(), grid_for(mine.scene()));
  plain.step(steps);
  for (std::int64_t k = 0; k < steps; ++k) {
    decomposed.begin_step();
    mine.step(1);
  }
  Matrix3X x, v;
  std::vector<std::array<std::int32_t, 3>> images;
  decomposed.gather(0, x, v, images);
  if (world_rank() == 0) {
    const System& p = plain.system();
    EXPECT_EQ(x.cols(), p.size());
    EXPECT_EQ(std::memcmp(x.data(), p.positions().data(), sizeof(double) * 3 * p.size()), 0);
    EXPECT_EQ(std::memcmp(v.data(), p.velocities().data(), sizeof(double) * 3 * p.size()), 0);
    EXPECT_EQ(images, p.images());
    EXPECT_NE(x, Matrix3X(liquid(solver).system->positions()));  // they moved
  }
  return decomposed.exchanges();
}

TEST(Decomposed, VelocityVerletStepsAreThePlainRunsBitForBit) {
  // 200 steps, t = 1: the particles move past the skin several times, so
  // they migrate and the kept forces travel with them.
  EXPECT_GE(expect_plain_steps("verlet", 200), 3);
}

TEST(Decomposed, Rk4StepsAreThePlainRunsBitForBit) { expect_plain_steps("rk4", 40); }

TEST(Decomposed, AStepThatOutrunsTheGhostsIsRefusedNotComputed) {
  // Skin 0.001 m, speeds near 1 m/s, dt 0.005 s: a particle moves five
  // half-skins in one step, so the ghosts chosen before it may miss a
  // partner at its force evaluation. The step must fail, on the rank that
  // saw it, rather than give a force without that partner.
  Scene tight = load_scene_text(
      fmt::format(
          "simulation: {{ dt: 0.005, steps: 1, solver: {{ type: verlet }},\n"
          "  box: {{ min: [0, 0, 0], max: [{0}, {0}, {0}], periodic: [true, true, true] }} }}\n"
          "particles:\n"
          "  - cloud: {{ n: {1}, box: {{ min: [0, 0, 0], max: [1, 1, 1] }}, mass: 1 }}\n"
          "forces:\n"
          "  - {{ type: lennard_jones, epsilon: 1, sigma: 1, cutoff: 2.5, skin: 0.001, shift: true "
          "}}\n",
          kBox, kSide * kSide * kSide),
      "tight.yaml", plugins());
  jitter(*tight.system, 0.1);
  tight.system->velocities() *= 2.0;
  Simulation sim(std::move(tight), 1);
  DecomposedSystem decomposed(MPI_COMM_WORLD, sim.scene(), grid_for(sim.scene()));
  MpiRankDriver driver(decomposed);
  int failed = -1;
  for (int k = 0; k < 3 && failed < 0; ++k) {
    ASSERT_TRUE(driver.begin_step());
    sim.step(1);
    failed = driver.end_step(sim.scene(), false, false, nullptr);
  }
  EXPECT_GE(failed, 0);
  int mine = decomposed.violation().empty() ? 0 : 1, any = 0;
  MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  EXPECT_EQ(any, 1);
  if (mine != 0) {
    EXPECT_NE(decomposed.violation().find("more than half the skin (0.0005 m), within one step"),
              std::string::npos)
        << decomposed.violation();
  }
  driver.finish();
}

TEST(Decomposed, TheEnergyCheckSumsEachRanksShare) {
  // The energy check under ranks (RankDriver::end_step): each rank's owned
  // particles' kinetic energy and its forces' potential energy, summed on
  // rank 0. Under gravity alone no term spans two subdomains, so the sum
  // is the plain system's K + U and K + |U| to the rounding of its order.
  Scene scene = load_scene_text(
      fmt::format(
          "simulation: {{ dt: 0.005, steps: 1, solver: {{ type: verlet }},\n"
          "  box: {{ min: [0, 0, 0], max: [{0}, {0}, {0}], periodic: [true, true, true] }} }}\n"
          "particles:\n"
          "  - cloud: {{ n: {1}, box: {{ min: [0, 0, 0], max: [1, 1, 1] }}, mass: 2 }}\n"
          "forces:\n  - {{ type: gravity }}\n",
          kBox, kSide * kSide * kSide),
      "falling.yaml", plugins());
  jitter(*scene.system);
  const System& sys = *scene.system;
  const double k = sys.kinetic_energy();
  const double u = *sys.force_objects().front().force->potential_energy(sys.view());
  DecomposedSystem decomposed(MPI_COMM_WORLD, scene, grid_for(scene));
  MpiRankDriver driver(decomposed);
  ASSERT_TRUE(driver.begin_step());
  std::array<double, 2> sum{-1.0, -1.0};
  EXPECT_EQ(driver.end_step(scene, false, false, world_rank() == 0 ? &sum : nullptr), -1);
  if (world_rank() == 0) {
    EXPECT_NEAR(sum[0], k + u, 1e-12 * (k + std::abs(u)));
    EXPECT_NEAR(sum[1], k + std::abs(u), 1e-12 * (k + std::abs(u)));
  } else {
    EXPECT_EQ(sum[0], -1.0) << "only rank 0 receives the sum";
  }
  driver.finish();
}

TEST(Decomposed, WhatCannotRunDecomposedYetIsRefusedByName) {
  Scene scene = load_scene_text(
      "simulation: { dt: 0.01, steps: 1, solver: { type: verlet } }\n"
      "particles:\n  - { position: [0, 0, 0], mass: 1 }\n  - { position: [1, 0, 0], mass: 1 }\n"
      "forces:\n  - { type: spring, pairs: [[0, 1]], ks: 10 }\n",
      "chain.yaml", plugins());
  try {
    DecomposedSystem d(MPI_COMM_WORLD, scene);
    FAIL() << "no error";
  } catch (const DecompositionError& e) {
    EXPECT_EQ(
        std::string(e.what()),
        fmt::format(
            "spring (chain.yaml:6:5): cannot run on {} yet (a force that declares no "
            "decomposed loop; runs decomposed: pair forces without a group, gravity, drag, "
            "field; the colliders box, plane, sphere (any SurfaceCollider); the solvers "
            "verlet, symplectic_euler, euler, midpoint, rk4; or run one process)",
            world_size() == 1 ? std::string("1 rank") : fmt::format("{} ranks", world_size())));
  }
}

TEST(Halo, AGridOfTheWrongSizeIsRefused) {
  const Decomposition d(RankGrid{{world_size() + 1, 1, 1}}, Vec3::Zero(), Vec3::Ones(),
                        {true, true, true}, 0.1);
  try {
    Halo halo(MPI_COMM_WORLD, d);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              fmt::format("a grid of {} subdomains for {} ranks (expected one per rank)",
                          world_size() + 1, world_size()));
  }
}

}  // namespace
}  // namespace pdyn

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  if (pdyn::world_rank() != 0) {
    // One report: the other ranks print only their failures.
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  int failed = RUN_ALL_TESTS() != 0 ? 1 : 0, any = 0;
  MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return any;
}
