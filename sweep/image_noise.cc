#include "sweep/image_noise.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <vector>

#include "base/check.h"

namespace ms {

double EstimateNoiseSigma(const cv::Mat& gray) {
  if (gray.empty() || gray.cols < 3 || gray.rows < 3) return 0;
  MS_CHECK(gray.type() == CV_32FC1) << "EstimateNoiseSigma takes gray float images";
  // One pass over the rows with the mask's two factors, [1 -2 1] down then across (a dozen
  // milliseconds for a 3072 x 2048 image, against half a second for filter2D and a resize).
  const int width = gray.cols, interior_w = width - 2, interior_h = gray.rows - 2;
  const int blocks_x = interior_w / kNoiseBlockPx, blocks_y = interior_h / kNoiseBlockPx;
  std::vector<double> block_sums(static_cast<size_t>(blocks_x) * blocks_y, 0.0);
  std::vector<float> down(width), response(interior_w);
  double total = 0;
  for (int y = 1; y <= interior_h; ++y) {
    const float* above = gray.ptr<float>(y - 1);
    const float* row = gray.ptr<float>(y);
    const float* below = gray.ptr<float>(y + 1);
    for (int x = 0; x < width; ++x) down[x] = above[x] - 2 * row[x] + below[x];
    for (int x = 0; x < interior_w; ++x) {
      response[x] = std::abs(down[x] - 2 * down[x + 1] + down[x + 2]);
    }
    const int block_row = (y - 1) / kNoiseBlockPx;
    for (int bx = 0; bx < blocks_x; ++bx) {
      float sum = 0;
      for (int i = 0; i < kNoiseBlockPx; ++i) sum += response[bx * kNoiseBlockPx + i];
      if (block_row < blocks_y) block_sums[static_cast<size_t>(block_row) * blocks_x + bx] += sum;
      total += sum;
    }
    for (int x = blocks_x * kNoiseBlockPx; x < interior_w; ++x) total += response[x];
  }
  const double to_sigma = std::sqrt(M_PI / 2) / 6;
  if (block_sums.empty()) return total / (static_cast<double>(interior_w) * interior_h) * to_sigma;
  const auto quantile =
      block_sums.begin() + static_cast<std::ptrdiff_t>(kNoiseQuantile * block_sums.size());
  std::nth_element(block_sums.begin(), quantile, block_sums.end());
  return *quantile / (kNoiseBlockPx * kNoiseBlockPx) * to_sigma;
}

double SmoothingSigmaPx(double noise_sigma, double target_sigma, double window_sigma_px) {
  if (!(target_sigma > 0) || !(noise_sigma > 0)) return 0;
  const double sigma = std::min(noise_sigma / (2 * std::sqrt(M_PI) * target_sigma),
                                kMaxSmoothingOfWindow * window_sigma_px);
  // Whole steps, so that the estimate's last bits (its summation order) do not change the images.
  const double stepped = std::round(sigma / kSmoothingStepPx) * kSmoothingStepPx;
  return stepped >= 0.5 ? stepped : 0;
}

}  // namespace ms
