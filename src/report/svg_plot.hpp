// Line plots written as inline SVG, for the run report (report.html). The report must open with
// no network and no JavaScript, so the plots are plain SVG text the program writes: axes with
// "nice" tick values (1, 2 or 5 times a power of ten), one polyline per series, a legend.
// Presentation attributes are set on the elements themselves, so a plot copied out of the page
// still draws the same.
#pragma once

#include <string>
#include <vector>

namespace sandflow {

/// Tick values covering [lo, hi]: an axis from `first` to `last` in steps of `step`, with
/// `first` <= lo and `last` >= hi, about `target` ticks. An empty or zero-width range is widened
/// first, so every axis has at least two ticks.
struct Ticks {
  double first = 0, last = 1, step = 1;
  std::vector<double> values;
};
Ticks nice_ticks(double lo, double hi, int target = 5);

/// A tick's label: fixed notation with as many decimals as `step` needs (thousands separated by
/// commas: "20,000", "0.25"), or "1.5e-4" for very small or very large values.
std::string tick_label(double value, double step);

struct PlotSeries {
  std::string name;  ///< shown in the legend and as the polyline's data-series
  std::vector<double> x, y;
  std::string color;  ///< CSS colour; empty: the palette's next
  bool dashed = false;
};

struct LinePlot {
  std::string id;  ///< the svg element's id
  std::string title;
  std::string x_label, y_label;  ///< with the unit: "t [s]"
  std::vector<PlotSeries> series;
  bool y_from_zero = true;  ///< the y axis starts at 0 (counts, durations)
  bool x_from_zero = true;
  int width = 620, height = 300;  ///< of the plot without its legend [px]
};

/// The plot as an <svg> element. Non-finite points are left out of the polylines and the ranges;
/// a plot with no points draws its axes and says "no data".
std::string svg_line_plot(const LinePlot& plot);

}  // namespace sandflow
