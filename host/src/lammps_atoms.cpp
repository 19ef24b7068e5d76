// LAMMPS's own atoms and velocities, bit for bit (lammps_atoms.hpp). Each
// function follows one LAMMPS routine's arithmetic, operation for operation:
// a velocity drawn by `loop geom` hashes the position's bytes, so a site one
// rounding away from LAMMPS's would get entirely different numbers.
#include "lammps_atoms.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstring>

#include "pdyn/error.hpp"

namespace pdyn::lammps {

std::vector<Vec3> lattice_basis(const std::string& style) {
  if (style == "sc") return {Vec3(0.0, 0.0, 0.0)};
  if (style == "bcc") return {Vec3(0.0, 0.0, 0.0), Vec3(0.5, 0.5, 0.5)};
  if (style == "fcc") {
    return {Vec3(0.0, 0.0, 0.0), Vec3(0.5, 0.5, 0.0), Vec3(0.5, 0.0, 0.5), Vec3(0.0, 0.5, 0.5)};
  }
  return {};
}

double lattice_spacing(std::size_t nbasis, double rho) {
  const double volume = 1.0;  // a1 . (a2 x a3) of the unit cube
  return std::pow(static_cast<double>(nbasis) / volume / rho, 1.0 / 3.0);
}

std::vector<Vec3> lattice_sites(const std::vector<Vec3>& basis, double spacing, const Block& box,
                                const Block* region) {
  // The insertion box: LAMMPS moves both faces of a periodic axis inwards
  // by e and 2 e, so that a site on the upper face (the image of one on the
  // lower face) is not made twice.
  std::array<double, 3> lo{}, hi{};
  std::array<int, 3> first{}, last{};
  for (int k = 0; k < 3; ++k) {
    const double e = (box.hi[k] - box.lo[k]) * 1.0e-6;
    lo[k] = box.lo[k] - e;
    hi[k] = box.hi[k] - 2.0 * e;
    // Every cell that can hold a site inside; LAMMPS's own range (from the
    // box corners in lattice units, one cell more each way) is within it,
    // and cells outside add nothing, so the order is the same.
    first[k] = static_cast<int>(std::floor(box.lo[k] / spacing)) - 2;
    last[k] = static_cast<int>(std::ceil(box.hi[k] / spacing)) + 2;
  }
  std::vector<Vec3> out;
  for (int k = first[2]; k <= last[2]; ++k) {
    for (int j = first[1]; j <= last[1]; ++j) {
      for (int i = first[0]; i <= last[0]; ++i) {
        for (const Vec3& b : basis) {
          // Lattice::lattice2box with the identity orientation and origin
          // 0: exactly (i + b) a.
          const Vec3 x((i + b.x()) * spacing, (j + b.y()) * spacing, (k + b.z()) * spacing);
          bool inside = true;
          for (int a = 0; a < 3; ++a) {
            if (region && !(x[a] >= region->lo[a] && x[a] <= region->hi[a])) inside = false;
            if (x[a] < lo[a] || x[a] >= hi[a]) inside = false;
          }
          if (inside) out.push_back(x);
        }
      }
    }
  }
  return out;
}

// Park and Miller's minimal standard (Comm. ACM 31, 1192, 1988) with
// Schrage's factorisation m = a q + r, so that a seed never overflows.
double ParkMiller::uniform() {
  constexpr int kA = 16807, kM = 2147483647, kQ = 127773, kR = 2836;
  const int k = seed_ / kQ;
  seed_ = kA * (seed_ - k * kQ) - kR * k;
  if (seed_ < 0) seed_ += kM;
  return (1.0 / kM) * seed_;
}

double ParkMiller::gaussian() {
  if (saved_) {
    saved_ = false;
    return second_;
  }
  double v1 = 0.0, v2 = 0.0, rsq = 0.0;
  do {
    v1 = 2.0 * uniform() - 1.0;
    v2 = 2.0 * uniform() - 1.0;
    rsq = v1 * v1 + v2 * v2;
  } while (!(rsq < 1.0 && rsq != 0.0));
  const double fac = std::sqrt(-2.0 * std::log(rsq) / rsq);
  second_ = v1 * fac;
  saved_ = true;
  return v2 * fac;
}

void ParkMiller::reset(int ibase, const std::array<double, 3>& coord) {
  unsigned int hash = 0;
  // LAMMPS reads the bytes through a char *, signed on x86-64: a byte of
  // 0x80 or more adds a negative number.
  auto mix = [&hash](const unsigned char* bytes, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
      hash += static_cast<unsigned int>(static_cast<int>(static_cast<signed char>(bytes[i])));
      hash += hash << 10;
      hash ^= hash >> 6;
    }
  };
  unsigned char base[sizeof(int)], where[sizeof(coord)];
  std::memcpy(base, &ibase, sizeof(base));
  std::memcpy(where, coord.data(), sizeof(where));
  mix(base, sizeof(base));
  mix(where, sizeof(where));
  hash += hash << 3;
  hash ^= hash >> 11;
  hash += hash << 15;
  seed_ = static_cast<int>(hash & 0x7ffffff);  // 27 bits, whatever LAMMPS's comment says
  if (seed_ == 0) seed_ = 1;
  for (int i = 0; i < 5; ++i) uniform();
  saved_ = false;
}

