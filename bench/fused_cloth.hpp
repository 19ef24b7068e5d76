// The hand-fused reference for bench/cloth.cpp: the hanging cloth of
// tests/scenes/shared/cloth.yaml (a grid with structural and shear springs,
// gravity, drag, two pinned top corners) stepped with classic rk4, written
// as the fastest straightforward single-threaded code (issue 46). The
// tricks, each one measured in docs/performance.md ("The fused reference"):
//
// - one struct, structure of arrays (positions, velocities, forces, masses
//   each one flat array, x y z of a particle adjacent, the layout pdyn's
//   store has), no virtual calls, no plugin boundary, 32-bit spring indices;
// - one pass per spring family (structural, shear) with its constants in
//   registers;
// - the damped spring with one division: 1/|l| once, both terms scaled by it;
// - gravity, drag and f/m fused into one pass over the particles, and that
//   pass also does the rk4 stage's arithmetic (the weighted sum and the next
//   stage's state) from the slope held in registers: no slope array, no
//   separate axpy passes, the force array cleared as it is read;
// - the start-of-step copy y0 made in the first stage's pass.
//
// The physics is exactly pdyn's: Witkin's damped spring (SIGGRAPH '97
// notes, "Damped Spring"), f = m g, f = -k v, fixed particles held by a
// zero inverse mass, rk4 with the stage sum k1 + 2 k2 + 2 k3 + k4
// accumulated as pdyn's plugin does. The reciprocal form rounds differently
// from pdyn's spring, so the two agree to a few ulps per step, not to the
// bit; bench/cloth.cpp checks 1e-12 over the whole state before timing.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

namespace pdyn::bench {

/// Parameters of the cloth; the defaults are tests/scenes/shared/cloth.yaml's.
struct ClothSpec {
  int nx = 100, ny = 100;
  double spacing = 0.01;                              // m
  double origin[3] = {-0.495, 0.0, 1.01};             // m; u along x, v along z
  double mass = 0.0001;                               // kg per particle
  double velocity[3] = {0.0, 1.0, 0.0};               // m/s, the gust
  double g[3] = {0.0, 0.0, -9.81};                    // m/s^2
  double drag = 0.00001;                              // kg/s
  double ks_structural = 1000, kd_structural = 0.02;  // N/m, N s/m
  double ks_shear = 500, kd_shear = 0.01;
};

class FusedCloth {
 public:
  explicit FusedCloth(const ClothSpec& c) : spec_(c), n_(c.nx * c.ny) {
    const std::size_t n = static_cast<std::size_t>(n_);
    y_.resize(6 * n);
    m_.assign(n, c.mass);
    inv_m_.assign(n, 1.0 / c.mass);
    f_.resize(3 * n);
    y0_.resize(6 * n);
    sum_.resize(6 * n);
    auto id = [&](int i, int j) { return j * c.nx + i; };
    for (int j = 0; j < c.ny; ++j) {
      for (int i = 0; i < c.nx; ++i) {
        double* x = &y_[3 * static_cast<std::size_t>(id(i, j))];
        x[0] = c.origin[0] + i * c.spacing;
        x[1] = c.origin[1];
        x[2] = c.origin[2] + j * c.spacing;
        double* v = &y_[3 * (n + static_cast<std::size_t>(id(i, j)))];
        for (int d = 0; d < 3; ++d) v[d] = c.velocity[d];
      }
    }
    // The two top corners are nailed: zero velocity, zero inverse mass.
    for (int p : {id(0, c.ny - 1), id(c.nx - 1, c.ny - 1)}) {
      inv_m_[static_cast<std::size_t>(p)] = 0.0;
      for (int d = 0; d < 3; ++d) y_[3 * (n + static_cast<std::size_t>(p)) + d] = 0.0;
    }
    // The grid builder's order: structural, then shear, row by row.
    for (int j = 0; j < c.ny; ++j) {
      for (int i = 0; i < c.nx; ++i) {
        if (i + 1 < c.nx) structural_.add(id(i, j), id(i + 1, j));
        if (j + 1 < c.ny) structural_.add(id(i, j), id(i, j + 1));
      }
    }
    for (int j = 0; j < c.ny; ++j) {
      for (int i = 0; i < c.nx; ++i) {
        if (i + 1 < c.nx && j + 1 < c.ny) {
          shear_.add(id(i, j), id(i + 1, j + 1));
          shear_.add(id(i + 1, j), id(i, j + 1));
        }
      }
    }
    structural_.rest_from(y_.data());
    shear_.rest_from(y_.data());
  }

