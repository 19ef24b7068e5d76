// rk45: the Dormand-Prince 5(4) embedded Runge-Kutta pair with error
// control, a PI step-size controller and dense output -- the method of
// Hairer's DOPRI5 and Boost.Odeint's runge_kutta_dopri5.
//
//   J. R. Dormand, P. J. Prince, "A family of embedded Runge-Kutta
//   formulae", J. Comput. Appl. Math. 6 (1980) 19-26.
//   E. Hairer, S. P. Norsett, G. Wanner, "Solving Ordinary Differential
//   Equations I", 2nd ed., Springer 1993: section II.4 (error estimate and
//   step-size selection), II.5 (Table 5.2, the coefficients), II.6 (dense
//   output, eq. 6.12 and the DOPRI5 code's CONTD5).
//   K. Gustafsson, "Control theoretic techniques for stepsize selection in
//   explicit Runge-Kutta methods", ACM TOMS 17 (1991) 533-554 (PI control).
//
// The step advances with the fifth-order solution (local extrapolation);
// the difference to the embedded fourth-order one estimates the error,
//   err = sqrt(mean_i (e_i / (atol + rtol max(|y0_i|, |y1_i|)))^2),
// and the step is accepted when err <= 1. The next step is
//   h_new = h / clamp((err^0.17 / err_prev^0.04) / 0.9, 1/10, 5)
// (Hairer & Wanner's "Lund stabilisation" of the controller, DOPRI5's
// defaults alpha = 0.2 - 0.75 beta, beta = 0.04, safety 0.9, growth <= 10,
// shrink >= 0.2), and after a rejection h / min(5, err^0.17 / 0.9) with no
// growth on the step that follows a rejection.
//
// FSAL: the seventh stage is f(t1, y1), the next step's first. It is reused
// only when the system still holds exactly (t1, y1) when the next step
// starts: a collider response or a host that sets the state in between
// makes the solver evaluate k1 afresh, so reuse never changes results.
//
// `fixed_step: true` makes the solver non-adaptive: the runner then takes
// fixed steps of the scene's dt with the fifth-order formula and no error
// control, which is how its order is measured.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <pdyn/plugin.hpp>
#include <pdyn/system.hpp>

namespace {

// Dormand-Prince coefficients (Hairer, Norsett & Wanner, Table II.5.2).
constexpr double c2 = 1.0 / 5, c3 = 3.0 / 10, c4 = 4.0 / 5, c5 = 8.0 / 9;
constexpr double a21 = 1.0 / 5;
constexpr double a31 = 3.0 / 40, a32 = 9.0 / 40;
constexpr double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
constexpr double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561,
                 a54 = -212.0 / 729;
constexpr double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247, a64 = 49.0 / 176,
                 a65 = -5103.0 / 18656;
// Fifth-order weights, also the last row of the tableau (FSAL).
constexpr double b1 = 35.0 / 384, b3 = 500.0 / 1113, b4 = 125.0 / 192, b5 = -2187.0 / 6784,
                 b6 = 11.0 / 84;
// Fifth minus fourth-order weights: the error estimate.
constexpr double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920, e5 = -17253.0 / 339200,
                 e6 = 22.0 / 525, e7 = -1.0 / 40;
// The fourth-order continuous extension (Hairer, Norsett & Wanner II.6;
// Shampine, "Some practical Runge-Kutta formulas", Math. Comp. 46 (1986)).
constexpr double d1 = -12715105075.0 / 11282082432, d3 = 87487479700.0 / 32700410799,
                 d4 = -10690763975.0 / 1880347072, d5 = 701980252875.0 / 199316789632,
                 d6 = -1453857185.0 / 822651844, d7 = 69997945.0 / 29380423;

// Step-size controller constants (DOPRI5's defaults).
constexpr double kSafety = 0.9;
constexpr double kBeta = 0.04;                 // PI term exponent
constexpr double kAlpha = 0.2 - 0.75 * kBeta;  // I term exponent, 1/5 for a 4th-order estimate
constexpr double kMaxGrowth = 10.0;
constexpr double kMaxShrink = 5.0;  // h may fall to h/5 at most per attempt
constexpr double kMinErrPrev = 1e-4;

// Checkpoint layout: "rk45", version, h_next, err_prev, accepted, rejected.
constexpr char kMagic[4] = {'r', 'k', '4', '5'};
constexpr std::uint32_t kStateVersion = 1;
constexpr std::size_t kStateBytes = 4 + 4 + 8 + 8 + 8 + 8;

struct Options {
  double rtol = 1e-6;
  double atol = 1e-9;
  double dt_min = 1e-12;
  double dt_max = 0.0;  // 0: no limit
  bool fixed_step = false;
};

class DormandPrince final : public pdyn::Solver {
 public:
  explicit DormandPrince(const Options& o) : o_(o) {}

