// Images of a scene: sizes from file headers (no decoding), loading through OpenCV, and removal
// of lens distortion so later stages can treat every view as a pinhole camera.
#pragma once

#include <functional>
#include <opencv2/core/mat.hpp>
#include <string>
#include <string_view>

#include "scene/camera.h"

namespace ms {

struct ImageSize {
  int width = 0;
  int height = 0;
  bool operator==(const ImageSize& o) const { return width == o.width && height == o.height; }
};

// Image size by image name, for formats that do not store sizes (NVM, Bundler, Middlebury):
// the file readers look the images up on disk; parsers fed from memory (fuzzing) pass a constant.
using ImageSizeLookup = std::function<ImageSize(const std::string& image_name)>;

// Size from the header of a PNG or JPEG held in memory (`name` for messages). Reads only header
// structures, walks at most 4096 JPEG segments, never allocates from sizes in the data. Throws
// InputError if the bytes are neither, or the header is malformed or truncated.
ImageSize ParseImageSize(const std::string& name, std::string_view bytes);

// Size of an image file from its header: PNG and JPEG read only the first bytes (JPEG follows
// segment lengths with seeks); other formats OpenCV can read are decoded as a fallback.
ImageSize ReadImageSize(const std::string& path);

enum class ImageMode {
  kGrayFloat,  // CV_32FC1, values in [0, 1] (8- and 16-bit files scaled by their range)
  kColor,      // CV_8UC3 in RGB order (16-bit files scaled down)
};

// Loads an image. Throws InputError naming the path if it is missing or cannot be decoded.
cv::Mat LoadImage(const std::string& path, ImageMode mode);

struct UndistortedImage {
  View view;      // the input view with its distortion coefficients set to zero
  cv::Mat image;  // same size and type as the input, resampled bilinearly
};

// Resamples `image` (the view's own image, any type OpenCV can remap) so that the view becomes an
// ideal pinhole camera with the same K. Pixels whose source falls outside the image are 0.
// Views without distortion are returned unchanged (the image is shared, not copied).
// Throws InputError if the image size differs from the view's intrinsics.
UndistortedImage Undistort(const View& view, const cv::Mat& image);

}  // namespace ms
