// @NAME@: Heun's method (the explicit trapezoidal rule, a second-order
// Runge-Kutta method):
//   k1 = f(t0, y0),  k2 = f(t0 + h, y0 + h k1),  y1 = y0 + h/2 (k1 + k2).
// Its global error is O(h^2), so it declares order 2; `pdyn check @NAME@`
// measures the order on a harmonic oscillator and holds the claim to it.
#include <pdyn/plugin.hpp>
#include <pdyn/system.hpp>

namespace {

class Heun final : public pdyn::Solver {
 public:
  void step(pdyn::System& sys, double h) override {
    const double t0 = sys.time();
    // Members, so that only the first step (or a change of N) allocates.
    y0_ = sys.state();
    k1_.resize(sys.dimension());
    k2_.resize(sys.dimension());
    sys.derivative(k1_);
    sys.state() = y0_ + h * k1_;
    sys.set_time(t0 + h);
    sys.derivative(k2_);
    sys.state() = y0_ + (0.5 * h) * (k1_ + k2_);
    sys.set_time(t0 + h);  // exactly t0 + h: the kit checks it
  }

 private:
  Eigen::VectorXd y0_, k1_, k2_;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Solver;
  d.name = "@NAME@";
  d.version = "0.1.0";
  d.description = "Heun's method: y1 = y0 + h/2 (f(t0, y0) + f(t0 + h, y0 + h f(t0, y0))); order 2";
  d.solver_traits.order = 2;
  d.solver_traits.symplectic = false;
  d.create_solver = [](const pdyn::Params&, const pdyn::SceneContext&) {
    return std::make_unique<Heun>();
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
