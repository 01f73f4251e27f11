// The shared statistics (analysis/statistics.hpp): a line through exact points is recovered with
// no residual, the slope's standard error follows the textbook formula on a small noisy set, and
// the sample standard deviation divides by n - 1.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "analysis/statistics.hpp"

namespace sandflow {
namespace {

TEST(Statistics, MeanAndSampleStandardDeviation) {
  EXPECT_TRUE(std::isnan(mean({})));
  EXPECT_DOUBLE_EQ(mean({1, 2, 3, 6}), 3.0);
  EXPECT_DOUBLE_EQ(standard_deviation({5}), 0.0);
  // deviations -2, -1, 0, 3: squares 14 over n - 1 = 3
  EXPECT_DOUBLE_EQ(standard_deviation({1, 2, 3, 6}), std::sqrt(14.0 / 3.0));
}

TEST(Statistics, ExactLineHasNoResidualAndItsDescentAngle) {
  const double t = std::tan(deg_to_rad(33.0));
  std::vector<double> x, y;
  for (int k = 0; k < 10; ++k) {
    x.push_back(0.1 * k);
    y.push_back(0.5 - t * 0.1 * k);
  }
  const LineFit f = fit_line(x, y);
  EXPECT_NEAR(f.slope, -t, 1e-12);
  EXPECT_NEAR(f.intercept, 0.5, 1e-12);
  EXPECT_NEAR(f.rms(), 0.0, 1e-12);
  EXPECT_NEAR(f.descent_deg(), 33.0, 1e-9);
  EXPECT_NEAR(f.descent_se_deg(), 0.0, 1e-9);
}

TEST(Statistics, SlopeStandardErrorOnNoisyPoints) {
  // y = 2x + e with residuals e = +1, -1, -1, +1 at x = 0..3: the fitted slope stays 2 (e is
  // orthogonal to x - mean), sse = 4, sxx = 5, so se = sqrt(4 / 2 / 5)
  const LineFit f = fit_line({0, 1, 2, 3}, {1, 1, 3, 7});
  EXPECT_NEAR(f.slope, 2.0, 1e-12);
  EXPECT_NEAR(f.sse, 4.0, 1e-12);
  EXPECT_NEAR(f.slope_se(), std::sqrt(0.4), 1e-12);
  EXPECT_NEAR(f.rms(), 1.0, 1e-12);
}

}  // namespace
}  // namespace sandflow
