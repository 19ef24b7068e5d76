// Statistics for the tests of random processes (initial velocities,
// thermostats): the Kolmogorov-Smirnov distance to the standard normal
// distribution, and the standard error of a correlated series' mean by
// block averaging (Flyvbjerg & Petersen 1989).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace pdyn::test {

/// The Kolmogorov-Smirnov statistic D_n = sup |F_n(x) - Phi(x)| of the
/// sample `x` against the standard normal distribution.
inline double ks_normal(std::vector<double> x) {
  std::sort(x.begin(), x.end());
  const double n = static_cast<double>(x.size());
  double d = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    const double phi = 0.5 * std::erfc(-x[k] / std::sqrt(2.0));
    d = std::max({d, static_cast<double>(k + 1) / n - phi, phi - static_cast<double>(k) / n});
  }
  return d;
}

/// The KS test's critical distance at significance 0.01 for n samples
/// (the asymptotic 1.628 / sqrt(n), good for n > 35).
inline double ks_critical_1percent(std::size_t n) {
  return 1.628 / std::sqrt(static_cast<double>(n));
}

/// Mean of `x` and the standard error of that mean for a correlated series:
/// the series is cut into `blocks` blocks whose means are taken as
/// independent (blocks much longer than the correlation time).
struct MeanError {
  double mean = 0.0, error = 0.0;
};
inline MeanError block_average(const std::vector<double>& x, std::size_t blocks = 20) {
  const std::size_t len = x.size() / blocks;
  std::vector<double> means;
  for (std::size_t b = 0; b < blocks; ++b) {
    double s = 0.0;
    for (std::size_t k = b * len; k < (b + 1) * len; ++k) s += x[k];
    means.push_back(s / static_cast<double>(len));
  }
  MeanError out;
  for (const double m : means) out.mean += m / static_cast<double>(blocks);
  double var = 0.0;
  for (const double m : means) var += (m - out.mean) * (m - out.mean);
  out.error = std::sqrt(var / static_cast<double>(blocks - 1) / static_cast<double>(blocks));
  return out;
}

}  // namespace pdyn::test
