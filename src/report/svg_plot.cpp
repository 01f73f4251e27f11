#include "report/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "report/html.hpp"

namespace sandflow {

namespace {

/// 1, 2, 5 or 10 times a power of ten, the nearest to `raw` (Heckbert's "nice numbers").
double nice_step(double raw) {
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / p;
  return (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * p;
}

/// "12345.6" -> "12,345.6"
std::string group_thousands(const std::string& s) {
  const std::size_t start = s[0] == '-' ? 1 : 0;
  const std::size_t dot = std::min(s.find('.'), s.size());
  std::string out = s.substr(0, start);
  for (std::size_t k = start; k < dot; ++k) {
    out += s[k];
    const std::size_t left = dot - k - 1;
    if (left > 0 && left % 3 == 0) out += ',';
  }
  return out + s.substr(dot);
}

// Okabe & Ito's colour-blind-safe palette, without its yellow (too pale on white)
constexpr const char* kPalette[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                    "#E69F00", "#56B4E9", "#000000", "#999999"};

constexpr double kLeft = 74, kRight = 18, kTop = 34, kBottom = 50;  // margins [px]
constexpr double kLegendRow = 18;
constexpr double kCharWidth = 6.6;  // of the 12 px legend font, on average [px]

}  // namespace

Ticks nice_ticks(double lo, double hi, int target) {
  if (!std::isfinite(lo) || !std::isfinite(hi)) lo = 0, hi = 1;
  if (lo > hi) std::swap(lo, hi);
  // a zero-width range: widened around its value (or to [0, 1] at zero)
  if (hi - lo <= 1e-12 * std::max(std::abs(lo), std::abs(hi))) {
    if (lo == 0 && hi == 0) {
      hi = 1;
    } else {
      const double pad = 0.5 * std::max(std::abs(lo), std::abs(hi));
      lo -= pad;
      hi += pad;
    }
  }
  target = std::max(target, 2);
  Ticks t;
  t.step = nice_step((hi - lo) / (target - 1));
  // whole multiples of the step, so that 0.1 * 3 prints as 0.3 and not 0.30000000000000004
  const double k0 = std::floor(lo / t.step + 1e-9), k1 = std::ceil(hi / t.step - 1e-9);
  for (double k = k0; k <= k1 + 0.5; ++k) {
    const double v = k * t.step;
    t.values.push_back(v == 0 ? 0.0 : v);  // no "-0"
  }
  t.first = t.values.front();
  t.last = t.values.back();
  return t;
}

std::string tick_label(double value, double step) {
  if (!std::isfinite(value)) return fmt::format("{}", value);
  if (step <= 0 || !std::isfinite(step)) step = std::abs(value) > 0 ? std::abs(value) : 1;
  if (std::abs(value) < 1e-9 * step) return "0";
  const double mag = std::max(std::abs(value), step);
  const int e_step = static_cast<int>(std::floor(std::log10(step) + 1e-9));
  if (mag >= 1e7 || step < 1e-3) {
    // scientific: as many mantissa digits as the step needs, exponent without '+' or zeros
    const int e_value = static_cast<int>(std::floor(std::log10(std::abs(value)) + 1e-9));
    const std::string s = fmt::format("{:.{}e}", value, std::max(0, e_value - e_step));
    const std::size_t e = s.find('e');
    const int exponent = std::stoi(s.substr(e + 1));
    return s.substr(0, e) + "e" + std::to_string(exponent);
  }
  return group_thousands(fmt::format("{:.{}f}", value, std::max(0, -e_step)));
}

std::string svg_line_plot(const LinePlot& plot) {
  // the ranges of the finite points
  const double inf = std::numeric_limits<double>::infinity();
  double x_lo = inf, x_hi = -inf, y_lo = inf, y_hi = -inf;
  for (const PlotSeries& s : plot.series)
    for (std::size_t k = 0; k < std::min(s.x.size(), s.y.size()); ++k)
      if (std::isfinite(s.x[k]) && std::isfinite(s.y[k])) {
        x_lo = std::min(x_lo, s.x[k]);
        x_hi = std::max(x_hi, s.x[k]);
        y_lo = std::min(y_lo, s.y[k]);
        y_hi = std::max(y_hi, s.y[k]);
      }
  const bool empty = x_lo > x_hi;
  if (empty) x_lo = 0, x_hi = 1, y_lo = 0, y_hi = 1;
  if (plot.x_from_zero) x_lo = std::min(x_lo, 0.0), x_hi = std::max(x_hi, 0.0);
  if (plot.y_from_zero) y_lo = std::min(y_lo, 0.0), y_hi = std::max(y_hi, 0.0);
  const Ticks xt = nice_ticks(x_lo, x_hi, 7), yt = nice_ticks(y_lo, y_hi, 5);

  const double W = plot.width, H = plot.height;
  const double left = kLeft, right = W - kRight, top = kTop, bottom = H - kBottom;
  auto px = [&](double x) { return left + (x - xt.first) / (xt.last - xt.first) * (right - left); };
  auto py = [&](double y) { return bottom - (y - yt.first) / (yt.last - yt.first) * (bottom - top); };

  // the legend below the plot, its entries wrapped into rows
  struct Entry {
    double x, y;
  };
  std::vector<Entry> legend;
  double lx = left, ly = H + 2;
  for (const PlotSeries& s : plot.series) {
    const double w = 30 + kCharWidth * static_cast<double>(s.name.size()) + 16;
    if (lx > left && lx + w > W - kRight) lx = left, ly += kLegendRow;
    legend.push_back({lx, ly});
    lx += w;
  }
  const double total_h = plot.series.empty() ? H : ly + kLegendRow + 4;

  const std::string id = html_escape(plot.id);
  std::string o = fmt::format(
      "<svg class=\"plot\" id=\"{0}\" viewBox=\"0 0 {1:.0f} {2:.0f}\" width=\"{1:.0f}\" "
      "height=\"{2:.0f}\" role=\"img\" aria-labelledby=\"{0}-title\" font-family=\"sans-serif\">\n"
      "<title id=\"{0}-title\">{3}</title>\n"
      "<text x=\"{4:.1f}\" y=\"20\" font-size=\"14\" font-weight=\"bold\">{3}</text>\n",
      id, W, total_h, html_escape(plot.title), left);

  // grid and ticks
  o += "<g class=\"grid\" stroke=\"#e2e2e2\" stroke-width=\"1\">\n";
  for (double v : xt.values)
    o += fmt::format("<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{0:.1f}\" y2=\"{2:.1f}\"/>\n", px(v),
                     top, bottom);
  for (double v : yt.values)
    o += fmt::format("<line x1=\"{1:.1f}\" y1=\"{0:.1f}\" x2=\"{2:.1f}\" y2=\"{0:.1f}\"/>\n", py(v),
                     left, right);
  o += "</g>\n<g class=\"axes\" stroke=\"#333333\" stroke-width=\"1\">\n";
  o += fmt::format("<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{0:.1f}\" y2=\"{2:.1f}\"/>\n", left,
                   top, bottom);
  o += fmt::format("<line x1=\"{1:.1f}\" y1=\"{0:.1f}\" x2=\"{2:.1f}\" y2=\"{0:.1f}\"/>\n", bottom,
                   left, right);
  for (double v : xt.values)
    o += fmt::format("<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{0:.1f}\" y2=\"{2:.1f}\"/>\n", px(v),
                     bottom, bottom + 4);
  for (double v : yt.values)
    o += fmt::format("<line x1=\"{1:.1f}\" y1=\"{0:.1f}\" x2=\"{2:.1f}\" y2=\"{0:.1f}\"/>\n", py(v),
                     left - 4, left);
  o += "</g>\n<g class=\"tick-labels\" font-size=\"11\" fill=\"#333333\">\n";
  for (double v : xt.values)
    o += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>\n", px(v),
                     bottom + 16, html_escape(tick_label(v, xt.step)));
  for (double v : yt.values)
    o += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"end\">{}</text>\n", left - 7,
                     py(v) + 4, html_escape(tick_label(v, yt.step)));
  o += "</g>\n";
  o += fmt::format(
      "<text class=\"axis-label\" x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"12\" "
      "text-anchor=\"middle\">{}</text>\n",
      (left + right) / 2, H - 12, html_escape(plot.x_label));
  o += fmt::format(
      "<text class=\"axis-label\" x=\"0\" y=\"0\" font-size=\"12\" text-anchor=\"middle\" "
      "transform=\"translate(16 {:.1f}) rotate(-90)\">{}</text>\n",
      (top + bottom) / 2, html_escape(plot.y_label));
  if (empty)
    o += fmt::format(
        "<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"13\" fill=\"#777777\" "
        "text-anchor=\"middle\">no data</text>\n",
        (left + right) / 2, (top + bottom) / 2);

