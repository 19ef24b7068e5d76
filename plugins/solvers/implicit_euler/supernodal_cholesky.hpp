// implicit_euler's direct solve: a hand-written sparse supernodal Cholesky
// factorisation of the step's matrix A = M - h df/dv - h^2 df/dx, which is
// symmetric positive definite and made of 3 x 3 blocks (one block row and
// column per free particle). Also built into bench/ (stiff_cloth.cpp times
// it beside Eigen's SimplicialLLT on the same matrices) and tested by
// itself (tests/plugins/solvers/supernodal_cholesky_test.cpp). Its dense
// kernels are BLAS and LAPACK routines loaded at run time (blas.hpp).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <pdyn/types.hpp>
#include <vector>

namespace pdyn::solvers::detail {

/// Sparse Cholesky factorisation A = L L^T of a symmetric positive definite
/// matrix of 3 x 3 blocks, supernodal and left-looking (Ng & Peyton, "Block
/// sparse Cholesky algorithms on advanced uniprocessor computers", SIAM J.
/// Sci. Comput. 14 (1993); the linked lists of descendants as in CHOLMOD,
/// Chen, Davis, Hager & Rajamanickam, ACM TOMS 35 (2008)), after an
/// approximate minimum degree ordering of the block graph (Eigen's AMD).
/// Block columns of L with nested patterns are grouped into supernodes and
/// stored as dense column-major panels, so that nearly all of the work is
/// dense matrix products (BLAS dgemm / dsyrk), a dense Cholesky (LAPACK
/// dpotrf) and a dense triangular solve (dtrsm). analyze() does everything
/// that depends only on the pattern; the first factorize() after it
/// allocates, later ones and solve() allocate nothing.
class SupernodalCholesky {
 public:
  /// The pattern: `particles` lists the unknowns' particle indices; block row
  /// r (of particle particles[r]) holds slots row_start[particles[r]] ..
  /// row_start[particles[r] + 1] - 1 of the caller's block-CSR matrix, slot s
  /// at column particle col[s]. `compact` maps a particle to its position in
  /// `particles` (-1: not an unknown; such columns must not appear).
  void analyze(const std::vector<Index>& particles, const std::vector<Index>& compact,
               const std::vector<Index>& row_start, const std::vector<Index>& col);
  /// Factorises the matrix whose block-CSR values are `val` (same slots as
  /// given to analyze). Returns -1, or the elimination step of the first
  /// block column whose pivot was not positive.
  Index factorize(const std::vector<Eigen::Matrix3d>& val);
  /// x = A^-1 b on the unknowns' particles; other entries of x are not touched.
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);
  /// 3 x 3 blocks of L below the diagonal blocks, known after analyze().
  std::size_t factor_blocks() const noexcept { return blocks_; }
  /// Memory factorize() needs, known after analyze().
  double factor_bytes() const noexcept;
  /// Floating-point operations of one factorize() on L's nonzero blocks,
  /// known after analyze(): 54 per 3 x 3 block product (27 multiplies, 27
  /// additions), counted as the up-looking block algorithm would, for bench/.
  double factor_flops() const noexcept { return flops_; }
  /// Supernodes, known after analyze() (bench/ and tests).
  std::size_t supernodes() const noexcept { return super_.empty() ? 0 : super_.size() - 1; }

 private:
  std::vector<Index> order_;  // elimination step -> particle
  // A's lower triangle in elimination order, by block column: column j
  // lists (step i >= j, slot of A(order_[i], order_[j])).
  std::vector<Index> acol_start_, arow_, aslot_;
  // Supernode s covers block columns super_[s] .. super_[s + 1] - 1; its
  // block rows are rows_[row_start_[s] ..], the columns themselves first,
  // then the rows below in increasing order. Its panel of 3 x 3 blocks is
  // dense, column-major, 3 rows per block row, at lx_[panel_[s]].
  std::vector<Index> super_, super_of_, row_start_, rows_;
  std::vector<std::size_t> panel_;
  std::vector<double> lx_, work_;
  std::size_t work_size_ = 0;  // the largest update, doubles
  // Factorisation workspace: per supernode, the next of its rows still to
  // update an ancestor and the link of the list of descendants waiting to
  // update the supernode head_[t] belongs to; block row -> panel row.
  std::vector<Index> head_, next_, cursor_, local_;
  std::vector<double> z_, t_;  // solve's permuted right side and a gather buffer
  std::size_t blocks_ = 0;
  double flops_ = 0.0;
  // Supernode s's panel: block columns first .. first + cols - 1, nrows
  // block rows (rows[0 .. nrows)), values at x: ld = 3 nrows scalar rows,
  // width = 3 cols scalar columns, below = ld - width rows under the
  // diagonal block.
  struct Panel {
    Index first, cols, nrows;
    const Index* rows;
    int ld, width, below;
    double* x;
  };
  Panel panel(Index s);
  void gather(const Panel& p, const std::vector<Eigen::Matrix3d>& val);
  void update(Index d, const Panel& p);
  void link(Index d, Index row);
  bool allocated_ = false;  // the storage above, by the first factorize() after analyze()

  // analyze()'s steps, in the order it takes them (supernodal_cholesky.cpp).
  struct Pattern;      // analyze()'s arguments, read by the unknowns' positions
  struct Elimination;  // an order's elimination tree and L's column counts
  void clear();
  static std::vector<Index> fill_reducing_order(const Pattern& a);
  static Elimination eliminate(const Pattern& a, const std::vector<Index>& node);
  void count_factor(const std::vector<Index>& count);
  void lower_triangle(const Pattern& a, const std::vector<Index>& node,
                      const std::vector<Index>& step_of);
  void supernode_rows(const std::vector<Index>& parent);
  std::size_t largest_update() const;
};

}  // namespace pdyn::solvers::detail
