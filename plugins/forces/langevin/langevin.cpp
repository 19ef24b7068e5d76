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
//
// `generator: lammps` takes LAMMPS's numbers instead (lammps_noise.hpp), in
// LAMMPS's form of the same force: the noise of each component is uniform,
// sqrt(24 m k_B T / (tau h)) (u - 1/2), of the same variance 2 m k_B T /
// (tau h) (Dunweg & Paul 1991 showed uniform numbers serve as well as
// normal ones), drawn anew at each evaluation at a step's end; with verlet's
// `velocity_forces: half_step` a converted input then follows LAMMPS's run.
#include <fmt/format.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <memory>
#include <pdyn/error.hpp>
#include <pdyn/parallel.hpp>
#include <pdyn/periodic_invariant.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/random.hpp>
#include <pdyn/selection.hpp>
#include <pdyn/step_aware.hpp>
#include <pdyn/thermo.hpp>

#include "lammps_noise.hpp"

namespace {

using pdyn::Index;

// PeriodicInvariant: it reads velocities only. VirialSource: a bath outside
// the system adds no virial, as LAMMPS's fixes.
class Langevin final : public pdyn::Force,
                       public pdyn::StepAware,
                       public pdyn::PeriodicInvariant,
                       public pdyn::VirialSource {
 public:
  // `lammps`: LAMMPS's generator and form, its sort's bin edge `bin` (m).
  Langevin(double kT, double tau, std::uint64_t seed, pdyn::Selection selection,
           std::unique_ptr<pdyn_langevin::LammpsNoise> lammps)
      : kT_(kT),
        tau_(tau),
        key_{seed, pdyn::random_stream::kLangevin},
        selection_(std::move(selection)),
        lammps_(std::move(lammps)) {}

  // Before the first step (pdyn check, a host that evaluates without
  // stepping) h is 0 and the force is the drag alone.
  void begin_step(double t, double h) override {
    step_ = std::bit_cast<std::uint64_t>(t);
    h_ = h;
  }

  void add_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    if (lammps_ && h_ > 0) {
      add_lammps_forces(p, f);
      return;
    }
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
    for_bath(p.size(), one);
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
  // the philox generator carries nothing in a checkpoint; LAMMPS's carries
  // its place in the stream.
  std::vector<std::uint8_t> save_state() const override {
    return lammps_ ? lammps_->save() : std::vector<std::uint8_t>{};
  }
  void restore_state(std::span<const std::uint8_t> bytes) override {
    if (lammps_) {
      lammps_->restore(bytes);
    } else {
      pdyn::Force::restore_state(bytes);
    }
  }

 private:
  // `one(i)` for each particle of the bath: every particle, over the
  // host's threads (columns are independent), or the selection's.
  template <class One>
  void for_bath(Index n, const One& one) const {
    if (selection_.all()) {
      pdyn::parallel_ranges(n, [&](Index b, Index e) {
        for (Index i = b; i < e; ++i) one(i);
      });
      return;
    }
    for (const Index i : selection_.ids()) one(i);
  }

  // LAMMPS's fix langevin: f += gamma1 v + gamma2 (u - 1/2), gamma1 =
  // -m / tau, gamma2 = sqrt(m) sqrt(24 / tau / h) sqrt(k_B T), in LAMMPS's
  // order of operations (fix_langevin.cpp with k_B = 1 in its lj units), the
  // numbers of the evaluation at t = k h.
  void add_lammps_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) {
    const double k = std::round(p.t / h_);
    if (k < 0 || std::abs(p.t - k * h_) > 1e-6 * h_) {
      throw pdyn::Error(fmt::format(
          "langevin: generator lammps draws LAMMPS's numbers for evaluations at the ends of "
          "steps, and this one is at t = {} inside a step of {} (expected solver verlet or "
          "nose_hoover, which evaluate there)",
          p.t, h_));
    }
    if (in_bath_.empty()) {
      in_bath_.assign(static_cast<std::size_t>(p.size()), 0);
      for_bath(p.size(), [&](Index i) {
        if (p.fixed.empty() || p.fixed[static_cast<std::size_t>(i)] == 0) {
          in_bath_[static_cast<std::size_t>(i)] = 1;
        }
      });
    }
    const std::vector<double>& u =
        lammps_->block(static_cast<long long>(k), in_bath_, p.x, p.domain);
    const std::vector<Index>& first = lammps_->first_of();
    const double amplitude = std::sqrt(24.0 / tau_ / h_);
    const double root_kT = std::sqrt(kT_);
    for_bath(p.size(), [&](Index i) {
      const Index at = first[static_cast<std::size_t>(i)];
      if (at < 0) return;
      const double m = p.mass(i);
      const double gamma1 = -m / tau_;
      const double gamma2 = std::sqrt(m) * amplitude * root_kT;
      for (Index d = 0; d < 3; ++d) {
        // u - 1/2 is exact: u is a multiple of 2^-24.
        const double fran = gamma2 * (u[static_cast<std::size_t>(at + d)] - 0.5);
        f(d, i) += gamma1 * p.v(d, i) + fran;
      }
    });
  }

