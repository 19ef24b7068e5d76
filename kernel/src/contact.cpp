// Witkin's collision and contact rules for a surface given by a signed
// distance and an outward normal (pdyn/contact.hpp has the equations).
//
// The frictionless path performs exactly the floating-point operations of
// the original plane collider, in the same order, so that scenes written
// before friction existed run bit-identically; every friction term sits
// behind `mu > 0`.
#include "pdyn/contact.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>

namespace pdyn {

std::vector<ParamSpec> with_contact_params(std::vector<ParamSpec> specs) {
  const ContactModel fallback;
  const ParamSpec contact[] = {
      param::real("restitution", fallback.restitution, "", "coefficient of restitution kr")
          .at_least(0)
          .at_most(1),
      param::real("friction", fallback.friction, "", "Coulomb friction coefficient mu").at_least(0),
      param::real("epsilon", fallback.epsilon, "m, m/s", "contact tolerance on distance and speeds")
          .greater_than(0),
  };
  specs.insert(specs.end(), std::begin(contact), std::end(contact));
  return specs;
}

ContactModel ContactModel::from_params(const Params& p) {
  return {p.real("restitution"), p.real("friction"), p.real("epsilon")};
}

ContactLoad apply_contact_force(const ContactModel& model, const SurfacePoint& s, const Vec3& v,
                                Vec3& f) {
  const Vec3& n = s.normal;
  const double fn = n.dot(f);
  if (!(fn < 0.0 && s.distance < model.epsilon && std::abs(n.dot(v)) < model.epsilon)) return {};
  f -= fn * n;  // F' = F_T: the wall pushes back with -F_N
  ContactLoad load{-fn, 0.0};
  const double mu = model.friction;
  if (mu > 0.0) {
    load.tangential = f.norm();
    const double limit = mu * load.normal;  // mu |F_N|, N
    const Vec3 vt = v - n.dot(v) * n;
    const double speed = vt.norm();
    if (speed > model.epsilon) {
      f -= (limit / speed) * vt;  // kinetic: opposes the slide
    } else if (load.tangential <= limit) {
      f.setZero();  // static: the wall holds the particle (F_N already cancelled)
    } else {
      f -= (limit / load.tangential) * f;  // static limit exceeded: starts to slide
    }
  }
  return load;
}

void respond_to_contact(const ContactModel& model, const SurfacePoint& s, double mass,
                        const Vec3& f, const ContactLoad& load, double h, Vec3& x, Vec3& v) {
  const double depth = s.distance;
  if (depth >= model.epsilon) return;
  const Vec3& n = s.normal;
  const double mu = model.friction;
  const double vn = n.dot(v);
  if (vn < 0.0) {
    const double an = std::min(0.0, n.dot(f) / mass);
    const double vn_out = model.restitution * -vn;
    // V_N' = -kr V_N, or 0 for a bounce the step cannot resolve (resting rule).
    const double target = vn_out < -an * h ? 0.0 : vn_out;
    if (mu > 0.0) {
      // Coulomb: the tangential impulse is at most mu times the normal one,
      // and stops the slide rather than reversing it.
      const Vec3 vt = v - vn * n;
      const double speed = vt.norm();
      if (speed > 0.0) v -= (std::min(speed, mu * (target - vn)) / speed) * vt;
    }
    v += (target - vn) * n;
  }
  if (depth < 0.0) x -= depth * n;  // put back onto the surface
  if (mu > 0.0 && load.normal > 0.0 && load.tangential <= mu * load.normal) {
    const double vn_after = n.dot(v);
    if (std::abs(vn_after) < model.epsilon) {
      const Vec3 vt = v - vn_after * n;
      // The least speed friction removes in one step: the slide ends within
      // the next step, which cannot resolve the moment it stops. Stick.
      if (vt.norm() <= (mu * load.normal - load.tangential) * h / mass) v -= vt;
    }
  }
}

void SurfaceCollider::apply_contact_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) {
  const int count = surface_count();
  const Index n = p.size();
  const bool keep = model_.friction > 0.0;
  if (keep && loads_.size() != static_cast<std::size_t>(count * n)) {
    loads_.assign(static_cast<std::size_t>(count * n), ContactLoad{});
  }
  for (Index i = 0; i < n; ++i) {
    if (p.fixed[i]) continue;
    const Vec3 x = p.x.col(i), v = p.v.col(i);
    for (int k = 0; k < count; ++k) {
      Vec3 fi = f.col(i);
      const ContactLoad load = apply_contact_force(model_, surface(x, k), v, fi);
      f.col(i) = fi;
      if (keep) loads_[static_cast<std::size_t>(k * n + i)] = load;
    }
  }
}

void SurfaceCollider::respond(MutableParticleView& p, double h) {
  const int count = surface_count();
  const Index n = p.size();
  // Loads from an evaluation of this many particles, else none (a response
  // without a preceding evaluation cannot stick anything).
  const bool have_loads =
      model_.friction > 0.0 && loads_.size() == static_cast<std::size_t>(count * n);
  for (Index i = 0; i < n; ++i) {
    if (p.fixed[i]) continue;
    Vec3 x = p.x.col(i), v = p.v.col(i);
    const Vec3 f = p.f.col(i);
    for (int k = 0; k < count; ++k) {
      const ContactLoad load =
          have_loads ? loads_[static_cast<std::size_t>(k * n + i)] : ContactLoad{};
      respond_to_contact(model_, surface(x, k), p.mass(i), f, load, h, x, v);
    }
    p.x.col(i) = x;
    p.v.col(i) = v;
  }
}

}  // namespace pdyn
