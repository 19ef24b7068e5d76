#include "pdyn/thermo.hpp"

#include <fmt/format.h>

#include <Eigen/OrderingMethods>
#include <Eigen/QR>
#include <Eigen/SparseCore>
#include <Eigen/SparseQR>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>

#include "pdyn/constraint_solver.hpp"
#include "pdyn/error.hpp"
#include "pdyn/solver.hpp"
#include "pdyn/system.hpp"

namespace pdyn {

VirialSource::~VirialSource() = default;
EnergyReservoir::~EnergyReservoir() = default;
ConstraintVirialSource::~ConstraintVirialSource() = default;

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

namespace {

// The rank of a group of rows (each row's free entries scaled to unit
// length, so that rows in different units weigh alike), by column-pivoted
// QR: rank-revealing with the threshold 1e-10 relative to the largest pivot.
// `entries` lists, per row, its (free particle's column, gradient) pairs.
constexpr double kRankThreshold = 1e-10;
constexpr Index kDenseRows = 200;

struct Entry {
  Index column;  // the particle's position among the group's particles
  Vec3 gradient;
};

double group_rank(const std::vector<std::vector<Entry>>& rows, Index columns) {
  const auto m = static_cast<Index>(rows.size());
  if (m <= kDenseRows) {
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(3 * columns, m);  // J^T: QR pivots J's rows
    for (Index r = 0; r < m; ++r) {
      for (const Entry& e : rows[r]) a.block<3, 1>(3 * e.column, r) = e.gradient;
    }
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
    qr.setThreshold(kRankThreshold);
    return static_cast<double>(qr.rank());
  }
  std::vector<Eigen::Triplet<double>> triplets;
  for (Index r = 0; r < m; ++r) {
    for (const Entry& e : rows[r]) {
      for (int d = 0; d < 3; ++d) triplets.emplace_back(r, 3 * e.column + d, e.gradient(d));
    }
  }
  // J itself (rows x coordinates): a cloth has more rods than coordinates,
  // and sparse QR's cost grows with the columns it eliminates.
  Eigen::SparseMatrix<double> a(m, 3 * columns);
  a.setFromTriplets(triplets.begin(), triplets.end());
  a.makeCompressed();
  Eigen::SparseQR<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>> qr;
  qr.setPivotThreshold(kRankThreshold);
  qr.compute(a);
  return static_cast<double>(qr.rank());
}

// The large groups' ranks cost a sparse QR (seconds for a 5,000-rod cloth):
// they are counted once per structure (the System, its constraint objects,
// rows and fixed particles) and kept, per thread, for the frames after.
struct LargeGroupCache {
  std::uint64_t key = 0;
  double rank = -1.0;
};

std::uint64_t structure_key(const System& sys) {
  // FNV-1a over what decides the rows' pattern and which particles are free.
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&](std::uint64_t v) {
    h ^= v;
    h *= 1099511628211ull;
  };
  mix(reinterpret_cast<std::uintptr_t>(&sys));
  mix(static_cast<std::uint64_t>(sys.size()));
  mix(static_cast<std::uint64_t>(sys.constraint_rows()));
  for (const auto& c : sys.constraint_objects()) {
    mix(reinterpret_cast<std::uintptr_t>(c.constraint.get()));
  }
  for (const auto f : sys.fixed()) mix(f);
  return h;
}

}  // namespace

