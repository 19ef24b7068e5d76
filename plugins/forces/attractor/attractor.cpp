// attractor: a central force towards (strength > 0) or away from (strength <
// 0) a fixed center, proportional to each particle's mass like gravity, so
// `strength` is the G M of the central body and every particle orbits alike
// whatever its mass. With d = x_i - c, r = |d|, q = r^2 + eps^2, p the
// exponent:
//
//   f_i = -strength m_i d / q^((p+1)/2)
//
// i.e. magnitude strength m_i r / (r^2 + eps^2)^((p+1)/2): exactly strength
// m_i / r^p without softening and far from the center, and Plummer-softened
// near it (Plummer 1911; Aarseth, "Gravitational N-body simulations", 2003,
// section 2.4): smooth, and zero at the center instead of singular. This
// softened form has a closed-form potential for every exponent:
//
//   U_i = -strength m_i q^((1-p)/2) / (p - 1)     (p != 1)
//   U_i =  strength m_i ln(q) / 2                 (p = 1)
//
// (dU/dr = strength m_i r q^(-(p+1)/2) in both cases). p = 2 is Newtonian
// gravity, p = -1 an isotropic harmonic trap.
#include <fmt/format.h>

#include <cmath>
#include <pdyn/plugin.hpp>
#include <pdyn/selection.hpp>
#include <pdyn/thermo.hpp>

namespace {

using pdyn::Index;
using pdyn::Vec3;

class Attractor final : public pdyn::Force, public pdyn::VirialSource {
 public:
  /// From outside the system: no virial (pdyn/thermo.hpp), as LAMMPS's fixes.
  double virial(const pdyn::ParticleView&) const override { return 0.0; }

  Attractor(const Vec3& center, double strength, double softening, double exponent,
            pdyn::Selection selection)
      : center_(center),
        strength_(strength),
        eps2_(softening * softening),
        p_(exponent),
        selection_(std::move(selection)) {}

  void add_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    each(p, [&](Index i) {
      const Vec3 d = p.x.col(i) - center_;
      const double q = d.squaredNorm() + eps2_;
      if (!(q > 0.0)) return;  // unsoftened, at the center: no direction
      f.col(i) -= strength_ * p.mass(i) * std::pow(q, -0.5 * (p_ + 1.0)) * d;
    });
  }

  pdyn::StateDependence dependence() const override { return {false, false}; }

  std::optional<double> potential_energy(const pdyn::ParticleView& p) const override {
    double u = 0.0;
    each(p, [&](Index i) {
      const double q = (p.x.col(i) - center_).squaredNorm() + eps2_;
      if (!(q > 0.0)) return;
      const double shape =
          p_ == 1.0 ? 0.5 * std::log(q) : -std::pow(q, 0.5 * (1.0 - p_)) / (p_ - 1.0);
      u += strength_ * p.mass(i) * shape;
    });
    return u;
  }

  // df_i/dx_i = -strength m_i [I q^(-(p+1)/2) - (p+1) d d^T q^(-(p+3)/2)].
  bool add_jacobians(const pdyn::ParticleView& p, pdyn::JacobianSink& sink) override {
    each(p, [&](Index i) {
      const Vec3 d = p.x.col(i) - center_;
      const double q = d.squaredNorm() + eps2_;
      if (!(q > 0.0)) return;
      const double a = std::pow(q, -0.5 * (p_ + 1.0));
      const Eigen::Matrix3d block =
          -strength_ * p.mass(i) *
          (a * Eigen::Matrix3d::Identity() - (p_ + 1.0) * a / q * d * d.transpose());
      sink.add_dfdx(i, i, block);
    });
    return true;
  }

 private:
  template <class F>
  void each(const pdyn::ParticleView& p, F&& f) const {
    if (selection_.all()) {
      for (Index i = 0; i < p.size(); ++i) f(i);
    } else {
      for (const Index i : selection_.ids()) f(i);
    }
  }

  Vec3 center_;
  double strength_, eps2_, p_;
  pdyn::Selection selection_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "attractor";
  d.version = "1.0.0";
  d.description =
      "central force per unit mass: f = -strength m d / (r^2 + softening^2)^((exponent+1)/2), d = "
      "x - center";
  d.params = {
      pdyn::param::vec3("center", pdyn::Vec3::Zero(), "m", "the center"),
      pdyn::param::real("strength", 1.0, "m^(exponent+1)/s^2",
                        "G M of the center: > 0 attracts, < 0 repels"),
      pdyn::param::real("softening", 0.01, "m", "Plummer softening length").at_least(0),
      pdyn::param::real("exponent", 2.0, "", "p in 1/r^p (2: gravity)"),
  };
  for (auto& s : pdyn::selection_params()) d.params.push_back(std::move(s));
  d.create_force = [](const pdyn::Params& p, const pdyn::SceneContext& ctx) {
    return std::make_unique<Attractor>(p.vec3("center"), p.real("strength"), p.real("softening"),
                                       p.real("exponent"), pdyn::Selection::from_params(p, ctx));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
