// @NAME@: a linear tether pulling every particle towards an anchor point,
//   f_i = -k (x_i - a) - c v_i,   U = k/2 sum_i |x_i - a|^2.
// A zero-rest-length spring to a fixed point, with damping: the simplest force
// that has a potential and analytic Jacobians. Replace the physics with yours;
// `pdyn check @NAME@` then tells you whether the claims below still hold.
#include <pdyn/plugin.hpp>

namespace {

class Tether final : public pdyn::Force {
 public:
  Tether(const pdyn::Vec3& anchor, double k, double c) : a_(anchor), k_(k), c_(c) {}

  // Only add into f: the other forces' contributions are already there.
  void add_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    f.noalias() -= k_ * (p.x.colwise() - a_) + c_ * p.v;
  }

  // The damping term has no potential; the kit compares f with -dU/dx at v = 0.
  std::optional<double> potential_energy(const pdyn::ParticleView& p) const override {
    return 0.5 * k_ * (p.x.colwise() - a_).squaredNorm();
  }

  // Reads velocities only through the damping, and never the time: with
  // c = 0, velocity Verlet evaluates it once per step instead of twice.
  pdyn::StateDependence dependence() const override { return {c_ > 0.0, false}; }

  // df_i/dx_i = -k I, df_i/dv_i = -c I, for implicit solvers.
  bool add_jacobians(const pdyn::ParticleView& p, pdyn::JacobianSink& sink) override {
    const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
    for (pdyn::Index i = 0; i < p.size(); ++i) {
      sink.add_dfdx(i, i, -k_ * identity);
      sink.add_dfdv(i, i, -c_ * identity);
    }
    return true;
  }

 private:
  pdyn::Vec3 a_;
  double k_, c_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "@NAME@";
  d.version = "0.1.0";
  d.description = "tether to an anchor point: f = -k (x - a) - c v, U = k/2 |x - a|^2";
  d.params = {
      pdyn::param::vec3("anchor", {0, 0, 0}, "m", "anchor point a"),
      pdyn::param::real("k", 10.0, "N/m", "stiffness").at_least(0),
      pdyn::param::real("c", 0.1, "N s/m", "damping coefficient").at_least(0),
  };
  // Not internal (it pulls towards a fixed point, so momentum is not
  // conserved) and not dissipative (the spring does positive work too).
  d.force_traits.internal = false;
  d.force_traits.dissipative = false;
  d.create_force = [](const pdyn::Params& p, const pdyn::SceneContext&) {
    return std::make_unique<Tether>(p.vec3("anchor"), p.real("k"), p.real("c"));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
