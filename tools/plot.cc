#include "tools/plot.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "base/error.h"
#include "base/file_util.h"

namespace ms {
namespace {

const int kFont = cv::FONT_HERSHEY_SIMPLEX;

void PutText(cv::Mat& image, const std::string& text, cv::Point origin, double scale,
             const cv::Scalar& color, int thickness = 1) {
  cv::putText(image, text, origin, kFont, scale, color, thickness, cv::LINE_AA);
}

cv::Size TextSize(const std::string& text, double scale, int thickness = 1) {
  int baseline = 0;
  return cv::getTextSize(text, kFont, scale, thickness, &baseline);
}

// Text centred horizontally on x.
void PutCentered(cv::Mat& image, const std::string& text, int x, int baseline_y, double scale,
                 const cv::Scalar& color, int thickness = 1) {
  PutText(image, text, {x - TextSize(text, scale, thickness).width / 2, baseline_y}, scale, color,
          thickness);
}

cv::Vec3b JetColor(double t) {
  cv::Mat one(1, 1, CV_8U, cv::Scalar(std::clamp(t, 0.0, 1.0) * 255));
  cv::Mat color;
  cv::applyColorMap(one, color, cv::COLORMAP_JET);
  return color.at<cv::Vec3b>(0, 0);
}

std::string Number(double v) { return fmt::format("{:.3g}", v); }

}  // namespace

cv::Mat ErrorImage(const cv::Mat& depth, const cv::Mat& gt, double max_error) {
  if (depth.type() != CV_32F || gt.type() != CV_32F || depth.size() != gt.size()) {
    throw InternalError("ErrorImage: depth maps must be CV_32F of equal size");
  }
  if (!(max_error > 0)) throw InternalError("ErrorImage: max_error must be > 0");
  cv::Mat level(gt.size(), CV_8U, cv::Scalar(0));
  for (int r = 0; r < gt.rows; ++r) {
    for (int c = 0; c < gt.cols; ++c) {
      const float g = gt.at<float>(r, c), d = depth.at<float>(r, c);
      if (g > 0 && d > 0) {
        level.at<uint8_t>(r, c) =
            cv::saturate_cast<uint8_t>(std::min(1.0, std::abs(d - g) / max_error) * 255);
      }
    }
  }
  cv::Mat image;
  cv::applyColorMap(level, image, cv::COLORMAP_JET);
  for (int r = 0; r < gt.rows; ++r) {
    for (int c = 0; c < gt.cols; ++c) {
      const float g = gt.at<float>(r, c), d = depth.at<float>(r, c);
      if (!(g > 0)) {
        image.at<cv::Vec3b>(r, c) = cv::Vec3b(0, 0, 0);
      } else if (!(d > 0)) {
        image.at<cv::Vec3b>(r, c) = cv::Vec3b(255, 255, 255);
      }
    }
  }
  return image;
}

cv::Mat ErrorFigure(const std::vector<ErrorPanel>& panels, const cv::Mat& gt, double max_error,
                    int panel_width) {
  if (panels.empty()) throw InternalError("ErrorFigure: no panels");
  const double scale = std::min(1.0, static_cast<double>(panel_width) / gt.cols);
  const cv::Size panel(std::max(1, static_cast<int>(std::lround(gt.cols * scale))),
                       std::max(1, static_cast<int>(std::lround(gt.rows * scale))));
  const int title = 34, gap = 12, bar_width = 24, bar_area = 130, bottom = 40;
  const cv::Scalar background(240, 240, 240), ink(30, 30, 30);
  cv::Mat figure(title + panel.height + bottom,
                 gap + static_cast<int>(panels.size()) * (panel.width + gap) + bar_area, CV_8UC3,
                 background);
  for (size_t i = 0; i < panels.size(); ++i) {
    cv::Mat image = ErrorImage(panels[i].depth, gt, max_error), scaled;
    cv::resize(image, scaled, panel, 0, 0, cv::INTER_AREA);
    const int x = gap + static_cast<int>(i) * (panel.width + gap);
    scaled.copyTo(figure(cv::Rect(x, title, panel.width, panel.height)));
    PutCentered(figure, panels[i].label, x + panel.width / 2, title - 10, 0.6, ink);
  }
  // Colour bar: max_error at the top, 0 at the bottom.
  const int bx = gap + static_cast<int>(panels.size()) * (panel.width + gap) + 6;
  for (int y = 0; y < panel.height; ++y) {
    const cv::Vec3b c = JetColor(1.0 - static_cast<double>(y) / std::max(1, panel.height - 1));
    cv::line(figure, {bx, title + y}, {bx + bar_width, title + y}, cv::Scalar(c[0], c[1], c[2]));
  }
  cv::rectangle(figure, cv::Rect(bx, title, bar_width, panel.height), ink);
  for (int k = 0; k <= 4; ++k) {
    const int y = title + static_cast<int>(std::lround((1 - k / 4.0) * (panel.height - 1)));
    cv::line(figure, {bx + bar_width, y}, {bx + bar_width + 5, y}, ink);
    PutText(figure, Number(max_error * k / 4.0) + (k == 4 ? "+" : ""), {bx + bar_width + 8, y + 5},
            0.45, ink);
  }
  PutText(figure, "|d - d*|", {bx - 2, title - 10}, 0.5, ink);
  // Key for the pixels that are not errors.
  const int ky = title + panel.height + 14;
  cv::rectangle(figure, cv::Rect(gap, ky, 14, 14), cv::Scalar(0, 0, 0), cv::FILLED);
  PutText(figure, "no ground truth", {gap + 20, ky + 12}, 0.45, ink);
  cv::rectangle(figure, cv::Rect(gap + 170, ky, 14, 14), cv::Scalar(255, 255, 255), cv::FILLED);
  cv::rectangle(figure, cv::Rect(gap + 170, ky, 14, 14), ink);
  PutText(figure, "mesh missing", {gap + 190, ky + 12}, 0.45, ink);
  return figure;
}

cv::Mat CumulativePlot(const std::vector<PlotCurve>& curves, double sigma, const std::string& title,
                       cv::Size size) {
  const cv::Scalar background(255, 255, 255), ink(30, 30, 30), grid(225, 225, 225);
  cv::Mat plot(size, CV_8UC3, background);
  const int left = 80, right = 30, top = 50, bottom = 70;
  const cv::Rect area(left, top, size.width - left - right, size.height - top - bottom);
  if (area.width < 50 || area.height < 50) throw InternalError("CumulativePlot: size too small");
  int max_m = 1;
  for (const PlotCurve& c : curves) max_m = std::max(max_m, static_cast<int>(c.values.size()));
  auto to_pixel = [&](double m, double share) {
    return cv::Point2d(area.x + area.width * m / max_m, area.y + area.height * (1 - share));
  };
  // Grid and ticks.
  for (int pct = 0; pct <= 100; pct += 10) {
    const cv::Point2d p = to_pixel(0, pct / 100.0);
    cv::line(plot, {area.x, static_cast<int>(p.y)}, {area.x + area.width, static_cast<int>(p.y)},
             grid);
    cv::line(plot, {area.x - 5, static_cast<int>(p.y)}, {area.x, static_cast<int>(p.y)}, ink);
    if (pct % 20 == 0) {
      const std::string label = std::to_string(pct);
      PutText(plot, label, {area.x - 10 - TextSize(label, 0.5).width, static_cast<int>(p.y) + 5},
              0.5, ink);
    }
  }
  const int tick_step = max_m <= 20 ? 1 : (max_m + 9) / 10;
  for (int m = 0; m <= max_m; m += tick_step) {
    const cv::Point2d p = to_pixel(m, 0);
    cv::line(plot, {static_cast<int>(p.x), area.y}, {static_cast<int>(p.x), area.y + area.height},
             grid);
    cv::line(plot, {static_cast<int>(p.x), area.y + area.height},
             {static_cast<int>(p.x), area.y + area.height + 5}, ink);
    PutCentered(plot, std::to_string(m), static_cast<int>(p.x), area.y + area.height + 22, 0.5,
                ink);
  }
  cv::rectangle(plot, area, ink);
  // Labels and title.
  PutCentered(plot, fmt::format("error threshold m * Sigma  (Sigma = {})", Number(sigma)),
              area.x + area.width / 2, size.height - 18, 0.55, ink);
  const std::string y_label = "% of ground-truth pixels with error < m * Sigma";
  const cv::Size y_size = TextSize(y_label, 0.55);
  cv::Mat y_text(y_size.height + 10, y_size.width + 4, CV_8UC3, background);
  PutText(y_text, y_label, {2, y_size.height + 3}, 0.55, ink);
  cv::Mat rotated;
  cv::rotate(y_text, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
  const int ry = std::max(0, area.y + area.height / 2 - rotated.rows / 2);
  if (ry + rotated.rows <= size.height && rotated.cols + 8 <= left) {
    rotated.copyTo(plot(cv::Rect(8, ry, rotated.cols, rotated.rows)));
  }
  PutCentered(plot, title, size.width / 2, 30, 0.65, ink, 1);
  // Curves, starting at (0, 0): no pixel has an error below 0.
  const cv::Scalar palette[] = {{200, 80, 30},  {30, 30, 200}, {40, 150, 40}, {0, 140, 230},
                                {160, 50, 160}, {120, 120, 0}, {80, 80, 80},  {0, 200, 200}};
  for (size_t i = 0; i < curves.size(); ++i) {
    const cv::Scalar color = palette[i % 8];
    std::vector<cv::Point> points{to_pixel(0, 0)};
    for (size_t m = 0; m < curves[i].values.size(); ++m) {
      points.push_back(to_pixel(static_cast<double>(m + 1), curves[i].values[m]));
    }
    cv::polylines(plot, points, false, color, 2, cv::LINE_AA);
    for (size_t k = 1; k < points.size(); ++k) {
      cv::circle(plot, points[k], 4, color, cv::FILLED, cv::LINE_AA);
    }
  }
  // Legend, bottom right inside the axes (cumulative curves are high there).
  if (!curves.empty()) {
    int width = 0;
    for (const PlotCurve& c : curves) width = std::max(width, TextSize(c.label, 0.5).width);
    const int row = 24, box_w = width + 60, box_h = row * static_cast<int>(curves.size()) + 10;
    const cv::Rect box(area.x + area.width - box_w - 10, area.y + area.height - box_h - 10, box_w,
                       box_h);
    cv::rectangle(plot, box, background, cv::FILLED);
    cv::rectangle(plot, box, ink);
    for (size_t i = 0; i < curves.size(); ++i) {
      const int y = box.y + 17 + row * static_cast<int>(i);
      cv::line(plot, {box.x + 8, y - 4}, {box.x + 38, y - 4}, palette[i % 8], 2, cv::LINE_AA);
      cv::circle(plot, {box.x + 23, y - 4}, 4, palette[i % 8], cv::FILLED, cv::LINE_AA);
      PutText(plot, curves[i].label, {box.x + 46, y + 1}, 0.5, ink);
    }
  }
  return plot;
}

void WritePng(const std::string& path, const cv::Mat& image) {
  std::vector<uchar> png;
  if (image.empty() || !cv::imencode(".png", image, png)) {
    throw InputError(path + ": cannot encode the image as PNG");
  }
  WriteFileAtomically(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  });
}

}  // namespace ms
