// One scene run by several MPI ranks (pdyn/host/decomposed.hpp).
#include "pdyn/host/decomposed.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <numeric>
#include <ostream>
#include <set>
#include <string_view>
#include <utility>

#include "pdyn/contact.hpp"
#include "pdyn/force_reuse.hpp"
#include "pdyn/host/assembly.hpp"
#include "pdyn/host/stepper.hpp"
#include "pdyn/host/threads.hpp"
#include "pdyn/kernel/neighbor_schedule.hpp"
#include "pdyn/local_force.hpp"
#include "pdyn/pair.hpp"
#include "pdyn/periodic_invariant.hpp"
#include "pdyn/system.hpp"

namespace pdyn {

namespace {

// The first force object of a decomposed System: it adds nothing, and
// refreshes the ghosts' positions and velocities from their owners before
// the scene's forces read them (LAMMPS's forward communication). It writes
// through the view's memory rather than System::positions(), which would
// count as a change of state and stop velocity Verlet from reusing its
// forces; the ghosts it writes are the owners' values, which the state
// already stands for.
class HaloForce final : public Force, public PeriodicInvariant {
 public:
  explicit HaloForce(DecomposedSystem& d) : d_(d) {}
  void add_forces(const ParticleView& p, Eigen::Ref<Matrix3X>) override {
    const Index n = p.size();
    Eigen::Map<Matrix3X> x(const_cast<double*>(p.x.data()), 3, n);
    Eigen::Map<Matrix3X> v(const_cast<double*>(p.v.data()), 3, n);
    d_.halo().forward(x, v);
    d_.check_reach(p);
  }
  // The ghosts follow their owners; the owned particles' forces depend on
  // nothing through this object.
  StateDependence dependence() const override { return {false, false}; }

