// euler: the explicit (forward) Euler method, y1 = y0 + h f(t0, y0).
// First order; Witkin's notes use it to introduce the solver interface.
#include <pdyn/parallel.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/system.hpp>

namespace {

class Euler final : public pdyn::Solver {
 public:
  void step(pdyn::System& sys, double h) override {
    dydt_.resize(sys.dimension());  // no-op after the first step
    sys.derivative(dydt_);
    auto y = sys.state();
    // Split over the host's threads by particle (pdyn::parallel_state_chunks);
    // element-wise, so thread-count independent.
    pdyn::parallel_state_chunks(y.size(), y.size(), [&](pdyn::Index b, pdyn::Index e) {
      y.segment(b, e - b) += h * dydt_.segment(b, e - b);
    });
    sys.set_time(sys.time() + h);
  }

 private:
  Eigen::VectorXd dydt_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Solver;
  d.name = "euler";
  d.version = "1.0.0";
  d.description = "explicit Euler: y1 = y0 + h f(t0, y0); order 1";
  d.solver_traits.order = 1;
  d.create_solver = [](const pdyn::Params&, const pdyn::SceneContext&) {
    return std::make_unique<Euler>();
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
