// The report's SVG line plots: tick values on known ranges, tick labels, one polyline per series.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <string>

#include "html_check.hpp"
#include "report/html.hpp"
#include "report/svg_plot.hpp"

using namespace sandflow;

namespace {

std::vector<double> range(double first, double step, int n) {
  std::vector<double> v;
  for (int k = 0; k < n; ++k) v.push_back(first + k * step);
  return v;
}

}  // namespace

TEST(NiceTicks, KnownRanges) {
  // 20,000 grains in about five ticks: steps of 5,000
  Ticks t = nice_ticks(0, 20000, 5);
  EXPECT_DOUBLE_EQ(t.step, 5000);
  EXPECT_EQ(t.values, (std::vector<double>{0, 5000, 10000, 15000, 20000}));
  // [0, 1]: 1/4 = 0.25 rounds to 0.2 (the nearest of 1, 2, 5); values exact multiples
  t = nice_ticks(0, 1, 5);
  EXPECT_DOUBLE_EQ(t.step, 0.2);
  ASSERT_EQ(t.values.size(), 6u);
  EXPECT_EQ(t.values[3], 3 * 0.2);
  EXPECT_DOUBLE_EQ(t.last, 1.0);
  // the ends round outwards to the step
  t = nice_ticks(0.3, 9.7, 5);
  EXPECT_DOUBLE_EQ(t.step, 2);
  EXPECT_DOUBLE_EQ(t.first, 0);
  EXPECT_DOUBLE_EQ(t.last, 10);
  t = nice_ticks(-3, 7, 5);
  EXPECT_DOUBLE_EQ(t.step, 2);
  EXPECT_DOUBLE_EQ(t.first, -4);
  EXPECT_DOUBLE_EQ(t.last, 8);
  EXPECT_EQ(t.values[2], 0.0);
  EXPECT_FALSE(std::signbit(t.values[2]));  // no "-0"
  // a dt of 1e-4 s from zero: steps of 2e-5
  t = nice_ticks(0, 1.01e-4, 5);
  EXPECT_DOUBLE_EQ(t.step, 2e-5);
  EXPECT_DOUBLE_EQ(t.last, 1.2e-4);
}

TEST(NiceTicks, DegenerateRangesAreWidened) {
  // a constant series (dt of a run) gets an axis around its value
  Ticks t = nice_ticks(1.01e-4, 1.01e-4, 5);
  EXPECT_LT(t.first, 1.01e-4);
  EXPECT_GT(t.last, 1.01e-4);
  EXPECT_GE(t.values.size(), 2u);
  t = nice_ticks(0, 0, 5);
  EXPECT_DOUBLE_EQ(t.first, 0);
  EXPECT_DOUBLE_EQ(t.last, 1);
  t = nice_ticks(std::nan(""), 3, 5);
  EXPECT_GE(t.values.size(), 2u);
  t = nice_ticks(5, 1, 5);  // reversed
  EXPECT_LE(t.first, 1);
  EXPECT_GE(t.last, 5);
}

TEST(NiceTicks, CoverAnyRangeWithFewTicksOnTheStep) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> mant(-1, 1);
  std::uniform_int_distribution<int> expo(-8, 8);
  for (int k = 0; k < 2000; ++k) {
    const double a = mant(rng) * std::pow(10.0, expo(rng)), b = a + std::abs(mant(rng)) *
                                                                         std::pow(10.0, expo(rng));
    const Ticks t = nice_ticks(a, b, 5);
    // the ends may miss by a billionth of a step (the rounding guard in nice_ticks): far below
    // a pixel
    ASSERT_LE(t.first, a + 1e-9 * t.step) << a << " " << b;
    ASSERT_GE(t.last, b - 1e-9 * t.step) << a << " " << b;
    // at most about twice the target (the step rounds down by up to 1.5x and the ends outwards)
    ASSERT_GE(t.values.size(), 2u);
    ASSERT_LE(t.values.size(), 12u) << a << " " << b;
    // the step is 1, 2 or 5 times a power of ten
    const double m = t.step / std::pow(10.0, std::floor(std::log10(t.step) + 1e-9));
    ASSERT_TRUE(std::abs(m - 1) < 1e-9 || std::abs(m - 2) < 1e-9 || std::abs(m - 5) < 1e-9) << m;
  }
}

