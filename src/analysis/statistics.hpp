// The few statistics the measurements share: means, medians, sample standard deviations and a
// least-squares line with its slope's standard error.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/vec3.hpp"

namespace sandflow {

/// Mean of the values (NaN when there are none).
inline double mean(const std::vector<double>& v) {
  if (v.empty()) return std::nan("");
  double s = 0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

/// Median of v (reordered; v not empty); the mean of the two middle values for an even count.
inline double median(std::vector<double>& v) {
  const std::size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + m, v.end());
  const double upper = v[m];
  if (v.size() % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(v.begin(), v.begin() + m));
}

/// Sample standard deviation (n - 1); 0 for fewer than two values.
inline double standard_deviation(const std::vector<double>& v) {
  if (v.size() < 2) return 0;
  const double m = mean(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}

/// y = intercept + slope x by least squares over the points (x[k], y[k]).
struct LineFit {
  double slope = 0, intercept = 0;
  double sse = 0;  ///< sum of the squared residuals
  std::size_t n = 0;
  double rms() const { return n ? std::sqrt(sse / static_cast<double>(n)) : 0.0; }
  /// Standard error of the slope (needs n > 2).
  double slope_se() const { return std::sqrt(sse / (static_cast<double>(n) - 2) / sxx); }
  /// The angle below the horizontal of a line descending in x, and its standard error carried
  /// through atan [deg].
  double descent_deg() const { return rad_to_deg(std::atan(-slope)); }
  double descent_se_deg() const { return rad_to_deg(slope_se() / (1 + slope * slope)); }
  double sxx = 0;  ///< sum of (x - mean x)^2
};

/// Fits the line; the points are summed in their order, so the result follows it bit for bit.
inline LineFit fit_line(const std::vector<double>& x, const std::vector<double>& y) {
  LineFit f;
  f.n = x.size();
  if (f.n == 0) return f;
  double mx = 0, my = 0;
  for (std::size_t k = 0; k < f.n; ++k) {
    mx += x[k];
    my += y[k];
  }
  mx /= static_cast<double>(f.n);
  my /= static_cast<double>(f.n);
  double sxy = 0;
  for (std::size_t k = 0; k < f.n; ++k) {
    f.sxx += (x[k] - mx) * (x[k] - mx);
    sxy += (x[k] - mx) * (y[k] - my);
  }
  f.slope = sxy / f.sxx;
  f.intercept = my - f.slope * mx;
  for (std::size_t k = 0; k < f.n; ++k) {
    const double e = y[k] - (f.intercept + f.slope * x[k]);
    f.sse += e * e;
  }
  return f;
}

}  // namespace sandflow
