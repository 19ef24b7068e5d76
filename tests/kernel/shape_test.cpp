// pdyn/shape.hpp: every kind of shape a drawable hook may give is checked,
// each bad one with its exact reason; valid ones pass.
#include "pdyn/shape.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace pdyn {
namespace {

constexpr double kShapeNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kShapeInf = std::numeric_limits<double>::infinity();

TEST(Shape, ValidShapesHaveNoProblem) {
  const Shape valid[] = {
      shape::Plane{Vec3(0, 0, 1), Vec3(0, 0, 3)},  // any non-zero normal: the host normalizes it
      shape::Sphere{Vec3(1, 2, 3), 1e-9},
      shape::Box{Vec3(-1, -1, -1), Vec3(1, 2, 3)},
      shape::Mesh{{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}, {{0, 1, 2}}},
      shape::Mesh{},  // nothing to draw, nothing wrong
  };
  for (const auto& s : valid) EXPECT_EQ(shape_problem(s), "") << s.index();
}

TEST(Shape, EachBadShapeGetsItsExactReason) {
  const std::pair<Shape, std::string> bad[] = {
      {shape::Plane{Vec3(kShapeNaN, 0, 0), Vec3::UnitZ()}, "plane: non-finite point or normal"},
      {shape::Plane{Vec3::Zero(), Vec3(0, kShapeInf, 0)}, "plane: non-finite point or normal"},
      {shape::Plane{Vec3::Zero(), Vec3::Zero()}, "plane: zero normal (expected a unit normal)"},
      {shape::Sphere{Vec3::Zero(), kShapeNaN}, "sphere: non-finite centre or radius"},
      {shape::Sphere{Vec3::Zero(), 0.0}, "sphere: radius 0 (expected a radius > 0 m)"},
      {shape::Sphere{Vec3::Zero(), -2.5}, "sphere: radius -2.5 (expected a radius > 0 m)"},
      {shape::Box{Vec3(0, 0, -kShapeInf), Vec3::Ones()}, "box: non-finite corner"},
      {shape::Box{Vec3::Zero(), Vec3(1, 0, 1)},
       "box: min is not below max (expected min < max in every component)"},
      {shape::Mesh{{Vec3::Zero(), Vec3(0, kShapeNaN, 0)}, {}}, "mesh: non-finite vertex 1"},
      {shape::Mesh{{Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY()}, {{0, 1, 2}, {0, 3, 1}}},
       "mesh: triangle 1 names vertex 3 (expected 0..2)"},
      {shape::Mesh{{Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY()}, {{-1, 1, 2}}},
       "mesh: triangle 0 names vertex -1 (expected 0..2)"},
  };
  for (const auto& [s, why] : bad) EXPECT_EQ(shape_problem(s), why);
}

}  // namespace
}  // namespace pdyn
