// nose_hoover: velocity Verlet in a Nose-Hoover chain thermostat at k_B T
// (Martyna, Klein & Tuckerman, J. Chem. Phys. 97, 2635 (1992); integrated
// as Martyna, Tuckerman, Tobias & Klein, Mol. Phys. 87, 1117 (1996), and as
// LAMMPS's `fix nvt`). The free particles' velocities are coupled to a
// chain of M thermostats with positions eta_j and velocities xi_j:
//
//   dx/dt = v,   dv/dt = F/m - xi_1 v,   deta_j/dt = xi_j,
//   dxi_1/dt = (2K - N_f kT) / Q_1 - xi_1 xi_2,
//   dxi_j/dt = (Q_{j-1} xi_{j-1}^2 - kT) / Q_j - xi_j xi_{j+1}   (j >= 2, xi_{M+1} = 0),
//
// with K the free particles' kinetic energy, N_f = 3 N_free - extra_dof -
// the independent constraint rows (as the energy writer counts them,
// pdyn/thermo.hpp: constraint_dof, since 0.10.0), Q_1 = N_f kT tau^2
// and Q_j = kT tau^2: each thermostat's natural period is about 2 pi tau.
// The extended energy
//
//   H' = K + U + sum_j Q_j xi_j^2 / 2 + N_f kT eta_1 + kT sum_{j>=2} eta_j
//
// is conserved; reservoir_energy() (pdyn::EnergyReservoir) is its part
// beyond K + U, so the energy writer's `conserved` column is H'.
//
// One step of h is the Trotter splitting of MTK 1996 (LAMMPS's
// initial_integrate and final_integrate with `tloop 1`):
//
//   chain half step (h/2) -> v += h/2 a0 -> x += h v -> evaluate a1
//   -> v += h/2 a1 -> chain half step (h/2).
//
// A chain half step of d = h/2 (half_step below, LAMMPS's
// nhc_temp_integrate) moves xi_M .. xi_1 by d/2 each, every one between two
// scalings by exp(-d/4 xi_{j+1}); scales the free particles' velocities by
// exp(-d xi_1), and 2K by its square (not summed again, as LAMMPS);
// advances every eta_j by d xi_j; and moves xi_1 .. xi_M by d/2 again. The
// step is time-reversible and second order; it is not symplectic.
//
// The particle update is verlet's, operation for operation (v += h/2 a0,
// x += h v, v += h/2 a1; with velocity-dependent forces or a collider,
// verlet's predictor: a1 sees v0 + h a0), so with the chain inert the bits
// are verlet's. The chain is inert when N_f <= 0 (a single particle with
// the default extra_dof 3): there is no temperature to control, the
// velocities are left alone and eta, xi stay 0. Fixed particles have v = 0
// (the kernel keeps them so), which the scaling keeps without a branch.
//
// Force reuse: the end-of-step accelerations stand in for the next step's
// a0 under verlet's conditions (pdyn::ForceReuse, pdyn/force_reuse.hpp):
// one force evaluation per step when every force reads positions only. The
// chain's own drag -xi_1 v is not a force: it acts through the scalings,
// between the evaluations, so it does not stop the reuse.
//
// Threads: the particle loops are pdyn::parallel_chunks, as verlet's. 2K,
// which the chain needs twice per step, is a fixed-chunk reduction: chunks
// of kChunk particles at fixed offsets (the same for any thread count),
// each summed in particle order, then the chunks' sums added in chunk
// order: the same bits for any thread count. The end-of-step sum is taken
// in the pass that adds h/2 a1; the start-of-step one is a pass of its own
// (the state may have been written between steps, and a resumed run must
// compute what the uninterrupted one did).
//
// Checkpoints carry eta, xi and N_f (save_state), bit for bit. The chain's
// new values are kept only when the step ends with them finite: a step that
// throws or blows up (the Stepper then restores the particles' last good
// state) leaves the chain as it was.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <pdyn/error.hpp>
#include <pdyn/force_reuse.hpp>
#include <pdyn/parallel.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/system.hpp>
#include <pdyn/thermo.hpp>
#include <span>
#include <vector>

