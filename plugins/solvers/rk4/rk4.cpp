// rk4: the classic fourth-order Runge-Kutta method,
//   k1 = f(t0, y0)             k2 = f(t0 + h/2, y0 + h/2 k1)
//   k3 = f(t0 + h/2, y0 + h/2 k2)   k4 = f(t0 + h, y0 + h k3)
//   y1 = y0 + h/6 (k1 + 2 k2 + 2 k3 + k4).
// Stage states are written straight into the system's state (no set_state
// copy); the weighted sum is accumulated in `sum_` as the stages arrive so
// only one derivative buffer is live at a time. Each stage's update (sum and
// next stage state together) is done chunk by chunk inside the derivative's
// own pass over the particles, as each chunk's slope is written: at large N
// the step is memory-bound, so passes, not flops, are what cost.
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
    double* y = sys.state().data();
    double* y0 = y0_.data();
    double* k = k_.data();
    double* sum = sum_.data();
    // Applies op(element) to the elements of each chunk of particles as the
    // system hands it over, right after writing the chunk's slope
    // (System::derivative_then): the stage's arithmetic reads k from cache,
    // not from memory, and one loop does all of a stage's statements. Each
    // element is computed alike whatever the chunking or the thread, so the
    // result does not depend on the thread count.
    const Index half = n / 2;
    auto stage = [&](auto op) {
      sys.derivative_then(k_, [&](Index b, Index e) {
        for (const Index at : {3 * b, half + 3 * b}) {
          const Index end = at + 3 * (e - b);
#pragma omp simd
          for (Index i = at; i < end; ++i) op(i);
        }
      });
    };
    // k1; y0 is saved in the pass that takes the first stage: one pass less.
    stage([=](Index i) {
      y0[i] = y[i];
      sum[i] = k[i];
      y[i] = y[i] + (0.5 * h) * k[i];
    });
    sys.set_time(t0 + 0.5 * h);
    stage([=](Index i) {  // k2
      sum[i] += 2.0 * k[i];
      y[i] = y0[i] + (0.5 * h) * k[i];
    });
    stage([=](Index i) {  // k3
      sum[i] += 2.0 * k[i];
      y[i] = y0[i] + h * k[i];
    });
    sys.set_time(t0 + h);
    stage([=](Index i) {  // k4
      y[i] = y0[i] + (h / 6.0) * (sum[i] + k[i]);
    });
  }

 private:
  Eigen::VectorXd y0_, k_, sum_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Solver;
  d.name = "rk4";
  d.version = "1.1.0";
  d.description = "classic fourth-order Runge-Kutta; order 4";
  d.solver_traits.order = 4;
  d.create_solver = [](const pdyn::Params&, const pdyn::SceneContext&) {
    return std::make_unique<Rk4>();
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