  bool adaptive() const noexcept override { return !o_.fixed_step; }

  void step(pdyn::System& sys, double h) override {
    const double t0 = sys.time();
    begin(sys);
    attempt(sys, t0, h, t0 + h);
    ++accepted_;
    finish(t0, h, t0 + h);
  }

  double advance(pdyn::System& sys, double t_stop, double h_hint) override {
    if (o_.fixed_step) return Solver::advance(sys, t_stop, h_hint);
    const double t0 = sys.time();
    const double span = t_stop - t0;
    if (!(span > 0.0)) {
      throw pdyn::Error(
          fmt::format("rk45: asked to advance from t = {:.17g} s to t = {:.17g} s "
                      "(expected a later stop time)",
                      t0, t_stop));
    }
    double h = h_next_ > 0.0 ? h_next_ : h_hint;
    if (o_.dt_max > 0.0) h = std::min(h, o_.dt_max);
    begin(sys);
    bool after_rejection = false;
    for (;;) {
      // Stretch a step that would leave a sliver of less than 1% before
      // t_stop (DOPRI5's rule), and never step past it.
      const bool last = h * 1.01 >= span;
      if (!last && h < o_.dt_min) {
        throw pdyn::Error(fmt::format(
            "rk45: the step size fell to {:.3g} s at t = {:.17g} s, below dt_min = {:.3g} s "
            "(the error estimate could not be met with rtol = {:g}, atol = {:g}: the problem may "
            "be stiff, try implicit_euler, or have a discontinuity; or lower dt_min or loosen "
            "rtol/atol)",
            h, t0, o_.dt_min, o_.rtol, o_.atol));
      }
      if (last) h = span;
      const double t1 = last ? t_stop : t0 + h;
      const double err = attempt(sys, t0, h, t1);
      const double fac11 = std::pow(err, kAlpha);
      if (err <= 1.0) {
        ++accepted_;
        double fac = fac11 / std::pow(err_prev_, kBeta) / kSafety;
        fac = std::clamp(fac, 1.0 / kMaxGrowth, kMaxShrink);
        double h_new = h / fac;
        if (after_rejection) h_new = std::min(h_new, h);
        if (o_.dt_max > 0.0) h_new = std::min(h_new, o_.dt_max);
        err_prev_ = std::max(err, kMinErrPrev);
        h_next_ = h_new;
        finish(t0, h, t1);
        return h;
      }
      // Rejected (a non-finite error estimate counts as a large one).
      ++rejected_;
      after_rejection = true;
      h /= std::isfinite(fac11) ? std::min(kMaxShrink, fac11 / kSafety) : kMaxShrink;
      sys.state() = y0_;
      sys.set_time(t0);
    }
  }

