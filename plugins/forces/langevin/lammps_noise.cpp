#include "lammps_noise.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <pdyn/error.hpp>

namespace pdyn_langevin {

using pdyn::Index;

// The paper's initialisation (its routine RSTART) from ij = (seed - 1) /
// 30082 and kl = the remainder: four seeds of a lagged Fibonacci and a
// congruential sequence whose bits fill the 97 lagged values, 24 bits
// each.
Ranmar::Ranmar(std::int64_t seed) {
  const std::int64_t ij = (seed - 1) / 30082;
  const std::int64_t kl = (seed - 1) - 30082 * ij;
  std::int64_t i = (ij / 177) % 177 + 2;
  std::int64_t j = ij % 177 + 2;
  std::int64_t k = (kl / 169) % 178 + 1;
  std::int64_t l = kl % 169;
  for (double& value : u_) {
    double s = 0.0;
    double t = 0.5;
    for (int bit = 0; bit < 24; ++bit) {
      const std::int64_t m = ((i * j) % 179) * k % 179;
      i = j;
      j = k;
      k = m;
      l = (53 * l + 1) % 169;
      if ((l * m) % 64 >= 32) s += t;
      t *= 0.5;
    }
    value = s;
  }
  c_ = 362436.0 / 16777216.0;
  i_ = 96;
  j_ = 32;
  uniform();  // as RanMars's constructor
}

void Ranmar::fill(double* out, std::size_t count, std::vector<double>& history) {
  constexpr double kCd = 7654321.0 / 16777216.0;
  constexpr double kCm = 16777213.0 / 16777216.0;
  // history[m] = x_{n-97+m}: the slot written 97 - m calls ago, i_ - m (mod
  // 97), since uniform() writes the slots in decreasing order.
  history.resize(97 + count);
  double* h = history.data();
  for (int m = 0; m < 97; ++m) h[m] = u_[static_cast<std::size_t>((i_ - m + 97) % 97)];
#pragma omp simd safelen(32)
  for (std::size_t k = 0; k < count; ++k) {
    // x_{n-97} - x_{n-33}: iteration k reads what iteration k - 33 wrote,
    // so 32 in a row are independent.
    const double x = h[k] - h[k + 64];
    h[k + 97] = x + (x < 0.0 ? 1.0 : 0.0);
  }
  // c after k + 1 steps of -cd (mod cm), four chains of -4 cd (mod cm).
  constexpr double kCd4 = (4.0 * 7654321.0 - 16777213.0) / 16777216.0;  // 4 cd mod cm
  std::array<double, 4> c{};
  double previous = c_;
  for (double& lane : c) {
    previous -= kCd;
    previous += previous < 0.0 ? kCm : 0.0;
    lane = previous;
  }
  const auto step = [&](std::size_t k, std::size_t l) {
    const double y = h[k + l + 97] - c[l];
    out[k + l] = y + (y < 0.0 ? 1.0 : 0.0);
    const double next = c[l] - kCd4;
    c[l] = next + (next < 0.0 ? kCm : 0.0);
  };
  std::size_t k = 0;
  for (; k + 4 <= count; k += 4) {
    for (std::size_t l = 0; l < 4; ++l) step(k, l);
  }
  for (std::size_t l = 0; k + l < count; ++l) step(k, l);
  // The state after `count` calls: c stepped count times, the slots moved.
  c_ = count == 0 ? c_ : c[(count - 1) % 4];
  if (count > 0) {
    // Lane (count - 1) % 4 holds c after count steps only before its last
    // advance: step it back.
    const double back = c_ + kCd4;
    c_ = back >= kCm ? back - kCm : back;
  }
  const int moved = static_cast<int>(count % 97);
  i_ = (i_ - moved + 97) % 97;
  j_ = (j_ - moved + 97) % 97;
  for (int m = 0; m < 97; ++m) u_[static_cast<std::size_t>((i_ - m + 97) % 97)] = h[count + m];
}

void Ranmar::save(std::uint8_t* out) const {
  std::memcpy(out, u_.data(), 97 * 8);
  std::memcpy(out + 97 * 8, &c_, 8);
  const std::int32_t ij[2] = {i_, j_};
  std::memcpy(out + 98 * 8, ij, 8);
}

void Ranmar::load(const std::uint8_t* in) {
  std::memcpy(u_.data(), in, 97 * 8);
  std::memcpy(&c_, in + 97 * 8, 8);
  std::int32_t ij[2];
  std::memcpy(ij, in + 98 * 8, 8);
  if (ij[0] < 0 || ij[0] > 96 || ij[1] < 0 || ij[1] > 96) {
    throw pdyn::Error("langevin: the checkpoint's generator state is damaged");
  }
  i_ = ij[0];
  j_ = ij[1];
}

// LAMMPS's Atom::sort on one process: bins of edge `bin` (as many whole
// bins as fit, then stretched to fill the box), numbered x fastest; the
// particles bin after bin and, within a bin, in index order (the order
// read, the atoms' ids for a data file written in id order).
void LammpsNoise::set_order(const Eigen::Ref<const pdyn::Matrix3X>& x, const pdyn::Domain& domain) {
  const Index n = x.cols();
  first_of_.clear();
  order_.resize(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) order_[static_cast<std::size_t>(i)] = i;
  if (bin_ <= 0.0) return;
  if (!(domain.periodic[0] && domain.periodic[1] && domain.periodic[2])) {
    throw pdyn::Error(
        "langevin: lammps_sort_bin needs a box periodic along x, y and z, the box LAMMPS bins "
        "its atoms in (expected lammps_sort_bin: 0 for open space)");
  }
  std::array<int, 3> bins{};
  std::array<double, 3> inverse{};
  for (int d = 0; d < 3; ++d) {
    const double length = domain.max[d] - domain.min[d];
    bins[static_cast<std::size_t>(d)] = std::max(1, static_cast<int>(length * (1.0 / bin_)));
    inverse[static_cast<std::size_t>(d)] = bins[static_cast<std::size_t>(d)] / length;
  }
  if (bins[0] * bins[1] * bins[2] == 1) return;  // LAMMPS does not sort into one bin
  std::vector<std::int64_t> key(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) {
    const pdyn::Vec3 w = domain.wrap(x.col(i));
    std::array<std::int64_t, 3> cell{};
    for (int d = 0; d < 3; ++d) {
      const auto ud = static_cast<std::size_t>(d);
      const int c = static_cast<int>((w[d] - domain.min[d]) * inverse[ud]);
      cell[ud] = std::clamp(c, 0, bins[ud] - 1);
    }
    key[static_cast<std::size_t>(i)] = (cell[2] * bins[1] + cell[1]) * bins[0] + cell[0];
  }
  std::stable_sort(order_.begin(), order_.end(), [&](Index a, Index b) {
    return key[static_cast<std::size_t>(a)] < key[static_cast<std::size_t>(b)];
  });
}

void LammpsNoise::draw(std::vector<double>& into) {
  if (first_of_.size() != order_.size()) {  // where each particle's numbers start
    first_of_.assign(order_.size(), -1);
    Index next = 0;
    for (const Index i : order_) {
      if (in_bath_[static_cast<std::size_t>(i)] == 0) continue;
      first_of_[static_cast<std::size_t>(i)] = next;
      next += 3;
    }
    count_ = static_cast<std::size_t>(next);
  }
  into.resize(count_);
  gen_.fill(into.data(), count_, history_);
}

const std::vector<double>& LammpsNoise::block(long long k, const std::vector<std::uint8_t>& in_bath,
                                              const Eigen::Ref<const pdyn::Matrix3X>& x,
                                              const pdyn::Domain& domain) {
  if (order_.empty()) {
    in_bath_ = in_bath;
    set_order(x, domain);
  }
  if (static_cast<std::size_t>(x.cols()) != order_.size()) {
    throw pdyn::Error(fmt::format(
        "langevin: the system has {} particles, but LAMMPS's order was set for {} (expected the "
        "particles the run started with)",
        x.cols(), order_.size()));
  }
  if (k == block_) return noise_;
  if (k == block_ - 1 && have_previous_) return previous_;
  if (k == block_ + 1) {
    std::swap(previous_, noise_);
    have_previous_ = block_ >= 0;
    before_ = gen_;
    draw(noise_);
    block_ = k;
    return noise_;
  }
  // Another block (a step replayed further back, a run started later than
  // t = 0): the stream again from the seed.
  gen_ = Ranmar(seed_);
  for (long long b = 0; b <= k; ++b) {
    std::swap(previous_, noise_);
    before_ = gen_;
    draw(noise_);
  }
  have_previous_ = k > 0;
  block_ = k;
  return noise_;
}

namespace {

constexpr char kMagic[4] = {'L', 'G', 'V', '1'};

}  // namespace

// 'LGV1', N, the block, the generator before it, then the order and the
// bath (8 and 1 bytes per particle). Nothing before the first draw.
std::vector<std::uint8_t> LammpsNoise::save() const {
  if (block_ < 0) return {};
  const std::int64_t n = static_cast<std::int64_t>(order_.size());
  std::vector<std::uint8_t> out(4 + 8 + 8 + Ranmar::kStateBytes + static_cast<std::size_t>(n) * 9);
  std::uint8_t* p = out.data();
  std::memcpy(p, kMagic, 4);
  std::memcpy(p + 4, &n, 8);
  const std::int64_t b = block_;
  std::memcpy(p + 12, &b, 8);
  before_.save(p + 20);
  p += 20 + Ranmar::kStateBytes;
  for (const Index i : order_) {
    const std::int64_t v = i;
    std::memcpy(p, &v, 8);
    p += 8;
  }
  std::memcpy(p, in_bath_.data(), in_bath_.size());
  return out;
}

void LammpsNoise::restore(std::span<const std::uint8_t> bytes) {
  if (bytes.empty()) {  // checkpointed before the first draw
    order_.clear();
    first_of_.clear();
    block_ = -1;
    have_previous_ = false;
    gen_ = before_ = Ranmar(seed_);
    return;
  }
  constexpr std::size_t kHead = 4 + 8 + 8 + Ranmar::kStateBytes;
  std::int64_t n = -1;
  if (bytes.size() >= 12) std::memcpy(&n, bytes.data() + 4, 8);
  if (bytes.size() < kHead || std::memcmp(bytes.data(), kMagic, 4) != 0 || n < 0 ||
      bytes.size() != kHead + static_cast<std::size_t>(n) * 9) {
    throw pdyn::Error(fmt::format(
        "langevin: the checkpoint's state ({} bytes) is not the lammps generator's (expected "
        "'LGV1', N and {} + 9 N bytes)",
        bytes.size(), kHead));
  }
  const std::uint8_t* p = bytes.data();
  std::int64_t b = 0;
  std::memcpy(&b, p + 12, 8);
  Ranmar before(seed_);
  before.load(p + 20);
  p += 20 + Ranmar::kStateBytes;
  std::vector<Index> order(static_cast<std::size_t>(n));
  std::vector<bool> seen(static_cast<std::size_t>(n), false);
  for (auto& i : order) {
    std::int64_t v = 0;
    std::memcpy(&v, p, 8);
    p += 8;
    if (v < 0 || v >= n || seen[static_cast<std::size_t>(v)] || b < 0) {
      throw pdyn::Error("langevin: the checkpoint's draw order is damaged");
    }
    seen[static_cast<std::size_t>(v)] = true;
    i = static_cast<Index>(v);
  }
  order_ = std::move(order);
  first_of_.clear();
  in_bath_.assign(p, p + n);
  before_ = gen_ = before;
  draw(noise_);
  block_ = b;
  have_previous_ = false;
}

}  // namespace pdyn_langevin
