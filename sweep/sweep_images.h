// Images for sweep jobs: gray float in [0, 1], undistorted to the pinhole model the kernels take.
#pragma once

#include <opencv2/core/mat.hpp>
#include <string>

#include "scene/camera.h"
#include "sweep/sweep_kernel.h"

namespace ms {

// Reads an image file as gray CV_32FC1 in [0, 1] (8-bit / 255, 16-bit / 65535, float as is).
// Throws InputError naming the file if it is missing or unreadable.
cv::Mat ReadGrayImage(const std::string& path);

// Resamples an image taken through `intrinsics` (with distortion) to the same K without
// distortion (bilinear; pixels whose source falls outside the image get the nearest border
// value). Returns the input unchanged if there is no distortion.
cv::Mat UndistortImage(const cv::Mat& image, const Intrinsics& intrinsics);

// Loads view.image_path as a sweep camera: gray float, undistorted, the view's distortion set to
// zero. Throws InputError if the path is empty or the file's size differs from the view's.
SweepCamera LoadSweepCamera(int32_t id, const View& view);
// The same camera without reading its image (image empty): what code that needs only the
// views, as LoadSweepCamera gives them, works with.
SweepCamera SweepCameraGeometry(int32_t id, const View& view);

}  // namespace ms
