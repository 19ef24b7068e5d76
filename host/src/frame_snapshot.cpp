#include "frame_snapshot.hpp"

#include <fmt/format.h>

#include <cstring>
#include <limits>
#include <type_traits>

#include "pdyn/bonded_reference.hpp"
#include "pdyn/error.hpp"
#include "pdyn/kernel/plugin_call.hpp"
#include "pdyn/thermo.hpp"

namespace pdyn {

namespace {

// LAMMPS's E_mol: the potential energy of the bonded terms' forces (those
// with pdyn/bonded_reference.hpp's hook), summed in the System's order.
double bonded_potential(const System& sys) {
  const ParticleView p = sys.view();
  double u = 0.0;
  for (const auto& entry : sys.force_objects()) {
    if (dynamic_cast<const BondedReference*>(entry.force.get()) == nullptr) continue;
    const crash::CallScope scope(entry.label, "potential_energy");
    if (const auto e = entry.force->potential_energy(p)) u += *e;
  }
  return u;
}

}  // namespace

void FrameSnapshot::capture(const System& sys, const Solver* solver, std::int64_t frame_step,
                            bool with_force, bool with_energy, double h,
                            bool with_constraint_virial) {
  const ParticleView p = sys.view();
  step = frame_step;
  t = p.t;
  x = p.x;
  v = p.v;
  mass = p.mass;
  fixed.assign(p.fixed.begin(), p.fixed.end());
  domain = p.domain;
  radius.assign(p.radius.begin(), p.radius.end());
  type.assign(p.type.begin(), p.type.end());
  images.assign(sys.images().begin(), sys.images().end());
  has_force = with_force;
  if (with_force) force = sys.forces();
  kinetic_energy = with_energy ? sys.kinetic_energy() : 0.0;
  potential_energy = with_energy ? sys.potential_energy() : 0.0;
  virial = 0.0;
  virial_missing.clear();
  reservoir_energy = 0.0;
  constraint_dof = 0.0;
  bonded_energy = 0.0;
  if (with_energy) {
    VirialSum w = with_constraint_virial ? total_virial(sys, solver, h) : total_virial(sys);
    if (!with_constraint_virial && sys.constraint_rows() > 0) {
      w.value = std::numeric_limits<double>::quiet_NaN();
      w.missing = "the constraint forces (no writer asked for the pressure)";
    }
    virial = w.value;
    virial_missing = std::move(w.missing);
    reservoir_energy = total_reservoir_energy(sys, solver);
    constraint_dof = pdyn::constraint_dof(sys);
    bonded_energy = bonded_potential(sys);
  }
}

Frame FrameSnapshot::frame(bool with_force, bool with_energy) const {
  Frame f(ParticleView{t, Eigen::Map<const Matrix3X>(x.data(), 3, x.cols()),
                       Eigen::Map<const Matrix3X>(v.data(), 3, v.cols()),
                       Eigen::Map<const Eigen::VectorXd>(mass.data(), mass.size()),
                       std::span<const std::uint8_t>(fixed), domain,
                       std::span<const double>(radius), std::span<const std::int32_t>(type)});
  f.step = step;
  f.images = images;
  if (with_force && has_force) f.force = &force;
  if (with_energy) {
    f.kinetic_energy = kinetic_energy;
    f.potential_energy = potential_energy;
    f.virial = virial;
    f.virial_missing = virial_missing;
    f.reservoir_energy = reservoir_energy;
    f.constraint_dof = constraint_dof;
    f.bonded_energy = bonded_energy;
  }
  return f;
}

namespace {

// Version 1: i64 step, f64 t, u64 N, f64[3N] x, f64[3N] v, f64[N] mass,
// u8[N] fixed, f64[3] min, f64[3] max, u8[3] periodic, u64 n + f64[n]
// radius, u64 n + i32[n] type, u64 n + i32[3n] images, u8 has_force,
// f64[3N] force if has_force, f64 kinetic, f64 potential.
// Version 2 (pdyn 0.8.0) appends f64 virial, f64 reservoir energy, u64 n +
// char[n] virial_missing. Version 3 (pdyn 0.10.0) appends f64
// constraint_dof. Version 4 (pdyn 0.10.0, later) appends f64
// bonded_energy. Earlier versions are still read (0.7's to 0.9's
// checkpoints; what they lack is 0).
constexpr std::uint32_t kVersion = 4;

struct Out {
  std::vector<std::uint8_t> bytes;
  void raw(const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    bytes.insert(bytes.end(), b, b + n);
  }
  template <class T>
  void pod(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    raw(&value, sizeof(T));
  }
  template <class T>
  void array(const T* p, std::size_t n) {
    pod<std::uint64_t>(n);
    raw(p, n * sizeof(T));
  }
};

struct In {
  std::span<const std::uint8_t> data;
  std::size_t at = 0;
  void raw(void* p, std::size_t n) {
    if (n > data.size() - at) {
      throw Error(
          fmt::format("a pending output frame is truncated (needs {} more bytes at offset "
                      "{}, has {})",
                      n, at, data.size() - at));
    }
    if (n) std::memcpy(p, data.data() + at, n);
    at += n;
  }
  template <class T>
  T pod() {
    T value{};
    raw(&value, sizeof(T));
    return value;
  }
  // A count of items of `size` bytes, checked against what is left.
  std::size_t count(std::size_t size) {
    const auto n = pod<std::uint64_t>();
    if (n > (data.size() - at) / size) {
      throw Error(fmt::format("a pending output frame announces {} items, more than it holds", n));
    }
    return static_cast<std::size_t>(n);
  }
  template <class T>
  void array(std::vector<T>& out) {
    out.resize(count(sizeof(T)));
    raw(out.data(), out.size() * sizeof(T));
  }
};

}  // namespace

std::vector<std::uint8_t> FrameSnapshot::encode() const {
  Out o;
  const auto n = static_cast<std::size_t>(x.cols());
  o.pod(kVersion);
  o.pod(step);
  o.pod(t);
  o.pod<std::uint64_t>(n);
  o.raw(x.data(), 3 * n * sizeof(double));
  o.raw(v.data(), 3 * n * sizeof(double));
  o.raw(mass.data(), n * sizeof(double));
  o.raw(fixed.data(), n);
  for (int k = 0; k < 3; ++k) o.pod(domain.min[k]);
  for (int k = 0; k < 3; ++k) o.pod(domain.max[k]);
  for (int k = 0; k < 3; ++k) o.pod<std::uint8_t>(domain.periodic[k]);
  o.array(radius.data(), radius.size());
  o.array(type.data(), type.size());
  o.array(images.data(), images.size());
  o.pod<std::uint8_t>(has_force);
  if (has_force) o.raw(force.data(), 3 * n * sizeof(double));
  o.pod(kinetic_energy);
  o.pod(potential_energy);
  o.pod(virial);
  o.pod(reservoir_energy);
  o.array(virial_missing.data(), virial_missing.size());
  o.pod(constraint_dof);
  o.pod(bonded_energy);
  return std::move(o.bytes);
}

FrameSnapshot FrameSnapshot::decode(std::span<const std::uint8_t> data) {
  In in{data};
  FrameSnapshot s;
  const auto version = in.pod<std::uint32_t>();
  if (version < 1 || version > kVersion) {
    throw Error(
        fmt::format("a pending output frame has version {} (expected 1 to {})", version, kVersion));
  }
  s.step = in.pod<std::int64_t>();
  s.t = in.pod<double>();
  const std::size_t n = in.count(7 * sizeof(double) + 1);
  const auto cols = static_cast<Index>(n);
  s.x.resize(3, cols);
  s.v.resize(3, cols);
  s.mass.resize(cols);
  s.fixed.resize(n);
  in.raw(s.x.data(), 3 * n * sizeof(double));
  in.raw(s.v.data(), 3 * n * sizeof(double));
  in.raw(s.mass.data(), n * sizeof(double));
  in.raw(s.fixed.data(), n);
  for (int k = 0; k < 3; ++k) s.domain.min[k] = in.pod<double>();
  for (int k = 0; k < 3; ++k) s.domain.max[k] = in.pod<double>();
  for (int k = 0; k < 3; ++k) s.domain.periodic[k] = in.pod<std::uint8_t>() != 0;
  in.array(s.radius);
  in.array(s.type);
  in.array(s.images);
  s.has_force = in.pod<std::uint8_t>() != 0;
  if (s.has_force) {
    s.force.resize(3, cols);
    in.raw(s.force.data(), 3 * n * sizeof(double));
  }
  s.kinetic_energy = in.pod<double>();
  s.potential_energy = in.pod<double>();
  if (version >= 2) {
    s.virial = in.pod<double>();
    s.reservoir_energy = in.pod<double>();
    std::vector<char> missing;
    in.array(missing);
    s.virial_missing.assign(missing.begin(), missing.end());
  } else {
    s.virial = std::numeric_limits<double>::quiet_NaN();
    s.virial_missing = "(a frame from pdyn 0.7)";
  }
  if (version >= 3) s.constraint_dof = in.pod<double>();
  if (version >= 4) s.bonded_energy = in.pod<double>();
  if (in.at != data.size()) {
    throw Error(fmt::format("a pending output frame has {} unexpected bytes at its end",
                            data.size() - in.at));
  }
  if ((!s.radius.empty() && s.radius.size() != n) || (!s.type.empty() && s.type.size() != n) ||
      (!s.images.empty() && s.images.size() != n)) {
    throw Error(
        fmt::format("a pending output frame's radii, types or images are not {} values", n));
  }
  return s;
}

}  // namespace pdyn
