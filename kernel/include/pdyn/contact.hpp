// pdyn/contact.hpp — Witkin's collision and contact rules, for any obstacle
// given by a signed distance and an outward normal.
//
// Witkin's point-plane rules (SIGGRAPH '97 notes, "Bouncing off the Walls")
// only need, at the particle's position X, the distance to the surface and
// the surface normal there. A collider that supplies those two gets the whole
// response from this header: restitution, resting contact, put-back, and
// Coulomb friction. The shipped plane, sphere and box colliders are built on
// it; so can a third-party collider.
//
// With N the outward unit normal, V_N = (N . V) N, V_T = V - V_N, F likewise,
// kr the restitution, mu the friction coefficient and eps the tolerance:
//
// Collision, after each step of length h (respond_to_contact):
//   a particle with d < eps heading in (N . V < 0) gets the normal velocity
//   V_N' = -kr V_N, or V_N' = 0 when kr |N . V| < |a_N| h (a bounce the step
//   cannot resolve, which would land again within the next step: the
//   resting rule, so that a dropped ball comes to rest instead of micro-
//   bouncing at ~|g| h forever). The normal impulse per unit mass is
//   j = |V_N' - V_N|; friction removes min(|V_T|, mu j) of the tangential
//   speed (Coulomb: tangential impulse <= mu times the normal impulse, never
//   reversing V_T). A particle with d < 0 is moved back along N by -d.
//   Then, for a particle in resting contact (d < eps, |N . V| < eps) that
//   was pressed on in the step's last force evaluation with |F_T| <= mu
//   |F_N|: if |V_T| <= (mu |F_N| - |F_T|) h / m, the least speed friction
//   takes away in one step, the slide would stop (and reverse) within the
//   next step, which the step cannot resolve: V_T is set to 0 (sticking).
//   This is the tangential twin of the resting rule; it stops a sliding
//   block exactly, without jitter around V_T = 0.
//
// Contact, during each derivative evaluation (apply_contact_force):
//   a particle with d < eps, |N . V| < eps and N . F < 0 has F_N cancelled,
//   F' = F_T ("Contact Force"). With mu > 0, the normal load |F_N| also
//   produces friction: kinetic, -mu |F_N| V_T / |V_T|, when |V_T| > eps;
//   static when |V_T| <= eps: F_T is cancelled if |F_T| <= mu |F_N| (the
//   particle is held), else reduced by mu |F_N| along F_T.
//
// With mu = 0 every friction term is skipped, and the result is bit-
// identical to the frictionless rules above.
#pragma once

#include <vector>

#include "pdyn/collider.hpp"
#include "pdyn/export.hpp"
#include "pdyn/params.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

/// The material of a contact: the parameters of Witkin's rules.
struct PDYN_API ContactModel {
  double restitution = 0.5;  ///< coefficient of restitution kr, in [0, 1]; 1 elastic, 0 inelastic
  double friction = 0.0;     ///< Coulomb friction coefficient mu, >= 0 (0.3 ~ wood on wood)
  double epsilon = 1e-4;     ///< contact tolerance, m on the distance and m/s on speeds

  /// The model named by the parameters that contact_params() declares.
  static ContactModel from_params(const Params& p);
};

/// The parameters of a ContactModel, declared once for every collider:
/// restitution in [0, 1], friction >= 0 and epsilon > 0, with the defaults
/// above, after the collider's own `specs`:
///   d.params = pdyn::with_contact_params({pdyn::param::vec3("point", ...), ...});
/// and ContactModel::from_params(p) in create_collider.
PDYN_API std::vector<ParamSpec> with_contact_params(std::vector<ParamSpec> specs);

/// The obstacle's surface as seen from one point X.
struct PDYN_API SurfacePoint {
  /// Signed distance from X to the surface, m: > 0 on the free side, < 0
  /// inside the obstacle. Its magnitude must be exact near the surface
  /// (|d| < a step's travel): put-back moves X by -d N.
  double distance = 0.0;
  /// Unit outward normal of the surface nearest X, pointing to the free side.
  Vec3 normal = Vec3::UnitZ();
};

/// What one contact-force evaluation saw: the load that the collision
/// response's sticking rule needs (the response only sees forces after the
/// contact force has cancelled F_N).
struct PDYN_API ContactLoad {
  double normal = 0.0;      ///< |F_N| cancelled by the contact force, N; 0: not in contact
  double tangential = 0.0;  ///< |F_T| of the applied force (before friction), N
};

/// Contact force on one free particle with velocity `v` (m/s), during a
/// derivative evaluation: modifies the total force `f` (N) as described
/// above and returns the load it found (zero when not in contact).
PDYN_API ContactLoad apply_contact_force(const ContactModel& model, const SurfacePoint& s,
                                         const Vec3& v, Vec3& f);

/// Collision response for one free particle of mass `mass` (kg) after an
/// accepted step of `h` (s): updates position `x` (m) and velocity `v`
/// (m/s). `f` (N) is the particle's force from the step's last derivative
/// evaluation and `load` what apply_contact_force returned in it.
PDYN_API void respond_to_contact(const ContactModel& model, const SurfacePoint& s, double mass,
                                 const Vec3& f, const ContactLoad& load, double h, Vec3& x,
                                 Vec3& v);

/// A collider whose obstacle is described by one or more surfaces (e.g. the
/// six walls of a box seen from inside), each a signed distance function.
/// Implements both Collider hooks with the rules above; the subclass
/// supplies only the geometry. A particle is outside the obstacle when it is
/// on the free side of every surface. Fixed particles are ignored.
class PDYN_API SurfaceCollider : public Collider {
 public:
  explicit SurfaceCollider(const ContactModel& model) : model_(model) {}

  /// Number of surfaces (>= 1), constant for the object's lifetime.
  virtual int surface_count() const noexcept { return 1; }
  /// Surface `k` (0 <= k < surface_count()) as seen from `x` (m). Called for
  /// every free particle in every derivative evaluation and response: keep
  /// it cheap and free of allocation. Must be finite for every finite x.
  virtual SurfacePoint surface(const Vec3& x, int k) const = 0;

  void apply_contact_forces(const ParticleView& p, Eigen::Ref<Matrix3X> f) override;
  void respond(MutableParticleView& p, double h) override;

  const ContactModel& model() const noexcept { return model_; }

 private:
  ContactModel model_;
  // Loads of the last contact-force evaluation, surface_count() x N, kept
  // only when mu > 0 (the sticking rule needs them). Scratch, not state:
  // every step evaluates forces before its response rewrites it, so a
  // resumed run does not need it in its checkpoint.
  std::vector<ContactLoad> loads_;
};

}  // namespace pdyn
