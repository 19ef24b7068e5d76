// pdyn/particle_constraint.hpp: the base class of constraints whose rows
// each hold one particle (pin, on_plane, on_sphere, on_circle, the `pdyn
// new constraint` template), and require_distinct_ids (pdyn/params.hpp),
// which their factories and force selections share.
#include "pdyn/particle_constraint.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "pdyn/error.hpp"
#include "pdyn/params.hpp"

namespace pdyn {
namespace {

// Two rows per particle about its site s: C0 = x - s (m), C1 = t y v_z
// (m^2/s ... any unit will do), with J, c_t and b written as numbers the
// test can find again: row 1's bias is 100 k + 7 for site k.
struct TwoRowLaw {
  static constexpr int rows = 2;
  using Site = double;
  double scale = 1.0;

  void operator()(const ParticlePoint& p, const double& site, ParticleRows<2>& out) const {
    out.value[0] = p.x.x() - site;
    out.jacobian[0] = Vec3::UnitX();
    out.value[1] = scale * p.t * p.x.y() * p.v.z();
    out.jacobian[1] = Vec3(0.0, scale * p.t * p.v.z(), 0.0);
    out.rate[1] = scale * p.x.y() * p.v.z();
    out.bias[1] = 100.0 * site + 7.0;
  }
};

// A law that writes only C's rate: its value and Jacobian stay NaN.
struct ForgetfulLaw {
  static constexpr int rows = 1;
  using Site = int;
  void operator()(const ParticlePoint&, const int&, ParticleRows<1>& out) const {
    out.rate[0] = 1.0;
  }
};

struct ParticleConstraintState {
  Matrix3X x, v;
  Eigen::VectorXd mass;
  std::vector<std::uint8_t> fixed;
  double t = 2.0;
  ParticleView view() const {
    return ParticleView{
        t, {x.data(), 3, x.cols()}, {v.data(), 3, v.cols()}, {mass.data(), mass.size()}, fixed};
  }
};

ParticleConstraintState FourParticles() {
  ParticleConstraintState s;
  s.x.resize(3, 4);
  s.v.resize(3, 4);
  for (Index i = 0; i < 4; ++i) {
    s.x.col(i) = Vec3(1.0 + i, 2.0 * i, -1.0);
    s.v.col(i) = Vec3(0.0, 0.0, 0.5 + i);
  }
  s.mass = Eigen::VectorXd::Ones(4);
  s.fixed.assign(4, 0);
  return s;
}

ConstraintValues SizedValues(const ConstraintPattern& pat) {
  ConstraintValues out;
  out.value = Eigen::VectorXd::Zero(pat.rows());
  out.rate = Eigen::VectorXd::Zero(pat.rows());
  out.bias = Eigen::VectorXd::Zero(pat.rows());
  out.jacobian = Matrix3X::Zero(3, pat.entries());
  return out;
}

// Particle ids[k]'s rows are 2 k and 2 k + 1, each with one entry, the
// entry at row_begin[r]; the law's numbers land there.
TEST(ParticleConstraint, RowsOfIdsKAreItsOwnAndEachHasOneEntry) {
  const ParticleConstraint<TwoRowLaw> c({3, 0, 2}, {0.5, 1.5, 2.5}, TwoRowLaw{2.0});
  const ConstraintPattern pat = c.pattern();
  EXPECT_EQ(pat.rows(), 6);
  EXPECT_EQ(pat.row_begin, (std::vector<Index>{0, 1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(pat.particle, (std::vector<Index>{3, 3, 0, 0, 2, 2}));
  const ParticleConstraintState s = FourParticles();
  ConstraintValues out = SizedValues(pat);
  c.evaluate(s.view(), out);
  const std::vector<Index> ids{3, 0, 2};
  const std::vector<double> sites{0.5, 1.5, 2.5};
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const Index i = ids[k], r = 2 * static_cast<Index>(k);
    const double y = 2.0 * i, vz = 0.5 + i;
    EXPECT_EQ(out.value[r], 1.0 + i - sites[k]) << k;
    EXPECT_EQ(out.value[r + 1], 2.0 * 2.0 * y * vz) << k;
    EXPECT_EQ(out.rate[r], 0.0) << k;
    EXPECT_EQ(out.rate[r + 1], 2.0 * y * vz) << k;
    EXPECT_EQ(out.bias[r], 0.0) << k;
    EXPECT_EQ(out.bias[r + 1], 100.0 * sites[k] + 7.0) << k;
    EXPECT_EQ(Vec3(out.jacobian.col(pat.row_begin[r])), Vec3::UnitX()) << k;
    EXPECT_EQ(Vec3(out.jacobian.col(pat.row_begin[r + 1])), Vec3(0.0, 2.0 * 2.0 * vz, 0.0)) << k;
  }
  EXPECT_EQ(c.ids(), ids);
  EXPECT_EQ(c.sites(), sites);
  EXPECT_EQ(c.law().scale, 2.0);
}

// A row the law leaves unwritten reaches the kernel as NaN (so `pdyn check`
// fails it), not as the previous call's number or 0.
TEST(ParticleConstraint, ARowTheLawLeavesOutIsNaN) {
  const ParticleConstraint<ForgetfulLaw> c({1}, {0});
  const ParticleConstraintState s = FourParticles();
  ConstraintValues out = SizedValues(c.pattern());
  c.evaluate(s.view(), out);
  EXPECT_TRUE(std::isnan(out.value[0]));
  EXPECT_TRUE(std::isnan(out.jacobian(0, 0)) && std::isnan(out.jacobian(1, 0)) &&
              std::isnan(out.jacobian(2, 0)));
  EXPECT_EQ(out.rate[0], 1.0);
  EXPECT_EQ(out.bias[0], 0.0);
}

std::string DistinctIdsMessage(const std::vector<Index>& ids, const char* twice, long* element) {
  Params p;
  p.set("ids", ids);
  try {
    if (twice) {
      require_distinct_ids(p, "ids", twice);
    } else {
      require_distinct_ids(p, "ids");
    }
  } catch (const ParamError& e) {
    EXPECT_EQ(e.param(), "ids");
    *element = e.element();
    return e.what();
  }
  return "(no error)";
}

TEST(ParticleConstraint, RequireDistinctIdsNamesTheFirstRepeat) {
  long element = -2;
  EXPECT_EQ(DistinctIdsMessage({4, 1, 2}, nullptr, &element), "(no error)");
  EXPECT_EQ(DistinctIdsMessage({4, 1, 2, 1, 4}, nullptr, &element),
            "particle 1 is listed twice (expected each id once)");
  EXPECT_EQ(element, 3);
  EXPECT_EQ(DistinctIdsMessage({0, 0}, "is pinned twice", &element),
            "particle 0 is pinned twice (expected each id once)");
  EXPECT_EQ(element, 1);
}

}  // namespace
}  // namespace pdyn
