#include "pdyn/thermo.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "pdyn/error.hpp"
#include "pdyn/solver.hpp"
#include "pdyn/system.hpp"

namespace pdyn {

VirialSource::~VirialSource() = default;
EnergyReservoir::~EnergyReservoir() = default;

std::vector<ParamSpec> temperature_params(const std::string& what, bool positive) {
  ParamSpec kelvin = param::optional("temperature", ParamType::Real, "K", what + " (or give kT)");
  ParamSpec energy =
      param::optional("kT", ParamType::Real, "J",
                      "k_B T, " + what + " in energy units (reduced units: LAMMPS's T*)");
  for (ParamSpec* s : {&kelvin, &energy}) {
    if (positive) {
      s->greater_than(0);
    } else {
      s->at_least(0);
    }
  }
  energy.with_sample(1.0);
  return {kelvin, energy};
}

double temperature_kT(const Params& p) {
  const bool kelvin = p.has("temperature"), energy = p.has("kT");
  constexpr const char* kExpected = "temperature: T in K, or kT: k_B T in J for reduced units";
  if (!kelvin && !energy) {
    throw ParamError("temperature", fmt::format("no temperature given (expected {})", kExpected));
  }
  if (kelvin && energy) {
    throw ParamError("kT", fmt::format("given with temperature (expected one of {})", kExpected));
  }
  return kelvin ? kBoltzmann * p.real("temperature") : p.real("kT");
}

VirialSum total_virial(const System& sys) {
  VirialSum sum;
  const ParticleView p = sys.view();
  for (const auto& entry : sys.force_objects()) {
    const auto* source = dynamic_cast<const VirialSource*>(entry.force.get());
    if (source == nullptr) {
      if (sum.missing.empty()) sum.missing = entry.label;
      continue;
    }
    sum.value += source->virial(p);
  }
  if (!sum.missing.empty()) sum.value = std::numeric_limits<double>::quiet_NaN();
  return sum;
}

double total_reservoir_energy(const System& sys, const Solver* solver) {
  double e = 0.0;
  for (const auto& entry : sys.force_objects()) {
    if (const auto* r = dynamic_cast<const EnergyReservoir*>(entry.force.get())) {
      e += r->reservoir_energy();
    }
  }
  if (const auto* r = dynamic_cast<const EnergyReservoir*>(solver)) e += r->reservoir_energy();
  return e;
}

Thermo thermo(const ParticleView& p, double virial, double extra_dof) {
  Thermo out;
  double twice_k = 0.0;
  Index free = 0;
  for (Index i = 0; i < p.size(); ++i) {
    if (!p.fixed.empty() && p.fixed[static_cast<std::size_t>(i)] != 0) continue;
    ++free;
    twice_k += p.mass(i) * p.v.col(i).squaredNorm();
  }
  out.dof = std::max(0.0, 3.0 * static_cast<double>(free) - extra_dof);
  out.kinetic = 0.5 * twice_k;
  out.kT = out.dof > 0 ? twice_k / out.dof : 0.0;
  out.temperature = out.kT / kBoltzmann;
  // A box is given when max > min along every axis (Domain's default, open
  // space, has max == min).
  const Vec3 length = p.domain.length();
  out.volume =
      (length.array() > 0).all() ? length.prod() : std::numeric_limits<double>::quiet_NaN();
  out.virial = virial;
  out.pressure = (twice_k + virial) / (3.0 * out.volume);
  return out;
}

}  // namespace pdyn