  int size() const { return n_; }
  std::size_t springs() const { return structural_.i.size() + shear_.i.size(); }
  std::vector<double>& state() { return y_; }

  /// dy/dt = [v | f/m] at the state `y` (6N), written into `dydt` (for Odeint's stepper).
  void derivative(const double* y, double* dydt) {
    const std::size_t n = static_cast<std::size_t>(n_);
    const double* x = y;
    const double* v = y + 3 * n;
    structural_.add_forces(x, v, f_.data(), spec_.ks_structural, spec_.kd_structural);
    shear_.add_forces(x, v, f_.data(), spec_.ks_shear, spec_.kd_shear);
    const double gx = spec_.g[0], gy = spec_.g[1], gz = spec_.g[2], k = spec_.drag;
    double* dx = dydt;
    double* dv = dydt + 3 * n;
    for (std::size_t p = 0; p < n; ++p) {
      const double m = m_[p], w = inv_m_[p];
      dv[3 * p + 0] = ((f_[3 * p + 0] + gx * m) - k * v[3 * p + 0]) * w;
      dv[3 * p + 1] = ((f_[3 * p + 1] + gy * m) - k * v[3 * p + 1]) * w;
      dv[3 * p + 2] = ((f_[3 * p + 2] + gz * m) - k * v[3 * p + 2]) * w;
      dx[3 * p + 0] = v[3 * p + 0];
      dx[3 * p + 1] = v[3 * p + 1];
      dx[3 * p + 2] = v[3 * p + 2];
      f_[3 * p + 0] = f_[3 * p + 1] = f_[3 * p + 2] = 0.0;  // zero between calls
    }
  }

  /// One classic rk4 step of h seconds, fused by hand (the tricks are in the
  /// file's head): per stage, the two spring passes, then one pass over the
  /// particles that makes the stage's slope k = [v | a] in registers and
  /// folds it at once into the weighted sum and the next stage's state.
  void step(double h) {
    springs(y_.data());
    stage<Stage::first>(0.5 * h);
    springs(y_.data());
    stage<Stage::middle>(0.5 * h);
    springs(y_.data());
    stage<Stage::middle>(h);
    springs(y_.data());
    stage<Stage::last>(h / 6.0);
  }

 private:
  enum class Stage { first, middle, last };

  void springs(const double* y) {
    const double* v = y + 3 * static_cast<std::size_t>(n_);
    structural_.add_forces(y, v, f_.data(), spec_.ks_structural, spec_.kd_structural);
    shear_.add_forces(y, v, f_.data(), spec_.ks_shear, spec_.kd_shear);
  }

