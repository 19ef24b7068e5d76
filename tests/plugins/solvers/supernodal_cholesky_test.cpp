// implicit_euler's sparse factorisation by itself (detail::SupernodalCholesky):
// on block patterns of the kinds scenes make (a cloth grid, a chain, a hub
// tied to every particle, separate pieces, fixed particles left out) it must
// solve A x = b as a dense Cholesky of the same matrix does, refactorise
// in place when the values change, and report a matrix that is not positive
// definite, then factorise the next good one as if nothing had happened.
#include "supernodal_cholesky.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <random>

namespace pdyn {
namespace {

using solvers::detail::SupernodalCholesky;

// A block-CSR matrix over `n` particles, as ImplicitEuler builds it: rows
// and columns of fixed particles left out, every other row holding its
// diagonal block.
struct BlockMatrix {
  Index n = 0;
  std::vector<Index> particles, compact, row_start, col;
  std::vector<Eigen::Matrix3d> val;

  BlockMatrix(Index count, const std::vector<std::pair<Index, Index>>& edges,
              const std::vector<bool>& fixed)
      : n(count) {
    std::vector<std::pair<Index, Index>> entries;
    compact.assign(static_cast<std::size_t>(n), -1);
    for (Index i = 0; i < n; ++i) {
      if (fixed[i]) continue;
      compact[i] = static_cast<Index>(particles.size());
      particles.push_back(i);
      entries.emplace_back(i, i);
    }
    for (auto [i, j] : edges) {
      if (fixed[i] || fixed[j]) continue;
      entries.emplace_back(i, j);
      entries.emplace_back(j, i);
    }
    std::sort(entries.begin(), entries.end());
    entries.erase(std::unique(entries.begin(), entries.end()), entries.end());
    row_start.assign(static_cast<std::size_t>(n) + 1, 0);
    for (auto [i, j] : entries) {
      ++row_start[i + 1];
      col.push_back(j);
    }
    for (Index i = 0; i < n; ++i) row_start[i + 1] += row_start[i];
    val.resize(col.size());
  }

  Index slot(Index i, Index j) const {
    const auto b = col.begin() + row_start[i], e = col.begin() + row_start[i + 1];
    return static_cast<Index>(std::lower_bound(b, e, j) - col.begin());
  }

  // Random off-diagonal blocks (A_ji = A_ij^T) and diagonal blocks that
  // make A strictly block diagonally dominant, so symmetric positive definite.
  void fill(std::mt19937& rng) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (Index i = 0; i < n; ++i) {
      for (Index s = row_start[i]; s < row_start[i + 1]; ++s) {
        const Index j = col[s];
        if (j <= i) continue;
        Eigen::Matrix3d b;
        for (int k = 0; k < 9; ++k) b(k % 3, k / 3) = u(rng);
        val[s] = b;
        val[slot(j, i)] = b.transpose();
      }
    }
    for (Index i = 0; i < n; ++i) {
      if (row_start[i] == row_start[i + 1]) continue;
      double off = 0.0;
      for (Index s = row_start[i]; s < row_start[i + 1]; ++s) {
        if (col[s] != i) off += val[s].cwiseAbs().sum();
      }
      Eigen::Matrix3d d;
      for (int k = 0; k < 9; ++k) d(k % 3, k / 3) = 0.1 * u(rng);
      val[slot(i, i)] = 0.5 * (d + d.transpose()) + (off + 1.0) * Eigen::Matrix3d::Identity();
    }
  }

