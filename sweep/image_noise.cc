#include "sweep/image_noise.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace ms {

double EstimateNoiseSigma(const cv::Mat& gray) {
  if (gray.empty() || gray.cols < 3 || gray.rows < 3) return 0;
  const cv::Mat mask = (cv::Mat_<float>(3, 3) << 1, -2, 1, -2, 4, -2, 1, -2, 1);
  cv::Mat response;
  cv::filter2D(gray, response, CV_32F, mask);
  // Border pixels saw a reflected neighbourhood: only the interior counts.
  const cv::Mat interior = cv::abs(response(cv::Rect(1, 1, gray.cols - 2, gray.rows - 2)));
  const double to_sigma = std::sqrt(M_PI / 2) / 6;
  const int blocks_x = interior.cols / kNoiseBlockPx, blocks_y = interior.rows / kNoiseBlockPx;
  if (blocks_x == 0 || blocks_y == 0) return cv::mean(interior)[0] * to_sigma;
  // Mean |response| per block (an area resize by a whole factor averages exactly each block).
  cv::Mat block_means;
  cv::resize(interior(cv::Rect(0, 0, blocks_x * kNoiseBlockPx, blocks_y * kNoiseBlockPx)),
             block_means, cv::Size(blocks_x, blocks_y), 0, 0, cv::INTER_AREA);
  std::vector<float> means(block_means.begin<float>(), block_means.end<float>());
  const auto quantile = means.begin() + static_cast<std::ptrdiff_t>(kNoiseQuantile * means.size());
  std::nth_element(means.begin(), quantile, means.end());
  return *quantile * to_sigma;
}

double SmoothingSigmaPx(double noise_sigma, double target_sigma, double window_sigma_px) {
  if (!(target_sigma > 0) || !(noise_sigma > 0)) return 0;
  const double sigma = std::min(noise_sigma / (2 * std::sqrt(M_PI) * target_sigma),
                                kMaxSmoothingOfWindow * window_sigma_px);
  return sigma >= 0.5 ? sigma : 0;
}

}  // namespace ms
