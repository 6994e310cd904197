// The noise estimate and the smoothing of noisy images (sweep/image_noise.h), and how a sweep
// job's preparation applies them (SmoothNoisyImages in sweep/sweep_kernel.h).
#include "sweep/image_noise.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "sweep/sweep_kernel.h"
#include "testing/sweep_test_scene.h"

namespace ms {
namespace {

constexpr double kGrey = 1.0 / 255;

// A smooth ramp with low-frequency shading: next to nothing for the Laplacian mask.
cv::Mat SmoothImage(int width, int height) {
  cv::Mat image(height, width, CV_32F);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      image.at<float>(y, x) = static_cast<float>(0.3 + 0.4 * x / width + 0.1 * std::sin(y / 40.0));
    }
  }
  return image;
}

cv::Mat WithNoise(const cv::Mat& image, double sigma, uint64_t seed) {
  cv::Mat noise(image.size(), CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  return image + noise;
}

TEST(ImageNoise, ImmerkaersEstimateRecoversWhiteNoise) {
  EXPECT_LT(EstimateNoiseSigma(SmoothImage(640, 480)), 0.05 * kGrey);
  for (const double grey_levels : {1.0, 2.0, 5.0}) {
    const double estimate =
        EstimateNoiseSigma(WithNoise(SmoothImage(640, 480), grey_levels * kGrey, 7));
    // The low quantile of the blocks reads a little under the truth (image_noise.h).
    EXPECT_GT(estimate, 0.88 * grey_levels * kGrey) << grey_levels;
    EXPECT_LT(estimate, 1.02 * grey_levels * kGrey) << grey_levels;
  }
}

TEST(ImageNoise, TextureOverPartOfTheImageDoesNotReadAsNoise) {
  // Left two thirds: strong texture at the pixel scale; everywhere: 1 grey level of noise.
  cv::Mat image = SmoothImage(640, 480);
  cv::Mat texture(480, 640, CV_32F);
  cv::RNG rng(3);
  rng.fill(texture, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::GaussianBlur(texture, texture, cv::Size(), 1.0);
  texture(cv::Rect(0, 0, 427, 480)).copyTo(image(cv::Rect(0, 0, 427, 480)));
  image = WithNoise(image, kGrey, 11);
  const double estimate = EstimateNoiseSigma(image);
  EXPECT_GT(estimate, 0.85 * kGrey);
  EXPECT_LT(estimate, 1.1 * kGrey);
  // The whole image's mean response, Immerkaer's original figure, reads the texture.
  const cv::Mat mask = (cv::Mat_<float>(3, 3) << 1, -2, 1, -2, 4, -2, 1, -2, 1);
  cv::Mat response;
  cv::filter2D(image, response, CV_32F, mask);
  EXPECT_GT(cv::mean(cv::abs(response))[0] * std::sqrt(M_PI / 2) / 6, 1.5 * kGrey);
}

TEST(ImageNoise, FlatAndTinyImagesReadAsNoiseFree) {
  EXPECT_EQ(EstimateNoiseSigma(cv::Mat(100, 100, CV_32F, cv::Scalar(0.5))), 0);
  EXPECT_EQ(EstimateNoiseSigma(cv::Mat(2, 2, CV_32F, cv::Scalar(0.5))), 0);
  EXPECT_EQ(EstimateNoiseSigma(cv::Mat()), 0);
  // Smaller than a block: the whole interior's figure.
  EXPECT_NEAR(EstimateNoiseSigma(WithNoise(SmoothImage(12, 12), 5 * kGrey, 5)), 5 * kGrey,
              2.5 * kGrey);
}

TEST(ImageNoise, TheSmoothingBringsWhiteNoiseDownToTheTarget) {
  const double sigma_px = SmoothingSigmaPx(5, 1, 8);
  EXPECT_DOUBLE_EQ(sigma_px, 1.40);  // 5 / (2 sqrt(pi)) = 1.41, in steps of 0.05 px
  cv::Mat noise = WithNoise(cv::Mat(480, 640, CV_32F, cv::Scalar(0.5)), 5 * kGrey, 13);
  cv::Mat smoothed;
  cv::GaussianBlur(noise, smoothed, cv::Size(), sigma_px, sigma_px, cv::BORDER_REFLECT_101);
  cv::Scalar mean, stddev;
  cv::meanStdDev(smoothed, mean, stddev);
  EXPECT_NEAR(stddev[0], kGrey, 0.1 * kGrey);
}

TEST(ImageNoise, NoSmoothingUnderHalfAPixelOrAtTargetZeroAndAtMostAQuarterWindow) {
  EXPECT_EQ(SmoothingSigmaPx(0.5, 0.5, 8), 0);  // 0.28 px: photographs as the real sets'
  EXPECT_EQ(SmoothingSigmaPx(5, 0, 8), 0);
  EXPECT_EQ(SmoothingSigmaPx(0, 0.5, 8), 0);
  EXPECT_DOUBLE_EQ(SmoothingSigmaPx(0.9, 0.5, 8), 0.5);  // 0.508 px
  EXPECT_DOUBLE_EQ(SmoothingSigmaPx(50, 0.5, 8), 2);
  EXPECT_DOUBLE_EQ(SmoothingSigmaPx(50, 0.5, 1), 0);  // a quarter of 1 px is under half a pixel
}

TEST(SmoothNoisyImages, ANoisyJobsImagesAreSmoothedAlikeAndTheJobKeepsItsOwn) {
  const SweepJob job = MakeSmallSweepJob(NoisyPyramidScene(), NoisyPyramidScene().truth);
  const cv::Mat original = job.camera.image.clone();
  const PreparedSweep prep = PrepareSweep(job);
  // 2.55 grey levels of noise (and some texture in 160 x 120 pixels): about 1.5 px to reach
  // 0.5, capped at a quarter of the 4 px window.
  EXPECT_GT(prep.image_noise, 2.2);
  EXPECT_LT(prep.image_noise, 3.2);
  EXPECT_DOUBLE_EQ(prep.smoothing_px, 1);
  EXPECT_EQ(PreparedSweepStats(prep).smoothing_px, 1);
  cv::Mat expected;
  for (size_t i = 0; i < job.neighbours.size(); ++i) {
    cv::GaussianBlur(job.neighbours[i].image, expected, cv::Size(), 1, 1, cv::BORDER_REFLECT_101);
    EXPECT_EQ(cv::norm(prep.neighbours[i].image, expected, cv::NORM_INF), 0) << i;
  }
  EXPECT_EQ(cv::norm(job.camera.image, original, cv::NORM_INF), 0);
  EXPECT_GT(cv::norm(prep.camera.image, original, cv::NORM_INF), 0.01);

  SweepJob never = job;
  never.options.image_noise_target = 0;
  const PreparedSweep unsmoothed = PrepareSweep(never);
  EXPECT_EQ(unsmoothed.smoothing_px, 0);
  EXPECT_GT(unsmoothed.image_noise, 2.2);  // measured all the same, for the log
  EXPECT_EQ(unsmoothed.camera.image.data, job.camera.image.data);  // level 0: not even copied
}

TEST(SmoothNoisyImages, ACleanJobIsLeftAsItIs) {
  PyramidSceneOptions options;
  options.texture_contrast = 0.2;  // smooth value noise, no sensor noise
  const PyramidScene scene = MakePyramidScene(options);
  const SweepJob job = MakeSmallSweepJob(scene, scene.truth);
  const PreparedSweep prep = PrepareSweep(job);
  EXPECT_LT(prep.image_noise, 0.9);
  EXPECT_EQ(prep.smoothing_px, 0);
  EXPECT_EQ(prep.camera.image.data, job.camera.image.data);
}

}  // namespace
}  // namespace ms