  double kT_, tau_;
  pdyn::RandomKey key_;
  pdyn::Selection selection_;
  std::uint64_t step_ = 0;
  double h_ = 0.0;
  std::unique_ptr<pdyn_langevin::LammpsNoise> lammps_;  // generator: lammps, else null
  std::vector<std::uint8_t> in_bath_;                   // generator lammps's bath
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "langevin";
  d.version = "1.1.0";
  d.description =
      "Langevin thermostat: drag -m v / damp plus a random force at temperature T, "
      "reproducible for a seed";
  d.params = pdyn::temperature_params("the bath's temperature", false);
  d.params.insert(
      d.params.end(),
      {
          pdyn::param::required_real("damp", "s", "damping time tau: the drag is m v / tau")
              .greater_than(0),
          pdyn::param::integer("seed", 1,
                               "random seed, 0 to 4294967295 (1 to 900000000 for the lammps "
                               "generator)")
              .at_least(0)
              .at_most(4294967295.0),
          pdyn::param::string("generator", "philox",
                              "philox (pdyn's, normal deviates held over each step) or lammps "
                              "(LAMMPS's fix langevin numbers and form, for converted inputs)"),
          pdyn::param::real("lammps_sort_bin", 0.0, "m",
                            "with generator lammps: the bin edge of LAMMPS's atom sort, half "
                            "its neighbor cutoff (cutoff + skin) / 2; 0: the particles' order")
              .at_least(0.0),
      });
  for (auto& s : pdyn::selection_params()) d.params.push_back(std::move(s));
  d.force_traits.dissipative = false;  // the noise does positive work
  d.create_force = [](const pdyn::Params& p, const pdyn::SceneContext& ctx) {
    const std::string& generator = p.string("generator");
    if (generator != "philox" && generator != "lammps") {
      throw pdyn::ParamError("generator", fmt::format("'{}' is not a generator (expected philox "
                                                      "or lammps)",
                                                      generator));
    }
    std::unique_ptr<pdyn_langevin::LammpsNoise> lammps;
    if (generator == "lammps") {
      const long long seed = p.integer("seed");
      if (seed < 1 || seed > 900000000) {
        throw pdyn::ParamError("seed", fmt::format("{} is outside LAMMPS's generator's seeds "
                                                   "(expected 1 to 900000000)",
                                                   seed));
      }
      lammps = std::make_unique<pdyn_langevin::LammpsNoise>(seed, p.real("lammps_sort_bin"));
    } else if (p.real("lammps_sort_bin") != 0.0) {
      throw pdyn::ParamError("lammps_sort_bin",
                             "is for generator lammps only (expected generator: lammps)");
    }
    return std::make_unique<Langevin>(pdyn::temperature_kT(p), p.real("damp"),
                                      static_cast<std::uint64_t>(p.integer("seed")),
                                      pdyn::Selection::from_params(p, ctx), std::move(lammps));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