namespace {

Vec3 draw(ParkMiller& random, bool gaussian) {
  Vec3 u;
  for (int a = 0; a < 3; ++a) u[a] = gaussian ? random.gaussian() : random.uniform() - 0.5;
  return u;
}

}  // namespace

Matrix3X velocity_create(const Matrix3X& x, const std::vector<double>& mass,
                         const VelocityCreate& c) {
  const Index n = x.cols();
  Matrix3X v(3, n);
  ParkMiller random(c.loop == VelocityCreate::Loop::Geom ? 1 : c.seed);
  if (c.loop == VelocityCreate::Loop::Local) {
    for (int i = 0; i < 100; ++i) random.uniform();  // Velocity's WARMUP, process 0's seed
  }
  for (Index i = 0; i < n; ++i) {
    if (c.loop == VelocityCreate::Loop::Geom) random.reset(c.seed, {x(0, i), x(1, i), x(2, i)});
    const double factor = 1.0 / std::sqrt(mass[static_cast<std::size_t>(i)]);
    const Vec3 u = draw(random, c.gaussian);
    for (int a = 0; a < 3; ++a) v(a, i) = u[a] * factor;
  }
  if (c.momentum) {  // Velocity::zero_momentum, Group::mass and Group::vcm
    double total = 0.0;
    for (Index i = 0; i < n; ++i) total += mass[static_cast<std::size_t>(i)];
    std::array<double, 3> p{};
    for (Index i = 0; i < n; ++i) {
      for (int a = 0; a < 3; ++a) p[a] += v(a, i) * mass[static_cast<std::size_t>(i)];
    }
    if (total > 0.0) {
      for (double& pa : p) pa /= total;
    }
    for (Index i = 0; i < n; ++i) {
      for (int a = 0; a < 3; ++a) v(a, i) -= p[a];
    }
  }
  // ComputeTemp::compute_scalar: the sum times 1 / N_f, N_f = 3 n - 3.
  double sum = 0.0;
  for (Index i = 0; i < n; ++i) {
    sum += (v(0, i) * v(0, i) + v(1, i) * v(1, i) + v(2, i) * v(2, i)) *
           mass[static_cast<std::size_t>(i)];
  }
  double dof = 3.0 * static_cast<double>(n);
  dof -= 3.0;
  const double now = dof > 0.0 ? sum * (1.0 / (dof * 1.0)) : 0.0;
  if (!(now > 0.0)) {
    throw Error(fmt::format(
        "velocity create: the drawn velocities have no temperature to scale ({} atoms; expected "
        "at least 2)",
        n));
  }
  v *= std::sqrt(c.temperature / now);  // Velocity::rescale
  return v;
}

}  // namespace pdyn::lammps
