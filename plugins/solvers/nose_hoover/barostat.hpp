// nose_hoover's barostat (`pressure:`): the isotropic MTK barostat of
// Martyna, Tobias & Klein, J. Chem. Phys. 101, 4177 (1994), with its own
// Nose-Hoover chain, integrated as Shinoda, Shiga & Mikami, Phys. Rev. B
// 69, 134103 (2004) and as LAMMPS's `fix npt ... iso` (fix_nh.cpp), step
// for step. The box's log-volume rate omega_dot (1/s, per axis, the three
// equal) obeys
//
//   W d(omega_dot)/dt = (P - P0) V + 2K / (3 N) - W omega_dot xi_p1,
//
// with P = (2K + W_vir) / (3V) the virial pressure, W = (N + 1) kT / w_p^2
// the barostat's mass (w_p = 1 / pdamp), and xi_p the velocities of the
// barostat's own chain (masses kT / w_p^2), which keeps the barostat's
// kinetic energy 3 W omega_dot^2 / 2 at kT / 2. The particles feel it
// through v -> v exp(-(omega_dot + 3 omega_dot / (3 N)) dt / 2) and the box
// and positions through a dilation by exp(omega_dot dt / 2) about the box's
// first centre, twice per step (LAMMPS's remap() around and after x += dt v).
//
// The conserved quantity (reservoir_energy(), beside the particles' chain)
// is K + U + P0 (V - V0) + 3 W omega_dot^2 / 2 + the barostat chain's
// kT eta_p1 + sum kT eta_pj + Q_pj xi_pj^2 / 2. (LAMMPS's `f_ID` counts
// 3 kT eta_p1 for the first term while its integrator drives the chain to
// kT, so its reported sum drifts; pdyn reports the one that is conserved.)
#pragma once

#include <array>
#include <cstdint>
#include <pdyn/system.hpp>
#include <span>
#include <vector>

namespace nose_hoover {

class Barostat {
 public:
  static constexpr int kMaxChain = 10;

  /// pressure: P0 (Pa); pdamp: 1 / w_p (s, > 0); chain: the barostat's
  /// thermostats (1..kMaxChain); kT: the temperature's k_B T (J).
  Barostat(double pressure, double pdamp, int chain, double kT);

  /// LAMMPS's setup(): the masses from N, the fixed point (the box's centre)
  /// and V0, at the first step. Throws pdyn::Error when some axis is not
  /// periodic or some particle is fixed (the dilation moves every particle).
  void start(const pdyn::System& sys);
  bool started() const noexcept { return started_; }

  /// nhc_press_integrate: a chain half step for a step of h, which scales
  /// omega_dot.
  void chain_half_step(double h);
  /// nh_omega_dot: omega_dot += h / 2 (f), from the pressure `p` (Pa), the
  /// volume (m^3) and 2K (J) of the state.
  void kick(double p, double volume, double twice_k, double h);
  /// exp(-h / 4 (omega_dot + 3 omega_dot / (3 N))): nh_v_press scales the
  /// velocities by it twice.
  double velocity_factor(double h) const;
  /// remap(): the box and every position dilated by exp(omega_dot h / 2)
  /// about the fixed point, through scaled coordinates as LAMMPS does.
  void dilate(pdyn::System& sys, double h) const;

  /// The barostat's part of the conserved quantity, J, at the box `volume`.
  double reservoir_energy(double volume) const;

  /// Its state, bit for bit: omega_dot, the chain, the fixed point, V0.
  std::vector<std::uint8_t> save() const;
  /// Reads what save() wrote; false if `bytes` is not that.
  bool restore(std::span<const std::uint8_t> bytes);
  bool finite() const;

 private:
  double kinetic() const { return 3.0 * (w_ * omega_dot_ * omega_dot_); }

  double pressure_, pfreq_, kT_;
  int m_;
  bool started_ = false;
  double n_ = 0.0;  // particles, N
  double w_ = 0.0;  // W, kg m^2 (its unit makes W omega_dot^2 an energy)
  std::array<double, kMaxChain> q_{};
  double omega_dot_ = 0.0;
  std::array<double, kMaxChain> eta_{};
  std::array<double, kMaxChain + 1> xi_{};  // xi_[m_] stays 0
  std::array<double, 3> centre_{};
  double volume0_ = 0.0;
};

}  // namespace nose_hoover
