// Maxwell-Boltzmann velocities (pdyn/host/velocities.hpp).
#include "pdyn/host/velocities.hpp"

#include <fmt/format.h>

#include <cmath>

#include "pdyn/error.hpp"
#include "pdyn/random.hpp"

namespace pdyn {

void maxwell_boltzmann(Eigen::Ref<Matrix3X> v, const Eigen::VectorXd& mass,
                       std::span<const std::uint8_t> fixed, const VelocitySpec& spec) {
  std::vector<Index> free;
  auto consider = [&](Index i) {
    if (fixed.empty() || fixed[static_cast<std::size_t>(i)] == 0) free.push_back(i);
  };
  if (spec.members.empty()) {
    for (Index i = 0; i < v.cols(); ++i) consider(i);
  } else {
    for (const Index i : spec.members) consider(i);
  }
  const RandomKey key{spec.seed, random_stream::kVelocities};
  for (const Index i : free) {
    v.col(i) =
        std::sqrt(spec.kT / mass(i)) * standard_normal3(key, 0, static_cast<std::uint64_t>(i));
  }
  // Sums in the members' order: the same bits on every machine and thread count.
  if (spec.zero_momentum && !free.empty()) {
    Vec3 p = Vec3::Zero();
    double m = 0.0;
    for (const Index i : free) {
      p += mass(i) * v.col(i);
      m += mass(i);
    }
    const Vec3 centre = p / m;
    for (const Index i : free) v.col(i) -= centre;
  }
  if (!spec.scale) return;
  const double dof = 3.0 * static_cast<double>(free.size()) - (spec.zero_momentum ? 3.0 : 0.0);
  if (dof <= 0) {
    throw Error(fmt::format(
        "{} free particle{} {} no thermal degrees of freedom once the momentum is removed "
        "(expected at least 2, or zero_momentum: false)",
        free.size(), free.size() == 1 ? "" : "s", free.size() == 1 ? "has" : "have"));
  }
  double twice_k = 0.0;
  for (const Index i : free) twice_k += mass(i) * v.col(i).squaredNorm();
  if (spec.kT == 0.0) return;  // every velocity is zero already
  if (!(twice_k > 0)) throw Error("every drawn velocity is zero (expected a temperature > 0)");
  const double factor = std::sqrt(spec.kT * dof / twice_k);
  for (const Index i : free) v.col(i) *= factor;
}

}  // namespace pdyn
