#include "sweep/sweep_images.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "base/error.h"

namespace ms {
namespace {

namespace fs = std::filesystem;

fs::path TempDir() {
  const fs::path dir = fs::temp_directory_path() / ("ms_sweep_images_" + std::to_string(getpid()));
  fs::create_directories(dir);
  return dir;
}

TEST(SweepImages, ReadsGrayFloatInUnitRange) {
  const fs::path dir = TempDir();
  cv::Mat color(6, 8, CV_8UC3, cv::Scalar(255, 255, 255));
  color.at<cv::Vec3b>(2, 3) = {0, 0, 0};
  ASSERT_TRUE(cv::imwrite((dir / "a.png").string(), color));
  const cv::Mat gray = ReadGrayImage((dir / "a.png").string());
  EXPECT_EQ(gray.type(), CV_32FC1);
  EXPECT_FLOAT_EQ(gray.at<float>(0, 0), 1.0f);
  EXPECT_FLOAT_EQ(gray.at<float>(2, 3), 0.0f);
  cv::Mat deep(4, 4, CV_16U, cv::Scalar(65535));
  ASSERT_TRUE(cv::imwrite((dir / "b.png").string(), deep));
  EXPECT_FLOAT_EQ(ReadGrayImage((dir / "b.png").string()).at<float>(1, 1), 1.0f);

  // Missing, garbage, and wrong-size files are input errors naming the file.
  EXPECT_THROW(ReadGrayImage((dir / "none.png").string()), InputError);
  {
    std::ofstream garbage(dir / "c.png");
    garbage << "not an image";
  }
  try {
    ReadGrayImage((dir / "c.png").string());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("c.png"), std::string::npos) << e.what();
  }
  View view;
  view.name = "a.png";
  view.image_path = (dir / "a.png").string();
  view.intrinsics = {8, 7, 10, 10, 4, 3};
  EXPECT_THROW(LoadSweepCamera(0, view), InputError);
  view.intrinsics.height = 6;
  const SweepCamera camera = LoadSweepCamera(3, view);
  EXPECT_EQ(camera.id, 3);
  EXPECT_EQ(camera.image.size(), cv::Size(8, 6));
  view.image_path.clear();
  EXPECT_THROW(LoadSweepCamera(0, view), InputError);
  fs::remove_all(dir);
}

TEST(SweepImages, UndistortionRestoresThePinholeImage) {
  Intrinsics k{120, 90, 100, 100, 61, 44};
  k.k1 = -0.2;
  k.k2 = 0.05;
  k.p1 = 0.003;
  // A smooth pattern in pinhole pixel coordinates, and the image a distorted lens would take.
  const auto pattern = [](double u, double v) {
    return 0.5 + 0.4 * std::sin(u * 0.15) * std::cos(v * 0.11);
  };
  cv::Mat distorted(k.height, k.width, CV_32F);
  for (int row = 0; row < k.height; ++row) {
    for (int col = 0; col < k.width; ++col) {
      const Eigen::Vector2d d((col + 0.5 - k.cx) / k.fx, (row + 0.5 - k.cy) / k.fy);
      const Eigen::Vector2d n = k.Undistort(d);
      distorted.at<float>(row, col) =
          static_cast<float>(pattern(k.fx * n.x() + k.cx, k.fy * n.y() + k.cy));
    }
  }
  const cv::Mat undistorted = UndistortImage(distorted, k);
  double worst = 0;
  for (int row = 10; row < k.height - 10; ++row) {
    for (int col = 10; col < k.width - 10; ++col) {
      worst = std::max(worst,
                       std::abs(undistorted.at<float>(row, col) - pattern(col + 0.5, row + 0.5)));
    }
  }
  EXPECT_LT(worst, 0.01);
  // Without the correction the error is large (the test can fail).
  double uncorrected = 0;
  for (int row = 10; row < k.height - 10; ++row) {
    for (int col = 10; col < k.width - 10; ++col) {
      uncorrected = std::max(
          uncorrected, std::abs(distorted.at<float>(row, col) - pattern(col + 0.5, row + 0.5)));
    }
  }
  EXPECT_GT(uncorrected, 0.1);
}

}  // namespace
}  // namespace ms