  // One particle pass of rk4 (Butcher tableau 1/2, 1/2, 1; weights 1, 2, 2, 1
  // over 6): a = ((f + m g) - k v) / m (f = m g, f = -k v, Witkin's gravity
  // and drag) and the stage's k = [v | a]; the first stage keeps y0 and starts
  // the sum, the middle ones add 2 k, the last adds k and steps y0 + h/6 sum
  // (pdyn's rk4 sums k1 + 2 k2 + 2 k3 + k4 the same way). `c` is the stage's
  // h/2, h or h/6. The force array is cleared as it is read, for the next
  // stage's springs: no separate pass zeroes it.
  template <Stage S>
  void stage(double c) {
    const std::size_t n = static_cast<std::size_t>(n_);
    double* x = y_.data();
    double* v = x + 3 * n;
    double* x0 = y0_.data();
    double* v0 = x0 + 3 * n;
    double* sx = sum_.data();
    double* sv = sx + 3 * n;
    double* f = f_.data();
    const double g[3] = {spec_.g[0], spec_.g[1], spec_.g[2]};
    const double k = spec_.drag;
    for (std::size_t p = 0; p < n; ++p) {
      const double m = m_[p], w = inv_m_[p];
      for (std::size_t d = 0; d < 3; ++d) {
        const std::size_t e = 3 * p + d;
        const double kx = v[e];
        const double kv = ((f[e] + g[d] * m) - k * v[e]) * w;
        f[e] = 0.0;
        if constexpr (S == Stage::first) {
          x0[e] = x[e];
          v0[e] = v[e];
          sx[e] = kx;
          sv[e] = kv;
          x[e] = x0[e] + c * kx;
          v[e] = v0[e] + c * kv;
        } else if constexpr (S == Stage::middle) {
          sx[e] += 2.0 * kx;
          sv[e] += 2.0 * kv;
          x[e] = x0[e] + c * kx;
          v[e] = v0[e] + c * kv;
        } else {
          x[e] = x0[e] + c * (sx[e] + kx);
          v[e] = v0[e] + c * (sv[e] + kv);
        }
      }
    }
  }

  struct Family {
    std::vector<std::int32_t> i, j;
    std::vector<double> rest;  // m
    void add(int a, int b) {
      i.push_back(a);
      j.push_back(b);
    }
    void rest_from(const double* x) {
      rest.resize(i.size());
      for (std::size_t s = 0; s < i.size(); ++s) {
        const double* a = x + 3 * i[s];
        const double* b = x + 3 * j[s];
        const double d0 = a[0] - b[0], d1 = a[1] - b[1], d2 = a[2] - b[2];
        rest[s] = std::sqrt(d0 * d0 + d1 * d1 + d2 * d2);
      }
    }
    void add_forces(const double* x, const double* v, double* f, double ks, double kd) const {
      const std::size_t ns = i.size();
      for (std::size_t s = 0; s < ns; ++s) {
        const std::size_t a = 3 * static_cast<std::size_t>(i[s]);
        const std::size_t b = 3 * static_cast<std::size_t>(j[s]);
        const double d0 = x[a] - x[b], d1 = x[a + 1] - x[b + 1], d2 = x[a + 2] - x[b + 2];
        const double len = std::sqrt(d0 * d0 + d1 * d1 + d2 * d2);
        if (len == 0.0) continue;
        // One division: Witkin's -(ks (|l| - r) + kd (l' . l) / |l|) l / |l|
        // as -(ks (|l| - r) / |l| + kd (l' . l) / |l|^2) l.
        const double inv = 1.0 / len;
        const double w0 = v[a] - v[b], w1 = v[a + 1] - v[b + 1], w2 = v[a + 2] - v[b + 2];
        const double c =
            -(ks * (len - rest[s]) * inv + kd * (w0 * d0 + w1 * d1 + w2 * d2) * (inv * inv));
        const double f0 = c * d0, f1 = c * d1, f2 = c * d2;
        f[a] += f0;
        f[a + 1] += f1;
        f[a + 2] += f2;
        f[b] -= f0;
        f[b + 1] -= f1;
        f[b + 2] -= f2;
      }
    }
  };

  ClothSpec spec_;
  int n_;
  std::vector<double> y_, m_, inv_m_, f_;  // state [x | v] (6N), masses, 1/m (0: nailed), forces
  std::vector<double> y0_, sum_;           // rk4 scratch, 6N each
  Family structural_, shear_;
};

}  // namespace pdyn::bench
