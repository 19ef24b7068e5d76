#include "pdyn/random.hpp"

#include <Random123/philox.h>

#include <Random123/boxmuller.hpp>
#include <Random123/uniform.hpp>

namespace pdyn {

namespace {

r123::Philox4x64::ctr_type draw(const RandomKey& key, std::uint64_t step, std::uint64_t i) {
  const r123::Philox4x64 generator;
  const r123::Philox4x64::ctr_type counter = {{step, i, 0, 0}};
  const r123::Philox4x64::key_type k = {{key.seed, key.stream}};
  return generator(counter, k);
}

}  // namespace

Vec3 standard_normal3(const RandomKey& key, std::uint64_t step, std::uint64_t i) {
  const auto r = draw(key, step, i);
  // Each pair of 64-bit words gives two normals; the fourth is not used.
  const r123::double2 a = r123::boxmuller(r[0], r[1]);
  const r123::double2 b = r123::boxmuller(r[2], r[3]);
  return {a.x, a.y, b.x};
}

Eigen::Vector4d uniform4(const RandomKey& key, std::uint64_t step, std::uint64_t i) {
  const auto r = draw(key, step, i);
  // u01: (0, 1], never 0 (a logarithm of it is finite).
  return {r123::u01<double>(r[0]), r123::u01<double>(r[1]), r123::u01<double>(r[2]),
          r123::u01<double>(r[3])};
}

}  // namespace pdyn
