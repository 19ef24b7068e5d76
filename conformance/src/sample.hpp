// What the checks are run on: seeded random particle configurations, the
// kit's own forces (anchor, constant), the helpers that compare what a
// plugin produced, and (public, conformance.hpp) sample_params. Shared by
// the check modules; see sample.cpp.
#pragma once

#include <cstdint>
#include <random>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "pdyn/force.hpp"
#include "pdyn/periodic_invariant.hpp"
#include "pdyn/plugin.hpp"
#include "pdyn/thermo.hpp"

namespace pdyn::conformance::detail {

/// Particles in the configurations the checks build.
inline constexpr Index kParticles = 6;

// ---- particle configurations ----

/// Every particle's radius in the kit's states, m: large enough that
/// contact laws (soft_contact) see overlapping pairs among kParticles
/// particles in [-1, 1]^3 m.
inline constexpr double kRadius = 0.5;

struct State {
  Matrix3X x, v, f;
  Eigen::VectorXd mass;
  std::vector<std::uint8_t> fixed;
  std::vector<double> radius;
  Domain domain{};  ///< open space unless a check (pair.matches_brute_force) makes a box
  double t = 0.0;

  Index size() const { return x.cols(); }
  ParticleView view() const {
    return ParticleView{t,
                        Eigen::Map<const Matrix3X>(x.data(), 3, size()),
                        Eigen::Map<const Matrix3X>(v.data(), 3, size()),
                        Eigen::Map<const Eigen::VectorXd>(mass.data(), size()),
                        std::span<const std::uint8_t>(fixed),
                        domain,
                        std::span<const double>(radius),
                        {}};
  }
  MutableParticleView mutable_view() {
    return MutableParticleView{t,
                               Eigen::Map<Matrix3X>(x.data(), 3, size()),
                               Eigen::Map<Matrix3X>(v.data(), 3, size()),
                               Eigen::Map<const Matrix3X>(f.data(), 3, size()),
                               Eigen::Map<const Eigen::VectorXd>(mass.data(), size()),
                               std::span<const std::uint8_t>(fixed),
                               domain,
                               std::span<const double>(radius),
                               {}};
  }
};

/// `n` particles of 1 kg at rest at the origin, none fixed, t = 0.
State make_state(Index n);

/// Positions in [-1, 1]^3 m, velocities in [-1, 1]^3 m/s, masses in [0.5, 2] kg.
State random_state(std::mt19937_64& rng, Index n = kParticles);

/// The degenerate configurations of the no-NaN checks, each with its label.
std::vector<std::pair<std::string, State>> degenerate_states(std::mt19937_64& rng);

inline SceneContext context_of(const State& s) { return SceneContext{s.view(), nullptr}; }

// ---- the kit's own forces ----

/// f = -k x (k = 1 N/m) on every particle: with m = 1 kg, x(t) = x0 cos t + v0 sin t.
class Anchor final : public Force {
 public:
  void add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) override;
  bool add_jacobians(const ParticleView& p, JacobianSink& sink) override;
  std::optional<double> potential_energy(const ParticleView& p) const override;
};

/// f = m g, constant.
class Constant final : public Force {
 public:
  explicit Constant(Vec3 g) : g_(std::move(g)) {}
  void add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) override;
  bool add_jacobians(const ParticleView&, JacobianSink&) override;

 private:
  Vec3 g_;
};

/// Soft spheres: U = (1 - r / 1.2 m)^2 J per pair closer than 1.2 m,
/// every pair at its nearest periodic image, with its virial: the kit's
/// periodic liquid, on which solver.extended_energy runs a thermostat or a
/// barostat (a solver that reads the pressure needs pdyn::VirialSource).
class SoftSpheres final : public Force, public VirialSource, public PeriodicInvariant {
 public:
  void add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) override;
  std::optional<double> potential_energy(const ParticleView& p) const override;
  double virial(const ParticleView& p) const override;
  StateDependence dependence() const override { return {false, false}; }  // positions only
};

/// The force `force` adds to zero accumulators in state `s`, N.
Matrix3X forces_of(Force& force, const State& s);

// ---- comparing results ----

/// Same shape and the same bits.
bool bit_equal(const Matrix3X& a, const Matrix3X& b);
bool bit_equal(const Eigen::VectorXd& a, const Eigen::VectorXd& b);

/// max |m_ij|, 0 for an empty matrix.
double max_abs(const Matrix3X& m);

/// 0 when a and b are the same bits, else max |a - b| (at least 1e-300, so
/// that a difference in a zero's sign still counts): the measure of checks
/// that demand bit-identical results.
double bits_apart(const Matrix3X& a, const Matrix3X& b);

/// How many entries are NaN or infinite.
std::size_t non_finite(const Matrix3X& m);

}  // namespace pdyn::conformance::detail
