// The particle system: Witkin's derivative evaluation loop.
#include "pdyn/system.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

#include "constraint_force.hpp"
#include "pdyn/error.hpp"
#include "pdyn/kernel/plugin_call.hpp"
#include "pdyn/local_force.hpp"
#include "pdyn/parallel.hpp"
#include "pdyn/periodic_invariant.hpp"
#include "pdyn/thermo.hpp"

namespace pdyn {

void System::set_particles(const Matrix3X& x, const Matrix3X& v, const Eigen::VectorXd& mass,
                           const std::vector<std::uint8_t>& fixed) {
  const Index n = mass.size();
  if (x.cols() != n || v.cols() != n || static_cast<Index>(fixed.size()) != n) {
    throw Error("System::set_particles: x, v, mass and fixed must have the same length");
  }
  state_.resize(6 * n);
  mass_ = mass;
  fixed_ = fixed;
  positions() = x;
  velocities() = v;
  for (Index i = 0; i < n; ++i) {
    if (fixed_[i]) velocities().col(i).setZero();
  }
  force_.setZero(3, n);
  accel_.resize(3, 0);  // sized by the first compute_accelerations(): rk4 never needs it
  radius_.clear();
  type_.clear();
  images_.assign(static_cast<std::size_t>(n), {0, 0, 0});
  update_inverse_mass();
  touch();
}

Index System::add_particle(const Vec3& x, const Vec3& v, double mass, bool fixed) {
  const Index n = size();
  Matrix3X xs(3, n + 1), vs(3, n + 1);
  xs.leftCols(n) = positions();
  vs.leftCols(n) = velocities();
  xs.col(n) = x;
  vs.col(n) = v;
  Eigen::VectorXd m(n + 1);
  m.head(n) = mass_;
  m(n) = mass;
  std::vector<std::uint8_t> f = fixed_;
  f.push_back(fixed ? 1 : 0);
  std::vector<double> radius = std::move(radius_);
  std::vector<std::int32_t> type = std::move(type_);
  auto images = std::move(images_);
  set_particles(xs, vs, m, f);
  if (!radius.empty()) radius.push_back(0.0);
  if (!type.empty()) type.push_back(0);
  images.push_back({0, 0, 0});
  radius_ = std::move(radius);
  type_ = std::move(type);
  images_ = std::move(images);
  return n;
}

void System::set_domain(const Domain& domain) {
  for (int k = 0; k < 3; ++k) {
    if (domain.periodic[k] && !(std::isfinite(domain.min[k]) && std::isfinite(domain.max[k]) &&
                                domain.min[k] < domain.max[k])) {
      throw Error(
          fmt::format("System::set_domain: periodic axis {} runs from {} to {} m "
                      "(expected finite min < max)",
                      "xyz"[k], domain.min[k], domain.max[k]));
    }
  }
  domain_ = domain;
  touch();
}

void System::resize_box(const Vec3& min, const Vec3& max) {
  Domain d = domain_;
  for (int k = 0; k < 3; ++k) {
    if (!d.periodic[k]) continue;
    d.min[k] = min[k];
    d.max[k] = max[k];
  }
  set_domain(d);
}

void System::set_radii(std::vector<double> radius) {
  if (!radius.empty() && static_cast<Index>(radius.size()) != size()) {
    throw Error(fmt::format("System::set_radii: {} radii for {} particles", radius.size(), size()));
  }
  for (std::size_t i = 0; i < radius.size(); ++i) {
    if (!(std::isfinite(radius[i]) && radius[i] >= 0)) {
      throw Error(fmt::format("System::set_radii: particle {} has radius {} (expected >= 0 m)", i,
                              radius[i]));
    }
  }
  radius_ = std::move(radius);
  touch();
}

void System::set_types(std::vector<std::int32_t> type) {
  if (!type.empty() && static_cast<Index>(type.size()) != size()) {
    throw Error(fmt::format("System::set_types: {} types for {} particles", type.size(), size()));
  }
  for (std::size_t i = 0; i < type.size(); ++i) {
    if (type[i] < 0) {
      throw Error(
          fmt::format("System::set_types: particle {} has type {} (expected >= 0)", i, type[i]));
    }
  }
  type_ = std::move(type);
  touch();
}

void System::set_images(std::vector<std::array<std::int32_t, 3>> images) {
  if (static_cast<Index>(images.size()) != size()) {
    throw Error(
        fmt::format("System::set_images: {} entries for {} particles", images.size(), size()));
  }
  images_ = std::move(images);
}

// Wrapping moves x by whole box lengths only, so forces that measure
// separations by the minimum image see the same system before and after.
bool System::wrap_positions() { return wrap_positions(nullptr); }

bool System::wrap_positions(double* mirror) {
  if (!domain_.any_periodic()) return false;
  // Not positions(): only a wrap that moves a particle changes the version.
  // Forces evaluated before it stay valid otherwise, bit for bit. Columns
  // are independent: over the host's threads.
  Eigen::Map<Matrix3X> x(state_.data(), 3, size());
  const Vec3 length = domain_.length();
  std::atomic<bool> any{false};
  parallel_ranges(size(), [&](Index begin, Index end) {
    bool moved_here = false;
    for (Index i = begin; i < end; ++i) {
      const Vec3 before = x.col(i);
      const Vec3 after = domain_.wrap(before);
      if (after == before) continue;
      for (int k = 0; k < 3; ++k) {
        if (domain_.periodic[k] && std::isfinite(before[k])) {
          images_[static_cast<std::size_t>(i)][k] +=
              static_cast<std::int32_t>(std::lround((before[k] - after[k]) / length[k]));
        }
      }
      x.col(i) = after;
      if (mirror != nullptr) Eigen::Map<Vec3>(mirror + 3 * i) = after;
      moved_here = true;
    }
    if (moved_here) any.store(true, std::memory_order_relaxed);
  });
  const bool moved = any.load();
  // A wrap is a change of the state for a force that measures separations
  // as given (a spring across a face); not when every force is
  // periodic-invariant, so that a solver may keep the forces it evaluated
  // before the wrap (velocity Verlet's end-of-step forces, issue 30).
  // (Asked only when something moved: most steps wrap nobody.)
  auto invariant = [this] {
    return std::all_of(forces_.begin(), forces_.end(),
                       [](const ForceEntry& e) { return periodic_invariant(*e.force); });
  };
  if (moved && !invariant()) touch();
  return moved;
}

void System::set_fixed(Index i, bool fixed) {
  fixed_.at(static_cast<std::size_t>(i)) = fixed ? 1 : 0;
  if (fixed) velocities().col(i).setZero();
  update_inverse_mass();
  touch();
}

void System::update_inverse_mass() {
  inv_mass_.resize(mass_.size());
  fixed_ids_.clear();
  for (Index i = 0; i < mass_.size(); ++i) {
    inv_mass_(i) = fixed_[i] ? 0.0 : 1.0 / mass_(i);
    if (fixed_[i]) fixed_ids_.push_back(i);
  }
}

void System::add_force(std::shared_ptr<Force> force, std::string label) {
  local_.push_back(force ? LocalEntry{local_force(*force), linear_local_force(*force)}
                         : LocalEntry{});
  forces_.push_back({std::move(force), std::move(label)});
  touch();
}

bool System::remove_force(const Force* force) {
  const auto it = std::find_if(forces_.begin(), forces_.end(),
                               [&](const ForceEntry& e) { return e.force.get() == force; });
  if (it == forces_.end()) return false;
  local_.erase(local_.begin() + (it - forces_.begin()));
  forces_.erase(it);
  touch();
  return true;
}

void System::add_collider(std::shared_ptr<Collider> collider, std::string label) {
  colliders_.push_back({std::move(collider), std::move(label)});
  touch();
}

bool System::remove_collider(const Collider* collider) {
  const auto it = std::find_if(colliders_.begin(), colliders_.end(), [&](const ColliderEntry& e) {
    return e.collider.get() == collider;
  });
  if (it == colliders_.end()) return false;
  colliders_.erase(it);
  touch();
  return true;
}

void System::get_state(Eigen::Ref<Eigen::VectorXd> y) const { y = state_; }

void System::set_state(const Eigen::Ref<const Eigen::VectorXd>& y) {
  if (y.size() != state_.size()) throw Error("System::set_state: wrong state dimension");
  state_ = y;
  touch();
}

ParticleView System::view() const noexcept {
  return ParticleView{time_,
                      positions(),
                      velocities(),
                      Eigen::Map<const Eigen::VectorXd>(mass_.data(), mass_.size()),
                      std::span<const std::uint8_t>(fixed_.data(), fixed_.size()),
                      domain_,
                      std::span<const double>(radius_),
                      std::span<const std::int32_t>(type_)};
}

namespace {

// Runs one plugin call; an exception from it becomes a PluginRuntimeError
// naming the plugin object, so the user learns which scene entry failed.
// The try block costs nothing unless something is thrown; the call scope
// (two stores) lets `pdyn run` name the plugin if it crashes instead.
template <class Call>
void guarded(const std::string& label, const char* hook, Call&& call) {
  const crash::CallScope scope(label, hook);
  try {
    call();
  } catch (const PluginRuntimeError&) {
    throw;
  } catch (const std::exception& e) {
    throw PluginRuntimeError(label, fmt::format("{} threw: {}", hook, e.what()));
  } catch (...) {
    throw PluginRuntimeError(label, fmt::format("{} threw a non-standard exception", hook));
  }
}

void check_finite(const Matrix3X& f, const std::string& label) {
  if (f.allFinite()) return;
  Index i = 0;
  while (f.col(i).allFinite()) ++i;
  throw PluginRuntimeError(label, fmt::format("produced a non-finite force on particle {}: "
                                              "[{}, {}, {}] N",
                                              i, f(0, i), f(1, i), f(2, i)));
}

}  // namespace

void System::add_constraint(std::shared_ptr<Constraint> constraint, std::string label) {
  add_constraint(std::move(constraint), std::move(label), 0.0);
}

void System::add_constraint(std::shared_ptr<Constraint> constraint, std::string label,
                            double compliance) {
  if (!constraint) throw Error(fmt::format("{}: no constraint object", label));
  if (!(compliance >= 0.0) || !std::isfinite(compliance)) {
    throw Error(fmt::format("{}: compliance {} (expected a finite value >= 0)", label, compliance));
  }
  if (!constraint_force_) constraint_force_ = std::make_shared<ConstraintForce>();
  constraint_force_->add(*constraint, label, size(), compliance);
  constraints_.push_back({std::move(constraint), std::move(label)});
  touch();
}

void System::set_constraint_feedback(const ConstraintFeedback& feedback) {
  if (!(feedback.ks >= 0.0) || !(feedback.kd >= 0.0) || !std::isfinite(feedback.ks) ||
      !std::isfinite(feedback.kd) || !(feedback.tolerance > 0.0) || feedback.max_iterations < 0) {
    throw Error(
        "System::set_constraint_feedback: expected finite ks >= 0, kd >= 0, tolerance > 0 "
        "and max_iterations >= 0");
  }
  feedback_ = feedback;
  touch();
}

Index System::constraint_rows() const noexcept {
  return constraint_force_ ? constraint_force_->rows() : 0;
}

double System::constraint_error() const {
  if (!constraint_force_ || constraint_force_->rows() == 0) return 0.0;
  evaluate_constraints();
  return constraint_force_->max_error();
}

double System::constraint_force_virial() const {
  if (constraint_rows() == 0) return 0.0;
  const Eigen::VectorXd& lambda = constraint_force_->multipliers();
  if (!constraint_force_on_ || lambda.size() != constraint_rows()) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return pdyn::constraint_force_virial(view(), constraint_force_->gathered(), lambda);
}

const ConstraintRows& System::evaluate_constraint_rows() const {
  static const ConstraintRows none;
  if (!constraint_force_) return none;
  if (constraint_force_->rows() > 0) evaluate_constraints();
  return constraint_force_->gathered();
}

// Each object writes its rows; a throw, a resized output or a non-finite
// value is reported with the object's label, as for a force.
void System::evaluate_constraints() const {
  if (constraint_force_->max_particle() >= size()) {
    throw Error(
        fmt::format("constraints: a constraint names particle {} but the system has {} "
                    "particles",
                    constraint_force_->max_particle(), size()));
  }
  const ParticleView p = view();
  for (std::size_t k = 0; k < constraints_.size(); ++k) {
    const auto& entry = constraints_[k];
    ConstraintValues& values = constraint_force_->prepare(k);
    guarded(entry.label, "evaluate", [&] { entry.constraint->evaluate(p, values); });
    if (std::string problem = constraint_force_->gather(k); !problem.empty()) {
      throw PluginRuntimeError(entry.label, problem);
    }
  }
}

// Witkin's loop, steps 1 and 2 (clear accumulators, invoke force objects),
// followed by the colliders' contact forces, which must see the total force,
// and the constraint force, which must see both.
// The forces at the end of the list that act locally (pdyn/local_force.hpp)
// are left to the gather, which adds them chunk by chunk
// (add_local_forces); the index of the first of them is returned. Not with
// a collider or the constraint force (they must see them) or finite checks
// (each force is checked on its own).
std::size_t System::evaluate_forces() {
  ++evaluations_;
  std::size_t first_local = forces_.size();
  const bool constrained = constraint_force_on_ && constraint_rows() > 0;
  if (colliders_.empty() && !constrained && !finite_checks_) {
    while (first_local > 0 && local_[first_local - 1].local != nullptr &&
           local_[first_local - 1].local->acts_locally()) {
      --first_local;
    }
  }
  parallel_ranges(size(), [&](Index b, Index e) { force_.middleCols(b, e - b).setZero(); });
  const ParticleView p = view();
  for (std::size_t k = 0; k < first_local; ++k) {
    auto& entry = forces_[k];
    guarded(entry.label, "add_forces", [&] { entry.force->add_forces(p, force_); });
    if (finite_checks_) check_finite(force_, entry.label);
  }
  for (auto& entry : colliders_) {
    guarded(entry.label, "apply_contact_forces",
            [&] { entry.collider->apply_contact_forces(p, force_); });
    if (finite_checks_) check_finite(force_, entry.label);
  }
  // Last, Witkin's constraint force: it must see every applied force.
  if (constrained) {
    evaluate_constraints();
    constraint_force_->add_force(p, inv_mass_, feedback_, force_);
  }
  return first_local;
}

// Forces [first, end of list) on particles [begin, end), in list order; on
// the calling thread of a gather's chunk. The call scope names each for a
// crash report.
void System::add_local_forces(std::size_t first, Index begin, Index end) {
  if (first == forces_.size()) return;
  const ParticleView p = view();
  for (std::size_t k = first; k < forces_.size(); ++k) {
    const crash::CallScope scope(forces_[k].label, "add_forces");
    local_[k].local->add_forces_range(p, force_, begin, end);
  }
}

// The laws (pdyn/local_force.hpp) of local forces [first, end of list), in
// list order, when each has one now and there are at most kMaxLinearLaws;
// otherwise 0, and the gather calls add_forces_range.
int System::linear_laws(std::size_t first, LinearLocalLaw* laws) const {
  const std::size_t count = forces_.size() - first;
  if (count == 0 || count > static_cast<std::size_t>(kMaxLinearLaws)) return 0;
  for (std::size_t k = first; k < forces_.size(); ++k) {
    const LinearLocalForce* linear = local_[k].linear;
    const crash::CallScope scope(forces_[k].label, "linear_law");
    if (linear == nullptr || !linear->linear_law(laws[k - first])) return 0;
  }
  return static_cast<int>(count);
}

namespace {

// Particles per chunk of the gather: the local forces' passes and the gather
// then find the chunk's f, v, masses and output (about 28 KB) in the L1
// cache. 682 (kChunkElements / 3) spilled to L2: 25% slower gathers on the
// 316 x 316 cloth; 128 measured the same as 256.
constexpr Index kGatherChunk = 256;

// Particle i's force after the laws, in their order, stored back so that
// f holds the total force as when the plugins add it. The count is a
// template argument so that the loop over the laws unrolls.
template <int N>
inline void apply_laws(const LinearLocalLaw* laws, double m, const double* v, double* f) {
  double f0 = f[0], f1 = f[1], f2 = f[2];
  for (int k = 0; k < N; ++k) apply_linear_law(laws[k], m, v, f0, f1, f2);
  f[0] = f0;
  f[1] = f1;
  f[2] = f2;
}

}  // namespace

// Step 3, the gather, chunk by chunk: the local forces [first_local, end)
// added into the chunk's f (by their laws in the same loop when they all
// have one, else by add_forces_range), then each particle's f/m handed to
// out(i, f_i, 1/m_i). Each column is independent, so the split over
// threads cannot change a bit.
template <class Out, class Then>
void System::gather(std::size_t first_local, Out out, Then then) {
  LinearLocalLaw laws[kMaxLinearLaws];
  const int n_laws = linear_laws(first_local, laws);
  double* f = force_.data();
  const double* w = inv_mass_.data();
  const double* m = mass_.data();
  const double* v = std::as_const(*this).velocities().data();
  parallel_chunks(size(), kGatherChunk, [&](Index b, Index e) {
    auto by_laws = [&]<int N>(std::integral_constant<int, N>) {
      for (Index i = b; i < e; ++i) {
        apply_laws<N>(laws, m[i], v + 3 * i, f + 3 * i);
        out(i, f + 3 * i, w[i]);
      }
      then(b, e);
    };
    static_assert(kMaxLinearLaws == 4, "a case for every count of laws");
    switch (n_laws) {
      case 1:
        return by_laws(std::integral_constant<int, 1>{});
      case 2:
        return by_laws(std::integral_constant<int, 2>{});
      case 3:
        return by_laws(std::integral_constant<int, 3>{});
      case 4:
        return by_laws(std::integral_constant<int, 4>{});
      default:
        break;
    }
    add_local_forces(first_local, b, e);
    for (Index i = b; i < e; ++i) out(i, f + 3 * i, w[i]);
    then(b, e);
  });
}

namespace {

// 0 * NaN is NaN: a nailed particle must stay put even when a force on it
// blew up, so the blow-up is reported at the particle that moved. Zeroes
// the accelerations a (3 per particle) of the fixed particles in [b, e), a
// gather's chunk, before anything reads them: the sorted fixed ids of the
// chunk by binary search, none in most chunks.
void zero_fixed(const std::vector<Index>& fixed_ids, double* a, Index b, Index e) {
  auto it = std::lower_bound(fixed_ids.begin(), fixed_ids.end(), b);
  for (; it != fixed_ids.end() && *it < e; ++it) a[3 * *it] = a[3 * *it + 1] = a[3 * *it + 2] = 0.0;
}

}  // namespace

// [v | f/m]. A fixed particle has zero velocity (nailing zeroes it and its
// acceleration is zero) and zero inverse mass, so both halves vanish for it
// without a branch.
void System::derivative(Eigen::Ref<Eigen::VectorXd> dydt) { derivative(dydt, {}); }

void System::derivative(Eigen::Ref<Eigen::VectorXd> dydt, DerivativeChunk then) {
  const std::size_t first_local = evaluate_forces();
  const Index n = size();
  // One pass over the particles writes both halves (both streams are
  // memory-bound at large N; one pass reads the state and f once), over
  // local pointers: through Eigen's expressions they were reloaded per
  // element.
  double* out_v = dydt.data();
  double* out_a = dydt.data() + 3 * n;
  const double* in_v = std::as_const(*this).velocities().data();
  gather(
      first_local,
      [&](Index i, const double* fi, double wi) {
        out_v[3 * i] = in_v[3 * i];
        out_v[3 * i + 1] = in_v[3 * i + 1];
        out_v[3 * i + 2] = in_v[3 * i + 2];
        out_a[3 * i] = fi[0] * wi;
        out_a[3 * i + 1] = fi[1] * wi;
        out_a[3 * i + 2] = fi[2] * wi;
      },
      [&](Index b, Index e) {
        zero_fixed(fixed_ids_, out_a, b, e);  // before `then` reads them
        if (then.call != nullptr) then.call(then.context, b, e);
      });
}

const Matrix3X& System::compute_accelerations() {
  const std::size_t first_local = evaluate_forces();
  accel_.resize(3, size());  // allocates on the first call only
  double* out = accel_.data();
  gather(
      first_local,
      [&](Index i, const double* fi, double wi) {
        out[3 * i] = fi[0] * wi;
        out[3 * i + 1] = fi[1] * wi;
        out[3 * i + 2] = fi[2] * wi;
      },
      [&](Index b, Index e) { zero_fixed(fixed_ids_, out, b, e); });
  return accel_;
}

double System::kinetic_energy() const {
  return 0.5 * (velocities().colwise().squaredNorm() * mass_)(0);
}

double System::potential_energy() const {
  const ParticleView p = view();
  double u = 0.0;
  for (const auto& entry : forces_) {
    const crash::CallScope scope(entry.label, "potential_energy");
    if (auto e = entry.force->potential_energy(p)) u += *e;
  }
  return u;
}

void System::respond_to_collisions(double h) {
  if (colliders_.empty()) return;
  const Index n = size();
  MutableParticleView p{time_,
                        positions(),
                        velocities(),
                        Eigen::Map<const Matrix3X>(force_.data(), 3, n),
                        Eigen::Map<const Eigen::VectorXd>(mass_.data(), n),
                        std::span<const std::uint8_t>(fixed_.data(), fixed_.size()),
                        domain_,
                        std::span<const double>(radius_),
                        std::span<const std::int32_t>(type_)};
  for (auto& entry : colliders_) {
    guarded(entry.label, "respond", [&] { entry.collider->respond(p, h); });
  }
}

}  // namespace pdyn
