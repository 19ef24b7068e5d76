// @NAME@'s own tests (GoogleTest): the plugin's source is compiled into this
// program, so its descriptor is at hand without loading a library. The first
// test runs every check of the conformance kit (J, c_t and b against finite
// differences of C among them); the last checks the physics: the force the
// kernel would derive from C, J and b keeps a bead on its circular orbit.
// Add tests of your own beside them.
#include <gtest/gtest.h>

#include <cmath>
#include <pdyn/conformance.hpp>
#include <pdyn/plugin.hpp>
#include <vector>

TEST(@NAME@, PassesTheConformanceKit) {
  const auto results = pdyn::conformance::run_checks(*pdyn_plugin_descriptor(), {.seed = 1});
  ASSERT_FALSE(results.empty());
  for (const auto& r : results) {
    EXPECT_NE(r.verdict, pdyn::conformance::Verdict::Fail) << r.name << ": " << r.detail;
  }
}

TEST(@NAME@, DescriptorNamesThisPlugin) {
  EXPECT_EQ(pdyn_plugin_descriptor()->name, "@NAME@");
}

// One bead of mass m at radius r in the bowl of radius R (bottom at z = 0),
// moving along the horizontal circle at the angular speed w = sqrt(g / R),
// under gravity Q = (0, 0, -m g). With one row, Witkin's multiplier is
//   lambda = (-b - J W Q) / (J W J^T),   W = 1/m,
// and the acceleration a = W (Q + J^T lambda) must be the circle's
// centripetal one, (-w^2 r, 0, 0): no vertical part, so the bead keeps its
// height.
TEST(@NAME@, ConstraintForceKeepsACircularOrbit) {
  const double g = 9.81, m = 2.0, big_r = 1.5, r = 0.7;  // m/s^2, kg, m, m
  const double w = std::sqrt(g / big_r);                 // 1/s
  pdyn::Matrix3X x(3, 1), v(3, 1);
  x.col(0) = pdyn::Vec3(r, 0.0, r * r / (2.0 * big_r));
  v.col(0) = pdyn::Vec3(0.0, w * r, 0.0);
  const Eigen::VectorXd mass = Eigen::VectorXd::Constant(1, m);
  const std::vector<std::uint8_t> fixed(1, 0);
  const pdyn::ParticleView p{0.0, {x.data(), 3, 1}, {v.data(), 3, 1}, {mass.data(), 1}, fixed};

  const pdyn::PluginDescriptor& d = *pdyn_plugin_descriptor();
  pdyn::Params params = pdyn::conformance::sample_params(d, 4);
  params.set("ids", std::vector<pdyn::Index>{0});
  params.set("radius", big_r);
  params.set("bottom", 0.0);
  const auto c = d.create_constraint(params, pdyn::SceneContext{p});
  const pdyn::ConstraintPattern pattern = c->pattern();
  ASSERT_EQ(pattern.rows(), 1);
  pdyn::ConstraintValues out;
  out.value = Eigen::VectorXd::Zero(1);
  out.rate = Eigen::VectorXd::Zero(1);
  out.bias = Eigen::VectorXd::Zero(1);
  out.jacobian = pdyn::Matrix3X::Zero(3, 1);
  c->evaluate(p, out);

  EXPECT_NEAR(out.value[0], 0.0, 1e-15);                    // on the bowl, m
  EXPECT_NEAR(out.bias[0], -w * w * r * r / big_r, 1e-12);  // -|v|^2 / R, m/s^2
  const pdyn::Vec3 j = out.jacobian.col(0);
  const pdyn::Vec3 q(0.0, 0.0, -m * g);  // N
  const double lambda = (-out.bias[0] - j.dot(q) / m) / (j.squaredNorm() / m);
  const pdyn::Vec3 a = (q + j * lambda) / m;  // m/s^2
  EXPECT_NEAR(a.x(), -w * w * r, 1e-12);
  EXPECT_NEAR(a.y(), 0.0, 1e-12);
  EXPECT_NEAR(a.z(), 0.0, 1e-12);
}
