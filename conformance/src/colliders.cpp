// The collider checks: deterministic, read-only on the state in
// apply_contact_forces, finite on degenerate configurations, and what
// respond() promises: the kit finds the obstacle, drops particles on it and
// checks that none ends a step inside, the declared restitution, no
// tangential change without friction, and contact forces along the normal.
#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <random>

#include "checks.hpp"
#include "pdyn/shape.hpp"
#include "sample.hpp"

namespace pdyn::conformance::detail {

namespace {

// A collider does not describe its obstacle, so the kit finds it through the
// contract of respond(): "puts penetrating particles back on the surface". A
// point is *inside* when respond(), given a particle at rest there, moves it
// (by more than 1e-9 m). The kit probes a grid over [-2, 2]^3 m with that
// test, then drops particles at the inside point nearest the origin from 14
// directions (axes and diagonals) and checks after every step that respond()
// left no particle inside, and that the particle was deflected at all.

constexpr double kInsideTolerance = 1e-9;  // m

bool inside(Collider& c, const Vec3& x) {
  State s = make_state(1);
  s.x.col(0) = x;
  MutableParticleView view = s.mutable_view();
  c.respond(view, 1e-3);
  return (s.x.col(0) - x).norm() > kInsideTolerance;
}

// Points on a drawn shape with the shape's normal there: where the picture
// says the obstacle's surface is.
std::vector<std::pair<Vec3, Vec3>> surface_samples(const Shape& shape) {
  std::vector<std::pair<Vec3, Vec3>> out;
  if (const auto* p = std::get_if<shape::Plane>(&shape)) {
    const Vec3 n = p->normal.normalized();
    const Vec3 foot = p->point.dot(n) * n;  // the plane's point nearest the origin
    const Vec3 t = n.unitOrthogonal(), u = n.cross(t);
    for (const Vec3& off : {Vec3::Zero().eval(), Vec3(0.5 * t), Vec3(-0.5 * u)})
      out.emplace_back(foot + off, n);
  } else if (const auto* s = std::get_if<shape::Sphere>(&shape)) {
    for (int k = 0; k < 3; ++k) {
      for (double sign : {1.0, -1.0}) {
        const Vec3 u = sign * Vec3::Unit(k);
        out.emplace_back(s->center + s->radius * u, u);
      }
    }
  } else if (const auto* b = std::get_if<shape::Box>(&shape)) {
    const Vec3 c = 0.5 * (b->min + b->max);
    for (int k = 0; k < 3; ++k) {
      Vec3 lo = c, hi = c;
      lo[k] = b->min[k];
      hi[k] = b->max[k];
      out.emplace_back(lo, -Vec3::Unit(k));
      out.emplace_back(hi, Vec3::Unit(k));
    }
  } else {
    const auto& m = std::get<shape::Mesh>(shape);
    for (const auto& t : m.triangles) {
      const auto corner = [&](int k) -> const Vec3& {
        return m.vertices[static_cast<std::size_t>(t[static_cast<std::size_t>(k)])];
      };
      const Vec3 n = (corner(1) - corner(0)).cross(corner(2) - corner(0));
      if (n.norm() > 0) out.emplace_back((corner(0) + corner(1) + corner(2)) / 3, n.normalized());
    }
  }
  return out;
}

struct Drop {
  Vec3 direction;                   // unit, the direction of travel
  bool hit = false;                 // respond() changed the velocity
  bool ended_inside = false;        // some step ended inside
  Vec3 v_in, v_out, contact_point;  // at the first response
};

Drop drop(Collider& c, const Vec3& target, const Vec3& dir, double speed) {
  Drop r;
  r.direction = dir;
  State s = make_state(1);
  s.x.col(0) = target - 3.0 * dir;
  s.v.col(0) = speed * dir;
  const double h = 0.01;
  for (int step = 0; step < 120; ++step) {
    s.x.col(0) += h * s.v.col(0);
    s.t += h;
    const Vec3 before = s.v.col(0);
    MutableParticleView view = s.mutable_view();
    c.respond(view, h);
    if (!r.hit && (Vec3(s.v.col(0)) - before).norm() > 0) {
      r.hit = true;
      r.v_in = before;
      r.v_out = s.v.col(0);
      r.contact_point = s.x.col(0);
    }
    if (inside(c, s.x.col(0))) r.ended_inside = true;
  }
  return r;
}

std::vector<Vec3> drop_directions() {
  std::vector<Vec3> dirs;
  for (int k = 0; k < 3; ++k) {
    for (double sign : {-1.0, 1.0}) {
      Vec3 d = Vec3::Zero();
      d(k) = sign;
      dirs.push_back(d);
    }
  }
  for (double a : {-1.0, 1.0})
    for (double b : {-1.0, 1.0})
      for (double e : {-1.0, 1.0}) dirs.push_back(Vec3(a, b, e).normalized());
  return dirs;
}

}  // namespace

namespace {

// Determinism, a read-only state, finite values, and the drawing hook.
void basic_collider_checks(Collider& c, const std::function<std::shared_ptr<Collider>()>& make,
                           std::mt19937_64& rng, const State& home, std::vector<CheckResult>& out) {
  guarded(out, "deterministic", [&] {
    State a = random_state(rng);
    a.x *= 0.2;  // near the origin, where default obstacles are
    a.f.setRandom();
    State b = a;
    MutableParticleView va = a.mutable_view(), vb = b.mutable_view();
    c.respond(va, 0.01);
    make()->respond(vb, 0.01);
    const bool same = bit_equal(a.x, b.x) && bit_equal(a.v, b.v);
    return result("deterministic", same, std::max(max_abs(a.x - b.x), max_abs(a.v - b.v)), 0,
                  "respond() of two objects on the same state: bit-identical");
  });

  guarded(out, "read_only_state", [&] {
    State s = home;
    const State before = s;
    Matrix3X f = Matrix3X::Random(3, s.size());
    c.apply_contact_forces(s.view(), f);
    const bool same = bit_equal(s.x, before.x) && bit_equal(s.v, before.v);
    return result("read_only_state", same, same ? 0 : 1, 0,
                  "x, v unchanged by apply_contact_forces");
  });

  guarded(out, "finite_on_degenerate", [&] {
    std::size_t bad = 0;
    for (auto [label, s] : degenerate_states(rng)) {
      (void)label;
      s.f.setConstant(-1.0);
      Matrix3X f = s.f;
      c.apply_contact_forces(s.view(), f);
      MutableParticleView view = s.mutable_view();
      c.respond(view, 0.01);
      bad += non_finite(f) + non_finite(s.x) + non_finite(s.v);
    }
    return result("finite_on_degenerate", bad == 0, static_cast<double>(bad), 0,
                  "coincident, at rest, far: no NaN/inf from respond or contact forces");
  });

  // The optional drawing hook: valid shapes, drawn where respond() finds the
  // obstacle (1 mm to one side of the drawn surface is inside, to the other
  // side not).
  guarded(out, "collider.shape", [&] {
    const auto* source = dynamic_cast<const ShapeSource*>(&c);
    if (!source) return skip("collider.shape", "no shape hook (pdyn/shape.hpp): not drawn");
    const std::vector<Shape> shapes = source->shapes();
    if (shapes.empty()) return result("collider.shape", false, 0, 1, "shapes() returned nothing");
    int probes = 0, wrong = 0;
    for (std::size_t k = 0; k < shapes.size(); ++k) {
      if (const std::string problem = shape_problem(shapes[k]); !problem.empty()) {
        return result("collider.shape", false, 1, 0,
                      fmt::format("shapes()[{}] cannot be drawn: {}", k, problem));
      }
      for (const auto& [point, normal] : surface_samples(shapes[k])) {
        if (point.cwiseAbs().maxCoeff() > 2.0) continue;
        ++probes;
        const Vec3 step = 1e-3 * normal;
        wrong += inside(c, point + step) == inside(c, point - step) ? 1 : 0;
      }
    }
    return result("collider.shape", probes > 0 && wrong == 0, wrong, 0,
                  fmt::format("{} points of the drawn surface in [-2,2]^3 m: {} without the "
                              "obstacle on exactly one side (1 mm off the surface)",
                              probes, wrong));
  });
}

// The obstacle's point nearest the origin among probes in [-2,2]^3 m.
std::optional<Vec3> find_obstacle(Collider& c, std::vector<CheckResult>& out) {
  std::optional<Vec3> target;
  guarded(out, "collider.obstacle_found", [&] {
    int count = 0;
    for (int i = 0; i <= 16; ++i)
      for (int j = 0; j <= 16; ++j)
        for (int k = 0; k <= 16; ++k) {
          const Vec3 x = Vec3(i, j, k) * 0.25 - Vec3::Constant(2.0);
          if (!inside(c, x)) continue;
          ++count;
          if (!target || x.norm() < target->norm()) target = x;
        }
    return result("collider.obstacle_found", count > 0, count, 1,
                  "probe points in [-2,2]^3 m (step 0.25) that respond() moves out (>= bound)");
  });
  return target;
}

// Particles dropped onto `target` from every axis and diagonal.
std::vector<Drop> drop_checks(Collider& c, const Vec3& target, std::vector<CheckResult>& out) {
  std::vector<Drop> drops;
  guarded(out, "collider.no_particle_inside", [&] {
    int inside_count = 0, missed = 0, tried = 0;
    for (const Vec3& dir : drop_directions()) {
      if (inside(c, target - 3.0 * dir)) continue;  // would start inside
      ++tried;
      drops.push_back(drop(c, target, dir, 5.0));
      inside_count += drops.back().ended_inside ? 1 : 0;
      missed += drops.back().hit ? 0 : 1;
    }
    return result("collider.no_particle_inside", inside_count == 0 && missed == 0 && tried > 0,
                  inside_count + missed, 0,
                  fmt::format("{} drops at 5 m/s, h = 0.01 s: {} ended a step inside, {} passed "
                              "through without a response",
                              tried, inside_count, missed));
  });
  return drops;
}

// A normal impact: the drop whose velocity came back antiparallel, else
// one that stopped (perfectly inelastic); null if none.
const Drop* normal_impact(const std::vector<Drop>& drops) {
  for (const auto& dr : drops) {
    if (dr.hit && dr.v_out.norm() > 0 && dr.v_out.normalized().dot(-dr.direction) > 1 - 1e-12) {
      return &dr;
    }
  }
  for (const auto& dr : drops) {
    if (dr.hit && dr.v_out.norm() == 0) return &dr;
  }
  return nullptr;
}

// Restitution, no tangential change without friction, contact forces that
// only cancel a push into the surface.
void impact_checks(Collider& c, const PluginDescriptor& d, const Params& params,
                   const std::vector<Drop>& drops, const Drop* normal,
                   std::vector<CheckResult>& out) {
  const Vec3 n = -normal->direction;  // outward normal at the contact point

  guarded(out, "collider.restitution", [&] {
    const double e = normal->v_out.norm() / normal->v_in.norm();
    for (const auto& spec : d.params) {
      if (spec.name == "restitution" && spec.type == ParamType::Real) {
        const double kr = params.real("restitution");
        return result(
            "collider.restitution", std::abs(e - kr) <= 1e-9, std::abs(e - kr), 1e-9,
            fmt::format("normal impact at 5 m/s: |v_out|/|v_in| = {:.6g}, declared {}", e, kr));
      }
    }
    return result("collider.restitution", e <= 1.0 + 1e-12, e, 1.0,
                  "normal impact at 5 m/s, no 'restitution' parameter: |v_out|/|v_in| <= bound");
  });

  // The tangential change is measured against the surface normal where each
  // drop hit, which a curved or faceted obstacle (sphere, box) varies: the
  // direction in which respond() puts back a particle at rest just inside
  // that point.
  auto local_normal = [&](const Drop& dr) -> std::optional<Vec3> {
    State s = make_state(1);
    s.x.col(0) = dr.contact_point + 1e-3 * dr.direction;
    const Vec3 before = s.x.col(0);
    MutableParticleView view = s.mutable_view();
    c.respond(view, 1e-3);
    const Vec3 moved = Vec3(s.x.col(0)) - before;
    if (moved.norm() <= kInsideTolerance) return std::nullopt;
    return moved.normalized();
  };
  guarded(out, "collider.frictionless_tangential", [&] {
    double worst = 0;
    int oblique = 0;
    for (const auto& dr : drops) {
      if (!dr.hit) continue;
      const auto m = local_normal(dr);
      if (!m || std::abs(dr.direction.dot(*m)) > 1 - 1e-9 || dr.direction.dot(*m) >= 0) continue;
      ++oblique;
      const Vec3 dv = dr.v_out - dr.v_in;
      worst = std::max(worst, (dv - dv.dot(*m) * *m).norm());
    }
    if (oblique == 0) return skip("collider.frictionless_tangential", "no oblique impact");
    return result(
        "collider.frictionless_tangential", worst <= 1e-12 * 5.0, worst, 1e-12 * 5.0,
        fmt::format("{} oblique impacts at 5 m/s: |tangential change of v|, m/s", oblique));
  });

  guarded(out, "collider.contact_force_normal_only", [&] {
    // A particle at rest on the surface where the normal impact happened.
    State s = make_state(1);
    s.x.col(0) = normal->contact_point;
    const Vec3 t = n.unitOrthogonal();
    double worst = 0;
    for (double push : {-1.0, 1.0}) {
      Matrix3X f(3, 1);
      f.col(0) = 10.0 * push * n + 3.0 * t;
      const Vec3 expected = push < 0 ? Vec3(3.0 * t) : Vec3(f.col(0));
      c.apply_contact_forces(s.view(), f);
      worst = std::max(worst, (Vec3(f.col(0)) - expected).norm());
    }
    return result("collider.contact_force_normal_only", worst <= 1e-12 * 10.0, worst, 1e-12 * 10.0,
                  "resting on the surface: pushing 10 N in + 3 N along -> 3 N along; pulling "
                  "unchanged; error, N");
  });
}

}  // namespace

void collider_checks(const PluginDescriptor& d, const Options& o, std::vector<CheckResult>& out) {
  std::mt19937_64 rng(o.seed);
  const State home = random_state(rng);
  Params params = sample_params(d, kParticles);
  // Frictionless, so that the tangential check applies.
  for (const auto& spec : d.params) {
    if (spec.name == "friction" && spec.type == ParamType::Real) params.set("friction", 0.0);
  }
  auto make = [&] {
    return std::shared_ptr<Collider>(d.create_collider(params, context_of(home)));
  };
  std::shared_ptr<Collider> c;
  guarded(out, "construct.defaults", [&] {
    c = make();
    return result("construct.defaults", c != nullptr, c ? 1 : 0, 1,
                  c ? "created with defaults" : "factory returned null");
  });
  if (!c) return;

  basic_collider_checks(*c, make, rng, home, out);
  const std::optional<Vec3> target = find_obstacle(*c, out);
  if (!target) return;
  const std::vector<Drop> drops = drop_checks(*c, *target, out);
  const Drop* normal = normal_impact(drops);
  if (!normal) {
    out.push_back(
        result("collider.restitution", false, 0, 0, "no axis-aligned drop was a normal impact"));
    return;
  }
  impact_checks(*c, d, params, drops, normal, out);
}

}  // namespace pdyn::conformance::detail
