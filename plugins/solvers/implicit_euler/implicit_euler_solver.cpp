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
// * When every force supplies Jacobians, A is factorised, A = L L^T, by a
//   supernodal Cholesky (supernodal_cholesky.hpp), by default. Its dense
//   panels put nearly all of the work in BLAS products: on the stiff cloth
//   it runs at 20 to 32 GFlop/s where the up-looking block LDL^T it
//   replaced ran at 6 to 13 (docs/solvers.md). Preconditioned CG needs
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
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <pdyn/error.hpp>
#include <pdyn/system.hpp>
#include <span>
#include <string>
#include <vector>

namespace pdyn::solvers {

namespace {

Eigen::Map<Eigen::VectorXd> flat(Matrix3X& m) { return {m.data(), m.size()}; }

}  // namespace

void ImplicitEuler::step(System& sys, double h) {
  const double t0 = sys.time();
  const Index n3 = 3 * sys.size();
  auto clock = std::chrono::steady_clock::now();
  auto lap = [&clock](double& part) {  // adds the time since the last lap to `part`
    const auto now = std::chrono::steady_clock::now();
    part += std::chrono::duration<double>(now - clock).count();
    clock = now;
  };
  sys.set_time(t0 + h);
  x0_ = Eigen::Map<const Eigen::VectorXd>(sys.positions().data(), n3);
  v0_ = Eigen::Map<const Eigen::VectorXd>(sys.velocities().data(), n3);
  sys.compute_accelerations();  // fills sys.forces() with f0, contact forces included
  f0_ = Eigen::Map<const Eigen::VectorXd>(sys.forces().data(), n3);
  lap(parts_.forces);

  collect_jacobians(sys, h);
  lap(parts_.jacobians);
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
    if (!cholesky_analyzed_) {
      cholesky_.analyze(free_, compact_, row_start_, col_);
      cholesky_analyzed_ = true;
    }
    direct = o_.linear_solver == LinearSolver::Direct ||
             cholesky_.factor_bytes() <= static_cast<double>(o_.direct_max_bytes);
  }
  lap(parts_.analysis);
  if (!direct) invert_diagonal_blocks(sys);

  // b = h (f0 + h df/dx v0): the analytic blocks' part is in kxv_ already,
  // then the matrix-free forces'.
  if (!fd_forces_.empty()) {
    uv_.setZero(n3);
    fd_jvp(sys, v0_, uv_, fd_out_);
    kxv_ += fd_out_;
  }
  b_ = h * (f0_ + h * kxv_);
  for (Index i = 0; i < sys.size(); ++i) {
    if (sys.fixed()[static_cast<std::size_t>(i)]) b_.segment<3>(3 * i).setZero();
  }

  const double factorised = parts_.factorisation;
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
  lap(parts_.solve);
  parts_.solve -= parts_.factorisation - factorised;  // counted as the factorisation's
}

namespace {

// A -= scale[kind] * block at `slot` (-1: a fixed particle's, left out), and
// for df/dx blocks kxv_i += block v0_j: the one place a reported block
// enters the system, whether it was recorded first or not, so both ways
// round alike.
inline void enter_block(Eigen::Matrix3d* val, std::ptrdiff_t slot, const double scale[2],
                        double* kxv, const double* v0, Index i, Index j, int kind,
                        const Eigen::Matrix3d& block) {
  if (slot >= 0) val[slot] -= scale[kind] * block;
  if (kind == 0) {
    Eigen::Map<Eigen::Vector3d>(kxv + 3 * i).noalias() +=
        block * Eigen::Map<const Eigen::Vector3d>(v0 + 3 * j);
  }
}

}  // namespace

// Recording is rare (a first step, a new pattern): kept out of line, so
// that the entering path, taken once per block every step, stays small.
[[gnu::noinline]] void ImplicitEuler::Sink::record(Index i, Index j, int kind,
                                                   const Eigen::Matrix3d& block) {
  blocks.push_back({i, j, kind, block});
}

void ImplicitEuler::Sink::add(Index i, Index j, int kind, const Eigen::Matrix3d& block) {
  if (!assembling) [[unlikely]] {
    record(i, j, kind, block);
    return;
  }
  if (missed) return;
  if (cursor == key_size || !(key[cursor] == Key{i, j, kind})) {
    missed = true;  // another pattern than the last step's: recorded again
    return;
  }
  enter_block(val, slot[cursor], scale, kxv, v0, i, j, kind, block);
  ++cursor;
}

