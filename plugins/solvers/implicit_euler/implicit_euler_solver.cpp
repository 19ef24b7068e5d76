// implicit_euler: linearised backward Euler, after D. Baraff and A. Witkin,
// "Large Steps in Cloth Simulation", SIGGRAPH 1998, sections 3 and 5.
//
// Backward Euler, v1 = v0 + h M^-1 f(x1, v1), x1 = x0 + h v1, linearised
// once about (x0, v0) gives the velocity change dv from (their eq. 18)
//
//   (M - h df/dv - h^2 df/dx) dv = h (f0 + h df/dx v0),
//
// then v1 = v0 + dv, x1 = x0 + h v1. One linear solve per step, no Newton
// iterations: first order, and unconditionally stable for the linearised
// system, which is what lets stiff cloth take large steps.
//
// Choices, and why:
// * f0, df/dx and df/dv are evaluated at (t0 + h, x0, v0). Backward Euler
//   wants forces at the end of the step; evaluating at t0 + h is, to first
//   order, the linearly implicit (Rosenbrock) Euler method's h df/dt term.
//   Colliders' contact forces are part of f0 but are not differentiated.
// * Fixed particles' rows and columns are left out of A (Baraff & Witkin's
//   constraint filter, section 5.3, with z = 0), so the system is solved on
//   the free particles only.
// * When every force supplies Jacobians, A is factorised, A = L D L^T with
//   3 x 3 blocks (BlockLdlt below), by default. Preconditioned CG needs
//   ~sqrt(cond A) ~ h w_max iterations, and on stiff cloth h w_max is in the
//   hundreds; a sparse factorisation costs about as much as 50 CG
//   iterations on the 30 x 30 cloth of bench/ and is exact, so it is 1.5x
//   faster there than CG at its loose default tolerance and more at any
//   tighter one (docs/solvers.md). The ordering and L's pattern depend only
//   on A's block pattern, which is kept from step to step, so they are
//   computed once; each step refactorises in place. Tried and dropped:
//   keeping a factor for several steps as CG's preconditioner (A changes
//   too fast on stiff cloth: at h^2 ks / m ~ 1e4 a spring turning by a
//   hundredth of a radian changes A by more than M; refactorising every 5
//   steps took 2.6x as long as every step, every 10 steps 8.5x).
// * Otherwise (or with linear_solver: cg) the system is solved by
//   preconditioned conjugate gradients, residuals and search directions
//   filtered.
// * The preconditioner is the inverse of A's 3 x 3 diagonal block of each
//   particle (block Jacobi). Baraff & Witkin use A's scalar diagonal; the
//   block form does not depend on how the springs are oriented against the
//   coordinate axes, which matters once cloth folds: on the stiff cloth of
//   bench/ it needs 3x fewer iterations than the scalar diagonal (103
//   against 298 per step at cg_tolerance 1e-3). Symmetric block
//   Gauss-Seidel halves the iterations again but doubles their cost, and
//   warm-starting from the previous step's dv saves under 20% while making
//   the solver carry state, so neither is used.
// * CG needs A symmetric positive definite: the shipped forces keep df/dx
//   symmetric negative semidefinite (see spring.cpp); a search direction
//   with p.Ap <= 0 is reported as an error rather than followed.
// * Forces whose add_jacobians() returns false (third-party forces) enter
//   matrix-free: their part of the product, h^2 df/dx u + h df/dv u, is the
//   central difference [F(x + e h^2 u, v + e h u) - F(x - e h^2 u,
//   v - e h u)] / (2 e) of their add_forces(), e = eps^(1/3) (1 + |(x, v)|)
//   / |(h^2 u, h u)| (max norms; Knoll & Keyes, "Jacobian-free
//   Newton-Krylov methods", J. Comput. Phys. 193 (2004), section 2.2, in
//   its central-difference form), and their h^2 df/dx v0 on the right side
//   likewise. That costs two evaluations of those forces per CG iteration;
//   forces with Jacobians cost nothing extra.
// * A is stored as 3 x 3 blocks in compressed rows, its pattern kept from
//   step to step while the forces report the same blocks, so a step
//   allocates nothing once the first has run.
#include "implicit_euler_solver.hpp"

