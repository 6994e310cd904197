// Image noise and the smoothing that keeps t_NCC meaningful under it (docs/design/sweep.md, "Noisy
// images"). With texture variance v and noise variance n in both images, the NCC of a perfect
// match is about v / (v + n): at 5 grey levels of noise few true matches reach the paper's
// t_NCC = 0.98. Smoothing both images with a Gaussian of sigma s divides white noise's variance
// by about 4 pi s^2 and low-frequency texture's by little.
#pragma once

#include <opencv2/core/mat.hpp>

namespace ms {

// Immerkaer's estimator per block, then a low quantile of the blocks: texture raises a block's
// figure and noise is everywhere, so the smoothest blocks measure the noise.
inline constexpr int kNoiseBlockPx = 16;
inline constexpr double kNoiseQuantile = 0.1;
// The smoothing's sigma: at most this fraction of the NCC window's, in steps of this many pixels.
inline constexpr double kMaxSmoothingOfWindow = 0.25;
inline constexpr double kSmoothingStepPx = 0.05;

// The standard deviation of additive white noise in a gray CV_32FC1 image (as sweep jobs hold
// them; same units as its pixels).
// Immerkaer's estimator (J. Immerkaer, "Fast noise variance estimation", CVIU 64(2), 1996):
// sqrt(pi/2) / 6 times the mean absolute response to the Laplacian difference mask
// [1 -2 1; -2 4 -2; 1 -2 1], here over each block of kNoiseBlockPx^2 interior pixels, and the
// kNoiseQuantile quantile of the blocks' figures (a little under the truth on pure noise:
// textured blocks are left out). Flat (clipped, synthetic) regions read as 0; docs/design/sweep.md
// gives the figures of real photographs. 0 for images smaller than 3 x 3.
double EstimateNoiseSigma(const cv::Mat& gray);

// The Gaussian's sigma (pixels) that brings white noise of `noise_sigma` down to about
// `target_sigma`: noise_sigma / (2 sqrt(pi) target_sigma), at most kMaxSmoothingOfWindow times
// the NCC window's `window_sigma_px` (texture at the pixel scale also reads as noise, and
// smoothing it away would leave the window nothing to match), rounded to kSmoothingStepPx (so
// the estimate's last bits do not change the images); 0 (no smoothing) when that is under half
// a pixel, where a discrete Gaussian barely filters, or when target_sigma is 0.
double SmoothingSigmaPx(double noise_sigma, double target_sigma, double window_sigma_px);

}  // namespace ms
