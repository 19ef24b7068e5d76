// The hand-fused reference for bench/cloth.cpp: the hanging cloth of
// tests/scenes/shared/cloth.yaml (a grid with structural and shear springs,
// gravity, drag, two pinned top corners) stepped with classic rk4, written
// as the fastest straightforward single-threaded code: one struct, structure
// of arrays (positions, velocities, forces, masses each one flat array,
// x y z of a particle adjacent, the layout pdyn's store has), no virtual
// calls, no plugin boundary, 32-bit spring indices, one pass per spring
// family with its constants in registers, and gravity, drag and f/m fused
// into one pass over the particles.
//
// The physics is exactly pdyn's: Witkin's damped spring (SIGGRAPH '97
// notes, "Damped Spring"), f = m g, f = -k v, fixed particles held by a
// zero inverse mass, rk4 with the stage sum accumulated as pdyn's plugin
// does. The order of the floating-point additions into each particle's
// force is pdyn's too (springs in the order the grid builder makes them,
// then gravity, then drag), so the two agree to rounding.
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
    k_.resize(6 * n);
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

  /// dy/dt = [v | f/m] at the state `y` (6N), written into `dydt`.
  void derivative(const double* y, double* dydt) {
    const std::size_t n = static_cast<std::size_t>(n_);
    const double* x = y;
    const double* v = y + 3 * n;
    std::fill(f_.begin(), f_.end(), 0.0);
    structural_.add_forces(x, v, f_.data(), spec_.ks_structural, spec_.kd_structural);
    shear_.add_forces(x, v, f_.data(), spec_.ks_shear, spec_.kd_shear);
    const double gx = spec_.g[0], gy = spec_.g[1], gz = spec_.g[2], k = spec_.drag;
    double* dx = dydt;
    double* dv = dydt + 3 * n;
    for (std::size_t p = 0; p < n; ++p) {
      const double m = m_[p], w = inv_m_[p];
      // ((f + m g) - k v) / m, the additions in pdyn's order.
      dv[3 * p + 0] = ((f_[3 * p + 0] + gx * m) - k * v[3 * p + 0]) * w;
      dv[3 * p + 1] = ((f_[3 * p + 1] + gy * m) - k * v[3 * p + 1]) * w;
      dv[3 * p + 2] = ((f_[3 * p + 2] + gz * m) - k * v[3 * p + 2]) * w;
      dx[3 * p + 0] = v[3 * p + 0];
      dx[3 * p + 1] = v[3 * p + 1];
      dx[3 * p + 2] = v[3 * p + 2];
    }
  }

  /// One rk4 step of h seconds (pdyn's rk4 plugin, fused by hand).
  void step(double h) {
    const std::size_t d = y_.size();
    double* y = y_.data();
    double *y0 = y0_.data(), *k = k_.data(), *sum = sum_.data();
    for (std::size_t e = 0; e < d; ++e) y0[e] = y[e];
    derivative(y, k);
    for (std::size_t e = 0; e < d; ++e) {
      sum[e] = k[e];
      y[e] = y0[e] + (0.5 * h) * k[e];
    }
    derivative(y, k);
    for (std::size_t e = 0; e < d; ++e) {
      sum[e] += 2.0 * k[e];
      y[e] = y0[e] + (0.5 * h) * k[e];
    }
    derivative(y, k);
    for (std::size_t e = 0; e < d; ++e) {
      sum[e] += 2.0 * k[e];
      y[e] = y0[e] + h * k[e];
    }
    derivative(y, k);
    for (std::size_t e = 0; e < d; ++e) {
      sum[e] += k[e];
      y[e] = y0[e] + (h / 6.0) * sum[e];
    }
  }

 private:
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
        const double w0 = v[a] - v[b], w1 = v[a + 1] - v[b + 1], w2 = v[a + 2] - v[b + 2];
        const double magnitude = ks * (len - rest[s]) + kd * (w0 * d0 + w1 * d1 + w2 * d2) / len;
        const double c = -(magnitude / len);
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
  std::vector<double> y0_, k_, sum_;       // rk4 scratch, 6N each
  Family structural_, shear_;
};

}  // namespace pdyn::bench