  bool interpolate(double t, Eigen::Ref<Eigen::VectorXd> y) const override {
    if (!dense_valid_) return false;
    const double theta = (t - t_dense_) / h_dense_;
    constexpr double kSlack = 1e-9;  // t may be the step's end rounded either way
    if (!(theta >= -kSlack && theta <= 1.0 + kSlack)) return false;
    // Hairer's CONTD5: y(t0 + theta h) = y0 + theta (dy + (1 - theta) (b +
    // theta (c + (1 - theta) d))), with dy = y1 - y0, b = h k1 - dy,
    // c = dy - h k7 - b, d = h sum_i d_i k_i.
    const double s = 1.0 - theta, h = h_dense_;
    y = y0_ + theta * ((y1_ - y0_) + s * ((h * k1_ - (y1_ - y0_)) +
                                          theta * ((2.0 * (y1_ - y0_) - h * (k7_ + k1_)) +
                                                   s * h *
                                                       (d1 * k1_ + d3 * k3_ + d4 * k4_ + d5 * k5_ +
                                                        d6 * k6_ + d7 * k7_))));
    return true;
  }

  pdyn::StepCounts counts() const noexcept override { return {accepted_, rejected_}; }

  std::vector<std::uint8_t> save_state() const override {
    std::vector<std::uint8_t> bytes(kStateBytes);
    std::uint8_t* p = bytes.data();
    auto put = [&p](const void* src, std::size_t n) {
      std::memcpy(p, src, n);
      p += n;
    };
    put(kMagic, 4);
    put(&kStateVersion, 4);
    put(&h_next_, 8);
    put(&err_prev_, 8);
    put(&accepted_, 8);
    put(&rejected_, 8);
    return bytes;
  }

  void restore_state(std::span<const std::uint8_t> bytes) override {
    std::uint32_t version = 0;
    if (bytes.size() == kStateBytes) std::memcpy(&version, bytes.data() + 4, 4);
    if (bytes.size() != kStateBytes || std::memcmp(bytes.data(), kMagic, 4) != 0 ||
        version != kStateVersion) {
      throw pdyn::Error(fmt::format(
          "rk45: the checkpoint's solver state is not one rk45 wrote ({} bytes; expected {} "
          "bytes starting with 'rk45' version {})",
          bytes.size(), kStateBytes, kStateVersion));
    }
    const std::uint8_t* p = bytes.data() + 8;
    auto get = [&p](void* dst, std::size_t n) {
      std::memcpy(dst, p, n);
      p += n;
    };
    get(&h_next_, 8);
    get(&err_prev_, 8);
    get(&accepted_, 8);
    get(&rejected_, 8);
    fsal_valid_ = false;
    dense_valid_ = false;
  }

 private:
  // Sizes the buffers, saves y0 and makes k1 = f(t0, y0), reusing the last
  // step's seventh stage when the system is still exactly at its end.
  void begin(pdyn::System& sys) {
    const pdyn::Index n = sys.dimension();
    if (y0_.size() != n) {
      for (Eigen::VectorXd* v : {&y0_, &y1_, &k1_, &k2_, &k3_, &k4_, &k5_, &k6_, &k7_}) {
        v->resize(n);
      }
      fsal_valid_ = false;
    }
    dense_valid_ = false;
    if (fsal_valid_ && sys.time() == t1_ && sys.state() == y1_) {
      std::swap(k1_, k7_);
    } else {
      sys.derivative(k1_);
    }
    y0_ = sys.state();
    fsal_valid_ = false;
  }

