// pdyn/domain.hpp — the simulation box: open space, or a box periodic along
// some axes (simulation.box in a scene).
//
// Along a periodic axis the system repeats with the box's length L: a
// particle leaving through max re-enters at min (the kernel wraps positions
// after each accepted step), and a force measures the separation of two
// particles to the nearest image of the other (minimum_image). Bonded
// terms (pdyn/bonded_force.hpp) place each particle of a term at its image
// nearest the term's first particle (nearest_image), so a spring, angle or
// dihedral may cross a periodic face.
#pragma once

#include <array>
#include <cmath>

#include "pdyn/export.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

/// The simulation box. Along a periodic axis a particle leaving through max
/// re-enters at min, and distances are measured to the nearest image. Along
/// any other axis space is open and min / max are not used by the neighbor
/// list. The default Domain (nothing periodic) is unbounded open space.
struct PDYN_API Domain {
  Vec3 min = Vec3::Zero();         ///< lower corner, m
  Vec3 max = Vec3::Zero();         ///< upper corner, m (> min along periodic axes)
  std::array<bool, 3> periodic{};  ///< per axis x, y, z: periodic or open

  /// Edge lengths max - min, m.
  Vec3 length() const { return max - min; }

  /// The separation d (m) of two particles, reduced to its nearest periodic
  /// image: d_k -= L_k round(d_k / L_k) along periodic axes, so |d_k| <= L_k / 2
  /// (the minimum-image convention, Allen & Tildesley sec. 1.5.2). Unchanged
  /// along open axes.
  Vec3 minimum_image(Vec3 d) const {
    for (int k = 0; k < 3; ++k) {
      if (periodic[k]) {
        const double L = max[k] - min[k];
        d[k] -= L * std::round(d[k] / L);
      }
    }
    return d;
  }

  /// The image of position x (m) nearest to position `ref` (m): x moved by
  /// whole box lengths along periodic axes so that |x_k - ref_k| <= L_k / 2,
  /// as LAMMPS's Domain::closest_image places a bond's partner. Unchanged,
  /// bit for bit, along open axes and where x is the nearest image already,
  /// so a bonded term away from the faces measures what it measured without
  /// a box (ref + minimum_image(x - ref) would round differently).
  Vec3 nearest_image(Vec3 x, const Vec3& ref) const {
    for (int k = 0; k < 3; ++k) {
      if (periodic[k]) {
        const double L = max[k] - min[k];
        const double n = std::round((x[k] - ref[k]) / L);
        if (n != 0.0) x[k] -= n * L;
      }
    }
    return x;
  }

  /// The position x (m) brought into [min, max) along periodic axes by a whole
  /// number of box lengths; unchanged along open axes, and unchanged where it
  /// is inside the box already (bit for bit). A non-finite coordinate stays
  /// non-finite.
  Vec3 wrap(Vec3 x) const {
    for (int k = 0; k < 3; ++k) {
      if (!periodic[k] || (x[k] >= min[k] && x[k] < max[k])) continue;
      const double L = max[k] - min[k];
      double w = x[k] - L * std::floor((x[k] - min[k]) / L);
      // Rounding can land a hair outside [min, max): one box length fixes it.
      if (w < min[k]) w += L;
      if (w >= max[k]) w = min[k];
      x[k] = w;
    }
    return x;
  }

  /// Same box: equal corners and the same periodic axes.
  bool operator==(const Domain& other) const {
    return min == other.min && max == other.max && periodic == other.periodic;
  }

  /// True when some axis is periodic.
  bool any_periodic() const { return periodic[0] || periodic[1] || periodic[2]; }
};

}  // namespace pdyn
