// symplectic_euler: the semi-implicit (symplectic) Euler method,
//   v1 = v0 + h a(t0, x0, v0),   x1 = x0 + h v1.
// Updating x with the new velocity is what makes it symplectic for
// velocity-independent forces (Hairer, Lubich & Wanner, "Geometric Numerical
// Integration", 2nd ed., Theorem VI.3.3): its energy error stays in a band of
// width O(h) instead of growing like explicit Euler's. First order.
// One force evaluation per step.
#include <pdyn/parallel.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/system.hpp>

namespace {

class SymplecticEuler final : public pdyn::Solver {
 public:
  void step(pdyn::System& sys, double h) override {
    const double t0 = sys.time();
    // Fixed particles get zero acceleration and already have zero velocity,
    // so they stay where they are without a branch.
    const pdyn::Matrix3X& a = sys.compute_accelerations();
    auto x = sys.positions();
    auto v = sys.velocities();
    // Column by column (v first, then x with the new v), split over the
    // host's threads: each column is independent, so no thread-count effect.
    // In chunks that stay in cache from the first statement to the second.
    pdyn::parallel_chunks(sys.size(), pdyn::kChunkElements / 3, [&](pdyn::Index b, pdyn::Index e) {
      v.middleCols(b, e - b) += h * a.middleCols(b, e - b);
      x.middleCols(b, e - b) += h * v.middleCols(b, e - b);
    });
    sys.set_time(t0 + h);
  }
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Solver;
  d.name = "symplectic_euler";
  d.version = "1.0.0";
  d.description = "symplectic Euler: v1 = v0 + h a(x0, v0), x1 = x0 + h v1; order 1, symplectic";
  d.solver_traits.order = 1;
  d.solver_traits.symplectic = true;
  d.create_solver = [](const pdyn::Params&, const pdyn::SceneContext&) {
    return std::make_unique<SymplecticEuler>();
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
