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
//   supernodal Cholesky (SupernodalCholesky below), by default. Its dense
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

#include <dlfcn.h>
#include <fmt/format.h>

#include <Eigen/LU>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <pdyn/error.hpp>
#include <pdyn/system.hpp>
#include <string>
#include <type_traits>
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

namespace detail {

namespace {

// The dense kernels come from a BLAS and LAPACK loaded the first time a
// matrix is factorised, not linked: the registry loads every plugin to read
// its descriptor, so a linked OpenBLAS (and its start-up: 5 to 9 ms of
// dlopen, measured) was paid by every pdyn process, implicit or not, as
// h5md's HDF5 was (plugins/writers/h5md/h5md.cpp). The routines are the
// reference interface (Fortran calling convention, the hidden lengths of
// the character arguments last), so any BLAS serves; Debian's OpenBLAS
// (BSD-3-Clause) is tried first, for its kernels chosen for the CPU.
struct Blas {
  void (*dgemm)(const char* transa, const char* transb, const int* m, const int* n, const int* k,
                const double* alpha, const double* a, const int* lda, const double* b,
                const int* ldb, const double* beta, double* c, const int* ldc, std::size_t,
                std::size_t) = nullptr;
  void (*dsyrk)(const char* uplo, const char* trans, const int* n, const int* k,
                const double* alpha, const double* a, const int* lda, const double* beta, double* c,
                const int* ldc, std::size_t, std::size_t) = nullptr;
  void (*dtrsm)(const char* side, const char* uplo, const char* transa, const char* diag,
                const int* m, const int* n, const double* alpha, const double* a, const int* lda,
                double* b, const int* ldb, std::size_t, std::size_t, std::size_t,
                std::size_t) = nullptr;
  void (*dtrsv)(const char* uplo, const char* trans, const char* diag, const int* n,
                const double* a, const int* lda, double* x, const int* incx, std::size_t,
                std::size_t, std::size_t) = nullptr;
  void (*dgemv)(const char* trans, const int* m, const int* n, const double* alpha, const double* a,
                const int* lda, const double* x, const int* incx, const double* beta, double* y,
                const int* incy, std::size_t) = nullptr;
  void (*dpotrf)(const char* uplo, const int* n, double* a, const int* lda, int* info,
                 std::size_t) = nullptr;
};

// PDYN_BLAS, when set, names the library (a path or a soname) and nothing
// else is tried. Loaded for good (RTLD_NODELETE): a threaded OpenBLAS keeps
// a thread pool that must not outlive its code.
Blas load_blas() {
  const char* chosen = std::getenv("PDYN_BLAS");
  const std::vector<std::string> names =
      chosen != nullptr && *chosen != '\0'
          ? std::vector<std::string>{chosen}
          : std::vector<std::string>{"libopenblas.so.0", "liblapack.so.3"};
  std::string tried;
  for (const std::string& name : names) {
    void* handle = dlopen(name.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    if (handle == nullptr) {
      const char* why = dlerror();
      tried += (tried.empty() ? "" : "; ") + std::string(why != nullptr ? why : name);
      continue;
    }
    Blas b;
    std::string missing;
    auto find = [&](auto& fn, const char* symbol) {
      fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(dlsym(handle, symbol));
      if (fn == nullptr) missing += (missing.empty() ? "" : ", ") + std::string(symbol);
    };
    find(b.dgemm, "dgemm_");
    find(b.dsyrk, "dsyrk_");
    find(b.dtrsm, "dtrsm_");
    find(b.dtrsv, "dtrsv_");
    find(b.dgemv, "dgemv_");
    find(b.dpotrf, "dpotrf_");
    if (!missing.empty()) {
      tried += (tried.empty() ? "" : "; ") + name + " lacks " + missing;
      continue;
    }
    // OpenBLAS's own: its threaded builds would otherwise start a thread
    // pool that spins beside the runner's OpenMP threads.
    if (auto threads = reinterpret_cast<void (*)(int)>(dlsym(handle, "openblas_set_num_threads"))) {
      threads(1);
    }
    return b;
  }
  throw Error(fmt::format(
      "implicit_euler: cannot load a BLAS and LAPACK for its direct solve: {} (expected "
      "Debian's libopenblas0 installed, or PDYN_BLAS naming a library with dgemm_, dsyrk_, "
      "dtrsm_, dtrsv_, dgemv_ and dpotrf_; linear_solver: cg needs none)",
      tried));
}

// A failed load throws and is tried again at the next factorisation.
const Blas& blas() {
  static const Blas b = load_blas();
  return b;
}

// The elimination tree of the pattern whose upper triangle, by column in
// elimination order, is `ucol_start` / `urow`, and the number of blocks
// below the diagonal in each column of L (Davis's ldl_symbolic: row k of L
// is the set of nodes reached from A's column k by climbing the tree, each
// climb stopping at a node already seen).
void elimination_tree(const std::vector<Index>& ucol_start, const std::vector<Index>& urow,
                      std::vector<Index>& parent, std::vector<Index>& count) {
  const Index n = static_cast<Index>(ucol_start.size()) - 1;
  std::vector<Index> flag(static_cast<std::size_t>(n), -1);
  parent.assign(static_cast<std::size_t>(n), -1);
  count.assign(static_cast<std::size_t>(n), 0);
  for (Index k = 0; k < n; ++k) {
    flag[k] = k;
    for (Index p = ucol_start[k]; p < ucol_start[k + 1]; ++p) {
      for (Index i = urow[p]; flag[i] != k; i = parent[i]) {
        if (parent[i] == -1) parent[i] = k;
        ++count[i];
        flag[i] = k;
      }
    }
  }
}

// The nodes of a forest given by `parent` (-1: a root) in postorder: each
// node after its children, each subtree contiguous. Children in increasing
// order, iteratively (a chain of a million particles is a million deep).
std::vector<Index> postorder(const std::vector<Index>& parent) {
  const Index n = static_cast<Index>(parent.size());
  std::vector<Index> first_child(static_cast<std::size_t>(n), -1),
      sibling(static_cast<std::size_t>(n), -1), post, stack;
  for (Index k = n - 1; k >= 0; --k) {
    if (parent[k] >= 0) {
      sibling[k] = first_child[parent[k]];
      first_child[parent[k]] = k;
    }
  }
  post.reserve(static_cast<std::size_t>(n));
  for (Index root = 0; root < n; ++root) {
    if (parent[root] != -1) continue;
    stack.push_back(root);
    while (!stack.empty()) {
      const Index k = stack.back();
      if (first_child[k] >= 0) {  // descend, detaching the child visited
        const Index c = first_child[k];
        first_child[k] = sibling[c];
        stack.push_back(c);
      } else {
        post.push_back(k);
        stack.pop_back();
      }
    }
  }
  return post;
}

// The first column of each supernode, then n, for the postordered
// elimination tree `parent` and L's column counts `count`. Fundamental
// supernodes first: column j joins column j - 1's supernode when j is its
// parent and their patterns are nested (one block fewer). Then relaxed: a
// supernode is merged with the next one when that holds its last column's
// parent and the explicit zeros the merge adds are few (CHOLMOD's rule:
// always up to 4 columns, then at most 80%, 10%, 5% zeros up to 16, 48 and
// more columns; here in block columns). Small supernodes cost a call each;
// dense updates of a few zeros cost less.
std::vector<Index> relaxed_supernodes(const std::vector<Index>& parent,
                                      const std::vector<Index>& count) {
  const Index n = static_cast<Index>(parent.size());
  std::vector<Index> fundamental{0};
  for (Index j = 1; j < n; ++j) {
    if (!(parent[j - 1] == j && count[j - 1] == count[j] + 1)) fundamental.push_back(j);
  }
  fundamental.push_back(n);
  std::vector<Index> merged{0};
  Index below = count[fundamental[1] - 1];  // rows below the current group
  double zeros = 0.0;                       // explicit zero blocks in its panel
  const Index ns = static_cast<Index>(fundamental.size()) - 1;
  auto group_blocks = [](double ncols, double nbelow) {
    return ncols * (ncols + 1.0) / 2.0 + ncols * nbelow;
  };
  for (Index s = 1; s < ns; ++s) {
    const Index gf = merged.back(), gl = fundamental[s] - 1;  // the group so far
    const Index f = fundamental[s], l = fundamental[s + 1] - 1;
    const Index nbelow = count[l];
    const double gcols = static_cast<double>(gl - gf + 1), cols = static_cast<double>(l - f + 1);
    const double new_zeros =
        zeros + gcols * (cols + static_cast<double>(nbelow) - static_cast<double>(below));
    const double new_size = group_blocks(gcols + cols, static_cast<double>(nbelow));
    const double total = gcols + cols, fraction = new_zeros / new_size;
    const bool merge = parent[gl] >= f && parent[gl] <= l &&
                       (total <= 4 || (total <= 16 && fraction < 0.8) ||
                        (total <= 48 && fraction < 0.1) || fraction < 0.05);
    if (merge) {
      zeros = new_zeros;
    } else {
      merged.push_back(f);
      zeros = 0.0;
    }
    below = nbelow;
  }
  merged.push_back(n);
  return merged;
}

}  // namespace

void SupernodalCholesky::analyze(const std::vector<Index>& particles,
                                 const std::vector<Index>& compact,
                                 const std::vector<Index>& row_start,
                                 const std::vector<Index>& col) {
  const Index n = static_cast<Index>(particles.size());
  order_.clear();
  acol_start_.assign(1, 0);
  super_.clear();
  row_start_.assign(1, 0);
  rows_.clear();
  panel_.assign(1, 0);
  lx_.clear();
  blocks_ = 0;
  flops_ = 0.0;
  work_size_ = 0;
  allocated_ = false;
  if (n == 0) return;                             // every particle fixed: nothing to solve
  auto neighbours = [&](Index r, auto&& visit) {  // compact indices of block row r's columns
    const Index i = particles[static_cast<std::size_t>(r)];
    for (Index s = row_start[static_cast<std::size_t>(i)];
         s < row_start[static_cast<std::size_t>(i) + 1]; ++s) {
      visit(compact[static_cast<std::size_t>(col[s])], s);
    }
  };
  // A fill-reducing order of the block graph: one node per particle rather
  // than per coordinate, so the ordering works on a 9x smaller graph and
  // keeps each particle's three unknowns together. Eigen's AMDOrdering
  // returns P with P.indices()[step] = the node eliminated at that step.
  std::vector<Eigen::Triplet<double, int>> entries;
  for (Index r = 0; r < n; ++r) {
    neighbours(r, [&](Index c, Index) {
      entries.emplace_back(static_cast<int>(r), static_cast<int>(c), 1.0);
    });
  }
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> graph(n, n);
  graph.setFromTriplets(entries.begin(), entries.end());
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> perm;
  Eigen::AMDOrdering<int>()(graph, perm);
  std::vector<Index> node(static_cast<std::size_t>(n)), step_of(static_cast<std::size_t>(n));
  for (Index k = 0; k < n; ++k) node[k] = perm.indices()[k];

  // The elimination tree of an order, from A's upper triangle by column.
  std::vector<Index> ucol_start, urow, parent, count;
  auto symbolic = [&] {
    for (Index k = 0; k < n; ++k) step_of[node[k]] = k;
    ucol_start.assign(static_cast<std::size_t>(n) + 1, 0);
    urow.clear();
    for (Index k = 0; k < n; ++k) {
      neighbours(node[k], [&](Index c, Index) {
        if (step_of[c] <= k) urow.push_back(step_of[c]);
      });
      ucol_start[k + 1] = static_cast<Index>(urow.size());
    }
    elimination_tree(ucol_start, urow, parent, count);
  };
  symbolic();
  // Postorder the tree (children before parents, each subtree contiguous):
  // the same fill, and a chain of columns with nested patterns then sits in
  // consecutive columns, which is what a supernode needs.
  {
    const std::vector<Index> post = postorder(parent);
    std::vector<Index> reordered(static_cast<std::size_t>(n));
    for (Index k = 0; k < n; ++k) reordered[k] = node[post[k]];
    node.swap(reordered);
  }
  symbolic();
  order_.resize(static_cast<std::size_t>(n));
  for (Index k = 0; k < n; ++k) order_[k] = particles[static_cast<std::size_t>(node[k])];
  for (Index k = 0; k < n; ++k) {
    const double c = static_cast<double>(count[k]);
    blocks_ += static_cast<std::size_t>(count[k]);
    flops_ += 54.0 * (0.5 * c * (c - 1.0) + 2.0 * c);
  }

  // A's lower triangle in elimination order, by column: the slot of
  // A(order_[i], order_[j]) is row order_[i]'s entry at column order_[j].
  acol_start_.assign(static_cast<std::size_t>(n) + 1, 0);
  arow_.clear();
  aslot_.clear();
  for (Index j = 0; j < n; ++j) {
    const Index pj = order_[j];
    neighbours(node[j], [&](Index c, Index) {
      const Index i = step_of[c];
      if (i < j) return;
      const Index pi = order_[i];
      const auto begin = col.begin() + row_start[static_cast<std::size_t>(pi)];
      const auto end = col.begin() + row_start[static_cast<std::size_t>(pi) + 1];
      arow_.push_back(i);
      aslot_.push_back(static_cast<Index>(std::lower_bound(begin, end, pj) - col.begin()));
    });
    acol_start_[j + 1] = static_cast<Index>(arow_.size());
  }

  super_ = relaxed_supernodes(parent, count);
  const Index ns = static_cast<Index>(super_.size()) - 1;
  super_of_.resize(static_cast<std::size_t>(n));
  for (Index s = 0; s < ns; ++s) {
    for (Index j = super_[s]; j < super_[s + 1]; ++j) super_of_[j] = s;
  }

  // Each supernode's rows: its columns, then below them the union of A's
  // entries in its columns and of its child supernodes' rows.
  std::vector<Index> mark(static_cast<std::size_t>(n), -1),
      child_head(static_cast<std::size_t>(ns), -1), child_next(static_cast<std::size_t>(ns), -1);
  row_start_.assign(1, 0);
  panel_.assign(1, 0);
  for (Index s = 0; s < ns; ++s) {
    const Index f = super_[s], l = super_[s + 1] - 1;
    for (Index j = f; j <= l; ++j) {
      rows_.push_back(j);
      mark[j] = s;
    }
    const std::size_t below = rows_.size();
    auto add = [&](Index i) {
      if (i > l && mark[i] != s) {
        mark[i] = s;
        rows_.push_back(i);
      }
    };
    for (Index j = f; j <= l; ++j) {
      for (Index p = acol_start_[j]; p < acol_start_[j + 1]; ++p) add(arow_[p]);
    }
    for (Index c = child_head[s]; c >= 0; c = child_next[c]) {
      for (Index p = row_start_[c]; p < row_start_[c + 1]; ++p) add(rows_[p]);
    }
    std::sort(rows_.begin() + static_cast<std::ptrdiff_t>(below), rows_.end());
    row_start_.push_back(static_cast<Index>(rows_.size()));
    const auto nr = static_cast<std::size_t>(row_start_[s + 1] - row_start_[s]);
    panel_.push_back(panel_.back() + 9 * nr * static_cast<std::size_t>(l - f + 1));
    if (parent[l] >= 0) {
      const Index t = super_of_[parent[l]];
      child_next[s] = child_head[t];
      child_head[t] = s;
    }
  }
  // The largest update a supernode makes to one ancestor: its rows from the
  // first in that ancestor down, times those in the ancestor.
  for (Index d = 0; d < ns; ++d) {
    const Index r0 = row_start_[d], nr = row_start_[d + 1] - r0;
    for (Index p = super_[d + 1] - super_[d]; p < nr;) {
      const Index t = super_of_[rows_[r0 + p]];
      Index q = p;
      while (q < nr && super_of_[rows_[r0 + q]] == t) ++q;
      work_size_ = std::max(work_size_, static_cast<std::size_t>(9 * (nr - p) * (q - p)));
      p = q;
    }
  }
  // The panels are allocated by the first factorize(), so that a caller can
  // look at factor_bytes() first.
}

double SupernodalCholesky::factor_bytes() const noexcept {
  if (panel_.empty()) return 0.0;  // not analysed (a CG-only solver never is)
  return static_cast<double>(panel_.back() + work_size_) * sizeof(double) +
         static_cast<double>(order_.size()) * (6.0 * sizeof(double) + 2.0 * sizeof(Index)) +
         static_cast<double>(super_.size()) * 3.0 * sizeof(Index);
}

// Left-looking, one supernode s at a time: gather A's columns of s into its
// dense panel, subtract the update L_d L_d(rows in s)^T of every descendant
// d whose pattern reaches s (one dgemm each, then a scatter by rows), factor
// the diagonal block (dpotrf) and divide the rows below by its transpose
// (dtrsm). Each descendant waits in the list of the next supernode its rows
// reach, so finding them costs nothing.
Index SupernodalCholesky::factorize(const std::vector<Eigen::Matrix3d>& val) {
  const Index n = static_cast<Index>(order_.size());
  if (n == 0) return -1;  // every particle fixed
  const Index ns = static_cast<Index>(super_.size()) - 1;
  if (!allocated_) {  // the first factorisation since analyze()
    blas();           // throws before anything changes if there is no BLAS
    allocated_ = true;
    lx_.resize(panel_.back());
    work_.resize(work_size_);
    head_.resize(static_cast<std::size_t>(ns));
    next_.resize(static_cast<std::size_t>(ns));
    cursor_.resize(static_cast<std::size_t>(ns));
    local_.resize(static_cast<std::size_t>(n));
    z_.resize(3 * static_cast<std::size_t>(n));
    Index widest = 0;
    for (Index s = 0; s < ns; ++s) widest = std::max(widest, row_start_[s + 1] - row_start_[s]);
    t_.resize(3 * static_cast<std::size_t>(widest));
  }
  std::fill(head_.begin(), head_.end(), -1);
  const Blas& lapack = blas();
  const double one = 1.0;
  for (Index s = 0; s < ns; ++s) {
    const Panel p = panel(s);
    gather(p, val);
    for (Index d = head_[s]; d >= 0;) {
      const Index after = next_[d];  // update() links d into the next list
      update(d, p);
      d = after;
    }
    int info = 0;
    lapack.dpotrf("L", &p.width, p.x, &p.ld, &info, 1);
    if (info != 0) return p.first + (info - 1) / 3;
    if (p.below > 0) {
      lapack.dtrsm("R", "L", "T", "N", &p.below, &p.width, &one, p.x, &p.ld, p.x + p.width, &p.ld,
                   1, 1, 1, 1);
      link(s, p.cols);
    }
  }
  return -1;
}

// A's columns of supernode p into its panel, zero elsewhere; local_ maps
// the panel's block rows to their places.
void SupernodalCholesky::gather(const Panel& p, const std::vector<Eigen::Matrix3d>& val) {
  for (Index r = 0; r < p.nrows; ++r) local_[p.rows[r]] = r;
  std::fill(p.x, p.x + 9 * p.nrows * p.cols, 0.0);
  for (Index c = 0; c < p.cols; ++c) {
    for (Index q = acol_start_[p.first + c]; q < acol_start_[p.first + c + 1]; ++q) {
      const Eigen::Matrix3d& a = val[static_cast<std::size_t>(aslot_[q])];
      double* dst = p.x + 3 * c * p.ld + 3 * local_[arow_[q]];
      for (int cc = 0; cc < 3; ++cc) {
        for (int rr = 0; rr < 3; ++rr) dst[cc * p.ld + rr] = a(rr, cc);
      }
    }
  }
}

// Supernode d's update of supernode p: with d's rows from its cursor on,
// L_d(rows, :) L_d(rows in p, :)^T, subtracted from p's panel at the rows
// local_ gives; then d waits for the supernode its next row falls in.
void SupernodalCholesky::update(Index d, const Panel& p) {
  const Panel dp = panel(d);
  const Index p1 = cursor_[d];
  Index p2 = p1;
  while (p2 < dp.nrows && dp.rows[p2] < p.first + p.cols) ++p2;
  const int m = static_cast<int>(3 * (dp.nrows - p1)), k = static_cast<int>(3 * (p2 - p1));
  const double* l1 = dp.x + 3 * p1;
  const double one = 1.0, zero = 0.0;
  const Blas& lapack = blas();
  // W = L_d(p1:, :) L_d(p1:p2, :)^T: the lower triangle of its top square
  // by dsyrk, the rows below by dgemm.
  lapack.dsyrk("L", "N", &k, &dp.width, &one, l1, &dp.ld, &zero, work_.data(), &m, 1, 1);
  if (m > k) {
    const int mb = m - k;
    lapack.dgemm("N", "T", &mb, &k, &dp.width, &one, l1 + k, &dp.ld, l1, &dp.ld, &zero,
                 work_.data() + k, &m, 1, 1);
  }
  for (Index c = 0; c < p2 - p1; ++c) {
    double* dst_col = p.x + 3 * (dp.rows[p1 + c] - p.first) * p.ld;
    const double* src_col = work_.data() + 3 * c * m;
    for (int cc = 0; cc < 3; ++cc) {
      double* dst = dst_col + cc * p.ld;
      const double* src = src_col + cc * m;
      for (Index r = c; r < dp.nrows - p1; ++r) {
        double* t = dst + 3 * local_[dp.rows[p1 + r]];
        const double* w = src + 3 * r;
        t[0] -= w[0];
        t[1] -= w[1];
        t[2] -= w[2];
      }
    }
  }
  if (p2 < dp.nrows) link(d, p2);
}

// Supernode d, its rows before `row` used, waits in the list of the
// supernode its row `row` falls in.
void SupernodalCholesky::link(Index d, Index row) {
  cursor_[d] = row;
  const Index t = super_of_[rows_[row_start_[d] + row]];
  next_[d] = head_[t];
  head_[t] = d;
}

SupernodalCholesky::Panel SupernodalCholesky::panel(Index s) {
  Panel p;
  p.first = super_[s];
  p.cols = super_[s + 1] - p.first;
  p.rows = rows_.data() + row_start_[s];
  p.nrows = row_start_[s + 1] - row_start_[s];
  p.ld = static_cast<int>(3 * p.nrows);
  p.width = static_cast<int>(3 * p.cols);
  p.below = p.ld - p.width;
  p.x = lx_.data() + panel_[s];
  return p;
}

// L y = P b by supernodes (a dense triangular solve, then the rows below by
// one product, scattered), then L^T P x = y in reverse.
void SupernodalCholesky::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  const Index n = static_cast<Index>(order_.size());
  if (n == 0) return;
  const Index ns = static_cast<Index>(super_.size()) - 1;
  for (Index k = 0; k < n; ++k) {
    for (int c = 0; c < 3; ++c) z_[3 * k + c] = b[3 * order_[k] + c];
  }
  const Blas& lapack = blas();
  const double one = 1.0, minus = -1.0, zero = 0.0;
  const int inc = 1;
  for (Index s = 0; s < ns; ++s) {
    const Panel p = panel(s);
    double* zs = z_.data() + 3 * p.first;
    lapack.dtrsv("L", "N", "N", &p.width, p.x, &p.ld, zs, &inc, 1, 1, 1);
    if (p.below == 0) continue;
    lapack.dgemv("N", &p.below, &p.width, &one, p.x + p.width, &p.ld, zs, &inc, &zero, t_.data(),
                 &inc, 1);
    for (Index r = p.cols; r < p.nrows; ++r) {
      for (int c = 0; c < 3; ++c) z_[3 * p.rows[r] + c] -= t_[3 * (r - p.cols) + c];
    }
  }
  for (Index s = ns - 1; s >= 0; --s) {
    const Panel p = panel(s);
    double* zs = z_.data() + 3 * p.first;
    if (p.below > 0) {
      for (Index r = p.cols; r < p.nrows; ++r) {
        for (int c = 0; c < 3; ++c) t_[3 * (r - p.cols) + c] = z_[3 * p.rows[r] + c];
      }
      lapack.dgemv("T", &p.below, &p.width, &minus, p.x + p.width, &p.ld, t_.data(), &inc, &one, zs,
                   &inc, 1);
    }
    lapack.dtrsv("L", "T", "N", &p.width, p.x, &p.ld, zs, &inc, 1, 1, 1);
  }
  for (Index k = 0; k < n; ++k) {
    for (int c = 0; c < 3; ++c) x[3 * order_[k] + c] = z_[3 * k + c];
  }
}

}  // namespace detail

}  // namespace pdyn::solvers
