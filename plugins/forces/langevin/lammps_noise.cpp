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

void LammpsNoise::draw(pdyn::Matrix3X& into) {
  into.setZero(3, static_cast<Index>(order_.size()));
  Ranmar g = gen_;  // a local copy stays in registers: `into` cannot alias it
  double* out = into.data();
  for (const Index i : order_) {
    if (in_bath_[static_cast<std::size_t>(i)] == 0) continue;
    for (Index d = 0; d < 3; ++d) out[3 * i + d] = g.uniform() - 0.5;  // exact: 24-bit fractions
  }
  gen_ = g;
}

const pdyn::Matrix3X& LammpsNoise::block(long long k, const std::vector<std::uint8_t>& in_bath,
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
  in_bath_.assign(p, p + n);
  before_ = gen_ = before;
  draw(noise_);
  block_ = b;
  have_previous_ = false;
}

}  // namespace pdyn_langevin