 private:
  DecomposedSystem& d_;
};

// The plugins whose local forces read nothing but the particle's own
// position, velocity and mass (not its index): they run unchanged on a
// rank's particles.
bool index_free_local(std::string_view type) {
  return type == "gravity" || type == "drag" || type == "field";
}

// What changes as particle i of `sys` moves, into its record: position,
// velocity, image counts and, if `kept` (a solver's kept accelerations,
// pdyn/force_reuse.hpp), its acceleration.
void copy_state(const System& sys, Index i, const Matrix3X* kept, ParticleRecord& rec) {
  for (int a = 0; a < 3; ++a) {
    const auto aa = static_cast<std::size_t>(a);
    rec.x[aa] = sys.positions()(a, i);
    rec.place[aa] = rec.x[aa];
    rec.v[aa] = sys.velocities()(a, i);
    rec.a[aa] = kept != nullptr ? (*kept)(a, i) : 0.0;
  }
  rec.images = sys.images()[static_cast<std::size_t>(i)];
}

// Every particle's record, gathered, into columns by id: positions,
// velocities, accelerations (if `a`) and image counts (N each).
void unpack(const std::vector<ParticleRecord>& all, Eigen::Ref<Matrix3X> x, Eigen::Ref<Matrix3X> v,
            Matrix3X* a, std::vector<std::array<std::int32_t, 3>>& images) {
  images.resize(all.size());
  for (const ParticleRecord& rec : all) {
    x.col(rec.id) = Vec3(rec.x[0], rec.x[1], rec.x[2]);
    v.col(rec.id) = Vec3(rec.v[0], rec.v[1], rec.v[2]);
    if (a != nullptr) a->col(rec.id) = Vec3(rec.a[0], rec.a[1], rec.a[2]);
    images[static_cast<std::size_t>(rec.id)] = rec.images;
  }
}

// Below this squared length (m^2) a displacement is its own nearest image
// (half the shortest periodic edge, squared; infinite without one).
double unwrapped_below2(const Domain& box) {
  double half = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (box.periodic[static_cast<std::size_t>(a)]) half = std::min(half, 0.5 * box.length()[a]);
  }
  return half * half;
}

// The displacement `raw` (m) at its nearest image, rounding only the few
// that could differ (`near2`: unwrapped_below2).
Vec3 displacement(const Domain& box, const Vec3& raw, double near2) {
  return raw.squaredNorm() < near2 ? raw : box.minimum_image(raw);
}

constexpr std::string_view kRuns =
    "runs decomposed: pair forces without a group, gravity, drag, field; the colliders box, "
    "plane, sphere (any SurfaceCollider); the solvers verlet, symplectic_euler, euler, midpoint, "
    "rk4";

// The ghost reach (the largest cutoff + skin of the scene's pair forces, m)
// and the skin it leaves beyond the largest cutoff (m; infinite without a
// pair force), once the scene is known to run decomposed; throws
// DecompositionError naming the first object that cannot.
std::pair<double, double> reach_and_skin(Scene& scene, int ranks) {
  System& sys = *scene.system;
  auto refuse = [&](const std::string& label, std::string_view why) {
    const std::string on = ranks == 1 ? std::string("1 rank") : fmt::format("{} ranks", ranks);
    throw DecompositionError(fmt::format("{}: cannot run on {} yet ({}; {}; or run one process)",
                                         label, on, why, kRuns));
  };
  static const std::set<std::string, std::less<>> solvers{"verlet", "symplectic_euler", "euler",
                                                          "midpoint", "rk4"};
  if (scene.solver->adaptive() || !solvers.contains(scene.solver_name)) {
    refuse(scene.solver_label, "a solver not yet decomposed");
  }
  // A SurfaceCollider (box, plane, sphere) treats each particle alone, by
  // the obstacle's geometry: it runs on a rank's particles unchanged.
  for (const auto& entry : sys.collider_objects()) {
    if (dynamic_cast<const SurfaceCollider*>(entry.collider.get()) == nullptr)
      refuse(entry.label, "a collider that is not a SurfaceCollider");
  }
  if (!sys.constraint_objects().empty())
    refuse(sys.constraint_objects().front().label, "a constraint");
  if (scene.special_bonds) refuse("special_bonds", "special bonds");
  // A pair force tells its range (PairRange); one built against an SDK
  // without that tells it through its list, which exists after a first
  // evaluation: of the whole scene, on every rank (memory a PairRange
  // spares).
  for (const auto& entry : sys.force_objects()) {
    const Force* f = entry.force.get();
    const auto* pair = dynamic_cast<const PairReference*>(f);
    if (pair != nullptr && dynamic_cast<const PairRange*>(f) == nullptr &&
        pair->pair_neighbors() == nullptr) {
      sys.compute_accelerations();
      break;
    }
  }
  // The ghosts reach as far as the farthest list, cutoff + skin; particles
  // may move half of what that leaves beyond the largest cutoff, as a
  // shared list's rebuild rule allows (pdyn/neighbors.hpp).
  double reach = 0.0, cutoff = 0.0;
  for (const auto& entry : sys.force_objects()) {
    if (const auto* pair = dynamic_cast<const PairReference*>(entry.force.get())) {
      const auto* range = dynamic_cast<const PairRange*>(entry.force.get());
      const NeighborList* list = pair->pair_neighbors();
      if (range == nullptr && list == nullptr)
        refuse(entry.label, "a pair force without a neighbor list");
      const double c = range != nullptr ? pair->pair_cutoff() : list->cutoff();
      reach = std::max(reach, range != nullptr ? c + range->pair_skin() : list->reach());
      cutoff = std::max(cutoff, c);
      continue;
    }
    const auto use = std::find_if(scene.uses.begin(), scene.uses.end(),
                                  [&](const PluginUse& u) { return u.label == entry.label; });
    if (use == scene.uses.end() || !index_free_local(use->type)) {
      refuse(entry.label, "a force that declares no decomposed loop");
    }
  }
  return {reach, cutoff > 0.0 ? reach - cutoff : std::numeric_limits<double>::infinity()};
}

}  // namespace

