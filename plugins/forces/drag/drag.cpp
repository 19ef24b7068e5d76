// drag: linear viscous drag, f = -k v (Witkin, SIGGRAPH '97 notes,
// "Viscous Drag"). It removes energy, so it declares itself dissipative.
#include <pdyn/parallel.hpp>
#include <pdyn/plugin.hpp>

namespace {

class Drag final : public pdyn::Force {
 public:
  explicit Drag(double k) : k_(k) {}

  void add_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    // Column ranges on the host's threads; columns are independent.
    pdyn::parallel_ranges(p.size(), [&](pdyn::Index b, pdyn::Index e) {
      f.middleCols(b, e - b).noalias() -= k_ * p.v.middleCols(b, e - b);
    });
  }

  // df_i/dv_i = -k I for every particle; no position dependence.
  bool add_jacobians(const pdyn::ParticleView& p, pdyn::JacobianSink& sink) override {
    const Eigen::Matrix3d block = -k_ * Eigen::Matrix3d::Identity();
    for (pdyn::Index i = 0; i < p.size(); ++i) sink.add_dfdv(i, i, block);
    return true;
  }

 private:
  double k_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "drag";
  d.version = "1.0.0";
  d.description = "linear viscous drag on every particle: f = -k v";
  d.params = {pdyn::param::real("k", 0.1, "kg/s", "drag coefficient").at_least(0)};
  d.force_traits.dissipative = true;
  d.create_force = [](const pdyn::Params& p, const pdyn::SceneContext&) {
    return std::make_unique<Drag>(p.real("k"));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