#include <fmt/format.h>

#include <Eigen/LU>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#endif
#include <limits>
#include <pdyn/error.hpp>
#include <pdyn/system.hpp>

namespace pdyn::solvers {

namespace {

Eigen::Map<Eigen::VectorXd> flat(Matrix3X& m) { return {m.data(), m.size()}; }

}  // namespace

void ImplicitEuler::step(System& sys, double h) {
  const double t0 = sys.time();
  const Index n3 = 3 * sys.size();
  sys.set_time(t0 + h);
  x0_ = Eigen::Map<const Eigen::VectorXd>(sys.positions().data(), n3);
  v0_ = Eigen::Map<const Eigen::VectorXd>(sys.velocities().data(), n3);
  sys.compute_accelerations();  // fills sys.forces() with f0, contact forces included
  f0_ = Eigen::Map<const Eigen::VectorXd>(sys.forces().data(), n3);

  collect_jacobians(sys);
  if (!pattern_matches(sys)) build_pattern(sys);
  // The direct solve needs the whole matrix, so every force must have
  // Jacobians: auto falls back to CG without them, an explicit request is
  // refused. Auto also falls back when the factor would outgrow
  // direct_max_bytes (the symbolic analysis knows its size before any
  // numbers are computed).
  if (o_.linear_solver == LinearSolver::Direct && !fd_forces_.empty()) {
    std::string label;
    for (const auto& entry : sys.force_objects()) {
      if (entry.force.get() == fd_forces_.front()) label = entry.label;
    }
    sys.set_time(t0);
    throw Error(fmt::format(
        "implicit_euler: linear_solver: direct needs every force's Jacobian, but force '{}' "
        "has none (use linear_solver: auto or cg, which solve matrix-free)",
        label));
  }
  bool direct = false;
  if (o_.linear_solver != LinearSolver::Cg && fd_forces_.empty()) {
    if (!ldlt_analyzed_) {
      ldlt_.analyze(free_, compact_, row_start_, col_);
      ldlt_analyzed_ = true;
    }
    direct = o_.linear_solver == LinearSolver::Direct ||
             ldlt_.factor_bytes() <= static_cast<double>(o_.direct_max_bytes);
  }
  assemble(sys, h, !direct);

  // b = h (f0 + h df/dx v0): analytic blocks, then the matrix-free forces.
  kxv_.setZero(n3);
  for (const Block& k : sink_.dfdx) {
    kxv_.segment<3>(3 * k.i).noalias() += k.b * v0_.segment<3>(3 * k.j);
  }
  if (!fd_forces_.empty()) {
    uv_.setZero(n3);
    fd_jvp(sys, v0_, uv_, fd_out_);
    kxv_ += fd_out_;
  }
  b_ = h * (f0_ + h * kxv_);
  for (Index i = 0; i < sys.size(); ++i) {
    if (sys.fixed()[static_cast<std::size_t>(i)]) b_.segment<3>(3 * i).setZero();
  }

  try {
    if (direct) {
      solve_direct(sys);
    } else {
      solve(sys, h);
    }
    last_direct_ = direct;
  } catch (...) {
    sys.set_time(t0);
    throw;
  }
  auto v = Eigen::Map<Eigen::VectorXd>(sys.velocities().data(), n3);
  auto x = Eigen::Map<Eigen::VectorXd>(sys.positions().data(), n3);
  v = v0_ + dv_;
  x = x0_ + h * v;
  ++steps_;
}

// Asks every force for its Jacobians at (t0 + h, x0, v0); remembers those
// that have none.
void ImplicitEuler::collect_jacobians(const System& sys) {
  sink_.dfdx.clear();
  sink_.dfdv.clear();
  fd_forces_.clear();
  const ParticleView p = sys.view();
  for (const auto& entry : sys.force_objects()) {
    const std::size_t nx = sink_.dfdx.size(), nv = sink_.dfdv.size();
    if (!entry.force->add_jacobians(p, sink_)) {
      // A force that declines must not contribute half a Jacobian.
      sink_.dfdx.resize(nx);
      sink_.dfdv.resize(nv);
      fd_forces_.push_back(entry.force.get());
    }
  }
}

bool ImplicitEuler::pattern_matches(const System& sys) const {
  if (pattern_fixed_ != sys.fixed()) return false;
  if (pattern_key_.size() != sink_.dfdx.size() + sink_.dfdv.size()) return false;
  std::size_t k = 0;
  for (const auto* blocks : {&sink_.dfdx, &sink_.dfdv}) {
    for (const Block& b : *blocks) {
      if (pattern_key_[k].first != b.i || pattern_key_[k].second != b.j) return false;
      ++k;
    }
  }
  return true;
}

void ImplicitEuler::build_pattern(const System& sys) {
  const Index n = sys.size();
  const auto& fixed = sys.fixed();
  pattern_fixed_ = fixed;
  pattern_key_.clear();
  std::vector<std::pair<Index, Index>> entries;
  for (Index i = 0; i < n; ++i) {
    if (!fixed[static_cast<std::size_t>(i)]) entries.emplace_back(i, i);  // the mass
  }
  for (const auto* blocks : {&sink_.dfdx, &sink_.dfdv}) {
    for (const Block& b : *blocks) {
      pattern_key_.emplace_back(b.i, b.j);
      if (!fixed[static_cast<std::size_t>(b.i)] && !fixed[static_cast<std::size_t>(b.j)]) {
        entries.emplace_back(b.i, b.j);
      }
    }
  }
  std::sort(entries.begin(), entries.end());
  entries.erase(std::unique(entries.begin(), entries.end()), entries.end());
  row_start_.assign(static_cast<std::size_t>(n) + 1, 0);
  col_.resize(entries.size());
  for (std::size_t s = 0; s < entries.size(); ++s) {
    ++row_start_[static_cast<std::size_t>(entries[s].first) + 1];
    col_[s] = entries[s].second;
  }
  for (Index i = 0; i < n; ++i) row_start_[i + 1] += row_start_[i];
  auto slot = [&](Index i, Index j) -> std::ptrdiff_t {
    if (fixed[static_cast<std::size_t>(i)] || fixed[static_cast<std::size_t>(j)]) return -1;
    const auto begin = col_.begin() + row_start_[i], end = col_.begin() + row_start_[i + 1];
    return std::lower_bound(begin, end, j) - col_.begin();
  };
  diag_slot_.assign(static_cast<std::size_t>(n), -1);
  for (Index i = 0; i < n; ++i) diag_slot_[i] = slot(i, i);
  slot_x_.clear();
  slot_v_.clear();
  for (const Block& b : sink_.dfdx) slot_x_.push_back(slot(b.i, b.j));
  for (const Block& b : sink_.dfdv) slot_v_.push_back(slot(b.i, b.j));
  val_.resize(entries.size());
  precond_.resize(static_cast<std::size_t>(n));
  free_.clear();
  compact_.assign(static_cast<std::size_t>(n), -1);
  for (Index i = 0; i < n; ++i) {
    if (!fixed[static_cast<std::size_t>(i)]) {
      compact_[static_cast<std::size_t>(i)] = static_cast<Index>(free_.size());
      free_.push_back(i);
    }
  }
  ldlt_analyzed_ = false;  // analysed when a direct step first needs it
}

// Fills A = M - h df/dv - h^2 df/dx into the pattern and, for CG, inverts
// its diagonal blocks for the preconditioner.
void ImplicitEuler::assemble(const System& sys, double h, bool precondition) {
  const Index n = sys.size();
  for (auto& v : val_) v.setZero();
  for (Index i = 0; i < n; ++i) {
    if (diag_slot_[i] >= 0) val_[diag_slot_[i]].diagonal().setConstant(sys.masses()(i));
  }
  for (std::size_t k = 0; k < sink_.dfdx.size(); ++k) {
    if (slot_x_[k] >= 0) val_[slot_x_[k]] -= (h * h) * sink_.dfdx[k].b;
  }
  for (std::size_t k = 0; k < sink_.dfdv.size(); ++k) {
    if (slot_v_[k] >= 0) val_[slot_v_[k]] -= h * sink_.dfdv[k].b;
  }
  if (!precondition) return;
  for (Index i = 0; i < n; ++i) {
    // The diagonal block is M_i minus negative semidefinite blocks, so it is
    // symmetric positive definite and invertible.
    precond_[i] = diag_slot_[i] >= 0 ? Eigen::Matrix3d(val_[diag_slot_[i]].inverse())
                                     : Eigen::Matrix3d::Zero();
  }
}

// out = S A S u: the assembled blocks plus the matrix-free forces, filtered.
void ImplicitEuler::apply(const System& sys, double h, const Eigen::VectorXd& u,
                          Eigen::VectorXd& out) {
  const Index n = sys.size();
  out.resize(3 * n);
  for (Index i = 0; i < n; ++i) {
    // One accumulator per block column: three independent add chains
    // instead of one, which is what limits this loop (3x faster measured).
    Eigen::Vector3d s0 = Eigen::Vector3d::Zero(), s1 = s0, s2 = s0;
    for (Index s = row_start_[i]; s < row_start_[i + 1]; ++s) {
      const Eigen::Matrix3d& b = val_[s];
      const double* x = u.data() + 3 * col_[s];
      s0.noalias() += b.col(0) * x[0];
      s1.noalias() += b.col(1) * x[1];
      s2.noalias() += b.col(2) * x[2];
    }
    out.segment<3>(3 * i) = s0 + s1 + s2;
  }
  if (!fd_forces_.empty()) {
    ux_ = (h * h) * u;
    uv_ = h * u;
    fd_jvp(sys, ux_, uv_, fd_out_);
    for (Index i = 0; i < n; ++i) {
      if (diag_slot_[i] >= 0) out.segment<3>(3 * i) -= fd_out_.segment<3>(3 * i);
    }
  }
}

// out = J_x dx + J_v dv of the forces without Jacobians, by central
// differences of their add_forces() at (t0 + h, x0, v0).
void ImplicitEuler::fd_jvp(const System& sys, const Eigen::VectorXd& dx, const Eigen::VectorXd& dv,
                           Eigen::VectorXd& out) {
  const Index n = sys.size();
  const double dnorm = std::max(dx.lpNorm<Eigen::Infinity>(), dv.lpNorm<Eigen::Infinity>());
  out.setZero(3 * n);
  if (dnorm == 0.0) return;
  const double unorm = std::max(x0_.lpNorm<Eigen::Infinity>(), v0_.lpNorm<Eigen::Infinity>());
  const double e = std::cbrt(std::numeric_limits<double>::epsilon()) * (1.0 + unorm) / dnorm;
  const Eigen::Map<const Eigen::VectorXd> mass(sys.masses().data(), n);
  const std::span<const std::uint8_t> fixed(sys.fixed().data(), sys.fixed().size());
  auto eval = [&](double sign, Matrix3X& f) {
    xp_.resize(3, n);
    vp_.resize(3, n);
    f.setZero(3, n);
    flat(xp_) = x0_ + (sign * e) * dx;
    flat(vp_) = v0_ + (sign * e) * dv;
    const ParticleView p{sys.time(), Eigen::Map<const Matrix3X>(xp_.data(), 3, n),
                         Eigen::Map<const Matrix3X>(vp_.data(), 3, n), mass, fixed};
    for (Force* force : fd_forces_) force->add_forces(p, f);
  };
  eval(1.0, fp_);
  eval(-1.0, fm_);
  out = (flat(fp_) - flat(fm_)) / (2.0 * e);
}

void ImplicitEuler::precondition(const Eigen::VectorXd& r, Eigen::VectorXd& z) const {
  z.resize(r.size());
  for (std::size_t i = 0; i < precond_.size(); ++i) {
    const Index k = 3 * static_cast<Index>(i);
    z.segment<3>(k).noalias() = precond_[i] * r.segment<3>(k);
  }
}

// Preconditioned conjugate gradients on the free particles, from dv = 0,
// stopping as Baraff & Witkin's modified PCG does: when the residual in the
// preconditioner's norm, r^T P^-1 r, has fallen below cg_tolerance^2 times
// b^T P^-1 b. (That norm weighs each particle's residual by the inverse of
// its diagonal block, close to the A^-1 norm, i.e. to the error in dv
// measured in A's energy norm.)
void ImplicitEuler::solve(const System& sys, double h) {
  const Index n3 = b_.size();
  dv_.setZero(n3);
  last_iterations_ = 0;
  const double b_norm = b_.norm();
  if (b_norm == 0.0) return;
  if (!std::isfinite(b_norm)) {
    // The forces are already non-finite: let the state become so, for the
    // runner to report the blow-up, rather than fail inside CG.
    dv_ = b_;
    return;
  }
  r_ = b_;
  precondition(r_, z_);
  p_ = z_;
  double rz = r_.dot(z_);
  const double rz0 = rz;
  const double tol2 = o_.cg_tolerance * o_.cg_tolerance;
  for (std::int64_t it = 1; it <= o_.cg_max_iterations; ++it) {
    apply(sys, h, p_, q_);
    const double pq = p_.dot(q_);
    if (!(pq > 0.0)) {
      throw Error(fmt::format(
          "implicit_euler: the linear system is not positive definite at t = {:.17g} s (p.Ap = "
          "{:.3g} at CG iteration {}): a force's Jacobian is not symmetric negative "
          "semidefinite, or dt is too large for it",
          sys.time(), pq, it));
    }
    const double alpha = rz / pq;
    dv_ += alpha * p_;
    r_ -= alpha * q_;
    precondition(r_, z_);
    const double rz_new = r_.dot(z_);
    last_iterations_ = it;
    if (rz_new <= tol2 * rz0) {
      total_iterations_ += it;
      return;
    }
    p_ = z_ + (rz_new / rz) * p_;
    rz = rz_new;
  }
  const double residual = std::sqrt(rz / rz0);
  total_iterations_ += o_.cg_max_iterations;
  throw Error(fmt::format(
      "implicit_euler: conjugate gradients did not converge in {} iterations at t = {:.17g} s "
      "(relative residual {:.3g}, cg_tolerance {:.3g}); raise cg_max_iterations, loosen "
      "cg_tolerance or reduce dt",
      o_.cg_max_iterations, sys.time(), residual, o_.cg_tolerance));
}

// The direct solve: A = L D L^T on the free particles, then two triangular
// solves. The factor's pattern (ordering, elimination tree, L's columns) is
// analysed once per matrix pattern; each step only refactorises. A is
// symmetric positive definite for the same reason CG needs it to be, and
// a pivot block that is not is the same error.
void ImplicitEuler::solve_direct(const System& sys) {
  dv_.setZero(b_.size());
  last_iterations_ = 0;
  if (!b_.allFinite()) {
    dv_ = b_;  // as in solve(): let the runner see the blow-up
    return;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const Index bad = ldlt_.factorize(val_);
  factor_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (bad >= 0) {
    throw Error(fmt::format(
        "implicit_euler: the linear system is not positive definite at t = {:.17g} s (pivot "
        "block {} of the direct factorisation): a force's Jacobian is not symmetric negative "
        "semidefinite, or dt is too large for it",
        sys.time(), bad));
  }
  ldlt_.solve(b_, dv_);
}

namespace detail {

namespace {

using Block = Eigen::Matrix<double, 4, 3>;

// y[rows[p]] -= lx[p] * yi for p < count: nearly all of the factorisation's
// work. Eigen vectorises it with the packets the build allows (two doubles
// with the default SSE2); where the CPU has AVX2 the same products run four
// doubles at a time, in the same order (multiply, then add, no fused
// multiply-add), so both paths give the same bits. Measured on the stiff
// cloth: 20% (30 x 30) and 30% (100 x 100) less time per step.
void subtract_products_eigen(Block* y, const Index* rows, const Block* lx, Index count,
                             const Eigen::Matrix3d& yi) {
  for (Index p = 0; p < count; ++p) y[rows[p]].noalias() -= lx[p] * yi;
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
__attribute__((target("avx2"))) void subtract_products_avx2(Block* y, const Index* rows,
                                                            const Block* lx, Index count,
                                                            const Eigen::Matrix3d& yi) {
  __m256d b[3][3];
  for (int k = 0; k < 3; ++k) {
    for (int c = 0; c < 3; ++c) b[k][c] = _mm256_set1_pd(yi(k, c));
  }
  for (Index p = 0; p < count; ++p) {
    const double* l = lx[p].data();
    double* t = y[rows[p]].data();
    const __m256d l0 = _mm256_loadu_pd(l), l1 = _mm256_loadu_pd(l + 4), l2 = _mm256_loadu_pd(l + 8);
    for (int c = 0; c < 3; ++c) {
      const __m256d s =
          _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(l0, b[0][c]), _mm256_mul_pd(l1, b[1][c])),
                        _mm256_mul_pd(l2, b[2][c]));
      _mm256_storeu_pd(t + 4 * c, _mm256_sub_pd(_mm256_loadu_pd(t + 4 * c), s));
    }
  }
}

const bool kHaveAvx2 = __builtin_cpu_supports("avx2");
#endif

void subtract_products(Block* y, const Index* rows, const Block* lx, Index count,
                       const Eigen::Matrix3d& yi) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  if (kHaveAvx2) {
    subtract_products_avx2(y, rows, lx, count, yi);
    return;
  }
#endif
  subtract_products_eigen(y, rows, lx, count, yi);
}

}  // namespace

void BlockLdlt::analyze(const std::vector<Index>& particles, const std::vector<Index>& compact,
                        const std::vector<Index>& row_start, const std::vector<Index>& col) {
  const Index n = static_cast<Index>(particles.size());
  order_.clear();
  ucol_start_.assign(1, 0);
  lp_.assign(1, 0);
  li_.clear();
  lx_.clear();
  allocated_ = false;
  if (n == 0) return;  // every particle fixed: nothing to solve
  // A fill-reducing order of the block graph: one node per particle rather
  // than per coordinate, so the ordering works on a 9x smaller graph and
  // keeps each particle's three unknowns together. Eigen's AMDOrdering
  // returns P with P.indices()[step] = the node eliminated at that step.
  std::vector<Eigen::Triplet<double, int>> entries;
  for (Index r = 0; r < n; ++r) {
    const Index i = particles[static_cast<std::size_t>(r)];
    for (Index s = row_start[static_cast<std::size_t>(i)];
         s < row_start[static_cast<std::size_t>(i) + 1]; ++s) {
      entries.emplace_back(static_cast<int>(r),
                           static_cast<int>(compact[static_cast<std::size_t>(col[s])]), 1.0);
    }
  }
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> graph(n, n);
  graph.setFromTriplets(entries.begin(), entries.end());
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> perm;
  Eigen::AMDOrdering<int>()(graph, perm);
  std::vector<Index> step_of(static_cast<std::size_t>(n));
  order_.resize(static_cast<std::size_t>(n));
  for (Index k = 0; k < n; ++k) {
    const Index r = perm.indices()[k];
    step_of[static_cast<std::size_t>(r)] = k;
    order_[static_cast<std::size_t>(k)] = particles[static_cast<std::size_t>(r)];
  }

  // A's upper triangle in elimination order, by column: column k lists the
  // slots A(i, k) with step i <= step k.
  ucol_start_.assign(static_cast<std::size_t>(n) + 1, 0);
  auto each_upper = [&](auto&& visit) {
    for (Index k = 0; k < n; ++k) {
      const Index j = order_[static_cast<std::size_t>(k)];  // column k's particle
      // A is symmetric in pattern: row j's slots name the rows of column j.
      for (Index s = row_start[static_cast<std::size_t>(j)];
           s < row_start[static_cast<std::size_t>(j) + 1]; ++s) {
        const Index i =
            step_of[static_cast<std::size_t>(compact[static_cast<std::size_t>(col[s])])];
        if (i <= k) visit(k, i, col[s], j);
      }
    }
  };
  each_upper([&](Index k, Index, Index, Index) { ++ucol_start_[static_cast<std::size_t>(k) + 1]; });
  for (Index k = 0; k < n; ++k) ucol_start_[k + 1] += ucol_start_[k];
  urow_.resize(static_cast<std::size_t>(ucol_start_.back()));
  uslot_.resize(urow_.size());
  std::vector<Index> next(ucol_start_.begin(), ucol_start_.end() - 1);
  each_upper([&](Index k, Index i, Index pi, Index pj) {
    // The slot of A(pi, pj): row pi's entry at column pj.
    const auto begin = col.begin() + row_start[static_cast<std::size_t>(pi)];
    const auto end = col.begin() + row_start[static_cast<std::size_t>(pi) + 1];
    const Index p = next[static_cast<std::size_t>(k)]++;
    urow_[static_cast<std::size_t>(p)] = i;
    uslot_[static_cast<std::size_t>(p)] = std::lower_bound(begin, end, pj) - col.begin();
  });

  // Elimination tree and the number of blocks in each column of L (Davis's
  // ldl_symbolic): row k of L is the set of nodes reached from A's column k
  // by climbing the tree, each climb stopping at a node already seen.
  parent_.assign(static_cast<std::size_t>(n), -1);
  flag_.assign(static_cast<std::size_t>(n), -1);
  lnz_.assign(static_cast<std::size_t>(n), 0);
  for (Index k = 0; k < n; ++k) {
    flag_[k] = k;
    for (Index p = ucol_start_[k]; p < ucol_start_[k + 1]; ++p) {
      for (Index i = urow_[p]; flag_[i] != k; i = parent_[i]) {
        if (parent_[i] == -1) parent_[i] = k;
        ++lnz_[i];
        flag_[i] = k;
      }
    }
  }
  lp_.assign(static_cast<std::size_t>(n) + 1, 0);
  for (Index k = 0; k < n; ++k) lp_[k + 1] = lp_[k] + lnz_[k];
  // L's storage is allocated by the first factorize(), so that a caller can
  // look at factor_bytes() first.
}

double BlockLdlt::factor_bytes() const noexcept {
  return static_cast<double>(lp_.empty() ? 0 : lp_.back()) *
             static_cast<double>(sizeof(Block) + sizeof(Index)) +
         static_cast<double>(order_.size()) *
             static_cast<double>(sizeof(Eigen::Matrix3d) + sizeof(Block) + sizeof(Eigen::Vector4d));
}

// Row k visits each column i of its pattern and subtracts the products of
// the column's entries found so far, then forms L(k, i) and updates D_k: a
// column of c blocks costs c (c - 1) / 2 block products, and 2 per block.
double BlockLdlt::factor_flops() const noexcept {
  double products = 0.0;
  for (std::size_t i = 0; i + 1 < lp_.size(); ++i) {
    const double c = static_cast<double>(lp_[i + 1] - lp_[i]);
    products += 0.5 * c * (c - 1.0) + 2.0 * c;
  }
  return 54.0 * products;
}

// Davis's ldl_numeric by 3 x 3 blocks. Block row k: solve L_{<k} y = A(<k, k)
// for y_i = D_i L(k, i)^T over the nonzero pattern of row k only (found by
// climbing the elimination tree, in topological order), then
// L(k, i) = y_i^T D_i^-1 and D_k = A(k, k) - sum_i L(k, i) y_i.
Index BlockLdlt::factorize(const std::vector<Eigen::Matrix3d>& val) {
  const Index n = static_cast<Index>(order_.size());
  if (!allocated_) {  // the first factorisation since analyze()
    allocated_ = true;
    li_.resize(static_cast<std::size_t>(lp_.back()));
    lx_.resize(li_.size());
    dinv_.resize(static_cast<std::size_t>(n));
    y_.assign(static_cast<std::size_t>(n), Block::Zero());
    pattern_.resize(static_cast<std::size_t>(n));
    z_.resize(static_cast<std::size_t>(n));
  }
  for (Index k = 0; k < n; ++k) {
    Index top = n;
    flag_[k] = k;
    lnz_[k] = 0;
    for (Index p = ucol_start_[k]; p < ucol_start_[k + 1]; ++p) {
      Index i = urow_[p];
      y_[i].topRows<3>() += val[static_cast<std::size_t>(uslot_[p])];
      Index len = 0;
      for (; flag_[i] != k; i = parent_[i]) {
        pattern_[len++] = i;
        flag_[i] = k;
      }
      while (len > 0) pattern_[--top] = pattern_[--len];
    }
    Eigen::Matrix3d d = y_[k].topRows<3>();
    y_[k].setZero();
    for (; top < n; ++top) {
      const Index i = pattern_[top];
      const Eigen::Matrix3d yi = y_[i].topRows<3>();
      y_[i].setZero();
      const Index end = lp_[i] + lnz_[i];
      subtract_products(y_.data(), li_.data() + lp_[i], lx_.data() + lp_[i], end - lp_[i], yi);
      const Eigen::Matrix3d lki = yi.transpose() * dinv_[i];
      d.noalias() -= lki * yi;
      li_[end] = k;
      lx_[end].topRows<3>() = lki;
      lx_[end].row(3).setZero();
      ++lnz_[i];
    }
    // D_k is symmetric positive definite if A is: by Sylvester's criterion,
    // exactly when its leading minors are positive, and then its inverse by
    // cofactors (cheaper than a Cholesky factor and a solve, which took 5% of
    // the time on the 30 x 30 cloth).
    d = (0.5 * (d + d.transpose())).eval();
    const double m1 = d(0, 0), m2 = d(0, 0) * d(1, 1) - d(0, 1) * d(1, 0), m3 = d.determinant();
    if (!(m1 > 0.0 && m2 > 0.0 && m3 > 0.0)) return k;  // y_ is all zero again
    dinv_[k] = d.inverse();
  }
  return -1;
}

void BlockLdlt::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  const Index n = static_cast<Index>(order_.size());
  for (Index k = 0; k < n; ++k) z_[k] << b.segment<3>(3 * order_[k]), 0.0;
  for (Index i = 0; i < n; ++i) {  // L z = P b
    const Eigen::Vector3d zi = z_[i].head<3>();
    for (Index p = lp_[i]; p < lp_[i + 1]; ++p) z_[li_[p]].noalias() -= lx_[p] * zi;
  }
  for (Index i = 0; i < n; ++i) z_[i].head<3>() = (dinv_[i] * z_[i].head<3>()).eval();
  for (Index i = n - 1; i >= 0; --i) {  // L^T x = D^-1 z
    Eigen::Vector3d zi = z_[i].head<3>();
    for (Index p = lp_[i]; p < lp_[i + 1]; ++p) zi.noalias() -= lx_[p].transpose() * z_[li_[p]];
    z_[i].head<3>() = zi;
  }
  for (Index k = 0; k < n; ++k) x.segment<3>(3 * order_[k]) = z_[k].head<3>();
}

}  // namespace detail

}  // namespace pdyn::solvers
