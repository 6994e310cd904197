#include "scene/image_io.h"

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "base/error.h"
#include "base/file_util.h"

namespace ms {
namespace {

// Larger sides are rejected: no camera makes them, and later stages multiply width by height.
constexpr int64_t kMaxSide = int64_t{1} << 20;
constexpr int kMaxJpegSegments = 4096;

// Reads `n` bytes at `offset` into `out`; false if the source ends first.
using ByteSource = std::function<bool(uint64_t offset, size_t n, uint8_t* out)>;

[[noreturn]] void Fail(const std::string& name, const std::string& message) {
  throw InputError(name + ": " + message);
}

uint32_t BigEndian32(const uint8_t* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | p[3];
}
uint16_t BigEndian16(const uint8_t* p) { return static_cast<uint16_t>((p[0] << 8) | p[1]); }

ImageSize CheckedSize(const std::string& name, const char* kind, int64_t width, int64_t height) {
  if (width <= 0 || height <= 0 || width > kMaxSide || height > kMaxSide) {
    Fail(name, std::string(kind) + " header: image size " + std::to_string(width) + "x" +
                   std::to_string(height) + " is out of range [1, " + std::to_string(kMaxSide) +
                   "]");
  }
  return {static_cast<int>(width), static_cast<int>(height)};
}

bool IsPng(const uint8_t* head) {
  static const uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  return std::memcmp(head, kSignature, 8) == 0;
}

ImageSize ParsePng(const std::string& name, const ByteSource& read) {
  // Signature, then the IHDR chunk: length (13), "IHDR", width, height (big-endian).
  uint8_t ihdr[16];
  if (!read(8, sizeof(ihdr), ihdr)) Fail(name, "PNG header truncated before IHDR");
  if (BigEndian32(ihdr) != 13 || std::memcmp(ihdr + 4, "IHDR", 4) != 0) {
    Fail(name, "PNG header: first chunk is not a 13-byte IHDR");
  }
  return CheckedSize(name, "PNG", BigEndian32(ihdr + 8), BigEndian32(ihdr + 12));
}

bool IsStartOfFrame(uint8_t marker) {
  // SOF0..SOF15 except DHT (C4), JPG (C8) and DAC (CC).
  return marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
}

ImageSize ParseJpeg(const std::string& name, const ByteSource& read) {
  uint64_t pos = 2;  // after SOI
  for (int segment = 0; segment < kMaxJpegSegments; ++segment) {
    uint8_t byte = 0;
    if (!read(pos, 1, &byte)) Fail(name, "JPEG truncated before the frame header");
    if (byte != 0xFF) {
      Fail(name, "JPEG: expected a marker at byte " + std::to_string(pos));
    }
    // Any number of 0xFF fill bytes may precede the marker code.
    uint8_t marker = 0xFF;
    int fill = 0;
    while (marker == 0xFF) {
      if (++fill > 64) Fail(name, "JPEG: too many fill bytes at byte " + std::to_string(pos));
      ++pos;
      if (!read(pos, 1, &marker)) Fail(name, "JPEG truncated before the frame header");
    }
    ++pos;
    if (marker == 0xD8 || marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) continue;
    if (marker == 0xD9 || marker == 0xDA) {
      Fail(name, "JPEG: no frame header (SOF) before the image data");
    }
    uint8_t length_bytes[2];
    if (!read(pos, 2, length_bytes)) Fail(name, "JPEG truncated in a segment length");
    const uint16_t length = BigEndian16(length_bytes);
    if (length < 2) Fail(name, "JPEG: segment length " + std::to_string(length) + " < 2");
    if (IsStartOfFrame(marker)) {
      uint8_t frame[5];  // precision, height, width
      if (length < 2 + 5 || !read(pos + 2, 5, frame)) Fail(name, "JPEG frame header truncated");
      const int height = BigEndian16(frame + 1);
      const int width = BigEndian16(frame + 3);
      if (height == 0) Fail(name, "JPEG: height given by a DNL marker is not supported");
      return CheckedSize(name, "JPEG", width, height);
    }
    pos += length;
  }
  Fail(name,
       "JPEG: no frame header within the first " + std::to_string(kMaxJpegSegments) + " segments");
}

ImageSize ParseFromSource(const std::string& name, const ByteSource& read, bool* recognised) {
  uint8_t head[8];
  *recognised = false;
  if (!read(0, 2, head)) Fail(name, "image file is too short to have a header");
  if (head[0] == 0xFF && head[1] == 0xD8) {
    *recognised = true;
    return ParseJpeg(name, read);
  }
  if (read(0, 8, head) && IsPng(head)) {
    *recognised = true;
    return ParsePng(name, read);
  }
  return {};
}

}  // namespace

ImageSize ParseImageSize(const std::string& name, std::string_view bytes) {
  const ByteSource read = [&](uint64_t offset, size_t n, uint8_t* out) {
    if (offset > bytes.size() || n > bytes.size() - offset) return false;
    std::memcpy(out, bytes.data() + offset, n);
    return true;
  };
  bool recognised = false;
  const ImageSize size = ParseFromSource(name, read, &recognised);
  if (!recognised) Fail(name, "not a PNG or JPEG image");
  return size;
}

ImageSize ReadImageSize(const std::string& path) {
  RequireFile(path, "image");
  std::ifstream in(path, std::ios::binary);
  if (!in) Fail(path, "cannot open image for reading");
  const ByteSource read = [&](uint64_t offset, size_t n, uint8_t* out) {
    in.clear();
    in.seekg(static_cast<std::streamoff>(offset));
    if (!in) return false;
    in.read(reinterpret_cast<char*>(out), static_cast<std::streamsize>(n));
    return static_cast<size_t>(in.gcount()) == n;
  };
  bool recognised = false;
  const ImageSize size = ParseFromSource(path, read, &recognised);
  if (recognised) return size;
  // Another format: let OpenCV decode it (slow, but only for unusual inputs).
  const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED | cv::IMREAD_IGNORE_ORIENTATION);
  if (image.empty()) Fail(path, "not a PNG or JPEG image, and OpenCV cannot decode it");
  return CheckedSize(path, "decoded", image.cols, image.rows);
}

