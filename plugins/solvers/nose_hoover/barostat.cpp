// The isotropic MTK barostat (barostat.hpp). Each function is one of
// LAMMPS's FixNH routines (29 Sep 2021), in its order of operations, so
// that a converted `fix npt ... iso` run follows LAMMPS's to rounding.
#include "barostat.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <pdyn/error.hpp>

namespace nose_hoover {

using pdyn::Index;

Barostat::Barostat(double pressure, double pdamp, int chain, double kT)
    : pressure_(pressure), pfreq_(1.0 / pdamp), kT_(kT), m_(chain) {}

void Barostat::start(const pdyn::System& sys) {
  const pdyn::Domain& d = sys.domain();
  for (int k = 0; k < 3; ++k) {
    if (!d.periodic[k]) {
      throw pdyn::Error(fmt::format(
          "nose_hoover: the barostat (pressure) needs a box periodic along every axis; axis {} "
          "is open (expected simulation.box with periodic: [true, true, true])",
          "xyz"[k]));
    }
  }
  const auto& fixed = sys.fixed();
  if (const auto it = std::find(fixed.begin(), fixed.end(), std::uint8_t{1}); it != fixed.end()) {
    throw pdyn::Error(fmt::format(
        "nose_hoover: the barostat (pressure) dilates every particle with the box, and particle "
        "{} is fixed (expected no fixed particles)",
        it - fixed.begin()));
  }
  n_ = static_cast<double>(sys.size());
  // LAMMPS's setup(): W = (N + 1) kT / w_p^2, Q_pj = kT / w_p^2.
  w_ = (n_ + 1.0) * kT_ / (pfreq_ * pfreq_);
  q_.fill(kT_ / (pfreq_ * pfreq_));
  for (int k = 0; k < 3; ++k) centre_[k] = 0.5 * (d.min[k] + d.max[k]);
  volume0_ = (d.max[0] - d.min[0]) * (d.max[1] - d.min[1]) * (d.max[2] - d.min[2]);
  started_ = true;
}

// nhc_press_integrate with ploop 1: the chain moves xi_M .. xi_1 by a
// quarter step each between two scalings, advances eta, scales omega_dot,
// then moves xi_1 .. xi_M again. The first thermostat's force drives the
// barostat's kinetic energy (summed over the three axes) to kT: one degree
// of freedom, as LAMMPS's iso.
void Barostat::chain_half_step(double h) {
  const double dt8 = 0.125 * h, dt4 = 0.25 * h, dthalf = 0.5 * h;
  std::array<double, kMaxChain> g{};  // the chain's forces, LAMMPS's etap_dotdot
  g[0] = (kinetic() - kT_) / q_[0];
  for (int j = 1; j < m_; ++j) g[j] = (q_[j - 1] * xi_[j - 1] * xi_[j - 1] - kT_) / q_[j];
  for (int j = m_ - 1; j > 0; --j) {
    const double e = std::exp(-dt8 * xi_[j + 1]);
    xi_[j] *= e;
    xi_[j] += g[j] * dt4;
    xi_[j] *= e;
  }
  const double e0 = std::exp(-dt8 * xi_[1]);
  xi_[0] *= e0;
  xi_[0] += g[0] * dt4;
  xi_[0] *= e0;
  for (int j = 0; j < m_; ++j) eta_[j] += dthalf * xi_[j];
  omega_dot_ *= std::exp(-dthalf * xi_[0]);
  g[0] = (kinetic() - kT_) / q_[0];
  xi_[0] *= e0;
  xi_[0] += g[0] * dt4;
  xi_[0] *= e0;
  for (int j = 1; j < m_; ++j) {
    const double e = std::exp(-dt8 * xi_[j + 1]);
    xi_[j] *= e;
    g[j] = (q_[j - 1] * xi_[j - 1] * xi_[j - 1] - kT_) / q_[j];
    xi_[j] += g[j] * dt4;
    xi_[j] *= e;
  }
}

// nh_omega_dot, iso: the force on omega_dot is the pressure's excess over
// the target (LAMMPS's p_hydro, the mean of three equal targets) times V,
// plus MTK's correction 2K / (3 N), both over W.
void Barostat::kick(double p, double volume, double twice_k, double h) {
  const double hydro = ((pressure_ + pressure_) + pressure_) / 3.0;
  const double mtk = twice_k / (3.0 * n_);
  const double f = (p - hydro) * volume / w_ + mtk / w_;
  omega_dot_ += f * (0.5 * h);
}

double Barostat::velocity_factor(double h) const {
  const double mtk = ((omega_dot_ + omega_dot_) + omega_dot_) / (3.0 * n_);
  return std::exp(-(0.25 * h) * (omega_dot_ + mtk));
}

// remap(): x -> lambda = (x - lo) / L with the old box, the box's faces
// moved away from the centre by exp(omega_dot h / 2), x = L' lambda + lo'.
void Barostat::dilate(pdyn::System& sys, double h) const {
  const pdyn::Domain& d = sys.domain();
  const double e = std::exp((0.5 * h) * omega_dot_);
  pdyn::Vec3 lo, hi, inverse, length;
  for (int k = 0; k < 3; ++k) {
    inverse[k] = 1.0 / (d.max[k] - d.min[k]);
    lo[k] = (d.min[k] - centre_[k]) * e + centre_[k];
    hi[k] = (d.max[k] - centre_[k]) * e + centre_[k];
    length[k] = hi[k] - lo[k];
  }
  const pdyn::Vec3 old_lo = d.min;
  auto x = sys.positions();
  for (Index i = 0; i < x.cols(); ++i) {
    for (int k = 0; k < 3; ++k) x(k, i) = length[k] * (inverse[k] * (x(k, i) - old_lo[k])) + lo[k];
  }
  sys.resize_box(lo, hi);
}

double Barostat::reservoir_energy(double volume) const {
  if (!started_) return 0.0;
  double e = 0.5 * kinetic() + pressure_ * (volume - volume0_);
  for (int j = 0; j < m_; ++j) e += kT_ * eta_[j] + 0.5 * q_[j] * xi_[j] * xi_[j];
  return e;
}

namespace {
constexpr char kMagic[4] = {'m', 't', 'k', '1'};
}

std::vector<std::uint8_t> Barostat::save() const {
  std::vector<std::uint8_t> out(4);
  std::memcpy(out.data(), kMagic, 4);
  auto put = [&out](const double* p, std::size_t k) {
    const auto* b = reinterpret_cast<const std::uint8_t*>(p);
    out.insert(out.end(), b, b + 8 * k);
  };
  const double flags[2] = {started_ ? 1.0 : 0.0, static_cast<double>(m_)};
  put(flags, 2);
  put(&n_, 1);
  put(&w_, 1);
  put(&omega_dot_, 1);
  put(&volume0_, 1);
  put(centre_.data(), 3);
  put(q_.data(), static_cast<std::size_t>(m_));
  put(eta_.data(), static_cast<std::size_t>(m_));
  put(xi_.data(), static_cast<std::size_t>(m_));
  return out;
}

bool Barostat::restore(std::span<const std::uint8_t> bytes) {
  const std::size_t m = static_cast<std::size_t>(m_);
  if (bytes.size() != 4 + 8 * (9 + 3 * m) || std::memcmp(bytes.data(), kMagic, 4) != 0) {
    return false;
  }
  const std::uint8_t* p = bytes.data() + 4;
  auto get = [&p](double* dst, std::size_t k) {
    std::memcpy(dst, p, 8 * k);
    p += 8 * k;
  };
  double flags[2];
  get(flags, 2);
  if (flags[1] != static_cast<double>(m_)) return false;
  Barostat b = *this;
  b.started_ = flags[0] != 0.0;
  get(&b.n_, 1);
  get(&b.w_, 1);
  get(&b.omega_dot_, 1);
  get(&b.volume0_, 1);
  get(b.centre_.data(), 3);
  get(b.q_.data(), m);
  get(b.eta_.data(), m);
  get(b.xi_.data(), m);
  if (!b.finite()) return false;
  *this = b;
  return true;
}

bool Barostat::finite() const {
  auto ok = [](double y) { return std::isfinite(y); };
  return std::isfinite(omega_dot_) && std::isfinite(w_) && std::isfinite(volume0_) &&
         std::all_of(eta_.begin(), eta_.end(), ok) && std::all_of(xi_.begin(), xi_.end(), ok) &&
         std::all_of(centre_.begin(), centre_.end(), ok);
}

}  // namespace nose_hoover
