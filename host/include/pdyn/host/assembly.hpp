// pdyn/host/assembly.hpp — what a host does to a System that a plugin must not.
//
// A solver plugin receives a System& and should see only Witkin's solver
// interface (dimension, state, time, derivative; pdyn/system.hpp). Building
// the system (particles, forces, colliders, the box, radii, types) and the
// step's bookkeeping (wrapping into the box, collision responses, finite
// checks, restoring image counts) are the host's: System keeps them private
// and lets this class call them. Each member forwards to the System member
// of the same name, documented in pdyn/system.hpp.
//
//     pdyn::SystemAssembly(sys).add_force(force, "spring (scene.yaml:12)");
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <pdyn/system.hpp>
#include <string>
#include <utility>
#include <vector>

namespace pdyn {

class SystemAssembly {
 public:
  explicit SystemAssembly(System& sys) noexcept : sys_(sys) {}

  // ---- assembly (the scene loader, the viewer, Python, the conformance kit) ----
  void set_particles(const Matrix3X& x, const Matrix3X& v, const Eigen::VectorXd& mass,
                     const std::vector<std::uint8_t>& fixed) const {
    sys_.set_particles(x, v, mass, fixed);
  }
  Index add_particle(const Vec3& x, const Vec3& v, double mass, bool fixed = false) const {
    return sys_.add_particle(x, v, mass, fixed);
  }
  void set_fixed(Index i, bool fixed) const { sys_.set_fixed(i, fixed); }
  void add_force(std::shared_ptr<Force> force, std::string label) const {
    sys_.add_force(std::move(force), std::move(label));
  }
  bool remove_force(const Force* force) const { return sys_.remove_force(force); }
  void add_collider(std::shared_ptr<Collider> collider, std::string label) const {
    sys_.add_collider(std::move(collider), std::move(label));
  }
  bool remove_collider(const Collider* collider) const { return sys_.remove_collider(collider); }
  void set_domain(const Domain& domain) const { sys_.set_domain(domain); }
  void set_radii(std::vector<double> radius) const { sys_.set_radii(std::move(radius)); }
  void set_types(std::vector<std::int32_t> type) const { sys_.set_types(std::move(type)); }
  void add_constraint(std::shared_ptr<Constraint> constraint, std::string label,
                      double compliance = 0.0) const {
    sys_.add_constraint(std::move(constraint), std::move(label), compliance);
  }
  void set_constraint_feedback(const ConstraintFeedback& feedback) const {
    sys_.set_constraint_feedback(feedback);
  }
  void enable_constraint_force(bool on) const noexcept { sys_.enable_constraint_force(on); }

  // ---- the step's bookkeeping (the Stepper, the runner, resume) ----
  void set_images(std::vector<std::array<std::int32_t, 3>> images) const {
    sys_.set_images(std::move(images));
  }
  bool wrap_positions() const { return sys_.wrap_positions(); }
  bool wrap_positions(double* mirror) const { return sys_.wrap_positions(mirror); }
  void respond_to_collisions(double h) const { sys_.respond_to_collisions(h); }
  void set_finite_checks(bool on) const noexcept { sys_.set_finite_checks(on); }

 private:
  System& sys_;
};

}  // namespace pdyn
