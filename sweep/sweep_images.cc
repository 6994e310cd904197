#include "sweep/sweep_images.h"

#include <fmt/format.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "base/error.h"
#include "base/file_util.h"

namespace ms {

cv::Mat ReadGrayImage(const std::string& path) {
  RequireFile(path, "image");
  cv::Mat raw;
  try {
    raw = cv::imread(path, cv::IMREAD_GRAYSCALE | cv::IMREAD_ANYDEPTH);
  } catch (const cv::Exception& e) {
    throw InputError(path + ": cannot read image (" + e.what() + ")");
  }
  if (raw.empty()) throw InputError(path + ": cannot read image (unknown or corrupt format)");
  cv::Mat gray;
  switch (raw.depth()) {
    case CV_8U:
      raw.convertTo(gray, CV_32F, 1.0 / 255.0);
      break;
    case CV_16U:
      raw.convertTo(gray, CV_32F, 1.0 / 65535.0);
      break;
    case CV_32F:
      gray = raw;
      break;
    default:
      raw.convertTo(gray, CV_32F);
      break;
  }
  if (!cv::checkRange(gray, true)) throw InputError(path + ": image has non-finite pixels");
  return gray;
}

cv::Mat UndistortImage(const cv::Mat& image, const Intrinsics& k) {
  if (!k.HasDistortion()) return image;
  cv::Mat map_x(image.size(), CV_32F), map_y(image.size(), CV_32F);
  for (int row = 0; row < image.rows; ++row) {
    for (int col = 0; col < image.cols; ++col) {
      // Pinhole pixel centre -> normalised -> distorted -> source pixel; cv::remap indexes
      // pixels by their centres, hence the -0.5.
      const Eigen::Vector2d n((col + 0.5 - k.cx) / k.fx, (row + 0.5 - k.cy) / k.fy);
      const Eigen::Vector2d d = k.Distort(n);
      map_x.at<float>(row, col) = static_cast<float>(k.fx * d.x() + k.cx - 0.5);
      map_y.at<float>(row, col) = static_cast<float>(k.fy * d.y() + k.cy - 0.5);
    }
  }
  cv::Mat out;
  cv::remap(image, out, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return out;
}

SweepCamera SweepCameraGeometry(int32_t id, const View& view) {
  SweepCamera camera;
  camera.id = id;
  camera.view = view;
  Intrinsics& k = camera.view.intrinsics;
  k.k1 = k.k2 = k.p1 = k.p2 = k.k3 = 0;
  return camera;
}

SweepCamera LoadSweepCamera(int32_t id, const View& view) {
  if (view.image_path.empty()) {
    throw InputError(fmt::format("view {} ('{}'): no image file known for it", id, view.name));
  }
  cv::Mat image = ReadGrayImage(view.image_path);
  if (image.cols != view.intrinsics.width || image.rows != view.intrinsics.height) {
    throw InputError(fmt::format("{}: image is {}x{} but view {} ('{}') says {}x{}",
                                 view.image_path, image.cols, image.rows, id, view.name,
                                 view.intrinsics.width, view.intrinsics.height));
  }
  SweepCamera camera = SweepCameraGeometry(id, view);
  camera.image = UndistortImage(image, view.intrinsics);
  return camera;
}

}  // namespace ms