  // One Dormand-Prince step of h from (t0, y0_, k1_), ending at time t1
  // (t0 + h, or exactly the stop time); leaves y1 in the system and returns
  // the scaled error norm. Stage states are written straight into the
  // system's state.
  double attempt(pdyn::System& sys, double t0, double h, double t1) {
    auto y = sys.state();
    y = y0_ + (h * a21) * k1_;
    sys.set_time(t0 + c2 * h);
    sys.derivative(k2_);
    y = y0_ + h * (a31 * k1_ + a32 * k2_);
    sys.set_time(t0 + c3 * h);
    sys.derivative(k3_);
    y = y0_ + h * (a41 * k1_ + a42 * k2_ + a43 * k3_);
    sys.set_time(t0 + c4 * h);
    sys.derivative(k4_);
    y = y0_ + h * (a51 * k1_ + a52 * k2_ + a53 * k3_ + a54 * k4_);
    sys.set_time(t0 + c5 * h);
    sys.derivative(k5_);
    y = y0_ + h * (a61 * k1_ + a62 * k2_ + a63 * k3_ + a64 * k4_ + a65 * k5_);
    sys.set_time(t1);
    sys.derivative(k6_);
    y = y0_ + h * (b1 * k1_ + b3 * k3_ + b4 * k4_ + b5 * k5_ + b6 * k6_);
    sys.derivative(k7_);
    y1_ = y;
    if (o_.fixed_step) return 0.0;
    double sum = 0.0;
    const pdyn::Index n = y.size();
    for (pdyn::Index i = 0; i < n; ++i) {
      const double e =
          h * (e1 * k1_[i] + e3 * k3_[i] + e4 * k4_[i] + e5 * k5_[i] + e6 * k6_[i] + e7 * k7_[i]);
      const double scale = o_.atol + o_.rtol * std::max(std::abs(y0_[i]), std::abs(y1_[i]));
      sum += (e / scale) * (e / scale);
    }
    const double err = n > 0 ? std::sqrt(sum / static_cast<double>(n)) : 0.0;
    return std::isnan(err) ? HUGE_VAL : err;
  }

  // Records the accepted step for dense output and FSAL.
  void finish(double t0, double h, double t1) {
    t_dense_ = t0;
    h_dense_ = h;
    t1_ = t1;
    dense_valid_ = true;
    fsal_valid_ = true;
  }

  Options o_;
  Eigen::VectorXd y0_, y1_, k1_, k2_, k3_, k4_, k5_, k6_, k7_;
  double h_next_ = 0.0;            // next step to try, s; 0 until the first accepted step
  double err_prev_ = kMinErrPrev;  // last accepted error, for the PI term
  std::int64_t accepted_ = 0, rejected_ = 0;
  double t_dense_ = 0.0, h_dense_ = 0.0, t1_ = 0.0;
  bool dense_valid_ = false, fsal_valid_ = false;
};

std::unique_ptr<pdyn::Solver> create(const pdyn::Params& p, const pdyn::SceneContext&) {
  Options o;
  o.rtol = p.real("rtol");
  o.atol = p.real("atol");
  o.dt_min = p.real("dt_min");
  o.dt_max = p.real("dt_max");
  o.fixed_step = p.boolean("fixed_step");
  if (o.dt_max > 0.0 && o.dt_max < o.dt_min) {
    throw pdyn::ParamError("dt_max", fmt::format("is {:g} s, smaller than dt_min = {:g} s "
                                                 "(expected dt_max >= dt_min, or 0 for no limit)",
                                                 o.dt_max, o.dt_min));
  }
  return std::make_unique<DormandPrince>(o);
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Solver;
  d.name = "rk45";
  d.version = "1.0.0";
  d.description =
      "Dormand-Prince 5(4), adaptive with PI step control, FSAL and dense output; order 5";
  d.params = {
      pdyn::param::real("rtol", 1e-6, "", "relative error tolerance per step").greater_than(0),
      pdyn::param::real("atol", 1e-9, "m or m/s",
                        "absolute error tolerance per step, on positions and velocities alike")
          .greater_than(0),
      pdyn::param::real("dt_min", 1e-12, "s",
                        "smallest step; a step the error needs below it is an error")
          .at_least(0),
      pdyn::param::real("dt_max", 0.0, "s", "largest step; 0: no limit").at_least(0),
      pdyn::param::boolean("fixed_step", false,
                           "take fixed steps of the scene's dt with no error control"),
  };
  d.solver_traits.order = 5;
  d.create_solver = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
