#include "report/svg_chart.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "report/html_page.h"

namespace ms {
namespace {

constexpr const char* kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e",
                                    "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"};

// A "nice" step (1, 2 or 5 times a power of ten) giving about `ticks` intervals over span.
double NiceStep(double span, int ticks) {
  const double raw = span / std::max(1, ticks);
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * power >= raw) return m * power;
  }
  return 10 * power;
}

std::string TickText(double value) {
  const double a = std::abs(value);
  if (a != 0 && (a >= 1e6 || a < 1e-3)) return fmt::format("{:.1e}", value);
  return fmt::format("{:.6g}", value);
}

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void Add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool Empty() const { return !(lo <= hi); }
};

}  // namespace

std::string SvgLineChart(const LineChart& chart) {
  const int w = chart.width, h = chart.height;
  const double left = 64, right = 112, top = 28, bottom = 44;  // the legend sits on the right
  const double pw = w - left - right, ph = h - top - bottom;
  std::string svg = fmt::format(
      "<svg class=\"chart\" width=\"{}\" height=\"{}\" viewBox=\"0 0 {} {}\" role=\"img\" "
      "aria-label=\"{}\">\n<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"#fff\"/>\n"
      "<text x=\"{}\" y=\"18\" font-size=\"14\" text-anchor=\"middle\">{}</text>\n",
      w, h, w, h, EscapeHtml(chart.title), w, h, w / 2, EscapeHtml(chart.title));
  Range xr, yr;
  for (const double x : chart.xs) xr.Add(x);
  for (const ChartSeries& s : chart.series) {
    for (const double v : s.values) yr.Add(v);
  }
  if (xr.Empty() || yr.Empty()) {
    svg += fmt::format(
        "<text x=\"{}\" y=\"{}\" font-size=\"13\" text-anchor=\"middle\">no data"
        "</text>\n</svg>\n",
        w / 2, h / 2);
    return svg;
  }
  yr.lo = std::min(yr.lo, 0.0);  // counts and times read from zero
  if (yr.hi <= yr.lo) yr.hi = yr.lo + 1;
  if (xr.hi <= xr.lo) xr.hi = xr.lo + 1;
  const double ystep = NiceStep(yr.hi - yr.lo, 5);
  yr.hi = std::ceil(yr.hi / ystep) * ystep;
  const double xstep = std::max(1.0, NiceStep(xr.hi - xr.lo, 8));
  const auto px = [&](double x) { return left + (x - xr.lo) / (xr.hi - xr.lo) * pw; };
  const auto py = [&](double y) { return top + ph - (y - yr.lo) / (yr.hi - yr.lo) * ph; };
  for (double y = yr.lo; y <= yr.hi + ystep * 1e-9; y += ystep) {
    svg += fmt::format(
        "<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#ddd\"/>"
        "<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\" text-anchor=\"end\">{}</text>\n",
        left, py(y), left + pw, py(y), left - 6, py(y) + 4, TickText(y));
  }
  for (double x = std::ceil(xr.lo / xstep) * xstep; x <= xr.hi + xstep * 1e-9; x += xstep) {
    svg += fmt::format(
        "<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#999\"/>"
        "<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\" text-anchor=\"middle\">{}</text>\n",
        px(x), top + ph, px(x), top + ph + 4, px(x), top + ph + 17, TickText(x));
  }
  svg += fmt::format(
      "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#333\"/>\n"
      "<text x=\"{:.1f}\" y=\"{}\" font-size=\"12\" text-anchor=\"middle\">{}</text>\n"
      "<text x=\"14\" y=\"{:.1f}\" font-size=\"12\" text-anchor=\"middle\" "
      "transform=\"rotate(-90 14 {:.1f})\">{}</text>\n",
      left, top, pw, ph, left + pw / 2, h - 6, EscapeHtml(chart.x_label), top + ph / 2,
      top + ph / 2, EscapeHtml(chart.y_label));
  for (size_t s = 0; s < chart.series.size(); ++s) {
    const ChartSeries& series = chart.series[s];
    const char* colour = kColours[s % std::size(kColours)];
    std::string points, dots;
    const size_t n = std::min(series.values.size(), chart.xs.size());
    for (size_t i = 0; i < n; ++i) {
      const double x = chart.xs[i], y = series.values[i];
      if (!std::isfinite(x) || !std::isfinite(y)) {
        if (!points.empty()) {
          svg += fmt::format(
              "<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"2\" "
              "points=\"{}\"/>\n",
              colour, points);
        }
        points.clear();
        continue;
      }
      points += fmt::format("{:.1f},{:.1f} ", px(x), py(y));
      dots += fmt::format(
          "<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"2.5\" fill=\"{}\">"
          "<title>{}: {} at {}</title></circle>",
          px(x), py(y), colour, EscapeHtml(series.name), TickText(y), TickText(x));
    }
    if (!points.empty()) {
      svg += fmt::format(
          "<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"2\" "
          "points=\"{}\"/>\n",
          colour, points);
    }
    svg += dots + "\n";
    const double ly = top + 10 + 16 * static_cast<double>(s);
    svg += fmt::format(
        "<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"12\" height=\"3\" fill=\"{}\"/>"
        "<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\">{}</text>\n",
        left + pw + 8, ly - 4, colour, left + pw + 24, ly, EscapeHtml(series.name));
  }
  svg += "</svg>\n";
  return svg;
}

}  // namespace ms