DecomposedSystem::DecomposedSystem(MPI_Comm comm, Scene& scene, std::optional<RankGrid> grid)
    : comm_(comm), scene_(scene) {
  int ranks = 1;
  MPI_Comm_size(comm_, &ranks);
  System& sys = *scene.system;
  // A resumed solver's kept accelerations (pdyn/force_reuse.hpp) would not
  // survive the force evaluation reach_and_skin may make: kept aside and
  // restored, or the first step would evaluate them afresh, which differs
  // in the last bits after a wrap.
  std::optional<Matrix3X> resumed;
  if (const Matrix3X* kept = kept_accelerations()) resumed = *kept;
  const auto [reach, skin] = reach_and_skin(scene, ranks);
  if (resumed) {
    if (auto* holder = dynamic_cast<ForceReuseHolder*>(scene.solver.get()))
      holder->restore_kept_accelerations(sys, *resumed);
  }
  half_skin_ = 0.5 * skin;
  total_ = sys.size();
  radii_ = !sys.radii().empty();
  types_ = !sys.types().empty();

  // The region: the box along periodic axes, the particles' bounds along
  // open ones (the same numbers on every rank: every rank loaded them all).
  const Domain& box = sys.domain();
  Vec3 lo = box.min, hi = box.max;
  for (int a = 0; a < 3; ++a) {
    if (box.periodic[static_cast<std::size_t>(a)]) continue;
    lo[a] = total_ > 0 ? sys.positions().row(a).minCoeff() : 0.0;
    hi[a] = total_ > 0 ? sys.positions().row(a).maxCoeff() : 0.0;
    if (!(hi[a] > lo[a])) hi[a] = lo[a] + 1.0;  // flat along this axis: one slab
  }
  const RankGrid g = grid ? *grid : choose_rank_grid(ranks, hi - lo);
  halo_ = std::make_unique<Halo>(comm_, Decomposition(g, lo, hi, box.periodic, reach));

  // Each rank starts with a contiguous share of the ids, with the
  // accelerations a resumed solver keeps.
  const Matrix3X* kept = kept_accelerations();
  kept_ = kept != nullptr;
  std::vector<ParticleRecord> held;
  const Index r = halo_->rank(), p = halo_->ranks();
  for (Index i = total_ * r / p; i < total_ * (r + 1) / p; ++i) {
    ParticleRecord rec;
    rec.id = i;
    copy_state(sys, i, kept, rec);
    rec.mass = sys.masses()[i];
    rec.fixed = sys.fixed()[static_cast<std::size_t>(i)];
    if (radii_) rec.radius = sys.radii()[static_cast<std::size_t>(i)];
    if (types_) rec.type = sys.types()[static_cast<std::size_t>(i)];
    held.push_back(rec);
  }
  halo_->exchange(held);
  ++exchanges_;

  // The halo first, then the scene's forces in their order.
  const std::vector<System::ForceEntry> forces = sys.force_objects();
  const SystemAssembly assembly(sys);
  for (const auto& entry : forces) assembly.remove_force(entry.force.get());
  halo_force_ = std::make_shared<HaloForce>(*this);
  assembly.add_force(halo_force_, "halo exchange (mpi)");
  for (const auto& entry : forces) assembly.add_force(entry.force, entry.label);
  load_local();
}

DecomposedSystem::~DecomposedSystem() {
  set_neighbor_ghosts(std::as_const(*scene_.system).positions().data(), nullptr, 0);
}

