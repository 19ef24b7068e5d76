// langevin's `generator: lammps`: the random numbers of LAMMPS's
// `fix langevin` on one process, so that a converted input follows LAMMPS's
// run step for step (issue 44; docs/lammps.md).
//
// LAMMPS's fix draws, at every force evaluation of velocity Verlet (the
// set-up's and each step's end), three uniform numbers per atom of its group
// in the order its atoms are stored, from one Marsaglia generator seeded
// with the fix's seed (RanMars, seed + rank). It stores its atoms in the
// order of its spatial sort (Atom::sort) at the set-up: the atoms binned
// by position into cubes of `bin` (half the neighbor cutoff by default),
// bin after bin, and in the order read within a bin.
//
// Here the numbers of the evaluation at t = k h (k = 0 the set-up) are the
// k-th block of 3 x (particles in the bath) draws: the same numbers however
// often the host evaluates at that time, and a run resumed from a
// checkpoint continues the stream (save() / restore()).
#pragma once

#include <array>
#include <cstdint>
#include <pdyn/domain.hpp>
#include <pdyn/types.hpp>
#include <span>
#include <vector>

namespace pdyn_langevin {

// RANMAR, the universal generator of Marsaglia, Zaman & Tsang, "Toward a
// universal random number generator", Statistics & Probability Letters 9
// (1990) 35-39: a lagged Fibonacci generator (lags 97, 33) on 24-bit
// fractions combined with an arithmetic sequence, period 2^144. Seeded
// from one number as LAMMPS's RanMars seeds it (1 <= seed <= 900000000,
// split into the paper's two seeds ij, kl), which also draws one number
// before its first use.
class Ranmar {
 public:
  explicit Ranmar(std::int64_t seed);

  // The paper's routine RANMAR: x_n = x_{n-97} - x_{n-33} mod 1, minus the
  // arithmetic sequence c_n = c_{n-1} - 7654321/2^24 mod 16777213/2^24. In
  // [0, 1). Each "mod 1" a select rather than a branch: the signs are
  // random. fill() gives a bath's block the same numbers faster.
  double uniform() {
    constexpr double kCd = 7654321.0 / 16777216.0;
    constexpr double kCm = 16777213.0 / 16777216.0;
    const auto i = static_cast<std::size_t>(i_), j = static_cast<std::size_t>(j_);
    double uni = u_[i] - u_[j];
    uni += uni < 0.0 ? 1.0 : 0.0;  // + 0.0 changes no value: uni is never -0.0
    u_[i] = uni;
    i_ = i_ == 0 ? 96 : i_ - 1;
    j_ = j_ == 0 ? 96 : j_ - 1;
    const double c = c_ - kCd;
    c_ = c + (c < 0.0 ? kCm : 0.0);
    uni -= c_;
    return uni + (uni < 0.0 ? 1.0 : 0.0);
  }

  // The next `count` numbers, as `count` calls of uniform() give them, into
  // out[0, count). The lagged values as one array, so that 33 consecutive
  // ones never depend on each other (the loop runs in vector registers),
  // and the arithmetic sequence in four interleaved chains: the numbers are
  // multiples of 2^-24 below 1, so every step is exact and the order of the
  // steps cannot change a bit. `history` is scratch, grown as needed.
  void fill(double* out, std::size_t count, std::vector<double>& history);

  static constexpr std::size_t kStateBytes = 97 * 8 + 8 + 2 * 4;
  void save(std::uint8_t* out) const;
  void load(const std::uint8_t* in);

 private:
  std::array<double, 97> u_{};
  double c_ = 0.0;
  int i_ = 96, j_ = 32;  // the paper's 97 and 33, 0-based
};

class LammpsNoise {
 public:
  // `bin`: the sort's bin edge (m); 0 keeps the particles' order.
  LammpsNoise(std::int64_t seed, double bin) : seed_(seed), bin_(bin), gen_(seed), before_(seed) {}

  // The numbers u in [0, 1) of the evaluation at step boundary `k` (>= 0),
  // in draw order: particle i's are those at first_of()[i] + 0, 1, 2, none
  // where first_of()[i] < 0 (outside the bath), read there by the force's
  // threads. At the first call `in_bath` (1 for a particle in the bath, N),
  // `x` (m, 3 x N) and `domain` set the draw order; later calls must give
  // the same N.
  const std::vector<double>& block(long long k, const std::vector<std::uint8_t>& in_bath,
                                   const Eigen::Ref<const pdyn::Matrix3X>& x,
                                   const pdyn::Domain& domain);

  // The draw order, the bath and the generator before the current block: a
  // checkpoint's state. restore() throws pdyn::Error for bytes save() did not
  // write, and leaves the stream as it was.
  std::vector<std::uint8_t> save() const;
  void restore(std::span<const std::uint8_t> bytes);

  const std::vector<pdyn::Index>& first_of() const noexcept { return first_of_; }

 private:
  void set_order(const Eigen::Ref<const pdyn::Matrix3X>& x, const pdyn::Domain& domain);
  void draw(std::vector<double>& into);

  std::int64_t seed_;
  double bin_;
  std::vector<pdyn::Index> order_;  // the draw order, set at the first draw
  std::vector<std::uint8_t> in_bath_;
  std::vector<pdyn::Index> first_of_;     // per particle: its first number, -1 outside the bath
  std::vector<double> history_;           // scratch of Ranmar::fill
  std::size_t count_ = 0;                 // numbers per block: 3 per particle in the bath
  Ranmar gen_;                            // after block_
  Ranmar before_;                         // before block_
  long long block_ = -1;                  // the block noise_ holds, -1 none
  std::vector<double> noise_, previous_;  // blocks block_ and block_ - 1, in draw order
  bool have_previous_ = false;
};

}  // namespace pdyn_langevin