double constraint_dof(const System& sys) {
  if (sys.constraint_rows() == 0) return 0.0;
  thread_local LargeGroupCache cache;
  const std::uint64_t key = structure_key(sys);
  const bool cached = cache.key == key && cache.rank >= 0.0;
  const ConstraintRows& rows = sys.evaluate_constraint_rows();
  const auto& fixed = sys.fixed();
  const Index m = rows.rows();
  // Each row's free entries, scaled to unit length; rows without any count 0.
  std::vector<std::vector<Entry>> free(static_cast<std::size_t>(m));
  for (Index r = 0; r < m; ++r) {
    double norm2 = 0.0;
    for (Index e = rows.row_begin[r]; e < rows.row_begin[r + 1]; ++e) {
      if (fixed[static_cast<std::size_t>(rows.particle[e])] != 0) continue;
      free[r].push_back({rows.particle[e], rows.jacobian.col(e)});
      norm2 += rows.jacobian.col(e).squaredNorm();
    }
    if (!(norm2 > 0.0)) {
      free[r].clear();
      continue;
    }
    for (Entry& e : free[r]) e.gradient /= std::sqrt(norm2);
  }
  // Groups of rows that share free particles (union-find over particles):
  // rows in different groups act on disjoint coordinates, so the ranks add.
  std::vector<Index> parent(static_cast<std::size_t>(sys.size()));
  std::iota(parent.begin(), parent.end(), Index{0});
  auto root = [&](Index k) {
    while (parent[k] != k) k = parent[k] = parent[parent[k]];
    return k;
  };
  for (Index r = 0; r < m; ++r) {
    for (std::size_t e = 1; e < free[r].size(); ++e) {
      parent[root(free[r][e].column)] = root(free[r][0].column);
    }
  }
  std::vector<std::vector<Index>> groups(static_cast<std::size_t>(sys.size()));
  for (Index r = 0; r < m; ++r) {
    if (!free[r].empty()) groups[root(free[r][0].column)].push_back(r);
  }
  double removed = 0.0, large = 0.0;
  std::vector<Index> column(static_cast<std::size_t>(sys.size()), -1);
  for (const auto& group : groups) {
    if (group.size() <= 1) {
      removed += static_cast<double>(group.size());  // one nonzero row: rank 1
      continue;
    }
    if (static_cast<Index>(group.size()) > kDenseRows && cached) continue;
    std::vector<std::vector<Entry>> local;
    Index columns = 0;
    for (const Index r : group) {
      local.push_back(free[r]);
      for (Entry& e : local.back()) {
        if (column[e.column] < 0) column[e.column] = columns++;
        e.column = column[e.column];
      }
    }
    const double rank = group_rank(local, columns);
    removed += rank;
    if (static_cast<Index>(group.size()) > kDenseRows) large += rank;
  }
  if (!cached) cache = {key, large};
  return removed + (cached ? cache.rank : 0.0);
}

double constraint_force_virial(const ParticleView& p, const ConstraintRows& rows,
                               const Eigen::VectorXd& multipliers) {
  double w = 0.0;
  for (Index r = 0; r + 1 < static_cast<Index>(rows.row_begin.size()); ++r) {
    const Index first = rows.row_begin[r];
    const Vec3 x0 = p.x.col(rows.particle[first]);
    double row = 0.0;
    for (Index e = first + 1; e < rows.row_begin[r + 1]; ++e) {
      const Vec3 d = p.domain.minimum_image(Vec3(p.x.col(rows.particle[e]) - x0));
      row += d.dot(rows.jacobian.col(e));
    }
    w += multipliers(r) * row;
  }
  return w;
}

VirialSum total_virial(const System& sys, const Solver* solver, double h) {
  VirialSum sum = total_virial(sys);
  if (sys.constraint_rows() == 0) return sum;
  const auto* keeper = dynamic_cast<const ConstraintSolver*>(solver);
  double w = std::numeric_limits<double>::quiet_NaN();
  if (keeper != nullptr && keeper->enforces_constraints()) {
    if (const auto* source = dynamic_cast<const ConstraintVirialSource*>(solver)) {
      // A state where the solver cannot compute it (one about to blow up,
      // rows it cannot factorise) must not stop a run that never writes a
      // pressure: the value is unknown, and a writer that needs it says why.
      try {
        w = source->constraint_virial(sys, h);
      } catch (const Error& e) {
        if (sum.missing.empty()) sum.missing = std::string(kSolverFailed) + e.what();
      }
    } else if (sum.missing.empty()) {
      sum.missing = "solver";
    }
  } else {
    w = sys.constraint_force_virial();
  }
  sum.value += w;
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