void DecomposedSystem::load_local() {
  System& sys = *scene_.system;
  const auto& local = halo_->local();
  const auto n = static_cast<Index>(local.size());
  Matrix3X x(3, n), v(3, n), a(3, n), placed(3, n);
  Eigen::VectorXd mass(n);
  std::vector<std::uint8_t> fixed(local.size());
  std::vector<double> radius(radii_ ? local.size() : 0);
  std::vector<std::int32_t> type(types_ ? local.size() : 0);
  std::vector<std::array<std::int32_t, 3>> images(local.size());
  for (std::size_t k = 0; k < local.size(); ++k) {
    const ParticleRecord& rec = local[k];
    const auto kk = static_cast<Index>(k);
    x.col(kk) = Vec3(rec.x[0], rec.x[1], rec.x[2]);
    placed.col(kk) = Vec3(rec.place[0], rec.place[1], rec.place[2]);
    v.col(kk) = Vec3(rec.v[0], rec.v[1], rec.v[2]);
    a.col(kk) = Vec3(rec.a[0], rec.a[1], rec.a[2]);
    mass[kk] = rec.mass;
    fixed[k] = rec.fixed;
    if (radii_) radius[k] = rec.radius;
    if (types_) type[k] = rec.type;
    images[k] = rec.images;
  }
  const SystemAssembly assembly(sys);
  const double t = sys.time();
  set_neighbor_ghosts(std::as_const(sys).positions().data(), nullptr, 0);
  assembly.set_particles(x, v, mass, fixed);
  // The pair loops skip pairs of two ghosts (they give no owned particle a
  // force): about a third of a 2-rank slab's pairs on the LJ melt.
  set_neighbor_ghosts(std::as_const(sys).positions().data(), halo_->ghost().data(),
                      static_cast<std::int64_t>(halo_->ghost().size()));
  sys.set_time(t);
  if (radii_) assembly.set_radii(std::move(radius));
  if (types_) assembly.set_types(std::move(type));
  assembly.set_images(std::move(images));
  placed_ = std::move(placed);
  owned_.clear();
  for (std::size_t k = 0; k < local.size(); ++k) {
    if (halo_->ghost()[k] == 0) owned_.push_back(static_cast<Index>(k));
  }
  // A solver that reuses its end-of-step forces gets the owned particles'
  // kept accelerations back (the ghosts' are never read): recomputed after
  // the wrap into the box they could differ in the last bit (pdyn/
  // periodic_invariant.hpp).
  if (kept_) {
    if (auto* holder = dynamic_cast<ForceReuseHolder*>(scene_.solver.get()))
      holder->restore_kept_accelerations(sys, a);
  }
}

const Matrix3X* DecomposedSystem::kept_accelerations() const {
  const auto* holder = dynamic_cast<const ForceReuseHolder*>(scene_.solver.get());
  return holder != nullptr ? holder->kept_accelerations(*scene_.system) : nullptr;
}

std::vector<ParticleRecord> DecomposedSystem::owned_records(bool place_ahead) const {
  const System& sys = *scene_.system;
  const Matrix3X* kept = kept_accelerations();
  kept_ = kept != nullptr;
  const Matrix3X* drift = place_ahead ? drift_accelerations() : nullptr;
  const double h = scene_.dt;
  std::vector<ParticleRecord> out;
  out.reserve(owned_.size());
  for (const Index k : owned_) {
    ParticleRecord rec = halo_->local()[static_cast<std::size_t>(k)];
    copy_state(sys, k, kept, rec);
    if (drift != nullptr) {
      const Vec3 next = sys.domain().wrap(sys.positions().col(k) + h * sys.velocities().col(k) +
                                          0.5 * h * h * drift->col(k));
      for (int a = 0; a < 3; ++a) rec.place[static_cast<std::size_t>(a)] = next[a];
    }
    out.push_back(rec);
  }
  return out;
}

const Matrix3X* DecomposedSystem::drift_accelerations() const {
  const Matrix3X* kept = kept_accelerations();
  const bool verlet =
      kept != nullptr && kept->cols() == scene_.system->size() && scene_.solver_name == "verlet";
  return verlet ? kept : nullptr;
}