TEST(TickLabel, FixedWithThousandsOrScientific) {
  EXPECT_EQ(tick_label(20000, 5000), "20,000");
  EXPECT_EQ(tick_label(-1500, 500), "-1,500");
  EXPECT_EQ(tick_label(107687, 1), "107,687");
  EXPECT_EQ(tick_label(0.2, 0.2), "0.2");
  EXPECT_EQ(tick_label(3 * 0.1, 0.1), "0.3");
  EXPECT_EQ(tick_label(0.05, 0.05), "0.05");
  EXPECT_EQ(tick_label(2, 0.5), "2.0");
  EXPECT_EQ(tick_label(0, 0.5), "0");
  EXPECT_EQ(tick_label(1e-17, 0.2), "0");  // rounding noise at zero
  EXPECT_EQ(tick_label(1.2e-4, 2e-5), "1.2e-4");
  EXPECT_EQ(tick_label(4e-5, 2e-5), "4e-5");
  EXPECT_EQ(tick_label(2.5e7, 5e6), "2.5e7");
}

TEST(SvgLinePlot, OnePolylinePerSeriesWithEveryPoint) {
  LinePlot p;
  p.id = "plot-test";
  p.title = "Grains <per> frame";
  p.x_label = "t [s]";
  p.y_label = "grains";
  p.series.push_back({"simulated", range(0.1, 0.1, 12), range(100, 50, 12), "", false});
  p.series.push_back({"a & b", range(0.1, 0.1, 12), range(600, -10, 12), "#123456", true});
  const std::string svg = svg_line_plot(p);
  EXPECT_EQ(sandflow_test::html_problem(svg), "") << svg;
  const auto lines = sandflow_test::polylines(svg);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0].series, "simulated");
  EXPECT_EQ(lines[0].points, 12u);
  EXPECT_EQ(lines[1].series, "a &amp; b");
  EXPECT_EQ(lines[1].points, 12u);
  EXPECT_NE(svg.find("stroke-dasharray"), std::string::npos);
  EXPECT_NE(svg.find("Grains &lt;per&gt; frame"), std::string::npos);
  // y from 0 to 650 (100 + 11 x 50): 650 / 4 rounds to steps of 200, so the axis ends at 800
  EXPECT_NE(svg.find(">800</text>"), std::string::npos);
  EXPECT_EQ(svg.find(">1,000</text>"), std::string::npos);
  EXPECT_NE(svg.find(">0</text>"), std::string::npos);
  EXPECT_EQ(svg.find("http"), std::string::npos);
}

TEST(SvgLinePlot, PointsStayInsideThePlotAndNonFiniteOnesAreLeftOut) {
  LinePlot p;
  p.id = "p";
  p.width = 600;
  p.height = 300;
  std::vector<double> y = range(1, 1, 10);
  y[4] = std::numeric_limits<double>::quiet_NaN();
  y[6] = std::numeric_limits<double>::infinity();
  p.series.push_back({"s", range(0, 1, 10), y, "", false});
  const std::string svg = svg_line_plot(p);
  const auto lines = sandflow_test::polylines(svg);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0].points, 8u);
  // every coordinate within the 600 x 300 plot
  const std::size_t s = svg.find("points=\"") + 8;
  std::string pts = svg.substr(s, svg.find('"', s) - s);
  for (char& c : pts)
    if (c == ',') c = ' ';
  std::istringstream in(pts);
  double px = 0, py = 0;
  int n = 0;
  while (in >> px >> py) {
    EXPECT_GE(px, 0);
    EXPECT_LE(px, 600);
    EXPECT_GE(py, 0);
    EXPECT_LE(py, 300);
    ++n;
  }
  EXPECT_EQ(n, 8);
}

TEST(SvgLinePlot, NoPointsSaysNoData) {
  LinePlot p;
  p.id = "empty";
  p.series.push_back({"nothing", {}, {}, "", false});
  const std::string svg = svg_line_plot(p);
  EXPECT_EQ(sandflow_test::html_problem(svg), "");
  EXPECT_NE(svg.find("no data"), std::string::npos);
  ASSERT_EQ(sandflow_test::polylines(svg).size(), 1u);
  EXPECT_EQ(sandflow_test::polylines(svg)[0].points, 0u);
}

TEST(Html, EscapeAndBase64) {
  EXPECT_EQ(html_escape("<a href=\"x\">Tom & Jerry's</a>"),
            "&lt;a href=&quot;x&quot;&gt;Tom &amp; Jerry&#39;s&lt;/a&gt;");
  // RFC 4648, section 10
  EXPECT_EQ(base64_encode(""), "");
  EXPECT_EQ(base64_encode("f"), "Zg==");
  EXPECT_EQ(base64_encode("fo"), "Zm8=");
  EXPECT_EQ(base64_encode("foo"), "Zm9v");
  EXPECT_EQ(base64_encode("foob"), "Zm9vYg==");
  EXPECT_EQ(base64_encode("fooba"), "Zm9vYmE=");
  EXPECT_EQ(base64_encode("foobar"), "Zm9vYmFy");
  // bytes above 0x7f (a PNG's signature starts with 0x89)
  EXPECT_EQ(base64_encode(std::string("\xff\xfe\x89", 3)), "//6J");
}
