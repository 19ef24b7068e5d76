// The particle store's box, radii and types (ABI 4): what forces see in
// their view, the wrap of positions into a periodic box with its image
// counts, and each bad value refused with its reason.
#include <gtest/gtest.h>

#include "pdyn/error.hpp"
#include "pdyn/host/assembly.hpp"
#include "pdyn/system.hpp"

namespace pdyn {
namespace {

void three_particles(System& s) {
  Matrix3X x(3, 3), v = Matrix3X::Zero(3, 3);
  x << 0.5, 2.5, -7.25,  //
      0.5, 0.5, 0.5,     //
      9.0, -1.0, 0.0;
  SystemAssembly(s).set_particles(x, v, Eigen::VectorXd::Ones(3), {0, 0, 0});
}

Domain box_xy() {
  Domain d;
  d.min = Vec3(0, 0, 0);
  d.max = Vec3(2, 1, 3);
  d.periodic = {true, true, false};
  return d;
}

TEST(SystemDomain, WrapBringsParticlesIntoThePeriodicAxesAndCountsImages) {
  System s;
  three_particles(s);
  SystemAssembly(s).set_domain(box_xy());
  const Matrix3X before = s.positions();
  SystemAssembly(s).wrap_positions();
  const Matrix3X after = s.positions();
  // x: 0.5 stays, 2.5 -> 0.5 (one length), -7.25 -> 0.75 (-4 lengths); y stays; z is open.
  EXPECT_EQ(after.row(0), Eigen::RowVector3d(0.5, 0.5, 0.75));
  EXPECT_EQ(after.row(1), before.row(1));
  EXPECT_EQ(after.row(2), before.row(2));
  const std::vector<std::array<std::int32_t, 3>> images{{0, 0, 0}, {1, 0, 0}, {-4, 0, 0}};
  EXPECT_EQ(s.images(), images);
  // The unwrapped positions are the ones before the wrap.
  const Vec3 length = s.domain().length();
  for (Index i = 0; i < 3; ++i) {
    const auto& n = s.images()[static_cast<std::size_t>(i)];
    const Vec3 unwrapped = after.col(i) + Vec3(n[0] * length[0], n[1] * length[1], 0);
    EXPECT_NEAR((unwrapped - before.col(i)).norm(), 0.0, 1e-12) << i;
  }
  // Open space: nothing moves.
  System open;
  three_particles(open);
  SystemAssembly(open).wrap_positions();
  EXPECT_EQ(Matrix3X(open.positions()), before);
}

TEST(SystemDomain, ForcesSeeTheBoxRadiiAndTypes) {
  System s;
  three_particles(s);
  EXPECT_FALSE(s.view().domain.any_periodic());
  EXPECT_TRUE(s.view().radius.empty());
  EXPECT_TRUE(s.view().type.empty());
  SystemAssembly(s).set_domain(box_xy());
  SystemAssembly(s).set_radii({0.1, 0.2, 0.3});
  SystemAssembly(s).set_types({0, 2, 1});
  const ParticleView v = s.view();
  EXPECT_TRUE(v.domain == box_xy());
  ASSERT_EQ(v.radius.size(), 3u);
  EXPECT_EQ(v.radius[1], 0.2);
  ASSERT_EQ(v.type.size(), 3u);
  EXPECT_EQ(v.type[1], 2);
  // A particle added interactively gets radius 0 and type 0; replacing all
  // particles clears both.
  EXPECT_EQ(SystemAssembly(s).add_particle(Vec3(1, 0.5, 0), Vec3::Zero(), 1.0), 3);
  EXPECT_EQ(s.radii(), (std::vector<double>{0.1, 0.2, 0.3, 0.0}));
  EXPECT_EQ(s.types(), (std::vector<std::int32_t>{0, 2, 1, 0}));
  EXPECT_EQ(s.images().size(), 4u);
  SystemAssembly(s).set_particles(Matrix3X::Zero(3, 2), Matrix3X::Zero(3, 2),
                                  Eigen::VectorXd::Ones(2), {0, 0});
  EXPECT_TRUE(s.radii().empty() && s.types().empty());
}

TEST(SystemDomain, BadValuesAreRefusedWithTheirReason) {
  System s;
  three_particles(s);
  auto message = [](auto&& call) {
    try {
      call();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  Domain flat = box_xy();
  flat.max.y() = 0;
  EXPECT_EQ(message([&] { SystemAssembly(s).set_domain(flat); }),
            "System::set_domain: periodic axis y runs from 0 to 0 m (expected finite min < max)");
  EXPECT_EQ(message([&] {
              SystemAssembly(s).set_radii({0.1, 0.2});
            }),
            "System::set_radii: 2 radii for 3 particles");
  EXPECT_EQ(message([&] {
              SystemAssembly(s).set_radii({0.1, -0.2, 0.1});
            }),
            "System::set_radii: particle 1 has radius -0.2 (expected >= 0 m)");
  EXPECT_EQ(message([&] {
              SystemAssembly(s).set_types({0, 0, -1});
            }),
            "System::set_types: particle 2 has type -1 (expected >= 0)");
  EXPECT_EQ(message([&] { SystemAssembly(s).set_images({}); }),
            "System::set_images: 0 entries for 3 particles");
  // A refused value changes nothing.
  EXPECT_FALSE(s.domain().any_periodic());
  EXPECT_TRUE(s.radii().empty());
}

}  // namespace
}  // namespace pdyn
