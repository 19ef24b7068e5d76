// drag: linear viscous drag, f = -k v (Witkin, SIGGRAPH '97 notes,
// "Viscous Drag"). It removes energy, so it declares itself dissipative.
#include <pdyn/local_force.hpp>
#include <pdyn/parallel.hpp>
#include <pdyn/periodic_invariant.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/selection.hpp>
#include <pdyn/thermo.hpp>

namespace {

// f_i = -k v_i depends on particle i alone: a LocalForce, which the kernel
// adds inside its gather pass when it can, and a LinearLocalForce, whose
// law the kernel then evaluates itself in that pass's loop.
// PeriodicInvariant: it reads velocities only, so a wrap into a periodic box
// cannot change it (pdyn/periodic_invariant.hpp).
class Drag final : public pdyn::Force,
                   public pdyn::LocalForce,
                   public pdyn::LinearLocalForce,
                   public pdyn::PeriodicInvariant,
                   public pdyn::VirialSource {
 public:
  /// From outside the system: no virial (pdyn/thermo.hpp), as LAMMPS's fixes.
  double virial(const pdyn::ParticleView&) const override { return 0.0; }

  Drag(double k, pdyn::Selection selection) : k_(k), selection_(std::move(selection)) {}

  void add_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    if (selection_.all()) {
      // Column ranges on the host's threads; columns are independent.
      pdyn::parallel_ranges(p.size(),
                            [&](pdyn::Index b, pdyn::Index e) { add_forces_range(p, f, b, e); });
      return;
    }
    for (const pdyn::Index i : selection_.ids()) f.col(i) -= k_ * p.v.col(i);
  }

  bool acts_locally() const override { return selection_.all(); }
  // f_i -= k v_i, as add_forces_range computes it.
  bool linear_law(pdyn::LinearLocalLaw& law) const override {
    law.has_damping = true;
    law.damping = k_;
    return true;
  }
  void add_forces_range(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f, pdyn::Index b,
                        pdyn::Index e) override {
    // Plain loops over locals, as gravity's (the gather's chunk is in cache);
    // over a dense accumulator one flat loop of 3 (e - b) doubles, which the
    // compiler vectorises.
    double* fp = f.data();
    const pdyn::Index fs = f.outerStride();
    const double* v = p.v.data();
    const double k = k_;
    if (fs == 3) {
      for (pdyn::Index q = 3 * b; q < 3 * e; ++q) fp[q] -= k * v[q];
      return;
    }
    for (pdyn::Index i = b; i < e; ++i) {
      double* fi = fp + fs * i;
      fi[0] -= k * v[3 * i];
      fi[1] -= k * v[3 * i + 1];
      fi[2] -= k * v[3 * i + 2];
    }
  }

  pdyn::StateDependence dependence() const override { return {true, false}; }

  // df_i/dv_i = -k I for every selected particle; no position dependence.
  bool add_jacobians(const pdyn::ParticleView& p, pdyn::JacobianSink& sink) override {
    const Eigen::Matrix3d block = -k_ * Eigen::Matrix3d::Identity();
    if (selection_.all()) {
      for (pdyn::Index i = 0; i < p.size(); ++i) sink.add_dfdv(i, i, block);
    } else {
      for (const pdyn::Index i : selection_.ids()) sink.add_dfdv(i, i, block);
    }
    return true;
  }

 private:
  double k_;
  pdyn::Selection selection_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "drag";
  d.version = "1.0.0";
  d.description = "linear viscous drag on every particle (or a group, or ids): f = -k v";
  d.params = {pdyn::param::real("k", 0.1, "kg/s", "drag coefficient").at_least(0)};
  for (auto& s : pdyn::selection_params()) d.params.push_back(std::move(s));
  d.force_traits.dissipative = true;
  d.create_force = [](const pdyn::Params& p, const pdyn::SceneContext& ctx) {
    return std::make_unique<Drag>(p.real("k"), pdyn::Selection::from_params(p, ctx));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