  // one polyline per series; dots at the points when they are few enough to tell apart
  o += "<g class=\"series\" fill=\"none\" stroke-width=\"1.8\" stroke-linejoin=\"round\">\n";
  for (std::size_t s = 0; s < plot.series.size(); ++s) {
    const PlotSeries& ser = plot.series[s];
    const std::string color =
        ser.color.empty() ? kPalette[s % std::size(kPalette)] : html_escape(ser.color);
    std::string points, dots;
    std::size_t n = 0;
    for (std::size_t k = 0; k < std::min(ser.x.size(), ser.y.size()); ++k) {
      if (!std::isfinite(ser.x[k]) || !std::isfinite(ser.y[k])) continue;
      points += fmt::format("{}{:.1f},{:.1f}", n++ ? " " : "", px(ser.x[k]), py(ser.y[k]));
    }
    if (n <= 40)
      for (std::size_t k = 0; k < std::min(ser.x.size(), ser.y.size()); ++k)
        if (std::isfinite(ser.x[k]) && std::isfinite(ser.y[k]))
          dots += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"2.2\" fill=\"{}\"/>", px(ser.x[k]),
                              py(ser.y[k]), color);
    o += fmt::format("<polyline data-series=\"{}\" stroke=\"{}\"{} points=\"{}\"/>{}\n",
                     html_escape(ser.name), color,
                     ser.dashed ? " stroke-dasharray=\"6 4\"" : "", points, dots);
  }
  o += "</g>\n";

  // the legend: a stroke of each series' line and its name
  o += "<g class=\"legend\" font-size=\"12\" fill=\"#222222\">\n";
  for (std::size_t s = 0; s < plot.series.size(); ++s) {
    const PlotSeries& ser = plot.series[s];
    const std::string color =
        ser.color.empty() ? kPalette[s % std::size(kPalette)] : html_escape(ser.color);
    const Entry& e = legend[s];
    o += fmt::format(
        "<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"{}\" "
        "stroke-width=\"2.5\"{}/><text x=\"{:.1f}\" y=\"{:.1f}\">{}</text>\n",
        e.x, e.y + 8, e.x + 24, e.y + 8, color, ser.dashed ? " stroke-dasharray=\"6 4\"" : "",
        e.x + 30, e.y + 12, html_escape(ser.name));
  }
  o += "</g>\n</svg>\n";
  return o;
}

}  // namespace sandflow
