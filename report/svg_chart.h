// Line charts as inline SVG for the run report: no script, no network, readable in any
// browser and as text.
#pragma once

#include <string>
#include <vector>

namespace ms {

struct ChartSeries {
  std::string name;
  std::vector<double> values;  // y at x = xs[i]; NaN leaves a gap
};

struct LineChart {
  std::string title;
  std::string x_label, y_label;
  std::vector<double> xs;
  std::vector<ChartSeries> series;
  int width = 640, height = 300;  // pixels
};

// One <svg> element: axes with rounded ticks, a polyline and dots per series, a legend.
// Text is escaped. An empty chart (no x or no finite value) says so in its frame.
std::string SvgLineChart(const LineChart& chart);

}  // namespace ms
