#include "pdyn/thermo.hpp"

#include <fmt/format.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <utility>
#include <vector>

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
// QR: rank-revealing with the threshold 1e-10 relative to the largest pivot;
// above kDenseRows rows by Givens rotations into R with the same threshold
// (sparse_rank). `entries` lists, per row, its (free particle's column,
// gradient) pairs.
constexpr double kRankThreshold = 1e-10;
constexpr Index kDenseRows = 200;

struct Entry {
  Index column;  // the particle's position among the group's particles
  Vec3 gradient;
};

// A large group's particles in reverse Cuthill-McKee order (George & Liu,
// "Computer Solution of Large Sparse Positive Definite Systems", 1981, 4.3):
// breadth first from a far end of each connected part, neighbours of fewer
// neighbours first, the whole reversed. Numbered so, the coordinates a row
// touches lie close together, and so does every row of R (R^T R = J^T J, whose
// envelope this order keeps narrow: a cloth's R is a band as wide as about
// two of its rows of particles). position[k] is particle k's place.
std::vector<Index> band_order(const std::vector<std::vector<Entry>>& rows, Index columns) {
  std::vector<std::vector<Index>> next(static_cast<std::size_t>(columns));
  for (const auto& row : rows) {
    for (const Entry& a : row) {
      for (const Entry& b : row) {
        if (a.column != b.column) next[a.column].push_back(b.column);
      }
    }
  }
  for (auto& n : next) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  std::vector<Index> order, seen(static_cast<std::size_t>(columns), -1);
  // Breadth first from `start`, marking with `mark`; returns where this pass began.
  auto visit = [&](Index start, Index mark) {
    const auto first = order.size();
    order.push_back(start);
    seen[start] = mark;
    for (auto at = first; at < order.size(); ++at) {
      std::vector<Index> fresh;
      for (const Index k : next[order[at]]) {
        if (seen[k] == mark) continue;
        seen[k] = mark;
        fresh.push_back(k);
      }
      std::stable_sort(fresh.begin(), fresh.end(),
                       [&](Index a, Index b) { return next[a].size() < next[b].size(); });
      order.insert(order.end(), fresh.begin(), fresh.end());
    }
    return first;
  };
  for (Index k = 0; k < columns; ++k) {
    if (seen[k] >= 0) continue;
    Index start = k;
    for (Index mark : {columns + 2 * k, columns + 2 * k + 1}) {  // twice to a far end
      const auto first = visit(start, mark);
      start = order.back();
      order.resize(first);
    }
    visit(start, k);
  }
  std::vector<Index> position(static_cast<std::size_t>(columns));
  for (Index i = 0; i < columns; ++i)
    position[order[static_cast<std::size_t>(i)]] = columns - 1 - i;
  return position;
}

// R of a QR factorisation of J built a row at a time by Givens rotations
// (George & Heath, "Solution of sparse linear least squares problems using
// Givens rotations", Linear Algebra Appl. 34, 1980), keeping R only: row k of
// R, if any, starts at column k and is held densely to its last nonzero.
class GivensRank {
 public:
  explicit GivensRank(Index n) : r_(static_cast<std::size_t>(n)), x_(static_cast<std::size_t>(n)) {}

  // Rotates the row x (nonzero in [lo, hi) only) into R, column by column:
  // where R has a row, a rotation zeroes x there; where it has none, an
  // entry of x at most the threshold is taken for 0 (the rounding left of a
  // row that depends on the ones before: a flat cloth's rows across its
  // plane, a rotation about a lone pin), and the first larger one makes the
  // rest of x that row of R: the rank grows by one. So a column of R is only
  // ever led by an entry above the threshold, and rotations only grow it.
  void add(Index lo, Index hi) {
    for (Index k = lo; k < hi; ++k) {
      if (x_[k] == 0.0) continue;
      std::vector<double>& row = r_[k];
      if (row.empty()) {
        if (std::abs(x_[k]) <= kRankThreshold) continue;
        row.assign(x_.begin() + k, x_.begin() + hi);
        ++rank_;
        break;
      }
      if (k + static_cast<Index>(row.size()) < hi) row.resize(static_cast<std::size_t>(hi - k));
      hi = k + static_cast<Index>(row.size());
      rotate(row, k, hi);
    }
    std::fill(x_.begin() + lo, x_.begin() + hi, 0.0);
  }

  double& x(Index column) { return x_[static_cast<std::size_t>(column)]; }
  Index rank() const { return rank_; }

 private:
  // The rotation of (row, x) that zeroes x_k, over columns [k, hi).
  void rotate(std::vector<double>& row, Index k, Index hi) {
    const double a = row[0], b = x_[k], h = std::hypot(a, b), c = a / h, s = b / h;
    row[0] = h;
    x_[k] = 0.0;
    for (Index j = k + 1; j < hi; ++j) {
      const double rj = row[j - k], xj = x_[j];
      row[j - k] = c * rj + s * xj;
      x_[j] = c * xj - s * rj;
    }
  }

  std::vector<std::vector<double>> r_;
  std::vector<double> x_;
  Index rank_ = 0;
};

// The rank of a large group: its rows rotated into R one by one (GivensRank),
// the coordinates in band order, the rows in the order of their first
// coordinate there. Each row counts if what remains of it, rotated against
// the rows before it, has an entry above the threshold where R has no row
// yet, as the sparse QR of J that this replaced counted each column whose
// remainder had a norm above it: on a cloth the two sides are apart by
// orders of magnitude (xpbd_cloth.yaml, pinned or not, of other sizes:
// pivots of 0.01 and more, rounding of 4e-14 and less, around 1e-10), so
// that both count the same; this in about 30 ms where that took 7 s.
double sparse_rank(const std::vector<std::vector<Entry>>& rows, Index columns) {
  const std::vector<Index> position = band_order(rows, columns);
  std::vector<std::pair<Index, Index>> first;  // (first coordinate, row)
  for (Index r = 0; r < static_cast<Index>(rows.size()); ++r) {
    Index lo = 3 * columns;
    for (const Entry& e : rows[r]) lo = std::min(lo, 3 * position[e.column]);
    first.emplace_back(lo, r);
  }
  std::stable_sort(first.begin(), first.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  GivensRank qr(3 * columns);
  for (const auto& [lo, r] : first) {
    Index hi = lo;
    for (const Entry& e : rows[r]) {
      for (int d = 0; d < 3; ++d) qr.x(3 * position[e.column] + d) = e.gradient(d);
      hi = std::max(hi, 3 * position[e.column] + 3);
    }
    qr.add(lo, hi);
  }
  return static_cast<double>(qr.rank());
}

double group_rank(const std::vector<std::vector<Entry>>& rows, Index columns) {
  const auto m = static_cast<Index>(rows.size());
  if (m > kDenseRows) return sparse_rank(rows, columns);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(3 * columns, m);  // J^T: QR pivots J's rows
  for (Index r = 0; r < m; ++r) {
    for (const Entry& e : rows[r]) a.block<3, 1>(3 * e.column, r) = e.gradient;
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
  qr.setThreshold(kRankThreshold);
  return static_cast<double>(qr.rank());
}

// The large groups' ranks cost Givens rotations (30 ms for a 5,000-rod cloth):
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
