// What the checks are run on (see sample.hpp): the seeded random particle
// configurations every check builds its own small system from, so that a
// report is reproducible from (plugin, seed); the kit's own forces; the
// helpers that compare results; and sample_params, the parameters every
// check constructs the plugin with.
#include "sample.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "pdyn/host/resolve.hpp"

namespace pdyn::conformance {

namespace detail {

// ---- particle configurations ----

State make_state(Index n) {
  State s;
  s.x = Matrix3X::Zero(3, n);
  s.v = Matrix3X::Zero(3, n);
  s.f = Matrix3X::Zero(3, n);
  s.mass = Eigen::VectorXd::Ones(n);
  s.fixed.assign(static_cast<std::size_t>(n), 0);
  s.radius.assign(static_cast<std::size_t>(n), kRadius);
  return s;
}

State random_state(std::mt19937_64& rng, Index n) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  State s = make_state(n);
  for (Index i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      s.x(k, i) = u(rng);
      s.v(k, i) = u(rng);
    }
    s.mass(i) = 1.25 + 0.75 * u(rng);
  }
  s.t = 0.5 + 0.5 * u(rng);
  return s;
}

std::vector<std::pair<std::string, State>> degenerate_states(std::mt19937_64& rng) {
  std::vector<std::pair<std::string, State>> out;
  State base = random_state(rng);
  State coincident = base;
  for (Index i = 0; i < coincident.size(); ++i) coincident.x.col(i) = base.x.col(0);
  out.emplace_back("coincident", coincident);
  State coincident_rest = coincident;
  coincident_rest.v.setZero();
  out.emplace_back("coincident at rest", coincident_rest);
  State rest = base;
  rest.v.setZero();
  out.emplace_back("at rest", rest);
  State far = base;
  far.x.colwise() += Vec3(1e6, -1e6, 1e6);
  out.emplace_back("far from the origin (1e6 m)", far);
  return out;
}

// ---- the kit's own forces ----

void Anchor::add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) { f -= p.x; }

bool Anchor::add_jacobians(const ParticleView& p, JacobianSink& sink) {
  for (Index i = 0; i < p.size(); ++i) sink.add_dfdx(i, i, -Eigen::Matrix3d::Identity());
  return true;
}

std::optional<double> Anchor::potential_energy(const ParticleView& p) const {
  return 0.5 * p.x.squaredNorm();
}

namespace {

// Calls pair(i, j, d, r) for every pair closer than the spheres' diameter,
// d = x_i - x_j at the nearest image, r = |d|.
template <class Pair>
void soft_pairs(const ParticleView& p, Pair&& pair) {
  constexpr double kDiameter = 1.2;
  for (Index i = 0; i < p.size(); ++i) {
    for (Index j = i + 1; j < p.size(); ++j) {
      const Vec3 d = p.domain.minimum_image(p.x.col(i) - p.x.col(j));
      const double r = d.norm();
      if (r < kDiameter && r > 0.0) pair(i, j, d, r, 1.0 - r / kDiameter, kDiameter);
    }
  }
}

}  // namespace

void SoftSpheres::add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) {
  soft_pairs(p, [&](Index i, Index j, const Vec3& d, double r, double overlap, double diameter) {
    const Vec3 fij = (2.0 * overlap / (diameter * r)) * d;  // -dU/dr along d
    f.col(i) += fij;
    f.col(j) -= fij;
  });
}

std::optional<double> SoftSpheres::potential_energy(const ParticleView& p) const {
  double u = 0.0;
  soft_pairs(p, [&](Index, Index, const Vec3&, double, double overlap, double) {
    u += overlap * overlap;
  });
  return u;
}

double SoftSpheres::virial(const ParticleView& p) const {
  double w = 0.0;
  soft_pairs(p, [&](Index, Index, const Vec3&, double r, double overlap, double diameter) {
    w += 2.0 * overlap * r / diameter;  // d . f_ij
  });
  return w;
}

void Constant::add_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) {
  f.noalias() += g_ * p.mass.transpose();
}

bool Constant::add_jacobians(const ParticleView&, JacobianSink&) { return true; }

