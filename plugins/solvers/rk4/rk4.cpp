// rk4: the classic fourth-order Runge-Kutta method,
//   k1 = f(t0, y0)             k2 = f(t0 + h/2, y0 + h/2 k1)
//   k3 = f(t0 + h/2, y0 + h/2 k2)   k4 = f(t0 + h, y0 + h k3)
//   y1 = y0 + h/6 (k1 + 2 k2 + 2 k3 + k4).
// Stage states are written straight into the system's state (no set_state
// copy); the weighted sum is accumulated in `sum_` as the stages arrive so
// only one derivative buffer is live at a time. Each vector update is one
// fused pass (sum and next stage state together): at large N the step is
// memory-bound, so passes, not flops, are what cost. The passes are split
// over the host's threads; every element is computed alike whatever the
// split, so the result does not depend on the thread count.
#include <pdyn/parallel.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/system.hpp>

namespace {

using pdyn::Index;

class Rk4 final : public pdyn::Solver {
 public:
  void step(pdyn::System& sys, double h) override {
    const double t0 = sys.time();
    const Index n = sys.dimension();
    y0_.resize(n);  // these allocate on the first step only
    k_.resize(n);
    sum_.resize(n);
    auto y = sys.state();
    // Applies update(segment of y, of y0, of k, of sum) over [0, n) in
    // parallel, chunk by chunk: the statements of one update then read each
    // vector from memory once.
    auto update = [&](auto&& op) {
      pdyn::parallel_state_chunks(n, pdyn::kChunkElements, [&](Index b, Index e) {
        op(y.segment(b, e - b), y0_.segment(b, e - b), k_.segment(b, e - b),
           sum_.segment(b, e - b));
      });
    };
    sys.derivative(k_);  // k1
    // y0 is saved in the pass that takes the first stage: one pass less.
    update([h](auto yy, auto y0, auto k, auto sum) {
      y0 = yy;
      sum = k;
      yy = y0 + (0.5 * h) * k;
    });
    sys.set_time(t0 + 0.5 * h);

    sys.derivative(k_);  // k2
    update([h](auto yy, auto y0, auto k, auto sum) {
      sum += 2.0 * k;
      yy = y0 + (0.5 * h) * k;
    });

    sys.derivative(k_);  // k3
    update([h](auto yy, auto y0, auto k, auto sum) {
      sum += 2.0 * k;
      yy = y0 + h * k;
    });
    sys.set_time(t0 + h);

    sys.derivative(k_);  // k4
    update([h](auto yy, auto y0, auto k, auto sum) {
      sum += k;
      yy = y0 + (h / 6.0) * sum;
    });
  }

 private:
  Eigen::VectorXd y0_, k_, sum_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Solver;
  d.name = "rk4";
  d.version = "1.0.0";
  d.description = "classic fourth-order Runge-Kutta; order 4";
  d.solver_traits.order = 4;
  d.create_solver = [](const pdyn::Params&, const pdyn::SceneContext&) {
    return std::make_unique<Rk4>();
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
