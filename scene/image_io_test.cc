#include "scene/image_io.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "base/error.h"
#include "base/file_util.h"
#include "testing/scene_testing.h"

namespace ms {
namespace {

std::string Encode(const cv::Mat& image, const std::string& ext) {
  std::vector<uchar> bytes;
  EXPECT_TRUE(cv::imencode(ext, image, bytes));
  return std::string(bytes.begin(), bytes.end());
}

TEST(ImageIo, HeaderSizesOfPngAndJpeg) {
  const cv::Mat image(37, 53, CV_8UC3, cv::Scalar(10, 20, 30));
  EXPECT_EQ(ParseImageSize("x.png", Encode(image, ".png")), (ImageSize{53, 37}));
  const std::string jpeg = Encode(image, ".jpg");
  EXPECT_EQ(ParseImageSize("x.jpg", jpeg), (ImageSize{53, 37}));
  // A large APP1 (EXIF-like) segment and fill bytes before the frame header.
  std::string app1 = "\xFF\xE1";
  const size_t length = 60000;
  app1 += static_cast<char>(length >> 8);
  app1 += static_cast<char>(length & 0xFF);
  app1 += std::string(length - 2, 'e');
  const std::string with_exif = jpeg.substr(0, 2) + app1 + "\xFF\xFF" + jpeg.substr(2);
  EXPECT_EQ(ParseImageSize("x.jpg", with_exif), (ImageSize{53, 37}));
  // 16-bit PNG.
  EXPECT_EQ(ParseImageSize("x.png", Encode(cv::Mat(5, 7, CV_16UC1, cv::Scalar(1000)), ".png")),
            (ImageSize{7, 5}));
}

TEST(ImageIo, MalformedHeadersFail) {
  const std::string jpeg = Encode(cv::Mat(8, 8, CV_8UC1, cv::Scalar(1)), ".jpg");
  const std::string png = Encode(cv::Mat(8, 8, CV_8UC1, cv::Scalar(1)), ".png");
  EXPECT_THROW(ParseImageSize("x", ""), InputError);
  EXPECT_THROW(ParseImageSize("x", "GIF89a......"), InputError);
  EXPECT_THROW(ParseImageSize("x.png", png.substr(0, 20)), InputError);
  EXPECT_THROW(ParseImageSize("x.jpg", jpeg.substr(0, 6)), InputError);
  std::string zero = png;
  zero[16] = zero[17] = zero[18] = zero[19] = 0;  // width 0
  try {
    ParseImageSize("x.png", zero);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "x.png: PNG header: image size 0x8 is out of range [1, 1048576]");
  }
  // A JPEG of nothing but markers without a frame header.
  EXPECT_THROW(ParseImageSize("x.jpg", std::string("\xFF\xD8\xFF\xD9", 4)), InputError);
}

TEST(ImageIo, ReadLoadAndFallback) {
  testing::TempDir dir("image_io");
  cv::Mat bgr(6, 9, CV_8UC3, cv::Scalar(255, 0, 0));  // blue in OpenCV's BGR order
  bgr.at<cv::Vec3b>(2, 3) = cv::Vec3b(0, 0, 255);     // one red pixel
  cv::imwrite(dir / "c.png", bgr);
  cv::imwrite(dir / "c.bmp", bgr);
  EXPECT_EQ(ReadImageSize(dir / "c.png"), (ImageSize{9, 6}));
  EXPECT_EQ(ReadImageSize(dir / "c.bmp"), (ImageSize{9, 6}));  // decoded by OpenCV
  const cv::Mat color = LoadImage(dir / "c.png", ImageMode::kColor);
  ASSERT_EQ(color.type(), CV_8UC3);
  EXPECT_EQ(color.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 0, 255));  // RGB order
  EXPECT_EQ(color.at<cv::Vec3b>(2, 3), cv::Vec3b(255, 0, 0));
  const cv::Mat gray = LoadImage(dir / "c.png", ImageMode::kGrayFloat);
  ASSERT_EQ(gray.type(), CV_32FC1);
  EXPECT_NEAR(gray.at<float>(0, 0), 29.0 / 255, 1.0 / 255);  // OpenCV's BGR->gray of blue
  cv::imwrite(dir / "g16.png", cv::Mat(4, 4, CV_16UC1, cv::Scalar(65535)));
  EXPECT_FLOAT_EQ(LoadImage(dir / "g16.png", ImageMode::kGrayFloat).at<float>(1, 1), 1.0f);
  EXPECT_THROW(ReadImageSize(dir / "missing.png"), InputError);
  WriteFileAtomically(dir / "junk.png", [](std::ostream& out) { out << "not an image"; });
  EXPECT_THROW(ReadImageSize(dir / "junk.png"), InputError);
  EXPECT_THROW(LoadImage(dir / "junk.png", ImageMode::kColor), InputError);
}

TEST(ImageIo, UndistortMovesPixelsWhereTheModelSays) {
  View view;
  view.name = "d.png";
  view.intrinsics = {120, 90, 100, 100, 60, 45};
  view.intrinsics.k1 = -0.2;
  view.intrinsics.p1 = 0.01;
  // A horizontal ramp: the value is the x coordinate of the pixel centre.
  cv::Mat ramp(90, 120, CV_32FC1);
  for (int r = 0; r < 90; ++r) {
    for (int c = 0; c < 120; ++c) ramp.at<float>(r, c) = c + 0.5f;
  }
  const UndistortedImage out = Undistort(view, ramp);
  EXPECT_FALSE(out.view.intrinsics.HasDistortion());
  EXPECT_EQ(out.view.intrinsics.fx, 100);
  // Undistorted pixel (col, row) samples the input where the distorted ray lands.
  for (const auto& [col, row] : {std::pair{10, 10}, {60, 45}, {100, 70}, {30, 80}}) {
    const Eigen::Vector2d n((col + 0.5 - 60) / 100, (row + 0.5 - 45) / 100);
    const Eigen::Vector2d d = view.intrinsics.Distort(n);
    // cv::remap interpolates at 1/32 pixel.
    EXPECT_NEAR(out.image.at<float>(row, col), 100 * d.x() + 60, 1.0 / 32) << col << "," << row;
  }
  view.intrinsics.k1 = view.intrinsics.p1 = 0;
  EXPECT_EQ(Undistort(view, ramp).image.data, ramp.data);  // no distortion: shared, not copied
  EXPECT_THROW(Undistort(view, cv::Mat(10, 10, CV_32FC1)), InputError);
}

}  // namespace
}  // namespace ms