// Asks every force for its Jacobians at (t0 + h, x0, v0) and enters them
// into A = M - h df/dv - h^2 df/dx and kxv_ = df/dx v0; remembers the forces
// that have none. While the forces report the same blocks in the same order
// as at the last step (nearly always), each block goes straight into its
// slot; otherwise the blocks are recorded, the pattern is rebuilt from them,
// and they are entered in the order they came, as they would have been.
void ImplicitEuler::collect_jacobians(const System& sys, double h) {
  const double scale[2] = {h * h, h};
  if (have_pattern_ && pattern_fixed_ == sys.fixed()) {
    begin_assembly(sys);
    sink_.assembling = true;
    sink_.missed = false;
    sink_.cursor = 0;
    sink_.key = pattern_key_.data();
    sink_.key_size = pattern_key_.size();
    sink_.slot = slot_.data();
    sink_.val = val_.data();
    sink_.kxv = kxv_.data();
    sink_.v0 = v0_.data();
    sink_.scale[0] = scale[0];
    sink_.scale[1] = scale[1];
    ask_forces(sys);
    if (!sink_.missed && sink_.cursor == pattern_key_.size()) return;
  }
  sink_.assembling = false;
  sink_.blocks.clear();
  ask_forces(sys);
  build_pattern(sys);
  begin_assembly(sys);
  for (std::size_t k = 0; k < sink_.blocks.size(); ++k) {
    const Block& b = sink_.blocks[k];
    enter_block(val_.data(), slot_[k], scale, kxv_.data(), v0_.data(), b.i, b.j, b.kind, b.b);
  }
}

void ImplicitEuler::ask_forces(const System& sys) {
  fd_forces_.clear();
  const ParticleView p = sys.view();
  for (const auto& entry : sys.force_objects()) {
    const std::size_t before = sink_.assembling ? sink_.cursor : sink_.blocks.size();
    if (!entry.force->add_jacobians(p, sink_)) {
      // A force that declines must not contribute half a Jacobian.
      if (sink_.assembling) {
        if (sink_.cursor != before) sink_.missed = true;
      } else {
        sink_.blocks.resize(before);
      }
      fd_forces_.push_back(entry.force.get());
    }
  }
}

// A = M on the pattern (the forces' blocks are entered next), kxv_ = 0.
void ImplicitEuler::begin_assembly(const System& sys) {
  const Index n = sys.size();
  for (auto& v : val_) v.setZero();
  for (Index i = 0; i < n; ++i) {
    if (diag_slot_[i] >= 0) val_[diag_slot_[i]].diagonal().setConstant(sys.masses()(i));
  }
  kxv_.setZero(3 * n);
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
  for (const Block& b : sink_.blocks) {
    pattern_key_.push_back({b.i, b.j, b.kind});
    if (!fixed[static_cast<std::size_t>(b.i)] && !fixed[static_cast<std::size_t>(b.j)]) {
      entries.emplace_back(b.i, b.j);
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
  slot_.clear();
  for (const Block& b : sink_.blocks) slot_.push_back(slot(b.i, b.j));
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
  have_pattern_ = true;
  cholesky_analyzed_ = false;  // analysed when a direct step first needs it
}

// CG's preconditioner: the inverses of A's diagonal blocks.
void ImplicitEuler::invert_diagonal_blocks(const System& sys) {
  for (Index i = 0; i < sys.size(); ++i) {
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

// The direct solve: A = L L^T on the free particles, then two triangular
// solves. The factor's pattern (ordering, elimination tree, L's columns) is
// analysed once per matrix pattern; each step only refactorises. A is
// symmetric positive definite for the same reason CG needs it to be, and
// a pivot that is not positive is the same error.
void ImplicitEuler::solve_direct(const System& sys) {
  dv_.setZero(b_.size());
  last_iterations_ = 0;
  if (!b_.allFinite()) {
    dv_ = b_;  // as in solve(): let the runner see the blow-up
    return;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const Index bad = cholesky_.factorize(val_);
  parts_.factorisation +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (bad >= 0) {
    throw Error(fmt::format(
        "implicit_euler: the linear system is not positive definite at t = {:.17g} s (pivot "
        "block {} of the direct factorisation): a force's Jacobian is not symmetric negative "
        "semidefinite, or dt is too large for it",
        sys.time(), bad));
  }
  cholesky_.solve(b_, dv_);
}

}  // namespace pdyn::solvers