  Eigen::MatrixXd dense() const {
    const Index m = static_cast<Index>(particles.size());
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(3 * m, 3 * m);
    for (Index i : particles) {
      for (Index s = row_start[i]; s < row_start[i + 1]; ++s) {
        a.block<3, 3>(3 * compact[i], 3 * compact[col[s]]) = val[s];
      }
    }
    return a;
  }
};

// x = A^-1 b by the sparse factor, on the free particles, against a dense
// Cholesky of the same matrix: relative difference in the max norm.
double solve_error(SupernodalCholesky& chol, const BlockMatrix& a, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd b(3 * a.n), x = Eigen::VectorXd::Constant(3 * a.n, 7.0);
  for (Index k = 0; k < b.size(); ++k) b[k] = u(rng);
  EXPECT_EQ(chol.factorize(a.val), -1);
  chol.solve(b, x);
  const Index m = static_cast<Index>(a.particles.size());
  Eigen::VectorXd bf(3 * m), xs(3 * m);
  for (Index r = 0; r < m; ++r) {
    bf.segment<3>(3 * r) = b.segment<3>(3 * a.particles[r]);
    xs.segment<3>(3 * r) = x.segment<3>(3 * a.particles[r]);
  }
  for (Index i = 0; i < a.n; ++i) {  // fixed particles' entries untouched
    if (a.compact[i] < 0) {
      EXPECT_EQ(x.segment<3>(3 * i), Eigen::Vector3d::Constant(7.0));
    }
  }
  const Eigen::VectorXd xd = a.dense().llt().solve(bf);
  return (xs - xd).lpNorm<Eigen::Infinity>() / xd.lpNorm<Eigen::Infinity>();
}

std::vector<std::pair<Index, Index>> grid_edges(Index nx, Index ny) {
  std::vector<std::pair<Index, Index>> e;
  for (Index y = 0; y < ny; ++y) {
    for (Index x = 0; x < nx; ++x) {
      const Index i = y * nx + x;
      if (x + 1 < nx) e.emplace_back(i, i + 1);
      if (y + 1 < ny) e.emplace_back(i, i + nx);
      if (x + 1 < nx && y + 1 < ny) {  // shear springs
        e.emplace_back(i, i + nx + 1);
        e.emplace_back(i + 1, i + nx);
      }
      if (x + 2 < nx) e.emplace_back(i, i + 2);  // bend springs
    }
  }
  return e;
}

TEST(SupernodalCholesky, SolvesAsADenseCholeskyOnTheBlockPatternsOfScenes) {
  std::mt19937 rng(7);
  struct Case {
    const char* name;
    Index n;
    std::vector<std::pair<Index, Index>> edges;
    std::vector<bool> fixed;
  };
  std::vector<Case> cases;
  cases.push_back(
      {"cloth 24 x 20, two corners fixed", 480, grid_edges(24, 20), std::vector<bool>(480, false)});
  cases.back().fixed[0] = cases.back().fixed[23] = true;
  {
    std::vector<std::pair<Index, Index>> chain;
    for (Index i = 0; i + 1 < 300; ++i) chain.emplace_back(i, i + 1);
    cases.push_back({"chain of 300", 300, chain, std::vector<bool>(300, false)});
  }
  {
    auto e = grid_edges(12, 12);
    for (Index i = 1; i < 144; ++i) e.emplace_back(0, i);  // a hub tied to all
    cases.push_back({"grid with a hub", 144, e, std::vector<bool>(144, false)});
  }
  {
    auto e = grid_edges(10, 10);  // two cloths and loose particles
    for (auto [i, j] : grid_edges(8, 5)) e.emplace_back(100 + i, 100 + j);
    cases.push_back({"two pieces and loose particles", 150, e, std::vector<bool>(150, false)});
  }
  cases.push_back({"every particle fixed", 4, grid_edges(2, 2), std::vector<bool>(4, true)});
  for (Case& c : cases) {
    BlockMatrix a(c.n, c.edges, c.fixed);
    SupernodalCholesky chol;
    chol.analyze(a.particles, a.compact, a.row_start, a.col);
    if (a.particles.size() > 100) {
      // Columns grouped: fewer supernodes than particles.
      EXPECT_LT(chol.supernodes(), a.particles.size() / 2) << c.name;
    }
    for (int round = 0; round < 3; ++round) {  // refactorised in place with new values
      a.fill(rng);
      if (a.particles.empty()) {
        EXPECT_EQ(chol.factorize(a.val), -1);
        continue;
      }
      const double err = solve_error(chol, a, rng);
      std::cout << c.name << ", round " << round << ": " << chol.supernodes()
                << " supernodes, relative error " << err << "\n";
      EXPECT_LT(err, 1e-12) << c.name << ", round " << round;
    }
  }
}

TEST(SupernodalCholesky, ReportsAMatrixThatIsNotPositiveDefiniteAndRecovers) {
  std::mt19937 rng(11);
  BlockMatrix a(400, grid_edges(20, 20), std::vector<bool>(400, false));
  SupernodalCholesky chol;
  chol.analyze(a.particles, a.compact, a.row_start, a.col);
  a.fill(rng);
  const std::vector<Eigen::Matrix3d> good = a.val;
  // One particle's diagonal block made negative definite: some pivot fails,
  // at an elimination step of the 400.
  a.val[a.slot(210, 210)] = -Eigen::Matrix3d::Identity();
  const Index bad = chol.factorize(a.val);
  EXPECT_GE(bad, 0);
  EXPECT_LT(bad, 400);
  a.val = good;
  EXPECT_LT(solve_error(chol, a, rng), 1e-12);
}

}  // namespace
}  // namespace pdyn