#include "barostat.hpp"

namespace {

using pdyn::Index;

constexpr int kMaxChain = 10;
// Columns per chunk, of the particle loops and of the 2K reduction.
constexpr Index kChunk = pdyn::kChunkElements / 3;

constexpr char kMagic[4] = {'n', 'h', 'c', 'h'};
constexpr std::uint32_t kStateVersion = 1;

// Calls body(c, b, e) for chunk c = [b, e) = [c k, min(n, (c + 1) k)) of
// [0, n), every chunk once: each thread of parallel_ranges takes the chunks
// that start in its range. The chunks do not depend on the thread count.
template <class Body>
void fixed_chunks(Index n, Index k, Body&& body) {
  pdyn::parallel_ranges(n, [&](Index begin, Index end) {
    for (Index c = (begin + k - 1) / k; c * k < end; ++c) body(c, c * k, std::min(n, (c + 1) * k));
  });
}

// The thermostats: positions eta_j, velocities xi_j (1/s). xi[M] stays 0,
// the end of the chain.
struct Chain {
  std::array<double, kMaxChain> eta{};
  std::array<double, kMaxChain + 1> xi{};
};

class NoseHoover final : public pdyn::Solver,
                         public pdyn::EnergyReservoir,
                         public pdyn::ForceReuseHolder {
 public:
  NoseHoover(double kT, double tdamp, int chain, double extra_dof,
             const std::optional<nose_hoover::Barostat>& barostat)
      : kT_(kT), tau2_(tdamp * tdamp), m_(chain), extra_dof_(extra_dof), barostat_(barostat) {}

  void step(pdyn::System& sys, double h) override {
    if (barostat_) {
      step_npt(sys, h);
      return;
    }
    const pdyn::ForceReuse::Needs needs = pdyn::ForceReuse::needs(sys);
    const pdyn::Matrix3X* kept = reuse_.kept(sys, needs);  // before this step's writable views
    const double t0 = sys.time();
    const Index n = sys.size();
    const double dof = degrees_of_freedom(sys);
    const bool on = dof > 0;
    Chain next = chain_;
    auto x = sys.positions();
    auto v = sys.velocities();
    const double s0 =
        on ? half_step(next, dof, update_then_twice_k(sys, [](Index, Index) {}), 0.5 * h) : 1.0;
    const pdyn::Matrix3X& a0 = kept != nullptr ? *kept : sys.compute_accelerations();
    if (!needs.velocity) {
      pdyn::parallel_chunks(n, kChunk, [&](Index b, Index e) {
        if (on) v.middleCols(b, e - b) *= s0;
        v.middleCols(b, e - b) += (0.5 * h) * a0.middleCols(b, e - b);  // v_half
        x.middleCols(b, e - b) += h * v.middleCols(b, e - b);
      });
    } else {
      half_.resize(3, n);  // no-op after the first step
      pdyn::parallel_chunks(n, kChunk, [&](Index b, Index e) {
        const Index m = e - b;
        if (on) v.middleCols(b, m) *= s0;
        half_.middleCols(b, m) = v.middleCols(b, m) + (0.5 * h) * a0.middleCols(b, m);
        x.middleCols(b, m) += h * half_.middleCols(b, m);
        v.middleCols(b, m) += h * a0.middleCols(b, m);  // predictor, only seen by a1's forces
      });
    }
    sys.set_time(t0 + h);

    const pdyn::Matrix3X& a1 = sys.compute_accelerations();
    const double twice_k = update_then_twice_k(sys, [&](Index b, Index e) {
      if (!needs.velocity) {
        v.middleCols(b, e - b) += (0.5 * h) * a1.middleCols(b, e - b);
      } else {
        v.middleCols(b, e - b) = half_.middleCols(b, e - b) + (0.5 * h) * a1.middleCols(b, e - b);
      }
    });
    if (on) {
      const double s1 = half_step(next, dof, twice_k, 0.5 * h);
      pdyn::parallel_chunks(n, kChunk, [&](Index b, Index e) { v.middleCols(b, e - b) *= s1; });
    }
    if (finite(next)) {
      chain_ = next;
      dof_ = dof;
    }
    reuse_.keep(sys, a1, needs);  // after the step's last write
  }

  // LAMMPS's fix npt iso, FixNH::initial_integrate and final_integrate in
  // their order (barostat.hpp): the barostat's chain, the particles' chain,
  // the barostat's kick from the pressure, v scaled by the box's rate,
  // v += h/2 a0, dilate, x += h v, dilate; evaluate a1; v += h/2 a1, v
  // scaled, the pressure at the new state, the kick, the particles' chain,
  // the barostat's chain.
  void step_npt(pdyn::System& sys, double h) {
    const pdyn::ForceReuse::Needs needs = pdyn::ForceReuse::needs(sys);
    const pdyn::Matrix3X* kept = reuse_.kept(sys, needs);  // before this step's writable views
    if (needs.velocity) {
      throw pdyn::Error(
          "nose_hoover: the barostat (pressure) needs forces of the positions only (expected no "
          "collider and no velocity-dependent force)");
    }
    nose_hoover::Barostat b = *barostat_;
    if (!b.started()) b.start(sys);
    const double t0 = sys.time();
    const Index n = sys.size();
    const double dof = degrees_of_freedom(sys);
    Chain next = chain_;
    const double virial0 = virial_kept_ && kept != nullptr ? virial_ : virial_of(sys);
    b.chain_half_step(h);
    double twice_k = update_then_twice_k(sys, [](Index, Index) {});
    const double s0 = dof > 0 ? half_step(next, dof, twice_k, 0.5 * h) : 1.0;
    twice_k *= s0 * s0;  // LAMMPS's tracked t_current
    b.kick(pressure(sys, twice_k, virial0), volume(sys), twice_k, h);
    const double f = b.velocity_factor(h);
    const pdyn::Matrix3X& a0 = kept != nullptr ? *kept : sys.compute_accelerations();
    auto v = sys.velocities();
    pdyn::parallel_chunks(n, kChunk, [&](Index bb, Index e) {
      auto vc = v.middleCols(bb, e - bb);
      vc *= s0;
      vc *= f;
      vc *= f;
      vc += (0.5 * h) * a0.middleCols(bb, e - bb);
    });
    b.dilate(sys, h);
    auto x = sys.positions();
    pdyn::parallel_chunks(n, kChunk, [&](Index bb, Index e) {
      x.middleCols(bb, e - bb) += h * v.middleCols(bb, e - bb);
    });
    b.dilate(sys, h);
    sys.set_time(t0 + h);

    const pdyn::Matrix3X& a1 = sys.compute_accelerations();
    twice_k = update_then_twice_k(sys, [&](Index bb, Index e) {
      auto vc = v.middleCols(bb, e - bb);
      vc += (0.5 * h) * a1.middleCols(bb, e - bb);
      vc *= f;
      vc *= f;
    });
    const double virial1 = virial_of(sys);
    b.kick(pressure(sys, twice_k, virial1), volume(sys), twice_k, h);
    if (dof > 0) {
      const double s1 = half_step(next, dof, twice_k, 0.5 * h);
      pdyn::parallel_chunks(n, kChunk, [&](Index bb, Index e) { v.middleCols(bb, e - bb) *= s1; });
    }
    b.chain_half_step(h);
    if (finite(next) && b.finite()) {
      chain_ = next;
      dof_ = dof;
      *barostat_ = b;
      volume_ = volume(sys);
    }
    reuse_.keep(sys, a1, needs);  // after the step's last write
    virial_ = virial1;            // the virial at the state a1 was evaluated at
    virial_kept_ = true;
  }

  static double volume(const pdyn::System& sys) {
    const pdyn::Domain& d = sys.domain();
    return (d.max[0] - d.min[0]) * (d.max[1] - d.min[1]) * (d.max[2] - d.min[2]);
  }

  // LAMMPS's compute pressure: (2K + W) / 3 / V, with 2K = N_f k_B T.
  static double pressure(const pdyn::System& sys, double twice_k, double virial) {
    return (twice_k + virial) / 3.0 * (1.0 / volume(sys));
  }

  static double virial_of(const pdyn::System& sys) {
    const pdyn::VirialSum w = pdyn::total_virial(sys);
    if (std::isnan(w.value)) {
      throw pdyn::Error(fmt::format(
          "nose_hoover: the barostat (pressure) needs every force's virial, and {} reports none "
          "(expected forces built with pdyn 0.8 or later, pdyn/thermo.hpp)",
          w.missing));
    }
    return w.value;
  }

  // A checkpoint carries the kept a1 (pdyn/force_reuse.hpp).
  const pdyn::Matrix3X* kept_accelerations(const pdyn::System& sys) const override {
    return reuse_.current(sys);
  }
  void restore_kept_accelerations(const pdyn::System& sys, const pdyn::Matrix3X& a1) override {
    reuse_.restore(sys, a1);
  }

  double reservoir_energy() const override {
    const std::array<double, kMaxChain> q = thermostat_masses(dof_);
    double e = barostat_ ? barostat_->reservoir_energy(volume_) : 0.0;
    for (int j = 0; j < m_; ++j) e += 0.5 * q[j] * chain_.xi[j] * chain_.xi[j];
    e += dof_ * kT_ * chain_.eta[0];
    for (int j = 1; j < m_; ++j) e += kT_ * chain_.eta[j];
    return e;
  }

  // magic, version, M (4 bytes each), N_f, eta_1..eta_M, xi_1..xi_M (8 each).
  std::vector<std::uint8_t> save_state() const override {
    std::vector<std::uint8_t> bytes(state_bytes(m_));
    std::uint8_t* p = bytes.data();
    auto put = [&p](const void* src, std::size_t k) {
      std::memcpy(p, src, k);
      p += k;
    };
    const auto m = static_cast<std::uint32_t>(m_);
    put(kMagic, 4);
    put(&kStateVersion, 4);
    put(&m, 4);
    put(&dof_, 8);
    put(chain_.eta.data(), 8 * static_cast<std::size_t>(m_));
    put(chain_.xi.data(), 8 * static_cast<std::size_t>(m_));
    if (barostat_) {  // version 2: the barostat and the volume follow
      const std::uint32_t v2 = 2;
      std::memcpy(bytes.data() + 4, &v2, 4);
      const std::vector<std::uint8_t> b = barostat_->save();
      const auto* vol = reinterpret_cast<const std::uint8_t*>(&volume_);
      bytes.insert(bytes.end(), vol, vol + 8);
      bytes.insert(bytes.end(), b.begin(), b.end());
    }
    return bytes;
  }

  void restore_state(std::span<const std::uint8_t> bytes) override {
    std::uint32_t version = 0, m = 0;
    if (bytes.size() >= 12) {
      std::memcpy(&version, bytes.data() + 4, 4);
      std::memcpy(&m, bytes.data() + 8, 4);
    }
    Chain c;
    double dof = 0.0;
    const std::size_t base = state_bytes(m_);
    // Version 1: the chain; version 2 (a barostat): the volume and the barostat after it.
    bool framed = bytes.size() >= base && std::memcmp(bytes.data(), kMagic, 4) == 0 &&
                  version == (barostat_ ? 2u : kStateVersion) &&
                  m == static_cast<std::uint32_t>(m_) && (barostat_ || bytes.size() == base);
    // Read into copies: a refused state leaves the solver as it was.
    std::optional<nose_hoover::Barostat> barostat = barostat_;
    double volume = volume_;
    if (framed && barostat) {
      framed = bytes.size() > base + 8 && barostat->restore(bytes.subspan(base + 8));
      if (framed) std::memcpy(&volume, bytes.data() + base, 8);
    }
    if (framed) {
      const std::uint8_t* p = bytes.data() + 12;
      std::memcpy(&dof, p, 8);
      std::memcpy(c.eta.data(), p + 8, 8 * static_cast<std::size_t>(m_));
      std::memcpy(c.xi.data(), p + 8 + 8 * static_cast<std::size_t>(m_),
                  8 * static_cast<std::size_t>(m_));
    }
    if (!framed || !finite(c) || !(dof >= 0 && std::isfinite(dof))) {
      throw pdyn::Error(fmt::format(
          "nose_hoover: the checkpoint's solver state is not one this nose_hoover (chain: {}) "
          "wrote ({} bytes; expected {} bytes starting with 'nhch' version {}, chain length {}, "
          "then finite numbers{})",
          m_, bytes.size(), state_bytes(m_), barostat_ ? 2u : kStateVersion, m_,
          barostat_ ? ", the volume and the barostat's state" : ""));
    }
    chain_ = c;
    dof_ = dof;
    barostat_ = barostat;
    volume_ = volume;
  }

 private:
  static std::size_t state_bytes(int m) { return 12 + 8 + 16 * static_cast<std::size_t>(m); }

  static bool finite(const Chain& c) {
    return std::all_of(c.eta.begin(), c.eta.end(), [](double y) { return std::isfinite(y); }) &&
           std::all_of(c.xi.begin(), c.xi.end(), [](double y) { return std::isfinite(y); });
  }

  // N_f = 3 N_free - extra_dof - rank J, at least 0 (pdyn::thermo's count):
  // each independent constraint row takes one degree of freedom, whose
  // kinetic energy the constraint keeps at 0, so the chain must not ask for
  // kT / 2 in it (Martyna, Klein & Tuckerman 1992 count the constrained
  // system's degrees of freedom).
  double degrees_of_freedom(const pdyn::System& sys) const {
    const auto& fixed = sys.fixed();
    const auto nailed = std::count_if(fixed.begin(), fixed.end(), [](auto f) { return f != 0; });
    const double removed = sys.constraint_rows() > 0 ? pdyn::constraint_dof(sys) : 0.0;
    return std::max(0.0, 3.0 * static_cast<double>(sys.size() - nailed) - extra_dof_ - removed);
  }

  // Q_1 = N_f kT tau^2, Q_j = kT tau^2.
  std::array<double, kMaxChain> thermostat_masses(double dof) const {
    std::array<double, kMaxChain> q{};
    q.fill(kT_ * tau2_);
    q[0] = dof * kT_ * tau2_;
    return q;
  }

  // Calls update(b, e) on the fixed chunks of the particles, then returns
  // 2K = sum_i m_i |v_i|^2 of the velocities it leaves: each chunk's sum in
  // particle order, the chunks' sums in chunk order (fixed_chunks: the same
  // bits for any thread count). Fixed particles add m 0 = 0.
  template <class Update>
  double update_then_twice_k(const pdyn::System& sys, Update&& update) {
    const Index n = sys.size();
    const auto v = sys.velocities();
    const Eigen::VectorXd& mass = sys.masses();
    partial_.resize((n + kChunk - 1) / kChunk);  // no-op after the first step
    fixed_chunks(n, kChunk, [&](Index c, Index b, Index e) {
      update(b, e);
      double s = 0.0;
      for (Index i = b; i < e; ++i) s += mass(i) * v.col(i).squaredNorm();
      partial_[static_cast<std::size_t>(c)] = s;
    });
    double sum = 0.0;
    for (const double s : partial_) sum += s;
    return sum;
  }

  // One chain half step of length d (h/2), from 2K = `twice_k` of the
  // velocities before it: updates `c` and returns the factor
  // exp(-d xi_1) that scales the velocities (see the top of this file).
  double half_step(Chain& c, double dof, double twice_k, double d) const {
    const std::array<double, kMaxChain> q = thermostat_masses(dof);
    auto force = [&](int j) {  // G_j, 1/s^2
      return j == 0 ? (twice_k - dof * kT_) / q[0]
                    : (q[j - 1] * c.xi[j - 1] * c.xi[j - 1] - kT_) / q[j];
    };
    auto kick = [&](int j) {
      const double f = std::exp(-0.25 * d * c.xi[j + 1]);
      c.xi[j] = (c.xi[j] * f + force(j) * (0.5 * d)) * f;
    };
    for (int j = m_ - 1; j >= 0; --j) kick(j);
    const double scale = std::exp(-d * c.xi[0]);
    twice_k *= scale * scale;
    for (int j = 0; j < m_; ++j) c.eta[j] += d * c.xi[j];
    for (int j = 0; j < m_; ++j) kick(j);
    return scale;
  }

  double kT_, tau2_;
  int m_;
  double extra_dof_;
  Chain chain_;
  std::optional<nose_hoover::Barostat> barostat_;  // `pressure:` given
  double volume_ = 0.0;  // the box's volume after the last step (barostat)
  double virial_ = 0.0;  // W at the last step's end, with the kept a1
  bool virial_kept_ = false;
  double dof_ = 0.0;             // N_f of the last step, for reservoir_energy()
  std::vector<double> partial_;  // 2K per fixed chunk
  pdyn::Matrix3X half_;          // v_half for velocity-dependent forces, sized on first use
  pdyn::ForceReuse reuse_;       // the last step's a1, while it may stand in for a0
};

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Solver;
  d.name = "nose_hoover";
  d.version = "1.1.0";
  d.description =
      "velocity Verlet in a Nose-Hoover chain thermostat at temperature T (MTK 1996, as LAMMPS's "
      "fix nvt); order 2, conserves K + U + reservoir";
  d.solver_traits.order = 2;
  d.solver_traits.symplectic = false;
  d.params = pdyn::temperature_params("the target temperature", true);
  d.params.insert(
      d.params.end(),
      {
          pdyn::param::required_real("tdamp", "s",
                                     "damping time tau; LAMMPS suggests about 100 time steps")
              .greater_than(0),
          pdyn::param::integer("chain", 3, "thermostats in the chain, M")
              .at_least(1)
              .at_most(kMaxChain),
          pdyn::param::real(
              "extra_dof", 3.0, "",
              "degrees of freedom removed from 3 N_free for N_f (3: the total momentum, "
              "as the energy writer)")
              .at_least(0),
          pdyn::param::optional("pressure", pdyn::ParamType::Real, "Pa",
                                "the target pressure P0: an isotropic MTK barostat (LAMMPS's fix "
                                "npt iso); without it, constant volume"),
          pdyn::param::optional("pdamp", pdyn::ParamType::Real, "s",
                                "the barostat's damping time; LAMMPS suggests about 1000 time "
                                "steps (needed with pressure)")
              .greater_than(0),
          pdyn::param::integer("pchain", 3, "thermostats in the barostat's chain")
              .at_least(1)
              .at_most(nose_hoover::Barostat::kMaxChain),
      });
  d.create_solver = [](const pdyn::Params& p, const pdyn::SceneContext&) {
    const double kT = pdyn::temperature_kT(p);
    std::optional<nose_hoover::Barostat> barostat;
    if (p.has("pressure") != p.has("pdamp")) {
      throw pdyn::ParamError(p.has("pressure") ? "pdamp" : "pressure",
                             "the barostat needs both pressure and pdamp (expected both or "
                             "neither)");
    }
    if (p.has("pressure")) {
      barostat.emplace(p.real("pressure"), p.real("pdamp"), static_cast<int>(p.integer("pchain")),
                       kT);
    }
    return std::make_unique<NoseHoover>(kT, p.real("tdamp"), static_cast<int>(p.integer("chain")),
                                        p.real("extra_dof"), barostat);
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