bool DecomposedSystem::exchange_due() const {
  if (!std::isfinite(half_skin_)) return false;
  const System& sys = *scene_.system;
  // Velocity Verlet's drift is x + h v + h^2 a / 2 with the kept a, so
  // each owned particle's next position is known before the step: the
  // exchange comes at the step whose force evaluation would find a
  // particle past skin / 2, as LAMMPS's decide() after its drift (a relative
  // 1e-9 covers the rounding of the two sums), and places the particles
  // where that evaluation will find them (owned_records). Other solvers
  // move by h |v| + h^2 |a| / 2 to second order, with a the last
  // evaluation's: the exchange then comes when the farthest moved plus the
  // fastest's stride passes skin / 2 (check_reach catches a step that
  // outruns it). Squared lengths throughout: one square root per step.
  const Matrix3X* kept = drift_accelerations();
  const bool exact = kept != nullptr;
  const double h = scene_.dt, limit = exact ? half_skin_ * (1.0 - 1e-9) : half_skin_;
  const Matrix3X& f = sys.forces();
  const bool have_f = f.cols() == sys.size();
  const Domain& box = sys.domain();
  const double near2 = unwrapped_below2(box);
  double moved2 = 0.0, v2 = 0.0, a2 = 0.0;
  for (const Index k : owned_) {
    const Vec3 d = displacement(box, sys.positions().col(k) - placed_.col(k), near2);
    const Vec3 v = sys.velocities().col(k);
    if (exact) {
      moved2 = std::max(moved2, (d + h * v + 0.5 * h * h * kept->col(k)).squaredNorm());
      continue;
    }
    moved2 = std::max(moved2, d.squaredNorm());
    v2 = std::max(v2, v.squaredNorm());
    if (have_f) {
      const double w = sys.inverse_masses()[k];
      a2 = std::max(a2, f.col(k).squaredNorm() * w * w);
    }
  }
  return !(std::sqrt(moved2) + h * std::sqrt(v2) + 0.5 * h * h * std::sqrt(a2) <= limit);
}

bool DecomposedSystem::begin_step(bool stop) {
  int flags[2] = {!stop && exchange_due() ? 1 : 0, stop ? 1 : 0};  // exchange, stop
  int agreed[2] = {0, 0};
  MPI_Allreduce(flags, agreed, 2, MPI_INT, MPI_MAX, comm_);
  if (agreed[1] != 0) return false;
  if (agreed[0] == 0) return true;
  const std::vector<ParticleRecord> held = owned_records(true);
  halo_->exchange(held);
  ++exchanges_;
  load_local();
  return true;
}

void DecomposedSystem::check_reach(const ParticleView& p) {
  if (!std::isfinite(half_skin_) || !violation_.empty()) return;
  const double near2 = unwrapped_below2(p.domain), limit2 = half_skin_ * half_skin_;
  for (const Index k : owned_) {
    const Vec3 moved = displacement(p.domain, p.x.col(k) - placed_.col(k), near2);
    if (moved.squaredNorm() <= limit2) continue;
    const double d = moved.norm();
    violation_ = fmt::format(
        "particle {} moved {:.6g} m from where the last exchange of particles placed it, more than "
        "half the skin ({:.6g} m), within one step: its rank's ghosts may miss a partner, so the "
        "step is refused (expected a smaller dt or a larger skin)",
        halo_->local()[static_cast<std::size_t>(k)].id, d, half_skin_);
    return;
  }
}

std::array<double, 2> DecomposedSystem::local_energy() const {
  const System& sys = *scene_.system;
  double k = 0.0;
  for (const Index i : owned_) k += 0.5 * sys.masses()[i] * sys.velocities().col(i).squaredNorm();
  return energy_and_magnitude(sys, k);
}

std::vector<ParticleRecord> DecomposedSystem::gathered(int root) const {
  const std::vector<ParticleRecord> mine = owned_records(false);
  const int count = static_cast<int>(mine.size());
  const bool at_root = halo_->rank() == root;
  std::vector<int> counts(at_root ? static_cast<std::size_t>(halo_->ranks()) : 0, 0);
  MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, root, comm_);
  std::vector<int> offsets(counts.size(), 0);
  std::exclusive_scan(counts.begin(), counts.end(), offsets.begin(), 0);
  std::vector<ParticleRecord> all(at_root ? static_cast<std::size_t>(total_) : 0);
  MPI_Gatherv(mine.data(), count, halo_->record_type(), all.data(), counts.data(), offsets.data(),
              halo_->record_type(), root, comm_);
  return all;
}

