// langevin: a Langevin thermostat, the force of a heat bath at temperature
// T on each particle (Schneider & Stoll 1978; as LAMMPS's `fix langevin`):
//
//   f_i = -(m_i / tau) v_i + sqrt(2 m_i k_B T / (tau h)) xi_i,
//
// a drag with damping time tau plus a random force, xi_i three standard
// normal deviates drawn anew for every step of length h and held over it
// (pdyn/step_aware.hpp). The amplitude is the fluctuation-dissipation
// theorem's: over a step the noise adds a velocity of variance
// 2 k_B T h / (m tau) per component, what the drag removes at temperature T,
// so the particles' velocities relax to Maxwell-Boltzmann at T with the
// time constant tau (Allen & Tildesley, "Computer Simulation of Liquids",
// 2nd ed., sec. 12.2).
//
// The numbers come from a counter-based generator (pdyn/random.hpp) keyed by
// the seed, the bits of the step's start time and the particle's index: the
// same for any thread count, for a step replayed after a fault and for a run
// resumed from a checkpoint, with no generator state to save.
#include <bit>
#include <cmath>
#include <cstdint>
#include <pdyn/error.hpp>
#include <pdyn/parallel.hpp>
#include <pdyn/periodic_invariant.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/random.hpp>
#include <pdyn/selection.hpp>
#include <pdyn/step_aware.hpp>
#include <pdyn/thermo.hpp>

namespace {

using pdyn::Index;

// PeriodicInvariant: it reads velocities only. VirialSource: a bath outside
// the system adds no virial, as LAMMPS's fixes.
class Langevin final : public pdyn::Force,
                       public pdyn::StepAware,
                       public pdyn::PeriodicInvariant,
                       public pdyn::VirialSource {
 public:
  Langevin(double kT, double tau, std::uint64_t seed, pdyn::Selection selection)
      : kT_(kT),
        tau_(tau),
        key_{seed, pdyn::random_stream::kLangevin},
        selection_(std::move(selection)) {}

  // Before the first step (pdyn check, a host that evaluates without
  // stepping) h is 0 and the force is the drag alone.
  void begin_step(double t, double h) override {
    step_ = std::bit_cast<std::uint64_t>(t);
    h_ = h;
  }

  void add_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    const double noise = h_ > 0 ? 2.0 * kT_ / (tau_ * h_) : 0.0;  // times m_i, N^2
    auto one = [&](Index i) {
      if (!p.fixed.empty() && p.fixed[static_cast<std::size_t>(i)] != 0) return;
      const double m = p.mass(i);
      f.col(i) -= (m / tau_) * p.v.col(i);
      if (noise > 0) {
        f.col(i) += std::sqrt(noise * m) *
                    pdyn::standard_normal3(key_, step_, static_cast<std::uint64_t>(i));
      }
    };
    if (selection_.all()) {
      // Columns are independent and each one's numbers depend on i only.
      pdyn::parallel_ranges(p.size(), [&](Index b, Index e) {
        for (Index i = b; i < e; ++i) one(i);
      });
      return;
    }
    for (const Index i : selection_.ids()) one(i);
  }

  // The drag reads velocities; the noise changes with the step.
  pdyn::StateDependence dependence() const override { return {true, true}; }

  // df_i/dv_i = -(m_i / tau) I: the noise does not depend on the state.
  bool add_jacobians(const pdyn::ParticleView& p, pdyn::JacobianSink& sink) override {
    auto one = [&](Index i) {
      if (!p.fixed.empty() && p.fixed[static_cast<std::size_t>(i)] != 0) return;
      sink.add_dfdv(i, i, -(p.mass(i) / tau_) * Eigen::Matrix3d::Identity());
    };
    if (selection_.all()) {
      for (Index i = 0; i < p.size(); ++i) one(i);
    } else {
      for (const Index i : selection_.ids()) one(i);
    }
    return true;
  }

  double virial(const pdyn::ParticleView&) const override { return 0.0; }

  // begin_step() is called before every step, a resumed run's first too:
  // nothing to carry in a checkpoint.

 private:
  double kT_, tau_;
  pdyn::RandomKey key_;
  pdyn::Selection selection_;
  std::uint64_t step_ = 0;
  double h_ = 0.0;
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "langevin";
  d.version = "1.0.0";
  d.description =
      "Langevin thermostat: drag -m v / damp plus a random force at temperature T, "
      "reproducible for a seed";
  d.params = pdyn::temperature_params("the bath's temperature", false);
  d.params.insert(
      d.params.end(),
      {
          pdyn::param::required_real("damp", "s", "damping time tau: the drag is m v / tau")
              .greater_than(0),
          pdyn::param::integer("seed", 1, "random seed, 0 to 4294967295")
              .at_least(0)
              .at_most(4294967295.0),
      });
  for (auto& s : pdyn::selection_params()) d.params.push_back(std::move(s));
  d.force_traits.dissipative = false;  // the noise does positive work
  d.create_force = [](const pdyn::Params& p, const pdyn::SceneContext& ctx) {
    return std::make_unique<Langevin>(pdyn::temperature_kT(p), p.real("damp"),
                                      static_cast<std::uint64_t>(p.integer("seed")),
                                      pdyn::Selection::from_params(p, ctx));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
