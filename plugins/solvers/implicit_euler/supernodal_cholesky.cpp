// The supernodal Cholesky factorisation of supernodal_cholesky.hpp: the
// symbolic analysis (a fill-reducing order, the elimination tree, relaxed
// supernodes, each supernode's rows and panel), the left-looking numeric
// factorisation, and the two triangular solves.
#include "supernodal_cholesky.hpp"

#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>
#include <algorithm>
#include <vector>

#include "blas.hpp"

namespace pdyn::solvers::detail {

namespace {

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

// The caller's block pattern (analyze()'s arguments), by the unknowns'
// positions 0 .. n - 1 in `particles`.
struct SupernodalCholesky::Pattern {
  const std::vector<Index>& particles;
  const std::vector<Index>& compact;
  const std::vector<Index>& row_start;
  const std::vector<Index>& col;

  Index size() const { return static_cast<Index>(particles.size()); }
  // visit(c, s) for each slot s of unknown r's block row, c the position of
  // the slot's column particle.
  template <class Visit>
  void neighbours(Index r, Visit&& visit) const {
    const Index i = particles[static_cast<std::size_t>(r)];
    for (Index s = row_start[static_cast<std::size_t>(i)];
         s < row_start[static_cast<std::size_t>(i) + 1]; ++s) {
      visit(compact[static_cast<std::size_t>(col[s])], s);
    }
  }
  // The slot of A(particle pi, particle pj), in pi's block row.
  Index slot(Index pi, Index pj) const {
    const auto begin = col.begin() + row_start[static_cast<std::size_t>(pi)];
    const auto end = col.begin() + row_start[static_cast<std::size_t>(pi) + 1];
    return static_cast<Index>(std::lower_bound(begin, end, pj) - col.begin());
  }
};

struct SupernodalCholesky::Elimination {
  std::vector<Index> step_of;  // unknown -> the step that eliminates it
  std::vector<Index> parent;   // the elimination tree, by step (-1: a root)
  std::vector<Index> count;    // blocks below the diagonal in each column of L
};

void SupernodalCholesky::analyze(const std::vector<Index>& particles,
                                 const std::vector<Index>& compact,
                                 const std::vector<Index>& row_start,
                                 const std::vector<Index>& col) {
  clear();
  const Pattern a{particles, compact, row_start, col};
  const Index n = a.size();
  if (n == 0) return;  // every particle fixed: nothing to solve
  std::vector<Index> node = fill_reducing_order(a);
  // Postorder the tree (children before parents, each subtree contiguous):
  // the same fill, and a chain of columns with nested patterns then sits in
  // consecutive columns, which is what a supernode needs.
  {
    const std::vector<Index> post = postorder(eliminate(a, node).parent);
    std::vector<Index> reordered(static_cast<std::size_t>(n));
    for (Index k = 0; k < n; ++k) reordered[k] = node[post[k]];
    node.swap(reordered);
  }
  const Elimination e = eliminate(a, node);
  order_.resize(static_cast<std::size_t>(n));
  for (Index k = 0; k < n; ++k) order_[k] = particles[static_cast<std::size_t>(node[k])];
  count_factor(e.count);
  lower_triangle(a, node, e.step_of);
  super_ = relaxed_supernodes(e.parent, e.count);
  supernode_rows(e.parent);
  work_size_ = largest_update();
  // The panels are allocated by the first factorize(), so that a caller can
  // look at factor_bytes() first.
}

// Forgets the last analysis: an empty factor.
void SupernodalCholesky::clear() {
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
}

// A fill-reducing order of the block graph: one node per particle rather
// than per coordinate, so the ordering works on a 9x smaller graph and
// keeps each particle's three unknowns together. Eigen's AMDOrdering
// returns P with P.indices()[step] = the node eliminated at that step.
std::vector<Index> SupernodalCholesky::fill_reducing_order(const Pattern& a) {
  const Index n = a.size();
  std::vector<Eigen::Triplet<double, int>> entries;
  for (Index r = 0; r < n; ++r) {
    a.neighbours(r, [&](Index c, Index) {
      entries.emplace_back(static_cast<int>(r), static_cast<int>(c), 1.0);
    });
  }
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> graph(n, n);
  graph.setFromTriplets(entries.begin(), entries.end());
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> perm;
  Eigen::AMDOrdering<int>()(graph, perm);
  std::vector<Index> node(static_cast<std::size_t>(n));
  for (Index k = 0; k < n; ++k) node[k] = perm.indices()[k];
  return node;
}

// The elimination tree of the order `node` (node[k]: the unknown eliminated
// at step k), from A's upper triangle by column.
SupernodalCholesky::Elimination SupernodalCholesky::eliminate(const Pattern& a,
                                                              const std::vector<Index>& node) {
  const Index n = a.size();
  Elimination e;
  e.step_of.resize(static_cast<std::size_t>(n));
  for (Index k = 0; k < n; ++k) e.step_of[node[k]] = k;
  std::vector<Index> ucol_start(static_cast<std::size_t>(n) + 1, 0), urow;
  for (Index k = 0; k < n; ++k) {
    a.neighbours(node[k], [&](Index c, Index) {
      if (e.step_of[c] <= k) urow.push_back(e.step_of[c]);
    });
    ucol_start[k + 1] = static_cast<Index>(urow.size());
  }
  elimination_tree(ucol_start, urow, e.parent, e.count);
  return e;
}

// blocks_ and flops_ (see factor_flops()) from L's column counts.
void SupernodalCholesky::count_factor(const std::vector<Index>& count) {
  for (const Index k : count) {
    const double c = static_cast<double>(k);
    blocks_ += static_cast<std::size_t>(k);
    flops_ += 54.0 * (0.5 * c * (c - 1.0) + 2.0 * c);
  }
}

// A's lower triangle in elimination order, by column: the slot of
// A(order_[i], order_[j]) is row order_[i]'s entry at column order_[j].
void SupernodalCholesky::lower_triangle(const Pattern& a, const std::vector<Index>& node,
                                        const std::vector<Index>& step_of) {
  const Index n = a.size();
  acol_start_.assign(static_cast<std::size_t>(n) + 1, 0);
  arow_.clear();
  aslot_.clear();
  for (Index j = 0; j < n; ++j) {
    const Index pj = order_[j];
    a.neighbours(node[j], [&](Index c, Index) {
      const Index i = step_of[c];
      if (i < j) return;
      arow_.push_back(i);
      aslot_.push_back(a.slot(order_[i], pj));
    });
    acol_start_[j + 1] = static_cast<Index>(arow_.size());
  }
}

// Each supernode's rows: its columns, then below them the union of A's
// entries in its columns and of its child supernodes' rows; and where its
// panel starts in lx_.
void SupernodalCholesky::supernode_rows(const std::vector<Index>& parent) {
  const Index n = static_cast<Index>(parent.size());
  const Index ns = static_cast<Index>(super_.size()) - 1;
  super_of_.resize(static_cast<std::size_t>(n));
  for (Index s = 0; s < ns; ++s) {
    for (Index j = super_[s]; j < super_[s + 1]; ++j) super_of_[j] = s;
  }
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
}

// The largest update a supernode makes to one ancestor, doubles: its rows
// from the first in that ancestor down, times those in the ancestor.
std::size_t SupernodalCholesky::largest_update() const {
  std::size_t largest = 0;
  const Index ns = static_cast<Index>(super_.size()) - 1;
  for (Index d = 0; d < ns; ++d) {
    const Index r0 = row_start_[d], nr = row_start_[d + 1] - r0;
    for (Index p = super_[d + 1] - super_[d]; p < nr;) {
      const Index t = super_of_[rows_[r0 + p]];
      Index q = p;
      while (q < nr && super_of_[rows_[r0 + q]] == t) ++q;
      largest = std::max(largest, static_cast<std::size_t>(9 * (nr - p) * (q - p)));
      p = q;
    }
  }
  return largest;
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

}  // namespace pdyn::solvers::detail