void DecomposedSystem::gather_into(Scene& whole) const {
  const std::vector<ParticleRecord> all = gathered(0);
  if (halo_->rank() != 0) return;
  System& sys = *whole.system;
  Matrix3X a(3, total_);
  std::vector<std::array<std::int32_t, 3>> images;
  unpack(all, sys.positions(), sys.velocities(), &a, images);
  SystemAssembly(sys).set_images(std::move(images));
  sys.set_time(scene_.system->time());
  if (kept_) {
    if (auto* holder = dynamic_cast<ForceReuseHolder*>(whole.solver.get())) {
      holder->restore_kept_accelerations(sys, a);
    }
  }
}

void DecomposedSystem::gather(int root, Matrix3X& x, Matrix3X& v,
                              std::vector<std::array<std::int32_t, 3>>& images) const {
  const std::vector<ParticleRecord> all = gathered(root);
  if (halo_->rank() != root) return;
  x.resize(3, total_);
  v.resize(3, total_);
  unpack(all, x, v, nullptr, images);
}

int MpiRankDriver::end_step(Scene& whole, bool gather, bool failed, std::array<double, 2>* energy) {
  // One reduction: rank 0's wishes to gather and to check the energy, and
  // the lowest failing rank as ranks - rank (the largest), 0 for none.
  const int ranks = d_.halo().ranks(), rank = d_.halo().rank();
  if (!d_.violation().empty()) {
    std::cerr << fmt::format("pdyn (MPI rank {}): {}\n", rank, d_.violation());
    failed = true;
  }
  int flags[3] = {gather ? 1 : 0, failed ? ranks - rank : 0, energy != nullptr ? 1 : 0};
  int agreed[3] = {0, 0, 0};
  MPI_Allreduce(flags, agreed, 3, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  if (agreed[0] != 0 && agreed[1] == 0) d_.gather_into(whole);
  if (agreed[2] != 0 && agreed[1] == 0) {
    const std::array<double, 2> mine = d_.local_energy();
    std::array<double, 2> sum{};
    MPI_Reduce(mine.data(), sum.data(), 2, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
    if (energy != nullptr) *energy = sum;
  }
  return agreed[1] != 0 ? ranks - agreed[1] : -1;
}

int follow_run(DecomposedSystem& decomposed, std::int64_t k0, int threads, std::ostream& err) {
  Scene& scene = decomposed.scene();
  set_threads(threads > 0         ? threads
              : scene.threads > 0 ? scene.threads
                                  : default_threads(scene.system->size()));
  MpiRankDriver driver(decomposed);
  Stepper stepper(*scene.system, *scene.solver, scene.solver_label, scene.neighbor_schedule);
  // As rank 0's run_steps: agree to start (rank 0 may have stopped before
  // its first step), then set up the forces together.
  if (!driver.begin_step()) return 0;
  set_up_forces(scene);
  driver.end_step(scene, false, false, nullptr);  // the energy check's start (run_steps)
  int status = 0;
  for (std::int64_t k = k0 + 1; driver.begin_step(); ++k) {
    // The step's end time as run_fixed computes it; after the scene's last
    // step rank 0 finishes, so k never passes it.
    const double t_end = k >= scene.steps ? scene.end_time : static_cast<double>(k) * scene.dt;
    const bool ok = stepper.step_to(t_end).has_value();
    if (!ok) {
      err << fmt::format("pdyn (MPI rank {}): {}\n", decomposed.halo().rank(),
                         step_fault_message(stepper.fault(), scene, k, "is on this rank"));
      status = 4;
    }
    driver.end_step(scene, false, !ok, nullptr);
  }
  return status;
}

}  // namespace pdyn
