// Figures for `manisweep evaluate`, drawn with OpenCV: colour-mapped depth-error images (as the
// paper's Figure 5, first row) and cumulative error plots (as its Figures 3 and 4).
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace ms {

// |depth - gt| through the jet colour map, 0 (blue) .. max_error (red, and above); black where
// the ground truth has no surface, white where the ground truth has one but `depth` does not.
// CV_8UC3 BGR of the maps' size.
cv::Mat ErrorImage(const cv::Mat& depth, const cv::Mat& gt, double max_error);

struct ErrorPanel {
  std::string label;
  cv::Mat depth;  // CV_32F, compared with the shared ground truth
};
// Panels side by side (scaled to at most `panel_width` pixels wide), each titled, with a colour
// bar from 0 to max_error labelled in scene units and a key for the black/white pixels.
cv::Mat ErrorFigure(const std::vector<ErrorPanel>& panels, const cv::Mat& gt, double max_error,
                    int panel_width = 640);

struct PlotCurve {
  std::string label;
  std::vector<double> values;  // share (0..1) at m = 1..values.size()
};
// Cumulative error plot: x = m (threshold m * sigma), y = percentage of ground-truth pixels;
// axes, ticks, grid, axis labels, a title and a legend. CV_8UC3 BGR, white background.
cv::Mat CumulativePlot(const std::vector<PlotCurve>& curves, double sigma, const std::string& title,
                       cv::Size size = cv::Size(900, 600));

// Encodes `image` as PNG and writes it atomically; throws InputError naming the path on failure.
void WritePng(const std::string& path, const cv::Mat& image);

}  // namespace ms
