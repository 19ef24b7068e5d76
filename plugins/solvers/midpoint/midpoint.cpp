// midpoint: the explicit midpoint method (second-order Runge-Kutta):
//   k1 = f(t0, y0),  k2 = f(t0 + h/2, y0 + h/2 k1),  y1 = y0 + h k2.
#include <pdyn/parallel.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/system.hpp>

namespace {

class Midpoint final : public pdyn::Solver {
 public:
  void step(pdyn::System& sys, double h) override {
    const double t0 = sys.time();
    const pdyn::Index n = sys.dimension();
    y0_.resize(n);  // allocates only when the dimension changes
    k_.resize(n);
    auto y = sys.state();
    // y = y0 + c k, split over the host's threads; element-wise, so the
    // result does not depend on the thread count.
    auto stage = [&](double c) {
      pdyn::parallel_state_chunks(n, n, [&](pdyn::Index b, pdyn::Index e) {
        y.segment(b, e - b) = y0_.segment(b, e - b) + c * k_.segment(b, e - b);
      });
    };
    pdyn::parallel_state_chunks(
        n, n, [&](pdyn::Index b, pdyn::Index e) { y0_.segment(b, e - b) = y.segment(b, e - b); });
    sys.derivative(k_);
    stage(0.5 * h);
    sys.set_time(t0 + 0.5 * h);
    sys.derivative(k_);
    stage(h);
    sys.set_time(t0 + h);
  }

 private:
  Eigen::VectorXd y0_, k_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Solver;
  d.name = "midpoint";
  d.version = "1.0.0";
  d.description = "explicit midpoint: y1 = y0 + h f(t0 + h/2, y0 + h/2 f(t0, y0)); order 2";
  d.solver_traits.order = 2;
  d.create_solver = [](const pdyn::Params&, const pdyn::SceneContext&) {
    return std::make_unique<Midpoint>();
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