// ---- comparing results ----

bool bit_equal(const Matrix3X& a, const Matrix3X& b) {
  return a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0;
}

double bits_apart(const Matrix3X& a, const Matrix3X& b) {
  return bit_equal(a, b) ? 0.0 : std::max(max_abs(a - b), 1e-300);
}

bool bit_equal(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0;
}

Matrix3X forces_of(Force& force, const State& s) {
  Matrix3X f = Matrix3X::Zero(3, s.size());
  force.add_forces(s.view(), f);
  return f;
}

double max_abs(const Matrix3X& m) { return m.size() == 0 ? 0.0 : m.cwiseAbs().maxCoeff(); }

std::size_t non_finite(const Matrix3X& m) {
  std::size_t count = 0;
  for (Index k = 0; k < m.size(); ++k) count += std::isfinite(m.data()[k]) ? 0 : 1;
  return count;
}

}  // namespace detail

// ---- the parameters the checks construct a plugin with ----
//
// Documented in pdyn/conformance.hpp. Every check of every kind, and
// params.bad_rejected's baseline scene, constructs the plugin with
// sample_params; constraint.satisfied_at_creation with default_params.

namespace {

// A typical value of a required parameter's type that declares no sample:
// a number inside the declared range, preferring 1; particle lists over the
// first, second and last of the `n` particles.
ParamValue typical_value(const ParamSpec& s, Index n) {
  double x = 1.0;
  if (s.min && x <= *s.min) x = *s.min + 1.0;
  if (s.max && x > *s.max) x = s.min ? 0.5 * (*s.min + *s.max) : *s.max - 1.0;
  switch (s.type) {
    case ParamType::Real:
      return x;
    case ParamType::Integer:
      return static_cast<std::int64_t>(std::ceil(x));
    case ParamType::Boolean:
      return false;
    case ParamType::String:
      return std::string{};
    case ParamType::Vector:
      return Vec3(0.3, -0.2, 0.9);
    case ParamType::RealList:
      return std::vector<double>{x};
    case ParamType::VectorList:
      return std::vector<Vec3>{Vec3(0.3, -0.2, 0.9)};
    case ParamType::IndexList:
      return std::vector<Index>{0, 1, n - 1};
    case ParamType::IndexPairs:
      return std::vector<IndexPair>{{0, 1}, {1, 2}, {2, 3}, {0, n - 1}};
    case ParamType::IndexTriples:
      return std::vector<IndexTriple>{{0, 1, 2}, {1, 2, 3}};
    case ParamType::IndexQuads:
      return std::vector<IndexQuad>{{0, 1, 2, 3}, {1, 2, 3, 4}};
    case ParamType::IntegerList:
      return IntegerValues{static_cast<std::int64_t>(std::ceil(x))};
    case ParamType::StringList:
      return std::vector<std::string>{"1"};
    case ParamType::NamedReals:
      return NamedReals{{"a", x}};
  }
  return x;
}

}  // namespace

// The given values are each parameter's `sample`, and for a required one
// without a sample a typical value of its type; resolve() (the loader's own
// resolver) adds every default. Its problems are ignored: a sample is not
// checked against the bounds (ParamSpec::sample says so), and a default that
// breaks them is params.bad_rejected's finding, not this function's.
Params sample_params(const PluginDescriptor& d, Index n) {
  Params p;
  for (const auto& s : d.params) {
    if (s.sample) {
      p.set(s.name, *s.sample);
    } else if (s.required && !s.fallback) {
      p.set(s.name, typical_value(s, n));
    }
  }
  return resolve(d.params, p).params;
}

// Only the required parameters are given (their sample, or a typical
// value); resolve() adds the defaults, and an optional parameter without a
// default stays out even if it declares a sample.
Params default_params(const PluginDescriptor& d, Index n) {
  Params p;
  for (const auto& s : d.params) {
    if (!s.required || s.fallback) continue;
    p.set(s.name, s.sample ? *s.sample : typical_value(s, n));
  }
  return resolve(d.params, p).params;
}

}  // namespace pdyn::conformance