cv::Mat LoadImage(const std::string& path, ImageMode mode) {
  RequireFile(path, "image");
  cv::Mat image;
  const int orientation = cv::IMREAD_IGNORE_ORIENTATION;  // pixels as stored, like SfM tools
  if (mode == ImageMode::kGrayFloat) {
    image = cv::imread(path, cv::IMREAD_GRAYSCALE | cv::IMREAD_ANYDEPTH | orientation);
  } else {
    image = cv::imread(path, cv::IMREAD_COLOR | cv::IMREAD_ANYDEPTH | orientation);
  }
  if (image.empty()) Fail(path, "cannot decode image");
  cv::Mat out;
  if (mode == ImageMode::kGrayFloat) {
    double scale = 1.0;
    if (image.depth() == CV_8U) scale = 1.0 / 255.0;
    if (image.depth() == CV_16U) scale = 1.0 / 65535.0;
    image.convertTo(out, CV_32F, scale);
  } else {
    cv::Mat bgr8;
    if (image.depth() == CV_8U) {
      bgr8 = image;
    } else if (image.depth() == CV_16U) {
      image.convertTo(bgr8, CV_8U, 1.0 / 257.0);
    } else {
      image.convertTo(bgr8, CV_8U, 255.0);  // float images hold [0, 1]
    }
    cv::cvtColor(bgr8, out, cv::COLOR_BGR2RGB);
  }
  return out;
}

UndistortedImage Undistort(const View& view, const cv::Mat& image) {
  const Intrinsics& k = view.intrinsics;
  if (image.cols != k.width || image.rows != k.height) {
    throw InputError("view '" + view.name + "': image is " + std::to_string(image.cols) + "x" +
                     std::to_string(image.rows) + " but the camera is " + std::to_string(k.width) +
                     "x" + std::to_string(k.height));
  }
  UndistortedImage result{view, image};
  if (!k.HasDistortion()) return result;
  result.view.intrinsics.k1 = result.view.intrinsics.k2 = result.view.intrinsics.k3 = 0;
  result.view.intrinsics.p1 = result.view.intrinsics.p2 = 0;
  // For every output pixel centre (corner-origin convention), where its ray lands in the
  // distorted input. cv::remap puts pixel centres at integers, hence the -0.5.
  cv::Mat map_x(k.height, k.width, CV_32F), map_y(k.height, k.width, CV_32F);
  for (int row = 0; row < k.height; ++row) {
    float* mx = map_x.ptr<float>(row);
    float* my = map_y.ptr<float>(row);
    for (int col = 0; col < k.width; ++col) {
      const Eigen::Vector2d n((col + 0.5 - k.cx) / k.fx, (row + 0.5 - k.cy) / k.fy);
      const Eigen::Vector2d d = k.Distort(n);
      mx[col] = static_cast<float>(k.fx * d.x() + k.cx - 0.5);
      my[col] = static_cast<float>(k.fy * d.y() + k.cy - 0.5);
    }
  }
  cv::remap(image, result.image, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
            cv::Scalar::all(0));
  return result;
}

}  // namespace ms
