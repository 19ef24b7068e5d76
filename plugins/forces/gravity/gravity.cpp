// gravity: constant gravitational acceleration, f = m g
// (Witkin, SIGGRAPH '97 notes, "Gravity").
#include <pdyn/local_force.hpp>
#include <pdyn/parallel.hpp>
#include <pdyn/periodic_invariant.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/selection.hpp>
#include <pdyn/thermo.hpp>

namespace {

// f_i = m_i g depends on particle i alone: a LocalForce, which the kernel
// adds inside its gather pass when it can, and a LinearLocalForce, whose
// law the kernel then evaluates itself in that pass's loop.
// PeriodicInvariant: a uniform field, so a wrap into a periodic box
// cannot change it (pdyn/periodic_invariant.hpp).
class Gravity final : public pdyn::Force,
                      public pdyn::LocalForce,
                      public pdyn::LinearLocalForce,
                      public pdyn::PeriodicInvariant,
                      public pdyn::VirialSource {
 public:
  /// From outside the system: no virial (pdyn/thermo.hpp), as LAMMPS's fixes.
  double virial(const pdyn::ParticleView&) const override { return 0.0; }

  Gravity(const pdyn::Vec3& g, pdyn::Selection selection)
      : g_(g), selection_(std::move(selection)) {}

  void add_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    if (selection_.all()) {
      // Column ranges on the host's threads; columns are independent.
      pdyn::parallel_ranges(p.size(),
                            [&](pdyn::Index b, pdyn::Index e) { add_forces_range(p, f, b, e); });
      return;
    }
    for (const pdyn::Index i : selection_.ids()) f.col(i) += p.mass(i) * g_;
  }

  bool acts_locally() const override { return selection_.all(); }
  // f_i += g m_i, as add_forces_range computes it.
  bool linear_law(pdyn::LinearLocalLaw& law) const override {
    law.has_acceleration = true;
    law.acceleration = g_;
    return true;
  }
  void add_forces_range(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f, pdyn::Index b,
                        pdyn::Index e) override {
    // Plain loops over locals: Eigen's outer product g m^T through a Ref
    // with a run-time stride took twice the time of the hand-fused gather.
    double* fp = f.data();
    const pdyn::Index fs = f.outerStride();
    const double* m = p.mass.data();
    const double gx = g_.x(), gy = g_.y(), gz = g_.z();
    for (pdyn::Index i = b; i < e; ++i) {
      double* fi = fp + fs * i;
      fi[0] += gx * m[i];
      fi[1] += gy * m[i];
      fi[2] += gz * m[i];
    }
  }

  // f = m g reads neither velocities nor time.
  pdyn::StateDependence dependence() const override { return {false, false}; }

  // A constant force: both Jacobians are zero, so there is nothing to add,
  // but saying so spares implicit solvers a finite difference.
  bool add_jacobians(const pdyn::ParticleView&, pdyn::JacobianSink&) override { return true; }

  // U = -sum m g.x, so that f = -grad U = m g.
  std::optional<double> potential_energy(const pdyn::ParticleView& p) const override {
    if (selection_.all()) return -(g_.transpose() * p.x * p.mass)(0);
    double u = 0.0;
    for (const pdyn::Index i : selection_.ids()) u -= p.mass(i) * g_.dot(p.x.col(i));
    return u;
  }

 private:
  pdyn::Vec3 g_;
  pdyn::Selection selection_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "gravity";
  d.version = "1.0.0";
  d.description = "constant gravity on every particle (or a group, or ids): f = m g";
  d.params = {pdyn::param::vec3("g", {0, 0, -9.81}, "m/s^2", "gravitational acceleration")};
  for (auto& s : pdyn::selection_params()) d.params.push_back(std::move(s));
  d.create_force = [](const pdyn::Params& p, const pdyn::SceneContext& ctx) {
    return std::make_unique<Gravity>(p.vec3("g"), pdyn::Selection::from_params(p, ctx));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
