// rk4: the classic fourth-order Runge-Kutta method,
//   k1 = f(t0, y0)             k2 = f(t0 + h/2, y0 + h/2 k1)
//   k3 = f(t0 + h/2, y0 + h/2 k2)   k4 = f(t0 + h, y0 + h k3)
//   y1 = y0 + h/6 (k1 + 2 k2 + 2 k3 + k4).
// Stage states are written straight into the system's state (no set_state
// copy); the weighted sum is accumulated in `sum_` as the stages arrive so
// only one derivative buffer is live at a time.
#include <pdyn/plugin.hpp>
#include <pdyn/system.hpp>

namespace {

class Rk4 final : public pdyn::Solver {
 public:
  void step(pdyn::System& sys, double h) override {
    const double t0 = sys.time();
    y0_ = sys.state();
    k_.resize(sys.dimension());
    sum_.resize(sys.dimension());

    sys.derivative(k_);  // k1
    sum_ = k_;
    sys.state() = y0_ + (0.5 * h) * k_;
    sys.set_time(t0 + 0.5 * h);

    sys.derivative(k_);  // k2
    sum_ += 2.0 * k_;
    sys.state() = y0_ + (0.5 * h) * k_;

    sys.derivative(k_);  // k3
    sum_ += 2.0 * k_;
    sys.state() = y0_ + h * k_;
    sys.set_time(t0 + h);

    sys.derivative(k_);  // k4
    sum_ += k_;
    sys.state() = y0_ + (h / 6.0) * sum_;
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
